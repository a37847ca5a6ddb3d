// Block rules that span several commands: action blocks move and vanish with their step,
// pasted steps and transitions get fresh names and no comments (the comments stay with the
// original), and pasted action blocks and jumps follow their pasted step.
import CommandInterceptor from 'diagram-js/lib/command/CommandInterceptor.js';
import { clone, freshName, isConnection, usedNames, type Service, type SfcShape } from '../../model';

export class BlockBehavior extends CommandInterceptor {
  static $inject = ['eventBus', 'elementRegistry', 'modeling'];

  constructor(eventBus: Service, elementRegistry: Service, modeling: Service) {
    super(eventBus);

    const actionBlocksOf = (stepIds: Set<string>): SfcShape[] =>
      elementRegistry.filter((e: Service) => e.businessObject?.kind === 'actionBlock' && stepIds.has(e.businessObject.step));

    this.preExecute('elements.move', (event: Service) => {
      const ctx = event.context;
      const shapes: SfcShape[] = ctx.shapes;
      const steps = new Set(shapes.filter((s) => s.businessObject?.kind === 'step').map((s) => s.id));
      if (steps.size === 0) return;
      const inMove = new Set(shapes);
      for (const ab of actionBlocksOf(steps)) if (!inMove.has(ab)) shapes.push(ab);
    });

    this.preExecute('shape.delete', (event: Service) => {
      const shape = event.context.shape as SfcShape;
      if (shape.businessObject?.kind !== 'step') return;
      for (const ab of actionBlocksOf(new Set([shape.id]))) {
        if (elementRegistry.get(ab.id)) modeling.removeShape(ab);
      }
    });

    // Copy: the clipboard holds a copy of the block's data and where it came from.
    eventBus.on('copyPaste.copyElement', 500, (ctx: Service) => {
      const { descriptor, element } = ctx;
      if (!element.businessObject) return;
      descriptor.businessObject = clone(element.businessObject);
      descriptor.sfcCopiedFrom = element.id;
    });
    eventBus.on('copyPaste.pasteElement', 500, (ctx: Service) => {
      const d = ctx.descriptor;
      if (d.businessObject) {
        d.businessObject = clone(d.businessObject);
        delete d.businessObject.comments;
      }
    });

    this.preExecute('elements.create', (event: Service) => {
      const elements: Service[] = event.context.elements;
      const pasted = elements.filter((e) => !isConnection(e) && e.sfcCopiedFrom && e.businessObject);
      if (pasted.length === 0) return;
      const used = usedNames(elementRegistry);
      const newId = new Map<string, string>();
      const newName = new Map<string, string>();
      for (const s of pasted) {
        newId.set(s.sfcCopiedFrom, s.id);
        const bo = s.businessObject;
        if ((bo.kind === 'step' || bo.kind === 'transition') && bo.name) {
          if (used.has(bo.name.toUpperCase())) {
            const fresh = freshName(bo.kind === 'step' ? 'S' : 'T', used);
            if (bo.kind === 'step') newName.set(bo.name, fresh);
            bo.name = fresh;
          } else {
            used.add(bo.name.toUpperCase());
          }
        }
      }
      for (const s of pasted) {
        const bo = s.businessObject;
        if (bo.kind === 'actionBlock' && bo.step && newId.has(bo.step)) bo.step = newId.get(bo.step);
        if (bo.kind === 'jump' && bo.target && newName.has(bo.target)) bo.target = newName.get(bo.target);
      }
    });
  }
}
