// CONTRACT between the canvas (web/src/diagram, built on diagram-js) and the app shell
// (web/src/app). The app only talks to the canvas through this interface.
import type { EditorDoc, Element } from '../doc';

export type HighlightKind =
  | 'error' // red frame: a diagnostic's block
  | 'warning' // orange frame
  | 'selected-diagnostic' // the block of the error-list row the user clicked
  | 'witness' // the current transition/step of a witness being stepped through
  | 'active' // monitor: active step (green frame)
  | 'enabled' // monitor: transition whose condition holds
  | 'breakpoint' // monitor: breakpoint set (red dot)
  | 'hit' // monitor: breakpoint hit (orange frame)
  | 'diff-added' // compare: block added since the saved file / git HEAD (green)
  | 'diff-changed' // compare: block renamed or changed since (orange)
  | 'conflict'; // merge: block of an element `sfc merge` marked as a conflict (red-orange)

export type StructureOp = 'insertAfter' | 'insertBefore' | 'deleteStep';

export interface CanvasEvents {
  /** The document changed (any command executed, undone or redone). */
  change: () => void;
  /** The selection changed; ids of the selected blocks and connections. */
  selection: (ids: string[]) => void;
  /** Zoom level changed (1 = 100 %). */
  zoom: (level: number) => void;
  /** The user asked for the properties of a block (double click or Enter). */
  properties: (id: string) => void;
}

export interface CanvasOptions {
  /** Translates UI keys (palette titles, tooltips); called again after `relabel()`. */
  t: (key: string, opts?: Record<string, unknown>) => string;
  /** Read-only canvas (monitor mode, print preview). */
  readOnly?: boolean;
}

export interface CanvasHandle {
  /** Replaces the contents with `doc` and clears the undo history. */
  load(doc: EditorDoc): void;
  /** The current document (blocks, connections, geometry, and the doc-level fields): a copy. */
  getDoc(): EditorDoc;
  /** A number that changes whenever the document does (load, every command, undo, redo), so a
   *  view can keep its copy of `getDoc()` until then. */
  revision(): number;
  /** Changes properties of a block or connection (one undoable command). */
  updateElement(id: string, props: Partial<Element> & Record<string, unknown>): void;
  /** Changes document-level fields (one undoable command); `attributes` are the POU's pragmas
   *  the editor passes through, e.g. an IEC chart's `sfc.build`. */
  updateDoc(props: Partial<Pick<EditorDoc, 'pou' | 'target' | 'description' | 'declarations' | 'actions' | 'attributes' | 'body' | 'bodyLanguage'>>): void;
  /** Replaces all geometry with that of `laidOut` (same ids), as one undoable command. */
  applyLayout(laidOut: EditorDoc): void;
  /** Replaces the whole document by `doc` as an edit (the chart is dirty afterwards): one
   *  undoable command when `doc` has the same blocks and wires (ids, kinds, ends), else loaded
   *  with the undo history cleared. Returns whether it can be undone. */
  replace(doc: EditorDoc): boolean;
  /** Structured editing of the selected block (one undoable command; docs/editor.md,
   *  "Structured editing"): `insertAfter` / `insertBefore` a step and a transition into the
   *  sequence after or before the selected step or transition; `deleteStep` the selected step
   *  between two transitions with the transition after it, reconnecting. Returns whether it applied. */
  structure(op: StructureOp): boolean;
  /** Whether `structure(op)` applies to the selection. */
  canStructure(op: StructureOp): boolean;
  undo(): void;
  redo(): void;
  canUndo(): boolean;
  canRedo(): boolean;
  /** True when there are changes since `load()` or the last `markSaved()`. */
  isDirty(): boolean;
  markSaved(): void;
  select(ids: string[]): void;
  selection(): string[];
  /** Frames blocks; replaces the previous set of that kind. `labels` adds a small text (elapsed time) per id. */
  highlight(kind: HighlightKind, ids: string[], labels?: Record<string, string>): void;
  clearHighlights(kind?: HighlightKind): void;
  /** Scrolls a block into view. */
  reveal(id: string): void;
  /** 'fit' fits the whole chart. */
  zoom(level: number | 'fit'): void;
  getZoom(): number;
  /** Standalone SVG of the chart as drawn (no selection, no grid); the highlights' marks
   *  (validation and comparison frames, monitor states) only with `marks`. */
  exportSvg(options?: { marks?: boolean }): string;
  /** Re-translates palette and tooltips after a language switch. */
  relabel(): void;
  on<K extends keyof CanvasEvents>(event: K, cb: CanvasEvents[K]): () => void;
  destroy(): void;
}

export type CreateCanvas = (container: HTMLElement, opts: CanvasOptions) => CanvasHandle;
