// Follows the visible area without forcing a layout: diagram-js's `canvas.viewbox()` measures
// the whole drawing (getBBox) whenever blocks changed, which costs a forced layout on big
// charts. Here the view comes from the viewport's transform and the container size (kept by a
// ResizeObserver), once per animation frame; listeners get `sfc.view`.
import type { Service } from '../model';

export interface View {
  x: number;
  y: number;
  width: number;
  height: number;
  scale: number;
}

export class ViewTracker {
  static $inject = ['eventBus', 'canvas'];

  private w = 0;
  private h = 0;
  private pending = false;
  private observer?: ResizeObserver;

  constructor(
    private eventBus: Service,
    private canvas: Service,
  ) {
    eventBus.on('canvas.init', () => {
      const container: HTMLElement = canvas.getContainer();
      this.measure();
      if (typeof ResizeObserver !== 'undefined') {
        this.observer = new ResizeObserver(() => {
          this.measure();
          canvas.resized();
        });
        this.observer.observe(container);
      }
    });
    eventBus.on('canvas.viewbox.changing', () => this.schedule());
    eventBus.on(['canvas.viewbox.changed', 'canvas.resized', 'sfc.loaded'], () => this.tick());
    eventBus.on('elements.changed', () => this.schedule());
    eventBus.on('diagram.destroy', () => this.observer?.disconnect());
  }

  /** Measures the container again (after the palette docked beside it). */
  measure() {
    const c: HTMLElement = this.canvas.getContainer();
    this.w = c.clientWidth;
    this.h = c.clientHeight;
  }

  /** The visible area in canvas units. */
  view(): View {
    const vp: SVGGElement = this.canvas._viewport;
    const m = /matrix\(([^)]*)\)/.exec(vp?.getAttribute('transform') ?? '');
    const [a, , , , e, f] = m ? m[1].split(/[ ,]+/).map(Number) : [1, 0, 0, 1, 0, 0];
    const scale = a || 1;
    return { x: -e / scale, y: -f / scale, width: this.w / scale, height: this.h / scale, scale };
  }

  /** Container size in pixels as last measured. */
  size(): { width: number; height: number } {
    return { width: this.w, height: this.h };
  }

  private schedule() {
    if (this.pending) return;
    this.pending = true;
    const run = () => {
      this.pending = false;
      this.tick();
    };
    if (typeof requestAnimationFrame === 'function') requestAnimationFrame(run);
    else setTimeout(run, 0);
  }

  /** Tells listeners about the current view now. */
  tick() {
    this.eventBus.fire('sfc.view', { view: this.view() });
  }
}
