// The SFC Editor canvas: diagram-js with SFC blocks, pins and wires. The app uses it only
// through `CreateCanvas` (types.ts).
import Diagram from 'diagram-js/lib/Diagram.js';
import BendpointsModule from 'diagram-js/lib/features/bendpoints/index.js';
import CopyPasteModule from 'diagram-js/lib/features/copy-paste/index.js';
import EditorActionsModule from 'diagram-js/lib/features/editor-actions/index.js';
import GridSnappingModule from 'diagram-js/lib/features/grid-snapping/index.js';
import KeyboardModule from 'diagram-js/lib/features/keyboard/index.js';
import KeyboardMoveSelectionModule from 'diagram-js/lib/features/keyboard-move-selection/index.js';
import LassoToolModule from 'diagram-js/lib/features/lasso-tool/index.js';
import MoveModule from 'diagram-js/lib/features/move/index.js';
import OutlineModule from 'diagram-js/lib/features/outline/index.js';
import ResizeModule from 'diagram-js/lib/features/resize/index.js';
import SelectionModule from 'diagram-js/lib/features/selection/index.js';
import ZoomScrollModule from 'diagram-js/lib/navigation/zoomscroll/index.js';
import 'diagram-js/assets/diagram-js.css';
import '../diagram.css';

import type { EditorDoc } from '../doc';
import ConnectModule from './connect';
import CoreModule from './core';
import type { DocFields } from './core/DocState';
import EditingModule from './editing';
import { exportSvg } from './export/SvgExport';
import type { Highlights } from './highlight/Highlights';
import { validate, type DocImporter } from './import/DocImporter';
import { sameStructure } from './modeling/cmd/ReplaceDocHandler';
import { canDeleteStep, canInsert } from './modeling/cmd/StructureHandlers';
import ImportModule from './import';
import { isConnection, shapesOf, type Service } from './model';
import ModelingModule from './modeling';
import PaletteModule from './palette';
import RenderModule from './render';
import type { SfcRenderer } from './render/SfcRenderer';
import RulesModule from './rules';
import type { CanvasEvents, CanvasHandle, CanvasOptions, CreateCanvas } from './types';
import ViewModule from './view';
import type { ViewTracker } from './view/ViewTracker';
import { chartBounds } from './view/bounds';

export type { CanvasHandle, CanvasOptions, CreateCanvas } from './types';

const MIN_ZOOM = 0.1;
const MAX_ZOOM = 4;
/** The smallest zoom a chart opens at (smaller, it opens at 100 % showing its top; *Fit*
 *  shows all of it). */
export const OPEN_MIN_ZOOM = 0.6;

