//! Interval expectations and forbidden events of scenario files (`docs/scenarios.md`): every
//! `tests/scenarios/*.scenario.toml` runs, and its outcome (PASS, or FAIL with the failure
//! lines) must equal the `.expected` file beside it (rewritten with `UPDATE_EXPECT=1`).

use sfc_sim::scenario::run_path;
use std::path::{Path, PathBuf};

fn folder() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenarios")
}

#[test]
fn outcomes_match_the_expected_files() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(folder())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".scenario.toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 8, "the fixtures were found");
    let update = std::env::var_os("UPDATE_EXPECT").is_some();
    let mut problems = Vec::new();
    for path in &files {
        // Names relative to the folder, so the expected text does not depend on the checkout.
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let cwd = std::env::current_dir().unwrap();
        std::env::set_current_dir(folder()).unwrap();
        let outcome = run_path(Path::new(&name));
        std::env::set_current_dir(cwd).unwrap();
        let text = match outcome {
            Ok(o) if o.passed() => "PASS\n".to_string(),
            Ok(o) => {
                let mut t = String::from("FAIL\n");
                for f in &o.failures {
                    t.push_str(f);
                    t.push('\n');
                }
                if let Some(e) = &o.error {
                    t.push_str(e);
                    t.push('\n');
                }
                t
            }
            Err(e) => format!("INVALID\n{e}\n"),
        };
        let expected_path = path.with_file_name(name.replace(".scenario.toml", ".expected"));
        if update {
            std::fs::write(&expected_path, &text).unwrap();
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
        if expected != text {
            problems.push(format!("{name}:\n--- expected\n{expected}--- actual\n{text}"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
