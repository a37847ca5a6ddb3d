// Requirements in the editor: the car wash with a property file beside it, Edit → Prove
// requirements, the violated property in the Error List, and Replay starting monitor mode on
// the witness (the simulator halted, the witness's inputs set scan by scan).
import fs from 'node:fs';
import path from 'node:path';
import { until as untilWithin } from '../helpers.mjs';

const until = (page, what, check, ms = 20_000) => untilWithin(page, what, check, ms);

const OUT = (name) => path.join(path.dirname(new URL(import.meta.url).pathname), '..', 'out', `prove-${name}.png`);

const PROPS = `[[property]]
name = "never forward and back"
never = "Travel AND TravelBack"

[[property]]
name = "no travel without a car"
never = "Travel AND NOT CarPresent"
`;

export const tests = [
  {
    name: 'prove requirements, list the violation, replay its witness',
    run: async (t) => {
      const { page } = t;
      const errors = [];
      page.on('pageerror', (e) => errors.push(e.message));
      const dir = path.join(t.scratch, 'examples', 'carwash');
      fs.writeFileSync(path.join(dir, 'carwash.props.toml'), PROPS);
      const s = await t.edit([path.join(dir, 'carwash.st')]);
      await page.goto(s.url);
      await page.locator('.canvas-pane.active .djs-container').waitFor();
      await page.locator('.tab.active', { hasText: 'CarWash' }).waitFor();

      await page.locator('.menubar .menu-title').filter({ hasText: 'Edit' }).click();
      await page.locator('.menu-dropdown .menu-item').filter({ hasText: 'Prove requirements' }).first().click();
      await page.locator('.toast', { hasText: '1 held, 1 violated, 0 not decided' }).waitFor({ timeout: 30_000 });
      const row = page.locator('tr', { hasText: 'no travel without a car' });
      await row.waitFor();
      const text = await row.textContent();
      if (!text.includes('SFC1002')) throw new Error(`the row names no SFC1002: ${text}`);
      if (await page.locator('tr', { hasText: 'never forward and back' }).count()) {
        throw new Error('a property that holds is listed as a problem');
      }
      await page.screenshot({ path: OUT('1-error-list') });

      // Replay: monitor mode, halted, after the witness's three scans (scan 0 to 2).
      await row.getByRole('button', { name: 'Replay' }).click();
      await page.locator('.mon-overlay').waitFor();
      await page.locator('.toast', { hasText: 'Witness replayed: 3 scans' }).waitFor({ timeout: 20_000 });
      await until(page, 'the monitor at scan 2', async () => /\b2\b/.test((await page.getByTestId('monitor-scan').textContent()) ?? ''));
      const state = await page.getByTestId('monitor-state').textContent();
      if (!/Halted/.test(state)) throw new Error(`the replayed run is not halted: ${state}`);
      // The witness's situation: travelling without a car.
      await page.getByRole('tab', { name: 'Variables' }).click();
      const shown = (name) => page.locator(`.mon-vars tr[data-var="${name}"] .mon-val`).textContent();
      await until(page, 'Travel TRUE', async () => (await shown('Travel')) === 'TRUE');
      await until(page, 'CarPresent FALSE', async () => (await shown('CarPresent')) === 'FALSE');
      await page.screenshot({ path: OUT('2-replayed') });
      if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
      await s.stop();
    },
  },
];
