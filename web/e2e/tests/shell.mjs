// The window at a laptop's size: the start screen with no chart open keeps the normal layout
// (menu, toolbar, the start screen with recent charts, the panels, the status bar at the
// bottom), the palette scrolls to its last entry at 1280×720, and German labels fit.
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, shotPath, waitChart } from '../helpers.mjs';

const overlap = (a, b) => a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;

export const tests = [
  {
    name: 'the start screen: New, Open, the charts there and recent ones, in the normal layout',
    run: async (t) => {
      const { page } = t;
      await page.setViewportSize({ width: 1280, height: 720 });
      const dir = path.join(t.scratch, 'work');
      fs.mkdirSync(dir);
      fs.copyFileSync(path.join(t.scratch, 'examples/blinker/blinker.st'), path.join(dir, 'blinker.st'));
      await openEditor(t, [dir]);
      const welcome = page.getByTestId('welcome');
      await welcome.waitFor();
      await page.locator('.welcome-file', { hasText: 'blinker.st' }).waitFor();
      await page.screenshot({ path: shotPath(t, 'start-screen-1280x720.png') });
      const rect = (sel) => page.locator(sel).first().boundingBox();
      const [toolbar, title, status, bottom, side] = await Promise.all([rect('.toolbar'), rect('.welcome h1'), rect('.statusbar'), rect('.bottom-panel'), rect('.side-panel')]);
      assert(!overlap(toolbar, title), 'the title does not overlap the toolbar');
      assert(Math.abs(status.y + status.height - 720) <= 1, `the status bar sits at the bottom (${status.y + status.height})`);
      assert(bottom.y > title.y + title.height && bottom.height >= 150, `the error list has its room below: ${JSON.stringify(bottom)}`);
      assert(side.height > 500, 'the properties panel spans the workspace');
      for (const name of ['New…', 'Open…']) assert(await welcome.getByRole('button', { name }).isVisible(), name);
      // Opening a chart from the list; after closing it, it is listed as recent.
      await page.locator('.welcome-file', { hasText: 'blinker.st' }).click();
      await waitChart(page);
      await page.locator('.tab .tab-close').click();
      await page.locator('.welcome-list', { hasText: 'Recent charts' }).locator('.welcome-file', { hasText: 'blinker.st' }).waitFor();
    },
  },
  {
    name: 'at 1280×720 the palette scrolls to Action block; in German every label fits',
    run: async (t) => {
      const { page } = t;
      await page.setViewportSize({ width: 1280, height: 720 });
      await openEditor(t, ['examples/carwash/carwash.st']);
      await waitChart(page);
      const palette = page.locator('.canvas-pane.active .djs-palette');
      const last = page.locator('.canvas-pane.active .djs-palette [data-action="create.action-block"]');
      await last.scrollIntoViewIfNeeded();
      const p = await palette.boundingBox();
      const l = await last.boundingBox();
      assert(l.y >= p.y && l.y + l.height <= p.y + p.height + 1, `Action block is reachable inside the palette: ${JSON.stringify({ p, l })}`);
      const pane = await page.locator('.canvas-pane.active').boundingBox();
      assert(p.y + p.height <= pane.y + pane.height, 'the palette stays inside the canvas');
      // German from the status bar, kept by the server (its answer awaited), then a fresh page.
      const kept = page.waitForResponse((r) => r.url().endsWith('/api/settings') && r.request().method() === 'POST');
      await page.locator('.statusbar .status-lang select').selectOption('de');
      await kept;
      await page.reload();
      await waitChart(page);
      const overflowing = await page.evaluate(() =>
        [...document.querySelectorAll('.canvas-pane.active .djs-palette .entry, .canvas-pane.active .djs-palette .sfc-palette-title')]
          .filter((e) => e.scrollWidth > e.clientWidth + 1 || e.getBoundingClientRect().right > e.closest('.djs-palette').getBoundingClientRect().right + 1)
          .map((e) => e.textContent),
      );
      assert(overflowing.length === 0, `German labels overflow: ${overflowing.join(', ')}`);
      assert(await page.locator('.djs-palette', { hasText: 'Alternativzusammenführung' }).count() === 1, 'the German palette is shown');
      await page.screenshot({ path: shotPath(t, 'palette-de-1280x720.png') });
    },
  },
];
