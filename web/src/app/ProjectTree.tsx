// The project tree (issue 36): a file of several POUs lists them on the left, with their actions
// and transitions; a click opens the chart (or the action's chart), the one shown is highlighted.
import type { PouEntry } from '../api';
import type { EditorDoc } from '../doc';
import { t } from '../i18n';
import { Icon } from './icons';
import { problemCounts, projectTree, type TreeNode } from './project';
import type { Diag } from '../api';

export function ProjectTree(props: {
  file: string;
  pous: PouEntry[];
  /** The documents of the POUs open now, by POU name. */
  live: (pou: string) => EditorDoc | undefined;
  /** The whole file's diagnostics, for the counts of each POU. */
  diagnostics: Diag[];
  /** The POU and view shown (view: an action's name, null for the POU's chart). */
  activePou: string | null;
  activeView: string | null;
  onOpen: (node: TreeNode) => void;
  onCollapse: () => void;
}) {
  const rows = projectTree(props.file, props.pous, props.live);
  const counts = problemCounts(props.diagnostics);
  const same = (a: string | null | undefined, b: string | null | undefined) => !!a && !!b && a.toLowerCase() === b.toLowerCase();
  const isActive = (r: TreeNode) =>
    same(r.pou, props.activePou) && ((r.kind === 'pou' && props.activeView === null) || (r.kind === 'action' && same(r.name, props.activeView)));
  return (
    <aside class="project-tree no-print" aria-label={t('project.title')}>
      <div class="panel-header">
        <span>{t('project.title')}</span>
        <button class="icon-button" title={t('project.collapse')} onClick={props.onCollapse}>
          <Icon name="prev" />
        </button>
      </div>
      <ul class="tree" role="tree">
        {rows.map((r, k) => {
          const n = r.kind === 'pou' ? counts.get(r.pou.toLowerCase()) ?? 0 : 0;
          const tip =
            r.kind === 'file'
              ? r.label
              : r.kind === 'pou'
                ? r.openable
                  ? t('project.openChart', { pou: r.pou })
                  : t('project.notChart', { pou: r.pou, language: r.language ?? '' })
                : r.kind === 'action'
                  ? r.openable
                    ? t('project.openAction', { action: `${r.pou}.${r.label}` })
                    : t('project.action', { action: `${r.pou}.${r.label}` })
                  : t('project.transition', { transition: r.label, pou: r.pou });
          return (
            <li
              key={k}
              role="treeitem"
              aria-selected={isActive(r)}
              data-kind={r.kind}
              data-pou={r.pou}
              data-name={r.name}
              class={`tree-row depth-${r.depth} ${r.openable ? 'openable' : 'muted'} ${isActive(r) ? 'active' : ''}`}
              title={tip}
              onClick={() => r.kind !== 'file' && r.openable && props.onOpen(r)}
            >
              {r.language && <span class="tree-kind">{r.language}</span>}
              <span class="tree-label">{r.label}</span>
              {n > 0 && <span class="badge badge-error">{n}</span>}
            </li>
          );
        })}
      </ul>
    </aside>
  );
}
