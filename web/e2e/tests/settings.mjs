// Settings that last (issue 36): the language and the recent charts are kept by the server in the
// config directory (SFC_CONFIG_DIR, the test's own, t.config), not in the browser's storage of
// one origin, so a later `sfc edit` on another port comes up in the language chosen and lists
// the charts opened; a recent chart that editor does not serve is listed greyed, not opened; a
// choice an older editor left in localStorage moves to the server once.
import fs from 'node:fs';
import path from 'node:path';
import { assert, shotPath, waitChart } from '../helpers.mjs';

/** The settings as the server answers them to the page. */
const kept = (page) => page.evaluate(async () => (await fetch('/api/settings', { headers: { 'X-Sfc-Page': '1' } })).json());

/** `action` and the answer of the POST /api/settings it causes. */
async function storing(page, action) {
  const answer = page.waitForResponse((r) => r.url().endsWith('/api/settings') && r.request().method() === 'POST');
  await action();
  const r = await answer;
  assert(r.ok(), `POST /api/settings: ${r.status()}`);
  return r.json();
}

/** A folder of the scratch directory holding the blinker chart. */
function work(t) {
  const dir = path.join(t.scratch, 'work');
  fs.mkdirSync(dir, { recursive: true });
  fs.copyFileSync(path.join(t.scratch, 'examples/blinker/blinker.st'), path.join(dir, 'blinker.st'));
  return dir;
}

export const tests = [
  {
    name: 'German and the recent chart outlast the server: a new one on another port comes up with them',
    run: async (t) => {
      const { page } = t;
      const dir = work(t);
      const chart = path.join(fs.realpathSync(dir), 'blinker.st');
      const first = await t.edit([dir]);
      await page.goto(first.url);
      await page.getByTestId('welcome').waitFor();
      await page.waitForFunction(() => document.documentElement.lang === 'en');
      // Open the chart from the start screen: it becomes recent, on the server.
      const afterOpen = await storing(page, () => page.locator('.welcome-file', { hasText: 'blinker.st' }).click());
      assert(JSON.stringify(afterOpen.recent) === JSON.stringify([chart]), `recent: ${JSON.stringify(afterOpen.recent)}`);
      await waitChart(page);
      const afterLang = await storing(page, () => page.locator('.statusbar .status-lang select').selectOption('de'));
      assert(afterLang.language === 'de' && afterLang.recent[0] === chart, `kept: ${JSON.stringify(afterLang)}`);
      const file = JSON.parse(fs.readFileSync(path.join(t.config, 'editor.json'), 'utf8'));
      assert(file.language === 'de', `the settings file in SFC_CONFIG_DIR: ${JSON.stringify(file)}`);
      assert((await page.evaluate(() => localStorage.length)) === 0, 'nothing kept in localStorage');
      await first.stop();

      // Another run, on another port: another origin, whose localStorage is empty.
      const second = await t.edit([dir]);
      assert(second.base !== first.base, `another port: ${second.base}`);
      const fresh = await t.context.newPage();
      // The first menu title as first rendered: German from the start, not English switched.
      await fresh.addInitScript(() => {
        new MutationObserver((_, observer) => {
          const m = document.querySelector('.menubar .menu-title');
          if (m) {
            window.__firstMenu = m.textContent.trim();
            observer.disconnect();
          }
        }).observe(document, { subtree: true, childList: true });
      });
      await fresh.goto(second.url);
      await fresh.getByTestId('welcome').waitFor();
      const de = JSON.parse(fs.readFileSync(path.join(t.root, 'web/src/i18n/de.json'), 'utf8'));
      assert((await fresh.evaluate(() => document.documentElement.lang)) === 'de', 'the page is in German');
      const firstMenu = await fresh.evaluate(() => window.__firstMenu);
      assert(firstMenu === de.menu.file, `the first render is German: ${firstMenu}`);
      const recent = fresh.locator('.welcome-list', { hasText: de.start.recent });
      await recent.locator('.welcome-file', { hasText: 'blinker.st' }).waitFor();
      await fresh.screenshot({ path: shotPath(t, 'settings-second-run-de.png') });
      // The recent chart opens from there.
      await recent.locator('.welcome-file', { hasText: 'blinker.st' }).click();
      await waitChart(fresh);
      await fresh.close();
      await second.stop();

      // A third run on another chart only: blinker.st is listed greyed with the reason, and
      // not opened (the server opens only what it was started on).
      const other = await t.edit(['examples/carwash/carwash.st']);
      const third = await t.context.newPage();
      await third.goto(other.url);
      // The named chart opens at start; closing it shows the start screen.
      await waitChart(third);
      await third.locator('.tab .tab-close').click();
      const listed = third.locator('.welcome-list', { hasText: de.start.recent }).locator('.welcome-file', { hasText: 'blinker.st' });
      await listed.waitFor();
      assert(await listed.evaluate((e) => e.classList.contains('not-served')), 'greyed');
      assert((await listed.textContent()).includes(de.start.notServed), 'with the reason');
      await third.screenshot({ path: shotPath(t, 'settings-not-served.png') });
      const opens = [];
      third.on('request', (r) => r.url().endsWith('/api/open') && opens.push(r.url()));
      await listed.click();
      await third.waitForTimeout(300);
      assert(opens.length === 0, 'a chart the editor does not serve is not asked for');
      assert((await third.locator('.tab').count()) === 0, 'nothing opened');
    },
  },
  {
    name: 'what an older editor kept in localStorage moves to the server once',
    run: async (t) => {
      const { page } = t;
      const dir = work(t);
      const server = await t.edit([dir]);
      await page.goto(server.url);
      await page.getByTestId('welcome').waitFor();
      await page.evaluate(() => {
        localStorage.setItem('sfc.language', 'cs');
        localStorage.setItem('sfc.recent', JSON.stringify(['/elsewhere/old.st']));
        localStorage.setItem('sfc.monitor.watch.Blinker', JSON.stringify(['Lamp']));
      });
      await page.reload();
      await page.getByTestId('welcome').waitFor();
      await page.waitForFunction(() => document.documentElement.lang === 'cs');
      const s = await kept(page);
      assert(s.language === 'cs', `language moved: ${JSON.stringify(s)}`);
      assert(JSON.stringify(s.recent) === JSON.stringify(['/elsewhere/old.st']), `recent moved: ${JSON.stringify(s)}`);
      assert(JSON.stringify(s.watch) === JSON.stringify({ Blinker: ['Lamp'] }), `watch list moved: ${JSON.stringify(s)}`);
      assert((await page.evaluate(() => localStorage.length)) === 0, 'localStorage emptied once moved');
      // From now on the server's choice holds: a stale value in localStorage does not win.
      await page.evaluate(() => localStorage.setItem('sfc.language', 'en'));
      await page.reload();
      await page.getByTestId('welcome').waitFor();
      assert((await page.evaluate(() => document.documentElement.lang)) === 'cs', 'the server wins');
    },
  },
];
