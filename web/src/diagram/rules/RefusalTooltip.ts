// Says why a block cannot be dropped: while a block the chart's target refuses (an action block
// or an AND branch in an ATMT/EATMT chart) is dragged over the chart, a tooltip beside the
// pointer gives the reason (the rules refuse the drop itself); after a refused drop it stays a
// moment so the user can read it.
import type { ElementKind } from '../../doc';
import type { DocState } from '../core/DocState';
import type { Service } from '../model';
import { refusalReason } from './SfcRules';

const LINGER_MS = 4000;

export class RefusalTooltip {
  static $inject = ['eventBus', 'canvas', 'config.sfc', 'sfcDocState'];

  private tip: HTMLDivElement | null = null;
  private timer: ReturnType<typeof setTimeout> | undefined;

  constructor(
    eventBus: Service,
    private canvas: Service,
    private config: { t: (key: string, opts?: Record<string, unknown>) => string },
    private state: DocState,
  ) {
    eventBus.on(['create.move', 'create.hover'], 200, (event: Service) => {
      const why = this.reason(event.context);
      if (why) this.show(why, event.originalEvent);
      else this.hide();
    });
    eventBus.on('create.out', () => this.hide());
    eventBus.on('create.end', 2000, (event: Service) => {
      const why = this.reason(event.context);
      if (why) {
        this.show(why, event.originalEvent);
        this.hideLater();
      } else {
        this.hide();
      }
    });
    eventBus.on(['create.cancel'], () => this.hide());
    eventBus.on('diagram.destroy', () => this.hide());
  }

  private reason(ctx: Service): string {
    const shapes: Service[] = ctx?.elements ?? (ctx?.shape ? [ctx.shape] : []);
    for (const s of shapes) {
      const kind = s?.businessObject?.kind as ElementKind | undefined;
      const why = kind ? refusalReason(kind, this.state.fields.target, this.config.t) : '';
      if (why) return why;
    }
    return '';
  }

  private show(text: string, pointer: MouseEvent | undefined) {
    clearTimeout(this.timer);
    const container = this.canvas.getContainer() as HTMLElement;
    if (!this.tip) {
      this.tip = document.createElement('div');
      this.tip.className = 'sfc-refusal-tip';
      this.tip.setAttribute('role', 'tooltip');
      container.appendChild(this.tip);
    }
    this.tip.textContent = text;
    const r = container.getBoundingClientRect();
    const x = (pointer?.clientX ?? r.left + r.width / 2) - r.left + 16;
    const y = (pointer?.clientY ?? r.top + r.height / 2) - r.top + 16;
    this.tip.style.left = `${Math.min(x, Math.max(0, r.width - 300))}px`;
    this.tip.style.top = `${Math.min(y, Math.max(0, r.height - 80))}px`;
  }

  private hideLater() {
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.hide(), LINGER_MS);
  }

  private hide() {
    clearTimeout(this.timer);
    this.tip?.remove();
    this.tip = null;
  }
}
