// Issue 15's defects of drawing and saving, by mouse and keyboard: ATMT/EATMT target rules at
// the drop and in Properties, a condition that does not parse is never replaced by FALSE, and
// diagnostics about the drawing name their block.
import fs from 'node:fs';
import path from 'node:path';
import { assert, box, doc, dropFromPalette, openEditor, select, setField, shotPath, waitChart } from '../helpers.mjs';

const ATMT = `{attribute 'sfc.target' := 'atmt'}
PROGRAM Table
    INITIAL_STEP State0: END_STEP

    TRANSITION Go FROM State0 TO State1
        := C0;
    END_TRANSITION

    STEP State1: END_STEP

    TRANSITION Back FROM State1 TO State0
        := C1;
    END_TRANSITION
END_PROGRAM
`;

const UNPARSED = `PROGRAM Lose
    VAR
        a, b : BOOL;
    END_VAR

    INITIAL_STEP S0: END_STEP

    TRANSITION T1 FROM S0 TO S1
        := a AND ;
    END_TRANSITION

    STEP S1: END_STEP

    TRANSITION T2 FROM S1 TO S0
        := b;
    END_TRANSITION
END_PROGRAM
`;

export const tests = [
  {
    name: 'ATMT: an action block is refused at the drop with a tooltip; a Tag sets the condition C<n>',
    run: async (t) => {
      const { page } = t;
      fs.writeFileSync(path.join(t.scratch, 'table.st'), ATMT);
      await openEditor(t, ['table.st']);
      const d = await waitChart(page);
      // The palette shows the entry greyed, with the reason.
      const entry = page.locator('.canvas-pane.active .djs-palette [data-action="create.action-block"]');
      assert((await entry.getAttribute('class')).includes('refused'), 'the action block entry is greyed');
      assert((await entry.getAttribute('title')).includes('no actions'), 'its tooltip says why');
      // Dragged onto the chart: a tooltip says why while hovering, and the drop adds nothing.
      const from = await entry.boundingBox();
      const pane = await page.locator('.canvas-pane.active').boundingBox();
      await page.mouse.move(from.x + 20, from.y + from.height / 2);
      await page.mouse.down();
      await page.mouse.move(from.x + 30, from.y + 20, { steps: 2 });
      await page.mouse.move(pane.x + pane.width * 0.6, pane.y + pane.height * 0.5, { steps: 10 });
      const tip = page.locator('.canvas-pane.active .sfc-refusal-tip');
      await tip.waitFor();
      assert((await tip.textContent()).includes('ATMT chart has no actions'), await tip.textContent());
      await page.mouse.up();
      assert((await doc(page)).elements.length === d.elements.length, 'no block was added');
      await tip.waitFor();
      const grey = await entry.evaluate((e) => getComputedStyle(e).color + ' ' + e.className); assert(grey.startsWith('rgb(148, 163, 184)'), 'greyed: ' + grey);
      await page.screenshot({ path: shotPath(t, 'atmt-refused-action-block.png') });
      await page.mouse.click(pane.x + pane.width - 150, pane.y + 60);
      // The Tag of a transition is its condition number.
      await select(page, 'transition:Go');
      await setField(page, '#p-tag', '5');
      await page.waitForFunction(() => window.__sfc.doc().elements.find((e) => e.id === 'transition:Go')?.condition === 'C5');
      // (the Properties panel follows the document in its next render: wait for it, then check)
      await page
        .waitForFunction(() => document.querySelector('.side-panel .code-editor textarea')?.value === 'C5', null, { timeout: 5000 })
        .catch(() => {});
      assert((await page.locator('.side-panel .code-editor textarea').inputValue()) === 'C5', 'Properties show C5');
      // A new transition takes the next free input.
      const id = await dropFromPalette(page, 'transition', { x: 300, y: 260 });
      const added = (await doc(page)).elements.find((e) => e.id === id);
      assert(added.condition === 'C0' && added.tag === 0, JSON.stringify(added));
    },
  },
  {
    name: 'a condition that does not parse: its error names and frames T1, and Ctrl+S refuses instead of writing FALSE',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'lose.st');
      fs.writeFileSync(file, UNPARSED);
      await openEditor(t, ['lose.st']);
      await waitChart(page);
      const row = page.locator('.error-list tbody tr', { hasText: 'SFC0101' });
      await row.waitFor();
      assert((await row.locator('.col-element').textContent()) === 'T1', 'the Block column names T1');
      assert((await row.locator('.col-line').textContent()) === '9:18', await row.locator('.col-line').textContent());
      await row.click();
      await page.waitForFunction(() => document.querySelector('.canvas-pane.active [data-element-id="transition:T1"] rect[stroke="#7c3aed"]'));
      const t1 = (await doc(page)).elements.find((e) => e.id === 'transition:T1');
      assert(t1.condition === 'a AND ;', `kept as typed: ${t1.condition}`);
      // Make the chart dirty (move S1), then save: refused, nothing written.
      const b = await box(page, 'step:S1');
      await page.mouse.move(b.x + b.width / 2, b.y + b.height / 2);
      await page.mouse.down();
      await page.mouse.move(b.x + b.width / 2 + 30, b.y + b.height / 2 + 5, { steps: 5 });
      await page.mouse.up();
      await page.keyboard.press('Control+s');
      const toast = page.locator('.toast', { hasText: 'not saved' });
      await toast.waitFor();
      assert((await toast.textContent()).includes('T1'), await toast.textContent());
      assert(fs.readFileSync(file, 'utf8') === UNPARSED, 'the file is unchanged');
      assert(!fs.readFileSync(file, 'utf8').includes('FALSE'), 'never FALSE');
      assert((await page.evaluate(() => window.__sfc.tabs()[0].dirty)) === true, 'the chart stays unsaved');
    },
  },
  {
    name: 'drawing problems (a jump to no step, a dangling transition) name their block and a line',
    run: async (t) => {
      const { page } = t;
      await openEditor(t, ['.']);
      await page.locator('.welcome .button.primary').click();
      await page.locator('#new-name').fill('Drawn');
      await page.locator('.modal .button.primary').click();
      await waitChart(page);
      await dropFromPalette(page, 'transition', { x: 500, y: 300 });
      await page.keyboard.press('F7');
      const row = page.locator('.error-list tbody tr', { hasText: 'SFC0204' });
      await row.waitFor();
      const block = await row.locator('.col-element').textContent();
      assert(/^T\d+$/.test(block), `the Block column names the transition: ${block}`);
      const line = await row.locator('.col-line').textContent();
      assert(line !== '' && line !== '1:1', `a real line: ${line}`);
    },
  },
];
