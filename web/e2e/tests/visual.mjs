// Visual regression: every example chart and three charts imported from real files of other
// tools (Beremiz's first_steps and svghmi_traffic_light, matiec's SFC_TEST in PLCopen v1.0),
// opened in the editor and drawn by its SVG export, compared pixel by pixel with the reviewed
// pictures in e2e/visual/ (a difference in at most 0.5 % of the pixels passes: font hinting).
// `UPDATE_VISUAL=1` writes the pictures anew; look at each one before committing it.
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, shotPath, waitChart } from '../helpers.mjs';

const TOLERANCE = 0.005;

const CHARTS = [
  ['blinker', 'examples/blinker/blinker.st'],
  ['carwash', 'examples/carwash/carwash.st'],
  ['spindle', 'examples/spindle/spindle.st'],
  ['traffic', 'examples/traffic/traffic.st'],
  ['beremiz-first-steps', '../shared/corpus/beremiz/first_steps.plc.xml'],
  ['beremiz-traffic-light', '../shared/corpus/beremiz/svghmi_traffic_light.plc.xml'],
  ['matiec-sfc-test', '../shared/corpus/matiec/SFC_TEST.xml'],
];

/** The picture of an SVG, drawn by Chromium at 100 %. */
async function picture(t, svg) {
  const page = await t.context.newPage();
  await page.setContent(`<html><body style="margin:0;background:#fff">${svg.replace(/^<\?xml[^>]*>/, '')}</body></html>`);
  const png = await page.locator('svg').first().screenshot();
  await page.close();
  return png;
}

/** Share of pixels that differ clearly, or 1 when the sizes differ. */
async function difference(t, a, b) {
  const page = await t.context.newPage();
  const share = await page.evaluate(
    async ([x, y]) => {
      const load = (b64) =>
        new Promise((res, rej) => {
          const img = new Image();
          img.onload = () => res(img);
          img.onerror = rej;
          img.src = `data:image/png;base64,${b64}`;
        });
      const [i, j] = await Promise.all([load(x), load(y)]);
      if (i.width !== j.width || i.height !== j.height) return 1;
      const data = (img) => {
        const c = document.createElement('canvas');
        c.width = img.width;
        c.height = img.height;
        const g = c.getContext('2d');
        g.drawImage(img, 0, 0);
        return g.getImageData(0, 0, img.width, img.height).data;
      };
      const p = data(i);
      const q = data(j);
      let diff = 0;
      for (let k = 0; k < p.length; k += 4) {
        if (Math.max(Math.abs(p[k] - q[k]), Math.abs(p[k + 1] - q[k + 1]), Math.abs(p[k + 2] - q[k + 2])) > 64) diff++;
      }
      return diff / (p.length / 4);
    },
    [a.toString('base64'), b.toString('base64')],
  );
  await page.close();
  return share;
}

export const tests = CHARTS.map(([name, file]) => ({
  name: `${name}: the chart as drawn matches its reviewed picture`,
  run: async (t) => {
    const source = path.resolve(t.root, file);
    if (!fs.existsSync(source)) {
      t.log(`${file} is not there; skipped`);
      return;
    }
    const local = path.join(t.scratch, path.basename(file));
    fs.copyFileSync(source, local);
    await openEditor(t, [local]);
    await waitChart(t.page);
    const svg = await t.page.evaluate(() => window.__sfc.exportSvg());
    const png = await picture(t, svg);
    fs.writeFileSync(shotPath(t, `visual-${name}.png`), png);
    const reference = path.join(t.root, 'web', 'e2e', 'visual', `${name}.png`);
    if (process.env.UPDATE_VISUAL || !fs.existsSync(reference)) {
      fs.writeFileSync(reference, png);
      t.log(`wrote ${path.relative(t.root, reference)}: review it`);
      return;
    }
    const share = await difference(t, png, fs.readFileSync(reference));
    t.log(`${(share * 100).toFixed(3)} % of the pixels differ from the reviewed picture`);
    assert(share <= TOLERANCE, `${name}: ${(share * 100).toFixed(2)} % of the pixels differ (see e2e/out/visual-${name}.png)`);
  },
}));
