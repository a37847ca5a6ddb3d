// The monitor's side panels: variables (watch list, force, set), breakpoints, the condition
// analysis of a stuck step, the time analysis per step, and the runtime's events.
import { Fragment } from 'preact';
import { useEffect, useState } from 'preact/hooks';
import { t } from '../i18n';
import { settings, WATCH_MAX } from '../app/settings';
import { toasts } from '../app/toast';
import type { MonitorClient } from './client';
import { parseValue, showValue, type MechanismRuns, type ScanState, type StepReport, type VariableInfo } from './protocol';

/** The variables watched at first: the located ones (the I/O), else the first ten. */
export function defaultWatch(vars: VariableInfo[]): string[] {
  const located = vars.filter((v) => v.location).map((v) => v.name);
  return located.length ? located : vars.slice(0, 10).map((v) => v.name);
}

/** The watch list kept for the POU `pou` (the settings the server keeps, src/app/settings.ts). */
function storedWatch(pou: string): string[] | null {
  return settings.watch(pou);
}

function storeWatch(pou: string, list: string[]): void {
  void settings.update({ watch: { [pou]: list.slice(0, WATCH_MAX) } });
}

function fail(e: Error): void {
  toasts.show('error', t('monitor.refused', { message: e.message }));
}

export function VariablesPanel({ client, state }: { client: MonitorClient; state: ScanState | null }) {
  const info = client.info;
  const [watch, setWatch] = useState<string[] | null>(null);
  const [adding, setAdding] = useState('');
  useEffect(() => {
    if (info && watch === null) {
      const known = new Set(info.variables.map((v) => v.name));
      setWatch((storedWatch(info.pou) ?? defaultWatch(info.variables)).filter((n) => known.has(n)));
    }
  }, [info]);
  if (!info) return <div class="empty">{t('monitor.waiting')}</div>;
  const list = watch ?? [];
  const update = (next: string[]) => {
    setWatch(next);
    storeWatch(info.pou, next);
  };
  const others = info.variables.filter((v) => !list.includes(v.name));
  const control = client.canControl();
  return (
    <div class="mon-vars">
      {!control && <div class="mon-note">{info.control ? t('monitor.vars.noToken') : t('monitor.vars.watchOnly')}</div>}
      <table class="mon-table">
        <thead>
          <tr>
            <th>{t('monitor.vars.name')}</th>
            <th>{t('monitor.vars.value')}</th>
            <th>{t('monitor.vars.write')}</th>
            <th />
          </tr>
        </thead>
        <tbody>
          {list.map((name) => {
            const v = info.variables.find((x) => x.name === name);
            if (!v) return null;
            return <VariableRow key={name} v={v} client={client} state={state} control={control} onRemove={() => update(list.filter((n) => n !== name))} />;
          })}
        </tbody>
      </table>
      {others.length > 0 && (
        <div class="mon-add">
          <select aria-label={t('monitor.vars.addWhich')} value={adding} onChange={(e) => setAdding(e.currentTarget.value)}>
            <option value="">{t('monitor.vars.addWhich')}</option>
            {others.map((v) => (
              <option key={v.name} value={v.name}>
                {v.name} : {v.type}
              </option>
            ))}
          </select>
          <button
            class="button"
            disabled={!adding}
            onClick={() => {
              update([...list, adding]);
              setAdding('');
            }}
          >
            {t('monitor.vars.add')}
          </button>
        </div>
      )}
    </div>
  );
}

