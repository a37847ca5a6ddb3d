//! `sfc build --target simaticml` through the binary: charts written in IEC text and a GRAPH
//! export's re-import are written as S7-GRAPH blocks, simulated from the XML (which runs with
//! the `graph` profile by itself) and from the text with `--profile graph`: the traces are equal
//! on the columns both have (the XML's interface adds GRAPH's standard parameters, which the
//! text does not declare). The written XML also builds `--target plcopen` and `--target st`,
//! and what GRAPH cannot hold is a located SFC0830 with nothing written.
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

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-simaticml-export-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A CSV trace as its header and rows.
fn csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let t = std::fs::read_to_string(path).unwrap();
    let mut lines = t.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    let rows = lines.map(|l| l.split(',').map(str::to_string).collect()).collect();
    (head, rows)
}

/// The rows of `a` and `b` on the columns both have are equal, and there are some.
fn same_traces(a: &Path, b: &Path, what: &str) {
    let (ha, ra) = csv(a);
    let (hb, rb) = csv(b);
    let common: Vec<&String> = ha.iter().filter(|h| hb.contains(h)).collect();
    assert!(common.len() >= 3, "{what}: columns {ha:?} / {hb:?}");
    assert_eq!(ra.len(), rb.len(), "{what}: scans");
    let ia: Vec<usize> = common.iter().map(|h| ha.iter().position(|x| x == *h).unwrap()).collect();
    let ib: Vec<usize> = common.iter().map(|h| hb.iter().position(|x| x == *h).unwrap()).collect();
    for (n, (x, y)) in ra.iter().zip(rb.iter()).enumerate() {
        let xa: Vec<&String> = ia.iter().map(|&i| &x[i]).collect();
        let yb: Vec<&String> = ib.iter().map(|&i| &y[i]).collect();
        assert_eq!(xa, yb, "{what}: row {n} differs on {common:?}");
    }
}

