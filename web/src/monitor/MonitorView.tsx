// Monitor mode (seed 001 chapter 10): the chart as it was when monitoring started, read-only,
// with the runtime's state on it — active steps framed green with their elapsed time,
// transitions whose condition holds, breakpoints, the block a breakpoint halted on framed
// orange — and the toolbar that drives the run: halt, continue, single scan, pause the display,
// breakpoints, stepping through the last ≤ 100 states. Beside it: variables (watch, force, set),
// the condition analysis of a stuck step, the time analysis and the runtime's events.
import { useEffect, useMemo, useRef, useState } from 'preact/hooks';
import type { CanvasHandle, CreateCanvas } from '../diagram/types';
import { t } from '../i18n';
import { toasts } from '../app/toast';
import { MonitorClient, type SocketFactory } from './client';
import { MonitorIcon, type MonitorIconName } from './icons';
import { shortDuration, type Hello, type ScanState, type StepReport } from './protocol';
import { blocksOf, elementsByName, nameOfBlock, type MonitorTarget } from './session';
import { ExplainPanel, TimingPanel, EventsPanel, VariablesPanel, BreakpointsPanel, MechanismsPanel } from './panels';

type SideTab = 'variables' | 'breakpoints' | 'why' | 'timing' | 'events' | 'mechanisms';

interface MenuAt {
  x: number;
  y: number;
  id: string;
}

/** Re-renders when the client changes. */
function useClient(client: MonitorClient): void {
  const [, set] = useState(0);
  useEffect(() => client.subscribe(() => set((n) => n + 1)), [client]);
}

/** Shows a refused command or a lost connection as a toast. */
function report(p: Promise<unknown>): void {
  p.catch((e: Error) => toasts.show('error', t('monitor.refused', { message: e.message })));
}

/**
 * Runtime names spelled as the runtime spells them → blocks. With `instance` (an SFC instance
 * of the running program chosen in the Mechanisms panel, whose function block is the chart
 * shown), its steps and transitions (`Rev.OpenKM1`) are matched to the chart's by name.
 */
function resolveElements(info: Hello | null, elements: Record<string, string[]>, instance: string | null, byName: Record<string, string[]>): Record<string, string[]> {
  if (!info) return elements;
  const out: Record<string, string[]> = {};
  const prefix = instance ? `${instance}.`.toUpperCase() : null;
  for (const n of [...info.steps.map((s) => s.name), ...info.transitions.map((x) => x.name)]) {
    if (prefix) {
      if (!n.toUpperCase().startsWith(prefix)) continue;
      const rest = n.slice(prefix.length);
      if (rest.includes('.')) continue;
      const ids = blocksOf(byName, rest);
      if (ids.length) out[n] = ids;
      continue;
    }
    const ids = blocksOf(elements, n);
    if (ids.length) out[n] = ids;
  }
  return out;
}

/** Where block `id` is drawn, relative to `host`; null when it is not on screen. */
function blockRect(host: HTMLElement | null, id: string): DOMRect | null {
  const g = host?.querySelector(`[data-element-id="${CSS.escape(id)}"] .djs-visual`) ?? host?.querySelector(`[data-element-id="${CSS.escape(id)}"]`);
  if (!host || !g) return null;
  const r = g.getBoundingClientRect();
  const h = host.getBoundingClientRect();
  return new DOMRect(r.left - h.left, r.top - h.top, r.width, r.height);
}

export interface MonitorViewProps {
  target: MonitorTarget;
  createCanvas: CreateCanvas;
  /** Stop (simulation) or detach (runtime). */
  onLeave: () => void;
  /** For tests: the WebSocket to use. */
  socket?: SocketFactory;
  /** Moves the monitor to the chart of `pou` showing `instance`; false when no tab shows it. */
  onOpenChart?: (instance: string, pou: string) => boolean;
}

