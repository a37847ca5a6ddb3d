// `replace`: a whole document put on the canvas as an edit (a merge conflict resolved on the
// server): one undo step when the blocks and wires stay the same, else loaded; dirty either way.
import { describe, expect, it } from 'vitest';
import { mount } from './harness';
import { conveyorDoc } from './fixtures';
import { sameStructure } from '../../src/diagram/modeling/cmd/ReplaceDocHandler';

describe('replace', () => {
  it('takes another copy with the same blocks as one undoable command', () => {
    const { canvas, container } = mount();
    canvas.load(conveyorDoc());
    const before = canvas.getDoc();
    const next = conveyorDoc();
    next.elements.find((e) => e.id === 'transition:Go')!.condition = 'start AND permit';
    next.elements.find((e) => e.id === 'step:Run')!.x = 120;
    next.attributes = [{ name: 'sfc.build', value: 'st' }];
    next.declarations = 'VAR\n  start, box, stop, permit : BOOL;\nEND_VAR\n';
    delete next.connections.find((c) => c.id === 'c2')!.waypoints;
    let changes = 0;
    canvas.on('change', () => changes++);
    expect(canvas.replace(next)).toBe(true);
    const after = canvas.getDoc();
    expect(changes).toBe(1);
    expect(canvas.isDirty()).toBe(true);
    expect(after.elements.find((e) => e.id === 'transition:Go')!.condition).toBe('start AND permit');
    expect(after.elements.find((e) => e.id === 'step:Run')!.x).toBe(120);
    expect(after.attributes).toEqual([{ name: 'sfc.build', value: 'st' }]);
    expect(after.declarations).toContain('permit');
    // The wire without a route is routed to its blocks' pins.
    expect(after.connections.find((c) => c.id === 'c2')!.waypoints!.length).toBeGreaterThanOrEqual(2);
    // Drawn: the condition's text is on the canvas.
    expect(container.textContent).toContain('start AND permit');
    canvas.undo();
    expect(canvas.getDoc()).toStrictEqual(before);
    expect(canvas.isDirty()).toBe(false);
    expect(canvas.canUndo()).toBe(false);
    canvas.redo();
    expect(canvas.getDoc()).toStrictEqual(after);
  });

  it('loads a copy with other blocks, dirty until saved', () => {
    const { canvas } = mount();
    canvas.load(conveyorDoc());
    const next = conveyorDoc();
    next.elements = next.elements.filter((e) => e.id !== 'b5');
    expect(sameStructure(canvas.getDoc(), next)).toBe(false);
    expect(canvas.replace(next)).toBe(false);
    expect(canvas.getDoc().elements.map((e) => e.id)).not.toContain('b5');
    expect(canvas.isDirty()).toBe(true);
    expect(canvas.canUndo()).toBe(false);
    canvas.markSaved();
    expect(canvas.isDirty()).toBe(false);
  });

  it('tells the same structure: ids, kinds, wire ends and pins', () => {
    const a = conveyorDoc();
    expect(sameStructure(a, conveyorDoc())).toBe(true);
    const rewired = conveyorDoc();
    rewired.connections.find((c) => c.id === 'c5')!.sourcePin = 0;
    expect(sameStructure(a, rewired)).toBe(false);
    const kind = conveyorDoc();
    kind.elements.find((e) => e.id === 'b4')!.kind = 'text';
    expect(sameStructure(a, kind)).toBe(false);
    const moved = conveyorDoc();
    moved.elements[0].x += 10;
    expect(sameStructure(a, moved)).toBe(true);
  });
});
