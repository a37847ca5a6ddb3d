//! `sfc run`: the chart as a soft-PLC on the wall clock (Modbus TCP I/O, monitor protocol), or
//! with `--atmt` the monitor for a REX ATMT/EATMT block running elsewhere.
//! `docs/runtime.md` and `docs/monitor.md` describe both.

use sfc_diagnostics::{render_human, RenderOptions};
use sfc_runtime::{AtmtModel, Limits, LineSource, RunOptions, Runtime};
use sfc_sim::{Profile, SimOptions, Simulation};
use std::io::IsTerminal;
use std::net::{SocketAddr, ToSocketAddrs};
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `sfc run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The chart (IEC text), or with `--atmt` a transition table file or an ATMT/EATMT chart.
    pub file: PathBuf,
    /// The POU to run when the file has several.
    #[arg(long)]
    pub pou: Option<String>,
    /// Scan period (a TIME literal).
    #[arg(long, default_value = "T#10ms")]
    pub period: String,
    /// Stop with an error when one scan takes longer than this (a TIME literal).
    #[arg(long)]
    pub watchdog: Option<String>,
    /// Serve Modbus TCP at this address (e.g. 127.0.0.1:1502); the located variables are the I/O.
    #[arg(long)]
    pub modbus: Option<String>,
    /// Serve the monitor protocol (WebSocket) at this address (e.g. 127.0.0.1:9002).
    #[arg(long)]
    pub monitor: Option<String>,
    /// The secret monitor clients need to force or write variables (default: a random one,
    /// printed at start).
    #[arg(long)]
    pub token: Option<String>,
    /// Stop after this many scans.
    #[arg(long)]
    pub scans: Option<u64>,
    /// Stop after this much wall-clock time (a TIME literal).
    #[arg(long = "for", value_name = "TIME")]
    pub duration: Option<String>,
    /// Start halted: nothing scans until a monitor client sends `continue` or `step`.
    #[arg(long)]
    pub halted: bool,
    /// Run the scan thread with real-time priority (Linux SCHED_FIFO; needs root or CAP_SYS_NICE).
    #[arg(long)]
    pub realtime: bool,
    /// Print the scan statistics at this interval (a TIME literal) while running.
    #[arg(long, value_name = "TIME")]
    pub report: Option<String>,
    /// Monitor a REX ATMT/EATMT block: FILE is its table (`N[…][…]`) or its chart, and the block's
    /// `state condition_bits` lines come from `--atmt-input`.
    #[arg(long)]
    pub atmt: bool,
    /// Where the ATMT lines come from: `-` (standard input) or an address to listen on.
    #[arg(long, default_value = "-", requires = "atmt")]
    pub atmt_input: String,
}

fn time_arg(flag: &str, s: &str) -> Result<Duration, String> {
    match sfc_sim::parse_time(s) {
        Some(t) if t > 0 => Ok(Duration::from_micros(t as u64)),
        Some(_) => Err(format!("`{flag}` must be positive, found `{s}`")),
        None => Err(format!("`{flag}`: `{s}` is not a TIME literal (write e.g. T#10ms)")),
    }
}

fn addr_arg(flag: &str, s: &str) -> Result<SocketAddr, String> {
    s.to_socket_addrs()
        .ok()
        .and_then(|mut a| a.next())
        .ok_or_else(|| format!("`{flag}`: `{s}` is not an address (write e.g. 127.0.0.1:1502)"))
}

/// Runs `sfc run`; returns the exit status (0 done, 1 the run stopped on an error, 2 bad
/// arguments or input).
pub fn run(a: RunArgs) -> u8 {
    match start(&a) {
        Ok(rt) => supervise(rt, &a),
        Err(e) if e.starts_with("error") => {
            eprintln!("{e}");
            2
        }
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}

fn start(a: &RunArgs) -> Result<Runtime, String> {
    let period = time_arg("--period", &a.period)?;
    let limits = Limits {
        scans: a.scans,
        duration: a.duration.as_deref().map(|d| time_arg("--for", d)).transpose()?,
        watchdog: a.watchdog.as_deref().map(|d| time_arg("--watchdog", d)).transpose()?,
    };
    let opts = RunOptions {
        modbus: a.modbus.as_deref().map(|m| addr_arg("--modbus", m)).transpose()?,
        monitor: a.monitor.as_deref().map(|m| addr_arg("--monitor", m)).transpose()?,
        token: a.token.clone(),
        limits,
        halted: a.halted,
        ctrl_c: true,
        realtime: a.realtime,
    };
    let bytes = std::fs::read(&a.file).map_err(|e| format!("error: cannot read `{}`: {e}", a.file.display()))?;
    let text = String::from_utf8(bytes).map_err(|_| format!("error: `{}` is not UTF-8 text", a.file.display()))?;
    let name = a.file.display().to_string();
    let rt = if a.atmt {
        if opts.monitor.is_none() {
            return Err("error: `--atmt` serves the monitor protocol: give `--monitor ADDR`".into());
        }
        let model = if sfc_codegen::atmt::parse_table(text.trim()).is_some() {
            AtmtModel::from_table(&text)
        } else {
            AtmtModel::from_chart(&name, &text, a.pou.as_deref())
        }
        .map_err(|e| format!("error: {e}"))?;
        let source = if a.atmt_input == "-" {
            LineSource::Reader(Box::new(std::io::BufReader::new(std::io::stdin())))
        } else {
            let addr = addr_arg("--atmt-input", &a.atmt_input)?;
            let l = std::net::TcpListener::bind(addr).map_err(|e| format!("error: cannot listen on {addr}: {e}"))?;
            LineSource::Listen(l)
        };
        Runtime::start_atmt(model, source, opts)?
    } else {
        let sim_opts = SimOptions { period: period.as_micros() as i64, profile: Profile::Iec };
        let sim = Simulation::from_source(&name, &text, a.pou.as_deref(), sim_opts).map_err(|(file, diags)| {
            let color = std::io::stderr().is_terminal();
            let mut out: Vec<String> =
                diags.iter().map(|d| render_human(d, std::slice::from_ref(&file), RenderOptions { color })).collect();
            out.push(format!("{} error{} emitted", diags.len(), if diags.len() == 1 { "" } else { "s" }));
            out.join("\n")
        })?;
        Runtime::start(sim, opts).map_err(|e| format!("error: {e}"))?
    };
    Ok(rt)
}

/// Prints where the run serves, waits for its end (limits, error, Ctrl-C) and prints the
/// statistics.
fn supervise(rt: Runtime, a: &RunArgs) -> u8 {
    if let Some(m) = rt.modbus_addr() {
        eprintln!("sfc run: Modbus TCP on {m} ({} located variables)", rt.io_points().len());
    }
    if let Some(m) = rt.monitor_addr() {
        eprintln!("sfc run: monitor on ws://{m}/?token={}", rt.token());
    }
    let every = a.report.as_deref().and_then(|r| time_arg("--report", r).ok());
    let mut last = std::time::Instant::now();
    while !rt.is_finished() {
        std::thread::sleep(Duration::from_millis(50));
        if let Some(e) = every {
            if last.elapsed() >= e {
                last = std::time::Instant::now();
                eprintln!("sfc run: {}", rt.stats_json());
            }
        }
    }
    let report = rt.wait();
    if let Err(e) = &report.realtime {
        eprintln!("warning: {e}");
    }
    if a.atmt {
        eprintln!("sfc run: {} states of the block observed", report.stats.scans);
    } else {
        eprintln!("sfc run: {}", report.stats.summary());
    }
    if report.dropped > 0 {
        eprintln!("sfc run: {} monitor clients dropped (flooding, garbage or too slow)", report.dropped);
    }
    match report.error {
        Some(e) => {
            eprintln!("error: {e}");
            1
        }
        None => 0,
    }
}
