// Manual demo: mounts the canvas with an example chart (`?big=N` for an N-step chart).
import { createCanvas, diagramOf } from '../../src/diagram';
import { conveyorDoc } from './fixtures';
import { makeBigDoc } from './big';

const params = new URLSearchParams(location.search);
const big = Number(params.get('big') ?? 0);
const status = document.getElementById('status')!;
const canvas = createCanvas(document.getElementById('canvas')!, { t: (k) => k, readOnly: params.has('ro') });
const doc = big > 0 ? makeBigDoc(big) : conveyorDoc();
const t0 = performance.now();
canvas.load(doc);
const loadMs = performance.now() - t0;
(window as unknown as Record<string, unknown>).sfcCanvas = canvas;
(window as unknown as Record<string, unknown>).sfcLoadMs = loadMs;
(window as unknown as Record<string, unknown>).sfcDiagram = diagramOf(canvas);

const show = () => {
  status.textContent = `${doc.elements.length} blocks · load ${loadMs.toFixed(0)} ms · zoom ${Math.round(canvas.getZoom() * 100)} % · ${canvas.isDirty() ? 'modified' : 'saved'} · selection: ${canvas.selection().join(', ') || '—'}`;
};
canvas.on('change', show);
canvas.on('selection', show);
canvas.on('zoom', show);
canvas.on('properties', (id) => (status.textContent = `properties of ${id}`));
document.getElementById('undo')!.onclick = () => canvas.undo();
document.getElementById('redo')!.onclick = () => canvas.redo();
document.getElementById('fit')!.onclick = () => canvas.zoom('fit');
document.getElementById('z100')!.onclick = () => canvas.zoom(1);
let monitoring = false;
const monitor = () => {
  monitoring = !monitoring;
  if (!monitoring) return canvas.clearHighlights();
  if (big > 0) return canvas.highlight('active', ['step:S3'], { 'step:S3': '1.2 s' });
  canvas.highlight('active', ['step:Run'], { 'step:Run': '3.4 s' });
  canvas.highlight('enabled', ['transition:Box']);
  canvas.highlight('breakpoint', ['transition#3']);
  canvas.highlight('warning', ['b4']);
};
document.getElementById('monitor')!.onclick = monitor;
if (params.has('monitor')) monitor();
if (params.has('zoom')) canvas.zoom(Number(params.get('zoom')));
show();
