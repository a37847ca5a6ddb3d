// A standalone SVG of the chart as drawn: the blocks' and wires' drawings only (no hit areas,
// selection outlines, handles or grid), every style as an attribute, a viewBox around the
// chart with a margin. Without `marks` (the default) the blocks and wires are drawn afresh
// without their highlights: no error, warning or comparison frames, monitor states or
// breakpoints in a printed or exported chart unless asked for.
import { connectionsOf, shapesOf, type Service } from '../model';
import type { SfcRenderer } from '../render/SfcRenderer';
import { FONT } from '../render/svg';
import { chartBounds } from '../view/bounds';

const NS = 'http://www.w3.org/2000/svg';
const MARGIN = 20;

export interface ExportOptions {
  /** Keep the highlights' marks (validation and comparison frames, monitor states). */
  marks?: boolean;
}

export function exportSvg(elementRegistry: Service, renderer: SfcRenderer, options: ExportOptions = {}): string {
  const b = chartBounds(elementRegistry) ?? { x: 0, y: 0, width: 100, height: 100 };
  const x = Math.floor(b.x - MARGIN);
  const y = Math.floor(b.y - MARGIN);
  const w = Math.ceil(b.width + 2 * MARGIN);
  const h = Math.ceil(b.height + 2 * MARGIN);
  const svg = document.createElementNS(NS, 'svg');
  svg.setAttribute('viewBox', `${x} ${y} ${w} ${h}`);
  svg.setAttribute('width', String(w));
  svg.setAttribute('height', String(h));
  svg.setAttribute('font-family', FONT);
  const bg = document.createElementNS(NS, 'rect');
  for (const [k, v] of Object.entries({ x, y, width: w, height: h, fill: '#ffffff' })) bg.setAttribute(k, String(v));
  svg.appendChild(bg);
  // Wires under blocks, as on the canvas.
  for (const c of connectionsOf(elementRegistry)) {
    const visual = visualOf(elementRegistry, c);
    if (!visual) continue;
    const g = document.createElementNS(NS, 'g');
    g.setAttribute('data-id', c.id);
    copyVisual(g, visual, c, renderer, options);
    svg.appendChild(g);
  }
  for (const s of shapesOf(elementRegistry)) {
    const visual = visualOf(elementRegistry, s);
    if (!visual) continue;
    const g = document.createElementNS(NS, 'g');
    g.setAttribute('data-id', s.id);
    g.setAttribute('transform', `translate(${s.x},${s.y})`);
    const title = visual.parentNode?.querySelector(':scope > title');
    if (title) g.appendChild(title.cloneNode(true));
    copyVisual(g, visual, s, renderer, options);
    svg.appendChild(g);
  }
  return '<?xml version="1.0" encoding="UTF-8"?>\n' + new XMLSerializer().serializeToString(svg);
}

/** The drawing of `e` into `g`: its visual as on the canvas, or drawn afresh without marks. */
function copyVisual(g: Element, visual: Element, e: Service, renderer: SfcRenderer, options: ExportOptions) {
  if (options.marks) {
    for (const child of Array.from(visual.childNodes)) g.appendChild(child.cloneNode(true));
  } else {
    renderer.drawUnmarked(g as SVGElement, e);
  }
}

function visualOf(elementRegistry: Service, e: Service): Element | null {
  const gfx: Element | undefined = elementRegistry.getGraphics(e);
  return gfx ? gfx.querySelector('.djs-visual') : null;
}
