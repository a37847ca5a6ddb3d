// Mouse and keyboard glue: a drag on empty canvas draws a selection lasso, the middle button
// pans, a double click opens the properties (or edits a text label in place), Enter opens the
// properties of the selected block.
import { isPrimaryButton } from 'diagram-js/lib/util/Mouse.js';
import { isShape, type Service } from '../model';
import type { TextEditing } from './TextEditing';

export class Interaction {
  static $inject = ['eventBus', 'canvas', 'selection', 'keyboard', 'sfcTextEditing', 'injector', 'config.sfc'];

  constructor(
    private eventBus: Service,
    canvas: Service,
    selection: Service,
    keyboard: Service,
    textEditing: TextEditing,
    injector: Service,
    config: { readOnly?: boolean },
  ) {
    const lasso = injector.get('lassoTool', false);
    eventBus.on('element.mousedown', 500, (event: Service) => {
      const oe = event.originalEvent as MouseEvent | undefined;
      if (!oe || event.element !== canvas.getRootElement() || !isPrimaryButton(oe) || !lasso) return;
      lasso.activateLasso(oe);
      return true;
    });

    eventBus.on('element.dblclick', (event: Service) => {
      const e = event.element;
      if (!isShape(e)) {
        if (e?.waypoints) this.properties(e.id);
        return;
      }
      if (e.businessObject.kind === 'text' && !config?.readOnly) textEditing.activate(e);
      else this.properties(e.id);
    });

    keyboard.addListener(2000, (ctx: Service) => {
      const ev = ctx.keyEvent as KeyboardEvent;
      if (ev.key !== 'Enter' || ev.ctrlKey || ev.altKey || ev.metaKey) return;
      const sel = selection.get();
      if (sel.length !== 1) return;
      this.properties(sel[0].id);
      return true;
    });

    // Middle-button drag pans the view.
    eventBus.on('canvas.init', () => {
      const container: HTMLElement = canvas.getContainer();
      container.addEventListener('mousedown', (down) => {
        if (down.button !== 1) return;
        down.preventDefault();
        let last = { x: down.clientX, y: down.clientY };
        container.classList.add('sfc-panning');
        const move = (e: MouseEvent) => {
          canvas.scroll({ dx: e.clientX - last.x, dy: e.clientY - last.y });
          last = { x: e.clientX, y: e.clientY };
        };
        const up = () => {
          container.classList.remove('sfc-panning');
          window.removeEventListener('mousemove', move);
          window.removeEventListener('mouseup', up);
        };
        window.addEventListener('mousemove', move);
        window.addEventListener('mouseup', up);
      });
    });
  }

  private properties(id: string) {
    this.eventBus.fire('sfc.properties', { id });
  }
}
