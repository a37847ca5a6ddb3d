// Modal dialogs of the shell: New chart, Open, Save as, the close guard (Save / Discard /
// Cancel), the save conflict, About and the keyboard shortcuts.
import type { ComponentChildren } from 'preact';
import { useEffect, useMemo, useRef, useState } from 'preact/hooks';
import type { FileFormat, Session } from '../api';
import { t } from '../i18n';
import { isIecName } from './chart';
import { CHART_KINDS, type ChartKind } from './chartKind';
import type { CloseChoice } from './store';
import { baseName, formatOf, underRoot } from './store';

export function Modal(props: {
  title: string;
  onClose: () => void;
  children: ComponentChildren;
  footer: ComponentChildren;
  wide?: boolean;
  class?: string;
}) {
  const box = useRef<HTMLDivElement>(null);
  useEffect(() => {
    const first = box.current?.querySelector<HTMLElement>('[data-autofocus], input, select, textarea, button');
    first?.focus();
    const onKey = (e: KeyboardEvent) => {
      if (e.key === 'Escape') {
        e.stopPropagation();
        props.onClose();
      }
    };
    document.addEventListener('keydown', onKey, true);
    return () => document.removeEventListener('keydown', onKey, true);
  }, []);
  return (
    <div class={`modal-backdrop ${props.class ?? ''}`}>
      <div class={`modal ${props.wide ? 'modal-wide' : ''}`} role="dialog" aria-modal="true" aria-label={props.title} ref={box}>
        <div class="modal-title no-print">
          <span>{props.title}</span>
          <button class="icon-button" title={t('common.close')} onClick={props.onClose}>
            ×
          </button>
        </div>
        <div class="modal-body">{props.children}</div>
        <div class="modal-footer no-print">{props.footer}</div>
      </div>
    </div>
  );
}

export interface NewChartRequest {
  pou: string;
  /** `iec`: a Blank chart with `sfc.build` (see chartKind.ts). */
  target: ChartKind;
  format: FileFormat;
}

export function NewDialog(props: { initialTarget: ChartKind; onCreate: (r: NewChartRequest) => void; onClose: () => void }) {
  const [pou, setPou] = useState('Chart1');
  const [target, setTarget] = useState<ChartKind>(props.initialTarget);
  const [format, setFormat] = useState<FileFormat>('st');
  const valid = isIecName(pou);
  const submit = () => valid && props.onCreate({ pou, target, format });
  return (
    <Modal
      title={t('new.title')}
      onClose={props.onClose}
      footer={
        <>
          <button class="button primary" disabled={!valid} onClick={submit}>
            {t('common.create')}
          </button>
          <button class="button" onClick={props.onClose}>
            {t('common.cancel')}
          </button>
        </>
      }
    >
      <form
        class="form-grid"
        onSubmit={(e) => {
          e.preventDefault();
          submit();
        }}
      >
        <label for="new-name">{t('new.name')}</label>
        <div>
          <input id="new-name" value={pou} onInput={(e) => setPou(e.currentTarget.value)} class={valid ? '' : 'invalid'} />
          {!valid && <div class="field-error">{t('props.invalidName')}</div>}
        </div>
        <span>{t('new.target')}</span>
        <div class="target-choice" role="radiogroup">
          {CHART_KINDS.map((k) => (
            <label class={`target-option ${target === k ? 'checked' : ''}`} key={k}>
              <input type="radio" name="new-target" checked={target === k} onChange={() => setTarget(k)} />
              <span class="target-name">{t(`target.${k}`)}</span>
              <span class="target-description">{t(`new.describe.${k}`)}</span>
            </label>
          ))}
        </div>
        <label for="new-format">{t('new.format')}</label>
        <select id="new-format" value={format} onChange={(e) => setFormat(e.currentTarget.value as FileFormat)}>
          <option value="st">{t('format.st')}</option>
          <option value="xml">{t('format.xml')}</option>
        </select>
        <button type="submit" hidden />
      </form>
    </Modal>
  );
}

