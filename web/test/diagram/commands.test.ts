// Every change is one command on diagram-js's CommandStack: undo gives back the document before
// it, redo the document after it.
import { describe, expect, it } from 'vitest';
import { mount, type Mounted } from './harness';
import { conveyorDoc } from './fixtures';
import type { EditorDoc } from '../../src/doc';

function undoable(
  name: string,
  op: (m: Mounted) => void,
  check?: (before: EditorDoc, after: EditorDoc, m: Mounted) => void,
  setup?: (m: Mounted) => void,
) {
  it(name, () => {
    const m = mount();
    const { canvas } = m;
    canvas.load(conveyorDoc());
    if (setup) {
      setup(m);
      canvas.load(canvas.getDoc());
    }
    const before = canvas.getDoc();
    let changes = 0;
    canvas.on('change', () => changes++);
    op(m);
    const after = canvas.getDoc();
    expect(after).not.toStrictEqual(before);
    expect(changes).toBeGreaterThan(0);
    expect(canvas.isDirty()).toBe(true);
    check?.(before, after, m);
    canvas.undo();
    expect(canvas.getDoc()).toStrictEqual(before);
    expect(canvas.isDirty()).toBe(false);
    expect(canvas.canRedo()).toBe(true);
    canvas.redo();
    expect(canvas.getDoc()).toStrictEqual(after);
    expect(canvas.isDirty()).toBe(true);
    // A single undo step, whatever the command did inside.
    canvas.undo();
    expect(canvas.canUndo()).toBe(false);
  });
}

const el = (doc: EditorDoc, id: string) => doc.elements.find((e) => e.id === id)!;
const wire = (doc: EditorDoc, id: string) => doc.connections.find((c) => c.id === id)!;

