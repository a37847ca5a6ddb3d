// Merge conflicts: the tank of `sfc merge`'s fixtures (crates/sfc-cli/tests/merge) merged with a
// conflict on TStart's condition (changed both ways), opened in the editor: the Merge conflicts
// panel lists TStart with their version, the transition is framed red-orange, a click on the row
// selects it; "Take theirs" puts their condition on the canvas as an undoable edit (the tab
// dirty, the panel saying none is left); saved with Ctrl+S, `sfc check` passes without SFC0605.
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, sfc, shotPath, waitChart } from '../helpers.mjs';

const CONFLICT = '#e64a19';

/** The stroke colours of the frames drawn around a block on the active canvas. */
const frames = (page, id) =>
  page.evaluate((i) => {
    const v = document.querySelector(`.canvas-pane.active [data-element-id="${i}"] .djs-visual`);
    return v ? [...v.querySelectorAll(':scope > rect')].map((r) => r.getAttribute('stroke')) : [];
  }, id);

const condition = (page, id) => page.evaluate((i) => window.__sfc.doc().elements.find((e) => e.id === i)?.condition, id);

export const tests = [
  {
    name: 'a merged file: the TStart conflict listed and framed, theirs taken, saved, checked',
    run: async (t) => {
      const { page } = t;
      const errors = [];
      page.on('pageerror', (e) => errors.push(e.message));
      // The merge, as `git merge` runs it through `sfc git setup`'s driver: exit 1, one conflict.
      const fixtures = path.join(t.root, 'crates', 'sfc-cli', 'tests', 'merge');
      const dir = path.join(t.scratch, 'merge');
      fs.mkdirSync(dir, { recursive: true });
      const file = path.join(dir, 'tank.st');
      const merged = spawnSync(
        t.sfcBin,
        ['merge', ...['tank_base.st', 'tank_ours.st', 'tank_theirs_conflict.st'].map((f) => path.join(fixtures, f)), '-o', file],
        { encoding: 'utf8' },
      );
      assert(merged.status === 1, `sfc merge: exit ${merged.status}\n${merged.stderr}`);
      assert(fs.readFileSync(file, 'utf8').includes("{attribute 'sfc.conflict' := 'transition:TStart$N"), 'the merged file has no mark');

      await openEditor(t, [file]);
      const before = await waitChart(page);
      const tstart = before.elements.find((e) => e.name === 'TStart').id;
      assert((await condition(page, tstart)) === 'Start AND Empty AND NOT Full', 'the chart does not show ours');

      // The panel opens by itself with the conflict and their version; the status bar counts it.
      const panel = page.locator('[data-testid="conflict-panel"]');
      await panel.waitFor();
      const row = panel.locator('tbody tr[data-element="transition:TStart"]');
      await row.waitFor();
      assert((await row.textContent()).includes('Transition'), await row.textContent());
      const theirs = await row.locator('pre').textContent();
      assert(theirs.includes('TRANSITION TStart FROM Idle TO Filling') && theirs.includes(':= Start AND Empty AND Permit;'), `their text: ${theirs}`);
      assert((await panel.textContent()).includes('1 merge conflict left'), await panel.textContent());
      await page.locator('[data-testid="status-conflicts"]', { hasText: '1 merge conflict left' }).waitFor();
      // The Error List has SFC0605 (its tab's badge).
      await page.locator('.panel-tab .badge-error').waitFor();
      // TStart framed red-orange, Idle not.
      await page.waitForFunction(([i, c]) => {
        const v = document.querySelector(`.canvas-pane.active [data-element-id="${i}"] .djs-visual`);
        return !!v && [...v.querySelectorAll(':scope > rect')].some((r) => r.getAttribute('stroke') === c);
      }, [tstart, CONFLICT]);
      const idle = before.elements.find((e) => e.name === 'Idle').id;
      assert(!(await frames(page, idle)).includes(CONFLICT), 'Idle is framed as a conflict');
      await page.screenshot({ path: shotPath(t, 'conflicts-1-open.png') });

      // A click on the row selects the transition.
      await row.click();
      await page.waitForFunction((i) => JSON.stringify(window.__sfc.selection()) === JSON.stringify([i]), tstart);

      // Take theirs: their condition, the mark gone, the tab dirty, the file untouched.
      const onDisk = fs.readFileSync(file, 'utf8');
      await row.locator('button[data-side="theirs"]').click();
      await page.waitForFunction(([i, c]) => window.__sfc.doc().elements.find((e) => e.id === i)?.condition === c, [tstart, 'Start AND Empty AND Permit']);
      await panel.locator('.conflict-count', { hasText: 'No merge conflicts left' }).waitFor();
      await page.locator('[data-testid="status-conflicts"]').waitFor({ state: 'detached' });
      assert(!(await frames(page, tstart)).includes(CONFLICT), 'TStart is still framed');
      assert(!(await page.evaluate(() => (window.__sfc.doc().attributes ?? []).some((a) => a.name === 'sfc.conflict'))), 'the mark is still there');
      assert((await page.evaluate(() => window.__sfc.tabs()[0].dirty)) === true, 'the tab is not dirty');
      await page.locator('.panel-tab .badge-error').waitFor({ state: 'detached' });
      assert(fs.readFileSync(file, 'utf8') === onDisk, 'resolving wrote the file');
      await page.screenshot({ path: shotPath(t, 'conflicts-2-theirs.png') });

      // Undoable: Ctrl+Z brings ours and the conflict back, Ctrl+Y takes theirs again.
      assert(await page.evaluate(() => window.__sfc.canUndo()), 'taking theirs cannot be undone');
      await page.keyboard.press('Control+z');
      await page.waitForFunction(([i, c]) => window.__sfc.doc().elements.find((e) => e.id === i)?.condition === c, [tstart, 'Start AND Empty AND NOT Full']);
      await panel.locator('tbody tr[data-element="transition:TStart"]').waitFor();
      await page.keyboard.press('Control+y');
      await page.waitForFunction(([i, c]) => window.__sfc.doc().elements.find((e) => e.id === i)?.condition === c, [tstart, 'Start AND Empty AND Permit']);
      await panel.locator('.conflict-count', { hasText: 'No merge conflicts left' }).waitFor();

      // Saved: no mark in the file, their condition, and `sfc check` passes without SFC0605.
      await page.keyboard.press('Control+s');
      await page.locator('.toast', { hasText: 'Saved' }).waitFor();
      const text = fs.readFileSync(file, 'utf8');
      assert(!text.includes('sfc.conflict'), `the mark was saved:\n${text}`);
      assert(text.includes(':= Start AND Empty AND Permit;'), `their condition was not saved:\n${text}`);
      assert(text.includes('STEP Stirring'), `our rename was lost:\n${text}`);
      const checked = sfc(t, ['check', file]);
      assert(!checked.includes('SFC0605'), checked);
      assert((await page.evaluate(() => window.__sfc.tabs()[0].dirty)) === false, 'the tab is dirty after saving');
      assert(errors.length === 0, `page errors: ${errors.join('; ')}`);
    },
  },
];
