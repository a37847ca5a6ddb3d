//! The `sfc` binary on TIA Portal SimaticML exports of S7-GRAPH blocks (`sfc-simaticml`'s
//! fixtures): `sfc check` of every fixture, a broken network located on its `Part`, `sfc build
//! --target text` and `--target svg`, and the fixtures' scenarios run by `sfc test` and `sfc sim`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn fixtures() -> PathBuf {
    root().join("crates/sfc-simaticml/tests/fixtures")
}

fn sfc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).current_dir(root()).output().expect("sfc runs")
}

fn text(o: &Output) -> String {
    format!("--- stdout\n{}--- stderr\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn xml_fixtures() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(fixtures())
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_fixture_checks_without_errors() {
    let all = xml_fixtures();
    assert!(all.len() >= 12);
    for p in all {
        let name = p.file_name().unwrap().to_str().unwrap().to_string();
        let out = sfc(&["check", p.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        if name.starts_with("error_") {
            assert_eq!(out.status.code(), Some(1), "{name}: {}", text(&out));
            assert!(err.contains("error[SFC0740]"), "{name}: {}", text(&out));
        } else {
            assert_eq!(out.status.code(), Some(0), "{name}: {}", text(&out));
            assert!(!err.contains("error["), "{name}: {}", text(&out));
        }
    }
}

#[test]
fn a_broken_network_is_reported_at_its_part() {
    let src = std::fs::read_to_string(fixtures().join("conveyor_handover_v6.xml")).unwrap();
    let broken = src.replacen("<Part Name=\"O\"", "<Part Name=\"PContact\"", 1);
    let at = broken.find("<Part Name=\"PContact\"").unwrap();
    let line = broken[..at].matches('\n').count() + 1;
    let col = broken[..at].rsplit('\n').next().unwrap().chars().count() + 1;
    let dir = std::env::temp_dir().join(format!("sfc-simaticml-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("broken.xml");
    std::fs::write(&path, &broken).unwrap();
    let out = sfc(&["check", path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(err.contains("error[SFC0743]") && err.contains("`PContact`"), "{}", text(&out));
    assert!(err.contains(&format!("broken.xml:{line}:{col}")), "expected {line}:{col}: {}", text(&out));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn build_writes_the_text_and_draws_the_chart() {
    let p = fixtures().join("drilling_station_v5.xml");
    let out = sfc(&["build", p.to_str().unwrap(), "--target", "text"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        stdout.contains("{attribute 'sfc.dialect' := 'graph'}") && stdout.contains("FUNCTION_BLOCK DrillingStation"),
        "{stdout}"
    );
    assert!(stdout.contains("TRANSITION T1 FROM Idle TO (Clamp_part, Spin_up)"), "{stdout}");
    let dir = std::env::temp_dir().join(format!("sfc-simaticml-svg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("drill.svg");
    let out = sfc(&["build", p.to_str().unwrap(), "--target", "svg", "-o", svg.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out));
    let drawn = std::fs::read_to_string(&svg).unwrap();
    assert!(drawn.contains("<svg") && drawn.contains("Clamp_part") && drawn.contains("Release"), "{drawn}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_scenarios_pass() {
    let out = sfc(&["test", fixtures().to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", text(&out));
    let last = stdout.lines().last().unwrap_or("");
    let passed: usize = last.split(' ').next().unwrap_or("0").parse().unwrap_or(0);
    assert!(passed >= 6 && last.ends_with(" 0 failed"), "{stdout}");
    let p = fixtures().join("sequence_end_v1.xml");
    let s = fixtures().join("sequence_end_v1.scenario.toml");
    let out = sfc(&["sim", p.to_str().unwrap(), "--scenario", s.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("PASS"), "{}", text(&out));
}
