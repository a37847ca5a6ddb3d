// The open charts (one tab each in MDI mode, the only one in host mode), their dirty state,
// last diagnostics and build result, and the guard that asks before unsaved changes are lost.
import type { BuildResult, BuildTarget, CompareResult, Diag, FileFormat } from '../api';
import { targetsFor } from './buildResult';
import type { ChartKind } from './chartKind';

export type Outcome = 'none' | 'succeeded' | 'failed';

export interface TabState {
  id: string;
  /** Absolute path of the file, null for a chart never saved. */
  path: string | null;
  format: FileFormat;
  /** Hash of the file as last read or written (the save conflict check), null for a new file. */
  hash: string | null;
  pou: string;
  /** The POU's name in the file as last opened or saved (null: not in the file yet). A save
   *  replaces that POU, so renaming the chart does not leave the old one behind. */
  filePou: string | null;
  /** The chart's kind as the badge shows it: its `sfc.target`, or IEC (see chartKind.ts). */
  chartTarget: ChartKind;
  /** The chart has changes no file holds (a new chart), whatever the canvas' undo history says. */
  unsaved: boolean;
  /** The canvas reports changes since load or the last save. */
  canvasDirty: boolean;
  diagnostics: Diag[];
  /** The Succeeded/Failed overlay, cleared by the next change. */
  outcome: Outcome;
  result: { target: BuildTarget; result: BuildResult } | null;
  /** The toolbar's build target; an IEC chart's mirrors its `sfc.build` attribute. */
  buildTarget: BuildTarget;
  /** The chart shown: null for the POU's own (or its body in ST), else the name of an action
   *  written in SFC whose chart is open (see actionCharts.ts). */
  view: string | null;
  /** The actions whose charts have a canvas in this tab, in the order they were opened. */
  views: string[];
  /** File → Compare with saved / git HEAD: its answer while the chart shows it (cleared by
   *  the next change of the chart and by Close comparison). */
  compare: CompareResult | null;
}

export type NewTab = Pick<TabState, 'path' | 'format' | 'hash' | 'pou' | 'chartTarget'> & Partial<Pick<TabState, 'unsaved' | 'diagnostics' | 'filePou' | 'buildTarget'>>;

export class TabStore {
  tabs: TabState[] = [];
  activeId: string | null = null;
  private listeners = new Set<() => void>();
  private counter = 0;

  subscribe(listener: () => void): () => void {
    this.listeners.add(listener);
    return () => this.listeners.delete(listener);
  }

  private emit(): void {
    for (const l of [...this.listeners]) l();
  }

  /** Adds a tab and makes it the active one. */
  add(init: NewTab): TabState {
    this.counter += 1;
    const tab: TabState = {
      id: `tab${this.counter}`,
      unsaved: false,
      filePou: null,
      canvasDirty: false,
      diagnostics: [],
      outcome: 'none',
      result: null,
      buildTarget: targetsFor(init.chartTarget)[0],
      view: null,
      views: [],
      compare: null,
      ...init,
    };
    this.tabs = [...this.tabs, tab];
    this.activeId = tab.id;
    this.emit();
    return tab;
  }

  get(id: string): TabState | undefined {
    return this.tabs.find((t) => t.id === id);
  }

  active(): TabState | undefined {
    return this.activeId === null ? undefined : this.get(this.activeId);
  }

  activate(id: string): void {
    if (this.get(id) && this.activeId !== id) {
      this.activeId = id;
      this.emit();
    }
  }

  update(id: string, patch: Partial<Omit<TabState, 'id'>>): void {
    const at = this.tabs.findIndex((t) => t.id === id);
    if (at < 0) return;
    const tab = { ...this.tabs[at], ...patch };
    if (patch.chartTarget && !targetsFor(tab.chartTarget).includes(tab.buildTarget)) {
      tab.buildTarget = targetsFor(tab.chartTarget)[0];
    }
    this.tabs = this.tabs.map((t, k) => (k === at ? tab : t));
    this.emit();
  }

  /** Removes a tab; the neighbour to its right (else left) becomes active. */
  remove(id: string): void {
    const at = this.tabs.findIndex((t) => t.id === id);
    if (at < 0) return;
    this.tabs = this.tabs.filter((t) => t.id !== id);
    if (this.activeId === id) {
      const next = this.tabs[at] ?? this.tabs[at - 1];
      this.activeId = next ? next.id : null;
    }
    this.emit();
  }

  /** The tab already showing this POU of this file, if any (paths compare exactly, POUs case-insensitively). */
  find(path: string, pou: string): TabState | undefined {
    return this.tabs.find((t) => t.path === path && t.pou.toLowerCase() === pou.toLowerCase());
  }

  anyDirty(): boolean {
    return this.tabs.some(isDirty);
  }
}

export function isDirty(tab: TabState): boolean {
  return tab.unsaved || tab.canvasDirty;
}

/** The file name of a path (either separator). */
export function baseName(path: string): string {
  return path.split(/[\\/]/).pop() ?? path;
}

/** The tab's caption: `file.st: POU`, or the POU alone for a new chart; `*` when dirty. */
export function tabTitle(tab: TabState): string {
  const name = tab.path ? `${baseName(tab.path)}: ${tab.pou}` : tab.pou;
  return isDirty(tab) ? `${name}*` : name;
}

export type CloseChoice = 'save' | 'discard' | 'cancel';

/**
 * Decides whether a tab may close: a clean tab closes at once; for a dirty one `ask` shows the
 * Save / Discard / Cancel dialog, and Save closes only when `save` succeeded.
 */
export async function mayClose(
  tab: TabState,
  ask: (tab: TabState) => Promise<CloseChoice>,
  save: (tab: TabState) => Promise<boolean>,
): Promise<boolean> {
  if (!isDirty(tab)) return true;
  const choice = await ask(tab);
  if (choice === 'cancel') return false;
  if (choice === 'discard') return true;
  return save(tab);
}

/** The `beforeunload` handler: the browser's leave-page warning while any tab is dirty. */
export function unloadGuard(store: TabStore): (ev: BeforeUnloadEvent) => void {
  return (ev) => {
    if (store.anyDirty()) {
      ev.preventDefault();
      // Older browsers show the warning only when returnValue is set.
      ev.returnValue = '';
    }
  };
}

/** Whether a path lies under one of the server's roots (Save as accepts only those). */
export function underRoot(path: string, roots: string[]): boolean {
  const norm = (p: string) => p.replace(/\\/g, '/').replace(/\/+$/, '');
  const p = norm(path);
  if (p.split('/').includes('..')) return false;
  return roots.some((r) => p.startsWith(norm(r) + '/'));
}

/** The file format a path implies (`.xml` is PLCopen XML, anything else textual SFC). */
export function formatOf(path: string): FileFormat {
  return /\.xml$/i.test(path) ? 'xml' : 'st';
}
