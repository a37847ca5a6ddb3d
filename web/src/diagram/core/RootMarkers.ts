// The markers diagram-js puts on the chart itself (the root) while something is dragged —
// `drop-ok`, `new-parent`, `attach-ok`, `connect-ok`, `djs-drag-active` — are not set. The
// editor draws nothing for them, and diagram-js's stylesheet has rules such as `.drop-ok *`
// for them, so each toggle on the root restyles every node of the drawing: about 80 ms per
// toggle on a 500-step chart, four of them when a drag starts and four when it ends. The
// refusals (`drop-not-ok`, `connect-not-ok`) stay: they give the "not allowed" cursor.
import type { Service } from '../model';

const QUIET = new Set(['drop-ok', 'new-parent', 'attach-ok', 'connect-ok', 'djs-drag-active']);

export class RootMarkers {
  static $inject = ['canvas'];

  constructor(canvas: Service) {
    const update = canvas._updateMarker.bind(canvas);
    canvas._updateMarker = (element: Service, marker: string, add: boolean) => {
      if (QUIET.has(marker) && isRoot(canvas, element)) return;
      update(element, marker, add);
    };
  }
}

function isRoot(canvas: Service, element: Service): boolean {
  const root = canvas.getRootElement();
  return element === root || element === root.id;
}
