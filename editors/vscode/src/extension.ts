// The SFC extension: starts `sfc lsp` (diagnostics, formatting, navigation, completion, …),
// opens explanations of diagnostic codes, and adds the commands "Open in SFC Editor",
// "Preview chart" and "Run scenarios" (results in the Testing view).

import * as vscode from 'vscode';
import { ChildProcess, execFile, spawn } from 'child_process';
import * as fs from 'fs';
import * as os from 'os';
import * as path from 'path';
import { LanguageClient, LanguageClientOptions, ServerOptions } from 'vscode-languageclient/node';
import { editorUrl, locatedLines, parseJunit, pouChoices } from './junit';

let client: LanguageClient | undefined;
const editors: ChildProcess[] = [];

function sfcPath(): string {
  return vscode.workspace.getConfiguration('sfc').get<string>('path') || 'sfc';
}

function run(args: string[], cwd?: string): Promise<{ code: number; stdout: string; stderr: string }> {
  return new Promise((resolve) => {
    execFile(sfcPath(), args, { cwd, maxBuffer: 64 << 20 }, (err, stdout, stderr) => {
      const code = err && typeof (err as NodeJS.ErrnoException).code === 'number' ? Number((err as NodeJS.ErrnoException).code) : err ? 2 : 0;
      if (err && (err as NodeJS.ErrnoException).code === 'ENOENT') {
        resolve({ code: 2, stdout: '', stderr: `cannot start \`${sfcPath()}\`: set "sfc.path" to the sfc program` });
        return;
      }
      resolve({ code, stdout: String(stdout), stderr: String(stderr) });
    });
  });
}

async function startClient(ctx: vscode.ExtensionContext): Promise<void> {
  const server: ServerOptions = { command: sfcPath(), args: ['lsp'] };
  const idle = vscode.workspace.getConfiguration('sfc').get<number>('analysis.idleMs') ?? 1500;
  const options: LanguageClientOptions = {
    documentSelector: [
      { scheme: 'file', language: 'sfc' },
      { scheme: 'untitled', language: 'sfc' },
      { scheme: 'file', pattern: '**/*.xml' },
    ],
    initializationOptions: { analysisIdleMs: idle },
    synchronize: { fileEvents: vscode.workspace.createFileSystemWatcher('**/*.st') },
  };
  client = new LanguageClient('sfc', 'SFC language server', server, options);
  ctx.subscriptions.push(client);
  await client.start();
}

function activeChart(uri?: vscode.Uri): vscode.Uri | undefined {
  const u = uri ?? vscode.window.activeTextEditor?.document.uri;
  if (!u || u.scheme !== 'file') {
    void vscode.window.showErrorMessage('SFC: open a chart file (.st or .xml) first');
    return undefined;
  }
  return u;
}

/** "Open in SFC Editor": `sfc edit FILE`, then the browser at the address it prints. */
async function openInEditor(uri?: vscode.Uri): Promise<void> {
  const file = activeChart(uri);
  if (!file) {
    return;
  }
  const dir = vscode.workspace.getWorkspaceFolder(file)?.uri.fsPath ?? path.dirname(file.fsPath);
  const child = spawn(sfcPath(), ['edit', '--no-open', file.fsPath], { cwd: dir });
  editors.push(child);
  let seen = '';
  child.stdout.on('data', async (chunk: Buffer) => {
    seen += chunk.toString();
    const url = editorUrl(seen);
    if (url) {
      seen = '';
      await vscode.env.openExternal(vscode.Uri.parse(url));
    }
  });
  let errors = '';
  child.stderr.on('data', (chunk: Buffer) => (errors += chunk.toString()));
  child.on('error', (e) => void vscode.window.showErrorMessage(`SFC: cannot start \`${sfcPath()} edit\`: ${e.message}`));
  child.on('exit', (code) => {
    if (code) {
      void vscode.window.showErrorMessage(`SFC Editor ended (${code}): ${errors.trim()}`);
    }
  });
}