export function OpenDialog(props: {
  load: () => Promise<{ path: string; format: FileFormat }[]>;
  onOpen: (path: string) => void;
  onClose: () => void;
}) {
  const [files, setFiles] = useState<{ path: string; format: FileFormat }[] | null>(null);
  const [failed, setFailed] = useState(false);
  const [filter, setFilter] = useState('');
  const [chosen, setChosen] = useState<string | null>(null);
  useEffect(() => {
    props.load().then(setFiles, () => setFailed(true));
  }, []);
  const shown = useMemo(() => {
    const words = filter.toLowerCase().split(/\s+/).filter(Boolean);
    return (files ?? []).filter((f) => words.every((w) => f.path.toLowerCase().includes(w)));
  }, [files, filter]);
  return (
    <Modal
      title={t('open.title')}
      onClose={props.onClose}
      wide
      footer={
        <>
          <button class="button primary" disabled={!chosen} onClick={() => chosen && props.onOpen(chosen)}>
            {t('common.open')}
          </button>
          <button class="button" onClick={props.onClose}>
            {t('common.cancel')}
          </button>
        </>
      }
    >
      <input
        class="filter-box"
        placeholder={t('open.filter')}
        value={filter}
        onInput={(e) => setFilter(e.currentTarget.value)}
        onKeyDown={(e) => {
          if (e.key === 'Enter' && shown.length > 0) props.onOpen((chosen && shown.some((f) => f.path === chosen) ? chosen : shown[0].path));
        }}
      />
      <div class="file-list" role="listbox">
        {files === null && !failed && <div class="empty">{t('common.loading')}</div>}
        {failed && <div class="empty">{t('open.failed')}</div>}
        {files !== null && shown.length === 0 && <div class="empty">{t('open.none')}</div>}
        {shown.map((f) => (
          <div
            key={f.path}
            role="option"
            aria-selected={chosen === f.path}
            class={`file-row ${chosen === f.path ? 'selected' : ''}`}
            onClick={() => setChosen(f.path)}
            onDblClick={() => props.onOpen(f.path)}
          >
            <span class="file-name">{baseName(f.path)}</span>
            <span class="file-path">{f.path}</span>
            <span class="file-format">{f.format === 'xml' ? 'PLCopen XML' : 'SFC'}</span>
          </div>
        ))}
      </div>
    </Modal>
  );
}

export function SaveAsDialog(props: {
  session: Session;
  initialPath: string;
  initialFormat: FileFormat;
  onSave: (path: string, format: FileFormat) => void;
  onClose: () => void;
}) {
  const [path, setPath] = useState(props.initialPath);
  const [format, setFormat] = useState<FileFormat>(props.initialFormat);
  const inRoot = underRoot(path, props.session.roots);
  const hasName = /[^\\/]\.(st|xml)$/i.test(path);
  const error = !inRoot ? t('saveAs.outsideRoots') : !hasName ? t('saveAs.extension') : '';
  const changeFormat = (f: FileFormat) => {
    setFormat(f);
    setPath((p) => p.replace(/\.(st|xml)$/i, f === 'xml' ? '.xml' : '.st'));
  };
  const submit = () => !error && props.onSave(path, format);
  return (
    <Modal
      title={t('saveAs.title')}
      onClose={props.onClose}
      wide
      footer={
        <>
          <button class="button primary" disabled={!!error} onClick={submit}>
            {t('common.save')}
          </button>
          <button class="button" onClick={props.onClose}>
            {t('common.cancel')}
          </button>
        </>
      }
    >
      <form
        class="form-grid"
        onSubmit={(e) => {
          e.preventDefault();
          submit();
        }}
      >
        <label for="save-path">{t('saveAs.path')}</label>
        <div>
          <input
            id="save-path"
            class={`wide-input ${error ? 'invalid' : ''}`}
            value={path}
            onInput={(e) => {
              const p = e.currentTarget.value;
              setPath(p);
              if (/\.(st|xml)$/i.test(p)) setFormat(formatOf(p));
            }}
          />
          {error && <div class="field-error">{error}</div>}
        </div>
        <label for="save-format">{t('new.format')}</label>
        <select id="save-format" value={format} onChange={(e) => changeFormat(e.currentTarget.value as FileFormat)}>
          <option value="st">{t('format.st')}</option>
          <option value="xml">{t('format.xml')}</option>
        </select>
        <span>{t('saveAs.roots')}</span>
        <ul class="roots">
          {props.session.roots.map((r) => (
            <li key={r}>{r}</li>
          ))}
        </ul>
        <button type="submit" hidden />
      </form>
    </Modal>
  );
}

