// The shell with a fake server and fake canvases: start-up tabs, dirty marks and the close guard,
// building with the Succeeded/Failed overlay and the result table, the error list, host mode.
import { render } from 'preact';
import { act } from 'preact/test-utils';
import { afterEach, beforeEach, describe, expect, it, vi } from 'vitest';
import type { BuildResult, Diag, OpenResult, Session } from '../../src/api';
import { createApi } from '../../src/app/api';
import { App, pouFromFile } from '../../src/app/App';
import { chartKind } from '../../src/app/chartKind';
import type { EditorDoc } from '../../src/doc';
import { initI18n, setLanguage } from '../../src/i18n';
import { createFakeCanvas, type FakeCanvas } from './fakeCanvas';
import mixer from './fixtures/mixer.doc.json';

const doc = mixer as EditorDoc;

interface Server {
  session: Session;
  files: Record<string, OpenResult>;
  check: Diag[];
  build: BuildResult;
  calls: { url: string; body: unknown }[];
}

function serve(server: Server): typeof fetch {
  return (async (input: RequestInfo | URL, init?: RequestInit) => {
    const url = String(input);
    const body = init?.body ? JSON.parse(init.body as string) : undefined;
    server.calls.push({ url, body });
    const json = (status: number, v: unknown) => new Response(JSON.stringify(v), { status });
    switch (url) {
      case '/api/session':
        return json(200, server.session);
      case '/api/open': {
        const f = server.files[(body as { path: string }).path];
        return f ? json(200, f) : json(404, { error: 'no such file' });
      }
      case '/api/save':
        return json(200, { path: (body as { path: string }).path, hash: 'h2', diagnostics: [] });
      case '/api/check':
        return json(200, { diagnostics: server.check });
      case '/api/build':
        return json(200, server.build);
      case '/api/new':
        return json(200, { doc: { ...doc, pou: (body as { name: string }).name, target: (body as { target: string }).target, elements: [doc.elements[0]], connections: [] } });
      default:
        return json(404, { error: `no API call ${url}` });
    }
  }) as typeof fetch;
}

const diag = (over: Partial<Diag>): Diag => ({
  code: 'SFC0301',
  severity: 'error',
  message: 'undeclared variable `Strt`',
  title: 'undeclared variable',
  file: 'chart.st',
  line: 3,
  column: 1,
  endLine: 3,
  endColumn: 5,
  element: 'T1',
  elementIds: ['transition:T1'],
  notes: [],
  witness: null,
  ...over,
});

let root: HTMLElement;
let canvases: FakeCanvas[];
let server: Server;

const flush = async () => {
  for (let k = 0; k < 6; k++) await act(async () => new Promise((r) => setTimeout(r, 0)));
};

async function start() {
  const api = createApi({ token: 'tok', fetch: serve(server), notify: vi.fn() });
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
}

const text = () => root.textContent ?? '';
const chartOf = (c: FakeCanvas) => chartKind(c.getDoc());
/** A button by its text or title, inside the open dialog when there is one. */
const button = (label: string) => {
  const scope = root.ownerDocument.querySelector('.modal') ?? root.ownerDocument;
  return [...scope.querySelectorAll('button')].find((b) => b.textContent?.trim() === label || b.title === label);
};
const click = async (el: Element | undefined) => {
  if (!el) throw new Error('element not found');
  await act(async () => (el as HTMLElement).click());
  await flush();
};

beforeEach(() => {
  initI18n('en');
  setLanguage('en');
  root = document.createElement('div');
  document.body.appendChild(root);
  canvases = [];
  server = {
    session: { mode: 'mdi', version: '0.1.0', roots: ['/w'], open: ['/w/mixer.st'] },
    files: { '/w/mixer.st': { path: '/w/mixer.st', format: 'st', charts: [doc], diagnostics: [], hash: 'h1' } },
    check: [],
    build: { ok: true, diagnostics: [], output: '3[0 0 1;1 1 2;2 2 1][8.1 2 1]', table: { rules: [{ state: 0, condition: 0, next: 1 }, { state: 1, condition: 1, next: 2 }, { state: 2, condition: 2, next: 1 }], timeouts: [8.1, 2, 1] } },
    calls: [],
  };
});

afterEach(() => {
  render(null, root);
  root.remove();
  document.body.innerHTML = '';
});

