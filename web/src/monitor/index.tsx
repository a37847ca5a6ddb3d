// Monitor mode in the shell: the Monitor menu (start the simulator on the open chart, attach to
// a runtime, stop/detach), its toolbar button, and the monitor view over the workspace. The
// chart being edited stays as it is underneath; the monitor shows a copy taken at the start.
import { useEffect, useRef, useState } from 'preact/hooks';
import type { JSX } from 'preact';
import type { CreateCanvas } from '../diagram/types';
import type { Replay } from '../api';
import type { EditorDoc } from '../doc';
import { Modal } from '../app/dialogs';
import type { MenuDef } from '../app/Menu';
import { toasts } from '../app/toast';
import { t } from '../i18n';
import { MonitorIcon } from './icons';
import { MonitorView } from './MonitorView';
import { elementsByName, SimError, startSimulation, stopSimulation, type MonitorTarget } from './session';
import './monitor.css';

export { MonitorClient } from './client';
export { MonitorView } from './MonitorView';

export interface UseMonitorOptions {
  createCanvas: CreateCanvas;
  /** The open chart and its tab title, or null when no chart is open (called when monitoring
   *  starts: it copies the whole document). */
  current: () => { doc: EditorDoc; title: string; path?: string | null } | null;
  /** A chart is open (read on every render, so cheap). */
  hasChart: boolean;
  /** The open chart of POU `pou`, made the active tab; null when no tab shows it. */
  chartOf?: (pou: string) => { doc: EditorDoc; title: string } | null;
}

export interface MonitorUi {
  /** Monitoring is on (the editor's own shortcuts should leave the hidden canvas alone). */
  active: boolean;
  menu: MenuDef;
  /** The toolbar button that starts the simulation. */
  button: JSX.Element;
  /** The monitor view over the workspace, and the attach dialog. */
  overlay: JSX.Element | null;
  /** Starts the simulator halted and replays a witness of `sfc prove` in it. */
  replay: (r: Replay) => Promise<void>;
}

/** Posts `stop` for a simulation as the page goes away (a beacon-like request that outlives it). */
function stopOnExit(id: number): void {
  void fetch('/api/sim/stop', {
    method: 'POST',
    keepalive: true,
    credentials: 'same-origin',
    headers: { 'Content-Type': 'application/json', 'X-Sfc-Page': '1' },
    body: JSON.stringify({ id }),
  }).catch(() => undefined);
}

