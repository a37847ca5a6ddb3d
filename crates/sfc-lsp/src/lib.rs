//! `sfc lsp`: a Language Server Protocol server for textual SFC (IEC 61131-3 text with SFC, ST
//! and IL) and PLCopen XML, over standard input and output.
//!
//! Built on `lsp-server` (the connection, JSON-RPC framing, the reader and writer threads) and
//! `lsp-types`, on the driver crate for checking and formatting (so the editor shows exactly
//! what `sfc check` and `sfc fmt` say). Layers of this crate:
//!
//! - [`text`]: byte offsets ↔ LSP positions (UTF-16 columns), incremental edits;
//! - [`index`]: declarations and uses of every name of a file, from the syntax tree;
//! - [`workspace`]: open documents and the chart files of the workspace folders;
//! - [`check`]: diagnostics providers per kind of file and the background check workers;
//! - features: [`navigate`] (definition, references, rename), [`hover`], [`complete`],
//!   [`symbols`], [`actions`], [`tokens`], [`format`];
//! - [`server`]: the main loop, which answers requests from the index and never waits for a
//!   check.

pub mod actions;
pub mod check;
pub mod complete;
pub mod dispose;
pub mod format;
pub mod hover;
pub mod index;
pub mod navigate;
pub mod server;
pub mod symbols;
pub mod text;
pub mod tokens;
pub mod workspace;

pub use check::{ChartDiagnostics, DiagnosticsProvider};
pub use server::{run_stdio, serve, ServerOptions};
