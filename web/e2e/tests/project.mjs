// A Beremiz project of 13 SFC programs and two POUs in ST (issue 36): the first chart is shown
// and its tab in view, the project tree lists every POU, each chart's Error list holds only its
// own errors (the function's under the file), a click on an error frames its block in its
// chart; an error fixed by an edit leaves the list, and comes back on undo.
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, select, setCondition, until, waitChart } from '../helpers.mjs';

const UNITS = ['Intake', 'Mixer', 'Heater', 'Filler', 'Capper', 'Labeler', 'Conveyor', 'Washer', 'Dryer', 'Sorter', 'Palletizer', 'Wrapper', 'Dispatch'];

async function openProject(t) {
  const file = path.join(t.scratch, 'plant13.plc.xml');
  fs.copyFileSync(path.join(t.root, 'web', 'e2e', 'fixtures', 'plant13.plc.xml'), file);
  await openEditor(t, [file]);
  await t.page.waitForFunction((n) => window.__sfc.tabs().length === n, UNITS.length);
  await waitChart(t.page);
  return file;
}

/** The messages of the rows of the shown chart's own errors. */
const ownErrors = (page) => page.locator('.error-list tbody tr.sev-error:not(.in-file) .col-message').allTextContents();

export const tests = [
  {
    name: 'project: 13 charts, the first shown, the tree lists every POU, each tab its own errors framed in its chart',
    run: async (t) => {
      const { page } = t;
      await openProject(t);
      const tabs = await page.evaluate(() => window.__sfc.tabs());
      assert(tabs[0].active && tabs[0].pou === 'Intake', `the first chart is shown: ${JSON.stringify(tabs.find((x) => x.active))}`);
      const inView = await page.evaluate(() => {
        const strip = document.querySelector('.tabstrip').getBoundingClientRect();
        const tab = document.querySelector('.tabstrip .tab.active').getBoundingClientRect();
        return tab.left >= strip.left - 1 && tab.right <= strip.right + 1;
      });
      assert(inView, 'the active tab is in view');

      const pous = await page.locator('.project-tree [data-kind="pou"]').evaluateAll((rows) => rows.map((r) => r.dataset.pou));
      assert(JSON.stringify(pous) === JSON.stringify([...UNITS, 'Scale', 'Debounce']), `the tree lists every POU: ${pous}`);

      for (const [k, unit] of UNITS.entries()) {
        // A real click on the chart's row of the tree shows it.
        await page.locator(`.project-tree [data-kind="pou"][data-pou="${unit}"]`).click();
        await page.waitForFunction((u) => window.__sfc.doc()?.pou === u && window.__sfc.tabs().find((x) => x.active).pou === u, unit);
        await waitChart(page);
        assert(await page.locator(`.project-tree [data-kind="pou"][data-pou="${unit}"].active`).count() === 1, `${unit} is highlighted in the tree`);
        const messages = await ownErrors(page);
        const expected = k % 2 === 1 ? [`Missing${unit}`, `Level${unit}`] : [`Level${unit}`];
        assert(messages.length === expected.length, `${unit}: ${expected.length} errors listed, got ${JSON.stringify(messages)}`);
        for (const name of expected) assert(messages.some((m) => m.includes(name)), `${unit}: the error on ${name} is listed: ${JSON.stringify(messages)}`);
        // The function's error is the file's, under every chart, not the chart's.
        const inFile = await page.locator('.error-list tbody tr.in-file .col-message').allTextContents();
        assert(inFile.some((m) => m.includes('Gain')), `${unit}: the function's error is listed under the file: ${JSON.stringify(inFile)}`);
        // Each error frames the transition whose condition names the variable, in this chart.
        const rows = page.locator('.error-list tbody tr.sev-error:not(.in-file)');
        for (let r = 0; r < (await rows.count()); r++) {
          const row = rows.nth(r);
          const text = await row.locator('.col-message').textContent();
          const name = expected.find((n) => text.includes(n));
          await row.click();
          const id = await page.evaluate((n) => window.__sfc.doc().elements.find((e) => e.kind === 'transition' && e.condition.includes(n))?.id, name);
          assert(id, `${unit}: a transition names ${name}`);
          await until(page, `${unit}: the block of ${name} framed`, () =>
            page.evaluate((i) => !!document.querySelector(`.canvas-pane.active [data-element-id="${i}"] rect[stroke="#7c3aed"]`), id),
          );
          const framed = await page.evaluate(() => document.querySelectorAll('.canvas-pane.active rect[stroke="#7c3aed"]').length);
          assert(framed === 1, `${unit}: one block framed, got ${framed}`);
        }
      }
    },
  },
  {
    name: 'project: an error fixed by an edit leaves the Error list, comes back on undo and leaves again on redo',
    run: async (t) => {
      const { page } = t;
      await openProject(t);
      const listed = async () => (await ownErrors(page)).some((m) => m.includes('LevelIntake'));
      assert(await listed(), 'the error on LevelIntake is listed');
      const d = await page.evaluate(() => window.__sfc.doc());
      const tr = d.elements.find((e) => e.kind === 'transition' && e.condition.includes('LevelIntake'));
      await select(page, tr.id);
      await setCondition(page, tr.id, 'Level > 10');
      await until(page, 'the fixed error gone', async () => !(await listed()));
      await page.locator('.toolbar button[title^="Undo"]').click();
      await page.waitForFunction((i) => window.__sfc.doc().elements.find((e) => e.id === i).condition.includes('LevelIntake'), tr.id);
      await until(page, 'the error back after undo', listed);
      await page.locator('.toolbar button[title^="Redo"]').click();
      await until(page, 'the error gone after redo', async () => !(await listed()));
      // Other charts' lists are untouched.
      await page.locator('.project-tree [data-kind="pou"][data-pou="Mixer"]').click();
      await page.waitForFunction(() => window.__sfc.doc()?.pou === 'Mixer');
      assert((await ownErrors(page)).length === 2, 'Mixer keeps its two errors');
    },
  },
];
