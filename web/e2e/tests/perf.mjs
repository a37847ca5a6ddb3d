// A 500-step chart: the time from navigation to the chart drawn (target: under 1 s), and the
// frame times while a step is dragged by mouse for about 60 frames. The figures are printed;
// only a generous sanity bound is asserted (the machine running the tests may be busy).
//
// The chart is IEC text without any layout (no sfc.* positions), as another tool would write
// it, so the server lays it out on opening: a sequence of 125 sections, each a step with a
// two-way selection whose branches (one step each) meet again in a step: 500 steps, 625
// transitions, and a jump from the last step back to the initial one.
import fs from 'node:fs';
import path from 'node:path';
import { assert, box, openEditor, shotPath } from '../helpers.mjs';

const SECTIONS = 125;

/** IEC text of the chart (4 steps per section). */
export function bigChartText(sections = SECTIONS) {
  const out = ['PROGRAM Big', '    VAR', '        Go, Left, Right, Done : BOOL;', '    END_VAR', ''];
  const step = (name, initial = false) => out.push(`    ${initial ? 'INITIAL_STEP' : 'STEP'} ${name}: END_STEP`);
  const tr = (name, from, to, cond) => out.push(`    TRANSITION ${name} FROM ${from} TO ${to}`, `        := ${cond};`, '    END_TRANSITION');
  for (let k = 0; k < sections; k++) {
    step(`P${k}`, k === 0);
    tr(`TL${k}`, `P${k}`, `L${k}`, 'Go AND Left');
    tr(`TR${k}`, `P${k}`, `R${k}`, 'Go AND NOT Left');
    step(`L${k}`);
    tr(`TLM${k}`, `L${k}`, `M${k}`, 'Done');
    step(`R${k}`);
    tr(`TRM${k}`, `R${k}`, `M${k}`, 'Right');
    step(`M${k}`);
    tr(`TN${k}`, `M${k}`, k + 1 < sections ? `P${k + 1}` : 'P0', 'NOT Go');
  }
  out.push('END_PROGRAM', '');
  return out.join('\n');
}

const percentile = (sorted, p) => sorted[Math.min(sorted.length - 1, Math.floor((p / 100) * sorted.length))];

export const tests = [
  {
    name: '500 steps: open time and frame times while dragging a step',
    run: async (t) => {
      const { page } = t;
      const file = path.join(t.scratch, 'big.st');
      fs.writeFileSync(file, bigChartText());
      const server = await t.edit([file]);
      await page.addInitScript(() => localStorage.setItem('sfc.language', 'en'));

      // Navigation → every block and wire drawn.
      const started = Date.now();
      await page.goto(server.url);
      const drawnAt = await page.waitForFunction(
        () => {
          const d = window.__sfc?.doc();
          if (!d) return false;
          const shapes = document.querySelectorAll('.canvas-pane.active .djs-shape').length;
          const wires = document.querySelectorAll('.canvas-pane.active .djs-connection').length;
          return shapes === d.elements.length && wires === d.connections.length ? performance.now() : false;
        },
        null,
        { polling: 'raf', timeout: 30_000 },
      );
      const openMs = Date.now() - started;
      const inPageMs = await drawnAt.jsonValue();
      const d = await page.evaluate(() => window.__sfc.doc());
      const steps = d.elements.filter((e) => e.kind === 'step');
      assert(steps.length === 4 * SECTIONS, `${steps.length} steps`);
      t.log(`open: ${openMs} ms from navigation to ${steps.length} steps, ${d.elements.length} blocks and ${d.connections.length} wires drawn (${inPageMs.toFixed(0)} ms after navigation start in the page); target < 1000 ms`);
      assert(openMs < 10_000, `opening took ${openMs} ms`);
      await page.screenshot({ path: shotPath(t, 'big-500-steps.png') });

      // Drag a visible step for 60 frames, one mouse move per animation frame.
      const pane = await page.locator('.canvas-pane.active').boundingBox();
      let target = null;
      for (const s of steps.slice(1)) {
        const b = await box(page, s.id);
        if (b.x > pane.x + 250 && b.y > pane.y + 40 && b.x + b.width < pane.x + pane.width - 200 && b.y + b.height < pane.y + pane.height - 200) {
          target = { id: s.id, b };
          break;
        }
      }
      assert(target, 'no step fully in view to drag');
      const from = { x: target.b.x + target.b.width / 2, y: target.b.y + target.b.height / 2 };
      await page.evaluate(() => {
        window.__frames = [];
        const tick = (now) => {
          window.__frames.push(now);
          if (window.__framesOn) requestAnimationFrame(tick);
        };
        window.__framesOn = true;
        requestAnimationFrame(tick);
      });
      const nextFrame = () => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
      const mark = () => page.evaluate(() => window.__frames.length);
      await page.mouse.move(from.x, from.y);
      const down = await mark();
      await page.mouse.down();
      const FRAMES = 60;
      let moving = 0;
      for (let k = 1; k <= FRAMES; k++) {
        await page.mouse.move(from.x + 2.5 * k, from.y + 1.5 * k);
        await nextFrame();
        // The first moves pick the step up (diagram-js starts the drag after a few pixels).
        if (k === 3) moving = await mark();
      }
      const up = await mark();
      await page.mouse.up();
      await nextFrame();
      await nextFrame();
      const frames = await page.evaluate(() => {
        window.__framesOn = false;
        return window.__frames;
      });
      const moved = await page.evaluate((id) => window.__sfc.doc().elements.find((e) => e.id === id), target.id);
      const before = steps.find((s) => s.id === target.id);
      assert(moved.x !== before.x || moved.y !== before.y, 'the step did not move');
      // Frame times (ms) between frames `a` and `b` of the recording.
      const span = (a, b) => frames.slice(a + 1, b + 1).map((f, i) => f - frames[a + i]);
      const deltas = span(moving, up).sort((a, b) => a - b);
      assert(deltas.length >= FRAMES / 2, `only ${deltas.length} frames recorded while moving`);
      const p50 = percentile(deltas, 50);
      const p95 = percentile(deltas, 95);
      const max = deltas[deltas.length - 1];
      const pickUp = Math.max(...span(down, moving));
      const drop = Math.max(...span(up, frames.length - 1));
      t.log(
        `drag of ${target.id}, ${FRAMES} mouse moves: while moving ${deltas.length} frames, frame time p50 ${p50.toFixed(1)} ms, p95 ${p95.toFixed(1)} ms, max ${max.toFixed(1)} ms; ` +
          `longest frame at pick-up ${pickUp.toFixed(1)} ms, at drop ${drop.toFixed(1)} ms`,
      );
      assert(p50 < 250, `dragging is not interactive: p50 frame time ${p50} ms`);
    },
  },
];
