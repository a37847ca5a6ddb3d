//! `cargo bench -p sfc-sim --bench scan`: cost of one scan on three chart families, in a release
//! build, through `Simulation::advance` (no trace records are built).
//!
//! * a ring of N steps with one token (N = 100 and 10,000): the cost must depend on the active
//!   steps, not on the chart size; the token moves every scan;
//! * K parallel two-step loops, all active (K = 1,000): cost per active step;
//! * a chart whose guards and actions do integer arithmetic.
//!
//! Under `cargo test` (no `--bench` argument) every case runs a few scans as a smoke test.

use sfc_sim::{SimOptions, Simulation, Value};
use std::fmt::Write;
use std::time::Instant;

/// A ring of `n` steps; each transition is `Go`, so the token moves every scan. With
/// `actions`, every step runs an N action with an ST body.
fn ring(n: usize, actions: bool) -> String {
    let mut s = String::from(
        "PROGRAM Ring\n    VAR_INPUT\n        Go : BOOL;\n    END_VAR\n    VAR\n        Count : DINT;\n    END_VAR\n\n",
    );
    for i in 0..n {
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        if actions {
            let _ = writeln!(s, "    {kw} S{i}:\n        A{i}(N);\n    END_STEP\n");
        } else {
            let _ = writeln!(s, "    {kw} S{i}: END_STEP\n");
        }
        let _ = writeln!(s, "    TRANSITION T{i} FROM S{i} TO S{}\n        := Go;\n    END_TRANSITION\n", (i + 1) % n);
    }
    if actions {
        for i in 0..n {
            let _ = writeln!(s, "    ACTION A{i}:\n        Count := Count + 1;\n    END_ACTION\n");
        }
    }
    s.push_str("END_PROGRAM\n");
    s
}

/// `k` independent loops of two steps, each its own network with an initial step.
fn loops(k: usize) -> String {
    let mut s = String::from("PROGRAM Loops\n    VAR_INPUT\n        Go : BOOL;\n    END_VAR\n\n");
    for i in 0..k {
        let _ = writeln!(s, "    INITIAL_STEP A{i}: END_STEP\n\n    STEP B{i}: END_STEP\n");
        let _ = writeln!(s, "    TRANSITION FROM A{i} TO B{i}\n        := Go;\n    END_TRANSITION\n");
        let _ = writeln!(s, "    TRANSITION FROM B{i} TO A{i}\n        := Go;\n    END_TRANSITION\n");
    }
    s.push_str("END_PROGRAM\n");
    s
}

/// A ten-step ring whose guards and actions compute with integers.
fn arithmetic() -> String {
    let mut s = String::from(
        "PROGRAM Arith\n    VAR\n        Count : DINT;\n        Acc : DINT := 7;\n        Small : INT;\n        Bits : WORD := 16#00FF;\n    END_VAR\n\n",
    );
    let n = 10;
    for i in 0..n {
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        let _ = writeln!(s, "    {kw} S{i}:\n        A{i}(N);\n    END_STEP\n");
        let _ = writeln!(
            s,
            "    TRANSITION FROM S{i} TO S{}\n        := (Count MOD 3 = {}) OR (Acc > 1000 AND S{i}.T >= T#20ms);\n    END_TRANSITION\n",
            (i + 1) % n,
            i % 3
        );
    }
    for i in 0..n {
        let _ = writeln!(
            s,
            "    ACTION A{i}:\n        Count := Count + {};\n        Acc := (Acc * 31 + Count) MOD 100003;\n        Small := Small + 1000;\n        Bits := ROL(Bits, 1) XOR WORD#{};\n    END_ACTION\n",
            i + 1,
            i
        );
    }
    s.push_str("END_PROGRAM\n");
    s
}

