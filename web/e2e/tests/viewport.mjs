// The viewport and the layouts of the translations (issue 36, parts 5, 6 and 8): the car wash in
// a 1600×1000 window fits after *Fit* at no more than 100 %, centred in the canvas beside the
// docked palette, which covers no block; a block dragged onto another stays where it was; in
// German and Czech the action table's headers do not overlap and the table is not clipped, and
// the monitor's toolbar shows the chart's name whole; a new transition has no condition and is
// saved as FALSE. Real mouse and keyboard.
import fs from 'node:fs';
import path from 'node:path';
import { assert, box, dropFromPalette, drag, openEditor, select, shotPath, until, waitChart, wire } from '../helpers.mjs';

const here = path.dirname(new URL(import.meta.url).pathname);
const catalogue = (name) => JSON.parse(fs.readFileSync(path.join(here, '..', '..', 'src', 'i18n', `${name}.json`), 'utf8'));
const CARWASH = 'examples/carwash/carwash.st';

/** The screen rectangles of the active canvas's view and of every block. */
const screen = (page) =>
  page.evaluate(() => {
    const c = document.querySelector('.canvas-pane.active .djs-container').getBoundingClientRect();
    const blocks = window.__sfc.doc().elements.map((e) => ({ id: e.id, ...window.__sfc.box(e.id) }));
    const p = document.querySelector('.canvas-pane.active .djs-palette')?.getBoundingClientRect();
    return { view: { x: c.left, y: c.top, width: c.width, height: c.height }, blocks, palette: p && { x: p.left, y: p.top, width: p.width, height: p.height } };
  });

const overlap = (a, b) => a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;

/** The headers of the Properties action table: each header's text stays in its column. */
const headers = (page) =>
  page.evaluate(() =>
    [...document.querySelectorAll('.side-panel .assoc-table th')].map((th) => {
      const r = document.createRange();
      r.selectNodeContents(th);
      const text = [...r.getClientRects()].reduce(
        (a, q) => ({ left: Math.min(a.left, q.left), right: Math.max(a.right, q.right) }),
        { left: Infinity, right: -Infinity },
      );
      const cell = th.getBoundingClientRect();
      return { text: th.textContent, cellLeft: cell.left, cellRight: cell.right, textLeft: text.left, textRight: text.right, overflow: th.scrollWidth > th.clientWidth };
    }),
  );

async function checkActionTable(page, lang) {
  const d = await page.evaluate(() => window.__sfc.doc());
  const block = d.elements.find((e) => e.kind === 'actionBlock');
  await select(page, block.id);
  await page.locator('.side-panel .assoc-table').waitFor();
  const hs = await headers(page);
  for (let k = 0; k < hs.length; k++) {
    const h = hs[k];
    if (!h.text) continue;
    assert(!h.overflow, `${lang}: the header "${h.text}" overflows its column`);
    assert(h.textRight <= h.cellRight + 0.5 && h.textLeft >= h.cellLeft - 0.5, `${lang}: the header "${h.text}" runs out of its column ${JSON.stringify(h)}`);
    const next = hs[k + 1];
    if (next?.text) assert(h.textRight <= next.textLeft, `${lang}: "${h.text}" overlaps "${next.text}"`);
  }
  // The table is not clipped: its right edge, and its last column's buttons, are in the panel.
  const clip = await page.evaluate(() => {
    const table = document.querySelector('.side-panel .assoc-table').getBoundingClientRect();
    const panel = document.querySelector('.side-panel').getBoundingClientRect();
    const buttons = [...document.querySelectorAll('.side-panel .assoc-table .row-buttons button')].map((b) => b.getBoundingClientRect().right);
    const chain = [];
    for (let e = document.querySelector('.side-panel .assoc-table'); e && e !== document.body; e = e.parentElement) {
      const r = e.getBoundingClientRect();
      chain.push(`${e.tagName.toLowerCase()}.${[...e.classList].join('.')}:${Math.round(r.left)}-${Math.round(r.right)}/${e.scrollWidth}`);
    }
    return { table: table.right, panel: panel.right, buttons: Math.max(0, ...buttons), chain };
  });
  assert(clip.table <= clip.panel && clip.buttons <= clip.panel, `${lang}: the action table is clipped ${JSON.stringify(clip)}`);
  await page.screenshot({ path: shotPath({ root: path.resolve(here, '..', '..', '..') }, `viewport-actions-${lang}.png`) });
}

