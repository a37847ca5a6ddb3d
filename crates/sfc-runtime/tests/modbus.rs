//! `sfc run` driven by a real Modbus TCP client (pymodbus): the car wash example through two
//! full cycles (`scripts/modbus-carwash.py`).

use sfc_runtime::{Limits, RunOptions, Runtime};
use sfc_sim::{SimOptions, Simulation};
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn carwash_full_cycles_over_modbus() {
    let deps = Command::new("bash").arg(root().join("scripts/pymodbus-deps.sh")).status();
    if !deps.is_ok_and(|s| s.success()) {
        eprintln!("\n\n*** SKIPPED: pymodbus cannot be installed (scripts/pymodbus-deps.sh failed) ***\n\n");
        return;
    }
    let path = root().join("examples/carwash/carwash.st");
    let text = std::fs::read_to_string(&path).unwrap();
    let sim = Simulation::from_source("carwash.st", &text, None, SimOptions { period: 10_000, ..Default::default() })
        .unwrap_or_else(|(_, d)| panic!("{d:?}"));
    let opts = RunOptions {
        modbus: Some("127.0.0.1:0".parse().unwrap()),
        limits: Limits { duration: Some(std::time::Duration::from_secs(120)), ..Default::default() },
        ..Default::default()
    };
    let rt = Runtime::start(sim, opts).unwrap();
    let points: Vec<(String, String)> = rt
        .io_points()
        .iter()
        .map(|p| (p.name.clone(), format!("{} {}", sfc_runtime::io::table_name(p.table), p.address)))
        .collect();
    assert!(points.contains(&("StartButton".into(), "discrete input 0".into())), "{points:?}");
    assert!(points.contains(&("FaultLamp".into(), "coil 5".into())), "{points:?}");
    let addr = rt.modbus_addr().unwrap();
    let out = Command::new("python3")
        .arg(root().join("scripts/modbus-carwash.py"))
        .arg(addr.ip().to_string())
        .arg(addr.port().to_string())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    rt.stop();
    let report = rt.wait();
    assert!(out.status.success(), "the Modbus client failed:\n{stdout}\n{stderr}");
    assert!(stdout.contains("back to idle after returning"), "{stdout}");
    assert_eq!(report.error, None);
    assert!(report.stats.scans > 100, "{}", report.stats.summary());
}

#[test]
fn unmapped_addresses_are_refused_with_their_name() {
    let text = "PROGRAM P\nVAR\n  Level AT %IB3 : BYTE;\n  Go AT %IX0.0 : BOOL;\nEND_VAR\nINITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1 := Go; END_TRANSITION\nSTEP S1: END_STEP\nTRANSITION FROM S1 TO S0 := NOT Go; END_TRANSITION\nEND_PROGRAM\n";
    let sim =
        Simulation::from_source("p.st", text, None, SimOptions::default()).unwrap_or_else(|(_, d)| panic!("{d:?}"));
    let opts = RunOptions { modbus: Some("127.0.0.1:0".parse().unwrap()), ..Default::default() };
    let err = Runtime::start(sim, opts).err().expect("%IB is not on the map");
    assert!(err.contains("`Level` %IB3") && err.contains("size `B`"), "{err}");
}
