// Syntax colouring for the code editors (declarations, action bodies, transition conditions):
// a lossless tokenizer (the tokens concatenate to the input) and the mapping of diagnostics to
// squiggled ranges of the editor's text.
import type { Diag } from '../api';

export type TokenKind = 'keyword' | 'literal' | 'comment' | 'string' | 'number' | 'pragma' | 'ident' | 'other';

export interface Token {
  kind: TokenKind;
  text: string;
  /** Offset of the token's first character in the input. */
  start: number;
}

const ST_KEYWORDS = [
  'PROGRAM', 'END_PROGRAM', 'FUNCTION_BLOCK', 'END_FUNCTION_BLOCK', 'FUNCTION', 'END_FUNCTION',
  'VAR', 'VAR_INPUT', 'VAR_OUTPUT', 'VAR_IN_OUT', 'VAR_TEMP', 'VAR_EXTERNAL', 'VAR_GLOBAL', 'END_VAR',
  'CONSTANT', 'RETAIN', 'NON_RETAIN', 'AT', 'TYPE', 'END_TYPE', 'STRUCT', 'END_STRUCT', 'ARRAY', 'OF',
  'IF', 'THEN', 'ELSIF', 'ELSE', 'END_IF', 'CASE', 'END_CASE', 'FOR', 'TO', 'BY', 'DO', 'END_FOR',
  'WHILE', 'END_WHILE', 'REPEAT', 'UNTIL', 'END_REPEAT', 'EXIT', 'RETURN', 'CONTINUE',
  'AND', 'OR', 'XOR', 'NOT', 'MOD',
  'STEP', 'INITIAL_STEP', 'END_STEP', 'TRANSITION', 'END_TRANSITION', 'FROM', 'ACTION', 'END_ACTION', 'PRIORITY',
  'BOOL', 'BYTE', 'WORD', 'DWORD', 'LWORD', 'SINT', 'INT', 'DINT', 'LINT', 'USINT', 'UINT', 'UDINT', 'ULINT',
  'REAL', 'LREAL', 'TIME', 'DATE', 'TIME_OF_DAY', 'TOD', 'DATE_AND_TIME', 'DT', 'STRING', 'WSTRING', 'CHAR', 'WCHAR',
];
/** IL operators (also keywords in an IL body or condition). */
const IL_OPERATORS = [
  'LD', 'LDN', 'ST', 'STN', 'S', 'R', 'ANDN', 'ORN', 'XORN', 'ADD', 'SUB', 'MUL', 'DIV', 'GT', 'GE', 'EQ', 'NE',
  'LE', 'LT', 'JMP', 'JMPC', 'JMPCN', 'CAL', 'CALC', 'CALCN', 'RET', 'RETC', 'RETCN', 'AND', 'OR', 'XOR', 'NOT', 'MOD',
];
const ST_SET = new Set(ST_KEYWORDS);
const IL_SET = new Set([...ST_KEYWORDS, ...IL_OPERATORS]);
const LITERAL_WORDS = new Set(['TRUE', 'FALSE']);
/** Prefixes of typed literals: `T#5s`, `TIME#…`, `D#…`, `TOD#…`, `DT#…`, `INT#5`, `16#FF`. */
const TYPED_PREFIX = /^(?:T|TIME|LTIME|D|DATE|TOD|TIME_OF_DAY|DT|DATE_AND_TIME|[A-Z_]+|\d+)#[A-Z0-9_.:+\-#]*/i;

