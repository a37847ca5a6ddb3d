// The monitor client's state handling against a fake socket: snapshot and delta merging, the
// halt / hit / resume cycle, history navigation, breakpoint lists, reply matching by id, the
// queue before the socket opens, and what a closed connection does to waiting commands.
import { describe, expect, it } from 'vitest';
import { MonitorClient, MonitorError, type SocketLike } from '../../src/monitor/client';
import { elementsByName, blocksOf, nameOfBlock } from '../../src/monitor/session';
import { mergeDelta, parseValue, shortDuration, showValue, toState } from '../../src/monitor/protocol';
import type { EditorDoc } from '../../src/doc';

class FakeSocket implements SocketLike {
  readyState = 0;
  sent: Record<string, unknown>[] = [];
  onopen: ((ev: unknown) => void) | null = null;
  onmessage: ((ev: { data: unknown }) => void) | null = null;
  onclose: ((ev: unknown) => void) | null = null;
  onerror: ((ev: unknown) => void) | null = null;
  constructor(readonly url: string) {}
  send(data: string) {
    this.sent.push(JSON.parse(data));
  }
  close() {
    this.readyState = 3;
  }
  open() {
    this.readyState = 1;
    this.onopen?.({});
  }
  push(m: unknown) {
    this.onmessage?.({ data: JSON.stringify(m) });
  }
  /** Answers the last command sent. */
  reply(result: unknown, ok = true) {
    const last = this.sent[this.sent.length - 1];
    this.push(ok ? { type: 'reply', re: last.id, ok: true, result } : { type: 'reply', re: last.id, ok: false, error: result });
  }
  drop() {
    this.readyState = 3;
    this.onclose?.({});
  }
}

const HELLO = {
  type: 'hello',
  protocol: 'sfc-monitor',
  version: 1,
  runtime: 'sfc run',
  pou: 'CarWash',
  period: 'T#10ms',
  control: true,
  tokenRequired: true,
  authorized: true,
  halted: false,
  history: 100,
  steps: [
    { name: 'Idle', initial: true },
    { name: 'Spraying', initial: false },
  ],
  transitions: [{ name: 'TStart', from: ['Idle'], to: ['Spraying'] }],
  variables: [
    { name: 'StartButton', type: 'BOOL', location: '%IX0.0' },
    { name: 'Washes', type: 'UDINT' },
  ],
};

const SNAPSHOT = {
  type: 'snapshot',
  scan: 10,
  time: 'T#100ms',
  timeUs: 100000,
  halted: false,
  active: [{ step: 'Idle', elapsed: 'T#100ms', elapsedUs: 100000 }],
  fired: [],
  guards: { TStart: false },
  vars: { StartButton: false, Washes: 0 },
  forced: [],
  stats: { scans: 11 },
};

function connected(): { c: MonitorClient; s: FakeSocket } {
  let s!: FakeSocket;
  const c = new MonitorClient('ws://127.0.0.1:1/?token=x', (u) => (s = new FakeSocket(u)));
  s.open();
  s.push(HELLO);
  // The client asks for the breakpoint list after hello.
  expect(s.sent[0]).toMatchObject({ cmd: 'breakpoints' });
  s.reply([]);
  s.push(SNAPSHOT);
  return { c, s };
}

const flush = () => new Promise((r) => setTimeout(r, 0));

