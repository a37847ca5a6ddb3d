//! Files as other tools and editors write them, through the `sfc` binary: every corpus file
//! converts to text and checks; errors of one POU do not block another; a file with no SFC POU
//! says so; a UTF-8 BOM, Latin-1 and CRLF survive `fmt` and `build` reads them.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sfc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).output().expect("sfc runs")
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-real-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(o: &[u8]) -> String {
    String::from_utf8_lossy(o).into_owned()
}

fn corpus() -> Vec<PathBuf> {
    fn walk(d: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "xml") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(&root().join("tests/corpus/real"), &mut out);
    out.sort();
    out
}

/// `sfc build x.xml --target text` converts every corpus file, and `sfc check` finds no error.
#[test]
fn every_corpus_file_converts_and_checks() {
    let files = corpus();
    assert!(files.len() >= 25);
    for f in &files {
        let p = f.to_str().unwrap();
        let out = sfc(&["build", p, "--target", "text"]);
        assert_eq!(out.status.code(), Some(0), "{p}: {}", text(&out.stderr));
        let t = text(&out.stdout);
        assert!(t.contains("INITIAL_STEP"), "{p}: no chart in\n{t}");
        let out = sfc(&["check", "--no-analysis", p]);
        assert_eq!(out.status.code(), Some(0), "{p}: {}", text(&out.stderr));
    }
}

/// Every POU of the files in the shapes of CODESYS, TwinCAT and e!COCKPIT (found in the XML
/// itself, wherever the file keeps it) simulates on its own through `sfc sim --pou NAME`:
/// function blocks whose code is in actions, charts inside actions, step actions.
#[test]
fn every_pou_of_codesys_family_files_simulates() {
    let mut runs = 0;
    let mut kept = Vec::new();
    for f in corpus().iter().filter(|f| {
        let dir = f.parent().and_then(|d| d.file_name()).and_then(|d| d.to_str()).unwrap_or("");
        ["codesys", "twincat", "ecockpit"].contains(&dir)
    }) {
        let p = f.to_str().unwrap();
        let xml = std::fs::read_to_string(f).unwrap();
        for rest in xml.split("<pou name=\"").skip(1) {
            let n = rest.split('"').next().unwrap_or("");
            // A FUNCTION has no state to simulate: programs and blocks are what a user runs.
            if rest.split('>').next().is_some_and(|tag| tag.contains("pouType=\"function\"")) {
                continue;
            }
            let out = sfc(&["sim", p, "--pou", n, "--scans", "3"]);
            // A POU the import keeps as written (object orientation, pointers: said by a note
            // when the file is read) is not simulated yet, and `sim` says so.
            if text(&out.stderr).contains("is kept as written, not analysed") {
                kept.push(format!("{n} ({})", f.file_name().unwrap().to_string_lossy()));
                continue;
            }
            assert_eq!(out.status.code(), Some(0), "{p} --pou {n}: {}", text(&out.stderr));
            assert!(text(&out.stdout).contains(&format!("simulated {n}")), "{p} --pou {n}: {}", text(&out.stdout));
            runs += 1;
        }
    }
    eprintln!("{runs} POUs simulated; kept as written, not simulated yet: {}", kept.join(", "));
    assert!(runs >= 90, "only {runs} POUs simulated");
    // Only PLC_PRG of library_fb_instances.xml is kept (a WAGO library block reached through
    // its namespace). Methods, properties, interfaces, EXTENDS, pointers, `SIZEOF` and
    // `__ISVALIDREF` (tank_objects.xml, elevator_oop.xml, st_dialect_enum_oop.xml) simulate.
    assert!(kept.len() <= 1, "more POUs kept as written than the one known: {kept:?}");
}

