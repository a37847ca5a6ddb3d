// A client of the monitor protocol (docs/monitor.md) over one WebSocket: the chart's description
// (`hello`), the latest scan state (snapshot and deltas merged), halts and breakpoint hits, the
// breakpoint list, the display pause, browsing the runtime's last ≤ 100 states, and commands
// with their replies matched by id. No reconnect: a closed connection ends the session.
import {
  mergeDelta,
  toState,
  type Breakpoint,
  type Delta,
  type Fault,
  type Hello,
  type MonEvent,
  type MonValue,
  type RunState,
  type ScanState,
  type StepReport,
  type Mechanisms,
  type Timing,
} from './protocol';

/** The part of a WebSocket the client uses (a fake one in tests). */
export interface SocketLike {
  readonly readyState: number;
  send(data: string): void;
  close(): void;
  onopen: ((ev: unknown) => void) | null;
  onmessage: ((ev: { data: unknown }) => void) | null;
  onclose: ((ev: unknown) => void) | null;
  onerror: ((ev: unknown) => void) | null;
}

export type SocketFactory = (url: string) => SocketLike;

/** WebSocket.OPEN */
const OPEN = 1;
/** Events kept for the log. */
const EVENT_LOG = 200;

/** A command the runtime refused (`ok: false`), or a connection that closed before the reply. */
export class MonitorError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'MonitorError';
  }
}

export type Status = 'connecting' | 'open' | 'closed';

/** Browsing the runtime's buffered states: `index` into `states` (oldest first). */
export interface HistoryView {
  states: ScanState[];
  index: number;
}

/** The block where the runtime halted on a breakpoint. */
export interface Hit {
  kind: 'step' | 'transition';
  name: string;
  scan: number;
}

interface Pending {
  resolve: (v: unknown) => void;
  reject: (e: Error) => void;
}

export class MonitorClient {
  status: Status = 'connecting';
  /** Why the connection closed or failed, when it did. */
  closeReason = '';
  info: Hello | null = null;
  /** The latest state the runtime sent (moves on while the display is paused or browsing). */
  live: ScanState | null = null;
  /** What the display froze on while paused. */
  frozen: ScanState | null = null;
  halted = false;
  haltReason = '';
  /** RUN, STOP or FAULT (docs/runtime.md, "States"). */
  runState: RunState = 'RUN';
  /** What put the runtime in FAULT (`kind`, `message`, `step`, `action`, `line` …). */
  fault: Fault | null = null;
  /** The display is paused: the runtime keeps running and buffering, the view stands still. */
  displayPaused = false;
  history: HistoryView | null = null;
  breakpoints: Breakpoint[] = [];
  hit: Hit | null = null;
  events: MonEvent[] = [];
  private socket: SocketLike;
  private queue: string[] = [];
  private pending = new Map<number, Pending>();
  private nextId = 1;
  private listeners = new Set<() => void>();

  constructor(url: string, socket: SocketFactory = (u) => new WebSocket(u) as unknown as SocketLike) {
    this.socket = socket(url);
    this.socket.onopen = () => {
      this.status = 'open';
      for (const m of this.queue.splice(0)) this.socket.send(m);
      this.changed();
    };
    this.socket.onmessage = (ev) => {
      if (typeof ev.data !== 'string') return;
      let m: unknown;
      try {
        m = JSON.parse(ev.data);
      } catch {
        return;
      }
      if (m && typeof m === 'object') this.receive(m as Record<string, unknown>);
    };
    this.socket.onerror = () => {
      if (!this.closeReason) this.closeReason = 'connection failed';
    };
    this.socket.onclose = () => this.closed(this.closeReason || 'connection closed');
  }

  /** Calls `listener` after every change; returns the unsubscribe function. */
  subscribe(listener: () => void): () => void {
    this.listeners.add(listener);
    return () => this.listeners.delete(listener);
  }

  private changed(): void {
    for (const l of [...this.listeners]) l();
  }

  /** The state the display shows: the browsed one, the frozen one, else the latest. */
  view(): ScanState | null {
    if (this.history) return this.history.states[this.history.index] ?? null;
    if (this.displayPaused) return this.frozen;
    return this.live;
  }