export function MonitorView({ target, createCanvas, onLeave, socket, onOpenChart }: MonitorViewProps) {
  const client = useMemo(() => new MonitorClient(target.url, socket), [target.url]);
  useClient(client);
  useEffect(() => () => client.close(), [client]);
  const canvasHost = useRef<HTMLDivElement>(null);
  const [canvas, setCanvas] = useState<CanvasHandle | null>(null);
  const [selected, setSelected] = useState<string | null>(null);
  const [side, setSide] = useState<SideTab>(target.instance ? 'mechanisms' : 'variables');
  const [menu, setMenu] = useState<MenuAt | null>(null);
  const [explained, setExplained] = useState<StepReport | null>(null);
  const [explainError, setExplainError] = useState('');
  /** The SFC instance shown on the chart (Mechanisms panel); null: the chart's own names. */
  const [instance, setInstance] = useState<string | null>(target.instance ?? null);
  const [, setTick] = useState(0);

  // A witness to replay: once connected, set each scan's inputs and run that scan.
  const replayed = useRef(false);
  useEffect(() => {
    const w = target.replay;
    if (!w || replayed.current || client.status !== 'open' || !client.canControl()) return;
    replayed.current = true;
    void (async () => {
      try {
        for (const scan of w.scans) {
          for (const [name, value] of scan) await client.set(name, value);
          await client.singleScan();
        }
        toasts.show('success', t('monitor.replayed', { scans: w.scans.length }));
      } catch (e) {
        toasts.show('error', t('monitor.replayFailed', { message: (e as Error).message }));
      }
    })();
  });

  const info = client.info;
  const byName = useMemo(() => elementsByName(target.doc), [target.doc]);
  const elements = useMemo(() => resolveElements(info, target.elements, instance, byName), [info, target.elements, instance, byName]);
  const selectInstance = (name: string, pou: string) => {
    if (pou.toUpperCase() !== target.doc.pou.toUpperCase()) {
      // Its chart, when a tab shows it: the monitor moves there, on the same runtime.
      if (onOpenChart?.(name, pou)) return;
      toasts.show('info', t('monitor.mechanisms.otherChart', { instance: name, pou, shown: target.doc.pou }));
      return;
    }
    // The top chart of a simulation is the chart itself: its names carry no instance path.
    const isTop = info?.steps.some((s) => !s.name.includes('.')) && !info?.steps.some((s) => s.name.toUpperCase().startsWith(`${name.toUpperCase()}.`));
    setInstance(isTop ? null : name);
  };
  const kindOf = (id: string) => target.doc.elements.find((e) => e.id === id)?.kind;
  const selName = selected ? nameOfBlock(elements, selected) : undefined;
  const selKind = selected ? kindOf(selected) : undefined;
  const selBreakKind = selKind === 'step' || selKind === 'transition' ? selKind : undefined;

  // The read-only canvas with the chart as it was when monitoring started.
  useEffect(() => {
    const c = createCanvas(canvasHost.current!, { t: (k) => t(k), readOnly: true });
    c.load(target.doc);
    // The whole chart in view: a monitor is watched more than scrolled.
    c.zoom('fit');
    const off = c.on('selection', (ids) => setSelected(ids.length === 1 ? ids[0] : null));
    setCanvas(c);
    return () => {
      off();
      c.destroy();
    };
  }, [target.doc]);

  const view: ScanState | null = client.view();
  const browsing = client.history !== null;

  // The runtime's state on the chart.
  useEffect(() => {
    if (!canvas) return;
    const active: string[] = [];
    const labels: Record<string, string> = {};
    for (const a of view?.active ?? []) {
      for (const id of blocksOf(elements, a.step)) {
        active.push(id);
        labels[id] = shortDuration(a.elapsedUs);
      }
    }
    // The block a breakpoint halted on is framed orange only (with its elapsed time).
    // (Not on the states before the hit, when stepping back through them.)
    const h = client.hit;
    const hit = h && (client.halted || client.displayPaused) && (!view || view.scan >= h.scan) ? blocksOf(elements, h.name) : [];
    canvas.highlight('hit', hit, labels);
    canvas.highlight(
      'active',
      active.filter((id) => !hit.includes(id)),
      labels,
    );
    const enabled = Object.entries(view?.guards ?? {})
      .filter(([, v]) => v === true)
      .flatMap(([n]) => blocksOf(elements, n));
    canvas.highlight('enabled', enabled);
    canvas.highlight(
      'breakpoint',
      client.breakpoints.filter((b) => b.enabled).flatMap((b) => blocksOf(elements, b.name)),
    );
  });

  // Overlays that follow the drawing (disabled breakpoints, the explanation) while it scrolls.
  useEffect(() => {
    let frame = 0;
    const loop = () => {
      setTick((n) => (n + 1) % 1_000_000);
      frame = requestAnimationFrame(loop);
    };
    const needed = explained !== null || client.breakpoints.some((b) => !b.enabled);
    if (needed) frame = requestAnimationFrame(loop);
    return () => cancelAnimationFrame(frame);
  }, [explained, client.breakpoints]);

  // The explanation is of one moment: it goes when the step is no longer active.
  useEffect(() => {
    if (explained && view && !view.active.some((a) => a.step.toLowerCase() === explained.step.toLowerCase())) setExplained(null);
  }, [view, explained]);

  async function explain(step: string): Promise<void> {
    setExplainError('');
    try {
      const r = await client.explain(step);
      setExplained(r);
      setSide('why');
    } catch (e) {
      setExplained(null);
      setExplainError((e as Error).message);
      setSide('why');
    }
  }

  const control = client.canControl();
  const connected = client.status === 'open';
  const activeSel = !!selName && selKind === 'step' && !!view?.active.some((a) => a.step.toLowerCase() === selName.toLowerCase());
  const selBreak = selBreakKind && selName ? client.findBreakpoint(selBreakKind, selName) : undefined;

  function toggleBreakpoint(id: string | null = selected): void {
    const n = id ? nameOfBlock(elements, id) : undefined;
    const k = id ? kindOf(id) : undefined;
    if (!n || (k !== 'step' && k !== 'transition')) return;
    report(client.toggleBreakpoint(k, n));
  }

  // Keys of the monitor; the editor's own (undo, delete …) do not reach the hidden editing canvas.
  const keys = useRef<(e: KeyboardEvent) => void>(() => undefined);
  keys.current = (e: KeyboardEvent) => {
    if (document.querySelector('.modal-backdrop')) return;
    const ctrl = e.ctrlKey || e.metaKey;
    const inField = e.target instanceof HTMLElement && e.target.closest('input, textarea, select') !== null;
    const run = (f: () => void) => {
      e.preventDefault();
      e.stopPropagation();
      f();
    };
    if (e.key === 'F5') return run(() => control && client.halted && report(client.resume()));
    if (e.key === 'F6') return run(() => control && !client.halted && report(client.halt()));
    if (e.key === 'F10') return run(() => control && client.halted && report(client.singleScan()));
    if (e.key === 'F9') return run(() => toggleBreakpoint());
    if (e.key === 'F7') return run(() => undefined);
    if (inField) return;
    if (e.key === 'Delete' || e.key === 'Backspace' || (ctrl && 'zyaxcvd'.includes(e.key.toLowerCase()))) {
      e.stopPropagation();
      if (ctrl) e.preventDefault();
    }
    if (e.key === 'Escape') setMenu(null);
  };
  useEffect(() => {
    const onKey = (e: KeyboardEvent) => keys.current(e);
    window.addEventListener('keydown', onKey, true);
    return () => window.removeEventListener('keydown', onKey, true);
  }, []);

  function onContextMenu(e: MouseEvent): void {
    const g = (e.target as Element | null)?.closest?.('[data-element-id]');
    const id = g?.getAttribute('data-element-id');
    const k = id ? kindOf(id) : undefined;
    e.preventDefault();
    if (!id || (k !== 'step' && k !== 'transition')) {
      setMenu(null);
      return;
    }
    canvas?.select([id]);
    setSelected(id);
    const host = canvasHost.current!.getBoundingClientRect();
    setMenu({ x: e.clientX - host.left, y: e.clientY - host.top, id });
  }

  useEffect(() => {
    if (!menu) return;
    const close = (e: MouseEvent) => {
      if (!(e.target as Element | null)?.closest?.('.mon-context')) setMenu(null);
    };
    document.addEventListener('mousedown', close);
    return () => document.removeEventListener('mousedown', close);
  }, [menu]);

  const hist = client.history;
  const faulted = connected && client.runState === 'FAULT';
  const stateBadge = !connected
    ? client.status === 'connecting'
      ? { cls: 'connecting', text: t('monitor.state.connecting') }
      : { cls: 'closed', text: t('monitor.state.closed') }
    : faulted
      ? { cls: 'fault', text: t('monitor.state.fault') }
      : client.runState === 'STOP'
        ? { cls: 'halted', text: t('monitor.state.stopped') }
        : client.halted
      ? { cls: 'halted', text: client.hit ? t('monitor.state.hit', { name: client.hit.name }) : t('monitor.state.halted') }
      : client.displayPaused
        ? { cls: 'paused', text: t('monitor.state.paused') }
        : { cls: 'running', text: t('monitor.state.running') };

  // The profile the chart runs with, and why: the editor's simulation says (the file's vendor);
  // an attached runtime names it in `hello`.
  const profile: { name: string; why: string } | null = target.profile
    ? {
        name: target.profile.name,
        why:
          target.profile.source === 'vendor'
            ? t('monitor.profile.vendor', { file: target.profile.file ?? target.title, vendor: target.profile.vendor ?? '' })
            : t('monitor.profile.default'),
      }
    : client.info?.profile
      ? { name: client.info.profile, why: t('monitor.profile.runtime', { profile: client.info.profile }) }
      : null;

  return (
    <div class="mon-overlay" role="region" aria-label={t('monitor.title')}>
      <div class="mon-toolbar" role="toolbar" aria-label={t('monitor.toolbar')}>
        <span
          class="mon-title"
          title={`${target.simId !== null ? t('monitor.simulating', { title: target.title }) : t('monitor.attached', { title: target.title })}\n${target.url.replace(/token=[^&]*/, 'token=…')}`}
        >
          <MonitorIcon name={target.simId !== null ? 'monitor' : 'plug'} />
          <span>{target.doc.pou}</span>
        </span>
        <span class={`mon-badge mon-${stateBadge.cls}`} role="status" data-testid="monitor-state" title={faulted ? client.fault?.message : undefined}>
          {stateBadge.text}
        </span>
        {profile && (
          <span class="mon-profile" data-testid="monitor-profile" title={profile.why} aria-description={profile.why}>
            {t('monitor.profile.label', { profile: profile.name })}
          </span>
        )}
        <span class="tool-separator" />
        {faulted ? (
          <MonButton icon="run" label={t('monitor.reset')} title={t('monitor.resetTip')} disabled={!control} onClick={() => report(client.reset('warm'))} primary={control} />
        ) : (
          <MonButton icon="run" label={t('monitor.continue')} title={`${t('monitor.continueTip')} (F5)`} disabled={!control || !connected || !client.halted} onClick={() => report(client.resume())} primary={client.halted && control} />
        )}
        <MonButton icon="halt" label={t('monitor.halt')} title={`${t('monitor.haltTip')} (F6)`} disabled={!control || !connected || client.halted} onClick={() => report(client.halt())} />
        <MonButton icon="scan" label={t('monitor.singleScan')} title={`${t('monitor.singleScanTip')} (F10)`} disabled={!control || !connected || !client.halted} onClick={() => report(client.singleScan())} />
        <MonButton
          icon={client.displayPaused ? 'eye' : 'eyeOff'}
          label={client.displayPaused ? t('monitor.resumeDisplay') : t('monitor.pauseDisplay')}
          title={client.displayPaused ? t('monitor.resumeDisplayTip') : t('monitor.pauseDisplayTip')}
          disabled={!connected}
          pressed={client.displayPaused}
          onClick={() => report(client.displayPaused ? client.resumeDisplay() : client.pauseDisplay())}
        />
        <span class="tool-separator" />
        <MonButton icon="bpSet" title={`${selBreak ? t('monitor.bp.remove') : t('monitor.bp.set')} (F9)`} disabled={!connected || !selBreakKind || !selName} pressed={!!selBreak} onClick={() => toggleBreakpoint()} />
        <MonButton
          icon="bpDisable"
          title={selBreak && !selBreak.enabled ? t('monitor.bp.enable') : t('monitor.bp.disable')}
          disabled={!connected || !selBreak}
          onClick={() => selBreak && report(client.breakpoint(selBreak.enabled ? 'disable' : 'enable', selBreak.kind, selBreak.name))}
        />
        <MonButton icon="bpDelete" title={t('monitor.bp.delete')} disabled={!connected || !selBreak} onClick={() => selBreak && report(client.breakpoint('delete', selBreak.kind, selBreak.name))} />
        <MonButton
          icon="bpDisableAll"
          title={client.breakpoints.some((b) => b.enabled) ? t('monitor.bp.disableAll') : t('monitor.bp.enableAll')}
          disabled={!connected || client.breakpoints.length === 0}
          onClick={() => report(client.toggleAllBreakpoints())}
        />
        <MonButton icon="bpDeleteAll" title={t('monitor.bp.deleteAll')} disabled={!connected || client.breakpoints.length === 0} onClick={() => report(client.deleteAllBreakpoints())} />
        <span class="tool-separator" />
        <span class="mon-history" aria-label={t('monitor.history.label')}>
          <MonButton icon="first" title={t('monitor.history.first')} disabled={!connected || (browsing && hist!.index === 0)} onClick={() => (browsing ? client.moveHistory('first') : report(client.loadHistory().then(() => client.moveHistory('first'))))} />
          <MonButton icon="back" title={t('monitor.history.back')} disabled={!connected || (browsing && hist!.index === 0)} onClick={() => (browsing ? client.moveHistory(-1) : report(client.loadHistory().then(() => client.moveHistory(-1))))} />
          <span class={`mon-counter ${browsing ? 'on' : ''}`} title={t('monitor.history.counterTip')} data-testid="history-counter">
            {browsing ? `${hist!.index + 1} / ${hist!.states.length}` : `– / ${Math.min(100, (view?.scan ?? -1) + 1)}`}
          </span>
          <MonButton icon="forward" title={t('monitor.history.forward')} disabled={!browsing || hist!.index >= hist!.states.length - 1} onClick={() => client.moveHistory(1)} />
          <MonButton icon="last" title={t('monitor.history.last')} disabled={!browsing || hist!.index >= hist!.states.length - 1} onClick={() => client.moveHistory('last')} />
          <MonButton icon="live" title={t('monitor.history.liveTip')} disabled={!browsing} onClick={() => client.leaveHistory()} />
        </span>
        <span class="tool-separator" />
        <MonButton icon="why" label={t('monitor.why')} title={t('monitor.whyTip')} disabled={!connected || !activeSel} onClick={() => selName && void explain(selName)} />
        <span class="spacer" />
        <span class="mon-scan" data-testid="monitor-scan">
          {view ? t('monitor.scanAt', { scan: view.scan, time: view.time }) : ''}
        </span>
        <button class="button mon-leave" title={target.simId !== null ? t('monitor.stopSim') : t('monitor.detach')} aria-label={target.simId !== null ? t('monitor.stopSim') : t('monitor.detach')} onClick={onLeave}>
          <MonitorIcon name="stop" />
          {target.simId !== null ? t('monitor.stop') : t('monitor.detach')}
        </button>
      </div>
      {client.status === 'closed' && client.closeReason !== 'detached' && (
        <div class="mon-banner" role="alert">
          {t('monitor.lost', { reason: client.closeReason })}
        </div>
      )}
      <div class="mon-body">
        <div class="mon-canvas-wrap" onContextMenu={onContextMenu}>
          <div class="mon-canvas" ref={canvasHost} />
          {browsing && view && (
            <div class="mon-history-note" role="status">
              {t('monitor.history.showing', { scan: view.scan, time: view.time })}
            </div>
          )}
          {client.breakpoints
            .filter((b) => !b.enabled)
            .flatMap((b) => blocksOf(elements, b.name))
            .map((id) => {
              const r = blockRect(canvasHost.current, id);
              return r ? <span key={id} class="mon-bp-off" style={{ left: `${r.left - 8}px`, top: `${r.top - 8}px` }} title={t('monitor.bp.disabledDot')} /> : null;
            })}
          {explained && <ExplainBubble report={explained} host={canvasHost.current} ids={blocksOf(elements, explained.step)} onClose={() => setExplained(null)} />}
          {menu && (
            <ContextMenu
              at={menu}
              name={nameOfBlock(elements, menu.id)}
              kind={kindOf(menu.id) as 'step' | 'transition'}
              client={client}
              active={!!view?.active.some((a) => a.step.toLowerCase() === (nameOfBlock(elements, menu.id) ?? '').toLowerCase())}
              onExplain={(n) => void explain(n)}
              onClose={() => setMenu(null)}
            />
          )}
        </div>
        <aside class="mon-side" aria-label={t('monitor.panel')}>
          <div class="panel-tabs mon-tabs" role="tablist">
            {(['variables', 'breakpoints', 'why', 'timing', 'mechanisms', 'events'] as SideTab[]).map((k) => (
              <button key={k} role="tab" aria-selected={side === k} class={`panel-tab ${side === k ? 'active' : ''}`} onClick={() => setSide(k)}>
                {t(`monitor.tab.${k}`)}
                {k === 'breakpoints' && client.breakpoints.length > 0 && <span class="mon-count">{client.breakpoints.length}</span>}
              </button>
            ))}
          </div>
          <div class="mon-side-body">
            {side === 'variables' && <VariablesPanel client={client} state={view} />}
            {side === 'breakpoints' && <BreakpointsPanel client={client} onReveal={(n) => blocksOf(elements, n)[0] && canvas?.reveal(blocksOf(elements, n)[0])} />}
            {side === 'why' && (
              <ExplainPanel report={explained} error={explainError} selectedStep={selKind === 'step' ? selName ?? null : null} canExplain={activeSel} onExplain={() => selName && void explain(selName)} />
            )}
            {side === 'timing' && <TimingPanel client={client} shown={instance} />}
            {side === 'mechanisms' && <MechanismsPanel client={client} shown={instance} onSelect={selectInstance} />}
            {side === 'events' && <EventsPanel client={client} />}
          </div>
        </aside>
      </div>
    </div>
  );
}