/** "Preview chart": the SVG of `sfc build --target svg`, refreshed on save. */
class Preview {
  private static panels = new Map<string, Preview>();
  private pou: string | undefined;

  static show(ctx: vscode.ExtensionContext, uri?: vscode.Uri): void {
    const file = activeChart(uri);
    if (!file) {
      return;
    }
    const existing = Preview.panels.get(file.toString());
    if (existing) {
      existing.panel.reveal(vscode.ViewColumn.Beside);
      void existing.refresh();
      return;
    }
    const panel = vscode.window.createWebviewPanel('sfc.preview', `Chart: ${path.basename(file.fsPath)}`, vscode.ViewColumn.Beside, {
      enableScripts: false,
    });
    const p = new Preview(file, panel);
    Preview.panels.set(file.toString(), p);
    const saved = vscode.workspace.onDidSaveTextDocument((d) => {
      if (d.uri.toString() === file.toString()) {
        void p.refresh();
      }
    });
    panel.onDidDispose(() => {
      saved.dispose();
      Preview.panels.delete(file.toString());
    });
    ctx.subscriptions.push(saved);
    void p.refresh();
  }

  private constructor(private file: vscode.Uri, private panel: vscode.WebviewPanel) {}

  async refresh(): Promise<void> {
    const args = ['build', this.file.fsPath, '--target', 'svg', ...(this.pou ? ['--pou', this.pou] : [])];
    let r = await run(args, path.dirname(this.file.fsPath));
    const choices = pouChoices(r.stderr);
    if (r.code !== 0 && choices.length > 0) {
      this.pou = await vscode.window.showQuickPick(choices, { placeHolder: 'The file has several charts: which one?' });
      if (this.pou) {
        r = await run([...args, '--pou', this.pou], path.dirname(this.file.fsPath));
      }
    }
    const csp = `<meta http-equiv="Content-Security-Policy" content="default-src 'none'; img-src data:; style-src 'unsafe-inline';">`;
    const body =
      r.code === 0
        ? `<div class="chart">${r.stdout.replace(/^<\?xml[^>]*>/, '')}</div>`
        : `<h3>The chart cannot be drawn</h3><pre>${escapeHtml(r.stderr || r.stdout)}</pre>`;
    this.panel.webview.html = `<!DOCTYPE html><html><head>${csp}<style>
      body { background: #fff; color: #222; } .chart svg { max-width: 100%; height: auto; }
      pre { white-space: pre-wrap; }</style></head><body>${body}</body></html>`;
  }
}

function escapeHtml(s: string): string {
  return s.replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;');
}

