// The editor's settings that last from one run to the next: the language, the charts opened
// lately and the monitor's watch lists. The server keeps them in the user's config directory
// (`GET`/`POST /api/settings`, docs/editor.md "Settings"): `sfc edit` takes a new port on every
// run without `--port`, and the browser keeps its storage per origin, port included, so the
// page's own storage would forget them each run.
//
// localStorage is only the fallback: when the server cannot be asked (or cannot write its file)
// the settings are read from and written there, and what an editor of before (or the fallback)
// left there is moved to the server once, where the server has nothing for it yet. These
// three were the page's only localStorage keys (`sfc.language`, `sfc.recent`,
// `sfc.monitor.watch.POU`); nothing per browser by nature (panel sizes, the zoom) is kept today,
// and should it be, it belongs in localStorage, not here.
import type { Settings, SettingsUpdate } from '../api';

/** The server's bounds (crates/sfc-server/src/settings.rs). */
export const RECENT_MAX = 20;
export const WATCH_MAX = 200;

/** localStorage keys: the fallback's, and those of editors before the server kept settings. */
export const LOCAL_KEYS = { language: 'sfc.language', recent: 'sfc.recent', watchPrefix: 'sfc.monitor.watch.' } as const;

/** How the settings reach the server (the API client's calls). */
export interface SettingsServer {
  read(): Promise<Settings>;
  write(update: SettingsUpdate): Promise<Settings>;
}

export function emptySettings(): Settings {
  return { recent: [], watch: {} };
}

function strings(v: unknown): string[] | null {
  return Array.isArray(v) ? v.filter((x): x is string => typeof x === 'string') : null;
}

/** `v` as settings: the fields of the right types, the rest dropped. */
export function normalize(v: unknown): Settings {
  const o = (v && typeof v === 'object' ? v : {}) as Record<string, unknown>;
  const s = emptySettings();
  if (typeof o.language === 'string' && o.language !== '') s.language = o.language;
  s.recent = (strings(o.recent) ?? []).slice(0, RECENT_MAX);
  if (o.watch && typeof o.watch === 'object') {
    for (const [chart, list] of Object.entries(o.watch as Record<string, unknown>)) {
      const names = strings(list);
      if (names) s.watch[chart] = names.slice(0, WATCH_MAX);
    }
  }
  return s;
}

/** `update` applied to `s`, as the server merges it: absent fields stay, `language: null`
 *  clears it, `recent` replaces the list, each chart of `watch` gets its list (`null`: none). */
export function apply(s: Settings, update: SettingsUpdate): Settings {
  const next: Settings = { ...s, recent: [...s.recent], watch: { ...s.watch } };
  if (update.language === null) delete next.language;
  else if (update.language !== undefined) next.language = update.language;
  if (update.recent) next.recent = [...new Set(update.recent)];
  for (const [chart, list] of Object.entries(update.watch ?? {})) {
    if (list) next.watch[chart] = list;
    else delete next.watch[chart];
  }
  return next;
}

/** `path` first among the recent charts. */
export function withRecent(recent: string[], path: string): string[] {
  return [path, ...recent.filter((p) => p !== path)].slice(0, RECENT_MAX);
}

/** What localStorage holds that the server does not: the language when the server has none,
 *  recent charts after the server's, watch lists of charts the server has none for. `null`
 *  when there is nothing to move. */
export function migration(server: Settings, local: Settings): SettingsUpdate | null {
  const update: SettingsUpdate = {};
  if (server.language === undefined && local.language !== undefined) update.language = local.language;
  const extra = local.recent.filter((p) => !server.recent.includes(p));
  if (extra.length && server.recent.length < RECENT_MAX) update.recent = [...server.recent, ...extra].slice(0, RECENT_MAX);
  const watch: Record<string, string[]> = {};
  for (const [chart, list] of Object.entries(local.watch)) if (!(chart in server.watch)) watch[chart] = list;
  if (Object.keys(watch).length) update.watch = watch;
  return Object.keys(update).length ? update : null;
}

function browserStorage(): Storage | null {
  try {
    return globalThis.localStorage ?? null;
  } catch {
    // Storage can be disabled (privacy settings).
    return null;
  }
}

