// A stand-in for `sfc edit` to look at the shell without the Rust server: serves web/dist and
// answers the API with canned data built from fixtures/mixer.doc.json.
//   node test/app/mock-server.mjs [PORT]     (MOCK_MODE=host for host mode)
import { readFileSync, existsSync, statSync } from 'node:fs';
import { createServer } from 'node:http';
import { dirname, extname, join, normalize } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const dist = join(here, '..', '..', 'dist');
const doc = JSON.parse(readFileSync(join(here, 'fixtures', 'mixer.doc.json'), 'utf8'));
const port = Number(process.argv[2] ?? 5174);
const host = process.env.MOCK_MODE === 'host';

const session = host
  ? { mode: 'host', version: '0.1.0-mock', roots: ['/demo'], open: [], host: { fb: 'atmt', nstep: 16, ntr: 64, file: '/demo/tank.st', result: '/demo/tank.atmt.txt' } }
  : { mode: 'mdi', version: '0.1.0-mock', roots: ['/demo'], open: ['/demo/mixer.st'] };

const diag = (code, severity, message, title, element, ids, extra = {}) => ({
  code, severity, message, title, line: 12, column: 5, endLine: 12, endColumn: 9, element, elementIds: ids, notes: [], witness: null, ...extra,
});
const diagnostics = [
  diag('SFC0301', 'error', 'undeclared variable `Levl`', 'undeclared variable', 'T2', ['transition:T2']),
  diag('SFC0213', 'warning', 'step `Done` has no way out but the jump', 'step without a way out', 'Done', ['step:Done']),
  diag('SFC0501', 'error', 'unsafe chart: step `A` can be activated while active', 'unsafe chart', 'A', ['step:A'], {
    witness: ['T1', 'T2', 'T3'], witnessIds: ['transition:T1', 'transition:T2', 'transition:T3'],
  }),
  diag('SFC0506', 'note', 'the alternatives after `Init` do not cover every case', 'incomplete alternatives', 'Init', ['step:Init']),
];

const MIME = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css', '.svg': 'image/svg+xml', '.json': 'application/json' };

function send(res, status, value) {
  res.writeHead(status, { 'Content-Type': 'application/json' });
  res.end(JSON.stringify(value));
}

function api(path, body, res) {
  switch (path) {
    case '/api/session':
      return send(res, 200, session);
    case '/api/files':
      return send(res, 200, { files: ['/demo/mixer.st', '/demo/tank.st', '/demo/plant/line1.xml', '/demo/plant/line2.xml'].map((p) => ({ path: p, format: p.endsWith('.xml') ? 'xml' : 'st' })) });
    case '/api/open':
      if (host && body.path === '/demo/tank.st') return send(res, 404, { error: 'no such file: /demo/tank.st' });
      return send(res, 200, { path: body.path, format: body.path.endsWith('.xml') ? 'xml' : 'st', charts: [doc], diagnostics: [], hash: 'mock-1' });
    case '/api/save':
      return send(res, 200, { path: body.path, hash: `mock-${Date.now()}`, diagnostics: [] });
    case '/api/check':
      return send(res, 200, { diagnostics: body.analysis ? diagnostics : diagnostics.slice(0, 2) });
    case '/api/build':
      if (body.target === 'atmt' || body.target === 'eatmt') {
        const rules = [[0, 0, 1], [1, 1, 2], [2, 2, 3], [3, 3, 4], [4, 5, 3], [4, 4, 5], [5, 12, 6], [5, 10, 7], [5, 11, 8]];
        const timeouts = [1, 1, 1, 1, 1, 0, 0, 8.1, 2];
        const output = `${rules.length}[${rules.map((r) => r.join(' ')).join(';')}][${timeouts.join(' ')}]`;
        return send(res, 200, { ok: true, diagnostics: [], output, table: { rules: rules.map(([state, condition, next]) => ({ state, condition, next })), timeouts } });
      }
      return send(res, 200, { ok: true, diagnostics: [], output: `PROGRAM ${body.doc.pou}\n  (* ${body.target} output of the mock server *)\nEND_PROGRAM\n` });
    case '/api/layout':
      return send(res, 200, { doc: body.doc });
    case '/api/new':
      return send(res, 200, { doc: { ...doc, pou: body.name, target: body.target, actions: [], elements: [{ id: 'step:Init', kind: 'step', name: 'Init', initial: true, x: 200, y: 60, w: 80, h: 40 }], connections: [] } });
    case '/api/codes':
      return send(res, 200, []);
    default:
      return send(res, 404, { error: `no API call \`${path}\`` });
  }
}

createServer((req, res) => {
  const url = new URL(req.url ?? '/', `http://${req.headers.host}`);
  if (url.pathname.startsWith('/api/')) {
    let raw = '';
    req.on('data', (c) => (raw += c));
    req.on('end', () => {
      let body = {};
      try {
        body = raw ? JSON.parse(raw) : {};
      } catch {
        return send(res, 400, { error: 'the body is not JSON' });
      }
      api(url.pathname, body, res);
    });
    return;
  }
  const file = normalize(join(dist, url.pathname === '/' ? 'index.html' : url.pathname));
  if (!file.startsWith(dist) || !existsSync(file) || !statSync(file).isFile()) {
    res.writeHead(404);
    return res.end('not found');
  }
  res.writeHead(200, { 'Content-Type': MIME[extname(file)] ?? 'application/octet-stream' });
  res.end(readFileSync(file));
}).listen(port, '127.0.0.1', () => console.log(`mock sfc edit on http://127.0.0.1:${port}/?token=mock`));
