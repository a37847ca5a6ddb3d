//! `sfc check PATH…`: parse, validate and analyse every chart file named or found under the
//! directories named, reporting each and going on after a file that cannot be read; the
//! diagnostics as rustc-like text, one JSON array, or a SARIF 2.1.0 log.

use crate::term::{self, plural, summary};
use crate::{DenyArg, ProfileArg, Status};
use sfc_diagnostics::{render_json, render_sarif, SarifNotification, SarifTool, Severity, SourceFile};
use sfc_driver::load::{collect, is_chart_file, Found};
use sfc_model::{CheckOptions, Target};
use std::path::PathBuf;

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum CheckFormat {
    /// rustc-like text on standard error.
    Human,
    /// One JSON array on standard output (`interfaces.md`).
    Json,
    /// A SARIF 2.1.0 log on standard output (GitHub code scanning, GitLab, IDEs).
    Sarif,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum TargetArg {
    Blank,
    Atmt,
    Eatmt,
}

#[derive(clap::Args)]
pub struct CheckArgs {
    /// IEC 61131-3 files (`.st`), PLCopen XML files (`.xml`), `-` for standard input, or
    /// directories searched recursively for both.
    #[arg(required_unless_present = "explain")]
    files: Vec<PathBuf>,
    /// Output format: rustc-like text on stderr, a JSON array or a SARIF log on stdout.
    #[arg(long, value_enum, default_value = "human")]
    format: CheckFormat,
    /// Fail (exit 1) on warnings too: `--deny warnings`.
    #[arg(long, short = 'D', value_enum, value_name = "LINTS")]
    deny: Vec<DenyArg>,
    /// Apply the rules of a REX automaton block (overrides the `sfc.target` attribute).
    #[arg(long, value_enum)]
    target: Option<TargetArg>,
    /// State limit override for ATMT/EATMT.
    #[arg(long)]
    nstep: Option<u32>,
    /// Rule limit override for ATMT/EATMT.
    #[arg(long)]
    ntr: Option<u32>,
    /// Skip the reachability and guard analysis (structural and type checks only).
    #[arg(long)]
    no_analysis: bool,
    /// Also warn where the chart behaves differently under this profile than under `iec`
    /// (`matiec`: SFC0901–SFC0908; `codesys`: SFC0911–SFC0913).
    #[arg(long, value_enum)]
    profile: Option<ProfileArg>,
    /// Print what a diagnostic code means and how to fix it.
    #[arg(long, value_name = "CODE")]
    explain: Option<String>,
}

pub fn check(a: CheckArgs) -> u8 {
    if let Some(code) = &a.explain {
        return match sfc_diagnostics::explain(code) {
            Some(info) => {
                println!("{} ({}): {}\n\n{}", info.code, info.severity.as_str(), info.title, info.explanation);
                Status::Ok.code()
            }
            None => {
                term::error(&format!("unknown diagnostic code `{code}`"));
                Status::Usage.code()
            }
        };
    }
    let opts = CheckOptions {
        target: a.target.map(|t| match t {
            TargetArg::Blank => Target::Blank,
            TargetArg::Atmt => Target::Atmt,
            TargetArg::Eatmt => Target::Eatmt,
        }),
        nstep: a.nstep,
        ntr: a.ntr,
        analysis: !a.no_analysis,
        ..CheckOptions::default()
    };
    if let Some(p @ (ProfileArg::Iec | ProfileArg::Grafcet | ProfileArg::Graph)) = a.profile {
        // Said, not silently ignored: only `matiec`, `codesys` and `logix` have warnings of their own.
        let name = match p {
            ProfileArg::Iec => "iec",
            ProfileArg::Grafcet => "grafcet",
            _ => "graph",
        };
        eprintln!(
            "note: `--profile {name}` adds no warnings to `sfc check` (only `matiec` does: SFC0901–SFC0908, \
             `codesys`: SFC0911–SFC0913, and `logix`: SFC0921–SFC0923)"
        );
    }
    let human = matches!(a.format, CheckFormat::Human);
    let mut files: Vec<SourceFile> = Vec::new();
    let mut diags = Vec::new();
    let mut unreadable: Vec<SarifNotification> = Vec::new();
    for found in collect(&a.files, is_chart_file) {
        let path = match found {
            Found::File(p) => p,
            Found::Missing(e) => {
                term::error(&e.message);
                unreadable.push(SarifNotification { message: e.message, file: Some(e.path.display().to_string()) });
                continue;
            }
        };
        let decoded = match sfc_driver::read_source(&path) {
            Ok(t) => t,
            Err(e) => {
                term::error(&e.message);
                unreadable.push(SarifNotification { message: e.message, file: Some(path.display().to_string()) });
                continue;
            }
        };
        let id = files.len() as u32;
        let shown = if path.as_os_str() == "-" { PathBuf::from("<stdin>") } else { path.clone() };
        let (file, checked, mut found) = sfc_driver::check_any(id, &shown, &decoded.text, &opts);
        let clean = !found.iter().any(|d| d.severity == Severity::Error);
        found.splice(0..0, sfc_syntax::encoding::warning(id, &decoded));
        if matches!(a.profile, Some(ProfileArg::Matiec)) && clean && !sfc_driver::is_xml(&shown, &decoded.text) {
            let mut extra = sfc_sim::matiec_check::differences(&checked.charts, &decoded.text);
            for d in &mut extra {
                d.span.file = id;
            }
            found.extend(extra);
            sfc_diagnostics::sort(&mut found);
        }
        if matches!(a.profile, Some(ProfileArg::Codesys | ProfileArg::Logix)) && clean {
            let mut extra = if matches!(a.profile, Some(ProfileArg::Logix)) {
                sfc_sim::logix_check::differences(&checked.charts, &checked.action_charts)
            } else {
                sfc_sim::codesys_check::differences(&checked.charts, &checked.action_charts)
            };
            for d in &mut extra {
                d.span.file = id;
            }
            // In an export, located in the XML (as the check's own findings are).
            if sfc_driver::is_xml(&shown, &decoded.text) {
                extra = sfc_driver::locate_in_xml(id, &shown.display().to_string(), &decoded.text, &extra);
            }
            found.extend(extra);
            sfc_diagnostics::sort(&mut found);
        }
        // Human output goes file by file, so a long run shows its findings as it goes.
        if human {
            files.push(file);
            term::print_diagnostics(&found, &files);
        } else {
            files.push(file);
        }
        diags.extend(found);
    }
    let errors = diags.iter().filter(|d| d.severity == Severity::Error).count();
    let warnings = diags.iter().filter(|d| d.severity == Severity::Warning).count();
    let deny_warnings = a.deny.contains(&DenyArg::Warnings);
    match a.format {
        CheckFormat::Json => println!("{}", render_json(&diags, &files)),
        CheckFormat::Sarif => {
            let cwd = std::env::current_dir().map(|d| d.display().to_string()).unwrap_or_default();
            let (mut cwd_uri, _) = sfc_diagnostics::sarif_uri(&cwd);
            if !cwd_uri.ends_with('/') {
                cwd_uri.push('/');
            }
            let tool = SarifTool {
                name: "sfc",
                version: crate::VERSION,
                semantic_version: env!("CARGO_PKG_VERSION"),
                information_uri: option_env!("CARGO_PKG_HOMEPAGE").filter(|h| !h.is_empty()),
            };
            println!("{}", render_sarif(&diags, &files, &tool, &cwd_uri, &unreadable));
        }
        CheckFormat::Human => {
            if errors + warnings > 0 {
                eprintln!("{}", summary(errors, warnings));
            }
            if deny_warnings && warnings > 0 {
                term::error(&format!("{} denied by `--deny warnings`", plural(warnings, "warning")));
            }
            if files.is_empty() && unreadable.is_empty() {
                term::error("nothing to check");
            }
        }
    }
    if !unreadable.is_empty() || files.is_empty() {
        Status::Usage.code()
    } else if errors > 0 || (deny_warnings && warnings > 0) {
        Status::Findings.code()
    } else {
        Status::Ok.code()
    }
}