/// Builds `chart` (`--pou` when given) as SimaticML and compares the traces of `scenario`.
fn equal_traces(dir: &Path, chart: &Path, pou: Option<&str>, scenario: &Path, text_profile: &[&str]) {
    let name = scenario.file_stem().unwrap().to_string_lossy().to_string();
    let xml = dir.join(format!("{name}.xml"));
    let mut args = vec!["build", chart.to_str().unwrap(), "--target", "simaticml", "-o", xml.to_str().unwrap()];
    if let Some(p) = pou {
        args.extend(["--pou", p]);
    }
    let out = sfc(&args);
    assert_eq!(out.status.code(), Some(0), "{name}: {}", text(&out));
    let a = dir.join(format!("{name}.xml.csv"));
    let b = dir.join(format!("{name}.st.csv"));
    // Both runs give the same verdict; only the traces are compared.
    let ra =
        sfc(&["sim", xml.to_str().unwrap(), "--scenario", scenario.to_str().unwrap(), "--trace", a.to_str().unwrap()]);
    let graph = !std::fs::read_to_string(scenario).unwrap().contains("profile = \"iec\"");
    assert!(!graph || text(&ra).contains("profile graph"), "{name}: {}", text(&ra));
    let mut args =
        vec!["sim", chart.to_str().unwrap(), "--scenario", scenario.to_str().unwrap(), "--trace", b.to_str().unwrap()];
    args.extend(text_profile);
    let rb = sfc(&args);
    assert_eq!(ra.status.code(), rb.status.code(), "{name}: {}\n{}", text(&ra), text(&rb));
    same_traces(&a, &b, &name);
    // The XML is a chart file like any other.
    for target in ["plcopen", "st", "text"] {
        let o = dir.join(format!("{name}.{target}.out"));
        let out = sfc(&["build", xml.to_str().unwrap(), "--target", target, "-o", o.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{name} --target {target}: {}", text(&out));
    }
}

#[test]
fn iec_charts_run_alike_as_graph_blocks() {
    let dir = temp_dir("iec");
    let r = root();
    let carwash = r.join("examples/carwash/carwash.st");
    equal_traces(&dir, &carwash, None, &r.join("examples/carwash/carwash.scenario.toml"), &["--profile", "graph"]);
    equal_traces(
        &dir,
        &carwash,
        None,
        &r.join("examples/carwash/carwash_faults.scenario.toml"),
        &["--profile", "graph"],
    );
}

#[test]
fn every_branch_kind_runs_alike() {
    let dir = temp_dir("branches");
    let here = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/simaticml_export");
    equal_traces(&dir, &here.join("branches.st"), None, &here.join("branches.scenario.toml"), &["--profile", "graph"]);
    // The XML holds each kind of branch and a jump.
    let xml = std::fs::read_to_string(dir.join("branches.scenario.xml")).unwrap();
    for kind in [
        "\"AltBegin\"",
        "\"AltEnd\"",
        "\"SimBegin\"",
        "\"SimEnd\"",
        "<LinkType>Jump</LinkType>",
        "Event=\"S1\"",
        "Event=\"S0\"",
        "Qualifier=\"D\"",
        "Qualifier=\"L\"",
    ] {
        assert!(xml.contains(kind), "{kind} in\n{xml}");
    }
}

#[test]
fn graph_profile_fixtures_run_alike_as_graph_blocks() {
    let dir = temp_dir("graph");
    let g = root().join("crates/sfc-sim/tests/graph");
    let mut n = 0;
    for f in [
        "01_interlock",
        "02_supervision_acknowledged",
        "03_supervision_without_acknowledgement",
        "05_init_sq",
        "06_file_chooses_graph",
        "07_step_events",
    ] {
        equal_traces(
            &dir,
            &g.join(format!("{f}.st")),
            None,
            &g.join(format!("{f}.scenario.toml")),
            &["--profile", "graph"],
        );
        n += 1;
    }
    assert_eq!(n, 6);
}

#[test]
fn a_graph_export_written_back_runs_alike() {
    let dir = temp_dir("back");
    let fx = root().join("crates/sfc-simaticml/tests/fixtures");
    for f in [
        "drilling_station_v5",
        "sequence_end_v1",
        "palletizer_alt_v1",
        "two_sequences_v6",
        "refrigerant_fill_graph2_v5",
        "conveyor_handover_v6",
        "type_change_v4",
    ] {
        // The profile the file and its scenario choose, the same on both sides (graph; the
        // type change's scenario says iec).
        equal_traces(&dir, &fx.join(format!("{f}.xml")), None, &fx.join(format!("{f}.scenario.toml")), &[]);
    }
}

/// Permanent instructions with arithmetic are not LAD: located errors, nothing written.
#[test]
fn what_graph_cannot_hold_is_refused() {
    let dir = temp_dir("refused");
    let chart = root().join("crates/sfc-sim/tests/graph/04_permanent_instructions.st");
    let xml = dir.join("out.xml");
    let out = sfc(&["build", chart.to_str().unwrap(), "--target", "simaticml", "-o", xml.to_str().unwrap()]);
    assert_ne!(out.status.code(), Some(0));
    assert!(text(&out).contains("error[SFC0830]"), "{}", text(&out));
    assert!(text(&out).contains("04_permanent_instructions.st:"), "{}", text(&out));
    assert!(!xml.exists());
    // A file holding a program in ST besides the chart: the program is not a GRAPH block.
    let spindle = root().join("examples/spindle/spindle.st");
    let out = sfc(&["build", spindle.to_str().unwrap(), "--target", "simaticml", "-o", xml.to_str().unwrap()]);
    assert!(text(&out).contains("`Main` is not a chart"), "{}", text(&out));
    assert!(!xml.exists());
    // The spindle's block reads CODESYS's implicit SFCError, which GRAPH has not.
    let out = sfc(&[
        "build",
        spindle.to_str().unwrap(),
        "--pou",
        "SpindleReversal",
        "--target",
        "simaticml",
        "-o",
        xml.to_str().unwrap(),
    ]);
    assert!(text(&out).contains("`SFCError` is no variable of the block"), "{}", text(&out));
    assert!(text(&out).contains("spindle.st:88:"), "{}", text(&out));
    assert!(!xml.exists());
}
