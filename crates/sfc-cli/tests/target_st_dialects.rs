//! `sfc build --target st --st-dialect …` through the binary: the flag's usage rule, every chart
//! of a file translated without `--pou`, only one with it, and CODESYS's refusal of durations
//! below the millisecond, located where they are written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn sfc(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).current_dir(dir).args(args).output().expect("sfc runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn st_dialect_needs_the_st_target() {
    let out = sfc(&root(), &["build", "examples/carwash/carwash.st", "--target", "stl", "--st-dialect", "matiec"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--st-dialect applies to --target st"), "{}", text(&out.stderr));
    assert!(out.stdout.is_empty());
}

#[test]
fn every_chart_of_the_file_unless_one_is_named() {
    let file = "crates/sfc-codegen/tests/st/two_charts.st";
    let all = sfc(&root(), &["build", file, "--target", "st"]);
    assert_eq!(all.status.code(), Some(0), "{}", text(&all.stderr));
    let all = text(&all.stdout);
    assert!(!all.contains("INITIAL_STEP") && !all.contains("END_STEP"), "a chart is left:\n{all}");
    // `--pou Blink`: the block becomes plain ST, the program stays a chart.
    let one = sfc(&root(), &["build", file, "--target", "st", "--pou", "Blink"]);
    assert_eq!(one.status.code(), Some(0), "{}", text(&one.stderr));
    let one = text(&one.stdout);
    let panel = &one[one.find("PROGRAM Panel").unwrap()..];
    assert!(panel.contains("INITIAL_STEP"), "Panel should stay a chart:\n{panel}");
    let blink = &one[one.find("FUNCTION_BLOCK Blink").unwrap()..];
    let blink = &blink[..blink.find("END_FUNCTION_BLOCK").unwrap()];
    assert!(!blink.contains("INITIAL_STEP"), "{blink}");
}

#[test]
fn codesys_refuses_durations_below_the_millisecond_where_they_are_written() {
    let dir = std::env::temp_dir().join(format!("sfc-st-dialects-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("fine.st"),
        "PROGRAM Fine\n  VAR Go : BOOL; Y : BOOL; END_VAR\n  INITIAL_STEP S0: END_STEP\n  STEP S1: Y(D, T#2ms500us); END_STEP\n  TRANSITION FROM S0 TO S1 := Go; END_TRANSITION\n  TRANSITION FROM S1 TO S0 := NOT Go; END_TRANSITION\nEND_PROGRAM\n",
    )
    .unwrap();
    let out = sfc(&dir, &["build", "fine.st", "--target", "st", "--st-dialect", "codesys", "-o", "fine.xml"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("error[SFC0807]") && err.contains("fine.st:4:17"), "{err}");
    assert!(!dir.join("fine.xml").exists(), "nothing is written on a refusal");
    // The same chart for an IEC compiler, whose TIME holds microseconds: built.
    let out = sfc(&dir, &["build", "fine.st", "--target", "st", "-o", "fine_plain.st"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(std::fs::read_to_string(dir.join("fine_plain.st")).unwrap().contains("T#2ms500us"));
    let _ = std::fs::remove_dir_all(&dir);
}
