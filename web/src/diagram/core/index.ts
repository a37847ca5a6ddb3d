import { SfcElementFactory } from './SfcElementFactory';
import { DocState } from './DocState';
import { OrderCounter } from '../model';
import { Highlights } from '../highlight/Highlights';

export default {
  elementFactory: ['type', SfcElementFactory],
  sfcOrder: ['type', OrderCounter],
  sfcDocState: ['type', DocState],
  sfcHighlights: ['type', Highlights],
};
