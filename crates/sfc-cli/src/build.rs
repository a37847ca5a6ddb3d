//! `sfc build FILE --target T [-o OUT]`: compile a chart (textual SFC or PLCopen XML) to a
//! REX ATMT/EATMT table, Structured Text, S7-200 statement list, PLCopen XML, SVG or text.
//! The checking and compiling are `sfc_server::compile`'s, shared with the editor.

use crate::{print_diagnostics, read, write_atomically};
use sfc_server::compile::{self, CompileError, CompileOptions};
use std::path::PathBuf;

pub use sfc_codegen::stl::StlMethod;
pub use sfc_server::compile::{check_any, BuildTarget};

pub struct BuildRequest {
    pub file: PathBuf,
    pub target: BuildTarget,
    pub out: Option<PathBuf>,
    pub pou: Option<String>,
    pub flatten: bool,
    pub nstep: Option<u32>,
    pub ntr: Option<u32>,
    /// `--stl-method` (STL only).
    pub stl_method: Option<StlMethod>,
    /// `--symbols OUT.csv` (STL only).
    pub symbols: Option<PathBuf>,
}

pub fn build(r: BuildRequest) -> u8 {
    if r.target != BuildTarget::Stl && (r.stl_method.is_some() || r.symbols.is_some()) {
        eprintln!("error: --stl-method and --symbols apply to --target stl");
        return 2;
    }
    let text = match read(&r.file) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let mut opts = compile::validation_options(r.target, r.nstep, r.ntr);
    // With --flatten the simultaneous branches are compiled, not refused.
    opts.flatten = r.flatten;
    let (file, checked, diags) = check_any(0, &r.file, &text, &opts);
    let errors = print_diagnostics(&diags, &[file]);
    if errors > 0 {
        eprintln!("`{}` has errors: nothing was built", r.file.display());
        return 1;
    }
    let copts = CompileOptions {
        pou: r.pou.as_deref(),
        flatten: r.flatten,
        nstep: r.nstep,
        ntr: r.ntr,
        stl_method: r.stl_method.unwrap_or_default(),
    };
    let text = match compile::compile(&checked, r.target, &copts) {
        Ok(built) => {
            print_diagnostics(&built.notes, std::slice::from_ref(&checked.file));
            if let Some(n) = built.flattened {
                eprintln!("flattened into {n} states");
            }
            if let (Some(path), Some(csv)) = (&r.symbols, &built.symbols) {
                if let Err(e) = write_atomically(path, csv) {
                    eprintln!("error: cannot write `{}`: {e}", path.display());
                    return 2;
                }
            }
            built.text
        }
        Err(CompileError::Chart(e)) => {
            eprintln!("error: {e}");
            return 2;
        }
        Err(CompileError::Diagnostics(diags)) => {
            // Generation diagnostics are located in the checked text (for XML input, the
            // generated IEC text).
            print_diagnostics(&diags, std::slice::from_ref(&checked.file));
            eprintln!("`{}` cannot be built for this target", r.file.display());
            return 1;
        }
    };
    match &r.out {
        Some(path) if path.as_os_str() != "-" => {
            if let Err(e) = write_atomically(path, &text) {
                eprintln!("error: cannot write `{}`: {e}", path.display());
                return 2;
            }
        }
        _ => {
            print!("{text}");
            if !text.ends_with('\n') && std::io::IsTerminal::is_terminal(&std::io::stdout()) {
                println!();
            }
        }
    }
    0
}
