// Screenshot of the demo page: node test/diagram/shot.mjs URL OUT.png [width height]
import { chromium } from 'playwright-core';
import { mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const [url, out, w = '1200', h = '800'] = process.argv.slice(2);
const dir = mkdtempSync(join(tmpdir(), 'sfc-shot-'));
const browser = await chromium.launchPersistentContext(dir, {
  executablePath: '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  viewport: { width: Number(w), height: Number(h) },
});
const page = await browser.newPage();
page.on('console', (m) => console.log('console:', m.text()));
page.on('pageerror', (e) => console.log('pageerror:', e.message));
await page.goto(url);
await page.waitForTimeout(800);
console.log('load ms:', await page.evaluate(() => window.sfcLoadMs));
await page.screenshot({ path: out });
await browser.close();
