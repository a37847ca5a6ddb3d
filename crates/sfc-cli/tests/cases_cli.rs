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
    let out = common::command(&["run", chart, "--scans", "3", "--no-retain", "--profile", "cds"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown profile `cds`"));
}
