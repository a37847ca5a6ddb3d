//! `sfc build FILE --target T [-o OUT]`: compile a chart (textual SFC or PLCopen XML) to a
//! REX ATMT/EATMT table, Structured Text, S7-200 statement list, PLCopen XML, SVG or text.
//! The checking and compiling are the driver's (`sfc_driver::compile`), shared with the editor.

use crate::term::{self, print_diagnostics};
use crate::Status;
use sfc_driver::compile::{self, CompileError, CompileOptions};
use std::path::PathBuf;

pub use sfc_codegen::st::StDialect;
pub use sfc_codegen::stl::StlMethod;
pub use sfc_driver::compile::BuildTarget;

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
    /// `--st-dialect` (ST only).
    pub st_dialect: Option<StDialect>,
}

pub fn build(r: BuildRequest) -> u8 {
    if r.target != BuildTarget::Stl && (r.stl_method.is_some() || r.symbols.is_some()) {
        term::error("--stl-method and --symbols apply to --target stl");
        return Status::Usage.code();
    }
    if r.target != BuildTarget::St && r.st_dialect.is_some() {
        term::error("--st-dialect applies to --target st");
        return Status::Usage.code();
    }
    for out in r.out.iter().chain(&r.symbols) {
        if sfc_driver::same_file(out, &r.file) {
            term::error(&format!(
                "`{}` is the input: refusing to overwrite the chart with the build output (choose another file)",
                out.display()
            ));
            return Status::Usage.code();
        }
    }
    let decoded = match sfc_driver::read_source(&r.file) {
        Ok(t) => t,
        Err(e) => {
            term::error(&e.message);
            return Status::Usage.code();
        }
    };
    let mut opts = compile::validation_options(r.target, r.nstep, r.ntr);
    // With --flatten the simultaneous branches are compiled, not refused.
    opts.flatten = r.flatten;
    let (file, mut checked, mut diags) = sfc_driver::check_any(0, &r.file, &decoded.text, &opts);
    diags.splice(0..0, sfc_syntax::encoding::warning(0, &decoded));
    let compiling = matches!(r.target, BuildTarget::Atmt | BuildTarget::Eatmt | BuildTarget::St | BuildTarget::Stl);
    // Converting (text, PLCopen XML, SVG) never refuses a chart for its problems: they are
    // reported. Compiling refuses a chart with errors, but only its own errors count (those of
    // the POU built, of what it uses, of the file's types and globals), never another POU's.
    let errors = if !compiling {
        print_diagnostics(&diags, std::slice::from_ref(&file));
        0
    } else {
        match compile::pick_chart(&checked, r.pou.as_deref()).map(|c| c.pou.clone()) {
            Ok(pou) if checked.has_errors() => {
                let mine = sfc_model::errors_for(&checked, &pou);
                let shown: Vec<_> = diags
                    .iter()
                    .filter(|d| !d.is_error() || mine.iter().any(|m| m.code == d.code && m.message == d.message))
                    .cloned()
                    .collect();
                let n = print_diagnostics(&shown, std::slice::from_ref(&file));
                if n == 0 {
                    sfc_model::set_aside_unrelated(&mut checked, &pou);
                }
                n
            }
            _ => print_diagnostics(&diags, std::slice::from_ref(&file)),
        }
    };
    if errors > 0 {
        term::error(&format!("`{}` has errors: nothing was built", r.file.display()));
        return Status::Findings.code();
    }
    let copts = CompileOptions {
        pou: r.pou.as_deref(),
        flatten: r.flatten,
        nstep: r.nstep,
        ntr: r.ntr,
        stl_method: r.stl_method.unwrap_or_default(),
        st_dialect: r.st_dialect.unwrap_or_default(),
        original: compile::is_xml(&r.file, &decoded.text).then_some(decoded.text.as_str()),
    };
    // A conversion writes its output whatever the file's errors (reported above), and then
    // says by its exit code that the file has errors.
    let status_after = if !compiling && checked.has_errors() { Status::Findings } else { Status::Ok };
    let unparsed = checked
        .diagnostics
        .iter()
        .any(|d| d.is_error() && (d.code.starts_with("SFC00") || d.code.starts_with("SFC01")));
    if r.target == BuildTarget::Text && unparsed {
        // Text that does not parse is not reprinted (the printer would drop what it could not
        // read): it is written as it is, its errors reported above.
        return finish(write_out(&r, &checked.file.text), status_after);
    }
    let text = match compile::compile(&checked, r.target, &copts) {
        Ok(built) => {
            print_diagnostics(&built.notes, std::slice::from_ref(&checked.file));
            if let Some(n) = built.flattened {
                eprintln!("flattened into {n} states");
            }
            if let (Some(path), Some(csv)) = (&r.symbols, &built.symbols) {
                if let Err(e) = sfc_driver::write_atomically(path, csv.as_bytes()) {
                    term::error(&format!("cannot write `{}`: {e}", path.display()));
                    return Status::Usage.code();
                }
            }
            built.text
        }
        Err(CompileError::Chart(e)) => {
            term::error(&e);
            return Status::Usage.code();
        }
        Err(CompileError::Diagnostics(diags)) => {
            // Generation diagnostics are located in the checked text (for XML input, the
            // generated IEC text).
            print_diagnostics(&diags, std::slice::from_ref(&checked.file));
            term::error(&format!("`{}` cannot be built for this target", r.file.display()));
            return Status::Findings.code();
        }
    };
    // `--target st -o OUT.xml`: the plain ST POUs as PLCopen XML, which CODESYS, TwinCAT and
    // Beremiz import (a text file of several POUs is not something they open).
    let xml_out = r.out.as_ref().and_then(|p| p.extension()).is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    let text = if r.target == BuildTarget::St && xml_out {
        let st = sfc_model::check_source(0, &checked.file.name, &text, &Default::default());
        match compile::compile(&st, BuildTarget::Plcopen, &CompileOptions::default()) {
            Ok(xml) if !st.has_errors() => xml.text,
            Ok(_) | Err(_) => {
                term::error("the Structured Text could not be written as PLCopen XML (an internal error: please report it); write it to a .st file instead");
                return Status::Usage.code();
            }
        }
    } else {
        text
    };
    finish(write_out(&r, &text), status_after)
}

/// The exit code of a build whose output was written (`written`): `status` unless writing failed.
fn finish(written: u8, status: Status) -> u8 {
    if written == Status::Ok.code() {
        status.code()
    } else {
        written
    }
}

/// Writes the result to `-o OUT` (atomically) or standard output.
fn write_out(r: &BuildRequest, text: &str) -> u8 {
    match &r.out {
        Some(path) if path.as_os_str() != "-" => {
            if let Err(e) = sfc_driver::write_atomically(path, text.as_bytes()) {
                term::error(&format!("cannot write `{}`: {e}", path.display()));
                return Status::Usage.code();
            }
        }
        _ => {
            print!("{text}");
            if !text.ends_with('\n') && std::io::IsTerminal::is_terminal(&std::io::stdout()) {
                println!();
            }
        }
    }
    Status::Ok.code()
}
