import { describe, expect, it } from 'vitest';
import { locateInText, segments, tokenize } from '../../src/app/highlight';

const kinds = (src: string, lang: 'ST' | 'IL' = 'ST') => tokenize(src, lang).filter((t) => t.kind !== 'other').map((t) => [t.kind, t.text]);

describe('tokenizer', () => {
  it('is lossless', () => {
    for (const src of [
      'VAR\n  x : INT := 16#FF; (* hex *)\nEND_VAR',
      "IF a AND NOT b THEN s := 'it''s $N'; END_IF // tail",
      'LD TRUE\nANDN x\nST y',
      '(* unterminated',
      '"wide',
      '{attribute \'sfc.tag\' := \'0\'}',
      'T#5d14h12m18s3.5ms + TIME#1s - x',
      '',
    ]) {
      expect(tokenize(src).map((t) => t.text).join('')).toBe(src);
      expect(tokenize(src, 'IL').map((t) => t.text).join('')).toBe(src);
    }
  });
  it('tells keywords, literals, numbers, strings and comments apart', () => {
    expect(kinds("IF x > 10 THEN y := T#2.5s; s := 'a'; END_IF (* c *) // d")).toEqual([
      ['keyword', 'IF'],
      ['ident', 'x'],
      ['number', '10'],
      ['keyword', 'THEN'],
      ['ident', 'y'],
      ['literal', 'T#2.5s'],
      ['ident', 's'],
      ['string', "'a'"],
      ['keyword', 'END_IF'],
      ['comment', '(* c *)'],
      ['comment', '// d'],
    ]);
  });
  it('colours typed and based literals, TRUE/FALSE, and IL operators only in IL', () => {
    expect(kinds('INT#5 16#E5 2#1010 TRUE false 1.5e3')).toEqual([
      ['literal', 'INT#5'],
      ['literal', '16#E5'],
      ['literal', '2#1010'],
      ['literal', 'TRUE'],
      ['literal', 'false'],
      ['number', '1.5e3'],
    ]);
    expect(kinds('LD x', 'ST')[0]).toEqual(['ident', 'LD']);
    expect(kinds('LD x', 'IL')[0]).toEqual(['keyword', 'LD']);
  });
  it('keeps positions', () => {
    const toks = tokenize('a := b;');
    for (const t of toks) expect('a := b;'.slice(t.start, t.start + t.text.length)).toBe(t.text);
  });
});

describe('squiggles', () => {
  it('cuts tokens at the marked range', () => {
    const segs = segments('Level := Levl + 1;', 'ST', [{ start: 9, end: 13 }]);
    expect(segs.map((s) => s.text).join('')).toBe('Level := Levl + 1;');
    expect(segs.filter((s) => s.marked).map((s) => s.text)).toEqual(['Levl']);
  });
  it('finds a diagnostic by the quoted name in its message, as a whole word', () => {
    const d = { message: 'undeclared variable `Levl`', line: 30, column: 14, endLine: 30, endColumn: 18 };
    expect(locateInText('Levl2 := Levl + 1;', d)).toEqual({ start: 9, end: 13 });
    expect(locateInText('x := 1;', d)).toBeNull();
    expect(locateInText('x := 1;', { ...d, message: 'syntax error' })).toBeNull();
  });
  it('prefers the quoted fragment as long as the reported span', () => {
    const d = { message: 'type mismatch: `Lvl` is INT, `Start` is BOOL', line: 1, column: 5, endLine: 1, endColumn: 10 };
    expect(locateInText('Lvl AND Start', d)).toEqual({ start: 8, end: 13 });
    expect(locateInText('Lvl AND Start', { ...d, endColumn: 8 })).toEqual({ start: 0, end: 3 });
  });
});