fn simulation(name: &str, text: &str) -> Simulation {
    let mut sim = match Simulation::from_source(name, text, None, SimOptions::default()) {
        Ok(s) => s,
        Err((file, diags)) => {
            let files = [file];
            let text: Vec<String> =
                diags.iter().map(|d| sfc_diagnostics::render_human(d, &files, Default::default())).collect();
            panic!("{name}: {}", text.join("\n"))
        }
    };
    if sim.type_of("Go").is_some() {
        sim.set("Go", Value::Bool(true)).expect("Go is an input");
    }
    sim
}

/// Median over `rounds` of the time per scan in ns, running `scans` scans per round.
fn measure(sim: &mut Simulation, scans: u64, rounds: usize) -> f64 {
    let mut per_scan = Vec::new();
    for _ in 0..rounds {
        let t = Instant::now();
        for _ in 0..scans {
            if let Err(e) = sim.advance() {
                panic!("runtime error: {}", e.message);
            }
        }
        per_scan.push(t.elapsed().as_secs_f64() * 1e9 / scans as f64);
    }
    per_scan.sort_by(f64::total_cmp);
    per_scan[per_scan.len() / 2]
}

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    // `cargo bench -p sfc-sim --bench scan -- ring-plain` runs only the cases whose name contains
    // the argument (`ring-plain`, `ring-actions`, `loops`, `arith`).
    let filter: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let wanted = |name: &str| filter.is_empty() || filter.iter().any(|f| name.contains(f.as_str()));
    let (scale, rounds) = if full { (1u64, 7) } else { (0, 1) };
    // SFC_BENCH_SCANS overrides the number of scans per round (e.g. small, under callgrind).
    let fixed: Option<u64> = std::env::var("SFC_BENCH_SCANS").ok().and_then(|v| v.parse().ok());
    let scans = |n: u64| fixed.unwrap_or(if scale == 0 { 20 } else { n });

    println!("sfc-sim scan benchmark ({} build)", if cfg!(debug_assertions) { "debug" } else { "release" });
    let mut ring_ns = Vec::new();
    for &(n, actions) in &[(100usize, false), (10_000, false), (100, true), (10_000, true)] {
        if !wanted(if actions { "ring-actions" } else { "ring-plain" }) {
            ring_ns.push(f64::NAN);
            continue;
        }
        let text = ring(n, actions);
        let mut sim = simulation("ring", &text);
        let _ = measure(&mut sim, scans(20_000), 1);
        let ns = measure(&mut sim, scans(2_000_000), rounds);
        let what = if actions { "with an N action per step" } else { "without actions" };
        println!("ring of {n:>6} steps, one token, {what}: {ns:8.1} ns/scan");
        ring_ns.push(ns);
    }
    println!(
        "  ring 10,000 vs 100 steps: {:+.1} % (without actions), {:+.1} % (with actions)",
        (ring_ns[1] / ring_ns[0] - 1.0) * 100.0,
        (ring_ns[3] / ring_ns[2] - 1.0) * 100.0
    );

    let k = if full { 1000 } else { 50 };
    if wanted("loops") {
        let mut sim = simulation("loops", &loops(k));
        let _ = measure(&mut sim, scans(200), 1);
        let ns = measure(&mut sim, scans(20_000), rounds);
        println!(
            "{k} parallel loops, all active, every token moving: {ns:10.1} ns/scan, {:6.2} ns per active step",
            ns / k as f64
        );
        // The same loops waiting: every step active, every guard tested and FALSE.
        sim.set("Go", Value::Bool(false)).expect("Go is an input");
        let ns = measure(&mut sim, scans(20_000), rounds);
        println!(
            "{k} parallel loops, all active, every guard FALSE: {ns:10.1} ns/scan, {:6.2} ns per active step",
            ns / k as f64
        );
    }
    if !wanted("arith") {
        return;
    }

    let mut sim = simulation("arith", &arithmetic());
    let _ = measure(&mut sim, scans(20_000), 1);
    let ns = measure(&mut sim, scans(1_000_000), rounds);
    println!("integer arithmetic chart (10 steps, ST guards and actions): {ns:8.1} ns/scan");
}
