//! The `sfc` command's contract (`interfaces.md`): exit codes, where output goes, the JSON
//! diagnostic keys, `--explain`, and `fmt` in place, with `--check`, and on standard input.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn sfc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).output().expect("sfc runs")
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-cli-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const BROKEN: &str = "PROGRAM P\n    VAR_INPUT Start : BOOL; END_VAR\n    INITIAL_STEP S1: END_STEP\n    STEP S2: END_STEP\n    TRANSITION T1 FROM S1 TO S3 := Start; END_TRANSITION\n    TRANSITION T2 FROM S2 TO S1 := Start; END_TRANSITION\nEND_PROGRAM\n";

#[test]
fn clean_chart_is_silent_and_exits_0() {
    // The traffic light has no selection divergence, so not even a note about waiting.
    let ex = root().join("examples/traffic/traffic.st");
    let out = sfc(&["check", ex.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stdout.is_empty() && out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// Every example checks without errors or warnings; the only findings allowed are SFC0506
/// notes (a divergence that waits for some inputs, which is normal).
#[test]
fn examples_have_no_errors_or_warnings() {
    for ex in ["blinker/blinker.st", "carwash/carwash.st", "spindle/spindle.st", "traffic/traffic.st"] {
        let path = root().join("examples").join(ex);
        let out = sfc(&["check", "--format", "json", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{ex}: {}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON array");
        for d in v.as_array().expect("array") {
            assert_eq!(d["code"], "SFC0506", "{ex}: unexpected finding {d}");
            assert_eq!(d["severity"], "note");
            assert!(d["witness"].is_object(), "{ex}: an incomplete divergence has a valuation witness");
        }
    }
}

const UNSAFE: &str = "PROGRAM P\n    VAR_INPUT a, b, c : BOOL; END_VAR\n    INITIAL_STEP S0: END_STEP\n    STEP S1: END_STEP\n    STEP S2: END_STEP\n    TRANSITION T1 FROM S0 TO (S1, S2) := a; END_TRANSITION\n    TRANSITION T2 FROM S1 TO S0 := b; END_TRANSITION\n    TRANSITION T3 FROM S2 TO S0 := c; END_TRANSITION\nEND_PROGRAM\n";

/// An unsafe chart: an error with the firing sequence as JSON witness, confirmed in the
/// simulator with an input schedule.
#[test]
fn analysis_reports_unsafe_with_witness() {
    let d = temp_dir("unsafe");
    let f = d.join("unsafe.st");
    std::fs::write(&f, UNSAFE).unwrap();
    let out = sfc(&["check", "--format", "json", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON array");
    let unsafe_s0 = v
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["code"] == "SFC0501" && d["element"] == "S0")
        .unwrap_or_else(|| panic!("no unsafe finding for S0 in {v}"));
    assert_eq!(unsafe_s0["severity"], "error");
    assert_eq!(unsafe_s0["witness"], serde_json::json!(["T1", "T2", "T3"]));
    let notes: Vec<&str> = unsafe_s0["notes"].as_array().unwrap().iter().filter_map(|n| n.as_str()).collect();
    assert!(notes.iter().any(|n| n.starts_with("confirmed")), "{notes:?}");
    // Without analysis only the structural checks run.
    let out = sfc(&["check", "--no-analysis", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}

/// `sfc build`: the seed's ATMT table byte for byte, PLCopen XML that checks again, SVG, ST
/// that checks, and a clear refusal for a target that cannot express the chart.
#[test]
fn build_targets() {
    let d = temp_dir("build");
    let seed = root().join("crates/sfc-codegen/tests/atmt/seed.st");
    let out = sfc(&["build", seed.to_str().unwrap(), "--target", "atmt"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout), "3[0 0 1;1 1 2;2 2 1][8.1 2 1]");

    let carwash = root().join("examples/carwash/carwash.st");
    let xml = d.join("carwash.xml");
    let out = sfc(&["build", carwash.to_str().unwrap(), "--target", "plcopen", "-o", xml.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let out = sfc(&["check", "--format", "json", xml.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let out = sfc(&["build", xml.to_str().unwrap(), "--target", "text"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("INITIAL_STEP Idle"));

    let out = sfc(&["build", carwash.to_str().unwrap(), "--target", "svg"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("<svg"));

    let st = d.join("carwash_st.st");
    let out = sfc(&["build", carwash.to_str().unwrap(), "--target", "st", "-o", st.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let out = sfc(&["check", "--no-analysis", st.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));

    // The S7-200 program of the textbook's car wash (its TIME parameters folded, with warnings).
    let out = sfc(&["build", carwash.to_str().unwrap(), "--target", "stl"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("NETWORK 1"));
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning[SFC0817]"));
}

#[test]
fn errors_go_to_stderr_and_exit_1() {
    let d = temp_dir("errors");
    let f = d.join("broken.st");
    std::fs::write(&f, BROKEN).unwrap();
    let out = sfc(&["check", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("error[SFC0208]: undeclared step `S3`"), "{err}");
    assert!(err.contains("broken.st:5:30"), "{err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn json_has_the_contract_keys() {
    let d = temp_dir("json");
    let f = d.join("broken.st");
    std::fs::write(&f, BROKEN).unwrap();
    let out = sfc(&["check", "--format", "json", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is JSON");
    let arr = v.as_array().expect("an array");
    let d0 = arr.iter().find(|d| d["code"] == "SFC0208").expect("SFC0208 reported");
    for key in [
        "code",
        "severity",
        "message",
        "file",
        "line",
        "column",
        "end_line",
        "end_column",
        "element",
        "notes",
        "witness",
    ] {
        assert!(d0.get(key).is_some(), "missing key {key} in {d0}");
    }
    assert_eq!(d0["severity"], "error");
    assert_eq!(d0["line"], 5);
    assert_eq!(d0["column"], 30);
    assert_eq!(d0["end_column"], 32);
    assert_eq!(d0["element"], "S3");
    assert!(d0["witness"].is_null());
}

#[test]
fn missing_file_and_bad_usage_exit_2() {
    assert_eq!(sfc(&["check", "/nonexistent/chart.st"]).status.code(), Some(2));
    assert_eq!(sfc(&["check", "--format", "yaml", "x.st"]).status.code(), Some(2));
    assert_eq!(sfc(&["frobnicate"]).status.code(), Some(2));
    for sub in ["check", "fmt"] {
        assert_eq!(sfc(&[sub, "--help"]).status.code(), Some(0));
    }
}

#[test]
fn explain_prints_the_registry_text() {
    let out = sfc(&["check", "--explain", "SFC0209"]);
    assert_eq!(out.status.code(), Some(0));
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(s.contains("unknown action qualifier") && s.contains("N R S L D P SD DS SL P1 P0"), "{s}");
    assert_eq!(sfc(&["check", "--explain", "SFC9999"]).status.code(), Some(2));
}

#[test]
fn target_option_applies_atmt_rules() {
    let d = temp_dir("target");
    let f = d.join("a.st");
    std::fs::write(&f, "PROGRAM A\n    INITIAL_STEP S0: END_STEP\n    STEP S1: END_STEP\n    TRANSITION FROM S0 TO S1 := C0; END_TRANSITION\n    TRANSITION FROM S1 TO S0 := NOT C1; END_TRANSITION\nEND_PROGRAM\n").unwrap();
    let out = sfc(&["check", "--target", "atmt", "--format", "json", f.to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let codes: Vec<&str> = v.as_array().unwrap().iter().map(|d| d["code"].as_str().unwrap()).collect();
    assert_eq!(codes, vec!["SFC0407"]);
    let out = sfc(&["check", "--target", "eatmt", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn fmt_rewrites_in_place_and_check_reports() {
    let d = temp_dir("fmt");
    let f = d.join("messy.st");
    let messy = "program P\nvar x : BOOL; (* keep me *) end_var\ninitial_step S1: end_step\nstep S2 : end_step\ntransition from S1 to S2 := x; end_transition\ntransition from S2 to S1 := not x; end_transition\nend_program\n";
    std::fs::write(&f, messy).unwrap();
    let out = sfc(&["fmt", "--check", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(std::fs::read_to_string(&f).unwrap(), messy, "--check must not write");
    assert_eq!(sfc(&["fmt", f.to_str().unwrap()]).status.code(), Some(0));
    let formatted = std::fs::read_to_string(&f).unwrap();
    assert!(formatted.contains("(* keep me *)") && formatted.contains("INITIAL_STEP S1: END_STEP"), "{formatted}");
    assert_eq!(sfc(&["fmt", "--check", f.to_str().unwrap()]).status.code(), Some(0));
    let leftovers: Vec<_> = std::fs::read_dir(&d).unwrap().flatten().filter(|e| e.file_name() != "messy.st").collect();
    assert!(leftovers.is_empty(), "temporary files left behind");
}

/// An editor's layout saved in the older form (one `sfc.graph` line) is written one element per
/// line by `sfc fmt`, and opens in the editor as before; a formatted file stays as it is.
#[test]
fn fmt_writes_the_layout_one_element_per_line() {
    let d = temp_dir("fmt-layout");
    let f = d.join("v1.st");
    let v1 = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../sfc-doc/tests/snapshots/layout_v1.st")).unwrap();
    std::fs::write(&f, &v1).unwrap();
    assert_eq!(sfc(&["fmt", f.to_str().unwrap()]).status.code(), Some(0));
    let formatted = std::fs::read_to_string(&f).unwrap();
    assert!(formatted.contains("{attribute 'sfc.graph' := '{\"v\":2$7D'}\n{attribute 'sfc.graph.e' := '{\"s\":\"Idle\"$7D'}\n"), "{formatted}");
    assert_eq!(formatted.matches("sfc.graph.c").count(), 4, "{formatted}");
    let before = sfc_doc::open(0, "v1.st", &v1).charts;
    let after = sfc_doc::open(0, "v1.st", &formatted).charts;
    assert_eq!(before, after);
    assert_eq!(sfc(&["fmt", "--check", f.to_str().unwrap()]).status.code(), Some(0));
}

#[test]
fn fmt_refuses_files_with_syntax_errors() {
    let d = temp_dir("fmt-bad");
    let f = d.join("bad.st");
    let bad = "PROGRAM P\nINITIAL_STEP S1: END_STEP\nTRANSITION FROM S1 TO := ; END_TRANSITION\nEND_PROGRAM\n";
    std::fs::write(&f, bad).unwrap();
    let out = sfc(&["fmt", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(std::fs::read_to_string(&f).unwrap(), bad, "a file with errors is left untouched");
}

#[test]
fn fmt_filters_standard_input() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["fmt", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(b"program p\nvar x:int;end_var\nx:=x+1;\nend_program").unwrap();
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "PROGRAM p\n    VAR\n        x : int;\n    END_VAR\n\n    x := x + 1;\nEND_PROGRAM\n"
    );
}

#[test]
fn examples_are_in_canonical_layout() {
    let mut args = vec!["fmt".to_string(), "--check".to_string()];
    for dir in std::fs::read_dir(root().join("examples")).unwrap().flatten() {
        for f in std::fs::read_dir(dir.path()).into_iter().flatten().flatten() {
            if f.path().extension().is_some_and(|e| e == "st") {
                args.push(f.path().display().to_string());
            }
        }
    }
    assert!(args.len() >= 6);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = sfc(&refs);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
}

/// `sfc check` replays the witness of an unsafe finding in the simulator; a step whose action
/// loops forever on the witness's inputs stops the replay at the loop (SFC0510, a warning at
/// its line) and the finding stays *possible*, instead of the check hanging.
#[test]
fn check_reports_a_runaway_witness_replay_at_its_loop() {
    let text = std::fs::read_to_string(root().join("crates/sfc-analysis/tests/replay/fig68_unsafe.st"))
        .unwrap()
        .replace("        g : BOOL;\n    END_VAR", "        g : BOOL;\n    END_VAR\n    VAR n : DINT; END_VAR")
        .replace("    STEP K2: END_STEP", "    STEP K2:\n        Spin(N);\n    END_STEP")
        .replace(
            "END_PROGRAM",
            "    ACTION Spin:\n        WHILE a DO n := n + 1; END_WHILE;\n    END_ACTION\nEND_PROGRAM",
        );
    assert!(text.contains("WHILE a DO"), "the fixture still has the shape this test edits");
    let dir = temp_dir("runaway");
    let file = dir.join("spin.st");
    std::fs::write(&file, &text).unwrap();
    let line = text.lines().position(|l| l.contains("WHILE a DO")).unwrap() + 1;
    let o = sfc(&["check", file.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "the unsafe findings are errors: {err}");
    assert!(err.contains("warning[SFC0510]: runaway scan") && err.contains(&format!("spin.st:{line}:9")), "{err}");
    assert!(err.contains(&format!("= note: possible: the replay stopped trying to fire `T1` (step 1 of the witness): a scan ran away at line {line}, column 9")), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A Studio 5000 L5X export is read (`sfc-l5x`): its two SFC routines, drawn empty, are two
/// charts without an initial step, each reported on its `SFCContent`.
#[test]
fn a_logix_export_is_read_with_its_sfc_routines() {
    let dir = temp_dir("logix");
    let l5x = dir.join("Main.L5X");
    std::fs::write(
        &l5x,
        "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>\n<RSLogix5000Content SchemaRevision=\"1.0\" SoftwareRevision=\"32.01\">\n<Controller Use=\"Context\" Name=\"Demo\"><Programs><Program Name=\"Main\"><Routines>\n<Routine Name=\"Fill\" Type=\"SFC\"><SFCContent/></Routine>\n<Routine Name=\"Logic\" Type=\"RLL\"/>\n<Routine Name=\"Drain\" Type=\"SFC\"><SFCContent/></Routine>\n</Routines></Program></Programs></Controller>\n</RSLogix5000Content>\n",
    )
    .unwrap();
    let out = sfc(&["check", l5x.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("SFC0702"), "{err}");
    assert_eq!(err.matches("error[SFC0725]: the chart has no initial step").count(), 2, "{err}");
    assert!(err.contains("Main.L5X:4:") && err.contains("Main.L5X:6:"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A TIA Portal export is read by `sfc-simaticml`; one that holds no GRAPH block is one located
/// error (SFC0740) naming what it holds.
#[test]
fn a_tia_export_without_graph_blocks_is_named_with_what_it_holds() {
    let dir = temp_dir("tia");
    let tia = dir.join("Sequence.xml");
    std::fs::write(
        &tia,
        "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<Document>\n  <Engineering version=\"V17\" />\n  <SW.Blocks.FB ID=\"0\"><AttributeList><Name>Motor</Name><ProgrammingLanguage>LAD</ProgrammingLanguage></AttributeList></SW.Blocks.FB>\n</Document>\n",
    )
    .unwrap();
    let out = sfc(&["check", tia.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("error[SFC0740]") && err.contains(":2:1"), "{err}");
    assert!(err.contains("holds no S7-GRAPH block: it holds the LAD FB \"Motor\""), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A vendor's own XML (a TwinCAT `.TcPOU`) is not PLCopen: one located error that names the
/// export to use, and no second finding about an "empty" file (the import said why).
#[test]
fn a_twincat_source_file_is_refused_with_the_export_to_use() {
    let dir = temp_dir("tcpou");
    let path = dir.join("FB_Fill.TcPOU");
    std::fs::write(
        &path,
        "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<TcPlcObject Version=\"1.1.0.1\">\n  <POU Name=\"FB_Fill\">\n    <Implementation><SFC /></Implementation>\n  </POU>\n</TcPlcObject>\n",
    )
    .unwrap();
    for cmd in ["check", "sim"] {
        let out = sfc(&[cmd, path.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{cmd}: {err}");
        assert!(err.contains("error[SFC0702]") && err.contains("FB_Fill.TcPOU:2:1"), "{cmd}: {err}");
        assert!(err.contains("`Export PLCopenXML...`"), "{cmd}: {err}");
        assert!(!err.contains("nothing to check"), "{cmd}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--target svg` draws a long condition whole, wrapped over as many lines as it needs (the
/// editor's drawing, `sfc_doc::svg`): every word in the picture, nothing cut with `…`.
#[test]
fn svg_target_wraps_long_conditions_whole() {
    let d = temp_dir("svg-wrap");
    let words: Vec<String> = (0..16).map(|k| format!("Sensor{k}")).collect();
    let condition = words.join(" AND ");
    let text = format!(
        "PROGRAM P\n    VAR {} : BOOL; END_VAR\n    INITIAL_STEP S1: END_STEP\n    STEP S2: END_STEP\n    \
         TRANSITION FROM S1 TO S2 := {condition}; END_TRANSITION\n    TRANSITION FROM S2 TO S1 := Sensor0; END_TRANSITION\nEND_PROGRAM\n",
        words.join(", ")
    );
    let chart = d.join("long.st");
    std::fs::write(&chart, text).unwrap();
    let out = sfc(&["build", chart.to_str().unwrap(), "--target", "svg"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let svg = String::from_utf8_lossy(&out.stdout);
    assert!(!svg.contains('…'), "{svg}");
    let lines: Vec<&str> = svg
        .lines()
        .filter(|l| l.starts_with("<text") && l.contains("Mono"))
        .filter_map(|l| l.split('>').nth(1)?.split('<').next())
        .collect();
    // The long condition's lines, then the other transition's.
    assert!(lines.len() >= 5 && lines.last() == Some(&"Sensor0"), "{lines:?}");
    assert_eq!(lines[..lines.len() - 1].join(" "), condition);
}
