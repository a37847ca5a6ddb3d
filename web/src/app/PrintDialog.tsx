// Print…: page setup beside a large preview of the pages (the chart scaled to the page, or cut
// into several pages at a scale; then the legend, every transition with its whole condition);
// "Print" prints exactly these pages. The chart is printed without the highlights' marks
// (error and comparison frames, monitor states) unless asked for.
import { useMemo, useState } from 'preact/hooks';
import type { EditorDoc } from '../doc';
import { currentLanguage, t } from '../i18n';
import { legendRows } from './chart';
import { Modal } from './dialogs';
import { chartPages, DEFAULT_SETUP, HEADER_MM, legendPages, pageRule, pageSize, svgSize, type PageSetup, type Paper } from './print';
import { baseName } from './store';

/** `svg(marks)`: the chart as Export SVG writes it, with the highlights' marks or without. */
export function PrintDialog(props: { svg: (marks: boolean) => string; doc: EditorDoc; path: string | null; onClose: () => void }) {
  const [setup, setSetup] = useState<PageSetup>(DEFAULT_SETUP);
  const [zoom, setZoom] = useState(0.5);
  const set = (p: Partial<PageSetup>) => setSetup({ ...setup, ...p });
  const page = pageSize(setup);
  const svg = useMemo(() => props.svg(setup.marks), [props.svg, setup.marks]);
  const size = useMemo(() => svgSize(svg), [svg]);
  const layout = chartPages(setup, size);
  const src = useMemo(() => `data:image/svg+xml;charset=utf-8,${encodeURIComponent(svg)}`, [svg]);
  const legend = useMemo(() => legendPages(legendRows(props.doc)), [props.doc]);
  const date = new Date().toLocaleString(currentLanguage());
  const shownLegend = setup.legend ? legend : [];
  const total = layout.cols * layout.rows + shownLegend.length;

  const header = (n: number) =>
    setup.header && (
      <div class="print-header" style={{ height: `${HEADER_MM}mm` }}>
        <strong>{props.doc.pou}</strong>
        <span>{props.path ? baseName(props.path) : t('print.unsaved')}</span>
        <span>{date}</span>
        <span>{t('print.pageOf', { page: n, total })}</span>
      </div>
    );
  const pageStyle = { width: `${page.w}mm`, height: `${page.h}mm`, padding: `${setup.margin}mm` };
  const pages = [];
  let n = 0;
  for (let r = 0; r < layout.rows; r++) {
    for (let c = 0; c < layout.cols; c++) {
      n++;
      pages.push(
        <div class="print-page" style={pageStyle} key={`c${r}-${c}`}>
          {header(n)}
          <div class="print-area" style={{ width: `${layout.areaW}mm`, height: `${layout.areaH}mm` }}>
            <img
              src={src}
              alt={props.doc.pou}
              style={{
                width: `${layout.drawW}mm`,
                height: `${layout.drawH}mm`,
                left: `${-c * layout.areaW}mm`,
                top: `${-r * layout.areaH}mm`,
              }}
            />
          </div>
        </div>,
      );
    }
  }
  shownLegend.forEach((rows, k) => {
    n++;
    pages.push(
      <div class="print-page" style={pageStyle} key={`l${k}`}>
        {header(n)}
        <h2 class="legend-title">{t('print.legend')}</h2>
        <table class="legend">
          <thead>
            <tr>
              <th>{t('print.kind')}</th>
              <th>{t('print.name')}</th>
              <th>{t('print.tag')}</th>
              <th>{t('print.condition')}</th>
              <th>{t('print.description')}</th>
            </tr>
          </thead>
          <tbody>
            {rows.map((row) => (
              <tr key={row.id}>
                <td>{t(`kind.${row.kind}`)}</td>
                <td>{row.name}</td>
                <td>{row.tag}</td>
                <td class="legend-condition">{row.condition}</td>
                <td class="legend-description">{row.description}</td>
              </tr>
            ))}
          </tbody>
        </table>
      </div>,
    );
  });

  return (
    <Modal
      title={t('print.title')}
      onClose={props.onClose}
      wide
      class="print-modal"
      footer={
        <>
          <button class="button primary" onClick={() => window.print()}>
            {t('print.print')}
          </button>
          <button class="button" onClick={props.onClose}>
            {t('common.close')}
          </button>
        </>
      }
    >
      <style>{`${pageRule(setup)}`}</style>
      <div class="print-layout">
        <div class="print-setup no-print">
          <label>
            {t('print.paper')}
            <select value={setup.paper} onChange={(e) => set({ paper: e.currentTarget.value as Paper })}>
              <option value="A4">A4</option>
              <option value="A3">A3</option>
              <option value="Letter">Letter</option>
            </select>
          </label>
          <label>
            {t('print.orientation')}
            <select value={setup.orientation} onChange={(e) => set({ orientation: e.currentTarget.value as PageSetup['orientation'] })}>
              <option value="portrait">{t('print.portrait')}</option>
              <option value="landscape">{t('print.landscape')}</option>
            </select>
          </label>
          <label>
            {t('print.margin')}
            <input type="number" min={0} max={50} value={setup.margin} onChange={(e) => set({ margin: Math.min(50, Math.max(0, Number(e.currentTarget.value) || 0)) })} />
          </label>
          <fieldset>
            <legend>{t('print.scaling')}</legend>
            <label class="inline-check">
              <input type="radio" name="print-fit" checked={setup.fit} onChange={() => set({ fit: true })} />
              {t('print.fit')}
            </label>
            <label class="inline-check">
              <input type="radio" name="print-fit" checked={!setup.fit} onChange={() => set({ fit: false })} />
              {t('print.scale')}
              <input
                type="number"
                min={10}
                max={400}
                step={10}
                value={setup.scale}
                disabled={setup.fit}
                onChange={(e) => set({ scale: Math.min(400, Math.max(10, Number(e.currentTarget.value) || 100)) })}
              />
              %
            </label>
          </fieldset>
          <label class="inline-check">
            <input type="checkbox" checked={setup.header} onChange={(e) => set({ header: e.currentTarget.checked })} />
            {t('print.header')}
          </label>
          <label class="inline-check">
            <input type="checkbox" name="print-marks" checked={setup.marks} onChange={(e) => set({ marks: e.currentTarget.checked })} />
            {t('print.marks')}
          </label>
          <label class="inline-check">
            <input type="checkbox" name="print-legend" checked={setup.legend} onChange={(e) => set({ legend: e.currentTarget.checked })} />
            {t('print.withLegend')}
          </label>
          <label>
            {t('print.previewZoom')}
            <input type="range" min={0.2} max={1} step={0.05} value={zoom} onInput={(e) => setZoom(Number(e.currentTarget.value))} />
          </label>
          <div class="muted small">{t('print.pages', { count: total })}</div>
        </div>
        <div class="print-preview">
          <div class="print-pages" style={{ zoom: String(zoom) }}>
            {pages}
          </div>
        </div>
      </div>
    </Modal>
  );
}