export const createCanvas: CreateCanvas = (container: HTMLElement, opts: CanvasOptions): CanvasHandle => {
  const readOnly = !!opts.readOnly;
  const config = { t: opts.t, readOnly };
  const host = document.createElement('div');
  host.className = 'sfc-canvas' + (readOnly ? ' sfc-readonly' : '');
  container.appendChild(host);

  const editing = readOnly
    ? []
    : [MoveModule, ResizeModule, BendpointsModule, CopyPasteModule, KeyboardMoveSelectionModule, GridSnappingModule, PaletteModule, ConnectModule];
  const diagram = new Diagram({
    // Deferred: diagram-js measures the whole drawing for each `viewbox.changed`; the grid,
    // scrollbars and zoom events follow the view through `sfc.view` instead.
    canvas: { container: host, deferUpdate: true },
    keyboard: { bind: true },
    keyboardMoveSelection: { moveSpeed: 10, moveSpeedAccelerated: 1 },
    zoomScroll: { enabled: true },
    sfc: config,
    modules: [
      CoreModule,
      RenderModule,
      SelectionModule,
      OutlineModule,
      RulesModule,
      ModelingModule,
      ImportModule,
      KeyboardModule,
      EditorActionsModule,
      LassoToolModule,
      ZoomScrollModule,
      ViewModule,
      EditingModule,
      ...editing,
    ],
  } as Service);

  // The palette docks: its own column left of the drawing (not floating over it), so the view,
  // and "fit", have the free canvas only.
  const dockedPalette = host.querySelector('.djs-palette');
  if (dockedPalette) {
    host.classList.add('sfc-docked');
    host.insertBefore(dockedPalette, host.firstChild);
  }

  const get = <T = Service>(name: string): T => diagram.get(name) as T;
  const eventBus = get('eventBus');
  const canvas = get('canvas');
  const elementRegistry = get('elementRegistry');
  const commandStack = get('commandStack');
  const modeling = get('modeling');
  const selection = get('selection');
  const importer = get<DocImporter>('sfcImporter');
  const highlights = get<Highlights>('sfcHighlights');
  const view = get<ViewTracker>('sfcView');
  if (dockedPalette) view.measure();

  type Listener = (...args: unknown[]) => void;
  const listeners = new Map<keyof CanvasEvents, Set<Listener>>();
  const emit = (event: keyof CanvasEvents, ...args: unknown[]) => {
    for (const cb of [...(listeners.get(event) ?? [])]) cb(...args);
  };

  let revision = 0;
  eventBus.on('commandStack.changed', () => {
    revision++;
    emit('change');
  });
  eventBus.on('selection.changed', (e: Service) => emit('selection', (e.newSelection as Service[]).map((x) => x.id)));
  eventBus.on('sfc.properties', (e: Service) => emit('properties', e.id));
  let lastZoom = 1;
  eventBus.on('sfc.view', (e: Service) => {
    const z = e.view.scale;
    if (z !== lastZoom) {
      lastZoom = z;
      emit('zoom', z);
    }
  });

  // Where the saved state sits in the undo stack: the action on top when saved.
  let savedTop: unknown = undefined;
  const top = () => commandStack._stack[commandStack._stackIdx];

  const find = (id: string, where: string) => {
    const e = elementRegistry.get(id);
    if (!e || (!isConnection(e) && !e.businessObject)) throw new Error(`${where}: no block or connection "${id}"`);
    return e;
  };

  /** Shows the chart: all of it centred in the view (`whole`, never beyond 100 %: *Fit*), or
   *  on load all of it when that stays readable, else its top at 100 %. The palette has its own
   *  column, so the view is the free canvas. */
  const showChart = (whole: boolean) => {
    const b = chartBounds(elementRegistry);
    const { width, height } = view.size();
    if (!b || width === 0 || height === 0) return;
    const m = 40;
    let scale = Math.max(MIN_ZOOM, Math.min(1, width / (b.width + 2 * m), height / (b.height + 2 * m)));
    // On load, names and conditions (12 px) stay readable: a chart that fits only below 60 %
    // shows its top at 100 % instead.
    if (!whole && scale < OPEN_MIN_ZOOM) scale = 1;
    // A chart wider than the view shows its top around the initial step (where it starts),
    // kept within the chart's extent.
    let x: number;
    if (b.width + 2 * m <= width / scale) {
      x = b.x + b.width / 2 - width / 2 / scale;
    } else {
      const first = shapesOf(elementRegistry).find((s) => s.businessObject.kind === 'step' && s.businessObject.initial);
      const left = b.x - m;
      const right = b.x + b.width + m - width / scale;
      x = first ? Math.min(right, Math.max(left, first.x + first.width / 2 - width / 2 / scale)) : left;
    }
    // *Fit* centres it vertically too; on load (and when it does not fit) it shows from its top,
    // where blocks dropped below it land in view.
    const y = whole && b.height + 2 * m <= height / scale ? b.y + b.height / 2 - height / 2 / scale : b.y - m;
    // As `canvas.viewbox(box)` with the size kept by the tracker: diagram-js would read the
    // container's size, forcing a layout of the whole drawing just added (200 ms at 500 steps).
    canvas._changeViewbox(() => {
      canvas._viewport.setAttribute('transform', `matrix(${scale},0,0,${scale},${-x * scale},${-y * scale})`);
    });
    view.tick();
  };

  const handle: CanvasHandle = {
    load(doc: EditorDoc) {
      importer.load(doc);
      revision++;
      savedTop = top();
      showChart(false);
    },
    getDoc: () => importer.getDoc(),
    revision: () => revision,
    updateElement(id, props) {
      modeling.updateElement(find(id, 'updateElement'), props as Record<string, unknown>);
    },
    updateDoc(props) {
      modeling.updateDoc(props as Partial<DocFields>);
    },
    applyLayout(laidOut) {
      for (const e of laidOut.elements) {
        const s = elementRegistry.get(e.id);
        if (!s || isConnection(s)) throw new Error(`applyLayout: no block "${e.id}" on the canvas`);
      }
      for (const c of laidOut.connections) {
        if (!isConnection(elementRegistry.get(c.id))) throw new Error(`applyLayout: no connection "${c.id}" on the canvas`);
      }
      modeling.applyLayout(laidOut);
    },
    replace(doc) {
      validate(doc);
      if (sameStructure(importer.getDoc(), doc)) {
        modeling.replaceDoc(doc);
        return true;
      }
      // Another set of blocks: loaded, and dirty until saved (no saved state to undo to).
      savedTop = { unsaved: true };
      importer.load(doc);
      revision++;
      return false;
    },
    structure(op) {
      if (readOnly || !handle.canStructure(op)) return false;
      const e = selection.get()[0];
      if (op === 'deleteStep') {
        modeling.deleteStepReconnect(e);
      } else {
        const created: Service[] = modeling.insertStructure(e, op === 'insertAfter' ? 'after' : 'before');
        const same = created.find((b) => b.businessObject.kind === e.businessObject.kind);
        if (same) selection.select(same);
      }
      return true;
    },
    canStructure(op) {
      const sel: Service[] = selection.get();
      if (readOnly || sel.length !== 1) return false;
      return op === 'deleteStep' ? canDeleteStep(sel[0]) : canInsert(sel[0]);
    },
    undo: () => commandStack.undo(),
    redo: () => commandStack.redo(),
    canUndo: () => commandStack.canUndo(),
    canRedo: () => commandStack.canRedo(),
    isDirty: () => top() !== savedTop,
    markSaved() {
      savedTop = top();
    },
    select(ids) {
      selection.select(ids.map((id) => find(id, 'select')));
    },
    selection: () => (selection.get() as Service[]).map((e) => e.id),
    highlight(kind, ids, labels) {
      highlights.set(kind, ids, labels);
    },
    clearHighlights(kind) {
      highlights.clear(kind);
    },
    reveal(id) {
      const e = find(id, 'reveal');
      if (isConnection(e)) {
        const xs = e.waypoints.map((p) => p.x);
        const ys = e.waypoints.map((p) => p.y);
        const box = { x: Math.min(...xs), y: Math.min(...ys), width: Math.max(...xs) - Math.min(...xs) + 1, height: Math.max(...ys) - Math.min(...ys) + 1 };
        canvas.scrollToElement({ ...box, id }, 60);
      } else {
        canvas.scrollToElement(e, 60);
      }
    },
    zoom(level) {
      if (level === 'fit') {
        showChart(true);
        return;
      } else {
        // About the middle of the view (diagram-js takes the centre in screen units).
        canvas.zoom(Math.max(MIN_ZOOM, Math.min(MAX_ZOOM, level)));
      }
      view.tick();
    },
    getZoom: () => view.view().scale,
    exportSvg: (options) => exportSvg(elementRegistry, get<SfcRenderer>('sfcRenderer'), options),
    relabel() {
      eventBus.fire('i18n.changed');
    },
    on(event, cb) {
      let set = listeners.get(event);
      if (!set) listeners.set(event, (set = new Set()));
      set.add(cb as Listener);
      return () => set!.delete(cb as Listener);
    },
    destroy() {
      listeners.clear();
      // With `deferUpdate`, diagram-js reports a view change 300 ms later from a timer that its
      // own destroy leaves running; it would then measure the removed container (a page error
      // when a tab closes or the monitor moves to another chart right after a zoom or scroll).
      canvas._viewboxChanged?.cancel?.();
      diagram.destroy();
      host.remove();
    },
  };
  diagrams.set(handle, diagram);
  return handle;
};

const diagrams = new WeakMap<CanvasHandle, Service>();

/** The diagram-js instance behind a handle (for tests and the demo page; the app uses the handle). */
export function diagramOf(handle: CanvasHandle): Service {
  return diagrams.get(handle);
}