function VariableRow(props: { v: VariableInfo; client: MonitorClient; state: ScanState | null; control: boolean; onRemove: () => void }) {
  const { v, client, state, control } = props;
  const isBool = v.type.toUpperCase() === 'BOOL';
  // The chart writes its outputs every scan: a one-time write would not last, forcing does.
  const output = /^%Q/i.test(v.location ?? '');
  const value = state?.vars[v.name];
  const forced = !!state?.forced.some((f) => f.toLowerCase() === v.name.toLowerCase());
  const [text, setText] = useState(isBool ? (value === true ? 'FALSE' : 'TRUE') : '');
  const [error, setError] = useState('');
  const typed = () => {
    const p = parseValue(v.type, text);
    if (p instanceof Error) {
      setError(t('monitor.vars.badValue', { type: v.type }));
      return null;
    }
    setError('');
    return p;
  };
  const send = (op: 'set' | 'force') => {
    const p = typed();
    if (p === null) return;
    (op === 'set' ? client.set(v.name, p) : client.force(v.name, p)).catch((e: Error) => setError(e.message));
  };
  return (
    <tr class={forced ? 'forced' : ''} data-var={v.name}>
      <td class="mon-var-name" title={`${v.name} : ${v.type}${v.location ? ` AT ${v.location}` : ''}`}>
        <span>{v.name}</span>
        <span class="muted mon-type">
          {v.type}
          {v.location ? ` ${v.location}` : ''}
        </span>
      </td>
      <td class="mon-var-value">
        <span class={`mon-val ${value === true ? 'on' : value === false ? 'off' : ''}`}>{showValue(value)}</span>
        {forced && (
          <span class="mon-forced" title={t('monitor.vars.forcedTip')}>
            {t('monitor.vars.forced')}
          </span>
        )}
      </td>
      <td class="mon-var-write">
        {control && (
          <form
            class="mon-write"
            onSubmit={(e) => {
              e.preventDefault();
              send(output ? 'force' : 'set');
            }}
          >
            {isBool ? (
              <select aria-label={t('monitor.vars.newValue', { name: v.name })} value={text} onChange={(e) => setText(e.currentTarget.value)}>
                <option value="TRUE">TRUE</option>
                <option value="FALSE">FALSE</option>
              </select>
            ) : (
              <input
                aria-label={t('monitor.vars.newValue', { name: v.name })}
                class={error ? 'invalid' : ''}
                value={text}
                placeholder={showValue(value)}
                onInput={(e) => setText(e.currentTarget.value)}
              />
            )}
            {!output && (
              <button type="submit" class="mini" title={t('monitor.vars.setTip')}>
                {t('monitor.vars.set')}
              </button>
            )}
            <button type="button" class="mini" title={t('monitor.vars.forceTip')} onClick={() => send('force')}>
              {t('monitor.vars.force')}
            </button>
            {forced && (
              <button type="button" class="mini" title={t('monitor.vars.unforceTip')} onClick={() => client.unforce(v.name).catch(fail)}>
                {t('monitor.vars.unforce')}
              </button>
            )}
          </form>
        )}
        {error && <div class="field-error">{error}</div>}
      </td>
      <td>
        <button class="icon-button" title={t('monitor.vars.remove')} aria-label={t('monitor.vars.remove')} onClick={props.onRemove}>
          ×
        </button>
      </td>
    </tr>
  );
}

export function BreakpointsPanel({ client, onReveal }: { client: MonitorClient; onReveal: (name: string) => void }) {
  if (client.breakpoints.length === 0) return <div class="empty">{t('monitor.bp.none')}</div>;
  return (
    <table class="mon-table">
      <tbody>
        {client.breakpoints.map((b) => (
          <tr key={`${b.kind}:${b.name}`} class={b.enabled ? '' : 'disabled'}>
            <td>
              <span class={`mon-dot ${b.enabled ? 'on' : 'off'}`} />
            </td>
            <td>
              <button class="link" onClick={() => onReveal(b.name)}>
                {b.name}
              </button>
              <span class="muted"> {t(`monitor.bp.kind.${b.kind}`)}</span>
            </td>
            <td class="mon-actions">
              <button class="mini" onClick={() => client.breakpoint(b.enabled ? 'disable' : 'enable', b.kind, b.name).catch(fail)}>
                {b.enabled ? t('monitor.bp.disable') : t('monitor.bp.enable')}
              </button>
              <button class="mini" onClick={() => client.breakpoint('delete', b.kind, b.name).catch(fail)}>
                {t('monitor.bp.delete')}
              </button>
            </td>
          </tr>
        ))}
      </tbody>
    </table>
  );
}

