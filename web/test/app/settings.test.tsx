// The settings that last (src/app/settings.ts): merged as the server merges them, read from the
// server at start with what localStorage held moved there once, localStorage as the fallback when
// the server cannot keep them; the API client's calls never toast; the start screen lists a
// recent chart this editor does not serve greyed, without opening it.
import { render } from 'preact';
import { act } from 'preact/test-utils';
import { afterEach, beforeEach, describe, expect, it, vi } from 'vitest';
import type { Settings, SettingsUpdate } from '../../src/api';
import { createApi } from '../../src/app/api';
import {
  apply,
  emptySettings,
  migration,
  normalize,
  readLocal,
  RECENT_MAX,
  settings,
  SettingsStore,
  withRecent,
  type SettingsServer,
} from '../../src/app/settings';
import { Welcome } from '../../src/app/Welcome';
import { initI18n, t } from '../../src/i18n';

/** A server keeping settings in memory, as crates/sfc-server merges them. */
function memoryServer(initial: Settings = emptySettings()) {
  let kept = initial;
  const writes: SettingsUpdate[] = [];
  const server: SettingsServer & { writes: SettingsUpdate[]; kept: () => Settings } = {
    writes,
    kept: () => kept,
    read: vi.fn(async () => structuredClone(kept)),
    write: vi.fn(async (u: SettingsUpdate) => {
      writes.push(u);
      kept = apply(kept, u);
      return structuredClone(kept);
    }),
  };
  return server;
}

const failing: SettingsServer = {
  read: async () => Promise.reject(new Error('offline')),
  write: async () => Promise.reject(new Error('offline')),
};

beforeEach(() => localStorage.clear());

describe('settings', () => {
  it('merge as the server merges: absent fields stay, null clears, recent replaced, watch per chart', () => {
    let s = apply(emptySettings(), { language: 'de', recent: ['/a.st', '/b.st', '/a.st'], watch: { P: ['x'], Q: ['y'] } });
    expect(s).toEqual({ language: 'de', recent: ['/a.st', '/b.st'], watch: { P: ['x'], Q: ['y'] } });
    s = apply(s, { watch: { P: null, R: ['z'] } });
    expect(s.watch).toEqual({ Q: ['y'], R: ['z'] });
    expect(s.language).toBe('de');
    s = apply(s, { language: null });
    expect('language' in s).toBe(false);
  });
  it('keep at most 20 recent charts, the newest first, each once', () => {
    let recent: string[] = [];
    for (let k = 0; k < 25; k++) recent = withRecent(recent, `/c${k}.st`);
    expect(recent).toHaveLength(RECENT_MAX);
    expect(recent[0]).toBe('/c24.st');
    expect(withRecent(recent, '/c10.st').slice(0, 2)).toEqual(['/c10.st', '/c24.st']);
    expect(withRecent(recent, '/c10.st')).toHaveLength(RECENT_MAX);
  });
  it('read only fields of the right types', () => {
    expect(normalize({ language: 3, recent: ['/a', 4], watch: { P: 'x', Q: ['n'] }, theme: 'dark' })).toEqual({ recent: ['/a'], watch: { Q: ['n'] } });
    expect(normalize(null)).toEqual(emptySettings());
  });
  it('move from localStorage only what the server lacks', () => {
    const local: Settings = { language: 'cs', recent: ['/old.st', '/a.st'], watch: { P: ['x'], Q: ['y'] } };
    expect(migration(emptySettings(), local)).toEqual({ language: 'cs', recent: ['/old.st', '/a.st'], watch: { P: ['x'], Q: ['y'] } });
    expect(migration({ language: 'de', recent: ['/a.st'], watch: { P: ['z'] } }, local)).toEqual({ recent: ['/a.st', '/old.st'], watch: { Q: ['y'] } });
    expect(migration({ language: 'de', recent: ['/a.st', '/old.st'], watch: { P: [], Q: [] } }, local)).toBeNull();
    expect(migration(emptySettings(), emptySettings())).toBeNull();
  });
});

