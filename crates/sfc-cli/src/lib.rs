//! The commands of the `sfc` binary that run charts (`sim`, `test`, `run`), as a library: the
//! binary calls them, and so do the tests that count allocations (`tests/alloc.rs`) and the
//! benchmark of what users run (`benches/cli.rs`), so both measure exactly the commands.

pub mod run;
pub mod sim;
