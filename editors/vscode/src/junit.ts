// Reading the JUnit XML that `sfc test --junit` writes, for the Testing view. Pure functions
// (no vscode API), so the unit tests run in plain Node.

/** One scenario's result. */
export interface CaseResult {
  /** The scenario file as `sfc test` was given it. */
  name: string;
  /** Seconds. */
  time: number;
  outcome: 'passed' | 'failed' | 'errored' | 'skipped';
  /** The failure's message attribute. */
  message?: string;
  /** The failure's text: one line per failed expectation (`file:line: …`). */
  details?: string;
}

function unescape(s: string): string {
  return s
    .replace(/&lt;/g, '<')
    .replace(/&gt;/g, '>')
    .replace(/&quot;/g, '"')
    .replace(/&apos;/g, "'")
    .replace(/&#(\d+);/g, (_, d) => String.fromCodePoint(Number(d)))
    .replace(/&#x([0-9a-fA-F]+);/g, (_, h) => String.fromCodePoint(parseInt(h, 16)))
    .replace(/&amp;/g, '&');
}

function attr(tag: string, name: string): string | undefined {
  const m = new RegExp(`\\s${name}="([^"]*)"`).exec(tag);
  return m ? unescape(m[1]) : undefined;
}

/** Every `<testcase>` of a JUnit report. */
export function parseJunit(xml: string): CaseResult[] {
  const out: CaseResult[] = [];
  const re = /<testcase\b([^>]*?)(\/>|>([\s\S]*?)<\/testcase>)/g;
  let m: RegExpExecArray | null;
  while ((m = re.exec(xml)) !== null) {
    const head = m[1];
    const body = m[3] ?? '';
    const result: CaseResult = {
      name: attr(head, 'name') ?? '',
      time: Number(attr(head, 'time') ?? '0') || 0,
      outcome: 'passed',
    };
    const problem = /<(failure|error)\b([^>]*?)(?:\/>|>([\s\S]*?)<\/\1>)/.exec(body);
    if (problem) {
      result.outcome = problem[1] === 'failure' ? 'failed' : 'errored';
      result.message = attr(problem[2], 'message');
      result.details = unescape(problem[3] ?? '');
    } else if (/<skipped\b/.test(body)) {
      result.outcome = 'skipped';
    }
    out.push(result);
  }
  return out;
}

/** A located message: `path:line: text` lines of a failure. */
export interface Located {
  file: string;
  /** 1-based. */
  line: number;
  message: string;
}

/** The `file:line: message` lines of a failure's text. */
export function locatedLines(details: string): Located[] {
  const out: Located[] = [];
  for (const line of details.split(/\r?\n/)) {
    const m = /^(.+?):(\d+): (.*)$/.exec(line.trim());
    if (m) {
      out.push({ file: m[1], line: Number(m[2]), message: m[3] });
    }
  }
  return out;
}

/** The editor's address in what `sfc edit` prints (`SFC Editor: http://127.0.0.1:…`). */
export function editorUrl(output: string): string | undefined {
  const m = /SFC Editor: (https?:\/\/\S+)/.exec(output);
  return m ? m[1] : undefined;
}

/** The POU names `sfc build` lists when a file has several SFC POUs. */
export function pouChoices(stderr: string): string[] {
  const m = /choose one with --pou \(([^)]*)\)/.exec(stderr);
  return m ? m[1].split(',').map((s) => s.trim()).filter((s) => s.length > 0) : [];
}
