// The start screen, shown while no chart is open: New and Open, the charts opened lately (kept
// by the server in the user's config directory, src/app/settings.ts) and the charts in the
// folders it serves. A recent chart this editor does not serve (it was started on other files)
// is listed greyed with a note, not opened: the server opens only what it was started on.
import { useEffect, useState } from 'preact/hooks';
import type { FileFormat } from '../api';
import { t } from '../i18n';
import { Icon } from './icons';
import { settings, withRecent } from './settings';

/** Recent charts shown (the server keeps up to 20). */
const RECENT_SHOWN = 10;
const LISTED_MAX = 12;

/** Paths opened lately, newest first. */
export function recentFiles(): string[] {
  return settings.recent();
}

/** Puts `path` first among the recent files. */
export function rememberFile(path: string): void {
  void settings.update({ recent: withRecent(settings.recent(), path) });
}

function baseName(p: string): string {
  return p.split(/[\\/]/).pop() ?? p;
}

export function Welcome(props: {
  /** Whether New and Open are offered (not in host mode). */
  mdi: boolean;
  files: () => Promise<{ path: string; format: FileFormat }[]>;
  onNew: () => void;
  onOpenDialog: () => void;
  onOpen: (path: string) => void;
}) {
  const [files, setFiles] = useState<string[] | null>(null);
  useEffect(() => {
    if (!props.mdi) return;
    props.files().then(
      (list) => setFiles(list.map((f) => f.path)),
      () => setFiles([]),
    );
  }, [props.mdi]);
  const served = new Set(files ?? []);
  // Listed once the served files are known (until then every chart would look unserved).
  const recent = files === null ? [] : recentFiles().slice(0, RECENT_SHOWN);
  const others = (files ?? []).filter((p) => !recent.includes(p)).slice(0, LISTED_MAX);
  const row = (p: string) => {
    if (served.has(p)) {
      return (
        <li key={p}>
          <button class="welcome-file" title={p} onClick={() => props.onOpen(p)}>
            <Icon name="open" />
            <span class="welcome-file-name">{baseName(p)}</span>
            <span class="welcome-file-path muted">{p}</span>
          </button>
        </li>
      );
    }
    // Not served by this editor: listed, greyed, with the reason; never opened.
    return (
      <li key={p}>
        <div class="welcome-file not-served" title={`${p}\n${t('start.notServed')}`} aria-disabled="true">
          <Icon name="open" />
          <span class="welcome-file-name">{baseName(p)}</span>
          <span class="welcome-file-path muted">{p}</span>
          <span class="welcome-file-note muted">{t('start.notServed')}</span>
        </div>
      </li>
    );
  };
  return (
    <div class="welcome" data-testid="welcome">
      <div class="welcome-card">
        <h1>{t('app.name')}</h1>
        <p class="muted">{t('start.hint')}</p>
        {props.mdi && (
          <div class="welcome-buttons">
            <button class="button primary" onClick={props.onNew}>
              <Icon name="new" /> {t('menu.new')}
            </button>
            <button class="button" onClick={props.onOpenDialog}>
              <Icon name="open" /> {t('menu.open')}
            </button>
          </div>
        )}
        {props.mdi && recent.length > 0 && (
          <section class="welcome-list" aria-label={t('start.recent')}>
            <h2>{t('start.recent')}</h2>
            <ul>{recent.map(row)}</ul>
          </section>
        )}
        {props.mdi && others.length > 0 && (
          <section class="welcome-list" aria-label={t('start.charts')}>
            <h2>{t('start.charts')}</h2>
            <ul>{others.map(row)}</ul>
          </section>
        )}
        {props.mdi && files !== null && files.length === 0 && <p class="muted">{t('start.noCharts')}</p>}
      </div>
    </div>
  );
}
