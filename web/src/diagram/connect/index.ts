import DraggingModule from 'diagram-js/lib/features/dragging/index.js';
import { PinConnect } from './PinConnect';

export default {
  __depends__: [DraggingModule],
  __init__: ['sfcConnect'],
  sfcConnect: ['type', PinConnect],
};
