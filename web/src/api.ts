// Types of the editor's HTTP API (served by `crates/sfc-server`; contract in docs/editor.md),
// generated from crates/sfc-server/src/contract.rs by ts-rs (./contracts/api.ts, kept current by
// sfc-server's `contracts_are_current` test; `tests/contract_api.rs` reads every kind of answer
// back into those Rust types, so they say exactly what the server sends).
export type {
  BuildResult,
  BuildTarget,
  ChangeKind,
  CompareAgainst,
  CompareChange,
  CompareResult,
  ConflictSide,
  Diag,
  FileEntry,
  FileFormat,
  HostInfo,
  OpenResult,
  PouAction,
  PouEntry,
  ProveResult,
  ProveSummary,
  Replay,
  ResolveResult,
  SaveResult,
  Session,
  SessionMode,
  Settings,
  SettingsUpdate,
  Severity,
  Table,
  TableRule,
} from './contracts/api';
export type { ChartTarget } from './doc';
