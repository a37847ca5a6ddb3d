//! Command lines and what they print, as data: every `*.case` file under `tests/profile`
//! (the profile chosen from the file: CODESYS, TwinCAT and e!COCKPIT exports run with `codesys`)
//! and `tests/nested` (charts inside charts, two levels deep) holds one `sfc` command line
//! (`args:`, run in the case's directory) and its exit status (`status:`); `NAME.stdout` and
//! `NAME.stderr` beside it are what the command must print, exactly. `SFC_BLESS=1` writes them
//! anew from what the binary prints (then read the difference before committing it).

mod common;

use std::path::{Path, PathBuf};

struct Case {
    path: PathBuf,
    args: Vec<String>,
    status: i32,
}

fn read_case(path: &Path) -> Case {
    let text = std::fs::read_to_string(path).unwrap();
    let (mut args, mut status) = (None, None);
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#')) {
        match line.split_once(':') {
            Some(("args", a)) => args = Some(a.split_whitespace().map(String::from).collect()),
            Some(("status", s)) => status = Some(s.trim().parse().unwrap()),
            _ => panic!("{}: unknown line `{line}`", path.display()),
        }
    }
    Case {
        path: path.to_path_buf(),
        args: args.unwrap_or_else(|| panic!("{}: no `args:`", path.display())),
        status: status.unwrap_or(0),
    }
}

fn cases(dir: &str) -> Vec<Case> {
    let dir = common::root().join("crates/sfc-cli/tests").join(dir);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "case"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no cases in {}", dir.display());
    files.iter().map(|p| read_case(p)).collect()
}

