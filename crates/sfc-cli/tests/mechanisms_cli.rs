//! Seed 003's diagnostics of mechanisms through the `sfc` binary, on the spindle reversal
//! (examples/spindle): the condition analysis names each input with its terminal, a
//! supervision timeout makes an error record (instance, step, error code, the unmet condition
//! with terminals and values, the time waited) in `sfc sim`'s output, its trace and scenario
//! expectations, in `sfc run`'s log and monitor; the time analysis per run and every mechanism
//! at a glance in `sim --stats` and the monitor.

mod common;

use common::{command, root, scratch, Modbus, Run, Ws};

fn sfc(args: &[&str]) -> std::process::Output {
    command(args).output().expect("sfc runs")
}

fn text(o: &std::process::Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

const SCENARIO: &str = "examples/spindle/spindle.scenario.toml";
const CHART: &str = "examples/spindle/spindle.st";

/// Both seed error cases (4.04 KM1 does not drop out, 4.05 KM2 does not pull in) give error
/// records whose condition names the feedback contact with its terminal and value.
#[test]
fn sim_prints_error_records_with_terminals() {
    let o = sfc(&["sim", CHART, "--scenario", SCENARIO]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(
        out.contains(
            "scan 52, T#5s200ms: error record: Rev: error 404 in step Rev.OpenKM1 after T#1s100ms (supervision time T#1s); \
             waiting for Rev.TKM1Released: KM1Fb (X12.2, %IX0.4) is TRUE; needs FALSE"
        ),
        "{out}"
    );
    assert!(
        out.contains(
            "scan 85, T#8s500ms: error record: Rev: error 405 in step Rev.CloseKM2 after T#1s100ms (supervision time T#1s); \
             waiting for Rev.TKM2Closed: KM2Fb (X12.3, %IX0.5) is FALSE; needs TRUE"
        ),
        "{out}"
    );
    // The condition analysis of the timed-out step names the terminal too.
    assert!(out.contains("Rev.TKM2Closed := KM2Fb is FALSE with KM2Fb (X12.3, %IX0.5) = FALSE"), "{out}");
}

/// `--explain` at a chosen moment: the terminal of an input of the block is the caller's
/// located variable it is wired to (`Rev(KM2Fb := KM2Contact)`, `KM2Contact AT %IX0.5`).
#[test]
fn explain_names_terminals() {
    let o = sfc(&["sim", CHART, "--scenario", SCENARIO, "--until", "T#8s", "--explain"]);
    let out = text(&o);
    assert!(out.contains("step Rev.CloseKM2 active for T#700ms, timeout T#1s (T#300ms left)"), "{out}");
    assert!(out.contains("KM2Fb (X12.3, %IX0.5) is FALSE; needs TRUE"), "{out}");
    let o = sfc(&["sim", CHART, "--scenario", SCENARIO, "--until", "T#8s", "--explain", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", text(&o)));
    let t = &v["explain"][0]["transitions"][0];
    assert_eq!(t["operands"][0]["terminal"], "X12.3, %IX0.5", "{v}");
    assert_eq!(t["needs"][0], "KM2Fb (X12.3, %IX0.5) is FALSE; needs TRUE", "{v}");
}

/// The JSON-lines trace carries each record as an added `supervision` event, after the
/// contract's events, in the scan it was completed.
#[test]
fn trace_has_supervision_events() {
    let dir = scratch("mech-trace");
    let trace = dir.join("t.jsonl");
    let o = sfc(&["sim", CHART, "--scenario", SCENARIO, "--trace", trace.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let rows: Vec<serde_json::Value> =
        std::fs::read_to_string(&trace).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let records: Vec<(u64, &serde_json::Value)> = rows
        .iter()
        .flat_map(|r| {
            r["events"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|e| e["kind"] == "supervision")
                .map(|e| (r["scan"].as_u64().unwrap(), e))
        })
        .collect();
    assert_eq!(records.len(), 2, "{records:?}");
    let (scan, e) = records[0];
    assert_eq!(scan, 52);
    assert_eq!(
        (e["instance"].as_str(), e["step"].as_str(), e["code"].as_i64()),
        (Some("Rev"), Some("Rev.OpenKM1"), Some(404))
    );
    assert_eq!(
        (e["scan"].as_u64(), e["time"].as_str(), e["waited"].as_str()),
        (Some(51), Some("T#5s100ms"), Some("T#1s100ms"))
    );
    assert_eq!(e["code_variable"], "Rev.ErrorCode");
    assert_eq!(e["conditions"][0]["condition"], "KM1Fb (X12.2, %IX0.4) is TRUE; needs FALSE");
    let (scan, e) = records[1];
    assert_eq!((scan, e["code"].as_i64(), e["step"].as_str()), (85, Some(405), Some("Rev.CloseKM2")));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scenario's `error_record` expectation checks the text; a wrong text fails with both.
#[test]
fn scenario_checks_the_record_text() {
    let o = sfc(&["test", "examples/spindle"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let dir = scratch("mech-scenario");
    let chart = root().join(CHART);
    std::fs::write(
        dir.join("wrong.scenario.toml"),
        format!(
            "chart = {:?}\npou = \"SpindleReversal\"\nperiod = \"T#100ms\"\n\
             [[at]]\ntime = \"T#0s\"\nset = {{ Start = true, KM1Fb = true }}\n\
             [[at]]\ntime = \"T#1s300ms\"\nexpect = {{ error_record = \"KM1Fb is FALSE\" }}\n",
            chart.to_str().unwrap()
        ),
    )
    .unwrap();
    let o = sfc(&["test", dir.to_str().unwrap()]);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(
        out.contains(
            "`error_record`: expected a record containing \"KM1Fb is FALSE\", actual \"SpindleReversal: error 404 in step \
             OpenKM1 after T#1s100ms (supervision time T#1s); waiting for TKM1Released: KM1Fb is TRUE; needs FALSE\""
        ),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--stats`: the runs of the mechanism with the states passed, how each ended (the reset by
/// SFCInit counted), the statistics per state over runs, and the mechanisms overview.
#[test]
fn stats_show_runs_and_mechanisms() {
    let o = sfc(&["sim", CHART, "--scenario", SCENARIO, "--stats"]);
    let out = text(&o);
    assert!(out.contains("runs of Rev: 4 (1 normal, 2 error, 1 reset)"), "{out}");
    for row in [
        "1    T#1s   T#800ms    normal     Rev.OpenKM1 T#300ms → Rev.Settle T#200ms → Rev.CloseKM2 T#200ms → Rev.Finished T#100ms",
        "2    T#4s   T#1s500ms  error 404  Rev.OpenKM1 T#1s200ms → Rev.Err404 T#300ms",
        "3    T#7s   T#2s       error 405  Rev.OpenKM1 T#100ms → Rev.Settle T#200ms → Rev.CloseKM2 T#1s200ms → Rev.Err405 T#500ms",
        "4    T#10s  T#200ms    reset      Rev.OpenKM1 T#200ms",
        "Rev.OpenKM1   4      T#100ms  T#450ms  T#1s200ms",
    ] {
        assert!(out.contains(row), "missing `{row}` in\n{out}");
    }
    assert!(out.contains("Rev       SpindleReversal  FALSE       idle   Rev.Idle (T#200ms)  4     1       2"), "{out}");
    assert!(out.contains("last error of Rev: Rev: error 405 in step Rev.CloseKM2"), "{out}");
    let o = sfc(&["sim", CHART, "--scenario", SCENARIO, "--stats", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", text(&o)));
    assert_eq!(v["mechanisms"][0]["runs"], 4, "{v}");
    assert_eq!(v["mechanisms"][0]["lastError"]["code"], 405, "{v}");
    assert_eq!(v["runs"][0]["runs"][3]["ended"], "reset", "{v}");
    assert_eq!(v["error_records"].as_array().map(Vec::len), Some(2), "{v}");
}

/// `sfc run`: the error record in the log on standard error, as a monitor event and in the
/// Modbus error record block; the monitor's `explain` names terminals, `mechanisms` lists the
/// instance with its last error, `timing` gives the runs.
#[test]
fn run_logs_error_records_and_the_monitor_lists_mechanisms() {
    let mut run = Run::start(&[
        CHART,
        "--period",
        "T#10ms",
        "--monitor",
        "127.0.0.1:0",
        "--modbus",
        "127.0.0.1:0",
        "--no-retain",
        "--scans",
        "600",
    ]);
    let mut mb = Modbus::connect(run.modbus());
    // No record yet: the block reads zeros.
    assert_eq!(mb.read_input_registers(40000, 8), vec![0; 8]);
    let line = run.line("the monitor URL", 20, |l| l.starts_with("sfc run: monitor on "));
    let url = line.strip_prefix("sfc run: monitor on ").unwrap().split(' ').next().unwrap().to_string();
    let mut ws = Ws::connect(&format!("{url}?token=t0k3n"));
    let set = |ws: &mut Ws, id: u64, name: &str| {
        let r = ws.cmd(id, serde_json::json!({"cmd": "set", "name": name, "value": true}));
        assert_eq!(r["ok"], true, "{r}");
    };
    set(&mut ws, 1, "StartCwButton");
    set(&mut ws, 2, "KM1Contact");
    std::thread::sleep(std::time::Duration::from_millis(100));
    set(&mut ws, 3, "ReverseButton");
    // While OpenKM1 waits (1 s), the condition analysis names KSMP's terminal.
    let mut explained = None;
    for k in 0..40 {
        let r = ws.cmd(10 + k, serde_json::json!({"cmd": "explain", "step": "Rev.OpenKM1"}));
        if r["ok"] == true {
            explained = Some(r);
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let r = explained.expect("Rev.OpenKM1 became active");
    let lines = r["result"]["lines"].to_string();
    assert!(lines.contains("KM1Fb (X12.2, %IX0.4) is TRUE; needs FALSE"), "{r}");
    let e = ws.until("the error record", |m| m["type"] == "event" && m["kind"] == "supervision");
    assert_eq!((e["instance"].as_str(), e["code"].as_i64()), (Some("Rev"), Some(404)), "{e}");
    assert!(e["condition"].as_str().unwrap().contains("KM1Fb (X12.2, %IX0.4) is TRUE; needs FALSE"), "{e}");
    let m = ws.cmd(100, serde_json::json!({"cmd": "mechanisms"}));
    let rev = &m["result"]["mechanisms"][0];
    assert_eq!((rev["instance"].as_str(), rev["pou"].as_str()), (Some("Rev"), Some("SpindleReversal")), "{m}");
    assert_eq!(rev["lastError"]["code"], 404, "{m}");
    assert_eq!(rev["activationVariable"], "Rev.Start", "{m}");
    assert!(rev["runs"].as_u64().unwrap() >= 1, "{m}");
    let t = ws.cmd(101, serde_json::json!({"cmd": "timing"}));
    let first = &t["result"]["mechanisms"][0]["runs"][0];
    assert_eq!(first["states"][0]["state"], "Rev.OpenKM1", "{t}");
    let logged = run.line("the error record in the log", 20, |l| l.contains("error record: Rev: error 404"));
    assert!(logged.contains("KM1Fb (X12.2, %IX0.4) is TRUE; needs FALSE"), "{logged}");
    // Modbus: input registers 40000… hold the record for an HMI (docs/runtime.md).
    let mut head = mb.read_input_registers(40000, 8);
    for _ in 0..50 {
        if head[0] != 0 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
        head = mb.read_input_registers(40000, 8);
    }
    assert_eq!(head[0], 1, "one record: {head:?}");
    assert_eq!((head[1], head[2]), (0, 404), "the error code, DINT high word first: {head:?}");
    let waited = u32::from(head[3]) << 16 | u32::from(head[4]);
    assert!((1000..1200).contains(&waited), "time waited in ms: {head:?}");
    assert_eq!((head[5], head[6]), (0, 1000), "supervision time T#1s in ms: {head:?}");
    let len = usize::from(head[7]);
    let mut regs = mb.read_input_registers(40008, 125);
    regs.extend(mb.read_input_registers(40133, 75));
    let bytes: Vec<u8> = regs.iter().flat_map(|r| r.to_be_bytes()).take(len).collect();
    let shown = String::from_utf8(bytes).expect("UTF-8 text");
    assert!(shown.starts_with("Rev: error 404 in step Rev.OpenKM1"), "{shown}");
    assert!(shown.contains("KM1Fb (X12.2, %IX0.4) is TRUE; needs FALSE"), "{shown}");
    // The record ends at 40207; the run's status block follows at 40300–40307 (the registers
    // between read 0), and a read past 40307 is refused (exception 2).
    assert_eq!(mb.read_input_registers(40208, 92), vec![0; 92]);
    assert_eq!(mb.read_input_registers(40300, 1), [0], "RUN in the status block");
    let mut pdu = vec![4];
    pdu.extend_from_slice(&40300u16.to_be_bytes());
    pdu.extend_from_slice(&9u16.to_be_bytes());
    assert_eq!(mb.request(&pdu), vec![0x84, 2]);
    drop(ws);
    let (status, _) = run.finish(30);
    assert_eq!(status, Some(0));
}

/// A chart that supervises its wait with its own timer guard (`Closing.T > T#500ms` into an
/// error step, no `sfc.timeout`) gets the same error record, naming that transition.
#[test]
fn a_timer_guard_into_an_error_step_makes_a_record() {
    let dir = "crates/sfc-cli/tests/mechanisms";
    let o = sfc(&["test", dir]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let o = sfc(&["sim", &format!("{dir}/clamp.st"), "--scenario", &format!("{dir}/clamp.scenario.toml"), "--stats"]);
    let out = text(&o);
    assert!(
        out.contains(
            "error record: Clamp: error 7 in step Closing after T#600ms (timer guard of TTooLong); \
             waiting for TClosed: Closed (X3.1, %IX1.0) is FALSE; needs TRUE"
        ),
        "{out}"
    );
    assert!(out.contains("runs of Clamp: 1 (0 normal, 1 error, 0 reset)"), "{out}");
}
