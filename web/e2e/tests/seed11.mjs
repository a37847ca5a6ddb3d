// Seed 001, chapter 11 ("Příklad vytvoření diagramu"): a new ATMT chart "test bloku atmt" built
// by mouse from an empty chart, validated, built, and its transition table read back.
//
// The seed shows the chart only as a garbled screenshot (fig. 29a) and its table (fig. 29b):
//
//   # | state condition next        OCR of fig. 29(b), rows 0-17; timeouts "# | 1" for 0-9
//   0-5:  0 0 1 / 1 1 2 / 2 2 3 / 3 3 4 / 4 5 3 / 4 4 5     (read cleanly)
//   6-8:  5 12 7 / 5 10 g / 5 11 9
//   9:    5 5 ]      10: 6 10 g   11: 6 9 3   12: 6 13 3   13: 7 9 3
//   14:   7 g a      15: 8 g a    16: 9 ] g   17: 9 ] 2
//
// Our reading: `g` is 8 (then C10 leads to state 8 from both 5 and 6, and C8 is the one
// condition of state 8); row 9's next state is 6 (no other rule enters state 6, which has
// rules of its own); `a` is 0 (a round glyph: states 7 and 8 end the cycle in the initial
// state); the two `]` conditions of state 9 are C6 and C7 (they must differ). Ten states, each
// with the timeout "1" of fig. 28(a)/29(b). The expected one-line table is in
// ../fixtures/seed11.expected:
//
//   18[0 0 1;1 1 2;2 2 3;3 3 4;4 5 3;4 4 5;5 12 7;5 10 8;5 11 9;5 5 6;6 10 8;6 9 3;6 13 3;
//      7 9 3;7 8 0;8 8 0;9 6 8;9 7 2][1 1 1 1 1 1 1 1 1 1]                (one line)
//
// The chart is drawn from that table, as a user of the seed's editor would: the initial step
// Init (state 0) and steps S1…S9, each state's rules as transitions in priority order (a
// selection divergence when there are several), the first rule reaching a state wired to its
// step and every other one ending in a jump. The layout is a tree from Init; blocks are
// dragged from the palette, wired pin to pin by mouse and given their tags, timeouts,
// conditions and jump targets in the Properties panel.
import fs from 'node:fs';
import path from 'node:path';
import { assert, box, doc, drag, dropFromPalette, openEditor, panelShows, setCondition, setField, sfc, shotPath, waitChart, wire } from '../helpers.mjs';

const here = path.dirname(new URL(import.meta.url).pathname);
const EXPECTED = fs.readFileSync(path.join(here, '..', 'fixtures', 'seed11.expected'), 'utf8').trim();

/** `N[s c n;…][t0 t1 …]` → rules and timeouts. */
export function parseTable(line) {
  const m = /^(\d+)\[([^\]]*)\]\[([^\]]*)\]$/.exec(line);
  if (!m) throw new Error(`not a transition table: ${line}`);
  const rules = m[2] === '' ? [] : m[2].split(';').map((r) => r.split(' ').map(Number));
  if (rules.length !== Number(m[1])) throw new Error(`${m[1]} rules announced, ${rules.length} given`);
  return { rules: rules.map(([state, condition, next]) => ({ state, condition, next })), timeouts: m[3].split(' ').map(Number) };
}

/** A branch that ends in a jump is one column this wide (canvas units); step size. */
const LEAF = 100;
const STEP = { w: 80, h: 40 };
/** Equidistant bar pins: the spacing is rounded up to this, so every block lands on the grid. */
const SPACING_STEP = 20;

/**
 * The chart of a table as a tree from state 0: steps with their centre x and top y, the bars,
 * transitions and jumps, and the wires to draw (between plan keys). Siblings sit as close as
 * their subtrees allow; a bar's pins are equidistant, so its spacing is that of its widest pair.
 */
