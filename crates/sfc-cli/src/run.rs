//! `sfc run`: the chart as a soft-PLC on the wall clock (Modbus TCP I/O, monitor protocol), or
//! with `--atmt` the monitor for a REX ATMT/EATMT block running elsewhere.
//! `docs/runtime.md` and `docs/monitor.md` describe both.

use crate::run_config::{self, RunConfig};
use sfc_diagnostics::{render_human, RenderOptions};
use sfc_runtime::board::RunState;
use sfc_runtime::io::WordOrder;
use sfc_runtime::{AtmtModel, Limits, LineSource, ModbusLimits, MonitorAccess, RetainOptions, RunOptions, Runtime};
use sfc_sim::{Profile, SimOptions, Simulation};
use std::io::IsTerminal;
use std::net::{SocketAddr, ToSocketAddrs};
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `sfc run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The chart (IEC text), or with `--atmt` a transition table file or an ATMT/EATMT chart
    /// (may come from the run configuration's `chart`).
    pub file: Option<PathBuf>,
    /// A run configuration (TOML): period, watchdog, Modbus, monitor, retain, safe values …
    /// Options on the command line win over it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// The POU to run when the file has several.
    #[arg(long)]
    pub pou: Option<String>,
    /// Scan period (a TIME literal; default T#10ms).
    #[arg(long, value_name = "TIME")]
    pub period: Option<String>,
    /// Whose execution rules to follow: iec, matiec, codesys, grafcet, logix or graph (default iec; codesys
    /// for a CODESYS, TwinCAT or e!COCKPIT export, with a note saying so).
    #[arg(long, value_name = "PROFILE", value_parser = parse_profile)]
    pub profile: Option<Profile>,
    /// Stop a scan that runs longer than this (a TIME literal) and enter FAULT: outputs at
    /// their safe values until a monitor `reset`.
    #[arg(long, value_name = "TIME")]
    pub watchdog: Option<String>,
    /// Serve Modbus TCP at this address (e.g. 127.0.0.1:1502); the located variables are the I/O.
    #[arg(long, value_name = "ADDR")]
    pub modbus: Option<String>,
    /// Most Modbus connections served at once (default 32).
    #[arg(long, value_name = "N")]
    pub modbus_max_clients: Option<usize>,
    /// Close a Modbus connection idle this long (a TIME literal; default T#60s).
    #[arg(long, value_name = "TIME")]
    pub modbus_idle_timeout: Option<String>,
    /// Register order of 32- and 64-bit values on Modbus: big (high word first, default) or
    /// little.
    #[arg(long, value_name = "ORDER")]
    pub word_order: Option<String>,
    /// Let Modbus clients restart the chart: holding register 40000 := 1 (warm) or 2 (cold),
    /// coil 40000 := TRUE (warm). Off by default: Modbus has no authentication.
    #[arg(long)]
    pub modbus_reset: bool,
    /// Serve the monitor protocol (WebSocket) at this address (e.g. 127.0.0.1:9002).
    #[arg(long, value_name = "ADDR")]
    pub monitor: Option<String>,
    /// Serve OPC UA at this endpoint (e.g. opc.tcp://127.0.0.1:4840; port 0 picks a free one).
    #[arg(long, value_name = "URL")]
    pub opcua: Option<String>,
    /// Also offer SecurityPolicy None, anonymous with read and write access (loopback only:
    /// for local tools and tests).
    #[arg(long)]
    pub opcua_allow_none: bool,
    /// The OPC UA PKI folder: the server's certificate (made on first start), trusted and
    /// rejected client certificates (default: $XDG_DATA_HOME/sfc/opcua-pki).
    #[arg(long, value_name = "DIR")]
    pub opcua_pki: Option<PathBuf>,
    /// The shortest OPC UA publishing and sampling interval granted (a TIME literal; default
    /// T#10ms): a client asking for less gets this.
    #[arg(long, value_name = "TIME")]
    pub opcua_min_publish: Option<String>,
    /// Read a password on standard input, print its argon2 hash for `[[opcua.user]]`, and exit.
    #[arg(long)]
    pub hash_password: bool,
    /// A file holding the secret monitor clients need to change the run (default: the
    /// environment variable SFC_TOKEN, else a random one printed at start).
    #[arg(long, value_name = "FILE")]
    pub token_file: Option<PathBuf>,
    /// Refused: a token on the command line is visible to every local user.
    #[arg(long, hide = true, value_name = "SECRET")]
    pub token: Option<String>,
    /// A web page origin the monitor accepts (repeatable; default: pages served from
    /// loopback, as the editor's).
    #[arg(long, value_name = "ORIGIN")]
    pub allow_origin: Vec<String>,
    /// Keep RETAIN/PERSISTENT values in this file (default: beside the chart, `<chart>.retain`).
    #[arg(long, value_name = "PATH")]
    pub retain: Option<PathBuf>,
    /// Keep no retain file.
    #[arg(long, conflicts_with = "retain")]
    pub no_retain: bool,
    /// Write the retain file at most this often, when a value changed (default T#1s).
    #[arg(long, value_name = "TIME")]
    pub retain_interval: Option<String>,
    /// Cold start: only PERSISTENT values are restored (RETAIN ones start from their initial
    /// values).
    #[arg(long)]
    pub cold: bool,
    /// The safe value of a variable (repeatable), e.g. `--safe Blower=TRUE`.
    #[arg(long = "safe", value_name = "NAME=VALUE", value_parser = crate::sim::parse_set)]
    pub safe: Vec<(String, String)>,
    /// After a fault: `wait` in FAULT for a monitor `reset` (the default when Modbus or the
    /// monitor serves) or `exit` with status 1.
    #[arg(long, value_name = "WHAT")]
    pub on_fault: Option<String>,
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
    /// Print the state, the outputs and the scan statistics at this interval (a TIME literal)
    /// while running.
    #[arg(long, value_name = "TIME")]
    pub report: Option<String>,
    /// How `--report` prints: `text` (one line for the operator, default) or `json` (one JSON
    /// object per line, for a log collector).
    #[arg(long, value_name = "FORMAT", requires = "report")]
    pub report_format: Option<String>,
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

/// `opc.tcp://host:port[/path]` (or `host:port`) as a socket address.
fn opcua_arg(s: &str) -> Result<SocketAddr, String> {
    let rest = s.strip_prefix("opc.tcp://").unwrap_or(s);
    let hostport = rest.split('/').next().unwrap_or(rest);
    addr_arg("--opcua", hostport)
        .map_err(|_| format!("`--opcua`: `{s}` is not an OPC UA endpoint (write e.g. opc.tcp://127.0.0.1:4840)"))
}