function MonButton(props: { icon: MonitorIconName; label?: string; title: string; onClick: () => void; disabled?: boolean; primary?: boolean; pressed?: boolean }) {
  return (
    <button
      class={`tool-button mon-button ${props.primary ? 'primary' : ''} ${props.pressed ? 'pressed' : ''}`}
      title={props.title}
      aria-label={props.label ?? props.title}
      aria-pressed={props.pressed === undefined ? undefined : props.pressed}
      disabled={props.disabled}
      onClick={props.onClick}
    >
      <MonitorIcon name={props.icon} />
      {props.label && <span>{props.label}</span>}
    </button>
  );
}

function ContextMenu(props: {
  at: MenuAt;
  name: string | undefined;
  kind: 'step' | 'transition';
  client: MonitorClient;
  active: boolean;
  onExplain: (name: string) => void;
  onClose: () => void;
}) {
  const { name, kind, client } = props;
  const bp = name ? client.findBreakpoint(kind, name) : undefined;
  const item = (label: string, action: () => void, disabled = false) => (
    <button
      role="menuitem"
      class="mon-context-item"
      disabled={disabled}
      onClick={() => {
        props.onClose();
        action();
      }}
    >
      {label}
    </button>
  );
  return (
    <div class="mon-context" role="menu" style={{ left: `${props.at.x}px`, top: `${props.at.y}px` }}>
      <div class="mon-context-title">{name ?? '?'}</div>
      {!bp && item(t('monitor.bp.set'), () => name && report(client.breakpoint('set', kind, name)), !name)}
      {bp && item(bp.enabled ? t('monitor.bp.disable') : t('monitor.bp.enable'), () => report(client.breakpoint(bp.enabled ? 'disable' : 'enable', kind, bp.name)))}
      {bp && item(t('monitor.bp.remove'), () => report(client.breakpoint('delete', kind, bp.name)))}
      {kind === 'step' && item(t('monitor.why'), () => name && props.onExplain(name), !props.active)}
    </div>
  );
}

