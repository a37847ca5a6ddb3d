//! The commands of the `sfc` binary that run charts (`sim`, `test`, `run`) and what they share
//! (exit status, terminal output, CI reports), as a library: the binary calls them, and so do the
//! test that counts allocations (`tests/alloc.rs`) and the benchmark of what users run
//! (`benches/cli.rs`), so both measure exactly the commands.

use clap::ValueEnum;

pub mod ci;
pub mod run;
pub mod run_config;
pub mod sim;
pub mod term;
pub mod test;

/// `0.1.0 (commit date)`: the version with the git commit it was built from (`build.rs`).
pub const VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), " (", env!("SFC_BUILD_COMMIT"), ")");

/// Exit status of a command, ordered by precedence: a usage or I/O problem outweighs findings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// 0: done, nothing found.
    Ok,
    /// 1: the input has errors, a test failed, or denied warnings.
    Findings,
    /// 2: usage or I/O error.
    Usage,
}

impl Status {
    pub fn code(self) -> u8 {
        match self {
            Status::Ok => 0,
            Status::Findings => 1,
            Status::Usage => 2,
        }
    }
}

/// `--deny warnings`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DenyArg {
    /// Warnings fail the command (exit 1) as errors do.
    Warnings,
}
