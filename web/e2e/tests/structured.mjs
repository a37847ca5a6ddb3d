// Structured editing (docs/editor.md, "Structured editing"), with real clicks and keys on the
// car wash (examples/carwash/carwash.st): Insert / Shift+Insert put a step and a transition
// after / before the selected block, the Edit menu does the same, Delete on a step between two
// transitions removes its transition too and reconnects (inside a selection branch), a step
// dropped from the palette on a wire goes into the sequence, a press beside a pin draws a
// wire and a selected step has no resize handle on its pins. Each saves (Ctrl+S) and the file
// holds the new STEP/TRANSITION with the right FROM/TO and has no SFC0204/SFC0205 problem.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { assert, box, doc, drag, dropFromPalette, openEditor, pin, select, shotPath, toScreen, waitChart } from '../helpers.mjs';

const CARWASH = 'examples/carwash/carwash.st';

async function openCarwash(t) {
  await t.page.setViewportSize({ width: 1600, height: 1200 });
  await openEditor(t, [CARWASH]);
  await waitChart(t.page);
  return path.join(t.scratch, CARWASH);
}

/** Scrolls the canvas (mouse wheel) until block `id` is in the middle part of the view. */
async function inView(page, id) {
  const pane = await page.locator('.canvas-pane.active').boundingBox();
  const cx = pane.x + 200 + (pane.width - 200) / 2;
  const cy = pane.y + pane.height / 2;
  for (let k = 0; k < 8; k++) {
    const b = await box(page, id);
    const dx = b.x + b.width / 2 - cx;
    const dy = b.y + b.height / 2 - cy;
    if (Math.abs(dx) < (pane.width - 200) / 3 && Math.abs(dy) < pane.height / 3) return;
    await page.mouse.move(cx, cy);
    await page.mouse.wheel(dx, dy);
    await page.waitForTimeout(100);
  }
}

/** Selects the block named `name`, scrolled into view; returns its id. */
async function pick(page, name) {
  const id = await idOf(page, name);
  assert(id, `no block ${name}`);
  await inView(page, id);
  await select(page, id);
  return id;
}

const idOf = async (page, name) => (await doc(page)).elements.find((e) => e.name === name)?.id;

async function saveNow(page) {
  const saves = page.waitForResponse((r) => r.url().endsWith('/api/save') && r.status() === 200);
  await page.keyboard.press('Control+s');
  await saves;
  await page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty));
}

