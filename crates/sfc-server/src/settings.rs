//! `GET /api/settings` and `POST /api/settings`: the editor's settings (the language, the charts
//! opened lately, the monitor's watch lists) kept in the user's config directory, so they
//! outlast the run. `sfc edit` takes a new port on every run without `--port`, and the browser
//! keeps its storage per origin (port included), so the page's own storage forgets them.
//!
//! The file is `editor.json` in `$SFC_CONFIG_DIR` when set, else in `sfc` under the platform's
//! config directory: `$XDG_CONFIG_HOME/sfc`, else `$HOME/.config/sfc` on Unix, `%APPDATA%\sfc`
//! on Windows. It is read on every call (another editor may have changed it), changed one call
//! at a time, and written through a temporary file renamed over it. A file that cannot be read
//! as settings is reported once on stderr, set aside as `editor.json.corrupt` and replaced by
//! the defaults; the editor keeps running.
//!
//! The server only keeps the recent charts' paths: opening one is `POST /api/open`, confined as
//! ever to the files and directories the session was started on.

use crate::api::ApiError;
use crate::contract::{Settings, SettingsUpdate};
use crate::disk::write_atomically;
use crate::AppState;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// The environment variable naming the directory the settings file is kept in.
pub const CONFIG_DIR_VAR: &str = "SFC_CONFIG_DIR";
/// The settings file's name in that directory.
pub const FILE_NAME: &str = "editor.json";
/// At most this many recent charts.
pub const MAX_RECENT: usize = 20;
/// At most this many names in one watch list.
pub const MAX_WATCH: usize = 200;
/// The settings file (and a request's body) is at most this large.
pub const MAX_SIZE: usize = 1 << 20;
/// A path of the recent list is at most this long (bytes).
const MAX_PATH: usize = 4096;
/// A chart's key or a watched name is at most this long (bytes).
const MAX_NAME: usize = 1024;

/// The directory the settings are kept in: `SFC_CONFIG_DIR` (relative to `cwd` when relative),
/// else `XDG_CONFIG_HOME/sfc` (when absolute) or `HOME/.config/sfc` on Unix, `APPDATA\sfc` on
/// Windows. `None` when none of these is set. Empty variables count as unset.
pub fn config_dir(var: &dyn Fn(&str) -> Option<OsString>, windows: bool, cwd: &Path) -> Option<PathBuf> {
    let get = |name: &str| var(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    if let Some(d) = get(CONFIG_DIR_VAR) {
        return Some(if d.is_absolute() { d } else { cwd.join(d) });
    }
    if windows {
        return get("APPDATA").filter(|d| d.is_absolute()).map(|d| d.join("sfc"));
    }
    // The XDG base directory specification ignores a relative XDG_CONFIG_HOME.
    if let Some(d) = get("XDG_CONFIG_HOME").filter(|d| d.is_absolute()) {
        return Some(d.join("sfc"));
    }
    get("HOME").filter(|d| d.is_absolute()).map(|d| d.join(".config").join("sfc"))
}

/// Where one session keeps its settings.
#[derive(Debug)]
pub(crate) struct Store {
    /// The settings file; `None` when no config directory is known.
    file: Option<PathBuf>,
    /// Changes are read, merged and written one at a time.
    lock: std::sync::Mutex<()>,
    /// A corrupt file has been reported (once per run).
    reported: AtomicBool,
}

impl Store {
    /// The store in `dir` (`None`: settings cannot be kept; the calls answer `500`).
    pub(crate) fn new(dir: Option<PathBuf>) -> Store {
        Store {
            file: dir.map(|d| d.join(FILE_NAME)),
            lock: std::sync::Mutex::new(()),
            reported: AtomicBool::new(false),
        }
    }

    fn file(&self) -> Result<&Path, ApiError> {
        self.file.as_deref().ok_or_else(|| {
            ApiError::new(
                StatusCode::INTERNAL_SERVER_ERROR,
                format!("no config directory to keep the settings in: set {CONFIG_DIR_VAR} (or HOME)"),
            )
        })
    }

    /// The settings as the file holds them; the defaults when there is none or it is corrupt.
    fn load(&self) -> Result<Settings, ApiError> {
        let file = self.file()?;
        let bytes = match std::fs::metadata(file) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Settings::default()),
            Err(e) => return Err(io_error(file, &e)),
            Ok(m) if m.len() > MAX_SIZE as u64 => {
                return Ok(self.corrupt(file, &format!("it is larger than {} MiB", MAX_SIZE >> 20)))
            }
            Ok(_) => match std::fs::read(file) {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Settings::default()),
                Err(e) => return Err(io_error(file, &e)),
            },
        };
        match serde_json::from_slice::<Stored>(&bytes) {
            Ok(s) => Ok(s.settings()),
            Err(e) => Ok(self.corrupt(file, &e.to_string())),
        }
    }

    /// A file that is not settings: said once on stderr, set aside, and the defaults.
    fn corrupt(&self, file: &Path, why: &str) -> Settings {
        let aside = file.with_file_name(format!("{FILE_NAME}.corrupt"));
        let moved = std::fs::rename(file, &aside).is_ok();
        if !self.reported.swap(true, Ordering::SeqCst) {
            let kept = if moved { format!("; it was kept as `{}`", aside.display()) } else { String::new() };
            eprintln!(
                "warning: the editor's settings file `{}` cannot be read ({why}): the settings start afresh{kept}",
                file.display()
            );
        }
        Settings::default()
    }

    /// Merges `update` into the file and answers the whole.
    fn update(&self, update: SettingsUpdate) -> Result<Settings, ApiError> {
        let _one_at_a_time = self.lock.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let file = self.file()?;
        let mut settings = self.load()?;
        merge(&mut settings, update);
        let mut bytes = serde_json::to_vec_pretty(&settings)
            .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, format!("cannot write the settings: {e}")))?;
        bytes.push(b'\n');
        if bytes.len() > MAX_SIZE {
            return Err(ApiError::new(
                StatusCode::PAYLOAD_TOO_LARGE,
                format!("the settings would be larger than {} MiB; nothing was changed", MAX_SIZE >> 20),
            ));
        }
        if let Some(dir) = file.parent() {
            std::fs::create_dir_all(dir).map_err(|e| io_error(dir, &e))?;
        }
        write_atomically(file, &bytes).map_err(|e| io_error(file, &e))?;
        Ok(settings)
    }
}

