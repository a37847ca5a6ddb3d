// Wires drawn by mouse: an invalid connection (step → step, transition → transition) is refused
// while dragging (the "not allowed" cursor, no pin ringed) and on release (no wire in the
// document); valid ones, the mixed branch structures of IEC included, are accepted.
import { assert, doc, dropFromPalette, openEditor, pin, waitChart, wire } from '../helpers.mjs';

/** A new blank chart in a fresh editor; returns the id of its initial step. */
async function blankChart(t) {
  await openEditor(t, ['.']);
  await t.page.locator('.welcome .button.primary').click();
  await t.page.locator('#new-name').fill('Rules');
  await t.page.locator('.modal .button.primary').click();
  const d = await waitChart(t.page);
  return d.elements[0].id;
}

/** Drags from output `outPin` of `from` to input `inPin` of `to`, reporting what the canvas
 *  showed over the target before the button was released. */
async function tryWire(page, from, to, outPin = 0, inPin = 0) {
  const wires = (await doc(page)).connections.length;
  const a = await pin(page, from, 'out', outPin);
  const b = await pin(page, to, 'in', inPin);
  await page.mouse.move(a.x, a.y);
  await page.mouse.down();
  await page.mouse.move(a.x + 4, a.y + 4, { steps: 2 });
  await page.mouse.move(b.x, b.y + 2, { steps: 8 });
  const during = await page.evaluate(() => ({
    cursor: window.__sfc.cursor(),
    // The ring drawn round the pin a release would connect to.
    ringed: document.querySelectorAll('.canvas-pane.active .layer-sfc-connect circle[stroke="#16a34a"]').length,
  }));
  await page.mouse.up();
  await page.waitForFunction(() => !document.querySelector('.canvas-pane.active .layer-sfc-connect g'));
  const after = (await doc(page)).connections.length;
  return { ...during, added: after - wires };
}

export const tests = [
  {
    name: 'invalid wires are refused while dragging and on release; valid ones are drawn',
    run: async (t) => {
      const { page } = t;
      const init = await blankChart(t);
      const d = await doc(page);
      const s0 = d.elements.find((e) => e.id === init);
      const cx = s0.x + s0.w / 2;
      const s1 = await dropFromPalette(page, 'step', { x: cx, y: s0.y + 160 });
      const t1 = await dropFromPalette(page, 'transition', { x: cx + 200, y: s0.y + 90 });
      const t2 = await dropFromPalette(page, 'transition', { x: cx + 200, y: s0.y + 190 });

      // Step output → step input: not allowed.
      let r = await tryWire(page, init, s1);
      assert(r.cursor === 'not-allowed' && r.ringed === 0 && r.added === 0, `step → step: ${JSON.stringify(r)}`);
      // Transition output → transition input: not allowed.
      r = await tryWire(page, t1, t2);
      assert(r.cursor === 'not-allowed' && r.ringed === 0 && r.added === 0, `transition → transition: ${JSON.stringify(r)}`);
      // Step → transition and transition → step: allowed, the target pin ringed.
      r = await tryWire(page, init, t1);
      assert(r.ringed === 1 && r.cursor !== 'not-allowed' && r.added === 1, `step → transition: ${JSON.stringify(r)}`);
      r = await tryWire(page, t1, s1);
      assert(r.ringed === 1 && r.added === 1, `transition → step: ${JSON.stringify(r)}`);
      // A pin holds one wire: the step's output is taken now.
      r = await tryWire(page, init, t2);
      assert(r.ringed === 0 && r.added === 0, `second wire on a taken pin: ${JSON.stringify(r)}`);
      const wires = (await doc(page)).connections;
      assert(wires.length === 2, `wires: ${JSON.stringify(wires)}`);
      assert(wires.some((c) => c.source === init && c.target === t1) && wires.some((c) => c.source === t1 && c.target === s1), 'the two valid wires');
    },
  },
  {
    name: 'the mixed branch structures of IEC are accepted',
    run: async (t) => {
      const { page } = t;
      await blankChart(t);
      // Simultaneous divergence → jump and → selection convergence; selection divergence →
      // simultaneous convergence (sfc-doc reads and writes all three).
      const and = await dropFromPalette(page, 'simultaneous-divergence', { x: 200, y: 100 });
      const jump = await dropFromPalette(page, 'jump', { x: 150, y: 200 });
      const or = await dropFromPalette(page, 'selection-convergence', { x: 320, y: 200 });
      const sel = await dropFromPalette(page, 'selection-divergence', { x: 200, y: 300 });
      const join = await dropFromPalette(page, 'simultaneous-convergence', { x: 200, y: 420 });
      assert(await wire(page, and, jump, 0, 0), 'simultaneous divergence → jump refused');
      assert(await wire(page, and, or, 1, 0), 'simultaneous divergence → selection convergence refused');
      assert(await wire(page, sel, join, 0, 0), 'selection divergence → simultaneous convergence refused');
      // …but a selection divergence still cannot feed a step directly.
      const step = await dropFromPalette(page, 'step', { x: 420, y: 440 });
      const r = await tryWire(page, sel, step, 1, 0);
      assert(r.added === 0 && r.cursor === 'not-allowed', `selection divergence → step: ${JSON.stringify(r)}`);
    },
  },
];
