// A CanvasHandle that keeps the document in memory (no drawing), with undo/redo and events, for
// testing the shell without diagram-js.
import type { CanvasEvents, CanvasHandle, HighlightKind } from '../../src/diagram/types';
import type { EditorDoc } from '../../src/doc';

export interface FakeCanvas extends CanvasHandle {
  highlights: Partial<Record<HighlightKind, { ids: string[]; labels?: Record<string, string> }>>;
  revealed: string[];
  emit<K extends keyof CanvasEvents>(event: K, ...args: Parameters<CanvasEvents[K]>): void;
  container: HTMLElement;
}

const clone = <T>(x: T): T => JSON.parse(JSON.stringify(x));

export function createFakeCanvas(container: HTMLElement): FakeCanvas {
  let doc: EditorDoc | null = null;
  let revision = 0;
  let undo: EditorDoc[] = [];
  let redo: EditorDoc[] = [];
  let savedAt = 0;
  let selected: string[] = [];
  let zoom = 1;
  const listeners = new Map<keyof CanvasEvents, Set<(...args: never[]) => void>>();
  const svg = document.createElementNS('http://www.w3.org/2000/svg', 'svg');
  container.appendChild(svg);
  const current = () => {
    if (!doc) throw new Error('fake canvas: no document loaded');
    return doc;
  };
  const apply = (next: EditorDoc) => {
    undo.push(current());
    redo = [];
    doc = next;
    revision++;
    fc.emit('change');
  };
  const fc: FakeCanvas = {
    container,
    highlights: {},
    revealed: [],
    emit(event, ...args) {
      for (const cb of listeners.get(event) ?? []) (cb as (...a: unknown[]) => void)(...args);
    },
    load(d) {
      doc = clone(d);
      revision++;
      undo = [];
      redo = [];
      savedAt = 0;
    },
    getDoc: () => clone(current()),
    revision: () => revision,
    updateElement(id, props) {
      const d = clone(current());
      d.elements = d.elements.map((e) => (e.id === id ? { ...e, ...props } : e));
      d.connections = d.connections.map((c) => (c.id === id ? { ...c, ...props } : c));
      apply(d);
    },
    updateDoc(props) {
      apply({ ...clone(current()), ...props });
    },
    applyLayout(laidOut) {
      apply(clone(laidOut));
    },
    replace(d) {
      apply(clone(d));
      return true;
    },
    undo() {
      const prev = undo.pop();
      if (prev) {
        redo.push(current());
        doc = prev;
        revision++;
        fc.emit('change');
      }
    },
    redo() {
      const next = redo.pop();
      if (next) {
        undo.push(current());
        doc = next;
        revision++;
        fc.emit('change');
      }
    },
    canUndo: () => undo.length > 0,
    canRedo: () => redo.length > 0,
    structure: () => false,
    canStructure: () => false,
    isDirty: () => undo.length !== savedAt,
    markSaved() {
      savedAt = undo.length;
    },
    select(ids) {
      selected = [...ids];
      fc.emit('selection', selected);
    },
    selection: () => [...selected],
    highlight(kind, ids, labels) {
      fc.highlights[kind] = { ids: [...ids], labels };
    },
    clearHighlights(kind) {
      if (kind) delete fc.highlights[kind];
      else fc.highlights = {};
    },
    reveal(id) {
      fc.revealed.push(id);
    },
    zoom(level) {
      zoom = level === 'fit' ? 0.8 : level;
      fc.emit('zoom', zoom);
    },
    getZoom: () => zoom,
    exportSvg: () => '<svg xmlns="http://www.w3.org/2000/svg" width="600" height="400" viewBox="0 0 600 400"></svg>',
    relabel() {},
    on(event, cb) {
      const set = listeners.get(event) ?? new Set();
      listeners.set(event, set);
      set.add(cb);
      return () => void set.delete(cb);
    },
    destroy() {
      svg.remove();
    },
  };
  return fc;
}
