// Draws the IEC 61131-3 SFC blocks and wires (seed 001, fig. 13a–h).
import BaseRenderer from 'diagram-js/lib/draw/BaseRenderer.js';
import { pinCounts, type Element } from '../../doc';
import { inputPin, outputPin, type Box } from '../geometry';
import { isConnection, type Service, type SfcConnection, type SfcShape } from '../model';
import type { Highlights } from '../highlight/Highlights';
import type { HighlightKind } from '../types';
import { actionColumns, BAR_HALF, LINE_H, labelsOf, MARK, nameWithTag, qualifierText, stepMarks, wrapCondition } from '../drawing';
import { el, fit, MONO, points, text, wrap } from './svg';

export const INK = '#1e293b';
const PAPER = '#ffffff';
const LABEL = 12;
const SMALL = 10;

const FRAME: Partial<Record<HighlightKind, { stroke: string; width: number; dash?: string; fill?: string }>> = {
  'selected-diagnostic': { stroke: '#7c3aed', width: 3, fill: 'rgba(124,58,237,0.08)' },
  error: { stroke: '#dc2626', width: 2.5 },
  warning: { stroke: '#f59e0b', width: 2.5, dash: '6 3' },
  witness: { stroke: '#2563eb', width: 3, fill: 'rgba(37,99,235,0.08)' },
  active: { stroke: '#16a34a', width: 3, fill: 'rgba(22,163,74,0.12)' },
  hit: { stroke: '#f97316', width: 3, fill: 'rgba(249,115,22,0.12)' },
  // The colours of `sfc diff --format svg` (crates/sfc-cli/src/diff.rs).
  'diff-added': { stroke: '#2e7d32', width: 3, fill: 'rgba(46,125,50,0.10)' },
  'diff-changed': { stroke: '#ef6c00', width: 3, fill: 'rgba(239,108,0,0.10)' },
  // A merge conflict (`sfc.conflict`): red-orange, apart from the comparison's orange.
  conflict: { stroke: '#e64a19', width: 3, dash: '8 3', fill: 'rgba(230,74,25,0.12)' },
};
const LABEL_COLOUR: Partial<Record<HighlightKind, string>> = {
  active: '#15803d',
  hit: '#c2410c',
  witness: '#1d4ed8',
  error: '#b91c1c',
  warning: '#b45309',
};
export const ENABLED = '#16a34a';
const BREAKPOINT = '#dc2626';

/** No highlight: how a block is drawn for Print and Export SVG without marks. */
const UNMARKED: { kinds: Set<HighlightKind>; label?: string } = { kinds: new Set() };

export class SfcRenderer extends BaseRenderer {
  static $inject = ['eventBus', 'elementRegistry', 'sfcHighlights'];

  /** While set, blocks and wires are drawn without their highlights (`drawUnmarked`). */
  private unmarked = false;

  constructor(
    eventBus: Service,
    private elementRegistry: Service,
    private highlights: Highlights,
  ) {
    super(eventBus, 1500);
  }

  canRender(element: Service): boolean {
    return !!element.businessObject;
  }

  /**
   * Draws a block or wire into `parent` as it is, without the marks of its highlights (error,
   * warning and comparison frames, monitor states, breakpoints, their labels and colours): what
   * Print and Export SVG show unless asked for the marks.
   */
  drawUnmarked(parent: SVGElement, element: Service): void {
    this.unmarked = true;
    try {
      if (isConnection(element)) this.drawConnection(parent, element);
      else this.drawShape(parent, element);
    } finally {
      this.unmarked = false;
    }
  }

  private marks(id: string): { kinds: Set<HighlightKind>; label?: string } {
    return this.unmarked ? UNMARKED : this.highlights.of(id);
  }

