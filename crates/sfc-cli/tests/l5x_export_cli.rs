//! `sfc build --target l5x` through the binary: an IEC chart written as an L5X SFC routine runs
//! as the chart did under the `logix` profile (the L5X runs with it by itself), an L5X fixture
//! written back runs as the fixture did, the way on to PLCopen and ST from an L5X file, and what
//! Logix cannot hold refused with located errors and no file written.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sfc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).output().expect("sfc runs")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-l5x-export-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// The trace of a simulation as rows of (column → value).
fn trace(file: &Path, scenario: &Path, profile: Option<&str>, out: &Path) -> Vec<Vec<(String, String)>> {
    let mut args = vec!["sim", file.to_str().unwrap(), "--scenario", scenario.to_str().unwrap()];
    if let Some(p) = profile {
        args.extend(["--profile", p]);
    }
    args.extend(["--trace", out.to_str().unwrap()]);
    let o = sfc(&args);
    // A scenario's expectations may fail (they were derived under IEC's rules); the trace is
    // written all the same and is what is compared.
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}: {}", file.display(), text(&o));
    let csv = std::fs::read_to_string(out).unwrap();
    let mut lines = csv.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    lines.map(|l| head.iter().cloned().zip(l.split(',').map(str::to_string)).collect()).collect()
}

/// The columns both traces have, except `skip`, compared row by row.
fn same_trace(a: &[Vec<(String, String)>], b: &[Vec<(String, String)>], skip: &[&str], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: number of scans");
    assert!(!a.is_empty(), "{what}: empty trace");
    let shared: Vec<String> = a[0]
        .iter()
        .map(|(k, _)| k.clone())
        .filter(|k| b[0].iter().any(|(j, _)| j == k) && !skip.contains(&k.as_str()))
        .collect();
    assert!(shared.len() >= 3, "{what}: {shared:?}");
    for (i, (ra, rb)) in a.iter().zip(b).enumerate() {
        for k in &shared {
            let va = ra.iter().find(|(j, _)| j == k).map(|(_, v)| v);
            let vb = rb.iter().find(|(j, _)| j == k).map(|(_, v)| v);
            assert_eq!(va, vb, "{what}: scan {i}, column {k}");
        }
    }
}

fn build_l5x(src: &Path, out: &Path) -> Output {
    sfc(&["build", src.to_str().unwrap(), "--target", "l5x", "-o", out.to_str().unwrap()])
}

/// An IEC chart, its L5X, and the traces of both under `logix`.
fn iec_equal(chart: &Path, scenario: &Path, skip: &[&str]) {
    let name = chart.file_stem().unwrap().to_str().unwrap().to_string();
    let l5x = tmp(&format!("{name}.L5X"));
    let o = build_l5x(chart, &l5x);
    assert_eq!(o.status.code(), Some(0), "{}: {}", chart.display(), text(&o));
    let a = trace(&l5x, scenario, None, &tmp(&format!("{name}.a.csv")));
    let b = trace(chart, scenario, Some("logix"), &tmp(&format!("{name}.b.csv")));
    same_trace(&a, &b, skip, &name);
}

#[test]
fn the_logix_fixtures_of_the_simulator_run_alike_as_l5x() {
    let dir = root().join("crates/sfc-sim/tests/logix");
    let mut n = 0;
    let mut list: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    list.sort();
    for st in list {
        iec_equal(&st, &st.with_extension("scenario.toml"), &[]);
        n += 1;
    }
    assert!(n >= 9);
}

#[test]
fn the_car_wash_runs_alike_as_l5x() {
    // Its TIME variables are DINT tags of milliseconds in Logix: their columns read `60000`
    // against `T#1m`, the only columns left out.
    let dir = root().join("examples/carwash");
    for s in ["carwash.scenario.toml", "carwash_faults.scenario.toml"] {
        iec_equal(&dir.join("carwash.st"), &dir.join(s), &["MaxTravelTime", "MaxBrushTime", "BlowerSpinUp"]);
    }
    let o = build_l5x(&dir.join("carwash.st"), &tmp("carwash_notes.L5X"));
    let t = text(&o);
    assert!(t.contains("warning[SFC0821]") && t.contains("already tested in the first call"), "{t}");
    assert!(t.contains("note[SFC0821]") && t.contains("DINT tag of milliseconds"), "{t}");
}

/// The spindle reversal's block: its in-outs become InOut parameters of the program, its
/// supervision times (sfc.timeout), the SFCError its error transitions read and the
/// SFCQuitError that acknowledges it become a first action of each step, and it runs as the
/// text does under the `logix` profile. The program `Main` (ST) is not written, and says so.
#[test]
fn the_spindle_runs_alike_as_l5x() {
    let chart = root().join("examples/spindle/spindle.st");
    let scenario = root().join("examples/spindle/spindle_fb.scenario.toml");
    let l5x = tmp("spindle.L5X");
    let o = build_l5x(&chart, &l5x);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.contains("the PROGRAM `Main` is not written"), "{t}");
    assert!(t.contains("of OpenKM1, CloseKM2 is written as actions: Logix has no SFCError"), "{t}");
    let x = std::fs::read_to_string(&l5x).unwrap();
    assert!(x.contains("Usage=\"InOut\"") && x.contains("OpenKM1_Supervision"), "{x}");
    let a = trace(&l5x, &scenario, None, &tmp("spindle.a.csv"));
    let b = trace(&chart, &scenario, Some("logix"), &tmp("spindle.b.csv"));
    same_trace(&a, &b, &["SettleDelay"], "spindle");
    let at = |row: &Vec<(String, String)>, k: &str| row.iter().find(|(j, _)| j == k).map(|(_, v)| v.clone()).unwrap();
    assert!(a.iter().any(|r| at(r, "active") == "Err405"), "the supervision time runs out in CloseKM2");
    // Back from the L5X and written again: the same routine.
    let again = tmp("spindle_again.L5X");
    let o = build_l5x(&l5x, &again);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let t1 = sfc(&["build", l5x.to_str().unwrap(), "--target", "text"]);
    let t2 = sfc(&["build", again.to_str().unwrap(), "--target", "text"]);
    assert_eq!(t1.stdout, t2.stdout);
}

#[test]
fn an_l5x_fixture_written_back_runs_alike() {
    let dir = root().join("crates/sfc-l5x/tests/fixtures");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap().flatten() {
        let p = e.path();
        let Some(name) = p.file_name().and_then(|n| n.to_str()).and_then(|n| n.strip_suffix(".scenario.toml")) else {
            continue;
        };
        let src = dir.join(format!("{name}.L5X"));
        let back = tmp(&format!("{name}.back.L5X"));
        let o = build_l5x(&src, &back);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", text(&o));
        let a = trace(&src, &p, None, &tmp(&format!("{name}.x.csv")));
        let b = trace(&back, &p, None, &tmp(&format!("{name}.y.csv")));
        same_trace(&a, &b, &[], name);
        for target in ["plcopen", "st"] {
            let o = sfc(&[
                "build",
                back.to_str().unwrap(),
                "--target",
                target,
                "-o",
                tmp(&format!("{name}.{target}")).to_str().unwrap(),
            ]);
            assert_eq!(o.status.code(), Some(0), "{name} → {target}: {}", text(&o));
        }
        n += 1;
    }
    assert!(n >= 6, "{n}");
}
