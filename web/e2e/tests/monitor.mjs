// Monitor mode in the browser: the car wash opened in `sfc edit`, the built-in simulator started
// from the toolbar, inputs written from the Variables panel, a breakpoint set from the context
// menu and hit (orange frame, halted), the condition analysis of the halted step, stepping back
// through the buffered states, an input forced, Continue, and the chart moving on. Real mouse and
// keyboard; screenshots of each state in e2e/out/monitor-*.png.
import fs from 'node:fs';
import path from 'node:path';
import { until as untilWithin } from '../helpers.mjs';

const until = (page, what, check, ms = 10_000) => untilWithin(page, what, check, ms);

const OUT = (t, name) => path.join(path.dirname(new URL(import.meta.url).pathname), '..', 'out', `monitor-${name}.png`);

/** Fails with `what` unless `check()` becomes truthy within `ms`. */
/** The steps of the monitor's canvas framed in `colour` (green: active, orange: hit). */
function framed(page, colour) {
  return page.evaluate((c) => {
    const out = [];
    for (const g of document.querySelectorAll('.mon-canvas g.djs-shape[data-element-id]')) {
      const visual = g.querySelector('.djs-visual');
      if (!visual || !visual.querySelector(`rect[stroke="${c}"]`)) continue;
      const name = [...visual.querySelectorAll('text')].map((x) => x.textContent.trim()).find((x) => /^[A-Za-z_]\w*$/.test(x));
      out.push(name);
    }
    return out.sort();
  }, colour);
}
const active = (page) => framed(page, '#16a34a');
const hit = (page) => framed(page, '#f97316');

/** The centre of the step or transition `name` on the monitor's canvas, in page pixels. */
async function centreOf(page, name) {
  const r = await page.evaluate((n) => {
    for (const g of document.querySelectorAll('.mon-canvas g.djs-shape[data-element-id]')) {
      const texts = [...g.querySelectorAll('.djs-visual text')].map((x) => x.textContent.trim());
      if (!texts.includes(n)) continue;
      const b = g.querySelector('.djs-visual').getBoundingClientRect();
      return { x: b.left + b.width / 2, y: b.top + b.height / 2 };
    }
    return null;
  }, name);
  if (!r) throw new Error(`no block ${name} on the monitor's canvas`);
  return r;
}

/** Writes (Set) or forces a BOOL variable in the Variables panel. */
async function writeBool(page, name, value, op = 'Set') {
  const row = page.locator(`.mon-vars tr[data-var="${name}"]`);
  await row.locator('select').selectOption(value ? 'TRUE' : 'FALSE');
  await row.getByRole('button', { name: op, exact: true }).click();
}

/** The value shown for a variable. */
function shown(page, name) {
  return page.locator(`.mon-vars tr[data-var="${name}"] .mon-val`).textContent();
}