/** Splits `src` into tokens; `lang` chooses whether IL operators count as keywords. */
export function tokenize(src: string, lang: 'ST' | 'IL' = 'ST'): Token[] {
  const keywords = lang === 'IL' ? IL_SET : ST_SET;
  const tokens: Token[] = [];
  let i = 0;
  const push = (kind: TokenKind, end: number) => {
    const last = tokens[tokens.length - 1];
    // Runs of plain characters merge so the overlay has few nodes.
    if (kind === 'other' && last && last.kind === 'other') last.text += src.slice(i, end);
    else tokens.push({ kind, text: src.slice(i, end), start: i });
    i = end;
  };
  while (i < src.length) {
    const c = src[i];
    const rest = src.slice(i);
    if (rest.startsWith('(*')) {
      const close = src.indexOf('*)', i + 2);
      push('comment', close < 0 ? src.length : close + 2);
    } else if (rest.startsWith('//')) {
      const nl = src.indexOf('\n', i);
      push('comment', nl < 0 ? src.length : nl);
    } else if (c === '{') {
      const close = src.indexOf('}', i + 1);
      push('pragma', close < 0 ? src.length : close + 1);
    } else if (c === "'" || c === '"') {
      let j = i + 1;
      while (j < src.length && src[j] !== c && src[j] !== '\n') j += src[j] === '$' ? 2 : 1;
      push('string', Math.min(src.length, j < src.length && src[j] === c ? j + 1 : j));
    } else if (/[A-Za-z_]/.test(c)) {
      const typed = TYPED_PREFIX.exec(rest);
      const word = /^[A-Za-z_][A-Za-z0-9_]*/.exec(rest)![0];
      if (typed && typed[0].length > word.length) {
        push('literal', i + typed[0].length);
      } else {
        const upper = word.toUpperCase();
        push(LITERAL_WORDS.has(upper) ? 'literal' : keywords.has(upper) ? 'keyword' : 'ident', i + word.length);
      }
    } else if (/[0-9]/.test(c)) {
      const based = /^\d+#[0-9A-Fa-f_]+/.exec(rest);
      const num = based ?? /^\d[\d_]*(?:\.\d[\d_]*)?(?:[eE][+-]?\d+)?/.exec(rest)!;
      push(based ? 'literal' : 'number', i + num[0].length);
    } else {
      push('other', i + 1);
    }
  }
  return tokens;
}

/** A piece of the coloured overlay: a token, or a part of one when a squiggle starts or ends in it. */
export interface Segment {
  kind: TokenKind;
  text: string;
  marked: boolean;
}

/** Tokens cut at the edges of `marks` (half-open character ranges), for the overlay. */
export function segments(src: string, lang: 'ST' | 'IL', marks: { start: number; end: number }[]): Segment[] {
  const cuts = new Set<number>();
  for (const m of marks) {
    cuts.add(m.start);
    cuts.add(m.end);
  }
  const inMark = (pos: number) => marks.some((m) => pos >= m.start && pos < m.end);
  const out: Segment[] = [];
  for (const tok of tokenize(src, lang)) {
    let from = 0;
    for (let k = 1; k <= tok.text.length; k++) {
      if (k === tok.text.length || cuts.has(tok.start + k)) {
        out.push({ kind: tok.kind, text: tok.text.slice(from, k), marked: inMark(tok.start + from) });
        from = k;
      }
    }
  }
  return out;
}

/**
 * Where a diagnostic falls in an editor's text. The server reports positions in the whole
 * generated source, which the client does not have, so the span is found by content: the
 * backtick-quoted fragments of the message (`undeclared variable \`Foo\``) are searched in the
 * text as whole words, preferring one as long as the reported span; the squiggle covers that
 * occurrence. Returns null when nothing in the message can be found.
 */
export function locateInText(text: string, diag: Pick<Diag, 'message' | 'line' | 'column' | 'endLine' | 'endColumn'>): { start: number; end: number } | null {
  const quoted = [...diag.message.matchAll(/`([^`]+)`/g)].map((m) => m[1]).filter((q) => q.trim() !== '');
  if (quoted.length === 0) return null;
  const spanLength = diag.endLine === diag.line ? diag.endColumn - diag.column : -1;
  const ordered = [...quoted].sort((a, b) => Number(b.length === spanLength) - Number(a.length === spanLength));
  const lower = text.toLowerCase();
  for (const q of ordered) {
    const needle = q.toLowerCase();
    let from = 0;
    while (from <= lower.length) {
      const at = lower.indexOf(needle, from);
      if (at < 0) break;
      const before = at === 0 ? '' : lower[at - 1];
      const after = lower[at + needle.length] ?? '';
      const wordy = /\w/.test(needle[0]) && /\w/.test(needle[needle.length - 1]);
      if (!wordy || (!/\w/.test(before) && !/\w/.test(after))) return { start: at, end: at + needle.length };
      from = at + 1;
    }
  }
  return null;
}