export function planChart(table) {
  const states = table.timeouts.length;
  const rulesOf = (s) => table.rules.map((r, i) => ({ r, i })).filter(({ r }) => r.state === s);
  // A state is the tree child of the first rule (in state order, then priority) reaching it,
  // claimed when its parent is laid out (so siblings keep the table's order).
  const child = new Map(); // rule index → the state it enters by a wire
  const claimed = new Set([0]);
  const order = [0];
  for (let k = 0; k < order.length; k++) {
    for (const { r, i } of rulesOf(order[k])) {
      if (!claimed.has(r.next)) {
        claimed.add(r.next);
        child.set(i, r.next);
        order.push(r.next);
      }
    }
  }
  for (let s = 0; s < states; s++) if (!claimed.has(s)) throw new Error(`state ${s} is not reachable from state 0`);
  // How far a state's subtree reaches left and right of its step's centre, and its bar's
  // pin spacing.
  const extent = new Map();
  const measure = (s) => {
    const branches = rulesOf(s).map(({ i }) => (child.has(i) ? measure(child.get(i)) : { l: LEAF / 2, r: LEAF / 2 }));
    let e;
    if (branches.length === 0) e = { l: LEAF / 2, r: LEAF / 2, spacing: 0 };
    else if (branches.length === 1) e = { ...branches[0], spacing: 0 };
    else {
      let spacing = 0;
      for (let k = 0; k + 1 < branches.length; k++) spacing = Math.max(spacing, branches[k].r + branches[k + 1].l);
      spacing = Math.ceil(spacing / SPACING_STEP) * SPACING_STEP;
      const off = (k) => (k - (branches.length - 1) / 2) * spacing;
      e = {
        l: Math.max(...branches.map((b, k) => b.l - off(k))),
        r: Math.max(...branches.map((b, k) => off(k) + b.r)),
        spacing,
      };
    }
    extent.set(s, e);
    return e;
  };
  const root = measure(0);
  const plan = { steps: [], bars: [], transitions: [], jumps: [], wires: [] };
  const lay = (s, cx, y) => {
    plan.steps.push({ key: `s${s}`, state: s, cx, y });
    const rs = rulesOf(s);
    if (rs.length === 0) return;
    const { spacing } = extent.get(s);
    let ty = y + STEP.h + 30;
    if (rs.length > 1) {
      const w = (rs.length - 1) * spacing + 20;
      plan.bars.push({ key: `d${s}`, pins: rs.length, cx, y: ty, w });
      plan.wires.push({ from: { key: `s${s}`, pin: 0 }, to: { key: `d${s}`, pin: 0 } });
      ty += 30;
    }
    rs.forEach(({ r, i }, k) => {
      const tx = cx + (k - (rs.length - 1) / 2) * spacing;
      plan.transitions.push({ key: `t${i}`, rule: i, condition: `C${r.condition}`, cx: tx, y: ty });
      plan.wires.push({ from: rs.length > 1 ? { key: `d${s}`, pin: k } : { key: `s${s}`, pin: 0 }, to: { key: `t${i}`, pin: 0 } });
      if (child.has(i)) {
        plan.wires.push({ from: { key: `t${i}`, pin: 0 }, to: { key: `s${r.next}`, pin: 0 } });
        lay(r.next, tx, ty + 20 + 30);
      } else {
        plan.jumps.push({ key: `j${i}`, target: r.next, cx: tx, y: ty + 20 + 20 });
        plan.wires.push({ from: { key: `t${i}`, pin: 0 }, to: { key: `j${i}`, pin: 0 } });
      }
    });
  };
  lay(0, Math.ceil(root.l / 10) * 10, 0);
  plan.width = Math.ceil(root.l / 10) * 10 + root.r;
  plan.height = Math.max(...plan.steps.map((s) => s.y + STEP.h), ...plan.jumps.map((j) => j.y + 20));
  return plan;
}

const stepName = (s) => (s === 0 ? 'Init' : `S${s}`);

async function zoomOut(page, times) {
  const button = page.locator('.statusbar button[title="Zoom out"]');
  for (let k = 0; k < times; k++) {
    const before = await page.evaluate(() => window.__sfc.zoom());
    await button.click();
    await page.waitForFunction((z) => window.__sfc.zoom() < z - 1e-6, before);
  }
}