  /** The runtime can be halted, stepped, forced and written (not the ATMT adapter). */
  canControl(): boolean {
    return !!this.info?.control && this.info.authorized;
  }

  /** Handles one message of the runtime. */
  receive(m: Record<string, unknown>): void {
    switch (m.type) {
      case 'hello':
        this.info = m as unknown as Hello;
        this.halted = this.info.halted;
        this.setRunState(m);
        // The breakpoints of an attached runtime may have been set by another client.
        void this.request('breakpoints').then(
          (list) => this.setBreakpoints(list),
          () => undefined,
        );
        break;
      case 'snapshot':
        this.live = toState(m);
        if (typeof m.halted === 'boolean') this.halted = m.halted;
        this.setRunState(m);
        break;
      case 'state':
        this.setRunState(m);
        break;
      case 'delta':
        if (this.live) this.live = mergeDelta(this.live, m as unknown as Delta);
        break;
      case 'event': {
        const e = m as unknown as MonEvent;
        this.events.push(e);
        if (this.events.length > EVENT_LOG) this.events.splice(0, this.events.length - EVENT_LOG);
        if (e.kind === 'breakpoint') {
          const kind = e.step !== undefined ? 'step' : 'transition';
          this.hit = { kind, name: String(e.step ?? e.transition), scan: Number(e.scan ?? 0) };
          // A runtime that cannot halt (the ATMT adapter) runs on: the display stops instead,
          // while the runtime keeps buffering the states.
          if (this.info && !this.info.control && !this.displayPaused) {
            this.frozen = this.live;
            this.displayPaused = true;
            void this.request('pause').catch(() => undefined);
          }
        }
        break;
      }
      case 'halted':
        this.halted = true;
        this.haltReason = String(m.reason ?? '');
        break;
      case 'resumed':
        this.halted = false;
        this.haltReason = '';
        this.hit = null;
        break;
      case 'reply':
      case 'history': {
        const id = typeof m.re === 'number' ? m.re : null;
        const p = id === null ? undefined : this.pending.get(id);
        if (!p) return;
        this.pending.delete(id!);
        if (m.ok === true) p.resolve(m.type === 'history' ? m.states : m.result);
        else p.reject(new MonitorError(String(m.error ?? 'refused')));
        break;
      }
      case 'error':
        this.closeReason = String(m.error ?? 'dropped by the runtime');
        break;
      default:
        return;
    }
    this.changed();
  }

  private setRunState(m: Record<string, unknown>): void {
    // `hello`, `snapshot` and `state` carry the state (an older runtime's do not: it runs).
    if (m.state !== 'RUN' && m.state !== 'STOP' && m.state !== 'FAULT') return;
    this.runState = m.state;
    this.fault = m.fault && typeof m.fault === 'object' ? (m.fault as Fault) : null;
  }

  private closed(reason: string): void {
    if (this.status === 'closed') return;
    this.status = 'closed';
    this.closeReason = reason;
    for (const p of this.pending.values()) p.reject(new MonitorError(reason));
    this.pending.clear();
    this.queue = [];
    this.changed();
  }

  /** Sends a command; resolves with its `result` (or `states`), rejects with the runtime's error. */
  request<T = unknown>(cmd: string, fields: Record<string, unknown> = {}): Promise<T> {
    if (this.status === 'closed') return Promise.reject(new MonitorError(this.closeReason || 'connection closed'));
    const id = this.nextId++;
    const text = JSON.stringify({ ...fields, id, cmd });
    const reply = new Promise<T>((resolve, reject) => this.pending.set(id, { resolve: resolve as (v: unknown) => void, reject }));
    if (this.status === 'open' && this.socket.readyState === OPEN) this.socket.send(text);
    else this.queue.push(text);
    return reply;
  }

  private setBreakpoints(list: unknown): void {
    if (Array.isArray(list)) {
      this.breakpoints = list as Breakpoint[];
      this.changed();
    }
  }

  halt(): Promise<unknown> {
    return this.request('halt');
  }

  /** Runs again after a halt or a breakpoint; leaves history browsing. */
  async resume(): Promise<void> {
    this.history = null;
    await this.request('continue');
  }

