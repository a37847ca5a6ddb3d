// The Result panel: the ATMT/EATMT transition table and timeout vector (seed 001 fig. 21) with
// the one-line result, or the generated text; Copy and Download.
import type { BuildResult, BuildTarget } from '../api';
import { t } from '../i18n';
import { parseTable, resultFileName, resultMime, tableRows, type TransitionTable } from './buildResult';
import { Icon } from './icons';
import { toasts } from './toast';

/** Saves text as a file through the browser's download. */
export function download(name: string, text: string, mime: string): void {
  const url = URL.createObjectURL(new Blob([text], { type: `${mime};charset=utf-8` }));
  const a = document.createElement('a');
  a.href = url;
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

export function ResultPanel(props: { pou: string; result: { target: BuildTarget; result: BuildResult } | null }) {
  if (!props.result) return <div class="empty">{t('result.none')}</div>;
  const { target, result } = props.result;
  if (!result.ok || result.output === undefined) return <div class="empty">{t('result.failed')}</div>;
  const output = result.output;
  const isTable = target === 'atmt' || target === 'eatmt';
  let table: TransitionTable | null = null;
  let tableError = '';
  if (isTable) {
    try {
      table = result.table ?? parseTable(output);
    } catch (e) {
      tableError = (e as Error).message;
    }
  }
  const copy = () =>
    navigator.clipboard.writeText(output).then(
      () => toasts.show('success', t('result.copied')),
      () => toasts.show('error', t('result.copyFailed')),
    );
  const name = resultFileName(props.pou, target);
  return (
    <div class="result-panel">
      <div class="panel-toolbar">
        <span class="muted">{t(`buildTarget.${target}`)}</span>
        {result.resultWritten && <span class="muted">{t('result.written', { path: result.resultWritten })}</span>}
        <span class="spacer" />
        <button class="button small" onClick={copy}>
          <Icon name="copy" /> {t('result.copy')}
        </button>
        <button class="button small" onClick={() => download(name, output, resultMime(target))}>
          <Icon name="download" /> {t('result.download', { name })}
        </button>
      </div>
      {isTable ? (
        <div class="result-table-view">
          <div class="one-line">
            <span class="muted">{t('result.oneLine')}</span>
            <code>{output}</code>
          </div>
          {table && <TableView table={table} />}
          {tableError && <div class="field-error">{tableError}</div>}
        </div>
      ) : (
        <pre class="result-text">{output}</pre>
      )}
    </div>
  );
}

function TableView({ table }: { table: TransitionTable }) {
  const rows = tableRows(table);
  return (
    <div class="atmt-tables">
      <table class="grid atmt">
        <caption>{t('result.rules')}</caption>
        <thead>
          <tr>
            <th>#</th>
            <th>{t('result.activeState')}</th>
            <th>{t('result.condition')}</th>
            <th>{t('result.newState')}</th>
          </tr>
        </thead>
        <tbody>
          {rows.rules.map((r) => (
            <tr key={r[0]}>
              {r.map((c, k) => (
                <td key={k}>{c}</td>
              ))}
            </tr>
          ))}
        </tbody>
      </table>
      <table class="grid atmt">
        <caption>{t('result.timeouts')}</caption>
        <thead>
          <tr>
            <th>#</th>
            <th>{t('result.timeout')}</th>
          </tr>
        </thead>
        <tbody>
          {rows.timeouts.map((r) => (
            <tr key={r[0]}>
              <td>{r[0]}</td>
              <td>{r[1]}</td>
            </tr>
          ))}
        </tbody>
      </table>
    </div>
  );
}
