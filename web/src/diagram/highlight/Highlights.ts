// Highlight frames (diagnostics, witnesses, monitoring). The set lives here; the renderer draws
// it, so only the blocks whose highlight changed are drawn again.
import type { HighlightKind } from '../types';
import type { Service } from '../model';

export class Highlights {
  static $inject = ['elementRegistry', 'graphicsFactory', 'eventBus'];

  private byKind = new Map<HighlightKind, Map<string, string | undefined>>();

  constructor(
    private elementRegistry: Service,
    private graphicsFactory: Service,
    eventBus: Service,
  ) {
    eventBus.on('diagram.clear', () => this.byKind.clear());
  }

  /** Replaces the set of `kind`; redraws the blocks that gained or lost it. */
  set(kind: HighlightKind, ids: string[], labels?: Record<string, string>) {
    const before = this.byKind.get(kind) ?? new Map<string, string | undefined>();
    const after = new Map<string, string | undefined>();
    for (const id of ids) after.set(id, labels?.[id]);
    if (after.size === 0) this.byKind.delete(kind);
    else this.byKind.set(kind, after);
    const touched = new Set<string>();
    for (const [id, label] of after) if (!before.has(id) || before.get(id) !== label) touched.add(id);
    for (const id of before.keys()) if (!after.has(id)) touched.add(id);
    this.redraw(touched);
  }

  clear(kind?: HighlightKind) {
    const touched = new Set<string>();
    const kinds = kind ? [kind] : [...this.byKind.keys()];
    for (const k of kinds) {
      for (const id of this.byKind.get(k)?.keys() ?? []) touched.add(id);
      this.byKind.delete(k);
    }
    this.redraw(touched);
  }

  /** The highlight kinds of `id` and the label to show under it (the last one set wins). */
  of(id: string): { kinds: Set<HighlightKind>; label?: string } {
    const kinds = new Set<HighlightKind>();
    let label: string | undefined;
    for (const [k, m] of this.byKind) {
      if (m.has(id)) {
        kinds.add(k);
        label = m.get(id) ?? label;
      }
    }
    return { kinds, label };
  }

  private redraw(ids: Set<string>) {
    for (const id of ids) {
      const e = this.elementRegistry.get(id);
      if (!e) continue;
      const gfx = this.elementRegistry.getGraphics(e);
      this.graphicsFactory.update(e.waypoints ? 'connection' : 'shape', e, gfx);
    }
  }
}
