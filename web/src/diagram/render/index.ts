import { HitAreas } from './HitAreas';
import { SfcRenderer } from './SfcRenderer';

export default {
  __init__: ['sfcRenderer', 'sfcHitAreas'],
  sfcRenderer: ['type', SfcRenderer],
  sfcHitAreas: ['type', HitAreas],
};
