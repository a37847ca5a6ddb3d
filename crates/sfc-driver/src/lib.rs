//! The driver: what every front end of sfc does with a chart file, in one place.
//!
//! - [`load`]: read a file (or standard input) as text, tell IEC text from PLCopen XML, find
//!   the chart files under directories;
//! - [`check_any`] / [`check_text`]: check a file of either kind, diagnostics located in the
//!   file the user wrote (for XML, at XML lines and columns);
//! - [`compile`]: check-then-compile for a target (ATMT/EATMT tables, ST, STL, PLCopen, SVG,
//!   text);
//! - [`format`]: the canonical layout of IEC text (`sfc fmt`);
//! - [`write_atomically`] and [`same_file`]: writes that never leave a partial file, and the
//!   guard that keeps an output from overwriting its input.
//!
//! `sfc check`, `build` and `fmt`, the editor's server and the language server call it; every
//! function works on text in memory as well as on paths. Nothing here prints or exits.

pub mod compile;
mod disk;
pub mod load;

pub use compile::{
    check_any, check_parsed_text, check_text, is_xml, locate_in_xml, BuildTarget, CompileError, CompileOptions,
    Compiled, IecText,
};
pub use disk::{same_file, write_atomically};
pub use load::{read_source, FileKind, LoadError};

use sfc_diagnostics::{Diagnostic, SourceFile};

/// Why a text could not be formatted.
#[derive(Debug, Clone)]
pub enum FormatError {
    /// PLCopen XML: `fmt` rewrites IEC text only.
    Xml,
    /// The text has syntax errors (located in `file`); nothing was formatted.
    Syntax { file: SourceFile, diagnostics: Vec<Diagnostic> },
}

/// The canonical layout of IEC text (`sfc fmt`): comments and pragmas kept, idempotent.
/// PLCopen XML is refused (by `path`'s extension or the text's first character).
pub fn format(name: &str, text: &str) -> Result<String, FormatError> {
    if is_xml(std::path::Path::new(name), text) {
        return Err(FormatError::Xml);
    }
    let (unit, diags) = sfc_syntax::parse(0, text);
    let errors: Vec<Diagnostic> = diags.into_iter().filter(Diagnostic::is_error).collect();
    if !errors.is_empty() {
        return Err(FormatError::Syntax { file: SourceFile::new(name, text), diagnostics: errors });
    }
    // The editor's layout attribute of an older save is written one element per line, as the
    // editor writes it now (`sfc_doc::split_layout`).
    Ok(sfc_doc::split_layout(&sfc_syntax::print::print(&unit)))
}
