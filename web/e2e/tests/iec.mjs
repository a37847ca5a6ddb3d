// The "IEC 61131-3" target of the New dialog: a Blank chart that names its build output in the
// POU attribute `sfc.build` (default ST). New → IEC → a name → nothing else → Validate & build
// gives Structured Text; after saving and reloading the page, the chart still says IEC and the
// build select still shows ST.
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, sfc, shotPath, waitChart } from '../helpers.mjs';

export const tests = [
  {
    name: 'New → IEC 61131-3 builds Structured Text and stays IEC after save and reload',
    run: async (t) => {
      const { page } = t;
      await openEditor(t, ['.']);
      const badge = () => page.locator('.tab.active .tab-target').textContent();
      const buildSelect = page.locator('select.tool-select').nth(1);

      // File → New…: the name and the IEC 61131-3 target.
      await page.locator('.menubar .menu-title').filter({ hasText: 'File' }).click();
      await page.locator('.menu-dropdown .menu-item').filter({ hasText: 'New…' }).first().click();
      await page.locator('#new-name').fill('IecChart');
      const option = page.locator('.target-option').filter({ hasText: 'IEC 61131-3' });
      assert((await option.count()) === 1, 'the New dialog offers no IEC 61131-3 target');
      await option.click();
      await page.locator('.modal .button.primary').click();
      const d = await waitChart(page);
      assert(d.pou === 'IecChart' && d.target === 'blank', `new chart: ${d.pou} ${d.target}`);
      assert(JSON.stringify(d.attributes) === JSON.stringify([{ name: 'sfc.build', value: 'st' }]), `attributes: ${JSON.stringify(d.attributes)}`);
      assert((await badge()) === 'IEC', `badge: ${await badge()}`);
      assert((await buildSelect.inputValue()) === 'st', `build select: ${await buildSelect.inputValue()}`);
      // A Blank chart's palette: every block, simultaneous branches included.
      assert((await page.locator('.djs-palette [data-action="create.simultaneous-divergence"]').count()) === 1, 'no AND divergence for an IEC chart');

      // Validate & build: Structured Text in the Result panel.
      await page.locator('select.tool-select').first().selectOption('build');
      await page.locator('.toolbar .tool-button.primary').click();
      await page.waitForSelector('.outcome');
      const outcome = await page.locator('.outcome').textContent();
      if (outcome !== 'Succeeded') throw new Error(`build: ${outcome}\n${await page.locator('.bottom-panel').innerText()}`);
      const st = await page.locator('.result-panel pre.result-text').textContent();
      assert(/\bPROGRAM IecChart\b/.test(st) && /END_PROGRAM/.test(st) && !/INITIAL_STEP/.test(st), `not Structured Text of the chart:\n${st}`);
      assert((await page.locator('.result-panel .panel-toolbar .muted').first().textContent()) === 'Structured Text', 'result not labelled Structured Text');
      // No diagnostic at all: `sfc.build` is a known attribute.
      assert((await page.locator('.error-list tbody tr').count()) === 0, 'the build reported diagnostics');
      await page.screenshot({ path: shotPath(t, 'iec-built.png') });

      // Save (Ctrl+S → Save as…); the file carries the attribute and checks clean.
      const file = path.join(t.scratch, 'iec_chart.st');
      await page.keyboard.press('Control+s');
      await page.locator('.modal #save-path').fill(file);
      await page.locator('.modal .button.primary').click();
      await page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty && x.path));
      const text = fs.readFileSync(file, 'utf8');
      assert(text.includes("{attribute 'sfc.target' := 'blank'}") && text.includes("{attribute 'sfc.build' := 'st'}"), `saved file:\n${text}`);
      const checked = sfc(t, ['check', '--format', 'json', file]);
      assert(!/SFC06/.test(checked), `sfc check of the saved file: ${checked}`);

      // Reopen: reload the page and open the file again.
      await page.reload();
      await page.waitForSelector('.statusbar');
      await page.waitForFunction(() => !!window.__sfc && window.__sfc.tabs().length === 0);
      await page.locator('.menubar .menu-title').filter({ hasText: 'File' }).click();
      await page.locator('.menu-dropdown .menu-item').filter({ hasText: 'Open…' }).first().click();
      await page.locator('.modal .filter-box').fill('iec_chart.st');
      await page.locator('.modal .file-row').filter({ hasText: 'iec_chart.st' }).first().dblclick();
      const again = await waitChart(page);
      assert(again.pou === 'IecChart' && again.target === 'blank', `reopened: ${again.pou} ${again.target}`);
      assert((await badge()) === 'IEC', `badge after reopening: ${await badge()}`);
      assert((await buildSelect.inputValue()) === 'st', `build select after reopening: ${await buildSelect.inputValue()}`);
      assert((await page.locator('.tab.active .tab-title').textContent()) === 'iec_chart.st: IecChart', 'reopened chart is dirty or misnamed');
      await page.screenshot({ path: shotPath(t, 'iec-reopened.png') });
    },
  },
];
