// diagram-js modeling plus the SFC commands: property updates of blocks and wires, document
// fields and applying a whole layout, each one undoable step.
import BaseModeling from 'diagram-js/lib/features/modeling/Modeling.js';
import type { EditorDoc } from '../../doc';
import type { DocFields } from '../core/DocState';
import type { Service, SfcElement } from '../model';
import { ApplyLayoutHandler } from './cmd/ApplyLayoutHandler';
import { ReplaceDocHandler } from './cmd/ReplaceDocHandler';
import { DeleteStepHandler, InsertStructureHandler, type InsertWhere } from './cmd/StructureHandlers';
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
      'sfc.doc.replace': ReplaceDocHandler,
      'sfc.structure.insert': InsertStructureHandler,
      'sfc.structure.deleteStep': DeleteStepHandler,
    };
  }

  /** A moved block keeps its place among the chart's children. diagram-js would append it:
   *  that changes the drawing order, and bringing the DOM in line then re-inserts every
   *  block drawn after it (a full restyle and layout, about 0.4 s on a 500-step chart). */
  moveShape(shape: Service, delta: Service, newParent?: Service, newParentIndex?: Service, hints?: Service) {
    if (typeof newParentIndex === 'object' && newParentIndex !== null) {
      hints = newParentIndex;
      newParentIndex = undefined;
    }
    const parent = newParent || shape.parent;
    if ((newParentIndex === undefined || newParentIndex === null) && parent === shape.parent && parent?.children) {
      newParentIndex = parent.children.indexOf(shape);
    }
    return (BaseModeling.prototype as Service).moveShape.call(this, shape, delta, newParent, newParentIndex, hints);
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

  /** A step and a transition inserted into the sequence after or before `element` (a step or
   *  transition); returns the new blocks, top to bottom. */
  insertStructure(element: SfcElement, where: InsertWhere): SfcElement[] {
    const ctx: Record<string, unknown> = { element, where };
    this._commandStack.execute('sfc.structure.insert', ctx);
    return (ctx.created as SfcElement[]) ?? [];
  }

  /** A step between two transitions removed with the transition after it, the one before
   *  wired to what followed. */
  deleteStepReconnect(step: SfcElement) {
    this._commandStack.execute('sfc.structure.deleteStep', { step });
  }

  /** Everything of a document with the same blocks and wires (see ReplaceDocHandler). */
  replaceDoc(doc: EditorDoc) {
    this._commandStack.execute('sfc.doc.replace', { doc });
  }
}