/** The scenarios of the workspace in the Testing view; a run is `sfc test … --junit`. */
function scenarios(ctx: vscode.ExtensionContext): (request?: vscode.TestRunRequest) => Promise<void> {
  const ctrl = vscode.tests.createTestController('sfcScenarios', 'SFC scenarios');
  ctx.subscriptions.push(ctrl);
  const add = (uri: vscode.Uri) => {
    const item = ctrl.createTestItem(uri.toString(), path.basename(uri.fsPath), uri);
    ctrl.items.add(item);
  };
  const discover = async () => {
    for (const uri of await vscode.workspace.findFiles('**/*.scenario.toml', '**/node_modules/**')) {
      add(uri);
    }
  };
  ctrl.resolveHandler = async (item) => {
    if (!item) {
      await discover();
    }
  };
  const watcher = vscode.workspace.createFileSystemWatcher('**/*.scenario.toml');
  watcher.onDidCreate(add);
  watcher.onDidDelete((u) => ctrl.items.delete(u.toString()));
  ctx.subscriptions.push(watcher);

  const runHandler = async (request: vscode.TestRunRequest, token?: vscode.CancellationToken) => {
    if (ctrl.items.size === 0) {
      await discover();
    }
    const items: vscode.TestItem[] = [];
    if (request.include) {
      items.push(...request.include);
    } else {
      ctrl.items.forEach((i) => items.push(i));
    }
    const excluded = new Set((request.exclude ?? []).map((i) => i.id));
    const chosen = items.filter((i) => !excluded.has(i.id) && i.uri);
    const testRun = ctrl.createTestRun(request);
    if (chosen.length === 0) {
      testRun.appendOutput('No scenario files (*.scenario.toml) in the workspace.\r\n');
      testRun.end();
      return;
    }
    chosen.forEach((i) => testRun.started(i));
    const report = path.join(fs.mkdtempSync(path.join(os.tmpdir(), 'sfc-test-')), 'junit.xml');
    const cwd = vscode.workspace.workspaceFolders?.[0]?.uri.fsPath;
    const r = await run(['test', '--color', 'never', '--junit', report, ...chosen.map((i) => i.uri!.fsPath)], cwd);
    if (token?.isCancellationRequested) {
      testRun.end();
      return;
    }
    testRun.appendOutput((r.stdout + r.stderr).replace(/\r?\n/g, '\r\n'));
    let results: ReturnType<typeof parseJunit> = [];
    try {
      results = parseJunit(fs.readFileSync(report, 'utf8'));
    } catch {
      // No report: `sfc test` failed before running (the output says why).
    }
    for (const item of chosen) {
      const res = results.find((c) => path.resolve(cwd ?? '', c.name) === item.uri!.fsPath);
      if (!res) {
        testRun.errored(item, new vscode.TestMessage(`no result from \`sfc test\`:\n${r.stderr || r.stdout}`));
        continue;
      }
      const ms = res.time * 1000;
      if (res.outcome === 'passed') {
        testRun.passed(item, ms);
      } else if (res.outcome === 'skipped') {
        testRun.skipped(item);
      } else {
        const located = locatedLines(res.details ?? '');
        const messages = located.length
          ? located.map((l) => {
              const m = new vscode.TestMessage(l.message);
              m.location = new vscode.Location(vscode.Uri.file(path.resolve(cwd ?? '', l.file)), new vscode.Position(l.line - 1, 0));
              return m;
            })
          : [new vscode.TestMessage(res.details || res.message || 'failed')];
        if (res.outcome === 'failed') {
          testRun.failed(item, messages, ms);
        } else {
          testRun.errored(item, messages, ms);
        }
      }
    }
    testRun.end();
    fs.rmSync(path.dirname(report), { recursive: true, force: true });
  };
  ctrl.createRunProfile('Run', vscode.TestRunProfileKind.Run, runHandler, true);
  return (request) => runHandler(request ?? new vscode.TestRunRequest());
}

export async function activate(ctx: vscode.ExtensionContext): Promise<void> {
  ctx.subscriptions.push(
    vscode.workspace.registerTextDocumentContentProvider('sfc-explain', {
      async provideTextDocumentContent(uri: vscode.Uri): Promise<string> {
        const code = uri.path;
        if (client) {
          try {
            return await client.sendRequest<string>('sfc/explain', { code });
          } catch {
            // Fall back to the command line.
          }
        }
        const r = await run(['check', '--explain', code]);
        return r.stdout || r.stderr;
      },
    }),
  );
  const runScenarios = scenarios(ctx);
  ctx.subscriptions.push(
    vscode.commands.registerCommand('sfc.openInEditor', (uri?: vscode.Uri) => openInEditor(uri)),
    vscode.commands.registerCommand('sfc.previewChart', (uri?: vscode.Uri) => Preview.show(ctx, uri)),
    vscode.commands.registerCommand('sfc.runScenarios', () => runScenarios()),
    vscode.commands.registerCommand('sfc.restartServer', async () => {
      await client?.stop();
      client = undefined;
      await startClient(ctx);
    }),
  );
  try {
    await startClient(ctx);
  } catch (e) {
    void vscode.window.showErrorMessage(`SFC: cannot start \`${sfcPath()} lsp\` (${e}); set "sfc.path" to the sfc program`);
  }
}

export async function deactivate(): Promise<void> {
  for (const e of editors) {
    e.kill();
  }
  await client?.stop();
}
