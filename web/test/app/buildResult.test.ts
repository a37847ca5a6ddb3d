import { describe, expect, it } from 'vitest';
import { conditionLabel, formatTable, parseTable, resultFileName, tableRows, targetsFor } from '../../src/app/buildResult';
import fixture from './fixtures/tables.txt?raw';

const cases = fixture
  .split('\n')
  .filter((l) => l.trim() !== '' && !l.startsWith('#'))
  .map((l) => l.split(' => ') as [string, string]);

describe('transition table (fixtures/tables.txt)', () => {
  for (const [line, expected] of cases) {
    it(line, () => {
      if (expected.startsWith('error: ')) {
        expect(() => parseTable(line)).toThrow(expected.slice('error: '.length));
        return;
      }
      const table = parseTable(line);
      const [rules, timeouts] = expected.split('|').map((s) => s.trim());
      expect(table.rules.map((r) => `${r.state} ${r.condition} ${r.next}`).join(';')).toBe(rules);
      expect(table.timeouts.join(' ')).toBe(timeouts);
      // Formatting gives back the server's line byte for byte.
      expect(formatTable(table)).toBe(line);
    });
  }
});

describe('result view', () => {
  it('numbers the rows like seed 001 fig. 21', () => {
    const rows = tableRows(parseTable('3[0 0 1;1 1 2;2 2 1][8.1 2 1]'));
    expect(rows.rules).toEqual([
      ['0', '0', '0', '1'],
      ['1', '1', '1', '2'],
      ['2', '2', '2', '1'],
    ]);
    expect(rows.timeouts).toEqual([
      ['0', '8.1'],
      ['1', '2'],
      ['2', '1'],
    ]);
  });
  it('names inputs and result files', () => {
    expect(conditionLabel(3, 'atmt')).toBe('C3');
    expect(conditionLabel(1005, 'eatmt')).toBe('!c5');
    expect(resultFileName('Mixer', 'atmt')).toBe('Mixer.atmt.txt');
    expect(resultFileName('Mixer', 'st')).toBe('Mixer.st');
    expect(resultFileName('Mixer', 'stl')).toBe('Mixer.stl.txt');
    expect(resultFileName('Mixer', 'plcopen')).toBe('Mixer.xml');
    expect(resultFileName('Mixer', 'svg')).toBe('Mixer.svg');
    expect(resultFileName('a/b c', 'svg')).toBe('a_b_c.svg');
  });
  it('offers the table for ATMT/EATMT charts and the generators for blank ones', () => {
    expect(targetsFor('atmt')).toEqual(['atmt']);
    expect(targetsFor('eatmt')).toEqual(['eatmt']);
    expect(targetsFor('blank')).toEqual(['st', 'stl', 'plcopen', 'text', 'svg']);
  });
});
