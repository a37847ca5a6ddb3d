// Example documents for the canvas tests: what the server sends for small real charts.
import type { EditorDoc } from '../../src/doc';

/** A conveyor: initial step, two-way selection, a parallel branch, a jump back; with an action
 *  block, a text label and wires with their full polylines. */
export function conveyorDoc(): EditorDoc {
  return {
    pou: 'Conveyor',
    pouKind: 'program',
    target: 'atmt',
    description: 'Stops the belt when the box arrives',
    declarations: 'VAR\n  start, box, stop : BOOL;\nEND_VAR\n',
    actions: [{ name: 'Motor', language: 'ST', body: 'motor := TRUE;' }],
    elements: [
      { id: 'step:Init', kind: 'step', x: 100, y: 40, w: 80, h: 40, name: 'Init', initial: true, tag: 0, description: 'Waiting for start' },
      { id: 'transition:Go', kind: 'transition', x: 120, y: 110, w: 40, h: 20, name: 'Go', condition: 'start AND NOT stop' },
      { id: 'step:Run', kind: 'step', x: 100, y: 160, w: 80, h: 40, name: 'Run', tag: 1, timeout: 'T#8.1s', background: '#fef9c3' },
      { id: 'b1', kind: 'actionBlock', x: 220, y: 170, w: 180, h: 20, step: 'step:Run', associations: [{ qualifier: 'N', action: 'Motor', indicator: 'busy' }] },
      { id: 'b2', kind: 'selectionDivergence', x: 60, y: 230, w: 160, h: 10, pins: 2 },
      { id: 'transition:Box', kind: 'transition', x: 50, y: 270, w: 40, h: 20, name: 'Box', condition: 'box', priority: 1 },
      { id: 'transition#3', kind: 'transition', x: 190, y: 270, w: 40, h: 20, condition: 'stop', conditionLanguage: 'ST' },
      { id: 'b3', kind: 'simultaneousDivergence', x: 20, y: 320, w: 120, h: 10, pins: 2 },
      { id: 'step:A', kind: 'step', x: 0, y: 360, w: 60, h: 40, name: 'A' },
      { id: 'step:B', kind: 'step', x: 100, y: 360, w: 60, h: 40, name: 'B', foreground: '#1d4ed8', lineWidth: 2 },
      { id: 'b4', kind: 'jump', x: 200, y: 320, w: 20, h: 20, target: 'Init' },
      { id: 'b5', kind: 'text', x: 300, y: 40, w: 160, h: 50, text: 'Belt conveyor\nsee drawing 12', align: 'left', font: '13px sans-serif' },
    ],
    connections: [
      { id: 'c1', source: 'step:Init', sourcePin: 0, target: 'transition:Go', targetPin: 0, waypoints: [{ x: 140, y: 80 }, { x: 140, y: 110 }] },
      { id: 'c2', source: 'transition:Go', sourcePin: 0, target: 'step:Run', targetPin: 0, waypoints: [{ x: 140, y: 130 }, { x: 140, y: 160 }] },
      { id: 'c3', source: 'step:Run', sourcePin: 0, target: 'b2', targetPin: 0, waypoints: [{ x: 140, y: 200 }, { x: 140, y: 230 }] },
      { id: 'c4', source: 'b2', sourcePin: 0, target: 'transition:Box', targetPin: 0, waypoints: [{ x: 70, y: 240 }, { x: 70, y: 270 }] },
      { id: 'c5', source: 'b2', sourcePin: 1, target: 'transition#3', targetPin: 0, waypoints: [{ x: 210, y: 240 }, { x: 210, y: 270 }], color: '#dc2626', lineWidth: 2 },
      { id: 'c6', source: 'transition:Box', sourcePin: 0, target: 'b3', targetPin: 0, waypoints: [{ x: 70, y: 290 }, { x: 70, y: 305 }, { x: 80, y: 305 }, { x: 80, y: 320 }] },
      { id: 'c7', source: 'b3', sourcePin: 0, target: 'step:A', targetPin: 0, waypoints: [{ x: 30, y: 330 }, { x: 30, y: 360 }] },
      { id: 'c8', source: 'b3', sourcePin: 1, target: 'step:B', targetPin: 0, waypoints: [{ x: 130, y: 330 }, { x: 130, y: 360 }] },
      { id: 'c9', source: 'transition#3', sourcePin: 0, target: 'b4', targetPin: 0, waypoints: [{ x: 210, y: 290 }, { x: 210, y: 320 }] },
    ],
  };
}
