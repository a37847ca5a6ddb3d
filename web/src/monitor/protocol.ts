// The monitor protocol, version 1 (docs/monitor.md): the messages a runtime (`sfc run`, the
// editor's simulator, the ATMT adapter) sends, as the client keeps them.

// The messages' types are generated from crates/sfc-runtime/src/contract.rs by ts-rs
// (../contracts/monitor.ts, kept current by sfc-runtime's `contracts_are_current` test;
// `tests/contract.rs` there reads the messages a running chart sends back into those types).
import type { ActiveStep, Delta, MonValue, ScanState } from '../contracts/monitor';
export type {
  ActiveStep,
  Delta,
  Fault,
  Hello,
  MonValue,
  RunState,
  ScanState,
  Snapshot,
  StateMessage,
  StepInfo,
  TransitionInfo,
  VariableInfo,
} from '../contracts/monitor';

export interface MonEvent {
  type: 'event';
  kind: string;
  scan?: number;
  step?: string;
  transition?: string;
  transitions?: string[];
  message?: string;
  [k: string]: unknown;
}

export interface Breakpoint {
  kind: 'step' | 'transition';
  name: string;
  enabled: boolean;
}

/** Why one transition leaving a stuck step does not fire (`explain`). */
export interface TransitionReport {
  transition: string;
  guard: string;
  value: boolean;
  /** `terminal`: where the operand is wired (`X12.3, %IX0.5`), null when it is not. */
  operands: { operand: string; value: string; terminal?: string | null }[];
  change: string[];
  /** The operands that must change, in words with terminals and values: `KM2Fb (X12.3, %IX0.5) is FALSE; needs TRUE`. */
  needs?: string[];
  missing: string[];
  /** Preceding steps still inside their minimum time (`sfc.min_time`): `Hold (T#20ms of T#30ms)`. */
  dwell?: string[];
  masked_by: string | null;
}

export interface StepReport {
  step: string;
  elapsed: string;
  elapsedUs: number;
  timeout: string | null;
  transitions: TransitionReport[];
  lines: string[];
  scan: number;
}

export interface StepTiming {
  step: string;
  activations: number;
  min: string | null;
  mean: string | null;
  max: string | null;
  minUs: number | null;
  meanUs: number | null;
  maxUs: number | null;
}

/** One state of a run: the step passed and how long it was active. */
export interface RunPassage {
  state: string;
  time: string;
  timeUs: number;
}

/** One run of a mechanism: an activation from its start to its end (docs/sim.md, "Runs"). */
export interface MechanismRun {
  run: number;
  start: string;
  total: string;
  totalUs: number;
  /** `normal`, `error 404`, `reset`, or null for the run in progress. */
  ended: string | null;
  states: RunPassage[];
  /** States of a long run not kept (the first ones). */
  dropped_states: number;
}

/** A state's statistics over the runs. */
export interface StateOverRuns {
  state: string;
  count: number;
  min: string;
  mean: string;
  max: string;
  minUs: number;
  meanUs: number;
  maxUs: number;
}

/** The time analysis per run of one SFC instance. */
export interface MechanismRuns {
  instance: string;
  /** Earlier runs not kept (still counted in `states`). */
  dropped: number;
  resets: number;
  runs: MechanismRun[];
  states: StateOverRuns[];
}

export interface Timing {
  scan: number;
  steps: StepTiming[];
  mechanisms: MechanismRuns[];
}

/** An error record of a supervision timeout (docs/sim.md, "Error records"). */
export interface ErrorRecord {
  kind: 'supervision';
  instance: string;
  step: string;
  code: number | null;
  code_variable: string | null;
  condition: string;
  conditions: { transition: string; condition: string }[];
  waited: string;
  /** The step's `sfc.timeout`; null when the chart's own timer guard (`by`) ended the wait. */
  timeout: string | null;
  by: string | null;
  scan: number;
  time: string;
  message: string;
}

/** One SFC instance of the running program (`mechanisms`, docs/monitor.md). */
export interface Mechanism {
  instance: string;
  pou: string;
  activation: boolean | null;
  activationVariable: string | null;
  running: boolean;
  active: { step: string; time: string; timeUs: number }[];
  lastError: ErrorRecord | null;
  runs: number;
  resets: number;
  errors: number;
}

export interface Mechanisms {
  scan: number;
  mechanisms: Mechanism[];
  errorRecords: ErrorRecord[];
}

/** Merges a `delta` into the state it follows: a new object, the old one untouched. */
export function mergeDelta(base: ScanState, d: Delta): ScanState {
  return {
    scan: d.scan,
    time: d.time,
    timeUs: d.timeUs,
    active: d.active,
    // A delta names the fired transitions only when some fired.
    fired: d.fired ?? [],
    guards: d.guards ?? base.guards,
    vars: d.vars ? { ...base.vars, ...d.vars } : base.vars,
    forced: d.forced ?? base.forced,
  };
}

/** A `snapshot` or `history` entry as a state (extra fields such as `stats` dropped). */
export function toState(m: Record<string, unknown>): ScanState {
  return {
    scan: Number(m.scan ?? 0),
    time: String(m.time ?? 'T#0s'),
    timeUs: Number(m.timeUs ?? 0),
    active: (m.active as ActiveStep[] | undefined) ?? [],
    fired: (m.fired as string[] | undefined) ?? [],
    guards: (m.guards as Record<string, boolean | null> | undefined) ?? {},
    vars: (m.vars as Record<string, MonValue> | undefined) ?? {},
    forced: (m.forced as string[] | undefined) ?? [],
  };
}

/**
 * A value typed by the user for a variable of IEC type `type`, as the protocol carries it;
 * an Error with the reason when it is not one.
 */
export function parseValue(type: string, text: string): MonValue | Error {
  const s = text.trim();
  const ty = type.toUpperCase();
  if (ty === 'BOOL') {
    if (/^(true|1)$/i.test(s)) return true;
    if (/^(false|0)$/i.test(s)) return false;
    return new Error('BOOL');
  }
  if (/^(S|D|L|U|US|UD|UL)?INT$|^(BYTE|WORD|DWORD|LWORD)$/.test(ty)) {
    if (!/^[+-]?\d+$/.test(s)) return new Error(ty);
    return Number(s);
  }
  if (ty === 'REAL' || ty === 'LREAL') {
    const n = Number(s);
    if (s === '' || !Number.isFinite(n)) return new Error(ty);
    return n;
  }
  if (ty === 'TIME' || ty === 'LTIME') {
    if (!/^(L?T|L?TIME)#[-+]?[\d._a-z]+$/i.test(s)) return new Error(ty);
    return s;
  }
  return text;
}

/** A value as the user reads it: TRUE/FALSE, numbers, TIME literals, 'strings'. */
export function showValue(v: MonValue | undefined): string {
  if (v === undefined) return '';
  if (typeof v === 'boolean') return v ? 'TRUE' : 'FALSE';
  return String(v);
}

/** An elapsed time compactly, for the label beside an active step: 250 ms, 12.3 s, 2:05 min. */
export function shortDuration(us: number): string {
  if (us < 1_000_000) return `${Math.round(us / 1000)} ms`;
  if (us < 60_000_000) return `${(us / 1_000_000).toFixed(1)} s`;
  const s = Math.floor(us / 1_000_000);
  return `${Math.floor(s / 60)}:${String(s % 60).padStart(2, '0')} min`;
}
