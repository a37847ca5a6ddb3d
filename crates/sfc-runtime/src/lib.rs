//! The soft-PLC of `sfc run`: the chart scanned on the wall clock with the `iec` semantics,
//! Modbus TCP I/O, and the monitor protocol (`docs/monitor.md`); also the ATMT adapter that
//! serves the same protocol for a REX block running elsewhere (`docs/runtime.md`).
//!
//! Threads: the scan thread owns the [`Simulation`] and never waits on the network; a small
//! tokio runtime serves Modbus and the monitor clients. They meet on the [`board::Hub`]. With a
//! watchdog, a supervisor thread watches the scan (`watchdog.rs`); with a retain file, a writer
//! thread keeps it (`retain.rs`).

pub mod access;
pub mod atmt;
pub mod board;
pub mod contract;
pub mod io;
pub mod jitter;
pub mod modbus;
#[cfg(feature = "opcua")]
pub mod opcua;
pub mod protocol;
pub mod retain;
pub mod safe;
pub mod scan;
pub mod watchdog;

use board::{ChartInfo, Hub, RunState, VarInfo};
use io::{Image, IoPoint, WordOrder};
use jitter::ScanStats;
use sfc_sim::{Simulation, Value};
use std::net::SocketAddr;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

pub use access::MonitorAccess;
pub use atmt::{AtmtModel, LineSource};
pub use modbus::ModbusLimits;
pub use retain::RetainOptions;
pub use scan::Limits;

/// A variable's memory slot in the simulation, with its type.
#[derive(Debug, Clone, PartialEq)]
pub struct Slot {
    pub index: usize,
    pub ty: sfc_st::Type,
}

impl Slot {
    /// The value of a fresh input of this type (FALSE, 0 or 0.0).
    pub fn default_value(&self) -> Value {
        match self.ty.base() {
            sfc_st::Type::Bool => Value::Bool(false),
            t if t.is_real() => Value::Real(0.0),
            _ => Value::Int(0),
        }
    }
}

/// How to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Serve Modbus TCP here (port 0 picks a free port).
    pub modbus: Option<SocketAddr>,
    /// Connections and idle timeout of the Modbus server.
    pub modbus_limits: ModbusLimits,
    /// Register order of 32- and 64-bit values on Modbus.
    pub word_order: WordOrder,
    /// Holding register and coil 40000 reset the chart (`--modbus-reset`; off by default:
    /// Modbus has no authentication).
    pub modbus_reset: bool,
    /// Serve the monitor protocol here.
    pub monitor: Option<SocketAddr>,
    /// Which web pages (`Origin`) and host names (`Host`) the monitor accepts.
    pub monitor_access: MonitorAccess,
    /// The secret for `force`/`set`; a random one when `None`.
    pub token: Option<String>,
    pub limits: Limits,
    /// Safe values given by the run configuration (`NAME`, value text), over the chart's.
    pub safe: Vec<(String, String)>,
    /// Keep RETAIN/PERSISTENT values in this file.
    pub retain: Option<RetainOptions>,
    /// After a fault, wait in FAULT for a monitor `reset` instead of ending the run.
    pub wait_in_fault: bool,
    /// Start halted (nothing scans until `continue` or `step`).
    pub halted: bool,
    /// Run the scan thread with real-time priority (Linux `SCHED_FIFO` 50; needs root or
    /// CAP_SYS_NICE; [`RunReport::realtime`] says whether it was granted).
    pub realtime: bool,
    /// Serve OPC UA (`docs/runtime.md`, "OPC UA"); needs the cargo feature `opcua`.
    pub opcua: Option<OpcuaOptions>,
    /// End the run in order on Ctrl-C (SIGINT) and SIGTERM instead of letting them kill the
    /// process, so the outputs go to their safe values and the caller still gets the report.
    pub ctrl_c: bool,
}

/// The OPC UA server of a run.
#[derive(Debug, Clone)]
pub struct OpcuaOptions {
    /// Where to listen (port 0 picks a free port).
    pub addr: SocketAddr,
    /// Offer SecurityPolicy None with anonymous read/write access (loopback only).
    pub allow_none: bool,
    /// Anonymous sessions may read (not write) on the secure endpoints.
    pub anonymous_read: bool,
    /// The PKI folder: `own/cert.der` and `private/private.pem` (made on first start),
    /// `trusted/` and `rejected/` client certificates.
    pub pki_dir: std::path::PathBuf,
    pub users: Vec<OpcuaUser>,
    /// The shortest publishing and sampling interval granted (`--opcua-min-publish`, default
    /// 10 ms): a client asking for less gets this.
    pub min_publish: std::time::Duration,
}

