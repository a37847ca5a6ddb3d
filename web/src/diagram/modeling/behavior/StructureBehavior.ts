// The keys and drops of structured editing (cmd/StructureHandlers.ts): Insert inserts a step
// and a transition after the selected step or transition, Shift+Insert before it; Delete (or
// Backspace) on a single step between two transitions removes the transition after it too and
// reconnects; a step or transition dropped from the palette onto a wire between a transition
// and a step goes into that sequence, all in the command that created it.
import CommandInterceptor from 'diagram-js/lib/command/CommandInterceptor.js';
import { isConnection, type Service, type SfcShape } from '../../model';
import { canDeleteStep, canInsert, spliceDropped, wireAt } from '../cmd/StructureHandlers';

export class StructureBehavior extends CommandInterceptor {
  static $inject = ['eventBus', 'injector', 'elementRegistry', 'modeling', 'elementFactory', 'canvas', 'selection', 'config.sfc'];

  constructor(
    eventBus: Service,
    injector: Service,
    elementRegistry: Service,
    modeling: Service,
    elementFactory: Service,
    canvas: Service,
    selection: Service,
    config: { readOnly?: boolean },
  ) {
    super(eventBus);
    if (config?.readOnly) return;

    const keyboard = injector.get('keyboard', false);
    keyboard?.addListener(1500, (ctx: Service) => {
      const ev = ctx.keyEvent as KeyboardEvent;
      if (ev.ctrlKey || ev.altKey || ev.metaKey) return;
      const sel: Service[] = selection.get();
      if (sel.length !== 1) return;
      if (ev.key === 'Insert' && canInsert(sel[0])) {
        const created = modeling.insertStructure(sel[0], ev.shiftKey ? 'before' : 'after');
        // The new block of the selected one's kind: pressing again goes on with the sequence.
        const same = created.find((b: SfcShape) => b.businessObject.kind === sel[0].businessObject.kind);
        if (same) selection.select(same);
        return true;
      }
      if ((ev.key === 'Delete' || ev.key === 'Backspace') && !ev.shiftKey && canDeleteStep(sel[0])) {
        modeling.deleteStepReconnect(sel[0]);
        return true;
      }
    });

    // A drop on a wire: the create command is told which wire (the palette's drop position
    // is what the user aimed at; the hover is always the chart, EditBehavior).
    eventBus.on('create.end', 1500, (event: Service) => {
      const ctx = event.context;
      const shape = ctx.shape as SfcShape | undefined;
      const kind = shape?.businessObject?.kind;
      if (!shape || (shape as Service).sfcCopiedFrom || (kind !== 'step' && kind !== 'transition')) return;
      if ((ctx.elements?.length ?? 1) !== 1) return;
      const wire = wireAt(elementRegistry, { x: event.x, y: event.y }, Math.max(10, shape.width / 4));
      if (wire) ctx.hints = { ...(ctx.hints ?? {}), sfcSpliceWire: wire.id };
    });

    this.postExecuted('elements.create', (event: Service) => {
      const ctx = event.context;
      const id = ctx.hints?.sfcSpliceWire;
      if (!id) return;
      const wire = elementRegistry.get(id);
      const dropped = (ctx.elements as Service[]).find((e) => !isConnection(e));
      if (!wire || !isConnection(wire) || !dropped) return;
      spliceDropped({ modeling, elementFactory, elementRegistry, canvas }, dropped, wire);
    });
  }
}
