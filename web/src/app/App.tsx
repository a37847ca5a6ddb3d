// The SFC Editor's shell: menus, toolbar, chart tabs (MDI) or the single chart (host mode), the
// canvas of each chart, the Properties, Error List and Result panels, dialogs and status bar.
import { useEffect, useMemo, useRef, useState } from 'preact/hooks';
import type { BuildTarget, CompareAgainst, Diag, FileFormat, PouEntry, Session } from '../api';
import type { CanvasHandle, CreateCanvas } from '../diagram/types';
import type { EditorDoc } from '../doc';
import { currentLanguage, i18n, LANGUAGES, nextLanguage, setLanguage, t, type Lang } from '../i18n';
import { ApiError, type Api } from './api';
import { targetsFor } from './buildResult';
import { chartBuild, chartKind, kindFields, withBuild, type ChartKind } from './chartKind';
import { witnessSituations } from './chart';
import { actionChart, assemble, blocksNamed, sfcActions, viewKey } from './actionCharts';
import { compareColours, type ChangeRow } from './compare';
import { ComparePanel } from './ComparePanel';
import { ConflictPanel } from './ConflictPanel';
import { conflictBlocks, conflictIds, conflictKindLabel, conflictsOf, type MergeConflict } from './conflicts';
import { AboutDialog, CloseDialog, ConflictDialog, NewDialog, OpenDialog, SaveAsDialog, ShortcutsDialog, type NewChartRequest } from './dialogs';
import { ErrorList, type WitnessView } from './ErrorList';
import { rememberFile, Welcome } from './Welcome';
import { Icon } from './icons';
import { MenuBar, type MenuDef } from './Menu';
import { PrintDialog } from './PrintDialog';
import { diagnosticsOf, fileDiagnostics, type TreeNode } from './project';
import { ProjectTree } from './ProjectTree';
import { useMonitor } from '../monitor';
import { installProbe } from './probe';
import { PropertiesPanel } from './Properties';
import { download, ResultPanel } from './ResultPanel';
import { baseName, formatOf, isDirty, mayClose, tabTitle, TabStore, unloadGuard, type CloseChoice, type NewTab, type TabState } from './store';
import { toasts } from './toast';

type Dialog =
  | { kind: 'new'; target: ChartKind }
  | { kind: 'open' }
  | { kind: 'saveAs'; path: string; format: FileFormat; resolve: (r: { path: string; format: FileFormat } | null) => void }
  | { kind: 'close'; name: string; resolve: (c: CloseChoice) => void }
  | { kind: 'conflict'; path: string; resolve: (overwrite: boolean) => void }
  | { kind: 'print'; svg: (marks: boolean) => string; doc: EditorDoc; path: string | null }
  | { kind: 'about' }
  | { kind: 'shortcuts' };

type BuildMode = 'validate' | 'build';

/** A function that re-renders the component. */
function useForceUpdate(): () => void {
  const [, set] = useState(0);
  return () => set((n) => n + 1);
}

/** Re-renders the component when `source` reports a change. */
function useSubscription(source: { subscribe: (l: () => void) => () => void }): void {
  const force = useForceUpdate();
  useEffect(() => source.subscribe(force), [source]);
}

/** The tab fields that follow the document: its kind and, for an IEC chart, the build target
 *  its `sfc.build` names (other charts keep the target chosen in the toolbar). */
function kindOfTab(doc: EditorDoc): Pick<TabState, 'chartTarget'> & Partial<Pick<TabState, 'buildTarget'>> {
  const kind = chartKind(doc);
  return kind === 'iec' ? { chartTarget: kind, buildTarget: chartBuild(doc) } : { chartTarget: kind };
}

/** The badge of a chart's tab: the target's name, `IEC` for IEC 61131-3 charts. */
function badge(kind: ChartKind): string {
  return kind === 'iec' ? t('target.iecShort') : t(`target.${kind}`);
}

/** A valid POU name from a file name (`my chart.st` → `my_chart`). */
export function pouFromFile(path: string): string {
  const stem = baseName(path).replace(/\.[^.]*$/, '');
  const cleaned = stem.replace(/[^A-Za-z0-9_]+/g, '_').replace(/_+/g, '_').replace(/^_|_$/g, '');
  return /^[A-Za-z_]/.test(cleaned) ? cleaned : `Chart_${cleaned || '1'}`;
}

export interface AppProps {
  api: Api;
  createCanvas: CreateCanvas;
}

