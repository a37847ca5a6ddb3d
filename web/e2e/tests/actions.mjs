// CODESYS's actions written in SFC and step actions through the real `sfc edit`: the fixture
// press_actions.st holds a function block written in ST whose cycle is an action written in SFC,
// and a program whose chart has one too. The block's tab shows its body as text; a click on the
// action in the charts bar opens the action's chart on a canvas of its own, where a transition's
// condition is changed, a step moved (undone and redone), a step's entry action set in
// Properties and a step added from the Tools palette in place of the jump back. Saved, the file
// holds the changes inside the action, keeps the other POU byte for byte, and `sfc check`
// passes; reloaded, the editor shows them again. Screenshot in e2e/out/actions-chart.png.
import fs from 'node:fs';
import path from 'node:path';
import { assert, box, drag, dropFromPalette, openEditor, panelShows, select, setCondition, setField, sfc, shotPath, waitChart, wire } from '../helpers.mjs';

const here = path.dirname(new URL(import.meta.url).pathname);
const doc = (page) => page.evaluate(() => window.__sfc.doc());
const step = (d, name) => d.elements.find((e) => e.kind === 'step' && e.name === name);

async function showTab(page, pou) {
  await page.locator('.tabstrip .tab', { hasText: `: ${pou}` }).click();
  await page.waitForFunction((p) => window.__sfc.tabs().find((x) => x.active)?.pou === p, pou);
}

