// Seed 003's mechanisms in the editor's monitor mode: `sfc run` runs the spindle reversal's
// program Main (examples/spindle), whose SFC instance Rev is the mechanism CWCCW; the editor,
// with the mechanism's chart open, attaches to it. The inputs start a reversal with the CW
// contactor's feedback stuck: after its supervision time, error 4.04. The Mechanisms tab lists
// Rev with its state, runs and the error record naming the feedback contact with its terminal;
// selecting Rev shows that instance on the chart; the Time analysis tab shows Rev's runs with
// the states passed. Screenshots in e2e/out/mechanisms-*.png.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { until } from '../helpers.mjs';

const OUT = (name) => path.join(path.dirname(new URL(import.meta.url).pathname), '..', 'out', `mechanisms-${name}.png`);

/** The names of the steps framed green (active) on the monitor's canvas. */
function active(page) {
  return page.evaluate(() => {
    const out = [];
    for (const g of document.querySelectorAll('.mon-canvas g.djs-shape[data-element-id]')) {
      const visual = g.querySelector('.djs-visual');
      if (!visual || !visual.querySelector('rect[stroke="#16a34a"]')) continue;
      out.push([...visual.querySelectorAll('text')].map((x) => x.textContent.trim()).find((x) => /^[A-Za-z_]\w*$/.test(x)));
    }
    return out.sort();
  });
}

/** Starts `sfc run CHART` with a monitor on a free port; resolves with its URL and a stop. */
function runtime(t, chart, token) {
  return new Promise((resolve, reject) => {
    const proc = spawn(t.sfcBin, ['run', chart, '--period', 'T#10ms', '--monitor', '127.0.0.1:0', '--no-retain'], {
      env: { ...process.env, SFC_TOKEN: token },
      stdio: ['ignore', 'ignore', 'pipe'],
    });
    let err = '';
    const timer = setTimeout(() => {
      proc.kill('SIGTERM');
      reject(new Error(`sfc run printed no monitor URL within 20 s: ${err}`));
    }, 20_000);
    proc.stderr.on('data', (d) => {
      err += d;
      const m = /sfc run: monitor on (ws:\/\/127\.0\.0\.1:\d+\/)/.exec(err);
      if (m) {
        clearTimeout(timer);
        resolve({
          url: m[1],
          log: () => err,
          stop: () =>
            new Promise((done) => {
              if (proc.exitCode !== null || proc.signalCode !== null) return done();
              proc.once('exit', () => done());
              proc.kill('SIGTERM');
            }),
        });
      }
    });
    proc.on('exit', (code) => reject(new Error(`sfc run exited with ${code}: ${err}`)));
  });
}

async function writeBool(page, name) {
  const row = page.locator(`.mon-vars tr[data-var="${name}"]`);
  await row.locator('select').selectOption('TRUE');
  await row.getByRole('button', { name: 'Set', exact: true }).click();
}

