// GENERATED from crates/sfc-server/src/contract.rs by ts-rs: do not edit.
// `UPDATE_CONTRACTS=1 cargo test -p sfc-server contracts` writes it anew; the test fails when it is stale.
import type { EditorDoc } from './doc';

export type Severity = "error" | "warning" | "note";

export type Diag = { code: string, severity: Severity, 
/**
 * English message as `sfc check` prints it.
 */
message: string, 
/**
 * English title of the code (the page translates it by `code`).
 */
title: string, file: string, line: number, column: number, endLine: number, endColumn: number, 
/**
 * The element name the diagnostic concerns (step, transition or action), if any.
 */
element: string | null, 
/**
 * Ids of the blocks it concerns.
 */
elementIds: Array<string>, notes: Array<string>, 
/**
 * Firing sequence (transition names) or variable valuation, for analysis findings.
 */
witness: string[] | Record<string, unknown> | null, 
/**
 * For a firing-sequence witness: the transition block ids, in firing order.
 */
witnessIds?: Array<string>, 
/**
 * For a violated requirement (`sfc prove`): its witness, to replay in monitor mode.
 */
replay?: Replay, 
/**
 * The POU of the file the diagnostic lies in (its chart's, when it concerns a chart); absent
 * for one outside every POU (a TYPE, the XML itself). The page lists it under that chart's
 * tab, or under the file when no chart of the file is that POU.
 */
pou?: string, };

export type FileFormat = "st" | "xml";

export type SessionMode = "mdi" | "host";

export type HostInfo = { fb: "atmt" | "eatmt", nstep: number, ntr: number, file: string, result: string, };

export type Session = { mode: SessionMode, version: string, 
/**
 * Directories named on the command line (absolute): their charts are served.
 */
roots: Array<string>, 
/**
 * Files named on the command line (absolute): served alone.
 */
open: Array<string>, host?: HostInfo, };

export type FileEntry = { path: string, format: FileFormat, };

export type PouAction = { name: string, sfc: boolean, };

export type PouEntry = { name: string, 
/**
 * `program`, `functionBlock` or `function`.
 */
kind: string, 
/**
 * The body's language: `SFC`, `ST` or `IL`.
 */
language: string, 
/**
 * Whether the editor opens it as a chart (its body, or an action, is written in SFC).
 */
chart: boolean, 
/**
 * Its actions, in order.
 */
actions: Array<PouAction>, 
/**
 * Its chart's transitions by name (an unnamed one `T<n>`), in order.
 */
transitions: Array<string>, };

export type OpenResult = { path: string, format: FileFormat, charts: Array<EditorDoc>, diagnostics: Array<Diag>, 
/**
 * Hash of the file's bytes when read; sent back on save to detect changes made outside.
 */
hash: string, 
/**
 * Every POU of the file in order (the project tree), charts or not.
 */
pous?: Array<PouEntry>, };

export type SaveResult = { path: string, hash: string, diagnostics: Array<Diag>, };

export type BuildTarget = "atmt" | "eatmt" | "st" | "stl" | "plcopen" | "svg" | "text";

export type TableRule = { state: number, 
/**
 * The input index, `1000 + index` when negated.
 */
condition: number, next: number, };

export type Table = { rules: Array<TableRule>, timeouts: Array<number>, };

export type BuildResult = { ok: boolean, diagnostics: Array<Diag>, 
/**
 * The built text (the one-line table for atmt/eatmt).
 */
output?: string, 
/**
 * atmt/eatmt: the table and the timeout vector.
 */
table?: Table, 
/**
 * Host mode: the result file written.
 */
resultWritten?: string, };

export type Replay = { 
/**
 * Scan period, a TIME literal.
 */
period: string, 
/**
 * Per scan: `[name, value]` pairs (only the inputs that change).
 */
scans: [string, boolean | number | string][][], 
/**
 * The witness scenario file's text.
 */
scenario: string, 
/**
 * The witness scenario file's name (`<chart>.<property>.witness.toml`).
 */
file: string, };

export type ProveSummary = { holds: number, violated: number, unknown: number, };

export type ProveResult = { propertiesFile: string, diagnostics: Array<Diag>, summary: ProveSummary | null, };

export type CompareAgainst = "saved" | "head";

export type ChangeKind = "added" | "removed" | "renamed" | "changed";

export type CompareChange = { 
/**
 * `pou`, `variable`, `step`, `transition`, `action` or `body`.
 */
element: string, 
/**
 * The element's name (the old one when renamed or removed).
 */
name: string, kind: ChangeKind, 
/**
 * For a change, what changed (`condition`, `steps`, `actions`, `type`, `attribute NAME` …).
 */
what: string, old: string | null, new: string | null, 
/**
 * Ids of the blocks of the current chart it concerns (`step:NAME`, `transition:NAME`, the
 * action blocks naming an action); none for a variable, the POU, or a removed element.
 */
elementIds: Array<string>, };

export type CompareResult = { against: CompareAgainst, 
/**
 * What the chart was compared with: the file's path, `PATH@HEAD` for git HEAD.
 */
file: string, pou: string, 
/**
 * Equal in meaning (the layout may differ).
 */
equal: boolean, 
/**
 * Added, renamed and changed elements.
 */
changes: Array<CompareChange>, 
/**
 * Removed elements: the current chart has no block for them.
 */
removed: Array<CompareChange>, 
/**
 * How many blocks of the chart have another place or size than in the chart the file
 * opens as (steps and transitions matched by name, through renames).
 */
layout: number, 
/**
 * A side with errors compared as far as it could be read.
 */
notes: Array<string>, };

export type ConflictSide = "ours" | "theirs";

export type ResolveResult = { doc: EditorDoc, diagnostics: Array<Diag>, };

export type Settings = { 
/**
 * The language chosen in the status bar (`cs`, `en`, `de`); none: the browser's.
 */
language?: string, 
/**
 * Charts opened lately, newest first, as the page opened them (at most 20).
 */
recent: Array<string>, 
/**
 * The monitor's watch list per chart (its POU's name), at most 200 names each.
 */
watch: { [key in string]: Array<string> }, };

export type SettingsUpdate = { language?: string | null, recent?: Array<string>, watch?: { [chart in string]?: string[] | null }, };