export const tests = [
  {
    name: 'build the seed 001 chapter 11 chart by mouse, validate, build for ATMT and read the table',
    run: async (t) => {
      const { page } = t;
      const table = parseTable(EXPECTED);
      const plan = planChart(table);
      await openEditor(t, ['.']);

      // File → New…: the name and the ATMT target (seed fig. 26).
      await page.locator('.menubar .menu-title').filter({ hasText: 'File' }).click();
      await page.locator('.menu-dropdown .menu-item').filter({ hasText: 'New…' }).first().click();
      await page.locator('#new-name').fill('test_bloku_atmt');
      await page.locator('.target-option').filter({ hasText: 'ATMT' }).first().click();
      await page.locator('.modal .button.primary').click();
      let d = await waitChart(page);
      assert(d.pou === 'test_bloku_atmt' && d.target === 'atmt', `new chart: ${d.pou} ${d.target}`);
      // ATMT has no simultaneous branches: the palette greys them (and refuses them at the drop).
      const and = page.locator('.canvas-pane.active .djs-palette [data-action="create.simultaneous-divergence"]');
      assert((await and.count()) === 0 || (await and.getAttribute('class')).includes('refused'), 'AND divergence offered for ATMT');
      await page.screenshot({ path: shotPath(t, 'new-atmt-chart.png') });

      // Room for the whole chart: the bottom panel closed, the view zoomed out.
      await page.locator('.bottom-panel .panel-tabs .icon-button').click();
      await zoomOut(page, 3);
      const view = await page.evaluate(() => window.__sfc.view());
      // The palette is docked beside the view (it covers none of it).
      const pane = await page.locator('.canvas-pane.active .djs-container').boundingBox();
      const palette = await page.locator('.canvas-pane.active .djs-palette').boundingBox();
      const grid = (v) => Math.ceil(v / 10) * 10;
      const left = grid(view.x + Math.max(0, palette.x + palette.width - pane.x) / view.scale + 40);
      const top = grid(view.y + 40 / view.scale);
      assert(left + plan.width <= view.x + view.width && top + plan.height <= view.y + view.height, `the chart (${plan.width}×${plan.height}) does not fit the view ${JSON.stringify(view)}`);
      const at = (cx, y, h) => ({ x: left + cx, y: top + y + h / 2 });

      // Init, moved by mouse to the top of the tree; the other steps from the palette.
      const ids = {};
      ids.s0 = 'step:Init';
      const init = await box(page, ids.s0);
      const p0 = plan.steps.find((s) => s.state === 0);
      const to = await page.evaluate((p) => window.__sfc.toScreen(p), at(p0.cx, p0.y, STEP.h));
      await drag(page, { x: init.x + init.width / 2, y: init.y + init.height / 2 }, to);
      await page.waitForFunction(([x, y]) => {
        const e = window.__sfc.doc().elements.find((el) => el.id === 'step:Init');
        return e.x === x && e.y === y;
      }, [left + p0.cx - STEP.w / 2, top + p0.y]);
      const props = async (id, fields) => {
        const sel = await page.evaluate(() => window.__sfc.selection());
        if (sel.length !== 1 || sel[0] !== id) {
          const b = await box(page, id);
          await page.mouse.click(b.x + b.width / 2, b.y + b.height / 2);
          await page.waitForFunction((i) => window.__sfc.selection().join() === i, id);
        }
        await panelShows(page, id);
        for (const [sel2, value] of fields) await setField(page, sel2, value);
      };
      for (const s of [...plan.steps].sort((a, b) => a.state - b.state)) {
        if (s.state !== 0) ids[s.key] = await dropFromPalette(page, 'step', at(s.cx, s.y, STEP.h));
        await props(ids[s.key], [
          ['#p-tag', s.state],
          ['#p-timeout', table.timeouts[s.state]],
        ]);
      }
      d = await doc(page);
      for (const s of plan.steps) {
        const e = d.elements.find((x) => x.id === ids[s.key]);
        assert(e.name === stepName(s.state) && e.tag === s.state && e.timeout === 'T#1s', `step ${s.key}: ${JSON.stringify(e)}`);
      }

      // The selection divergences: number of branches, then width and place.
      for (const b of plan.bars) {
        ids[b.key] = await dropFromPalette(page, 'selection-divergence', at(b.cx, b.y, 10));
        await props(ids[b.key], [
          ['#p-pins', b.pins],
          ['#p-size-w', b.w],
          ['#p-pos-x', left + b.cx - b.w / 2],
        ]);
      }
      // The transitions in table order (which is their priority), then the jumps.
      for (const tr of plan.transitions) {
        ids[tr.key] = await dropFromPalette(page, 'transition', at(tr.cx, tr.y, 20));
        await panelShows(page, ids[tr.key]);
        await setCondition(page, ids[tr.key], tr.condition);
      }
      for (const j of plan.jumps) {
        ids[j.key] = await dropFromPalette(page, 'jump', at(j.cx, j.y, 20));
        await panelShows(page, ids[j.key]);
        await page.locator('.side-panel #p-jump').selectOption(stepName(j.target));
        await page.waitForFunction(([i, s]) => window.__sfc.doc().elements.find((e) => e.id === i)?.target === s, [ids[j.key], stepName(j.target)]);
      }

      // Every wire by mouse, output pin to input pin.
      for (const w of plan.wires) {
        const ok = await wire(page, ids[w.from.key], ids[w.to.key], w.from.pin, w.to.pin);
        assert(ok, `wire ${w.from.key}:${w.from.pin} → ${w.to.key}:${w.to.pin} was not drawn`);
      }
      d = await doc(page);
      assert(d.connections.length === plan.wires.length, `${d.connections.length} wires, ${plan.wires.length} drawn`);
      for (const w of plan.wires) {
        const c = d.connections.find((x) => x.source === ids[w.from.key] && x.sourcePin === w.from.pin);
        assert(c && c.target === ids[w.to.key] && c.targetPin === w.to.pin, `wire ${w.from.key} → ${w.to.key}: ${JSON.stringify(c)}`);
      }

      // Validate: "Succeeded" on the canvas (seed fig. 28b).
      await page.locator('select.tool-select').first().selectOption('validate');
      await page.locator('.toolbar .tool-button.primary').click();
      await page.waitForSelector('.outcome');
      const outcome = await page.locator('.outcome').textContent();
      if (outcome !== 'Succeeded') {
        const list = await page.locator('.bottom-panel').innerText();
        throw new Error(`validation: ${outcome}\n${list}`);
      }
      await page.locator('.statusbar button[title="Fit chart"]').click();
      await page.screenshot({ path: shotPath(t, 'seed11-chart.png') });

      // Validate & build for ATMT: the table in the Result panel (seed fig. 29b).
      await page.locator('select.tool-select').first().selectOption('build');
      await page.locator('.toolbar .tool-button.primary').click();
      await page.waitForSelector('.result-panel .one-line code');
      const line = (await page.locator('.result-panel .one-line code').textContent()).trim();
      assert(line === EXPECTED, `built table\n  ${line}\nexpected\n  ${EXPECTED}`);
      const rows = await page.locator('.result-panel table.atmt').first().locator('tbody tr').evaluateAll((trs) =>
        trs.map((tr) => [...tr.querySelectorAll('td')].map((td) => Number(td.textContent))),
      );
      const expectedRows = table.rules.map((r, i) => [i, r.state, r.condition, r.next]);
      assert(JSON.stringify(rows) === JSON.stringify(expectedRows), `table rows ${JSON.stringify(rows)}`);
      const timeouts = await page.locator('.result-panel table.atmt').nth(1).locator('tbody tr').evaluateAll((trs) =>
        trs.map((tr) => [...tr.querySelectorAll('td')].map((td) => Number(td.textContent))),
      );
      assert(JSON.stringify(timeouts) === JSON.stringify(table.timeouts.map((v, i) => [i, v])), `timeouts ${JSON.stringify(timeouts)}`);
      await page.screenshot({ path: shotPath(t, 'seed11-atmt-table.png') });

      // Save (Ctrl+S → Save as…), and the file on disk checks and builds the same table.
      await page.keyboard.press('Control+s');
      const pathInput = page.locator('.modal #save-path');
      await pathInput.fill(path.join(t.scratch, 'test_bloku_atmt.st'));
      await page.locator('.modal .button.primary').click();
      await page.waitForFunction(() => window.__sfc.tabs().every((x) => !x.dirty && x.path));
      const file = path.join(t.scratch, 'test_bloku_atmt.st');
      sfc(t, ['check', '--target', 'atmt', file]);
      const built = sfc(t, ['build', '--target', 'atmt', file]).trim();
      assert(built === EXPECTED, `sfc build of the saved file: ${built}`);
    },
  },
];
