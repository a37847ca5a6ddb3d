//! The `sfc` binary. Exit status: 0 success, 1 the input has errors, 2 usage or I/O error.

use clap::{Parser, Subcommand, ValueEnum};
use sfc_diagnostics::{render_human, render_json, RenderOptions, Severity, SourceFile};
use sfc_model::{CheckOptions, Target};
use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

mod build;
mod edit;

use sfc_cli::{run, sim};

#[derive(Parser)]
#[command(
    name = "sfc",
    version,
    about = "Check, format, build, simulate, edit and run IEC 61131-3 Sequential Function Charts"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Parse and validate charts, printing diagnostics.
    Check(CheckArgs),
    /// Rewrite textual SFC in canonical layout.
    Fmt(FmtArgs),
    /// Compile a chart: REX ATMT/EATMT table, Structured Text, S7-200 STL, PLCopen XML, SVG or text.
    Build(BuildArgs),
    /// Simulate a chart on virtual time, optionally against a scenario, writing a trace.
    Sim(SimArgs),
    /// Run every `*.scenario.toml` under the given files and directories.
    Test(TestArgs),
    /// Open the SFC Editor in a browser, served on 127.0.0.1 (Ctrl-C stops it).
    Edit(edit::EditArgs),
    /// Run a chart as a soft-PLC on the wall clock, with Modbus TCP I/O and the monitor protocol.
    Run(run::RunArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum ProfileArg {
    Iec,
    Matiec,
    Codesys,
    Grafcet,
}

#[derive(clap::Args)]
struct SimArgs {
    /// The chart to simulate (`.st`); it takes the place of the scenario's `chart`.
    file: PathBuf,
    /// Set inputs and check expectations from a scenario file (`*.scenario.toml`).
    #[arg(long, value_name = "S.toml")]
    scenario: Option<PathBuf>,
    /// Scan period (default T#10ms, or the scenario's `period`).
    #[arg(long, value_name = "TIME", value_parser = sim::parse_period)]
    period: Option<i64>,
    /// Run every scan whose time is at most this (default: 100 scans, or the scenario's length).
    #[arg(long, value_name = "TIME", value_parser = sim::parse_until, conflicts_with = "scans")]
    until: Option<i64>,
    /// Run this many scans (0 … N-1).
    #[arg(long, value_name = "N")]
    scans: Option<u64>,
    /// Write a trace: `.jsonl`, `.csv` or `.vcd` by extension, `-` for JSON lines on stdout.
    #[arg(long, value_name = "OUT")]
    trace: Option<PathBuf>,
    /// Whose execution rules to follow (default iec).
    #[arg(long, value_enum)]
    profile: Option<ProfileArg>,
    /// The POU to simulate when the file has several.
    #[arg(long, value_name = "NAME")]
    pou: Option<String>,
    /// Print the time analysis: activations and active times per step, sequence of situations.
    #[arg(long)]
    stats: bool,
    /// Print, at the end, why each active step has not been left.
    #[arg(long)]
    explain: bool,
    /// Output format of the summary, `--stats` and `--explain`.
    #[arg(long, value_enum, default_value = "human")]
    format: Format,
    /// Write a variable before scan 0 (repeatable), e.g. `--set Start=TRUE --set Limit=T#2s`.
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = sim::parse_set)]
    set: Vec<(String, String)>,
}

#[derive(clap::Args)]
struct TestArgs {
    /// Scenario files, or directories searched recursively for `*.scenario.toml`.
    #[arg(required = true)]
    paths: Vec<PathBuf>,
    /// Print which steps were never active and which transitions never fired, per chart.
    #[arg(long)]
    coverage: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Human,
    Json,
}

#[derive(Clone, Copy, ValueEnum)]
enum TargetArg {
    Blank,
    Atmt,
    Eatmt,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// IEC 61131-3 source files (`.st`) or PLCopen XML files (`.xml`).
    #[arg(required_unless_present = "explain")]
    files: Vec<PathBuf>,
    /// Output format: rustc-like text on stderr, or a JSON array on stdout.
    #[arg(long, value_enum, default_value = "human")]
    format: Format,
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
    /// Print what a diagnostic code means and how to fix it.
    #[arg(long, value_name = "CODE")]
    explain: Option<String>,
}

