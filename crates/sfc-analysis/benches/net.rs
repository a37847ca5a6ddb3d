//! `cargo bench -p sfc-analysis --bench net`: the net analysis on chart families, in a release
//! build, each through `check_source` and `analyze_net`.
//!
//! * `explicit`: the explicit search forced on a chart with a big finite state space (states/s);
//! * `matiec`: the largest chart of the MatIEC corpus (`shared/corpus/matiec/sfc.txt`);
//! * `loops-nested`: 40 parallel 10-step loops in a well-nested simultaneous block (certificate);
//! * `loops-irregular`: 40 parallel 10-step loops started by one divergence, never converging, with
//!   synchronising shortcuts between neighbours (not block-structured: symbolic search);
//! * `loops-unsafe`: the irregular loops with one jump from the last loop into the first (unsafe:
//!   symbolic search with a witness);
//! * `branches`: a 2,000-step chart with 200 alternative branches (certificate), and the same
//!   chart searched explicitly;
//! * `linear`: a ring and a set of 10 state machines of 1,000, 10,000 and 100,000 steps: the
//!   time per step stays flat (the analysis of such charts is linear).
//!
//! `cargo bench -p sfc-analysis --bench net -- loops` runs only the cases whose name contains the
//! argument. Under `cargo test --benches` (no `--bench` argument) every case runs once on smaller
//! charts as a smoke test. Peak memory is read from `/proc/self/status` (VmHWM).

/// The allocator of the `sfc` binary, so the figures are those `sfc check` sees.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use sfc_analysis::net::{analyze_net, analyze_net_with, Method, NetOptions, NetReport, Strategy};
use std::fmt::Write;
use std::time::Instant;

const HEADER: &str = "PROGRAM Bench\n    VAR_INPUT\n        Go : BOOL;\n    END_VAR\n\n";

fn step(s: &mut String, name: &str, initial: bool) {
    let kw = if initial { "INITIAL_STEP" } else { "STEP" };
    let _ = writeln!(s, "    {kw} {name}: END_STEP\n");
}

fn trans(s: &mut String, from: &[String], to: &[String]) {
    let list = |v: &[String]| if v.len() == 1 { v[0].clone() } else { format!("({})", v.join(", ")) };
    let _ = writeln!(s, "    TRANSITION FROM {} TO {}\n        := Go;\n    END_TRANSITION\n", list(from), list(to));
}

/// `k` loops of `len` steps started by one divergence. `converge`: each loop may leave from its
/// last step into one synchronisation back to the initial step (well-nested). Otherwise the loops
/// never converge and neighbours share a synchronising shortcut; with `unsafe_jump` the last loop
/// can also jump into the first one.
fn loops(k: usize, len: usize, converge: bool, unsafe_jump: bool) -> String {
    let mut s = String::from(HEADER);
    let n = |i: usize, j: usize| format!("L{i}_{j}");
    rings_from_init(&mut s, k, len);
    if !converge {
        for i in 0..k.saturating_sub(1) {
            let (a, b) = (len / 2, 1);
            trans(&mut s, &[n(i, a), n(i + 1, b)], &[n(i, a + 1), n(i + 1, b + 1)]);
        }
    }
    if converge {
        trans(&mut s, &(0..k).map(|i| n(i, len - 1)).collect::<Vec<_>>(), &["Init".into()]);
    }
    if unsafe_jump {
        trans(&mut s, &[n(k - 1, len - 1)], &[n(0, 0)]);
    }
    s.push_str("END_PROGRAM\n");
    s
}

/// `k` rings of `len` steps entered together from the initial step (for `k` = 1, the ring is
/// the initial step's own): each a state machine with one token.
fn rings(k: usize, len: usize) -> String {
    let mut s = String::from(HEADER);
    if k == 1 {
        let n = |j: usize| format!("R{j}");
        for j in 0..len {
            step(&mut s, &n(j), j == 0);
            trans(&mut s, &[n(j)], &[n((j + 1) % len)]);
        }
    } else {
        rings_from_init(&mut s, k, len);
    }
    s.push_str("END_PROGRAM\n");
    s
}

/// The initial step `Init` and `k` rings of `len` steps `L{i}_{j}` it enters together.
fn rings_from_init(s: &mut String, k: usize, len: usize) {
    let n = |i: usize, j: usize| format!("L{i}_{j}");
    step(s, "Init", true);
    trans(s, &["Init".into()], &(0..k).map(|i| n(i, 0)).collect::<Vec<_>>());
    for i in 0..k {
        for j in 0..len {
            step(s, &n(i, j), false);
            trans(s, &[n(i, j)], &[n(i, (j + 1) % len)]);
        }
    }
}

/// A chart of `branches` alternative branches of `len` steps between Choose and Merge.
fn branches(branches: usize, len: usize) -> String {
    let mut s = String::from(HEADER);
    step(&mut s, "Init", true);
    trans(&mut s, &["Init".into()], &["Choose".into()]);
    step(&mut s, "Choose", false);
    for b in 0..branches {
        let n = |j: usize| format!("B{b}_{j}");
        trans(&mut s, &["Choose".into()], &[n(0)]);
        for j in 0..len {
            step(&mut s, &n(j), false);
            let next = if j + 1 < len { n(j + 1) } else { "Merge".into() };
            trans(&mut s, &[n(j)], &[next]);
        }
    }
    step(&mut s, "Merge", false);
    trans(&mut s, &["Merge".into()], &["Init".into()]);
    s.push_str("END_PROGRAM\n");
    s
}

fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn chart_of(name: &str, text: &str) -> Option<sfc_model::Chart> {
    let checked = sfc_model::check_source(0, name, text, &sfc_model::CheckOptions::default());
    if let Some(d) = checked.diagnostics.iter().find(|d| d.is_error()) {
        println!("{name}: does not check: {}", d.message);
        return None;
    }
    checked.charts.into_iter().max_by_key(|c| c.steps.len())
}

fn summary(r: &NetReport) -> String {
    let method = match &r.method {
        Method::Empty => "empty".to_string(),
        Method::Structure => "structure".to_string(),
        Method::Explicit { states } => format!("explicit, {states} situations"),
        Method::Symbolic { states } => format!("symbolic, {states:.3e} situations"),
    };
    format!(
        "{method}{}; {} unsafe, {} unreachable, {} dead, {} lock-ups",
        if r.complete { "" } else { ", INCOMPLETE" },
        r.unsafe_steps.len(),
        r.unreachable.len(),
        r.dead.len(),
        r.lockups.len()
    )
}

/// Median wall time in ms over `runs` analyses, and the last report.
fn time(chart: &sfc_model::Chart, strategy: Strategy, runs: usize) -> (f64, NetReport) {
    let opts = NetOptions::default();
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..runs {
        let t = Instant::now();
        let r = if strategy == Strategy::Auto {
            analyze_net(chart, &opts)
        } else {
            analyze_net_with(chart, &opts, strategy)
        };
        times.push(t.elapsed().as_secs_f64() * 1e3);
        last = Some(r);
    }
    times.sort_by(f64::total_cmp);
    let Some(r) = last else { unreachable!("runs >= 1") };
    (times[times.len() / 2], r)
}

fn case(label: &str, text: &str, strategy: Strategy, runs: usize) -> Option<(f64, NetReport)> {
    let chart = chart_of(label, text)?;
    let (ms, r) = time(&chart, strategy, runs);
    println!(
        "{label}: {} steps, {} transitions: {ms:9.2} ms  ({})",
        chart.steps.len(),
        chart.transitions.len(),
        summary(&r)
    );
    Some((ms, r))
}

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let filter: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let wanted = |name: &str| filter.is_empty() || filter.iter().any(|f| name.contains(f.as_str()));
    let runs = if full { 5 } else { 1 };
    println!("sfc-analysis net benchmark ({} build)", if cfg!(debug_assertions) { "debug" } else { "release" });

    if wanted("explicit") {
        // 7 loops of 7 steps with shortcuts: 7^7 + 1 = 823,544 situations.
        let (k, len) = if full { (7, 7) } else { (3, 5) };
        if let Some((ms, r)) = case("explicit (forced)", &loops(k, len, false, false), Strategy::Explicit, runs) {
            if let Method::Explicit { states } = r.method {
                println!("  explicit search: {:.2} M situations/s", states as f64 / ms / 1e3);
            }
        }
    }
    if wanted("matiec") {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/corpus/matiec/sfc.txt");
        match std::fs::read_to_string(path) {
            Ok(text) => {
                let _ = case("matiec corpus (largest chart)", &text, Strategy::Auto, runs);
            }
            Err(_) => println!("matiec corpus: skipped ({path} not found)"),
        }
    }
    let k = if full { 40 } else { 6 };
    if wanted("loops-nested") {
        let _ =
            case(&format!("{k} parallel 10-step loops, well-nested"), &loops(k, 10, true, false), Strategy::Auto, runs);
    }
    if wanted("loops-irregular") {
        let label = format!("{k} parallel 10-step loops, irregular");
        if let Some((ms, _)) = case(&label, &loops(k, 10, false, false), Strategy::Auto, runs) {
            if full {
                println!("  target < 2000 ms: {}", if ms < 2000.0 { "met" } else { "MISSED" });
            }
        }
    }
    if wanted("loops-unsafe") {
        let _ =
            case(&format!("{k} parallel 10-step loops, unsafe jump"), &loops(k, 10, false, true), Strategy::Auto, runs);
    }
    if wanted("branches") {
        let (b, len) = if full { (200, 10) } else { (20, 5) };
        let text = branches(b, len);
        if let Some((ms, _)) = case(&format!("{b} alternative branches"), &text, Strategy::Auto, runs) {
            if full {
                println!("  target < 1000 ms: {}", if ms < 1000.0 { "met" } else { "MISSED" });
            }
        }
        let _ = case(&format!("{b} alternative branches (explicit)"), &text, Strategy::Explicit, runs);
    }
    if wanted("linear") {
        // A ring, and a set of state machines (one divergence into 10 rings that never meet
        // again), at growing sizes: proved by structure, in time proportional to the steps.
        let sizes: &[usize] = if full { &[1_000, 10_000, 100_000] } else { &[100, 1_000] };
        for &n in sizes {
            for (what, text) in [("ring", rings(1, n)), ("10 state machines", rings(10, n / 10))] {
                if let Some((ms, _)) = case(&format!("linear: {what} of {n} steps"), &text, Strategy::Auto, runs) {
                    println!("  {:.3} µs per step", ms * 1e3 / n as f64);
                }
            }
        }
    }
    if let Some(kib) = peak_rss_kib() {
        println!("peak memory (VmHWM): {:.1} MiB", kib as f64 / 1024.0);
    }
}
