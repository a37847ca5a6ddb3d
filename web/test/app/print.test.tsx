// Print…: the legend lists every transition with its whole condition, cut into pages by the
// lines its rows take; the chart is printed without the highlights' marks unless asked for.
import { render } from 'preact';
import { act } from 'preact/test-utils';
import { afterEach, beforeEach, describe, expect, it } from 'vitest';
import { legendRows } from '../../src/app/chart';
import { PrintDialog } from '../../src/app/PrintDialog';
import { DEFAULT_SETUP, LEGEND_CHARS, legendPages, legendRowLines } from '../../src/app/print';
import type { EditorDoc } from '../../src/doc';
import { initI18n, setLanguage } from '../../src/i18n';
import mixer from './fixtures/mixer.doc.json';

const LONG = 'Brushing.T >= MaxBrushTime AND NOT CarLeft AND NOT StopButton AND NOT Reset AND NOT Fault AND Ready';
const row = (name: string, condition = '', description = '') => ({ name, condition, description });

describe('print legend', () => {
  it('counts the lines of a row by its tallest cell', () => {
    expect(legendRowLines(row('S1'))).toBe(1);
    expect(legendRowLines(row('T1', 'a AND b'))).toBe(1);
    expect(legendRowLines(row('T2', LONG))).toBe(Math.ceil(LONG.length / LEGEND_CHARS));
    expect(legendRowLines(row('T3', 'LD a\nAND b\nST c', 'x'))).toBe(3);
  });

  it('cuts the rows into pages by their lines, a tall row alone, one empty page for none', () => {
    expect(legendPages([])).toEqual([[]]);
    const short = Array.from({ length: 30 }, (_, k) => row(`S${k}`));
    expect(legendPages(short).map((p) => p.length)).toEqual([28, 2]);
    const tall = row('T', Array.from({ length: 40 }, () => 'a AND b').join('\n'));
    expect(legendPages([row('A'), tall, row('B')], 28).map((p) => p.map((r) => r.name))).toEqual([['A'], ['T'], ['B']]);
  });

  it('prints no marks by default', () => {
    expect(DEFAULT_SETUP.marks).toBe(false);
  });
});

describe('PrintDialog', () => {
  let host: HTMLElement;
  beforeEach(() => {
    initI18n('en');
    setLanguage('en');
    host = document.createElement('div');
    document.body.appendChild(host);
  });
  afterEach(() => {
    render(null, host);
    host.remove();
  });

  it('lists every transition with its whole condition, and draws the marks only when asked', async () => {
    const doc = mixer as EditorDoc;
    const withLong: EditorDoc = {
      ...doc,
      elements: doc.elements.map((e) => (e.id === 'transition:T1' ? { ...e, condition: LONG } : e)),
    };
    const asked: boolean[] = [];
    const svg = (marks: boolean) => {
      asked.push(marks);
      return `<svg xmlns="http://www.w3.org/2000/svg" width="600" height="400"><text>${marks ? 'marked' : 'plain'}</text></svg>`;
    };
    await act(() => render(<PrintDialog svg={svg} doc={withLong} path="/w/mixer.st" onClose={() => {}} />, host));
    const cells = [...host.querySelectorAll('table.legend tbody tr')].map((tr) => [...tr.querySelectorAll('td')].map((td) => td.textContent));
    expect(cells.length).toBe(legendRows(withLong).length);
    const t1 = cells.find((c) => c[1] === 'T1')!;
    expect(t1[3]).toBe(LONG);
    for (const e of withLong.elements.filter((x) => x.kind === 'transition')) {
      expect(cells.some((c) => c[0] === 'Transition' && c[3] === (e.condition ?? '').trim())).toBe(true);
    }
    const img = () => decodeURIComponent(host.querySelector<HTMLImageElement>('.print-area img')!.getAttribute('src')!);
    expect(asked).toEqual([false]);
    expect(img()).toContain('plain');
    const marks = host.querySelector<HTMLInputElement>('input[name="print-marks"]')!;
    expect(marks.checked).toBe(false);
    await act(() => marks.click());
    expect(asked).toEqual([false, true]);
    expect(img()).toContain('marked');
  });
});
