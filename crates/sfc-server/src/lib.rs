//! The SFC Editor's server: the HTTP API of `docs/editor.md` and the web app built from `web/`,
//! embedded in the binary. Loopback only, a per-run token, and file access confined to the
//! directories it was started with.
//!
//! [`serve`] runs it (what `sfc edit` calls); [`app`] is the router alone, for tests in-process.
//! [`compile`] is the driver's check-then-compile dispatch (`sfc_driver::compile`), shared with
//! `sfc build`.

mod access;
mod api;
mod assets;
mod compare;
mod confine;
pub mod contract;
mod diag;
mod disk;
mod prove;
mod resolve;
mod settings;
mod sim;

use sfc_driver::compile;

pub use access::TOKEN_HEADER;
pub use confine::{confine, Refusal};
pub use disk::content_hash;
pub use settings::{config_dir, CONFIG_DIR_VAR};

use axum::extract::DefaultBodyLimit;
use axum::routing::{any, get, post};
use axum::Router;
use sfc_model::{Limits, Target};
use std::path::PathBuf;
use std::sync::Arc;

/// Request bodies larger than this are refused (`413`).
pub const MAX_BODY: usize = 16 << 20;

/// The REX block a host application builds for (seed 001, `/fb=`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostBlock {
    Atmt,
    Eatmt,
}

impl HostBlock {
    /// `atmt` or `eatmt`.
    pub fn name(self) -> &'static str {
        match self {
            HostBlock::Atmt => "atmt",
            HostBlock::Eatmt => "eatmt",
        }
    }

    /// The chart target whose rules the block imposes.
    pub fn target(self) -> Target {
        match self {
            HostBlock::Atmt => Target::Atmt,
            HostBlock::Eatmt => Target::Eatmt,
        }
    }

    /// The matching build target.
    pub fn build_target(self) -> compile::BuildTarget {
        match self {
            HostBlock::Atmt => compile::BuildTarget::Atmt,
            HostBlock::Eatmt => compile::BuildTarget::Eatmt,
        }
    }
}

/// Host mode (seed 001 chapter 12): one chart edited for a host application, which reads the
/// built transition table from `result` after the editor is closed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HostMode {
    pub fb: HostBlock,
    /// State limit (`/nstep=`); the block's own (16 or 256) when not given.
    pub nstep: Option<u32>,
    /// Rule limit (`/ntr=`); the block's own (64 or 1024) when not given.
    pub ntr: Option<u32>,
    /// Where a successful build writes the one-line table (`/mmf:` in the original editor).
    pub result: PathBuf,
}

/// How `sfc edit` was started.
#[derive(Debug, Clone, Default)]
pub struct EditOptions {
    /// Files and directories to edit; relative ones are taken from the current directory. None:
    /// the current directory.
    pub files: Vec<PathBuf>,
    /// Port on 127.0.0.1; `None` or 0: any free port.
    pub port: Option<u16>,
    /// Host mode; then `files` holds exactly the one chart file (which may not exist yet).
    pub host: Option<HostMode>,
}

/// Host mode as the session holds it: canonical paths and the effective limits.
#[derive(Debug, Clone)]
struct HostSession {
    fb: HostBlock,
    nstep: u32,
    ntr: u32,
    file: PathBuf,
    result: PathBuf,
}

/// One run of the editor: what it may touch and who may ask.
#[derive(Debug)]
struct Session {
    roots: Vec<PathBuf>,
    open: Vec<PathBuf>,
    host: Option<HostSession>,
    token: String,
    port: u16,
    /// Saves run one at a time, so the conflict check and the write of one are not interleaved
    /// with another's.
    save_lock: Arc<tokio::sync::Mutex<()>>,
    /// The built-in simulator's runs (monitor mode), stopped with the session.
    sims: sim::Simulations,
    /// The first named file, opened while the browser loads the app (taken by its first
    /// `POST /api/open`; locked while it is being made).
    prepared: Arc<tokio::sync::Mutex<Option<api::Prepared>>>,
    /// The editor's settings in the user's config directory (`GET`/`POST /api/settings`).
    settings: settings::Store,
}

/// The server's state, shared by every request.
#[derive(Debug, Clone)]
pub struct AppState(Arc<Session>);

impl AppState {
    /// The session for `opts`, served on `port` (the `Host` header must name it). Fails when a
    /// path cannot be used, or host mode is not given exactly one chart file. The settings are
    /// kept in the directory [`config_dir`] names (`SFC_CONFIG_DIR`, else the user's).
    pub fn new(opts: &EditOptions, port: u16) -> Result<AppState, String> {
        AppState::with_config_dir(opts, port, None)
    }