  /** Restarts the chart from its initial values (warm: RETAIN values kept) and runs it again,
   * also out of FAULT; leaves history browsing. */
  async reset(mode: 'warm' | 'cold' = 'warm'): Promise<void> {
    this.history = null;
    await this.request('reset', { mode });
  }

  /** One scan of a halted runtime; the display follows it (history browsing ends). */
  async singleScan(): Promise<number> {
    this.history = null;
    const r = await this.request<{ scan: number }>('step');
    return r.scan;
  }

  /** Freezes the display; the runtime keeps scanning and buffering. */
  async pauseDisplay(): Promise<void> {
    this.frozen = this.live;
    this.displayPaused = true;
    this.changed();
    await this.request('pause');
  }

  /** Live display again (the runtime sends a fresh snapshot). */
  async resumeDisplay(): Promise<void> {
    this.displayPaused = false;
    this.frozen = null;
    this.history = null;
    this.changed();
    await this.request('resume');
  }

  /** Fetches the runtime's buffered states and shows the latest of them. */
  async loadHistory(): Promise<HistoryView> {
    const raw = await this.request<Record<string, unknown>[]>('history', { count: 100 });
    const states = raw.map(toState);
    this.history = { states, index: states.length - 1 };
    this.changed();
    return this.history;
  }

  /** Moves through the buffered states: by `delta`, or to the first or last. */
  moveHistory(to: number | 'first' | 'last'): void {
    const h = this.history;
    if (!h || h.states.length === 0) return;
    const target = to === 'first' ? 0 : to === 'last' ? h.states.length - 1 : h.index + to;
    h.index = Math.min(h.states.length - 1, Math.max(0, target));
    this.changed();
  }

  /** Back to the live (or frozen) display. */
  leaveHistory(): void {
    this.history = null;
    this.changed();
  }

  private async breakpointOp(op: string, fields: Record<string, unknown> = {}): Promise<Breakpoint[]> {
    const list = await this.request<Breakpoint[]>('breakpoint', { op, ...fields });
    this.setBreakpoints(list);
    return list;
  }

  /** Sets (enabled), disables, enables or deletes the breakpoint of a step or transition. */
  breakpoint(op: 'set' | 'disable' | 'enable' | 'delete', kind: 'step' | 'transition', name: string): Promise<Breakpoint[]> {
    return this.breakpointOp(op, { kind, name });
  }

  /** Toggles a block's breakpoint: none → enabled → deleted. */
  toggleBreakpoint(kind: 'step' | 'transition', name: string): Promise<Breakpoint[]> {
    const b = this.findBreakpoint(kind, name);
    return this.breakpoint(b ? 'delete' : 'set', kind, name);
  }

  findBreakpoint(kind: 'step' | 'transition', name: string): Breakpoint | undefined {
    const n = name.toLowerCase();
    return this.breakpoints.find((b) => b.kind === kind && b.name.toLowerCase() === n);
  }

  deleteAllBreakpoints(): Promise<Breakpoint[]> {
    return this.breakpointOp('deleteAll');
  }

  /** Disables every enabled breakpoint, or when none is enabled enables them all. */
  async toggleAllBreakpoints(): Promise<Breakpoint[]> {
    const anyEnabled = this.breakpoints.some((b) => b.enabled);
    const op = anyEnabled ? 'disable' : 'enable';
    let list = this.breakpoints;
    for (const b of this.breakpoints.filter((x) => x.enabled === anyEnabled)) list = await this.breakpoint(op, b.kind, b.name);
    return list;
  }

  force(name: string, value: MonValue): Promise<MonValue> {
    return this.request<MonValue>('force', { name, value });
  }

  unforce(name?: string): Promise<null> {
    return this.request<null>('unforce', name === undefined ? {} : { name });
  }

  set(name: string, value: MonValue): Promise<MonValue> {
    return this.request<MonValue>('set', { name, value });
  }

  /** The condition analysis of an active step. */
  explain(step: string): Promise<StepReport> {
    return this.request<StepReport>('explain', { step });
  }

  /** The time analysis per step. */
  mechanisms(): Promise<Mechanisms> {
    return this.request<Mechanisms>('mechanisms');
  }

  timing(): Promise<Timing> {
    return this.request<Timing>('timing');
  }

  close(): void {
    this.closeReason = 'detached';
    this.socket.close();
    this.closed('detached');
  }
}
