// Host mode (seed 001 chapter 12: `SFCEditor.exe /fb=ATMT /nstep=16 /ntr=64 chart.sfc`):
// `sfc edit --fb atmt --nstep 16 --ntr 64 --result RESULT FILE` with a FILE that does not exist
// yet. The page creates the chart; after a few edits by mouse, a build writes the one-line table
// to RESULT, the same line `sfc build --target atmt` gives for the saved file.
import fs from 'node:fs';
import path from 'node:path';
import { assert, doc, dropFromPalette, openEditor, setCondition, setField, sfc, waitChart, wire } from '../helpers.mjs';

export const tests = [
  {
    name: 'host mode creates the missing chart, builds it and writes the result file',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'plant', 'conveyor.st');
      const result = path.join(t.scratch, 'conveyor.atmt.txt');
      fs.mkdirSync(path.dirname(file));
      await openEditor(t, ['--fb', 'atmt', '--nstep', '16', '--ntr', '64', '--result', result, file]);
      let d = await waitChart(page);
      assert(!fs.existsSync(file), 'the chart was written before it was saved');
      assert(d.pou === 'conveyor' && d.target === 'atmt', `new host chart ${d.pou} ${d.target}`);
      // One chart, no tabs, New or Open; the limits in the status bar.
      assert((await page.locator('.tabstrip').count()) === 0, 'host mode shows tabs');
      assert((await page.locator('.host-title').textContent()).includes('conveyor'), 'no host title');
      assert((await page.locator('.statusbar').textContent()).includes('16'), 'the status bar does not show the limits');
      assert(await page.locator('.toolbar button[title^="New"]').count() === 0, 'host mode offers New');

      // Init → C0 → Fill (timeout 2.5 s) → C1 → back to Init by a jump.
      const init = d.elements[0];
      const cx = init.x + init.w / 2;
      const t1 = await dropFromPalette(page, 'transition', { x: cx, y: init.y + 90 });
      await setCondition(page, t1, 'C0');
      const fill = await dropFromPalette(page, 'step', { x: cx, y: init.y + 160 });
      await setField(page, '#p-name', 'Fill');
      await setField(page, '#p-timeout', '2.5');
      const t2 = await dropFromPalette(page, 'transition', { x: cx, y: init.y + 230 });
      await setCondition(page, t2, 'C1');
      const back = await dropFromPalette(page, 'jump', { x: cx, y: init.y + 280 });
      await page.locator('.side-panel #p-jump').selectOption('Init');
      for (const [a, b] of [[init.id, t1], [t1, fill], [fill, t2], [t2, back]]) assert(await wire(page, a, b), `wire ${a} → ${b}`);
      d = await doc(page);
      assert(d.elements.find((e) => e.id === fill).timeout === 'T#2.5s', 'timeout not set');

      // Build (F7): the host's block and limits; the result file is written.
      await page.keyboard.press('F7');
      await page.waitForSelector('.result-panel .one-line code');
      const shown = (await page.locator('.result-panel .one-line code').textContent()).trim();
      assert(shown === '2[0 0 1;1 1 0][0 2.5]', `built table ${shown}`);
      await page.waitForFunction(() => document.querySelector('.toast')?.textContent.includes('conveyor.atmt.txt'));
      const written = fs.readFileSync(result, 'utf8');
      assert(written === shown, `result file ${JSON.stringify(written)}`);

      // Save (Ctrl+S) writes FILE; `sfc build` of it gives the same line.
      await page.keyboard.press('Control+s');
      await page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty));
      const built = sfc(t, ['build', '--target', 'atmt', file]);
      assert(built.trimEnd() === written, `sfc build: ${JSON.stringify(built)} vs result ${JSON.stringify(written)}`);
    },
  },
];
