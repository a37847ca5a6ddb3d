// `window.__sfc`: read-only views of the open charts for the browser tests (web/e2e), which
// drive the editor with the real mouse and keyboard and use these only to aim and to assert.
import type { CanvasHandle } from '../diagram/types';
import { blockOnScreen, cursorOf, pinOnScreen, toScreen, viewOf } from '../diagram/probe';
import type { EditorDoc, Point } from '../doc';
import type { TabStore } from './store';
import { viewKey } from './actionCharts';

export interface SfcProbe {
  /** The active chart's document (the POU's, or the action's whose chart is shown), or null without one. */
  doc(): EditorDoc | null;
  /** The document of every tab, in tab order. */
  docs(): EditorDoc[];
  /** The open tabs: path, POU, target, unsaved changes. */
  tabs(): { path: string | null; pou: string; chartTarget: string; dirty: boolean; active: boolean }[];
  /** A block's box on screen (client pixels). */
  box(id: string): { x: number; y: number; width: number; height: number };
  /** A pin of a block on screen. */
  pin(id: string, side: 'in' | 'out', k: number): Point;
  /** A canvas point on screen. */
  toScreen(p: Point): Point;
  zoom(): number;
  /** Ids of the selected blocks and connections. */
  selection(): string[];
  /** The visible area in canvas units. */
  view(): { x: number; y: number; width: number; height: number; scale: number };
  cursor(): string;
  canUndo(): boolean;
  canRedo(): boolean;
  /** The active chart as Export SVG writes it (with the highlights' marks when asked). */
  exportSvg(options?: { marks?: boolean }): string;
}

/** Installs `window.__sfc` over the app's tabs and canvases; returns the uninstaller. */
export function installProbe(store: TabStore, canvases: Map<string, CanvasHandle>): () => void {
  // The canvas of the active tab's view: the POU's chart or an action's (actionCharts.ts).
  const shown = (): CanvasHandle | undefined => {
    const tab = store.active();
    return tab ? canvases.get(viewKey(tab.id, tab.view)) : undefined;
  };
  const active = (): CanvasHandle => {
    const c = shown();
    if (!c) throw new Error('no chart is open');
    return c;
  };
  const probe: SfcProbe = {
    doc: () => shown()?.getDoc() ?? null,
    docs: () => store.tabs.map((x) => canvases.get(x.id)).filter((c): c is CanvasHandle => !!c).map((c) => c.getDoc()),
    tabs: () =>
      store.tabs.map((x) => ({
        path: x.path,
        pou: x.pou,
        chartTarget: x.chartTarget,
        dirty: x.unsaved || x.canvasDirty,
        active: x.id === store.activeId,
      })),
    box: (id) => blockOnScreen(active(), id),
    pin: (id, side, k) => pinOnScreen(active(), id, side, k),
    toScreen: (p) => toScreen(active(), p),
    zoom: () => active().getZoom(),
    selection: () => active().selection(),
    view: () => viewOf(active()),
    cursor: cursorOf,
    canUndo: () => active().canUndo(),
    canRedo: () => active().canRedo(),
    exportSvg: (options?: { marks?: boolean }) => active().exportSvg(options),
  };
  const w = window as unknown as { __sfc?: SfcProbe };
  w.__sfc = probe;
  return () => {
    if (w.__sfc === probe) delete w.__sfc;
  };
}
