//! `sfc build FILE --target T [-o OUT]`: compile a chart (textual SFC or PLCopen XML) to a
//! REX ATMT/EATMT table, Structured Text, S7-200 statement list, PLCopen XML, SVG or text.

use crate::{print_diagnostics, read, write_atomically};
use sfc_diagnostics::{Diagnostic, SourceFile};
use sfc_model::{CheckOptions, Chart, Checked, Limits, Target};
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BuildTarget {
    Atmt,
    Eatmt,
    St,
    Stl,
    Plcopen,
    Svg,
    Text,
}

pub struct BuildRequest {
    pub file: PathBuf,
    pub target: BuildTarget,
    pub out: Option<PathBuf>,
    pub pou: Option<String>,
    pub flatten: bool,
    pub nstep: Option<u32>,
    pub ntr: Option<u32>,
}

/// A file is PLCopen XML by its extension, or by its first non-blank character.
pub fn is_xml(path: &Path, text: &str) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml")) || text.trim_start().starts_with('<')
}

/// Checks a file of either kind: the diagnostics are located in the file the user wrote (for
/// XML, the importer maps them back to XML lines and columns); `Checked` is the IEC text.
pub fn check_any(file_id: u32, path: &Path, text: &str, opts: &CheckOptions) -> (SourceFile, Checked, Vec<Diagnostic>) {
    let name = path.display().to_string();
    if is_xml(path, text) {
        let imported = sfc_plcopen::import(file_id, &name, text);
        let checked = sfc_analysis::check_source(file_id, &format!("{name} (imported)"), &imported.text, opts);
        let mut diags = imported.diagnostics.clone();
        diags.extend(checked.diagnostics.iter().map(|d| sfc_plcopen::relocate(d, &imported.map, file_id)));
        sfc_diagnostics::sort(&mut diags);
        diags.dedup();
        (imported.xml, checked, diags)
    } else {
        let checked = sfc_analysis::check_source(file_id, &name, text, opts);
        let diags = checked.diagnostics.clone();
        (checked.file.clone(), checked, diags)
    }
}

/// The chart to build: the one named by `--pou`, or the only SFC POU of the file.
fn pick_chart<'a>(checked: &'a Checked, pou: Option<&str>) -> Result<&'a Chart, String> {
    let names = || checked.charts.iter().map(|c| c.pou.as_str()).collect::<Vec<_>>().join(", ");
    match pou {
        Some(p) => checked
            .charts
            .iter()
            .find(|c| c.pou.eq_ignore_ascii_case(p))
            .ok_or_else(|| format!("`{p}` is not an SFC POU of the file (SFC POUs: {})", names())),
        None => match checked.charts.as_slice() {
            [one] => Ok(one),
            [] => Err("the file has no SFC POU to build".to_string()),
            _ => Err(format!("the file has several SFC POUs; choose one with --pou ({})", names())),
        },
    }
}

pub fn build(r: BuildRequest) -> u8 {
    let text = match read(&r.file) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let table_target = match r.target {
        BuildTarget::Atmt => Some(Target::Atmt),
        BuildTarget::Eatmt => Some(Target::Eatmt),
        _ => None,
    };
    // The target rules of ATMT/EATMT are part of the check; the analysis is `sfc check`'s job.
    let opts = CheckOptions { target: table_target, nstep: r.nstep, ntr: r.ntr, analysis: false, ..Default::default() };
    let (file, checked, diags) = check_any(0, &r.file, &text, &opts);
    let errors = print_diagnostics(&diags, &[file]);
    if errors > 0 {
        eprintln!("`{}` has errors: nothing was built", r.file.display());
        return 1;
    }
    let output: Result<String, Vec<Diagnostic>> = match r.target {
        BuildTarget::Text => Ok(sfc_syntax::print::print(&checked.unit)),
        BuildTarget::Plcopen => sfc_plcopen::export(&checked),
        _ => {
            let chart = match pick_chart(&checked, r.pou.as_deref()) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("error: {e}");
                    return 2;
                }
            };
            match r.target {
                BuildTarget::Atmt | BuildTarget::Eatmt => {
                    let target = table_target.unwrap_or(Target::Atmt);
                    let limits = Limits::of(target, r.nstep, r.ntr);
                    sfc_codegen::atmt::build_table(chart, target, limits, r.flatten).map(|t| {
                        print_diagnostics(&t.notes, std::slice::from_ref(&checked.file));
                        if let Some(n) = t.flattened {
                            eprintln!("flattened into {n} states");
                        }
                        t.text
                    })
                }
                BuildTarget::St => sfc_codegen::st::build_st(&checked, chart),
                BuildTarget::Stl => sfc_codegen::stl::build_stl(&checked, chart),
                BuildTarget::Svg => {
                    let layout = sfc_render::layout(chart);
                    Ok(sfc_render::svg(chart, &layout, &sfc_render::SvgOptions::default()))
                }
                BuildTarget::Text | BuildTarget::Plcopen => unreachable!("handled above"),
            }
        }
    };
    let text = match output {
        Ok(t) => t,
        Err(diags) => {
            // Generation diagnostics are located in the checked text (for XML input, the
            // generated IEC text).
            let files = [checked.file.clone()];
            print_diagnostics(&diags, &files);
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
