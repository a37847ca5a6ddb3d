//! `sfc build` for the code targets, on the binary: ATMT/EATMT flattening and state numbering,
//! the S7-200 statement list in both methods with its symbol table, and every example built to
//! every target its README claims.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sfc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).current_dir(root()).args(args).output().expect("sfc runs")
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-targets-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// `--flatten` compiles the simultaneous branches of a chart into one automaton through the
/// command (the check before the build must not refuse them); without it the branches are
/// refused with a hint.
#[test]
fn flatten_works_through_the_command() {
    let twin = "crates/sfc-codegen/tests/atmt/twin.st";
    let out = sfc(&["build", twin, "--target", "eatmt", "--flatten"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let expected = std::fs::read_to_string(root().join("crates/sfc-codegen/tests/atmt/twin.flat.eatmt")).unwrap();
    assert_eq!(text(&out.stdout), expected);
    assert!(text(&out.stderr).contains("flattened into 5 states"), "{}", text(&out.stderr));
    let out = sfc(&["build", twin, "--target", "eatmt"]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.contains("SFC0404") && err.contains("--flatten"), "{err}");
    // Two networks, each with its initial step: flattened into pairs of states.
    let two = "crates/sfc-codegen/tests/atmt/two_networks.st";
    let out = sfc(&["build", two, "--target", "atmt", "--flatten", "-o", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let expected =
        std::fs::read_to_string(root().join("crates/sfc-codegen/tests/atmt/two_networks.flat.atmt")).unwrap();
    assert_eq!(text(&out.stdout), expected);
}

/// interfaces.md: an untagged initial step is state 0 wherever it is declared.
#[test]
fn untagged_initial_step_is_state_zero() {
    let out = sfc(&["build", "tests/fixtures/valid/atmt/initial_step_last.st", "--target", "atmt"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout), "3[0 0 1;1 1 2;2 2 0][0 0 0]");
    let out = sfc(&["check", "tests/fixtures/valid/atmt/initial_step_last.st", "--target", "atmt"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

/// Both STL methods from the command, each saying which it is; the symbol table beside the
/// program; the STL options refused for other targets.
#[test]
fn stl_methods_and_symbol_table() {
    let d = temp_dir("stl");
    let chart = "crates/sfc-codegen/tests/stl/carwash_textbook.st";
    let out = sfc(&["build", chart, "--target", "stl"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let setreset = text(&out.stdout);
    assert!(setreset.contains("// Method: SET/RESET"), "{setreset}");
    assert!(!setreset.contains("LSCR"));
    let csv = d.join("carwash.csv");
    let prog = d.join("carwash.stl");
    let out = sfc(&[
        "build",
        chart,
        "--target",
        "stl",
        "--stl-method",
        "scr",
        "--symbols",
        csv.to_str().unwrap(),
        "-o",
        prog.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(out.stdout.is_empty());
    let scr = std::fs::read_to_string(&prog).unwrap();
    assert!(scr.contains("// Method: SCR") && scr.contains("LSCR   S0.1") && scr.contains("SCRT   S0.2"), "{scr}");
    assert!(scr.is_ascii());
    let symbols = std::fs::read_to_string(&csv).unwrap();
    assert!(symbols.starts_with("Symbol,Address,Comment\n"), "{symbols}");
    assert!(symbols.contains("\nSpraying,S0.1,"), "{symbols}");
    // The symbol table and the method apply to STL only: a usage error, nothing written.
    let other = d.join("other.csv");
    let out = sfc(&["build", chart, "--target", "st", "--symbols", other.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!other.exists());
    let out = sfc(&["build", chart, "--target", "stl", "--stl-method", "ladder"]);
    assert_eq!(out.status.code(), Some(2));
}

/// A TIME variable used as a preset is folded with a warning on standard error; the program is
/// still built (exit 0).
#[test]
fn time_parameters_are_folded_with_a_warning() {
    let out = sfc(&["build", "examples/carwash/carwash.st", "--target", "stl"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(err.contains("warning[SFC0817]") && err.contains("MaxTravelTime"), "{err}");
    let stl = text(&out.stdout);
    assert!(stl.contains("INCD   VD0"), "Washes := Washes + 1 counts in a double word");
    assert!(stl.contains("SFCError"), "the supervision times set SFCError");
}

/// Every `sfc build` command line in an example's README runs as written (outputs to a
/// temporary directory), and the car wash claims the S7-200 target.
#[test]
fn examples_build_to_every_target_their_readme_claims() {
    let d = temp_dir("readme");
    let mut ran = Vec::new();
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(root().join("examples")).unwrap().flatten().map(|e| e.path()).collect();
    entries.sort();
    for dir in entries.into_iter().filter(|p| p.is_dir()) {
        let readme = std::fs::read_to_string(dir.join("README.md")).expect("every example has a README");
        let mut claims = Vec::new();
        for line in readme.lines() {
            let line = line.split('#').next().unwrap_or("").trim();
            let Some(rest) = line.strip_prefix("sfc build ") else { continue };
            let mut args: Vec<String> = vec!["build".into()];
            let mut words = rest.split_whitespace().peekable();
            while let Some(w) = words.next() {
                args.push(w.to_string());
                if matches!(w, "-o" | "--output" | "--symbols") {
                    let file = words.next().expect("an output file");
                    args.push(d.join(Path::new(file).file_name().unwrap()).display().to_string());
                }
            }
            let target = args.iter().position(|a| a == "--target").map(|i| args[i + 1].clone()).expect("--target");
            let argv: Vec<&str> = args.iter().map(String::as_str).collect();
            let out = sfc(&argv);
            assert_eq!(out.status.code(), Some(0), "`sfc {}` failed:\n{}", args.join(" "), text(&out.stderr));
            let written = args.iter().position(|a| a == "-o").map(|i| std::fs::read(&args[i + 1]).unwrap());
            let produced = written.unwrap_or(out.stdout);
            assert!(!produced.is_empty(), "`sfc {}` produced nothing", args.join(" "));
            claims.push(target);
        }
        let name = dir.file_name().unwrap().to_string_lossy().to_string();
        assert!(!claims.is_empty(), "{name}: its README shows no `sfc build`");
        ran.push(format!("{name}: {}", claims.join(", ")));
        if name == "carwash" {
            assert!(claims.iter().any(|t| t == "stl"), "the car wash of the S7-200 textbook builds to STL");
        }
    }
    eprintln!("{}", ran.join("\n"));
    assert!(ran.len() >= 4, "{ran:?}");
}
