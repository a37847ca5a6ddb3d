// Mounts a canvas in jsdom for a test.
import './setup';
import { createCanvas, diagramOf } from '../../src/diagram';
import type { CanvasHandle } from '../../src/diagram/types';
import type { Service } from '../../src/diagram/model';

export interface Mounted {
  canvas: CanvasHandle;
  get: (name: string) => Service;
  container: HTMLElement;
}

export function mount(opts: { readOnly?: boolean; t?: (k: string) => string } = {}): Mounted {
  const container = document.createElement('div');
  document.body.appendChild(container);
  const canvas = createCanvas(container, { t: opts.t ?? ((k) => k), readOnly: opts.readOnly });
  const diagram = diagramOf(canvas);
  return { canvas, get: (name) => diagram.get(name), container };
}
