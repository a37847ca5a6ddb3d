// The Properties panel: the selected block's fields, or with nothing selected the chart's (POU,
// target, declarations, actions). Every change goes to the canvas as one undoable command.
import type { ComponentChildren } from 'preact';
import { useEffect, useState } from 'preact/hooks';
import type { Diag } from '../api';
import type { CanvasHandle } from '../diagram/types';
import type { ActionDef, Association, Connection, EditorDoc, Element, Language } from '../doc';
import { t, diagMessage } from '../i18n';
import { freshName, isIecName, stepNames } from './chart';
import { isStepActionName, stepActionsOf, withStepAction, type StepActionKind } from './actionCharts';
import { CHART_KINDS, chartKind, kindFields, type ChartKind } from './chartKind';
import { CodeEditor } from './CodeEditor';
import { parseDuration, secondsToLiteral } from './duration';
import { Icon } from './icons';

export const QUALIFIERS = ['N', 'R', 'S', 'L', 'D', 'P', 'P0', 'P1', 'SD', 'DS', 'SL'];
/** Qualifiers that need a duration. */
export const TIMED_QUALIFIERS = new Set(['L', 'D', 'SD', 'DS', 'SL']);

const BRANCH_KINDS = new Set(['selectionDivergence', 'selectionConvergence', 'simultaneousDivergence', 'simultaneousConvergence']);

/** Diagnostics that concern a block (by id, or by the step/transition/action name). */
export function diagnosticsOf(diags: Diag[], id: string, name: string | undefined): Diag[] {
  const lower = name?.toLowerCase();
  return diags.filter((d) => d.elementIds.includes(id) || (lower !== undefined && lower !== '' && d.element?.toLowerCase() === lower));
}

/** Diagnostics of the declarations: those that name no element. */
export function declarationDiagnostics(diags: Diag[]): Diag[] {
  return diags.filter((d) => d.element === null && d.elementIds.length === 0);
}

/** A timeout as the user typed it: an IEC duration, or seconds as the seed writes them (`8.1`). */
export function normaliseTimeout(input: string): { value?: string; error?: string } {
  const text = input.trim();
  if (text === '') return {};
  if (/^\d+(\.\d+)?$/.test(text)) return { value: secondsToLiteral(Number(text)) };
  const r = parseDuration(text);
  if (!r.ok) return { error: r.error };
  if (r.micros < 0) return { error: 'duration.negative' };
  return { value: text };
}

interface PanelProps {
  doc: EditorDoc;
  selection: string[];
  canvas: CanvasHandle;
  diagnostics: Diag[];
  /** Checks the document with a pending code edit (debounced by the editor). */
  onDraft: (doc: EditorDoc) => void;
  /** Host mode: the chart's target is fixed. */
  targetFixed: boolean;
  /** The chart shown is that of this action written in SFC (null: the POU's). */
  action?: string | null;
  /** The POU's actions (an action's chart names them; its own document lists none). */
  pouActions?: ActionDef[];
  /** The actions whose charts are open in the tab (their names cannot change meanwhile). */
  openViews?: string[];
  /** Shows the chart of an action written in SFC. */
  onOpenAction?: (name: string) => void;
}

/** The actions the blocks of the shown chart may name: the POU's. */
function actionsFor(props: PanelProps): ActionDef[] {
  return props.action ? props.pouActions ?? [] : props.doc.actions;
}

function Field(props: { label: string; children: ComponentChildren; error?: string; for?: string; hint?: string }) {
  return (
    <div class="prop-row">
      <label for={props.for} title={props.hint}>
        {props.label}
      </label>
      <div class="prop-value">
        {props.children}
        {props.error && <div class="field-error">{props.error}</div>}
      </div>
    </div>
  );
}

function Section(props: { title: string; children: ComponentChildren }) {
  return (
    <section class="prop-section">
      <h3>{props.title}</h3>
      {props.children}
    </section>
  );
}

