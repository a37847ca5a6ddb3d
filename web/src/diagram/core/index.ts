import { SfcElementFactory } from './SfcElementFactory';
import { DocState } from './DocState';
import { OrderCounter } from '../model';
import { Highlights } from '../highlight/Highlights';
import { RootMarkers } from './RootMarkers';

export default {
  __init__: ['sfcRootMarkers'],
  sfcRootMarkers: ['type', RootMarkers],
  elementFactory: ['type', SfcElementFactory],
  sfcOrder: ['type', OrderCounter],
  sfcDocState: ['type', DocState],
  sfcHighlights: ['type', Highlights],
};
