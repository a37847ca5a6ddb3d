//! `sfc run` until the command is wired into `sfc`: the same arguments (`--help`).

#[path = "../../sfc-cli/src/run.rs"]
mod run;

use clap::Parser;

#[derive(Parser)]
#[command(name = "sfc-run", about = "sfc run: the chart as a soft-PLC (docs/runtime.md)")]
struct Cli {
    #[command(flatten)]
    args: run::RunArgs,
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    std::process::ExitCode::from(run::run(cli.args))
}