fn io_error(path: &Path, e: &std::io::Error) -> ApiError {
    ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, format!("cannot keep the settings in `{}`: {e}", path.display()))
}

/// The file as read: unknown fields (of a newer editor) are ignored, missing ones are the
/// defaults, and lists beyond the bounds (a file edited by hand) are cut to them.
#[derive(Deserialize)]
struct Stored {
    #[serde(default)]
    language: Option<String>,
    #[serde(default)]
    recent: Vec<String>,
    #[serde(default)]
    watch: BTreeMap<String, Vec<String>>,
}

impl Stored {
    fn settings(self) -> Settings {
        let mut recent = self.recent;
        recent.truncate(MAX_RECENT);
        let watch = self
            .watch
            .into_iter()
            .map(|(k, mut v)| {
                v.truncate(MAX_WATCH);
                (k, v)
            })
            .collect();
        Settings { language: self.language.filter(|l| valid_language(l)), recent, watch }
    }
}

/// A language tag (`de`, `pt-BR`).
fn valid_language(l: &str) -> bool {
    (1..=35).contains(&l.len()) && l.chars().all(|c| c.is_ascii_alphanumeric() || c == '-')
}

fn unprocessable(message: String) -> ApiError {
    ApiError::new(StatusCode::UNPROCESSABLE_ENTITY, message)
}

/// The update within the bounds, else `422` saying which bound.
fn validate(u: &SettingsUpdate) -> Result<(), ApiError> {
    if let Some(Some(l)) = &u.language {
        if !valid_language(l) {
            return Err(unprocessable(format!("`{l}` is not a language tag")));
        }
    }
    if let Some(recent) = &u.recent {
        if recent.len() > MAX_RECENT {
            return Err(unprocessable(format!("{} recent charts: at most {MAX_RECENT} are kept", recent.len())));
        }
        if let Some(p) = recent.iter().find(|p| p.is_empty() || p.len() > MAX_PATH) {
            return Err(unprocessable(format!("a recent chart's path must have 1 to {MAX_PATH} bytes ({})", p.len())));
        }
    }
    for (chart, list) in u.watch.iter().flatten() {
        if chart.is_empty() || chart.len() > MAX_NAME {
            return Err(unprocessable(format!("a watch list's chart must have 1 to {MAX_NAME} bytes")));
        }
        let Some(list) = list else { continue };
        if list.len() > MAX_WATCH {
            return Err(unprocessable(format!(
                "{} names in the watch list of `{chart}`: at most {MAX_WATCH} are kept",
                list.len()
            )));
        }
        if list.iter().any(|n| n.is_empty() || n.len() > MAX_NAME) {
            return Err(unprocessable(format!("a watched name of `{chart}` must have 1 to {MAX_NAME} bytes")));
        }
    }
    Ok(())
}

/// Applies a (validated) update: absent fields stay, `language: null` clears it, `recent`
/// replaces the list (repeated paths once), each chart of `watch` gets its list or, for `null`,
/// none.
fn merge(s: &mut Settings, u: SettingsUpdate) {
    if let Some(l) = u.language {
        s.language = l;
    }
    if let Some(recent) = u.recent {
        let mut seen = std::collections::HashSet::new();
        s.recent = recent.into_iter().filter(|p| seen.insert(p.clone())).collect();
    }
    for (chart, list) in u.watch.into_iter().flatten() {
        match list {
            Some(list) => {
                s.watch.insert(chart, list);
            }
            None => {
                s.watch.remove(&chart);
            }
        }
    }
}

/// Runs store work on a blocking thread (file system calls) and answers with its JSON.
async fn answer(s: AppState, work: impl FnOnce(&Store) -> Result<Settings, ApiError> + Send + 'static) -> Response {
    match tokio::task::spawn_blocking(move || work(&s.0.settings)).await {
        Ok(Ok(v)) => Json(v).into_response(),
        Ok(Err(e)) => e.into_response(),
        Err(_) => ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal error while keeping the settings")
            .into_response(),
    }
}

