// Unit tests of the extension's pure parts, on real output of the `sfc` binary (SFC_BIN).

import { test } from 'node:test';
import * as assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { editorUrl, locatedLines, parseJunit, pouChoices } from '../src/junit';

const root = path.resolve(__dirname, '../../../..');
const sfc = process.env.SFC_BIN ?? path.join(root, 'target/debug/sfc');

test('reads the JUnit report of `sfc test`: a passing and a failing scenario', () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sfc-vscode-'));
  for (const f of ['blinker.st', 'blinker.scenario.toml']) {
    fs.copyFileSync(path.join(root, 'examples/blinker', f), path.join(dir, f));
  }
  const scenario = fs.readFileSync(path.join(dir, 'blinker.scenario.toml'), 'utf8');
  fs.writeFileSync(path.join(dir, 'wrong.scenario.toml'), scenario.replace('active = ["S2"]', 'active = ["S1"]'));
  const report = path.join(dir, 'junit.xml');
  const r = spawnSync(sfc, ['test', '--junit', report, dir], { encoding: 'utf8' });
  assert.equal(r.status, 1, r.stderr);
  const cases = parseJunit(fs.readFileSync(report, 'utf8'));
  assert.equal(cases.length, 2);
  const ok = cases.find((c) => c.name.endsWith('blinker.scenario.toml'))!;
  const bad = cases.find((c) => c.name.endsWith('wrong.scenario.toml'))!;
  assert.equal(ok.outcome, 'passed');
  assert.equal(bad.outcome, 'failed');
  const lines = locatedLines(bad.details ?? '');
  assert.ok(lines.length >= 1, bad.details);
  assert.equal(path.basename(lines[0].file), 'wrong.scenario.toml');
  assert.match(lines[0].message, /`active`: expected \["S1"\], actual \["S2"\]/);
  assert.ok(lines[0].line > 1);
  fs.rmSync(dir, { recursive: true, force: true });
});

test('skipped and errored cases, entities', () => {
  const xml = `<testsuites><testsuite>
    <testcase name="a &amp; b.scenario.toml" time="0.5"><skipped/></testcase>
    <testcase name="c.scenario.toml" time="x"><error message="cannot read &quot;c&quot;" type="io">c.scenario.toml:3: bad &lt;key&gt;</error></testcase>
  </testsuite></testsuites>`;
  const [a, c] = parseJunit(xml);
  assert.deepEqual([a.name, a.outcome, a.time], ['a & b.scenario.toml', 'skipped', 0.5]);
  assert.deepEqual([c.outcome, c.message, c.time], ['errored', 'cannot read "c"', 0]);
  assert.deepEqual(locatedLines(c.details!), [{ file: 'c.scenario.toml', line: 3, message: 'bad <key>' }]);
});

test('the address `sfc edit` prints and the POUs `sfc build` offers', () => {
  assert.equal(editorUrl('SFC Editor: http://127.0.0.1:40123/?token=abc\n'), 'http://127.0.0.1:40123/?token=abc');
  assert.equal(editorUrl('starting'), undefined);
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sfc-vscode-'));
  const two = path.join(dir, 'two.st');
  const chart = (n: string) => `PROGRAM ${n}\n  INITIAL_STEP S1: END_STEP\n  TRANSITION FROM S1 TO S1 := TRUE; END_TRANSITION\nEND_PROGRAM\n`;
  fs.writeFileSync(two, chart('Filler') + chart('Capper'));
  const r = spawnSync(sfc, ['build', two, '--target', 'svg'], { encoding: 'utf8' });
  assert.notEqual(r.status, 0);
  assert.deepEqual(pouChoices(r.stderr), ['Filler', 'Capper']);
  const svg = execFileSync(sfc, ['build', two, '--target', 'svg', '--pou', 'Capper'], { encoding: 'utf8' });
  assert.match(svg, /<svg/);
  fs.rmSync(dir, { recursive: true, force: true });
});