export const tests = [
  {
    name: 'simulate, break, step back, force, continue',
    run: async (t) => {
      const { page } = t;
      const errors = [];
      page.on('pageerror', (e) => errors.push(e.message));
      const chart = path.join(t.scratch, 'examples', 'carwash', 'carwash.st');
      const s = await t.edit([chart]);
      await page.goto(s.url);
      await page.locator('.canvas-pane.active .djs-container').waitFor();
      await page.locator('.tab.active', { hasText: 'CarWash' }).waitFor();

      // Start the simulation from the toolbar: the chart read-only, Idle active.
      await page.getByRole('button', { name: 'Start simulation' }).click();
      await page.locator('.mon-overlay').waitFor();
      await until(page, 'the running badge', async () => (await page.getByTestId('monitor-state').textContent()) === 'Running');
      await until(page, 'Idle framed green', async () => JSON.stringify(await active(page)) === '["Idle"]');
      // Its elapsed time is written beside it and grows.
      const label = async () =>
        page.evaluate(() => [...document.querySelectorAll('.mon-canvas .djs-visual text')].map((x) => x.textContent).find((x) => / (ms|s)$/.test(x)));
      const first = await until(page, 'an elapsed time label', label);
      await until(page, 'the elapsed time to move', async () => (await label()) !== first);
      await page.screenshot({ path: OUT(t, '1-running') });

      // A breakpoint on Brushing from the context menu (right click on the step).
      const brushing = await centreOf(page, 'Brushing');
      await page.mouse.click(brushing.x, brushing.y, { button: 'right' });
      await page.locator('.mon-context').getByRole('menuitem', { name: 'Set breakpoint' }).click();
      await page.getByRole('tab', { name: /Breakpoints/ }).click();
      await page.locator('.mon-side-body', { hasText: 'Brushing' }).waitFor();
      // And one on Fault from the toolbar (select it, then the breakpoint button), removed again with F9.
      const fault = await centreOf(page, 'Fault');
      await page.mouse.click(fault.x, fault.y);
      await page.getByRole('button', { name: 'Set breakpoint (F9)' }).click();
      await until(page, 'two breakpoints', async () => (await page.locator('.mon-side-body tr').count()) === 2);
      await page.keyboard.press('F9');
      await until(page, 'one breakpoint', async () => (await page.locator('.mon-side-body tr').count()) === 1);
      // The chart is redrawn after the list (a frame later on a busy machine).
      const dots = () => page.evaluate(() => document.querySelectorAll('.mon-canvas circle[fill="#dc2626"]').length);
      await until(page, 'one breakpoint dot on the chart', async () => (await dots()) === 1);

      // Inputs from the Variables panel: a car at home, then Start: the active step moves.
      await page.getByRole('tab', { name: 'Variables' }).click();
      await writeBool(page, 'CarPresent', true);
      await writeBool(page, 'AtHome', true);
      await until(page, 'CarPresent TRUE', async () => (await shown(page, 'CarPresent')) === 'TRUE');
      await writeBool(page, 'StartButton', true);
      await until(page, 'Spraying framed green', async () => JSON.stringify(await active(page)) === '["Spraying"]');
      await page.screenshot({ path: OUT(t, '2-spraying') });

      // The car reaches the brushes: Brushing becomes active, the breakpoint halts the run.
      await writeBool(page, 'CarAtBrush', true);
      await until(page, 'Brushing framed orange', async () => JSON.stringify(await hit(page)) === '["Brushing"]');
      await until(page, 'the halted badge', async () => (await page.getByTestId('monitor-state').textContent()) === 'Halted at Brushing');
      const scanAtHit = await page.getByTestId('monitor-scan').textContent();
      await page.waitForTimeout(300);
      if ((await page.getByTestId('monitor-scan').textContent()) !== scanAtHit) throw new Error('the simulator kept scanning while halted');

      // Why is Brushing still active? The analysis beside the step and in the panel.
      const b2 = await centreOf(page, 'Brushing');
      await page.mouse.click(b2.x, b2.y);
      await page.getByRole('button', { name: 'Why is it stuck?' }).click();
      const bubble = page.locator('.mon-explain');
      await bubble.waitFor();
      for (const text of ['TCarLeftDry', 'TCarLeftNoDry', 'CarLeft = FALSE', 'fires when CarLeft → TRUE']) {
        if (!(await bubble.textContent()).includes(text)) throw new Error(`the explanation lacks "${text}": ${await bubble.textContent()}`);
      }
      await page.screenshot({ path: OUT(t, '3-breakpoint-hit') });
      await bubble.getByRole('button', { name: 'Close' }).click();

      // Back through the buffered states: the counter moves, the earlier active step shows.
      const counter = page.getByTestId('history-counter');
      await page.getByRole('button', { name: 'Previous state' }).click();
      await until(page, 'the counter to show a browsed state', async () => /^\d+ \/ \d+$/.test(await counter.textContent()));
      const [k, n] = (await counter.textContent()).split(' / ').map(Number);
      if (k !== n - 1) throw new Error(`one step back from the latest of ${n} states shows ${k}`);
      await until(page, 'Spraying active in the history', async () => JSON.stringify(await active(page)) === '["Spraying"]');
      if (JSON.stringify(await hit(page)) !== '[]') throw new Error('the hit frame shows on a state before the hit');
      await page.locator('.mon-history-note').waitFor();
      await page.screenshot({ path: OUT(t, '4-history') });
      await page.getByRole('button', { name: 'Next state' }).click();
      await until(page, 'the latest state again', async () => (await counter.textContent()) === `${n} / ${n}`);
      await until(page, 'Brushing hit in the latest state', async () => JSON.stringify(await hit(page)) === '["Brushing"]');

      // Force the car-left sensor, release Start, continue: Brushing → Returning → Idle.
      await page.getByRole('tab', { name: 'Variables' }).click();
      await writeBool(page, 'CarLeft', true, 'Force');
      // Halted, the runtime holds the value from now on; the mark comes with the next scan's state.
      await writeBool(page, 'StartButton', false);
      await page.getByRole('button', { name: 'Continue', exact: true }).click();
      await until(page, 'the running badge again', async () => (await page.getByTestId('monitor-state').textContent()) === 'Running');
      await until(page, 'Idle active again', async () => JSON.stringify(await active(page)) === '["Idle"]');
      await until(page, 'CarLeft forced', async () => (await page.locator('.mon-vars tr[data-var="CarLeft"].forced').count()) === 1);
      if ((await shown(page, 'CarLeft')) !== 'TRUE') throw new Error('the forced CarLeft is not TRUE');
      if (JSON.stringify(await hit(page)) !== '[]') throw new Error('the hit frame stayed after Continue');
      await page.getByRole('tab', { name: 'Time analysis' }).click();
      const row = page.locator('.mon-steps-timing tr', { hasText: 'Brushing' });
      await until(page, 'Brushing timed once', async () => (await row.locator('td').nth(1).textContent()) === '1');
      await page.screenshot({ path: OUT(t, '5-continued') });

      // Stop: the editor is back, with the chart as it was.
      await page.getByRole('button', { name: 'Stop simulation' }).click();
      await until(page, 'the monitor to close', async () => (await page.locator('.mon-overlay').count()) === 0);
      await page.locator('.canvas-pane.active .djs-container').waitFor();
      if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
    },
  },
];