/// A CODESYS project export keeps its POUs in the application's resource: they are found, and
/// the program instance without a type names the POU.
#[test]
fn codesys_application_pous_are_found() {
    let f = root().join("tests/corpus/real/codesys/project_export_application.xml");
    let out = sfc(&["build", f.to_str().unwrap(), "--target", "text"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let t = text(&out.stdout);
    assert!(t.contains("PROGRAM PLC_PRG"), "{t}");
    assert!(t.contains("PROGRAM PLC_PRG WITH MainTask : PLC_PRG;"), "{t}");
    assert!(t.contains(":= Full OR Abort;"), "GVL.Abort is the global Abort:\n{t}");
}

const TWO_POUS: &str = "PROGRAM Good
    VAR Go : BOOL; END_VAR
    INITIAL_STEP S0: END_STEP
    TRANSITION FROM S0 TO S1 := Go; END_TRANSITION
    STEP S1: END_STEP
    TRANSITION FROM S1 TO S0 := NOT Go; END_TRANSITION
END_PROGRAM

PROGRAM Broken
    VAR X : INT; END_VAR
    INITIAL_STEP A: END_STEP
    TRANSITION FROM A TO B := X; END_TRANSITION
    STEP B: END_STEP
    TRANSITION FROM B TO A := Undeclared; END_TRANSITION
END_PROGRAM
";

/// Errors of one POU never block another: `--pou` builds and simulates the sound one; `check`
/// still reports the broken one; converting to text never refuses.
#[test]
fn an_error_in_one_pou_does_not_block_another() {
    let d = temp_dir("isolation");
    let f = d.join("two.st");
    std::fs::write(&f, TWO_POUS).unwrap();
    let p = f.to_str().unwrap();
    let out = sfc(&["build", p, "--target", "st", "--pou", "Good"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("Good"));
    let out = sfc(&["build", p, "--target", "st", "--pou", "Broken"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let out = sfc(&["sim", p, "--pou", "Good", "--scans", "3", "--set", "Go=TRUE"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("active steps: S1"), "{}", text(&out.stdout));
    let out = sfc(&["check", "--no-analysis", p]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("Undeclared"), "{}", text(&out.stderr));
    // A conversion writes its output and says by its exit code that the file has errors.
    let out = sfc(&["build", p, "--target", "text"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("PROGRAM Broken"));
    assert!(text(&out.stderr).contains("Undeclared"), "the errors are reported: {}", text(&out.stderr));
    // To PLCopen too, with the type errors reported.
    let xml = d.join("two.xml");
    let out = sfc(&["build", p, "--target", "plcopen", "-o", xml.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(std::fs::read_to_string(&xml).unwrap().contains("<pou name=\"Broken\""));
}

/// A POU whose errors keep its chart from being written whole (an association naming no
/// action) is still exported: from text with its text in its addData, which the import reads
/// back as it was; from PLCopen as it was read. Both with SFC0716 and exit code 1.
#[test]
fn plcopen_export_never_refuses_a_pou() {
    let d = temp_dir("export-never-refuses");
    let f = d.join("two.st");
    std::fs::write(&f, TWO_POUS.replace("STEP B: END_STEP", "STEP B: Missing(N); END_STEP")).unwrap();
    let xml = d.join("two.xml");
    let out = sfc(&["build", f.to_str().unwrap(), "--target", "plcopen", "-o", xml.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("SFC0716"), "{}", text(&out.stderr));
    let written = std::fs::read_to_string(&xml).unwrap();
    assert!(written.contains("<pou name=\"Good\"") && written.contains("<SFC>"), "{written}");
    assert!(written.contains("<pou name=\"Broken\"") && written.contains("Missing(N)"), "{written}");
    let back = sfc(&["build", xml.to_str().unwrap(), "--target", "text"]);
    assert_eq!(back.status.code(), Some(1), "{}", text(&back.stderr));
    assert!(
        text(&back.stdout).contains("PROGRAM Broken") && text(&back.stdout).contains("Missing(N);"),
        "{}",
        text(&back.stdout)
    );
    assert!(text(&back.stderr).contains("Missing") && text(&back.stderr).contains("SFC0716"), "{}", text(&back.stderr));
    let again = d.join("again.xml");
    let out = sfc(&["build", xml.to_str().unwrap(), "--target", "plcopen", "-o", again.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("as it was read from the PLCopen file"), "{}", text(&out.stderr));
    assert!(std::fs::read_to_string(&again).unwrap().contains("Missing(N)"));
}

/// A PLCopen file without any SFC POU gets a warning, never a silent exit 0 with empty output.
#[test]
fn a_file_without_sfc_pou_says_so() {
    let d = temp_dir("nosfc");
    let f = d.join("st_only.xml");
    std::fs::write(
        &f,
        r#"<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0200">
  <fileHeader companyName="" productName="CODESYS" productVersion="CODESYS V3.5 SP19" creationDateTime="2024-01-01T00:00:00" />
  <contentHeader name="Lib.project"><coordinateInfo><fbd><scaling x="1" y="1" /></fbd><ld><scaling x="1" y="1" /></ld><sfc><scaling x="1" y="1" /></sfc></coordinateInfo></contentHeader>
  <types><dataTypes /><pous>
    <pou name="Scale" pouType="function"><interface><returnType><REAL /></returnType><inputVars><variable name="x"><type><INT /></type></variable></inputVars></interface>
      <body><ST><xhtml xmlns="http://www.w3.org/1999/xhtml">Scale := INT_TO_REAL(x) / 10.0;</xhtml></ST></body></pou>
  </pous></types>
  <instances><configurations /></instances>
</project>
"#,
    )
    .unwrap();
    let out = sfc(&["check", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    assert!(text(&out.stderr).contains("SFC0712"), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("POUs found: Scale"), "{}", text(&out.stderr));
    let out = sfc(&["build", f.to_str().unwrap(), "--target", "text"]);
    assert!(text(&out.stderr).contains("SFC0712"), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("FUNCTION Scale"), "{}", text(&out.stdout));
}

const CHART: &str = "PROGRAM P\r\n  VAR Go : BOOL; (* Ventil öffnen *) END_VAR\r\n  INITIAL_STEP S0: END_STEP\r\n  TRANSITION FROM S0 TO S1 := Go; END_TRANSITION\r\n  STEP S1: END_STEP\r\n  TRANSITION FROM S1 TO S0 := NOT Go; END_TRANSITION\r\nEND_PROGRAM\r\n";

/// A UTF-8 BOM is accepted and kept by `fmt`, with the CRLF line endings.
#[test]
fn bom_and_crlf_survive_fmt_and_build() {
    let d = temp_dir("bom");
    let f = d.join("bom.st");
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend_from_slice(CHART.as_bytes());
    std::fs::write(&f, &bytes).unwrap();
    let p = f.to_str().unwrap();
    let out = sfc(&["check", "--no-analysis", p]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(out.stderr.is_empty(), "{}", text(&out.stderr));
    let out = sfc(&["fmt", p]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let after = std::fs::read(&f).unwrap();
    assert!(after.starts_with(b"\xEF\xBB\xBF"), "the BOM is kept");
    let body = &after[3..];
    let lf = body.iter().filter(|&&b| b == b'\n').count();
    let crlf = body.windows(2).filter(|w| w == b"\r\n").count();
    assert!(lf > 0 && lf == crlf, "every line ends in CRLF");
    assert!(String::from_utf8_lossy(body).contains("Ventil öffnen"));
    let out = sfc(&["build", p, "--target", "st"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

/// Latin-1 text is read with a warning naming its first non-UTF-8 line, and `fmt` writes it
/// back in Latin-1.
#[test]
fn latin1_is_read_with_a_warning_and_kept() {
    let d = temp_dir("latin1");
    let f = d.join("latin1.st");
    let latin1: Vec<u8> = CHART.replace("\r\n", "\n").chars().map(|c| c as u32 as u8).collect();
    std::fs::write(&f, &latin1).unwrap();
    let p = f.to_str().unwrap();
    let out = sfc(&["check", "--no-analysis", p]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(err.contains("SFC0011") && err.contains("line 2"), "{err}");
    let out = sfc(&["fmt", p]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let after = std::fs::read(&f).unwrap();
    assert!(after.windows(2).any(|w| w == b" \xF6"), "written back in Latin-1");
    assert!(std::str::from_utf8(&after).is_err());
    assert!(!after.contains(&b'\r'), "LF stays LF");
    let out = sfc(&["build", p, "--target", "text"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("Ventil öffnen"), "{}", text(&out.stdout));
}

/// A PLCopen chart simulates like its text.
#[test]
fn xml_charts_simulate() {
    let f = root().join("tests/corpus/real/beremiz/tank_sequence.plc.xml");
    let out = sfc(&["sim", f.to_str().unwrap(), "--scans", "3", "--set", "Start=TRUE"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("active steps: Filling"), "{}", text(&out.stdout));
}
