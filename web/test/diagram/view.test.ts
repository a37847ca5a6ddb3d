// Highlights, zoom and grid, the SVG export.
import { describe, expect, it } from 'vitest';
import { mount } from './harness';
import { conveyorDoc } from './fixtures';
import { makeBigDoc } from './big';
import { CONDITION_CHARS, conditionLines, LINE_H, labelsOf, wrapCondition } from '../../src/diagram/drawing';

describe('highlights', () => {
  it('frames blocks by kind, labels them, and replaces the set of a kind', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const gfx = (id: string) => m.get('elementRegistry').getGraphics(id) as Element;
    const strokes = (id: string) => [...gfx(id).querySelectorAll('rect')].map((r) => r.getAttribute('stroke'));
    m.canvas.highlight('active', ['step:Run', 'step:A'], { 'step:Run': '3.4 s' });
    expect(strokes('step:Run')).toContain('#16a34a');
    expect(gfx('step:Run').textContent).toContain('3.4 s');
    m.canvas.highlight('active', ['step:B']);
    expect(strokes('step:Run')).not.toContain('#16a34a');
    expect(strokes('step:B')).toContain('#16a34a');
    m.canvas.highlight('error', ['step:B']);
    m.canvas.highlight('warning', ['b4']);
    m.canvas.highlight('hit', ['step:A']);
    m.canvas.highlight('witness', ['transition:Go']);
    m.canvas.highlight('enabled', ['transition:Box']);
    m.canvas.highlight('breakpoint', ['transition#3']);
    expect(strokes('step:B')).toEqual(expect.arrayContaining(['#dc2626', '#16a34a']));
    expect([...gfx('b4').querySelectorAll('rect')].some((r) => r.getAttribute('stroke-dasharray'))).toBe(true);
    expect(strokes('step:A')).toContain('#f97316');
    expect(strokes('transition:Go')).toContain('#2563eb');
    expect(gfx('transition:Box').querySelector('rect')!.getAttribute('fill')).toBe('#16a34a');
    expect(gfx('transition#3').querySelector('circle[fill="#dc2626"]')).not.toBeNull();
    m.canvas.clearHighlights('error');
    expect(strokes('step:B')).not.toContain('#dc2626');
    m.canvas.clearHighlights();
    expect(strokes('step:B')).not.toContain('#16a34a');
    expect(gfx('transition#3').querySelector('circle[fill="#dc2626"]')).toBeNull();
    // Highlights are not edits.
    expect(m.canvas.canUndo()).toBe(false);
  });

  it('frames a block with a tooltip, drawn in its visual, as often as it is redrawn', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    // step:Init has a description: its tooltip must not take the place of the visual.
    const gfx = m.get('elementRegistry').getGraphics('step:Init') as Element;
    const visual = () => gfx.firstElementChild!;
    const frames = () => [...visual().querySelectorAll('rect')].filter((r) => r.getAttribute('stroke') === '#dc2626').length;
    for (let k = 0; k < 3; k++) {
      m.canvas.highlight('error', ['step:Init']);
      expect(visual().classList.contains('djs-visual')).toBe(true);
      expect(frames()).toBe(1);
      m.canvas.clearHighlights('error');
      expect(frames()).toBe(0);
    }
    m.canvas.updateElement('step:Init', { description: 'Changed' });
    m.canvas.highlight('warning', ['step:Init']);
    expect(visual().classList.contains('djs-visual')).toBe(true);
    expect(gfx.querySelectorAll(':scope > title')).toHaveLength(1);
    expect(gfx.querySelector(':scope > title')!.textContent).toBe('Changed');
  });
});

describe('zoom and grid', () => {
  it('zooms, reports it, and hides the grid below 75 %', () => {
    const m = mount();
    // jsdom does no layout: give the canvas a size.
    const box = m.get('canvas').getContainer() as HTMLElement;
    Object.defineProperty(box, 'clientWidth', { value: 800 });
    Object.defineProperty(box, 'clientHeight', { value: 600 });
    m.canvas.load(conveyorDoc());
    expect(m.canvas.getZoom()).toBe(1); // fitted, but never blown up beyond 100 %
    const levels: number[] = [];
    m.canvas.on('zoom', (z) => levels.push(z));
    m.canvas.zoom(2);
    expect(m.canvas.getZoom()).toBeCloseTo(2);
    expect(levels.at(-1)).toBeCloseTo(2);
    const grid = m.get('sfcGrid');
    expect(grid.isVisible()).toBe(true);
    m.canvas.zoom(0.5);
    expect(grid.isVisible()).toBe(false);
    m.canvas.zoom(0.75);
    expect(grid.isVisible()).toBe(true);
    // The grid is a pattern on a layer under the blocks.
    const layer = m.container.querySelector('.sfc-grid')!;
    expect(layer.querySelector('pattern')).not.toBeNull();
    const base = m.get('canvas').getActiveLayer() as Element;
    expect(layer.parentElement!.compareDocumentPosition(base) & Node.DOCUMENT_POSITION_FOLLOWING).toBeTruthy();
  });

  it('has scrollbars over the canvas edges', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    expect(m.container.querySelector('.sfc-scrollbar-h .sfc-scrollbar-thumb')).not.toBeNull();
    expect(m.container.querySelector('.sfc-scrollbar-v .sfc-scrollbar-thumb')).not.toBeNull();
  });
});

