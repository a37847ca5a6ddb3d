//! The soft-PLC of `sfc run`: the chart scanned on the wall clock with the `iec` semantics,
//! Modbus TCP I/O, and the monitor protocol (`docs/monitor.md`); also the ATMT adapter that
//! serves the same protocol for a REX block running elsewhere (`docs/runtime.md`).
//!
//! Threads: the scan thread owns the [`Simulation`] and never waits on the network; a small
//! tokio runtime serves Modbus and the monitor clients. They meet on the [`board::Hub`].

pub mod atmt;
pub mod board;
pub mod io;
pub mod jitter;
pub mod protocol;
pub mod scan;

use board::{ChartInfo, Hub, VarInfo};
use io::{Image, IoPoint};
use jitter::ScanStats;
use sfc_sim::{Simulation, Value};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

pub use atmt::{AtmtModel, LineSource};
pub use scan::Limits;

/// A variable's memory slot in the simulation, with its type.
#[derive(Debug, Clone, PartialEq)]
pub struct Slot {
    pub index: usize,
    pub ty: sfc_st::Type,
}

impl Slot {
    /// The value of a fresh input of this type (FALSE or 0).
    pub fn default_value(&self) -> Value {
        if matches!(self.ty.base(), sfc_st::Type::Bool) {
            Value::Bool(false)
        } else {
            Value::Int(0)
        }
    }
}

/// How to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Serve Modbus TCP here (port 0 picks a free port).
    pub modbus: Option<SocketAddr>,
    /// Serve the monitor protocol here.
    pub monitor: Option<SocketAddr>,
    /// The secret for `force`/`set`; a random one when `None`.
    pub token: Option<String>,
    pub limits: Limits,
    /// Start halted (nothing scans until `continue` or `step`).
    pub halted: bool,
    /// Run the scan thread with real-time priority (Linux `SCHED_FIFO` 50; needs root or
    /// CAP_SYS_NICE; [`RunReport::realtime`] says whether it was granted).
    pub realtime: bool,
    /// End the run on Ctrl-C (SIGINT) instead of letting it kill the process, so the caller
    /// still gets the report.
    pub ctrl_c: bool,
}

/// How a run ended.
#[derive(Debug, Clone)]
pub struct RunReport {
    pub stats: ScanStats,
    /// What stopped the run: a runtime error of the chart, or the watchdog.
    pub error: Option<String>,
    /// Monitor clients dropped for flooding, garbage or reading too slowly.
    pub dropped: u64,
    /// The scan thread ran with real-time priority; `Err` says why it was asked for and
    /// refused (`Ok(false)`: not asked for).
    pub realtime: Result<bool, String>,
}

impl Default for RunReport {
    fn default() -> Self {
        RunReport { stats: ScanStats::default(), error: None, dropped: 0, realtime: Ok(false) }
    }
}

/// A running soft-PLC (or ATMT adapter).
pub struct Runtime {
    hub: Arc<Hub>,
    net: Option<JoinHandle<()>>,
    worker: Option<JoinHandle<RunReport>>,
    monitor: Option<SocketAddr>,
    modbus: Option<SocketAddr>,
    points: Arc<Vec<IoPoint>>,
}

fn random_token() -> String {
    let mut b = [0u8; 16];
    // Without an entropy source, the time is still unknown to a remote client.
    if getrandom::fill(&mut b).is_err() {
        let t = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default().as_nanos();
        b.copy_from_slice(&t.to_le_bytes());
    }
    b.iter().map(|x| format!("{x:02x}")).collect()
}

fn bind(what: &str, addr: SocketAddr) -> Result<std::net::TcpListener, String> {
    let l = std::net::TcpListener::bind(addr).map_err(|e| format!("cannot serve {what} on {addr}: {e}"))?;
    l.set_nonblocking(true).map_err(|e| e.to_string())?;
    Ok(l)
}

/// The network side: a tokio runtime on its own threads, serving Modbus and the monitor until
/// the hub stops. It is built, run and shut down on its own OS thread, so a caller that is
/// itself async (a test) can start and wait for a run.
/// A bound Modbus listener with the map and image it serves.
type ModbusSide = (std::net::TcpListener, Arc<Vec<IoPoint>>, Arc<Mutex<Image>>);

