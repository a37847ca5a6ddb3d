//! `sfc run` attacked as a plant would be: the real binary, with a runaway loop under the
//! watchdog, SIGTERM, kill -9 during retain writes, file descriptors exhausted, every Modbus
//! exception case, foreign web pages, wrong tokens, a run configuration, warm and cold starts.
//! Timings are printed, never asserted tightly (the machine is shared).

mod common;

use common::{chart, command, eventually, handshake, root, scratch, Modbus, Run, Ws};
use serde_json::json;
use std::path::Path;
use std::time::{Duration, Instant};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The retain file's JSON, checked against its CRC-32 the way zlib computes it (an independent
/// implementation of the check `sfc run` makes).
fn read_retain(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (body, tail) = text.split_once("\ncrc32 ").unwrap_or_else(|| panic!("no checksum line in {text:?}"));
    let want = u32::from_str_radix(tail.trim_end(), 16).expect("a hexadecimal checksum");
    let mut table = [0u32; 256];
    for (n, t) in table.iter_mut().enumerate() {
        let mut c = n as u32;
        for _ in 0..8 {
            c = if c & 1 == 1 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
        }
        *t = c;
    }
    let crc = !body.bytes().fold(!0u32, |c, b| table[((c ^ u32::from(b)) & 0xFF) as usize] ^ (c >> 8));
    assert_eq!(crc, want, "a damaged retain file: {text:?}");
    serde_json::from_str(body).expect("JSON")
}

fn retained(file: &serde_json::Value, name: &str) -> serde_json::Value {
    file["values"]
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v["name"] == name)
        .map(|v| v["value"].clone())
        .unwrap_or_default()
}

