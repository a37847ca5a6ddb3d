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

/// The way back: the ST that `sfc build --target st` writes is an sfc input. For every example
/// scenario: `sfc check` of the ST prints nothing the chart's check does not, and `sfc sim` of
/// it with the scenario gives the chart's variables the values `sfc sim` of the chart gives
/// them, scan by scan.
#[test]
fn the_st_reads_back_and_simulates_like_the_chart() {
    let root = common::root();
    let dir = common::scratch("st-back");
    let sfc = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).current_dir(&root).output().unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).to_string(),
            String::from_utf8_lossy(&out.stderr).to_string(),
        )
    };
    let mut n = 0;
    for ex in ["blinker/blinker", "carwash/carwash", "spindle/spindle", "traffic/traffic"] {
        let chart = format!("examples/{ex}.st");
        let st = dir.join(format!("{}.plain.st", ex.replace('/', "_")));
        let (code, _, err) = sfc(&["build", &chart, "--target", "st", "-o", st.to_str().unwrap()]);
        assert_eq!(code, Some(0), "{chart}: {err}");
        let (_, _, chart_check) = sfc(&["check", &chart]);
        let (code, _, st_check) = sfc(&["check", st.to_str().unwrap()]);
        assert_eq!(code, Some(0), "{chart}: the ST does not check:\n{st_check}");
        let codes = |s: &str| -> Vec<String> {
            s.lines().filter(|l| l.contains("[SFC")).map(|l| l.split(']').next().unwrap_or("").to_string()).collect()
        };
        for c in codes(&st_check) {
            assert!(codes(&chart_check).contains(&c), "{chart}: the ST has {c}, the chart has not:\n{st_check}");
        }
        let base = root.join("examples").join(ex);
        let scenarios: Vec<PathBuf> = std::fs::read_dir(base.parent().unwrap())
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.to_string_lossy().ends_with(".scenario.toml"))
            .collect();
        for s in scenarios {
            // The scenario's inputs without its expectations (the ST has no steps to expect).
            // (the examples write each expectation on one line)
            let text = std::fs::read_to_string(&s).unwrap();
            let kept: Vec<&str> =
                text.lines().filter(|l| !l.starts_with("expect") && !l.starts_with("chart")).collect();
            let inputs = dir.join(s.file_name().unwrap());
            std::fs::write(&inputs, kept.join("\n")).unwrap();
            let trace = |file: &str| -> Vec<serde_json::Value> {
                let (_, out, err) = sfc(&["sim", file, "--scenario", inputs.to_str().unwrap(), "--trace", "-"]);
                let rows: Vec<serde_json::Value> = out.lines().filter_map(|l| serde_json::from_str(l).ok()).collect();
                assert!(!rows.is_empty(), "{file} with {}: no trace\n{err}", s.display());
                rows
            };
            let a = trace(&chart);
            let b = trace(st.to_str().unwrap());
            assert_eq!(a.len(), b.len(), "{chart} {}: scans", s.display());
            for (ra, rb) in a.iter().zip(&b) {
                for (k, v) in ra["vars"].as_object().unwrap() {
                    assert_eq!(Some(v), rb["vars"].get(k), "{chart} {}: scan {}: {k}", s.display(), ra["scan"]);
                }
            }
            n += 1;
        }
    }
    assert!(n >= 6, "{n} scenarios");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The public corpus (`../shared/corpus`: Beremiz's projects, MatIEC's SFC test) through the ST
/// target, compiled by the real compilers: `--st-dialect matiec` by `iec2c -f -l -p` (as
/// Beremiz runs it), `--st-dialect strucpp` by STruC++ and g++ (syntax only).
#[test]
fn the_public_corpus_compiles_with_matiec_and_strucpp() {
    let root = common::root();
    let iec2c = PathBuf::from(tool("build-matiec.sh", "matiec"));
    let strucpp = tool("build-strucpp.sh", "strucpp");
    let runtime = root.join("target/tools/strucpp/src/runtime/include");
    let dir = common::scratch("st-corpus");
    let corpus = root.join("../shared/corpus");
    let files: Vec<PathBuf> =
        ["beremiz/first_steps.plc.xml", "beremiz/svghmi_traffic_light.plc.xml", "matiec/SFC_TEST.xml"]
            .iter()
            .map(|f| corpus.join(f))
            .collect();
    let mut failures = Vec::new();
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        for dialect in ["matiec", "strucpp"] {
            let out = dir.join(format!("{name}.{dialect}.st"));
            let b = Command::new(env!("CARGO_BIN_EXE_sfc"))
                .args(["build", f.to_str().unwrap(), "--target", "st", "--st-dialect", dialect, "-o"])
                .arg(&out)
                .output()
                .unwrap();
            if !b.status.success() {
                failures.push(format!("{name} {dialect}: sfc build: {}", String::from_utf8_lossy(&b.stderr)));
                continue;
            }
            let compiled = if dialect == "matiec" {
                let c = dir.join(format!("{name}.c"));
                std::fs::create_dir_all(&c).unwrap();
                Command::new("timeout")
                    .arg("60")
                    .arg(&iec2c)
                    .args(["-f", "-l", "-p", "-I"])
                    .arg(root.join("target/tools/matiec/lib"))
                    .arg("-T")
                    .arg(&c)
                    .arg(&out)
                    .output()
                    .unwrap()
            } else {
                let cpp = dir.join(format!("{name}.cpp"));
                let mut args: Vec<String> = strucpp.split_whitespace().map(String::from).collect();
                let program = args.remove(0);
                let s = Command::new(program).args(&args).arg(&out).arg("-o").arg(&cpp).output().unwrap();
                if !s.status.success() {
                    s
                } else {
                    Command::new("g++")
                        .args(["-std=c++17", "-fsyntax-only", "-I"])
                        .arg(&runtime)
                        .arg(&cpp)
                        .output()
                        .unwrap()
                }
            };
            if !compiled.status.success() {
                failures.push(format!(
                    "{name} {dialect}: the compiler refuses it:\n{}{}",
                    String::from_utf8_lossy(&compiled.stdout),
                    String::from_utf8_lossy(&compiled.stderr)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    println!("{} corpus files, each compiled by MatIEC and by STruC++", files.len());
    let _ = std::fs::remove_dir_all(&dir);
}
