// GENERATED from crates/sfc-runtime/src/contract.rs by ts-rs: do not edit.
// `UPDATE_CONTRACTS=1 cargo test -p sfc-runtime contracts` writes it anew; the test fails when it is stale.

export type MonValue = boolean | number | string;

export type StepInfo = { name: string, initial: boolean, };

export type TransitionInfo = { name: string, from: Array<string>, to: Array<string>, };

export type VariableInfo = { name: string, 
/**
 * IEC type name (BOOL, INT, UDINT, TIME, REAL, STRING …).
 */
type: string, 
/**
 * `%IX0.0` for a located variable.
 */
location?: string, 
/**
 * The output's safe value (`sfc.safe` or the run configuration; FALSE/0 by default), for
 * the outputs of `sfc run`.
 */
safe?: MonValue, };

export type RunState = "RUN" | "STOP" | "FAULT";

export type Fault = { 
/**
 * `watchdog` or `error`.
 */
kind: string, message: string, scan?: number, 
/**
 * How long the scan had run when it was stopped (watchdog).
 */
scanUs?: number, watchdogUs?: number, 
/**
 * The active step the scan was in (the first of `steps`).
 */
step?: string, steps?: Array<string>, action?: string, transition?: string, line?: number, column?: number, };

export type Hello = { type: "hello", protocol: string, version: number, runtime: string, 
/**
 * The simulator's profile (`iec`, `matiec`, `codesys`, `grafcet`, `logix`, `graph`; `docs/sim.md`,
 * "Profiles"); absent for the ATMT adapter.
 */
profile?: string, pou: string, period: string, 
/**
 * False when the runtime can only be watched (no halt, step, force or set).
 */
control: boolean, tokenRequired: boolean, authorized: boolean, halted: boolean, 
/**
 * RUN, STOP or FAULT (`docs/runtime.md`, "States").
 */
state: RunState, 
/**
 * In FAULT, what caused it; null otherwise.
 */
fault: Fault | null, history: number, steps: Array<StepInfo>, transitions: Array<TransitionInfo>, variables: Array<VariableInfo>, };

export type ActiveStep = { step: string, elapsed: string, elapsedUs: number, };

export type ScanState = { scan: number, time: string, timeUs: number, active: Array<ActiveStep>, fired: Array<string>, 
/**
 * Guard of every transition leaving an active step; null when evaluating it faulted.
 */
guards: { [key in string]: boolean | null }, vars: { [key in string]: MonValue }, forced: Array<string>, };

export type Snapshot = { type: "snapshot", scan: number, time: string, timeUs: number, active: Array<ActiveStep>, fired: Array<string>, guards: { [key in string]: boolean | null }, vars: { [key in string]: MonValue }, forced: Array<string>, halted: boolean, 
/**
 * RUN, STOP or FAULT (`sfc run`); in STOP and FAULT `vars` shows the outputs' safe values.
 */
state: RunState, 
/**
 * In FAULT, what caused it; null otherwise.
 */
fault: Fault | null, 
/**
 * Scan statistics of the runtime (free form).
 */
stats: Record<string, unknown> | null, };

export type Delta = { type: "delta", scan: number, time: string, timeUs: number, active: Array<ActiveStep>, fired?: Array<string>, guards?: { [key in string]: boolean | null }, vars?: { [key in string]: MonValue }, forced?: Array<string>, };

export type StateMessage = { type: "state", state: RunState, 
/**
 * In FAULT, what caused it; null otherwise.
 */
fault: Fault | null, 
/**
 * The last scan that ran.
 */
scan: number, 
/**
 * The outputs as they are now (their safe values in STOP and FAULT).
 */
outputs?: { [key in string]: MonValue }, };
