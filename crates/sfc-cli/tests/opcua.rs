//! `sfc run --opcua` against an independent OPC UA client: Python `asyncua`
//! (`tests/opcua/carwash_client.py`, installed by scripts/asyncua-deps.sh from the README's test
//! command) on the real binary running the car wash. Figures are printed, never asserted.
#![cfg(feature = "opcua")]

mod common;

use common::{command, root, scratch, Run, Ws};
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Stdio;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn carwash() -> PathBuf {
    root().join("examples/carwash/carwash.st")
}

use common::asyncua;

/// `carwash_client.py` in `mode` against `url`; its JSON report.
fn client(mode: &str, url: &str, rest: &[&str]) -> serde_json::Value {
    let mut args = vec![mode, url];
    args.extend_from_slice(rest);
    client_script("carwash_client.py", &args)
}

/// `sfc run CHART` with OPC UA on a free loopback port, SecurityPolicy None allowed (local
/// clients, anonymous), its PKI in `pki`, no retain file, for at most two minutes, and `extra`.
fn open_run(chart: &Path, pki: &Path, extra: &[&str]) -> Run {
    let mut args =
        vec![s(chart), "--no-retain", "--opcua", "opc.tcp://127.0.0.1:0", "--opcua-allow-none", "--opcua-pki"];
    args.push(s(pki));
    args.extend_from_slice(extra);
    if !extra.contains(&"--for") {
        args.extend(["--for", "T#120s"]);
    }
    Run::start(&args)
}

fn opcua_url(run: &mut Run) -> String {
    let l = run.line("the OPC UA endpoint", 120, |l| l.starts_with("sfc run: OPC UA on "));
    l["sfc run: OPC UA on ".len()..].split(' ').next().unwrap().to_string()
}

/// The car wash as the chart declares it: every variable in its section with its OPC UA type
/// and address, every step.
const VARIABLES: &[(&str, &str, &str, Option<&str>)] = &[
    ("StartButton", "Inputs", "Boolean", Some("%IX0.0")),
    ("CarAtBrush", "Inputs", "Boolean", Some("%IX0.1")),
    ("CarLeft", "Inputs", "Boolean", Some("%IX0.2")),
    ("StopButton", "Inputs", "Boolean", Some("%IX0.3")),
    ("CarPresent", "Inputs", "Boolean", Some("%IX0.4")),
    ("AtHome", "Inputs", "Boolean", Some("%IX0.5")),
    ("DryerSelect", "Inputs", "Boolean", Some("%IX0.6")),
    ("SprayValve", "Outputs", "Boolean", Some("%QX0.0")),
    ("Travel", "Outputs", "Boolean", Some("%QX0.1")),
    ("Brush", "Outputs", "Boolean", Some("%QX0.2")),
    ("TravelBack", "Outputs", "Boolean", Some("%QX0.3")),
    ("Blower", "Outputs", "Boolean", Some("%QX0.4")),
    ("FaultLamp", "Outputs", "Boolean", Some("%QX0.5")),
    ("MaxTravelTime", "Locals", "Duration", None),
    ("MaxBrushTime", "Locals", "Duration", None),
    ("BlowerSpinUp", "Locals", "Duration", None),
    ("Washes", "Locals", "UInt32", None),
];
const STEPS: &[&str] = &["Idle", "Spraying", "Brushing", "Drying", "Returning", "Fault"];

