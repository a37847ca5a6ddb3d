// How the canvas draws a block's texts, mirrored from crates/sfc-doc/src/drawing.rs (the layout
// keeps exactly these places clear): block sizes that fit their text, action block columns, a
// transition's condition lines right of its bar and its name left of it, a jump's target right
// of its arrow. Widths are estimated from the characters (DejaVu Sans advances, the canvas's
// first font), never measured, so the server's layout and the canvas agree.
import type { Association, Element } from '../doc';

/** Advance widths of DejaVu Sans for ' '..'~' in font units (2048 per em), as sfc-render's. */
const ADVANCE = [
  651, 821, 942, 1716, 1303, 1946, 1597, 563, 799, 799, 1024, 1716, 651, 739, 651, 690, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 690, 690,
  1716, 1716, 1716, 1087, 2048, 1401, 1405, 1430, 1577, 1294, 1178, 1587, 1540, 604, 604, 1343, 1141, 1767, 1532, 1612, 1235, 1612, 1423, 1300, 1251, 1499,
  1401, 2025, 1403, 1251, 1403, 799, 690, 799, 1716, 1024, 1024, 1255, 1300, 1126, 1300, 1260, 721, 1300, 1298, 569, 569, 1186, 569, 1995, 1298, 1253, 1300,
  1300, 842, 1067, 803, 1298, 1212, 1675, 1212, 1212, 1075, 1303, 690, 1303, 1716,
];

export const FONT_SIZE = 12;
export const LINE_H = 14;
/** One character of the monospaced condition font (DejaVu Sans Mono: 1233/2048 em). */
export const MONO_ADVANCE = (FONT_SIZE * 1233) / 2048;
export const BOLD = 1.2;
export const CONDITION_CHARS = 32;
export const BAR_HALF = 14;
export const LABEL_GAP = 6;
export const ROW_H = 24;

/** Estimated advance of `s` in DejaVu Sans at `size` px (sfc-render's `text_width`). */
export function textWidth(s: string, size: number): number {
  let units = 0;
  for (const ch of s) {
    const c = ch.codePointAt(0)!;
    if (c >= 0x20 && c <= 0x7e) units += ADVANCE[c - 0x20];
    else if (c >= 0xa0 && c <= 0x24f) units += 1400;
    else units += 2048;
  }
  return (units * size) / 2048;
}

/** `name : tag` (seed 001: the name before the tag, separated by a colon). */
export function nameWithTag(e: Pick<Element, 'name' | 'tag'>): string {
  const name = e.name ?? '';
  if (e.tag === undefined || e.tag === null) return name;
  return name ? `${name} : ${e.tag}` : `: ${e.tag}`;
}

const ceilTo = (v: number, step: number) => Math.ceil(v / step) * step;

/** A step box wide enough for its bold name with tag and its timeout line (sfc-doc's `step_size`). */
export function stepSize(e: Pick<Element, 'name' | 'tag' | 'timeout' | 'initial'>): { w: number; h: number } {
  const name = textWidth(nameWithTag(e), FONT_SIZE) * BOLD;
  const timeout = e.timeout ? textWidth(e.timeout, 10) : 0;
  const inner = Math.max(name, timeout) + (e.initial ? 28 : 22);
  return { w: Math.max(80, ceilTo(inner, 20)), h: 40 };
}

/** A pragma value as written (IEC string escapes `$$ $27 $N $R $T $7D`) read back. */
export function unescapePragma(v: string): string {
  const map: Record<string, string> = { $: '$', '27': "'", N: '\n', R: '\r', T: '\t', '7D': '}', '7d': '}' };
  return v.replace(/\$(\$|27|7D|7d|N|R|T|n|r|t)/g, (_, k: string) => map[k] ?? map[k.toUpperCase()] ?? `$${k}`);
}

/** The side of a step mark's box (S7-GRAPH's interlock `C`, supervision `V`). */
export const MARK = 14;

/**
 * The S7-GRAPH conditions drawn on a step's left side, as S7-GRAPH shows them: `C` for the
 * interlock (`sfc.s7graph.interlock`), `V` for the supervision (`sfc.s7graph.supervision`), each
 * with its condition for the tooltip (the same as sfc-doc's `step_marks`).
 */
