// The editor opens only what it was given, and the token leaves no trace the page or another
// site could read: the printed URL is exchanged for an HttpOnly, SameSite=Strict cookie and
// the address bar drops it; the build users get has no test hook.
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, waitChart } from '../helpers.mjs';

export const tests = [
  {
    name: 'the token becomes an HttpOnly SameSite=Strict cookie and leaves the address; a named file is served alone',
    run: async (t) => {
      const { page } = t;
      fs.writeFileSync(path.join(t.scratch, 'neighbour.st'), 'PROGRAM Neighbour\nEND_PROGRAM\n');
      const server = await openEditor(t, ['examples/blinker/blinker.st']);
      await waitChart(page);
      assert(!page.url().includes('token'), `the address drops the token: ${page.url()}`);
      assert((await page.evaluate(() => history.length)) >= 1, 'history');
      assert((await page.evaluate(() => document.cookie)) === '', 'scripts cannot read the cookie');
      const cookies = await t.context.cookies();
      const c = cookies.find((x) => x.name.startsWith('sfc_token_'));
      assert(c && c.httpOnly && c.sameSite === 'Strict' && c.value === server.token, JSON.stringify(cookies));
      // From the page: only the named file is listed and opened; its neighbours are refused.
      const answer = await page.evaluate(async (dir) => {
        const call = (p, body) =>
          fetch(p, { method: body ? 'POST' : 'GET', headers: { 'X-Sfc-Page': '1', 'Content-Type': 'application/json' }, body: body && JSON.stringify(body) });
        const files = await (await call('/api/files')).json();
        const neighbour = (await call('/api/open', { path: `${dir}/neighbour.st` })).status;
        const other = (await call('/api/open', { path: `${dir}/examples/carwash/carwash.st` })).status;
        const save = (await call('/api/save', { path: `${dir}/new.st`, format: 'st', doc: { pou: 'N', pouKind: 'program', target: 'blank', elements: [], connections: [] }, hash: null })).status;
        const noHeader = (await fetch('/api/session')).status;
        return { files: files.files.map((f) => f.path), neighbour, other, save, noHeader };
      }, t.scratch);
      assert(answer.files.length === 1 && answer.files[0].endsWith('examples/blinker/blinker.st'), JSON.stringify(answer.files));
      assert(answer.neighbour === 403 && answer.other === 403 && answer.save === 403, JSON.stringify(answer));
      assert(answer.noHeader === 403, 'the cookie alone is not enough');
      assert(!fs.existsSync(path.join(t.scratch, 'new.st')), 'nothing written');
    },
  },
  {
    name: 'the build users get has no window.__sfc',
    run: async (t) => {
      const { page } = t;
      const server = await t.edit(['examples/blinker/blinker.st'], t.scratch, { production: true });
      await page.goto(server.url);
      await page.locator('.canvas-pane.active .djs-container').waitFor();
      assert((await page.evaluate(() => typeof window.__sfc)) === 'undefined', 'no test hook in production');
    },
  },
];
