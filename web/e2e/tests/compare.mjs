// File → Compare with saved / git HEAD: the blinker example, a step renamed and a condition
// changed on the canvas, then Compare with saved: the renamed step and the changed transition
// framed orange on the canvas, both listed in the Comparison panel (a click on a row selects its
// block), an edit clearing the colours; a step added framed green; Compare with git HEAD in a
// repository of its own, and outside one its message.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { assert, doc, dropFromPalette, openEditor, select, setCondition, setField, shotPath, waitChart } from '../helpers.mjs';

const ORANGE = '#ef6c00';
const GREEN = '#2e7d32';

/** The stroke colours of the frames drawn around a block on the active canvas. */
const frames = (page, id) =>
  page.evaluate((i) => {
    const v = document.querySelector(`.canvas-pane.active [data-element-id="${i}"] .djs-visual`);
    return v ? [...v.querySelectorAll(':scope > rect')].map((r) => r.getAttribute('stroke')) : [];
  }, id);

async function pick(page, menu, item) {
  await page.locator('.menubar .menu-title').filter({ hasText: menu }).click();
  await page.locator('.menu-dropdown .menu-item').filter({ hasText: item }).first().click();
}

const panelRow = (page, name) => page.locator('[data-testid="compare-panel"] tbody tr', { has: page.locator('td', { hasText: new RegExp(`^${name}$`) }) });

