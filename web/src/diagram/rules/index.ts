import RulesModule from 'diagram-js/lib/features/rules/index.js';
import { RefusalTooltip } from './RefusalTooltip';
import { SfcRules } from './SfcRules';

export default {
  __depends__: [RulesModule],
  __init__: ['sfcRules', 'sfcRefusalTooltip'],
  sfcRules: ['type', SfcRules],
  sfcRefusalTooltip: ['type', RefusalTooltip],
};