  drawShape(parent: SVGElement, shape: Service): SVGElement {
    const s = shape as SfcShape;
    const e = s.businessObject;
    // Drawn straight into diagram-js's visual group: no wrapper, fewer nodes per block.
    const g = parent;
    const hl = this.marks(s.id);
    this.drawFrames(g, s, hl.kinds);
    switch (e.kind) {
      case 'step':
        this.drawStep(g, s, e);
        break;
      case 'transition':
        this.drawTransition(g, s, e, hl.kinds.has('enabled'));
        break;
      case 'selectionDivergence':
      case 'selectionConvergence':
      case 'simultaneousDivergence':
      case 'simultaneousConvergence':
        this.drawBar(g, s, e);
        break;
      case 'jump':
        this.drawJump(g, s, e);
        break;
      case 'text':
        this.drawText(g, s, e);
        break;
      case 'actionBlock':
        this.drawActionBlock(g, s, e);
        break;
    }
    if (e.kind !== 'jump') this.drawPins(g, s, e);
    if (hl.kinds.has('breakpoint')) {
      el('circle', { cx: -3, cy: -3, r: 5, fill: BREAKPOINT, stroke: PAPER, 'stroke-width': 1.5 }, g);
    }
    if (hl.label) {
      const colour = [...hl.kinds].map((k) => LABEL_COLOUR[k]).find(Boolean) ?? INK;
      // Left of the centre line, where the outgoing wire runs.
      text(g, s.width / 2 - 5, s.height + 11, hl.label, { 'font-size': SMALL, 'text-anchor': 'end', fill: colour, 'font-weight': 600 });
    }
    this.setTooltip(parent, e.description);
    return g.firstChild as SVGElement;
  }

  drawConnection(parent: SVGElement, connection: Service): SVGElement {
    const c = connection as SfcConnection;
    const bo = c.businessObject;
    const hl = this.marks(c.id);
    const colour = hl.kinds.has('error') ? FRAME.error!.stroke : hl.kinds.has('witness') ? FRAME.witness!.stroke : (bo.color ?? INK);
    return el(
      'polyline',
      {
        points: points(c.waypoints),
        fill: 'none',
        stroke: colour,
        'stroke-width': bo.lineWidth ?? 1.5,
        'stroke-linejoin': 'miter',
        'stroke-linecap': 'square',
      },
      parent,
    );
  }

  getShapePath(shape: Service): string {
    const { x, y, width: w, height: h } = shape;
    return `M${x},${y}h${w}v${h}h${-w}z`;
  }

  getConnectionPath(connection: Service): string {
    const ps = (connection as SfcConnection).waypoints;
    return ps.map((p, i) => `${i === 0 ? 'M' : 'L'}${p.x},${p.y}`).join('');
  }

  // ---- blocks -------------------------------------------------------------------------------

  private drawStep(g: SVGElement, s: SfcShape, e: Element) {
    const fg = e.foreground ?? INK;
    const lw = e.lineWidth ?? 1.5;
    el('rect', { x: 0, y: 0, width: s.width, height: s.height, fill: e.background ?? PAPER, stroke: fg, 'stroke-width': lw }, g);
    if (e.initial) {
      const inset = 3 + lw;
      el('rect', { x: inset, y: inset, width: Math.max(0, s.width - 2 * inset), height: Math.max(0, s.height - 2 * inset), fill: 'none', stroke: fg, 'stroke-width': lw }, g);
    }
    const label = nameWithTag(e);
    const room = s.width - (e.initial ? 16 : 10);
    const cy = e.timeout ? s.height / 2 - 5 : s.height / 2;
    text(g, s.width / 2, cy, fit(label, LABEL, room), { 'font-size': LABEL, 'text-anchor': 'middle', fill: fg, 'font-weight': 600 });
    if (e.timeout) {
      text(g, s.width / 2, cy + 12, fit(e.timeout, SMALL, room), { 'font-size': SMALL, 'text-anchor': 'middle', fill: fg, opacity: 0.75 });
    }
    // S7-GRAPH's interlock (C) and supervision (V), on the step's left side.
    stepMarks(e).forEach(({ mark, condition }, k) => {
      const m = el('g', {}, g);
      const title = el('title', {}, m);
      title.textContent = `${mark === 'C' ? 'interlock' : 'supervision'}: ${condition}`;
      const x = -MARK - 2;
      const y = 2 + k * (MARK + 2);
      el('rect', { x, y, width: MARK, height: MARK, fill: PAPER, stroke: fg, 'stroke-width': 1 }, m);
      text(m, x + MARK / 2, y + MARK / 2, mark, { 'font-size': SMALL, 'text-anchor': 'middle', fill: fg, 'font-weight': 600 });
    });
  }

