import KeyboardModule from 'diagram-js/lib/features/keyboard/index.js';
import SelectionModule from 'diagram-js/lib/features/selection/index.js';
import { TextEditing } from './TextEditing';
import { Interaction } from './Interaction';

export default {
  __depends__: [KeyboardModule, SelectionModule],
  __init__: ['sfcInteraction'],
  sfcTextEditing: ['type', TextEditing],
  sfcInteraction: ['type', Interaction],
};
