// File → Compare with saved / Compare with git HEAD: the answer of `POST /api/compare` turned
// into what the page shows: the blocks to colour on the canvas (added green, renamed or changed
// orange; a removed element has no block) and one line per change for the Comparison panel.
import type { CompareChange, CompareResult } from '../api';

/** Translates a UI key (the app's `t`, passed in so this stays free of i18next). */
export type Translate = (key: string, opts?: Record<string, unknown>) => string;

/** The blocks of the current chart to colour: added ones, and renamed or changed ones. A block
 *  both added and changed (a new step whose actions the diff also lists) is coloured added. */
export function compareColours(r: CompareResult): { added: string[]; changed: string[] } {
  const added = new Set<string>();
  const changed = new Set<string>();
  for (const c of r.changes) {
    for (const id of c.elementIds) (c.kind === 'added' ? added : changed).add(id);
  }
  for (const id of added) changed.delete(id);
  return { added: [...added], changed: [...changed] };
}

/** One row of the panel: every change the page can show on the canvas first, in the server's
 *  order, then the removed elements (no block). */
export interface ChangeRow {
  change: CompareChange;
  /** `+`, `~` or `−`. */
  mark: string;
  /** The name shown: the new name of a renamed element. */
  name: string;
  /** Whether a click can select blocks of the chart. */
  onCanvas: boolean;
}

const MARK: Record<CompareChange['kind'], string> = { added: '+', removed: '−', renamed: '~', changed: '~' };

export function changeRows(r: CompareResult): ChangeRow[] {
  return [...r.changes, ...r.removed].map((c) => ({
    change: c,
    mark: MARK[c.kind],
    name: c.kind === 'renamed' && c.new ? c.new : c.name,
    onCanvas: c.kind !== 'removed' && c.elementIds.length > 0,
  }));
}

const ELEMENTS = ['pou', 'variable', 'step', 'transition', 'action', 'body'];
const WHAT: Record<string, string> = {
  condition: 'condition',
  steps: 'steps',
  priority: 'priority',
  actions: 'actions',
  initial: 'initial',
  type: 'type',
  kind: 'kind',
  'initial value': 'initialValue',
  body: 'body',
  statements: 'statements',
  language: 'language',
};

/** The element's kind in the user's language (`step` → Step / Krok / Schritt). */
export function elementLabel(element: string, t: Translate): string {
  return ELEMENTS.includes(element) ? t(`compare.element.${element}`) : element;
}

/** What changed in the user's language; an attribute keeps its name (`sfc.timeout`). */
export function whatLabel(what: string, t: Translate): string {
  if (what.startsWith('attribute ')) return t('compare.what.attribute', { name: what.slice('attribute '.length) });
  const key = WHAT[what];
  return key ? t(`compare.what.${key}`) : what;
}

/** The text of a change after its element and name: `renamed Stirring`, `condition: a → a AND b`,
 *  `(FROM A TO B)` for an added transition. */
export function changeDetail(c: CompareChange, t: Translate): string {
  const none = t('compare.none');
  switch (c.kind) {
    case 'added':
      return c.new ? `${t('compare.kind.added')} (${c.new})` : t('compare.kind.added');
    case 'removed':
      return c.old ? `${t('compare.kind.removed')} (${c.old})` : t('compare.kind.removed');
    case 'renamed':
      return t('compare.renamedTo', { name: c.new ?? '' });
    case 'changed':
      return `${whatLabel(c.what, t)}: ${oneLine(c.old) || none} → ${oneLine(c.new) || none}`;
  }
}

/** Statements on one line (a body changed is shown whole in the tooltip). */
function oneLine(s: string | null): string {
  return (s ?? '').split('\n').map((l) => l.trim()).filter(Boolean).join(' ');
}

/** The counts the panel's toolbar shows. */
export function compareCounts(r: CompareResult): { added: number; changed: number; removed: number } {
  return {
    added: r.changes.filter((c) => c.kind === 'added').length,
    changed: r.changes.filter((c) => c.kind !== 'added').length,
    removed: r.removed.length,
  };
}