export function CloseDialog(props: { name: string; onChoose: (c: CloseChoice) => void }) {
  return (
    <Modal
      title={t('close.title')}
      onClose={() => props.onChoose('cancel')}
      footer={
        <>
          <button class="button primary" data-autofocus onClick={() => props.onChoose('save')}>
            {t('common.save')}
          </button>
          <button class="button danger" onClick={() => props.onChoose('discard')}>
            {t('close.discard')}
          </button>
          <button class="button" onClick={() => props.onChoose('cancel')}>
            {t('common.cancel')}
          </button>
        </>
      }
    >
      <p>{t('close.question', { name: props.name })}</p>
    </Modal>
  );
}

export function ConflictDialog(props: { path: string; onChoose: (overwrite: boolean) => void }) {
  return (
    <Modal
      title={t('conflict.title')}
      onClose={() => props.onChoose(false)}
      footer={
        <>
          <button class="button danger" onClick={() => props.onChoose(true)}>
            {t('conflict.overwrite')}
          </button>
          <button class="button" data-autofocus onClick={() => props.onChoose(false)}>
            {t('common.cancel')}
          </button>
        </>
      }
    >
      <p>{t('conflict.question', { path: props.path })}</p>
    </Modal>
  );
}

export function AboutDialog(props: { version: string; onClose: () => void }) {
  return (
    <Modal
      title={t('about.title')}
      onClose={props.onClose}
      footer={
        <button class="button primary" onClick={props.onClose}>
          {t('common.ok')}
        </button>
      }
    >
      <p class="about-name">{t('app.name')}</p>
      <p>{t('about.version', { version: props.version })}</p>
      <p>{t('about.text')}</p>
      <p class="muted">{t('about.license')}</p>
    </Modal>
  );
}

/** The shortcuts the shell handles, as [label key, keys]. */
export const SHORTCUTS: [string, string][] = [
  ['menu.new', 'Ctrl+Shift+N'],
  ['menu.newAtmt', 'Ctrl+Shift+A'],
  ['menu.newEatmt', 'Ctrl+Shift+E'],
  ['menu.save', 'Ctrl+S'],
  ['menu.print', 'Ctrl+P'],
  ['menu.undo', 'Ctrl+Z'],
  ['menu.redo', 'Ctrl+Y'],
  ['menu.cut', 'Ctrl+X'],
  ['menu.copy', 'Ctrl+C'],
  ['menu.paste', 'Ctrl+V'],
  ['menu.delete', 'Del'],
  ['menu.selectAll', 'Ctrl+A'],
  ['menu.insertAfter', 'Ins'],
  ['menu.insertBefore', 'Shift+Ins'],
  ['menu.deleteStep', 'Del'],
  ['menu.build', 'F7'],
  ['menu.zoomIn', 'Ctrl++'],
  ['menu.zoomOut', 'Ctrl+-'],
  ['menu.zoomFit', 'Ctrl+0'],
  ['shortcuts.properties', 'Enter'],
  ['shortcuts.commit', 'Ctrl+Enter'],
];

export function ShortcutsDialog(props: { onClose: () => void }) {
  return (
    <Modal
      title={t('shortcuts.title')}
      onClose={props.onClose}
      footer={
        <button class="button primary" onClick={props.onClose}>
          {t('common.ok')}
        </button>
      }
    >
      <table class="shortcuts">
        <tbody>
          {SHORTCUTS.map(([key, keys]) => (
            <tr key={key}>
              <td>{t(key).replace(/…$/, '')}</td>
              <td>
                <kbd>{keys}</kbd>
              </td>
            </tr>
          ))}
        </tbody>
      </table>
    </Modal>
  );
}