#[derive(Clone, Copy, ValueEnum)]
enum BuildTargetArg {
    Atmt,
    Eatmt,
    St,
    Stl,
    Plcopen,
    Svg,
    Text,
}

#[derive(clap::Args)]
struct BuildArgs {
    /// The chart: IEC 61131-3 text (`.st`) or PLCopen XML (`.xml`).
    file: PathBuf,
    /// What to produce.
    #[arg(long, value_enum)]
    target: BuildTargetArg,
    /// Write the result here (atomically) instead of standard output.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    out: Option<PathBuf>,
    /// The SFC POU to build when the file has several.
    #[arg(long, value_name = "NAME")]
    pou: Option<String>,
    /// ATMT/EATMT: compile simultaneous branches into one automaton, one state per reachable situation.
    #[arg(long)]
    flatten: bool,
    /// State limit override for ATMT/EATMT.
    #[arg(long)]
    nstep: Option<u32>,
    /// Rule limit override for ATMT/EATMT.
    #[arg(long)]
    ntr: Option<u32>,
}

#[derive(clap::Args)]
struct FmtArgs {
    /// Files to format in place; `-` reads standard input and writes standard output.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Only report files whose layout differs (exit 1 if any).
    #[arg(long)]
    check: bool,
}

fn main() -> ExitCode {
    // Like other Unix tools, end quietly when the reader of our output goes away
    // (`sfc check --format json | head`) instead of failing on the broken pipe: Rust ignores
    // SIGPIPE by default, which turns that into a panic in `println!`.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of one signal before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // Parsing and checking recurse along the (depth-capped) syntax tree: give them room.
    let child = std::thread::Builder::new().stack_size(64 << 20).spawn(run);
    match child.map(|h| h.join()) {
        Ok(Ok(code)) => ExitCode::from(code),
        _ => {
            eprintln!("error: internal failure");
            ExitCode::from(2)
        }
    }
}

fn run() -> u8 {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return code;
        }
    };
    match cli.command {
        Command::Check(a) => check(a),
        Command::Fmt(a) => fmt(a),
        Command::Build(a) => build::build(build::BuildRequest {
            file: a.file,
            target: match a.target {
                BuildTargetArg::Atmt => build::BuildTarget::Atmt,
                BuildTargetArg::Eatmt => build::BuildTarget::Eatmt,
                BuildTargetArg::St => build::BuildTarget::St,
                BuildTargetArg::Stl => build::BuildTarget::Stl,
                BuildTargetArg::Plcopen => build::BuildTarget::Plcopen,
                BuildTargetArg::Svg => build::BuildTarget::Svg,
                BuildTargetArg::Text => build::BuildTarget::Text,
            },
            out: a.out,
            pou: a.pou,
            flatten: a.flatten,
            nstep: a.nstep,
            ntr: a.ntr,
        }),
        Command::Sim(a) => sim::sim(sim::SimRequest {
            file: a.file,
            scenario: a.scenario,
            period: a.period,
            until: a.until,
            scans: a.scans,
            trace: a.trace,
            profile: a.profile.map(|p| match p {
                ProfileArg::Iec => sfc_sim::Profile::Iec,
                ProfileArg::Matiec => sfc_sim::Profile::Matiec,
                ProfileArg::Codesys => sfc_sim::Profile::Codesys,
                ProfileArg::Grafcet => sfc_sim::Profile::Grafcet,
            }),
            pou: a.pou,
            stats: a.stats,
            explain: a.explain,
            json: matches!(a.format, Format::Json),
            set: a.set,
        }),
        Command::Test(a) => sim::test(&a.paths, a.coverage),
        Command::Edit(a) => edit::edit(a),
        Command::Run(a) => run::run(a),
    }
}

