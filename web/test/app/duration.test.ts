import { describe, expect, it } from 'vitest';
import { formatSeconds, parseDuration, secondsToLiteral } from '../../src/app/duration';
import { normaliseTimeout } from '../../src/app/Properties';
import table from './fixtures/durations.txt?raw';

const cases = table
  .split('\n')
  .filter((l) => l.trim() !== '' && !l.startsWith('#'))
  .map((l) => l.split(' => ').map((s) => s.trim()) as [string, string]);

describe('IEC duration literals (fixtures/durations.txt)', () => {
  it('has cases', () => expect(cases.length).toBeGreaterThan(10));
  for (const [literal, expected] of cases) {
    it(`${literal} => ${expected}`, () => {
      const r = parseDuration(literal);
      if (/^-?\d+$/.test(expected)) expect(r).toEqual({ ok: true, micros: Number(expected) });
      else expect(r.ok ? 'ok' : r.error).toBe(expected);
    });
  }
});

describe('timeouts', () => {
  it('writes seconds the way the ATMT timeout vector does', () => {
    expect(formatSeconds(8_100_000)).toBe('8.1');
    expect(formatSeconds(500_000)).toBe('0.5');
    expect(formatSeconds(2_000_000)).toBe('2');
    expect(secondsToLiteral(8.1)).toBe('T#8.1s');
  });
  it('accepts seconds as the seed writes them, IEC literals, and rejects the rest', () => {
    expect(normaliseTimeout('8.1')).toEqual({ value: 'T#8.1s' });
    expect(normaliseTimeout(' T#2s ')).toEqual({ value: 'T#2s' });
    expect(normaliseTimeout('')).toEqual({});
    expect(normaliseTimeout('T#-1s')).toEqual({ error: 'duration.negative' });
    expect(normaliseTimeout('T#1s2m')).toEqual({ error: 'duration.order' });
    expect(normaliseTimeout('soon')).toEqual({ error: 'duration.prefix' });
  });
});