export const tests = [
  {
    name: 'compare with saved: the renamed step and the changed condition framed and listed',
    run: async (t) => {
      const { page } = t;
      const errors = [];
      page.on('pageerror', (e) => errors.push(e.message));
      const dir = path.join(t.scratch, 'examples', 'blinker');
      const file = path.join(dir, 'blinker.st');
      await openEditor(t, [file]);
      const before = await waitChart(page);
      const s1 = before.elements.find((e) => e.name === 'S1').id;
      const t1 = before.elements.find((e) => e.name === 'T1').id;

      // Nothing edited yet: equal in meaning.
      await pick(page, 'File', 'Compare with saved');
      await page.locator('[data-testid="compare-panel"] .compare-equal', { hasText: 'No differences in meaning' }).waitFor();
      await pick(page, 'File', 'Close comparison');
      await page.locator('[data-testid="compare-panel"]').waitFor({ state: 'detached' });

      // S1 renamed Idle, T1's condition changed.
      await select(page, s1);
      await setField(page, '#p-name', 'Idle');
      await page.waitForFunction((i) => window.__sfc.doc().elements.find((e) => e.id === i)?.name === 'Idle', s1);
      await select(page, t1);
      await setCondition(page, t1, 'Start AND NOT Stop');

      await pick(page, 'File', 'Compare with saved');
      const panel = page.locator('[data-testid="compare-panel"]');
      await panel.waitFor();
      const renamed = panelRow(page, 'Idle');
      await renamed.waitFor();
      assert((await renamed.textContent()).includes('renamed Idle'), `the rename row: ${await renamed.textContent()}`);
      const cond = panelRow(page, 'T1');
      assert((await cond.textContent()).includes('condition: Start → Start AND NOT Stop'), `the condition row: ${await cond.textContent()}`);
      assert((await panel.textContent()).includes(`Compared with the saved file ${file}`), await panel.textContent());
      // Framed orange on the canvas; the other blocks not.
      await page.waitForFunction(([i, c]) => {
        const v = document.querySelector(`.canvas-pane.active [data-element-id="${i}"] .djs-visual`);
        return !!v && [...v.querySelectorAll(':scope > rect')].some((r) => r.getAttribute('stroke') === c);
      }, [s1, ORANGE]);
      assert((await frames(page, t1)).includes(ORANGE), `T1's frames: ${await frames(page, t1)}`);
      const s2 = before.elements.find((e) => e.name === 'S2').id;
      assert(!(await frames(page, s2)).includes(ORANGE), 'S2 did not change and is framed');
      // The document is untouched: no edit, no undo step.
      const undoable = await page.evaluate(() => window.__sfc.canUndo());
      await page.screenshot({ path: shotPath(t, 'compare-1-saved.png') });

      // A click on a row selects its block.
      await cond.click();
      await page.waitForFunction((i) => JSON.stringify(window.__sfc.selection()) === JSON.stringify([i]), t1);
      assert((await page.evaluate(() => window.__sfc.canUndo())) === undoable, 'comparing changed the undo history');

      // Any edit clears the colours and the panel.
      await page.keyboard.press('Control+z');
      await page.waitForFunction((i) => window.__sfc.doc().elements.find((e) => e.id === i)?.condition === 'Start', t1);
      await panel.waitFor({ state: 'detached' });
      assert(!(await frames(page, s1)).includes(ORANGE), 'the colours stay after an edit');

      // The file saved, then compared: equal again; the file on disk changed by another
      // program (a step added before the chart's): that step is listed as removed.
      await page.keyboard.press('Control+s');
      await page.locator('.toast', { hasText: 'Saved' }).waitFor();
      const text = fs.readFileSync(file, 'utf8');
      assert(text.includes('INITIAL_STEP Idle'), 'the rename was not saved');
      const spareText = '    STEP Spare: END_STEP\n\n    TRANSITION TSpare FROM Spare TO Idle\n        := Stop;\n    END_TRANSITION\n\n';
      fs.writeFileSync(file, text.replace('    (* ShowOn runs once more', `${spareText}    (* ShowOn runs once more`));
      await pick(page, 'File', 'Compare with saved');
      const spare = panelRow(page, 'Spare');
      await spare.waitFor();
      assert((await spare.getAttribute('class')).includes('compare-removed'), `Spare's row: ${await spare.getAttribute('class')}`);
      await page.screenshot({ path: shotPath(t, 'compare-2-removed.png') });
      assert(errors.length === 0, `page errors: ${errors.join('; ')}`);
    },
  },
  {
    name: 'compare with git HEAD: a step added framed green; outside git a message',
    run: async (t) => {
      const { page } = t;
      const dir = path.join(t.scratch, 'examples', 'traffic');
      const file = path.join(dir, 'traffic.st');
      // Outside a repository first (the scratch directory is not in one).
      await openEditor(t, [file]);
      const before = await waitChart(page);
      await pick(page, 'File', 'Compare with git HEAD');
      await page.locator('.toast', { hasText: 'is not under git' }).waitFor();

      const git = (...args) => execFileSync('git', args, { cwd: dir, stdio: ['ignore', 'pipe', 'pipe'] });
      git('init', '-q');
      git('config', 'user.name', 'sfc e2e');
      git('config', 'user.email', 'e2e@example.invalid');
      git('config', 'commit.gpgsign', 'false');
      git('add', 'traffic.st');
      git('commit', '-q', '-m', 'traffic');

      // A new step on the canvas, from the palette.
      // Right of the top of the chart, where the canvas is empty and in view.
      const right = Math.max(...before.elements.filter((e) => e.y < 300).map((e) => e.x + e.w));
      const added = await dropFromPalette(page, 'step', { x: right + 120, y: 200 });
      await pick(page, 'File', 'Compare with git HEAD');
      const panel = page.locator('[data-testid="compare-panel"]');
      await panel.waitFor();
      assert((await panel.textContent()).includes(`Compared with git HEAD: ${file}@HEAD`), await panel.textContent());
      const name = (await doc(page)).elements.find((e) => e.id === added).name;
      const row = panelRow(page, name);
      await row.waitFor();
      assert((await row.getAttribute('class')).includes('compare-added'), `the added step's row: ${await row.getAttribute('class')}`);
      await page.waitForFunction(([i, c]) => {
        const v = document.querySelector(`.canvas-pane.active [data-element-id="${i}"] .djs-visual`);
        return !!v && [...v.querySelectorAll(':scope > rect')].some((r) => r.getAttribute('stroke') === c);
      }, [added, GREEN]);
      await page.screenshot({ path: shotPath(t, 'compare-3-head.png') });
    },
  },
];
