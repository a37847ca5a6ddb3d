// Non-blocking notifications (toasts) in the bottom-right corner: API errors, saves, copies.

export type ToastKind = 'error' | 'info' | 'success';

export interface Toast {
  id: number;
  kind: ToastKind;
  text: string;
}

export class Toasts {
  items: Toast[] = [];
  private listeners = new Set<() => void>();
  private next = 1;

  subscribe(listener: () => void): () => void {
    this.listeners.add(listener);
    return () => this.listeners.delete(listener);
  }

  /** Shows `text`; errors stay 8 s, others 4 s (or until dismissed). */
  show(kind: ToastKind, text: string): number {
    const id = this.next++;
    this.items = [...this.items, { id, kind, text }];
    this.emit();
    setTimeout(() => this.dismiss(id), kind === 'error' ? 8000 : 4000);
    return id;
  }

  dismiss(id: number): void {
    const before = this.items.length;
    this.items = this.items.filter((t) => t.id !== id);
    if (this.items.length !== before) this.emit();
  }

  private emit(): void {
    for (const l of [...this.listeners]) l();
  }
}

/** The app's notification area. */
export const toasts = new Toasts();