/// The runaway nested loop of `tests/run/runaway.st` under `--watchdog T#50ms`: the scan is
/// stopped near its deadline, Modbus reads the safe values, the monitor reports FAULT with the
/// step, the action and the line; a warm `reset` runs it again, and SIGTERM ends it with 0.
#[test]
fn the_watchdog_stops_a_runaway_loop_and_the_outputs_go_to_their_safe_values() {
    let dir = scratch("watchdog");
    let retain = dir.join("filler.retain");
    let mut run = Run::start(&[
        s(&chart("runaway.st")),
        "--watchdog",
        "T#50ms",
        "--modbus",
        "127.0.0.1:0",
        "--monitor",
        "127.0.0.1:0",
        "--retain",
        s(&retain),
        "--for",
        "T#120s",
    ]);
    let (mb, mon) = (run.modbus(), run.monitor());
    let mut m = Modbus::connect(mb);
    eventually("the first scans", 20, || m.read_coils(0, 2) == [true, false]);
    // Pressure 3.25 (REAL, high word first) and Batch 70000 (UDINT) on two registers each.
    assert_eq!(m.read_holding(2, 4), [0x4050, 0x0000, 0x0001, 0x1170]);
    let mut ws = Ws::connect(&format!("ws://{mon}/?token=t0k3n"));
    let hello = ws.until("hello", |m| m["type"] == "hello");
    assert_eq!((hello["state"].as_str(), hello["authorized"].as_bool()), (Some("RUN"), Some(true)));
    let vars = hello["variables"].as_array().unwrap();
    let safe_of = |n: &str| vars.iter().find(|v| v["name"] == n).map(|v| v["safe"].clone());
    assert_eq!(
        (safe_of("Pump"), safe_of("Vent"), safe_of("Pressure")),
        (Some(json!(false)), Some(json!(true)), Some(json!(1.5)))
    );

    m.write_coil(32768, true); // Go: Filling starts its endless loop.
    let line = run.line("the watchdog's line", 60, |l| l.starts_with("watchdog:"));
    let past: f64 = line
        .split(" ms past its deadline")
        .next()
        .and_then(|h| h.rsplit('(').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("how late in `{line}`"));
    println!("the watchdog stopped the scan {past} ms after its deadline: {line}");
    assert!(past < 1000.0, "{line}");
    let for_j =
        std::fs::read_to_string(chart("runaway.st")).unwrap().lines().position(|l| l.contains("FOR j")).unwrap() + 1;
    assert!(
        line.contains("in action Fill of step Filling") && line.contains(&format!("line {for_j} column")),
        "{line}"
    );

    // Modbus reads the safe values: Pump FALSE, Vent TRUE, Pressure 1.5, Batch 0.
    assert_eq!(m.read_coils(0, 2), [false, true]);
    assert_eq!(m.read_holding(2, 4), [0x3FC0, 0x0000, 0x0000, 0x0000]);
    // The monitor reports FAULT with the step that was running.
    let st = ws.until("FAULT with its place", |m| m["type"] == "state" && m["fault"]["step"].is_string());
    assert_eq!(st["state"], "FAULT");
    let f = &st["fault"];
    assert_eq!(
        (f["kind"].as_str(), f["step"].as_str(), f["action"].as_str()),
        (Some("watchdog"), Some("Filling"), Some("Fill"))
    );
    assert_eq!(f["line"], for_j);
    assert_eq!((st["outputs"]["Pump"].clone(), st["outputs"]["Vent"].clone()), (json!(false), json!(true)));
    let mut other = Ws::connect(&format!("ws://{mon}/"));
    let h = other.until("hello", |m| m["type"] == "hello");
    assert_eq!((h["state"].as_str(), h["fault"]["step"].as_str()), (Some("FAULT"), Some("Filling")));
    let snap = other.until("snapshot", |m| m["type"] == "snapshot");
    assert_eq!((snap["state"].as_str(), snap["vars"]["Pump"].clone()), (Some("FAULT"), json!(false)));
    // Watching is not enough to reset.
    let r = other.cmd(1, json!({"cmd": "reset"}));
    assert_eq!(r["error"], "`reset` needs the run's token");

    // A warm reset with the token: RUN again, from the initial step.
    m.write_coil(32768, false);
    let r = ws.cmd(2, json!({"cmd": "reset", "mode": "warm"}));
    assert_eq!((r["ok"].as_bool(), r["result"]["state"].as_str()), (Some(true), Some("RUN")), "{r}");
    ws.until("RUN", |m| m["type"] == "state" && m["state"] == "RUN");
    eventually("Prime runs again", 20, || m.read_coils(0, 2) == [true, false]);
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    assert!(lines.iter().any(|l| l.starts_with("sfc run: warm restart from FAULT")), "{lines:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGTERM in the middle of a wash: an orderly stop, the outputs at their safe values (a
/// watching client sees them), the retain file written, the statistics printed, exit 0.
#[test]
fn sigterm_stops_in_order() {
    let dir = scratch("sigterm");
    let retain = dir.join("carwash.retain");
    let mut run = Run::start(&[
        "examples/carwash/carwash.st",
        "--modbus",
        "127.0.0.1:0",
        "--monitor",
        "127.0.0.1:0",
        "--retain",
        s(&retain),
        "--for",
        "T#120s",
    ]);
    let (mb, mon) = (run.modbus(), run.monitor());
    let mut m = Modbus::connect(mb);
    for b in [4, 5, 6, 0] {
        m.write_coil(32768 + b, true); // CarPresent, AtHome, DryerSelect, then StartButton
    }
    eventually("spraying", 20, || m.read_coils(0, 2) == [true, true]);
    let mut ws = Ws::connect(&format!("ws://{mon}/"));
    ws.until("hello", |m| m["type"] == "hello");
    run.signal(libc::SIGTERM);
    let st = ws.until("STOP", |m| m["type"] == "state");
    assert_eq!(st["state"], "STOP");
    for out in ["SprayValve", "Travel", "Brush", "TravelBack", "Blower", "FaultLamp"] {
        assert_eq!(st["outputs"][out], false, "{out}: {st}");
    }
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    let has = |p: &str| lines.iter().any(|l| l.starts_with(p));
    assert!(has("sfc run: SIGTERM: stopping in order"), "{lines:?}");
    assert!(has("sfc run: STOP: outputs at their safe values (SprayValve=FALSE, Travel=FALSE"), "{lines:?}");
    assert!(lines.iter().any(|l| l.starts_with("sfc run: ") && l.contains(" scans; start jitter p50 ")), "{lines:?}");
    let file = read_retain(&retain);
    assert_eq!((file["pou"].as_str(), retained(&file, "Washes")), (Some("CarWash"), json!(0)));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `kill -9` at random moments while the retain file is written every millisecond: the file
/// is never damaged, the counter in it never goes back, and each run restores exactly the last
/// completed write. 1,000 kills (`SFC_KILL_LOOP=N` changes the number).
#[test]
fn kill_9_during_retain_writes_never_damages_the_file() {
    let dir = scratch("kill9");
    let kills: usize = std::env::var("SFC_KILL_LOOP").ok().and_then(|n| n.parse().ok()).unwrap_or(1000);
    let workers = 3;
    let started = Instant::now();
    let handles: Vec<_> = (0..workers)
        .map(|w| {
            let dir = dir.clone();
            std::thread::spawn(move || {
                let file = dir.join(format!("counter{w}.retain"));
                let mut last_scans = 0u64;
                let mut last_saved: Option<u64> = None;
                let mut rng = 0x9E37_79B9_7F4A_7C15u64 ^ (w as u64 + 1);
                let mut restored = 0;
                for _ in 0..kills / workers + usize::from(w < kills % workers) {
                    let mut run = Run::spawn({
                        let mut c = command(&[
                            "run",
                            s(&chart("counter.st")),
                            "--period",
                            "T#1ms",
                            "--retain",
                            s(&file),
                            "--retain-interval",
                            "T#1ms",
                        ]);
                        c.current_dir(&dir);
                        c
                    });
                    let first = run.line("the retain line", 60, |l| l.starts_with("retain: "));
                    if let Some(saved) = last_saved {
                        // The run restored the last completed write.
                        assert!(first.contains(&format!("(saved after scan {saved})")), "{first}");
                        restored += 1;
                    }
                    rng ^= rng << 13;
                    rng ^= rng >> 7;
                    rng ^= rng << 17;
                    std::thread::sleep(Duration::from_millis(1 + rng % 16));
                    run.signal(libc::SIGKILL);
                    let _ = run.finish(30);
                    if file.exists() {
                        let f = read_retain(&file);
                        let scans = retained(&f, "Scans").as_u64().expect("Scans");
                        assert!(scans >= last_scans, "the counter went back from {last_scans} to {scans}");
                        last_scans = scans;
                        last_saved = f["scan"].as_u64();
                    }
                }
                (last_scans, restored)
            })
        })
        .collect();
    let mut total = 0;
    for h in handles {
        let (scans, restored) = h.join().unwrap();
        assert!(scans > 0 && restored > 0, "the counter advanced over the runs");
        total += restored;
    }
    let took = started.elapsed();
    println!("{kills} runs killed with SIGKILL in {took:?}; {total} restored the last completed write");
    // What killed runs leave is only their temporary file, removed by the next run.
    let left: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert!(left.iter().filter(|n| n.ends_with(".tmp")).count() <= workers, "{left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// CPU time (user + system) of a process so far, in clock ticks.
fn cpu_ticks(pid: i32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = after.split_whitespace().collect();
    f.get(11).and_then(|u| u.parse::<u64>().ok()).unwrap_or(0)
        + f.get(12).and_then(|s| s.parse::<u64>().ok()).unwrap_or(0)
}

/// With `ulimit -n 64`, 100 Modbus and 100 monitor connections exhaust the file descriptors:
/// accepting fails, the servers back off (no core spinning), and once the connections are
/// closed a new client of each is served.
#[cfg(target_os = "linux")]
#[test]
fn exhausted_file_descriptors_do_not_silence_the_servers() {
    let mut cmd = std::process::Command::new("sh");
    cmd.args([
        "-c",
        "ulimit -n 64 && exec \"$0\" run \"$@\"",
        env!("CARGO_BIN_EXE_sfc"),
        s(&chart("io.st")),
        "--modbus",
        "127.0.0.1:0",
        "--monitor",
        "127.0.0.1:0",
        "--modbus-max-clients",
        "1000",
        "--no-retain",
        "--for",
        "T#120s",
    ])
    .env("SFC_TOKEN", "t0k3n")
    .current_dir(root());
    let mut run = Run::spawn(cmd);
    let (mb, mon) = (run.modbus(), run.monitor());
    for (what, addr) in [("Modbus", mb), ("monitor", mon)] {
        let held: Vec<std::net::TcpStream> = (0..100).filter_map(|_| std::net::TcpStream::connect(addr).ok()).collect();
        assert!(held.len() >= 90, "{what}: the kernel queues connections: {}", held.len());
        let prefix = format!("{}: accepting a connection failed", if what == "Modbus" { "Modbus" } else { "monitor" });
        let told = run.line("the failed accept", 30, |l| l.starts_with(&prefix));
        assert!(told.contains("Too many open files") && told.ends_with("retrying with back-off"), "{told}");
        let before = cpu_ticks(run.pid());
        std::thread::sleep(Duration::from_secs(1));
        let spent = cpu_ticks(run.pid()) - before;
        println!("{what}: file descriptors exhausted; the process used {spent} clock ticks of CPU in 1 s ({told})");
        drop(held);
        match what {
            "Modbus" => {
                let mut fresh = None;
                eventually("a new Modbus client is served", 30, || {
                    fresh = std::net::TcpStream::connect(mb).ok().inspect(|s| {
                        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
                    });
                    fresh.is_some()
                });
                let mut m = Modbus::connect(mb);
                assert_eq!(m.read_holding(1000, 1), [100], "the new client is answered");
            }
            _ => {
                let mut ws = Ws::connect(&format!("ws://{mon}/"));
                assert_eq!(ws.until("hello", |m| m["type"] == "hello")["pou"], "Io");
            }
        }
    }
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    let modbus = lines.iter().find(|l| l.starts_with("sfc run: Modbus: ")).unwrap();
    // Backing off, a second of exhaustion costs a handful of failed accepts, not thousands.
    let failed: u64 = modbus.split(" failed accepts").next().unwrap().rsplit(' ').next().unwrap().parse().unwrap();
    println!("{modbus}");
    assert!((1..1000).contains(&failed), "{modbus}");
}

/// A request PDU from its parts.
fn pdu(fc: u8, words: &[u16], tail: &[u8]) -> Vec<u8> {
    let mut p = vec![fc];
    for w in words {
        p.extend_from_slice(&w.to_be_bytes());
    }
    p.extend_from_slice(tail);
    p
}

/// Every exception of the Modbus Application Protocol the server answers, on one connection
/// that stays open; FC 23 all or nothing; forced inputs read back as forced; 32-bit values.
#[test]
fn modbus_answers_every_exception_and_keeps_the_connection() {
    let mut run = Run::start(&[
        s(&chart("io.st")),
        "--modbus",
        "127.0.0.1:0",
        "--monitor",
        "127.0.0.1:0",
        "--no-retain",
        "--for",
        "T#120s",
    ]);
    let (mb, mon) = (run.modbus(), run.monitor());
    let mut m = Modbus::connect(mb);
    // Limit reads 100 before any scan (declared values are served at once); Count is written by
    // the first scan's action, so it is what says a scan has run.
    eventually("the first scan", 20, || m.read_holding(2, 2) == [0xEE6B, 0x2800]);
    let exc = |fc: u8, code: u8| vec![fc | 0x80, code];
    let cases: Vec<(&str, Vec<u8>, Vec<u8>)> = vec![
        ("FC5 with a value other than 0xFF00/0x0000", pdu(5, &[32768, 0x1234], &[]), exc(5, 3)),
        ("FC5 with a value of 0x00FF", pdu(5, &[32768, 0x00FF], &[]), exc(5, 3)),
        ("FC15 whose byte count disagrees with the quantity", pdu(15, &[32768, 2], &[2, 0x03, 0]), exc(15, 3)),
        ("FC15 whose frame is shorter than its byte count", pdu(15, &[32768, 2], &[1]), exc(15, 3)),
        ("FC15 of 1969 coils", pdu(15, &[32768, 1969], &[247]), exc(15, 3)),
        ("FC16 whose byte count disagrees with the quantity", pdu(16, &[32768, 1], &[4, 0, 1, 0, 2]), exc(16, 3)),
        ("FC16 of 124 registers", pdu(16, &[1000, 124], &[248]), exc(16, 3)),
        ("FC16 of 0 registers", pdu(16, &[1000, 0], &[0]), exc(16, 3)),
        ("FC3 of 126 registers", pdu(3, &[0, 126], &[]), exc(3, 3)),
        ("FC3 of 0 registers", pdu(3, &[0, 0], &[]), exc(3, 3)),
        ("FC4 of 126 registers", pdu(4, &[0, 126], &[]), exc(4, 3)),
        ("FC1 of 2001 coils", pdu(1, &[0, 2001], &[]), exc(1, 3)),
        ("FC2 of 0 inputs", pdu(2, &[0, 0], &[]), exc(2, 3)),
        ("FC3 with a byte too many", pdu(3, &[0, 1], &[0]), exc(3, 3)),
        ("FC6 without its value", pdu(6, &[1000], &[]), exc(6, 3)),
        ("FC23 reading 126 registers", pdu(23, &[0, 126, 1000, 1], &[2, 0, 5]), exc(23, 3)),
        ("FC23 writing 122 registers", pdu(23, &[0, 1, 1000, 122], &[244]), exc(23, 3)),
        ("FC23 whose byte count disagrees", pdu(23, &[0, 1, 1000, 1], &[4, 0, 5, 0, 6]), exc(23, 3)),
        ("FC3 beyond the map", pdu(3, &[1004, 1], &[]), exc(3, 2)),
        ("FC1 beyond the map", pdu(1, &[0, 3], &[]), exc(1, 2)),
        ("FC5 to an output coil", pdu(5, &[0, 0xFF00], &[]), exc(5, 2)),
        ("FC6 to an output register", pdu(6, &[0, 7], &[]), exc(6, 2)),
        ("FC16 to an unmapped register", pdu(16, &[1005, 1], &[2, 0, 1]), exc(16, 2)),
        ("FC8 (diagnostics)", pdu(8, &[0, 0], &[]), exc(8, 1)),
        ("FC43 (device identification)", vec![43, 14, 1, 0], exc(43, 1)),
        ("FC22 (mask write register)", pdu(22, &[1000, 0xFFFF, 0], &[]), exc(22, 1)),
        ("a lone function code", vec![3], exc(3, 3)),
    ];
    for (what, req, want) in &cases {
        let got = m.request(req);
        assert_eq!(&got, want, "{what}");
    }
    // FC23 is all or nothing: its read part fails (2000 is beyond the map), so its write of
    // Limit (holding register 1000) is not applied.
    let got = m.request(&pdu(23, &[2000, 1, 1000, 1], &[2, 0, 55]));
    assert_eq!(got, exc(23, 2));
    assert_eq!(m.read_holding(1000, 1), [100], "FC23 wrote nothing");
    // A good FC23 writes, then reads what it wrote.
    let got = m.request(&pdu(23, &[1000, 1, 1000, 1], &[2, 0, 55]));
    assert_eq!(got, vec![23, 2, 0, 55]);
    // The connection still serves after every exception.
    assert_eq!(m.read_holding(1000, 1), [55]);

    // 32-bit values on two registers, high word first: Count 4000000000 = 0xEE6B2800.
    assert_eq!(m.read_holding(2, 2), [0xEE6B, 0x2800]);
    // Target (%ID1, DINT) through the input window at 32768 + 2; Copy (%QD3) follows it.
    assert_eq!(m.write_registers(32770, &[0xFFFF, 0xFFFE]), pdu(16, &[32770, 2], &[]));
    eventually("Copy = -2", 20, || m.read_holding(6, 2) == [0xFFFF, 0xFFFE]);
    // Flow = Setpoint * Gain (REAL): 4 * 2.5 = 10.0 = 0x41200000.
    assert_eq!(m.write_registers(32768, &[4]), pdu(16, &[32768, 1], &[]));
    eventually("Flow = 10.0", 20, || m.read_holding(4, 2) == [0x4120, 0x0000]);
    // Gain (%MD1, REAL) written by the client: 0.5 → Flow 2.0 = 0x40000000.
    m.write_registers(1002, &[0x3F00, 0x0000]);
    eventually("Flow = 2.0", 20, || m.read_holding(4, 2) == [0x4000, 0x0000]);

    // A forced input is what Modbus reads; released, the client's value again.
    m.write_coil(32768, false);
    let mut ws = Ws::connect(&format!("ws://{mon}/?token=t0k3n"));
    let r = ws.cmd(1, json!({"cmd": "force", "name": "Go", "value": true}));
    assert_eq!(r["ok"], true, "{r}");
    assert_eq!(m.read_discrete(0, 1), [true]);
    assert_eq!(m.read_coils(32768, 1), [true], "the input window reads the forced value too");
    eventually("Echo follows the forced Go", 20, || m.read_coils(1, 1) == [true]);
    let r = ws.cmd(2, json!({"cmd": "unforce", "name": "Go"}));
    assert_eq!(r["ok"], true, "{r}");
    assert_eq!(m.read_discrete(0, 1), [false]);
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    let counters = lines.iter().find(|l| l.starts_with("sfc run: Modbus: ")).unwrap();
    assert!(counters.contains(&format!("{} exceptions", cases.len() + 1)), "{counters}");
}

/// Before the first scan has run (here: started halted), Modbus reads the chart's declared
/// values of outputs and `%M`, not zeros: Limit := 100, Gain := 2.5 (0x40200000).
#[test]
fn modbus_reads_declared_values_before_the_first_scan() {
    // Halted before the first scan (the monitor is there to let it go on: `--halted` needs one).
    let mut run = Run::start(&[
        s(&chart("io.st")),
        "--modbus",
        "127.0.0.1:0",
        "--monitor",
        "127.0.0.1:0",
        "--halted",
        "--no-retain",
        "--for",
        "T#60s",
    ]);
    let mut m = Modbus::connect(run.modbus());
    assert_eq!(m.read_holding(1000, 4), [100, 0, 0x4020, 0x0000]);
    assert_eq!(m.read_holding(2, 2), [0, 0], "Count is assigned by the chart's first scan, not declared");
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
}

/// A retain file that cannot be written (its directory does not exist) is said at the start,
/// once, and the run goes on; when the directory appears, the file is written and that is said.
#[test]
fn a_retain_file_that_cannot_be_written_is_said_at_the_start() {
    let dir = scratch("retain-dir");
    let missing = dir.join("later");
    let retain = missing.join("carwash.retain");
    let mut run = Run::start(&["examples/carwash/carwash.st", "--retain", s(&retain), "--for", "T#60s"]);
    let warning = run.line("the retain warning", 30, |l| l.starts_with("warning: retain: cannot write "));
    assert!(warning.contains("will not survive a restart"), "{warning}");
    std::fs::create_dir_all(&missing).unwrap();
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    assert_eq!(lines.iter().filter(|l| l.contains("cannot write")).count(), 1, "said once: {lines:?}");
    assert!(lines.iter().any(|l| l == &format!("retain: {} written", retain.display())), "{lines:?}");
    assert_eq!(retained(&read_retain(&retain), "Washes"), json!(0));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A retain file named for a chart without RETAIN or PERSISTENT variables is said unused, not
/// silently ignored; without `--retain` nothing is said.
#[test]
fn a_retain_file_named_for_a_chart_without_retentive_values_is_said_unused() {
    let dir = scratch("retain-unused");
    let retain = dir.join("io.retain");
    let o = command(&["run", s(&chart("io.st")), "--retain", s(&retain), "--scans", "3"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let unused = format!(
        "retain: the chart has no RETAIN or PERSISTENT variables: {} is neither read nor written",
        retain.display()
    );
    assert!(err.lines().any(|l| l == unused), "{err}");
    assert!(!retain.exists());
    let o = command(&["run", s(&chart("io.st")), "--scans", "3"]).output().unwrap();
    assert!(!String::from_utf8_lossy(&o.stderr).contains("retain"), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGTERM the moment the run says where it listens (systemd stopping a unit just started):
/// the handler is already installed, so the run still stops in order and exits 0. It was
/// installed by the network side's first poll, and a signal before that killed the process.
#[test]
fn sigterm_right_after_start_stops_in_order() {
    for round in 0..10 {
        let mut run = Run::start(&[s(&chart("io.st")), "--modbus", "127.0.0.1:0", "--no-retain", "--for", "T#60s"]);
        run.modbus();
        run.signal(libc::SIGTERM);
        let (status, lines) = run.finish(30);
        assert_eq!(status, Some(0), "round {round}: {lines:?}");
        assert!(lines.iter().any(|l| l == "sfc run: SIGTERM: stopping in order"), "round {round}: {lines:?}");
    }
}

/// A Modbus connection idle longer than the timeout is closed; the server counts it.
#[test]
fn idle_modbus_connections_are_closed() {
    let mut run = Run::start(&[
        s(&chart("io.st")),
        "--modbus",
        "127.0.0.1:0",
        "--modbus-idle-timeout",
        "T#300ms",
        "--no-retain",
        "--for",
        "T#60s",
    ]);
    let mb = run.modbus();
    let mut busy = Modbus::connect(mb);
    let mut idle = Modbus::connect(mb);
    idle.s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    // One client keeps asking every 100 ms; the other says nothing for a second.
    let started = Instant::now();
    while started.elapsed() < Duration::from_secs(1) {
        assert_eq!(busy.read_holding(1000, 1), [100]);
        std::thread::sleep(Duration::from_millis(100));
    }
    use std::io::Read;
    let mut b = [0u8; 1];
    assert!(matches!(idle.s.read(&mut b), Ok(0) | Err(_)), "the idle connection is closed");
    assert_eq!(busy.read_holding(1000, 1), [100], "the busy one is served");
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    assert!(lines.iter().any(|l| l.starts_with("sfc run: Modbus: ") && l.contains(" 1 closed idle")), "{lines:?}");
}

/// A real client (pymodbus) reads the 32-bit values in the documented word orders.
#[test]
fn pymodbus_reads_32_bit_values_in_both_word_orders() {
    if !common::pymodbus() {
        return;
    }
    for order in ["big", "little"] {
        let mut run = Run::start(&[
            s(&chart("io.st")),
            "--modbus",
            "127.0.0.1:0",
            "--word-order",
            order,
            "--no-retain",
            "--for",
            "T#60s",
        ]);
        let mb = run.modbus();
        let script = format!(
            r#"
import sys, time
from pymodbus.client import ModbusTcpClient
c = ModbusTcpClient("127.0.0.1", port={port}); c.connect()
c.write_register(32768, 4)                                 # Setpoint := 4
time.sleep(0.3)
t = c.DATATYPE
r = c.read_holding_registers(2, count=4).registers
count = c.convert_from_registers(r[0:2], data_type=t.UINT32, word_order="{order}")
flow = c.convert_from_registers(r[2:4], data_type=t.FLOAT32, word_order="{order}")
c.write_registers(32770, c.convert_to_registers(-123456, data_type=t.INT32, word_order="{order}"))
time.sleep(0.3)
copy = c.convert_from_registers(c.read_holding_registers(6, count=2).registers, data_type=t.INT32, word_order="{order}")
print(count, flow, copy)
"#,
            port = mb.port()
        );
        let out = std::process::Command::new("python3").arg("-c").arg(&script).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{order}: {text}{}", String::from_utf8_lossy(&out.stderr));
        assert_eq!(text.trim(), "4000000000 10.0 -123456", "word order {order}");
        run.signal(libc::SIGTERM);
        assert_eq!(run.finish(30).0, Some(0));
    }
}

/// The monitor refuses foreign web pages and foreign host names, takes the token from the
/// environment or a file but never from the command line, and slows down wrong tokens.
#[test]
fn the_monitor_refuses_foreign_pages_and_slows_down_guessing() {
    let out = command(&["run", "examples/carwash/carwash.st", "--monitor", "127.0.0.1:0", "--token", "s3cret"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("`--token` is not accepted") && err.contains("SFC_TOKEN") && err.contains("--token-file"),
        "{err}"
    );

    let dir = scratch("origin");
    let token = dir.join("token");
    std::fs::write(&token, "from-a-file\n").unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&token, std::fs::Permissions::from_mode(0o600)).unwrap();
    }
    let mut run = Run::start(&[
        "examples/carwash/carwash.st",
        "--monitor",
        "127.0.0.1:0",
        "--token-file",
        s(&token),
        "--no-retain",
        "--for",
        "T#60s",
    ]);
    let mon = run.monitor();
    let line = run.line("the monitor", 10, |l| l.starts_with("sfc run: monitor on "));
    assert!(line.ends_with(&format!("(token from {})", token.display())) && !line.contains("from-a-file"), "{line}");
    let cases: [(&[(&str, &str)], &str); 6] = [
        (&[("Origin", "https://evil.example")], "403"),
        (&[("Origin", "http://127.0.0.1.evil.example:8080")], "403"),
        (&[("Origin", "null")], "403"),
        (&[("Host", "evil.example:9002")], "403"),
        (&[("Origin", "http://127.0.0.1:8080")], "101"),
        (&[("Origin", "http://localhost:5173")], "101"),
    ];
    for (headers, want) in cases {
        let (_, head) = handshake(mon, "/?token=from-a-file", headers);
        assert!(head.starts_with(&format!("HTTP/1.1 {want}")), "{headers:?}: {head}");
    }
    // Two Host headers (the first loopback, the second not): which one a check reads would
    // differ between a proxy and the server, so neither is trusted.
    let own = mon.to_string();
    let (_, head) = handshake(mon, "/?token=from-a-file", &[("Host", own.as_str()), ("Host", "evil.example")]);
    assert!(head.starts_with("HTTP/1.1 400"), "two Host headers: {head}");
    // Wrong tokens: each makes the client wait longer before the next try.
    let (_, head) = handshake(mon, "/?token=guess1", &[]);
    assert!(head.starts_with("HTTP/1.1 101"), "a wrong token still watches: {head}");
    let (_, head) = handshake(mon, "/?token=guess2", &[]);
    assert!(head.starts_with("HTTP/1.1 429"), "the second guess comes too soon: {head}");
    std::thread::sleep(Duration::from_millis(150));
    let mut ws = Ws::connect(&format!("ws://{mon}/"));
    ws.until("hello", |m| m["type"] == "hello");
    let r = ws.cmd(1, json!({"cmd": "halt", "token": "guess3"}));
    assert_eq!(r["error"], "wrong token");
    let r = ws.cmd(2, json!({"cmd": "halt", "token": "from-a-file"}));
    assert!(r["error"].as_str().unwrap().starts_with("too many wrong tokens"), "{r}");
    std::thread::sleep(Duration::from_millis(500));
    let r = ws.cmd(3, json!({"cmd": "halt", "token": "from-a-file"}));
    assert_eq!(r["ok"], true, "{r}");
    run.signal(libc::SIGINT);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    assert!(lines.iter().any(|l| l == "sfc run: SIGINT: stopping in order"), "{lines:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `sfc run --config plant.toml`: the chart, period, watchdog, Modbus (little word order),
/// monitor with a token file, safe values and retain settings from one file; a mistake in it
/// is located.
#[test]
fn a_run_configuration_sets_up_the_plant() {
    let dir = scratch("config");
    std::fs::write(dir.join("token"), "cfg-token").unwrap();
    let config = dir.join("plant.toml");
    std::fs::write(
        &config,
        format!(
            r#"# The Io test bench.
chart = "{chart}"
period = "T#5ms"
watchdog = "T#500ms"

[modbus]
address = "127.0.0.1:0"
max_clients = 4
word_order = "little"

[monitor]
address = "127.0.0.1:0"
token_file = "token"

[retain]
enabled = false

[safe]
Running = true
Level = -1
"#,
            chart = s(&chart("io.st"))
        ),
    )
    .unwrap();
    let mut run = Run::start(&["--config", s(&config), "--for", "T#60s"]);
    let (mb, mon) = (run.modbus(), run.monitor());
    let mut m = Modbus::connect(mb);
    // `Limit` (register 1000) holds its declared value before any scan; `Count` is written by
    // the first scan, so waiting for it is waiting for that scan (a loaded machine once read
    // the registers between the two).
    eventually("the first scan", 20, || m.read_holding(1000, 1) == [100] && m.read_holding(2, 2) != [0, 0]);
    // Little word order: the low word first.
    assert_eq!(m.read_holding(2, 2), [0x2800, 0xEE6B]);
    let mut ws = Ws::connect(&format!("ws://{mon}/?token=cfg-token"));
    let hello = ws.until("hello", |m| m["type"] == "hello");
    assert_eq!((hello["period"].as_str(), hello["authorized"].as_bool()), (Some("T#5ms"), Some(true)));
    // Four clients at most: the fifth is closed at once.
    let extra: Vec<Modbus> = (0..3).map(|_| Modbus::connect(mb)).collect();
    let mut fifth = Modbus::connect(mb);
    fifth.s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut b = [0u8; 1];
    use std::io::Read;
    assert!(matches!(fifth.s.read(&mut b), Ok(0) | Err(_)), "the fifth connection is closed");
    drop(extra);
    let r = ws.cmd(1, json!({"cmd": "stop"}));
    assert_eq!(r["result"]["state"], "STOP", "{r}");
    // In STOP the safe values of the configuration: Running TRUE, Level -1.
    assert_eq!(m.read_coils(0, 1), [true]);
    assert_eq!(m.read_holding(0, 1), [0xFFFF]);
    let r = ws.cmd(2, json!({"cmd": "start"}));
    assert_eq!(r["result"]["state"], "RUN", "{r}");
    eventually("outputs from the chart again", 20, || m.read_coils(0, 1) == [false]);
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    assert!(
        lines.iter().any(|l| l.contains("outputs at their safe values (Running=TRUE, Echo=FALSE, Level=-1")),
        "{lines:?}"
    );
    assert!(lines.iter().any(|l| l.contains(" refused over the limit") && !l.contains(" 0 refused")), "{lines:?}");

    std::fs::write(&config, "chart = \"x.st\"\n[modbus]\nadress = \"127.0.0.1:502\"\n").unwrap();
    let out = command(&["run", "--config", s(&config)]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("plant.toml:3:1: unknown key `adress` in [modbus]"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// RETAIN and PERSISTENT over warm and cold starts, a damaged file set aside, and a file of an
/// older chart restored where names and types still match.
#[test]
fn retain_and_persistent_over_warm_and_cold_starts() {
    let dir = scratch("retain");
    let file = dir.join("counter.retain");
    let counter = chart("counter.st");
    let run = |args: &[&str]| {
        let mut all = vec!["run", "--period", "T#1ms", "--retain", s(&file)];
        all.extend_from_slice(args);
        let out = command(&all).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(0), "{err}");
        (read_retain(&file), err)
    };
    let (f, err) = run(&[s(&counter), "--scans", "20"]);
    assert!(err.contains("retain: warm start; no file"), "{err}");
    let v = |f: &serde_json::Value, n: &str| retained(f, n);
    assert_eq!(
        (v(&f, "Scans"), v(&f, "Hours"), v(&f, "Runs"), v(&f, "Level")),
        (json!(20), json!(20), json!(1), json!(5.5))
    );
    assert_eq!(v(&f, "Scratch"), serde_json::Value::Null, "not retentive");
    let (f, err) = run(&[s(&counter), "--scans", "10"]);
    assert!(err.contains("retain: warm start: restored 4 values from"), "{err}");
    assert_eq!((v(&f, "Scans"), v(&f, "Hours"), v(&f, "Runs")), (json!(30), json!(30), json!(1)));
    let (f, err) = run(&[s(&counter), "--scans", "5", "--cold"]);
    assert!(err.contains("retain: cold start: restored 2 values") && err.contains("reset 2 RETAIN values"), "{err}");
    assert_eq!(
        (v(&f, "Scans"), v(&f, "Hours"), v(&f, "Runs"), v(&f, "Level")),
        (json!(5), json!(35), json!(2), json!(1.75))
    );

    // The chart changed: Scans is now a ULINT, Hours was renamed.
    let changed = dir.join("counter.st");
    let text =
        std::fs::read_to_string(&counter).unwrap().replace("Scans : UDINT", "Scans : ULINT").replace("Hours", "Uptime");
    std::fs::write(&changed, text).unwrap();
    let (f, err) = run(&[s(&changed), "--scans", "1"]);
    assert!(err.contains("restored 2 values"), "{err}");
    assert!(
        err.contains("dropped 2 saved values that do not match the chart: Scans (was UDINT, now ULINT), Hours (no longer declared RETAIN or PERSISTENT)"),
        "{err}"
    );
    assert!(err.contains("not in the file and start from their initial values: Uptime"), "{err}");
    assert_eq!((v(&f, "Scans"), v(&f, "Uptime"), v(&f, "Runs")), (json!(1), json!(1), json!(3)));

    // A damaged file is set aside, said, and the run starts from the initial values.
    let text = std::fs::read_to_string(&file).unwrap().replace("\"Runs\"", "\"Runz\"");
    std::fs::write(&file, text).unwrap();
    let (f, err) = run(&[s(&changed), "--scans", "1"]);
    assert!(
        err.contains("warning: retain:") && err.contains("is damaged (the checksum does not match the content)"),
        "{err}"
    );
    assert!(dir.join("counter.retain.corrupt").exists());
    assert_eq!(v(&f, "Runs"), json!(1));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A runtime error (a division by zero) is a FAULT like a watchdog trip: the outputs go to
/// their safe values on Modbus, the monitor names the step, the action and the line, the
/// retentive values are written; a cold `reset` clears RETAIN and keeps PERSISTENT.
#[test]
fn a_runtime_error_faults_to_the_safe_state_and_a_cold_reset_keeps_only_persistent() {
    let dir = scratch("runtime-error");
    let retain = dir.join("hoist.retain");
    let mut run = Run::start(&[
        s(&chart("guarded.st")),
        "--modbus",
        "127.0.0.1:0",
        "--monitor",
        "127.0.0.1:0",
        "--retain",
        s(&retain),
        "--for",
        "T#120s",
    ]);
    let (mb, mon) = (run.modbus(), run.monitor());
    let mut m = Modbus::connect(mb);
    // Parked: brake released, lamp on (the opposite of the safe values).
    eventually("the first scans", 20, || m.read_coils(0, 2) == [false, true]);
    let mut ws = Ws::connect(&format!("ws://{mon}/?token=t0k3n"));
    ws.until("hello", |m| m["type"] == "hello" && m["state"] == "RUN");

    m.write_coil(32768, true); // Go: the first scan of Lifting divides by zero.
    let line = run.line("the fault's line", 60, |l| l.starts_with("error: ") && l.contains("division by zero"));
    let div =
        std::fs::read_to_string(chart("guarded.st")).unwrap().lines().position(|l| l.contains("/ Divisor")).unwrap()
            + 1;
    assert!(line.starts_with(&format!("error: {div}:")) && line.contains("in action Lift of step Lifting"), "{line}");
    assert_eq!(m.read_coils(0, 2), [true, false], "Modbus reads the safe values");
    let st = ws.until("FAULT", |m| m["type"] == "state" && m["state"] == "FAULT");
    let f = &st["fault"];
    assert_eq!(
        (f["kind"].as_str(), f["step"].as_str(), f["action"].as_str(), f["line"].as_u64()),
        (Some("error"), Some("Lifting"), Some("Lift"), Some(div as u64)),
        "{st}"
    );
    assert_eq!((st["outputs"]["Brake"].clone(), st["outputs"]["Lamp"].clone()), (json!(true), json!(false)));
    // Entering FAULT writes the retentive values of the scan that faulted.
    eventually("the retain file", 20, || retain.exists() && retained(&read_retain(&retain), "Lifts") == json!(1));
    assert_eq!(retained(&read_retain(&retain), "Attempts"), json!(1));

    // A cold reset: Lifts (RETAIN) starts again from 0, Attempts (PERSISTENT) is kept.
    m.write_coil(32768, false);
    let r = ws.cmd(1, json!({"cmd": "reset", "mode": "cold"}));
    assert_eq!((r["ok"].as_bool(), r["result"]["mode"].as_str()), (Some(true), Some("cold")), "{r}");
    ws.until("RUN", |m| m["type"] == "state" && m["state"] == "RUN");
    eventually("parked again", 20, || m.read_coils(0, 2) == [false, true]);
    let r = ws.cmd(2, json!({"cmd": "snapshot"}));
    assert_eq!(r["ok"], true, "{r}");
    let snap = ws.until("snapshot", |m| m["type"] == "snapshot");
    assert_eq!((snap["vars"]["Lifts"].clone(), snap["vars"]["Attempts"].clone()), (json!(0), json!(1)), "{snap}");
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
    assert!(lines.iter().any(|l| l.starts_with("sfc run: cold restart from FAULT")), "{lines:?}");
    let file = read_retain(&retain);
    assert_eq!((retained(&file, "Lifts"), retained(&file, "Attempts")), (json!(0), json!(1)));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A client's write to `%M` memory is never lost, even when it arrives while the chart runs:
/// the scan's copy of memory back to the image must not overwrite a write it has not applied.
/// (The chart takes milliseconds a scan, so nearly every write lands in that window.)
#[test]
fn a_memory_write_during_a_scan_is_not_lost() {
    let mut run = Run::start(&[
        s(&chart("slow_memory.st")),
        "--modbus",
        "127.0.0.1:0",
        "--period",
        "T#1ms",
        "--no-retain",
        "--for",
        "T#120s",
    ]);
    let mut m = Modbus::connect(run.modbus());
    eventually("the first scan", 20, || m.read_holding(0, 1) == [2]);
    for v in 2..=40u16 {
        assert_eq!(m.write_registers(1000, &[v]), pdu(16, &[1000, 1], &[]));
        eventually(&format!("Twice = {}", 2 * v), 20, || m.read_holding(0, 1) == [2 * v]);
        assert_eq!(m.read_holding(1000, 1), [v], "Gain keeps the client's value");
    }
    run.signal(libc::SIGTERM);
    let (status, lines) = run.finish(30);
    assert_eq!(status, Some(0), "{lines:?}");
}

/// The status block (input registers 40300…): state, halted, scan, last fault, faults.
fn status(m: &mut Modbus) -> (u16, u16, u64, u16, u16) {
    let r = m.read_input_registers(40300, 8);
    let scan = r[2..6].iter().fold(0u64, |a, w| a << 16 | u64::from(*w));
    (r[0], r[1], scan, r[6], r[7])
}

/// Issue 30, items 6 and 8: with `--modbus-reset`, a Modbus client (an HMI without the monitor)
/// restarts the chart out of FAULT through holding register 40000 (1 warm, 2 cold) or coil
/// 40000; the status block tells RUN/STOP/FAULT, the scan and the last fault; the FAULT line
/// names the way out.
#[test]
fn a_modbus_client_reads_the_status_and_resets_a_fault() {
    let mut run = Run::start(&[
        s(&chart("runaway.st")),
        "--watchdog",
        "T#50ms",
        "--modbus",
        "127.0.0.1:0",
        "--modbus-reset",
        "--no-retain",
        "--for",
        "T#120s",
    ]);
    let mut m = Modbus::connect(run.modbus());
    eventually("RUN in the status block, scanning", 20, || {
        let st = status(&mut m);
        st.0 == 0 && st.2 > 2
    });
    let (_, halted, scan, fault, faults) = status(&mut m);
    assert_eq!((halted, fault, faults), (0, 0, 0));
    eventually("the scan number moves", 20, || status(&mut m).2 > scan);
    assert_eq!(m.read_holding(40000, 1), [0], "the reset register reads 0");
    assert_eq!(m.read_coils(40000, 1), [false], "the reset coil reads FALSE");
    // Go: the watchdog stops Filling's loop.
    m.write_coil(32768, true);
    let line = run.line("the FAULT line", 30, |l| l.starts_with("sfc run: FAULT:"));
    assert!(
        line.ends_with(
            "Modbus keeps serving; to restart the chart: Modbus holding register 40000 := 1 (warm) or 2 \
             (cold), or coil 40000 := TRUE"
        ),
        "{line}"
    );
    eventually("FAULT in the status block", 20, || status(&mut m).0 == 2);
    let (_, _, at, fault, faults) = status(&mut m);
    assert_eq!((fault, faults), (1, 1), "the watchdog's fault (1), the first");
    assert_eq!(m.read_coils(0, 2), [false, true], "the safe outputs");
    // Nothing but 0, 1, 2 on the register, TRUE or FALSE on the coil.
    assert_eq!(m.request(&[6, 0x9C, 0x40, 0, 3]), [0x86, 3], "3 is no reset mode");
    assert_eq!(status(&mut m).0, 2, "still in FAULT");
    m.write_coil(32768, false);
    // A warm reset through the register: RUN again from Ready (Prime drives the outputs).
    assert_eq!(m.request(&[6, 0x9C, 0x40, 0, 1]), [6, 0x9C, 0x40, 0, 1]);
    eventually("RUN after the reset", 20, || status(&mut m).0 == 0);
    eventually("Prime runs again", 20, || m.read_coils(0, 2) == [true, false]);
    let (_, _, after, fault, faults) = status(&mut m);
    assert!(after > at, "scan numbers go on counting: {after} after {at}");
    assert_eq!((fault, faults), (1, 1), "the last fault is kept after a reset");
    // Again, and out through the coil.
    m.write_coil(32768, true);
    eventually("the second FAULT", 30, || status(&mut m).0 == 2);
    m.write_coil(32768, false);
    m.write_coil(40000, true);
    eventually("RUN after the coil's reset", 20, || status(&mut m).0 == 0);
    assert_eq!(status(&mut m).4, 2, "two faults so far");
    run.signal(libc::SIGTERM);
    let (code, lines) = run.finish(30);
    assert_eq!(code, Some(0), "{lines:?}");
    assert!(lines.iter().any(|l| l == "sfc run: Modbus: warm reset requested (holding register 40000)"), "{lines:?}");
    assert!(lines.iter().any(|l| l == "sfc run: Modbus: warm reset requested (coil 40000)"), "{lines:?}");
}

/// Issue 30, item 6: a run with no way out of FAULT says so in its FAULT line; `--halted` with
/// nothing that could send `continue` is refused at start; the reset register refuses to hide
/// an input, and needs Modbus.
#[test]
fn a_run_without_a_way_out_says_so() {
    let mut run = Run::start(&[
        s(&chart("runaway.st")),
        "--watchdog",
        "T#50ms",
        "--modbus",
        "127.0.0.1:0",
        "--no-retain",
        "--for",
        "T#120s",
    ]);
    let mut m = Modbus::connect(run.modbus());
    eventually("the first scans", 20, || m.read_coils(0, 2) == [true, false]);
    // Without --modbus-reset, 40000 is only the (unmapped) inputs' window.
    assert_eq!(m.request(&[6, 0x9C, 0x40, 0, 1]), [0x86, 2]);
    m.write_coil(32768, true);
    let line = run.line("the FAULT line", 30, |l| l.starts_with("sfc run: FAULT:"));
    assert!(
        line.ends_with(
            "Modbus keeps serving; nothing in this run can restart the chart (no monitor, no OPC UA user of \
             role admin, no --modbus-reset): stop sfc run and start it again"
        ),
        "{line}"
    );
    drop(run);
    let refused = |args: &[&str], why: &str| {
        let mut full = vec!["run"];
        full.extend_from_slice(args);
        let out = command(&full).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(why), "{args:?}: {err}");
    };
    refused(
        &["examples/carwash/carwash.st", "--halted", "--modbus", "127.0.0.1:0", "--no-retain"],
        "--halted waits for a `continue`, and nothing in this run can send one",
    );
    refused(&["examples/carwash/carwash.st", "--modbus-reset", "--no-retain"], "`--modbus-reset` needs Modbus");
    let dir = scratch("reset-overlap");
    let overlap = dir.join("far.st");
    std::fs::write(
        &overlap,
        "PROGRAM Far\n  VAR\n    Far AT %IX904.0 : BOOL;\n    Lamp AT %QX0.0 : BOOL;\n  END_VAR\n  \
         INITIAL_STEP S: Lamp(N); END_STEP\nEND_PROGRAM\n",
    )
    .unwrap();
    refused(
        &[s(&overlap), "--modbus", "127.0.0.1:0", "--modbus-reset", "--no-retain"],
        "`Far` %IX904.0 is written through coil 40000, which --modbus-reset takes for the reset",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30, item 7: `--report` prints the state, the scan, the outputs and the statistics as a
/// line for the operator; `--report-format json` as one JSON object per line.
#[test]
fn report_lines_for_the_operator_and_for_a_log_collector() {
    let mut run = Run::start(&["examples/carwash/carwash.st", "--no-retain", "--report", "T#100ms", "--for", "T#60s"]);
    let line = run.line("a report", 20, |l| l.starts_with("sfc run: report: "));
    assert!(line.starts_with("sfc run: report: RUN, scan "), "{line}");
    assert!(
        line.contains(
            "; outputs SprayValve=FALSE, Travel=FALSE, Brush=FALSE, TravelBack=FALSE, Blower=FALSE, FaultLamp=FALSE; "
        ),
        "{line}"
    );
    assert!(line.contains(" scans; start jitter p50 ") && line.ends_with(" periods skipped"), "{line}");
    assert!(!line.contains('{'), "no raw JSON: {line}");
    drop(run);
    let mut run = Run::start(&[
        "examples/carwash/carwash.st",
        "--no-retain",
        "--report",
        "T#100ms",
        "--report-format",
        "json",
        "--for",
        "T#60s",
    ]);
    let line = run.line("a JSON report", 20, |l| l.starts_with('{'));
    let j: serde_json::Value = serde_json::from_str(&line).unwrap();
    assert_eq!((j["state"].as_str(), j["halted"].as_bool()), (Some("RUN"), Some(false)), "{j}");
    assert!(j["scan"].as_u64().is_some() && j["stats"]["scans"].as_u64().is_some(), "{j}");
    assert_eq!(j["outputs"]["SprayValve"], false, "{j}");
    drop(run);
    let out = command(&["run", "examples/carwash/carwash.st", "--report", "T#1s", "--report-format", "xml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("`--report-format`: `xml` is `text` or `json`"));
}
