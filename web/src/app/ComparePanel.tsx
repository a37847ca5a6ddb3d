// The Comparison panel (File → Compare with saved / git HEAD): what the chart on the canvas
// changed against its saved file or git HEAD, by meaning. One row per change; a click selects
// its blocks on the canvas (coloured there: added green, renamed or changed orange). Removed
// elements have no block: they are listed last. "Close comparison" clears the colours.
import type { CompareResult } from '../api';
import { t } from '../i18n';
import { changeDetail, changeRows, compareCounts, elementLabel, type ChangeRow } from './compare';
import { Icon } from './icons';

export function ComparePanel(props: {
  result: CompareResult;
  /** The row whose blocks are selected, if any. */
  selected: number | null;
  onSelect: (index: number, row: ChangeRow) => void;
  onClose: () => void;
}) {
  const r = props.result;
  const rows = changeRows(r);
  const counts = compareCounts(r);
  const against = r.against === 'head' ? t('compare.withHead', { file: r.file }) : t('compare.withSaved', { file: r.file });
  return (
    <div class="error-list compare-panel" data-testid="compare-panel">
      <div class="panel-toolbar">
        <span class="muted compare-against" title={r.file}>
          {against}
        </span>
        <span class="spacer" />
        {!r.equal && (
          <span class="compare-counts">
            <span class="compare-count added">+{counts.added}</span>
            <span class="compare-count changed">~{counts.changed}</span>
            <span class="compare-count removed">−{counts.removed}</span>
          </span>
        )}
        <span class="muted">{t('compare.layout', { count: r.layout })}</span>
        <button class="button small" onClick={props.onClose}>
          <Icon name="close" /> {t('compare.close')}
        </button>
      </div>
      {r.notes.map((n, k) => (
        <div key={k} class="compare-note muted">
          {n}
        </div>
      ))}
      <div class="table-scroll">
        {r.equal ? (
          <div class="empty compare-equal" role="status">
            {t('compare.equal')} — {t('compare.layout', { count: r.layout })}
          </div>
        ) : (
          <table class="grid">
            <thead>
              <tr>
                <th class="col-icon" />
                <th class="col-element">{t('compare.col.element')}</th>
                <th class="col-element">{t('compare.col.name')}</th>
                <th>{t('compare.col.change')}</th>
              </tr>
            </thead>
            <tbody>
              {rows.map((row, k) => (
                <tr
                  key={k}
                  class={`compare-row compare-${row.change.kind} ${props.selected === k ? 'selected' : ''} ${row.onCanvas ? 'on-canvas' : ''}`}
                  data-element={row.change.element}
                  data-name={row.name}
                  title={row.change.kind === 'removed' ? t('compare.notOnCanvas') : (row.change.new ?? undefined)}
                  onClick={() => props.onSelect(k, row)}
                >
                  <td class="col-icon compare-mark">{row.mark}</td>
                  <td class="col-element">{elementLabel(row.change.element, t)}</td>
                  <td class="col-element">{row.name}</td>
                  <td class="col-message">{changeDetail(row.change, t)}</td>
                </tr>
              ))}
            </tbody>
          </table>
        )}
      </div>
    </div>
  );
}