export function stepMarks(e: Pick<Element, 'attributes'>): { mark: 'C' | 'V'; condition: string }[] {
  const out: { mark: 'C' | 'V'; condition: string }[] = [];
  for (const [mark, name] of [['C', 'sfc.s7graph.interlock'], ['V', 'sfc.s7graph.supervision']] as const) {
    const a = [...(e.attributes ?? [])].reverse().find((x) => x.name.toLowerCase() === name);
    if (a) out.push({ mark, condition: unescapePragma(a.value ?? '') });
  }
  return out;
}

export function qualifierText(a: Association): string {
  return a.duration ? `${a.qualifier}, ${a.duration}` : a.qualifier;
}

/** Qualifier, action and indicator column widths (sfc-doc's `action_columns`). */
export function actionColumns(rows: Association[]): { q: number; a: number; i: number } {
  let q = 28;
  let a = 60;
  let i = 0;
  const hasInd = rows.some((r) => !!r.indicator);
  if (hasInd) i = 36;
  for (const r of rows) {
    q = Math.max(q, textWidth(qualifierText(r), FONT_SIZE) * BOLD + 12);
    a = Math.max(a, textWidth(r.action, FONT_SIZE) + 12);
    if (hasInd) i = Math.max(i, textWidth(r.indicator ?? '', FONT_SIZE) + 12);
  }
  return { q: Math.ceil(q), a: Math.ceil(a), i: Math.ceil(i) };
}

/** An action block holding its rows (sfc-doc's `action_block_size`). */
export function actionBlockSize(rows: Association[]): { w: number; h: number } {
  const c = actionColumns(rows);
  return { w: Math.max(100, ceilTo(c.q + c.a + c.i, 10)), h: ROW_H * Math.max(1, rows.length) };
}

/**
 * One line of a condition as lines of whole words of at most `max` characters (greedy; runs of
 * white space become one space); a longer word stands whole on a line of its own. A line that
 * fits is kept as written (sfc-doc's `wrap_condition`).
 */
export function wrapCondition(line: string, max = CONDITION_CHARS): string[] {
  if ([...line].length <= max) return [line];
  const out: string[] = [];
  let cur = '';
  for (const word of line.split(/\s+/).filter(Boolean)) {
    if (cur !== '' && [...cur].length + 1 + [...word].length > max) {
      out.push(cur);
      cur = word;
    } else {
      cur = cur === '' ? word : `${cur} ${word}`;
    }
  }
  if (cur !== '') out.push(cur);
  return out;
}

/**
 * The condition as printed beside the bar: every line of it, each wrapped (`wrapCondition`).
 * Never cut: the label is as tall as its lines. The same rule as sfc-doc's `condition_lines`,
 * on the shared cases of crates/sfc-doc/tests/shared/condition_lines.json.
 */
export function conditionLines(e: Pick<Element, 'condition'>): string[] {
  const c = e.condition?.trim();
  if (!c) return [];
  return c
    .split('\n')
    .map((l) => l.trim())
    .filter((l) => l !== '')
    .flatMap((l) => wrapCondition(l));
}

export interface LabelBox {
  kind: 'condition' | 'name' | 'jump';
  lines: string[];
  x: number;
  y: number;
  width: number;
  height: number;
}

/** Where the labels of a block go, in the block's own coordinates (sfc-doc's `labels_of`). */
export function labelsOf(e: Element, w: number, h: number): LabelBox[] {
  if (e.hideLabel) return [];
  if (e.kind === 'transition') {
    const cx = w / 2;
    const cy = h / 2;
    const lines = conditionLines(e);
    const name = nameWithTag(e);
    const out: LabelBox[] = [];
    if (lines.length > 0) {
      const width = Math.max(...lines.map((l) => [...l].length * MONO_ADVANCE));
      const height = LINE_H * lines.length;
      out.push({ kind: 'condition', lines, x: cx + BAR_HALF + LABEL_GAP, y: cy - height / 2, width, height });
      if (name) {
        const nw = textWidth(name, FONT_SIZE);
        out.push({ kind: 'name', lines: [name], x: cx - BAR_HALF - LABEL_GAP - nw, y: cy - LINE_H / 2, width: nw, height: LINE_H });
      }
    } else if (name) {
      out.push({ kind: 'name', lines: [name], x: cx + BAR_HALF + LABEL_GAP, y: cy - LINE_H / 2, width: textWidth(name, FONT_SIZE), height: LINE_H });
    }
    return out;
  }
  if (e.kind === 'jump') {
    const target = e.target ?? '?';
    return [{ kind: 'jump', lines: [target], x: w + 8, y: h * 0.62 - LINE_H / 2, width: textWidth(target, FONT_SIZE) * BOLD, height: LINE_H }];
  }
  return [];
}