/// `GET /api/settings`.
pub async fn read(State(s): State<AppState>) -> Response {
    answer(s, |store| {
        let _one_at_a_time = store.lock.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        store.load()
    })
    .await
}

/// `POST /api/settings` with a [`SettingsUpdate`]: merged into the file; answers the whole.
pub async fn update(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let bytes = match body {
        Ok(b) => b,
        Err(r) => return ApiError::new(r.status(), r.body_text()).into_response(),
    };
    if bytes.len() > MAX_SIZE {
        return ApiError::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!("settings larger than {} MiB are not kept", MAX_SIZE >> 20),
        )
        .into_response();
    }
    let update: SettingsUpdate = match serde_json::from_slice(&bytes) {
        Ok(u) => u,
        Err(e) => return ApiError::new(StatusCode::BAD_REQUEST, format!("bad request body: {e}")).into_response(),
    };
    if let Err(e) = validate(&update) {
        return e.into_response();
    }
    answer(s, move |store| store.update(update)).await
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<OsString> + 'a {
        move |k| vars.iter().find(|(n, _)| *n == k).map(|(_, v)| OsString::from(v))
    }

    #[test]
    fn the_config_directory() {
        let cwd = Path::new("/work");
        let unix = |vars: &[(&str, &str)]| config_dir(&env(vars), false, cwd);
        assert_eq!(unix(&[("SFC_CONFIG_DIR", "/t/cfg"), ("HOME", "/home/u")]), Some(PathBuf::from("/t/cfg")));
        assert_eq!(unix(&[("SFC_CONFIG_DIR", "cfg")]), Some(PathBuf::from("/work/cfg")));
        assert_eq!(unix(&[("SFC_CONFIG_DIR", ""), ("HOME", "/home/u")]), Some(PathBuf::from("/home/u/.config/sfc")));
        assert_eq!(
            unix(&[("XDG_CONFIG_HOME", "/x"), ("HOME", "/home/u")]),
            Some(PathBuf::from("/x/sfc")),
            "XDG_CONFIG_HOME first"
        );
        assert_eq!(
            unix(&[("XDG_CONFIG_HOME", "rel"), ("HOME", "/home/u")]),
            Some(PathBuf::from("/home/u/.config/sfc")),
            "a relative XDG_CONFIG_HOME is ignored"
        );
        assert_eq!(unix(&[]), None);
        assert_eq!(unix(&[("APPDATA", "/a")]), None, "APPDATA is Windows'");
    }

    #[cfg(windows)]
    #[test]
    fn the_config_directory_on_windows() {
        let cwd = Path::new(r"C:\work");
        let win = |vars: &[(&str, &str)]| config_dir(&env(vars), true, cwd);
        assert_eq!(
            win(&[("APPDATA", r"C:\Users\u\AppData\Roaming")]),
            Some(PathBuf::from(r"C:\Users\u\AppData\Roaming\sfc"))
        );
        assert_eq!(win(&[("HOME", r"C:\Users\u")]), None);
    }

    #[test]
    fn updates_merge() {
        let mut s = Settings::default();
        let u: SettingsUpdate = serde_json::from_str(
            r#"{"language":"de","recent":["/a.st","/b.st","/a.st"],"watch":{"P":["x"],"Q":["y"]}}"#,
        )
        .unwrap();
        validate(&u).unwrap();
        merge(&mut s, u);
        assert_eq!(s.language.as_deref(), Some("de"));
        assert_eq!(s.recent, ["/a.st", "/b.st"]);
        let u: SettingsUpdate = serde_json::from_str(r#"{"watch":{"P":null,"R":["z"]}}"#).unwrap();
        merge(&mut s, u);
        assert_eq!(s.language.as_deref(), Some("de"), "absent: kept");
        assert_eq!(s.watch.keys().collect::<Vec<_>>(), ["Q", "R"]);
        let u: SettingsUpdate = serde_json::from_str(r#"{"language":null}"#).unwrap();
        merge(&mut s, u);
        assert_eq!(s.language, None, "null: cleared");
        assert_eq!(s.recent, ["/a.st", "/b.st"]);
    }

    #[test]
    fn bounds() {
        let over: Vec<String> = (0..=MAX_RECENT).map(|k| format!("/c{k}.st")).collect();
        let u = SettingsUpdate { recent: Some(over), ..SettingsUpdate::default() };
        assert!(validate(&u).is_err());
        let names: Vec<String> = (0..=MAX_WATCH).map(|k| format!("v{k}")).collect();
        let u = SettingsUpdate {
            watch: Some([("P".to_string(), Some(names))].into_iter().collect()),
            ..SettingsUpdate::default()
        };
        assert!(validate(&u).is_err());
        let u = SettingsUpdate { language: Some(Some("de\"; x".into())), ..SettingsUpdate::default() };
        assert!(validate(&u).is_err());
    }
}