fn start_net(
    hub: &Arc<Hub>,
    modbus: Option<ModbusSide>,
    monitor: Option<std::net::TcpListener>,
    ctrl_c: bool,
) -> Result<JoinHandle<()>, String> {
    let net = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("sfc-net")
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the network threads: {e}"))?;
    let hub = hub.clone();
    std::thread::Builder::new()
        .name("sfc-net-main".into())
        .spawn(move || {
            net.block_on(async {
                if let Some((l, points, image)) = modbus {
                    tokio::spawn(io::serve(l, points, image));
                }
                if let Some(l) = monitor {
                    tokio::spawn(protocol::serve(l, hub.clone()));
                }
                if ctrl_c {
                    let hub = hub.clone();
                    tokio::spawn(async move {
                        if tokio::signal::ctrl_c().await.is_ok() {
                            hub.stop.store(true, std::sync::atomic::Ordering::Relaxed);
                        }
                    });
                }
                while !hub.stopping() {
                    tokio::time::sleep(std::time::Duration::from_millis(20)).await;
                }
            });
            net.shutdown_timeout(std::time::Duration::from_secs(1));
        })
        .map_err(|e| format!("cannot start the network threads: {e}"))
}

impl Runtime {
    /// Starts scanning `sim` (its period is the scan period) with the I/O and monitor of `opts`.
    /// Errors: a located variable the Modbus map does not cover (with `modbus`), or an address
    /// that cannot be bound.
    pub fn start(sim: Simulation, opts: RunOptions) -> Result<Runtime, String> {
        let points = Arc::new(if opts.modbus.is_some() { io::map_located(&sim)? } else { Vec::new() });
        let located = sim.located_vars();
        let mut variables = Vec::new();
        let mut vars = Vec::new();
        let mut names: Vec<(String, String)> = sim.trace_vars().into_iter().map(|(n, t)| (n, t.to_string())).collect();
        for (n, _, slot, ty) in &located {
            if !names.iter().any(|(m, _)| m.eq_ignore_ascii_case(n)) && sim.handle(n).is_some_and(|h| h.0 == *slot) {
                names.push((n.clone(), ty.to_string()));
            }
        }
        for (name, ty) in names {
            let Some((index, t)) = sim.handle(&name) else { continue };
            let location = located.iter().find(|l| l.2 == index).map(|l| l.1.clone());
            variables.push(VarInfo { name, ty, location });
            vars.push(Slot { index, ty: t });
        }
        let var_point = vars.iter().map(|s| points.iter().position(|p| p.slot.index == s.index)).collect();
        let (steps, transitions) = sim.outline();
        let post = transitions.iter().map(|t| t.2.clone()).collect();
        let initial = steps.iter().enumerate().filter(|s| s.1 .1).map(|s| s.0 as u32).collect();
        let info = ChartInfo {
            runtime: "sfc run",
            pou: sim.pou_name().to_string(),
            period: sim.options().period,
            steps,
            transitions,
            variables,
            control: true,
        };
        let token = opts.token.clone().unwrap_or_else(random_token);
        let (hub, rx) = Hub::new(info, token);
        if opts.halted {
            // Before any client can connect: the first `hello` already says halted.
            hub.lock().push_halt(true, "halt".into());
        }
        let image = Arc::new(Mutex::new(Image::new(&points)));
        let modbus_l = opts.modbus.map(|a| bind("Modbus", a)).transpose()?;
        let monitor_l = opts.monitor.map(|a| bind("the monitor", a)).transpose()?;
        let modbus = modbus_l.as_ref().and_then(|l| l.local_addr().ok());
        let monitor = monitor_l.as_ref().and_then(|l| l.local_addr().ok());
        let net = start_net(&hub, modbus_l.map(|l| (l, points.clone(), image.clone())), monitor_l, opts.ctrl_c)?;
        let thread = scan::ScanThread {
            sim,
            hub: hub.clone(),
            rx,
            points: points.clone(),
            image,
            vars,
            var_point,
            post,
            initial,
            limits: opts.limits,
            halted: opts.halted,
            realtime: opts.realtime,
            inputs: Vec::new(),
            forced: Vec::new(),
            pending_sets: Vec::new(),
            breakpoints: Default::default(),
            stats: ScanStats::default(),
            unpublished_states: Default::default(),
            spare_states: Vec::new(),
            newest: None,
            unpublished_events: Vec::new(),
            halt_change: Vec::new(),
            error: None,
            steps_requested: Vec::new(),
        };
        // The simulator may recurse deeply in user code: the same stack as the CLI's.
        let worker = std::thread::Builder::new()
            .name("sfc-scan".into())
            .stack_size(64 << 20)
            .spawn(move || thread.run())
            .map_err(|e| format!("cannot start the scan thread: {e}"))?;
        Ok(Runtime { hub, net: Some(net), worker: Some(worker), monitor, modbus, points })
    }