/** A text input that commits on change (Enter or blur), with an optional check. */
function TextInput(props: {
  id?: string;
  value: string;
  onCommit: (v: string) => void;
  validate?: (v: string) => string | undefined;
  placeholder?: string;
  list?: string;
}) {
  const [draft, setDraft] = useState(props.value);
  useEffect(() => setDraft(props.value), [props.value]);
  const error = props.validate?.(draft);
  return (
    <>
      <input
        id={props.id}
        list={props.list}
        class={error ? 'invalid' : ''}
        value={draft}
        placeholder={props.placeholder}
        onInput={(e) => setDraft(e.currentTarget.value)}
        onChange={(e) => {
          const v = e.currentTarget.value;
          if (!props.validate?.(v) && v !== props.value) props.onCommit(v);
        }}
      />
      {error && <div class="field-error">{error}</div>}
    </>
  );
}

function NumberInput(props: { id?: string; value: number | undefined; min?: number; step?: number; integer?: boolean; onCommit: (v: number | undefined) => void; allowEmpty?: boolean }) {
  const [draft, setDraft] = useState(props.value === undefined ? '' : String(props.value));
  useEffect(() => setDraft(props.value === undefined ? '' : String(props.value)), [props.value]);
  const parse = (s: string): { v?: number; error?: string } => {
    if (s.trim() === '') return props.allowEmpty ? {} : { error: t('props.required') };
    const v = Number(s);
    if (!Number.isFinite(v)) return { error: t('props.notNumber') };
    if (props.integer && !Number.isInteger(v)) return { error: t('props.notInteger') };
    if (props.min !== undefined && v < props.min) return { error: t('props.atLeast', { min: props.min }) };
    return { v };
  };
  const { error } = parse(draft);
  return (
    <>
      <input
        id={props.id}
        type="number"
        class={error ? 'invalid' : ''}
        min={props.min}
        step={props.step ?? 1}
        value={draft}
        onInput={(e) => setDraft(e.currentTarget.value)}
        onChange={(e) => {
          const r = parse(e.currentTarget.value);
          if (!r.error && r.v !== props.value) props.onCommit(r.v);
        }}
      />
      {error && <div class="field-error">{error}</div>}
    </>
  );
}

function ColourInput(props: { value: string | undefined; fallback: string; onCommit: (v: string | undefined) => void; label: string }) {
  return (
    <div class="colour-input">
      <input type="color" aria-label={props.label} value={props.value ?? props.fallback} disabled={props.value === undefined} onChange={(e) => props.onCommit(e.currentTarget.value)} />
      <label class="inline-check">
        <input type="checkbox" checked={props.value === undefined} onChange={(e) => props.onCommit(e.currentTarget.checked ? undefined : props.fallback)} />
        {t('props.none')}
      </label>
    </div>
  );
}

export function PropertiesPanel(props: PanelProps) {
  const { doc, selection } = props;
  const elements = doc.elements.filter((e) => selection.includes(e.id));
  const connections = doc.connections.filter((c) => selection.includes(c.id));
  if (elements.length === 0 && connections.length === 0) return <ChartProperties {...props} />;
  if (elements.length + connections.length > 1) return <MultiProperties {...props} elements={elements} />;
  // Keyed by the block: another block's fields start from its own values in the render that
  // shows it (a draft reset by an effect comes a frame later and would wipe what was typed first).
  if (connections.length === 1) return <ConnectionProperties key={connections[0].id} canvas={props.canvas} connection={connections[0]} />;
  return <ElementProperties key={elements[0].id} {...props} element={elements[0]} />;
}

function MultiProperties(props: PanelProps & { elements: Element[] }) {
  const common = (f: 'x' | 'y') => (props.elements.every((e) => e[f] === props.elements[0]?.[f]) ? props.elements[0]?.[f] : undefined);
  const move = (f: 'x' | 'y', v: number | undefined) => {
    if (v === undefined) return;
    for (const e of props.elements) props.canvas.updateElement(e.id, { [f]: v });
  };
  return (
    <div class="properties">
      <div class="prop-heading">{t('props.multi', { count: props.selection.length })}</div>
      <Section title={t('props.layout')}>
        <Field label={t('props.x')} for="p-x">
          <NumberInput id="p-x" value={common('x')} allowEmpty onCommit={(v) => move('x', v)} />
        </Field>
        <Field label={t('props.y')} for="p-y">
          <NumberInput id="p-y" value={common('y')} allowEmpty onCommit={(v) => move('y', v)} />
        </Field>
      </Section>
    </div>
  );
}

