//! Charts moved between vendors through the binary (issue 34, "Conversion both ways"): an S7-GRAPH
//! block to Studio 5000 and a Studio 5000 routine to S7-GRAPH, each conversion naming, per
//! construct, what runs differently under the target's rules (SFC0821, SFC0831) and refusing what
//! the target cannot hold (SFC0820); both to PLCopen with the same trace as the original file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sfc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).output().expect("sfc runs")
}

fn both(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-vendor-conversion-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// The fixture's scenario with `chart` pointing at `file`.
fn scenario_for(scenario: &Path, file: &Path, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenario).unwrap();
    let moved: String = text
        .lines()
        .map(|l| if l.starts_with("chart = ") { format!("chart = {:?}", file.to_str().unwrap()) } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n");
    let out = tmp(name);
    std::fs::write(&out, moved + "\n").unwrap();
    out
}

/// The CSV trace of `file` run with `scenario`.
fn trace(file: &Path, scenario: &Path, out: &str) -> String {
    let csv = tmp(out);
    let o = sfc(&["sim", file.to_str().unwrap(), "--scenario", scenario.to_str().unwrap(), "--trace", csv.to_str().unwrap()]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", both(&o));
    std::fs::read_to_string(csv).unwrap()
}

#[test]
fn a_graph_block_goes_to_studio_5000_saying_what_changes() {
    let graph = root().join("crates/sfc-simaticml/tests/fixtures/palletizer_alt_v1.xml");
    let l5x = tmp("palletizer.L5X");
    let o = sfc(&["build", graph.to_str().unwrap(), "--target", "l5x", "-o", l5x.to_str().unwrap()]);
    let out = both(&o);
    assert_eq!(o.status.code(), Some(0), "{out}");
    // The call order, the first call and the block becoming a program: each said once.
    assert!(out.contains("warning[SFC0821]: the chart is written for Studio 5000, whose call differs from S7-GRAPH's"), "{out}");
    assert!(out.contains("is already tested in the first call on Logix"), "{out}");
    assert!(out.contains("is written as a program whose SFC routine is the chart"), "{out}");
    // S7-GRAPH runs no final run of an action, nor does Logix's Don't scan: nothing said of it.
    assert!(!out.contains("does not execute again when it stops"), "{out}");
    // The routine reads back and runs with the logix profile.
    let o = sfc(&["sim", l5x.to_str().unwrap(), "--scans", "5"]);
    assert!(o.status.success(), "{}", both(&o));
    assert!(both(&o).contains("profile logix"), "{}", both(&o));
}

#[test]
fn a_studio_5000_routine_goes_to_s7_graph_saying_what_changes() {
    let l5x = root().join("crates/sfc-l5x/tests/fixtures/tank_fill.L5X");
    let xml = tmp("tank_fill_graph.xml");
    let o = sfc(&["build", l5x.to_str().unwrap(), "--target", "simaticml", "-o", xml.to_str().unwrap()]);
    let out = both(&o);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("warning[SFC0831]: the chart is written for S7-GRAPH, whose call differs from Studio 5000's"), "{out}");
    assert!(out.contains("is tested in the first call under Studio 5000's rules, not in S7-GRAPH's first call"), "{out}");
    // Logix's Don't scan has no final run either: nothing said of the N actions.
    assert!(!out.contains("once more when its step is left"), "{out}");
    let o = sfc(&["sim", xml.to_str().unwrap(), "--scans", "5"]);
    assert!(o.status.success(), "{}", both(&o));
    assert!(both(&o).contains("profile graph"), "{}", both(&o));
}

#[test]
fn what_studio_5000_cannot_hold_of_a_graph_block_is_refused_on_its_element() {
    let graph = root().join("crates/sfc-simaticml/tests/fixtures/type_change_v4.xml");
    let l5x = tmp("type_change.L5X");
    let o = sfc(&["build", graph.to_str().unwrap(), "--target", "l5x", "-o", l5x.to_str().unwrap()]);
    let out = both(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("error[SFC0820]: the step `Achse_Pos_A` has step actions, an interlock or a supervision"), "{out}");
    assert!(!l5x.exists(), "nothing is written");
}

#[test]
fn both_go_to_plcopen_with_the_trace_of_the_original() {
    for (file, scenario) in [
        ("crates/sfc-simaticml/tests/fixtures/palletizer_alt_v1.xml", "crates/sfc-simaticml/tests/fixtures/palletizer_alt_v1.scenario.toml"),
        ("crates/sfc-l5x/tests/fixtures/tank_fill.L5X", "crates/sfc-l5x/tests/fixtures/tank_fill.scenario.toml"),
    ] {
        let (file, scenario) = (root().join(file), root().join(scenario));
        let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
        let plc = tmp(&format!("{stem}.plcopen.xml"));
        let o = sfc(&["build", file.to_str().unwrap(), "--target", "plcopen", "-o", plc.to_str().unwrap()]);
        assert!(o.status.success(), "{}", both(&o));
        // What runs differently in the IEC tools the PLCopen file is for is said (SFC0840): the
        // Logix routine's call order and first call; the palletizer's Boolean actions and call
        // run alike under S7-GRAPH's and IEC's rules, and nothing is said.
        assert_eq!(both(&o).contains("warning[SFC0840]"), stem == "tank_fill", "{}", both(&o));
        let original = trace(&file, &scenario, &format!("{stem}.orig.csv"));
        let moved = trace(&plc, &scenario_for(&scenario, &plc, &format!("{stem}.plc.scenario.toml")), &format!("{stem}.plc.csv"));
        assert_eq!(moved, original, "{stem}");
    }
}

/// An S7-GRAPH block with interlocks and supervisions to PLCopen or ST: written, and SFC0840 says
/// that those conditions act in no IEC 61131-3 tool.
#[test]
fn graph_conditions_going_to_iec_tools_are_named() {
    let graph = root().join("crates/sfc-simaticml/tests/fixtures/type_change_v4.xml");
    for target in ["plcopen", "st"] {
        let out = tmp(&format!("type_change.{target}"));
        let o = sfc(&["build", graph.to_str().unwrap(), "--target", target, "-o", out.to_str().unwrap()]);
        assert!(o.status.success(), "{target}: {}", both(&o));
        assert!(
            both(&o).contains("has 2 step(s) with an S7-GRAPH interlock or supervision: kept in the output's attributes, they act in no IEC 61131-3 tool"),
            "{target}: {}",
            both(&o)
        );
    }
}
