import PaletteModule from 'diagram-js/lib/features/palette/index.js';
import CreateModule from 'diagram-js/lib/features/create/index.js';
import { SfcPalette } from './SfcPalette';

export default {
  __depends__: [PaletteModule, CreateModule],
  __init__: ['sfcPalette'],
  sfcPalette: ['type', SfcPalette],
};
