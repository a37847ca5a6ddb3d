// The canvas with blocks that have tooltips (descriptions): a diagnostic frames its step even
// when the step has an action block and a tooltip, clicking its row frames it again, and clicks
// on transitions (forced, on their graphics) select them without a script error.
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, waitChart } from '../helpers.mjs';

const here = path.dirname(new URL(import.meta.url).pathname);

/** The stroke colours of the frames drawn in a block's visual. */
const frames = (page, id) =>
  page.evaluate((i) => {
    const visual = document.querySelector(`.canvas-pane.active [data-element-id="${i}"] > .djs-visual`);
    return visual ? [...visual.querySelectorAll(':scope > rect[rx="3"]')].map((r) => r.getAttribute('stroke')) : null;
  }, id);

export const tests = [
  {
    name: 'a described step with an action block shows its frame; forced clicks on transitions select them',
    run: async (t) => {
      const { page } = t;
      const errors = [];
      page.on('pageerror', (e) => errors.push(e.message));
      page.on('console', (m) => m.type() === 'error' && errors.push(m.text()));
      fs.copyFileSync(path.join(here, '..', 'fixtures', 'described.st'), path.join(t.scratch, 'described.st'));
      await openEditor(t, ['described.st']);
      const d = await waitChart(page);
      const lit = d.elements.find((e) => e.id === 'step:Lit');
      assert(lit.description === 'The lamp stays on', 'the step has its description');
      assert(d.elements.some((e) => e.kind === 'actionBlock' && e.step === 'step:Lit'), 'the step has an action block');
      // The warning of the open check frames the step (orange, dashed).
      await page.waitForSelector('.bottom-panel tbody tr.sev-warning');
      await page.waitForFunction(
        (i) => [...(document.querySelector(`.canvas-pane.active [data-element-id="${i}"] > .djs-visual`)?.querySelectorAll(':scope > rect') ?? [])].some((r) => r.getAttribute('stroke') === '#f59e0b'),
        'step:Lit',
      );
      // The tooltip stays the element's, after the visual.
      const title = await page.evaluate(() => {
        const g = document.querySelector('.canvas-pane.active [data-element-id="step:Lit"]');
        return { text: g.querySelector(':scope > title')?.textContent, first: g.firstElementChild.classList.contains('djs-visual') };
      });
      assert(title.text === 'The lamp stays on' && title.first, `tooltip ${JSON.stringify(title)}`);
      // Clicking the row adds the purple frame of the selected diagnostic, several times over.
      for (let k = 0; k < 3; k++) {
        await page.locator('.bottom-panel tbody tr.sev-warning').click();
        await page.waitForFunction((i) => {
          const v = document.querySelector(`.canvas-pane.active [data-element-id="${i}"] > .djs-visual`);
          return [...v.querySelectorAll(':scope > rect')].some((r) => r.getAttribute('stroke') === '#7c3aed');
        }, 'step:Lit');
        await page.locator('.bottom-panel .toggle', { hasText: 'Highlight' }).click();
        await page.waitForFunction((i) => {
          const v = document.querySelector(`.canvas-pane.active [data-element-id="${i}"] > .djs-visual`);
          return ![...v.querySelectorAll(':scope > rect')].some((r) => r.getAttribute('stroke') === '#7c3aed');
        }, 'step:Lit');
        await page.locator('.bottom-panel .toggle', { hasText: 'Highlight' }).click();
      }
      const litFrames = await frames(page, 'step:Lit');
      assert(litFrames.includes('#f59e0b'), `frames of Lit: ${litFrames}`);

      // Forced clicks on a described transition's hit area select it; no script errors.
      for (const id of ['transition:SwitchOn']) {
        await page.locator(`.canvas-pane.active [data-element-id="${id}"] .djs-hit`).click({ force: true });
        await page.waitForFunction((i) => window.__sfc.selection().join() === i, id);
        await page.locator(`.canvas-pane.active [data-element-id="${id}"]`).click({ force: true });
      }
      assert(errors.length === 0, `script errors: ${errors.join('\n')}`);
    },
  },
  {
    name: 'zoom with Ctrl+wheel and the status-bar slider; the grid shows from 75 %',
    run: async (t) => {
      const { page } = t;
      await openEditor(t, ['examples/traffic/traffic.st']);
      await waitChart(page);
      const zoom = () => page.evaluate(() => window.__sfc.zoom());
      const gridShown = () =>
        page.evaluate(() => {
          const g = document.querySelector('.canvas-pane.active .sfc-grid');
          return !!g && getComputedStyle(g).display !== 'none' && g.getAttribute('visibility') !== 'hidden';
        });
      // The slider sets an absolute level (logarithmic, in hundredths of ln zoom).
      const slider = page.getByTestId('zoom-slider');
      await slider.fill(String(Math.round(100 * Math.log(0.5))));
      await page.waitForFunction(() => Math.abs(window.__sfc.zoom() - 0.5) < 0.02);
      assert(!(await gridShown()), 'no grid at 50 %');
      await slider.fill(String(Math.round(100 * Math.log(1.5))));
      await page.waitForFunction(() => Math.abs(window.__sfc.zoom() - 1.5) < 0.02);
      assert(await gridShown(), 'the grid at 150 %');
      const shown = (await page.locator('.statusbar .zoom-value').textContent()).trim();
      assert(shown === `${Math.round((await zoom()) * 100)} %`, `the status bar shows the zoom: ${shown}`);
      // Ctrl+wheel over the chart zooms out; a plain wheel scrolls without zooming.
      const pane = await page.locator('.canvas-pane.active').boundingBox();
      await page.mouse.move(pane.x + pane.width / 2, pane.y + pane.height / 2);
      const before = await zoom();
      await page.keyboard.down('Control');
      await page.mouse.wheel(0, 300);
      await page.keyboard.up('Control');
      await page.waitForFunction((z) => window.__sfc.zoom() < z - 0.05, before);
      // The wheel arrives as several events: wait until the zoom settles.
      let zoomed = await zoom();
      for (let settled = 0; settled < 3; ) {
        await page.waitForTimeout(100);
        const z = await zoom();
        settled = z === zoomed ? settled + 1 : 0;
        zoomed = z;
      }
      const view = await page.evaluate(() => window.__sfc.view());
      await page.mouse.wheel(0, 200);
      await page.waitForFunction((y) => window.__sfc.view().y !== y, view.y);
      const after = await zoom();
      assert(Math.abs(after - zoomed) < 1e-6, `a plain wheel does not zoom: ${zoomed} → ${after}`);
    },
  },
];