describe('state', () => {
  it('merges deltas into the snapshot', () => {
    const { c, s } = connected();
    expect(c.info?.pou).toBe('CarWash');
    expect(c.live?.scan).toBe(10);
    expect((c.live as unknown as Record<string, unknown>).stats).toBeUndefined();
    s.push({ type: 'delta', scan: 12, time: 'T#120ms', timeUs: 120000, active: [{ step: 'Idle', elapsed: 'T#120ms', elapsedUs: 120000 }], fired: [], vars: { StartButton: true } });
    expect(c.live).toMatchObject({ scan: 12, vars: { StartButton: true, Washes: 0 }, guards: { TStart: false }, forced: [] });
    s.push({
      type: 'delta',
      scan: 13,
      time: 'T#130ms',
      timeUs: 130000,
      active: [{ step: 'Spraying', elapsed: 'T#0s', elapsedUs: 0 }],
      fired: ['TStart'],
      guards: { TCarAtBrush: false },
      forced: ['Washes'],
    });
    expect(c.view()).toMatchObject({ scan: 13, fired: ['TStart'], guards: { TCarAtBrush: false }, forced: ['Washes'], vars: { StartButton: true } });
    expect(c.view()!.active.map((a) => a.step)).toEqual(['Spraying']);
  });

  it('mergeDelta leaves the base state untouched', () => {
    const base = toState(SNAPSHOT);
    const next = mergeDelta(base, { type: 'delta', scan: 11, time: 'T#110ms', timeUs: 110000, active: [], fired: [], vars: { Washes: 3 } });
    expect(base.vars.Washes).toBe(0);
    expect(next.vars).toEqual({ StartButton: false, Washes: 3 });
  });

  it('a breakpoint hit halts; continue resumes and forgets the hit', async () => {
    const { c, s } = connected();
    s.push({ type: 'event', kind: 'breakpoint', step: 'Spraying', scan: 14 });
    s.push({ type: 'halted', reason: 'breakpoint', scan: 14 });
    expect(c.halted).toBe(true);
    expect(c.haltReason).toBe('breakpoint');
    expect(c.hit).toEqual({ kind: 'step', name: 'Spraying', scan: 14 });
    expect(c.displayPaused).toBe(false);
    const done = c.resume();
    expect(s.sent[s.sent.length - 1]).toMatchObject({ cmd: 'continue' });
    s.reply(null);
    await done;
    s.push({ type: 'resumed', scan: 14 });
    expect(c.halted).toBe(false);
    expect(c.hit).toBeNull();
    expect(c.events.map((e) => e.kind)).toEqual(['breakpoint']);
  });

  it('follows RUN, FAULT and a reset (docs/runtime.md, "States")', async () => {
    const { c, s } = connected();
    expect(c.runState).toBe('RUN');
    const fault = { kind: 'watchdog', step: 'Spraying', action: 'Spray', line: 12, message: 'watchdog: scan 14 …' };
    s.push({ type: 'state', state: 'FAULT', fault, scan: 14, outputs: { SprayValve: false } });
    s.push({ type: 'halted', reason: 'fault', scan: 14 });
    expect(c.runState).toBe('FAULT');
    expect(c.fault).toMatchObject({ step: 'Spraying', line: 12 });
    const done = c.reset();
    expect(s.sent[s.sent.length - 1]).toMatchObject({ cmd: 'reset', mode: 'warm' });
    s.reply({ state: 'RUN', mode: 'warm', scan: 15 });
    await done;
    s.push({ type: 'state', state: 'RUN', fault: null, scan: 15 });
    s.push({ type: 'resumed', scan: 15 });
    expect(c.runState).toBe('RUN');
    expect(c.fault).toBeNull();
    expect(c.halted).toBe(false);
  });

  it('a runtime that cannot halt freezes the display on a hit instead', () => {
    let s!: FakeSocket;
    const c = new MonitorClient('ws://x/', (u) => (s = new FakeSocket(u)));
    s.open();
    s.push({ ...HELLO, runtime: 'atmt', control: false });
    s.reply([]);
    s.push(SNAPSHOT);
    s.push({ type: 'event', kind: 'breakpoint', transition: 'TStart', scan: 11 });
    expect(c.hit).toMatchObject({ kind: 'transition', name: 'TStart' });
    expect(c.displayPaused).toBe(true);
    expect(s.sent[s.sent.length - 1]).toMatchObject({ cmd: 'pause' });
    // Deltas move the live state; the display stays on the moment of the hit.
    s.push({ type: 'delta', scan: 20, time: 'T#200ms', timeUs: 200000, active: [], fired: [] });
    expect(c.live?.scan).toBe(20);
    expect(c.view()?.scan).toBe(10);
    expect(c.canControl()).toBe(false);
  });

  it('pausing the display freezes the view while the live state moves on', async () => {
    const { c, s } = connected();
    const p = c.pauseDisplay();
    expect(s.sent[s.sent.length - 1]).toMatchObject({ cmd: 'pause' });
    s.reply({ paused: true });
    await p;
    s.push({ type: 'delta', scan: 30, time: 'T#300ms', timeUs: 300000, active: [], fired: [] });
    expect(c.view()?.scan).toBe(10);
    const r = c.resumeDisplay();
    s.reply({ paused: false });
    await r;
    s.push({ ...SNAPSHOT, scan: 40 });
    expect(c.view()?.scan).toBe(40);
  });
});

