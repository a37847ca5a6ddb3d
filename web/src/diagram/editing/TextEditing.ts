// In-place editing of a text label (seed 001 §7.2): double click opens a textarea over the
// block; Ctrl+Enter or a click outside ends it (one undoable change), Escape cancels.
import type { Service, SfcShape } from '../model';
import type { ViewTracker } from '../view/ViewTracker';

export class TextEditing {
  static $inject = ['eventBus', 'canvas', 'modeling', 'sfcView'];

  private area?: HTMLTextAreaElement;
  private shape?: SfcShape;

  constructor(
    eventBus: Service,
    private canvas: Service,
    private modeling: Service,
    private view: ViewTracker,
  ) {
    eventBus.on(['canvas.viewbox.changing', 'diagram.clear', 'diagram.destroy', 'commandStack.changed'], () => {
      if (this.area && !this.committing) this.complete();
    });
  }

  private committing = false;

  isActive(): boolean {
    return !!this.area;
  }

  activate(shape: SfcShape) {
    this.complete();
    const vb = this.view.view();
    const area = document.createElement('textarea');
    area.className = 'sfc-text-editor';
    area.value = shape.businessObject.text ?? '';
    area.spellcheck = false;
    const s = vb.scale;
    Object.assign(area.style, {
      left: `${(shape.x - vb.x) * s}px`,
      top: `${(shape.y - vb.y) * s}px`,
      width: `${Math.max(80, shape.width * s)}px`,
      height: `${Math.max(40, shape.height * s)}px`,
      fontSize: `${12 * s}px`,
      textAlign: shape.businessObject.align ?? 'left',
    });
    area.addEventListener('keydown', (e) => {
      e.stopPropagation();
      if (e.key === 'Enter' && (e.ctrlKey || e.metaKey)) {
        e.preventDefault();
        this.complete();
      } else if (e.key === 'Escape') {
        e.preventDefault();
        this.cancel();
      }
    });
    area.addEventListener('blur', () => this.complete());
    (this.canvas.getContainer() as HTMLElement).appendChild(area);
    this.area = area;
    this.shape = shape;
    area.focus();
    area.select();
  }

  /** Ends editing and stores the text when it changed. */
  complete() {
    const area = this.area;
    const shape = this.shape;
    if (!area || !shape) return;
    this.area = undefined;
    this.shape = undefined;
    area.remove();
    if (area.value !== (shape.businessObject.text ?? '')) {
      this.committing = true;
      try {
        this.modeling.updateElement(shape, { text: area.value });
      } finally {
        this.committing = false;
      }
    }
  }

  cancel() {
    const area = this.area;
    this.area = undefined;
    this.shape = undefined;
    area?.remove();
  }
}
