//! The `sfc` binary. Exit status (`interfaces.md`): 0 success, 1 the input has errors or
//! findings (a test failed, `--deny warnings`), 2 usage or I/O error. The table of every
//! command is in `docs/cli.md`.

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;

mod build;
mod check;
mod diff;
mod git;
mod merge;
mod edit;
mod fmt;
mod lsp;
mod prove;

use sfc_cli::{run, sim, term, test, DenyArg, Status, VERSION};

/// mimalloc instead of the system allocator: parsing and checking a large chart allocate and
/// free millions of small nodes, often freed on another thread than the one that made them (the
/// language server's workers). With glibc's allocator that cost a third of `sfc lsp`'s
/// diagnostics after an edit on the 10,000-step ring (`crates/sfc-lsp/benches/ring.rs`).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(
    name = "sfc",
    version = VERSION,
    about = "Check, format, build, simulate, test, edit and run IEC 61131-3 Sequential Function Charts"
)]
struct Cli {
    /// When to colour the output: on a terminal (auto; `NO_COLOR` turns it off), always or never.
    #[arg(long, global = true, value_enum, default_value = "auto")]
    color: term::ColorChoice,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Parse, validate and analyse charts, printing diagnostics.
    Check(check::CheckArgs),
    /// Rewrite textual SFC in canonical layout.
    Fmt(fmt::FmtArgs),
    /// Compile a chart: REX ATMT/EATMT table, Structured Text, S7-200 STL, PLCopen XML, SVG or text.
    Build(BuildArgs),
    /// Simulate a chart on virtual time, optionally against a scenario, writing a trace.
    Sim(SimArgs),
    /// Compare two versions of a chart file by meaning: steps, transitions, conditions, actions
    /// and variables added, removed, renamed or changed (`sfc diff OLD NEW`, `sfc diff REV --
    /// FILE`, `sfc diff REV1 REV2 -- FILE`).
    Diff(diff::DiffArgs),
    /// Merge two versions of a chart file with their common ancestor by element: changes to
    /// different steps, transitions and actions merge, the same element changed both ways is a
    /// conflict (`sfc merge BASE OURS THEIRS -o OUT`; git's merge driver).
    Merge(merge::MergeArgs),
    /// Set a git repository up so that `git diff` and `git merge` treat charts by meaning.
    Git(git::GitArgs),
    /// Run every `*.scenario.toml` under the given files and directories.
    Test(test::TestArgs),
    /// Prove or refute the requirements of `<chart>.props.toml` under the exact scan semantics.
    Prove(prove::ProveArgs),
    /// Open the SFC Editor in a browser, served on 127.0.0.1 (Ctrl-C stops it).
    Edit(edit::EditArgs),
    /// Run a chart as a soft-PLC on the wall clock, with Modbus TCP I/O and the monitor protocol.
    Run(run::RunArgs),
    /// Serve the Language Server Protocol on standard input and output, for editors.
    Lsp(lsp::LspArgs),
    /// Print a shell completion script (e.g. `sfc completions bash > /etc/bash_completion.d/sfc`).
    Completions(CompletionsArgs),
    /// Print the manual page (roff), or write one page per command into a directory.
    Man(ManArgs),
}

#[derive(clap::Args)]
struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    shell: clap_complete::Shell,
}

