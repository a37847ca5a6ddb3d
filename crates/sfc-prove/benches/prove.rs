//! `cargo bench -p sfc-prove --bench prove`: time and peak memory of `sfc prove` on the three
//! cases of the issue — the car wash with 5 properties, 40 synchronised parallel loops with an
//! invariant over two of them, a 200-step chart with integer counters in 0..1000 (targets:
//! each under 1 s and 500 MB). Each case runs in a child process so its peak resident memory
//! is its own. Under `cargo test` (no `--bench` argument) the cases run once, smaller, as a
//! smoke test.

use std::fmt::Write;
use std::time::Instant;

/// `n` loops of `m` steps, started together, advancing together on `Tick`, and joined by one
/// synchronisation back to their first steps.
fn loops(n: usize, m: usize) -> (String, String) {
    let mut s = String::from("PROGRAM Loops\n    VAR_INPUT\n        Go : BOOL;\n        Tick : BOOL;\n    END_VAR\n\n    INITIAL_STEP Init: END_STEP\n");
    let firsts: Vec<String> = (1..=n).map(|i| format!("L{i}_0")).collect();
    let lasts: Vec<String> = (1..=n).map(|i| format!("L{i}_{}", m - 1)).collect();
    let _ =
        writeln!(s, "    TRANSITION TStart FROM Init TO ({})\n        := Go;\n    END_TRANSITION", firsts.join(", "));
    for i in 1..=n {
        for j in 0..m {
            let _ = writeln!(s, "    STEP L{i}_{j}: END_STEP");
        }
        for j in 0..m - 1 {
            let _ = writeln!(s, "    TRANSITION FROM L{i}_{j} TO L{i}_{}\n        := Tick;\n    END_TRANSITION", j + 1);
        }
    }
    let _ = writeln!(
        s,
        "    TRANSITION TSync FROM ({}) TO ({})\n        := Tick;\n    END_TRANSITION",
        lasts.join(", "),
        firsts.join(", ")
    );
    s.push_str("END_PROGRAM\n");
    let props = "[[property]]\nname = \"loops 1 and 2 in step\"\nalways = \"L1_3.X = L2_3.X\"\n".to_string();
    (s, props)
}

/// A ring of `n` steps; every tenth counts a part (P1, capped at 1000), every tenth checks it
/// (a reject, never more than the parts), a batch counter wraps at 100.
fn line(n: usize) -> (String, String) {
    let mut s = String::from("PROGRAM Line\n    VAR_INPUT\n        Next : BOOL;\n        Bad : BOOL;\n    END_VAR\n    VAR\n        Parts : INT;\n        Rejects : INT;\n        Batch : INT;\n    END_VAR\n\n");
    let mut actions = String::new();
    for k in 0..n {
        let kw = if k == 0 { "INITIAL_STEP" } else { "STEP" };
        let body = match k % 10 {
            5 => {
                let _ = writeln!(actions, "    ACTION Count{k}:\n        IF Parts < 1000 THEN\n            Parts := Parts + 1;\n        END_IF;\n        Batch := (Batch + 1) MOD 100;\n    END_ACTION");
                format!("        Count{k}(P1);\n")
            }
            7 => {
                let _ = writeln!(actions, "    ACTION Check{k}:\n        IF Bad AND Rejects < Parts THEN\n            Rejects := Rejects + 1;\n        END_IF;\n    END_ACTION");
                format!("        Check{k}(P1);\n")
            }
            _ => String::new(),
        };
        let _ = writeln!(s, "    {kw} S{k}:\n{body}    END_STEP");
        let _ = writeln!(s, "    TRANSITION FROM S{k} TO S{}\n        := Next;\n    END_TRANSITION", (k + 1) % n);
    }
    s.push_str(&actions);
    s.push_str("END_PROGRAM\n");
    let props = "[assume]\nranges = { Parts = \"0..1000\", Rejects = \"0..1000\", Batch = \"0..99\" }\n\n[[property]]\nname = \"no more rejects than parts\"\nalways = \"Rejects <= Parts\"\n".to_string();
    (s, props)
}

fn carwash() -> (String, String) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let chart = std::fs::read_to_string(root.join("tests/fixtures/carwash.st")).expect("car wash");
    let props = std::fs::read_to_string(root.join("tests/fixtures/carwash.props.toml")).expect("car wash props");
    (chart, props)
}

fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn case(name: &str, small: bool) -> (String, String) {
    match (name, small) {
        ("carwash", _) => carwash(),
        ("loops", false) => loops(40, 10),
        ("loops", true) => loops(4, 5),
        ("line", false) => line(200),
        _ => line(20),
    }
}

/// Runs one case in this process and prints `name seconds KiB verdicts`.
fn run_one(name: &str, small: bool) {
    let (chart, props) = case(name, small);
    let file = sfc_prove::props::parse(&format!("{name}.props.toml"), &props).expect("property file");
    let t = Instant::now();
    let report =
        sfc_prove::prove(&format!("{name}.st"), &chart, &file, &sfc_prove::Options::default()).expect("proves");
    let secs = t.elapsed().as_secs_f64();
    let verdicts: Vec<String> = report.properties.iter().map(|p| format!("{}={}", p.name, p.verdict.name())).collect();
    println!("{name} {secs:.3} {} {}", peak_rss_kib().unwrap_or(0), verdicts.join("; "));
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(pos) = args.iter().position(|a| a == "--case") {
        let name = args.get(pos + 1).cloned().unwrap_or_default();
        run_one(&name, args.iter().any(|a| a == "--small"));
        return;
    }
    let bench = args.iter().any(|a| a == "--bench");
    let exe = std::env::current_exe().expect("own path");
    println!("sfc prove: time and peak memory per case ({})", if bench { "full size" } else { "smoke test, small" });
    for name in ["carwash", "loops", "line"] {
        let mut cmd = std::process::Command::new(&exe);
        cmd.arg("--case").arg(name);
        if !bench {
            cmd.arg("--small");
        }
        let out = cmd.output().expect("child");
        let text = String::from_utf8_lossy(&out.stdout);
        let line = text.lines().last().unwrap_or("");
        let mut parts = line.splitn(4, ' ');
        let (n, secs, kib, verdicts) = (
            parts.next().unwrap_or(name),
            parts.next().unwrap_or("?"),
            parts.next().unwrap_or("0"),
            parts.next().unwrap_or(""),
        );
        let mib = kib.parse::<f64>().unwrap_or(0.0) / 1024.0;
        let label = match n {
            "carwash" => "car wash, 5 properties",
            "loops" => "40 synchronised loops, invariant over two",
            _ => "200-step chart, counters in 0..1000",
        };
        println!("  {label:<44} {secs:>7} s  {mib:>7.1} MiB peak  (targets: 1 s, 500 MB)");
        println!("      {verdicts}");
        if !out.status.success() {
            eprintln!("{}", String::from_utf8_lossy(&out.stderr));
            std::process::exit(1);
        }
    }
}
