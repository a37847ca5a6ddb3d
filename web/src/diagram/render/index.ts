import { SfcRenderer } from './SfcRenderer';

export default {
  __init__: ['sfcRenderer'],
  sfcRenderer: ['type', SfcRenderer],
};
