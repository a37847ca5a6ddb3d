//! `sfc run` as a user runs it: the real binary on the car wash, its monitor URL on standard
//! error, a WebSocket client speaking the monitor protocol (a minimal RFC 6455 client over a
//! TCP socket), the exit status and the printed statistics.

mod common;

use common::{command, root, scratch, Run, Ws};
use std::process::Command;

/// The car wash, halted until the client continues, then 50 scans: hello, snapshot, a
/// breakpoint hit, the end of the run, exit status 0 and the statistics.
#[test]
fn a_monitor_client_drives_the_car_wash_to_its_end() {
    let mut run = Run::start(&[
        "examples/carwash/carwash.st",
        "--period",
        "T#5ms",
        "--monitor",
        "127.0.0.1:0",
        "--no-retain",
        "--halted",
        "--scans",
        "50",
    ]);
    let line = run.line("the monitor URL", 20, |l| l.starts_with("sfc run: monitor on "));
    let url = line.strip_prefix("sfc run: monitor on ").unwrap().to_string();
    // A token of the user's is not printed (logs are read by others).
    assert!(url.starts_with("ws://127.0.0.1:") && url.ends_with("/ (token from SFC_TOKEN)"), "{url}");
    assert!(!url.contains(":0/"), "port 0 is replaced by the port bound: {url}");
    let url = format!("{}?token=t0k3n", url.split(' ').next().unwrap());

    let mut ws = Ws::connect(&url);
    let hello = ws.next().expect("hello");
    assert_eq!(hello["type"], "hello");
    assert_eq!((hello["runtime"].as_str(), hello["pou"].as_str()), (Some("sfc run"), Some("CarWash")));
    assert_eq!((hello["period"].as_str(), hello["authorized"].as_bool()), (Some("T#5ms"), Some(true)));
    assert_eq!(hello["halted"], true);
    // One scan by hand: the snapshot of scan 0 with the initial step.
    ws.send(r#"{"id":1,"cmd":"step"}"#);
    let first = ws.until("the first scan", |m| m["type"] == "snapshot" || m["type"] == "delta");
    assert_eq!((first["scan"].as_u64(), first["active"][0]["step"].as_str()), (Some(0), Some("Idle")));
    // A breakpoint on Spraying, the inputs that start a wash, and on.
    ws.send(r#"{"id":2,"cmd":"breakpoint","op":"set","name":"Spraying"}"#);
    for (i, name) in ["CarPresent", "AtHome", "StartButton"].iter().enumerate() {
        ws.send(&format!(r#"{{"id":{},"cmd":"set","name":"{name}","value":true}}"#, 3 + i));
    }
    ws.send(r#"{"id":9,"cmd":"continue"}"#);
    let hit = ws.until("the breakpoint", |m| m["type"] == "event" && m["kind"] == "breakpoint");
    assert_eq!(hit["step"], "Spraying");
    let halted = ws.until("the halt", |m| m["type"] == "halted");
    assert_eq!(halted["reason"], "breakpoint");
    ws.send(r#"{"id":10,"cmd":"continue"}"#);
    let end = ws.until("the end of the run", |m| m["type"] == "halted" && m["reason"] == "end");

    let (status, rest) = run.finish(20);
    assert_eq!(status, Some(0));
    let stats = rest.iter().find(|l| l.starts_with("sfc run: 50 scans; start jitter p50 ")).unwrap_or_else(|| {
        panic!("no statistics line in {rest:?}");
    });
    assert!(stats.contains(" overruns, ") && stats.ends_with(" periods skipped"), "{stats}");
    // --scans 50 runs 50 scans: numbers 0..=49, plus the periods an overrun skipped (a loaded
    // machine skips some; scan numbers follow the clock).
    let skipped: u64 = stats
        .strip_suffix(" periods skipped")
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count of skipped periods in {stats}"));
    assert_eq!(end["scan"].as_u64(), Some(49 + skipped), "--scans 50 runs scans 0..=49 (+{skipped} skipped): {end}");
}

/// A chart with errors is refused like `sfc check` (exit 2), and so is a bad monitor address.
#[test]
fn bad_charts_and_arguments_exit_2() {
    let dir = std::env::temp_dir().join(format!("sfc-run-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.st");
    std::fs::write(
        &bad,
        "PROGRAM P\nINITIAL_STEP S: END_STEP\nTRANSITION FROM S TO S := Nope; END_TRANSITION\nEND_PROGRAM\n",
    )
    .unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_sfc")).args(["run", bad.to_str().unwrap(), "--scans", "1"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.st:3:") && err.contains("Nope"), "{err}");
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["run", "examples/carwash/carwash.st", "--monitor", "localhost"])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A runtime error of the chart stops the run with exit status 1 and says where.
#[test]
fn a_runtime_error_exits_1() {
    let dir = std::env::temp_dir().join(format!("sfc-run-test-div-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let chart = dir.join("div.st");
    std::fs::write(
        &chart,
        "PROGRAM Divide\nVAR d : INT; q : INT; END_VAR\nINITIAL_STEP S:\n    A(N);\nEND_STEP\n\
         ACTION A:\n    q := 10 / d;\nEND_ACTION\n\
         TRANSITION FROM S TO S := FALSE; END_TRANSITION\nEND_PROGRAM\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["run", chart.to_str().unwrap(), "--scans", "10", "--period", "T#1ms"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("error: 7:") && err.contains("(scan 0)"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A PLCopen XML chart runs as the IEC text it imports to, as `sfc sim` runs it: Beremiz's
/// traffic light with its svghmi buttons (HMI_BOOL, declared as the svghmi library does, said
/// in a note). A chart error is located in the XML.
#[test]
fn a_plcopen_chart_runs() {
    let corpus = root().join("../shared/corpus/beremiz/svghmi_traffic_light.plc.xml");
    let out = command(&["run", corpus.to_str().unwrap(), "--scans", "3", "--no-retain"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(err.contains("note[SFC0714]: type `HMI_BOOL` is not declared in the file: declared as BOOL"), "{err}");
    assert!(err.contains("sfc run: 3 scans"), "{err}");
    let dir = scratch("run-plcopen-error");
    let bad = dir.join("bad.xml");
    let xml = std::fs::read_to_string(&corpus)
        .unwrap()
        .replace("<expression>SwitchButton</expression>", "<expression>NoSuchButton</expression>");
    std::fs::write(&bad, xml).unwrap();
    let out = command(&["run", bad.to_str().unwrap(), "--scans", "3", "--no-retain"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("bad.xml:1348:"), "the error at its XML line: {err}");
    assert!(err.contains("NoSuchButton"), "{err}");
}

/// A runtime fault of a PLCopen chart is located in its XML (line and column of the body's
/// text there), not in the IEC text it was imported to.
#[test]
fn a_plcopen_charts_fault_is_located_in_its_xml() {
    let dir = scratch("run-plcopen-fault");
    let xml = dir.join("dz.xml");
    let st = root().join("crates/sfc-cli/tests/run/divide_by_zero.st");
    let out =
        command(&["build", st.to_str().unwrap(), "--target", "plcopen", "-o", xml.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&xml).unwrap();
    let (n, line) = text.lines().enumerate().find(|(_, l)| l.contains("Q := 10 / Zero;")).expect("the body in the XML");
    let column = line.find("10 / Zero").unwrap() + 1;
    let out = command(&["run", xml.to_str().unwrap(), "--scans", "5", "--no-retain"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    let at = format!("error: {}:{column}: division by zero (scan 1) in action A1 of step S1", n + 1);
    assert!(err.contains(&at), "expected `{at}` in: {err}");
}