async function checkMonitorName(t, lang) {
  const { page } = t;
  const m = catalogue(`monitor.${lang}`);
  await page.getByRole('button', { name: m.monitor?.startSim ?? m.startSim }).first().click();
  await page.locator('.mon-overlay').waitFor();
  const title = await page.evaluate(() => {
    const s = document.querySelector('.mon-toolbar .mon-title > span');
    const b = s.getBoundingClientRect();
    const bar = document.querySelector('.mon-toolbar').getBoundingClientRect();
    return { text: s.textContent, scroll: s.scrollWidth, client: s.clientWidth, right: b.right, bar: bar.right };
  });
  assert(title.text === 'CarWash', `${lang}: the monitor's title is ${title.text}`);
  assert(title.scroll <= title.client && title.right <= title.bar, `${lang}: the chart's name is cut ${JSON.stringify(title)}`);
  await page.screenshot({ path: shotPath(t, `viewport-monitor-${lang}.png`) });
}

export const tests = [
  {
    name: 'the car wash at 1600×1000 fits after Fit, centred, at most 100 %; the palette covers no block',
    run: async (t) => {
      const { page } = t;
      await page.setViewportSize({ width: 1600, height: 1000 });
      await openEditor(t, [CARWASH]);
      await waitChart(page);
      await page.locator('.statusbar button[title="Fit chart"]').click();
      await page.waitForTimeout(300);
      const zoom = await page.evaluate(() => window.__sfc.zoom());
      assert(zoom <= 1 + 1e-9, `zoom after Fit: ${zoom}`);
      const s = await screen(page);
      const all = s.blocks.reduce(
        (a, b) => ({ x0: Math.min(a.x0, b.x), y0: Math.min(a.y0, b.y), x1: Math.max(a.x1, b.x + b.width), y1: Math.max(a.y1, b.y + b.height) }),
        { x0: Infinity, y0: Infinity, x1: -Infinity, y1: -Infinity },
      );
      const v = s.view;
      assert(all.x0 >= v.x && all.y0 >= v.y && all.x1 <= v.x + v.width && all.y1 <= v.y + v.height, `the chart does not fit: ${JSON.stringify({ all, v })}`);
      // Centred: the drawing (blocks with their labels) has as much room left as right, and
      // above as below.
      const drawn = await page.evaluate(() => {
        const rs = [...document.querySelectorAll('.canvas-pane.active .djs-element > .djs-visual')].map((g) => g.getBoundingClientRect()).filter((r) => r.width > 0 || r.height > 0);
        return { x0: Math.min(...rs.map((r) => r.left)), y0: Math.min(...rs.map((r) => r.top)), x1: Math.max(...rs.map((r) => r.right)), y1: Math.max(...rs.map((r) => r.bottom)) };
      });
      const [left, right] = [drawn.x0 - v.x, v.x + v.width - drawn.x1];
      const [top, bottom] = [drawn.y0 - v.y, v.y + v.height - drawn.y1];
      assert(left >= 0 && right >= 0 && top >= 0 && bottom >= 0, `the drawing does not fit: ${JSON.stringify({ drawn, v })}`);
      assert(Math.abs(left - right) < 24, `not centred across: ${left} | ${right}`);
      assert(Math.abs(top - bottom) < 24, `not centred down: ${top} | ${bottom}`);
      assert(s.palette, 'the palette is shown');
      for (const b of s.blocks) assert(!overlap(s.palette, b), `the palette covers ${b.id}`);
      await page.screenshot({ path: shotPath(t, 'viewport-carwash-fit.png') });
      // Docked: the palette is a column beside the view, never over it, however the chart is
      // scrolled (the drawing is clipped at the view's edge).
      assert(s.palette.x + s.palette.width <= v.x + 0.5, `the palette lies over the view: ${JSON.stringify(s)}`);
      const clipped = await page.evaluate(() => getComputedStyle(document.querySelector('.canvas-pane.active .djs-container svg')).overflow);
      assert(clipped === 'hidden', `the drawing is not clipped at the view's edge: ${clipped}`);
    },
  },
  {
    name: 'a block dragged onto another stays where it was',
    run: async (t) => {
      const { page } = t;
      await page.setViewportSize({ width: 1600, height: 1000 });
      await openEditor(t, ['examples/traffic/traffic.st']);
      const d = await waitChart(page);
      const steps = d.elements.filter((e) => e.kind === 'step');
      const [a, b] = [steps[0], steps[1]];
      const ba = await box(page, a.id);
      const bb = await box(page, b.id);
      await drag(page, { x: ba.x + ba.width / 2, y: ba.y + ba.height / 2 }, { x: bb.x + bb.width / 2 + 8, y: bb.y + bb.height / 2 + 4 }, 12);
      await page.waitForTimeout(300);
      const moved = await page.evaluate((i) => window.__sfc.doc().elements.find((e) => e.id === i), a.id);
      assert(moved.x === a.x && moved.y === a.y, `${a.id} was moved onto ${b.id}: ${moved.x},${moved.y}`);
      // A move to free room is still taken.
      const free = { x: ba.x + ba.width / 2 - 200, y: ba.y + ba.height / 2 };
      await drag(page, { x: ba.x + ba.width / 2, y: ba.y + ba.height / 2 }, free, 12);
      await page.waitForFunction(([i, x]) => window.__sfc.doc().elements.find((e) => e.id === i).x !== x, [a.id, a.x]);
    },
  },
  {
    name: 'German and Czech at 1600×1000: action-table headers apart and whole, the monitor shows the chart name whole',
    run: async (t) => {
      const { page } = t;
      await page.setViewportSize({ width: 1600, height: 1000 });
      await openEditor(t, [CARWASH], { lang: 'de' });
      await waitChart(page);
      await checkActionTable(page, 'de');
      await checkMonitorName(t, 'de');
    },
  },
  {
    name: 'Czech at 1600×1000: action-table headers apart and whole, the monitor shows the chart name whole',
    run: async (t) => {
      const { page } = t;
      await page.setViewportSize({ width: 1600, height: 1000 });
      await openEditor(t, [CARWASH], { lang: 'cs' });
      await waitChart(page);
      await checkActionTable(page, 'cs');
      await checkMonitorName(t, 'cs');
    },
  },
  {
    name: 'a new transition has no condition and is saved as FALSE',
    run: async (t) => {
      const { page } = t;
      fs.writeFileSync(
        path.join(t.scratch, 'fresh.st'),
        'PROGRAM Fresh\nVAR\nEND_VAR\nINITIAL_STEP Init : END_STEP\nEND_PROGRAM\n',
      );
      await openEditor(t, ['fresh.st']);
      const d = await waitChart(page);
      const init = d.elements.find((e) => e.kind === 'step');
      const tr = await dropFromPalette(page, 'transition', { x: init.x + init.w / 2, y: init.y + init.h + 60 });
      const made = await page.evaluate((i) => window.__sfc.doc().elements.find((e) => e.id === i), tr);
      assert((made.condition ?? '') === '', `a new transition's condition: ${JSON.stringify(made.condition)}`);
      const st = await dropFromPalette(page, 'step', { x: init.x + init.w / 2, y: init.y + init.h + 160 });
      assert(await wire(page, init.id, tr), 'Init wired to the transition');
      assert(await wire(page, tr, st), 'the transition wired to the step');
      const saved = page.waitForResponse((r) => r.url().endsWith('/api/save') && r.status() === 200);
      await page.keyboard.press('Control+s');
      await saved;
      const text = fs.readFileSync(path.join(t.scratch, 'fresh.st'), 'utf8');
      assert(/TRANSITION[^;]*FROM Init TO \w+\s*:=\s*FALSE;/.test(text), `the saved transition:\n${text}`);
    },
  },
];