function ConnectionProperties(props: { canvas: CanvasHandle; connection: Connection }) {
  const c = props.connection;
  const set = (p: Partial<Connection>) => props.canvas.updateElement(c.id, p as Record<string, unknown>);
  return (
    <div class="properties">
      <div class="prop-heading">{t('props.connection')}</div>
      <Section title={t('props.appearance')}>
        <Field label={t('props.lineColour')}>
          <ColourInput label={t('props.lineColour')} value={c.color} fallback="#000000" onCommit={(v) => set({ color: v })} />
        </Field>
        <Field label={t('props.lineWidth')} for="p-lw">
          <NumberInput id="p-lw" value={c.lineWidth} min={0.5} step={0.5} allowEmpty onCommit={(v) => set({ lineWidth: v })} />
        </Field>
      </Section>
    </div>
  );
}

function ElementProperties(props: PanelProps & { element: Element }) {
  const { element: e, doc, canvas } = props;
  const set = (p: Partial<Element>) => canvas.updateElement(e.id, p as Record<string, unknown>);
  const diags = diagnosticsOf(props.diagnostics, e.id, e.name);
  const isStep = e.kind === 'step';
  const isTransition = e.kind === 'transition';
  const named = isStep || isTransition;
  const otherNames = new Set(
    [...doc.elements.filter((x) => x.id !== e.id && x.name).map((x) => x.name!), ...actionsFor(props).map((a) => a.name)].map((n) => n.toLowerCase()),
  );
  const nameError = (v: string) => {
    if (v === '' && isTransition) return undefined;
    if (!isIecName(v)) return t('props.invalidName');
    if (otherNames.has(v.toLowerCase())) return t('props.nameTaken');
    return undefined;
  };
  const [timeoutDraft, setTimeoutDraft] = useState(e.timeout ?? '');
  useEffect(() => setTimeoutDraft(e.timeout ?? ''), [e.id, e.timeout]);
  const timeoutCheck = normaliseTimeout(timeoutDraft);
  const actionBlock = isStep ? doc.elements.find((x) => x.kind === 'actionBlock' && x.step === e.id) : e.kind === 'actionBlock' ? e : undefined;
  const owner = e.kind === 'actionBlock' ? doc.elements.find((x) => x.id === e.step) : undefined;

  return (
    <div class="properties">
      <div class="prop-heading">
        <span class="kind-badge">{t(`kind.${e.kind}`)}</span>
        {/* Unnamed blocks: a jump by its target, an action block by its step, others by id. */}
        <span title={e.id}>{e.name || (e.kind === 'jump' ? `→ ${e.target ?? '?'}` : owner?.name ?? e.id)}</span>
      </div>
      {diags.length > 0 && (
        <ul class="inline-diagnostics">
          {diags.map((d, k) => (
            <li key={k} class={`sev-${d.severity}`} title={d.message}>
              <Icon name={d.severity} />
              <span class="diag-code">{d.code}</span>
              {/* In Czech and German the code's translated title; the English message is the tooltip. */}
              <span>{diagMessage(d)}</span>
            </li>
          ))}
        </ul>
      )}
      <Section title={t('props.general')}>
        {named && (
          <Field label={t('props.name')} for="p-name" hint={t('props.nameHint')}>
            <TextInput id="p-name" value={e.name ?? ''} validate={nameError} onCommit={(v) => set({ name: v })} />
          </Field>
        )}
        {named && (
          <Field label={t('props.tag')} for="p-tag" hint={t('props.tagHint')}>
            <NumberInput id="p-tag" value={e.tag} min={0} integer allowEmpty onCommit={(v) => set({ tag: v })} />
          </Field>
        )}
        <Field label={t('props.description')} for="p-desc" hint={t('props.descriptionHint')}>
          <DescriptionInput id="p-desc" value={e.description ?? ''} onCommit={(v) => set({ description: v })} />
        </Field>
      </Section>

      {isStep && (
        <Section title={t('props.special')}>
          <Field label={t('props.initial')}>
            <input type="checkbox" checked={!!e.initial} onChange={(ev) => set({ initial: ev.currentTarget.checked })} />
          </Field>
          <Field label={t('props.final')} hint={t('props.finalHint')}>
            <input type="checkbox" checked={!!e.final} onChange={(ev) => set({ final: ev.currentTarget.checked })} />
          </Field>
          <Field label={t('props.timeout')} for="p-timeout" hint={t('props.timeoutHint')} error={timeoutCheck.error ? t(timeoutCheck.error) : undefined}>
            <input
              id="p-timeout"
              class={timeoutCheck.error ? 'invalid' : ''}
              placeholder="T#8.1s"
              value={timeoutDraft}
              onInput={(ev) => setTimeoutDraft(ev.currentTarget.value)}
              onChange={(ev) => {
                const r = normaliseTimeout(ev.currentTarget.value);
                if (r.error) return;
                if (r.value !== e.timeout) set({ timeout: r.value });
                setTimeoutDraft(r.value ?? '');
              }}
            />
          </Field>
        </Section>
      )}

      {isStep && <StepActions step={e} actions={actionsFor(props)} onCommit={(stepActions) => set({ stepActions })} />}

      {isTransition && (
        <Section title={t('props.condition')}>
          <Field label={t('props.language')} for="p-lang">
            <select id="p-lang" value={e.conditionLanguage ?? 'ST'} onChange={(ev) => set({ conditionLanguage: ev.currentTarget.value as Language })}>
              <option value="ST">ST</option>
              <option value="IL">IL</option>
            </select>
          </Field>
          <CodeEditor
            key={e.id}
            label={t('props.condition')}
            language={e.conditionLanguage ?? 'ST'}
            value={e.condition ?? ''}
            rows={e.conditionLanguage === 'IL' ? 4 : 2}
            diagnostics={diags}
            onDraft={(v) => props.onDraft(withElement(doc, e.id, { condition: v }))}
            onCommit={(v) => set({ condition: v })}
          />
          <Field label={t('props.priority')} for="p-prio" hint={t('props.priorityHint')}>
            <NumberInput id="p-prio" value={e.priority} min={0} integer allowEmpty onCommit={(v) => set({ priority: v })} />
          </Field>
        </Section>
      )}

      {BRANCH_KINDS.has(e.kind) && (
        <Section title={t('props.special')}>
          <Field label={e.kind.endsWith('Divergence') ? t('props.outputs') : t('props.inputs')} for="p-pins">
            <NumberInput id="p-pins" value={e.pins ?? 2} min={2} integer onCommit={(v) => v !== undefined && set({ pins: v })} />
          </Field>
        </Section>
      )}

      {e.kind === 'jump' && (
        <Section title={t('props.special')}>
          <Field label={t('props.jumpTarget')} for="p-jump">
            <select id="p-jump" value={e.target ?? ''} onChange={(ev) => set({ target: ev.currentTarget.value || undefined })}>
              <option value="">{t('props.noTarget')}</option>
              {stepNames(doc).map((n) => (
                <option key={n} value={n}>
                  {n}
                </option>
              ))}
            </select>
          </Field>
        </Section>
      )}

      {e.kind === 'text' && (
        <Section title={t('props.text')}>
          <Field label={t('props.text')} for="p-text">
            <DescriptionInput id="p-text" value={e.text ?? ''} onCommit={(v) => set({ text: v })} />
          </Field>
          <Field label={t('props.align')} for="p-align">
            <select id="p-align" value={e.align ?? 'left'} onChange={(ev) => set({ align: ev.currentTarget.value as Element['align'] })}>
              <option value="left">{t('props.alignLeft')}</option>
              <option value="center">{t('props.alignCenter')}</option>
              <option value="right">{t('props.alignRight')}</option>
            </select>
          </Field>
          <Field label={t('props.font')} for="p-font" hint={t('props.fontHint')}>
            <TextInput id="p-font" value={e.font ?? ''} placeholder="12px system-ui" onCommit={(v) => set({ font: v || undefined })} />
          </Field>
        </Section>
      )}

      {(actionBlock || isStep) && (
        <Section title={owner?.name ? t('props.actionsOf', { step: owner.name }) : t('props.associations')}>
          {actionBlock ? (
            <AssociationTable doc={doc} actions={actionsFor(props)} block={actionBlock} canvas={canvas} />
          ) : (
            <div class="muted small">{t('props.noActionBlock')}</div>
          )}
        </Section>
      )}

      <Section title={t('props.layout')}>
        <Field label={t('props.position')} for="p-pos-x">
          <div class="pair">
            <NumberInput id="p-pos-x" value={e.x} onCommit={(v) => v !== undefined && set({ x: v })} />
            <NumberInput id="p-pos-y" value={e.y} onCommit={(v) => v !== undefined && set({ y: v })} />
          </div>
        </Field>
        {!isTransition && (
          <Field label={t('props.size')} for="p-size-w">
            <div class="pair">
              <NumberInput id="p-size-w" value={e.w} min={1} onCommit={(v) => v !== undefined && set({ w: v })} />
              <NumberInput id="p-size-h" value={e.h} min={1} onCommit={(v) => v !== undefined && set({ h: v })} />
            </div>
          </Field>
        )}
      </Section>

      <Section title={t('props.appearance')}>
        <Field label={t('props.background')}>
          <ColourInput label={t('props.background')} value={e.background} fallback="#ffffff" onCommit={(v) => set({ background: v })} />
        </Field>
        <Field label={t('props.foreground')}>
          <ColourInput label={t('props.foreground')} value={e.foreground} fallback="#000000" onCommit={(v) => set({ foreground: v })} />
        </Field>
        {e.kind !== 'text' && (
          <Field label={t('props.lineWidth')} for="p-elw">
            <NumberInput id="p-elw" value={e.lineWidth} min={0.5} step={0.5} allowEmpty onCommit={(v) => set({ lineWidth: v })} />
          </Field>
        )}
        {(isTransition || e.kind === 'jump' || isStep) && (
          <Field label={t('props.hideLabel')}>
            <input type="checkbox" checked={!!e.hideLabel} onChange={(ev) => set({ hideLabel: ev.currentTarget.checked })} />
          </Field>
        )}
      </Section>
    </div>
  );
}