    /// [`AppState::new`] with the settings kept in `config` (`None`: where [`config_dir`] says).
    pub fn with_config_dir(opts: &EditOptions, port: u16, config: Option<PathBuf>) -> Result<AppState, String> {
        let cwd = std::env::current_dir().map_err(|e| format!("cannot read the current directory: {e}"))?;
        let config = config.or_else(|| config_dir(&|k| std::env::var_os(k), cfg!(windows), &cwd));
        let (roots, open) = confine::roots_of(&opts.files, &cwd)?;
        let host = match &opts.host {
            None => None,
            Some(h) => {
                let [file] = open.as_slice() else {
                    return Err("host mode edits exactly one chart: give one FILE (not a directory)".to_string());
                };
                let result = if h.result.is_absolute() { h.result.clone() } else { cwd.join(&h.result) };
                let name = result
                    .file_name()
                    .ok_or_else(|| format!("--result `{}` is not a file name", h.result.display()))?;
                let dir = result.parent().unwrap_or(std::path::Path::new("/"));
                let dir = std::fs::canonicalize(dir)
                    .map_err(|e| format!("--result `{}`: its directory cannot be used: {e}", h.result.display()))?;
                let result = dir.join(name);
                if result.is_dir() {
                    return Err(format!("--result `{}` is a directory", h.result.display()));
                }
                let limits = Limits::of(h.fb.target(), h.nstep, h.ntr);
                Some(HostSession { fb: h.fb, nstep: limits.states, ntr: limits.rules, file: file.clone(), result })
            }
        };
        let token = access::new_token()?;
        Ok(AppState(Arc::new(Session {
            roots,
            open,
            host,
            token,
            port,
            save_lock: Arc::new(tokio::sync::Mutex::new(())),
            sims: sim::Simulations::default(),
            prepared: Arc::new(tokio::sync::Mutex::new(None)),
            settings: settings::Store::new(config),
        })))
    }

    /// The per-run token the page must send in `X-Sfc-Token`.
    pub fn token(&self) -> &str {
        &self.0.token
    }

    /// The port the `Host` header must name.
    pub fn port(&self) -> u16 {
        self.0.port
    }

    /// The canonical directories files may be read and written under.
    pub fn roots(&self) -> &[PathBuf] {
        &self.0.roots
    }

    /// The address to open in a browser: `http://127.0.0.1:PORT/?token=TOKEN`.
    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/?token={}", self.0.port, self.0.token)
    }
}

/// The router: the API under `/api/` and the web app everywhere else.
pub fn app(state: AppState) -> Router {
    Router::new()
        .route("/api/session", get(api::session))
        .route("/api/files", get(api::files))
        .route("/api/codes", get(api::codes))
        .route("/api/open", post(api::open))
        .route("/api/save", post(api::save))
        .route("/api/check", post(api::check))
        .route("/api/build", post(api::build))
        .route("/api/layout", post(api::layout))
        .route("/api/new", post(api::new_chart))
        .route("/api/prove", post(prove::prove))
        .route("/api/compare", post(compare::compare))
        .route("/api/resolve", post(resolve::resolve))
        .route("/api/settings", get(settings::read).post(settings::update))
        .route("/api/sim/start", post(sim::start))
        .route("/api/sim/stop", post(sim::stop))
        .route("/api", any(api::not_found))
        .route("/api/{*rest}", any(api::not_found))
        .method_not_allowed_fallback(api::method_not_allowed)
        .fallback(api::static_file)
        .layer(DefaultBodyLimit::max(MAX_BODY))
        .layer(axum::middleware::from_fn_with_state(state.clone(), access::guard))
        .with_state(state)
}

/// Runs the editor until Ctrl-C: binds 127.0.0.1 (`opts.port`, any free port by default), calls
/// `ready` with the URL to open, and serves. Blocking; it has its own runtime.
pub fn serve(opts: EditOptions, ready: impl FnOnce(&str)) -> Result<(), String> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        // Checking recurses along the (depth-capped) syntax tree, as in the CLI.
        .thread_stack_size(64 << 20)
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the server's runtime: {e}"))?;
    let result = runtime.block_on(async move {
        let port = opts.port.unwrap_or(0);
        let listener = tokio::net::TcpListener::bind(("127.0.0.1", port))
            .await
            .map_err(|e| format!("cannot listen on 127.0.0.1:{port}: {e}"))?;
        let port = listener.local_addr().map_err(|e| format!("cannot read the bound address: {e}"))?.port();
        let state = AppState::new(&opts, port)?;
        // The first named file is read, checked and laid out now, while the browser starts and
        // loads the app (half the time to a drawn chart at 500 steps). Locked before the URL is
        // given, so the page's request waits for it rather than doing it again.
        if state.0.host.is_none() && !state.0.open.is_empty() {
            let mut slot = state.0.prepared.clone().lock_owned().await;
            let s = state.clone();
            tokio::task::spawn_blocking(move || *slot = api::prepare_first(&s));
        }
        let router = app(state.clone());
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
        let server = tokio::spawn(async move {
            axum::serve(listener, router)
                .with_graceful_shutdown(async move {
                    let _ = stop_rx.await;
                })
                .await
        });
        ready(&state.url());
        tokio::signal::ctrl_c().await.map_err(|e| format!("cannot wait for Ctrl-C: {e}"))?;
        let _ = stop_tx.send(());
        state.0.sims.stop_all();
        // Open keep-alive connections of a browser must not hold the exit up for long.
        match tokio::time::timeout(std::time::Duration::from_secs(3), server).await {
            Ok(Ok(Err(e))) => Err(format!("the server failed: {e}")),
            _ => Ok(()),
        }
    });
    // A save still running finishes (its rename is atomic anyway); a long build is cut short.
    runtime.shutdown_timeout(std::time::Duration::from_secs(5));
    result
}