/** The settings localStorage holds. */
export function readLocal(storage: Storage | null): Settings {
  const s = emptySettings();
  if (!storage) return s;
  try {
    const lang = storage.getItem(LOCAL_KEYS.language);
    if (lang) s.language = lang;
    s.recent = (strings(JSON.parse(storage.getItem(LOCAL_KEYS.recent) ?? '[]')) ?? []).slice(0, RECENT_MAX);
    for (let k = 0; k < storage.length; k++) {
      const key = storage.key(k);
      if (!key?.startsWith(LOCAL_KEYS.watchPrefix)) continue;
      const list = strings(JSON.parse(storage.getItem(key) ?? 'null'));
      if (list) s.watch[key.slice(LOCAL_KEYS.watchPrefix.length)] = list.slice(0, WATCH_MAX);
    }
  } catch {
    // A value that is not JSON: what was read so far.
  }
  return s;
}

function writeLocal(storage: Storage | null, s: Settings): void {
  if (!storage) return;
  try {
    if (s.language) storage.setItem(LOCAL_KEYS.language, s.language);
    else storage.removeItem(LOCAL_KEYS.language);
    storage.setItem(LOCAL_KEYS.recent, JSON.stringify(s.recent));
    for (const [chart, list] of Object.entries(s.watch)) storage.setItem(LOCAL_KEYS.watchPrefix + chart, JSON.stringify(list));
  } catch {
    // Full or disabled: the settings last for this page.
  }
}

function clearLocal(storage: Storage | null): void {
  if (!storage) return;
  try {
    const keys: string[] = [];
    for (let k = 0; k < storage.length; k++) {
      const key = storage.key(k);
      if (key && (key === LOCAL_KEYS.language || key === LOCAL_KEYS.recent || key.startsWith(LOCAL_KEYS.watchPrefix))) keys.push(key);
    }
    for (const key of keys) storage.removeItem(key);
  } catch {
    // Disabled storage holds nothing to clear.
  }
}

/** The page's settings: read once at start (before the first render, so the page comes up in
 *  the kept language), changed at once in the page and written through the server. */
export class SettingsStore {
  private s: Settings = emptySettings();
  private server: SettingsServer | null = null;
  /** Writes sent and not answered yet: an answer is taken only when it is the last one's. */
  private pending = 0;
  private chain: Promise<void> = Promise.resolve();
  private listeners = new Set<() => void>();

  constructor(private readonly storage: Storage | null = browserStorage()) {}

  /** Reads the server's settings and moves localStorage's there once; when the server cannot
   *  be asked, localStorage's. Never fails. */
  async load(server: SettingsServer | null): Promise<Settings> {
    this.server = server;
    const local = readLocal(this.storage);
    let remote: Settings;
    try {
      if (!server) throw new Error('no server');
      remote = normalize(await server.read());
    } catch {
      this.set(local);
      return this.s;
    }
    const update = migration(remote, local);
    if (update) {
      try {
        remote = normalize(await server.write(update));
        clearLocal(this.storage);
      } catch {
        // Left in localStorage to move next time; this page uses them meanwhile.
        remote = apply(remote, update);
      }
    } else {
      clearLocal(this.storage);
    }
    this.set(remote);
    return this.s;
  }

  get(): Settings {
    return this.s;
  }

  language(): string | undefined {
    return this.s.language;
  }

  recent(): string[] {
    return this.s.recent;
  }

  /** The watch list kept for `chart`, if any. */
  watch(chart: string): string[] | null {
    return this.s.watch[chart] ?? null;
  }

  /** Changes the settings: at once in the page, then on the server (in order); where the
   *  server cannot keep them, in localStorage. */
  update(update: SettingsUpdate): Promise<void> {
    this.set(apply(this.s, update));
    const server = this.server;
    if (!server) {
      writeLocal(this.storage, this.s);
      return Promise.resolve();
    }
    this.pending++;
    this.chain = this.chain.then(async () => {
      try {
        const whole = normalize(await server.write(update));
        if (this.pending === 1) this.set(whole);
      } catch {
        writeLocal(this.storage, this.s);
      } finally {
        this.pending--;
      }
    });
    return this.chain;
  }

  /** Calls `listener` after every change; returns the unsubscription. */
  subscribe(listener: () => void): () => void {
    this.listeners.add(listener);
    return () => this.listeners.delete(listener);
  }

  private set(s: Settings): void {
    this.s = s;
    for (const l of this.listeners) l();
  }
}

/** The page's settings (main.ts loads them before the first render). */
export const settings = new SettingsStore();
