//! No per-scan allocation in the commands that run charts: `sfc sim` (coverage, time analysis,
//! a JSON-lines trace), `sfc test` and `sfc run`, on a dense chart (every token moving every
//! scan), a ring, a chart with ST actions and one with a step timeout, called exactly as the
//! binary calls them (`sfc_cli::sim`, `sfc_cli::run`) under a counting global allocator.
//!
//! Each command runs for N and for 2N scans; the second run may allocate only a few times more
//! than the first (growing buffers of the output), never once per scan. The counts are printed
//! (`cargo test -p sfc-cli --test alloc -- --nocapture`). One test function, so nothing else in
//! this process allocates at the same time.

use std::alloc::{GlobalAlloc, Layout, System};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

struct Counting;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

// SAFETY: every call is forwarded to the system allocator unchanged; only a counter is added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as ours.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as ours.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as ours.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as ours.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations(f: impl FnOnce() -> u8) -> (u8, u64) {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let status = f();
    (status, ALLOCATIONS.load(Ordering::Relaxed) - before)
}

/// `k` independent two-step loops; every token moves every scan.
fn loops(k: usize) -> String {
    let mut s = String::from("PROGRAM Loops\n    VAR\n        Go : BOOL := TRUE;\n    END_VAR\n");
    for i in 0..k {
        let _ = writeln!(s, "    INITIAL_STEP A{i}: END_STEP\n    STEP B{i}: END_STEP");
        let _ = writeln!(s, "    TRANSITION FROM A{i} TO B{i} := Go; END_TRANSITION");
        let _ = writeln!(s, "    TRANSITION FROM B{i} TO A{i} := Go; END_TRANSITION");
    }
    s + "END_PROGRAM\n"
}

/// A ring of ten steps whose guards and N actions compute with integers and read step times.
fn arithmetic() -> String {
    let mut s = String::from(
        "PROGRAM Arith\n    VAR\n        Count : DINT;\n        Acc : DINT := 7;\n        Bits : WORD := 16#00FF;\n    END_VAR\n",
    );
    for i in 0..10 {
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        let _ = writeln!(s, "    {kw} S{i}: A{i}(N); END_STEP");
        let _ = writeln!(
            s,
            "    TRANSITION FROM S{i} TO S{} := (Count MOD 3 = {}) OR (Acc > 1000 AND S{i}.T >= T#20ms); END_TRANSITION",
            (i + 1) % 10,
            i % 3
        );
    }
    for i in 0..10 {
        let _ = writeln!(
            s,
            "    ACTION A{i}:\n        Count := Count + {};\n        Acc := (Acc * 31 + Count) MOD 100003;\n        Bits := ROL(Bits, 1) XOR WORD#{i};\n    END_ACTION",
            i + 1
        );
    }
    s + "END_PROGRAM\n"
}

/// A short sequence that ends in a step with a timeout it overruns, so the run reports it once
/// and then waits: its situation changes a bounded number of times.
fn ending() -> String {
    "PROGRAM Ending
    VAR
        Count : INT;
    END_VAR
    INITIAL_STEP Start: Tick(N); END_STEP
    TRANSITION FROM Start TO Middle := Count >= 3; END_TRANSITION
    STEP Middle: END_STEP
    TRANSITION FROM Middle TO Last := Middle.T >= T#50ms; END_TRANSITION
    {attribute 'sfc.timeout' := 'T#100ms'}
    STEP Last: END_STEP
    ACTION Tick:
        Count := Count + 1;
    END_ACTION
END_PROGRAM
"
    .to_string()
}

struct Dir(PathBuf);

