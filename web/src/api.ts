// Types of the editor's HTTP API (served by `crates/sfc-server`; contract in docs/editor.md).
import type { ChartTarget, EditorDoc } from './doc';

export type Severity = 'error' | 'warning' | 'note';

export interface Diag {
  code: string;
  severity: Severity;
  /** English message as `sfc check` prints it. */
  message: string;
  /** English title of the code (the UI translates it by `code`). */
  title: string;
  line: number;
  column: number;
  endLine: number;
  endColumn: number;
  /** The element name the diagnostic concerns (step, transition or action), if any. */
  element: string | null;
  /** Ids of the blocks it concerns. */
  elementIds: string[];
  notes: string[];
  /** Firing sequence (transition names) or variable valuation, for analysis findings. */
  witness: string[] | Record<string, unknown> | null;
  /** For a firing-sequence witness: the transition block ids, in firing order. */
  witnessIds?: string[];
  /** For a violated requirement (`sfc prove`): its witness, to replay in monitor mode. */
  replay?: Replay;
}

/** A witness of `sfc prove` as the monitor replays it: the inputs to set before each scan. */
export interface Replay {
  /** Scan period, a TIME literal. */
  period: string;
  /** Per scan: `[name, value]` pairs (only the inputs that change). */
  scans: [string, boolean | number | string][][];
  /** The witness scenario file's text and name. */
  scenario: string;
  file: string;
}

/** What `POST /api/prove` answers. */
export interface ProveResult {
  propertiesFile: string;
  diagnostics: Diag[];
  summary: { holds: number; violated: number; unknown: number } | null;
}

export type FileFormat = 'st' | 'xml';

export interface Session {
  mode: 'mdi' | 'host';
  version: string;
  /** Directories the server may read and write under (absolute). */
  roots: string[];
  /** Files named on the command line (absolute). */
  open: string[];
  host?: { fb: 'atmt' | 'eatmt'; nstep: number; ntr: number; file: string; result: string };
}

export interface OpenResult {
  path: string;
  format: FileFormat;
  charts: EditorDoc[];
  diagnostics: Diag[];
  /** Hash of the file's bytes when read; sent back on save to detect changes made outside. */
  hash: string;
}

export interface SaveResult {
  path: string;
  hash: string;
  diagnostics: Diag[];
}

export type BuildTarget = 'atmt' | 'eatmt' | 'st' | 'stl' | 'plcopen' | 'svg' | 'text';

export interface TableRule {
  state: number;
  condition: number;
  next: number;
}

export interface BuildResult {
  ok: boolean;
  diagnostics: Diag[];
  /** The built text (the one-line table for atmt/eatmt). */
  output?: string;
  /** atmt/eatmt: the table and the timeout vector. */
  table?: { rules: TableRule[]; timeouts: number[] };
  /** Host mode: the result file written. */
  resultWritten?: string;
}

export type { ChartTarget };