describe('exportSvg', () => {
  it('is a standalone SVG of the chart with every step name and nothing of the editor', () => {
    const m = mount();
    const doc = makeBigDoc(60);
    m.canvas.load(doc);
    m.canvas.select(['step:S3']);
    const svg = m.canvas.exportSvg();
    expect(svg).toMatch(/^<\?xml[^>]*>\n<svg [^>]*xmlns="http:\/\/www.w3.org\/2000\/svg"/);
    expect(svg).toMatch(/viewBox="-?\d+ -?\d+ \d+ \d+"/);
    const parsed = new DOMParser().parseFromString(svg, 'image/svg+xml');
    expect(parsed.querySelector('parsererror')).toBeNull();
    const texts = new Set([...parsed.querySelectorAll('text')].map((t) => t.textContent));
    for (const e of doc.elements.filter((x) => x.kind === 'step')) expect(texts.has(e.name!)).toBe(true);
    for (const bad of ['djs-hit', 'djs-outline', 'selected', 'sfc-grid', 'djs-resizer', 'class=']) expect(svg).not.toContain(bad);
    // Every block and wire is there, at its place.
    expect(parsed.querySelectorAll('g[data-id]')).toHaveLength(doc.elements.length + doc.connections.length);
    expect(parsed.querySelector('g[data-id="step:S1"]')!.getAttribute('transform')).toBe('translate(200,140)');
  }, 60_000);

  it('leaves the highlights out (validation and comparison frames, monitor states) unless asked', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const clean = m.canvas.exportSvg();
    m.canvas.highlight('error', ['step:B', 'c2']);
    m.canvas.highlight('diff-added', ['step:A']);
    m.canvas.highlight('diff-changed', ['transition:Go']);
    m.canvas.highlight('active', ['step:Run'], { 'step:Run': '3.4 s' });
    m.canvas.highlight('enabled', ['transition:Box']);
    m.canvas.highlight('breakpoint', ['transition#3']);
    // Printed and exported as if nothing were highlighted.
    expect(m.canvas.exportSvg()).toBe(clean);
    expect(m.canvas.exportSvg({ marks: false })).toBe(clean);
    const marked = m.canvas.exportSvg({ marks: true });
    for (const colour of ['#dc2626', '#2e7d32', '#ef6c00', '#16a34a']) {
      expect(clean.split(colour).length, colour).toBeLessThan(marked.split(colour).length);
    }
    expect(marked).toContain('3.4 s');
    expect(clean).not.toContain('3.4 s');
    // The canvas keeps its highlights.
    const gfx = m.get('elementRegistry').getGraphics('step:B') as Element;
    expect([...gfx.querySelectorAll('rect')].map((r) => r.getAttribute('stroke'))).toContain('#dc2626');
  });

  it('keeps the tooltip as an SVG title', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const svg = m.canvas.exportSvg();
    expect(svg).toContain('<title>Waiting for start</title>');
  });

  it("draws S7-GRAPH's interlock (C) and supervision (V) on the step's left side, the condition as tooltip", () => {
    const m = mount();
    const doc = conveyorDoc();
    const run = doc.elements.find((e) => e.id === 'step:Run')!;
    run.attributes = [
      { name: 'sfc.s7graph.interlock', value: 'start AND NOT stop' },
      { name: 'sfc.s7graph.supervision', value: 'Run.T > T#10s AND box = $27x$27' },
    ];
    m.canvas.load(doc);
    const svg = m.canvas.exportSvg();
    const parsed = new DOMParser().parseFromString(svg, 'image/svg+xml');
    const step = parsed.querySelector('g[data-id="step:Run"]')!;
    const marks = [...step.querySelectorAll('text')].map((t) => t.textContent).filter((t) => t === 'C' || t === 'V');
    expect(marks).toEqual(['C', 'V']);
    const titles = [...step.querySelectorAll('title')].map((t) => t.textContent);
    expect(titles).toContain('interlock: start AND NOT stop');
    expect(titles).toContain("supervision: Run.T > T#10s AND box = 'x'");
    const init = parsed.querySelector('g[data-id="step:Init"]')!;
    expect([...init.querySelectorAll('text')].some((t) => t.textContent === 'C')).toBe(false);
  });
});

// The cases sfc-doc's tests check too (crates/sfc-doc/tests/drawing.rs): one wrap rule for the
// server's layout and SVG and the canvas. The file lies outside the web app, so it is read with
// node:fs (the module name a variable, so TypeScript needs no @types/node); tests run from web/.
const nodeFs = 'node:fs';
const fs = (await import(/* @vite-ignore */ nodeFs)) as { readFileSync(path: string, encoding: 'utf8'): string };
const shared = JSON.parse(
  fs.readFileSync(`${(globalThis as unknown as { process: { cwd(): string } }).process.cwd()}/../crates/sfc-doc/tests/shared/condition_lines.json`, 'utf8'),
) as { chars: number; cases: { what: string; condition: string; lines: string[] }[] };

describe('transition labels', () => {
  it('wrap long conditions at words, never cut, on the cases shared with sfc-doc', () => {
    expect(shared.chars).toBe(CONDITION_CHARS);
    expect(shared.cases.length).toBeGreaterThan(10);
    for (const c of shared.cases) expect(conditionLines({ condition: c.condition }), c.what).toEqual(c.lines);
    expect(wrapCondition('CarLeft AND NOT DryerSelect AND NOT StopButton')).toEqual(['CarLeft AND NOT DryerSelect AND', 'NOT StopButton']);
  });
  it('are as tall as their lines', () => {
    const condition = 'Brushing.T >= MaxBrushTime AND NOT CarLeft AND NOT StopButton AND NOT Reset';
    const [label] = labelsOf({ id: 't', kind: 'transition', condition, x: 0, y: 0, w: 40, h: 20 }, 40, 20);
    expect(label.lines.join(' ')).toBe(condition);
    expect(label.height).toBe(3 * LINE_H);
    expect(label.y).toBe(10 - (3 * LINE_H) / 2);
  });
});
