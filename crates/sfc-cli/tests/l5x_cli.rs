//! The `sfc` binary on Studio 5000 L5X exports (`sfc-l5x`'s fixtures): `check` without errors,
//! an error in a condition at the line and column of its CDATA characters, `build --target
//! text` and `--target svg`, the fixtures' scenarios through `sim` and `test`, and an `.L5X`
//! found in a directory.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sfc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).output().expect("sfc runs")
}

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../sfc-l5x/tests/fixtures")
}

fn files(ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(fixtures())
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.to_str().is_some_and(|s| s.ends_with(ext)))
        .collect();
    v.sort();
    v
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

#[test]
fn every_fixture_checks_without_errors() {
    let all = files(".L5X");
    assert!(all.len() >= 12, "{all:?}");
    for p in all {
        let out = sfc(&["check", p.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}: {}", p.display(), text(&out));
        assert!(!text(&out).contains("error["), "{}", text(&out));
    }
}

#[test]
fn an_error_in_a_condition_is_reported_on_its_cdata() {
    let p = fixtures().join("errors/condition_error.L5X");
    let xml = std::fs::read_to_string(&p).unwrap();
    let (line, l) = xml.lines().enumerate().find(|(_, l)| l.contains("Level > > 5")).unwrap();
    // The second `>`: where an expression was expected.
    let col = l.find("> > 5").unwrap() + 3;
    let out = sfc(&["check", p.to_str().unwrap()]);
    let err = text(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("error[SFC0101]: expected an expression, found `>`"), "{err}");
    assert!(err.contains(&format!("condition_error.L5X:{}:{col}", line + 1)), "{err}");
    // Logix members and instructions sfc does not have: located errors too.
    let out = sfc(&["check", fixtures().join("errors/logix_members.L5X").to_str().unwrap()]);
    let err = text(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    for code in ["SFC0723", "SFC0724"] {
        assert!(err.contains(&format!("error[{code}]")), "{err}");
    }
}

#[test]
fn build_text_and_svg() {
    let tank = fixtures().join("tank_fill.L5X");
    let out = sfc(&["build", tank.to_str().unwrap(), "--target", "text"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let t = String::from_utf8_lossy(&out.stdout);
    assert!(t.contains("INITIAL_STEP Idle") && t.contains("{attribute 'sfc.dialect' := 'logix'}"), "{t}");
    let out = sfc(&["build", tank.to_str().unwrap(), "--target", "svg"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let svg = String::from_utf8_lossy(&out.stdout);
    assert!(svg.contains("<svg") && svg.contains("Filling") && svg.contains("Draining"), "{svg}");
}

#[test]
fn the_scenarios_pass_through_sim_and_test() {
    let scenarios = files(".scenario.toml");
    assert!(scenarios.len() >= 6, "{scenarios:?}");
    for s in &scenarios {
        let out = sfc(&["test", s.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}: {}", s.display(), text(&out));
        assert!(text(&out).contains("PASS"), "{}", text(&out));
    }
    let tank = fixtures().join("tank_fill.L5X");
    let scenario = fixtures().join("tank_fill.scenario.toml");
    let out = sfc(&["sim", tank.to_str().unwrap(), "--scenario", scenario.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
}

#[test]
fn a_directory_check_finds_the_l5x_files() {
    let d = std::env::temp_dir().join(format!("sfc-l5x-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::copy(fixtures().join("mixer.L5X"), d.join("mixer.L5X")).unwrap();
    std::fs::copy(fixtures().join("errors/bad_links.L5X"), d.join("bad_links.l5x")).unwrap();
    let out = sfc(&["check", d.to_str().unwrap()]);
    let err = text(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("bad_links.l5x:") && err.contains("error[SFC0725]"), "{err}");
    assert!(err.contains("mixer.L5X:"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}
