// Actions written in SFC (CODESYS's SFC actions) and CODESYS's step actions, as the shell
// handles them. A POU's document lists its actions; one written in SFC carries its chart
// (`ActionDef.chart`, a document of its own). The tab of the POU shows the POU's chart (or, for a
// POU written in ST, its body as text) and, on request, each action's chart on a canvas of its
// own: the POU's views. Saving, checking and building send the POU's document with the charts
// as their canvases hold them (`assemble`).
import type { ActionDef, EditorDoc, Element } from '../doc';
import { isIecName } from './chart';

/** The actions of a document that are written in SFC, in order. */
export function sfcActions(doc: EditorDoc): ActionDef[] {
  return doc.actions.filter((a) => !!a.chart);
}

/** The key of a view's canvas: the tab's id for the POU's own chart, `tab::Action` for an action's. */
export function viewKey(tabId: string, view: string | null | undefined): string {
  return view ? `${tabId}::${view}` : tabId;
}

/** The chart of action `name` (case-insensitive), if it is written in SFC. */
export function actionChart(doc: EditorDoc, name: string): EditorDoc | undefined {
  const a = doc.actions.find((x) => x.name.toLowerCase() === name.toLowerCase());
  return a?.chart ?? undefined;
}

/**
 * The POU's document with the charts of its actions replaced by `charts` (action name → the
 * chart as its canvas holds it now); the other actions' charts stay as they are. Each chart is
 * the POU's (`pou` follows a renamed POU).
 */
export function assemble(pouDoc: EditorDoc, charts: Map<string, EditorDoc>): EditorDoc {
  if (charts.size === 0) return pouDoc;
  const byName = new Map([...charts].map(([k, v]) => [k.toLowerCase(), v]));
  return {
    ...pouDoc,
    actions: pouDoc.actions.map((a) => {
      const chart = a.chart ? byName.get(a.name.toLowerCase()) : undefined;
      return chart ? { ...a, chart: { ...chart, pou: pouDoc.pou } } : a;
    }),
  };
}

export type StepActionKind = 'entry' | 'main' | 'exit';

/** The word the text writes each kind with, in the order steps list them. */
export const STEP_ACTION_KEYWORDS: Record<StepActionKind, string> = {
  entry: 'ENTRY_ACTION',
  main: 'STEP_ACTION',
  exit: 'EXIT_ACTION',
};

const KINDS: StepActionKind[] = ['entry', 'main', 'exit'];

/** A step's step actions by kind, from `Element.stepActions` (`ENTRY_ACTION := Name`). */
export function stepActionsOf(step: Pick<Element, 'stepActions'>): Partial<Record<StepActionKind, string>> {
  const out: Partial<Record<StepActionKind, string>> = {};
  for (const written of step.stepActions ?? []) {
    const m = /^\s*(ENTRY_ACTION|STEP_ACTION|EXIT_ACTION)\s*:=\s*(.*?)\s*;?\s*$/i.exec(written);
    if (!m) continue;
    const kind = KINDS.find((k) => STEP_ACTION_KEYWORDS[k] === m[1].toUpperCase());
    if (kind && out[kind] === undefined) out[kind] = m[2];
  }
  return out;
}

/**
 * The step actions with one kind set to `action` (empty: removed), written in the order entry,
 * step, exit. Entries that are not step actions stay, after them.
 */
export function withStepAction(step: Pick<Element, 'stepActions'>, kind: StepActionKind, action: string): string[] {
  const now = { ...stepActionsOf(step), [kind]: action.trim() };
  const known = KINDS.filter((k) => now[k]).map((k) => `${STEP_ACTION_KEYWORDS[k]} := ${now[k]}`);
  const other = (step.stepActions ?? []).filter((w) => !/^\s*(ENTRY_ACTION|STEP_ACTION|EXIT_ACTION)\s*:=/i.test(w));
  return [...known, ...other];
}

/** Whether a step action can be written: an action's name or `instance.Action` (empty: none). */
export function isStepActionName(v: string): boolean {
  const s = v.trim();
  if (s === '') return true;
  // CODESYS's names with doubled or trailing underscores are read in a CODESYS POU.
  const part = (p: string) => isIecName(p) || /^[A-Za-z_][A-Za-z0-9_]*$/.test(p);
  const parts = s.split('.');
  return parts.length <= 2 && parts.every(part);
}

/** The blocks of `doc` a diagnostic designates by its element's name (step or transition),
 *  for the charts of actions, whose blocks the server does not locate. */
export function blocksNamed(doc: EditorDoc, element: string | null | undefined): string[] {
  if (!element) return [];
  const lower = element.toLowerCase();
  return doc.elements.filter((e) => (e.kind === 'step' || e.kind === 'transition') && e.name && e.name.toLowerCase() === lower).map((e) => e.id);
}
