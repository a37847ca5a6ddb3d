// The Error List panel: counts and filters per severity, one row per diagnostic; a click frames
// the diagnostic's blocks on the canvas; analysis witnesses can be stepped through.
import { useState } from 'preact/hooks';
import type { Diag, Severity } from '../api';
import { currentLanguage, t, diagMessage } from '../i18n';
import { Icon } from './icons';

export interface WitnessView {
  diag: number;
  /** Transitions fired so far (0 … n). */
  step: number;
}

export function ErrorList(props: {
  diagnostics: Diag[];
  selected: number | null;
  onSelect: (index: number) => void;
  highlightOn: boolean;
  onToggleHighlight: () => void;
  witness: WitnessView | null;
  onWitness: (w: WitnessView | null) => void;
  /** Replays a violated requirement's witness in monitor mode. */
  onReplay?: (d: Diag) => void;
  /** The name shown for a block without an element name (a jump, a bar, an action block). */
  blockName?: (id: string) => string;
  /** Diagnostics of the chart's file outside every chart (a TYPE, a POU in ST), listed under
   *  the file after the chart's own; selected as `diagnostics.length + k`. */
  fileDiagnostics?: Diag[];
  fileName?: string;
}) {
  const [shown, setShown] = useState<Record<Severity, boolean>>({ error: true, warning: true, note: true });
  const count = (s: Severity) => props.diagnostics.filter((d) => d.severity === s).length;
  const en = currentLanguage() === 'en';
  const witnessDiag = props.witness ? props.diagnostics[props.witness.diag] : undefined;
  const witnessLength = witnessDiag?.witnessIds?.length ?? 0;
  return (
    <div class="error-list">
      <div class="panel-toolbar">
        {(['error', 'warning', 'note'] as Severity[]).map((s) => (
          <button key={s} class={`toggle ${shown[s] ? 'on' : ''}`} aria-pressed={shown[s]} onClick={() => setShown({ ...shown, [s]: !shown[s] })}>
            <Icon name={s} /> {t(`errors.count.${s}`, { count: count(s) })}
          </button>
        ))}
        <span class="spacer" />
        {props.witness && witnessDiag && (
          <span class="witness-bar">
            <span class="muted">{t('errors.witness', { code: witnessDiag.code })}</span>
            <button class="icon-button" title={t('errors.witnessPrev')} disabled={props.witness.step === 0} onClick={() => props.onWitness({ ...props.witness!, step: props.witness!.step - 1 })}>
              <Icon name="prev" />
            </button>
            <span class="counter">
              {props.witness.step} / {witnessLength}
            </span>
            <button
              class="icon-button"
              title={t('errors.witnessNext')}
              disabled={props.witness.step >= witnessLength}
              onClick={() => props.onWitness({ ...props.witness!, step: props.witness!.step + 1 })}
            >
              <Icon name="next" />
            </button>
            <button class="icon-button" title={t('errors.witnessClose')} onClick={() => props.onWitness(null)}>
              <Icon name="close" />
            </button>
          </span>
        )}
        <button class={`toggle ${props.highlightOn ? 'on' : ''}`} aria-pressed={props.highlightOn} title={t('errors.highlightHint')} onClick={props.onToggleHighlight}>
          <Icon name="highlight" /> {t('errors.highlight')}
        </button>
      </div>
      <div class="table-scroll">
        <table class="grid">
          <thead>
            <tr>
              <th class="col-icon" />
              <th class="col-code">{t('errors.code')}</th>
              <th class="col-element">{t('errors.element')}</th>
              <th>{t('errors.message')}</th>
              <th class="col-line">{t('errors.line')}</th>
              <th class="col-action" />
            </tr>
          </thead>
          <tbody>
            {props.diagnostics.map((d, k) =>
              shown[d.severity] ? (
                <tr key={k} class={`sev-${d.severity} ${props.selected === k ? 'selected' : ''}`} onClick={() => props.onSelect(k)}>
                  <td class="col-icon">
                    <Icon name={d.severity} title={t(`severity.${d.severity}`)} />
                  </td>
                  <td class="col-code">{d.code}</td>
                  <td class="col-element">{d.element ?? (d.elementIds[0] && props.blockName ? props.blockName(d.elementIds[0]) : '')}</td>
                  <td class="col-message" title={en ? d.notes.join('\n') || undefined : d.message}>
                    {diagMessage(d)}
                  </td>
                  <td class="col-line">{d.line > 0 ? `${d.line}:${d.column}` : ''}</td>
                  <td class="col-action">
                    {d.replay && props.onReplay && (
                      <button
                        class="button small"
                        title={t('errors.replayTip')}
                        onClick={(e) => {
                          e.stopPropagation();
                          props.onReplay!(d);
                        }}
                      >
                        <Icon name="witness" /> {t('errors.replay')}
                      </button>
                    )}
                    {d.witnessIds && d.witnessIds.length > 0 && (
                      <button
                        class="button small"
                        onClick={(e) => {
                          e.stopPropagation();
                          props.onWitness({ diag: k, step: 1 });
                        }}
                      >
                        <Icon name="witness" /> {t('errors.showWitness')}
                      </button>
                    )}
                  </td>
                </tr>
              ) : null,
            )}
            {(props.fileDiagnostics ?? []).length > 0 && (
              <tr class="file-scope">
                <td colSpan={6}>{t('errors.fileScope', { file: props.fileName ?? '' })}</td>
              </tr>
            )}
            {(props.fileDiagnostics ?? []).map((d, j) => {
              const k = props.diagnostics.length + j;
              return shown[d.severity] ? (
                <tr key={`f${j}`} class={`sev-${d.severity} in-file ${props.selected === k ? 'selected' : ''}`} onClick={() => props.onSelect(k)}>
                  <td class="col-icon">
                    <Icon name={d.severity} title={t(`severity.${d.severity}`)} />
                  </td>
                  <td class="col-code">{d.code}</td>
                  <td class="col-element">{d.pou ?? ''}</td>
                  <td class="col-message" title={en ? d.notes.join('\n') || undefined : d.message}>
                    {diagMessage(d)}
                  </td>
                  <td class="col-line">{d.line > 0 ? `${d.line}:${d.column}` : ''}</td>
                  <td class="col-action" />
                </tr>
              ) : null;
            })}
          </tbody>
        </table>
        {props.diagnostics.length === 0 && (props.fileDiagnostics ?? []).length === 0 && <div class="empty">{t('errors.none')}</div>}
      </div>
    </div>
  );
}
