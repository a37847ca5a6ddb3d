//! Scan start jitter of `sfc run` at 1 ms, without and with 50 monitor clients on loopback
//! (`cargo bench -p sfc-runtime --bench jitter`; `SFC_JITTER_SECS` sets the seconds per run,
//! default 5). The figures go to docs/runtime.md.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use futures_util::StreamExt;
use sfc_runtime::{Limits, RunOptions, RunReport, Runtime};
use sfc_sim::{SimOptions, Simulation};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

fn carwash() -> Simulation {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/carwash/carwash.st");
    let text = std::fs::read_to_string(path).expect("examples/carwash/carwash.st");
    Simulation::from_source("carwash.st", &text, None, SimOptions { period: 1_000, ..Default::default() })
        .unwrap_or_else(|(_, d)| panic!("{d:?}"))
}

fn run(secs: u64, clients: usize, realtime: bool) -> (RunReport, u64) {
    let opts = RunOptions {
        monitor: Some("127.0.0.1:0".parse().unwrap()),
        limits: Limits { duration: Some(Duration::from_secs(secs)), ..Default::default() },
        realtime,
        ..Default::default()
    };
    let rt = Runtime::start(carwash(), opts).expect("start");
    let addr = rt.monitor_addr().unwrap();
    let received = Arc::new(AtomicU64::new(0));
    let net = tokio::runtime::Builder::new_multi_thread().worker_threads(1).enable_all().build().unwrap();
    for _ in 0..clients {
        let received = received.clone();
        net.spawn(async move {
            let Ok((mut ws, _)) = tokio_tungstenite::connect_async(format!("ws://{addr}/")).await else { return };
            while let Some(Ok(_)) = ws.next().await {
                received.fetch_add(1, Ordering::Relaxed);
            }
        });
    }
    let report = rt.wait();
    net.shutdown_timeout(Duration::from_secs(1));
    (report, received.load(Ordering::Relaxed))
}

fn main() {
    let secs = std::env::var("SFC_JITTER_SECS").ok().and_then(|s| s.parse().ok()).unwrap_or(5);
    // `cargo bench` passes `--bench`; `cargo test --benches` runs it briefly as a smoke test.
    let secs = if std::env::args().any(|a| a == "--bench") { secs } else { 1 };
    println!("car wash at 1 ms, {secs} s per run, scan start jitter (µs):");
    for (clients, realtime) in [(0usize, false), (50, false), (0, true), (50, true)] {
        let (r, received) = run(secs, clients, realtime);
        let prio = match (&r.realtime, realtime) {
            (Ok(true), _) => "real-time",
            (_, true) => "real-time refused, normal",
            _ => "normal",
        };
        let j = &r.stats.jitter;
        println!(
            "  {prio:>9} priority, {clients:>2} monitor clients: p50 {:>4}  p99 {:>4}  max {:>5}   (scans {}, scan time p50 {} µs p99 {} µs, overruns {}, messages to clients {received}, dropped {})",
            j.quantile(0.5),
            j.quantile(0.99),
            j.max(),
            r.stats.scans,
            r.stats.duration.quantile(0.5),
            r.stats.duration.quantile(0.99),
            r.stats.overruns,
            r.dropped
        );
    }
}