impl Dir {
    fn new() -> Dir {
        let d = std::env::temp_dir().join(format!("sfc-alloc-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        Dir(d)
    }
    fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn sim(file: &Path, scans: u64, stats: bool, trace: Option<PathBuf>) -> u8 {
    sfc_cli::sim::sim(sfc_cli::sim::SimRequest {
        file: file.to_path_buf(),
        scenario: None,
        period: None,
        until: None,
        scans: Some(scans),
        trace,
        profile: None,
        pou: None,
        stats,
        stats_full: false,
        explain: false,
        json: false,
        set: Vec::new(),
    })
}

/// The arguments of a command as the binary parses them.
#[derive(clap::Parser)]
struct Args<T: clap::Args> {
    #[command(flatten)]
    args: T,
}

fn parse<T: clap::Args>(argv: &[&str]) -> T {
    use clap::Parser;
    Args::<T>::try_parse_from(std::iter::once("sfc").chain(argv.iter().copied())).expect("arguments").args
}

fn run(file: &Path, scans: u64) -> u8 {
    let file = file.to_string_lossy();
    let scans = scans.to_string();
    sfc_cli::run::run(parse(&[&file, "--period", "T#1ms", "--scans", &scans, "--no-retain"]))
}

fn test(dir: &Path) -> u8 {
    let dir = dir.to_string_lossy();
    sfc_cli::test::test(parse(&[&dir, "--coverage"]))
}

/// Runs `f(n)` and `f(2n)` and checks that the second allocates at most `slack` times more.
fn check(what: &str, n: u64, slack: u64, f: impl Fn(u64) -> u8, failures: &mut Vec<String>) {
    // A first run warms up what is allocated once per process (stdout's buffer, thread locals).
    let _ = f(n);
    let (s1, a1) = allocations(|| f(n));
    let (s2, a2) = allocations(|| f(2 * n));
    eprintln!("{what}: {a1} allocations for {n} scans, {a2} for {} scans", 2 * n);
    if s1 != 0 || s2 != 0 {
        failures.push(format!("{what}: exit status {s1} / {s2}"));
    }
    if a2 > a1 + slack {
        failures.push(format!(
            "{what}: {} more allocations for {n} more scans ({a1} for {n} scans, {a2} for {})",
            a2 - a1,
            2 * n
        ));
    }
}

#[test]
fn commands_that_run_charts_do_not_allocate_per_scan() {
    let dir = Dir::new();
    let dense = dir.write("loops.st", &loops(100));
    let arith = dir.write("arith.st", &arithmetic());
    let ending = dir.write("ending.st", &ending());
    let scenario = |scans: u64| {
        let d = dir.0.join(format!("scen-{scans}"));
        std::fs::create_dir_all(&d).unwrap();
        let chart = d.join("arith.st");
        std::fs::copy(&arith, &chart).unwrap();
        std::fs::write(
            d.join("arith.scenario.toml"),
            format!(
                "chart = \"arith.st\"\nscans = {scans}\n\n[[at]]\ntime = \"T#0s\"\nexpect = {{ active = [\"S0\"] }}\n"
            ),
        )
        .unwrap();
        d
    };
    let mut failures = Vec::new();
    let n = 2_000;
    check("sfc sim, dense chart", n, 8, |k| sim(&dense, k, false, None), &mut failures);
    check("sfc sim, ST actions", n, 8, |k| sim(&arith, k, false, None), &mut failures);
    check("sfc sim --stats, ending chart", n, 8, |k| sim(&ending, k, true, None), &mut failures);
    let trace = dir.0.join("trace.jsonl");
    check(
        "sfc sim --trace out.jsonl, dense chart",
        n,
        8,
        |k| sim(&dense, k, false, Some(trace.clone())),
        &mut failures,
    );
    let (d1, d2) = (scenario(n), scenario(2 * n));
    check("sfc test --coverage", n, 8, |k| test(if k == n { &d1 } else { &d2 }), &mut failures);
    // The run has its threads beside the scan thread, and on a loaded machine overruns (each
    // an event in the bounded log, which grows to its size): more slack, still far below one
    // allocation per scan.
    check("sfc run, dense chart", 500, 150, |k| run(&dense, k), &mut failures);
    check("sfc run, ST actions", 500, 150, |k| run(&arith, k), &mut failures);
    assert!(failures.is_empty(), "allocation per scan:\n{}", failures.join("\n"));
}
