//! `sfc merge` through the binary: three versions of a chart merged by element, conflicts
//! listed and marked (exit 1), PLCopen XML merged into ours, and git's merge through the driver
//! `sfc git setup` writes.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sfc_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).current_dir(dir).args(args).output().expect("sfc runs")
}

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/merge")
}

fn fixture(name: &str) -> String {
    std::fs::read_to_string(fixtures().join(name)).unwrap()
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-merge-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn git(dir: &Path, args: &[&str]) -> Output {
    Command::new("git")
        .current_dir(dir)
        .args(["-c", "user.email=test@example.com", "-c", "user.name=test", "-c", "commit.gpgsign=false"])
        .args(args)
        .output()
        .expect("git runs")
}

fn git_ok(dir: &Path, args: &[&str]) {
    let o = git(dir, args);
    assert!(o.status.success(), "git {args:?}: {}{}", err(&o), String::from_utf8_lossy(&o.stdout));
}

#[test]
fn changes_to_different_elements_merge() {
    let dir = tmp("clean");
    let o = sfc_in(&fixtures(), &["merge", "tank_base.st", "tank_ours.st", "tank_theirs.st", "-o"]);
    assert_eq!(o.status.code(), Some(2), "-o needs a file");
    let out = dir.join("tank.st");
    let o = sfc_in(&fixtures(), &["merge", "tank_base.st", "tank_ours.st", "tank_theirs.st", "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), fixture("tank_merged.expected.st"));
    // Without -o, on standard output.
    let o = sfc_in(&fixtures(), &["merge", "tank_base.st", "tank_ours.st", "tank_theirs.st"]);
    assert_eq!(String::from_utf8_lossy(&o.stdout), fixture("tank_merged.expected.st"));
    // One side unchanged: the other side, byte for byte.
    let o = sfc_in(&fixtures(), &["merge", "tank_base.st", "tank_base.st", "tank_theirs.st"]);
    assert_eq!(String::from_utf8_lossy(&o.stdout), fixture("tank_theirs.st"));
}

#[test]
fn the_same_element_changed_both_ways_is_a_conflict() {
    let dir = tmp("conflict");
    let out = dir.join("tank.st");
    let o = sfc_in(
        &fixtures(),
        &["merge", "tank_base.st", "tank_ours.st", "tank_theirs_conflict.st", "-o", out.to_str().unwrap()],
    );
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("conflict: transition `TStart` of `Tank` changed both ways"), "{}", err(&o));
    assert!(err(&o).contains("1 conflict to resolve"), "{}", err(&o));
    let merged = std::fs::read_to_string(&out).unwrap();
    // Ours is written and marked; their variable merged.
    assert!(merged.contains(":= Start AND Empty AND NOT Full;"), "{merged}");
    assert!(merged.contains("{attribute 'sfc.conflict' := 'transition:TStart$N"), "{merged}");
    assert!(merged.contains("AND Permit;$N"), "{merged}");
    assert!(merged.contains("        Permit : BOOL;\n"), "{merged}");
    // `sfc check` refuses the marked file until the conflict is resolved.
    let c = sfc_in(&dir, &["check", "tank.st"]);
    assert_eq!(c.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&c.stdout).contains("SFC0605") || err(&c).contains("SFC0605"), "{}", err(&c));
}

#[test]
fn plcopen_files_merge_into_ours() {
    let dir = tmp("xml");
    for side in ["base", "ours", "theirs"] {
        let o = sfc_in(
            &fixtures(),
            &["build", &format!("tank_{side}.st"), "--target", "plcopen", "-o", dir.join(format!("{side}.xml")).to_str().unwrap()],
        );
        assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    }
    let o = sfc_in(&dir, &["merge", "base.xml", "ours.xml", "theirs.xml", "-o", "merged.xml"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let merged = std::fs::read_to_string(dir.join("merged.xml")).unwrap();
    assert!(merged.starts_with("<?xml"), "{merged}");
    std::fs::write(dir.join("expected.st"), fixture("tank_merged.expected.st")).unwrap();
    let d = sfc_in(&dir, &["diff", "--color", "never", "merged.xml", "expected.st"]);
    assert_eq!(d.status.code(), Some(0), "{}", String::from_utf8_lossy(&d.stdout));
}

#[test]
fn text_that_is_no_chart_merges_line_by_line() {
    let dir = tmp("lines");
    std::fs::write(dir.join("b.txt"), "one\ntwo\nthree\n").unwrap();
    std::fs::write(dir.join("o.txt"), "one!\ntwo\nthree\n").unwrap();
    std::fs::write(dir.join("t.txt"), "one\ntwo\nthree!\n").unwrap();
    let o = sfc_in(&dir, &["merge", "b.txt", "o.txt", "t.txt"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout), "one!\ntwo\nthree!\n");
    assert!(err(&o).contains("merged line by line"), "{}", err(&o));
}

/// `git merge` of two branches that changed the chart uses the driver `sfc git setup` wrote:
/// different elements merge without a conflict git would report line by line; the same
/// element changed both ways stops the merge with the file marked.
#[test]
fn git_merge_uses_the_driver() {
    let dir = tmp("git");
    git_ok(&dir, &["init", "-q", "-b", "main"]);
    let o = sfc_in(&dir, &["git", "setup"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let attrs = std::fs::read_to_string(dir.join(".gitattributes")).unwrap();
    assert!(attrs.contains("*.st diff=sfc merge=sfc"), "{attrs}");
    std::fs::write(dir.join("tank.st"), fixture("tank_base.st")).unwrap();
    git_ok(&dir, &["add", "."]);
    git_ok(&dir, &["commit", "-qm", "base"]);
    git_ok(&dir, &["checkout", "-qb", "theirs"]);
    std::fs::write(dir.join("tank.st"), fixture("tank_theirs.st")).unwrap();
    git_ok(&dir, &["commit", "-qam", "theirs"]);
    git_ok(&dir, &["checkout", "-qb", "conflicting", "main"]);
    std::fs::write(dir.join("tank.st"), fixture("tank_theirs_conflict.st")).unwrap();
    git_ok(&dir, &["commit", "-qam", "conflicting"]);
    git_ok(&dir, &["checkout", "-q", "main"]);
    std::fs::write(dir.join("tank.st"), fixture("tank_ours.st")).unwrap();
    git_ok(&dir, &["commit", "-qam", "ours"]);
    // Git's own line merge would conflict here: the rename and the new action of Mixing touch
    // neighbouring lines.
    git_ok(&dir, &["merge", "-q", "--no-edit", "theirs"]);
    assert_eq!(std::fs::read_to_string(dir.join("tank.st")).unwrap(), fixture("tank_merged.expected.st"));
    let o = git(&dir, &["merge", "--no-edit", "conflicting"]);
    assert!(!o.status.success(), "the conflict stops the merge");
    let text = std::fs::read_to_string(dir.join("tank.st")).unwrap();
    assert!(text.contains("sfc.conflict") && !text.contains("<<<<<<<"), "{text}");
    let status = String::from_utf8_lossy(&git(&dir, &["status", "--porcelain"]).stdout).to_string();
    assert!(status.contains("UU tank.st"), "{status}");
}
