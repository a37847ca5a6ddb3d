import { GridLayer } from './GridLayer';
import { Scrollbars } from './Scrollbars';
import { ViewTracker } from './ViewTracker';

export default {
  __init__: ['sfcView', 'sfcGrid', 'sfcScrollbars'],
  sfcView: ['type', ViewTracker],
  sfcGrid: ['type', GridLayer],
  sfcScrollbars: ['type', Scrollbars],
};