export function ExplainPanel(props: { report: StepReport | null; error: string; selectedStep: string | null; canExplain: boolean; onExplain: () => void }) {
  const r = props.report;
  return (
    <div class="mon-why">
      <div class="mon-why-head">
        <button class="button" disabled={!props.canExplain} onClick={props.onExplain}>
          {props.selectedStep ? t('monitor.explain.ask', { step: props.selectedStep }) : t('monitor.explain.select')}
        </button>
      </div>
      {props.error && <div class="field-error">{props.error}</div>}
      {!r && !props.error && <div class="empty">{t('monitor.explain.hint')}</div>}
      {r && (
        <>
          <h3>
            {t('monitor.explain.title', { step: r.step })} <span class="muted">{t('monitor.explain.activeFor', { time: r.elapsed })}</span>
          </h3>
          {r.timeout && <div class="muted">{t('monitor.explain.timeout', { time: r.timeout })}</div>}
          {r.transitions.length === 0 && <div class="muted">{t('monitor.explain.none')}</div>}
          {r.transitions.map((x) => (
            <div key={x.transition} class="mon-why-tr">
              <div>
                <b>{x.transition}</b> <span class={`mon-val ${x.value ? 'on' : 'off'}`}>{x.value ? 'TRUE' : 'FALSE'}</span>
              </div>
              <code class="mon-guard">{x.guard}</code>
              <table class="mon-table">
                <tbody>
                  {x.operands.map((o) => (
                    <tr key={o.operand}>
                      <td>
                        <code>{o.operand}</code>
                      </td>
                      <td>
                        <span class={`mon-val ${o.value === 'TRUE' ? 'on' : o.value === 'FALSE' ? 'off' : ''}`}>{o.value}</span>
                      </td>
                    </tr>
                  ))}
                </tbody>
              </table>
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
        </>
      )}
    </div>
  );
}

/**
 * Every SFC instance of the running program at a glance (seed 003's mechanisms): activation
 * bit, state, active steps with their times, runs, resets, errors and the last error record.
 * Selecting one shows it on the chart.
 */
export function MechanismsPanel(props: { client: MonitorClient; shown: string | null; onSelect: (instance: string, pou: string) => void }) {
  const { client } = props;
  const [list, error, load] = usePolled(client, () => client.mechanisms(), 500);
  return (
    <div class="mon-mechanisms">
      <div class="mon-why-head">
        <button class="button" onClick={load}>
          {t('monitor.mechanisms.refresh')}
        </button>
        {list && <span class="muted">{t('monitor.mechanisms.at', { scan: list.scan })}</span>}
      </div>
      {error && <div class="field-error">{error}</div>}
      {list && list.mechanisms.length === 0 && <div class="empty">{t('monitor.mechanisms.none')}</div>}
      {list && list.mechanisms.length > 0 && (
        <table class="mon-table">
          <thead>
            <tr>
              <th>{t('monitor.mechanisms.instance')}</th>
              <th>{t('monitor.mechanisms.state')}</th>
              <th>{t('monitor.mechanisms.active')}</th>
              <th>{t('monitor.mechanisms.runs')}</th>
              <th>{t('monitor.mechanisms.errors')}</th>
            </tr>
          </thead>
          <tbody>
            {list.mechanisms.map((m) => (
              <Fragment key={m.instance}>
                <tr
                  data-instance={m.instance}
                  class={`mon-mech ${props.shown === m.instance ? 'selected' : ''} ${m.lastError ? 'has-error' : ''}`}
                  title={t('monitor.mechanisms.select', { instance: m.instance })}
                  onClick={() => props.onSelect(m.instance, m.pou)}
                >
                  <td>
                    <b>{m.instance}</b>
                    <div class="muted">{m.pou}</div>
                  </td>
                  <td>
                    {m.activation !== null && (
                      <span class={`mon-val ${m.activation ? 'on' : 'off'}`} title={`${t('monitor.mechanisms.activation')}: ${m.activationVariable ?? ''}`}>
                        {m.activation ? 'TRUE' : 'FALSE'}
                      </span>
                    )}{' '}
                    {m.running ? t('monitor.mechanisms.running') : t('monitor.mechanisms.idle')}
                  </td>
                  <td class="mon-mech-steps">
                    {m.active.map((a) => (
                      <div key={a.step}>
                        {a.step} <span class="muted">{a.time}</span>
                      </div>
                    ))}
                  </td>
                  <td>
                    {m.runs}
                    {m.resets > 0 && <span class="muted"> ({t('monitor.mechanisms.resets')}: {m.resets})</span>}
                  </td>
                  <td>{m.errors}</td>
                </tr>
                {m.lastError && (
                  <tr class="mon-mech-error" data-instance-error={m.instance}>
                    <td colSpan={5}>
                      <span class="muted">{t('monitor.mechanisms.lastError')}:</span> {m.lastError.message}
                    </td>
                  </tr>
                )}
              </Fragment>
            ))}
          </tbody>
        </table>
      )}
    </div>
  );
}

/**
 * An answer of the runtime that a panel shows while it is open: asked for at once, then every
 * `periodMs` while the run moves (not while halted or disconnected); `load` asks again now.
 */
function usePolled<T>(client: MonitorClient, ask: () => Promise<T>, periodMs: number): [T | null, string, () => void] {
  const [value, setValue] = useState<T | null>(null);
  const [error, setError] = useState('');
  const load = () => {
    ask().then(
      (x) => {
        setValue(x);
        setError('');
      },
      (e: Error) => setError(e.message),
    );
  };
  useEffect(() => {
    load();
    const every = setInterval(() => {
      if (!client.halted && client.status === 'open') load();
    }, periodMs);
    return () => clearInterval(every);
  }, [client]);
  return [value, error, load];
}

export function TimingPanel({ client, shown }: { client: MonitorClient; shown: string | null }) {
  const [timing, error, load] = usePolled(client, () => client.timing(), 1000);
  return (
    <div class="mon-timing">
      <div class="mon-why-head">
        <button class="button" onClick={load}>
          {t('monitor.timing.refresh')}
        </button>
        {timing && <span class="muted">{t('monitor.timing.at', { scan: timing.scan })}</span>}
      </div>
      {error && <div class="field-error">{error}</div>}
      {timing && (timing.mechanisms ?? []).length > 0 && <RunsOfMechanisms list={timing.mechanisms} shown={shown} />}
      {timing && (
        <>
          <h4 class="mon-sub">{t('monitor.timing.perStep')}</h4>
          <StatsTable
            class="mon-steps-timing"
            name={t('monitor.timing.step')}
            count={t('monitor.timing.activations')}
            rows={timing.steps.map((x) => ({ name: x.step, count: x.activations, min: x.min, mean: x.mean, max: x.max }))}
          />
        </>
      )}
    </div>
  );
}

/** Durations per step or state: how often, and the shortest, mean and longest time (– for none). */
function StatsTable(props: { class: string; name: string; count: string; rows: { name: string; count: number; min: string | null; mean: string | null; max: string | null }[] }) {
  return (
    <table class={`mon-table mon-numbers ${props.class}`}>
      <thead>
        <tr>
          <th>{props.name}</th>
          <th>{props.count}</th>
          <th>{t('monitor.timing.min')}</th>
          <th>{t('monitor.timing.mean')}</th>
          <th>{t('monitor.timing.max')}</th>
        </tr>
      </thead>
      <tbody>
        {props.rows.map((r) => (
          <tr key={r.name} class={r.count === 0 ? 'never' : ''}>
            <td>{r.name}</td>
            <td>{r.count}</td>
            <td>{r.min ?? '–'}</td>
            <td>{r.mean ?? '–'}</td>
            <td>{r.max ?? '–'}</td>
          </tr>
        ))}
      </tbody>
    </table>
  );
}

/** How a run ended, in the user's language (`error 404` keeps its number). */
function endText(ended: string | null): string {
  if (ended === null) return t('monitor.timing.inProgress');
  if (ended === 'normal') return t('monitor.timing.endNormal');
  if (ended === 'reset') return t('monitor.timing.endReset');
  if (ended.startsWith('error')) return t('monitor.timing.endError', { code: ended.slice(5).trim() });
  return ended;
}

/**
 * Seed 003's time analysis per run: for the chosen mechanism (the one shown on the chart, else
 * the first), each run with the states passed in order and the time in each, its total and how
 * it ended (newest first), then each state's count, min, mean and max over the runs.
 */
function RunsOfMechanisms({ list, shown }: { list: MechanismRuns[]; shown: string | null }) {
  const [chosen, setChosen] = useState<string | null>(null);
  const name = chosen ?? (list.some((m) => m.instance === shown) ? shown : list[0].instance);
  const m = list.find((x) => x.instance === name) ?? list[0];
  const runs = [...m.runs].reverse();
  return (
    <div class="mon-runs" data-mechanism={m.instance}>
      <div class="mon-why-head">
        <h4 class="mon-sub">{t('monitor.timing.runsOf')}</h4>
        <select aria-label={t('monitor.timing.mechanism')} value={m.instance} onChange={(e) => setChosen((e.target as HTMLSelectElement).value)}>
          {list.map((x) => (
            <option key={x.instance} value={x.instance}>
              {x.instance}
            </option>
          ))}
        </select>
        <span class="muted">
          {t('monitor.timing.runCount', { runs: m.runs.length + m.dropped, resets: m.resets })}
          {m.dropped > 0 && ` · ${t('monitor.timing.dropped', { n: m.dropped })}`}
        </span>
      </div>
      {runs.length === 0 && <div class="empty">{t('monitor.timing.noRuns')}</div>}
      {runs.length > 0 && (
        <table class="mon-table mon-run-table">
          <thead>
            <tr>
              <th>{t('monitor.timing.run')}</th>
              <th>{t('monitor.timing.start')}</th>
              <th>{t('monitor.timing.states')}</th>
              <th>{t('monitor.timing.total')}</th>
              <th>{t('monitor.timing.ended')}</th>
            </tr>
          </thead>
          <tbody>
            {runs.map((r) => (
              <tr key={r.run} data-run={r.run} class={`${r.ended === null ? 'in-progress' : ''} ${r.ended?.startsWith('error') ? 'has-error' : ''}`}>
                <td>{r.run}</td>
                <td>{r.start}</td>
                <td class="mon-run-states">
                  {r.dropped_states > 0 && <span class="muted">{t('monitor.timing.droppedStates', { n: r.dropped_states })} </span>}
                  {r.states.map((x, i) => (
                    <Fragment key={i}>
                      {i > 0 && ' → '}
                      <span class="mon-run-state">
                        {x.state} <span class="muted">{x.time}</span>
                      </span>
                    </Fragment>
                  ))}
                </td>
                <td>{r.total}</td>
                <td>{endText(r.ended)}</td>
              </tr>
            ))}
          </tbody>
        </table>
      )}
      {m.states.length > 0 && (
        <StatsTable
          class="mon-state-stats"
          name={t('monitor.timing.state')}
          count={t('monitor.timing.count')}
          rows={m.states.map((x) => ({ name: x.state, count: x.count, min: x.min, mean: x.mean, max: x.max }))}
        />
      )}
    </div>
  );
}

/** One event as a line of text. */
function eventText(e: Record<string, unknown>): string {
  switch (e.kind) {
    case 'breakpoint':
      return t('monitor.events.breakpoint', { name: String(e.step ?? e.transition) });
    case 'conflict':
      return t('monitor.events.conflict', { step: String(e.step), transitions: ((e.transitions as string[]) ?? []).join(', ') });
    case 'unsafe':
      return t('monitor.events.unsafe', { step: String(e.step) });
    case 'overrun':
      return t('monitor.events.overrun', { us: String(e.scanUs), skipped: String(e.skipped) });
    case 'jump':
      return t('monitor.events.jump', { from: String(e.from), to: String(e.to) });
    default:
      return `${String(e.kind)}: ${String(e.message ?? JSON.stringify(e))}`;
  }
}

export function EventsPanel({ client }: { client: MonitorClient }) {
  if (client.events.length === 0) return <div class="empty">{t('monitor.events.none')}</div>;
  return (
    <ol class="mon-events" reversed>
      {[...client.events].reverse().map((e, i) => (
        <li key={client.events.length - i} class={`mon-event mon-event-${e.kind}`}>
          <span class="muted">{e.scan !== undefined ? t('monitor.events.scan', { scan: e.scan }) : ''}</span> {eventText(e)}
        </li>
      ))}
    </ol>
  );
}