/// The default PKI folder: `$XDG_DATA_HOME/sfc/opcua-pki` (or `~/.local/share/sfc/opcua-pki`).
fn default_pki() -> PathBuf {
    let data = std::env::var_os("XDG_DATA_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/share")))
        .unwrap_or_else(|| PathBuf::from("."));
    data.join("sfc").join("opcua-pki")
}

/// `sfc run --hash-password`: the password from standard input (never the command line).
fn hash_password() -> u8 {
    if !sfc_runtime::OPCUA {
        eprintln!("error: this sfc was built without OPC UA (cargo feature `opcua`)");
        return 2;
    }
    if std::io::stdin().is_terminal() {
        eprintln!("sfc run: type the password and press Enter (it is echoed: pipe it in to hide it)");
    }
    let mut line = String::new();
    if let Err(e) = std::io::stdin().read_line(&mut line) {
        eprintln!("error: cannot read the password: {e}");
        return 2;
    }
    let password = line.trim_end_matches(['\n', '\r']);
    if password.is_empty() {
        eprintln!("error: empty password on standard input");
        return 2;
    }
    #[cfg(feature = "opcua")]
    match sfc_runtime::opcua::hash_password(password) {
        Ok(h) => {
            println!("{h}");
            return 0;
        }
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    }
    #[allow(unreachable_code)]
    2
}

/// Where the monitor's token came from.
enum TokenSource {
    Random,
    Env,
    File(PathBuf),
}

/// The token: `--token-file` (or the configuration's), else `SFC_TOKEN`, else a random one.
fn token_of(a: &RunArgs, cfg: &RunConfig) -> Result<(Option<String>, TokenSource), String> {
    if a.token.is_some() {
        return Err("`--token` is not accepted: a secret on the command line is visible to every local user \
             (ps, /proc/PID/cmdline). Put it in the environment variable SFC_TOKEN, or in a file named by \
             --token-file (or `token_file` in [monitor] of the run configuration)"
            .into());
    }
    if let Some(path) = a.token_file.as_ref().or(cfg.monitor.token_file.as_ref()) {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read the token file `{}`: {e}", path.display()))?;
        let t = text.trim().to_string();
        if t.is_empty() {
            return Err(format!("the token file `{}` is empty", path.display()));
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            if std::fs::metadata(path).is_ok_and(|m| m.permissions().mode() & 0o077 != 0) {
                eprintln!("warning: the token file `{}` can be read by other users (chmod 600 it)", path.display());
            }
        }
        return Ok((Some(t), TokenSource::File(path.clone())));
    }
    match std::env::var("SFC_TOKEN") {
        Ok(t) if !t.trim().is_empty() => Ok((Some(t.trim().to_string()), TokenSource::Env)),
        _ => Ok((None, TokenSource::Random)),
    }
}