/// A user of the OPC UA server (`[[opcua.user]]`).
#[derive(Debug, Clone)]
pub struct OpcuaUser {
    pub name: String,
    /// An argon2 PHC string (`sfc run --hash-password`).
    pub password_hash: String,
    pub role: OpcuaRole,
}

/// What an OPC UA user may do (`role` of `[[opcua.user]]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum OpcuaRole {
    /// Read and subscribe.
    Read,
    /// Also write inputs and memory.
    Operate,
    /// Also call Halt, Continue and Reset.
    Admin,
}

impl OpcuaRole {
    pub fn from_name(s: &str) -> Option<OpcuaRole> {
        match s {
            "read" => Some(OpcuaRole::Read),
            "operate" => Some(OpcuaRole::Operate),
            "admin" => Some(OpcuaRole::Admin),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            OpcuaRole::Read => "read",
            OpcuaRole::Operate => "operate",
            OpcuaRole::Admin => "admin",
        }
    }
}

impl OpcuaOptions {
    /// Whether some OPC UA user may call Halt, Continue and Reset.
    pub fn can_control(&self) -> bool {
        self.users.iter().any(|u| u.role == OpcuaRole::Admin)
    }
}

/// What keeps serving in FAULT and the ways this run has to restart the chart (the end of the
/// FAULT line; `docs/runtime.md`, "Ways out of FAULT").
fn fault_ways(opts: &RunOptions, pou: &str) -> String {
    let mut serving = Vec::new();
    let mut ways = Vec::new();
    if opts.modbus.is_some() {
        serving.push("Modbus");
    }
    if opts.opcua.is_some() {
        serving.push("OPC UA");
    }
    if opts.monitor.is_some() {
        serving.push("the monitor");
        ways.push("a monitor `reset`".to_string());
    }
    if opts.opcua.as_ref().is_some_and(OpcuaOptions::can_control) {
        ways.push(format!("the OPC UA method {pou}/Runtime/Reset (a user of role admin)"));
    }
    if opts.modbus.is_some() && opts.modbus_reset {
        ways.push(format!(
            "Modbus holding register {a} := 1 (warm) or 2 (cold), or coil {a} := TRUE",
            a = io::RESET_ADDRESS
        ));
    }
    let serving = match serving.as_slice() {
        [] => String::new(),
        [one] => format!("{one} keeps serving; "),
        [init @ .., last] => format!("{} and {last} keep serving; ", init.join(", ")),
    };
    let ways = match ways.as_slice() {
        [] => "nothing in this run can restart the chart (no monitor, no OPC UA user of role admin, no \
               --modbus-reset): stop sfc run and start it again"
            .to_string(),
        [one] => format!("to restart the chart: {one}"),
        [init @ .., last] => format!("to restart the chart: {} or {last}", init.join(", ")),
    };
    format!("{serving}{ways}")
}

/// Whether this build has the OPC UA server (cargo feature `opcua`).
pub const OPCUA: bool = cfg!(feature = "opcua");

/// How a run ended.
#[derive(Debug, Clone)]
pub struct RunReport {
    pub stats: ScanStats,
    /// The fault the run ended in: a runtime error of the chart, or the watchdog.
    pub error: Option<String>,
    /// The state it ended in: STOP, or FAULT.
    pub state: RunState,
    /// The Modbus server's counters (`null` without Modbus).
    pub modbus: serde_json::Value,
    /// Lines for the operator not yet taken with [`Runtime::notices`].
    pub notices: Vec<String>,
    /// Monitor clients dropped for flooding, garbage or reading too slowly.
    pub dropped: u64,
    /// The scan thread ran with real-time priority; `Err` says why it was asked for and
    /// refused (`Ok(false)`: not asked for).
    pub realtime: Result<bool, String>,
}

impl Default for RunReport {
    fn default() -> Self {
        RunReport {
            stats: ScanStats::default(),
            error: None,
            state: RunState::Stop,
            modbus: serde_json::Value::Null,
            notices: Vec::new(),
            dropped: 0,
            realtime: Ok(false),
        }
    }
}

