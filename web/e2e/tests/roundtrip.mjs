// Every chart of examples/ through the editor and back: opened with `sfc edit FILE`, a step
// moved by mouse, undone and redone (Ctrl+Z, Ctrl+Y), saved (Ctrl+S); after a reload of the
// page the reopened documents equal the ones saved (positions, names, connections, every
// field), and a second save writes the same bytes again (the saved text is a fixed point).
import fs from 'node:fs';
import path from 'node:path';
import { assert, assertSame, box, drag, openEditor, setField, sfc, waitChart } from '../helpers.mjs';

/** The chart files of the scratch copy of examples/. */
function exampleFiles(scratch) {
  const dir = path.join(scratch, 'examples');
  return fs
    .readdirSync(dir, { withFileTypes: true })
    .filter((e) => e.isDirectory())
    .flatMap((e) => fs.readdirSync(path.join(dir, e.name)).filter((f) => f.endsWith('.st')).map((f) => path.join(dir, e.name, f)))
    .sort();
}

const docs = (page) => page.evaluate(() => window.__sfc.docs());
const activeDoc = (page) => page.evaluate(() => window.__sfc.doc());

/** Waits until every tab is saved (no `*`). */
const allSaved = (page) => page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty));

async function roundTrip(t, file) {
  const { page } = t;
  await openEditor(t, [file]);
  await waitChart(page);
  const tabs = await page.evaluate(() => window.__sfc.tabs().length);
  assert(tabs >= 1, `${file}: no chart opened`);
  for (let k = 0; k < tabs; k++) {
    await page.locator('.tabstrip .tab').nth(k).click();
    await page.waitForFunction((i) => window.__sfc.tabs()[i].active, k);
    const before = await waitChart(page);
    // A step in view (not the first one when there are others), moved by mouse 60 right and
    // 40 down.
    const steps = before.elements.filter((e) => e.kind === 'step');
    const pane = await page.locator('.canvas-pane.active').boundingBox();
    // A step and a move to a free place (a move onto another block is refused): 60 right and
    // 40 down where that is free, else 60 right.
    const free = (s, dx, dy) =>
      !before.elements.some(
        (o) => o.id !== s.id && o.kind !== 'text' && o.step !== s.id && o.x < s.x + dx + s.w && s.x + dx < o.x + o.w && o.y < s.y + dy + s.h && s.y + dy < o.y + o.h,
      ) &&
      !before.elements.some((a) => a.step === s.id && before.elements.some((o) => o.id !== a.id && o.id !== s.id && o.kind !== 'text' && o.step !== s.id && o.x < a.x + dx + a.w && a.x + dx < o.x + o.w && o.y < a.y + dy + a.h && a.y + dy < o.y + o.h));
    let step = steps[Math.min(1, steps.length - 1)];
    let [dx, dy] = [60, 40];
    search: for (const [vx, vy] of [[60, 40], [60, 0]]) {
      for (const s of [...steps.slice(1), ...steps.slice(0, 1)]) {
        const q = await box(page, s.id);
        if (free(s, vx, vy) && q.x > pane.x + 240 && q.y > pane.y + 10 && q.x + q.width + 70 < pane.x + pane.width && q.y + q.height + 50 < pane.y + pane.height) {
          step = s;
          [dx, dy] = [vx, vy];
          break search;
        }
      }
    }
    const b = await box(page, step.id);
    const scale = await page.evaluate(() => window.__sfc.zoom());
    const from = { x: b.x + b.width / 2, y: b.y + b.height / 2 };
    await drag(page, from, { x: from.x + dx * scale, y: from.y + dy * scale });
    await page.waitForFunction(([id, x, y]) => {
      const e = window.__sfc.doc().elements.find((el) => el.id === id);
      return e.x !== x || e.y !== y;
    }, [step.id, step.x, step.y]);
    const moved = await activeDoc(page);
    const m = moved.elements.find((e) => e.id === step.id);
    assert(Math.abs(m.x - step.x - dx) <= 10 && Math.abs(m.y - step.y - dy) <= 10, `${step.id} moved to ${m.x},${m.y} from ${step.x},${step.y}`);
    // Undo gives back exactly the document as opened, redo the moved one.
    await page.keyboard.press('Control+z');
    await page.waitForFunction(() => !window.__sfc.canUndo());
    assertSame(await activeDoc(page), before, `${path.basename(file)} ${before.pou}: after undo`);
    await page.keyboard.press('Control+y');
    await page.waitForFunction(() => !window.__sfc.canRedo());
    assertSame(await activeDoc(page), moved, `${path.basename(file)} ${before.pou}: after redo`);
    await page.keyboard.press('Control+s');
    await page.waitForFunction((i) => !window.__sfc.tabs()[i].dirty, k);
  }
  await allSaved(page);
  const saved = await docs(page);
  const firstSave = fs.readFileSync(file);

  // Reload: the same documents come back from the file.
  await page.reload();
  await page.waitForFunction((n) => window.__sfc?.tabs().length === n, tabs);
  await waitChart(page);
  const reopened = await docs(page);
  assert(reopened.length === saved.length, `${file}: ${reopened.length} charts after reload, ${saved.length} before`);
  reopened.forEach((d, k) => assertSame(d, saved[k], `${path.basename(file)} ${d.pou}: reopened`));

  // A second save of every chart writes the same bytes.
  for (let k = 0; k < tabs; k++) {
    await page.locator('.tabstrip .tab').nth(k).click();
    await page.waitForFunction((i) => window.__sfc.tabs()[i].active, k);
    const saves = page.waitForResponse((r) => r.url().endsWith('/api/save') && r.status() === 200);
    await page.keyboard.press('Control+s');
    await saves;
  }
  const secondSave = fs.readFileSync(file);
  assert(Buffer.compare(firstSave, secondSave) === 0, `${file}: the second save changed the file`);
  return { file: path.relative(t.scratch, file), charts: saved.map((d) => `${d.pou} (${d.elements.length} blocks)`) };
}

