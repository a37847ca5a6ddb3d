// Export SVG… downloads the chart as a standalone SVG file: well-formed (xmllint and the
// browser's XML parser), with every step's name; Print… opens the page preview whose legend
// lists every block of the chart. A long condition is drawn whole, wrapped, and the legend
// gives it whole; neither prints the error frames unless asked.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, shotPath, waitChart } from '../helpers.mjs';

const LONG = 'StartButton AND CarPresent AND AtHome AND NOT StopButton AND NOT EmergencyStop AND DoorClosed AND AirPressureOk';

// T1's condition wraps over four lines; T2 names a variable nobody declared: an error, framed red.
const MARKED = `PROGRAM Marked
    VAR
        StartButton, CarPresent, AtHome, StopButton, EmergencyStop, DoorClosed, AirPressureOk : BOOL;
    END_VAR

    INITIAL_STEP S0: END_STEP

    TRANSITION T1 FROM S0 TO S1
        := ${LONG};
    END_TRANSITION

    STEP S1: END_STEP

    TRANSITION T2 FROM S1 TO S0
        := Nobody;
    END_TRANSITION
END_PROGRAM
`;

const ERROR_RED = '#dc2626';

export const tests = [
  {
    name: 'Export SVG downloads valid SVG holding every step name',
    run: async (t) => {
      const { page } = t;
      await openEditor(t, ['examples/carwash/carwash.st']);
      const d = await waitChart(page);
      const downloading = page.waitForEvent('download');
      await page.locator('.toolbar button[title="Export SVG…"]').click();
      const download = await downloading;
      assert(download.suggestedFilename() === `${d.pou}.svg`, `file name ${download.suggestedFilename()}`);
      const file = path.join(t.scratch, download.suggestedFilename());
      await download.saveAs(file);
      const svg = fs.readFileSync(file, 'utf8');
      execFileSync('xmllint', ['--noout', file], { stdio: ['ignore', 'pipe', 'pipe'] });
      const parsed = await page.evaluate((text) => {
        const x = new DOMParser().parseFromString(text, 'image/svg+xml');
        return {
          error: x.querySelector('parsererror')?.textContent ?? null,
          root: x.documentElement.localName,
          ns: x.documentElement.namespaceURI,
          width: x.documentElement.getAttribute('width'),
          texts: [...x.querySelectorAll('text')].map((e) => e.textContent),
        };
      }, svg);
      assert(parsed.error === null, `SVG does not parse: ${parsed.error}`);
      assert(parsed.root === 'svg' && parsed.ns === 'http://www.w3.org/2000/svg', `root ${parsed.root} ${parsed.ns}`);
      assert(Number.parseFloat(parsed.width) > 0, `width ${parsed.width}`);
      const steps = d.elements.filter((e) => e.kind === 'step');
      assert(steps.length >= 5, `carwash has ${steps.length} steps`);
      for (const s of steps) {
        // A step shows `name` or `name : tag`.
        assert(parsed.texts.some((x) => x === s.name || x.startsWith(`${s.name} :`)), `step ${s.name} is not in the SVG`);
      }
      // The editor's own decorations stay out of the file.
      for (const bad of ['djs-', 'sfc-grid', 'class=']) assert(!svg.includes(bad), `the SVG holds ${bad}`);
    },
  },
  {
    name: 'Print… shows the page preview with a legend listing every block',
    run: async (t) => {
      const { page } = t;
      await openEditor(t, ['examples/carwash/carwash.st']);
      const d = await waitChart(page);
      await page.locator('.toolbar button[title^="Print…"]').click();
      await page.waitForSelector('.print-modal .print-page');
      const legend = await page.locator('.print-modal table.legend tbody tr').evaluateAll((rows) =>
        rows.map((r) => [...r.querySelectorAll('td')].map((td) => td.textContent.trim())),
      );
      assert(legend.length === d.elements.length, `${legend.length} legend rows for ${d.elements.length} blocks`);
      for (const e of d.elements.filter((x) => x.kind === 'step' || x.kind === 'transition')) {
        assert(legend.some((row) => row[1] === e.name), `${e.kind} ${e.name} is not in the legend`);
      }
      // The header names the POU; the preview shows the chart's drawing (the SVG as an image).
      const header = await page.locator('.print-modal .print-header').first().textContent();
      assert(header.includes(d.pou), `header: ${header}`);
      await page.waitForFunction(() => {
        const img = document.querySelector('.print-modal .print-area img');
        return !!img && img.complete && img.naturalWidth > 0;
      });
      await page.screenshot({ path: shotPath(t, 'print-preview.png') });
      // Without the legend page the preview has fewer pages.
      const pages = await page.locator('.print-modal .print-page').count();
      await page.locator('.print-modal .print-setup input[type="checkbox"]').last().uncheck();
      await page.waitForFunction((n) => document.querySelectorAll('.print-modal .print-page').length < n, pages);
      await page.keyboard.press('Escape');
      await page.waitForFunction(() => !document.querySelector('.print-modal'));
    },
  },
  {
    name: 'a long condition is exported and printed whole; the legend gives it; error frames only when asked',
    run: async (t) => {
      const { page } = t;
      fs.writeFileSync(path.join(t.scratch, 'marked.st'), MARKED);
      await openEditor(t, ['marked.st']);
      await waitChart(page);
      await page.waitForFunction((red) => document.querySelector(`.canvas-pane.active [data-element-id="transition:T2"] rect[stroke="${red}"]`), ERROR_RED);
      // Export SVG: the condition whole over several lines, no error frame.
      const downloading = page.waitForEvent('download');
      await page.locator('.toolbar button[title="Export SVG…"]').click();
      const file = path.join(t.scratch, 'marked.svg');
      await (await downloading).saveAs(file);
      const svg = fs.readFileSync(file, 'utf8');
      assert(!svg.includes(ERROR_RED), 'the exported SVG holds the error frame');
      assert(!svg.includes('…'), 'the exported SVG cuts a label');
      const lines = await page.evaluate((text) => {
        const x = new DOMParser().parseFromString(text, 'image/svg+xml');
        return [...x.querySelectorAll('g[data-id="transition:T1"] text')].map((e) => e.textContent).filter((l) => l !== 'T1');
      }, svg);
      assert(lines.length >= 3 && lines.join(' ') === LONG, `T1's condition as drawn: ${JSON.stringify(lines)}`);
      assert((await page.evaluate(() => window.__sfc.exportSvg({ marks: true }))).includes(ERROR_RED), 'asked for, the marks are there');
      // Print: the legend gives T1's condition whole; the picture has no frame until asked for.
      await page.locator('.toolbar button[title^="Print…"]').click();
      await page.waitForSelector('.print-modal .print-page');
      const legend = await page.locator('.print-modal table.legend tbody tr').evaluateAll((rows) =>
        rows.map((r) => [...r.querySelectorAll('td')].map((td) => td.textContent.trim())),
      );
      assert(legend.some((row) => row[1] === 'T1' && row[3] === LONG), `T1 in the legend: ${JSON.stringify(legend)}`);
      assert(legend.some((row) => row[1] === 'T2' && row[3] === 'Nobody'), `T2 in the legend: ${JSON.stringify(legend)}`);
      const picture = () => page.evaluate(() => decodeURIComponent(document.querySelector('.print-modal .print-area img').getAttribute('src')));
      assert(!(await picture()).includes(ERROR_RED), 'the printed chart holds the error frame');
      await page.locator('.print-modal input[name="print-marks"]').check();
      await page.waitForFunction(
        (red) => decodeURIComponent(document.querySelector('.print-modal .print-area img').getAttribute('src')).includes(red),
        ERROR_RED,
      );
      await page.keyboard.press('Escape');
      await page.waitForFunction(() => !document.querySelector('.print-modal'));
    },
  },
];