/// A running soft-PLC (or ATMT adapter).
pub struct Runtime {
    hub: Arc<Hub>,
    net: Option<JoinHandle<()>>,
    worker: Option<JoinHandle<RunReport>>,
    supervisor: Option<JoinHandle<()>>,
    monitor: Option<SocketAddr>,
    modbus: Option<SocketAddr>,
    opcua: Option<SocketAddr>,
    points: Arc<Vec<IoPoint>>,
    /// The simulation's interrupt flag: set on stop, so a scan that runs away still ends.
    interrupt: Option<Arc<std::sync::atomic::AtomicBool>>,
    counters: Option<Arc<modbus::ModbusCounters>>,
    safe: Arc<safe::SafeState>,
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
/// A bound Modbus listener with what it serves.
struct ModbusSide {
    listener: std::net::TcpListener,
    service: Arc<modbus::Service>,
    limits: ModbusLimits,
    counters: Arc<modbus::ModbusCounters>,
}

#[cfg(feature = "opcua")]
type OpcuaSide = opcua::Side;
#[cfg(not(feature = "opcua"))]
type OpcuaSide = ();

/// Checks the OPC UA options, binds the endpoint and builds the server (before any scan).
fn opcua_side(hub: &Arc<Hub>, o: Option<&OpcuaOptions>) -> Result<(Option<OpcuaSide>, Option<SocketAddr>), String> {
    let Some(o) = o else { return Ok((None, None)) };
    #[cfg(feature = "opcua")]
    {
        opcua::check(o)?;
        let l = bind("OPC UA", o.addr)?;
        let addr = l.local_addr().ok();
        let side = opcua::build(hub, o, l)?;
        hub.guards_always.store(true, Ordering::Relaxed);
        hub.step_times.store(true, Ordering::Relaxed);
        Ok((Some(side), addr))
    }
    #[cfg(not(feature = "opcua"))]
    {
        let _ = (hub, o);
        Err("this sfc was built without OPC UA (cargo feature `opcua`)".into())
    }
}

/// The handlers of SIGINT and SIGTERM, installed before the run says it is ready: a signal
/// that comes right after start (systemd stopping a unit at once, a test) still stops the run
/// in order instead of killing the process with its outputs as they were.
struct Signals {
    #[cfg(unix)]
    int: tokio::signal::unix::Signal,
    #[cfg(unix)]
    term: tokio::signal::unix::Signal,
}

impl Signals {
    /// Installs the handlers (inside the network runtime's context).
    fn install(net: &tokio::runtime::Runtime, hub: &Hub) -> Option<Signals> {
        let _context = net.enter();
        #[cfg(unix)]
        {
            use tokio::signal::unix::{signal, SignalKind};
            match (signal(SignalKind::interrupt()), signal(SignalKind::terminate())) {
                (Ok(int), Ok(term)) => Some(Signals { int, term }),
                _ => {
                    hub.notice(
                        "warning: cannot catch SIGINT and SIGTERM: they end the process without an orderly stop",
                    );
                    None
                }
            }
        }
        #[cfg(not(unix))]
        {
            let _ = hub;
            Some(Signals {})
        }
    }
}

/// Ends the run when SIGINT or SIGTERM arrives (SIGTERM is what systemd and `kill` send).
async fn stop_on_signals(signals: Signals, hub: Arc<Hub>) {
    #[cfg(unix)]
    {
        let Signals { mut int, mut term } = signals;
        let name = tokio::select! {
            _ = int.recv() => "SIGINT",
            _ = term.recv() => "SIGTERM",
        };
        hub.notice(format!("sfc run: {name}: stopping in order"));
    }
    #[cfg(not(unix))]
    {
        let Signals {} = signals;
        if tokio::signal::ctrl_c().await.is_err() {
            return;
        }
        hub.notice("sfc run: Ctrl-C: stopping in order");
    }
    hub.stop.store(true, std::sync::atomic::Ordering::Relaxed);
    hub.interrupt();
}

/// The tokio runtime of the network side (two worker threads).
fn net_runtime() -> Result<tokio::runtime::Runtime, String> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("sfc-net")
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the network threads: {e}"))
}

