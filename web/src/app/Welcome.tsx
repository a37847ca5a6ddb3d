// The start screen, shown while no chart is open: New and Open, the charts opened lately (kept
// in the browser, shown when this editor serves them) and the charts in the folders it serves.
import { useEffect, useState } from 'preact/hooks';
import type { FileFormat } from '../api';
import { t } from '../i18n';
import { Icon } from './icons';

const RECENT_KEY = 'sfc.recent';
const RECENT_MAX = 8;
const LISTED_MAX = 12;

/** Paths opened lately, newest first. */
export function recentFiles(): string[] {
  try {
    const v = JSON.parse(localStorage.getItem(RECENT_KEY) ?? '[]');
    return Array.isArray(v) ? v.filter((x): x is string => typeof x === 'string') : [];
  } catch {
    return [];
  }
}

/** Puts `path` first among the recent files. */
export function rememberFile(path: string): void {
  try {
    const list = [path, ...recentFiles().filter((p) => p !== path)].slice(0, RECENT_MAX);
    localStorage.setItem(RECENT_KEY, JSON.stringify(list));
  } catch {
    // Storage may be unavailable (private mode): the list is a convenience.
  }
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
  const recent = recentFiles().filter((p) => served.has(p));
  const others = (files ?? []).filter((p) => !recent.includes(p)).slice(0, LISTED_MAX);
  const row = (p: string) => (
    <li key={p}>
      <button class="welcome-file" title={p} onClick={() => props.onOpen(p)}>
        <Icon name="open" />
        <span class="welcome-file-name">{baseName(p)}</span>
        <span class="welcome-file-path muted">{p}</span>
      </button>
    </li>
  );
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