describe('the settings store', () => {
  it('reads the server, moves what localStorage held there once, and empties localStorage', async () => {
    localStorage.setItem('sfc.language', 'cs');
    localStorage.setItem('sfc.recent', JSON.stringify(['/w/a.st']));
    localStorage.setItem('sfc.monitor.watch.Lift', JSON.stringify(['Up', 'Down']));
    localStorage.setItem('other', 'kept');
    const server = memoryServer();
    const store = new SettingsStore(localStorage);
    const s = await store.load(server);
    expect(s).toEqual({ language: 'cs', recent: ['/w/a.st'], watch: { Lift: ['Up', 'Down'] } });
    expect(server.kept()).toEqual(s);
    expect(server.writes).toHaveLength(1);
    expect(localStorage.getItem('sfc.language')).toBeNull();
    expect(localStorage.getItem('sfc.monitor.watch.Lift')).toBeNull();
    expect(localStorage.getItem('other')).toBe('kept');
    // The next start moves nothing.
    await new SettingsStore(localStorage).load(server);
    expect(server.writes).toHaveLength(1);
  });
  it("keeps the server's language over a stale one in localStorage", async () => {
    localStorage.setItem('sfc.language', 'en');
    const server = memoryServer({ language: 'de', recent: [], watch: {} });
    const store = new SettingsStore(localStorage);
    await store.load(server);
    expect(store.language()).toBe('de');
    expect(server.writes).toEqual([]);
    expect(localStorage.length).toBe(0);
  });
  it('writes changes through the server, the page seeing them at once', async () => {
    const server = memoryServer();
    const store = new SettingsStore(localStorage);
    await store.load(server);
    const seen: (string | undefined)[] = [];
    store.subscribe(() => seen.push(store.language()));
    const done = store.update({ language: 'de' });
    expect(store.language()).toBe('de');
    void store.update({ recent: ['/w/a.st'] });
    await done;
    await store.update({ watch: { P: ['x'] } });
    expect(server.kept()).toEqual({ language: 'de', recent: ['/w/a.st'], watch: { P: ['x'] } });
    expect(store.get()).toEqual(server.kept());
    expect(seen.every((l) => l === 'de')).toBe(true);
    expect(localStorage.length).toBe(0);
  });
  it('falls back to localStorage when the server cannot be asked', async () => {
    localStorage.setItem('sfc.language', 'cs');
    const store = new SettingsStore(localStorage);
    expect(await store.load(failing)).toEqual({ language: 'cs', recent: [], watch: {} });
    await store.update({ recent: ['/w/a.st'], watch: { P: ['x'] } });
    expect(readLocal(localStorage)).toEqual({ language: 'cs', recent: ['/w/a.st'], watch: { P: ['x'] } });
  });
  it('keeps a change in localStorage when the server fails to write it, and moves it later', async () => {
    const server = memoryServer();
    const store = new SettingsStore(localStorage);
    await store.load(server);
    server.write = vi.fn(async () => Promise.reject(new Error('disk full')));
    await store.update({ language: 'de' });
    expect(store.language()).toBe('de');
    expect(localStorage.getItem('sfc.language')).toBe('de');
    const healed = memoryServer();
    await new SettingsStore(localStorage).load(healed);
    expect(healed.kept().language).toBe('de');
  });
});

describe('the API client', () => {
  it('takes over the settings index.html asked for, and never toasts a failure of settings', async () => {
    const notify = vi.fn();
    const json = (v: unknown) => Promise.resolve(new Response(JSON.stringify(v), { status: 200 }));
    const fetch = vi.fn(async () => new Response('{"error":"cannot keep the settings"}', { status: 500 }));
    const api = createApi({ fetch, notify, start: { session: json({}), open: Promise.resolve(null), settings: json({ language: 'de', recent: [], watch: {} }) } });
    expect(await api.settings()).toEqual({ language: 'de', recent: [], watch: {} });
    expect(fetch).not.toHaveBeenCalled();
    await expect(api.settings()).rejects.toMatchObject({ status: 500 });
    await expect(api.saveSettings({ language: 'cs' })).rejects.toMatchObject({ status: 500 });
    const [url, init] = fetch.mock.calls[1] as unknown as [string, RequestInit];
    expect(url).toBe('/api/settings');
    expect(JSON.parse(init.body as string)).toEqual({ language: 'cs' });
    const offline = createApi({ fetch: vi.fn(async () => Promise.reject(new TypeError('network'))), notify });
    await expect(offline.settings()).rejects.toMatchObject({ status: 0 });
    expect(notify).not.toHaveBeenCalled();
  });
});

describe('the start screen', () => {
  let root: HTMLElement;
  beforeEach(() => {
    initI18n('en');
    root = document.createElement('div');
    document.body.appendChild(root);
  });
  afterEach(() => {
    render(null, root);
    root.remove();
  });

  it('lists a recent chart this editor does not serve greyed, with the reason, and does not open it', async () => {
    const server = memoryServer({ recent: ['/w/served.st', '/elsewhere/other.st'], watch: {} });
    await settings.load(server);
    const onOpen = vi.fn();
    await act(async () => {
      render(
        <Welcome mdi files={async () => [{ path: '/w/served.st', format: 'st' }]} onNew={() => {}} onOpenDialog={() => {}} onOpen={onOpen} />,
        root,
      );
    });
    await act(async () => {});
    const recent = [...root.querySelectorAll('.welcome-list')].find((s) => s.textContent?.includes(t('start.recent')))!;
    const rows = [...recent.querySelectorAll('.welcome-file')] as HTMLElement[];
    expect(rows.map((r) => r.querySelector('.welcome-file-name')?.textContent)).toEqual(['served.st', 'other.st']);
    expect(rows[0].classList.contains('not-served')).toBe(false);
    expect(rows[1].classList.contains('not-served')).toBe(true);
    expect(rows[1].textContent).toContain(t('start.notServed'));
    rows[1].click();
    expect(onOpen).not.toHaveBeenCalled();
    rows[0].click();
    expect(onOpen).toHaveBeenCalledWith('/w/served.st');
    await settings.load(null);
  });
});
