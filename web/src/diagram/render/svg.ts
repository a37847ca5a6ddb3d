// Small helpers to build SVG with presentation attributes only (no CSS classes), so the same
// nodes serve the canvas and the standalone SVG export.
import { textWidth as estimate } from '../drawing';

const NS = 'http://www.w3.org/2000/svg';

// DejaVu Sans first: the layout estimates text widths with its advances (../drawing.ts).
export const FONT = "'DejaVu Sans', 'Segoe UI', 'Noto Sans', Roboto, Helvetica, Arial, sans-serif";
export const MONO = "'DejaVu Sans Mono', 'Cascadia Mono', Consolas, monospace";

export type Attrs = Record<string, string | number>;

export function el<K extends keyof SVGElementTagNameMap>(tag: K, attrs: Attrs, parent?: Element): SVGElementTagNameMap[K] {
  const node = document.createElementNS(NS, tag);
  for (const k in attrs) node.setAttribute(k, String(attrs[k]));
  if (parent) parent.appendChild(node);
  return node;
}

export function text(parent: Element, x: number, y: number, content: string, attrs: Attrs): SVGTextElement {
  const t = el('text', { x, y, 'font-family': FONT, 'dominant-baseline': 'central', ...attrs }, parent);
  t.textContent = content;
  return t;
}

/** Estimated advance of `s` (DejaVu Sans advances, as the layout estimates it). */
export const textWidth = estimate;

/** `s` cut with an ellipsis to fit `max` px. */
export function fit(s: string, size: number, max: number): string {
  if (textWidth(s, size) <= max) return s;
  let out = s;
  while (out.length > 1 && textWidth(out + '…', size) > max) out = out.slice(0, -1);
  return out.length > 0 ? out + '…' : '';
}

/** Greedy word wrap of `s` (with its own line breaks) to lines of at most `max` px. */
export function wrap(s: string, size: number, max: number): string[] {
  const out: string[] = [];
  for (const para of s.split('\n')) {
    let line = '';
    for (const word of para.split(/(\s+)/)) {
      const next = line + word;
      if (line !== '' && textWidth(next.trimEnd(), size) > max) {
        out.push(line.trimEnd());
        line = word.trimStart();
      } else {
        line = next;
      }
    }
    out.push(line.trimEnd());
  }
  return out;
}

export function points(ps: { x: number; y: number }[]): string {
  return ps.map((p) => `${p.x},${p.y}`).join(' ');
}
