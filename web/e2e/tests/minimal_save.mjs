// Saves that change only what changed (issue 35): a chart saved as opened leaves its file byte
// for byte; a step moved by mouse and saved changes at most 3 lines of a `.st` file, and only
// that step's `<position>` (and its action block's, which moves with it) in a Beremiz project.
import fs from 'node:fs';
import path from 'node:path';
import { assert, box, drag, openEditor, sfc, waitChart } from '../helpers.mjs';

/** Lines of `b` not in `a` and of `a` not in `b`, by a longest common subsequence. */
function lineDiff(a, b) {
  const x = a.split('\n');
  const y = b.split('\n');
  const n = x.length;
  const m = y.length;
  const dp = Array.from({ length: n + 1 }, () => new Uint32Array(m + 1));
  for (let i = n - 1; i >= 0; i--) {
    for (let j = m - 1; j >= 0; j--) {
      dp[i][j] = x[i] === y[j] ? dp[i + 1][j + 1] + 1 : Math.max(dp[i + 1][j], dp[i][j + 1]);
    }
  }
  const removed = [];
  const added = [];
  let i = 0;
  let j = 0;
  while (i < n && j < m) {
    if (x[i] === y[j]) {
      i++;
      j++;
    } else if (dp[i + 1][j] >= dp[i][j + 1]) removed.push(x[i++]);
    else added.push(y[j++]);
  }
  while (i < n) removed.push(x[i++]);
  while (j < m) added.push(y[j++]);
  return { removed, added };
}

async function saveNow(page) {
  const saves = page.waitForResponse((r) => r.url().endsWith('/api/save') && r.status() === 200);
  await page.keyboard.press('Control+s');
  await saves;
  await page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty));
}

/** Drags the block `id` by (dx, dy) canvas units and waits until the document has it. */
async function moveBlock(page, id, dx, dy) {
  const before = await page.evaluate((i) => window.__sfc.doc().elements.find((e) => e.id === i), id);
  const b = await box(page, id);
  const scale = await page.evaluate(() => window.__sfc.zoom());
  const from = { x: b.x + b.width / 2, y: b.y + b.height / 2 };
  await drag(page, from, { x: from.x + dx * scale, y: from.y + dy * scale });
  await page.waitForFunction(
    ([i, x, y]) => {
      const e = window.__sfc.doc().elements.find((k) => k.id === i);
      return e.x !== x || e.y !== y;
    },
    [id, before.x, before.y],
  );
}

/** The Beremiz projects at hand: our own fixture, and the real ones of the shared corpus. */
function beremizProjects(t) {
  const list = [path.join(t.root, 'tests', 'corpus', 'real', 'beremiz', 'sfc_fbd_ld_project.plc.xml')];
  const corpus = path.join(t.root, '..', 'shared', 'corpus', 'beremiz', 'first_steps.plc.xml');
  if (fs.existsSync(corpus)) list.push(corpus);
  return list;
}

export const tests = [
  {
    name: 'a chart saved as opened leaves its file byte for byte (text and a Beremiz project)',
    run: async (t) => {
      const { page } = t;
      const files = [path.join(t.scratch, 'examples', 'carwash', 'carwash.st')];
      for (const [k, p] of beremizProjects(t).entries()) {
        const copy = path.join(t.scratch, `project${k}.plc.xml`);
        fs.copyFileSync(p, copy);
        files.push(copy);
      }
      for (const file of files) {
        const original = fs.readFileSync(file);
        await openEditor(t, [file]);
        await waitChart(page);
        await saveNow(page);
        assert(Buffer.compare(fs.readFileSync(file), original) === 0, `${path.basename(file)} changed by a save without edits`);
      }
    },
  },
  {
    name: 'a step moved and saved changes at most 3 lines of a .st file',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'examples', 'carwash', 'carwash.st');
      const original = fs.readFileSync(file, 'utf8');
      await openEditor(t, [file]);
      const doc = await waitChart(page);
      const step = doc.elements.find((e) => e.kind === 'step' && e.name === 'Spraying');
      await moveBlock(page, step.id, 80, 0);
      await saveNow(page);
      const after = fs.readFileSync(file, 'utf8');
      const { removed, added } = lineDiff(original, after);
      assert(added.length >= 1 && added.length <= 3 && removed.length <= 3, `lines changed: -${JSON.stringify(removed)} +${JSON.stringify(added)}`);
      assert(added.every((l) => /\{attribute 'sfc\.(x|y|actionblock)'/.test(l)), `only positions added: ${JSON.stringify(added)}`);
      sfc(t, ['check', '--no-analysis', file]);
      // Reopened, the step is where it was put.
      const moved = await page.evaluate((i) => window.__sfc.doc().elements.find((e) => e.id === i), step.id);
      await page.reload();
      const reopened = await waitChart(page);
      const again = reopened.elements.find((e) => e.id === step.id);
      assert(again.x === moved.x && again.y === moved.y, `reopened at ${again.x},${again.y}, saved at ${moved.x},${moved.y}`);
      // Moved again (to free room: a move onto the transition below is refused): the position
      // lines change, nothing else.
      const before = fs.readFileSync(file, 'utf8');
      await moveBlock(page, step.id, 40, 0);
      await saveNow(page);
      const d = lineDiff(before, fs.readFileSync(file, 'utf8'));
      assert(d.added.length <= 3 && d.removed.length <= 3, `second move: -${JSON.stringify(d.removed)} +${JSON.stringify(d.added)}`);
    },
  },
  {
    name: "a step moved and saved in a Beremiz project changes only that step's position",
    run: async (t) => {
      const { page } = t;
      for (const [k, p] of beremizProjects(t).entries()) {
        const file = path.join(t.scratch, `moved${k}.plc.xml`);
        fs.copyFileSync(p, file);
        const original = fs.readFileSync(file, 'utf8');
        await openEditor(t, [file]);
        const doc = await waitChart(page);
        const step = doc.elements.find((e) => e.kind === 'step' && !e.initial);
        await moveBlock(page, step.id, 60, 20);
        await saveNow(page);
        const after = fs.readFileSync(file, 'utf8');
        const { removed, added } = lineDiff(original, after);
        // The step's own position, and its action block's, which moves with it.
        assert(added.length >= 1 && added.length <= 2 && removed.length === added.length, `${path.basename(p)}: -${JSON.stringify(removed)} +${JSON.stringify(added)}`);
        const lines = after.split('\n');
        const owners = added.map((line) => {
          assert(/^\s*<position x="[-\d.]+" y="[-\d.]+"\s*\/>$/.test(line), `${path.basename(p)}: not a position: ${line}`);
          const at = lines.indexOf(line);
          return lines.slice(0, at).reverse().find((l) => /<(step|transition|actionBlock|jumpStep|selectionDivergence|selectionConvergence|simultaneousDivergence|simultaneousConvergence|comment|block|inVariable|outVariable)\b/.test(l)) ?? '';
        });
        assert(owners[0].includes(`name="${step.name}"`), `${path.basename(p)}: the changed position belongs to ${owners[0]}`);
        assert(owners.slice(1).every((o) => o.includes('<actionBlock')), `${path.basename(p)}: also changed: ${owners.slice(1)}`);
        sfc(t, ['check', '--no-analysis', file]);
      }
    },
  },
];