/** `doc` with one element's fields replaced (for checking a pending edit). */
function withElement(doc: EditorDoc, id: string, patch: Partial<Element>): EditorDoc {
  return { ...doc, elements: doc.elements.map((x) => (x.id === id ? { ...x, ...patch } : x)) };
}

function DescriptionInput(props: { id?: string; value: string; onCommit: (v: string) => void }) {
  const [draft, setDraft] = useState(props.value);
  useEffect(() => setDraft(props.value), [props.value]);
  return (
    <textarea
      id={props.id}
      rows={Math.min(6, Math.max(2, draft.split('\n').length))}
      value={draft}
      onInput={(e) => setDraft(e.currentTarget.value)}
      onChange={(e) => e.currentTarget.value !== props.value && props.onCommit(e.currentTarget.value)}
    />
  );
}

/** CODESYS's step actions of a step: entry, step (main) and exit action, each an action of the
 *  POU or `instance.Action`; empty removes it. */
function StepActions(props: { step: Element; actions: ActionDef[]; onCommit: (list: string[]) => void }) {
  const now = stepActionsOf(props.step);
  const listId = `step-actions-${props.step.id}`;
  const row = (kind: StepActionKind) => (
    <Field label={t(`props.stepAction.${kind}`)} for={`p-sa-${kind}`} hint={t(`props.stepAction.${kind}Hint`)}>
      <TextInput
        id={`p-sa-${kind}`}
        list={listId}
        value={now[kind] ?? ''}
        placeholder={t('props.stepAction.none')}
        validate={(v) => (isStepActionName(v) ? undefined : t('props.stepAction.invalid'))}
        onCommit={(v) => props.onCommit(withStepAction(props.step, kind, v))}
      />
    </Field>
  );
  return (
    <Section title={t('props.stepActions')}>
      <datalist id={listId}>
        {props.actions.map((a) => (
          <option key={a.name} value={a.name} />
        ))}
      </datalist>
      {row('entry')}
      {row('main')}
      {row('exit')}
    </Section>
  );
}