  private drawTransition(g: SVGElement, s: SfcShape, e: Element, enabled: boolean) {
    const fg = e.foreground ?? INK;
    const cx = s.width / 2;
    const cy = s.height / 2;
    el('line', { x1: cx, y1: 0, x2: cx, y2: s.height, stroke: fg, 'stroke-width': e.lineWidth ?? 1.5 }, g);
    const bar = 2 * BAR_HALF;
    el('rect', { x: cx - bar / 2, y: cy - 2, width: bar, height: 4, fill: enabled ? ENABLED : (e.background ?? fg), stroke: enabled ? ENABLED : fg, 'stroke-width': 0.5 }, g);
    // The labels where the layout made room for them (../drawing.ts, sfc-doc's drawing.rs):
    // the condition right of the bar, the name left of it (right of it without a condition).
    for (const l of labelsOf(e, s.width, s.height)) {
      if (l.kind === 'condition') {
        l.lines.forEach((line, i) => {
          text(g, l.x, l.y + LINE_H / 2 + i * LINE_H, line, { 'font-size': LABEL, fill: fg, 'font-family': MONO });
        });
      } else {
        text(g, l.x + l.width, cy, l.lines[0], { 'font-size': LABEL, 'text-anchor': 'end', fill: fg, opacity: l.x < cx ? 0.75 : 1 });
      }
    }
  }

  private drawBar(g: SVGElement, s: SfcShape, e: Element) {
    const fg = e.foreground ?? INK;
    const lw = e.lineWidth ?? 1.5;
    const cy = s.height / 2;
    const double = e.kind === 'simultaneousDivergence' || e.kind === 'simultaneousConvergence';
    const lines = double ? [cy - 2, cy + 2] : [cy];
    for (const y of lines) el('line', { x1: 0, y1: y, x2: s.width, y2: y, stroke: fg, 'stroke-width': lw }, g);
    // Stubs from the line(s) to each pin, so wires meet the bar.
    const box = localBox(s);
    const { inputs, outputs } = pinCounts(e);
    for (let i = 0; i < inputs; i++) {
      const p = inputPin(e, box, i);
      el('line', { x1: p.x, y1: 0, x2: p.x, y2: lines[0], stroke: fg, 'stroke-width': 1.5 }, g);
    }
    for (let i = 0; i < outputs; i++) {
      const p = outputPin(e, box, i);
      el('line', { x1: p.x, y1: lines[lines.length - 1], x2: p.x, y2: s.height, stroke: fg, 'stroke-width': 1.5 }, g);
    }
  }

  private drawJump(g: SVGElement, s: SfcShape, e: Element) {
    const fg = e.foreground ?? INK;
    const cx = s.width / 2;
    const mid = s.height * 0.4;
    el('line', { x1: cx, y1: 0, x2: cx, y2: mid, stroke: fg, 'stroke-width': e.lineWidth ?? 1.5 }, g);
    el('polygon', { points: points([{ x: 0, y: mid }, { x: s.width, y: mid }, { x: cx, y: s.height }]), fill: e.background ?? fg, stroke: fg, 'stroke-width': 1, 'stroke-linejoin': 'round' }, g);
    for (const l of labelsOf(e, s.width, s.height)) {
      text(g, l.x, l.y + LINE_H / 2, l.lines[0], { 'font-size': LABEL, fill: fg, 'font-weight': 600 });
    }
  }

