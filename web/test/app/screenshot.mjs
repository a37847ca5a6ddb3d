// Screenshots of the shell against the mock server (test/app/mock-server.mjs must be running):
//   node test/app/screenshot.mjs [URL] [OUT.png] [actions…]
// actions: select=ID (select a block), validate, build, lang=cs|de, dialog=new|print|open
import { mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { chromium } from 'playwright-core';

const [url = 'http://127.0.0.1:5174/?token=mock', out = 'test/app/shell.png', ...actions] = process.argv.slice(2);
// A fresh profile directory per run (playwright takes it as launchPersistentContext's argument).
const browser = await chromium.launchPersistentContext(mkdtempSync(join(tmpdir(), 'sfc-shot-')), {
  executablePath: '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  viewport: { width: 1440, height: 900 },
});
const page = await browser.newPage();
const errors = [];
page.on('pageerror', (e) => errors.push(String(e)));
page.on('console', (m) => m.type() === 'error' && errors.push(m.text()));
await page.addInitScript(() => localStorage.setItem('sfc.language', 'en'));
await page.goto(url);
await page.waitForSelector('.tab, .host-title', { timeout: 10000 });
await page.waitForTimeout(500);
for (const a of actions) {
  const at = a.indexOf('=');
  const [k, v] = at < 0 ? [a, ''] : [a.slice(0, at), a.slice(at + 1)];
  if (k === 'select') await page.evaluate((id) => document.querySelector(`[data-element-id="${id}"]`)?.dispatchEvent(new MouseEvent('click', { bubbles: true })), v);
  if (k === 'click') await page.click(v);
  if (k === 'force') await page.click(v, { force: true });
  if (k === 'validate' || k === 'build') {
    await page.selectOption('select.tool-select >> nth=0', k === 'validate' ? 'validate' : 'build');
    await page.click('.tool-button.primary');
  }
  if (k === 'lang') await page.selectOption('.status-lang select', v);
  if (k === 'dialog') {
    await page.keyboard.press(v === 'new' ? 'Control+Shift+N' : v === 'print' ? 'Control+P' : 'Escape');
  }
  if (k === 'key') await page.keyboard.press(v);
  await page.waitForTimeout(400);
}
await page.screenshot({ path: out });
console.log(errors.length ? `page errors:\n${errors.join('\n')}` : 'no page errors');
await browser.close();
