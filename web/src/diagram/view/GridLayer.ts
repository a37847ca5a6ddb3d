// The grid (10 units, a heavier line every 5): an SVG pattern on a layer under the blocks,
// drawn only from zoom 0.75 up, where it helps to align blocks.
import { GRID } from '../geometry';
import type { Service } from '../model';
import { el } from '../render/svg';
import type { ViewTracker } from './ViewTracker';

export const GRID_MIN_ZOOM = 0.75;
let uid = 0;

export class GridLayer {
  static $inject = ['eventBus', 'canvas', 'sfcView'];

  private rect?: SVGRectElement;
  private minor?: SVGPathElement;
  private major?: SVGPathElement;
  private group?: SVGGElement;

  constructor(
    eventBus: Service,
    private canvas: Service,
    private tracker: ViewTracker,
  ) {
    eventBus.on('canvas.init', () => this.create());
    eventBus.on('sfc.view', () => this.update());
  }

  private create() {
    const layer = this.canvas.getLayer('sfc-grid', -100);
    const id = `sfc-grid-${++uid}`;
    this.group = el('g', { class: 'sfc-grid' }, layer);
    const defs = el('defs', {}, this.group);
    const pattern = el('pattern', { id, width: GRID * 5, height: GRID * 5, patternUnits: 'userSpaceOnUse' }, defs);
    let d = '';
    for (let i = 1; i < 5; i++) d += `M${i * GRID},0V${GRID * 5}M0,${i * GRID}H${GRID * 5}`;
    this.minor = el('path', { d, stroke: '#eef1f5', fill: 'none' }, pattern);
    this.major = el('path', { d: `M0,0V${GRID * 5}M0,0H${GRID * 5}`, stroke: '#dde3ea', fill: 'none' }, pattern);
    this.rect = el('rect', { fill: `url(#${id})` }, this.group);
    this.update();
  }

  /** Shows the grid when zoomed in enough and stretches it over the visible area. */
  update() {
    if (!this.rect || !this.group) return;
    const vb = this.tracker.view();
    const visible = vb.scale >= GRID_MIN_ZOOM;
    this.group.style.display = visible ? '' : 'none';
    if (!visible) return;
    const x = Math.floor(vb.x / (GRID * 5)) * GRID * 5;
    const y = Math.floor(vb.y / (GRID * 5)) * GRID * 5;
    this.rect.setAttribute('x', String(x));
    this.rect.setAttribute('y', String(y));
    this.rect.setAttribute('width', String(vb.width + GRID * 10));
    this.rect.setAttribute('height', String(vb.height + GRID * 10));
    // One screen pixel whatever the zoom.
    const w = String(1 / vb.scale);
    this.minor!.setAttribute('stroke-width', w);
    this.major!.setAttribute('stroke-width', w);
  }

  isVisible(): boolean {
    return !!this.group && this.group.style.display !== 'none';
  }
}