  private drawText(g: SVGElement, s: SfcShape, e: Element) {
    const fg = e.foreground ?? '#334155';
    el('rect', { x: 0, y: 0, width: s.width, height: s.height, fill: e.background ?? '#fefce8', stroke: '#a3a3a3', 'stroke-width': 1, 'stroke-dasharray': '4 2', rx: 2 }, g);
    const size = fontSize(e.font) ?? LABEL;
    const lines = wrap(e.text ?? '', size, s.width - 10);
    const lineH = Math.round(size * 1.3);
    const maxLines = Math.max(1, Math.floor((s.height - 6) / lineH));
    const shown = lines.slice(0, maxLines);
    const align = e.align ?? 'left';
    const x = align === 'center' ? s.width / 2 : align === 'right' ? s.width - 5 : 5;
    const anchor = align === 'center' ? 'middle' : align === 'right' ? 'end' : 'start';
    shown.forEach((line, i) => {
      const t = text(g, x, 5 + lineH / 2 + i * lineH, line, { 'font-size': size, fill: fg, 'text-anchor': anchor });
      if (e.font) t.setAttribute('style', `font: ${e.font}`);
    });
  }

  private drawActionBlock(g: SVGElement, s: SfcShape, e: Element) {
    const fg = e.foreground ?? INK;
    const lw = e.lineWidth ?? 1;
    const rows = e.associations ?? [];
    const n = Math.max(1, rows.length);
    const rowH = s.height / n;
    // The link from the owning step's right edge to the first row.
    const step = e.step ? this.elementRegistry.get(e.step) : undefined;
    if (step && !isConnection(step)) {
      const sx = step.x + step.width - s.x;
      const sy = step.y + step.height / 2 - s.y;
      const ty = rowH / 2;
      if (sx < 0) {
        const mx = sx / 2;
        el('polyline', { points: points([{ x: sx, y: sy }, { x: mx, y: sy }, { x: mx, y: ty }, { x: 0, y: ty }]), fill: 'none', stroke: fg, 'stroke-width': 1.5 }, g);
      }
    }
    el('rect', { x: 0, y: 0, width: s.width, height: s.height, fill: e.background ?? PAPER, stroke: fg, 'stroke-width': lw }, g);
    // The columns as the layout sized them (../drawing.ts); a block made narrower by hand
    // squeezes the action column first.
    const cols = actionColumns(rows);
    const hasInd = cols.i > 0;
    const q = Math.max(0, Math.min(cols.q, s.width - 40));
    const iw = Math.min(cols.i, Math.max(0, s.width - q - 40));
    el('line', { x1: q, y1: 0, x2: q, y2: s.height, stroke: fg, 'stroke-width': lw }, g);
    if (hasInd) el('line', { x1: s.width - iw, y1: 0, x2: s.width - iw, y2: s.height, stroke: fg, 'stroke-width': lw }, g);
    rows.forEach((r, i) => {
      const cy = i * rowH + rowH / 2;
      if (i > 0) el('line', { x1: 0, y1: i * rowH, x2: s.width, y2: i * rowH, stroke: fg, 'stroke-width': lw }, g);
      const size = Math.min(LABEL, rowH - 4);
      text(g, q / 2, cy, fit(qualifierText(r), size, q - 4), { 'font-size': size, 'text-anchor': 'middle', fill: fg, 'font-weight': 600 });
      text(g, q + 5, cy, fit(r.action, size, s.width - q - iw - 10), { 'font-size': size, fill: fg });
      if (r.indicator) text(g, s.width - iw / 2, cy, fit(r.indicator, size, iw - 4), { 'font-size': size, 'text-anchor': 'middle', fill: fg });
    });
    if (rows.length === 0) {
      text(g, s.width / 2, s.height / 2, '—', { 'font-size': LABEL, 'text-anchor': 'middle', fill: fg, opacity: 0.5 });
    }
  }

