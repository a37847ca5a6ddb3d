import RulesModule from 'diagram-js/lib/features/rules/index.js';
import { SfcRules } from './SfcRules';

export default {
  __depends__: [RulesModule],
  __init__: ['sfcRules'],
  sfcRules: ['type', SfcRules],
};