tests.push({
  name: 'the monitor in Czech and German, and attaching to a runtime',
  run: async (t) => {
    const { page } = t;
    const chart = path.join(t.scratch, 'examples', 'carwash', 'carwash.st');
    const s = await t.edit([chart]);
    await page.goto(s.url);
    await page.locator('.canvas-pane.active .djs-container').waitFor();
    await page.getByRole('button', { name: 'Start simulation' }).click();
    await until(page, 'Idle framed green', async () => JSON.stringify(await active(page)) === '["Idle"]');
    for (const [lang, running] of [
      ['cs', 'Běží'],
      ['de', 'Läuft'],
    ]) {
      await page.locator('.status-lang select').selectOption(lang);
      await until(page, `the ${lang} badge`, async () => (await page.getByTestId('monitor-state').textContent()) === running);
      // The toolbar stays one row high at 1440 px.
      const h = await page.locator('.mon-toolbar').evaluate((e) => e.getBoundingClientRect().height);
      if (h > 44) throw new Error(`the ${lang} monitor toolbar wraps (${h} px high)`);
      await page.screenshot({ path: OUT(t, `6-${lang}`) });
    }
    await page.locator('.status-lang select').selectOption('en');
    // The toolbar's tooltip names the runtime's URL without its token.
    const url = await page.evaluate(() => document.querySelector('.mon-title').getAttribute('title'));
    if (!/ws:\/\/127\.0\.0\.1:\d+\/\?token=…/.test(url)) throw new Error(`the monitor's tooltip hides the token: ${url}`);
    await page.getByRole('button', { name: 'Stop simulation' }).click();
    await until(page, 'the monitor to close', async () => (await page.locator('.mon-overlay').count()) === 0);
    // Attach to a runtime by URL (here one that is not there): the dialog checks the URL, the
    // monitor says the connection ended, Detach returns to the editor.
    await page.getByRole('menuitem', { name: 'Monitor' }).or(page.locator('.menubar button', { hasText: 'Monitor' })).first().click();
    await page.getByRole('menuitem', { name: 'Attach to runtime…' }).or(page.getByText('Attach to runtime…')).first().click();
    const input = page.locator('.modal input');
    await input.fill('http://nope');
    if (!(await page.locator('.modal .button.primary').isDisabled())) throw new Error('an http:// URL was accepted');
    await input.fill('ws://127.0.0.1:9/?token=x');
    await page.locator('.modal .button.primary').click();
    await until(page, 'the lost connection', async () => (await page.getByTestId('monitor-state').textContent()) === 'Disconnected');
    await page.locator('.mon-banner').waitFor();
    await page.getByRole('button', { name: 'Detach' }).click();
    await until(page, 'the monitor to close', async () => (await page.locator('.mon-overlay').count()) === 0);
  },
});

