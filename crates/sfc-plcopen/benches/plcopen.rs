//! `cargo bench -p sfc-plcopen --bench plcopen`: time of the PLCopen export and import of a
//! 500-step chart (the target is under 200 ms each). Under `cargo test` (no `--bench`
//! argument) it runs once on a small chart, as a smoke test. `N=2000 cargo bench …` changes
//! the number of steps.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

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

/// A PLCopen file of `n` steps in a loop whose every condition is an FBD network wired to the
/// transition (Beremiz's shape): `(A_k AND NOT B) OR (C AND A_k)`, the OR's inputs sharing `A_k`.
fn fbd_chart(n: usize) -> String {
    let mut els = String::new();
    let mut id = 1usize;
    let mut next = || {
        id += 1;
        id
    };
    let var = |id: usize, e: &str| {
        format!(
            r#"<inVariable localId="{id}" height="30" width="40"><position x="300" y="10"/><connectionPointOut><relPosition x="40" y="15"/></connectionPointOut><expression>{e}</expression></inVariable>"#
        )
    };
    let block = |id: usize, ty: &str, ins: &[(usize, bool)]| {
        let mut b = format!(
            r#"<block localId="{id}" typeName="{ty}" height="60" width="60"><position x="400" y="10"/><inputVariables>"#
        );
        for (k, (r, neg)) in ins.iter().enumerate() {
            let n = if *neg { r#" negated="true""# } else { "" };
            let _ = write!(
                b,
                r#"<variable formalParameter="IN{}"{n}><connectionPointIn><relPosition x="0" y="30"/><connection refLocalId="{r}"/></connectionPointIn></variable>"#,
                k + 1
            );
        }
        b.push_str(r#"</inputVariables><inOutVariables/><outputVariables><variable formalParameter="OUT"><connectionPointOut><relPosition x="60" y="30"/></connectionPointOut></variable></outputVariables></block>"#);
        b
    };
    let mut prev_step = 0;
    let first_step = next();
    for i in 0..n {
        let step = if i == 0 { first_step } else { next() };
        let initial = if i == 0 { "true" } else { "false" };
        let conn = if i == 0 {
            String::new()
        } else {
            format!(
                r#"<connectionPointIn><relPosition x="45" y="0"/><connection refLocalId="{prev_step}"/></connectionPointIn>"#
            )
        };
        let _ = write!(
            els,
            r#"<step localId="{step}" name="S{i}" initialStep="{initial}" height="30" width="90"><position x="100" y="{}"/>{conn}<connectionPointOut formalParameter=""><relPosition x="45" y="30"/></connectionPointOut></step>"#,
            20 + i * 80
        );
        let (a, b, c) = (next(), next(), next());
        els.push_str(&var(a, &format!("A{}", i % 16)));
        els.push_str(&var(b, "B"));
        els.push_str(&var(c, "C"));
        let and1 = next();
        els.push_str(&block(and1, "AND", &[(a, false), (b, true)]));
        let and2 = next();
        els.push_str(&block(and2, "AND", &[(c, false), (a, false)]));
        let or = next();
        els.push_str(&block(or, "OR", &[(and1, false), (and2, false)]));
        let tr = next();
        let _ = write!(
            els,
            r#"<transition localId="{tr}" height="2" width="20"><position x="135" y="{}"/><connectionPointIn><relPosition x="10" y="0"/><connection refLocalId="{step}"/></connectionPointIn><connectionPointOut><relPosition x="10" y="2"/></connectionPointOut><condition><connectionPointIn><connection refLocalId="{or}"/></connectionPointIn></condition></transition>"#,
            60 + i * 80
        );
        prev_step = tr;
    }
    let j = next();
    let _ = write!(
        els,
        r#"<jumpStep localId="{j}" targetName="S0" height="13" width="12"><position x="139" y="{}"/><connectionPointIn><relPosition x="6" y="0"/><connection refLocalId="{prev_step}"/></connectionPointIn></jumpStep>"#,
        40 + n * 80
    );
    let mut vars = String::new();
    for k in 0..16 {
        let _ = write!(vars, r#"<variable name="A{k}"><type><BOOL/></type></variable>"#);
    }
    format!(
        r#"<?xml version='1.0' encoding='utf-8'?><project xmlns="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml"><fileHeader companyName="Beremiz" productName="Beremiz" productVersion="1" creationDateTime="2024-01-01T00:00:00"/><contentHeader name="big"><coordinateInfo><fbd><scaling x="0" y="0"/></fbd><ld><scaling x="0" y="0"/></ld><sfc><scaling x="0" y="0"/></sfc></coordinateInfo></contentHeader><types><dataTypes/><pous><pou name="Big" pouType="program"><interface><localVars>{vars}<variable name="B"><type><BOOL/></type></variable><variable name="C"><type><BOOL/></type></variable></localVars></interface><body><SFC>{els}</SFC></body></pou></pous></types><instances><configurations/></instances></project>"#
    )
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

    // The same number of steps with every condition an FBD network (sharing an operand).
    let fbd = fbd_chart(n);
    let (mut fi, mut fc) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let t = Instant::now();
        let imported = sfc_plcopen::import(0, "fbd.xml", &fbd);
        fi.push(t.elapsed().as_secs_f64() * 1e3);
        assert!(!imported.diagnostics.iter().any(|d| d.is_error()), "{:?}", imported.diagnostics.first());
        let t = Instant::now();
        let (_, again, diags) = sfc_plcopen::check_xml(0, "fbd.xml", &fbd, &Default::default());
        fc.push(t.elapsed().as_secs_f64() * 1e3);
        assert!(!diags.iter().any(|d| d.is_error()), "{:?}", diags.iter().find(|d| d.is_error()));
        assert_eq!(again.charts[0].steps.len(), n);
    }
    println!("plcopen: {n} steps with FBD conditions, {} KiB of XML", fbd.len() / 1024);
    println!("  import (XML → text) {:8.1} ms", median(fi));
    println!("  import + check      {:8.1} ms", median(fc));
    if bench && (e >= 200.0 || i >= 200.0) {
        println!("  over the 200 ms target");
        std::process::exit(1);
    }
}