  // ---- pins, frames, tooltip ----------------------------------------------------------------

  /** Input pins: an arrow when wired, a short stub when free; free output pins: a stub. */
  private drawPins(g: SVGElement, s: SfcShape, e: Element) {
    const { inputs, outputs } = pinCounts(e);
    if (inputs === 0 && outputs === 0) return;
    const fg = e.foreground ?? INK;
    const box = localBox(s);
    const wiredIn = new Set(s.incoming.map((c) => c.businessObject.targetPin));
    const wiredOut = new Set(s.outgoing.map((c) => c.businessObject.sourcePin));
    for (let i = 0; i < inputs; i++) {
      const p = inputPin(e, box, i);
      if (wiredIn.has(i)) {
        // Seed 001 §7.3: a wired input pin is drawn as an arrow, for readability.
        el('polygon', { points: points([{ x: p.x - 4, y: p.y - 7 }, { x: p.x + 4, y: p.y - 7 }, { x: p.x, y: p.y }]), fill: fg, stroke: 'none' }, g);
      } else {
        el('line', { x1: p.x, y1: p.y - 5, x2: p.x, y2: p.y, stroke: '#94a3b8', 'stroke-width': 1.5 }, g);
        el('circle', { cx: p.x, cy: p.y - 6, r: 1.8, fill: PAPER, stroke: '#94a3b8', 'stroke-width': 1 }, g);
      }
    }
    for (let i = 0; i < outputs; i++) {
      if (wiredOut.has(i)) continue;
      const p = outputPin(e, box, i);
      el('line', { x1: p.x, y1: p.y, x2: p.x, y2: p.y + 5, stroke: '#94a3b8', 'stroke-width': 1.5 }, g);
      el('circle', { cx: p.x, cy: p.y + 6, r: 1.8, fill: PAPER, stroke: '#94a3b8', 'stroke-width': 1 }, g);
    }
  }

  private drawFrames(g: SVGElement, s: SfcShape, kinds: Set<HighlightKind>) {
    let pad = 4;
    for (const kind of ['conflict', 'diff-added', 'diff-changed', 'warning', 'error', 'witness', 'hit', 'active', 'selected-diagnostic'] as HighlightKind[]) {
      const f = FRAME[kind];
      if (!f || !kinds.has(kind)) continue;
      const attrs: Record<string, string | number> = {
        x: -pad,
        y: -pad,
        width: s.width + 2 * pad,
        height: s.height + 2 * pad,
        rx: 3,
        fill: f.fill ?? 'none',
        stroke: f.stroke,
        'stroke-width': f.width,
      };
      if (f.dash) attrs['stroke-dasharray'] = f.dash;
      el('rect', attrs, g);
      pad += 3;
    }
  }

  /** The description as the native tooltip; on the element group so hovering its hit area shows
   *  it. Appended, never first: diagram-js takes the group's first child as the block's visual
   *  (getVisual), and a title there would receive every later redraw, highlights included. */
  private setTooltip(visual: SVGElement, description: string | undefined) {
    const group = visual.parentNode as SVGElement | null;
    if (!group) return;
    // The group's own children, from the end (a selector query per block costs more).
    let title: SVGElement | null = null;
    for (let c = group.lastElementChild; c && !title; c = c.previousElementSibling) {
      if (c.tagName === 'title') title = c as SVGElement;
    }
    if (!description) {
      title?.remove();
      return;
    }
    if (!title) {
      title = document.createElementNS('http://www.w3.org/2000/svg', 'title');
      group.appendChild(title);
    }
    title.textContent = description;
  }
}

function localBox(s: SfcShape): Box {
  return { x: 0, y: 0, width: s.width, height: s.height };
}

export { nameWithTag, wrapCondition };

function fontSize(font: string | undefined): number | undefined {
  const m = font ? /(\d+(?:\.\d+)?)px/.exec(font) : null;
  return m ? Number(m[1]) : undefined;
}
