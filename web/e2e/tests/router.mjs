// The wire router by mouse: moving a block re-routes its own wires (and no others) without
// loops and through no block or label; a straight wire dragged sideways goes round what it
// would cross (issue 15: step Heat moved 120 left and 20 down overshot T4 and came back; a
// dragged wire crossed a transition bar and its label).
import fs from 'node:fs';
import path from 'node:path';
import { assert, box, doc, openEditor, shotPath, waitChart } from '../helpers.mjs';

/** Blocks and labels on the canvas (canvas units), and every wire's polyline. */
async function drawing(page) {
  return page.evaluate(() => {
    const d = window.__sfc.doc();
    const rects = d.elements.map((e) => ({ id: e.id, x: e.x, y: e.y, w: e.w, h: e.h }));
    for (const e of d.elements) {
      const g = document.querySelector(`.canvas-pane.active .djs-element[data-element-id="${CSS.escape(e.id)}"]`);
      for (const t of g ? g.querySelectorAll('.djs-visual text') : []) {
        const b = t.getBBox();
        // Labels outside the block (inside text is the block's own).
        if (b.x >= 0 && b.x + b.width <= e.w && b.y >= 0 && b.y + b.height <= e.h) continue;
        rects.push({ id: `${e.id} label "${t.textContent}"`, x: e.x + b.x, y: e.y + b.y, w: b.width, h: b.height });
      }
    }
    return { rects, wires: d.connections.map((c) => ({ id: c.id, source: c.source, target: c.target, points: c.waypoints ?? [] })) };
  });
}

const crosses = (a, b, r) => {
  const E = 1;
  if (a.y === b.y) return a.y > r.y + E && a.y < r.y + r.h - E && Math.min(a.x, b.x) < r.x + r.w - E && Math.max(a.x, b.x) > r.x + E;
  return a.x > r.x + E && a.x < r.x + r.w - E && Math.min(a.y, b.y) < r.y + r.h - E && Math.max(a.y, b.y) > r.y + E;
};

/** What is wrong with a wire: crossings, diagonal runs, and (going down) runs back up. */
function wireFaults(w, rects) {
  const out = [];
  const p = w.points;
  for (let i = 1; i < p.length; i++) {
    if (p[i].x !== p[i - 1].x && p[i].y !== p[i - 1].y) out.push(`${w.id} has a diagonal run`);
    for (const r of rects) if (crosses(p[i - 1], p[i], r)) out.push(`${w.id} runs through ${r.id}`);
  }
  if (p.length >= 2 && p[p.length - 1].y > p[0].y) {
    for (let i = 1; i < p.length; i++) if (p[i].y < p[i - 1].y) out.push(`${w.id} loops back up`);
  }
  return out;
}

async function dragBy(page, from, dx, dy) {
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  await page.mouse.move(from.x + Math.sign(dx || 1) * 5, from.y + 5, { steps: 2 });
  await page.mouse.move(from.x + dx, from.y + dy, { steps: 12 });
  await page.mouse.up();
}

export const tests = [
  {
    name: 'moving step Heat 120 left and 20 down re-routes its own wires, without loops, through nothing',
    run: async (t) => {
      const { page } = t;
      fs.copyFileSync(path.join(t.root, 'tests/fixtures/valid/simultaneous_divergence.st'), path.join(t.scratch, 'parallel.st'));
      await openEditor(t, ['parallel.st']);
      await waitChart(page);
      const before = await drawing(page);
      const b = await box(page, 'step:Heat');
      const zoom = await page.evaluate(() => window.__sfc.zoom());
      await dragBy(page, { x: b.x + b.width / 2, y: b.y + b.height / 2 }, -120 * zoom, 20 * zoom);
      const moved = (await doc(page)).elements.find((e) => e.id === 'step:Heat');
      const was = (await page.evaluate(() => 0)) || null;
      void was;
      const after = await drawing(page);
      assert(after.rects.find((r) => r.id === 'step:Heat').x !== before.rects.find((r) => r.id === 'step:Heat').x, `Heat moved: ${JSON.stringify(moved)}`);
      await page.screenshot({ path: shotPath(t, 'router-heat-moved.png') });
      const own = after.wires.filter((w) => w.source === 'step:Heat' || w.target === 'step:Heat');
      assert(own.length === 2, `Heat has two wires: ${own.length}`);
      const faults = own.flatMap((w) => wireFaults(w, after.rects));
      assert(faults.length === 0, faults.join('; '));
      // Only its own wires changed.
      for (const w of after.wires) {
        if (own.includes(w)) continue;
        const old = before.wires.find((x) => x.id === w.id);
        assert(JSON.stringify(old.points) === JSON.stringify(w.points), `wire ${w.id} of other blocks was re-routed`);
      }
    },
  },
  {
    name: 'a straight wire dragged sideways goes round the transition bar and label it would cross',
    run: async (t) => {
      const { page } = t;
      await openEditor(t, ['examples/blinker/blinker.st']);
      await waitChart(page);
      const d0 = await doc(page);
      // The wire from S2 down to its transition T2: drag its middle 60 units right, across T2's
      // bar and condition label.
      const w = d0.connections.find((c) => c.source === 'step:S2');
      const s2 = d0.elements.find((e) => e.id === 'step:S2');
      const t2 = d0.elements.find((e) => e.id === w.target);
      const mid = await page.evaluate(([x, y]) => window.__sfc.toScreen({ x, y }), [s2.x + s2.w / 2, (s2.y + s2.h + t2.y) / 2]);
      const zoom = await page.evaluate(() => window.__sfc.zoom());
      await page.mouse.move(mid.x, mid.y);
      await page.waitForTimeout(150);
      await dragBy(page, mid, 60 * zoom, 0);
      const after = await drawing(page);
      const wire = after.wires.find((x) => x.id === w.id);
      await page.screenshot({ path: shotPath(t, 'router-dragged-wire.png') });
      const faults = wireFaults(wire, after.rects);
      assert(faults.length === 0, `${faults.join('; ')}: ${JSON.stringify(wire.points)}`);
    },
  },
];
