import { DocImporter } from './DocImporter';

export default {
  sfcImporter: ['type', DocImporter],
};
