//! `sfc check --profile matiec`: the fixtures in `tests/matiec/check/` mark each expected
//! SFC09xx warning with `(*! SFC09nn *)` on the line where it is reported; the command must give
//! exactly those (code, line) pairs, and none of them without `--profile matiec`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/matiec/check");
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    files.sort();
    files
}

/// (code, line) of the SFC09xx diagnostics of `sfc check` with `args`.
fn reported(path: &Path, args: &[&str]) -> Vec<(String, u64)> {
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .arg("check")
        .arg(path)
        .args(["--format", "json"])
        .args(args)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}: {}", path.display(), String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut found: Vec<(String, u64)> = json
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["code"].as_str().unwrap().starts_with("SFC09"))
        .map(|d| {
            assert_eq!(d["severity"], "warning");
            assert!(d["element"].is_string(), "{d} names no element");
            (d["code"].as_str().unwrap().to_string(), d["line"].as_u64().unwrap())
        })
        .collect();
    found.sort();
    found
}

fn expected(path: &Path) -> Vec<(String, u64)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if let Some(m) = line.split("(*!").nth(1) {
            for code in m.trim_end_matches("*)").split_whitespace().filter(|c| c.starts_with("SFC")) {
                out.push((code.trim_end_matches("*)").to_string(), i as u64 + 1));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn matiec_differences_are_reported_on_their_elements() {
    let files = fixtures();
    assert!(files.len() >= 8);
    let mut codes = std::collections::BTreeSet::new();
    for f in &files {
        let want = expected(f);
        codes.extend(want.iter().map(|(c, _)| c.clone()));
        assert_eq!(reported(f, &["--profile", "matiec"]), want, "{}", f.display());
        assert!(reported(f, &[]).is_empty(), "{}: SFC09xx without --profile matiec", f.display());
    }
    for c in ["SFC0901", "SFC0902", "SFC0903", "SFC0904", "SFC0905", "SFC0906", "SFC0907", "SFC0908"] {
        assert!(codes.contains(c), "no fixture shows {c}");
        let out = Command::new(env!("CARGO_BIN_EXE_sfc")).args(["check", "--explain", c]).output().unwrap();
        assert!(out.status.success() && String::from_utf8_lossy(&out.stdout).contains("MatIEC"), "{c}");
    }
}

#[test]
fn the_warning_reads_as_a_sentence_on_the_element() {
    let f = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/matiec/check/scan0.st");
    let out =
        Command::new(env!("CARGO_BIN_EXE_sfc")).arg("check").arg(&f).args(["--profile", "matiec"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("warning[SFC0901]: T1 is already tested in scan 0 under MatIEC"), "{err}");
    assert!(err.contains("scan0.st:10:"), "{err}");
}
