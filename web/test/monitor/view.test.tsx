// The monitor view draws the runtime's state on the (fake) canvas: active steps with their
// elapsed time, true guards, breakpoints, the hit block framed instead of the active frame, and
// the toolbar's state; it loads a copy of the chart read-only and closes the socket on leaving.
import { render } from 'preact';
import { act } from 'preact/test-utils';
import { afterEach, beforeEach, describe, expect, it } from 'vitest';
import type { SocketLike } from '../../src/monitor/client';
import { MonitorView } from '../../src/monitor/MonitorView';
import type { MonitorTarget } from '../../src/monitor/session';
import type { EditorDoc } from '../../src/doc';
import { initI18n } from '../../src/i18n';
import { createFakeCanvas, type FakeCanvas } from '../app/fakeCanvas';

class FakeSocket implements SocketLike {
  readyState = 0;
  sent: Record<string, unknown>[] = [];
  closed = false;
  onopen: ((ev: unknown) => void) | null = null;
  onmessage: ((ev: { data: unknown }) => void) | null = null;
  onclose: ((ev: unknown) => void) | null = null;
  onerror: ((ev: unknown) => void) | null = null;
  send(d: string) {
    this.sent.push(JSON.parse(d));
  }
  close() {
    this.closed = true;
  }
  push(m: unknown) {
    this.onmessage?.({ data: JSON.stringify(m) });
  }
}

const doc: EditorDoc = {
  pou: 'Lamp',
  pouKind: 'program',
  target: 'blank',
  declarations: 'VAR Go : BOOL; END_VAR',
  actions: [],
  connections: [],
  elements: [
    { id: 'step:Off', kind: 'step', x: 0, y: 0, w: 80, h: 40, name: 'Off', initial: true },
    { id: 'transition:TOn', kind: 'transition', x: 0, y: 60, w: 20, h: 10, name: 'TOn' },
    { id: 'step:On', kind: 'step', x: 0, y: 100, w: 80, h: 40, name: 'On' },
  ],
};

const target: MonitorTarget = {
  url: 'ws://127.0.0.1:1/?token=t',
  doc,
  elements: { Off: ['step:Off'], TOn: ['transition:TOn'], On: ['step:On'] },
  simId: 3,
  title: 'lamp.st: Lamp',
};

let root: HTMLElement;
let canvas: FakeCanvas;
let socket: FakeSocket;

beforeEach(() => {
  initI18n('en');
  root = document.createElement('div');
  document.body.appendChild(root);
  socket = new FakeSocket();
  act(() => {
    render(
      <MonitorView
        target={target}
        createCanvas={(c, o) => {
          expect(o.readOnly).toBe(true);
          canvas = createFakeCanvas(c);
          return canvas;
        }}
        onLeave={() => undefined}
        socket={() => socket}
      />,
      root,
    );
  });
});

afterEach(() => {
  act(() => render(null, root));
  root.remove();
});

const say = (m: unknown) => act(() => socket.push(m));

describe('monitor view', () => {
  it('shows the state of the run on the chart and in the toolbar', async () => {
    expect(canvas.getDoc().pou).toBe('Lamp');
    act(() => {
      socket.readyState = 1;
      socket.onopen?.({});
    });
    say({
      type: 'hello', protocol: 'sfc-monitor', version: 1, runtime: 'sfc run', pou: 'Lamp', period: 'T#10ms', control: true,
      tokenRequired: true, authorized: true, halted: false, history: 100,
      steps: [{ name: 'Off', initial: true }, { name: 'On', initial: false }],
      transitions: [{ name: 'TOn', from: ['Off'], to: ['On'] }],
      variables: [{ name: 'Go', type: 'BOOL' }],
    });
    // The breakpoint list arrives as the reply to the client's `breakpoints` (a promise).
    await act(async () => socket.push({ type: 'reply', re: socket.sent[0].id, ok: true, result: [{ kind: 'step', name: 'On', enabled: true }] }));
    say({
      type: 'snapshot', scan: 5, time: 'T#50ms', timeUs: 50000, halted: false,
      active: [{ step: 'Off', elapsed: 'T#1s500ms', elapsedUs: 1_500_000 }], fired: [], guards: { TOn: true }, vars: { Go: true }, forced: [],
    });
    expect(canvas.highlights.active).toEqual({ ids: ['step:Off'], labels: { 'step:Off': '1.5 s' } });
    expect(canvas.highlights.enabled?.ids).toEqual(['transition:TOn']);
    expect(canvas.highlights.breakpoint?.ids).toEqual(['step:On']);
    expect(root.querySelector('[data-testid="monitor-state"]')?.textContent).toBe('Running');
    expect(root.querySelector('[data-testid="monitor-scan"]')?.textContent).toBe('scan 5 · T#50ms');
    expect(root.querySelector('tr[data-var="Go"] .mon-val')?.textContent).toBe('TRUE');

    // The breakpoint on On is hit: On framed orange (not green), the run halted.
    say({ type: 'event', kind: 'breakpoint', step: 'On', scan: 6 });
    say({ type: 'delta', scan: 6, time: 'T#60ms', timeUs: 60000, active: [{ step: 'On', elapsed: 'T#0s', elapsedUs: 0 }], fired: ['TOn'], guards: {} });
    say({ type: 'halted', reason: 'breakpoint', scan: 6 });
    expect(canvas.highlights.hit).toEqual({ ids: ['step:On'], labels: { 'step:On': '0 ms' } });
    expect(canvas.highlights.active?.ids ?? []).toEqual([]);
    expect(canvas.highlights.enabled?.ids ?? []).toEqual([]);
    expect(root.querySelector('[data-testid="monitor-state"]')?.textContent).toBe('Halted at On');
    const button = (name: string) => root.querySelector<HTMLButtonElement>(`button[aria-label="${name}"]`)!;
    expect(button('Continue').disabled).toBe(false);
    expect(button('Halt').disabled).toBe(true);

    // Continue sends `continue`; resumed clears the hit frame.
    act(() => button('Continue').click());
    expect(socket.sent[socket.sent.length - 1]).toMatchObject({ cmd: 'continue' });
    say({ type: 'resumed', scan: 6 });
    expect(canvas.highlights.hit?.ids ?? []).toEqual([]);
    expect(canvas.highlights.active?.ids).toEqual(['step:On']);
  });

  it('closes the connection when it goes', () => {
    act(() => render(null, root));
    expect(socket.closed).toBe(true);
  });
});
