// Client of the editor's HTTP API (contract: docs/editor.md "HTTP API", types in src/api.ts).
// The page authenticates with the HttpOnly cookie the server set when the printed URL was opened
// (the token itself never reaches the page's scripts) plus the header `X-Sfc-Page`, which other
// origins cannot send; scripts and tests may pass a token, sent as `X-Sfc-Token`. A failed call
// throws an ApiError and shows the server's message as a toast, and never touches the document
// being edited.
import type { BuildResult, BuildTarget, CompareAgainst, CompareResult, ConflictSide, Diag, FileFormat, OpenResult, ProveResult, ResolveResult, SaveResult, Session, Settings, SettingsUpdate } from '../api';
import type { ChartTarget, EditorDoc } from '../doc';
import { toasts } from './toast';

/** A failed API call: the HTTP status (0 when the server could not be reached) and its message. */
export class ApiError extends Error {
  constructor(
    message: string,
    readonly status: number,
    /** `409` on save: the file changed on disk since it was read. */
    readonly conflict = false,
  ) {
    super(message);
    this.name = 'ApiError';
  }
}

export interface ApiOptions {
  /** A token to send as `X-Sfc-Token` (the page itself has none: its cookie carries it). */
  token?: string | null;
  /** Defaults to the global fetch. */
  fetch?: typeof fetch;
  /** Shows an error to the user; defaults to a toast. */
  notify?: (message: string) => void;
  /** Base URL of the server; defaults to the page's origin. */
  base?: string;
  /** Requests the page started before the app loaded (index.html), each taken over once. */
  start?: StartRequests;
}

/** The session, the settings and the first named file's opening, requested by index.html's
 *  inline script. */
export interface StartRequests {
  session: Promise<Response>;
  settings?: Promise<Response>;
  open: Promise<{ path: string; res: Promise<Response> } | null>;
}

export interface SaveRequest {
  path: string;
  format: FileFormat;
  doc: EditorDoc;
  hash: string | null;
  overwrite?: boolean;
  /** The POU's name in the file when the chart was renamed since: that POU is replaced. */
  pou?: string;
}

export interface ResolveRequest {
  /** The chart's file, as opened (none for a chart never saved). */
  path?: string;
  /** The POU's name in the file when the chart was renamed since it was opened. */
  pou?: string;
  doc: EditorDoc;
  /** The conflict's element as marked (`transition:TStart`). */
  element: string;
  side: ConflictSide;
}

export type Api = ReturnType<typeof createApi>;

