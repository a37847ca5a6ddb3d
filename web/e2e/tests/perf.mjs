// A 500-step chart: the time from navigation to the chart drawn (target: under 1 s), and the
// frame times while a step is dragged by mouse for about 60 frames (target: p95 under 50 ms).
// The figures are printed, with the machine's load; only a generous sanity bound is asserted
// (the machine running the tests may be busy). It runs the release binary when there is one
// (SFC_RELEASE_BIN, default target/release/sfc, which is skipped when it is older than the
// binary the other tests run), which serves the production build of the app (no test hook), so
// it reads only the page's DOM.
//
// The chart is IEC text without any layout (no sfc.* positions), as another tool would write
// it, so the server lays it out on opening: a sequence of 125 sections, each a step with a
// two-way selection whose branches (one step each) meet again in a step: 500 steps, 625
// transitions, and a jump from the last step back to the initial one.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { assert, shotPath } from '../helpers.mjs';

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
      // The release binary, unless it is older than the binary the other tests run (then it
      // was built from older sources, and its figures would not be this code's).
      const release = process.env.SFC_RELEASE_BIN ?? path.join(t.root, 'target', 'release', 'sfc');
      const mtime = (p) => (fs.existsSync(p) ? fs.statSync(p).mtimeMs : -1);
      const stale = !process.env.SFC_RELEASE_BIN && mtime(release) >= 0 && mtime(release) < mtime(t.sfcBin);
      if (stale) t.log(`${release} is older than ${t.sfcBin}: measuring the debug binary instead`);
      const useRelease = mtime(release) >= 0 && !stale;
      const server = await t.edit([file], t.scratch, useRelease ? { bin: release, production: true } : {});
      await page.addInitScript(() => localStorage.setItem('sfc.language', 'en'));
      // 11 blocks and 12 wires per section, and the jump back.
      const blocks = 11 * SECTIONS + 1;
      const wires = 12 * SECTIONS;

      // Navigation → every block and wire drawn.
      const started = Date.now();
      await page.goto(server.url);
      // Checked before each frame is rendered: the frame in which everything is in the page is
      // then styled, laid out and painted, and a task posted now runs after that (`painted`).
      const drawnAt = await page.waitForFunction(
        ([b, w]) => {
          const shapes = document.querySelectorAll('.canvas-pane.active .djs-shape').length;
          const lines = document.querySelectorAll('.canvas-pane.active .djs-connection').length;
          if (shapes !== b || lines !== w) return false;
          setTimeout(() => (window.__painted = performance.now()));
          return performance.now();
        },
        [blocks, wires],
        { polling: 'raf', timeout: 30_000 },
      );
      const inPageMs = await drawnAt.jsonValue();
      const paintedMs = await (await page.waitForFunction(() => window.__painted ?? false, null, { timeout: 30_000 })).jsonValue();
      const openMs = Date.now() - started;
      // The server's share: the API requests of the page (opening the chart, its diagnostics).
      const api = await page.evaluate(() =>
        performance
          .getEntriesByType('resource')
          .filter((e) => e.name.includes('/api/'))
          .map((e) => `${new URL(e.name).pathname} ${e.duration.toFixed(0)} ms`)
          .join(', '),
      );
      t.log(`requests to the server while opening: ${api}`);
      // index.html asks for the session and the named file while the app loads; the app takes
      // both answers over instead of asking again.
      for (const p of ['/api/session', '/api/open']) {
        const n = api.split(', ').filter((x) => x.startsWith(`${p} `)).length;
        assert(n === 1, `${p} was requested ${n} times while opening (${api})`);
      }
      const load = os.loadavg().map((x) => x.toFixed(2)).join(' ');
      t.log(
        `open (${useRelease ? 'release' : 'debug'} binary): ${paintedMs.toFixed(0)} ms from navigation start to ${4 * SECTIONS} steps, ${blocks} blocks and ${wires} wires painted on screen ` +
          `(all in the page at ${inPageMs.toFixed(0)} ms, then styled, laid out and painted; ${openMs} ms by the test's clock, with its own round trips); target < 1000 ms; load average ${load} on ${os.cpus().length} cores`,
      );
      assert(openMs < 20_000, `opening took ${openMs} ms`);
      await page.screenshot({ path: shotPath(t, 'big-500-steps.png') });

      // Drag a visible step for 60 frames, one mouse move per animation frame.
      const pane = await page.locator('.canvas-pane.active').boundingBox();
      const target = await page.evaluate((p) => {
        for (const g of document.querySelectorAll('.canvas-pane.active .djs-shape[data-element-id^="step:"]')) {
          const id = g.getAttribute('data-element-id');
          if (id === 'step:P0') continue;
          const r = g.getBoundingClientRect();
          if (r.x > p.x + 250 && r.y > p.y + 40 && r.right < p.x + p.width - 200 && r.bottom < p.y + p.height - 200) {
            return { id, b: { x: r.x, y: r.y, width: r.width, height: r.height }, transform: g.getAttribute('transform') };
          }
        }
        return null;
      }, pane);
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
        // Left, into the free canvas beside the chart: a move onto another block is refused.
        await page.mouse.move(from.x - 2.5 * k, from.y + 1.5 * k);
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
      const moved = await page.evaluate((id) => document.querySelector(`.canvas-pane.active [data-element-id="${id}"]`).getAttribute('transform'), target.id);
      assert(moved !== target.transform, 'the step did not move');
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