#[derive(clap::Args)]
struct ManArgs {
    /// Write `sfc.1` and `sfc-COMMAND.1` for every command into this directory instead of
    /// printing `sfc.1`.
    #[arg(long, value_name = "DIR")]
    dir: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum ProfileArg {
    Iec,
    Matiec,
    Codesys,
    Grafcet,
    Logix,
    Graph,
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
    /// Print the time analysis: activations and active times per step, and the situations
    /// summarised (the ten that lasted longest, and how many there were).
    #[arg(long)]
    stats: bool,
    /// With the time analysis, list every situation in order with the time it began.
    #[arg(long)]
    stats_full: bool,
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

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum Format {
    Human,
    Json,
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
    L5x,
    Simaticml,
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
    /// STL: how the steps are programmed: set/reset networks (default) or SCR segments
    /// (LSCR/SCRT/SCRE).
    #[arg(long, value_enum, value_name = "METHOD")]
    stl_method: Option<StlMethodArg>,
    /// STL: also write STEP 7-Micro/WIN's symbol table (CSV: Symbol,Address,Comment) here.
    #[arg(long, value_name = "OUT.csv")]
    symbols: Option<PathBuf>,
    /// ST: the compiler the Structured Text is written for: IEC 61131-3 as written (default),
    /// MatIEC (Beremiz, OpenPLC v3), STruC++ (OpenPLC v4), or CODESYS/TwinCAT.
    #[arg(long, value_enum, value_name = "DIALECT")]
    st_dialect: Option<StDialectArg>,
}

#[derive(Clone, Copy, ValueEnum)]
enum StDialectArg {
    Iec,
    Matiec,
    Strucpp,
    Codesys,
}

#[derive(Clone, Copy, ValueEnum)]
enum StlMethodArg {
    Setreset,
    Scr,
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
    let args = with_coverage_value(std::env::args_os().collect());
    let choice = term::color_from_args(&args);
    term::set_color(choice);
    let clap_color = match choice {
        term::ColorChoice::Auto if std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty()) => {
            clap::ColorChoice::Never
        }
        term::ColorChoice::Auto => clap::ColorChoice::Auto,
        term::ColorChoice::Always => clap::ColorChoice::Always,
        term::ColorChoice::Never => clap::ColorChoice::Never,
    };
    let parsed = Cli::command().color(clap_color).try_get_matches_from(args).and_then(|m| Cli::from_arg_matches(&m));
    let cli = match parsed {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { Status::Usage.code() } else { Status::Ok.code() };
            let _ = e.print();
            return code;
        }
    };
    term::set_color(cli.color);
    match cli.command {
        Command::Check(a) => check::check(a),
        Command::Fmt(a) => fmt::fmt(a),
        Command::Diff(a) => diff::diff(a),
        Command::Merge(a) => merge::merge(a),
        Command::Git(a) => git::git(a),
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
                BuildTargetArg::L5x => build::BuildTarget::L5x,
                BuildTargetArg::Simaticml => build::BuildTarget::Simaticml,
            },
            out: a.out,
            pou: a.pou,
            flatten: a.flatten,
            nstep: a.nstep,
            ntr: a.ntr,
            stl_method: a.stl_method.map(|m| match m {
                StlMethodArg::Setreset => build::StlMethod::SetReset,
                StlMethodArg::Scr => build::StlMethod::Scr,
            }),
            symbols: a.symbols,
            st_dialect: a.st_dialect.map(|d| match d {
                StDialectArg::Iec => build::StDialect::Iec,
                StDialectArg::Matiec => build::StDialect::Matiec,
                StDialectArg::Strucpp => build::StDialect::Strucpp,
                StDialectArg::Codesys => build::StDialect::Codesys,
            }),
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
                ProfileArg::Logix => sfc_sim::Profile::Logix,
                ProfileArg::Graph => sfc_sim::Profile::Graph,
            }),
            pou: a.pou,
            stats: a.stats || a.stats_full,
            stats_full: a.stats_full,
            explain: a.explain,
            json: matches!(a.format, Format::Json),
            set: a.set,
        }),
        Command::Test(a) => test::test(a),
        Command::Prove(a) => prove::prove(a),
        Command::Edit(a) => edit::edit(a),
        Command::Run(a) => run::run(a),
        Command::Lsp(a) => lsp::lsp(a),
        Command::Completions(a) => {
            let mut cmd = Cli::command();
            clap_complete::generate(a.shell, &mut cmd, "sfc", &mut std::io::stdout());
            Status::Ok.code()
        }
        Command::Man(a) => man(a),
    }
}

/// `sfc man`: the roff page of `sfc` on stdout, or every page into `--dir`.
fn man(a: ManArgs) -> u8 {
    let cmd = Cli::command().version(VERSION);
    let Some(dir) = a.dir else {
        let mut out = Vec::new();
        if let Err(e) = clap_mangen::Man::new(cmd).render(&mut out) {
            term::error(&format!("cannot render the manual page: {e}"));
            return Status::Usage.code();
        }
        let mut stdout = std::io::stdout().lock();
        let _ = std::io::Write::write_all(&mut stdout, &out);
        return Status::Ok.code();
    };
    let mut pages = vec![("sfc".to_string(), cmd.clone())];
    for sub in cmd.get_subcommands() {
        let name = format!("sfc-{}", sub.get_name());
        // clap names a page by a `'static` string: leak the few names (the process ends soon).
        let page_name: &'static str = Box::leak(name.clone().into_boxed_str());
        pages.push((name, sub.clone().name(page_name).version(VERSION)));
    }
    if let Err(e) = std::fs::create_dir_all(&dir) {
        term::error(&format!("cannot create `{}`: {e}", dir.display()));
        return Status::Usage.code();
    }
    for (name, page) in pages {
        let mut out = Vec::new();
        let path = dir.join(format!("{name}.1"));
        let written =
            clap_mangen::Man::new(page).render(&mut out).and_then(|_| sfc_driver::write_atomically(&path, &out));
        if let Err(e) = written {
            term::error(&format!("cannot write `{}`: {e}", path.display()));
            return Status::Usage.code();
        }
    }
    eprintln!("wrote the manual pages into `{}`", dir.display());
    Status::Ok.code()
}

/// `--coverage` takes an optional format (`--coverage`, `--coverage lcov`): when the word after
/// it is not a format, it is a path (`sfc test --coverage examples`), so the flag gets its
/// default explicitly and clap does not take the path for a format.
fn with_coverage_value(mut args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    if args.get(1).is_none_or(|a| a != "test") {
        return args;
    }
    let formats = ["text", "json", "lcov", "cobertura"];
    let mut i = 2;
    while i < args.len() {
        if args.get(i).is_some_and(|a| a == "--coverage") {
            let next_is_format = args.get(i + 1).is_some_and(|n| formats.iter().any(|f| n == *f));
            if !next_is_format {
                if let Some(a) = args.get_mut(i) {
                    *a = "--coverage=text".into();
                }
            }
        }
        i += 1;
    }
    args
}