export const tests = [
  {
    name: 'every mechanism at a glance, its error record with terminals, and its chart',
    run: async (t) => {
      const { page } = t;
      const errors = [];
      page.on('pageerror', (e) => errors.push(e.message));
      const chart = path.join(t.scratch, 'examples', 'spindle', 'spindle.st');
      const rt = await runtime(t, chart, 'e2e-mechanisms');
      try {
        const s = await t.edit([chart]);
        await page.goto(s.url);
        await page.locator('.canvas-pane.active .djs-container').waitFor();
        await page.locator('.tab.active', { hasText: 'SpindleReversal' }).waitFor();

        // Attach to the runtime (Main with its instance Rev).
        await page.getByRole('menuitem', { name: 'Monitor' }).or(page.locator('.menubar button', { hasText: 'Monitor' })).first().click();
        await page.getByRole('menuitem', { name: 'Attach to runtime…' }).or(page.getByText('Attach to runtime…')).first().click();
        await page.locator('.modal input').fill(`${rt.url}?token=e2e-mechanisms`);
        await page.locator('.modal .button.primary').click();
        await until(page, 'the running badge', async () => (await page.getByTestId('monitor-state').textContent()) === 'Running');

        // Mechanisms: Rev, idle in Rev.Idle, no run yet.
        await page.getByRole('tab', { name: 'Mechanisms' }).click();
        const rev = page.locator('.mon-mechanisms tr[data-instance="Rev"]');
        await rev.waitFor();
        if (!(await rev.textContent()).includes('SpindleReversal')) throw new Error(`Rev's row: ${await rev.textContent()}`);
        await until(page, 'Rev idle in Rev.Idle', async () => /idle/.test(await rev.textContent()) && /Rev\.Idle/.test(await rev.textContent()));

        // The spindle runs CW with its contact closed; reverse: KSMP stays closed (welded).
        await page.getByRole('tab', { name: 'Variables' }).click();
        await writeBool(page, 'StartCwButton');
        await writeBool(page, 'KM1Contact');
        await page.waitForTimeout(100);
        await writeBool(page, 'ReverseButton');

        await page.getByRole('tab', { name: 'Mechanisms' }).click();
        await until(page, 'Rev running', async () => /running/.test(await page.locator('.mon-mechanisms tr[data-instance="Rev"]').textContent()));
        // After the supervision time of OpenKM1 (1 s): error 4.04 with the condition in words.
        const record = page.locator('.mon-mechanisms tr[data-instance-error="Rev"]');
        const text = await until(page, 'the error record', async () => ((await record.count()) ? await record.textContent() : ''));
        for (const want of ['error 404 in step Rev.OpenKM1', 'KM1Fb (X12.2, %IX0.4) is TRUE; needs FALSE']) {
          if (!text.includes(want)) throw new Error(`the error record lacks "${want}": ${text}`);
        }
        await until(page, 'Rev in Rev.Err404', async () => /Rev\.Err404/.test(await page.locator('.mon-mechanisms tr[data-instance="Rev"]').textContent()));
        await page.screenshot({ path: OUT('1-error') });

        // Selecting Rev shows that instance on the chart: Err404 framed green.
        await page.locator('.mon-mechanisms tr[data-instance="Rev"]').click();
        await until(page, 'Err404 framed green', async () => JSON.stringify(await active(page)) === '["Err404"]');
        await page.screenshot({ path: OUT('2-chart') });

        // The time analysis per run: Rev's run with the states passed in order, and the
        // statistics per state over runs.
        await page.getByRole('tab', { name: 'Time analysis' }).click();
        const runs = page.locator('.mon-runs[data-mechanism="Rev"]');
        await runs.waitFor();
        const run = runs.locator('.mon-run-table tr[data-run="1"]');
        const passed = await until(page, 'run 1 through OpenKM1 into Err404', async () => {
          if (!(await run.count())) return '';
          const x = await run.textContent();
          return /Rev\.OpenKM1 T#1s\d*ms → Rev\.Err404/.test(x) ? x : '';
        });
        if (!passed.includes('in progress')) throw new Error(`run 1 waits in its error step, in progress: ${passed}`);
        const stats = await runs.locator('.mon-state-stats').textContent();
        if (!/Rev\.OpenKM1\s*1/.test(stats)) throw new Error(`OpenKM1 counted once over runs: ${stats}`);
        await page.screenshot({ path: OUT('3-runs') });
        if (!rt.log().includes('error record: Rev: error 404')) throw new Error(`the runtime's log lacks the record: ${rt.log()}`);
        if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
      } finally {
        await rt.stop();
      }
    },
  },
  {
    name: "selecting a mechanism of another chart moves the monitor to that chart's tab",
    run: async (t) => {
      const { page } = t;
      const errors = [];
      page.on('pageerror', (e) => errors.push(e.message));
      const chart = path.join(t.scratch, 'two_mechanisms.st');
      fs.copyFileSync(path.join(path.dirname(new URL(import.meta.url).pathname), '..', 'fixtures', 'two_mechanisms.st'), chart);
      const rt = await runtime(t, chart, 'e2e-two');
      try {
        const s = await t.edit([chart]);
        await page.goto(s.url);
        await page.locator('.canvas-pane.active .djs-container').waitFor();
        await page.locator('.tab', { hasText: 'Drill' }).waitFor();
        await page.locator('.tab', { hasText: 'Clamp' }).click();
        await page.getByRole('menuitem', { name: 'Monitor' }).or(page.locator('.menubar button', { hasText: 'Monitor' })).first().click();
        await page.getByRole('menuitem', { name: 'Attach to runtime…' }).or(page.getByText('Attach to runtime…')).first().click();
        await page.locator('.modal input').fill(`${rt.url}?token=e2e-two`);
        await page.locator('.modal .button.primary').click();
        await until(page, 'the running badge', async () => (await page.getByTestId('monitor-state').textContent()) === 'Running');

        await writeBool(page, 'Start');
        await page.getByRole('tab', { name: 'Mechanisms', exact: true }).click();
        const spindle = page.locator('.mon-mechanisms tr[data-instance="Spindle"]');
        await until(page, 'Spindle boring', async () => /Spindle\.Boring/.test(await spindle.textContent()));
        // Holder is the clamp's own instance: shown on this chart.
        await page.locator('.mon-mechanisms tr[data-instance="Holder"]').click();
        await until(page, 'Holding framed green', async () => JSON.stringify(await active(page)) === '["Holding"]');
        // Spindle is a Drill: the monitor moves to the Drill tab, on the same runtime.
        await spindle.click();
        await until(page, 'Boring framed green on the drill', async () => JSON.stringify(await active(page)) === '["Boring"]');
        await page.locator('.mon-mechanisms tr[data-instance="Spindle"].selected').waitFor();
        await page.locator('.tab.active', { hasText: 'Drill' }).waitFor({ state: 'attached' });
        await page.screenshot({ path: OUT('4-other-chart') });
        if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
      } catch (e) {
        throw new Error(`${e.message}\nruntime log:\n${rt.log()}`);
      } finally {
        await rt.stop();
      }
    },
  },
];