export const tests = [
  {
    name: 'a renamed chart replaces its POU in the file',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'examples', 'blinker', 'blinker.st');
      await openEditor(t, [file]);
      await waitChart(page);
      // With nothing selected the Properties panel shows the chart: rename the POU.
      await setField(page, '#p-pou', 'Flasher');
      await page.waitForFunction(() => window.__sfc.doc().pou === 'Flasher');
      await page.keyboard.press('Control+s');
      await page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty && x.pou === 'Flasher'));
      const text = fs.readFileSync(file, 'utf8');
      assert(/^PROGRAM Flasher$/m.test(text), 'the renamed POU is not in the file');
      assert(!/^PROGRAM Blinker$/m.test(text), 'the old POU is still in the file');
      sfc(t, ['check', '--no-analysis', file]);
      // Saved again under its new name, it stays one POU.
      await setField(page, '#p-pou', 'Flasher2');
      await page.keyboard.press('Control+s');
      await page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty && x.pou === 'Flasher2'));
      const again = fs.readFileSync(file, 'utf8');
      assert((again.match(/^PROGRAM /gm) ?? []).length === 1, `POUs in the file: ${again.match(/^PROGRAM \w+/gm)}`);
    },
  },
  {
    name: 'comments between chart elements survive moving a step and saving',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'commented.st');
      const comments = [
        '(* before the POU *)',
        '(* between the header and the declarations *)',
        '(* level switches *)',
        '(* fill the tank *)',
        '// open the inlet',
        '(* ends the line of Fill *)',
        '// the level switch ends filling',
        '(* inside the condition *)',
        '(* drain it again,\n       with the pump *)',
        '// before the action',
        '(* inside the action *)',
        '(* after the last element *)',
        '// and the very last',
        '(* after the POU *)',
      ];
      const [pre, header, level, fill, inlet, ends, filled, cond, drain, action, body, last, veryLast, post] = comments;
      fs.writeFileSync(
        file,
        `${pre}
PROGRAM Tank
    ${header}
    VAR
        Full, Empty, Valve : BOOL; ${level}
    END_VAR

    ${fill}
    INITIAL_STEP Fill:
        ${inlet}
        Open(N);
    END_STEP ${ends}

    ${filled}
    TRANSITION FROM Fill TO Drain
        := Full ${cond} AND NOT Empty;
    END_TRANSITION

    ${drain}
    STEP Drain: END_STEP
    TRANSITION FROM Drain TO Fill
        := Empty;
    END_TRANSITION

    ${action}
    ACTION Open:
        ${body}
        Valve := TRUE;
    END_ACTION
    ${last}
    ${veryLast}
END_PROGRAM
${post}
`,
      );
      await openEditor(t, [file]);
      const before = await waitChart(page);
      const step = before.elements.find((e) => e.kind === 'step' && e.name === 'Drain');
      assert(step, 'no step Drain');
      const b = await box(page, step.id);
      const scale = await page.evaluate(() => window.__sfc.zoom());
      const from = { x: b.x + b.width / 2, y: b.y + b.height / 2 };
      await drag(page, from, { x: from.x + 80 * scale, y: from.y + 40 * scale });
      await page.waitForFunction(([id, x]) => window.__sfc.doc().elements.find((el) => el.id === id).x !== x, [step.id, step.x]);
      await page.keyboard.press('Control+s');
      await allSaved(page);
      const text = fs.readFileSync(file, 'utf8');
      for (const c of comments) {
        assert(text.split(c).length === 2, `the saved file has ${text.split(c).length - 1} × ${JSON.stringify(c)}:\n${text}`);
      }
      assert(/sfc\.x' := '[-\d.]+'\}\s*(?:\{[^\n]*\n\s*)*STEP Drain/.test(text), `the moved step has no position:\n${text}`);
      const moved = (await activeDoc(page)).elements.find((e) => e.id === step.id);
      assert(moved.x !== step.x, `Drain did not move: ${moved.x}`);
      sfc(t, ['check', '--no-analysis', file]);
      t.log(`${comments.length} comments kept in ${path.basename(file)}`);
    },
  },
  {
    name: 'examples: move a step, undo, redo, save, reload, compare; a second save is byte-identical',
    run: async (t) => {
      const files = exampleFiles(t.scratch);
      assert(files.length >= 4, `only ${files.length} example charts found`);
      for (const file of files) {
        const r = await roundTrip(t, file);
        t.log(`${r.file}: ${r.charts.join(', ')}`);
      }
    },
  },
];
