// End-to-end tests of the SFC Editor: the real `sfc edit` server, the built web app, headless
// Debian Chromium driven by playwright-core. Tests live in e2e/tests/*.mjs and export
// `tests = [{ name, run: async (t) => … }]`; `t` gives a fresh page, a scratch directory with
// copies of examples/, and `t.edit(args)` to start `sfc edit` on it, with the editor's settings
// kept in a scratch config directory of the test (`SFC_CONFIG_DIR` = `t.config`, shared by the
// test's servers; never the real home; `t.edit(args, cwd, { env })` adds variables). The (debug) binary serves
// the test build of the app, web/dist-test, the one with the test hook `window.__sfc`
// (`t.edit(args, cwd, { production: true })` serves web/dist, the build users get). A failing test leaves a
// screenshot in e2e/out/. The last line is cargo's `test result:` format (counted by .ci/run).
//
//   node e2e/run.mjs [FILTER…]      (SFC_BIN: the sfc binary, default ../target/debug/sfc)
import { chromium } from 'playwright-core';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '..', '..');
const sfcBin = process.env.SFC_BIN ?? path.join(root, 'target', 'debug', 'sfc');
const outDir = path.join(here, 'out');
const filters = process.argv.slice(2);

/** Starts `sfc edit ARGS` and resolves once it printed its URL. */
function edit(args, cwd, { production = false, bin = sfcBin, env = {} } = {}) {
  return new Promise((resolve, reject) => {
    const dist = production ? '' : (process.env.SFC_WEB_DIST ?? path.join(root, 'web', 'dist-test'));
    const proc = spawn(bin, ['edit', '--no-open', '--port', '0', ...args], {
      cwd,
      stdio: ['ignore', 'pipe', 'pipe'],
      env: { ...process.env, DISPLAY: '', WAYLAND_DISPLAY: '', SFC_WEB_DIST: dist, ...env },
    });
    let out = '';
    let err = '';
    const timer = setTimeout(() => {
      proc.kill('SIGKILL');
      reject(new Error(`sfc edit printed no URL within 20 s\nstdout: ${out}\nstderr: ${err}`));
    }, 20_000);
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/(http:\/\/127\.0\.0\.1:\d+)\/\?token=([0-9a-f]+)/);
      if (m) {
        clearTimeout(timer);
        resolve({
          url: m[0],
          base: m[1],
          token: m[2],
          proc,
          stderr: () => err,
          stop: () =>
            new Promise((r) => {
              // Stopped already (a test may stop its server itself): a process ended by a
              // signal has a signalCode and no exitCode, and its 'exit' event is gone.
              if (proc.exitCode !== null || proc.signalCode !== null) return r();
              proc.once('exit', () => r());
              proc.kill('SIGTERM');
              setTimeout(() => proc.kill('SIGKILL'), 3000);
            }),
        });
      }
    });
    proc.stderr.on('data', (d) => (err += d));
    proc.once('exit', (code) => {
      clearTimeout(timer);
      reject(new Error(`sfc edit exited with ${code}\nstdout: ${out}\nstderr: ${err}`));
    });
  });
}

function copyDir(from, to) {
  fs.mkdirSync(to, { recursive: true });
  for (const e of fs.readdirSync(from, { withFileTypes: true })) {
    const a = path.join(from, e.name);
    const b = path.join(to, e.name);
    if (e.isDirectory()) copyDir(a, b);
    else fs.copyFileSync(a, b);
  }
}

async function loadTests() {
  const dir = path.join(here, 'tests');
  const files = fs.existsSync(dir) ? fs.readdirSync(dir).filter((f) => f.endsWith('.mjs')).sort() : [];
  const all = [];
  for (const f of files) {
    const mod = await import(pathToFileURL(path.join(dir, f)).href);
    for (const t of mod.tests ?? []) all.push({ ...t, file: f.replace(/\.mjs$/, '') });
  }
  return all.filter((t) => filters.length === 0 || filters.some((f) => `${t.file}::${t.name}`.includes(f)));
}

async function main() {
  if (!fs.existsSync(sfcBin)) throw new Error(`no sfc binary at ${sfcBin} (cargo build first)`);
  const tests = await loadTests();
  fs.mkdirSync(outDir, { recursive: true });
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    headless: true,
    args: [
      '--no-sandbox',
      '--disable-gpu',
      '--disable-quic',
      '--no-first-run',
      '--disable-background-networking',
      '--disable-component-update',
      '--disable-sync',
    ],
  });
  let passed = 0;
  let failed = 0;
  for (const test of tests) {
    const id = `${test.file}::${test.name}`;
    const scratch = fs.mkdtempSync(path.join(os.tmpdir(), 'sfc-e2e-'));
    copyDir(path.join(root, 'examples'), path.join(scratch, 'examples'));
    const config = fs.mkdtempSync(path.join(os.tmpdir(), 'sfc-e2e-config-'));
    const context = await browser.newContext({ viewport: { width: 1440, height: 900 }, acceptDownloads: true });
    const page = await context.newPage();
    const consoleLines = [];
    page.on('console', (m) => consoleLines.push(`[${m.type()}] ${m.text()}`));
    page.on('pageerror', (e) => consoleLines.push(`[pageerror] ${e.stack ?? e.message}`));
    const servers = [];
    const t = {
      page,
      context,
      browser,
      scratch,
      config,
      root,
      sfcBin,
      log: (...a) => console.log(`    ${id}:`, ...a),
      edit: async (args = [], cwd = scratch, opts = {}) => {
        const s = await edit(args, cwd, { ...opts, env: { SFC_CONFIG_DIR: config, ...opts.env } });
        servers.push(s);
        return s;
      },
    };
    const started = Date.now();
    try {
      await Promise.race([
        test.run(t),
        new Promise((_, rej) => setTimeout(() => rej(new Error('timed out after 120 s')), 120_000)),
      ]);
      passed++;
      console.log(`test ${id} ... ok (${((Date.now() - started) / 1000).toFixed(1)} s)`);
    } catch (e) {
      failed++;
      const shot = path.join(outDir, `${id.replace(/[^\w.-]+/g, '_')}.png`);
      await page.screenshot({ path: shot, fullPage: true }).catch(() => {});
      console.log(`test ${id} ... FAILED`);
      console.log(`    ${String(e?.stack ?? e).split('\n').join('\n    ')}`);
      console.log(`    screenshot: ${shot}`);
      for (const l of consoleLines.slice(-20)) console.log(`    console: ${l}`);
      for (const s of servers) if (s.stderr()) console.log(`    server stderr: ${s.stderr().slice(-2000)}`);
    } finally {
      await context.close().catch(() => {});
      for (const s of servers) await s.stop();
      fs.rmSync(scratch, { recursive: true, force: true });
      fs.rmSync(config, { recursive: true, force: true });
    }
  }
  await browser.close();
  console.log(
    `test result: ${failed === 0 ? 'ok' : 'FAILED'}. ${passed} passed; ${failed} failed; 0 ignored; 0 measured; 0 filtered out (e2e)`,
  );
  process.exit(failed === 0 ? 0 : 1);
}

main().catch((e) => {
  console.error(e);
  console.log('test result: FAILED. 0 passed; 1 failed; 0 ignored; 0 measured; 0 filtered out (e2e)');
  process.exit(1);
});