fn run_cases(dir: &str) {
    let bless = std::env::var_os("SFC_BLESS").is_some();
    let mut failures = Vec::new();
    for case in cases(dir) {
        let here = case.path.parent().unwrap();
        let args: Vec<&str> = case.args.iter().map(String::as_str).collect();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_sfc"))
            .args(&args)
            .current_dir(here)
            .env("NO_COLOR", "1")
            .env_remove("SFC_PROGRESS_AFTER_MS")
            .output()
            .expect("sfc runs");
        let name = case.path.file_stem().unwrap().to_string_lossy().to_string();
        let got = [("stdout", String::from_utf8_lossy(&out.stdout)), ("stderr", String::from_utf8_lossy(&out.stderr))];
        if out.status.code() != Some(case.status) {
            failures.push(format!(
                "{}: exit status {:?}, expected {}\n{}{}",
                case.path.display(),
                out.status.code(),
                case.status,
                got[0].1,
                got[1].1
            ));
        }
        for (stream, text) in &got {
            let expected_path = here.join(format!("{name}.{stream}"));
            if bless {
                if text.is_empty() {
                    let _ = std::fs::remove_file(&expected_path);
                } else {
                    std::fs::write(&expected_path, text.as_bytes()).unwrap();
                }
                continue;
            }
            let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
            if expected != *text {
                failures.push(format!(
                    "{}: {stream} differs from {}\n--- expected\n{expected}--- actual\n{text}",
                    case.path.display(),
                    expected_path.display()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// A CODESYS, TwinCAT or e!COCKPIT export runs with profile `codesys` (with a note), unless
/// `--profile` or the scenario says otherwise; a Beremiz file stays `iec`.
#[test]
fn the_profile_is_chosen_from_the_file() {
    run_cases("profile");
}

/// `sfc run` of a TwinCAT export runs with `codesys`, says so, and its monitor's `hello` names
/// the profile; `--profile iec` overrides it without a note.
#[test]
fn run_takes_the_profile_from_the_file() {
    let chart = "crates/sfc-cli/tests/profile/final_scan.twincat.xml";
    let mut run = common::Run::start(&[chart, "--monitor", "127.0.0.1:0", "--no-retain", "--halted", "--scans", "5"]);
    let note = run.line("the profile note", 20, |l| l.starts_with("note: running with profile codesys"));
    assert_eq!(
        note,
        format!(
            "note: running with profile codesys: {chart} is a TwinCAT export, and TwinCAT runs SFC by CODESYS's rules \
             (--profile iec to use IEC 61131-3's)"
        )
    );
    let line = run.line("the monitor URL", 20, |l| l.starts_with("sfc run: monitor on "));
    let url = line.strip_prefix("sfc run: monitor on ").unwrap();
    let url = format!("{}?token=t0k3n", url.split(' ').next().unwrap());
    let mut ws = common::Ws::connect(&url);
    let hello = ws.next().expect("hello");
    assert_eq!(hello["profile"], "codesys", "{hello}");
    drop(ws);
    drop(run);

    let out = common::command(&["run", chart, "--scans", "3", "--no-retain", "--profile", "iec"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("note: running with profile"), "{err}");
    // `profile` in a run configuration chooses too.
    let dir = common::scratch("profile-config");
    let config = dir.join("plant.toml");
    let abs = common::root().join(chart);
    std::fs::write(&config, format!("chart = {:?}\nprofile = \"iec\"\n", abs.to_str().unwrap())).unwrap();
    let out = common::command(&["run", "--config", config.to_str().unwrap(), "--scans", "3", "--no-retain"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("note: running with profile"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
    let out = common::command(&["run", chart, "--scans", "3", "--no-retain", "--profile", "cds"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown profile `cds`"));
}

/// Charts inside charts, two levels deep (`tests/nested/machine.st`: the program Main calls the
/// lift, an SFC function block instance whose action ACT_Load is written in SFC and runs the
/// gripper's SFC action ACT_Grip): scenarios, traces, `--explain`, `--stats`, coverage.
#[test]
fn nested_charts_through_the_binary() {
    run_cases("nested");
}

/// The monitor of `sfc run` on the nested machine: `hello` lists the nested charts' steps by
/// path, a breakpoint on a step of the gripper's action chart halts the run when it becomes
/// active, `explain` of that step descends into its chart and reads its instance's variables,
/// the snapshot names the nested active steps, and `timing` counts them.
#[test]
fn the_monitor_on_nested_charts() {
    let chart = "crates/sfc-cli/tests/nested/machine.st";
    let mut run = common::Run::start(&[chart, "--monitor", "127.0.0.1:0", "--no-retain", "--halted", "--for", "T#60s"]);
    let line = run.line("the monitor URL", 20, |l| l.starts_with("sfc run: monitor on "));
    let url = line.strip_prefix("sfc run: monitor on ").unwrap();
    let url = format!("{}?token=t0k3n", url.split(' ').next().unwrap());
    let mut ws = common::Ws::connect(&url);
    let hello = ws.next().expect("hello");
    let steps: Vec<&str> = hello["steps"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    for s in ["Idle", "Lift.Home", "Lift.ACT_Load.Gripping", "Lift.Grip.ACT_Grip.Holding"] {
        assert!(steps.contains(&s), "{s} in {steps:?}");
    }
    let transitions: Vec<&str> =
        hello["transitions"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert!(transitions.contains(&"Lift.Grip.ACT_Grip.TClosed"), "{transitions:?}");
    // A breakpoint on a step two levels down, by its path (any case).
    let r = ws.cmd(
        1,
        serde_json::json!({"cmd": "breakpoint", "op": "set", "kind": "step", "name": "lift.grip.act_grip.closing"}),
    );
    assert_eq!(r["ok"], true, "{r}");
    assert_eq!(r["result"][0]["name"], "Lift.Grip.ACT_Grip.Closing", "{r}");
    let r = ws.cmd(2, serde_json::json!({"cmd": "breakpoint", "op": "set", "name": "Lift.Grip.Closed"}));
    assert_eq!(r["ok"], false, "{r}");
    let r = ws.cmd(3, serde_json::json!({"cmd": "set", "name": "Start", "value": true}));
    assert_eq!(r["ok"], true, "{r}");
    let r = ws.cmd(4, serde_json::json!({"cmd": "continue"}));
    assert_eq!(r["ok"], true, "{r}");
    let hit = ws.until("the breakpoint", |m| m["type"] == "event" && m["kind"] == "breakpoint");
    assert_eq!(hit["step"], "Lift.Grip.ACT_Grip.Closing", "{hit}");
    ws.until("the halt", |m| m["type"] == "halted");
    // Why is it stuck: the condition of the gripper's chart, with its step time.
    let r = ws.cmd(5, serde_json::json!({"cmd": "explain", "step": "Lift.Grip.ACT_Grip.Closing"}));
    assert_eq!(r["ok"], true, "{r}");
    let t = &r["result"]["transitions"][0];
    assert_eq!(t["transition"], "Lift.Grip.ACT_Grip.TClosed", "{r}");
    assert_eq!(t["operands"][0]["operand"], "Closing.T", "{r}");
    assert_eq!(t["operands"][0]["value"], "T#0s", "{r}");
    let r = ws.cmd(6, serde_json::json!({"cmd": "explain", "step": "Lift.ACT_Load.Gripping"}));
    let t = &r["result"]["transitions"][0];
    assert_eq!(
        (t["transition"].as_str(), t["guard"].as_str()),
        (Some("Lift.ACT_Load.TGripped"), Some("Grip.Closed")),
        "{r}"
    );
    assert_eq!(t["operands"][0]["value"], "FALSE", "the instance's variable is read: {r}");
    assert_eq!(t["needs"][0], "Grip.Closed is FALSE; needs TRUE", "{r}");
    let r = ws.cmd(7, serde_json::json!({"cmd": "explain", "step": "Lift.Top"}));
    assert_eq!(r["ok"], false, "{r}");
    // The snapshot names the nested active steps by path.
    ws.send(&serde_json::json!({"id": 8, "cmd": "snapshot"}).to_string());
    let snap = ws.until("a snapshot", |m| m["type"] == "snapshot");
    let mut active: Vec<&str> =
        snap["active"].as_array().unwrap().iter().map(|a| a["step"].as_str().unwrap()).collect();
    active.sort_unstable();
    assert_eq!(active, ["Lift.ACT_Load.Gripping", "Lift.Grip.ACT_Grip.Closing", "Loading"], "{snap}");
    let r = ws.cmd(9, serde_json::json!({"cmd": "timing"}));
    let closing =
        r["result"]["steps"].as_array().unwrap().iter().find(|s| s["step"] == "Lift.Grip.ACT_Grip.Closing").cloned();
    assert_eq!(closing.map(|s| s["activations"].clone()), Some(serde_json::json!(1)), "{r}");
}

/// The CSV and VCD traces of the nested machine name every chart's steps by path (VCD: one scope
/// per instance and action chart); compared with `tests/nested/machine.trace.csv` and `.vcd`.
#[test]
fn nested_charts_in_csv_and_vcd_traces() {
    let dir = common::scratch("nested-traces");
    let here = common::root().join("crates/sfc-cli/tests/nested");
    for ext in ["csv", "vcd"] {
        let out = dir.join(format!("t.{ext}"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_sfc"))
            .args(["sim", "machine.st", "--scenario", "machine.scenario.toml", "--trace", out.to_str().unwrap()])
            .current_dir(&here)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        let got = std::fs::read_to_string(&out).unwrap();
        // The VCD header's date is the day it was written.
        let got: String = got.lines().filter(|l| !l.starts_with("$date")).map(|l| format!("{l}\n")).collect();
        let expected_path = here.join(format!("machine.trace.{ext}"));
        if std::env::var_os("SFC_BLESS").is_some() {
            std::fs::write(&expected_path, &got).unwrap();
        }
        assert_eq!(got, std::fs::read_to_string(&expected_path).unwrap(), "{}", expected_path.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The coverage files of the nested machine: every step and transition of every chart, by path,
/// at the line of its declaration (the steps of actions written in SFC included); compared with
/// `tests/nested/machine.coverage.json` and `.lcov`.
#[test]
fn nested_coverage_files() {
    let dir = common::scratch("nested-coverage");
    let here = common::root().join("crates/sfc-cli/tests/nested");
    for (format, ext) in [("json", "json"), ("lcov", "lcov"), ("cobertura", "xml")] {
        let out = dir.join(format!("c.{ext}"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_sfc"))
            .args(["test", "machine.scenario.toml", "--coverage", format, "-o", out.to_str().unwrap()])
            .current_dir(&here)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        let got = std::fs::read_to_string(&out).unwrap();
        if format == "cobertura" {
            // Every step and transition line is there (the file's timestamp changes).
            for line in [14, 15, 40, 41, 52, 53, 79, 80] {
                assert!(got.contains(&format!("<line number=\"{line}\"")), "line {line} in\n{got}");
            }
            continue;
        }
        // The tool's version names the commit it was built from.
        let got: String =
            got.lines().filter(|l| !l.trim_start().starts_with("\"tool\":")).map(|l| format!("{l}\n")).collect();
        let expected_path = here.join(format!("machine.coverage.{ext}"));
        if std::env::var_os("SFC_BLESS").is_some() {
            std::fs::write(&expected_path, &got).unwrap();
        }
        assert_eq!(got, std::fs::read_to_string(&expected_path).unwrap(), "{}", expected_path.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The coverage of a PLCopen XML chart (the CODESYS export) is located in the XML: each step at
/// its `<step>`, each transition at its `<transition>` (was: no line, an empty lcov file).
#[test]
fn coverage_of_an_export_has_its_xml_lines() {
    let dir = common::scratch("xml-coverage");
    let out = dir.join("c.lcov");
    let here = common::root().join("crates/sfc-cli/tests/profile");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["test", "final_scan.scenario.toml", "--coverage", "lcov", "-o", out.to_str().unwrap()])
        .current_dir(&here)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let got = std::fs::read_to_string(&out).unwrap();
    let expected_path = here.join("final_scan.coverage.lcov");
    if std::env::var_os("SFC_BLESS").is_some() {
        std::fs::write(&expected_path, &got).unwrap();
    }
    assert_eq!(got, std::fs::read_to_string(&expected_path).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}
