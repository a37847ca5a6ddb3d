// The build result as the Result panel shows it: the REX ATMT/EATMT transition table (seed 001
// fig. 21), parsed from the one-line form `N[s c n;…][t0 … tM-1]` of interfaces.md, and the
// download file names per target.
import type { BuildTarget, TableRule } from '../api';
import { IEC_BUILDS, type ChartKind } from './chartKind';

export interface TransitionTable {
  rules: TableRule[];
  /** Seconds per state, `0` = no timeout. */
  timeouts: number[];
}

/** Parses `N[s c n;…][t0 … tM-1]`; throws an Error naming the offending part. */
export function parseTable(line: string): TransitionTable {
  const m = /^\s*(\d+)\[([^\]]*)\]\[([^\]]*)\]\s*$/.exec(line);
  if (!m) throw new Error(`not a transition table: expected N[s c n;…][t0 …], got "${line.slice(0, 40)}"`);
  const count = Number(m[1]);
  const ruleTexts = m[2].trim() === '' ? [] : m[2].split(';');
  const rules = ruleTexts.map((r, k) => {
    const parts = r.trim().split(' ');
    if (parts.length !== 3 || parts.some((p) => !/^\d+$/.test(p))) {
      throw new Error(`rule ${k}: expected "state condition next", got "${r}"`);
    }
    const [state, condition, next] = parts.map(Number);
    return { state, condition, next };
  });
  if (rules.length !== count) throw new Error(`the table announces ${count} rules but holds ${rules.length}`);
  const timeouts = m[3].trim() === '' ? [] : m[3].trim().split(' ').map((t, k) => {
    if (!/^\d+(\.\d+)?$/.test(t)) throw new Error(`timeout ${k}: "${t}" is not a number of seconds`);
    return Number(t);
  });
  return { rules, timeouts };
}

/** The one-line form, exactly as `sfc build --target atmt` writes it. */
export function formatTable(table: TransitionTable): string {
  const rules = table.rules.map((r) => `${r.state} ${r.condition} ${r.next}`).join(';');
  return `${table.rules.length}[${rules}][${table.timeouts.map((t) => String(t)).join(' ')}]`;
}

/** A condition index as the block's input: ATMT `C3`, EATMT `c3`, negated (EATMT, 1000+i) `!c3`. */
export function conditionLabel(condition: number, fb: 'atmt' | 'eatmt'): string {
  const prefix = fb === 'atmt' ? 'C' : 'c';
  return condition >= 1000 ? `!${prefix}${condition - 1000}` : `${prefix}${condition}`;
}

/** Rows of the Result panel's two tables. */
export function tableRows(table: TransitionTable): { rules: string[][]; timeouts: string[][] } {
  return {
    rules: table.rules.map((r, k) => [String(k), String(r.state), String(r.condition), String(r.next)]),
    timeouts: table.timeouts.map((t, k) => [String(k), String(t)]),
  };
}

const EXTENSIONS: Record<BuildTarget, string> = {
  atmt: '.atmt.txt',
  eatmt: '.eatmt.txt',
  st: '.st',
  stl: '.stl.txt',
  plcopen: '.xml',
  svg: '.svg',
  text: '.st',
};

const MIME: Record<BuildTarget, string> = {
  atmt: 'text/plain',
  eatmt: 'text/plain',
  st: 'text/plain',
  stl: 'text/plain',
  plcopen: 'application/xml',
  svg: 'image/svg+xml',
  text: 'text/plain',
};

/** Download name of a build result: `POU.atmt.txt`, `POU.st`, `POU.stl.txt`, `POU.xml`, `POU.svg`. */
export function resultFileName(pou: string, target: BuildTarget): string {
  return (pou.replace(/[^\w.-]+/g, '_') || 'chart') + EXTENSIONS[target];
}

export function resultMime(target: BuildTarget): string {
  return MIME[target];
}

/** Build targets offered for a chart: its table for ATMT/EATMT charts, the generators for Blank and IEC ones. */
export function targetsFor(chart: ChartKind): BuildTarget[] {
  return chart === 'blank' || chart === 'iec' ? [...IEC_BUILDS] : [chart];
}
