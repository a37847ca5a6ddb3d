//! `cargo bench -p sfc-model --bench check`: time and peak memory of `sfc check` on generated
//! charts. Each case runs in a child process so its peak resident memory is its own.
//! Under `cargo test` (no `--bench` argument) the cases run once at a small size, as a smoke test.

use std::fmt::Write;
use std::time::Instant;

/// A ring of `n` steps with a selection branch every tenth step, an action with an ST body per
/// step, timers and integer arithmetic: the shape of a long real sequence.
fn chart(n: usize) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "PROGRAM Big\n    VAR_INPUT\n        Go : BOOL;\n        Level : INT;\n    END_VAR\n    VAR\n        Count : DINT;\n        Timer : TON;\n        Out : BOOL;\n    END_VAR\n");
    for i in 0..n {
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        let _ = writeln!(s, "    {kw} S{i}:\n        A{i}(N);\n    END_STEP\n");
        let _ = writeln!(s, "    ACTION A{i}:\n        Count := Count + {i};\n        Timer(IN := TRUE, PT := T#1s);\n        Out := Timer.Q AND Level > {};\n    END_ACTION\n", i % 100);
        let next = (i + 1) % n;
        if i % 10 == 5 && i + 2 < n {
            let _ = writeln!(
                s,
                "    TRANSITION FROM S{i} TO S{}\n        := Go AND Level > {};\n    END_TRANSITION\n",
                i + 2,
                i % 50
            );
            let _ = writeln!(
                s,
                "    TRANSITION FROM S{i} TO S{next}\n        := NOT Go AND S{i}.T >= T#100ms;\n    END_TRANSITION\n"
            );
        } else {
            let _ = writeln!(
                s,
                "    TRANSITION FROM S{i} TO S{next}\n        := Go OR S{i}.T >= T#{}ms;\n    END_TRANSITION\n",
                10 + i % 90
            );
        }
    }
    s.push_str("END_PROGRAM\n");
    s
}

/// A file of about `lines` lines: the chart above, grown until it is long enough.
fn long_file(lines: usize) -> String {
    let mut n = lines / 16;
    loop {
        let c = chart(n);
        if c.lines().count() >= lines {
            return c;
        }
        n += n / 10 + 1;
    }
}

fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn run_case(name: &str, text: &str, runs: usize) -> f64 {
    let opts = sfc_model::CheckOptions { analysis: true, ..Default::default() };
    let mut times = Vec::new();
    for _ in 0..runs {
        let t = Instant::now();
        let checked = sfc_model::check_source(0, name, text, &opts);
        times.push(t.elapsed().as_secs_f64() * 1e3);
        assert!(!checked.has_errors(), "generated chart must be valid: {:?}", checked.diagnostics.first());
        std::hint::black_box(checked);
    }
    times.sort_by(|a, b| a.total_cmp(b));
    times[times.len() / 2]
}

fn case_text(case: &str, small: bool) -> String {
    match (case, small) {
        ("steps", false) => chart(10_000),
        ("lines", false) => long_file(100_000),
        ("steps", true) => chart(100),
        _ => long_file(1_000),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--case") {
        // Child: one case, full size; print "median_ms peak_kib lines".
        let case = args.get(i + 1).map(String::as_str).unwrap_or("steps");
        let text = case_text(case, false);
        let ms = run_case(case, &text, 5);
        println!("{ms:.1} {} {}", peak_rss_kib().unwrap_or(0), text.lines().count());
        return;
    }
    if !args.iter().any(|a| a == "--bench") {
        for case in ["steps", "lines"] {
            run_case(case, &case_text(case, true), 1);
        }
        println!("check bench: smoke run passed (use `cargo bench` for figures)");
        return;
    }
    println!("sfc check, release build, median of 5 runs (peak memory of the whole process, text included)");
    for (case, what, target) in
        [("steps", "10,000-step chart", "target < 200 ms, < 100 MB"), ("lines", "100,000-line file", "no target")]
    {
        let exe = std::env::current_exe().expect("own executable");
        let out = std::process::Command::new(exe).args(["--case", case]).output().expect("child run");
        let line = String::from_utf8_lossy(&out.stdout);
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 3 || !out.status.success() {
            println!("{what}: failed: {}", String::from_utf8_lossy(&out.stderr));
            continue;
        }
        let kib: f64 = f[1].parse().unwrap_or(0.0);
        println!("{what} ({} lines): {} ms, peak {:.1} MB   [{target}]", f[2], f[0], kib / 1024.0);
    }
}
