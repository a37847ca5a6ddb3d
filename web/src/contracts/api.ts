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
witnessIds?: Array<string>, };

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

export type OpenResult = { path: string, format: FileFormat, charts: Array<EditorDoc>, diagnostics: Array<Diag>, 
/**
 * Hash of the file's bytes when read; sent back on save to detect changes made outside.
 */
hash: string, };

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
