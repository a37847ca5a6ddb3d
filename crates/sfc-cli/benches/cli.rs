//! `cargo bench -p sfc-cli --bench cli`: what users run, next to the engine. For the two charts
//! of issue 16 (a ring of 1,000 steps with one token, and 1,000 two-step loops with every token
//! moving every scan) it prints, per scan:
//!
//! * the engine: `Simulation::advance` in a loop (what `cargo bench -p sfc-sim --bench scan`
//!   measures);
//! * `sfc sim`, `sfc sim --stats` (time analysis and the sequence of situations) and
//!   `sfc test --coverage` (a scenario, with coverage), each run as the `sfc` binary for N and
//!   for 2N scans: the difference divided by N is the cost of a scan,
//!   without the start-up (reading, checking and compiling the chart);
//! * `sfc run`: the scan time p50 the runtime reports (`scan time p50 … µs`) at a 20 µs and at
//!   a 1 ms period, each beside the engine paced the same way (`Simulation::advance` once per
//!   deadline, asleep between scans, p50). A scan that starts after a sleep finds the engine's
//!   data out of the caches: on this VM the engine alone then costs 1.2-1.8 times its
//!   back-to-back figure on the loops, and 10-30 times on the ring (whose scan is 0.1 µs).
//!
//! Under `cargo test` (no `--bench` argument) every case runs a few scans as a smoke test.

use sfc_sim::{SimOptions, Simulation, Value};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const SFC: &str = env!("CARGO_BIN_EXE_sfc");

