// Merge conflicts (`sfc merge`, docs/diff.md): a conflicting element is written as ours and its
// POU marked with `{attribute 'sfc.conflict' := 'KIND:NAME$N…their text…'}`, which the editor
// keeps among the document's other attributes. Read here into what the Merge conflicts panel
// lists and frames; `POST /api/resolve` takes a side.
import type { EditorDoc } from '../doc';

/** The attribute marking a conflict (sfc_diff::merge::CONFLICT). */
export const CONFLICT = 'sfc.conflict';

/** Translates a UI key (the app's `t`, passed in so this stays free of i18next). */
export type Translate = (key: string, opts?: Record<string, unknown>) => string;

export interface MergeConflict {
  /** As marked and as `/api/resolve` takes it: `transition:TStart`, `step:Fill`, `decl`, … */
  element: string;
  /** `step`, `transition`, `action`; else the region's key (`decl`, `head`, `@name#0`, …). */
  kind: string;
  /** The element's name (empty for a part of the POU without one). */
  name: string;
  /** Their version of the element, as merged (empty: their side removed it). */
  theirs: string;
}

/** Reads an attribute value written with IEC string escapes (sfc_syntax::attr_value::unescape):
 *  `$$`, `$N`/`$L`, `$R`, `$T` and `$hh`; a `$` not starting one stays. */
export function unescapeIec(v: string): string {
  let out = '';
  for (let i = 0; i < v.length; i++) {
    const c = v[i];
    if (c !== '$') {
      out += c;
      continue;
    }
    const n = v[i + 1] ?? '';
    if (n === '$') out += '$';
    else if ('NnLl'.includes(n) && n !== '') out += '\n';
    else if ('Rr'.includes(n) && n !== '') out += '\r';
    else if ('Tt'.includes(n) && n !== '') out += '\t';
    else {
      const hex = v.slice(i + 1, i + 3);
      const code = /^[0-9A-Fa-f]{2}$/.test(hex) ? parseInt(hex, 16) : -1;
      if (code >= 0 && code < 128) {
        out += String.fromCharCode(code);
        i += 2;
      } else out += '$';
      continue;
    }
    i += 1;
  }
  return out;
}

/** The conflicts the POU's document is marked with, in the order of their marks. */
export function conflictsOf(doc: Pick<EditorDoc, 'attributes'> | null | undefined): MergeConflict[] {
  const out: MergeConflict[] = [];
  for (const a of doc?.attributes ?? []) {
    if (a.name.toLowerCase() !== CONFLICT) continue;
    const v = unescapeIec(a.value ?? '');
    const nl = v.indexOf('\n');
    const element = (nl < 0 ? v : v.slice(0, nl)).trim();
    const theirs = nl < 0 ? '' : v.slice(nl + 1);
    const colon = element.indexOf(':');
    const kind = colon < 0 ? element : element.slice(0, colon).toLowerCase();
    const name = colon < 0 ? '' : element.slice(colon + 1);
    out.push({ element, kind, name, theirs });
  }
  return out;
}

/** The blocks of the chart a conflict concerns: a step or transition by its name, an action by
 *  the action blocks naming it; none for the declarations, the header or an attribute. */
export function conflictBlocks(doc: Pick<EditorDoc, 'elements'>, c: MergeConflict): string[] {
  const lower = c.name.toLowerCase();
  if (!lower) return [];
  if (c.kind === 'step' || c.kind === 'transition') {
    return doc.elements.filter((e) => e.kind === c.kind && (e.name ?? '').toLowerCase() === lower).map((e) => e.id);
  }
  if (c.kind === 'action') {
    return doc.elements
      .filter((e) => e.kind === 'actionBlock' && (e.associations ?? []).some((a) => a.action.toLowerCase() === lower))
      .map((e) => e.id);
  }
  return [];
}

/** Every block framed as a conflict. */
export function conflictIds(doc: Pick<EditorDoc, 'elements' | 'attributes'>): string[] {
  return [...new Set(conflictsOf(doc).flatMap((c) => conflictBlocks(doc, c)))];
}

const NAMED = ['step', 'transition', 'action', 'body'];

/** The conflicting part in the user's language: Step, Transition, Action, Declarations, … */
export function conflictKindLabel(c: MergeConflict, t: Translate): string {
  if (NAMED.includes(c.kind)) return t(`compare.element.${c.kind}`);
  if (c.kind === 'decl') return t('merge.part.declarations');
  if (c.kind === 'head') return t('merge.part.header');
  if (c.kind.startsWith('graph')) return t('merge.part.layout');
  const attr = /^@(.+)#\d+$/.exec(c.kind);
  if (attr) return t('compare.what.attribute', { name: attr[1] });
  if (c.kind.startsWith('transition#')) return t('compare.element.transition');
  return c.kind;
}

/** Their text as shown: without the blank lines around it and the indentation its lines share. */
export function theirText(s: string): string {
  const lines = s.replace(/\r\n?/g, '\n').split('\n');
  while (lines.length > 0 && lines[0].trim() === '') lines.shift();
  while (lines.length > 0 && lines[lines.length - 1].trim() === '') lines.pop();
  const indents = lines.filter((l) => l.trim() !== '').map((l) => /^[ \t]*/.exec(l)![0].length);
  const cut = indents.length > 0 ? Math.min(...indents) : 0;
  return lines.map((l) => l.slice(Math.min(cut, /^[ \t]*/.exec(l)![0].length))).join('\n');
}
