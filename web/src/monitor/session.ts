// Starting a monitor session: the editor's simulator on the open chart (`POST /api/sim/start`,
// docs/editor.md) or an attached runtime (a ws:// URL with its token), and which blocks of the
// chart show each step and transition of the runtime.
import type { Replay } from '../api';
import type { EditorDoc } from '../doc';

/** A monitor session as the shell holds it. */
export interface MonitorTarget {
  /** ws://HOST:PORT/?token=… */
  url: string;
  /** The chart as it was when monitoring started (the canvas shows it read-only). */
  doc: EditorDoc;
  /** Runtime names (steps, transitions) → block ids; from the server for a simulation. */
  elements: Record<string, string[]>;
  /** Id of the simulation to stop on leaving; null when attached to a runtime. */
  simId: number | null;
  /** The tab's title, shown in the monitor's toolbar. */
  title: string;
  /** A witness of `sfc prove` to replay once connected (the simulation starts halted). */
  replay?: Replay;
  /** The SFC instance to show at once (a mechanism selected on another chart's monitor). */
  instance?: string;
  /** The simulator's profile and why the server chose it (simulations only; an attached
   *  runtime names its profile in `hello`). */
  profile?: SimProfile;
}

/** The profile a simulation runs with (`POST /api/sim/start`'s `profile`): `codesys` for an
 *  export of CODESYS, TwinCAT or e!COCKPIT (`source: 'vendor'`), else `iec`. */
export interface SimProfile {
  name: string;
  source: 'vendor' | 'default';
  vendor?: string;
  /** The file's name (for `source: 'vendor'`). */
  file?: string;
}

/** An answer of the server that is not 2xx: its message and, for 422, the diagnostics. */
export class SimError extends Error {
  constructor(
    message: string,
    readonly status: number,
    readonly diagnostics: unknown[] = [],
  ) {
    super(message);
    this.name = 'SimError';
  }
}

export interface SimStart {
  id: number;
  url: string;
  period: string;
  elements: Record<string, string[]>;
  profile?: SimProfile;
}

type Fetch = (input: string, init?: RequestInit) => Promise<Response>;

async function post<T>(path: string, body: unknown, doFetch: Fetch): Promise<T> {
  let res: Response;
  try {
    res = await doFetch(path, {
      method: 'POST',
      // The page's cookie carries the token (src/app/api.ts); the header says it is the page.
      headers: { 'Content-Type': 'application/json', Accept: 'application/json', 'X-Sfc-Page': '1' },
      credentials: 'same-origin',
      body: JSON.stringify(body),
    });
  } catch (e) {
    throw new SimError(`${path}: the server cannot be reached (${(e as Error).message})`, 0);
  }
  const text = await res.text();
  let data: Record<string, unknown> = {};
  try {
    data = text ? (JSON.parse(text) as Record<string, unknown>) : {};
  } catch {
    if (res.ok) throw new SimError(`${path}: the answer is not JSON`, res.status);
  }
  if (!res.ok) throw new SimError(String(data.error ?? (text || `HTTP ${res.status}`)), res.status, (data.diagnostics as unknown[]) ?? []);
  return data as T;
}

/** Starts the simulator on `doc`; `path`, the file it was opened from, chooses the profile
 *  (a CODESYS, TwinCAT or e!COCKPIT export runs with `codesys`). */
export function startSimulation(doc: EditorDoc, opts: { period?: string; halted?: boolean; path?: string | null } = {}, doFetch: Fetch = (i, r) => fetch(i, r)): Promise<SimStart> {
  return post<SimStart>('/api/sim/start', { doc, ...(opts.period ? { period: opts.period } : {}), halted: !!opts.halted, ...(opts.path ? { path: opts.path } : {}) }, doFetch);
}

export function stopSimulation(id: number, doFetch: Fetch = (i, r) => fetch(i, r)): Promise<unknown> {
  return post('/api/sim/stop', { id }, doFetch);
}

/**
 * Blocks of each step and transition by name, for a runtime the editor did not start: named
 * steps and transitions match case-insensitively; an unnamed transition is `T<n>` (its place
 * among the transitions, as the text names it) when that name is free.
 */
export function elementsByName(doc: EditorDoc): Record<string, string[]> {
  const out: Record<string, string[]> = {};
  const taken = new Set(doc.elements.filter((e) => e.name).map((e) => e.name!.toUpperCase()));
  let k = 0;
  for (const e of doc.elements) {
    if (e.kind !== 'step' && e.kind !== 'transition') continue;
    let name = e.name ?? '';
    if (e.kind === 'transition') {
      k++;
      if (!name && !taken.has(`T${k}`)) name = `T${k}`;
    }
    if (!name) continue;
    (out[name.toUpperCase()] ??= []).push(e.id);
  }
  return out;
}

/** The blocks of runtime name `name` (case-insensitive; `elements` keys as the runtime spells them). */
export function blocksOf(elements: Record<string, string[]>, name: string): string[] {
  return elements[name] ?? elements[name.toUpperCase()] ?? Object.entries(elements).find(([k]) => k.toUpperCase() === name.toUpperCase())?.[1] ?? [];
}

/** The runtime name a block stands for (the inverse of `blocksOf`). */
export function nameOfBlock(elements: Record<string, string[]>, id: string): string | undefined {
  return Object.entries(elements).find(([, ids]) => ids.includes(id))?.[0];
}
