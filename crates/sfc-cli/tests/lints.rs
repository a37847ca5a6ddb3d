//! The input-facing crates keep the workspace lints (`Cargo.toml`, `[workspace.lints]`: no
//! `unwrap`, `expect` or unchecked indexing on data from outside). This runs clippy on every
//! crate whose manifest opts in with `[lints] workspace = true`, so a crate that joins is
//! checked without touching this test. About a minute of CPU on a cold target directory.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Workspace crates whose manifest has `[lints]` with `workspace = true`.
fn opted_in() -> Vec<String> {
    let mut out = Vec::new();
    let entries = std::fs::read_dir(root().join("crates")).expect("crates/");
    for e in entries.flatten() {
        let Ok(text) = std::fs::read_to_string(e.path().join("Cargo.toml")) else { continue };
        let doc: toml_edit::DocumentMut = text.parse().expect("a valid manifest");
        let opted = doc.get("lints").and_then(|l| l.get("workspace")).and_then(|w| w.as_bool()) == Some(true);
        if opted {
            out.push(doc["package"]["name"].as_str().expect("a package name").to_string());
        }
    }
    out.sort();
    out
}

#[test]
fn input_facing_crates_pass_clippy() {
    let crates = opted_in();
    for must in ["sfc-syntax", "sfc-plcopen", "sfc-server", "sfc-runtime", "sfc-driver", "sfc-diagnostics", "sfc-lsp"] {
        assert!(crates.iter().any(|c| c == must), "{must} opts into the workspace lints");
    }
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let has_clippy = Command::new(&cargo).args(["clippy", "--version"]).output().is_ok_and(|o| o.status.success());
    if !has_clippy {
        assert!(std::env::var_os("CI").is_none(), "cargo clippy is not installed");
        eprintln!("cargo clippy is not installed: skipped");
        return;
    }
    let mut cmd = Command::new(&cargo);
    cmd.current_dir(root()).args(["clippy", "--quiet", "--lib", "--message-format", "short"]);
    for c in &crates {
        cmd.args(["-p", c]);
    }
    let out = cmd.output().expect("cargo clippy runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    // Only the denied lints fail the build; other clippy warnings are not this test's business.
    assert!(out.status.success(), "clippy denies code in {crates:?}:\n{stderr}");
}