describe('undo/redo of every command', () => {
  undoable('move a block (wires follow, stay orthogonal)', ({ get }) => {
    get('modeling').moveElements([get('elementRegistry').get('step:Run')], { x: 40, y: 10 });
  }, (_b, a) => {
    expect(el(a, 'step:Run')).toMatchObject({ x: 140, y: 170 });
    // Its action block moves with it.
    expect(el(a, 'b1')).toMatchObject({ x: 260, y: 180 });
    for (const id of ['c2', 'c3']) {
      const wp = wire(a, id).waypoints!;
      expect(wp.every((p, i) => i === 0 || p.x === wp[i - 1].x || p.y === wp[i - 1].y)).toBe(true);
    }
    expect(wire(a, 'c2').waypoints!.at(-1)).toEqual({ x: 180, y: 170 });
    expect(wire(a, 'c3').waypoints![0]).toEqual({ x: 180, y: 210 });
  });

  undoable('resize a step', ({ get }) => {
    get('modeling').resizeShape(get('elementRegistry').get('step:Run'), { x: 100, y: 160, width: 120, height: 50 });
  }, (_b, a) => {
    expect(el(a, 'step:Run')).toMatchObject({ w: 120, h: 50 });
    expect(wire(a, 'c3').waypoints![0]).toEqual({ x: 160, y: 210 });
  });

  undoable('delete a step with its wires and action block', ({ get }) => {
    get('modeling').removeElements([get('elementRegistry').get('step:Run')]);
  }, (_b, a) => {
    expect(a.elements.map((e) => e.id)).not.toContain('step:Run');
    expect(a.elements.map((e) => e.id)).not.toContain('b1');
    expect(a.connections.map((c) => c.id)).not.toContain('c2');
  });

  undoable('create a step from the palette', ({ get }) => {
    const shape = get('sfcPalette').newShape({ make: () => ({ kind: 'step', name: 'S1' }) });
    get('modeling').createShape(shape, { x: 540, y: 220 }, get('canvas').getRootElement());
  }, (_b, a) => {
    const s = a.elements.at(-1)!;
    expect(s).toMatchObject({ kind: 'step', name: 'S1', x: 500, y: 200, w: 80, h: 40 });
    expect(s.id).toMatch(/^b\d+$/);
  });

  undoable('connect two pins', ({ get }) => {
    const reg = get('elementRegistry');
    const t = reg.get('b6');
    const c = get('elementFactory').createConnection({ businessObject: { id: '', source: 'step:A', sourcePin: 0, target: t.id, targetPin: 0 } });
    get('modeling').createConnection(reg.get('step:A'), t, c, get('canvas').getRootElement());
  }, (_b, a) => {
    const c = a.connections.at(-1)!;
    expect(c).toMatchObject({ source: 'step:A', sourcePin: 0, target: 'b6', targetPin: 0 });
    expect(c.waypoints).toEqual([{ x: 30, y: 400 }, { x: 30, y: 420 }, { x: 40, y: 420 }, { x: 40, y: 430 }]);
  }, ({ get }) => {
    const t = get('sfcPalette').newShape({ make: () => ({ kind: 'transition', name: 'T9' }) });
    get('modeling').createShape(t, { x: 40, y: 440 }, get('canvas').getRootElement());
  });

  undoable('reconnect a wire end to another block', ({ get }) => {
    const reg = get('elementRegistry');
    // c9: transition#3 → jump; move its end to a new step.
    get('modeling').reconnectEnd(reg.get('c9'), reg.get('b6'), { x: 300, y: 400 });
  }, (_b, a) => {
    const c = wire(a, 'c9');
    expect(c.target).toBe('b6');
    expect(c.waypoints!.at(-1)).toEqual({ x: 300, y: 400 });
    const wp = c.waypoints!;
    expect(wp.every((p, i) => i === 0 || p.x === wp[i - 1].x || p.y === wp[i - 1].y)).toBe(true);
  }, ({ get }) => {
    const s = get('sfcPalette').newShape({ make: () => ({ kind: 'step', name: 'S7' }) });
    get('modeling').createShape(s, { x: 300, y: 420 }, get('canvas').getRootElement());
  });

  undoable('drag a wire segment (bends stay orthogonal, ends stay on the pins)', ({ get }) => {
    const c = get('elementRegistry').get('c6');
    get('modeling').updateWaypoints(c, [{ x: 70, y: 290 }, { x: 70, y: 310 }, { x: 80, y: 310 }, { x: 80, y: 320 }]);
  }, (_b, a) => {
    expect(wire(a, 'c6').waypoints).toEqual([{ x: 70, y: 290 }, { x: 70, y: 310 }, { x: 80, y: 310 }, { x: 80, y: 320 }]);
  });

  undoable('move a middle vertex freely (made orthogonal)', ({ get }) => {
    const c = get('elementRegistry').get('c6');
    get('modeling').updateWaypoints(c, [{ x: 70, y: 290 }, { x: 95, y: 300 }, { x: 80, y: 320 }]);
  }, (_b, a) => {
    const wp = wire(a, 'c6').waypoints!;
    expect(wp[0]).toEqual({ x: 70, y: 290 });
    expect(wp.at(-1)).toEqual({ x: 80, y: 320 });
    expect(wp.every((p, i) => i === 0 || p.x === wp[i - 1].x || p.y === wp[i - 1].y)).toBe(true);
    expect(wp).toContainEqual({ x: 95, y: 300 });
  });

  undoable('updateElement', ({ canvas }) => canvas.updateElement('step:Run', { name: 'Running', timeout: 'T#9s' }));
  undoable('updateElement geometry', ({ canvas }) => canvas.updateElement('step:Init', { x: 90, w: 100 }));
  undoable('updateDoc', ({ canvas }) => canvas.updateDoc({ pou: 'Belt', declarations: 'VAR END_VAR', actions: [] }), (_b, a) => {
    expect(a.pou).toBe('Belt');
    expect(a.actions).toEqual([]);
  });
  // An IEC chart's build output (`sfc.build`) is a POU attribute; undo removes it again.
  undoable('updateDoc attributes', ({ canvas }) => canvas.updateDoc({ attributes: [{ name: 'sfc.build', value: 'stl' }] }), (b, a) => {
    expect(b.attributes).toBeUndefined();
    expect(a.attributes).toEqual([{ name: 'sfc.build', value: 'stl' }]);
  });
  undoable('applyLayout', ({ canvas }) => {
    const laid = canvas.getDoc();
    for (const e of laid.elements) e.y += 100;
    for (const c of laid.connections) c.waypoints = c.waypoints!.map((p) => ({ x: p.x, y: p.y + 100 }));
    delete laid.connections[0].waypoints;
    canvas.applyLayout(laid);
  }, (b, a) => {
    expect(el(a, 'step:Init').y).toBe(el(b, 'step:Init').y + 100);
    expect(wire(a, 'c2').waypoints).toEqual(wire(b, 'c2').waypoints!.map((p) => ({ x: p.x, y: p.y + 100 })));
    expect(wire(a, 'c1').waypoints).toEqual([{ x: 140, y: 180 }, { x: 140, y: 210 }]);
  });

  undoable('paste', ({ get }) => {
    const reg = get('elementRegistry');
    get('copyPaste').copy([reg.get('step:A'), reg.get('step:B')]);
    get('copyPaste').paste({ element: get('canvas').getRootElement(), point: { x: 400, y: 500 } });
  });

  undoable('edit a text label in place', ({ get }) => {
    const editing = get('sfcTextEditing');
    editing.activate(get('elementRegistry').get('b5'));
    const area = document.querySelector('.sfc-text-editor') as HTMLTextAreaElement;
    area.value = 'Belt conveyor\nrev. B';
    area.dispatchEvent(new KeyboardEvent('keydown', { key: 'Enter', ctrlKey: true }));
    expect(document.querySelector('.sfc-text-editor')).toBeNull();
  }, (_b, a) => expect(el(a, 'b5').text).toBe('Belt conveyor\nrev. B'));
});

describe('dirty state', () => {
  it('follows markSaved through undo and redo', () => {
    const { canvas } = mount();
    canvas.load(conveyorDoc());
    expect(canvas.isDirty()).toBe(false);
    canvas.updateElement('step:A', { name: 'A1' });
    canvas.markSaved();
    expect(canvas.isDirty()).toBe(false);
    canvas.undo();
    expect(canvas.isDirty()).toBe(true);
    canvas.redo();
    expect(canvas.isDirty()).toBe(false);
    canvas.undo();
    canvas.updateElement('step:A', { name: 'A2' });
    expect(canvas.isDirty()).toBe(true);
  });
});
