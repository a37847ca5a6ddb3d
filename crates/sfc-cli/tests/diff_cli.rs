//! `sfc diff` through the binary: charts compared by meaning, per POU, with `diff`'s exit
//! status (0 equal in meaning, 1 different, 2 usage), across text and PLCopen XML, and on git
//! revisions.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sfc_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).current_dir(dir).args(args).output().expect("sfc runs")
}

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/diff")
}

fn out(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-diff-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Each edit of a colleague's version is named once, and nothing else is.
#[test]
fn every_edit_is_named_once() {
    let o = sfc_in(&fixtures(), &["diff", "--color", "never", "fill_old.st", "fill_new.st"]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let expected = std::fs::read_to_string(fixtures().join("fill.expected.txt")).unwrap();
    assert_eq!(out(&o), expected);
    // The rename carries its references: no condition change for `Mixing.T` → `Stirring.T`.
    assert!(!out(&o).contains("Mixing.T"), "{}", out(&o));
}

#[test]
fn a_chart_equals_itself_and_a_moved_step_is_layout() {
    let o = sfc_in(&fixtures(), &["diff", "fill_old.st", "fill_old.st"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(out(&o).contains("equal in meaning"), "{}", out(&o));
    let o = sfc_in(&fixtures(), &["diff", "fill_old.st", "fill_moved.st"]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    assert!(out(&o).contains("layout: 1 element moved or resized"), "{}", out(&o));
    assert!(out(&o).contains("equal in meaning"), "{}", out(&o));
    let o = sfc_in(&fixtures(), &["diff", "--layout", "fill_old.st", "fill_moved.st"]);
    assert!(out(&o).contains("layout step Filling: sfc.x 200 -> 240"), "{}", out(&o));
}

#[test]
fn json_lists_the_changes() {
    let o = sfc_in(&fixtures(), &["diff", "--format", "json", "fill_old.st", "fill_new.st"]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_str(&out(&o)).unwrap();
    assert_eq!(v["equal"], false);
    let changes = v["changes"].as_array().unwrap();
    assert_eq!(changes.len(), 9, "{v}");
    let renamed = changes.iter().find(|c| c["kind"] == "renamed").unwrap();
    assert_eq!((renamed["element"].as_str(), renamed["old"].as_str(), renamed["new"].as_str()), (Some("step"), Some("Mixing"), Some("Stirring")));
    let cond = changes.iter().find(|c| c["what"] == "condition").unwrap();
    assert_eq!(cond["name"], "TStart");
    assert_eq!(cond["new"], "Start AND Empty AND NOT Full");
}

/// A chart and its PLCopen export are the same chart: only the layout the export adds differs.
#[test]
fn text_and_its_plcopen_export_are_equal_in_meaning() {
    let dir = tmp("xml");
    let xml = dir.join("fill.xml");
    let b = sfc_in(&fixtures(), &["build", "fill_old.st", "--target", "plcopen", "-o", xml.to_str().unwrap()]);
    assert_eq!(b.status.code(), Some(0), "{}", String::from_utf8_lossy(&b.stderr));
    let o = sfc_in(&fixtures(), &["diff", "fill_old.st", xml.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    assert!(out(&o).contains("equal in meaning"), "{}", out(&o));
    let o = sfc_in(&fixtures(), &["diff", xml.to_str().unwrap(), "fill_new.st"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(out(&o).contains("~ step Mixing renamed Stirring"), "{}", out(&o));
}

fn git(dir: &Path, args: &[&str]) {
    let o = Command::new("git")
        .current_dir(dir)
        .args(["-c", "user.email=test@example.com", "-c", "user.name=test", "-c", "commit.gpgsign=false"])
        .args(args)
        .output()
        .expect("git runs");
    assert!(o.status.success(), "git {args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn git_revisions_against_the_working_tree_and_each_other() {
    let dir = tmp("git");
    git(&dir, &["init", "-q"]);
    std::fs::copy(fixtures().join("fill_old.st"), dir.join("tank.st")).unwrap();
    git(&dir, &["add", "tank.st"]);
    git(&dir, &["commit", "-qm", "old"]);
    std::fs::copy(fixtures().join("fill_new.st"), dir.join("tank.st")).unwrap();
    let o = sfc_in(&dir, &["diff", "--color", "never", "HEAD", "--", "tank.st"]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out(&o).starts_with("--- tank.st@HEAD\n+++ tank.st\n"), "{}", out(&o));
    assert!(out(&o).contains("~ step Mixing renamed Stirring"), "{}", out(&o));
    git(&dir, &["commit", "-qam", "new"]);
    let o = sfc_in(&dir, &["diff", "--color", "never", "HEAD~1", "HEAD", "--", "tank.st"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(out(&o).contains("+ transition TSettled (FROM Settling TO Draining)"), "{}", out(&o));
    let o = sfc_in(&dir, &["diff", "HEAD", "--", "tank.st"]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    // A revision git does not know: a usage error that says so.
    let o = sfc_in(&dir, &["diff", "nosuchrev", "--", "tank.st"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nosuchrev"));
}

#[test]
fn one_file_alone_is_a_usage_error() {
    let o = sfc_in(&fixtures(), &["diff", "fill_old.st"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("two files"), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `sfc git setup`: `git diff` then shows charts by meaning (text and PLCopen XML alike), a
/// file that is no chart as git would, and a second setup changes nothing.
#[test]
fn git_setup_makes_git_diff_compare_charts_by_meaning() {
    let dir = tmp("setup");
    git(&dir, &["init", "-q"]);
    let o = sfc_in(&dir, &["git", "setup"]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let attrs = std::fs::read_to_string(dir.join(".gitattributes")).unwrap();
    assert!(attrs.contains("*.st diff=sfc") && attrs.contains("*.xml diff=sfc"), "{attrs}");
    std::fs::copy(fixtures().join("fill_old.st"), dir.join("tank.st")).unwrap();
    let b = sfc_in(&dir, &["build", "tank.st", "--target", "plcopen", "-o", "tank.xml"]);
    assert_eq!(b.status.code(), Some(0));
    std::fs::write(dir.join("other.xml"), "<note>not a chart</note>\n").unwrap();
    git(&dir, &["add", "."]);
    git(&dir, &["commit", "-qm", "old"]);
    std::fs::copy(fixtures().join("fill_new.st"), dir.join("tank.st")).unwrap();
    let b = sfc_in(&dir, &["build", "tank.st", "--target", "plcopen", "-o", "tank.xml"]);
    assert_eq!(b.status.code(), Some(0));
    std::fs::write(dir.join("other.xml"), "<note>still not</note>\n").unwrap();
    let o = Command::new("git").current_dir(&dir).args(["diff"]).output().unwrap();
    let shown = out(&o);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for file in ["tank.st", "tank.xml"] {
        assert!(shown.contains(&format!("sfc diff {file}\n--- a/{file}\n+++ b/{file}\n")), "{shown}");
    }
    assert_eq!(shown.matches("~ step Mixing renamed Stirring").count(), 2, "{shown}");
    assert!(shown.contains("-<note>not a chart</note>") && shown.contains("+<note>still not</note>"), "{shown}");
    // With --no-ext-diff, the charts as canonical text.
    let o = Command::new("git").current_dir(&dir).args(["diff", "--no-ext-diff", "tank.xml"]).output().unwrap();
    assert!(out(&o).contains("+    STEP Stirring:"), "{}", out(&o));
    let o = sfc_in(&dir, &["git", "setup"]);
    assert!(out(&o).contains("already"), "{}", out(&o));
    assert_eq!(std::fs::read_to_string(dir.join(".gitattributes")).unwrap(), attrs);
}

#[test]
fn git_setup_outside_a_repository_says_so() {
    let dir = tmp("norepo");
    let o = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .current_dir(&dir)
        .env("GIT_CEILING_DIRECTORIES", dir.parent().unwrap())
        .args(["git", "setup"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not in a git repository"));
}

/// `--format svg|html`: the old and new charts drawn side by side, the changed elements
/// coloured by a style on their drawing's `data-id`, scoped to their side.
#[test]
fn the_charts_are_drawn_side_by_side_with_the_changes_coloured() {
    let o = sfc_in(&fixtures(), &["diff", "--format", "svg", "fill_old.st", "fill_new.st"]);
    assert_eq!(o.status.code(), Some(1));
    let svg = out(&o);
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""), "{svg}");
    assert_eq!(svg.matches("<svg ").count(), 3, "one drawing per side in one document");
    assert!(svg.contains("class=\"sfc-old\"") && svg.contains("class=\"sfc-new\""));
    // Renamed: orange on both sides; added: green on the new side; a drawn element per rule.
    assert!(svg.contains(".sfc-old g[data-id=\"step:Mixing\"] rect, ") && svg.contains("#ef6c00"), "{svg}");
    assert!(svg.contains(".sfc-new g[data-id=\"step:Stirring\"] rect, "), "{svg}");
    assert!(svg.contains(".sfc-new g[data-id=\"step:Settling\"] rect, ") && svg.contains("#2e7d32"), "{svg}");
    assert!(svg.contains("<g data-id=\"step:Settling\">") && svg.contains("<g data-id=\"step:Mixing\">"));
    assert!(!svg.contains(".sfc-old g[data-id=\"step:Settling\"]"), "an added step is not on the old side");
    let o = sfc_in(&fixtures(), &["diff", "--format", "html", "fill_old.st", "fill_new.st"]);
    let page = out(&o);
    assert!(page.starts_with("<!DOCTYPE html>"), "{page}");
    assert!(page.contains("<li class=\"changed\">~ step Mixing renamed Stirring</li>"), "{page}");
    assert!(page.contains("<li class=\"added\">+ step Settling</li>"), "{page}");
    assert_eq!(page.matches("<figure>").count(), 2);
}

/// Two revisions of a project file as a tool saves them (the shape of a real public history,
/// see tests/diff/README.md): a short readable summary, the XML churn counted in one line.
#[test]
fn revisions_of_a_project_file_read_as_a_short_summary() {
    let dir = fixtures().join("history");
    let o = sfc_in(&dir, &["diff", "--color", "never", "crossing_v1.xml", "crossing_v2.xml"]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let expected = std::fs::read_to_string(dir.join("crossing.expected.txt")).unwrap();
    assert_eq!(out(&o), expected);
    assert!(out(&o).lines().count() < 15, "{}", out(&o));
    // The drawn chart itself is equal in meaning: only its layout and header changed.
    let v1 = std::fs::read_to_string(dir.join("crossing_v1.xml")).unwrap();
    let v2 = std::fs::read_to_string(dir.join("crossing_v2.xml")).unwrap();
    let lines_changed = v1.lines().zip(v2.lines()).filter(|(a, b)| a != b).count();
    assert!(lines_changed > 5, "the XML changes on many lines");
    let o = sfc_in(&dir, &["diff", "--color", "never", "--layout", "crossing_v1.xml", "crossing_v2.xml"]);
    assert!(out(&o).contains("layout comment \"The sequence of a pedestrian crossing"), "{}", out(&o));
    assert!(out(&o).contains("modificationDateTime=\"2024-05-21T16:44:03\""), "{}", out(&o));
}