/** The codes `sfc check` reports for the file (errors make it exit non-zero). */
function codes(t, file) {
  let out;
  try {
    out = execFileSync(t.sfcBin, ['check', '--no-analysis', '--format', 'json', file], { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
  } catch (e) {
    out = e.stdout;
  }
  return [...String(out).matchAll(/"code"\s*:\s*"(SFC\d+)"/g)].map((m) => m[1]);
}

/** The saved file has each of `lines` (regular expressions, multi-line) and no dangling piece. */
function checkSaved(t, file, has, hasNot = []) {
  const text = fs.readFileSync(file, 'utf8');
  for (const re of has) assert(re.test(text), `the saved file has no ${re}`);
  for (const re of hasNot) assert(!re.test(text), `the saved file still has ${re}`);
  const found = codes(t, file);
  assert(!found.includes('SFC0204') && !found.includes('SFC0205'), `sfc check reports ${found.join(', ')}`);
  return text;
}

export const tests = [
  {
    name: 'Insert after a step and Shift+Insert before a step behind a convergence, saved with their FROM/TO',
    run: async (t) => {
      const { page } = t;
      const file = await openCarwash(t);
      await pick(page, 'Drying');
      const before = (await box(page, await idOf(page, 'TDriedAtHome'))).y;
      await page.keyboard.press('Insert');
      await page.waitForFunction(() => window.__sfc.doc().elements.some((e) => e.name === 'Step1'));
      // The transition below moved down to make room.
      assert((await box(page, await idOf(page, 'TDriedAtHome'))).y > before, 'TDriedAtHome did not move down');
      // The new step is selected; Fault (two predecessors: a selection convergence above it).
      await pick(page, 'Fault');
      await page.keyboard.press('Shift+Insert');
      await page.waitForFunction(() => window.__sfc.doc().elements.some((e) => e.name === 'Step2'));
      await inView(page, await idOf(page, 'Step1'));
      await page.screenshot({ path: shotPath(t, 'structured-insert.png') });
      await saveNow(page);
      checkSaved(t, file, [
        /TRANSITION T1 FROM Drying TO Step1\b/,
        /TRANSITION TDriedAtHome FROM Step1 TO Idle\b/,
        /^\s*STEP Step1:/m,
        /TRANSITION \w+ FROM \w+ TO Step2\b/,
        /TRANSITION T2 FROM Step2 TO Fault\b/,
      ]);
      // One undo step each.
      await page.keyboard.press('Control+z');
      await page.keyboard.press('Control+z');
      await page.waitForFunction(() => !window.__sfc.doc().elements.some((e) => e.name === 'Step1' || e.name === 'Step2'));
    },
  },
  {
    name: 'the Edit menu inserts after a transition',
    run: async (t) => {
      const { page } = t;
      const file = await openCarwash(t);
      await pick(page, 'TCarLeftDry');
      await page.locator('.menubar .menu-title').filter({ hasText: 'Edit' }).click();
      await page.locator('.menu-dropdown .menu-item').filter({ hasText: 'Insert step and transition after' }).click();
      await page.waitForFunction(() => window.__sfc.doc().elements.some((e) => e.name === 'Step1'));
      await saveNow(page);
      checkSaved(t, file, [/TRANSITION TCarLeftDry FROM Brushing TO Step1\b/, /TRANSITION T1 FROM Step1 TO Drying\b/]);
    },
  },
  {
    name: 'Delete on a step inside a selection branch removes its transition and reconnects',
    run: async (t) => {
      const { page } = t;
      const file = await openCarwash(t);
      const n = (await doc(page)).elements.length;
      await pick(page, 'Drying');
      await page.keyboard.press('Delete');
      await page.waitForFunction(() => !window.__sfc.doc().elements.some((e) => e.name === 'Drying' || e.name === 'TDriedAtHome'));
      const d = await doc(page);
      // Drying, TDriedAtHome and Drying's action block.
      assert(d.elements.length <= n - 2, `${n - d.elements.length} blocks removed`);
      await saveNow(page);
      checkSaved(t, file, [/TRANSITION TCarLeftDry FROM Brushing TO Idle\b/], [/STEP Drying\b/, /TDriedAtHome/]);
    },
  },
  {
    name: 'a step dropped on the wire of a transition and a step goes into the sequence',
    run: async (t) => {
      const { page } = t;
      const file = await openCarwash(t);
      const tr = await idOf(page, 'TCarLeftDry');
      await inView(page, tr);
      // The middle of the wire's longest vertical run, in canvas units.
      const w = (await doc(page)).connections.find((c) => c.source === tr);
      let at = null;
      let longest = -1;
      for (let i = 1; i < w.waypoints.length; i++) {
        const [p, q] = [w.waypoints[i - 1], w.waypoints[i]];
        if (p.x === q.x && Math.abs(q.y - p.y) > longest) {
          longest = Math.abs(q.y - p.y);
          at = { x: p.x, y: (p.y + q.y) / 2 };
        }
      }
      const item = page.locator('.canvas-pane.active .djs-palette [data-action="create.step"]');
      const from = await item.boundingBox();
      await drag(page, { x: from.x + from.width / 2, y: from.y + from.height / 2 }, await toScreen(page, at), 10);
      const added = at;
      // The drop makes two blocks (the step and its transition): wait for both.
      await page.waitForFunction(() => window.__sfc.doc().elements.some((e) => e.name === 'T1'));
      const d = await doc(page);
      await page.screenshot({ path: shotPath(t, 'structured-drop.png') });
      const step = d.elements.find((e) => e.kind === 'step' && /^S\d+$/.test(e.name ?? ''));
      assert(step, `no new step (dropped at ${JSON.stringify(added)})`);
      await saveNow(page);
      checkSaved(t, file, [new RegExp(`TRANSITION TCarLeftDry FROM Brushing TO ${step.name}\\b`), new RegExp(`TRANSITION T1 FROM ${step.name} TO Drying\\b`)]);
    },
  },
  {
    name: 'a press 8 px beside a free pin draws a wire; a selected step has no resize handle on its pins',
    run: async (t) => {
      const { page } = t;
      await page.setViewportSize({ width: 1600, height: 1200 });
      fs.writeFileSync(path.join(t.scratch, 'pins.st'), 'PROGRAM Pins\n    VAR\n        x : BOOL;\n    END_VAR\n\n    INITIAL_STEP Init: END_STEP\nEND_PROGRAM\n');
      await openEditor(t, ['pins.st']);
      const d = await waitChart(page);
      const init = d.elements[0];
      const s = await dropFromPalette(page, 'step', { x: init.x + 300, y: init.y + 20 });
      const tr = await dropFromPalette(page, 'transition', { x: init.x + 300, y: init.y + 200 });
      // The first click after a drag from the palette does not select (diagram-js ends the
      // create on the mouse-up, without a click): click until the step is selected.
      for (let i = 0; i < 3; i++) {
        const b = await box(page, s);
        await page.mouse.click(b.x + 60, b.y + 20);
        await page.waitForTimeout(600);
        const sel = await page.evaluate(() => window.__sfc.selection());
        if (sel.length === 1 && sel[0] === s) break;
      }
      await page.waitForFunction((i) => window.__sfc.selection().join() === i, s, { timeout: 3000 });
      const dirs = await page.evaluate(() => [...document.querySelectorAll('.canvas-pane.active .djs-resizer')].map((r) => [...r.classList].find((c) => /^djs-resizer-[nswe]+$/.test(c))));
      assert(dirs.length > 0 && !dirs.includes('djs-resizer-s') && !dirs.includes('djs-resizer-n'), `resize handles ${dirs}`);
      // 8 px (on screen) below the output pin, outside the step.
      const out = await pin(page, s, 'out');
      const into = await pin(page, tr, 'in');
      const n = (await doc(page)).connections.length;
      await drag(page, { x: out.x, y: out.y + 8 }, { x: into.x, y: into.y + 2 });
      await page.waitForFunction((k) => window.__sfc.doc().connections.length > k, n, { timeout: 5000 });
      const c = (await doc(page)).connections.at(-1);
      assert(c.source === s && c.target === tr, `the wire runs ${c.source} → ${c.target}`);
      assert((await box(page, s)).height === 40, 'the step was resized');
    },
  },
];
