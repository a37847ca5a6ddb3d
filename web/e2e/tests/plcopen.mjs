// A Beremiz project with an SFC program and two function blocks drawn in FBD and LD, opened in
// the editor: a step is moved by mouse and the chart saved (Ctrl+S). The save replaces the SFC
// POU's element alone: every other byte of the file (the FBD and LD POUs, the headers, the
// instances) is unchanged, and the SFC POU reopens equal to what was saved.
import fs from 'node:fs';
import path from 'node:path';
import { assert, assertSame, box, drag, openEditor, sfc, waitChart } from '../helpers.mjs';

/** The byte range of `<pou name="NAME" …>…</pou>` in an XML text. */
function pouRange(xml, name) {
  const start = xml.indexOf(`<pou name="${name}"`);
  assert(start >= 0, `no POU ${name} in the file`);
  const end = xml.indexOf('</pou>', start) + '</pou>'.length;
  return [start, end];
}

export const tests = [
  {
    name: 'saving the SFC POU of a Beremiz project keeps every other byte',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'conveyor.plc.xml');
      fs.copyFileSync(path.join(t.root, 'tests', 'corpus', 'real', 'beremiz', 'sfc_fbd_ld_project.plc.xml'), file);
      const original = fs.readFileSync(file, 'utf8');
      await openEditor(t, [file]);
      const before = await waitChart(page);
      assert(before.pou === 'Conveyor', `opened ${before.pou}, expected the SFC POU Conveyor`);
      const step = before.elements.find((e) => e.kind === 'step' && e.name === 'Running');
      assert(step, 'no step Running');
      const b = await box(page, step.id);
      const scale = await page.evaluate(() => window.__sfc.zoom());
      const from = { x: b.x + b.width / 2, y: b.y + b.height / 2 };
      await drag(page, from, { x: from.x + 80 * scale, y: from.y + 40 * scale });
      await page.waitForFunction(([id, x]) => window.__sfc.doc().elements.find((e) => e.id === id).x !== x, [step.id, step.x]);
      const saves = page.waitForResponse((r) => r.url().endsWith('/api/save') && r.status() === 200);
      await page.keyboard.press('Control+s');
      await saves;
      await page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty));
      const saved = await page.evaluate(() => window.__sfc.doc());

      const after = fs.readFileSync(file, 'utf8');
      assert(after !== original, 'the save did not change the file');
      const [s0, e0] = pouRange(original, 'Conveyor');
      const [s1, e1] = pouRange(after, 'Conveyor');
      assert(s0 === s1, `the bytes before the SFC POU changed (it starts at ${s1}, was ${s0})`);
      assert(after.slice(0, s1) === original.slice(0, s0), 'the bytes before the SFC POU changed');
      assert(after.slice(e1) === original.slice(e0), 'the bytes after the SFC POU changed');
      for (const other of ['MotorLogic', 'LampLogic']) {
        const [a, b2] = pouRange(original, other);
        const [c, d] = pouRange(after, other);
        assert(original.slice(a, b2) === after.slice(c, d), `POU ${other} changed`);
      }
      // The moved step's new place is in the file, which still checks.
      assert(after.slice(s1, e1).includes('name="Running"'), 'the saved POU has no step Running');
      sfc(t, ['check', '--no-analysis', file]);

      // Reopened, the chart is the one saved.
      await page.reload();
      const reopened = await waitChart(page);
      assertSame(reopened, saved, 'the SFC POU reopened');
    },
  },
  {
    name: 'a chart still being drawn in Beremiz shows its unconnected transitions, and a save keeps them',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'tank.plc.xml');
      fs.copyFileSync(path.join(t.root, 'crates', 'sfc-plcopen', 'tests', 'fixtures', 'drawing_in_progress.xml'), file);
      await openEditor(t, [file]);
      const doc = await waitChart(page);
      const transitions = doc.elements.filter((e) => e.kind === 'transition');
      assert(transitions.length === 5, `5 transitions drawn, got ${transitions.length}`);
      const level = transitions.find((e) => e.condition === 'Level > 80');
      assert(level, 'the transition Level > 80, which has no step before it, is drawn');
      await page.keyboard.press('F7');
      const rows = page.locator('.error-list tbody tr', { hasText: 'SFC0204' });
      await rows.first().waitFor();
      assert((await rows.count()) === 3, `three transitions reported as not connected, got ${await rows.count()}`);
      const step = doc.elements.find((e) => e.kind === 'step' && e.name === 'Idle');
      const b = await box(page, step.id);
      const scale = await page.evaluate(() => window.__sfc.zoom());
      const from = { x: b.x + b.width / 2, y: b.y + b.height / 2 };
      await drag(page, from, { x: from.x - 20 * scale, y: from.y });
      await page.waitForFunction(([id, x]) => window.__sfc.doc().elements.find((e) => e.id === id).x !== x, [step.id, step.x]);
      const saves = page.waitForResponse((r) => r.url().endsWith('/api/save') && r.status() === 200);
      await page.keyboard.press('Control+s');
      await saves;
      const after = fs.readFileSync(file, 'utf8');
      assert(after.split('<transition ').length - 1 === 5, 'the saved file has the five transitions');
      assert(after.includes('Level > 80') && after.includes('Empty AND NOT Start'), 'with their conditions');
      await page.reload();
      const reopened = await waitChart(page);
      const again = reopened.elements.filter((e) => e.kind === 'transition');
      assert(again.length === 5, `5 transitions after reopening, got ${again.length}`);
    },
  },
];