tests.push({
  name: 'the monitor shows the profile it simulates with, and why',
  run: async (t) => {
    const { page } = t;
    // A TwinCAT export (crates/sfc-cli/tests/profile): simulated by CODESYS's rules.
    const here = path.dirname(new URL(import.meta.url).pathname);
    const xml = path.join(t.scratch, 'final_scan.twincat.xml');
    fs.copyFileSync(path.join(here, '..', '..', '..', 'crates', 'sfc-cli', 'tests', 'profile', 'final_scan.twincat.xml'), xml);
    const s = await t.edit([xml]);
    await page.goto(s.url);
    await page.locator('.canvas-pane.active .djs-container').waitFor();
    await page.getByRole('button', { name: 'Start simulation' }).click();
    await page.locator('.mon-overlay').waitFor();
    const badge = page.getByTestId('monitor-profile');
    await until(page, 'the profile badge', async () => (await badge.textContent()) === 'Profile: codesys');
    const why = await badge.getAttribute('title');
    if (!why.includes('final_scan.twincat.xml, a TwinCAT export') || !why.includes('--profile iec')) throw new Error(`the badge does not say why: ${why}`);
    for (const [lang, label] of [
      ['cs', 'Profil: codesys'],
      ['de', 'Profil: codesys'],
    ]) {
      await page.locator('.status-lang select').selectOption(lang);
      await until(page, `the ${lang} profile badge`, async () => (await badge.textContent()) === label && (await badge.getAttribute('title')) !== why);
      const h = await page.locator('.mon-toolbar').evaluate((e) => e.getBoundingClientRect().height);
      if (h > 44) throw new Error(`the ${lang} monitor toolbar wraps (${h} px high)`);
    }
    await page.locator('.status-lang select').selectOption('en');
    await page.screenshot({ path: OUT(t, '7-profile') });
    await page.getByRole('button', { name: 'Stop simulation' }).click();
    await until(page, 'the monitor to close', async () => (await page.locator('.mon-overlay').count()) === 0);
    await s.stop();

    // An IEC text file: iec, because it is no export of the CODESYS family.
    const chart = path.join(t.scratch, 'examples', 'carwash', 'carwash.st');
    const s2 = await t.edit([chart]);
    await page.goto(s2.url);
    await page.locator('.canvas-pane.active .djs-container').waitFor();
    await page.getByRole('button', { name: 'Start simulation' }).click();
    await until(page, 'the iec badge', async () => (await page.getByTestId('monitor-profile').textContent()) === 'Profile: iec');
    const title = await page.getByTestId('monitor-profile').getAttribute('title');
    if (!title.includes("IEC 61131-3's rules")) throw new Error(`the iec badge says: ${title}`);
    await page.getByRole('button', { name: 'Stop simulation' }).click();
  },
});

tests.push({
  name: 'the active steps of charts inside charts, on their own charts',
  run: async (t) => {
    // The loading station of crates/sfc-cli/tests/nested: Main runs the lift (LiftFB, an SFC
    // body) and its action ACT_Load (written in SFC), which runs the gripper's ACT_Grip.
    const { page } = t;
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    const here = path.dirname(new URL(import.meta.url).pathname);
    const chart = path.join(t.scratch, 'machine.st');
    fs.copyFileSync(path.join(here, '..', '..', '..', 'crates', 'sfc-cli', 'tests', 'nested', 'machine.st'), chart);
    const s = await t.edit([chart]);
    await page.goto(s.url);
    await page.locator('.canvas-pane.active .djs-container').waitFor();
    await page.locator('.tab', { hasText: 'Main' }).click();
    await page.locator('.tab.active', { hasText: 'Main' }).waitFor();
    await page.getByRole('button', { name: 'Start simulation' }).click();
    await until(page, 'Idle framed green', async () => JSON.stringify(await active(page)) === '["Idle"]');
    await writeBool(page, 'Start', true);
    await until(page, 'Lifting framed green', async () => JSON.stringify(await active(page)) === '["Lifting"]');
    // Every chart at a glance, with its active steps by path.
    await page.getByRole('tab', { name: 'Mechanisms', exact: true }).click();
    const row = (i) => page.locator(`.mon-mechanisms tr[data-instance="${i}"]`);
    await until(page, 'the gripper holding', async () => /Lift\.Grip\.ACT_Grip\.Holding/.test(await row('Lift.Grip.ACT_Grip').textContent()));
    await until(page, 'the lift raising', async () => /Lift\.Raise/.test(await row('Lift').textContent()));
    // The gripper's action chart: the monitor moves to it in the gripper's tab.
    await row('Lift.Grip.ACT_Grip').click();
    await until(page, 'Holding framed green on ACT_Grip', async () => JSON.stringify(await active(page)) === '["Holding"]');
    await page.locator('.mon-title', { hasText: 'GripperFB.ACT_Grip' }).waitFor();
    await page.screenshot({ path: OUT(t, '8-action-chart') });
    // The lift's action chart ACT_Load, and the lift's own chart.
    await page.getByRole('tab', { name: 'Mechanisms', exact: true }).click();
    await row('Lift.ACT_Load').click();
    await until(page, 'Done framed green on ACT_Load', async () => JSON.stringify(await active(page)) === '["Done"]');
    await page.getByRole('tab', { name: 'Mechanisms', exact: true }).click();
    await row('Lift').click();
    await until(page, 'Raise framed green on the lift', async () => JSON.stringify(await active(page)) === '["Raise"]');
    await page.locator('.mon-title', { hasText: 'LiftFB' }).waitFor();
    if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
  },
});
