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
    // A chart that reads SFCError but supervises no step: GRAPH has no SFCError to read.
    let chart = dir.join("error_read.st");
    std::fs::write(
        &chart,
        "FUNCTION_BLOCK F\n    VAR_OUTPUT lamp : BOOL; END_VAR\n    INITIAL_STEP S: END_STEP\n    STEP E: lamp(N); END_STEP\n    TRANSITION FROM S TO E := SFCError; END_TRANSITION\n    TRANSITION FROM E TO S := NOT SFCError; END_TRANSITION\nEND_FUNCTION_BLOCK\n",
    )
    .unwrap();
    let out = sfc(&["build", chart.to_str().unwrap(), "--target", "simaticml", "-o", xml.to_str().unwrap()]);
    assert!(text(&out).contains("`SFCError` is no variable of the block"), "{}", text(&out));
    assert!(text(&out).contains("error_read.st:5:"), "{}", text(&out));
    assert!(!xml.exists());
}

/// The spindle reversal's block: its supervision times (sfc.timeout), the SFCError its error
/// transitions read and the SFCQuitError that acknowledges it become permanent instructions,
/// and the block runs as the text does under the `graph` profile: a successful reversal, error
/// 4.05 and its acknowledgement, scan by scan. Written back from the XML, it is the same block.
#[test]
fn the_spindle_runs_alike_as_a_graph_block() {
    let dir = temp_dir("spindle");
    let r = root();
    let chart = r.join("examples/spindle/spindle.st");
    let scenario = r.join("examples/spindle/spindle_fb.scenario.toml");
    let xml = dir.join("spindle.xml");
    let args = ["build", chart.to_str().unwrap(), "--pou", "SpindleReversal", "--target", "simaticml", "-o", xml.to_str().unwrap()];
    let out = sfc(&args);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(text(&out).contains("of OpenKM1, CloseKM2 is written as permanent instructions"), "{}", text(&out));
    let x = std::fs::read_to_string(&xml).unwrap();
    assert!(x.contains("<PreOperations>") && x.contains("OpenKM1_Overdue") && x.contains("SFCQuitError"), "{x}");
    let (a, b) = (dir.join("xml.csv"), dir.join("st.csv"));
    let ra = sfc(&["sim", xml.to_str().unwrap(), "--scenario", scenario.to_str().unwrap(), "--trace", a.to_str().unwrap()]);
    let rb = sfc(&[
        "sim",
        chart.to_str().unwrap(),
        "--scenario",
        scenario.to_str().unwrap(),
        "--profile",
        "graph",
        "--trace",
        b.to_str().unwrap(),
    ]);
    assert_eq!(rb.status.code(), Some(0), "{}", text(&rb));
    // The block sets SFCError as the text does; only what sfc adds to its own supervision
    // (SFCErrorStep, the error record) is not in the GRAPH block.
    let failed: Vec<&str> = std::str::from_utf8(&ra.stderr).unwrap().lines().chain(std::str::from_utf8(&ra.stdout).unwrap().lines()).filter(|l| l.contains("expected")).collect();
    assert!(!failed.is_empty() && failed.iter().all(|l| l.contains("SFCErrorStep") || l.contains("error_record")), "{}", text(&ra));
    same_traces(&a, &b, "spindle");
    let (ha, ra) = csv(&a);
    let col = ha.iter().position(|h| h == "SFCError").unwrap();
    let act = ha.iter().position(|h| h == "active").unwrap();
    let first = ra.iter().position(|r| r[col] == "TRUE" || r[col] == "true" || r[col] == "1").unwrap();
    assert_eq!(ra[first][act], "CloseKM2", "SFCError rises in CloseKM2");
    assert_eq!(ra[first + 1][act], "Err405", "and TKM2Missing fires in the next scan");
    // Written back from the XML: the same block.
    let again = dir.join("again.xml");
    let out = sfc(&["build", xml.to_str().unwrap(), "--target", "simaticml", "-o", again.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let t1 = sfc(&["build", xml.to_str().unwrap(), "--target", "text"]);
    let t2 = sfc(&["build", again.to_str().unwrap(), "--target", "text"]);
    assert_eq!(t1.stdout, t2.stdout);
}