/// Runs `sfc run`; returns the exit status (0 done, 1 the run ended in FAULT, 2 bad arguments
/// or input).
pub fn run(a: RunArgs) -> u8 {
    if a.hash_password {
        return hash_password();
    }
    match start(&a) {
        Ok((rt, source)) => supervise(rt, &a, &source),
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

fn start(a: &RunArgs) -> Result<(Runtime, TokenSource), String> {
    let cfg = match &a.config {
        Some(p) => run_config::load(p)?,
        None => RunConfig::default(),
    };
    let file = a
        .file
        .clone()
        .or_else(|| cfg.chart.clone())
        .ok_or("no chart to run: name the chart file (`sfc run FILE`), or give `chart` in the run configuration")?;
    let period = time_arg("--period", a.period.as_deref().or(cfg.period.as_deref()).unwrap_or("T#10ms"))?;
    let limits = Limits {
        scans: a.scans,
        duration: a.duration.as_deref().map(|d| time_arg("--for", d)).transpose()?,
        watchdog: a.watchdog.as_deref().or(cfg.watchdog.as_deref()).map(|d| time_arg("--watchdog", d)).transpose()?,
    };
    let modbus = a.modbus.as_deref().or(cfg.modbus.address.as_deref()).map(|m| addr_arg("--modbus", m)).transpose()?;
    let monitor =
        a.monitor.as_deref().or(cfg.monitor.address.as_deref()).map(|m| addr_arg("--monitor", m)).transpose()?;
    let opcua_at = a.opcua.as_deref().or(cfg.opcua.endpoint.as_deref());
    let opcua = match opcua_at {
        None => {
            if a.opcua_allow_none {
                return Err("`--opcua-allow-none` needs an OPC UA endpoint (`--opcua URL`)".into());
            }
            None
        }
        Some(url) => Some(sfc_runtime::OpcuaOptions {
            addr: opcua_arg(url)?,
            allow_none: a.opcua_allow_none || cfg.opcua.allow_none == Some(true),
            anonymous_read: cfg.opcua.anonymous_read == Some(true),
            pki_dir: a.opcua_pki.clone().or_else(|| cfg.opcua.pki_dir.clone()).unwrap_or_else(default_pki),
            users: cfg
                .opcua
                .users
                .iter()
                .map(|u| sfc_runtime::OpcuaUser {
                    name: u.name.clone(),
                    password_hash: u.password_hash.clone(),
                    role: u.role.unwrap_or_else(|| {
                        // What every user could do before roles existed, said so it is a choice.
                        eprintln!(
                            "warning: {}: [[opcua.user]] `{}` has no `role`: admin (writes inputs, calls Halt, \
                             Continue and Reset), as before roles existed; give role = \"read\", \"operate\" or \"admin\"",
                            cfg.file.display(),
                            u.name
                        );
                        sfc_runtime::OpcuaRole::Admin
                    }),
                })
                .collect(),
            min_publish: match &a.opcua_min_publish {
                Some(t) => time_arg("--opcua-min-publish", t)?,
                None => cfg.opcua.min_publish.unwrap_or(Duration::from_millis(10)),
            },
        }),
    };
    if opcua.is_none() && a.opcua_min_publish.is_some() {
        return Err("`--opcua-min-publish` needs an OPC UA endpoint (`--opcua URL`)".into());
    }
    if modbus.is_none() && (a.modbus_reset || cfg.modbus.reset == Some(true)) {
        return Err("`--modbus-reset` needs Modbus (`--modbus ADDR`)".into());
    }
    if let Some(f) = a.report_format.as_deref().filter(|f| *f != "text" && *f != "json") {
        return Err(format!("`--report-format`: `{f}` is `text` or `json`"));
    }
    let pki = opcua.as_ref().map(|o| o.pki_dir.clone());
    let mut modbus_limits = ModbusLimits::default();
    if let Some(n) = a.modbus_max_clients.or(cfg.modbus.max_clients) {
        if n == 0 {
            return Err("`--modbus-max-clients` must be at least 1".into());
        }
        modbus_limits.max_clients = n;
    }
    if let Some(t) = &a.modbus_idle_timeout {
        modbus_limits.idle_timeout = time_arg("--modbus-idle-timeout", t)?;
    } else if let Some(t) = cfg.modbus.idle_timeout {
        modbus_limits.idle_timeout = t;
    }
    let word_order = match a.word_order.as_deref().or(cfg.modbus.word_order.as_deref()) {
        None => WordOrder::default(),
        Some(w) => WordOrder::from_name(w)
            .ok_or_else(|| format!("`--word-order`: `{w}` is not a word order (big or little)"))?,
    };
    let (token, source) = token_of(a, &cfg)?;
    let monitor_access = MonitorAccess {
        origins: if a.allow_origin.is_empty() {
            cfg.monitor.allow_origins.clone()
        } else {
            Some(a.allow_origin.clone())
        },
        hosts: cfg.monitor.allow_hosts.clone(),
    };
    let on_fault = a.on_fault.as_deref().or(cfg.on_fault.as_deref());
    let wait_in_fault = match on_fault {
        Some("wait") => true,
        Some("exit") => false,
        Some(other) => return Err(format!("`--on-fault`: `{other}` is `wait` or `exit`")),
        None => modbus.is_some() || monitor.is_some() || opcua_at.is_some(),
    };
    let retain_enabled = !a.no_retain && cfg.retain.enabled != Some(false);
    let retain = retain_enabled.then(|| -> Result<RetainOptions, String> {
        Ok(RetainOptions {
            path: a.retain.clone().or_else(|| cfg.retain.file.clone()).unwrap_or_else(|| file.with_extension("retain")),
            interval: match &a.retain_interval {
                Some(t) => time_arg("--retain-interval", t)?,
                None => cfg.retain.interval.unwrap_or(Duration::from_secs(1)),
            },
            cold: a.cold,
        })
    });
    let retain = retain.transpose()?;
    let mut safe = cfg.safe.clone();
    safe.extend(a.safe.iter().cloned());
    let mut opts = RunOptions {
        opcua,
        modbus,
        modbus_limits,
        word_order,
        modbus_reset: a.modbus_reset || cfg.modbus.reset == Some(true),
        monitor,
        monitor_access,
        token,
        limits,
        safe,
        retain: None,
        wait_in_fault,
        halted: a.halted,
        ctrl_c: true,
        realtime: a.realtime || cfg.realtime == Some(true),
    };
    let decoded = sfc_driver::read_source(&file).map_err(|e| format!("error: {e}"))?;
    let raw = decoded.text;
    let name = file.display().to_string();
    // PLCopen XML runs as the IEC text it imports to; what the import says is shown, and an
    // import error stops the run as a check error would.
    let iec = sfc_driver::IecText::of(&file, &raw);
    let render = |file: &sfc_diagnostics::SourceFile, diags: &[sfc_diagnostics::Diagnostic]| -> Vec<String> {
        let color = std::io::stderr().is_terminal();
        diags.iter().map(|d| render_human(d, std::slice::from_ref(file), RenderOptions { color })).collect()
    };
    if let Some(imported) = &iec.imported {
        let diags = iec.import_diagnostics();
        let errors = diags.iter().filter(|d| d.is_error()).count();
        let mut out = render(&imported.xml, diags);
        if errors > 0 {
            out.push(format!("{errors} error{} emitted", if errors == 1 { "" } else { "s" }));
            return Err(out.join("\n"));
        }
        for line in out {
            eprintln!("{line}");
        }
    }
    let text = iec.text.as_str();
    let pou = a.pou.as_deref().or(cfg.pou.as_deref());
    let rt = if a.atmt {
        if opts.monitor.is_none() {
            return Err("error: `--atmt` serves the monitor protocol: give `--monitor ADDR`".into());
        }
        let model = if sfc_codegen::atmt::parse_table(text.trim()).is_some() {
            AtmtModel::from_table(text)
        } else {
            AtmtModel::from_chart(&name, text, pou)
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
        // The profile: `--profile`, else the rules of the tool that wrote the file (said).
        let profile = match a.profile.or(cfg.profile) {
            Some(p) => p,
            None => {
                let (p, why) = sfc_sim::file_profile(sfc_sim::chart_vendor(&iec.text, iec.imported.as_ref()));
                if let sfc_sim::ProfileSource::Vendor(v) = why {
                    let instead = if a.config.is_some() {
                        "--profile iec, or profile = \"iec\" in the configuration,"
                    } else {
                        "--profile iec"
                    };
                    eprintln!("note: {}", sfc_sim::vendor_profile_note("running", &name, v, instead));
                }
                p
            }
        };
        let sim_opts = SimOptions { period: period.as_micros() as i64, profile };
        let mut sim = Simulation::from_source(&name, text, pou, sim_opts).map_err(|(file, diags)| {
            let (file, diags) = iec.locate(file, diags);
            let mut out = render(&file, &diags);
            out.push(format!("{} error{} emitted", diags.len(), if diags.len() == 1 { "" } else { "s" }));
            out.join("\n")
        })?;
        // A PLCopen chart's runtime errors (faults) are located in its XML.
        if let Some(i) = &iec.imported {
            sim.locate_faults_in(std::sync::Arc::new((i.xml.clone(), i.map.clone())));
        }
        // A chart without retentive values needs no file; one the user named is said unused.
        if !sim.retained().is_empty() {
            opts.retain = retain;
        } else if let Some(r) = retain.filter(|_| a.retain.is_some() || cfg.retain.file.is_some()) {
            eprintln!(
                "retain: the chart has no RETAIN or PERSISTENT variables: {} is neither read nor written",
                r.path.display()
            );
        }
        Runtime::start(sim, opts).map_err(|e| format!("error: {e}"))?
    };
    if let (Some(addr), Some(pki)) = (rt.opcua_addr(), pki) {
        eprintln!("sfc run: OPC UA on opc.tcp://{addr}/ (PKI in {})", pki.display());
    }
    Ok((rt, source))
}

fn print_notices(rt: &Runtime) {
    for line in rt.notices() {
        eprintln!("{line}");
    }
}

/// Prints where the run serves, waits for its end (limits, fault without servers, Ctrl-C,
/// SIGTERM), prints the statistics; the exit status.
fn supervise(rt: Runtime, a: &RunArgs, source: &TokenSource) -> u8 {
    if let Some(m) = rt.modbus_addr() {
        eprintln!("sfc run: Modbus TCP on {m} ({} located variables)", rt.io_points().len());
    }
    if let Some(m) = rt.monitor_addr() {
        match source {
            TokenSource::Random => eprintln!("sfc run: monitor on ws://{m}/?token={}", rt.token()),
            TokenSource::Env => eprintln!("sfc run: monitor on ws://{m}/ (token from SFC_TOKEN)"),
            TokenSource::File(p) => eprintln!("sfc run: monitor on ws://{m}/ (token from {})", p.display()),
        }
    }
    print_notices(&rt);
    let every = a.report.as_deref().and_then(|r| time_arg("--report", r).ok());
    let mut last = std::time::Instant::now();
    while !rt.is_finished() {
        std::thread::sleep(Duration::from_millis(20));
        print_notices(&rt);
        if let Some(e) = every {
            if last.elapsed() >= e {
                last = std::time::Instant::now();
                let image = rt.image();
                if a.report_format.as_deref() == Some("json") {
                    eprintln!("{}", image.report_json(rt.info()));
                } else {
                    eprintln!("sfc run: report: {}", image.report_text(rt.info()));
                }
            }
        }
    }
    let safe = rt.safe_state().summary(8);
    let report = rt.wait();
    for line in &report.notices {
        eprintln!("{line}");
    }
    if let Err(e) = &report.realtime {
        eprintln!("warning: {e}");
    }
    if a.atmt {
        eprintln!("sfc run: {} states of the block observed", report.stats.scans);
        return 0;
    }
    let ended = match report.state {
        RunState::Fault => "FAULT",
        _ => "STOP",
    };
    if !safe.is_empty() {
        eprintln!("sfc run: {ended}: outputs at their safe values ({safe})");
    }
    eprintln!("sfc run: {}", report.stats.summary());
    if !report.modbus.is_null() {
        let m = &report.modbus;
        eprintln!(
            "sfc run: Modbus: {} connections, {} refused over the limit, {} closed idle, {} failed accepts; {} requests, {} exceptions",
            m["accepted"], m["refused"], m["idleClosed"], m["acceptErrors"], m["requests"], m["exceptions"]
        );
    }
    if report.dropped > 0 {
        eprintln!("sfc run: {} monitor clients dropped (flooding, garbage or too slow)", report.dropped);
    }
    match report.state {
        RunState::Fault => 1,
        _ => 0,
    }
}

/// `--profile`: `iec`, `matiec`, `codesys` or `grafcet` (any case).
pub fn parse_profile(s: &str) -> Result<Profile, String> {
    Profile::from_name(s)
        .ok_or_else(|| format!("unknown profile `{s}` (expected iec, matiec, codesys, grafcet, logix or graph)"))
}
