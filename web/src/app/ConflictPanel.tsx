// The Merge conflicts panel: the conflicts `sfc merge` marked the chart's POU with (its
// `sfc.conflict` attributes), one row each: the element, its name, their version of it, and
// "Keep ours" / "Take theirs" (POST /api/resolve; the tab then holds the resolved chart as an
// unsaved edit). A click on a row selects its blocks (framed red-orange on the canvas).
import { t } from '../i18n';
import { conflictKindLabel, theirText, type MergeConflict } from './conflicts';

export function ConflictPanel(props: {
  conflicts: MergeConflict[];
  /** Whether each conflict has blocks on the canvas (a click selects them). */
  onCanvas: (c: MergeConflict) => boolean;
  /** The row whose blocks are selected, if any. */
  selected: number | null;
  /** A resolution is under way: the buttons wait. */
  busy: boolean;
  onSelect: (index: number, c: MergeConflict) => void;
  onResolve: (c: MergeConflict, side: 'ours' | 'theirs') => void;
}) {
  const n = props.conflicts.length;
  return (
    <div class="error-list compare-panel conflict-panel" data-testid="conflict-panel">
      <div class="panel-toolbar">
        <span class={`conflict-count ${n > 0 ? 'open' : 'done'}`} role="status">
          {n > 0 ? t('merge.left', { count: n }) : t('merge.none')}
        </span>
        <span class="spacer" />
        {n > 0 && <span class="muted conflict-hint">{t('merge.hint')}</span>}
      </div>
      <div class="table-scroll">
        {n === 0 ? (
          <div class="empty conflict-none">{t('merge.noneHint')}</div>
        ) : (
          <table class="grid">
            <thead>
              <tr>
                <th class="col-element">{t('compare.col.element')}</th>
                <th class="col-element">{t('compare.col.name')}</th>
                <th>{t('merge.col.theirs')}</th>
                <th class="col-resolve" />
              </tr>
            </thead>
            <tbody>
              {props.conflicts.map((c, k) => (
                <tr
                  key={`${c.element}#${k}`}
                  class={`conflict-row ${props.selected === k ? 'selected' : ''} ${props.onCanvas(c) ? 'on-canvas' : ''}`}
                  data-element={c.element}
                  data-name={c.name}
                  onClick={() => props.onSelect(k, c)}
                >
                  <td class="col-element">
                    <span class="conflict-mark">!</span> {conflictKindLabel(c, t)}
                  </td>
                  <td class="col-element">{c.name}</td>
                  <td class="col-message">
                    {c.theirs.trim() === '' ? (
                      <span class="muted">{t('merge.removedByThem')}</span>
                    ) : (
                      <pre class="conflict-theirs">{theirText(c.theirs)}</pre>
                    )}
                  </td>
                  <td class="col-resolve">
                    <button
                      class="button small"
                      data-side="ours"
                      disabled={props.busy}
                      title={t('merge.oursHint')}
                      onClick={(e) => {
                        e.stopPropagation();
                        props.onResolve(c, 'ours');
                      }}
                    >
                      {t('merge.ours')}
                    </button>{' '}
                    <button
                      class="button small primary"
                      data-side="theirs"
                      disabled={props.busy}
                      title={t('merge.theirsHint')}
                      onClick={(e) => {
                        e.stopPropagation();
                        props.onResolve(c, 'theirs');
                      }}
                    >
                      {t('merge.theirs')}
                    </button>
                  </td>
                </tr>
              ))}
            </tbody>
          </table>
        )}
      </div>
    </div>
  );
}