fn start_net(
    net: tokio::runtime::Runtime,
    hub: &Arc<Hub>,
    modbus: Option<ModbusSide>,
    monitor: Option<(std::net::TcpListener, MonitorAccess)>,
    opcua: Option<OpcuaSide>,
    ctrl_c: bool,
) -> Result<JoinHandle<()>, String> {
    let hub = hub.clone();
    let signals = if ctrl_c { Signals::install(&net, &hub) } else { None };
    #[cfg(feature = "opcua")]
    let opcua = match opcua {
        Some(side) => Some(opcua::spawn(side, hub.clone())?),
        None => None,
    };
    std::thread::Builder::new()
        .name("sfc-net-main".into())
        .spawn(move || {
            net.block_on(async {
                if let Some(m) = modbus {
                    tokio::spawn(modbus::serve(m.listener, m.service, m.limits, m.counters, hub.clone()));
                }
                if let Some((l, access)) = monitor {
                    tokio::spawn(protocol::serve(l, hub.clone(), Arc::new(access)));
                }
                if let Some(signals) = signals {
                    tokio::spawn(stop_on_signals(signals, hub.clone()));
                }
                while !hub.closing() {
                    tokio::time::sleep(std::time::Duration::from_millis(20)).await;
                }
                // Every session now sends what the end of the run published and closes its
                // connection (flushing for at most a second); shutting the runtime down before
                // that would cancel them and lose the end. Bounded for clients that never read.
                let deadline = tokio::time::Instant::now() + std::time::Duration::from_secs(3);
                while hub.sessions.load(Ordering::Relaxed) > 0 && tokio::time::Instant::now() < deadline {
                    tokio::time::sleep(std::time::Duration::from_millis(10)).await;
                }
            });
            net.shutdown_timeout(std::time::Duration::from_secs(1));
            // The OPC UA thread ends once the run closes (its server is cancelled then).
            #[cfg(feature = "opcua")]
            if let Some(t) = opcua {
                let _ = t.join();
            }
            #[cfg(not(feature = "opcua"))]
            let _ = opcua;
        })
        .map_err(|e| format!("cannot start the network threads: {e}"))
}

