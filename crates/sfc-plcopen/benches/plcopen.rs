//! `cargo bench -p sfc-plcopen --bench plcopen`: time of the PLCopen export and import of a
//! 500-step chart (the target is under 200 ms each). Under `cargo test` (no `--bench`
//! argument) it runs once on a small chart, as a smoke test. `N=2000 cargo bench …` changes
//! the number of steps.

use std::fmt::Write;
use std::time::Instant;

/// A ring of `n` steps with a selection branch every tenth step, a loop back, an action with
/// an ST body per step, timed associations: the shape of a long real sequence.
fn chart(n: usize) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "PROGRAM Big\n    VAR_INPUT\n        Go : BOOL;\n        Level : INT;\n    END_VAR\n    VAR\n        Count : DINT;\n        Timer : TON;\n        Out : BOOL;\n    END_VAR\n");
    for i in 0..n {
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        let _ = writeln!(s, "    {kw} S{i}:\n        A{i}(N);\n        Out(L, T#{}ms);\n    END_STEP\n", 10 + i % 90);
        let _ = writeln!(
            s,
            "    ACTION A{i}:\n        Count := Count + {i};\n        Timer(IN := TRUE, PT := T#1s);\n    END_ACTION\n"
        );
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

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let bench = std::env::args().any(|a| a == "--bench");
    let (n, runs) =
        if bench { (std::env::var("N").ok().and_then(|v| v.parse().ok()).unwrap_or(500), 9) } else { (50, 1) };
    let text = chart(n);
    let checked = sfc_model::check_source(0, "big.st", &text, &Default::default());
    assert!(!checked.has_errors(), "generated chart must check: {:?}", checked.diagnostics.first());

    let mut export_ms = Vec::new();
    let mut xml = String::new();
    for _ in 0..runs {
        let t = Instant::now();
        xml = sfc_plcopen::export(&checked).expect("the chart exports");
        export_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let mut import_ms = Vec::new();
    let mut check_ms = Vec::new();
    for _ in 0..runs {
        let t = Instant::now();
        let imported = sfc_plcopen::import(0, "big.xml", &xml);
        import_ms.push(t.elapsed().as_secs_f64() * 1e3);
        assert!(imported.diagnostics.is_empty(), "{:?}", imported.diagnostics.first());
        let t = Instant::now();
        let (_, again, diags) = sfc_plcopen::check_xml(0, "big.xml", &xml, &Default::default());
        check_ms.push(t.elapsed().as_secs_f64() * 1e3);
        assert!(!diags.iter().any(|d| d.is_error()), "{:?}", diags.first());
        assert_eq!(again.charts[0].steps.len(), n);
    }
    let (e, i, c) = (median(export_ms), median(import_ms), median(check_ms));
    println!("plcopen: {n} steps, {} KiB of XML", xml.len() / 1024);
    println!("  export              {e:8.1} ms");
    println!("  import (XML → text) {i:8.1} ms");
    println!("  import + check      {c:8.1} ms");
    if bench && (e >= 200.0 || i >= 200.0) {
        println!("  over the 200 ms target");
        std::process::exit(1);
    }
}
