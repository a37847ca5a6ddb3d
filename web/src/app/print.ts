// Page setup of the print dialog: paper sizes, how the chart's SVG is scaled and cut into
// pages, how the legend is cut into pages, and the `@page` rule of the print stylesheet.

export type Paper = 'A4' | 'A3' | 'Letter';
export type Orientation = 'portrait' | 'landscape';

export interface PageSetup {
  paper: Paper;
  orientation: Orientation;
  /** Margin on every side, mm. */
  margin: number;
  /** Fit the chart to one page; else print at `scale` % (over several pages when large). */
  fit: boolean;
  scale: number;
  legend: boolean;
  header: boolean;
  /** Print the highlights' marks (error, warning and comparison frames, monitor states). */
  marks: boolean;
}

export const DEFAULT_SETUP: PageSetup = {
  paper: 'A4',
  orientation: 'landscape',
  margin: 10,
  fit: true,
  scale: 100,
  legend: true,
  header: true,
  marks: false,
};

const PAPER_MM: Record<Paper, [number, number]> = { A4: [210, 297], A3: [297, 420], Letter: [215.9, 279.4] };
/** CSS pixels are 1/96 inch. */
export const MM_PER_PX = 25.4 / 96;
/** Height of the header line (title, file, date), mm. */
export const HEADER_MM = 10;

/** Page size in mm for the setup's paper and orientation. */
export function pageSize(setup: Pick<PageSetup, 'paper' | 'orientation'>): { w: number; h: number } {
  const [a, b] = PAPER_MM[setup.paper];
  return setup.orientation === 'portrait' ? { w: a, h: b } : { w: b, h: a };
}

/** The drawing size of an SVG document in CSS pixels (width/height, else its viewBox). */
export function svgSize(svg: string): { w: number; h: number } {
  const open = /<svg\b[^>]*>/i.exec(svg)?.[0] ?? '';
  const attr = (n: string) => new RegExp(`\\s${n}\\s*=\\s*["']([^"']+)["']`, 'i').exec(open)?.[1];
  const px = (v: string | undefined) => (v && /^\s*[\d.]+(px)?\s*$/.test(v) ? parseFloat(v) : NaN);
  let w = px(attr('width'));
  let h = px(attr('height'));
  const vb = attr('viewBox')?.trim().split(/[\s,]+/).map(Number);
  if ((!Number.isFinite(w) || !Number.isFinite(h)) && vb && vb.length === 4 && vb.every(Number.isFinite)) {
    w = vb[2];
    h = vb[3];
  }
  return { w: Number.isFinite(w) && w > 0 ? w : 1, h: Number.isFinite(h) && h > 0 ? h : 1 };
}

export interface ChartPages {
  /** Size of the printable area of each page (mm), below the header. */
  areaW: number;
  areaH: number;
  /** Drawing size on paper (mm). */
  drawW: number;
  drawH: number;
  cols: number;
  rows: number;
}

/** How the chart lies on the pages: fitted to one page, or at the scale over cols × rows pages. */
export function chartPages(setup: PageSetup, svgPx: { w: number; h: number }): ChartPages {
  const page = pageSize(setup);
  const areaW = Math.max(10, page.w - 2 * setup.margin);
  const areaH = Math.max(10, page.h - 2 * setup.margin - (setup.header ? HEADER_MM : 0));
  const naturalW = svgPx.w * MM_PER_PX;
  const naturalH = svgPx.h * MM_PER_PX;
  const factor = setup.fit ? Math.min(areaW / naturalW, areaH / naturalH) : Math.max(1, setup.scale) / 100;
  const drawW = naturalW * factor;
  const drawH = naturalH * factor;
  // A small tolerance keeps a drawing that exactly fits from spilling onto a second page.
  const cols = setup.fit ? 1 : Math.max(1, Math.ceil(drawW / areaW - 1e-6));
  const rows = setup.fit ? 1 : Math.max(1, Math.ceil(drawH / areaH - 1e-6));
  return { areaW, areaH, drawW, drawH, cols, rows };
}

/** The print stylesheet's page rule. */
export function pageRule(setup: PageSetup): string {
  const { w, h } = pageSize(setup);
  return `@page { size: ${w}mm ${h}mm; margin: 0; }`;
}

/** Lines of a legend page (a row of one line each). */
export const LEGEND_LINES_PER_PAGE = 28;
/** Characters of a line of the legend's condition and description columns, about (the
 *  narrowest page: A4 portrait). */
export const LEGEND_CHARS = 32;

/** How many lines a legend row takes: its tallest cell, each of its lines wrapped at about
 *  `LEGEND_CHARS` characters. */
export function legendRowLines(row: { name: string; condition: string; description: string }): number {
  const lines = (s: string) => s.split('\n').reduce((n, l) => n + Math.max(1, Math.ceil([...l].length / LEGEND_CHARS)), 0);
  return Math.max(1, lines(row.name), lines(row.condition), lines(row.description));
}

/** The legend's rows cut into pages of at most `perPage` lines (a taller row alone on its
 *  page); one empty page for no rows. */
export function legendPages<T extends { name: string; condition: string; description: string }>(rows: T[], perPage = LEGEND_LINES_PER_PAGE): T[][] {
  const pages: T[][] = [[]];
  let used = 0;
  for (const row of rows) {
    const n = legendRowLines(row);
    if (used > 0 && used + n > perPage) {
      pages.push([]);
      used = 0;
    }
    pages[pages.length - 1].push(row);
    used += n;
  }
  return pages;
}