/** The condition analysis beside the stuck step on the chart. */
function ExplainBubble(props: { report: StepReport; host: HTMLElement | null; ids: string[]; onClose: () => void }) {
  const r = props.ids.length ? blockRect(props.host, props.ids[0]) : null;
  if (!r) return null;
  const style = { left: `${r.right + 14}px`, top: `${Math.max(4, r.top - 6)}px` };
  return (
    <div class="mon-explain" style={style} role="note" aria-label={t('monitor.explain.title', { step: props.report.step })}>
      <div class="mon-explain-head">
        <span>{t('monitor.explain.title', { step: props.report.step })}</span>
        <button class="icon-button" title={t('monitor.close')} aria-label={t('monitor.close')} onClick={props.onClose}>
          ×
        </button>
      </div>
      {props.report.transitions.length === 0 && <div class="muted">{t('monitor.explain.none')}</div>}
      {props.report.transitions.map((x) => (
        <div key={x.transition} class={`mon-explain-tr ${x.value ? 'true' : 'false'}`}>
          <div>
            <b>{x.transition}</b> <code>{x.guard}</code> <span class={`mon-val ${x.value ? 'on' : 'off'}`}>{x.value ? 'TRUE' : 'FALSE'}</span>
          </div>
          <div class="mon-operands">
            {x.operands.map((o) => (
              <span key={o.operand} class={`mon-operand ${o.value === 'TRUE' ? 'on' : o.value === 'FALSE' ? 'off' : ''}`}>
                {o.operand} = {o.value}
              </span>
            ))}
          </div>
          {(x.needs ?? []).map((n) => (
            <div key={n} class="mon-needs">
              {n}
            </div>
          ))}
          {x.change.length > 0 && <div class="mon-fires">{t('monitor.explain.firesWhen', { change: x.change.join(', ') })}</div>}
          {x.missing.length > 0 && <div class="mon-fires">{t('monitor.explain.waitsFor', { steps: x.missing.join(', ') })}</div>}
          {x.masked_by && <div class="mon-fires">{t('monitor.explain.masked', { by: x.masked_by })}</div>}
        </div>
      ))}
    </div>
  );
}
