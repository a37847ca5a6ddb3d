import { describe, expect, it, vi } from 'vitest';
import { baseName, formatOf, isDirty, mayClose, tabTitle, TabStore, underRoot, unloadGuard, type CloseChoice } from '../../src/app/store';

const file = (path: string | null, pou = 'Mixer') => ({ path, format: 'st' as const, hash: path ? 'h1' : null, pou, chartTarget: 'blank' as const });

describe('tab store', () => {
  it('adds, activates and removes tabs, activating a neighbour', () => {
    const s = new TabStore();
    const seen = vi.fn();
    s.subscribe(seen);
    const a = s.add(file('/w/a.st', 'A'));
    const b = s.add(file('/w/a.st', 'B'));
    const c = s.add(file('/w/c.st', 'C'));
    expect(s.activeId).toBe(c.id);
    expect(seen).toHaveBeenCalledTimes(3);
    s.activate(b.id);
    s.remove(b.id);
    expect(s.active()?.id).toBe(c.id);
    s.remove(c.id);
    expect(s.active()?.id).toBe(a.id);
    s.remove(a.id);
    expect(s.active()).toBeUndefined();
    expect(s.find('/w/a.st', 'a')).toBeUndefined();
  });
  it('finds a POU of a file case-insensitively', () => {
    const s = new TabStore();
    const a = s.add(file('/w/a.st', 'Mixer'));
    expect(s.find('/w/a.st', 'MIXER')?.id).toBe(a.id);
    expect(s.find('/w/b.st', 'Mixer')).toBeUndefined();
  });
  it('tracks dirtiness from the canvas and for never-saved charts', () => {
    const s = new TabStore();
    const a = s.add(file('/w/a.st'));
    const n = s.add({ ...file(null, 'New1'), unsaved: true });
    expect(isDirty(s.get(a.id)!)).toBe(false);
    expect(isDirty(s.get(n.id)!)).toBe(true);
    expect(tabTitle(s.get(a.id)!)).toBe('a.st: Mixer');
    expect(tabTitle(s.get(n.id)!)).toBe('New1*');
    s.update(a.id, { canvasDirty: true });
    expect(tabTitle(s.get(a.id)!)).toBe('a.st: Mixer*');
    s.update(n.id, { unsaved: false, path: '/w/new1.st' });
    s.update(a.id, { canvasDirty: false });
    expect(s.anyDirty()).toBe(false);
  });
  it('keeps the build target valid for the chart target', () => {
    const s = new TabStore();
    const a = s.add(file('/w/a.st'));
    expect(s.get(a.id)!.buildTarget).toBe('st');
    s.update(a.id, { chartTarget: 'atmt' });
    expect(s.get(a.id)!.buildTarget).toBe('atmt');
    s.update(a.id, { chartTarget: 'blank' });
    expect(s.get(a.id)!.buildTarget).toBe('st');
  });
});

describe('close guard', () => {
  const s = new TabStore();
  const clean = s.add(file('/w/a.st'));
  const dirty = s.add({ ...file('/w/b.st'), unsaved: true });
  const run = async (choice: CloseChoice, saved: boolean, tab = dirty) => {
    const ask = vi.fn(async () => choice);
    const save = vi.fn(async () => saved);
    const ok = await mayClose(s.get(tab.id)!, ask, save);
    return { ok, asked: ask.mock.calls.length, saves: save.mock.calls.length };
  };
  it('closes a clean tab without asking', async () => expect(await run('cancel', false, clean)).toEqual({ ok: true, asked: 0, saves: 0 }));
  it('Cancel keeps the tab', async () => expect(await run('cancel', true)).toEqual({ ok: false, asked: 1, saves: 0 }));
  it('Discard closes without saving', async () => expect(await run('discard', false)).toEqual({ ok: true, asked: 1, saves: 0 }));
  it('Save closes when the save worked', async () => expect(await run('save', true)).toEqual({ ok: true, asked: 1, saves: 1 }));
  it('Save keeps the tab when the save failed', async () => expect(await run('save', false)).toEqual({ ok: false, asked: 1, saves: 1 }));
});

describe('leaving the page', () => {
  it('warns only while a tab is dirty', () => {
    const s = new TabStore();
    const a = s.add(file('/w/a.st'));
    const guard = unloadGuard(s);
    const ev = () => new Event('beforeunload', { cancelable: true }) as BeforeUnloadEvent;
    const e1 = ev();
    guard(e1);
    expect(e1.defaultPrevented).toBe(false);
    s.update(a.id, { canvasDirty: true });
    const e2 = ev();
    guard(e2);
    expect(e2.defaultPrevented).toBe(true);
  });
});

describe('paths', () => {
  it('accepts only paths under a root', () => {
    expect(underRoot('/w/proj/a.st', ['/w/proj'])).toBe(true);
    expect(underRoot('/w/proj/sub/a.st', ['/x', '/w/proj/'])).toBe(true);
    expect(underRoot('/w/project2/a.st', ['/w/proj'])).toBe(false);
    expect(underRoot('/w/proj/../etc/a.st', ['/w/proj'])).toBe(false);
    expect(underRoot('C:\\w\\proj\\a.st', ['C:\\w\\proj'])).toBe(true);
  });
  it('derives names and formats', () => {
    expect(baseName('/w/proj/a.st')).toBe('a.st');
    expect(baseName('C:\\w\\b.xml')).toBe('b.xml');
    expect(formatOf('/w/b.XML')).toBe('xml');
    expect(formatOf('/w/b.st')).toBe('st');
  });
});