    /// Serves the monitor protocol for an ATMT/EATMT block observed through `source`.
    pub fn start_atmt(model: AtmtModel, source: LineSource, opts: RunOptions) -> Result<Runtime, String> {
        let token = opts.token.clone().unwrap_or_else(random_token);
        let (hub, rx) = Hub::new(model.info(), token);
        let monitor_l = opts.monitor.map(|a| bind("the monitor", a)).transpose()?;
        let monitor = monitor_l.as_ref().and_then(|l| l.local_addr().ok());
        let net = start_net(&hub, None, monitor_l, opts.ctrl_c)?;
        let adapter = atmt::Adapter { model, hub: hub.clone(), source };
        let worker = std::thread::Builder::new()
            .name("sfc-atmt".into())
            .spawn(move || adapter.run(rx))
            .map_err(|e| format!("cannot start the adapter thread: {e}"))?;
        Ok(Runtime { hub, net: Some(net), worker: Some(worker), monitor, modbus: None, points: Arc::new(Vec::new()) })
    }

    /// Where the monitor protocol is served.
    pub fn monitor_addr(&self) -> Option<SocketAddr> {
        self.monitor
    }
    /// Where Modbus TCP is served.
    pub fn modbus_addr(&self) -> Option<SocketAddr> {
        self.modbus
    }
    /// The secret that `force` and `set` need.
    pub fn token(&self) -> &str {
        &self.hub.token
    }
    /// The located variables on the Modbus map.
    pub fn io_points(&self) -> &[IoPoint] {
        &self.points
    }
    /// The latest published scan statistics (`{"scans":…,"jitterUs":{…},…}`).
    pub fn stats_json(&self) -> serde_json::Value {
        self.hub.lock().stats_json()
    }
    /// Asks the run to end (the scan thread stops before its next scan).
    pub fn stop(&self) {
        self.hub.stop.store(true, std::sync::atomic::Ordering::Relaxed);
    }
    /// The run has ended (limit reached, error, watchdog, end of the ATMT input, or stop).
    pub fn is_finished(&self) -> bool {
        self.worker.as_ref().is_none_or(JoinHandle::is_finished)
    }

    /// Waits for the run to end, lets the monitor clients receive the last messages, and shuts
    /// the network down.
    pub fn wait(mut self) -> RunReport {
        let report = self.finish();
        report.unwrap_or_default()
    }

    fn finish(&mut self) -> Option<RunReport> {
        let worker = self.worker.take()?;
        // A stopped ATMT adapter may sit in a read of its input: give it a second, then leave it.
        let mut waited = 0;
        while self.hub.stopping() && !worker.is_finished() && waited < 50 {
            std::thread::sleep(std::time::Duration::from_millis(20));
            waited += 1;
        }
        let mut report = if self.hub.stopping() && !worker.is_finished() {
            RunReport::default()
        } else {
            worker
                .join()
                .unwrap_or_else(|_| RunReport { error: Some("the run's thread panicked".into()), ..Default::default() })
        };
        // Two ticks: every session sends what the end of the run published.
        std::thread::sleep(protocol::TICK * 3);
        self.stop();
        *self.hub.commands.lock().unwrap_or_else(|e| e.into_inner()) = None;
        if let Some(net) = self.net.take() {
            let _ = net.join();
        }
        report.dropped = self.hub.dropped.load(std::sync::atomic::Ordering::Relaxed);
        Some(report)
    }
}

impl Drop for Runtime {
    fn drop(&mut self) {
        self.stop();
        let _ = self.finish();
    }
}