fn read(path: &Path) -> Result<String, String> {
    if path.as_os_str() == "-" {
        let mut s = String::new();
        std::io::stdin().read_to_string(&mut s).map_err(|e| format!("cannot read standard input: {e}"))?;
        return Ok(s);
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    String::from_utf8(bytes).map_err(|_| format!("`{}` is not UTF-8 text", path.display()))
}

fn check(a: CheckArgs) -> u8 {
    if let Some(code) = &a.explain {
        return match sfc_diagnostics::explain(code) {
            Some(info) => {
                println!("{} ({}): {}\n\n{}", info.code, info.severity.as_str(), info.title, info.explanation);
                0
            }
            None => {
                eprintln!("error: unknown diagnostic code `{code}`");
                2
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
    let mut files: Vec<SourceFile> = Vec::new();
    let mut diags = Vec::new();
    for path in &a.files {
        let text = match read(path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        };
        let id = files.len() as u32;
        let (file, _, found) = build::check_any(id, path, &text, &opts);
        files.push(file);
        diags.extend(found);
    }
    let errors = diags.iter().filter(|d| d.severity == Severity::Error).count();
    let warnings = diags.iter().filter(|d| d.severity == Severity::Warning).count();
    match a.format {
        Format::Json => println!("{}", render_json(&diags, &files)),
        Format::Human => {
            let color = std::io::stderr().is_terminal();
            let mut err = std::io::stderr().lock();
            for d in &diags {
                let _ = writeln!(err, "{}", render_human(d, &files, RenderOptions { color }));
            }
            if errors + warnings > 0 {
                let _ = writeln!(err, "{}", summary(errors, warnings));
            }
        }
    }
    u8::from(errors > 0)
}

/// Prints diagnostics in the human form on stderr; returns the number of errors.
fn print_diagnostics(diags: &[sfc_diagnostics::Diagnostic], files: &[SourceFile]) -> usize {
    let color = std::io::stderr().is_terminal();
    let mut err = std::io::stderr().lock();
    for d in diags {
        let _ = writeln!(err, "{}", render_human(d, files, RenderOptions { color }));
    }
    diags.iter().filter(|d| d.severity == Severity::Error).count()
}

fn plural(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

fn summary(errors: usize, warnings: usize) -> String {
    match (errors, warnings) {
        (0, w) => format!("{} emitted", plural(w, "warning")),
        (e, 0) => format!("{} emitted", plural(e, "error")),
        (e, w) => format!("{} and {} emitted", plural(e, "error"), plural(w, "warning")),
    }
}

/// Writes `text` to a temporary file beside `path`, then renames it over `path` (the editor's
/// server does the same for saves: one implementation).
fn write_atomically(path: &Path, text: &str) -> std::io::Result<()> {
    sfc_server::write_atomically(path, text.as_bytes())
}

fn fmt(a: FmtArgs) -> u8 {
    let mut status = 0u8;
    let color = std::io::stderr().is_terminal();
    for path in &a.files {
        let text = match read(path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        };
        let (unit, diags) = sfc_syntax::parse(0, &text);
        let errors: Vec<_> = diags.iter().filter(|d| d.is_error()).collect();
        if !errors.is_empty() {
            let files = [SourceFile::new(path.display().to_string(), text.clone())];
            for d in &errors {
                eprintln!("{}", render_human(d, &files, RenderOptions { color }));
            }
            eprintln!("`{}` has syntax errors and was not formatted", path.display());
            status = 1;
            continue;
        }
        let formatted = sfc_syntax::print::print(&unit);
        if path.as_os_str() == "-" {
            print!("{formatted}");
            continue;
        }
        if formatted == text {
            continue;
        }
        if a.check {
            println!("would reformat {}", path.display());
            status = 1;
        } else if let Err(e) = write_atomically(path, &formatted) {
            eprintln!("error: cannot write `{}`: {e}", path.display());
            return 2;
        }
    }
    status
}
