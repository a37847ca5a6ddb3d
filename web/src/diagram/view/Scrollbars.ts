// Scrollbars over the canvas edges (diagram-js has none): they show where the view is within
// the chart plus a margin, and scroll the view when their thumb is dragged or the track clicked.
import type { Service } from '../model';
import { chartBounds, type Rect } from './bounds';
import type { ViewTracker } from './ViewTracker';

const MARGIN = 200;

export class Scrollbars {
  static $inject = ['eventBus', 'canvas', 'elementRegistry', 'sfcView'];

  private h!: HTMLDivElement;
  private v!: HTMLDivElement;
  private hThumb!: HTMLDivElement;
  private vThumb!: HTMLDivElement;
  private chart?: Rect;
  /** The chart's extent is measured again on the next view update after a change. */
  private stale = true;

  constructor(
    eventBus: Service,
    private canvas: Service,
    private elementRegistry: Service,
    private tracker: ViewTracker,
  ) {
    eventBus.on('canvas.init', () => this.create());
    eventBus.on(['elements.changed', 'sfc.loaded'], () => (this.stale = true));
    eventBus.on('sfc.view', () => this.update());
    eventBus.on('diagram.destroy', () => {
      this.h?.remove();
      this.v?.remove();
    });
  }

  private create() {
    const container: HTMLElement = this.canvas.getContainer();
    this.h = bar('sfc-scrollbar sfc-scrollbar-h');
    this.v = bar('sfc-scrollbar sfc-scrollbar-v');
    this.hThumb = this.h.firstChild as HTMLDivElement;
    this.vThumb = this.v.firstChild as HTMLDivElement;
    container.appendChild(this.h);
    container.appendChild(this.v);
    this.drag(this.hThumb, this.h, 'x');
    this.drag(this.vThumb, this.v, 'y');
  }

  /** The scrollable range: the chart plus a margin, and always the current view. */
  private range(): Rect {
    if (this.stale) {
      this.chart = chartBounds(this.elementRegistry);
      this.stale = false;
    }
    const vb = this.tracker.view();
    const c = this.chart ?? { x: 0, y: 0, width: 0, height: 0 };
    const x0 = Math.min(c.x - MARGIN, vb.x);
    const y0 = Math.min(c.y - MARGIN, vb.y);
    const x1 = Math.max(c.x + c.width + MARGIN, vb.x + vb.width);
    const y1 = Math.max(c.y + c.height + MARGIN, vb.y + vb.height);
    return { x: x0, y: y0, width: x1 - x0, height: y1 - y0 };
  }

  update() {
    if (!this.h) return;
    const vb = this.tracker.view();
    const r = this.range();
    place(this.h, this.hThumb, 'x', (vb.x - r.x) / r.width, vb.width / r.width);
    place(this.v, this.vThumb, 'y', (vb.y - r.y) / r.height, vb.height / r.height);
  }

  private drag(thumb: HTMLDivElement, track: HTMLDivElement, axis: 'x' | 'y') {
    thumb.addEventListener('mousedown', (down) => {
      down.preventDefault();
      down.stopPropagation();
      const r = this.range();
      const trackLen = axis === 'x' ? track.clientWidth : track.clientHeight;
      const total = axis === 'x' ? r.width : r.height;
      const start = axis === 'x' ? down.clientX : down.clientY;
      const vb0 = this.tracker.view();
      thumb.classList.add('active');
      const move = (e: MouseEvent) => {
        const d = ((axis === 'x' ? e.clientX : e.clientY) - start) * (total / Math.max(1, trackLen));
        const vb = this.tracker.view();
        const target = (axis === 'x' ? vb0.x : vb0.y) + d;
        const current = axis === 'x' ? vb.x : vb.y;
        const px = (target - current) * vb.scale;
        this.canvas.scroll(axis === 'x' ? { dx: -px, dy: 0 } : { dx: 0, dy: -px });
      };
      const up = () => {
        thumb.classList.remove('active');
        window.removeEventListener('mousemove', move);
        window.removeEventListener('mouseup', up);
      };
      window.addEventListener('mousemove', move);
      window.addEventListener('mouseup', up);
    });
    // A click on the track pages towards the click.
    track.addEventListener('mousedown', (e) => {
      if (e.target !== track) return;
      e.preventDefault();
      const rect = thumb.getBoundingClientRect();
      const before = axis === 'x' ? e.clientX < rect.left : e.clientY < rect.top;
      const vb = this.tracker.view();
      const page = (axis === 'x' ? vb.width : vb.height) * 0.9 * vb.scale;
      const px = before ? page : -page;
      this.canvas.scroll(axis === 'x' ? { dx: px, dy: 0 } : { dx: 0, dy: px });
    });
  }
}

function bar(cls: string): HTMLDivElement {
  const track = document.createElement('div');
  track.className = cls;
  const thumb = document.createElement('div');
  thumb.className = 'sfc-scrollbar-thumb';
  track.appendChild(thumb);
  return track;
}

function place(track: HTMLDivElement, thumb: HTMLDivElement, axis: 'x' | 'y', start: number, size: number) {
  const s = Math.max(0, Math.min(1, size));
  const p = Math.max(0, Math.min(1 - s, start));
  track.style.display = s >= 0.999 ? 'none' : '';
  if (axis === 'x') {
    thumb.style.left = `${p * 100}%`;
    thumb.style.width = `${s * 100}%`;
  } else {
    thumb.style.top = `${p * 100}%`;
    thumb.style.height = `${s * 100}%`;
  }
}
