import ModelingModule from 'diagram-js/lib/features/modeling/index.js';
import { SfcModeling } from './SfcModeling';
import { SfcLayouter } from '../layout/SfcLayouter';
import { WireBehavior } from './behavior/WireBehavior';
import { BlockBehavior } from './behavior/BlockBehavior';
import { EditBehavior } from './behavior/EditBehavior';
import { TargetBehavior } from './behavior/TargetBehavior';
import { StructureBehavior } from './behavior/StructureBehavior';

export default {
  __depends__: [ModelingModule],
  __init__: ['sfcWireBehavior', 'sfcBlockBehavior', 'sfcEditBehavior', 'sfcTargetBehavior', 'sfcStructureBehavior'],
  modeling: ['type', SfcModeling],
  layouter: ['type', SfcLayouter],
  sfcWireBehavior: ['type', WireBehavior],
  sfcBlockBehavior: ['type', BlockBehavior],
  sfcEditBehavior: ['type', EditBehavior],
  sfcTargetBehavior: ['type', TargetBehavior],
  sfcStructureBehavior: ['type', StructureBehavior],
};
