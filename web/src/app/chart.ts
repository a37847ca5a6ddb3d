// Read-only questions about an editor document: the legend of the print dialog, the steps a
// transition leaves and enters (for stepping through an analysis witness), and names for the
// Properties panel.
import type { EditorDoc, Element, ElementKind } from '../doc';

export interface LegendRow {
  id: string;
  kind: ElementKind;
  name: string;
  tag: string;
  /** A transition's condition, whole, with its line breaks (the drawing wraps it). */
  condition: string;
  description: string;
}

const KIND_ORDER: ElementKind[] = [
  'step',
  'transition',
  'selectionDivergence',
  'selectionConvergence',
  'simultaneousDivergence',
  'simultaneousConvergence',
  'jump',
  'actionBlock',
  'text',
];

/** What identifies a block in the legend: its name, else what it shows. */
export function blockLabel(e: Element, doc: EditorDoc): string {
  switch (e.kind) {
    case 'step':
      return e.name ?? '';
    case 'transition':
      return e.name || (e.condition ?? '').trim();
    case 'jump':
      return e.target ? `→ ${e.target}` : '';
    case 'text':
      return (e.text ?? '').split('\n')[0];
    case 'actionBlock': {
      const step = doc.elements.find((s) => s.id === e.step);
      const rows = (e.associations ?? []).map((a) => `${a.qualifier} ${a.action}`).join(', ');
      return step?.name ? `${step.name}: ${rows}` : rows;
    }
    default:
      return e.name ?? '';
  }
}

/** Every block of the chart, grouped by kind (steps first), then by tag and name; every
 *  transition with its whole condition. */
export function legendRows(doc: EditorDoc): LegendRow[] {
  const rows = doc.elements.map((e) => ({
    id: e.id,
    kind: e.kind,
    // A transition's condition has a column of its own.
    name: e.kind === 'transition' ? (e.name ?? '') : blockLabel(e, doc),
    tag: e.tag === undefined || e.tag === null ? '' : String(e.tag),
    condition: e.kind === 'transition' ? conditionText(e.condition) : '',
    description: e.description ?? '',
    order: KIND_ORDER.indexOf(e.kind),
  }));
  rows.sort(
    (a, b) =>
      a.order - b.order ||
      (a.tag === '' ? Infinity : Number(a.tag)) - (b.tag === '' ? Infinity : Number(b.tag)) ||
      a.name.localeCompare(b.name),
  );
  return rows.map(({ order: _order, ...row }) => row);
}

/** A condition as the legend prints it: whole, its lines trimmed, blank lines left out. */
function conditionText(c: string | undefined): string {
  return (c ?? '')
    .split('\n')
    .map((l) => l.trim())
    .filter((l) => l !== '')
    .join('\n');
}

function byId(doc: EditorDoc): Map<string, Element> {
  return new Map(doc.elements.map((e) => [e.id, e]));
}

/** Steps reached by walking from `start` along connections in one direction, through branches and jumps. */
function walk(doc: EditorDoc, start: string, forward: boolean): string[] {
  const elements = byId(doc);
  const found: string[] = [];
  const seen = new Set<string>();
  const next = (id: string) =>
    doc.connections.filter((c) => (forward ? c.source === id : c.target === id)).map((c) => (forward ? c.target : c.source));
  const queue = next(start);
  while (queue.length > 0) {
    const id = queue.shift()!;
    if (seen.has(id)) continue;
    seen.add(id);
    const e = elements.get(id);
    if (!e) continue;
    if (e.kind === 'step') found.push(id);
    else if (e.kind === 'jump' && forward) {
      const target = doc.elements.find((s) => s.kind === 'step' && s.name !== undefined && s.name.toLowerCase() === (e.target ?? '').toLowerCase());
      if (target) found.push(target.id);
    } else if (e.kind !== 'transition') queue.push(...next(id));
  }
  return found;
}

/** Steps a transition deactivates when it fires. */
export function stepsBefore(doc: EditorDoc, transition: string): string[] {
  return walk(doc, transition, false);
}

/** Steps a transition activates when it fires. */
export function stepsAfter(doc: EditorDoc, transition: string): string[] {
  return walk(doc, transition, true);
}

/**
 * The active steps after each firing of a witness (`witnessIds`, transition ids in firing order),
 * starting from the initial steps: entry k holds the steps active after firing k + 1 transitions.
 */
export function witnessSituations(doc: EditorDoc, witnessIds: string[]): string[][] {
  let active = new Set(doc.elements.filter((e) => e.kind === 'step' && e.initial).map((e) => e.id));
  return witnessIds.map((t) => {
    const leaving = new Set(stepsBefore(doc, t));
    active = new Set([...active].filter((s) => !leaving.has(s)));
    for (const s of stepsAfter(doc, t)) active.add(s);
    return [...active];
  });
}

/** The chart's steps as `[id, name]`, named ones only, for the jump target select. */
export function stepNames(doc: EditorDoc): string[] {
  return doc.elements
    .filter((e) => e.kind === 'step' && e.name)
    .map((e) => e.name!)
    .sort((a, b) => a.localeCompare(b));
}

/** A valid IEC name for a new POU or action (`[A-Za-z_][A-Za-z0-9_]*`, no double underscore). */
export function isIecName(name: string): boolean {
  return /^[A-Za-z_][A-Za-z0-9_]*$/.test(name) && !name.includes('__') && !(name.length > 1 && name.endsWith('_'));
}

/** A name not yet used by any step, action or transition of the chart (`Action1`, `Action2`, …). */
export function freshName(doc: EditorDoc, base: string): string {
  const used = new Set([
    ...doc.actions.map((a) => a.name.toLowerCase()),
    ...doc.elements.filter((e) => e.name).map((e) => e.name!.toLowerCase()),
  ]);
  for (let k = 1; ; k++) {
    if (!used.has(`${base}${k}`.toLowerCase())) return `${base}${k}`;
  }
}