describe('history', () => {
  it('loads the buffered states and steps through them', async () => {
    const { c, s } = connected();
    const loading = c.loadHistory();
    const req = s.sent[s.sent.length - 1];
    expect(req).toMatchObject({ cmd: 'history', count: 100 });
    const states = [7, 8, 9, 10].map((scan) => ({ ...SNAPSHOT, scan, active: [{ step: scan < 9 ? 'Idle' : 'Spraying', elapsed: 'T#0s', elapsedUs: 0 }] }));
    s.push({ type: 'history', re: req.id, ok: true, states });
    const h = await loading;
    expect(h.index).toBe(3);
    expect(c.view()?.scan).toBe(10);
    c.moveHistory(-1);
    c.moveHistory(-1);
    expect(c.view()?.scan).toBe(8);
    expect(c.view()?.active[0].step).toBe('Idle');
    c.moveHistory(-10);
    expect(c.history?.index).toBe(0);
    c.moveHistory('last');
    expect(c.view()?.scan).toBe(10);
    c.moveHistory(5);
    expect(c.history?.index).toBe(3);
    c.moveHistory('first');
    // Live deltas do not move the browsed state.
    s.push({ type: 'delta', scan: 50, time: 'T#500ms', timeUs: 500000, active: [], fired: [] });
    expect(c.view()?.scan).toBe(7);
    c.leaveHistory();
    expect(c.view()?.scan).toBe(50);
  });

  it('a single scan or continue leaves the history', async () => {
    const { c, s } = connected();
    const loading = c.loadHistory();
    s.push({ type: 'history', re: s.sent[s.sent.length - 1].id, ok: true, states: [SNAPSHOT] });
    await loading;
    const step = c.singleScan();
    expect(c.history).toBeNull();
    s.reply({ scan: 11 });
    expect(await step).toBe(11);
  });
});

describe('breakpoints', () => {
  it('keeps the list the runtime answers with', async () => {
    const { c, s } = connected();
    const set = c.toggleBreakpoint('step', 'Spraying');
    expect(s.sent[s.sent.length - 1]).toMatchObject({ cmd: 'breakpoint', op: 'set', kind: 'step', name: 'Spraying' });
    s.reply([{ kind: 'step', name: 'Spraying', enabled: true }]);
    await set;
    expect(c.findBreakpoint('step', 'spraying')?.enabled).toBe(true);
    const t2 = c.breakpoint('set', 'transition', 'TStart');
    s.reply([
      { kind: 'step', name: 'Spraying', enabled: true },
      { kind: 'transition', name: 'TStart', enabled: true },
    ]);
    await t2;
    // Disable all: one `disable` per enabled breakpoint.
    const all = c.toggleAllBreakpoints();
    expect(s.sent[s.sent.length - 1]).toMatchObject({ op: 'disable', name: 'Spraying' });
    s.reply([
      { kind: 'step', name: 'Spraying', enabled: false },
      { kind: 'transition', name: 'TStart', enabled: true },
    ]);
    await flush();
    expect(s.sent[s.sent.length - 1]).toMatchObject({ op: 'disable', kind: 'transition', name: 'TStart' });
    s.reply([
      { kind: 'step', name: 'Spraying', enabled: false },
      { kind: 'transition', name: 'TStart', enabled: false },
    ]);
    await all;
    expect(c.breakpoints.every((b) => !b.enabled)).toBe(true);
    // Toggling an existing breakpoint deletes it.
    const del = c.toggleBreakpoint('step', 'Spraying');
    expect(s.sent[s.sent.length - 1]).toMatchObject({ op: 'delete', name: 'Spraying' });
    s.reply([{ kind: 'transition', name: 'TStart', enabled: false }]);
    await del;
    const none = c.deleteAllBreakpoints();
    expect(s.sent[s.sent.length - 1]).toMatchObject({ op: 'deleteAll' });
    s.reply([]);
    expect(await none).toEqual([]);
  });
});