function AssociationTable(props: { doc: EditorDoc; actions: ActionDef[]; block: Element; canvas: CanvasHandle }) {
  const rows = props.block.associations ?? [];
  const commit = (next: Association[]) => props.canvas.updateElement(props.block.id, { associations: next });
  const change = (k: number, patch: Partial<Association>) => {
    const next = rows.map((r, i) => (i === k ? { ...r, ...patch } : r));
    const row = next[k];
    if (!TIMED_QUALIFIERS.has(row.qualifier)) delete row.duration;
    commit(next);
  };
  const move = (k: number, by: number) => {
    const next = [...rows];
    const [row] = next.splice(k, 1);
    next.splice(k + by, 0, row);
    commit(next);
  };
  const listId = `actions-${props.block.id}`;
  // The duration column only when a row needs one, so the action names get the room.
  const anyTimed = rows.some((r) => TIMED_QUALIFIERS.has(r.qualifier));
  return (
    <div class="assoc">
      <datalist id={listId}>
        {props.actions.map((a) => (
          <option key={a.name} value={a.name} />
        ))}
      </datalist>
      <table class="assoc-table">
        <thead>
          <tr>
            <th class="col-qualifier" title={t('props.qualifier')}>{t('props.qualifierHead')}</th>
            {anyTimed && <th class="col-duration" title={t('props.duration')}>{t('props.duration')}</th>}
            <th class="col-action" title={t('props.action')}>{t('props.action')}</th>
            <th class="col-indicator" title={t('props.indicator')}>{t('props.indicatorHead')}</th>
            <th class="col-buttons" />
          </tr>
        </thead>
        <tbody>
          {rows.map((r, k) => {
            const timed = TIMED_QUALIFIERS.has(r.qualifier);
            const durationError = timed ? durationProblem(r.duration ?? '') : undefined;
            return (
              <tr key={k}>
                <td>
                  <select aria-label={t('props.qualifier')} value={r.qualifier} onChange={(e) => change(k, { qualifier: e.currentTarget.value })}>
                    {QUALIFIERS.map((q) => (
                      <option key={q} value={q}>
                        {q}
                      </option>
                    ))}
                  </select>
                </td>
                {anyTimed && (
                  <td>
                    {timed && (
                      <input
                        aria-label={t('props.duration')}
                        class={durationError ? 'invalid' : ''}
                        title={durationError}
                        placeholder="T#1s"
                        value={r.duration ?? ''}
                        onChange={(e) => change(k, { duration: e.currentTarget.value.trim() || undefined })}
                      />
                    )}
                  </td>
                )}
                <td>
                  <input aria-label={t('props.action')} list={listId} value={r.action} onChange={(e) => change(k, { action: e.currentTarget.value.trim() })} />
                </td>
                <td>
                  <input aria-label={t('props.indicator')} value={r.indicator ?? ''} onChange={(e) => change(k, { indicator: e.currentTarget.value.trim() || undefined })} />
                </td>
                <td class="row-buttons">
                  <button class="icon-button" title={t('props.moveUp')} disabled={k === 0} onClick={() => move(k, -1)}>
                    <Icon name="up" />
                  </button>
                  <button class="icon-button" title={t('props.moveDown')} disabled={k === rows.length - 1} onClick={() => move(k, 1)}>
                    <Icon name="down" />
                  </button>
                  <button class="icon-button" title={t('props.removeRow')} onClick={() => commit(rows.filter((_, i) => i !== k))}>
                    <Icon name="delete" />
                  </button>
                </td>
              </tr>
            );
          })}
        </tbody>
      </table>
      <button class="button small" onClick={() => commit([...rows, { qualifier: 'N', action: props.actions[0]?.name ?? '' }])}>
        <Icon name="plus" /> {t('props.addRow')}
      </button>
    </div>
  );
}