export function App({ api, createCanvas }: AppProps) {
  const store = useMemo(() => new TabStore(), []);
  useSubscription(store);
  useSubscription(toasts);
  const relabel = useForceUpdate();
  const [session, setSession] = useState<Session | null>(null);
  const [startError, setStartError] = useState('');
  const canvases = useRef(new Map<string, CanvasHandle>());
  const containers = useRef(new Map<string, HTMLElement>());
  const pending = useRef(new Map<string, EditorDoc>());
  const [selection, setSelection] = useState<string[]>([]);
  const docChanged = useForceUpdate();
  const [zoom, setZoom] = useState(1);
  const [panels, setPanels] = useState({ tools: true, properties: true, bottom: true });
  const [bottomTab, setBottomTab] = useState<'errors' | 'result' | 'compare' | 'conflicts'>('errors');
  const [selectedChange, setSelectedChange] = useState<number | null>(null);
  const [selectedConflict, setSelectedConflict] = useState<number | null>(null);
  /** Tabs in which a merge conflict was resolved: their Merge conflicts tab stays (saying so)
   *  when none is left. */
  const [resolvedIn, setResolvedIn] = useState<ReadonlySet<string>>(new Set());
  const [buildMode, setBuildMode] = useState<BuildMode>('build');
  const [dialog, setDialog] = useState<Dialog | null>(null);
  const [selectedDiag, setSelectedDiag] = useState<number | null>(null);
  const [highlightOn, setHighlightOn] = useState(true);
  const [witness, setWitness] = useState<WitnessView | null>(null);
  const [busy, setBusy] = useState(false);
  /** Per opened file: its POUs (the project tree) and its diagnostics outside every chart. */
  const [files, setFiles] = useState<Record<string, { pous: PouEntry[]; charts: string[]; diagnostics: Diag[]; all: Diag[] }>>({});
  const [treeOpen, setTreeOpen] = useState(true);
  /** The pending revalidation of each tab after an edit (debounced). */
  const rechecks = useRef(new Map<string, number>());

  const host = session?.mode === 'host' ? session.host ?? null : null;
  const tab = store.active();
  // The canvas of the chart the tab shows: the POU's, or that of one of its actions written in SFC.
  const canvas = tab ? canvases.current.get(viewKey(tab.id, tab.view)) : undefined;
  const actionView = tab?.view ?? null;

  /** The POU's document of a tab with the charts of its actions as their canvases hold them
   *  (what save, check, build and prove send). `draft`: the shown action chart with a pending edit. */
  function docOf(tabId: string, draft?: EditorDoc): EditorDoc | null {
    const x = store.get(tabId);
    const pouCanvas = canvases.current.get(tabId);
    if (!x || !pouCanvas) return null;
    const charts = new Map<string, EditorDoc>();
    for (const v of x.views) {
      const c = canvases.current.get(viewKey(tabId, v));
      if (c) charts.set(v, draft && v === x.view ? draft : c.getDoc());
    }
    const pouDoc = draft && x.view === null ? draft : pouCanvas.getDoc();
    return assemble(pouDoc, charts);
  }

  /** Every canvas of a tab: the POU's and its open action charts'. */
  function canvasesOf(x: TabState): CanvasHandle[] {
    return [null, ...x.views].map((v) => canvases.current.get(viewKey(x.id, v))).filter((c): c is CanvasHandle => !!c);
  }

  // Monitor mode (web/src/monitor): its menu, toolbar button and view over the workspace.
  const monitor = useMonitor({
    createCanvas,
    current: () => {
      const d = tab ? docOf(tab.id) : null;
      return d && tab ? { doc: d, title: tabTitle(tab).replace(/\*$/, ''), path: tab.path } : null;
    },
    hasChart: !!canvas && !!tab,
    // A mechanism of another chart: its open tab becomes the one shown (and monitored). The
    // chart of an action written in SFC is `Pou.Action` (CODESYS's SFC action): the chart of
    // that action in the POU's tab, named so.
    chartOf: (pou) => {
      const dot = pou.indexOf('.');
      const owner = dot < 0 ? pou : pou.slice(0, dot);
      const action = dot < 0 ? null : pou.slice(dot + 1);
      const x = store.tabs.find((y) => y.pou.toUpperCase() === owner.toUpperCase());
      const d = x ? docOf(x.id) : null;
      if (!x || !d) return null;
      const chart = action ? actionChart(d, action) : d;
      if (!chart) return null;
      store.activate(x.id);
      const title = tabTitle(x).replace(/\*$/, '');
      return action ? { doc: { ...chart, pou }, title: `${title} › ${action}` } : { doc: d, title };
    },
  });

  // Language: every string is re-read on render; the canvases re-translate their palettes.
  useEffect(() => {
    const onChange = () => {
      relabel();
      for (const c of canvases.current.values()) c.relabel();
      document.documentElement.lang = currentLanguage();
    };
    i18n.on('languageChanged', onChange);
    document.documentElement.lang = currentLanguage();
    return () => i18n.off('languageChanged', onChange);
  }, []);

  useEffect(() => {
    const guard = unloadGuard(store);
    window.addEventListener('beforeunload', guard);
    return () => window.removeEventListener('beforeunload', guard);
  }, [store]);

  // Read-only views for the browser tests (window.__sfc), in test builds only: `vite build
  // --mode test` (web/dist-test) and vitest. The production bundle leaves the probe out.
  useEffect(() => (import.meta.env.MODE === 'test' ? installProbe(store, canvases.current) : undefined), [store]);

  // Start: the session, then the files named on the command line (or the host chart).
  useEffect(() => {
    api.session().then(
      async (s) => {
        setSession(s);
        if (s.mode === 'host' && s.host) await openHost(s);
        else for (const path of s.open) await openFile(path);
      },
      (e: Error) => setStartError(e.message),
    );
  }, []);

  // The active tab is scrolled into view in the tab strip.
  useEffect(() => {
    document.querySelector('.tabstrip .tab.active')?.scrollIntoView?.({ block: 'nearest', inline: 'nearest' });
  }, [store.activeId, store.tabs.length]);

  // Switching tabs shows that chart's selection, zoom and diagnostics (a row of the Error list
  // stays selected when it showed another chart of the same tab).
  const shownTab = useRef<string | undefined>(undefined);
  useEffect(() => {
    setSelection(canvas ? canvas.selection() : []);
    setZoom(canvas ? canvas.getZoom() : 1);
    if (shownTab.current !== tab?.id) setSelectedDiag(null);
    shownTab.current = tab?.id;
    setWitness(null);
    setSelectedChange(null);
    setSelectedConflict(null);
    setBottomTab((b) => (b === 'compare' && !store.active()?.compare ? 'errors' : b));
  }, [tab?.id, canvas]);

  // Every error and warning block framed. In an action's chart the blocks are found by the
  // names the diagnostics give (the server locates blocks in the POU's chart only).
  const diagnostics = tab?.diagnostics ?? [];
  const blocksOf = (d: Diag): string[] => {
    if (!actionView || !canvas) return d.elementIds;
    return blocksNamed(canvas.getDoc(), d.element);
  };
  useEffect(() => {
    if (!canvas) return;
    const ids = (sev: Diag['severity']) => [...new Set(diagnostics.filter((d) => d.severity === sev).flatMap(blocksOf))];
    canvas.highlight('error', ids('error'));
    canvas.highlight('warning', ids('warning'));
  }, [canvas, diagnostics]);

  // The clicked diagnostic's blocks.
  useEffect(() => {
    if (!canvas) return;
    const d = selectedDiag === null ? undefined : diagnostics[selectedDiag];
    const ids = d ? blocksOf(d) : [];
    if (highlightOn && d && ids.length > 0) {
      canvas.highlight('selected-diagnostic', ids);
      canvas.reveal(ids[0]);
    } else canvas.clearHighlights('selected-diagnostic');
  }, [canvas, selectedDiag, highlightOn, diagnostics]);

  // Stepping through a witness: the transition fired at step k and the steps active after it.
  useEffect(() => {
    if (!canvas) return;
    const ids = witness ? diagnostics[witness.diag]?.witnessIds : undefined;
    if (!witness || !ids) {
      canvas.clearHighlights('witness');
      canvas.clearHighlights('active');
      return;
    }
    const doc = canvas.getDoc();
    const fired = witness.step > 0 ? ids[witness.step - 1] : undefined;
    canvas.highlight('witness', fired ? [fired] : [], fired ? { [fired]: String(witness.step) } : undefined);
    const active =
      witness.step === 0 ? doc.elements.filter((e) => e.kind === 'step' && e.initial).map((e) => e.id) : witnessSituations(doc, ids)[witness.step - 1];
    canvas.highlight('active', active);
    if (fired) canvas.reveal(fired);
  }, [canvas, witness, diagnostics]);

  // A comparison's colours on the POU's chart of each tab: added green, renamed or changed
  // orange (highlights: the document is not touched); none once it is closed or the chart changed.
  const comparisons = store.tabs.map((x) => x.compare);
  useEffect(() => {
    for (const x of store.tabs) {
      const c = canvases.current.get(x.id);
      if (!c) continue;
      const colours = x.compare ? compareColours(x.compare) : { added: [], changed: [] };
      c.highlight('diff-added', colours.added);
      c.highlight('diff-changed', colours.changed);
    }
    setSelectedChange(null);
    setBottomTab((b) => (b === 'compare' && !store.active()?.compare ? 'errors' : b));
  }, comparisons);

  function addTab(init: NewTab, doc: EditorDoc): TabState {
    const created = store.add(init);
    pending.current.set(created.id, doc);
    return created;
  }

  /** Whether the canvas `key` is the one the active tab shows. */
  function shown(key: string): boolean {
    const x = store.active();
    return !!x && viewKey(x.id, x.view) === key;
  }

  /** A canvas for a tab's view (`key`: see viewKey): the POU's chart, or an action's. */
  function attachCanvas(key: string, container: HTMLElement): () => void {
    const [id] = key.split('::');
    const isPou = key === id;
    const c = createCanvas(container, { t: (k, opts) => t(k, opts) });
    canvases.current.set(key, c);
    containers.current.set(key, container);
    const doc = pending.current.get(key);
    pending.current.delete(key);
    if (doc) c.load(doc);
    const offs = [
      c.on('change', () => {
        const x = store.get(id);
        const dirty = x ? canvasesOf(x).some((o) => o.isDirty()) : c.isDirty();
        if (isPou) {
          const d = c.getDoc();
          store.update(id, { canvasDirty: dirty, outcome: 'none', compare: null, pou: d.pou, ...kindOfTab(d) });
        } else store.update(id, { canvasDirty: dirty, outcome: 'none', compare: null });
        scheduleRecheck(id);
        docChanged();
      }),
      c.on('selection', (ids) => {
        if (shown(key)) setSelection(ids);
      }),
      c.on('zoom', (level) => {
        if (shown(key)) setZoom(level);
      }),
      c.on('properties', () => setPanels((p) => ({ ...p, properties: true }))),
    ];
    docChanged();
    return () => {
      offs.forEach((off) => off());
      c.destroy();
      canvases.current.delete(key);
      containers.current.delete(key);
    };
  }

  /** Shows the chart of action `action` of a tab (opening its canvas the first time), or the
   *  POU's own with null. */
  function showView(x: TabState, action: string | null): void {
    if (action === null) {
      store.update(x.id, { view: null });
      return;
    }
    const known = x.views.find((v) => v.toLowerCase() === action.toLowerCase());
    if (known) {
      store.update(x.id, { view: known });
      return;
    }
    const pouDoc = canvases.current.get(x.id)?.getDoc();
    const chart = pouDoc ? actionChart(pouDoc, action) : undefined;
    if (!pouDoc || !chart) {
      toasts.show('error', t('views.noChart', { action }));
      return;
    }
    pending.current.set(viewKey(x.id, action), chart);
    store.update(x.id, { views: [...x.views, action], view: action });
  }

  /** Closes the canvas of an action's chart; the chart as edited goes back into the POU's
   *  document (one undoable change of the POU's chart when it differs). */
  function closeView(x: TabState, action: string): void {
    const c = canvases.current.get(viewKey(x.id, action));
    const pc = canvases.current.get(x.id);
    if (c && pc) {
      const d = pc.getDoc();
      const back = assemble(d, new Map([[action, c.getDoc()]]));
      if (JSON.stringify(back.actions) !== JSON.stringify(d.actions)) pc.updateDoc({ actions: back.actions });
    }
    store.update(x.id, { views: x.views.filter((v) => v !== action), view: x.view === action ? null : x.view });
    const y = store.get(x.id);
    if (y) store.update(y.id, { canvasDirty: canvasesOf(y).some((o) => o.isDirty()) });
  }

  async function openFile(path: string): Promise<void> {
    const already = store.tabs.find((x) => x.path === path);
    if (already) {
      store.activate(already.id);
      return;
    }
    try {
      const r = await api.open(path);
      rememberFile(r.path);
      if (r.charts.length === 0) toasts.show('info', t('open.noCharts', { file: baseName(path) }));
      // Each tab lists its own chart's diagnostics; the rest are the file's (project.ts).
      const names = r.charts.map((c) => c.pou);
      setFiles((f) => ({ ...f, [r.path]: { pous: r.pous ?? [], charts: names, diagnostics: fileDiagnostics(r.diagnostics, names), all: r.diagnostics } }));
      let first: TabState | undefined;
      for (const chart of r.charts) {
        const added = addTab({ path: r.path, format: r.format, hash: r.hash, pou: chart.pou, filePou: chart.pou, ...kindOfTab(chart), diagnostics: diagnosticsOf(r.diagnostics, chart.pou, names) }, chart);
        first ??= added;
      }
      // The file's first chart is the one shown.
      if (first) store.activate(first.id);
    } catch (e) {
      if (e instanceof ApiError && e.status === 404) toasts.show('error', t('open.missing', { file: path }));
    }
  }

  async function openHost(s: Session): Promise<void> {
    const h = s.host!;
    try {
      const r = await api.open(h.file);
      const chart = r.charts[0];
      if (!chart) {
        setStartError(t('host.noChart', { file: h.file }));
        return;
      }
      if (r.charts.length > 1) toasts.show('info', t('host.firstChart', { pou: chart.pou }));
      addTab({ path: r.path, format: r.format, hash: r.hash, pou: chart.pou, filePou: chart.pou, chartTarget: h.fb, diagnostics: r.diagnostics }, { ...chart, target: h.fb });
      store.update(store.activeId!, { buildTarget: h.fb });
    } catch (e) {
      if (!(e instanceof ApiError) || e.status !== 404) return;
      // The file does not exist yet: the host asked for a new chart there (seed 001, 12.1).
      const pou = pouFromFile(h.file);
      let doc: EditorDoc;
      try {
        doc = await api.newChart(pou, h.fb);
      } catch {
        return;
      }
      addTab({ path: h.file, format: formatOf(h.file), hash: null, pou: doc.pou, chartTarget: h.fb, unsaved: true }, doc);
      store.update(store.activeId!, { buildTarget: h.fb });
      toasts.show('info', t('host.created', { file: baseName(h.file) }));
    }
  }

  function askClose(x: TabState): Promise<CloseChoice> {
    return new Promise((resolve) => setDialog({ kind: 'close', name: tabTitle(x).replace(/\*$/, ''), resolve }));
  }

  function askSaveAs(x: TabState): Promise<{ path: string; format: FileFormat } | null> {
    const dir = x.path ? x.path.replace(/[\\/][^\\/]*$/, '') : session?.roots[0] ?? '';
    const ext = x.format === 'xml' ? '.xml' : '.st';
    const path = x.path ?? `${dir}/${x.pou}${ext}`;
    return new Promise((resolve) => setDialog({ kind: 'saveAs', path, format: x.format, resolve }));
  }

  async function save(x: TabState, saveAs = false): Promise<boolean> {
    const c = canvases.current.get(x.id);
    if (!c) return false;
    // A code editor still being typed in commits on blur, so the save includes its text.
    (document.activeElement as HTMLElement | null)?.blur?.();
    let path = x.path;
    let format = x.format;
    if (!path || saveAs) {
      if (host) return false;
      const chosen = await askSaveAs(x);
      if (!chosen) return false;
      ({ path, format } = chosen);
    }
    const doc = docOf(x.id) ?? c.getDoc();
    const hash = path === x.path ? x.hash : store.tabs.find((o) => o.path === path)?.hash ?? null;
    // Into its own file, the POU replaced is the one there, whatever the chart is called now.
    const replacing = path === x.path && x.filePou !== null ? { pou: x.filePou } : {};
    const request = { path, format, doc, hash, ...replacing };
    let result;
    try {
      result = await api.save(request);
    } catch (e) {
      if (!(e instanceof ApiError) || !e.conflict) return false;
      const overwrite = await new Promise<boolean>((resolve) => setDialog({ kind: 'conflict', path: path!, resolve }));
      if (!overwrite) return false;
      try {
        result = await api.save({ ...request, overwrite: true });
      } catch {
        return false;
      }
    }
    for (const o of canvasesOf(x)) o.markSaved();
    const known = files[result.path];
    const names = known ? known.charts.map((c) => (c.toLowerCase() === (x.filePou ?? x.pou).toLowerCase() ? doc.pou : c)) : [doc.pou];
    if (!names.some((c) => c.toLowerCase() === doc.pou.toLowerCase())) names.push(doc.pou);
    store.update(x.id, { path: result.path, format, hash: result.hash, unsaved: false, canvasDirty: false, pou: doc.pou, filePou: doc.pou, diagnostics: diagnosticsOf(result.diagnostics, doc.pou, names) });
    if (known) setFiles((f) => ({ ...f, [result.path]: { ...known, charts: names, diagnostics: fileDiagnostics(result.diagnostics, names), all: result.diagnostics } }));
    // Other charts of the same file now compare against the new contents.
    for (const o of store.tabs) if (o.id !== x.id && o.path === result.path) store.update(o.id, { hash: result.hash });
    toasts.show('success', t('save.saved', { file: baseName(result.path) }));
    return true;
  }

  async function closeTab(id: string): Promise<void> {
    const x = store.get(id);
    if (!x || host) return;
    if (await mayClose(x, askClose, (y) => save(y))) store.remove(id);
  }

  async function createChart(r: NewChartRequest): Promise<void> {
    setDialog(null);
    try {
      const made = await api.newChart(r.pou, r.target === 'iec' ? 'blank' : r.target);
      // An IEC chart is a Blank one that names its build output (`sfc.build`, default ST).
      const doc = r.target === 'iec' ? { ...made, ...kindFields(made, 'iec') } : made;
      addTab({ path: null, format: r.format, hash: null, pou: doc.pou, ...kindOfTab(doc), unsaved: true }, doc);
    } catch {
      // The API client has shown the server's message.
    }
  }

  /** The toolbar's build target: an IEC chart keeps it in `sfc.build` (one undoable change of the
   *  chart; the canvas' change event brings the tab along), other charts in the tab. */
  function chooseBuildTarget(x: TabState, target: BuildTarget): void {
    const c = canvases.current.get(x.id);
    if (x.chartTarget === 'iec' && c && !host) {
      const d = c.getDoc();
      if (chartBuild(d) !== target) c.updateDoc({ attributes: withBuild(d.attributes, target) });
    } else store.update(x.id, { buildTarget: target });
  }

  /** Validate (check with analysis) or Validate & build, by the toolbar's mode unless given. */
  async function runBuild(mode: BuildMode = buildMode): Promise<void> {
    if (!tab || !canvas || busy) return;
    (document.activeElement as HTMLElement | null)?.blur?.();
    const doc = docOf(tab.id) ?? canvas.getDoc();
    const id = tab.id;
    setBusy(true);
    setWitness(null);
    setSelectedDiag(null);
    try {
      if (mode === 'validate') {
        const diags = await api.check(doc, true);
        store.update(id, { diagnostics: diags, outcome: diags.some((d) => d.severity === 'error') ? 'failed' : 'succeeded' });
        setBottomTab('errors');
      } else {
        const target: BuildTarget = host ? host.fb : tab.buildTarget;
        const r = await api.build(doc, target, host ? { nstep: host.nstep, ntr: host.ntr } : undefined);
        store.update(id, { diagnostics: r.diagnostics, outcome: r.ok ? 'succeeded' : 'failed', result: { target, result: r } });
        setBottomTab(r.ok ? 'result' : 'errors');
        if (r.resultWritten) toasts.show('success', t('result.written', { path: r.resultWritten }));
      }
      setPanels((p) => ({ ...p, bottom: true }));
    } catch {
      store.update(id, { outcome: 'failed' });
    } finally {
      setBusy(false);
    }
  }

  /** `sfc prove` with the requirements beside the chart's file: violated and undecided
   * properties join the Error List (a violation with a Replay button). */
  async function runProve(): Promise<void> {
    if (!tab || !canvas || busy) return;
    if (!tab.path) {
      toasts.show('error', t('prove.saveFirst'));
      return;
    }
    const doc = docOf(tab.id) ?? canvas.getDoc();
    const id = tab.id;
    const path = tab.path;
    setBusy(true);
    setWitness(null);
    setSelectedDiag(null);
    try {
      const r = await api.prove(doc, path);
      const kept = (tab.diagnostics ?? []).filter((d) => !d.code.startsWith('SFC10'));
      store.update(id, { diagnostics: [...kept, ...r.diagnostics] });
      if (r.summary) toasts.show(r.summary.violated + r.summary.unknown > 0 ? 'error' : 'success', t('prove.summary', r.summary));
      setBottomTab('errors');
      setPanels((p) => ({ ...p, bottom: true }));
    } catch (e) {
      toasts.show('error', t('prove.failed', { message: (e as Error).message }));
    } finally {
      setBusy(false);
    }
  }

  /** File → Compare with saved / git HEAD: the chart as on the canvas compared by meaning with
   *  its file (`POST /api/compare`); the answer colours its blocks and fills the Comparison panel. */
  async function runCompare(against: CompareAgainst): Promise<void> {
    if (!tab || !canvas || busy) return;
    if (!tab.path) {
      toasts.show('error', t('compare.saveFirst'));
      return;
    }
    (document.activeElement as HTMLElement | null)?.blur?.();
    const x = tab;
    const doc = docOf(x.id) ?? canvas.getDoc();
    // An edit made while the server compares makes the answer stale: it is dropped.
    const revisions = () => canvasesOf(x).map((c) => c.revision()).join(',');
    const before = revisions();
    const renamed = x.filePou !== null && x.filePou !== doc.pou ? x.filePou : undefined;
    setBusy(true);
    try {
      const r = await api.compare(x.path!, doc, against, renamed);
      if (revisions() !== before) {
        toasts.show('info', t('compare.stale'));
        return;
      }
      store.update(x.id, { compare: r });
      setBottomTab('compare');
      setPanels((p) => ({ ...p, bottom: true }));
    } catch {
      // The API client has shown the server's message (not under git, does not parse, …).
    } finally {
      setBusy(false);
    }
  }

  /** Closes the comparison: its colours and its panel. */
  function closeCompare(x: TabState): void {
    store.update(x.id, { compare: null });
    if (bottomTab === 'compare') setBottomTab('errors');
  }

  /** A row of the Comparison panel: its blocks selected (and shown) on the POU's chart. */
  function selectChange(index: number, row: ChangeRow): void {
    setSelectedChange(index);
    if (!tab || !row.onCanvas) return;
    if (tab.view !== null) showView(tab, null);
    const c = canvases.current.get(tab.id);
    if (!c) return;
    const ids = row.change.elementIds.filter((id) => c.getDoc().elements.some((e) => e.id === id));
    if (ids.length === 0) return;
    c.select(ids);
    c.reveal(ids[0]);
  }

  /** A row of the Merge conflicts panel: its blocks selected (and shown) on the POU's chart. */
  function selectConflict(index: number, c: MergeConflict): void {
    setSelectedConflict(index);
    if (!tab) return;
    const pc = canvases.current.get(tab.id);
    const ids = pc ? conflictBlocks(pc.getDoc(), c) : [];
    if (!pc || ids.length === 0) return;
    if (tab.view !== null) showView(tab, null);
    pc.select(ids);
    pc.reveal(ids[0]);
  }

  /** "Keep ours" / "Take theirs" of a merge conflict: the chart resolved by the server
   *  (`POST /api/resolve`) replaces the tab's as an edit (undoable when its blocks stay the
   *  same); the file is written by the next save. */
  async function resolveConflict(c: MergeConflict, side: 'ours' | 'theirs'): Promise<void> {
    if (!tab || busy) return;
    (document.activeElement as HTMLElement | null)?.blur?.();
    const x = tab;
    const pc = canvases.current.get(x.id);
    const doc = docOf(x.id);
    if (!pc || !doc) return;
    // An edit made while the server resolves makes the answer stale: it is dropped.
    const revisions = () => canvasesOf(x).map((o) => o.revision()).join(',');
    const before = revisions();
    const renamed = x.filePou !== null && x.filePou !== doc.pou ? x.filePou : undefined;
    setBusy(true);
    try {
      const r = await api.resolve({ ...(x.path ? { path: x.path } : {}), ...(renamed ? { pou: renamed } : {}), doc, element: c.element, side });
      if (revisions() !== before) {
        toasts.show('info', t('merge.stale'));
        return;
      }
      // The charts of actions open in the tab went to the server within the document: the
      // resolved chart holds them; their canvases close.
      if (x.views.length > 0) store.update(x.id, { views: [], view: null });
      pc.replace(r.doc);
      store.update(x.id, { diagnostics: r.diagnostics, canvasDirty: true });
      setResolvedIn((prev) => new Set(prev).add(x.id));
      setSelectedConflict(null);
      setSelectedDiag(null);
      const what = `${conflictKindLabel(c, t)} ${c.name}`.trim();
      toasts.show('success', t(side === 'ours' ? 'merge.keptOurs' : 'merge.tookTheirs', { element: what }));
    } catch {
      // The API client has shown the server's message; the chart is unchanged.
    } finally {
      setBusy(false);
    }
  }

  async function autoLayout(): Promise<void> {
    if (!canvas) return;
    try {
      const before = canvas.getDoc();
      const laidOut = await api.layout(before);
      // A chart already laid out stays unmodified: no command, no undo step, no `*`.
      if (sameGeometry(before, laidOut)) {
        toasts.show('info', t('layout.unchanged'));
        return;
      }
      canvas.applyLayout(laidOut);
    } catch {
      // The API client has shown the server's message; the chart is unchanged.
    }
  }

  function liveCheck(draft: EditorDoc): void {
    const id = tab?.id;
    if (!id) return;
    const doc = docOf(id, draft) ?? draft;
    api.check(doc, false).then(
      (diags) => store.update(id, { diagnostics: diags }),
      () => undefined,
    );
  }

  /** After an edit (undo and redo included) the tab's Error list is checked again, 300 ms after
   *  the last change; an answer overtaken by a later edit is dropped. */
  function scheduleRecheck(id: string): void {
    const timers = rechecks.current;
    window.clearTimeout(timers.get(id));
    timers.set(
      id,
      window.setTimeout(() => {
        timers.delete(id);
        void recheck(id);
      }, 300),
    );
  }

  async function recheck(id: string): Promise<void> {
    const x = store.get(id);
    const doc = x ? docOf(id) : null;
    if (!x || !doc) return;
    const revisions = () => {
      const y = store.get(id);
      return y ? canvasesOf(y).map((c) => `${c.revision()}`).join(',') : '';
    };
    const before = revisions();
    try {
      const diags = await api.check(doc, false);
      if (!store.get(id) || revisions() !== before || rechecks.current.has(id)) return;
      // What the check of the chart does not see (a requirement's verdict) stays.
      const kept = (store.get(id)?.diagnostics ?? []).filter((d) => d.code.startsWith('SFC10'));
      store.update(id, { diagnostics: [...diags, ...kept] });
    } catch {
      // The API client has shown the server's message; the list stays as it was.
    }
  }

  /** A row of the project tree: its chart's tab shown (opened again when it was closed), the
   *  action's chart or the transition's block. */
  async function openFromTree(path: string, node: TreeNode): Promise<void> {
    let x = store.find(path, node.pou) ?? store.tabs.find((y) => y.path === path && y.filePou?.toLowerCase() === node.pou.toLowerCase());
    if (!x) {
      try {
        const r = await api.open(path);
        const chart = r.charts.find((c) => c.pou.toLowerCase() === node.pou.toLowerCase());
        if (!chart) return;
        const names = r.charts.map((c) => c.pou);
        x = addTab({ path: r.path, format: r.format, hash: r.hash, pou: chart.pou, filePou: chart.pou, ...kindOfTab(chart), diagnostics: diagnosticsOf(r.diagnostics, chart.pou, names) }, chart);
      } catch {
        return;
      }
    }
    store.activate(x.id);
    if (node.kind === 'action') showView(x, node.name ?? null);
    else if (node.kind === 'pou') store.update(x.id, { view: null });
    else if (node.kind === 'transition') {
      store.update(x.id, { view: null });
      const id = x.id;
      // The canvas of a tab just added is made on the next render.
      window.setTimeout(() => {
        const c = canvases.current.get(id);
        const d = c?.getDoc();
        const block = node.id ?? d?.elements.filter((e) => e.kind === 'transition').find((e, k) => (e.name || `T${k + 1}`).toLowerCase() === node.name?.toLowerCase())?.id;
        if (c && block) {
          c.select([block]);
          c.reveal(block);
        }
      }, 0);
    }
  }

  /** A row of the Error list: its block framed on the chart that holds it, the POU's or one of
   *  its actions' (shown when another is). */
  function selectDiag(index: number): void {
    setSelectedDiag(index);
    const d = diagnostics[index];
    if (!tab || !d || !d.element) return;
    const pc = canvases.current.get(tab.id);
    const shownDoc = canvas?.getDoc();
    const here = tab.view === null ? d.elementIds.length > 0 : !!shownDoc && blocksNamed(shownDoc, d.element).length > 0;
    if (here || !pc) return;
    const pouDocNow = pc.getDoc();
    if (tab.view !== null && d.elementIds.length > 0) {
      showView(tab, null);
      return;
    }
    const action = sfcActions(pouDocNow).find((a) => a.chart && blocksNamed(a.chart, d.element).length > 0);
    if (action) showView(tab, action.name);
  }

  /** Sends a key to the canvas' own keyboard handling (copy, paste, delete). */
  function canvasKey(key: string, ctrl = false): void {
    const container = tab ? containers.current.get(viewKey(tab.id, tab.view)) : undefined;
    // diagram-js listens on its canvas <svg> (not on the palette's icons).
    const target = container?.querySelector('.djs-container > svg') ?? container;
    target?.dispatchEvent(new KeyboardEvent('keydown', { key, ctrlKey: ctrl, bubbles: true, cancelable: true }));
  }

  const selectAll = () => {
    if (!canvas) return;
    const d = canvas.getDoc();
    canvas.select([...d.elements.map((e) => e.id), ...d.connections.map((c) => c.id)]);
  };
  const zoomBy = (f: number) => canvas?.zoom(Math.min(4, Math.max(0.2, canvas.getZoom() * f)));
  // An action's chart is exported as `POU.Action.svg`.
  const exportSvg = () => canvas && tab && download(`${tab.pou}${tab.view ? `.${tab.view}` : ''}.svg`, canvas.exportSvg(), 'image/svg+xml');
  const print = () => {
    const c = canvas;
    if (c && tab) setDialog({ kind: 'print', svg: (marks) => c.exportSvg({ marks }), doc: c.getDoc(), path: tab.path });
  };
  const mdi = session !== null && !host;
  const hasChart = !!canvas;

  // Keyboard shortcuts of the shell; the canvas handles its own keys first when it has focus.
  const keys = useRef<(e: KeyboardEvent) => void>(() => undefined);
  keys.current = (e: KeyboardEvent) => {
    if (dialog) return;
    const ctrl = e.ctrlKey || e.metaKey;
    const k = e.key.toLowerCase();
    const editing = e.target instanceof HTMLElement && e.target.closest('input, textarea, select, [contenteditable]') !== null;
    const run = (f: () => void) => {
      e.preventDefault();
      f();
    };
    if (e.key === 'F7') return run(() => void runBuild());
    if (ctrl && e.shiftKey && k === 'n' && mdi) return run(() => setDialog({ kind: 'new', target: 'blank' }));
    if (ctrl && e.shiftKey && k === 'a' && mdi) return run(() => setDialog({ kind: 'new', target: 'atmt' }));
    if (ctrl && e.shiftKey && k === 'e' && mdi) return run(() => setDialog({ kind: 'new', target: 'eatmt' }));
    if (ctrl && !e.shiftKey && k === 's' && tab) return run(() => void save(tab));
    if (ctrl && k === 'p' && hasChart) return run(() => ((document.activeElement as HTMLElement | null)?.blur?.(), print()));
    if (editing || e.defaultPrevented || !canvas) return;
    if (ctrl && !e.shiftKey && k === 'z') return run(() => canvas.undo());
    if (ctrl && (k === 'y' || (e.shiftKey && k === 'z'))) return run(() => canvas.redo());
    if (ctrl && k === 'a') return run(selectAll);
    if (ctrl && (k === '+' || k === '=')) return run(() => zoomBy(1.2));
    if (ctrl && k === '-') return run(() => zoomBy(1 / 1.2));
    if (ctrl && k === '0') return run(() => canvas.zoom('fit'));
    // Structured editing when the canvas has not the focus (it handles these keys itself).
    if (!ctrl && !e.altKey && e.key === 'Insert') return run(() => canvas.structure(e.shiftKey ? 'insertBefore' : 'insertAfter'));
  };
  useEffect(() => {
    const onKey = (e: KeyboardEvent) => keys.current(e);
    window.addEventListener('keydown', onKey);
    return () => window.removeEventListener('keydown', onKey);
  }, []);

  const lang = currentLanguage();
  const menus: MenuDef[] = [
    {
      id: 'file',
      label: t('menu.file'),
      items: [
        { label: t('menu.new'), shortcut: 'Ctrl+Shift+N', icon: 'new', disabled: !mdi, action: () => setDialog({ kind: 'new', target: 'blank' }) },
        { label: t('menu.newAtmt'), shortcut: 'Ctrl+Shift+A', disabled: !mdi, action: () => setDialog({ kind: 'new', target: 'atmt' }) },
        { label: t('menu.newEatmt'), shortcut: 'Ctrl+Shift+E', disabled: !mdi, action: () => setDialog({ kind: 'new', target: 'eatmt' }) },
        { label: t('menu.open'), icon: 'open', disabled: !mdi, action: () => setDialog({ kind: 'open' }) },
        { separator: true, label: '' },
        { label: t('menu.save'), shortcut: 'Ctrl+S', icon: 'save', disabled: !tab, action: () => tab && void save(tab) },
        { label: t('menu.saveAs'), disabled: !tab || !!host, action: () => tab && void save(tab, true) },
        { separator: true, label: '' },
        { label: t('compare.menuSaved'), disabled: !hasChart || !tab?.path || busy, action: () => void runCompare('saved') },
        { label: t('compare.menuHead'), disabled: !hasChart || !tab?.path || busy, action: () => void runCompare('head') },
        { label: t('compare.close'), disabled: !tab?.compare, action: () => tab && closeCompare(tab) },
        { separator: true, label: '' },
        { label: t('menu.exportSvg'), icon: 'svg', disabled: !hasChart, action: exportSvg },
        { label: t('menu.print'), shortcut: 'Ctrl+P', icon: 'print', disabled: !hasChart, action: print },
        { separator: true, label: '' },
        { label: t('menu.closeTab'), disabled: !tab || !!host, action: () => tab && void closeTab(tab.id) },
      ],
    },
    {
      id: 'edit',
      label: t('menu.edit'),
      items: [
        { label: t('menu.undo'), shortcut: 'Ctrl+Z', icon: 'undo', disabled: !canvas?.canUndo(), action: () => canvas?.undo() },
        { label: t('menu.redo'), shortcut: 'Ctrl+Y', icon: 'redo', disabled: !canvas?.canRedo(), action: () => canvas?.redo() },
        { separator: true, label: '' },
        { label: t('menu.cut'), shortcut: 'Ctrl+X', icon: 'cut', disabled: selection.length === 0, action: () => (canvasKey('c', true), canvasKey('Delete')) },
        { label: t('menu.copy'), shortcut: 'Ctrl+C', icon: 'copy', disabled: selection.length === 0, action: () => canvasKey('c', true) },
        { label: t('menu.paste'), shortcut: 'Ctrl+V', icon: 'paste', disabled: !hasChart, action: () => canvasKey('v', true) },
        { label: t('menu.delete'), shortcut: 'Del', icon: 'delete', disabled: selection.length === 0, action: () => canvasKey('Delete') },
        { label: t('menu.selectAll'), shortcut: 'Ctrl+A', disabled: !hasChart, action: selectAll },
        { separator: true, label: '' },
        { label: t('menu.insertAfter'), shortcut: 'Ins', disabled: !canvas?.canStructure('insertAfter'), action: () => canvas?.structure('insertAfter') },
        { label: t('menu.insertBefore'), shortcut: 'Shift+Ins', disabled: !canvas?.canStructure('insertBefore'), action: () => canvas?.structure('insertBefore') },
        { label: t('menu.deleteStep'), shortcut: 'Del', disabled: !canvas?.canStructure('deleteStep'), action: () => canvas?.structure('deleteStep') },
        { separator: true, label: '' },
        { label: t('menu.autoLayout'), icon: 'layout', disabled: !hasChart, action: () => void autoLayout() },
        { label: t('menu.validate'), icon: 'validate', disabled: !hasChart, action: () => void runBuild('validate') },
        { label: t('menu.prove'), icon: 'validate', disabled: !hasChart || !!host, action: () => void runProve() },
        { label: t('menu.build'), shortcut: 'F7', icon: 'build', disabled: !hasChart, action: () => void runBuild() },
      ],
    },
    {
      id: 'view',
      label: t('menu.view'),
      items: [
        { label: t('panel.tools'), checked: panels.tools, action: () => setPanels({ ...panels, tools: !panels.tools }) },
        { label: t('panel.properties'), checked: panels.properties, action: () => setPanels({ ...panels, properties: !panels.properties }) },
        { label: t('panel.errors'), checked: panels.bottom && bottomTab === 'errors', action: () => showBottom('errors') },
        { label: t('panel.result'), checked: panels.bottom && bottomTab === 'result', action: () => showBottom('result') },
        { separator: true, label: '' },
        { label: t('menu.zoomIn'), shortcut: 'Ctrl++', icon: 'zoomIn', disabled: !hasChart, action: () => zoomBy(1.2) },
        { label: t('menu.zoomOut'), shortcut: 'Ctrl+-', icon: 'zoomOut', disabled: !hasChart, action: () => zoomBy(1 / 1.2) },
        { label: t('menu.zoomFit'), shortcut: 'Ctrl+0', icon: 'fit', disabled: !hasChart, action: () => canvas?.zoom('fit') },
        { separator: true, label: '' },
        ...LANGUAGES.map((l) => ({ label: t(`lang.${l}`), checked: lang === l, action: () => setLanguage(l) })),
      ],
    },
    monitor.menu,
    {
      id: 'help',
      label: t('menu.help'),
      items: [
        { label: t('menu.shortcuts'), action: () => setDialog({ kind: 'shortcuts' }) },
        { label: t('menu.about'), action: () => setDialog({ kind: 'about' }) },
      ],
    },
  ];

  function showBottom(which: 'errors' | 'result'): void {
    if (panels.bottom && bottomTab === which) setPanels({ ...panels, bottom: false });
    else {
      setBottomTab(which);
      setPanels({ ...panels, bottom: true });
    }
  }

  const counts = { error: 0, warning: 0, note: 0 };
  for (const d of diagnostics) counts[d.severity]++;
  // The properties panel's copy of the document, made again only when it changed (a copy of a
  // 500-step chart costs about 30 ms, and the shell renders on every store update).
  const revision = canvas?.revision();
  const doc = useMemo(() => canvas?.getDoc(), [canvas, revision]);
  // The POU's own document (its actions, and whether its body is text), whatever the tab shows.
  const pouCanvas = tab ? canvases.current.get(tab.id) : undefined;
  const pouRevision = pouCanvas?.revision();
  const pouDoc = useMemo(() => pouCanvas?.getDoc(), [pouCanvas, pouRevision]);
  // Merge conflicts `sfc merge` marked the POU with (`sfc.conflict`): listed in their panel,
  // their blocks framed red-orange.
  const conflicts = useMemo(() => conflictsOf(pouDoc), [pouDoc]);
  const hasConflicts = conflicts.length > 0;
  const showConflicts = !!tab && (hasConflicts || resolvedIn.has(tab.id));
  useEffect(() => {
    if (pouCanvas && pouDoc) pouCanvas.highlight('conflict', conflictIds(pouDoc));
  }, [pouCanvas, pouDoc]);
  // A chart with conflicts shows their panel when it opens (or when an undo brings them back).
  useEffect(() => {
    if (!hasConflicts) return;
    setBottomTab('conflicts');
    setPanels((p) => (p.bottom ? p : { ...p, bottom: true }));
  }, [tab?.id, hasConflicts]);

  return (
    <>
    <div class="app-shell no-print">
      <MenuBar menus={menus} />
      <div class="toolbar no-print" role="toolbar">
        {mdi && (
          <>
            <ToolButton icon="new" label={t('toolbar.new')} title={`${t('menu.new')} (Ctrl+Shift+N)`} onClick={() => setDialog({ kind: 'new', target: 'blank' })} />
            <ToolButton icon="open" label={t('toolbar.open')} title={t('menu.open')} onClick={() => setDialog({ kind: 'open' })} />
          </>
        )}
        <ToolButton icon="save" label={t('toolbar.save')} title={`${t('menu.save')} (Ctrl+S)`} disabled={!tab} onClick={() => tab && void save(tab)} />
        <span class="tool-separator" />
        <ToolButton icon="undo" title={`${t('menu.undo')} (Ctrl+Z)`} disabled={!canvas?.canUndo()} onClick={() => canvas?.undo()} />
        <ToolButton icon="redo" title={`${t('menu.redo')} (Ctrl+Y)`} disabled={!canvas?.canRedo()} onClick={() => canvas?.redo()} />
        <ToolButton icon="layout" label={t('toolbar.layout')} title={t('menu.autoLayout')} disabled={!hasChart} onClick={() => void autoLayout()} />
        <span class="tool-separator" />
        <ToolButton icon="svg" title={t('menu.exportSvg')} disabled={!hasChart} onClick={exportSvg} />
        <ToolButton icon="print" title={`${t('menu.print')} (Ctrl+P)`} disabled={!hasChart} onClick={print} />
        <span class="tool-separator" />
        <select class="tool-select" aria-label={t('toolbar.buildMode')} title={t('toolbar.buildMode')} value={buildMode} onChange={(e) => setBuildMode(e.currentTarget.value as BuildMode)}>
          <option value="validate">{t('toolbar.validate')}</option>
          <option value="build">{t('toolbar.validateBuild')}</option>
        </select>
        <select
          class="tool-select"
          aria-label={t('toolbar.target')}
          title={t('toolbar.target')}
          disabled={!tab || !!host || buildMode === 'validate'}
          value={host ? host.fb : tab?.buildTarget}
          onChange={(e) => tab && chooseBuildTarget(tab, e.currentTarget.value as BuildTarget)}
        >
          {(host ? [host.fb] : targetsFor(tab?.chartTarget ?? 'blank')).map((x) => (
            <option key={x} value={x}>
              {t(`buildTarget.${x}`)}
            </option>
          ))}
        </select>
        <ToolButton
          icon={buildMode === 'validate' ? 'validate' : 'build'}
          label={buildMode === 'validate' ? t('toolbar.runValidate') : t('toolbar.runBuild')}
          title={`${t('menu.build')} (F7)`}
          disabled={!hasChart || busy}
          primary
          onClick={() => void runBuild()}
        />
        {busy && <span class="spinner" aria-label={t('common.working')} />}
        <span class="tool-separator" />
        {monitor.button}
      </div>

      {mdi && store.tabs.length > 0 && (
        <div class="tabstrip no-print" role="tablist">
          {store.tabs.map((x) => (
            <div
              key={x.id}
              role="tab"
              aria-selected={x.id === store.activeId}
              class={`tab ${x.id === store.activeId ? 'active' : ''} ${isDirty(x) ? 'dirty' : ''}`}
              title={x.path ?? t('tabs.unsaved')}
              onClick={() => store.activate(x.id)}
              onAuxClick={(e) => e.button === 1 && void closeTab(x.id)}
            >
              <span class={`tab-target target-${x.chartTarget}`}>{badge(x.chartTarget)}</span>
              <span class="tab-title">{tabTitle(x)}</span>
              <button
                class="tab-close"
                title={t('tabs.close')}
                onClick={(e) => {
                  e.stopPropagation();
                  void closeTab(x.id);
                }}
              >
                <Icon name="close" />
              </button>
            </div>
          ))}
        </div>
      )}
      {host && tab && (
        <div class="host-title no-print">
          <span class={`tab-target target-${tab.chartTarget}`}>{badge(tab.chartTarget)}</span>
          <span>{tabTitle(tab)}</span>
          <span class="muted">{tab.path}</span>
        </div>
      )}

      <div class="workspace">
        {monitor.overlay}
        {mdi && tab?.path && (files[tab.path]?.pous.length ?? 0) > 1 &&
          (treeOpen ? (
            <ProjectTree
              file={baseName(tab.path)}
              pous={files[tab.path].pous}
              live={(pou) => {
                const y = store.find(tab.path!, pou);
                return y && y.id === tab.id ? pouDoc : undefined;
              }}
              diagnostics={store.tabs.filter((y) => y.path === tab.path).flatMap((y) => y.diagnostics).concat(files[tab.path].diagnostics)}
              activePou={tab.pou}
              activeView={tab.view}
              onOpen={(node) => void openFromTree(tab.path!, node)}
              onCollapse={() => setTreeOpen(false)}
            />
          ) : (
            <button class="tree-expand no-print" title={t('project.expand')} aria-label={t('project.expand')} onClick={() => setTreeOpen(true)}>
              <Icon name="next" />
            </button>
          ))}
        <div class="main-column">
          {tab && pouDoc && (sfcActions(pouDoc).length > 0 || tab.views.length > 0) && (
            <div class="chart-views no-print" role="tablist" aria-label={t('views.label')}>
              <button role="tab" aria-selected={tab.view === null} class={`chart-view ${tab.view === null ? 'active' : ''}`} title={t('views.pouHint')} onClick={() => showView(tab, null)}>
                <span class="chart-view-kind">{pouDoc.body !== undefined ? pouDoc.bodyLanguage ?? 'ST' : 'SFC'}</span>
                {pouDoc.pou}
              </button>
              {sfcActions(pouDoc).map((a) => (
                <button
                  key={a.name}
                  role="tab"
                  data-action={a.name}
                  aria-selected={tab.view?.toLowerCase() === a.name.toLowerCase()}
                  class={`chart-view ${tab.view?.toLowerCase() === a.name.toLowerCase() ? 'active' : ''}`}
                  title={t('views.actionHint', { action: a.name })}
                  onClick={() => showView(tab, a.name)}
                >
                  <span class="chart-view-kind">SFC</span>
                  {pouDoc.pou}.{a.name}
                  {tab.views.some((v) => v.toLowerCase() === a.name.toLowerCase()) && (
                    <span
                      class="chart-view-close"
                      role="button"
                      title={t('views.close', { action: a.name })}
                      onClick={(e) => {
                        e.stopPropagation();
                        closeView(tab, tab.views.find((v) => v.toLowerCase() === a.name.toLowerCase())!);
                      }}
                    >
                      ×
                    </span>
                  )}
                </button>
              ))}
            </div>
          )}
          <div class={`canvas-area ${panels.tools && !(tab && tab.view === null && pouDoc?.body !== undefined) ? '' : 'hide-palette'}`}>
            {store.tabs.flatMap((x) =>
              [null, ...x.views].map((v) => (
                <CanvasPane key={viewKey(x.id, v)} id={viewKey(x.id, v)} active={x.id === store.activeId && (x.view ?? null) === v} attach={attachCanvas} />
              )),
            )}
            {tab && tab.view === null && pouDoc?.body !== undefined && (
              <div class="text-body-note" role="note">
                <p>{t('views.textBody', { pou: pouDoc.pou, language: pouDoc.bodyLanguage ?? 'ST' })}</p>
                {sfcActions(pouDoc).length > 0 && (
                  <p>
                    {t('views.openAction')}{' '}
                    {sfcActions(pouDoc).map((a) => (
                      <button key={a.name} class="button small" onClick={() => showView(tab, a.name)}>
                        {a.name}
                      </button>
                    ))}
                  </p>
                )}
              </div>
            )}
            {tab && tab.outcome !== 'none' && (
              <div class={`outcome ${tab.outcome}`} role="status">
                {t(`outcome.${tab.outcome}`)}
              </div>
            )}
            {store.tabs.length === 0 && (
              startError || !session ? (
                <div class="welcome">
                  {startError ? <div class="field-error">{t('start.failed', { message: startError })}</div> : <div class="muted">{t('common.loading')}</div>}
                </div>
              ) : (
                <Welcome
                  mdi={mdi}
                  files={api.files}
                  onNew={() => setDialog({ kind: 'new', target: 'blank' })}
                  onOpenDialog={() => setDialog({ kind: 'open' })}
                  onOpen={(p) => void openFile(p)}
                />
              )
            )}
          </div>
          {panels.bottom && (
            <div class="bottom-panel no-print">
              <div class="panel-tabs">
                <button class={`panel-tab ${bottomTab === 'errors' ? 'active' : ''}`} onClick={() => setBottomTab('errors')}>
                  {t('panel.errors')}
                  {counts.error + counts.warning > 0 && <span class={`badge ${counts.error ? 'badge-error' : 'badge-warning'}`}>{counts.error + counts.warning}</span>}
                </button>
                <button class={`panel-tab ${bottomTab === 'result' ? 'active' : ''}`} onClick={() => setBottomTab('result')}>
                  {t('panel.result')}
                </button>
                {tab?.compare && (
                  <button class={`panel-tab ${bottomTab === 'compare' ? 'active' : ''}`} onClick={() => setBottomTab('compare')}>
                    {t('compare.panel')}
                  </button>
                )}
                {showConflicts && (
                  <button class={`panel-tab ${bottomTab === 'conflicts' ? 'active' : ''}`} data-testid="conflict-tab" onClick={() => setBottomTab('conflicts')}>
                    {t('merge.panel')}
                    {hasConflicts && <span class="badge badge-conflict">{conflicts.length}</span>}
                  </button>
                )}
                <span class="spacer" />
                <button class="icon-button" title={t('common.close')} onClick={() => setPanels({ ...panels, bottom: false })}>
                  <Icon name="close" />
                </button>
              </div>
              <div class="panel-body">
                {bottomTab === 'errors' || (bottomTab === 'compare' && !tab?.compare) || (bottomTab === 'conflicts' && !showConflicts) ? (
                  <ErrorList
                    diagnostics={diagnostics}
                    fileDiagnostics={tab?.path ? files[tab.path]?.diagnostics : undefined}
                    fileName={tab?.path ? baseName(tab.path) : undefined}
                    selected={selectedDiag}
                    onSelect={selectDiag}
                    highlightOn={highlightOn}
                    onToggleHighlight={() => setHighlightOn(!highlightOn)}
                    witness={witness}
                    onWitness={setWitness}
                    onReplay={(d) => d.replay && void monitor.replay(d.replay)}
                    blockName={(id) => {
                      const e = canvas?.getDoc().elements.find((x) => x.id === id);
                      if (!e) return '';
                      if (e.name) return e.name;
                      return e.kind === 'jump' && e.target ? `${t('kind.jump')} → ${e.target}` : t(`kind.${e.kind}`);
                    }}
                  />
                ) : bottomTab === 'conflicts' ? (
                  <ConflictPanel
                    conflicts={conflicts}
                    onCanvas={(c) => !!pouDoc && conflictBlocks(pouDoc, c).length > 0}
                    selected={selectedConflict}
                    busy={busy}
                    onSelect={selectConflict}
                    onResolve={(c, side) => void resolveConflict(c, side)}
                  />
                ) : bottomTab === 'compare' && tab?.compare ? (
                  <ComparePanel result={tab.compare} selected={selectedChange} onSelect={selectChange} onClose={() => closeCompare(tab)} />
                ) : (
                  <ResultPanel pou={tab?.pou ?? ''} result={tab?.result ?? null} />
                )}
              </div>
            </div>
          )}
        </div>
        {panels.properties && (
          <aside class="side-panel no-print" aria-label={t('panel.properties')}>
            <div class="panel-header">
              <span>{t('panel.properties')}</span>
              <button class="icon-button" title={t('common.close')} onClick={() => setPanels({ ...panels, properties: false })}>
                <Icon name="close" />
              </button>
            </div>
            <div class="panel-body">
              {canvas && doc ? (
                <PropertiesPanel
                  doc={doc}
                  selection={selection}
                  canvas={canvas}
                  diagnostics={diagnostics}
                  onDraft={liveCheck}
                  targetFixed={!!host}
                  action={actionView}
                  pouActions={pouDoc?.actions}
                  openViews={tab?.views ?? []}
                  onOpenAction={(name) => tab && showView(tab, name)}
                />
              ) : (
                <div class="empty">{t('props.noChart')}</div>
              )}
            </div>
          </aside>
        )}
      </div>

      <StatusBar
        tab={tab}
        host={host}
        selection={selection.length}
        zoom={zoom}
        hasChart={hasChart}
        conflicts={conflicts.length}
        onZoom={(z) => (z === 'fit' ? canvas?.zoom('fit') : zoomBy(z))}
        onZoomTo={(z) => canvas?.zoom(Math.min(4, Math.max(0.2, z)))}
        lang={lang}
      />

    </div>
      <div class="toasts no-print" aria-live="polite">
        {toasts.items.map((x) => (
          <div key={x.id} class={`toast toast-${x.kind}`} onClick={() => toasts.dismiss(x.id)}>
            <Icon name={x.kind === 'error' ? 'error' : x.kind === 'success' ? 'validate' : 'note'} />
            <span>{x.text}</span>
          </div>
        ))}
      </div>

      {dialog?.kind === 'new' && <NewDialog initialTarget={dialog.target} onCreate={(r) => void createChart(r)} onClose={() => setDialog(null)} />}
      {dialog?.kind === 'open' && (
        <OpenDialog
          load={api.files}
          onClose={() => setDialog(null)}
          onOpen={(p) => {
            setDialog(null);
            void openFile(p);
          }}
        />
      )}
      {dialog?.kind === 'saveAs' && session && (
        <SaveAsDialog
          session={session}
          initialPath={dialog.path}
          initialFormat={dialog.format}
          onSave={(path, format) => {
            setDialog(null);
            dialog.resolve({ path, format });
          }}
          onClose={() => {
            setDialog(null);
            dialog.resolve(null);
          }}
        />
      )}
      {dialog?.kind === 'close' && (
        <CloseDialog
          name={dialog.name}
          onChoose={(c) => {
            setDialog(null);
            dialog.resolve(c);
          }}
        />
      )}
      {dialog?.kind === 'conflict' && (
        <ConflictDialog
          path={dialog.path}
          onChoose={(o) => {
            setDialog(null);
            dialog.resolve(o);
          }}
        />
      )}
      {dialog?.kind === 'print' && <PrintDialog svg={dialog.svg} doc={dialog.doc} path={dialog.path} onClose={() => setDialog(null)} />}
      {dialog?.kind === 'about' && <AboutDialog version={session?.version ?? ''} onClose={() => setDialog(null)} />}
      {dialog?.kind === 'shortcuts' && <ShortcutsDialog onClose={() => setDialog(null)} />}
    </>
  );
}

