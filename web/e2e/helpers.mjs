// Shared gestures and waits of the browser tests: open the editor, drag from the palette, draw
// wires pin to pin, move blocks, fill the Properties panel. Every gesture is a real mouse or
// keyboard action; `window.__sfc` (web/src/app/probe.ts) is read only to aim and to assert.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

/** Where screenshots of the main states go (e2e/out/, next to the failure screenshots). */
export function shotPath(t, name) {
  const dir = path.join(t.root, 'web', 'e2e', 'out');
  fs.mkdirSync(dir, { recursive: true });
  return path.join(dir, name);
}

/** Starts `sfc edit ARGS`, loads the page in English and waits for the shell. (The language is
 *  left in localStorage as an editor of before kept it; the page moves it to the settings the
 *  server keeps, in the test's own config directory, where they have no language yet.) */
export async function openEditor(t, args = [], { lang = 'en' } = {}) {
  const server = await t.edit(args);
  await t.page.addInitScript((l) => {
    if (!localStorage.getItem('sfc.language')) localStorage.setItem('sfc.language', l);
  }, lang);
  await t.page.goto(server.url);
  await t.page.waitForSelector('.statusbar');
  await t.page.waitForFunction(() => !!window.__sfc);
  return server;
}

/** Waits until a chart is shown and drawn, and returns its document. */
export async function waitChart(page) {
  await page.waitForFunction(() => {
    const d = window.__sfc?.doc();
    return !!d && document.querySelectorAll('.canvas-pane.active .djs-element.djs-shape').length >= d.elements.length;
  });
  return page.evaluate(() => window.__sfc.doc());
}

export const doc = (page) => page.evaluate(() => window.__sfc.doc());
export const box = (page, id) => page.evaluate((i) => window.__sfc.box(i), id);
export const pin = (page, id, side, k = 0) => page.evaluate(([i, s, n]) => window.__sfc.pin(i, s, n), [id, side, k]);
export const toScreen = (page, p) => page.evaluate((q) => window.__sfc.toScreen(q), p);

/** Moves the mouse from `a` to `b` in `steps` events with the button held. */
export async function drag(page, a, b, steps = 8) {
  await page.mouse.move(a.x, a.y);
  await page.mouse.down();
  // A first small move passes diagram-js's drag threshold before the long one.
  await page.mouse.move(a.x + (b.x > a.x ? 4 : -4), a.y + 4, { steps: 2 });
  await page.mouse.move(b.x, b.y, { steps });
  await page.mouse.up();
}

/**
 * Drags palette entry `entry` (`step`, `initial-step`, `transition`, `jump`,
 * `selection-divergence`, …) onto the canvas point `at` (canvas units: the new block's centre)
 * and returns the new block's id.
 */
export async function dropFromPalette(page, entry, at) {
  const before = new Set((await doc(page)).elements.map((e) => e.id));
  const item = page.locator(`.canvas-pane.active .djs-palette [data-action="create.${entry}"]`);
  const from = await item.boundingBox();
  if (!from) throw new Error(`palette entry ${entry} is not shown`);
  const to = await toScreen(page, at);
  await drag(page, { x: from.x + from.width / 2, y: from.y + from.height / 2 }, to, 10);
  const handle = await page.waitForFunction((ids) => {
    const added = window.__sfc.doc().elements.filter((e) => !ids.includes(e.id));
    return added.length === 1 ? added[0].id : null;
  }, [...before]);
  return handle.jsonValue();
}

/** Draws a wire from output pin `outPin` of `from` to input pin `inPin` of `to`; returns whether
 *  a connection was added. */
export async function wire(page, from, to, outPin = 0, inPin = 0) {
  const n = (await doc(page)).connections.length;
  const a = await pin(page, from, 'out', outPin);
  const b = await pin(page, to, 'in', inPin);
  await drag(page, a, { x: b.x, y: b.y + 2 }, 8);
  return page
    .waitForFunction((k) => window.__sfc.doc().connections.length > k, n, { timeout: 5000 })
    .then(() => true)
    .catch(() => false);
}

/** Clicks a block (selects it; the Properties panel then shows it). */
export async function select(page, id) {
  const b = await box(page, id);
  // Steps and bars: their middle; transitions: their bar (the middle too).
  await page.mouse.click(b.x + b.width / 2 + (b.width > 30 ? b.width / 4 : 0), b.y + b.height / 2);
  await page.waitForFunction((i) => {
    const sel = window.__sfc.selection();
    return sel.length === 1 && sel[0] === i;
  }, id, { timeout: 3000 });
  await panelShows(page, id);
}

/** Waits until the Properties panel shows block `id` (it renders after the selection changes:
 *  typing before that would go into the previous block's fields). */
export async function panelShows(page, id) {
  await page.locator(`.side-panel .prop-heading span[title="${id}"]`).waitFor({ timeout: 5000 });
}

/** Types into a Properties input and commits it (Enter). */
export async function setField(page, selector, value) {
  const input = page.locator(`.side-panel ${selector}`);
  await input.fill(String(value));
  await input.press('Enter');
}

/** Types a transition's condition into its code editor and commits it (Ctrl+Enter). */
export async function setCondition(page, id, text) {
  const editor = page.locator('.side-panel .code-editor textarea');
  await editor.fill(text);
  await editor.press('Control+Enter');
  await page.waitForFunction(([i, c]) => window.__sfc.doc().elements.find((e) => e.id === i)?.condition === c, [id, text]);
}

/** Runs `sfc ARGS` and returns its standard output (throws with stderr when it fails). */
export function sfc(t, args, cwd = t.scratch) {
  return execFileSync(t.sfcBin, args, { cwd, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
}

/** Fails with a message when `cond` is false. */
export function assert(cond, message) {
  if (!cond) throw new Error(message);
}

/** Deep equality for JSON data, with the first difference's path in the message. */
export function assertSame(actual, expected, what) {
  const diff = firstDifference(actual, expected, '');
  if (diff !== null) throw new Error(`${what}: differs at ${diff || '(root)'}`);
}

function firstDifference(a, b, at) {
  if (a === b) return null;
  if (typeof a !== typeof b || a === null || b === null || typeof a !== 'object') {
    return `${at}: ${JSON.stringify(a)} ≠ ${JSON.stringify(b)}`;
  }
  if (Array.isArray(a) !== Array.isArray(b)) return `${at}: array vs object`;
  const keys = new Set([...Object.keys(a), ...Object.keys(b)]);
  for (const k of keys) {
    const d = firstDifference(a[k], b[k], `${at}.${k}`);
    if (d !== null) return d;
  }
  return null;
}

/** Polls `check` every 50 ms until it returns something truthy (returned), or fails after `ms`. */
export async function until(page, what, check, ms = 15_000) {
  const end = Date.now() + ms;
  let last;
  while (Date.now() < end) {
    last = await check();
    if (last) return last;
    await page.waitForTimeout(50);
  }
  throw new Error(`timed out waiting for ${what} (last: ${JSON.stringify(last)})`);
}
