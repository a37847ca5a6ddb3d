// File → Compare with saved / git HEAD: the colours and rows made of the server's answer
// (compare.ts), and the shell with a fake server and canvas: the request, the coloured blocks,
// the Comparison panel, a click selecting a block, and an edit or Close comparison clearing it.
import { render } from 'preact';
import { act } from 'preact/test-utils';
import { afterEach, beforeEach, describe, expect, it, vi } from 'vitest';
import type { CompareChange, CompareResult, OpenResult, Session } from '../../src/api';
import { createApi } from '../../src/app/api';
import { App } from '../../src/app/App';
import { changeDetail, changeRows, compareColours, compareCounts, elementLabel, whatLabel } from '../../src/app/compare';
import type { EditorDoc } from '../../src/doc';
import { initI18n, setLanguage, t } from '../../src/i18n';
import { createFakeCanvas, type FakeCanvas } from './fakeCanvas';
import mixer from './fixtures/mixer.doc.json';

const change = (over: Partial<CompareChange>): CompareChange => ({
  element: 'step',
  name: 'A',
  kind: 'changed',
  what: '',
  old: null,
  new: null,
  elementIds: [],
  ...over,
});

const RESULT: CompareResult = {
  against: 'saved',
  file: '/w/mixer.st',
  pou: 'Mixer',
  equal: false,
  changes: [
    change({ kind: 'renamed', name: 'B', old: 'B', new: 'Stirring', elementIds: ['step:B'] }),
    change({ element: 'transition', name: 'T1', what: 'condition', old: 'Start', new: 'Start AND NOT Full', elementIds: ['transition:T1'] }),
    change({ kind: 'added', name: 'Done', elementIds: ['step:Done'] }),
    change({ name: 'Done', what: 'actions', old: '', new: 'Lamp(N)', elementIds: ['step:Done'] }),
    change({ element: 'variable', name: 'Level', kind: 'added', new: 'INT' }),
  ],
  removed: [change({ element: 'transition', name: 'T9', kind: 'removed', old: 'FROM A TO Init' })],
  layout: 2,
  notes: [],
};

describe('compare.ts', () => {
  beforeEach(() => {
    initI18n('en');
    setLanguage('en');
  });

  it('colours added blocks green and renamed or changed ones orange, added winning', () => {
    expect(compareColours(RESULT)).toEqual({ added: ['step:Done'], changed: ['step:B', 'transition:T1'] });
    expect(compareColours({ ...RESULT, changes: [], equal: true })).toEqual({ added: [], changed: [] });
  });

  it('lists the changes on the canvas first, the removed ones last, renamed ones by their new name', () => {
    const rows = changeRows(RESULT);
    expect(rows.map((r) => [r.mark, r.change.element, r.name, r.onCanvas])).toEqual([
      ['~', 'step', 'Stirring', true],
      ['~', 'transition', 'T1', true],
      ['+', 'step', 'Done', true],
      ['~', 'step', 'Done', true],
      ['+', 'variable', 'Level', false],
      ['−', 'transition', 'T9', false],
    ]);
    expect(compareCounts(RESULT)).toEqual({ added: 2, changed: 3, removed: 1 });
  });

  it('describes each change in the language chosen', () => {
    const [renamed, cond, added, actions, variable] = RESULT.changes;
    expect(changeDetail(renamed, t)).toBe('renamed Stirring');
    expect(changeDetail(cond, t)).toBe('condition: Start → Start AND NOT Full');
    expect(changeDetail(added, t)).toBe('added');
    expect(changeDetail(actions, t)).toBe('actions: (none) → Lamp(N)');
    expect(changeDetail(variable, t)).toBe('added (INT)');
    expect(changeDetail(RESULT.removed[0], t)).toBe('removed (FROM A TO Init)');
    expect(changeDetail(change({ what: 'statements', old: 'a := 1;\n  b := 2;', new: 'a := 1;' }), t)).toBe('statements: a := 1; b := 2; → a := 1;');
    expect(whatLabel('attribute sfc.timeout', t)).toBe('attribute sfc.timeout');
    expect(whatLabel('initial value', t)).toBe('initial value');
    expect(whatLabel('something new', t)).toBe('something new');
    expect(t('compare.layout', { count: 1 })).toBe('1 element only moved or resized');
    setLanguage('cs');
    expect(changeDetail(cond, t)).toBe('podmínka: Start → Start AND NOT Full');
    expect(elementLabel('transition', t)).toBe('Přechod');
    expect(t('compare.layout', { count: 3 })).toBe('3 prvky pouze přesunuty nebo změněny ve velikosti');
    setLanguage('de');
    expect(changeDetail(renamed, t)).toBe('umbenannt in Stirring');
    expect(elementLabel('step', t)).toBe('Schritt');
    expect(elementLabel('unknown', t)).toBe('unknown');
  });
});

// ---- the shell ----

const doc = mixer as EditorDoc;
let root: HTMLElement;
let canvases: FakeCanvas[];
let calls: { url: string; body: unknown }[];
let answer: { status: number; body: unknown };