export function useMonitor(opts: UseMonitorOptions): MonitorUi {
  const [target, setTarget] = useState<MonitorTarget | null>(null);
  const [starting, setStarting] = useState(false);
  const [attaching, setAttaching] = useState(false);
  const current = useRef(target);
  current.current = target;

  useEffect(() => {
    const onExit = () => {
      const id = current.current?.simId;
      if (id !== null && id !== undefined) stopOnExit(id);
    };
    window.addEventListener('pagehide', onExit);
    return () => window.removeEventListener('pagehide', onExit);
  }, []);

  async function leave(): Promise<void> {
    const was = current.current;
    setTarget(null);
    if (was?.simId !== null && was?.simId !== undefined) {
      await stopSimulation(was.simId).catch((e: Error) => toasts.show('error', t('monitor.stopFailed', { message: e.message })));
    }
  }

  async function startSim(): Promise<void> {
    const open = opts.current();
    if (!open || starting) return;
    (document.activeElement as HTMLElement | null)?.blur?.();
    await leave();
    setStarting(true);
    try {
      const doc = structuredClone(open.doc);
      const r = await startSimulation(doc, { path: open.path });
      setTarget({ url: r.url, doc, elements: r.elements, simId: r.id, title: open.title, profile: r.profile });
    } catch (e) {
      const err = e as SimError;
      const first = (err.diagnostics?.[0] as { message?: string } | undefined)?.message;
      toasts.show('error', err.status === 422 ? t('monitor.chartErrors', { message: first ?? err.message }) : t('monitor.startFailed', { message: err.message }));
    } finally {
      setStarting(false);
    }
  }

  async function replay(w: Replay): Promise<void> {
    const open = opts.current();
    if (!open || starting) return;
    await leave();
    setStarting(true);
    try {
      const doc = structuredClone(open.doc);
      const r = await startSimulation(doc, { period: w.period, halted: true, path: open.path });
      setTarget({ url: r.url, doc, elements: r.elements, simId: r.id, title: open.title, replay: w, profile: r.profile });
    } catch (e) {
      toasts.show('error', t('monitor.replayFailed', { message: (e as Error).message }));
    } finally {
      setStarting(false);
    }
  }

  /** Monitors the same runtime on the chart of `pou` (an open tab), showing `instance` on it. */
  function openChart(instance: string, pou: string): boolean {
    const was = current.current;
    const c = opts.chartOf?.(pou);
    if (!was || !c) return false;
    const doc = structuredClone(c.doc);
    setTarget({ url: was.url, doc, elements: elementsByName(doc), simId: was.simId, title: c.title, instance, profile: was.profile });
    return true;
  }

  async function attach(url: string): Promise<void> {
    const open = opts.current();
    if (!open) return;
    setAttaching(false);
    await leave();
    const doc = structuredClone(open.doc);
    setTarget({ url, doc, elements: elementsByName(doc), simId: null, title: open.title });
  }

  const hasChart = opts.hasChart;
  const menu: MenuDef = {
    id: 'monitor',
    label: t('monitor.menu'),
    items: [
      { label: t('monitor.startSim'), shortcut: 'Ctrl+F5', disabled: !hasChart || starting, action: () => void startSim() },
      { label: t('monitor.attach'), disabled: !hasChart, action: () => setAttaching(true) },
      { separator: true, label: '' },
      { label: target?.simId !== null ? t('monitor.stopSim') : t('monitor.detach'), disabled: !target, action: () => void leave() },
    ],
  };

  useEffect(() => {
    const onKey = (e: KeyboardEvent) => {
      if (e.key === 'F5' && (e.ctrlKey || e.metaKey) && !current.current) {
        e.preventDefault();
        void startSim();
      }
    };
    window.addEventListener('keydown', onKey);
    return () => window.removeEventListener('keydown', onKey);
  });

  const button = (
    <button class="tool-button" title={`${t('monitor.startSimTip')} (Ctrl+F5)`} aria-label={t('monitor.startSim')} disabled={!hasChart || starting || !!target} onClick={() => void startSim()}>
      <MonitorIcon name="monitor" />
      <span>{t('monitor.monitorButton')}</span>
    </button>
  );

  const overlay =
    target || attaching ? (
      <>
        {target && (
          <MonitorView key={`${target.url}#${target.doc.pou}`} target={target} createCanvas={opts.createCanvas} onLeave={() => void leave()} onOpenChart={openChart} />
        )}
        {attaching && <AttachDialog onAttach={(u) => void attach(u)} onClose={() => setAttaching(false)} />}
      </>
    ) : null;

  return { active: target !== null, menu, button, overlay, replay };
}

/** A ws:// URL of a runtime's monitor (what `sfc run` prints), or why it is not one. */
export function checkMonitorUrl(text: string): string | null {
  let u: URL;
  try {
    u = new URL(text.trim());
  } catch {
    return t('monitor.attachDialog.badUrl');
  }
  if (u.protocol !== 'ws:' && u.protocol !== 'wss:') return t('monitor.attachDialog.badUrl');
  return null;
}

function AttachDialog(props: { onAttach: (url: string) => void; onClose: () => void }) {
  const [url, setUrl] = useState('ws://127.0.0.1:9002/?token=');
  const problem = checkMonitorUrl(url);
  return (
    <Modal
      title={t('monitor.attachDialog.title')}
      onClose={props.onClose}
      footer={
        <>
          <button class="button" onClick={props.onClose}>
            {t('monitor.cancel')}
          </button>
          <button class="button primary" disabled={!!problem} onClick={() => props.onAttach(url.trim())}>
            {t('monitor.attachDialog.attach')}
          </button>
        </>
      }
    >
      <label class="field">
        <span>{t('monitor.attachDialog.url')}</span>
        <input
          value={url}
          onInput={(e) => setUrl(e.currentTarget.value)}
          onKeyDown={(e) => {
            if (e.key === 'Enter' && !problem) props.onAttach(url.trim());
          }}
          spellcheck={false}
          style={{ width: '100%', fontFamily: 'var(--mono)' }}
        />
      </label>
      <p class="muted">{t('monitor.attachDialog.hint')}</p>
      {problem && <div class="field-error">{problem}</div>}
    </Modal>
  );
}
