//! `sfc` as a citizen of CI and the terminal (issue 18), through the binary: several files and
//! directories, the exit codes of every command, JUnit XML and SARIF validated against their
//! schemas, coverage formats, `--deny warnings`, runtime events, interval expectations,
//! messages, colour, completions, the man page, `--version`, the progress bar.

// A panic in a test is a failure report.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn sfc_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(args)
        .current_dir(dir)
        .env_remove("NO_COLOR")
        .output()
        .expect("sfc runs")
}

fn sfc(args: &[&str]) -> Output {
    sfc_in(Path::new(env!("CARGO_MANIFEST_DIR")), args)
}

fn sfc_stdin(args: &[&str], input: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(input.as_bytes()).unwrap();
    child.wait_with_output().unwrap()
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-ci-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

const CLEAN: &str = "PROGRAM Clean\n    VAR_INPUT Go : BOOL; END_VAR\n    INITIAL_STEP S1: END_STEP\n    TRANSITION T1 FROM S1 TO S2 := Go; END_TRANSITION\n    STEP S2: END_STEP\n    TRANSITION T2 FROM S2 TO S1 := NOT Go; END_TRANSITION\nEND_PROGRAM\n";

const BROKEN: &str = "PROGRAM Broken\n    VAR_INPUT Go : BOOL; END_VAR\n    INITIAL_STEP S1: END_STEP\n    TRANSITION T1 FROM S1 TO S3 := Go; END_TRANSITION\n    STEP S2: END_STEP\n    TRANSITION T2 FROM S2 TO S1 := NOT Go; END_TRANSITION\nEND_PROGRAM\n";

/// Non-exclusive alternatives: a warning (SFC0505), exit 0 unless warnings are denied.
const WARNS: &str = "PROGRAM Warns\n    VAR_INPUT a, b : BOOL; END_VAR\n    INITIAL_STEP S0: END_STEP\n    TRANSITION T1 FROM S0 TO S1 := a; END_TRANSITION\n    TRANSITION T2 FROM S0 TO S2 := b; END_TRANSITION\n    STEP S1: END_STEP\n    STEP S2: END_STEP\n    TRANSITION T3 FROM S1 TO S0 := NOT a; END_TRANSITION\n    TRANSITION T4 FROM S2 TO S0 := NOT b; END_TRANSITION\nEND_PROGRAM\n";

fn project(name: &str) -> PathBuf {
    let d = temp_dir(name);
    std::fs::create_dir_all(d.join("charts/sub")).unwrap();
    std::fs::write(d.join("charts/clean.st"), CLEAN).unwrap();
    std::fs::write(d.join("charts/sub/broken.st"), BROKEN).unwrap();
    std::fs::write(d.join("charts/notes.txt"), "not a chart").unwrap();
    d
}

// ---------------------------------------------------------------------------------------------
// Several files, directories, going on after a bad one

#[test]
fn check_reports_every_file_and_goes_on() {
    let d = project("check-several");
    let out = sfc_in(&d, &["check", "charts/clean.st", "missing.st", "charts/sub/broken.st"]);
    assert_eq!(out.status.code(), Some(2), "an unreadable file is an I/O error");
    let err = text(&out.stderr);
    assert!(err.contains("cannot read `missing.st`"), "{err}");
    assert!(err.contains("undeclared step `S3`"), "the diagnostics of the other files are kept: {err}");
    // JSON: still one array on stdout, with the findings of the readable files.
    let out = sfc_in(&d, &["check", "--format", "json", "missing.st", "charts/sub/broken.st"]);
    assert_eq!(out.status.code(), Some(2));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("a JSON array");
    assert!(v.as_array().unwrap().iter().any(|d| d["code"] == "SFC0208"), "{v}");
    // A directory: every .st and .xml under it, recursively, other files ignored.
    let out = sfc_in(&d, &["check", "--format", "json", "charts"]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let files: Vec<&str> = v.as_array().unwrap().iter().map(|d| d["file"].as_str().unwrap()).collect();
    assert!(files.iter().all(|f| f.ends_with("broken.st")), "{files:?}");
    // An empty directory checks nothing: said, and exit 2.
    std::fs::create_dir_all(d.join("empty")).unwrap();
    let out = sfc_in(&d, &["check", "empty"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("no chart files"), "{}", text(&out.stderr));
}

#[test]
fn check_of_an_empty_file_is_not_silent() {
    let d = temp_dir("empty-file");
    std::fs::write(d.join("empty.st"), "").unwrap();
    std::fs::write(d.join("comments.st"), "(* nothing yet *)\n").unwrap();
    let out = sfc_in(&d, &["check", "empty.st", "comments.st"]);
    assert_eq!(out.status.code(), Some(0), "a warning");
    let err = text(&out.stderr);
    assert!(err.contains("warning[SFC0106]: nothing to check: the file is empty"), "{err}");
    assert!(err.contains("nothing to check: the file holds only comments"), "{err}");
    let out = sfc_in(&d, &["check", "--deny", "warnings", "empty.st"]);
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn deny_warnings_fails_check() {
    let d = temp_dir("deny");
    std::fs::write(d.join("warns.st"), WARNS).unwrap();
    let out = sfc_in(&d, &["check", "warns.st"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("warning[SFC0505]"), "{}", text(&out.stderr));
    for deny in [&["--deny", "warnings"][..], &["-D", "warnings"], &["--deny=warnings"]] {
        let mut args = vec!["check"];
        args.extend_from_slice(deny);
        args.push("warns.st");
        let out = sfc_in(&d, &args);
        assert_eq!(out.status.code(), Some(1), "{deny:?}");
        assert!(text(&out.stderr).contains("1 warning denied by `--deny warnings`"), "{}", text(&out.stderr));
    }
    let out = sfc_in(&d, &["check", "--deny", "everything", "warns.st"]);
    assert_eq!(out.status.code(), Some(2), "an unknown lint is a usage error");
}

#[test]
fn fmt_takes_directories_refuses_xml_and_checks_stdin_quietly() {
    let d = temp_dir("fmt");
    std::fs::create_dir_all(d.join("src")).unwrap();
    let messy = "PROGRAM P\nINITIAL_STEP S1:END_STEP\nEND_PROGRAM\n";
    std::fs::write(d.join("src/a.st"), messy).unwrap();
    let canonical = text(&sfc_stdin(&["fmt", "-"], CLEAN).stdout);
    std::fs::write(d.join("src/b.st"), &canonical).unwrap();
    let xml = root().join("crates/sfc-driver/tests/fixtures/seed.xml");
    std::fs::copy(&xml, d.join("src/plc.xml")).unwrap();
    // --check over the directory: the messy file is named, XML files are not formatted.
    let out = sfc_in(&d, &["fmt", "--check", "src"]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(text(&out.stdout), "would reformat src/a.st\n");
    assert!(text(&out.stderr).contains("1 file would be reformatted, 1 already formatted"), "{}", text(&out.stderr));
    assert_eq!(std::fs::read_to_string(d.join("src/a.st")).unwrap(), messy, "--check writes nothing");
    // An XML file named on the command line is refused clearly, and the others still go.
    let out = sfc_in(&d, &["fmt", "src/plc.xml", "src/a.st"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(err.contains("`src/plc.xml` is PLCopen XML: `sfc fmt` rewrites IEC 61131-3 text only"), "{err}");
    assert!(!err.contains("SFC01"), "no syntax errors from reading XML as ST: {err}");
    assert_ne!(std::fs::read_to_string(d.join("src/a.st")).unwrap(), messy, "a.st was formatted");
    // Standard input: --check prints nothing and tells by the exit status.
    let out = sfc_stdin(&["fmt", "--check", "-"], messy);
    assert_eq!((out.status.code(), out.stdout.len(), out.stderr.len()), (Some(1), 0, 0), "{}", text(&out.stderr));
    let formatted = text(&sfc_stdin(&["fmt", "-"], messy).stdout);
    let out = sfc_stdin(&["fmt", "--check", "-"], &formatted);
    assert_eq!((out.status.code(), out.stdout.len()), (Some(0), 0));
    // XML on standard input is refused too.
    let out = sfc_stdin(&["fmt", "-"], &std::fs::read_to_string(&xml).unwrap());
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("standard input is PLCopen XML"), "{}", text(&out.stderr));
}

#[test]
fn build_refuses_to_overwrite_its_input() {
    let d = temp_dir("build-o");
    std::fs::write(d.join("chart.st"), CLEAN).unwrap();
    std::fs::create_dir_all(d.join("sub")).unwrap();
    for out_path in ["chart.st", "./chart.st", "sub/../chart.st"] {
        let out = sfc_in(&d, &["build", "chart.st", "--target", "text", "-o", out_path]);
        assert_eq!(out.status.code(), Some(2), "{out_path}");
        assert!(text(&out.stderr).contains("is the input: refusing to overwrite the chart"), "{}", text(&out.stderr));
        assert_eq!(std::fs::read_to_string(d.join("chart.st")).unwrap(), CLEAN, "the chart is untouched");
    }
    let out = sfc_in(&d, &["build", "chart.st", "--target", "text", "-o", "copy.st"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

// ---------------------------------------------------------------------------------------------
// One table of exit codes for every command

#[test]
fn exit_codes_of_every_command() {
    let d = temp_dir("exit-codes");
    std::fs::write(d.join("clean.st"), CLEAN).unwrap();
    std::fs::write(d.join("formatted.st"), text(&sfc_stdin(&["fmt", "-"], CLEAN).stdout)).unwrap();
    std::fs::write(d.join("broken.st"), BROKEN).unwrap();
    std::fs::write(d.join("syntax.st"), "PROGRAM P\n    x := ;\nEND_PROGRAM\n").unwrap();
    std::fs::write(d.join("empty.st"), "").unwrap();
    // Not UTF-8: read as Latin-1 by every command alike, with the warning SFC0011.
    let mut latin1 = b"(* Ventil ge\xf6ffnet *)\n".to_vec();
    latin1.extend_from_slice(CLEAN.as_bytes());
    std::fs::write(d.join("latin1.st"), &latin1).unwrap();
    // UTF-16 (Notepad's "Unicode"): read as text, no warning.
    std::fs::write(d.join("utf16.st"), utf16le(CLEAN)).unwrap();
    // A vendor's binary project: one error (SFC0012), the input is wrong.
    std::fs::write(d.join("binary.project"), b"\x50\x4b\x03\x04\x14\x00\x00\x00PROGRAM\x00\x01\x02").unwrap();
    std::fs::write(
        d.join("ok.scenario.toml"),
        "chart = \"clean.st\"\n[[at]]\ntime = \"T#0s\"\nexpect = { active = [\"S1\"] }\n",
    )
    .unwrap();
    std::fs::write(
        d.join("bad.scenario.toml"),
        "chart = \"clean.st\"\n[[at]]\ntime = \"T#0s\"\nexpect = { active = [\"S2\"] }\n",
    )
    .unwrap();
    let table: &[(&[&str], i32)] = &[
        (&["check", "clean.st"], 0),
        (&["check", "broken.st"], 1),
        (&["check", "missing.st"], 2),
        (&["check", "latin1.st"], 0),
        (&["check", "--deny", "warnings", "latin1.st"], 1),
        (&["check", "--deny", "warnings", "utf16.st"], 0),
        (&["check", "binary.project"], 1),
        (&["fmt", "--check", "binary.project"], 1),
        (&["build", "binary.project", "--target", "st"], 1),
        (&["sim", "binary.project"], 1),
        (&["sim", "utf16.st", "--scans", "3"], 0),
        (&["build", "utf16.st", "--target", "st"], 0),
        (&["check", "--format", "yaml", "clean.st"], 2),
        (&["check", "--explain", "SFC9999"], 2),
        (&["fmt", "--check", "formatted.st"], 0),
        (&["fmt", "--check", "clean.st"], 1),
        (&["fmt", "--check", "syntax.st"], 1),
        (&["fmt", "--check", "broken.st", "missing.st"], 2),
        (&["fmt", "missing.st"], 2),
        (&["fmt", "--check", "latin1.st"], 1),
        (&["build", "clean.st", "--target", "st"], 0),
        (&["build", "broken.st", "--target", "st"], 1),
        (&["build", "missing.st", "--target", "st"], 2),
        (&["build", "latin1.st", "--target", "st"], 0),
        (&["build", "clean.st", "--target", "st", "--pou", "Nope"], 2),
        (&["build", "empty.st", "--target", "st"], 2),
        (&["sim", "clean.st", "--scans", "3"], 0),
        (&["sim", "broken.st"], 1),
        (&["sim", "missing.st"], 2),
        (&["sim", "latin1.st", "--scans", "3"], 0),
        (&["sim", "clean.st", "--pou", "Nope"], 2),
        (&["sim", "empty.st"], 2),
        (&["sim", "clean.st", "--period", "10ms"], 2),
        (&["sim", "clean.st", "--scenario", "bad.scenario.toml"], 1),
        (&["test", "ok.scenario.toml"], 0),
        (&["test", "bad.scenario.toml"], 1),
        (&["test", "missing.scenario.toml"], 2),
        (&["test", "ok.scenario.toml", "missing"], 2),
        (&["completions", "bash"], 0),
        (&["completions", "tcsh"], 2),
        (&["man"], 0),
        (&["--version"], 0),
        (&["frobnicate"], 2),
    ];
    let mut wrong = Vec::new();
    for (args, code) in table {
        let out = sfc_in(&d, args);
        if out.status.code() != Some(*code) {
            wrong.push(format!(
                "sfc {}: expected {code}, got {:?}\n{}",
                args.join(" "),
                out.status.code(),
                text(&out.stderr)
            ));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// `text` as UTF-16 little-endian with its byte order mark, as Notepad's "Unicode" saves it.
fn utf16le(text: &str) -> Vec<u8> {
    let mut out = vec![0xFF, 0xFE];
    out.extend(text.encode_utf16().flat_map(u16::to_le_bytes));
    out
}

/// A UTF-16 chart reads as text in every command, and `fmt` writes it back in UTF-16 with its
/// byte order mark; a binary file gets one error that says so, not one per stray byte.
#[test]
fn utf16_charts_are_text_and_binary_files_are_one_error() {
    let d = temp_dir("utf16");
    let chart = format!("(* Ventil öffnen, žluťoučký kůň *)\r\n{}", CLEAN.replace('\n', "\r\n"));
    std::fs::write(d.join("u.st"), utf16le(&chart)).unwrap();
    let out = sfc_in(&d, &["check", "u.st"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(out.stderr.is_empty(), "{}", text(&out.stderr));
    let out = sfc_in(&d, &["fmt", "u.st"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let written = std::fs::read(d.join("u.st")).unwrap();
    let formatted = text(&sfc_stdin(&["fmt", "-"], &chart).stdout);
    assert_eq!(written, utf16le(&formatted), "written back as UTF-16 LE with its BOM and CRLF");
    assert!(formatted.contains("žluťoučký kůň *)\r\n"), "{formatted}");

    let mut bytes = b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1".to_vec();
    bytes.extend((0..4000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8));
    std::fs::write(d.join("Untitled.project"), &bytes).unwrap();
    let out = sfc_in(&d, &["check", "Untitled.project"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("error[SFC0012]: the file is binary"), "{err}");
    assert!(err.contains("Export PLCopenXML"), "{err}");
    assert!(err.contains("1 error emitted") && !err.contains("SFC0003") && !err.contains("SFC0011"), "{err}");
}

#[test]
fn sim_names_what_is_missing() {
    let d = temp_dir("sim-messages");
    std::fs::write(d.join("empty.st"), "").unwrap();
    let out = sfc_in(&d, &["sim", "empty.st"]);
    assert!(text(&out.stderr).contains("the file has no SFC POU to simulate"), "{}", text(&out.stderr));
    // A chart that is not UTF-8 is simulated as Latin-1 and `sim` says so, as `check` does.
    let mut latin1 = b"(* Ventil ge\xf6ffnet *)\n".to_vec();
    latin1.extend_from_slice(CLEAN.as_bytes());
    std::fs::write(d.join("latin1.st"), &latin1).unwrap();
    let out = sfc_in(&d, &["sim", "latin1.st", "--scans", "2"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("warning[SFC0011]"), "{}", text(&out.stderr));
    let out = sfc_in(&d, &["check", "latin1.st"]);
    assert!(text(&out.stderr).contains("warning[SFC0011]"), "{}", text(&out.stderr));
    let blinker = root().join("examples/blinker/blinker.st");
    let out = sfc(&["sim", p(&blinker), "--pou", "Nope"]);
    assert!(text(&out.stderr).contains("no POU named `Nope`"), "{}", text(&out.stderr));
}

// ---------------------------------------------------------------------------------------------
// JUnit, SARIF, coverage

/// A scenario folder with one passing, one failing and one invalid scenario.
fn scenarios(name: &str) -> PathBuf {
    let d = temp_dir(name);
    std::fs::copy(root().join("examples/blinker/blinker.st"), d.join("blinker.st")).unwrap();
    std::fs::write(
        d.join("a_pass.scenario.toml"),
        "chart = \"blinker.st\"\nperiod = \"T#100ms\"\n[[at]]\ntime = \"T#0s\"\nset = { Start = true }\n[[at]]\ntime = \"T#100ms\"\nexpect = { active = [\"S2\"], Visible = true }\n",
    )
    .unwrap();
    std::fs::write(
        d.join("b_fail.scenario.toml"),
        "chart = \"blinker.st\"\nperiod = \"T#100ms\"\n[[at]]\ntime = \"T#0s\"\nset = { Start = true }\n[[at]]\ntime = \"T#300ms\"\nexpect = { active = [\"S3\"], Visible = false }\n",
    )
    .unwrap();
    std::fs::write(d.join("c_invalid.scenario.toml"), "chart = \"blinker.st\"\nperiods = \"T#1s\"\n").unwrap();
    d
}

fn xmllint_schema(xml: &Path, xsd: &Path) -> Output {
    Command::new("xmllint").arg("--noout").arg("--schema").arg(xsd).arg(xml).output().expect(
        "xmllint is installed (scripts/test-deps.sh installs it): the JUnit output is validated against its schema",
    )
}

#[test]
fn junit_is_valid_and_carries_the_first_failure() {
    let d = scenarios("junit");
    let out = sfc_in(&d, &["test", ".", "--junit", "report.xml"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    assert!(text(&out.stdout).ends_with("1 passed, 2 failed\n"), "{}", text(&out.stdout));
    let report = d.join("report.xml");
    let xsd = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/schemas/junit.xsd");
    let v = xmllint_schema(&report, &xsd);
    assert!(v.status.success(), "{}{}", text(&v.stdout), text(&v.stderr));
    let xml = std::fs::read_to_string(&report).unwrap();
    assert!(xml.contains("tests=\"3\" failures=\"1\" errors=\"1\""), "{xml}");
    // Ant's schema declares no attribute on the aggregate (Jenkins' allows some, needs none).
    assert!(xml.contains("\n<testsuites>\n"), "{xml}");
    // One testcase per scenario; the failure's message is the first differing expectation
    // with its scan.
    assert_eq!(xml.matches("<testcase ").count(), 3);
    assert!(
        xml.contains("message=\"b_fail.scenario.toml:6: at T#300ms (scan 3): `active`: expected [&quot;S3&quot;], actual [&quot;S2&quot;]\""),
        "{xml}"
    );
    assert!(xml.contains("<error message=\"c_invalid.scenario.toml:2:1: unknown key `periods`"), "{xml}");
    // A run where everything passes is valid too.
    let out = sfc_in(&d, &["test", "a_pass.scenario.toml", "--junit", "pass.xml"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(xmllint_schema(&d.join("pass.xml"), &xsd).status.success());
}

/// The SARIF 2.1.0 JSON schema, fetched by scripts/test-deps.sh (CI runs it first).
fn sarif_schema() -> Option<PathBuf> {
    let schema = root().join("target/test-tools/sarif-schema-2.1.0.json");
    if schema.exists() {
        return Some(schema);
    }
    assert!(std::env::var_os("CI").is_none(), "{} is missing: run scripts/test-deps.sh", schema.display());
    eprintln!("SARIF schema not found (run scripts/test-deps.sh); schema validation skipped");
    None
}

#[test]
fn sarif_is_valid_against_the_schema() {
    let d = project("sarif");
    std::fs::write(d.join("charts/warns.st"), WARNS).unwrap();
    std::fs::copy(root().join("crates/sfc-driver/tests/fixtures/unsafe.st"), d.join("charts/unsafe.st")).unwrap();
    let out = sfc_in(&d, &["check", "--format", "sarif", "charts", "missing.st"]);
    assert_eq!(out.status.code(), Some(2));
    let log: serde_json::Value = serde_json::from_slice(&out.stdout).expect("SARIF is JSON");
    let run = &log["runs"][0];
    assert_eq!(log["version"], "2.1.0");
    assert_eq!(run["tool"]["driver"]["name"], "sfc");
    let rules = run["tool"]["driver"]["rules"].as_array().unwrap();
    assert!(rules.iter().any(|r| r["id"] == "SFC0501" && r["shortDescription"]["text"] == "unsafe chart"));
    let results = run["results"].as_array().unwrap();
    let codes: Vec<&str> = results.iter().map(|r| r["ruleId"].as_str().unwrap()).collect();
    assert!(codes.contains(&"SFC0208") && codes.contains(&"SFC0505"), "{codes:?}");
    for r in results {
        let i = r["ruleIndex"].as_u64().unwrap() as usize;
        assert_eq!(rules[i]["id"], r["ruleId"], "ruleIndex points at the rule");
        let uri = r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"].as_str().unwrap();
        assert!(uri.starts_with("charts/"), "relative to %SRCROOT%: {uri}");
    }
    let unsafe_ = results.iter().find(|r| r["ruleId"] == "SFC0501").expect("the unsafe finding");
    assert_eq!(unsafe_["level"], "error");
    assert!(unsafe_["properties"]["witness"].is_array());
    // The unreadable file is a tool execution notification.
    let inv = &run["invocations"][0];
    assert_eq!(inv["executionSuccessful"], false);
    assert!(inv["toolExecutionNotifications"][0]["message"]["text"].as_str().unwrap().contains("missing.st"));
    let Some(schema) = sarif_schema() else { return };
    let file = d.join("out.sarif");
    std::fs::write(&file, &out.stdout).unwrap();
    let check = Command::new("python3")
        .arg("-c")
        .arg("import json,sys,jsonschema; jsonschema.validate(json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))); print('valid')")
        .arg(&file)
        .arg(&schema)
        .output()
        .expect("python3 runs (scripts/test-deps.sh installs python3-jsonschema)");
    assert!(check.status.success(), "SARIF does not validate:\n{}{}", text(&check.stdout), text(&check.stderr));
    // A clean run is a valid log with no results.
    let out = sfc_in(&d, &["check", "--format", "sarif", "charts/clean.st"]);
    assert_eq!(out.status.code(), Some(0));
    std::fs::write(&file, &out.stdout).unwrap();
    let check = Command::new("python3")
        .arg("-c")
        .arg("import json,sys,jsonschema; jsonschema.validate(json.load(open(sys.argv[1])), json.load(open(sys.argv[2])))")
        .arg(&file)
        .arg(&schema)
        .output()
        .unwrap();
    assert!(check.status.success(), "{}", text(&check.stderr));
}

#[test]
fn coverage_formats() {
    let d = scenarios("coverage");
    std::fs::remove_file(d.join("c_invalid.scenario.toml")).unwrap();
    // Text, as before, with the flag alone before or after the paths.
    for args in [&["test", "--coverage", "."][..], &["test", ".", "--coverage"]] {
        let out = sfc_in(&d, args);
        let stdout = text(&out.stdout);
        assert!(
            stdout.contains("coverage:\n  blinker.st (Blinker): steps 2/3 (67%), transitions 1/4 (25%)"),
            "{stdout}"
        );
        assert!(stdout.ends_with("1 passed, 1 failed\n"));
    }
    // A machine format needs -o.
    let out = sfc_in(&d, &["test", ".", "--coverage", "json"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("-o FILE"));
    // JSON: every step and transition with its line.
    let out = sfc_in(&d, &["test", "a_pass.scenario.toml", "--coverage", "json", "-o", "cov.json"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("cov.json")).unwrap()).unwrap();
    let chart = &v["charts"][0];
    assert_eq!((chart["chart"].as_str(), chart["pou"].as_str()), (Some("blinker.st"), Some("Blinker")));
    let items = chart["items"].as_array().unwrap();
    let s2 = items.iter().find(|i| i["name"] == "S2").unwrap();
    assert_eq!((s2["kind"].as_str(), s2["covered"].as_bool()), (Some("step"), Some(true)));
    let blinker = std::fs::read_to_string(d.join("blinker.st")).unwrap();
    let s2_line = blinker.lines().position(|l| l.contains("STEP S2:")).unwrap() + 1;
    assert_eq!(s2["line"].as_u64(), Some(s2_line as u64));
    let t5 = items.iter().find(|i| i["name"] == "T5").unwrap();
    assert_eq!(t5["covered"], false);
    // lcov: steps as lines, transitions as branches.
    sfc_in(&d, &["test", "a_pass.scenario.toml", "--coverage", "lcov", "-o", "lcov.info"]);
    let lcov = std::fs::read_to_string(d.join("lcov.info")).unwrap();
    assert!(lcov.starts_with("TN:sfc\nSF:blinker.st\n"), "{lcov}");
    assert!(lcov.contains(&format!("DA:{s2_line},1\n")), "{lcov}");
    assert!(
        lcov.contains("BRF:4\n") && lcov.contains("LF:3\n") && lcov.trim_end().ends_with("end_of_record"),
        "{lcov}"
    );
    // Cobertura: well-formed, with rates and the file as GitLab needs it.
    sfc_in(&d, &["test", ".", "--coverage", "cobertura", "-o", "cobertura.xml"]);
    let cob = d.join("cobertura.xml");
    let lint = Command::new("xmllint").arg("--noout").arg(&cob).output().expect("xmllint");
    assert!(lint.status.success(), "{}", text(&lint.stderr));
    let xml = std::fs::read_to_string(&cob).unwrap();
    assert!(xml.contains("<class name=\"Blinker\" filename=\"blinker.st\""), "{xml}");
    assert!(xml.contains("lines-covered=\"2\" lines-valid=\"3\""), "{xml}");
    assert!(xml.contains("branch=\"true\" condition-coverage=\""), "{xml}");
}

#[test]
fn deny_warnings_fails_scenarios_with_events_or_chart_warnings() {
    let d = temp_dir("test-deny");
    std::fs::copy(root().join("crates/sfc-sim/tests/scenarios/twin.st"), d.join("twin.st")).unwrap();
    std::fs::write(d.join("warns.st"), WARNS).unwrap();
    std::fs::write(
        d.join("twin.scenario.toml"),
        "chart = \"twin.st\"\nscans = 4\n[[at]]\ntime = \"T#0s\"\nset = { Go = true }\n",
    )
    .unwrap();
    std::fs::write(d.join("warns.scenario.toml"), "chart = \"warns.st\"\nscans = 2\n").unwrap();
    let out = sfc_in(&d, &["test", "."]);
    assert_eq!(out.status.code(), Some(0), "events and warnings alone do not fail: {}", text(&out.stdout));
    let out = sfc_in(&d, &["test", ".", "--deny", "warnings"]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("runtime event `conflict`") && stdout.contains("runtime event `unsafe`"), "{stdout}");
    assert!(stdout.contains("warning[SFC0505]"), "{stdout}");
    assert!(stdout.ends_with("0 passed, 2 failed\n"), "{stdout}");
}

#[test]
fn several_test_paths_go_on_after_a_missing_one() {
    let d = scenarios("test-several");
    let out = sfc_in(&d, &["test", "nope", "a_pass.scenario.toml", "empty-dir-missing"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stdout).contains("PASS a_pass.scenario.toml"), "{}", text(&out.stdout));
    assert!(text(&out.stdout).ends_with("1 passed, 0 failed\n"));
    assert!(text(&out.stderr).contains("`nope` does not exist"));
}

// ---------------------------------------------------------------------------------------------
// Events and interval expectations through the binary

#[test]
fn sim_prints_runtime_events() {
    let twin = root().join("crates/sfc-sim/tests/scenarios/twin.st");
    let out = sfc(&["sim", p(&twin), "--set", "Go=TRUE", "--scans", "30"]);
    assert_eq!(out.status.code(), Some(0));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("scan 1, T#10ms: conflict: step S0 has 2 true transitions without priority: T1, T2"),
        "{stdout}"
    );
    assert!(stdout.contains("scan 2, T#20ms: unsafe: step S0 gets a second token (from T3, T4)"), "{stdout}");
    assert_eq!(stdout.matches(": conflict: ").count(), 10, "ten of a kind, then a count");
    assert!(stdout.contains("… 5 more `conflict` events not shown"), "{stdout}");
    assert!(stdout.contains("events: 15 conflict, 14 unsafe"), "{stdout}");
    let out = sfc(&["sim", p(&twin), "--set", "Go=TRUE", "--scans", "3", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["event_counts"], serde_json::json!({"conflict": 1, "unsafe": 1}));
    assert_eq!(v["events"][1]["kind"], "unsafe");
    assert_eq!(v["events"][1]["scan"], 2);
}

#[test]
fn contention_names_the_action_as_declared() {
    let d = temp_dir("contention");
    let chart = "PROGRAM P\n    VAR_OUTPUT Y4 : BOOL; END_VAR\n    INITIAL_STEP A: y4(L, T#50ms); END_STEP\n    INITIAL_STEP B: Y4(D, T#20ms); END_STEP\nEND_PROGRAM\n";
    std::fs::write(d.join("c.st"), chart).unwrap();
    let out = sfc_in(&d, &["sim", "c.st", "--scans", "2", "--trace", "-"]);
    let trace = text(&out.stdout);
    assert!(trace.contains("{\"kind\":\"contention\",\"action\":\"Y4\""), "{trace}");
}

#[test]
fn scenario_intervals_through_sfc_test() {
    let folder = root().join("crates/sfc-sim/tests/scenarios");
    let out = sfc_in(
        &folder,
        &["test", "always_violated.scenario.toml", "within_met.scenario.toml", "forbid_events.scenario.toml"],
    );
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("PASS within_met.scenario.toml"), "{stdout}");
    assert!(
        stdout.contains(
            "always from T#0s to T#1s: at T#200ms (scan 2): `Motor`: expected false, actual true (and 2 more scans)"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("forbidden event `unsafe`"), "{stdout}");
    assert!(stdout.ends_with("1 passed, 2 failed\n"));
}

#[test]
fn stats_are_summarised_unless_full() {
    let blinker = root().join("examples/blinker/blinker.st");
    let args = ["sim", p(&blinker), "--set", "Start=TRUE", "--until", "T#10m", "--period", "T#100ms"];
    let out = sfc(&[&args[..], &["--stats"]].concat());
    let stdout = text(&out.stdout);
    assert!(stdout.contains("situations: 1001 entered, 3 different; the longest in total:"), "{stdout}");
    assert!(stdout.contains("     T#5m  500 times  S2\n"), "{stdout}");
    // The step table, the ten longest situations, the mechanisms overview and the run in
    // progress with its first states: a summary, not the 1001 situations.
    assert!(stdout.lines().count() < 30, "{stdout}");
    let out = sfc(&[&args[..], &["--stats-full"]].concat());
    assert!(text(&out.stdout).lines().count() > 1001, "every situation");
}

// ---------------------------------------------------------------------------------------------
// Messages

#[test]
fn misspelled_keywords_get_one_error_each() {
    let d = temp_dir("typos");
    let chart = "PROGRAM P\n    VAR_INPUT Go : BOOL; END_VAR\n    INITAL_STEP S1: END_STEP\n    TRANSITION T1 FROM S1 TO S2 := Go; END_TRANSITION\n    STEP S2: END_STEP\n    TRANSITION T2 FROM S2 TO S1 := NOT Go; END_TRANSITON\nEND_PROGRAM\n";
    std::fs::write(d.join("t.st"), chart).unwrap();
    let out = sfc_in(&d, &["check", "--format", "json", "t.st"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let msgs: Vec<(&str, &str)> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|d| (d["message"].as_str().unwrap(), d["notes"][0].as_str().unwrap_or("")))
        .collect();
    assert_eq!(
        msgs,
        [
            ("misspelled keyword `INITAL_STEP`", "did you mean `INITIAL_STEP`?"),
            ("misspelled keyword `END_TRANSITON`", "did you mean `END_TRANSITION`?")
        ]
    );
}

#[test]
fn suggestions_are_of_the_right_kind_and_lines_render_once() {
    let d = temp_dir("kinds");
    std::fs::write(
        d.join("c0.st"),
        "PROGRAM P\n    INITIAL_STEP S0: END_STEP\n    TRANSITION T1 FROM S0 TO S1 := C0; END_TRANSITION\n    STEP S1: END_STEP\n    TRANSITION T2 FROM S1 TO S0 := TRUE; END_TRANSITION\nEND_PROGRAM\n",
    )
    .unwrap();
    let out = sfc_in(&d, &["check", "c0.st"]);
    let err = text(&out.stderr);
    assert!(err.contains("undeclared variable `C0`") && !err.contains("did you mean `S0`"), "{err}");
    std::fs::write(d.join("same.st"), "PROGRAM P VAR x : INT; END_PROGRAM\n").unwrap();
    let out = sfc_in(&d, &["check", "same.st"]);
    let err = text(&out.stderr);
    let missing = err.split("\n\n").find(|b| b.contains("missing `END_VAR`")).unwrap();
    assert_eq!(missing.matches("PROGRAM P VAR x : INT; END_PROGRAM").count(), 1, "{missing}");
    assert!(missing.contains("opened here"), "{missing}");
}

#[test]
fn the_readme_tour_chart_is_clean_and_the_latch_is_found() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let start = readme.find("PROGRAM Blinker").unwrap();
    let end = readme[start..].find("END_PROGRAM").unwrap() + start + "END_PROGRAM".len();
    let d = temp_dir("tour");
    std::fs::write(d.join("tour.st"), &readme[start..end]).unwrap();
    let out = sfc_in(&d, &["check", "--deny", "warnings", "tour.st"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let latch = "PROGRAM Blinker\n    VAR_INPUT Start, Stop : BOOL; END_VAR\n    VAR_OUTPUT Visible : BOOL; END_VAR\n    INITIAL_STEP S1: END_STEP\n    TRANSITION T1 FROM S1 TO S2 := Start; END_TRANSITION\n    STEP S2: Show(N); END_STEP\n    TRANSITION T2 FROM S2 TO S1 := Stop OR S2.T >= T#5s; END_TRANSITION\n    ACTION Show: Visible := TRUE; END_ACTION\nEND_PROGRAM\n";
    std::fs::write(d.join("latch.st"), latch).unwrap();
    let out = sfc_in(&d, &["check", "latch.st"]);
    assert!(
        text(&out.stderr).contains("warning[SFC0219]: `Visible` is set TRUE by action `Show` (N in step S2)"),
        "{}",
        text(&out.stderr)
    );
}

// ---------------------------------------------------------------------------------------------
// The terminal

#[test]
fn colour_follows_the_flag_and_no_color() {
    let broken = temp_dir("color").join("broken.st");
    std::fs::write(&broken, BROKEN).unwrap();
    let has_ansi = |o: &Output| text(&o.stderr).contains("\x1b[");
    // In a pipe: no colour unless asked for.
    assert!(!has_ansi(&sfc(&["check", p(&broken)])));
    assert!(has_ansi(&sfc(&["check", "--color", "always", p(&broken)])));
    assert!(has_ansi(&sfc(&["--color=always", "check", p(&broken)])), "the flag is global");
    assert!(!has_ansi(&sfc(&["check", "--color", "never", p(&broken)])));
    let with_no_color =
        |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).env("NO_COLOR", "1").output().unwrap();
    assert!(has_ansi(&with_no_color(&["check", "--color", "always", p(&broken)])), "--color always wins");
    // On a terminal (a pseudo-terminal from `script`), auto colours unless NO_COLOR is set.
    if let Some(out) = on_terminal(&format!("{} check {}", env!("CARGO_BIN_EXE_sfc"), p(&broken)), &[]) {
        assert!(out.contains("\x1b["), "auto colours a terminal: {out}");
        let out =
            on_terminal(&format!("{} check {}", env!("CARGO_BIN_EXE_sfc"), p(&broken)), &[("NO_COLOR", "1")]).unwrap();
        assert!(!out.contains("\x1b["), "NO_COLOR: {out}");
    }
    // The test summary: PASS/FAIL coloured only when asked for.
    let d = scenarios("color-test");
    let out = sfc_in(&d, &["test", "--color", "always", "a_pass.scenario.toml"]);
    assert!(text(&out.stdout).contains("\x1b[1;32mPASS\x1b[0m"), "{}", text(&out.stdout));
}

/// Runs a shell command under a pseudo-terminal (util-linux `script`), returning what it
/// printed; `None` when `script` is not there.
fn on_terminal(command: &str, env: &[(&str, &str)]) -> Option<String> {
    let mut c = Command::new("script");
    c.args(["-qec", command, "/dev/null"]).env_remove("NO_COLOR").stdin(Stdio::null());
    for (k, v) in env {
        c.env(k, v);
    }
    let out = c.output().ok()?;
    Some(text(&out.stdout))
}

#[test]
fn progress_bar_only_on_a_terminal() {
    let blinker = root().join("examples/blinker/blinker.st");
    let cmd = format!("{} sim {} --set Start=TRUE --scans 200000", env!("CARGO_BIN_EXE_sfc"), p(&blinker));
    // In a pipe: never, even when asked to appear at once.
    let out = Command::new("sh").arg("-c").arg(&cmd).env("SFC_PROGRESS_AFTER_MS", "0").output().unwrap();
    assert!(!text(&out.stderr).contains("scans"), "{}", text(&out.stderr));
    // On a terminal, once the run has taken the delay (0 here, 1 s by default).
    if let Some(out) = on_terminal(&cmd, &[("SFC_PROGRESS_AFTER_MS", "0")]) {
        assert!(out.contains("/200000 scans"), "a bar with the scan count: {out:?}");
        assert!(out.contains("simulated Blinker: 200000 scans"));
    }
    // A short run on a terminal with the default delay draws none.
    let short = format!("{} sim {} --scans 10", env!("CARGO_BIN_EXE_sfc"), p(&blinker));
    if let Some(out) = on_terminal(&short, &[]) {
        assert!(!out.contains("/10 scans"), "{out:?}");
    }
}

#[test]
fn completions_man_page_and_version() {
    for (shell, marker) in [
        ("bash", "_sfc()"),
        ("zsh", "#compdef sfc"),
        ("fish", "complete -c sfc"),
        ("powershell", "Register-ArgumentCompleter"),
        ("elvish", "edit:completion"),
    ] {
        let out = sfc(&["completions", shell]);
        assert_eq!(out.status.code(), Some(0), "{shell}");
        let script = text(&out.stdout);
        assert!(script.contains(marker), "{shell}: {}", &script[..script.len().min(200)]);
        assert!(script.contains("--deny") && script.contains("junit"), "{shell} completes the options");
    }
    let out = sfc(&["man"]);
    let page = text(&out.stdout);
    assert!(page.starts_with(".ie") || page.contains(".TH sfc"), "{}", &page[..page.len().min(200)]);
    assert!(page.contains("check") && page.contains("completions"), "the page lists the commands");
    let d = temp_dir("man");
    let out = sfc(&["man", "--dir", p(&d)]);
    assert_eq!(out.status.code(), Some(0));
    for page in ["sfc.1", "sfc-check.1", "sfc-test.1", "sfc-sim.1"] {
        let t = std::fs::read_to_string(d.join(page)).unwrap();
        assert!(t.contains(".TH"), "{page}");
    }
    assert!(std::fs::read_to_string(d.join("sfc-test.1")).unwrap().contains("junit"));
    let out = sfc(&["--version"]);
    let v = text(&out.stdout);
    assert!(v.starts_with(&format!("sfc {} (", env!("CARGO_PKG_VERSION"))), "{v}");
    let inner = v.trim().trim_start_matches(&format!("sfc {} (", env!("CARGO_PKG_VERSION"))).trim_end_matches(')');
    let commit = inner.split(' ').next().unwrap();
    assert!(
        inner == "no git commit" || (commit.len() == 12 && commit.chars().all(|c| c.is_ascii_hexdigit())),
        "a commit or the archive's note: {v}"
    );
}

/// The README's GitLab CI jobs, run as a runner would (`sh -c` per script line, `sfc` on the
/// `PATH`) in a project with `charts/` and `scenarios/`: every command succeeds and leaves the
/// files the artifacts name.
#[test]
fn the_readme_ci_example_runs() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let ci = &readme[readme.find("### In CI").unwrap()..];
    let yaml = &ci[ci.find("```yaml\n").unwrap() + 8..];
    let yaml = &yaml[..yaml.find("```").unwrap()];
    let commands: Vec<&str> = yaml.lines().filter_map(|l| l.trim_start().strip_prefix("- sfc ")).collect();
    assert!(commands.len() >= 2, "{yaml}");
    let d = temp_dir("readme-ci");
    std::fs::create_dir_all(d.join("charts")).unwrap();
    std::fs::create_dir_all(d.join("scenarios")).unwrap();
    std::fs::write(d.join("charts/clean.st"), CLEAN).unwrap();
    std::fs::write(
        d.join("scenarios/clean.scenario.toml"),
        "chart = \"../charts/clean.st\"\n[[at]]\ntime = \"T#0s\"\nset = { Go = true }\nexpect = { active = [\"S1\"] }\n[[at]]\ntime = \"T#10ms\"\nexpect = { active = [\"S2\"] }\n",
    )
    .unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_sfc")).parent().unwrap().to_path_buf();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    for c in &commands {
        let out =
            Command::new("sh").arg("-c").arg(format!("sfc {c}")).current_dir(&d).env("PATH", &path).output().unwrap();
        assert!(out.status.success(), "sfc {c}: {:?}\n{}", out.status.code(), text(&out.stderr));
    }
    for named in ["sfc.sarif", "sfc-junit.xml", "sfc-coverage.xml"] {
        assert!(yaml.contains(named), "{yaml}");
        assert!(d.join(named).exists(), "`{named}` was not written");
    }
    let sarif: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("sfc.sarif")).unwrap()).unwrap();
    assert_eq!(sarif["version"], "2.1.0");
    let cobertura = std::fs::read_to_string(d.join("sfc-coverage.xml")).unwrap();
    assert!(cobertura.contains("<coverage line-rate=\"1.0000\""), "{cobertura}");
}

/// `check --profile` with a profile that has no warnings of its own says so; `matiec` and
/// `codesys` add their SFC09xx warnings, which `--deny warnings` fails on.
#[test]
fn check_profiles_are_never_silent() {
    let d = temp_dir("check-profile");
    std::fs::write(d.join("clean.st"), CLEAN).unwrap();
    for p in ["iec", "grafcet"] {
        let out = sfc_in(&d, &["check", "--profile", p, "clean.st"]);
        assert_eq!(out.status.code(), Some(0));
        assert!(text(&out.stderr).contains(&format!("`--profile {p}` adds no warnings")), "{}", text(&out.stderr));
    }
    for p in ["matiec", "codesys", "logix"] {
        let out = sfc_in(&d, &["check", "--profile", p, "clean.st"]);
        assert!(!text(&out.stderr).contains("adds no warnings"), "{}", text(&out.stderr));
    }
    let out = sfc_in(&d, &["check", "--profile", "codesys", "clean.st", "--deny", "warnings"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("SFC0912"), "{}", text(&out.stderr));
}