describe('shell', () => {
  it('opens every SFC POU of the session files as a tab', async () => {
    server.files['/w/mixer.st'].charts.push({ ...doc, pou: 'Second' });
    await start();
    const tabs = [...root.querySelectorAll('.tab')].map((t) => t.querySelector('.tab-title')?.textContent);
    expect(tabs).toEqual(['mixer.st: Mixer', 'mixer.st: Second']);
    expect(canvases.length).toBe(2);
    expect(canvases[0].getDoc().pou).toBe('Mixer');
    expect(server.calls[0].url).toBe('/api/session');
  });

  it('marks a changed chart with * and asks before discarding it', async () => {
    server.files['/w/mixer.st'].charts.push({ ...doc, pou: 'Second' });
    await start();
    // The file's first chart is shown; the second is chosen by its tab.
    expect(root.querySelector('.tab.active .tab-title')?.textContent).toBe('mixer.st: Mixer');
    await click(root.querySelectorAll<HTMLElement>('.tab')[1]);
    await act(async () => void canvases[1].updateDoc({ description: 'changed' }));
    await flush();
    expect(root.querySelector('.tab.active .tab-title')?.textContent).toBe('mixer.st: Second*');
    await click(root.querySelector('.tab.active .tab-close')!);
    expect(text()).toContain('has unsaved changes');
    await click(button('Cancel'));
    expect(root.querySelectorAll('.tab').length).toBe(2);
    await click(root.querySelector('.tab.active .tab-close')!);
    await click(button('Save'));
    const save = server.calls.find((c) => c.url === '/api/save');
    expect(save?.body).toMatchObject({ path: '/w/mixer.st', format: 'st', hash: 'h1', doc: { pou: 'Second', description: 'changed' } });
    expect(root.querySelectorAll('.tab').length).toBe(1);
    // The other chart of the same file now compares against the new contents.
    await act(async () => canvases[0].updateDoc({ description: 'x' }));
    await flush();
    await act(async () => void root.ownerDocument.defaultView!.dispatchEvent(new KeyboardEvent('keydown', { key: 's', ctrlKey: true, bubbles: true })));
    await flush();
    expect(server.calls.filter((c) => c.url === '/api/save').map((c) => (c.body as { hash: string }).hash)).toEqual(['h1', 'h2']);
  });

  it('saves a renamed chart over the POU it was opened as, then under its new name', async () => {
    await start();
    await act(async () => void canvases[0].updateDoc({ pou: 'Renamed' }));
    await flush();
    await act(async () => void root.ownerDocument.defaultView!.dispatchEvent(new KeyboardEvent('keydown', { key: 's', ctrlKey: true, bubbles: true })));
    await flush();
    await act(async () => void canvases[0].updateDoc({ description: 'again' }));
    await flush();
    await act(async () => void root.ownerDocument.defaultView!.dispatchEvent(new KeyboardEvent('keydown', { key: 's', ctrlKey: true, bubbles: true })));
    await flush();
    const saves = server.calls.filter((c) => c.url === '/api/save').map((c) => c.body as { pou?: string; doc: EditorDoc });
    expect(saves.map((b) => [b.pou, b.doc.pou])).toEqual([
      ['Mixer', 'Renamed'],
      ['Renamed', 'Renamed'],
    ]);
  });

  it('builds: Succeeded overlay until the next change, the table in the Result panel', async () => {
    server.files['/w/mixer.st'].charts = [{ ...doc, target: 'atmt' }];
    await start();
    await click(button('Build (F7)'));
    expect(server.calls.find((c) => c.url === '/api/build')?.body).toMatchObject({ target: 'atmt' });
    expect(root.querySelector('.outcome')?.textContent).toBe('Succeeded');
    const cells = [...root.querySelectorAll('.atmt tbody tr')].map((r) => [...r.querySelectorAll('td')].map((td) => td.textContent).join(' '));
    expect(cells).toEqual(['0 0 0 1', '1 1 1 2', '2 2 2 1', '0 8.1', '1 2', '2 1']);
    expect(text()).toContain('3[0 0 1;1 1 2;2 2 1][8.1 2 1]');
    expect(text()).toContain('Download Mixer.atmt.txt');
    await act(async () => canvases[0].updateElement('step:A', { x: 10 }));
    await flush();
    expect(root.querySelector('.outcome')).toBeNull();
  });

  it('shows a failed validation in the error list, frames the blocks and highlights a clicked row', async () => {
    server.check = [diag({}), diag({ code: 'SFC0213', severity: 'warning', message: 'step `Done` has no way out', title: 'step without a way out', element: 'Done', elementIds: ['step:Done'] })];
    await start();
    await act(async () => {
      const select = root.querySelector('select.tool-select') as HTMLSelectElement;
      select.value = 'validate';
      select.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await flush();
    await click(button('Build (F7)'));
    expect(server.calls.find((c) => c.url === '/api/check')?.body).toMatchObject({ analysis: true });
    expect(root.querySelector('.outcome')?.textContent).toBe('Failed');
    expect(text()).toContain('1 error');
    expect(text()).toContain('1 warning');
    const c = canvases[0];
    expect(c.highlights.error?.ids).toEqual(['transition:T1']);
    expect(c.highlights.warning?.ids).toEqual(['step:Done']);
    await click(root.querySelector('.error-list tbody tr')!);
    expect(c.highlights['selected-diagnostic']?.ids).toEqual(['transition:T1']);
    expect(c.revealed).toContain('transition:T1');
    await click(button('Highlight'));
    expect(c.highlights['selected-diagnostic']).toBeUndefined();
  });

  it('translates the error list in Czech, naming what the message quotes, with the English message as the tooltip', async () => {
    server.build = { ok: false, diagnostics: [diag({})] };
    await start();
    await click(button('Build (F7)'));
    expect(root.querySelector('.outcome')?.textContent).toBe('Failed');
    await act(async () => setLanguage('cs'));
    await flush();
    const cell = root.querySelector('.col-message') as HTMLElement;
    expect(cell.textContent).toBe('nedeklarovaná proměnná: Strt');
    expect(cell.title).toBe('undeclared variable `Strt`');
    expect(text()).toContain('Soubor');
  });

  it('steps through a witness with the steps active after each firing', async () => {
    server.check = [diag({ code: 'SFC0501', message: 'unsafe chart', elementIds: ['step:A'], witnessIds: ['transition:T1', 'transition:T2'] })];
    await start();
    await act(async () => {
      const select = root.querySelector('select.tool-select') as HTMLSelectElement;
      select.value = 'validate';
      select.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await click(button('Build (F7)'));
    await click(button('Show witness'));
    const c = canvases[0];
    expect(root.querySelector('.counter')?.textContent).toBe('1 / 2');
    expect(c.highlights.witness?.ids).toEqual(['transition:T1']);
    expect([...(c.highlights.active?.ids ?? [])].sort()).toEqual(['step:A', 'step:B']);
    await click(button('Next firing'));
    expect(c.highlights.witness?.ids).toEqual(['transition:T2']);
    expect(c.highlights.active?.ids).toEqual(['step:Done']);
    await click(button('End the witness'));
    expect(c.highlights.witness).toBeUndefined();
  });

  it('edits properties through the canvas (undoable)', async () => {
    await start();
    const c = canvases[0];
    await act(async () => c.select(['step:A']));
    await flush();
    const timeout = root.querySelector('#p-timeout') as HTMLInputElement;
    expect(timeout.value).toBe('T#8.1s');
    await act(async () => {
      timeout.value = '2.5';
      timeout.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await flush();
    expect(c.getDoc().elements.find((e) => e.id === 'step:A')?.timeout).toBe('T#2.5s');
    await act(async () => {
      timeout.value = 'T#1s2m';
      timeout.dispatchEvent(new Event('input', { bubbles: true }));
      timeout.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await flush();
    expect(text()).toContain('Units go from largest to smallest');
    expect(c.getDoc().elements.find((e) => e.id === 'step:A')?.timeout).toBe('T#2.5s');
    // The step's action block rows are edited in place.
    expect([...root.querySelectorAll('.assoc-table tbody tr')].length).toBe(2);
    c.undo();
    expect(c.getDoc().elements.find((e) => e.id === 'step:A')?.timeout).toBe('T#8.1s');
  });
});

describe('actions written in SFC and step actions', () => {
  const cycle: EditorDoc = {
    pou: 'Press',
    pouKind: 'functionBlock',
    target: 'blank',
    declarations: '',
    actions: [],
    elements: [
      { id: 'step:Ready', kind: 'step', name: 'Ready', initial: true, x: 40, y: 40, w: 80, h: 40 },
      { id: 'step:Lower', kind: 'step', name: 'Lower', x: 40, y: 160, w: 80, h: 40, stepActions: ['ENTRY_ACTION := Lower_entry'] },
    ],
    connections: [],
  };
  const press: EditorDoc = {
    pou: 'Press',
    pouKind: 'functionBlock',
    target: 'blank',
    declarations: 'VAR\nEND_VAR',
    body: 'Cycle();',
    actions: [
      { name: 'Lower_entry', body: 'Down := TRUE;' },
      { name: 'Cycle', body: 'INITIAL_STEP Ready: END_STEP', chart: cycle },
    ],
    elements: [],
    connections: [],
  };

  it('opens the chart of an action from its POU, edits it with undo and saves it into the POU', async () => {
    server.session.open = ['/w/press.st'];
    server.files['/w/press.st'] = { path: '/w/press.st', format: 'st', charts: [press], diagnostics: [], hash: 'h1' };
    await start();
    // The POU's body is text: the canvas says so and Properties edits it.
    expect(text()).toContain('The body of Press is written in ST');
    expect(root.querySelector('.canvas-area')?.classList.contains('hide-palette')).toBe(true);
    expect([...root.querySelectorAll('.chart-view')].map((b) => b.textContent)).toEqual(['STPress', 'SFCPress.Cycle']);
    await click(root.querySelector('.side-panel .open-action-chart[data-action="Cycle"]')!);
    expect(canvases.length).toBe(2);
    const c = canvases[1];
    expect(c.getDoc().elements.map((e) => e.name)).toEqual(['Ready', 'Lower']);
    expect(root.querySelector('.chart-view.active')?.textContent).toContain('Press.Cycle');
    // The step's entry action in Properties, one undoable change of the action's chart.
    await act(async () => c.select(['step:Lower']));
    await flush();
    const entry = root.querySelector('#p-sa-entry') as HTMLInputElement;
    expect(entry.value).toBe('Lower_entry');
    await act(async () => {
      entry.value = 'Raise_entry';
      entry.dispatchEvent(new Event('input', { bubbles: true }));
      entry.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await flush();
    expect(c.getDoc().elements[1].stepActions).toEqual(['ENTRY_ACTION := Raise_entry']);
    const exit = root.querySelector('#p-sa-exit') as HTMLInputElement;
    await act(async () => {
      exit.value = 'not a name';
      exit.dispatchEvent(new Event('input', { bubbles: true }));
      exit.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await flush();
    expect(text()).toContain('An action of the POU, or instance.Action');
    expect(c.getDoc().elements[1].stepActions).toEqual(['ENTRY_ACTION := Raise_entry']);
    expect(root.querySelector('.tab.active .tab-title')?.textContent).toBe('press.st: Press*');
    c.undo();
    expect(c.getDoc().elements[1].stepActions).toEqual(['ENTRY_ACTION := Lower_entry']);
    c.redo();
    await flush();
    // Saving from the action's chart sends the POU with the chart as edited.
    await act(async () => void root.ownerDocument.defaultView!.dispatchEvent(new KeyboardEvent('keydown', { key: 's', ctrlKey: true, bubbles: true })));
    await flush();
    const save = server.calls.find((x) => x.url === '/api/save')?.body as { doc: EditorDoc };
    expect(save.doc.pou).toBe('Press');
    expect(save.doc.body).toBe('Cycle();');
    expect(save.doc.actions[1].chart?.elements[1].stepActions).toEqual(['ENTRY_ACTION := Raise_entry']);
    expect(root.querySelector('.tab.active .tab-title')?.textContent).toBe('press.st: Press');
    // Back to the POU, then the chart's canvas closed: its chart goes back into the POU's document.
    await click(root.querySelectorAll('.chart-view')[0]);
    expect(root.querySelector('.chart-view.active')?.textContent).toBe('STPress');
    await click(root.querySelector('.chart-view-close')!);
    expect(canvases[0].getDoc().actions[1].chart?.elements[1].stepActions).toEqual(['ENTRY_ACTION := Raise_entry']);
  });
});

describe('IEC 61131-3 charts', () => {
  const choose = async (select: HTMLSelectElement, value: string) => {
    await act(async () => {
      select.value = value;
      select.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await flush();
  };
  const buildSelect = () => root.querySelectorAll('select.tool-select')[1] as HTMLSelectElement;

  it('New → IEC 61131-3 makes a Blank chart with sfc.build = st, badge IEC, built to ST', async () => {
    server.session.open = [];
    await start();
    await click(button('New…'));
    const iec = [...root.ownerDocument.querySelectorAll('.target-option')].find((l) => l.querySelector('.target-name')?.textContent === 'IEC 61131-3');
    expect(iec?.textContent).toContain('Structured Text');
    await click(iec!.querySelector('input')!);
    await click(button('Create'));
    expect(server.calls.find((c) => c.url === '/api/new')?.body).toEqual({ name: 'Chart1', target: 'blank' });
    const d = canvases[0].getDoc();
    expect(d.target).toBe('blank');
    expect(d.attributes).toEqual([{ name: 'sfc.build', value: 'st' }]);
    // Created with the attribute, not as an edit to undo.
    expect(canvases[0].canUndo()).toBe(false);
    expect(root.querySelector('.tab.active .tab-target')?.textContent).toBe('IEC');
    expect(buildSelect().value).toBe('st');
    await click(button('Build (F7)'));
    expect(server.calls.find((c) => c.url === '/api/build')?.body).toMatchObject({ target: 'st', doc: { attributes: [{ name: 'sfc.build', value: 'st' }] } });
  });

  it('the build select writes sfc.build as one undoable change of the chart', async () => {
    server.files['/w/mixer.st'].charts = [{ ...doc, attributes: [{ name: 'vendor.x', value: '1' }, { name: 'sfc.build', value: 'plcopen' }] }];
    await start();
    const c = canvases[0];
    expect(root.querySelector('.tab.active .tab-target')?.textContent).toBe('IEC');
    expect(buildSelect().value).toBe('plcopen');
    await choose(buildSelect(), 'stl');
    expect(c.getDoc().attributes).toEqual([{ name: 'vendor.x', value: '1' }, { name: 'sfc.build', value: 'stl' }]);
    expect(root.querySelector('.tab.active .tab-title')?.textContent).toBe('mixer.st: Mixer*');
    await click(button('Build (F7)'));
    expect(server.calls.find((c) => c.url === '/api/build')?.body).toMatchObject({ target: 'stl' });
    await act(async () => c.undo());
    await flush();
    expect(c.canUndo()).toBe(false);
    expect(c.getDoc().attributes).toEqual([{ name: 'vendor.x', value: '1' }, { name: 'sfc.build', value: 'plcopen' }]);
    expect(buildSelect().value).toBe('plcopen');
  });

  it('a Blank chart keeps its build target in the tab; Properties switches Blank and IEC', async () => {
    await start();
    const c = canvases[0];
    expect(root.querySelector('.tab.active .tab-target')?.textContent).toBe('Blank');
    await choose(buildSelect(), 'svg');
    expect(c.canUndo()).toBe(false);
    expect(c.getDoc().attributes).toBeUndefined();
    const target = root.querySelector('#p-target') as HTMLSelectElement;
    expect([...target.options].map((o) => o.value)).toEqual(['blank', 'atmt', 'eatmt', 'iec']);
    await choose(target, 'iec');
    expect(c.getDoc()).toMatchObject({ target: 'blank', attributes: [{ name: 'sfc.build', value: 'st' }] });
    expect(root.querySelector('.tab.active .tab-target')?.textContent).toBe('IEC');
    expect(buildSelect().value).toBe('st');
    await choose(root.querySelector('#p-target') as HTMLSelectElement, 'blank');
    expect(c.getDoc().attributes).toEqual([]);
    expect(root.querySelector('.tab.active .tab-target')?.textContent).toBe('Blank');
    c.undo();
    await flush();
    expect(chartOf(c)).toBe('iec');
  });
});

describe('host mode', () => {
  it('creates the missing chart, marks it dirty, fixes the target and shows the limits', async () => {
    server.session = { mode: 'host', version: '0.1.0', roots: ['/w'], open: [], host: { fb: 'atmt', nstep: 16, ntr: 64, file: '/w/tank chart.st', result: '/w/out.txt' } };
    await start();
    expect(server.calls.find((c) => c.url === '/api/new')?.body).toEqual({ name: 'tank_chart', target: 'atmt' });
    expect(root.querySelectorAll('.tab').length).toBe(0);
    expect(root.querySelector('.host-title')?.textContent).toContain('tank_chart*');
    expect(text()).toContain('ATMT: at most 16 steps, 64 rules');
    expect(button('New')).toBeUndefined();
    await click(button('Build (F7)'));
    expect(server.calls.find((c) => c.url === '/api/build')?.body).toMatchObject({ target: 'atmt', nstep: 16, ntr: 64 });
  });
  it('makes POU names from file names', () => {
    expect(pouFromFile('/w/tank chart.st')).toBe('tank_chart');
    expect(pouFromFile('/w/1st.xml')).toBe('Chart_1st');
  });
});
