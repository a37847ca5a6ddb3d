//! `sfc fmt PATH…`: rewrite IEC 61131-3 text in canonical layout, atomically; `--check` only
//! reports; `-` filters standard input. Directories are searched for `*.st`. PLCopen XML is
//! refused: it has a layout of its own.

use crate::term::{self, plural};
use crate::Status;
use sfc_diagnostics::SourceFile;
use sfc_driver::load::{collect, Found};
use sfc_driver::FormatError;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct FmtArgs {
    /// Files to format in place, directories searched recursively for `*.st`; `-` reads
    /// standard input and writes standard output.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Only report files whose layout differs (exit 1 if any); with `-`, print nothing.
    #[arg(long)]
    check: bool,
}

fn is_st(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("st"))
}

pub fn fmt(a: FmtArgs) -> u8 {
    let mut status = Status::Ok;
    let (mut changed, mut unchanged) = (0usize, 0usize);
    for found in collect(&a.files, is_st) {
        let path = match found {
            Found::File(p) => p,
            Found::Missing(e) => {
                let message =
                    e.message.replace("no chart files (`*.st`, `*.xml`, `*.l5x`)", "no IEC 61131-3 files (`*.st`)");
                term::error(&message);
                status = status.max(Status::Usage);
                continue;
            }
        };
        let stdin = path.as_os_str() == "-";
        let decoded = match sfc_driver::read_source(&path) {
            Ok(t) => t,
            Err(e) => {
                term::error(&e.message);
                status = status.max(Status::Usage);
                continue;
            }
        };
        let text = &decoded.text;
        let shown = if stdin { "standard input".to_string() } else { format!("`{}`", path.display()) };
        let name = if stdin { "<stdin>".to_string() } else { path.display().to_string() };
        if let Some(w) = sfc_syntax::encoding::warning(0, &decoded) {
            term::print_diagnostics(&[w], &[SourceFile::new(name.clone(), text.clone())]);
        }
        let formatted = match sfc_driver::format(&name, text) {
            Ok(f) => f,
            Err(FormatError::Xml) => {
                term::error(&format!(
                    "{shown} is PLCopen XML: `sfc fmt` rewrites IEC 61131-3 text only (to get text from it: `sfc build {} --target text`)",
                    if stdin { "FILE.xml".to_string() } else { path.display().to_string() }
                ));
                status = status.max(Status::Usage);
                continue;
            }
            Err(FormatError::Syntax { file, diagnostics }) => {
                term::print_diagnostics(&diagnostics, std::slice::from_ref(&file));
                term::error(&format!("{shown} has syntax errors and was not formatted"));
                status = status.max(Status::Findings);
                continue;
            }
        };
        // The file keeps its encoding, byte order mark and line endings.
        let (bytes, lost) = sfc_syntax::encoding::encode(&formatted, &decoded);
        let same = sfc_syntax::encoding::decode(&bytes) == decoded;
        if stdin {
            // `--check -` says nothing: the exit status tells whether the input is formatted.
            if a.check {
                if !same {
                    status = status.max(Status::Findings);
                }
            } else {
                let mut out = std::io::stdout().lock();
                let _ = out.write_all(&bytes);
                let _ = out.flush();
            }
            continue;
        }
        if lost > 0 {
            term::error(&format!(
                "{shown} is Latin-1 / Windows-1252, which cannot hold {} of its characters: not formatted",
                lost
            ));
            status = status.max(Status::Findings);
            continue;
        }
        if same {
            unchanged += 1;
            continue;
        }
        changed += 1;
        if a.check {
            println!("would reformat {}", path.display());
            status = status.max(Status::Findings);
        } else if let Err(e) = sfc_driver::write_atomically(&path, &bytes) {
            term::error(&format!("cannot write `{}`: {e}", path.display()));
            status = status.max(Status::Usage);
        }
    }
    // One line that says what happened to the files (not for standard input).
    if changed + unchanged > 0 {
        let done = if a.check { "would be reformatted" } else { "reformatted" };
        eprintln!("{} {done}, {} already formatted", plural(changed, "file"), unchanged);
    }
    status.code()
}