export const tests = [
  {
    name: 'an action written in SFC opens as a chart of its own, is edited and saved into its action',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'press_actions.st');
      fs.copyFileSync(path.join(here, '..', 'fixtures', 'press_actions.st'), file);
      const original = fs.readFileSync(file, 'utf8');
      await openEditor(t, ['press_actions.st']);
      await page.waitForFunction(() => window.__sfc.tabs().length === 2);
      const tabs = await page.evaluate(() => window.__sfc.tabs().map((x) => x.pou));
      assert(JSON.stringify(tabs) === '["Press","Line"]', `tabs ${tabs}`);

      // The block written in ST: its body as text, its action's chart one click away.
      await showTab(page, 'Press');
      await page.locator('.text-body-note', { hasText: 'The body of Press is written in ST' }).waitFor();
      const body = page.locator('.side-panel .code-editor textarea').nth(1);
      assert((await body.inputValue()).includes('Cycle();'), `body: ${await body.inputValue()}`);
      await page.locator('.chart-views .chart-view[data-action="Cycle"]').click();
      let d = await waitChart(page);
      assert(d.pou === 'Press' && ['Ready', 'Lower', 'Raise'].every((n) => step(d, n)), `chart of Cycle: ${JSON.stringify(d.elements.map((e) => e.name))}`);
      assert(step(d, 'Lower').stepActions?.[0] === 'ENTRY_ACTION := Lower_entry', 'Lower keeps its entry action');
      await page.locator('.side-panel .prop-heading', { hasText: 'Press.Cycle' }).waitFor();

      // A condition changed.
      const back = d.elements.find((e) => e.kind === 'transition' && e.condition === 'AtTop');
      await select(page, back.id);
      await setCondition(page, back.id, 'AtTop AND NOT Start');

      // A step moved by mouse, undone and redone.
      const raise = step(d, 'Raise');
      const b = await box(page, raise.id);
      const scale = await page.evaluate(() => window.__sfc.zoom());
      const from = { x: b.x + b.width / 2, y: b.y + b.height / 2 };
      await drag(page, from, { x: from.x + 120 * scale, y: from.y });
      await page.waitForFunction((id) => window.__sfc.doc().elements.find((e) => e.id === id).x !== 40, raise.id);
      const movedX = step(await doc(page), 'Raise').x;
      await page.keyboard.press('Control+z');
      await page.waitForFunction((id) => window.__sfc.doc().elements.find((e) => e.id === id).x === 40, raise.id);
      await page.keyboard.press('Control+y');
      await page.waitForFunction(([id, x]) => window.__sfc.doc().elements.find((e) => e.id === id).x === x, [raise.id, movedX]);

      // The step's entry action in Properties.
      // (A click on the block selected by the drag would unselect it: empty canvas first.)
      const pane = await page.locator('.canvas-pane.active').boundingBox();
      await page.mouse.click(pane.x + pane.width - 40, pane.y + 40);
      await page.waitForFunction(() => window.__sfc.selection().length === 0);
      await select(page, raise.id);
      const exit = page.locator('.side-panel #p-sa-exit');
      assert((await exit.inputValue()) === 'Raise_exit', `exit action shown: ${await exit.inputValue()}`);
      await setField(page, '#p-sa-entry', 'Lower_entry');
      await page.waitForFunction(
        (id) => JSON.stringify(window.__sfc.doc().elements.find((e) => e.id === id).stepActions) === '["ENTRY_ACTION := Lower_entry","EXIT_ACTION := Raise_exit"]',
        raise.id,
      );
      await page.waitForFunction(() => window.__sfc.tabs().find((x) => x.active)?.dirty);

      // A step added with the Tools palette: the jump back to Ready replaced by a final step Done.
      const jump = d.elements.find((e) => e.kind === 'jump');
      await select(page, jump.id);
      await page.locator('.menubar .menu-title', { hasText: 'Edit' }).click();
      await page.locator('.menu-dropdown .menu-item').filter({ has: page.locator('.menu-label', { hasText: /^Delete$/ }) }).click();
      await page.waitForFunction((id) => !window.__sfc.doc().elements.some((e) => e.id === id), jump.id);
      const done = await dropFromPalette(page, 'step', { x: 80, y: 440 });
      assert(await wire(page, back.id, done), 'the transition was not wired to the new step');
      await select(page, done);
      await setField(page, '#p-name', 'Done');
      await page.locator('.side-panel .prop-row', { hasText: 'Final step' }).locator('input[type=checkbox]').check();
      await page.waitForFunction((id) => {
        const e = window.__sfc.doc().elements.find((x) => x.id === id);
        return e.name === 'Done' && e.final;
      }, done);
      await page.screenshot({ path: shotPath(t, 'actions-chart.png') });

      // Saved from the action's chart: the whole POU, the action's body from its chart.
      await page.keyboard.press('Control+s');
      await page.waitForFunction(() => !window.__sfc.tabs().find((x) => x.active)?.dirty);
      const saved = fs.readFileSync(file, 'utf8');
      const press = saved.slice(0, saved.indexOf('END_FUNCTION_BLOCK'));
      assert(press.includes(':= AtTop AND NOT Start;'), `condition not saved:\n${press}`);
      assert(/STEP Raise:\n\s+ENTRY_ACTION := Lower_entry;\n\s+EXIT_ACTION := Raise_exit;\n\s+END_STEP/.test(press), `step actions not saved:\n${press}`);
      assert(/\n    Cycle\(\);\n/.test(press) && !press.includes("'sfc.target'"), `the block is no longer written in ST:\n${press}`);
      assert(/ACTION Cycle:[\s\S]*INITIAL_STEP Ready/.test(press), `the chart is not in its action:\n${press}`);
      assert(/ACTION Cycle:[\s\S]*FROM Raise TO Done\n[\s\S]*'sfc.final' := 'true'\}\n\s+STEP Done: END_STEP\n\s+END_ACTION/.test(press), `the new step is not in the action:\n${press}`);
      const line = original.slice(original.indexOf('PROGRAM Line'));
      assert(saved.endsWith(line), 'the other POU changed');
      sfc(t, ['check', 'press_actions.st']);

      // The program's chart holds another action written in SFC, reached from Properties.
      await showTab(page, 'Line');
      await page.locator('.canvas-pane.active').click({ position: { x: 700, y: 500 } });
      await page.locator('.side-panel .open-action-chart[data-action="Feed"]').click();
      d = await waitChart(page);
      const push = step(d, 'Push');
      await select(page, push.id);
      await panelShows(page, push.id);
      const main = page.locator('.side-panel #p-sa-main');
      assert((await main.inputValue()) === 'Count', `step action of Push: ${await main.inputValue()}`);

      // Reloaded, the file gives the same chart back.
      await page.reload();
      await page.waitForFunction(() => window.__sfc?.tabs().length === 2);
      await showTab(page, 'Press');
      await page.locator('.chart-views .chart-view[data-action="Cycle"]').click();
      d = await waitChart(page);
      assert(d.elements.some((e) => e.condition === 'AtTop AND NOT Start'), 'condition after reload');
      assert(step(d, 'Raise').x === movedX, `Raise at ${step(d, 'Raise').x} after reload, ${movedX} saved`);
      assert(step(d, 'Raise').stepActions.length === 2, 'step actions after reload');
      assert(step(d, 'Done')?.final && !d.elements.some((e) => e.kind === 'jump'), 'the new step after reload');
    },
  },
];
