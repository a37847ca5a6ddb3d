//! The README's section "Run your chart on OpenPLC v4, OpenPLC v3, Beremiz and CODESYS", run as
//! a user runs it: its shell block, word for word, in a scratch directory beside the examples,
//! with `sfc` this build's binary, `strucpp` STruC++'s command line and `iec2c` MatIEC's
//! compiler, both built from `../shared/tools` into `target/tools/` (as `scripts/test-deps.sh`
//! does). The STruC++ REPL must report the spray valve on after Start, `iec2c` must accept the
//! MatIEC file with OpenPLC v3's options, and the CODESYS file must be PLCopen XML that sfc
//! reads back with the ST POUs.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

/// Builds a tool with its script from `../shared/tools` into `target/tools/NAME`; what the
/// script prints (the path or the command).
fn tool(script: &str, name: &str) -> String {
    let root = common::root();
    let dest = root.join("target/tools").join(name);
    let out = Command::new(root.join("../shared/tools").join(script))
        .arg(&dest)
        .current_dir(&root)
        .output()
        .unwrap_or_else(|e| panic!("cannot run ../shared/tools/{script}: {e}"));
    assert!(
        out.status.success(),
        "../shared/tools/{script} could not build {name}:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// The shell block after the marker naming this test.
fn readme_block(root: &Path) -> String {
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let marker = readme.find("crates/sfc-cli/tests/st_readme.rs").expect("the README names this test");
    let rest = &readme[marker..];
    let start = rest.find("```sh\n").expect("a shell block after the marker") + "```sh\n".len();
    let end = rest[start..].find("```").expect("the block ends");
    rest[start..start + end].to_string()
}

#[test]
fn the_readme_commands_run_on_openplc_v4_openplc_v3_and_codesys() {
    let root = common::root();
    let iec2c = PathBuf::from(tool("build-matiec.sh", "matiec"));
    let strucpp = tool("build-strucpp.sh", "strucpp");
    let dir = common::scratch("st-readme");
    std::os::unix::fs::symlink(root.join("examples"), dir.join("examples")).unwrap();
    std::os::unix::fs::symlink(root.join("target/tools/matiec"), dir.join("matiec")).unwrap();
    let block = readme_block(&root);
    let script = format!(
        "set -euo pipefail\nsfc() {{ '{}' \"$@\"; }}\nstrucpp() {{ {strucpp} \"$@\"; }}\niec2c() {{ '{}' \"$@\"; }}\n{block}",
        env!("CARGO_BIN_EXE_sfc"),
        iec2c.display()
    );
    let out = Command::new("bash").arg("-c").arg(&script).current_dir(&dir).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "the README's commands failed:\n{block}\nstdout:\n{stdout}\nstderr:\n{stderr}");
    assert!(
        stdout.contains("CARWASH.SPRAYVALVE : BOOL = TRUE"),
        "STruC++'s REPL did not report the spray valve on after Start:\n{stdout}"
    );
    for f in ["POUS.c", "Config0.c", "Res0.c"] {
        assert!(dir.join(f).is_file(), "iec2c wrote no {f}:\n{stdout}\n{stderr}");
    }
    // (the note that a CONFIGURATION was added for OpenPLC v3)
    assert!(stderr.contains("SFC0808"), "{stderr}");
    let xml = std::fs::read_to_string(dir.join("carwash_codesys.xml")).unwrap();
    assert!(xml.starts_with("<?xml") && xml.contains("<pou name=\"CarWash\" pouType=\"program\">"), "{xml}");
    let back = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["build", "carwash_codesys.xml", "--target", "text"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&back.stdout);
    assert!(text.contains("FUNCTION_BLOCK SfcActionControl") && text.contains("PROGRAM CarWash"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}