impl Runtime {
    /// Starts scanning `sim` (its period is the scan period) with the I/O and monitor of `opts`.
    /// Errors: a located variable the Modbus map does not cover (with `modbus`), a safe value
    /// that does not fit its variable, a thread that cannot be started, or an address that
    /// cannot be bound. A retain file that cannot be written is a warning among the notices (the
    /// run still starts).
    pub fn start(mut sim: Simulation, opts: RunOptions) -> Result<Runtime, String> {
        let points = Arc::new(if opts.modbus.is_some() { io::map_located(&sim)? } else { Vec::new() });
        if opts.modbus_reset {
            // The reset register and coil lie in the inputs' window: an input there would be
            // unreachable.
            let at = io::RESET_ADDRESS - io::INPUT_WINDOW;
            if let Some(p) = points.iter().find(|p| {
                matches!(p.table, io::Table::DiscreteInput | io::Table::InputRegister)
                    && p.address <= at
                    && at < p.address + p.words.max(1)
            }) {
                return Err(format!(
                    "`{}` {} is written through {} {}, which --modbus-reset takes for the reset \
                     (docs/runtime.md, \"Ways out of FAULT\")",
                    p.name,
                    p.location,
                    if p.table == io::Table::DiscreteInput { "coil" } else { "holding register" },
                    io::RESET_ADDRESS
                ));
            }
        }
        let safe = Arc::new(safe::safe_state(&sim, &points, &opts.safe)?);
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
            let section = board::Section::of(sim.declared_kind(&name), location.as_deref());
            variables.push(VarInfo { name, ty, location, safe: safe.of_slot(index).cloned(), section });
            vars.push(Slot { index, ty: t });
        }
        let var_point = vars.iter().map(|s| points.iter().position(|p| p.slot.index == s.index)).collect();
        let (steps, transitions) = sim.outline();
        let post = transitions.iter().map(|t| t.2.clone()).collect();
        let initial = steps.iter().enumerate().filter(|s| s.1 .1).map(|s| s.0 as u32).collect();
        let info = ChartInfo {
            runtime: "sfc run",
            profile: Some(sim.options().profile.name()),
            pou: sim.pou_name().to_string(),
            period: sim.options().period,
            steps,
            transitions,
            variables,
            control: true,
            charts: sim.chart_outline(),
            actions: sim.action_outline(),
        };
        let fault_ways = fault_ways(&opts, &info.pou);
        if opts.halted && opts.monitor.is_none() && !opts.opcua.as_ref().is_some_and(OpcuaOptions::can_control) {
            return Err("--halted waits for a `continue`, and nothing in this run can send one: serve the monitor \
                        (--monitor ADDR) or OPC UA with a user of role admin ([[opcua.user]] role = \"admin\")"
                .into());
        }
        let token = opts.token.clone().unwrap_or_else(random_token);
        let (hub, rx) = Hub::new(info, token);
        if opts.halted {
            // Before any client can connect: the first `hello` already says halted.
            hub.lock().push_halt(true, "halt".into());
        }
        // Retentive values: restored before the first scan, then kept by the writer thread.
        let leaves = sim.retained();
        let writer = match &opts.retain {
            Some(r) => {
                let (lines, writable) = retain::start(&mut sim, &leaves, r);
                for line in lines {
                    hub.notice(line);
                }
                let pou = sim.pou_name().to_string();
                let h = hub.clone();
                let w =
                    retain::Writer::start(r.path.clone(), pou, leaves.clone(), writable, move |line| h.notice(line))
                        .map_err(|e| format!("cannot start the retain writer: {e}"))?;
                Some(w)
            }
            None => None,
        };
        let interrupt = sim.interrupt_flag();
        let _ = hub.interrupt_flag.set(interrupt.clone());
        // Outputs and `%M` read their declared (or restored) values before the first scan has
        // copied them out, not zeros: a client that connects at once sees what the chart holds.
        let mut first_image = Image::new(&points, opts.word_order);
        for p in points.iter().filter(|p| p.role != io::Role::Input) {
            if let Some(v) = sim.read_slot(p.slot.index) {
                first_image.put(p, v);
            }
        }
        let image = Arc::new(Mutex::new(first_image));
        let modbus_l = opts.modbus.map(|a| bind("Modbus", a)).transpose()?;
        let monitor_l = opts.monitor.map(|a| bind("the monitor", a)).transpose()?;
        let modbus = modbus_l.as_ref().and_then(|l| l.local_addr().ok());
        let monitor = monitor_l.as_ref().and_then(|l| l.local_addr().ok());
        let counters = modbus_l.as_ref().map(|_| Arc::new(modbus::ModbusCounters::default()));
        let modbus_side = match (modbus_l, &counters) {
            (Some(listener), Some(c)) => Some(ModbusSide {
                listener,
                service: Arc::new(modbus::Service {
                    points: points.clone(),
                    image: image.clone(),
                    reset: opts.modbus_reset.then(|| hub.clone()),
                }),
                limits: opts.modbus_limits,
                counters: c.clone(),
            }),
            _ => None,
        };
        let net_rt = net_runtime()?;
        // The OPC UA server is built inside the network runtime (it starts tasks of its own).
        let (opcua_side, opcua) = {
            let _inside = net_rt.enter();
            opcua_side(&hub, opts.opcua.as_ref())?
        };
        let net = start_net(
            net_rt,
            &hub,
            modbus_side,
            monitor_l.map(|l| (l, opts.monitor_access.clone())),
            opcua_side,
            opts.ctrl_c,
        )?;
        let clock = Arc::new(watchdog::ScanClock::new());
        let supervisor = match opts.limits.watchdog {
            Some(w) => {
                let s = watchdog::Supervisor {
                    clock: clock.clone(),
                    watchdog: w,
                    interrupt: interrupt.clone(),
                    hub: hub.clone(),
                    image: image.clone(),
                    points: points.clone(),
                    safe: safe.clone(),
                };
                Some(
                    std::thread::Builder::new()
                        .name("sfc-watchdog".into())
                        .spawn(move || s.run())
                        .map_err(|e| format!("cannot start the watchdog thread: {e}"))?,
                )
            }
            None => None,
        };
        let retain_interval = opts.retain.as_ref().map_or(std::time::Duration::from_secs(1), |r| r.interval);
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
            wait_in_fault: opts.wait_in_fault,
            safe: safe.clone(),
            clock,
            interrupt: interrupt.clone(),
            retain: scan::RetainRun {
                leaves,
                writer,
                interval: retain_interval,
                next: std::time::Instant::now() + retain_interval,
            },
            state: RunState::Run,
            fault: None,
            reanchor: false,
            restarted: true,
            since_key: u64::MAX,
            check: Default::default(),
            inputs: Vec::new(),
            forced: Vec::new(),
            pending_sets: Vec::new(),
            breakpoints: Default::default(),
            stats: ScanStats::default(),
            unpublished_states: Default::default(),
            spare_states: Vec::new(),
            unpublished_events: Vec::new(),
            halt_change: Vec::new(),
            last_state: None,
            unpublished_errors: None,
            steps_requested: Vec::new(),
            records: 0,
            unwritten_record: None,
            fault_code: 0,
            faults: 0,
            fault_ways,
            status_written: None,
        };
        // The simulator may recurse deeply in user code: the same stack as the CLI's.
        let worker = std::thread::Builder::new()
            .name("sfc-scan".into())
            .stack_size(64 << 20)
            .spawn(move || thread.run())
            .map_err(|e| format!("cannot start the scan thread: {e}"))?;
        Ok(Runtime {
            hub,
            net: Some(net),
            worker: Some(worker),
            supervisor,
            monitor,
            modbus,
            opcua,
            points,
            interrupt: Some(interrupt),
            counters,
            safe,
        })
    }

    /// Serves the monitor protocol for an ATMT/EATMT block observed through `source`.
    pub fn start_atmt(model: AtmtModel, source: LineSource, opts: RunOptions) -> Result<Runtime, String> {
        let token = opts.token.clone().unwrap_or_else(random_token);
        let (hub, rx) = Hub::new(model.info(), token);
        let monitor_l = opts.monitor.map(|a| bind("the monitor", a)).transpose()?;
        let monitor = monitor_l.as_ref().and_then(|l| l.local_addr().ok());
        if opts.opcua.is_some() {
            return Err("OPC UA is served by `sfc run` of a chart, not by the ATMT adapter".into());
        }
        let net = start_net(
            net_runtime()?,
            &hub,
            None,
            monitor_l.map(|l| (l, opts.monitor_access.clone())),
            None,
            opts.ctrl_c,
        )?;
        let adapter = atmt::Adapter { model, hub: hub.clone(), source };
        let worker = std::thread::Builder::new()
            .name("sfc-atmt".into())
            .spawn(move || adapter.run(rx))
            .map_err(|e| format!("cannot start the adapter thread: {e}"))?;
        Ok(Runtime {
            hub,
            net: Some(net),
            worker: Some(worker),
            supervisor: None,
            monitor,
            modbus: None,
            opcua: None,
            points: Arc::new(Vec::new()),
            interrupt: None,
            counters: None,
            safe: Arc::new(safe::SafeState::default()),
        })
    }

    /// Where the monitor protocol is served.
    pub fn monitor_addr(&self) -> Option<SocketAddr> {
        self.monitor
    }
    /// Where Modbus TCP is served.
    pub fn modbus_addr(&self) -> Option<SocketAddr> {
        self.modbus
    }
    /// Where OPC UA is served.
    pub fn opcua_addr(&self) -> Option<SocketAddr> {
        self.opcua
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
    /// One reading of the process image ([`Hub::image`]): what Modbus, OPC UA and the monitor show.
    pub fn image(&self) -> board::ImageView {
        self.hub.image()
    }
    /// What the run runs: its POU, steps, variables.
    pub fn info(&self) -> &ChartInfo {
        &self.hub.info
    }
    /// Asks the run to end in order: the scan thread stops before its next scan, and a scan
    /// running away is interrupted.
    pub fn stop(&self) {
        self.hub.stop.store(true, Ordering::Relaxed);
        if let Some(i) = &self.interrupt {
            i.store(true, Ordering::Relaxed);
        }
    }
    /// Lines for the operator since the last call (watchdog, faults, retain, servers).
    pub fn notices(&self) -> Vec<String> {
        self.hub.take_notices()
    }
    /// RUN, STOP or FAULT, with the fault.
    pub fn state(&self) -> (RunState, Option<serde_json::Value>) {
        let b = self.hub.lock();
        (b.state, b.fault.clone())
    }
    /// The safe values of the run.
    pub fn safe_state(&self) -> &safe::SafeState {
        &self.safe
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
            // A panic of the scan thread is a fault of the runtime itself: said, and the run
            // ends as FAULT (not as an orderly stop).
            worker.join().unwrap_or_else(|_| {
                let msg = "the scan thread panicked (a defect of sfc: please report it with the chart)";
                self.hub.notice(format!("sfc run: FAULT: {msg}"));
                RunReport { error: Some(msg.into()), state: RunState::Fault, ..Default::default() }
            })
        };
        // The sessions send what the end of the run published once they see `closing`, and
        // the network thread waits for them (`start_net`).
        self.stop();
        self.hub.closing.store(true, Ordering::Relaxed);
        *self.hub.commands.lock().unwrap_or_else(|e| e.into_inner()) = None;
        if let Some(net) = self.net.take() {
            let _ = net.join();
        }
        report.dropped = self.hub.dropped.load(Ordering::Relaxed);
        if let Some(c) = &self.counters {
            report.modbus = c.to_json();
        }
        if let Some(s) = self.supervisor.take() {
            let _ = s.join();
        }
        report.notices = self.hub.take_notices();
        Some(report)
    }
}

impl Drop for Runtime {
    fn drop(&mut self) {
        self.stop();
        let _ = self.finish();
    }
}