/// Browse, read, subscribe to Spraying.X, start the wash by writing inputs, and try to write
/// an output — over SecurityPolicy None (`--opcua-allow-none`, loopback), anonymous.
#[test]
fn an_asyncua_client_browses_reads_subscribes_and_writes() {
    if !asyncua() {
        return;
    }
    let dir = scratch("opcua-open");
    let pki = dir.join("pki");
    let mut run = open_run(&carwash(), &pki, &["--monitor", "127.0.0.1:0"]);
    let url = opcua_url(&mut run);
    // A variable forced from the monitor reads its forced value over OPC UA.
    let mon = run.monitor();
    let mut ws = Ws::connect(&format!("ws://{mon}/?token=t0k3n"));
    let f = ws.cmd(1, serde_json::json!({"cmd": "force", "name": "DryerSelect", "value": true}));
    assert_eq!(f["ok"], true, "{f}");
    let r = client("open", &url, &[]);
    assert_eq!(r["browse"]["variables"]["DryerSelect"]["value"], true, "the forced value");
    let vars = &r["browse"]["variables"];
    assert_eq!(vars.as_object().unwrap().len(), VARIABLES.len(), "{vars}");
    for (name, section, ty, at) in VARIABLES {
        let v = &vars[name];
        assert_eq!(v["section"], *section, "{name}: {v}");
        assert_eq!(v["type"], *ty, "{name}: {v}");
        assert_eq!(v["address"].as_str(), *at, "{name}: {v}");
        assert_eq!(v["writable"], *section != "Outputs", "{name}: {v}");
    }
    // Declared values, as the chart holds them (TIME as a Duration in ms).
    assert_eq!(vars["MaxTravelTime"]["value"], 60000.0);
    assert_eq!(vars["BlowerSpinUp"]["value"], 3000.0);
    assert_eq!(vars["Washes"]["value"], 0);
    let steps = &r["browse"]["steps"];
    assert_eq!(steps.as_object().unwrap().len(), STEPS.len(), "{steps}");
    for st in STEPS {
        assert_eq!(steps[st]["X"], *st == "Idle", "{st}: {steps}");
    }
    assert!(steps["Idle"]["T"].as_f64().unwrap() >= 0.0);
    // TStart leaves the active Idle: its guard is evaluated (false, nothing pressed); the
    // guards of transitions from inactive steps are not (GoodNoData).
    assert_eq!(r["browse"]["transitions"]["TStart"]["guard"], false, "{}", r["browse"]["transitions"]);
    assert_eq!(r["browse"]["transitions"]["TCarAtBrush"]["status"], "GoodNoData");
    assert_eq!(r["browse"]["runtime"]["State"], "RUN");
    assert!(r["browse"]["runtime"]["ScanCount"].as_u64().unwrap() > 0);
    // Writes: inputs accepted (a wrong type refused), the output refused.
    let w = &r["writes"];
    assert_eq!((w["CarPresent"].as_str(), w["AtHome"].as_str()), (Some("Good"), Some("Good")), "{w}");
    assert_eq!(w["StartButton as Int16"], "BadTypeMismatch", "{w}");
    assert_eq!(w["StartButton"], "Good", "{w}");
    assert_eq!(w["SprayValve"], "BadNotWritable", "{w}");
    // The subscription saw Spraying.X go from FALSE to TRUE after the write of Start.
    assert_eq!(r["spraying_changes"], serde_json::json!([false, true]), "{r}");
    assert_eq!(r["StartButton"], true);
    // The chart's own type, its steps' and actions' (CarWash's chart is the program's own).
    assert_eq!(r["browse"]["types"], serde_json::json!({"Chart": "SfcType", "step": "SfcStepType"}), "{r}");
    let actions = r["browse"]["actions"].as_object().unwrap();
    for a in ["SprayValve", "Travel", "Brush", "TravelBack", "Blower", "FaultLamp", "CountWash"] {
        assert_eq!(actions[a]["type"], "SfcActionType", "{a}: {r}");
    }
    // In Spraying: SprayValve (N) and Travel (N) have Q and A; Brush and FaultLamp neither.
    assert_eq!(
        r["actions_in_spraying"],
        serde_json::json!({"SprayValve": [true, true], "Travel": [true, true], "Brush": [false, false],
            "FaultLamp": [false, false]}),
        "{r}"
    );
    // Idle, left, keeps the duration of its last activation (IEC 61131-3), not 0.
    let idle = &r["idle_left"];
    assert_eq!(idle["X"], false, "{r}");
    assert!(idle["T"].as_f64().unwrap() > 0.0, "{r}");
    assert_eq!(idle["T"], idle["T later"], "{r}");
    assert_eq!(r["SprayValve"], true, "the chart drives the spray valve in Spraying");
    // Halt needs an authenticated user.
    assert_eq!(r["anonymous_halt"], "BadUserAccessDenied", "{r}");
    drop(run);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Basic256Sha256 SignAndEncrypt and Sign with a user from `[[opcua.user]]` (hash made by
/// `sfc run --hash-password`): an untrusted client certificate is refused and filed under
/// `rejected/`; trusted, the user halts and continues the run; a wrong password is refused.
#[test]
fn a_secure_session_with_a_user_and_an_untrusted_certificate() {
    if !asyncua() {
        return;
    }
    let dir = scratch("opcua-secure");
    let h = hash("op3rator");
    assert!(h.starts_with("$argon2id$"), "{h}");
    assert!(!h.contains("op3rator"));
    let config = dir.join("plant.toml");
    std::fs::write(
        &config,
        format!(
            "chart = \"{}\"\n[retain]\nenabled = false\n[opcua]\nendpoint = \"opc.tcp://127.0.0.1:0\"\npki_dir = \"pki\"\n\
             [[opcua.user]]\nname = \"operator\"\npassword_hash = \"{h}\"\n",
            s(&carwash())
        ),
    )
    .unwrap();
    let mut run = Run::start(&["--config", s(&config), "--for", "T#120s"]);
    let url = opcua_url(&mut run);
    // An entry without `role` keeps what users could do before roles existed, and says so.
    run.line("the role warning", 10, |l| {
        l.ends_with("[[opcua.user]] `operator` has no `role`: admin (writes inputs, calls Halt, Continue and Reset), as before roles existed; give role = \"read\", \"operate\" or \"admin\"")
    });
    let pki = dir.join("pki");
    assert!(pki.join("own/cert.der").is_file() && pki.join("private/private.pem").is_file());
    let r = client("secure", &url, &[s(&pki), "operator", "op3rator", s(&dir.join("client"))]);
    assert_eq!(r["untrusted"], "BadCertificateUntrusted", "{r}");
    assert_eq!(r["rejected_files"], 1, "{r}");
    assert_eq!(r["state"], "RUN", "{r}");
    assert_eq!(
        (r["halted_after_halt"].as_bool(), r["halted_after_continue"].as_bool()),
        (Some(true), Some(false)),
        "{r}"
    );
    assert_eq!(r["user_write"], "Good", "{r}");
    assert_eq!(r["sign_state"], "RUN", "{r}");
    assert_eq!(r["wrong_password"], "BadUserAccessDenied", "{r}");
    drop(run);
    let _ = std::fs::remove_dir_all(&dir);
}

/// SecurityPolicy None is for loopback only; a server with no way in is refused too.
#[test]
fn security_policy_none_only_on_loopback() {
    let dir = scratch("opcua-refuse");
    let out = command(&[
        "run",
        s(&carwash()),
        "--no-retain",
        "--opcua",
        "opc.tcp://0.0.0.0:0",
        "--opcua-allow-none",
        "--opcua-pki",
        s(&dir.join("pki")),
        "--scans",
        "1",
    ])
    .output()
    .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--opcua-allow-none") && err.contains("loopback"), "{err}");
    let out = command(&["run", s(&carwash()), "--no-retain", "--opcua", "opc.tcp://127.0.0.1:0", "--scans", "1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("no way in"), "{err}");
    let out = command(&["run", "--hash-password"]).stdin(Stdio::null()).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "an empty password is refused");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The start jitter p99 of one `sfc run` of `secs` seconds, with `clients` asyncua sessions
/// subscribed to every variable and step at 100 ms.
fn jitter_p99(dir: &Path, clients: usize, secs: u64, realtime: bool) -> (u64, serde_json::Value) {
    let pki = dir.join("pki");
    let d = format!("T#{secs}s");
    let chart = carwash();
    let mut extra = vec!["--for", d.as_str()];
    if realtime {
        extra.push("--realtime");
    }
    let mut run = open_run(&chart, &pki, &extra);
    let url = opcua_url(&mut run);
    let load = if clients > 0 {
        client("load", &url, &[&clients.to_string(), &(secs.saturating_sub(2)).to_string()])
    } else {
        serde_json::Value::Null
    };
    let (_, lines) = run.finish(secs + 60);
    let summary = lines.iter().find(|l| l.contains("start jitter p50")).expect("the summary line").clone();
    let p99 = summary.split("p99 ").nth(1).and_then(|t| t.split(' ').next()).and_then(|n| n.parse().ok()).unwrap();
    (p99, load)
}

/// The load test: 20 clients × every variable at 100 ms over 60 s with SFC_OPCUA_LOAD=1 (at
/// normal and at real-time priority); in CI a bounded portion (4 clients, 6 s, normal
/// priority). Prints the jitter p99 with and without clients.
#[test]
fn load_prints_the_jitter_with_and_without_clients() {
    if !asyncua() {
        return;
    }
    let full = std::env::var_os("SFC_OPCUA_LOAD").is_some();
    let (clients, secs) = if full { (20, 60) } else { (4, 6) };
    let dir = scratch("opcua-load");
    let priorities: &[bool] = if full { &[false, true] } else { &[false] };
    // Without and with clients in turn, twice in the full run: the machine's other load moves
    // between runs, and alternating shows how much.
    let rounds = if full { 2 } else { 1 };
    for &realtime in priorities {
        for round in 1..=rounds {
            let (quiet, _) = jitter_p99(&dir, 0, secs, realtime);
            let (loaded, load) = jitter_p99(&dir, clients, secs, realtime);
            eprintln!(
                "OPC UA load ({} priority, round {round}): {clients} clients × all variables at 100 ms for {secs} s: \
                 {} notifications; start jitter p99 {loaded} µs with clients, {quiet} µs without (ratio {:.2})",
                if realtime { "real-time" } else { "normal" },
                load["notifications"],
                loaded as f64 / quiet.max(1) as f64
            );
            assert_eq!(load["clients"], clients as u64, "{load}");
            assert!(load["notifications"].as_u64().unwrap() > 0, "{load}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The spindle reversal (examples/spindle): the mechanism `Rev` is a chart of its own under
/// `Chart`, typed (`SfcType`, `SfcStepType`, …); its actions show Q and A; a step left keeps
/// its T; error 4.05 (KM2's contact never comes) gives the error record on OPC UA —
/// `LastError`, `LastErrorCode`, `LastErrorStep`, `ErrorCount` — as the monitor's `mechanisms`
/// tells it.
#[test]
fn the_spindle_mechanism_its_actions_and_its_error_record() {
    if !asyncua() {
        return;
    }
    let dir = scratch("opcua-spindle");
    let chart = root().join("examples/spindle/spindle.st");
    let mut run = open_run(&chart, &dir.join("pki"), &["--period", "T#10ms", "--monitor", "127.0.0.1:0"]);
    let url = opcua_url(&mut run);
    let script = root().join("crates/sfc-cli/tests/opcua/spindle_client.py");
    let out = std::process::Command::new("python3").arg(script).arg(&url).output().expect("python3 runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "the asyncua client failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    let r: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap_or("")).unwrap();
    // The layout: Main (no chart of its own) has a Chart folder with the mechanism Rev.
    assert_eq!(
        r["types"],
        serde_json::json!({"Main": "SfcProgramType", "Chart": "FolderType", "Rev": "SfcType",
            "Steps": "SfcStepType", "Transitions": "SfcTransitionType", "Actions": "SfcActionType"}),
        "{r}"
    );
    assert_eq!(r["chart"], serde_json::json!(["Rev"]), "{r}");
    assert_eq!(r["function_block"], "SpindleReversal");
    assert_eq!(
        r["sfc_type_members"],
        serde_json::json!([
            "Actions",
            "ErrorCount",
            "LastError",
            "LastErrorCode",
            "LastErrorStep",
            "Steps",
            "Transitions"
        ]),
        "{r}"
    );
    assert_eq!(r["sfc_type_supertype"], serde_json::json!(["BaseObjectType"]), "{r}");
    assert_eq!(
        r["Steps"],
        serde_json::json!(["CloseKM2", "Err404", "Err405", "Finished", "Idle", "OpenKM1", "Settle"]),
        "{r}"
    );
    assert_eq!(r["Transitions"].as_array().map(Vec::len), Some(9), "{r}");
    assert_eq!(
        r["Actions"],
        serde_json::json!(["Busy", "Done", "EngageKM2", "Fault", "ReleaseKM1", "SetError404", "SetError405"]),
        "{r}"
    );
    // Before any error: empty record, count 0; a step never active has T = 0.
    assert_eq!(
        r["before"],
        serde_json::json!({"LastError": "", "LastErrorCode": 0, "LastErrorStep": "", "ErrorCount": 0}),
        "{r}"
    );
    assert_eq!(r["never_active_T"], 0.0);
    // In OpenKM1: Busy (N) has Q and A; Done and Fault neither.
    assert_eq!(
        r["actions_in_OpenKM1"],
        serde_json::json!({"Busy": [true, true], "Done": [false, false], "Fault": [false, false]}),
        "{r}"
    );
    // OpenKM1 left: X FALSE, T the duration of its activation (≥ the 300 ms the client waited),
    // not moving.
    let left = &r["OpenKM1_left"];
    assert_eq!(left["X"], false, "{r}");
    assert!(left["T"].as_f64().unwrap() >= 300.0, "{r}");
    assert_eq!(left["T"], left["T later"], "a step left keeps its T: {r}");
    // Error 4.05: the record with the condition, its terminal and value.
    let after = &r["after"];
    let text = after["LastError"].as_str().unwrap();
    assert!(text.starts_with("Rev: error 405 in step Rev.CloseKM2 after T#1s"), "{text}");
    assert!(
        text.ends_with(
            "(supervision time T#1s); waiting for Rev.TKM2Closed: KM2Fb (X12.3, %IX0.5) is FALSE; needs TRUE"
        ),
        "{text}"
    );
    assert_eq!((after["LastErrorCode"].as_i64(), after["LastErrorStep"].as_str()), (Some(405), Some("Rev.CloseKM2")));
    assert_eq!(after["ErrorCount"], 1, "{r}");
    assert_eq!(r["fault_action"], serde_json::json!([true, true]), "Fault (N) in Err405: {r}");
    // The monitor's `mechanisms` and the run log tell the same record.
    let mon = run.monitor();
    let mut ws = Ws::connect(&format!("ws://{mon}/?token=t0k3n"));
    let m = ws.cmd(1, serde_json::json!({"cmd": "mechanisms"}));
    let rev = &m["result"]["mechanisms"][0];
    assert_eq!(rev["lastError"]["message"].as_str(), Some(text), "{m}");
    assert_eq!(rev["errors"], 1, "{m}");
    let logged = run.line("the error record in the log", 20, |l| l.contains("error record: Rev: error 405"));
    assert!(logged.ends_with(text), "{logged}");
    drop(ws);
    drop(run);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30, item 1: Modbus, OPC UA (a read, and a subscription open through the whole run),
/// the monitor's snapshot and `--report` show the same outputs at the same scan, in RUN
/// (halted), STOP and FAULT: the chart's values in RUN, the safe values in STOP and FAULT — not
/// the values the chart last wrote (which OPC UA showed in FAULT before).
#[test]
fn every_view_shows_the_same_outputs_in_run_stop_and_fault() {
    if !asyncua() || !common::pymodbus() {
        return;
    }
    use std::io::BufRead;
    let dir = scratch("opcua-views");
    let mut run = open_run(
        &common::chart("runaway.st"),
        &dir.join("pki"),
        &[
            "--halted",
            "--watchdog",
            "T#50ms",
            "--modbus",
            "127.0.0.1:0",
            "--monitor",
            "127.0.0.1:0",
            "--report",
            "T#50ms",
            "--report-format",
            "json",
        ],
    );
    let url = opcua_url(&mut run);
    let mb = run.modbus();
    let mon = run.monitor();
    let mut ws = Ws::connect(&format!("ws://{mon}/?token=t0k3n"));
    // Three scans: Ready's action Prime writes the outputs.
    for id in 1..=3 {
        assert_eq!(ws.cmd(id, serde_json::json!({"cmd": "step"}))["ok"], true);
    }
    let mut client = std::process::Command::new("python3")
        .arg(root().join("crates/sfc-cli/tests/opcua/views_client.py"))
        .arg(&url)
        .arg(mb.port().to_string())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("python3 runs");
    let mut to_client = client.stdin.take().unwrap();
    let mut from_client = std::io::BufReader::new(client.stdout.take().unwrap());
    let mut snap = |state: &str| -> serde_json::Value {
        writeln!(to_client, "snap {state}").unwrap();
        let mut line = String::new();
        from_client.read_line(&mut line).unwrap();
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line:?}"))
    };
    let chart_values = serde_json::json!({"Pump": true, "Vent": false, "Pressure": 3.25, "Batch": 70000});
    let safe_values = serde_json::json!({"Pump": false, "Vent": true, "Pressure": 1.5, "Batch": 0});
    let mut check = |run: &mut Run, ws: &mut Ws, id: u64, state: &str, want: &serde_json::Value, code: u64| {
        let v = snap(state);
        assert_eq!(v["settled"], true, "{state}: the views did not agree within 10 s: {v}");
        let scan = v["status"]["scan"].as_u64().unwrap();
        for (name, value) in want.as_object().unwrap() {
            assert_eq!(&v["opcua_read"][name], value, "{state}: OPC UA read of {name}: {v}");
            assert_eq!(&v["opcua_subscription"][name], value, "{state}: OPC UA subscription of {name}: {v}");
            assert_eq!(&v["modbus"][name], value, "{state}: Modbus {name}: {v}");
        }
        assert_eq!(v["opcua_read"]["ScanCount"], scan, "{state}: OPC UA's scan is the status block's: {v}");
        // Nothing scans: halted in RUN (the debugger), and in STOP and FAULT, for both.
        assert_eq!((v["opcua_read"]["Halted"].clone(), v["status"]["halted"].clone()), (json!(true), json!(1)), "{v}");
        assert_eq!(v["status"]["state"], code, "{state}: {v}");
        // The monitor's snapshot.
        assert_eq!(ws.cmd(id, serde_json::json!({"cmd": "snapshot"}))["ok"], true);
        let m = ws.until("a snapshot", |m| m["type"] == "snapshot");
        assert_eq!(m["state"], state, "{m}");
        assert_eq!(m["scan"], scan, "the monitor shows the scan Modbus and OPC UA show: {m}");
        for (name, value) in want.as_object().unwrap() {
            assert_eq!(&m["vars"][name], value, "{state}: the monitor's {name}: {m}");
        }
        // `--report` (one JSON line per report).
        let r = run.line(&format!("a --report line in {state} at scan {scan}"), 10, |l| {
            serde_json::from_str::<serde_json::Value>(l)
                .is_ok_and(|j| j["state"] == state && j["scan"] == scan && j["outputs"] == *want)
        });
        eprintln!("{state}: every view shows {want} at scan {scan} (status block {}; report {r})", v["status"]);
    };
    check(&mut run, &mut ws, 10, "RUN", &chart_values, 0);
    assert_eq!(ws.cmd(11, serde_json::json!({"cmd": "stop"}))["ok"], true);
    check(&mut run, &mut ws, 12, "STOP", &safe_values, 1);
    assert_eq!(ws.cmd(13, serde_json::json!({"cmd": "start"}))["ok"], true);
    assert_eq!(ws.cmd(14, serde_json::json!({"cmd": "continue"}))["ok"], true);
    // Go: Filling's action runs away, the watchdog stops it.
    common::Modbus::connect(mb).write_coil(32768, true);
    run.line("the watchdog", 20, |l| l.starts_with("watchdog: scan"));
    check(&mut run, &mut ws, 15, "FAULT", &safe_values, 2);
    let mut modbus = common::Modbus::connect(mb);
    let status = modbus.read_input_registers(40300, 8);
    assert_eq!((status[6], status[7]), (1, 1), "the last fault is the watchdog's (1), one fault so far: {status:?}");
    writeln!(to_client, "quit").unwrap();
    let _ = client.wait();
    drop(run);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `sfc run --hash-password` of `password`.
fn hash(password: &str) -> String {
    let mut child = command(&["run", "--hash-password"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(format!("{password}\n").as_bytes()).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap().trim().to_string()
}

/// Issue 30, item 3: anonymous access is decided per endpoint (`allow_none` opens the None
/// endpoint only; `anonymous_read` the secure ones, to read), user names only on the secure
/// endpoints (a password could travel in clear over None), and each user has a role:
/// `read` reads, `operate` also writes inputs, `admin` also calls Halt, Continue and Reset —
/// enforced on every write and method, and shown in UserAccessLevel.
#[test]
fn anonymous_access_per_endpoint_and_roles_per_user() {
    if !asyncua() {
        return;
    }
    let dir = scratch("opcua-roles");
    let users: String = [("reader", "read"), ("operator", "operate"), ("boss", "admin")]
        .iter()
        .map(|(name, role)| {
            format!(
                "[[opcua.user]]\nname = \"{name}\"\npassword_hash = \"{}\"\nrole = \"{role}\"\n",
                hash(&format!("pw-{name}"))
            )
        })
        .collect();
    for anonymous_read in [false, true] {
        let config = dir.join(format!("plant-{anonymous_read}.toml"));
        let pki = dir.join(format!("pki-{anonymous_read}"));
        std::fs::write(
            &config,
            format!(
                "chart = \"{}\"\n[retain]\nenabled = false\n[opcua]\nendpoint = \"opc.tcp://127.0.0.1:0\"\npki_dir = \"{}\"\n\
                 allow_none = true\nanonymous_read = {anonymous_read}\n{users}",
                s(&carwash()),
                s(&pki)
            ),
        )
        .unwrap();
        let mut run = Run::start(&["--config", s(&config), "--for", "T#120s"]);
        let url = opcua_url(&mut run);
        let r = client("roles", &url, &[s(&pki), s(&dir.join(format!("client-{anonymous_read}")))]);
        eprintln!("anonymous_read = {anonymous_read}: {r:#}");
        let may = |who: &str, write: &str, writable: bool, halt: &str| {
            let s = &r[who];
            assert_eq!(s["read"], "RUN", "{who} reads: {r:#}");
            assert_eq!(s["write"], write, "{who} writes: {r:#}");
            assert_eq!(s["user_writable"], writable, "{who}'s UserAccessLevel: {r:#}");
            assert_eq!(s["halt"], halt, "{who} calls Halt: {r:#}");
        };
        let denied = "BadUserAccessDenied";
        may("reader secure", denied, false, denied);
        may("operator secure", "Good", true, denied);
        may("boss secure", "Good", true, "Good");
        // User names are refused on the None endpoint: a password could travel in clear there.
        for user in ["reader", "operator", "boss"] {
            assert!(r[format!("{user} none")]["connect"].is_string(), "{user} on the None endpoint: {r:#}");
        }
        // Anonymous on the None endpoint (loopback, --opcua-allow-none) reads and writes, calls
        // nothing; on SignAndEncrypt it gets in only with anonymous_read, and only to read.
        may("anonymous none", "Good", !anonymous_read, denied);
        if anonymous_read {
            may("anonymous secure", denied, false, denied);
        } else {
            assert!(r["anonymous secure"]["connect"].is_string(), "anonymous is refused on SignAndEncrypt: {r:#}");
        }
        drop(run);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30, item 3: the PKI folder is made 0700 and the private key 0600; a folder or key
/// others can read is refused at start with what to do.
#[test]
fn the_pki_folder_and_the_private_key_are_private() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("opcua-pki");
    let pki = dir.join("deep/pki");
    let args = |pki: &Path| -> Vec<String> {
        [s(&carwash()), "--no-retain", "--opcua", "opc.tcp://127.0.0.1:0", "--opcua-allow-none", "--opcua-pki"]
            .iter()
            .map(|a| a.to_string())
            .chain([s(pki).to_string(), "--scans".into(), "3".into()])
            .collect()
    };
    let run = |pki: &Path| {
        let a = args(pki);
        let mut full = vec!["run"];
        full.extend(a.iter().map(String::as_str));
        command(&full).output().unwrap()
    };
    let out = run(&pki);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode(&pki), 0o700);
    assert_eq!(mode(&pki.join("private")), 0o700);
    assert_eq!(mode(&pki.join("private/private.pem")), 0o600);
    // A key others can read (copied with the wrong umask, say): refused, nothing served.
    std::fs::set_permissions(pki.join("private/private.pem"), std::fs::Permissions::from_mode(0o644)).unwrap();
    let out = run(&pki);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("private key") && err.contains("chmod 600"), "{err}");
    std::fs::set_permissions(pki.join("private/private.pem"), std::fs::Permissions::from_mode(0o600)).unwrap();
    // A folder others can read: refused.
    std::fs::set_permissions(&pki, std::fs::Permissions::from_mode(0o755)).unwrap();
    let out = run(&pki);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("can be read by other users") && err.contains("chmod 700"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30, item 2: every node of the address space has the node id docs/runtime.md
/// documents (no `s=s=…`), and reads by it: the car wash (variables with addresses, the
/// program's own chart) and the spindle (a program without a chart of its own, and a function
/// block instance's chart), browsed whole by asyncua.
#[test]
fn every_node_has_its_documented_node_id() {
    if !asyncua() {
        return;
    }
    let dir = scratch("opcua-ids");
    for (chart, pou) in [("examples/carwash/carwash.st", "CarWash"), ("examples/spindle/spindle.st", "Main")] {
        let mut run = open_run(&root().join(chart), &dir.join("pki"), &[]);
        let url = opcua_url(&mut run);
        let out = std::process::Command::new("python3")
            .arg(root().join("crates/sfc-cli/tests/opcua/node_ids_client.py"))
            .arg(&url)
            .arg(pou)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
        let r: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap_or("")).unwrap();
        eprintln!("{chart}: {} nodes checked ({} types)", r["checked"], r["types"]);
        assert_eq!(r["wrong_count"], 0, "{chart}: node ids not as documented: {r:#}");
        assert_eq!(r["unread_count"], 0, "{chart}: nodes that do not read by their documented id: {r:#}");
        assert!(r["checked"].as_u64().unwrap() > 100, "{r}");
        assert_eq!(r["types"], 5, "{r}");
        drop(run);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30, item 5: an OPC UA subscriber sees a change within one publishing interval of the
/// scan that made it, with publishing intervals down to 10 ms granted (`--opcua-min-publish`,
/// default T#10ms). The lamp of `echo.st` follows its button in the next scan (period 1 ms);
/// the figure is the time from the Modbus write of the button to the notification of the lamp,
/// printed, not asserted (the machine is shared).
#[test]
fn a_subscriber_sees_a_change_within_its_publishing_interval() {
    if !asyncua() || !common::pymodbus() {
        return;
    }
    let dir = scratch("opcua-latency");
    let (echo, pki) = (common::chart("echo.st"), dir.join("pki"));
    for (publish, min) in [(10.0f64, None), (50.0, None), (10.0, Some("T#20ms"))] {
        let mut extra = vec!["--period", "T#1ms", "--modbus", "127.0.0.1:0"];
        if let Some(m) = min {
            extra.extend(["--opcua-min-publish", m]);
        }
        let mut run = open_run(&echo, &pki, &extra);
        let url = opcua_url(&mut run);
        let mb = run.modbus();
        let r = client_script("latency_client.py", &[&url, &mb.port().to_string(), "40", &publish.to_string()]);
        let granted = r["revised_publishing_ms"].as_f64().unwrap();
        let floor = min.map_or(10.0, |_| 20.0);
        assert_eq!(granted, publish.max(floor), "the publishing interval granted: {r}");
        let l: Vec<f64> = r["latencies_ms"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert_eq!(r["missed"], 0, "every change reached the subscriber: {r}");
        assert_eq!(l.len(), 40, "{r}");
        let q = |p: f64| l[((l.len() - 1) as f64 * p).round() as usize];
        eprintln!(
            "OPC UA latency, Modbus write to notification, publishing {granted} ms (asked {publish}, \
             --opcua-min-publish {}), scan period 1 ms, 40 changes: p50 {:.1} ms, p90 {:.1} ms, max {:.1} ms \
             (one publishing interval + one scan: {:.0} ms)",
            min.unwrap_or("T#10ms (default)"),
            q(0.5),
            q(0.9),
            q(1.0),
            granted + 1.0
        );
        drop(run);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A client script of `tests/opcua/` with its arguments; its JSON report (the last line).
fn client_script(script: &str, args: &[&str]) -> serde_json::Value {
    let out = std::process::Command::new("python3")
        .arg(root().join("crates/sfc-cli/tests/opcua").join(script))
        .args(args)
        .output()
        .expect("python3 runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{script} failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_str(stdout.lines().last().unwrap_or("")).unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

/// The resident memory of process `pid`, KiB.
fn rss_kib(pid: i32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0)
}

/// Issue 30, done: a soak of `sfc run` serving every client kind at once — 8 Modbus pollers and a
/// writer that keeps the car wash washing, 3 asyncua and 2 o6 (open62541) OPC UA sessions
/// subscribed to every variable and step, 3 monitor clients reading every delta and asking for
/// snapshots — thirty seconds in the test command, ten minutes with SFC_SOAK=1. Prints the
/// requests, notifications and errors of each kind and the process's memory over the run;
/// asserts no error and no growth of memory beyond the first third's (allocator noise: 8 MiB).
#[test]
fn soak_with_modbus_both_opcua_stacks_and_monitor_clients() {
    if !asyncua() || !common::pymodbus() || !common::o6() {
        return;
    }
    let secs: u64 = if std::env::var_os("SFC_SOAK").is_some() { 600 } else { 30 };
    let dir = scratch("opcua-soak");
    let mut run = open_run(
        &carwash(),
        &dir.join("pki"),
        &["--modbus", "127.0.0.1:0", "--monitor", "127.0.0.1:0", "--for", &format!("T#{}s", secs + 120)],
    );
    let url = opcua_url(&mut run);
    let mb = run.modbus();
    let mon = run.monitor();
    let pid = run.pid();
    let until = std::time::Instant::now() + std::time::Duration::from_secs(secs);
    // Monitor clients: read everything, ask for a snapshot every second.
    let monitors: Vec<_> = (0..3)
        .map(|k| {
            std::thread::spawn(move || {
                let mut ws = Ws::connect(&format!("ws://{mon}/"));
                ws.0.set_read_timeout(Some(std::time::Duration::from_secs(5))).unwrap();
                let (mut messages, mut snapshots, mut errors) = (0u64, 0u64, Vec::new());
                let mut next_ask = std::time::Instant::now();
                while std::time::Instant::now() < until {
                    if std::time::Instant::now() >= next_ask {
                        ws.send(&serde_json::json!({"id": messages, "cmd": "snapshot"}).to_string());
                        next_ask += std::time::Duration::from_secs(1);
                    }
                    match ws.next() {
                        Some(m) => {
                            messages += 1;
                            if m["type"] == "snapshot" {
                                snapshots += 1;
                            }
                            if m["type"] == "reply" && m["ok"] != true {
                                errors.push(format!("monitor client {k}: {m}"));
                            }
                        }
                        None => {
                            errors.push(format!("monitor client {k}: the connection closed or went silent"));
                            break;
                        }
                    }
                }
                (messages, snapshots, errors)
            })
        })
        .collect();
    // Memory, every two seconds.
    let sampler = std::thread::spawn(move || {
        let mut samples = Vec::new();
        while std::time::Instant::now() < until {
            samples.push(rss_kib(pid));
            std::thread::sleep(std::time::Duration::from_secs(2));
        }
        samples
    });
    let r = client_script("soak_client.py", &[&url, &mb.port().to_string(), &secs.to_string()]);
    let samples = sampler.join().unwrap();
    let mut monitor_errors = Vec::new();
    let (mut messages, mut snapshots) = (0, 0);
    for m in monitors {
        let (n, sn, e) = m.join().unwrap();
        messages += n;
        snapshots += sn;
        monitor_errors.extend(e);
    }
    let third = samples.len() / 3;
    let early = samples[..third.max(1)].iter().copied().max().unwrap_or(0);
    let late = samples[samples.len().saturating_sub(third.max(1))..].iter().copied().max().unwrap_or(0);
    eprintln!(
        "soak of {secs} s: Modbus {} requests, {} errors; asyncua {} sessions, {} notifications, {} errors; \
         o6 {} sessions, {} notifications, {} errors, {} restarts; monitor 3 clients, {messages} messages \
         ({snapshots} snapshots), {} errors; memory (RSS) {} KiB at the start, {early} KiB max in the first third, \
         {late} KiB max in the last third, {} KiB at the end",
        r["modbus"]["requests"],
        r["modbus"]["errors"],
        r["asyncua"]["sessions"],
        r["asyncua"]["notifications"],
        r["asyncua"]["errors"],
        r["o6"]["sessions"],
        r["o6"]["notifications"],
        r["o6"]["errors"],
        r["o6"]["restarts"],
        monitor_errors.len(),
        samples.first().copied().unwrap_or(0),
        samples.last().copied().unwrap_or(0),
    );
    assert_eq!(r["modbus"]["errors"], 0, "{r:#}");
    assert_eq!(r["asyncua"]["errors"], 0, "{r:#}");
    assert_eq!(r["o6"]["errors"], 0, "{r:#}");
    assert!(monitor_errors.is_empty(), "{monitor_errors:#?}");
    assert!(r["modbus"]["requests"].as_u64().unwrap() > 100 * secs, "{r:#}");
    assert!(r["asyncua"]["notifications"].as_u64().unwrap() > 0 && r["o6"]["notifications"].as_u64().unwrap() > 0);
    assert!(snapshots >= secs, "the monitor clients were answered: {snapshots} snapshots in {secs} s");
    assert!(late <= early + 8 * 1024, "memory grew: {early} KiB → {late} KiB ({samples:?})");
    run.signal(libc::SIGTERM);
    let (code, lines) = run.finish(60);
    assert_eq!(code, Some(0), "{lines:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30, item 4: a second, independent OPC UA stack — o6, a Python client on open62541 —
/// over the None endpoint (which open62541 refused before the server's nonce had 32 bytes):
/// browse, read, a subscription that sees Spraying.X go TRUE after the inputs written start
/// the wash, an output refused, Halt refused to an anonymous session.
#[test]
fn an_open62541_client_browses_reads_subscribes_and_writes() {
    if !common::o6() {
        return;
    }
    let dir = scratch("opcua-o6");
    let mut run = open_run(&carwash(), &dir.join("pki"), &[]);
    let url = opcua_url(&mut run);
    let r = client_script("o6_client.py", &["open", &url]);
    assert_eq!(r["client"], "o6");
    let browse = &r["browse"];
    let names = |k: &str| {
        let mut v: Vec<String> =
            browse[k].as_array().unwrap().iter().map(|x| x.as_str().unwrap().to_string()).collect();
        v.sort();
        v
    };
    assert_eq!(names("CarWash"), ["Chart", "Inputs", "Locals", "Outputs", "Runtime"], "{r:#}");
    assert_eq!(names("Steps"), ["Brushing", "Drying", "Fault", "Idle", "Returning", "Spraying"], "{r:#}");
    assert_eq!(names("Inputs").len(), 7, "{r:#}");
    assert_eq!(r["state"], "RUN", "{r:#}");
    assert_eq!(
        r["writes"],
        serde_json::json!({"CarPresent": "Good", "AtHome": "Good", "StartButton": "Good", "SprayValve": "BadNotWritable"}),
        "{r:#}"
    );
    assert_eq!(r["spraying_changes"], serde_json::json!([false, true]), "{r:#}");
    assert_eq!(r["SprayValve"], true, "{r:#}");
    assert_eq!(r["anonymous_halt"], "BadUserAccessDenied", "{r:#}");
    drop(run);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30, items 3 and 4: o6 as a user of role admin over Basic256Sha256 SignAndEncrypt with
/// its own certificate (untrusted first, then trusted by the operator's move): Halt, Continue, a
/// write; a wrong password refused; a user name over the None endpoint refused (a password could
/// travel in clear there), and none offered.
#[test]
fn an_open62541_client_as_a_user_over_sign_and_encrypt() {
    if !common::o6() {
        return;
    }
    let dir = scratch("opcua-o6-user");
    let pki = dir.join("pki");
    let config = dir.join("plant.toml");
    std::fs::write(
        &config,
        format!(
            "chart = \"{}\"\n[retain]\nenabled = false\n[opcua]\nendpoint = \"opc.tcp://127.0.0.1:0\"\npki_dir = \"{}\"\n\
             allow_none = true\n[[opcua.user]]\nname = \"boss\"\npassword_hash = \"{}\"\nrole = \"admin\"\n",
            s(&carwash()),
            s(&pki),
            hash("pw-boss")
        ),
    )
    .unwrap();
    let mut run = Run::start(&["--config", s(&config), "--for", "T#120s"]);
    let url = opcua_url(&mut run);
    let r = client_script("o6_client.py", &["user", &url, "boss", "pw-boss", s(&pki), s(&dir.join("client"))]);
    assert_eq!(r["none_user_tokens"], serde_json::json!([]), "no user name offered on None: {r:#}");
    assert_eq!(r["none_login"], "BadIdentityTokenRejected", "{r:#}");
    assert_eq!((r["untrusted"].as_str(), r["rejected_files"].as_u64()), (Some("BadCertificateUntrusted"), Some(1)));
    assert_eq!((r["login"].as_str(), r["state"].as_str()), (Some("Good"), Some("RUN")), "{r:#}");
    assert_eq!((r["halt"].as_str(), r["halted_after_halt"].as_bool()), (Some("Good"), Some(true)), "{r:#}");
    assert_eq!((r["continue"].as_str(), r["halted_after_continue"].as_bool()), (Some("Good"), Some(false)), "{r:#}");
    assert_eq!(r["user_write"], "Good", "{r:#}");
    assert_eq!(r["wrong_password"], "BadUserAccessDenied", "{r:#}");
    drop(run);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Charts inside charts two levels deep (crates/sfc-cli/tests/nested/machine.st): the lift (an
/// SFC function block instance), the chart of its action ACT_Load and the chart of its gripper's
/// action ACT_Grip are each a node of Main's `Chart` (SfcType, named by path) with its steps, and
/// their X follow the run.
#[test]
fn nested_charts_are_nodes_with_their_steps() {
    if !asyncua() {
        return;
    }
    let dir = scratch("opcua-nested");
    let chart = root().join("crates/sfc-cli/tests/nested/machine.st");
    let mut run = open_run(&chart, &dir.join("pki"), &["--period", "T#10ms"]);
    let url = opcua_url(&mut run);
    let script = root().join("crates/sfc-cli/tests/opcua/nested_client.py");
    let out = std::process::Command::new("python3").arg(script).arg(&url).output().expect("python3 runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "the asyncua client failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    let r: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap_or("")).unwrap();
    assert_eq!(
        r["chart"],
        serde_json::json!([
            "Actions",
            "ErrorCount",
            "LastError",
            "LastErrorCode",
            "LastErrorStep",
            "Lift",
            "Lift.ACT_Load",
            "Lift.Grip.ACT_Grip",
            "Steps",
            "Transitions"
        ]),
        "{r}"
    );
    assert_eq!(
        r["steps"],
        serde_json::json!({
            "Main": ["Finished", "Idle", "Lifting", "Loading"],
            "Lift": ["Home", "Raise", "Top"],
            "Lift.ACT_Load": ["Done", "Gripping", "Waiting"],
            "Lift.Grip.ACT_Grip": ["Closing", "Holding", "Open"]
        }),
        "{r}"
    );
    assert_eq!(
        r["types"],
        serde_json::json!({"Lift": "SfcType", "Lift.ACT_Load": "SfcType", "Lift.Grip.ACT_Grip": "SfcType"}),
        "{r}"
    );
    assert_eq!(r["node_ids"]["Lift.Grip.ACT_Grip"], "Main/Chart/Lift.Grip.ACT_Grip", "{r}");
    assert_eq!(r["holding_x_id"], "Main/Steps/Lift.Grip.ACT_Grip.Holding/X", "{r}");
    assert_eq!(
        r["active"],
        serde_json::json!({"Lift.Raise": true, "Lift.Home": false, "Lift.ACT_Load.Done": true,
            "Lift.Grip.ACT_Grip.Holding": true, "Lift.Grip.ACT_Grip.Open": false}),
        "{r}"
    );
    drop(run);
    let _ = std::fs::remove_dir_all(&dir);
}