/// A ring of `n` steps; each transition is `Go`, so the token moves every scan.
fn ring(n: usize) -> String {
    let mut s = String::from("PROGRAM Ring\n    VAR\n        Go : BOOL := TRUE;\n    END_VAR\n");
    for i in 0..n {
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        let _ = writeln!(s, "    {kw} S{i}: END_STEP");
        let _ = writeln!(s, "    TRANSITION T{i} FROM S{i} TO S{} := Go; END_TRANSITION", (i + 1) % n);
    }
    s + "END_PROGRAM\n"
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

/// The chart compiled for the engine, with `Go` TRUE.
fn simulation(name: &str, text: &str) -> Simulation {
    let mut sim = match Simulation::from_source(name, text, None, SimOptions::default()) {
        Ok(s) => s,
        Err((_, d)) => panic!("{name}: {:?}", d.first().map(|d| &d.message)),
    };
    sim.set("Go", Value::Bool(true)).expect("Go");
    sim
}

/// Median ns per scan of `Simulation::advance` over `rounds` rounds of `scans` scans.
fn engine(name: &str, text: &str, scans: u64, rounds: usize) -> f64 {
    let mut sim = simulation(name, text);
    let mut per = Vec::new();
    for _ in 0..=rounds {
        let t = Instant::now();
        for _ in 0..scans {
            if let Err(e) = sim.advance() {
                panic!("{name}: {}", e.message);
            }
        }
        per.push(t.elapsed().as_secs_f64() * 1e9 / scans as f64);
    }
    per.remove(0); // warm-up
    median(per)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Wall time of `sfc args…` in seconds (output discarded); panics when it fails.
fn wall(args: &[&str]) -> f64 {
    let t = Instant::now();
    let out = Command::new(SFC).args(args).output().expect("run sfc");
    let s = t.elapsed().as_secs_f64();
    assert!(out.status.success(), "sfc {}: {}", args.join(" "), String::from_utf8_lossy(&out.stderr));
    s
}

/// ns per scan of a command that takes `--scans N`-like arguments: `(make(2n) − make(n)) / n`,
/// median over `rounds`.
fn per_scan(n: u64, rounds: usize, make: impl Fn(u64) -> Vec<String>) -> f64 {
    let run = |k: u64| {
        let args = make(k);
        wall(&args.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let _ = run(n); // warm the page cache
    let per: Vec<f64> = (0..rounds).map(|_| (run(2 * n) - run(n)) * 1e9 / n as f64).collect();
    median(per)
}

/// p50 in ns of `Simulation::advance` called once per `period_us` deadline (asleep between
/// scans, as the runtime's scan thread is), over `scans` scans.
fn engine_paced(name: &str, text: &str, period_us: u64, scans: u64) -> f64 {
    let mut sim = simulation(name, text);
    let period = std::time::Duration::from_micros(period_us);
    let mut next = Instant::now() + period;
    let mut took = Vec::with_capacity(scans as usize);
    for _ in 0..scans {
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        next += period;
        let t = Instant::now();
        if let Err(e) = sim.advance() {
            panic!("{name}: {}", e.message);
        }
        took.push(t.elapsed().as_nanos() as f64);
    }
    median(took)
}

/// `sfc run --scans n --period <period>`: the scan time p50 it reports, in ns.
fn run_p50(chart: &Path, period: &str, n: u64) -> f64 {
    let out = Command::new(SFC)
        .args(["run", &chart.to_string_lossy(), "--period", period, "--no-retain", "--scans", &n.to_string()])
        .output()
        .expect("run sfc");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "sfc run: {err}");
    // `… scan time p50 1.2 µs, p99 …`
    err.lines()
        .find_map(|l| l.split("scan time p50 ").nth(1))
        .and_then(|rest| rest.split(' ').next())
        .and_then(|v| v.parse::<f64>().ok())
        .map_or(f64::NAN, |us| us * 1000.0)
}

fn scenario(dir: &Path, chart: &str, scans: u64) -> PathBuf {
    let d = dir.join(format!("{chart}-{scans}"));
    std::fs::create_dir_all(&d).expect("scenario dir");
    std::fs::copy(dir.join(format!("{chart}.st")), d.join(format!("{chart}.st"))).expect("copy chart");
    std::fs::write(
        d.join(format!("{chart}.scenario.toml")),
        format!("chart = \"{chart}.st\"\nperiod = \"T#10ms\"\nscans = {scans}\n"),
    )
    .expect("scenario");
    d
}

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let dir = std::env::temp_dir().join(format!("sfc-bench-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let (size, n, rounds) = if full { (1000, 20_000u64, 5) } else { (20, 20, 1) };
    println!("sfc CLI benchmark ({} build), ns per scan", if cfg!(debug_assertions) { "debug" } else { "release" });
    println!(
        "{:<40} {:>10} {:>12} {:>12} {:>14} {:>12} {:>12} {:>12} {:>12}",
        "chart", "engine", "sim", "sim --stats", "test --cov.", "engine@20µs", "run@20µs", "engine@1ms", "run@1ms"
    );
    // The ring's scans are cheap: many more of them, so the difference dwarfs the start-up noise.
    let charts = [
        ("ring", format!("ring of {size} steps, one token"), ring(size), if full { 50 } else { 1 }),
        ("loops", format!("{size} two-step loops, all moving"), loops(size), 1),
    ];
    for (name, title, text, more) in charts {
        let n = n * more;
        let chart = dir.join(format!("{name}.st"));
        std::fs::write(&chart, &text).expect("chart");
        let c = chart.to_string_lossy().to_string();
        let eng = engine(name, &text, if full { n.max(200_000) } else { n }, rounds);
        let stats =
            per_scan(n, rounds, |k| ["sim", &c, "--stats", "--scans", &k.to_string()].map(String::from).to_vec());
        let plain = per_scan(n, rounds, |k| ["sim", &c, "--scans", &k.to_string()].map(String::from).to_vec());
        let (s1, s2) = (scenario(&dir, name, n), scenario(&dir, name, 2 * n));
        let test = per_scan(n, rounds, |k| {
            let d = if k == n { &s1 } else { &s2 };
            ["test".to_string(), d.to_string_lossy().to_string(), "--coverage".to_string()].to_vec()
        });
        let (few, many) = if full { (3_000, 20_000) } else { (5, 20) };
        let paced_fast = engine_paced(name, &text, 20, many);
        let run_fast = run_p50(&chart, "T#20us", many);
        let paced = engine_paced(name, &text, 1_000, few);
        let run = run_p50(&chart, "T#1ms", few);
        println!(
            "{title:<40} {eng:>10.1} {plain:>12.1} {stats:>12.1} {test:>14.1} {paced_fast:>12.1} {run_fast:>12.1} {paced:>12.1} {run:>12.1}"
        );
        println!(
            "{:<40} {:>10} {:>12.2} {:>12.2} {:>14.2} {:>12.2} {:>12.2} {:>12.2} {:>12.2}",
            "  ratio to the engine",
            "1",
            plain / eng,
            stats / eng,
            test / eng,
            paced_fast / eng,
            run_fast / eng,
            paced / eng,
            run / eng
        );
        println!(
            "{:<40} {:>10} {:>12} {:>12} {:>14} {:>12} {:>12.2} {:>12} {:>12.2}",
            "  ratio to the engine at that period",
            "",
            "",
            "",
            "",
            "1",
            run_fast / paced_fast,
            "1",
            run / paced
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