export function createApi(opts: ApiOptions) {
  const doFetch = opts.fetch ?? ((input: RequestInfo | URL, init?: RequestInit) => fetch(input, init));
  const notify = opts.notify ?? ((m: string) => toasts.show('error', m));
  const base = opts.base ?? '';
  let session = opts.start?.session;
  let settings = opts.start?.settings;
  let opening = opts.start?.open;

  /** The response of a request index.html already made, if this is it (each taken once; one
   *  that failed to arrive is made again). */
  async function started(method: string, path: string, body: unknown): Promise<Response | undefined> {
    if (method === 'GET' && path === '/api/session' && session) {
      const s = session;
      session = undefined;
      return s.catch(() => undefined);
    }
    if (method === 'GET' && path === '/api/settings' && settings) {
      const s = settings;
      settings = undefined;
      return s.catch(() => undefined);
    }
    if (method === 'POST' && path === '/api/open' && opening) {
      const o = await opening.catch(() => null);
      if (o && opening && o.path === (body as { path?: string } | undefined)?.path) {
        opening = undefined;
        return o.res.catch(() => undefined);
      }
    }
    return undefined;
  }

  /** One call; statuses in `quiet` throw without a toast (the caller handles them; `'all'`:
   *  every failure, the server unreachable included). */
  async function call<T>(method: 'GET' | 'POST', path: string, body?: unknown, quiet: number[] | 'all' = []): Promise<T> {
    const loud = (status: number) => quiet !== 'all' && !quiet.includes(status);
    const headers: Record<string, string> = { Accept: 'application/json', 'X-Sfc-Page': '1' };
    if (opts.token) headers['X-Sfc-Token'] = opts.token;
    if (body !== undefined) headers['Content-Type'] = 'application/json';
    let res: Response;
    try {
      res = (await started(method, path, body)) ?? (await doFetch(base + path, {
        method,
        headers,
        credentials: 'same-origin',
        body: body === undefined ? undefined : JSON.stringify(body),
      }));
    } catch (e) {
      const err = new ApiError(`${method} ${path}: the server cannot be reached (${(e as Error).message})`, 0);
      if (loud(0)) notify(err.message);
      throw err;
    }
    const text = await res.text();
    let data: unknown = null;
    try {
      data = text === '' ? null : JSON.parse(text);
    } catch {
      if (res.ok) {
        const err = new ApiError(`${method} ${path}: the answer is not JSON`, res.status);
        if (loud(res.status)) notify(err.message);
        throw err;
      }
    }
    if (!res.ok) {
      const obj = (data ?? {}) as { error?: string; conflict?: boolean };
      const message = obj.error ?? (text.trim() || res.statusText || `HTTP ${res.status}`);
      const err = new ApiError(message, res.status, obj.conflict === true);
      // The toast shows the server's message alone, never the API path.
      if (loud(res.status)) notify(message);
      throw err;
    }
    return data as T;
  }

  return {
    session: () => call<Session>('GET', '/api/session'),
    files: () => call<{ files: { path: string; format: FileFormat }[] }>('GET', '/api/files').then((r) => r.files),
    /** `404` (missing file) throws without a toast: host mode then creates the chart. */
    open: (path: string) => call<OpenResult>('POST', '/api/open', { path }, [404]),
    /** `409` (changed on disk) throws without a toast: the caller asks whether to overwrite. */
    save: (req: SaveRequest) => call<SaveResult>('POST', '/api/save', req, [409]),
    check: (doc: EditorDoc, analysis: boolean) =>
      call<{ diagnostics: Diag[] }>('POST', '/api/check', { doc, analysis }).then((r) => r.diagnostics),
    build: (doc: EditorDoc, target: BuildTarget, limits?: { nstep: number; ntr: number }) =>
      call<BuildResult>('POST', '/api/build', { doc, target, ...(limits ?? {}) }),
    /** `sfc prove` on the chart with `<chart>.props.toml` beside `path`; `404`: no property file. */
    prove: (doc: EditorDoc, path: string) => call<ProveResult>('POST', '/api/prove', { doc, path }, [404]),
    /** The chart compared by meaning with its file as saved (`saved`) or in git HEAD (`head`);
     *  `pou`: the POU's name in the file when the chart was renamed since it was opened. */
    compare: (path: string, doc: EditorDoc, against: CompareAgainst, pou?: string) =>
      call<CompareResult>('POST', '/api/compare', { path, doc, against, ...(pou !== undefined ? { pou } : {}) }),
    /** One merge conflict of the chart resolved by taking a side (`sfc.conflict`, docs/diff.md):
     *  the resolved chart and its diagnostics; the file is not written. */
    resolve: (req: ResolveRequest) => call<ResolveResult>('POST', '/api/resolve', req),
    layout: (doc: EditorDoc) => call<{ doc: EditorDoc }>('POST', '/api/layout', { doc }).then((r) => r.doc),
    /** The settings kept in the user's config directory; failures throw without a toast (the
     *  page then keeps them in localStorage, src/app/settings.ts). */
    settings: () => call<Settings>('GET', '/api/settings', undefined, 'all'),
    /** Merges `update` into the kept settings; answers the whole. */
    saveSettings: (update: SettingsUpdate) => call<Settings>('POST', '/api/settings', update, 'all'),
    codes: () => call<{ code: string; severity: string; title: string }[]>('GET', '/api/codes'),
    /** The document of a new chart (an initial step), as `sfc-doc` makes it. */
    newChart: (name: string, target: ChartTarget) => call<{ doc: EditorDoc }>('POST', '/api/new', { name, target }).then((r) => r.doc),
  };
}
