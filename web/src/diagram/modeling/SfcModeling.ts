// diagram-js modeling plus the SFC commands: property updates of blocks and wires, document
// fields and applying a whole layout, each one undoable step.
import BaseModeling from 'diagram-js/lib/features/modeling/Modeling.js';
import type { EditorDoc } from '../../doc';
import type { DocFields } from '../core/DocState';
import type { Service, SfcElement } from '../model';
import { ApplyLayoutHandler } from './cmd/ApplyLayoutHandler';
import { UpdateDocHandler } from './cmd/UpdateDocHandler';
import { UpdateElementHandler } from './cmd/UpdateElementHandler';

export class SfcModeling extends BaseModeling {
  static $inject = ['eventBus', 'elementFactory', 'commandStack'];

  declare _commandStack: Service;

  getHandlers(): Service {
    return {
      ...(BaseModeling.prototype as Service).getHandlers.call(this),
      'sfc.element.update': UpdateElementHandler,
      'sfc.doc.update': UpdateDocHandler,
      'sfc.layout.apply': ApplyLayoutHandler,
    };
  }

  updateElement(element: SfcElement, props: Record<string, unknown>) {
    this._commandStack.execute('sfc.element.update', { element, props });
  }

  updateDoc(props: Partial<DocFields>) {
    this._commandStack.execute('sfc.doc.update', { props });
  }

  applyLayout(laidOut: EditorDoc) {
    this._commandStack.execute('sfc.layout.apply', { laidOut });
  }
}