describe('commands', () => {
  it('queues commands until the socket opens and matches replies by id', async () => {
    let s!: FakeSocket;
    const c = new MonitorClient('ws://x/', (u) => (s = new FakeSocket(u)));
    const a = c.force('Washes', 7);
    const b = c.set('StartButton', true);
    expect(s.sent).toEqual([]);
    s.open();
    expect(s.sent.map((m) => m.cmd)).toEqual(['force', 'set']);
    expect(s.sent[0]).toMatchObject({ name: 'Washes', value: 7 });
    // Replies out of order still reach their commands.
    s.push({ type: 'reply', re: s.sent[1].id, ok: true, result: true });
    s.push({ type: 'reply', re: s.sent[0].id, ok: false, error: '`Washes` is UDINT: -1 is out of range' });
    await expect(b).resolves.toBe(true);
    await expect(a).rejects.toThrow('out of range');
    // A reply nobody waits for, and garbage, are ignored.
    s.push({ type: 'reply', re: 999, ok: true, result: 1 });
    s.onmessage?.({ data: 'not json' });
  });

  it('a closed connection fails the waiting commands and refuses new ones', async () => {
    const { c, s } = connected();
    const waiting = c.explain('Idle');
    s.drop();
    await expect(waiting).rejects.toBeInstanceOf(MonitorError);
    expect(c.status).toBe('closed');
    await expect(c.timing()).rejects.toThrow('connection closed');
  });

  it('the runtime dropping the client says why', () => {
    const { c, s } = connected();
    s.push({ type: 'error', error: 'flooding: more than 200 messages a second' });
    s.drop();
    expect(c.closeReason).toBe('flooding: more than 200 messages a second');
  });
});

describe('values', () => {
  it('parses typed input by IEC type', () => {
    expect(parseValue('BOOL', 'true')).toBe(true);
    expect(parseValue('BOOL', 'FALSE')).toBe(false);
    expect(parseValue('BOOL', 'yes')).toBeInstanceOf(Error);
    expect(parseValue('UDINT', ' 42 ')).toBe(42);
    expect(parseValue('INT', '-3')).toBe(-3);
    expect(parseValue('INT', '1.5')).toBeInstanceOf(Error);
    expect(parseValue('REAL', '1.5')).toBe(1.5);
    expect(parseValue('REAL', '')).toBeInstanceOf(Error);
    expect(parseValue('TIME', 'T#1s500ms')).toBe('T#1s500ms');
    expect(parseValue('TIME', '1500')).toBeInstanceOf(Error);
    expect(parseValue('STRING', ' a b ')).toBe(' a b ');
  });
  it('shows values and durations', () => {
    expect(showValue(true)).toBe('TRUE');
    expect(showValue(0)).toBe('0');
    expect(showValue(undefined)).toBe('');
    expect(shortDuration(250_000)).toBe('250 ms');
    expect(shortDuration(12_340_000)).toBe('12.3 s');
    expect(shortDuration(125_000_000)).toBe('2:05 min');
  });
});

describe('blocks by name', () => {
  const doc: EditorDoc = {
    pou: 'P',
    pouKind: 'program',
    target: 'blank',
    declarations: '',
    actions: [],
    connections: [],
    elements: [
      { id: 's1', kind: 'step', x: 0, y: 0, w: 10, h: 10, name: 'Idle', initial: true },
      { id: 't1', kind: 'transition', x: 0, y: 0, w: 10, h: 10, name: '' },
      { id: 't2', kind: 'transition', x: 0, y: 0, w: 10, h: 10, name: 'TGo' },
      { id: 'x', kind: 'text', x: 0, y: 0, w: 10, h: 10, text: 'Idle' },
    ],
  };
  it('maps runtime names to blocks, unnamed transitions as T<n>', () => {
    const m = elementsByName(doc);
    expect(blocksOf(m, 'idle')).toEqual(['s1']);
    expect(blocksOf(m, 'T1')).toEqual(['t1']);
    expect(blocksOf(m, 'TGo')).toEqual(['t2']);
    expect(blocksOf(m, 'Nope')).toEqual([]);
    expect(nameOfBlock({ Idle: ['s1'] }, 's1')).toBe('Idle');
    expect(nameOfBlock({ Idle: ['s1'] }, 'x')).toBeUndefined();
  });
});