function ToolButton(props: { icon: Parameters<typeof Icon>[0]['name']; label?: string; title: string; onClick: () => void; disabled?: boolean; primary?: boolean }) {
  return (
    <button class={`tool-button ${props.primary ? 'primary' : ''}`} title={props.title} aria-label={props.title} disabled={props.disabled} onClick={props.onClick}>
      <Icon name={props.icon} />
      {props.label && <span>{props.label}</span>}
    </button>
  );
}

/** One chart's canvas; kept mounted while its tab is open so each chart keeps its undo history. */
function CanvasPane(props: { id: string; active: boolean; attach: (id: string, el: HTMLElement) => () => void }) {
  const ref = useRef<HTMLDivElement>(null);
  useEffect(() => props.attach(props.id, ref.current!), []);
  return <div ref={ref} class={`canvas-pane ${props.active ? 'active' : ''}`} aria-hidden={!props.active} />;
}

function StatusBar(props: {
  tab: TabState | undefined;
  host: Session['host'] | null;
  selection: number;
  zoom: number;
  hasChart: boolean;
  /** Merge conflicts left in the chart. */
  conflicts: number;
  onZoom: (z: number | 'fit') => void;
  /** An absolute zoom level, from the slider. */
  onZoomTo: (z: number) => void;
  lang: Lang;
}) {
  return (
    <div class="statusbar no-print">
      <span class="status-item">{props.tab ? (props.tab.path ?? t('tabs.unsaved')) : t('status.ready')}</span>
      {props.host && <span class="status-item">{t('status.limits', { fb: props.host.fb.toUpperCase(), nstep: props.host.nstep, ntr: props.host.ntr })}</span>}
      {props.selection > 0 && <span class="status-item">{t('status.selected', { count: props.selection })}</span>}
      {props.conflicts > 0 && (
        <span class="status-item status-conflicts" data-testid="status-conflicts">
          {t('merge.left', { count: props.conflicts })}
        </span>
      )}
      <span class="spacer" />
      <span class="status-zoom">
        <button class="icon-button" title={t('menu.zoomOut')} disabled={!props.hasChart} onClick={() => props.onZoom(1 / 1.2)}>
          <Icon name="zoomOut" />
        </button>
        {/* Logarithmic (hundredths of ln zoom), so 50 % and 200 % sit equally far from 100 %. */}
        <input
          type="range"
          class="zoom-slider"
          data-testid="zoom-slider"
          title={t('status.zoom')}
          aria-label={t('status.zoom')}
          disabled={!props.hasChart}
          min={Math.round(100 * Math.log(0.2))}
          max={Math.round(100 * Math.log(4))}
          step={1}
          value={Math.round(100 * Math.log(props.zoom))}
          onInput={(ev) => props.onZoomTo(Math.exp(Number(ev.currentTarget.value) / 100))}
        />
        <span class="zoom-value">{Math.round(props.zoom * 100)} %</span>
        <button class="icon-button" title={t('menu.zoomIn')} disabled={!props.hasChart} onClick={() => props.onZoom(1.2)}>
          <Icon name="zoomIn" />
        </button>
        <button class="icon-button" title={t('menu.zoomFit')} disabled={!props.hasChart} onClick={() => props.onZoom('fit')}>
          <Icon name="fit" />
        </button>
      </span>
      <span class="status-lang">
        <button class="lang-cycle" title={t('status.langCycle')} onClick={() => setLanguage(nextLanguage(props.lang))}>
          {t(`lang.${props.lang}`)}
        </button>
        <span class="lang-drop" title={t('status.language')}>
          ▾
          <select aria-label={t('status.language')} value={props.lang} onChange={(e) => setLanguage(e.currentTarget.value as Lang)}>
            {LANGUAGES.map((l) => (
              <option key={l} value={l}>
                {t(`lang.${l}`)}
              </option>
            ))}
          </select>
        </span>
      </span>
    </div>
  );
}

/** Whether two documents place every block and route every wire alike (same ids). */
export function sameGeometry(a: EditorDoc, b: EditorDoc): boolean {
  if (a.elements.length !== b.elements.length || a.connections.length !== b.connections.length) return false;
  const byId = new Map(b.elements.map((e) => [e.id, e]));
  for (const e of a.elements) {
    const o = byId.get(e.id);
    if (!o || o.x !== e.x || o.y !== e.y || o.w !== e.w || o.h !== e.h) return false;
  }
  const wires = new Map(b.connections.map((c) => [c.id, c]));
  const pts = (w?: { x: number; y: number }[]) => JSON.stringify((w ?? []).map((p) => [p.x, p.y]));
  for (const c of a.connections) {
    const o = wires.get(c.id);
    if (!o) return false;
    // An empty polyline is a straight wire, as is a two-point one.
    const norm = (w?: { x: number; y: number }[]) => (w && w.length > 2 ? pts(w) : 'straight');
    if (norm(c.waypoints) !== norm(o.waypoints)) return false;
  }
  return true;
}