/** A timed qualifier's duration: a literal is checked; a TIME variable name is accepted. */
function durationProblem(value: string): string | undefined {
  const v = value.trim();
  if (v === '') return t('props.durationRequired');
  if (/^[A-Za-z_][A-Za-z0-9_.]*$/.test(v) && !/^(T|TIME)#/i.test(v)) return undefined;
  const r = parseDuration(v);
  return r.ok ? undefined : t(r.error);
}

/** With nothing selected in an action's chart: which action of which POU it is. */
function ActionChartProperties(props: PanelProps) {
  const { doc } = props;
  const def = (props.pouActions ?? []).find((a) => a.name.toLowerCase() === props.action?.toLowerCase());
  return (
    <div class="properties">
      <div class="prop-heading">
        <span class="kind-badge">{t('props.sfcAction')}</span>
        <span>
          {doc.pou}.{props.action}
        </span>
      </div>
      <Section title={t('props.general')}>
        <Field label={t('props.pouName')}>
          <span class="readonly">{doc.pou}</span>
        </Field>
        <Field label={t('props.action')}>
          <span class="readonly">{props.action}</span>
        </Field>
        {def?.description && (
          <Field label={t('props.description')}>
            <span class="readonly">{def.description}</span>
          </Field>
        )}
      </Section>
      <div class="muted small">{t('props.sfcActionHint')}</div>
    </div>
  );
}

function ChartProperties(props: PanelProps) {
  if (props.action) return <ActionChartProperties {...props} />;
  const { doc, canvas } = props;
  const opened = new Set((props.openViews ?? []).map((v) => v.toLowerCase()));
  const setActions = (actions: ActionDef[]) => canvas.updateDoc({ actions });
  const rename = (k: number, name: string) => {
    const old = doc.actions[k].name;
    setActions(doc.actions.map((a, i) => (i === k ? { ...a, name } : a)));
    // Associations follow the renamed action.
    for (const b of doc.elements) {
      if (b.kind === 'actionBlock' && (b.associations ?? []).some((r) => r.action.toLowerCase() === old.toLowerCase())) {
        canvas.updateElement(b.id, {
          associations: b.associations!.map((r) => (r.action.toLowerCase() === old.toLowerCase() ? { ...r, action: name } : r)),
        });
      }
    }
  };
  const taken = (v: string, except: number) =>
    doc.actions.some((a, i) => i !== except && a.name.toLowerCase() === v.toLowerCase()) ||
    doc.elements.some((e) => e.name && e.name.toLowerCase() === v.toLowerCase());
  return (
    <div class="properties">
      <div class="prop-heading">
        <span class="kind-badge">{t('props.chart')}</span>
        <span>{doc.pou}</span>
      </div>
      <Section title={t('props.general')}>
        <Field label={t('props.pouName')} for="p-pou">
          <TextInput id="p-pou" value={doc.pou} validate={(v) => (isIecName(v) ? undefined : t('props.invalidName'))} onCommit={(v) => canvas.updateDoc({ pou: v })} />
        </Field>
        <Field label={t('props.pouKind')}>
          <span class="readonly">{t(`pouKind.${doc.pouKind}`)}</span>
        </Field>
        <Field label={t('props.target')} for="p-target">
          <select id="p-target" value={chartKind(doc)} disabled={props.targetFixed} onChange={(e) => canvas.updateDoc(kindFields(doc, e.currentTarget.value as ChartKind))}>
            {CHART_KINDS.map((k) => (
              <option key={k} value={k}>
                {t(`target.${k}`)}
              </option>
            ))}
          </select>
        </Field>
        <Field label={t('props.description')} for="p-cdesc">
          <DescriptionInput id="p-cdesc" value={doc.description ?? ''} onCommit={(v) => canvas.updateDoc({ description: v })} />
        </Field>
      </Section>
      <Section title={t('props.declarations')}>
        <CodeEditor
          label={t('props.declarations')}
          language="ST"
          value={doc.declarations}
          rows={5}
          diagnostics={declarationDiagnostics(props.diagnostics)}
          onDraft={(v) => props.onDraft({ ...doc, declarations: v })}
          onCommit={(v) => canvas.updateDoc({ declarations: v })}
        />
      </Section>
      {doc.body !== undefined && (
        <Section title={t('props.body', { language: doc.bodyLanguage ?? 'ST' })}>
          <Field label={t('props.language')} for="p-body-lang">
            <select id="p-body-lang" value={doc.bodyLanguage ?? 'ST'} onChange={(e) => canvas.updateDoc({ bodyLanguage: e.currentTarget.value as Language })}>
              <option value="ST">ST</option>
              <option value="IL">IL</option>
            </select>
          </Field>
          <CodeEditor
            label={t('props.body', { language: doc.bodyLanguage ?? 'ST' })}
            language={doc.bodyLanguage ?? 'ST'}
            value={doc.body}
            rows={6}
            diagnostics={[]}
            onDraft={(v) => props.onDraft({ ...doc, body: v })}
            onCommit={(v) => canvas.updateDoc({ body: v })}
          />
        </Section>
      )}
      <Section title={t('props.actions')}>
        {doc.actions.length === 0 && <div class="muted small">{t('props.noActions')}</div>}
        {doc.actions.map((a, k) => (
          <div class="action-def" key={`${k}:${a.name}`}>
            <div class="action-head">
              <TextInput
                value={a.name}
                validate={(v) =>
                  a.chart && opened.has(a.name.toLowerCase()) && v.toLowerCase() !== a.name.toLowerCase()
                    ? t('props.chartOpen')
                    : !isIecName(v)
                      ? t('props.invalidName')
                      : taken(v, k)
                        ? t('props.nameTaken')
                        : undefined
                }
                onCommit={(v) => rename(k, v)}
              />
              {a.chart ? (
                <span class="chart-view-kind" title={t('props.sfcAction')}>SFC</span>
              ) : (
                <select aria-label={t('props.language')} value={a.language ?? 'ST'} onChange={(e) => setActions(doc.actions.map((x, i) => (i === k ? { ...x, language: e.currentTarget.value as Language } : x)))}>
                  <option value="ST">ST</option>
                  <option value="IL">IL</option>
                </select>
              )}
              <button
                class="icon-button"
                title={t('props.deleteAction')}
                disabled={!!a.chart && opened.has(a.name.toLowerCase())}
                onClick={() => setActions(doc.actions.filter((_, i) => i !== k))}
              >
                <Icon name="delete" />
              </button>
            </div>
            {a.chart ? (
              <button class="button small open-action-chart" data-action={a.name} onClick={() => props.onOpenAction?.(a.name)}>
                {t('props.openChart', { name: a.name })}
              </button>
            ) : (
            <CodeEditor
              label={t('props.actionBody', { name: a.name })}
              language={a.language ?? 'ST'}
              value={a.body}
              rows={3}
              diagnostics={props.diagnostics.filter((d) => d.element?.toLowerCase() === a.name.toLowerCase())}
              onDraft={(v) => props.onDraft({ ...doc, actions: doc.actions.map((x, i) => (i === k ? { ...x, body: v } : x)) })}
              onCommit={(v) => setActions(doc.actions.map((x, i) => (i === k ? { ...x, body: v } : x)))}
            />
            )}
          </div>
        ))}
        <button
          class="button small"
          onClick={() => setActions([...doc.actions, { name: freshName(doc, 'Action'), language: 'ST', body: '' }])}
        >
          <Icon name="plus" /> {t('props.addAction')}
        </button>
      </Section>
    </div>
  );
}
