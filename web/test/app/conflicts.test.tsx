// Merge conflicts (`sfc.conflict` marks of `sfc merge`): the marks read from the document
// (conflicts.ts), and the shell with a fake server and canvas: the panel listing the conflict,
// its block framed, a click selecting it, "Take theirs" sending POST /api/resolve and putting
// the answer on the canvas as an undoable edit (the tab dirty), the panel then saying none is left.
import { render } from 'preact';
import { act } from 'preact/test-utils';
import { afterEach, beforeEach, describe, expect, it, vi } from 'vitest';
import type { OpenResult, ResolveResult, Session } from '../../src/api';
import { createApi } from '../../src/app/api';
import { App } from '../../src/app/App';
import { conflictBlocks, conflictIds, conflictKindLabel, conflictsOf, theirText, unescapeIec } from '../../src/app/conflicts';
import type { EditorDoc } from '../../src/doc';
import { initI18n, setLanguage, t } from '../../src/i18n';
import { createFakeCanvas, type FakeCanvas } from './fakeCanvas';
import mixer from './fixtures/mixer.doc.json';

/** A mark as `sfc merge` writes it (sfc_syntax::attr_value::escape of `KEY\nTHEIR TEXT`). */
const escape = (v: string) =>
  v.replace(/\$/g, '$$$$').replace(/'/g, '$27').replace(/\n/g, '$N').replace(/\r/g, '$R').replace(/\t/g, '$T').replace(/\}/g, '$7D');
const mark = (element: string, theirs: string) => ({ name: 'sfc.conflict', value: escape(`${element}\n${theirs}`) });

const T1_THEIRS = '\n    TRANSITION T1 FROM Init TO A\n        := Start AND Permit; (* {ok} *)\n    END_TRANSITION\n';

const marked = (): EditorDoc => ({
  ...(mixer as EditorDoc),
  attributes: [{ name: 'sfc.build', value: 'st' }, mark('transition:T1', T1_THEIRS), mark('action:Fill', ''), mark('decl', 'VAR\nEND_VAR\n')],
});

describe('conflicts.ts', () => {
  beforeEach(() => {
    initI18n('en');
    setLanguage('en');
  });

  it('reads IEC string escapes as sfc_syntax does', () => {
    expect(unescapeIec('a$Nb$$c$27d$7De$Tf$Rg')).toBe("a\nb$c'd}e\tf\rg");
    expect(unescapeIec('$l$L$n')).toBe('\n\n\n');
    // A `$` not starting an escape stays; a non-ASCII code too.
    expect(unescapeIec('5$ and $ZZ and $E9 and $')).toBe('5$ and $ZZ and $E9 and $');
  });

  it('lists the marks in their order, with kind, name and their text', () => {
    const list = conflictsOf(marked());
    expect(list.map((c) => [c.element, c.kind, c.name])).toEqual([
      ['transition:T1', 'transition', 'T1'],
      ['action:Fill', 'action', 'Fill'],
      ['decl', 'decl', ''],
    ]);
    expect(list[0].theirs).toBe(T1_THEIRS);
    expect(list[1].theirs).toBe('');
    expect(conflictsOf(mixer as EditorDoc)).toEqual([]);
    expect(conflictsOf(null)).toEqual([]);
    // The attribute's name is case-insensitive, as in the text.
    expect(conflictsOf({ attributes: [{ name: 'SFC.Conflict', value: 'step:A$Nx' }] })).toHaveLength(1);
  });

  it('finds the blocks: a transition or step by name, an action by its action blocks', () => {
    const doc = marked();
    const [t1, fill, decl] = conflictsOf(doc);
    expect(conflictBlocks(doc, t1)).toEqual(['transition:T1']);
    expect(conflictBlocks(doc, { ...t1, name: 't1' })).toEqual(['transition:T1']);
    expect(conflictBlocks(doc, fill)).toEqual(['b4']);
    expect(conflictBlocks(doc, decl)).toEqual([]);
    expect(conflictBlocks(doc, { element: 'step:Gone', kind: 'step', name: 'Gone', theirs: '' })).toEqual([]);
    expect(conflictIds(doc)).toEqual(['transition:T1', 'b4']);
  });

  it('names the part in the language chosen and shows their text dedented', () => {
    const [t1, fill, decl] = conflictsOf(marked());
    expect(conflictKindLabel(t1, t)).toBe('Transition');
    expect(conflictKindLabel(fill, t)).toBe('Action');
    expect(conflictKindLabel(decl, t)).toBe('Declarations');
    expect(conflictKindLabel({ ...decl, kind: '@sfc.timeout#0' }, t)).toBe('attribute sfc.timeout');
    expect(theirText(t1.theirs)).toBe('TRANSITION T1 FROM Init TO A\n    := Start AND Permit; (* {ok} *)\nEND_TRANSITION');
    setLanguage('cs');
    expect(conflictKindLabel(t1, t)).toBe('Přechod');
    expect(conflictKindLabel(decl, t)).toBe('Deklarace');
    expect(t('merge.left', { count: 3 })).toBe('Zbývají 3 konflikty sloučení');
    setLanguage('de');
    expect(conflictKindLabel(fill, t)).toBe('Aktion');
    expect(t('merge.theirs')).toBe('Deren übernehmen');
  });
});

// ---- the shell ----

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
    if (url === '/api/resolve') return json(answer.status, answer.body);
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

describe('Merge conflicts in the shell', () => {
  let notify: ReturnType<typeof vi.fn<(message: string) => void>>;
  beforeEach(async () => {
    initI18n('en');
    setLanguage('en');
    root = document.createElement('div');
    document.body.appendChild(root);
    canvases = [];
    calls = [];
    const doc = marked();
    // Theirs taken on T1: their condition, that mark gone.
    const resolved: EditorDoc = {
      ...doc,
      attributes: doc.attributes!.filter((a) => !a.value?.startsWith('transition')),
      elements: doc.elements.map((e) => (e.id === 'transition:T1' ? { ...e, condition: 'Start AND Permit' } : e)),
    };
    answer = { status: 200, body: { doc: resolved, diagnostics: [] } satisfies ResolveResult };
    notify = vi.fn<(message: string) => void>();
    const session: Session = { mode: 'mdi', version: '0.1.0', roots: ['/w'], open: ['/w/mixer.st'] };
    const sfc0605 = {
      code: 'SFC0605', severity: 'error' as const, message: 'unresolved merge conflict', title: 'unresolved merge conflict', file: '/w/mixer.st',
      line: 1, column: 1, endLine: 1, endColumn: 2, element: null, elementIds: [], notes: [], witness: null,
    };
    const files = { '/w/mixer.st': { path: '/w/mixer.st', format: 'st' as const, charts: [doc], diagnostics: [sfc0605], hash: 'h1' } };
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

  it('lists the conflicts, frames their blocks, and takes theirs as an undoable edit', async () => {
    const c = canvases[0];
    const panel = () => root.querySelector('[data-testid="conflict-panel"]')!;
    expect(panel()).not.toBeNull();
    expect(panel().textContent).toContain('3 merge conflicts left');
    expect(root.querySelector('[data-testid="status-conflicts"]')?.textContent).toBe('3 merge conflicts left');
    expect(c.highlights.conflict?.ids).toEqual(['transition:T1', 'b4']);
    const rows = [...panel().querySelectorAll('tbody tr')];
    expect(rows.map((r) => r.getAttribute('data-element'))).toEqual(['transition:T1', 'action:Fill', 'decl']);
    expect(rows[0].querySelector('pre')?.textContent).toContain(':= Start AND Permit;');
    expect(rows[1].textContent).toContain('Removed on their side');
    // A click on a row selects its block.
    await click(rows[0]);
    expect(c.selection()).toEqual(['transition:T1']);
    expect(c.revealed).toContain('transition:T1');

    await click(rows[0].querySelector('button[data-side="theirs"]'));
    expect(calls.find((x) => x.url === '/api/resolve')?.body).toMatchObject({
      path: '/w/mixer.st',
      element: 'transition:T1',
      side: 'theirs',
      doc: { pou: 'Mixer' },
    });
    expect(c.getDoc().elements.find((e) => e.id === 'transition:T1')?.condition).toBe('Start AND Permit');
    expect(panel().textContent).toContain('2 merge conflicts left');
    expect(c.highlights.conflict?.ids).toEqual(['b4']);
    // Dirty, undoable; the server's diagnostics replace SFC0605.
    expect(root.querySelector('.tab.dirty')).not.toBeNull();
    expect(root.querySelector('.panel-tab .badge-error')).toBeNull();
    await act(async () => c.undo());
    await flush();
    expect(panel().textContent).toContain('3 merge conflicts left');
  });

  it('says when none is left', async () => {
    const c = canvases[0];
    const none: EditorDoc = { ...c.getDoc(), attributes: [{ name: 'sfc.build', value: 'st' }] };
    answer = { status: 200, body: { doc: none, diagnostics: [] } };
    await click(root.querySelector('[data-testid="conflict-panel"] tbody tr button[data-side="ours"]'));
    const panel = root.querySelector('[data-testid="conflict-panel"]')!;
    expect(panel.textContent).toContain('No merge conflicts left');
    expect(root.querySelector('[data-testid="status-conflicts"]')).toBeNull();
    expect(c.highlights.conflict?.ids).toEqual([]);
    expect(calls.find((x) => x.url === '/api/resolve')?.body).toMatchObject({ side: 'ours' });
  });

  it("shows the server's refusal and leaves the chart as it was", async () => {
    answer = { status: 422, body: { error: 'the conflict on `decl` cannot be resolved: no' } };
    const before = canvases[0].getDoc();
    await click(root.querySelectorAll('[data-testid="conflict-panel"] tbody tr button[data-side="theirs"]')[2]);
    expect(notify).toHaveBeenCalledWith(expect.stringContaining('cannot be resolved'));
    expect(canvases[0].getDoc()).toEqual(before);
    expect(root.querySelector('.tab.dirty')).toBeNull();
  });
});
