import { describe, expect, it, vi } from 'vitest';
import { ApiError, createApi } from '../../src/app/api';

function fakeFetch(status: number, body: string) {
  return vi.fn(async (_url: RequestInfo | URL, _init?: RequestInit) => new Response(body, { status, headers: { 'Content-Type': 'application/json' } }));
}

describe('API client', () => {
  it('takes over the session and the named file index.html already asked for, once each', async () => {
    const fetch = fakeFetch(200, '{"path":"/w/b.st","charts":[]}');
    const json = (v: unknown) => Promise.resolve(new Response(JSON.stringify(v), { status: 200 }));
    const start = {
      session: json({ mode: 'mdi', open: ['/w/a.st'] }),
      open: Promise.resolve({ path: '/w/a.st', res: json({ path: '/w/a.st', charts: [] }) }),
    };
    const api = createApi({ fetch, notify: vi.fn(), start });
    expect(await api.session()).toMatchObject({ open: ['/w/a.st'] });
    expect(await api.open('/w/a.st')).toMatchObject({ path: '/w/a.st' });
    expect(fetch).not.toHaveBeenCalled();
    // Asked again, or for another file: the server is asked.
    expect(await api.open('/w/a.st')).toMatchObject({ path: '/w/b.st' });
    expect(fetch).toHaveBeenCalledTimes(1);
  });
  it('asks the server itself when the early request failed or was for another file', async () => {
    const fetch = fakeFetch(200, '{"path":"/w/b.st","charts":[]}');
    const start = {
      session: Promise.reject(new Error('offline')),
      open: Promise.resolve({ path: '/w/a.st', res: Promise.reject(new Error('offline')) }),
    };
    start.session.catch(() => undefined);
    const api = createApi({ fetch, notify: vi.fn(), start });
    expect(await api.open('/w/b.st')).toMatchObject({ path: '/w/b.st' });
    expect(await api.open('/w/a.st')).toMatchObject({ path: '/w/b.st' });
    expect(fetch).toHaveBeenCalledTimes(2);
  });
  it('the page sends its page header and the cookie, no token', async () => {
    const fetch = fakeFetch(200, '{"files":[]}');
    await createApi({ fetch, notify: vi.fn() }).files();
    const [, init] = fetch.mock.calls[0];
    const headers = init?.headers as Record<string, string>;
    expect(headers['X-Sfc-Page']).toBe('1');
    expect(headers['X-Sfc-Token']).toBeUndefined();
    expect(init?.credentials).toBe('same-origin');
  });
  it('sends the token header and JSON body', async () => {
    const fetch = fakeFetch(200, '{"diagnostics":[]}');
    const api = createApi({ token: 'tok', fetch, notify: vi.fn() });
    const doc = { pou: 'P', pouKind: 'program' as const, target: 'blank' as const, declarations: '', actions: [], elements: [], connections: [] };
    expect(await api.check(doc, false)).toEqual([]);
    const [url, init] = fetch.mock.calls[0];
    expect(url).toBe('/api/check');
    expect(init?.method).toBe('POST');
    expect((init?.headers as Record<string, string>)['X-Sfc-Token']).toBe('tok');
    expect(JSON.parse(init?.body as string)).toEqual({ doc, analysis: false });
  });
  it('turns an error answer into an ApiError and shows the server message', async () => {
    const notify = vi.fn();
    const api = createApi({ token: 't', fetch: fakeFetch(403, '{"error":"path outside the roots"}'), notify });
    const err = await api.open('/etc/passwd').catch((e) => e);
    expect(err).toBeInstanceOf(ApiError);
    expect(err.status).toBe(403);
    expect(err.message).toBe('path outside the roots');
    expect(notify).toHaveBeenCalledWith('path outside the roots');
  });
  it('leaves a missing file (404 on open) and a save conflict (409) to the caller', async () => {
    const notify = vi.fn();
    const missing = await createApi({ token: 't', fetch: fakeFetch(404, '{"error":"no such file"}'), notify }).open('/w/x.st').catch((e) => e);
    expect(missing.status).toBe(404);
    const conflict = await createApi({ token: 't', fetch: fakeFetch(409, '{"error":"changed on disk","conflict":true}'), notify })
      .save({ path: '/w/a.st', format: 'st', doc: {} as never, hash: 'h' })
      .catch((e) => e);
    expect(conflict.conflict).toBe(true);
    expect(notify).not.toHaveBeenCalled();
  });
  it('reports an unreachable server', async () => {
    const notify = vi.fn();
    const fetch = vi.fn(async () => {
      throw new TypeError('Failed to fetch');
    });
    const err = await createApi({ token: 't', fetch, notify }).session().catch((e) => e);
    expect(err.status).toBe(0);
    expect(notify.mock.calls[0][0]).toContain('cannot be reached');
  });
  it('asks for a new chart by name and target', async () => {
    const fetch = fakeFetch(200, '{"doc":{"pou":"Tank"}}');
    const doc = await createApi({ token: 't', fetch, notify: vi.fn() }).newChart('Tank', 'atmt');
    expect(doc.pou).toBe('Tank');
    expect(JSON.parse(fetch.mock.calls[0][1]?.body as string)).toEqual({ name: 'Tank', target: 'atmt' });
  });
});