function serve(session: Session, files: Record<string, OpenResult>): typeof fetch {
  return (async (input: RequestInfo | URL, init?: RequestInit) => {
    const url = String(input);
    const body = init?.body ? JSON.parse(init.body as string) : undefined;
    calls.push({ url, body });
    const json = (status: number, v: unknown) => new Response(JSON.stringify(v), { status });
    if (url === '/api/session') return json(200, session);
    if (url === '/api/open') return json(200, files[(body as { path: string }).path]);
    if (url === '/api/compare') return json(answer.status, answer.body);
    if (url === '/api/check') return json(200, { diagnostics: [] });
    return json(404, { error: `no API call ${url}` });
  }) as typeof fetch;
}

const flush = async () => {
  for (let k = 0; k < 6; k++) await act(async () => new Promise((r) => setTimeout(r, 0)));
};
const click = async (el: Element | null | undefined) => {
  if (!el) throw new Error('element not found');
  await act(async () => (el as HTMLElement).click());
  await flush();
};
/** Opens a menu and picks an item by its label. */
const pick = async (menu: string, item: string) => {
  await click([...root.querySelectorAll('.menu-title')].find((b) => b.textContent === menu));
  await click([...root.querySelectorAll('.menu-item')].find((b) => b.querySelector('.menu-label')?.textContent === item));
};

describe('Compare with saved / git HEAD in the shell', () => {
  let notify: ReturnType<typeof vi.fn<(message: string) => void>>;
  beforeEach(async () => {
    initI18n('en');
    setLanguage('en');
    root = document.createElement('div');
    document.body.appendChild(root);
    canvases = [];
    calls = [];
    answer = { status: 200, body: RESULT };
    notify = vi.fn<(message: string) => void>();
    const session: Session = { mode: 'mdi', version: '0.1.0', roots: ['/w'], open: ['/w/mixer.st'] };
    const files = { '/w/mixer.st': { path: '/w/mixer.st', format: 'st' as const, charts: [doc], diagnostics: [], hash: 'h1' } };
    const api = createApi({ token: 'tok', fetch: serve(session, files), notify });
    await act(async () => {
      render(
        <App
          api={api}
          createCanvas={(container) => {
            const c = createFakeCanvas(container);
            canvases.push(c);
            return c;
          }}
        />,
        root,
      );
    });
    await flush();
  });
  afterEach(() => {
    render(null, root);
    root.remove();
    document.body.innerHTML = '';
  });

  it('colours the blocks, lists the changes, selects a clicked one; an edit clears it', async () => {
    await pick('File', 'Compare with saved');
    expect(calls.find((c) => c.url === '/api/compare')?.body).toMatchObject({ path: '/w/mixer.st', against: 'saved', doc: { pou: 'Mixer' } });
    const c = canvases[0];
    expect(c.highlights['diff-added']?.ids).toEqual(['step:Done']);
    expect(c.highlights['diff-changed']?.ids).toEqual(['step:B', 'transition:T1']);
    const panel = root.querySelector('[data-testid="compare-panel"]')!;
    expect(panel.textContent).toContain('Compared with the saved file /w/mixer.st');
    expect(panel.textContent).toContain('2 elements only moved or resized');
    const rows = [...panel.querySelectorAll('tbody tr')];
    expect(rows.map((r) => r.querySelector('.col-message')?.textContent)).toContain('condition: Start → Start AND NOT Full');
    expect(rows[5].className).toContain('compare-removed');
    await click(rows[1]);
    expect(c.selection()).toEqual(['transition:T1']);
    expect(c.revealed).toContain('transition:T1');
    // Any edit clears the colours and the panel.
    await act(async () => c.updateElement('step:A', { x: 10 }));
    await flush();
    expect(c.highlights['diff-added']?.ids ?? []).toEqual([]);
    expect(c.highlights['diff-changed']?.ids ?? []).toEqual([]);
    expect(root.querySelector('[data-testid="compare-panel"]')).toBeNull();
  });

  it('says when nothing differs in meaning, and Close comparison clears it', async () => {
    answer = { status: 200, body: { ...RESULT, against: 'head', file: '/w/mixer.st@HEAD', equal: true, changes: [], removed: [], layout: 1 } };
    await pick('File', 'Compare with git HEAD');
    expect(calls.find((c) => c.url === '/api/compare')?.body).toMatchObject({ against: 'head' });
    const panel = root.querySelector('[data-testid="compare-panel"]')!;
    expect(panel.textContent).toContain('No differences in meaning — 1 element only moved or resized');
    expect(panel.textContent).toContain('Compared with git HEAD: /w/mixer.st@HEAD');
    await pick('File', 'Close comparison');
    expect(root.querySelector('[data-testid="compare-panel"]')).toBeNull();
  });

  it("shows the server's refusal and colours nothing", async () => {
    answer = { status: 422, body: { error: '`/w/mixer.st` is not under git: its folder is not in a git repository' } };
    await pick('File', 'Compare with git HEAD');
    expect(notify).toHaveBeenCalledWith(expect.stringContaining('is not under git'));
    expect(canvases[0].highlights['diff-changed']?.ids ?? []).toEqual([]);
    expect(root.querySelector('[data-testid="compare-panel"]')).toBeNull();
  });

  it('sends the name the POU has in the file when the chart was renamed', async () => {
    await act(async () => canvases[0].updateDoc({ pou: 'Renamed' }));
    await flush();
    await pick('File', 'Compare with saved');
    expect(calls.find((c) => c.url === '/api/compare')?.body).toMatchObject({ pou: 'Mixer', doc: { pou: 'Renamed' } });
  });
});
