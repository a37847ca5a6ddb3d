//! RETAIN and PERSISTENT values (IEC 61131-3 2.4.3; PERSISTENT as CODESYS and TwinCAT have it)
//! kept in a file across restarts of `sfc run`.
//!
//! - A warm start restores RETAIN and PERSISTENT values; a cold start (`--cold`) only the
//!   PERSISTENT ones; everything else starts from its declared initial value.
//! - The file is written by its own thread, never the scan thread: every interval (after a
//!   scan that completed) when a value changed, on a fault, and at every orderly stop. Each
//!   write goes to a temporary file in the same directory, which is synced, renamed over the
//!   file, and the directory synced: a crash at any moment leaves the previous file or the new
//!   one, and loses at most one interval.
//! - The file is one line of JSON and a line with its CRC-32, so a file damaged by other means
//!   is recognised: it is set aside (renamed `….corrupt`) and the run starts from the initial
//!   values, saying so.
//! - A file from an older version of the chart restores what still matches by name and type,
//!   and says what it dropped.

// Indices here come from tables this crate builds at start (the Modbus map, the variables) or
// are checked against the frame length just before (Modbus PDUs); the runtime work of issue 14
// landed after the workspace lints, and its conversion to `get` is still to do (ARCHITECTURE.md).
#![allow(clippy::indexing_slicing)]

use sfc_sim::code::Retained;
use sfc_sim::{Simulation, Value};
use sfc_st::Type;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::Duration;

/// Where and how often retentive values are kept.
#[derive(Debug, Clone, PartialEq)]
pub struct RetainOptions {
    pub path: PathBuf,
    /// Written at most this often, when a value changed (default 1 s).
    pub interval: Duration,
    /// Cold start: only PERSISTENT values are restored.
    pub cold: bool,
}

/// The `format` of a retain file.
pub const FORMAT: &str = "sfc-retain";

/// CRC-32 (IEEE 802.3, reflected, as zlib's `crc32`).
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// A value as the file holds it: BOOL as a boolean, numbers as numbers (TIME in µs), REAL
/// infinities and NaN as the strings `inf`, `-inf`, `NaN`, strings as strings.
fn encode(v: &Value) -> serde_json::Value {
    match v {
        Value::Bool(b) => serde_json::json!(b),
        Value::Int(i) | Value::Time(i) => serde_json::json!(i),
        Value::Real(r) if r.is_finite() => serde_json::json!(r),
        Value::Real(r) if r.is_nan() => serde_json::json!("NaN"),
        Value::Real(r) => serde_json::json!(if *r > 0.0 { "inf" } else { "-inf" }),
        Value::Str(s) => serde_json::json!(&**s),
    }
}

/// A file value as a value of `ty`.
fn decode(j: &serde_json::Value, ty: &Type) -> Option<Value> {
    let b = ty.base();
    let v = if b.is_bool() {
        Value::Bool(j.as_bool()?)
    } else if b.is_real() {
        match j {
            serde_json::Value::String(s) => Value::Real(match s.as_str() {
                "NaN" => f64::NAN,
                "inf" => f64::INFINITY,
                "-inf" => f64::NEG_INFINITY,
                _ => return None,
            }),
            _ => Value::Real(j.as_f64()?),
        }
    } else if b.is_duration() {
        Value::Time(j.as_i64()?)
    } else if b.is_string() {
        Value::Str(j.as_str()?.into())
    } else {
        Value::Int(j.as_i64()?)
    };
    Simulation::fit_to(ty, v).ok()
}

/// The file's text for `values` of `leaves`, saved after scan `scan`.
pub fn file_text(pou: &str, scan: u64, leaves: &[Retained], values: &[Value]) -> String {
    let list: Vec<serde_json::Value> = leaves
        .iter()
        .zip(values)
        .map(|(l, v)| {
            serde_json::json!({
                "name": l.name,
                "type": l.ty.to_string(),
                "class": if l.persistent { "persistent" } else { "retain" },
                "value": encode(v),
            })
        })
        .collect();
    let body =
        serde_json::json!({"format": FORMAT, "version": 1, "pou": pou, "scan": scan, "values": list}).to_string();
    format!("{body}\ncrc32 {:08x}\n", crc32(body.as_bytes()))
}

/// One value read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedValue {
    pub name: String,
    pub ty: String,
    pub persistent: bool,
    pub value: serde_json::Value,
}

/// A retain file's content.
#[derive(Debug, Clone, PartialEq)]
pub struct RetainFile {
    pub pou: String,
    pub scan: u64,
    pub values: Vec<SavedValue>,
}

/// Reads a retain file's text; `Err` says why it is not one (damaged, or another format).
pub fn parse_file(text: &str) -> Result<RetainFile, String> {
    let (body, tail) = text.split_once("\ncrc32 ").ok_or("no checksum line")?;
    let want = u32::from_str_radix(tail.trim_end(), 16).map_err(|_| "a damaged checksum line")?;
    if crc32(body.as_bytes()) != want {
        return Err("the checksum does not match the content".into());
    }
    let j: serde_json::Value = serde_json::from_str(body).map_err(|e| format!("not JSON: {e}"))?;
    if j["format"] != FORMAT || j["version"] != 1 {
        return Err(format!("not an {FORMAT} file of version 1"));
    }
    let values = j["values"]
        .as_array()
        .ok_or("no values")?
        .iter()
        .map(|v| {
            Some(SavedValue {
                name: v["name"].as_str()?.to_string(),
                ty: v["type"].as_str()?.to_string(),
                persistent: v["class"] == "persistent",
                value: v["value"].clone(),
            })
        })
        .collect::<Option<Vec<_>>>()
        .ok_or("a value without name or type")?;
    Ok(RetainFile {
        pou: j["pou"].as_str().unwrap_or_default().to_string(),
        scan: j["scan"].as_u64().unwrap_or(0),
        values,
    })
}

/// What a restore did, for the operator.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Restored {
    pub restored: usize,
    /// Saved values that no longer match the chart (`Name (was INT, now DINT)`, `Name (no
    /// longer retained)`), or that a cold start does not restore.
    pub dropped: Vec<String>,
    /// Retentive values of the chart the file does not hold (they start from their initial
    /// values).
    pub missing: Vec<String>,
    /// RETAIN values a cold start reset.
    pub reset: usize,
}

/// Writes the saved values that match `leaves` (by name, case-insensitive, and type) into the
/// simulation; on a cold start only the leaves that are PERSISTENT now.
pub fn restore(sim: &mut Simulation, leaves: &[Retained], file: &RetainFile, cold: bool) -> Restored {
    let mut out = Restored::default();
    let mut used = vec![false; leaves.len()];
    for saved in &file.values {
        let Some(i) = leaves.iter().position(|l| l.name.eq_ignore_ascii_case(&saved.name)) else {
            out.dropped.push(format!("{} (no longer declared RETAIN or PERSISTENT)", saved.name));
            continue;
        };
        let leaf = &leaves[i];
        used[i] = true;
        let ty = leaf.ty.to_string();
        if ty != saved.ty {
            out.dropped.push(format!("{} (was {}, now {ty})", saved.name, saved.ty));
            continue;
        }
        if cold && !leaf.persistent {
            out.reset += 1;
            continue;
        }
        match decode(&saved.value, &leaf.ty).map(|v| sim.write_slot(leaf.slot, &leaf.ty, v)) {
            Some(Ok(())) => out.restored += 1,
            _ => out.dropped.push(format!("{} (the value {} is not a {ty})", saved.name, saved.value)),
        }
    }
    for (leaf, used) in leaves.iter().zip(used) {
        if !used {
            out.missing.push(leaf.name.clone());
        }
    }
    out
}

/// The current values of `leaves`.
pub fn capture(sim: &Simulation, leaves: &[Retained]) -> Vec<Value> {
    leaves.iter().map(|l| sim.read_slot(l.slot).cloned().unwrap_or_default()).collect()
}

/// The temporary file a write goes through: hidden, beside the file, unique to this process.
fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    dir_of(path).join(format!(".{name}.{}.tmp", std::process::id()))
}

fn dir_of(path: &Path) -> &Path {
    path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."))
}

/// Writes `text` to `path` atomically and durably: temporary file, fsync, rename, fsync of the
/// directory.
pub fn write_durably(path: &Path, text: &[u8]) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut f = std::fs::OpenOptions::new().write(true).create(true).truncate(true).open(&tmp)?;
        f.write_all(text)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)?;
        // The rename is durable once the directory is.
        if let Ok(d) = std::fs::File::open(dir_of(path)) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Removes temporary files that killed runs left beside `path` (`.NAME.PID.tmp`).
pub fn remove_stale_temporaries(path: &Path) {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else { return };
    let prefix = format!(".{name}.");
    let Ok(rd) = std::fs::read_dir(dir_of(path)) else { return };
    for e in rd.flatten() {
        let f = e.file_name().to_string_lossy().into_owned();
        if let Some(pid) = f.strip_prefix(&prefix).and_then(|r| r.strip_suffix(".tmp")) {
            if pid.parse::<u32>().is_ok() && pid != std::process::id().to_string() {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// Reads the file at `path` and restores from it, and tries whether it can be written. Returns
/// the lines to tell the operator, and whether the file can be written (for
/// [`Writer::start`]): a file that cannot be written (no such directory, no permission) is said
/// at the start, not only at the first write a second or a stop later. The run still starts: a
/// PLC whose retain memory fails keeps controlling the machine.
pub fn start(sim: &mut Simulation, leaves: &[Retained], opts: &RetainOptions) -> (Vec<String>, bool) {
    remove_stale_temporaries(&opts.path);
    let mut lines = restore_from_file(sim, leaves, opts);
    let writable = try_writing(&opts.path);
    if let Err(e) = &writable {
        lines.push(format!(
            "warning: retain: cannot write {}: {e}: the retentive values will not survive a restart \
             (`--retain PATH` names a writable file, `--no-retain` keeps none)",
            opts.path.display()
        ));
    }
    (lines, writable.is_ok())
}

/// Creates and removes the temporary file a write of `path` uses.
fn try_writing(path: &Path) -> std::io::Result<()> {
    if path.is_dir() {
        return Err(std::io::Error::other("it is a directory"));
    }
    let tmp = temp_path(path);
    std::fs::OpenOptions::new().write(true).create(true).truncate(true).open(&tmp)?;
    std::fs::remove_file(&tmp)
}

fn restore_from_file(sim: &mut Simulation, leaves: &[Retained], opts: &RetainOptions) -> Vec<String> {
    let shown = opts.path.display();
    let start = if opts.cold { "cold start" } else { "warm start" };
    let text = match std::fs::read(&opts.path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return vec![format!(
                "retain: {start}; no file {shown} yet: {} retentive values start from their initial values",
                leaves.len()
            )];
        }
        Err(e) => return vec![format!("retain: cannot read {shown}: {e}; values start from their initial values")],
        Ok(b) => b,
    };
    let parsed = String::from_utf8(text).map_err(|_| "not UTF-8 text".to_string()).and_then(|t| parse_file(&t));
    let file = match parsed {
        Ok(f) => f,
        Err(why) => {
            let aside = opts.path.with_extension("retain.corrupt");
            let moved = std::fs::rename(&opts.path, &aside).is_ok();
            return vec![format!(
                "warning: retain: {shown} is damaged ({why}){}; values start from their initial values",
                if moved { format!(", kept as {}", aside.display()) } else { String::new() }
            )];
        }
    };
    let r = restore(sim, leaves, &file, opts.cold);
    let mut lines =
        vec![format!("retain: {start}: restored {} values from {shown} (saved after scan {})", r.restored, file.scan)];
    if r.reset > 0 {
        lines.push(format!("retain: the cold start reset {} RETAIN values to their initial values", r.reset));
    }
    if !r.dropped.is_empty() {
        lines.push(format!(
            "warning: retain: dropped {} saved values that do not match the chart: {}",
            r.dropped.len(),
            r.dropped.join(", ")
        ));
    }
    if !r.missing.is_empty() {
        lines.push(format!(
            "retain: {} retentive values are not in the file and start from their initial values: {}",
            r.missing.len(),
            r.missing.join(", ")
        ));
    }
    lines
}

/// What the scan thread hands the writer.
enum Job {
    Write {
        scan: u64,
        values: Vec<Value>,
    },
    /// Write this, then end.
    Last {
        scan: u64,
        values: Vec<Value>,
    },
}

/// The thread that writes the retain file.
pub struct Writer {
    tx: mpsc::Sender<Job>,
    thread: Option<JoinHandle<()>>,
    /// The values last handed over (to write only changes).
    last: Option<Vec<Value>>,
}

impl Writer {
    /// Starts the writer of `path` for `leaves` of POU `pou`; errors are told through `notice`.
    /// A file that was not `writable` at the start ([`start`] said so) is not said again at the
    /// first write, but when it can be written after all.
    pub fn start(
        path: PathBuf,
        pou: String,
        leaves: Vec<Retained>,
        writable: bool,
        notice: impl Fn(String) + Send + 'static,
    ) -> std::io::Result<Writer> {
        let (tx, rx) = mpsc::channel::<Job>();
        let mut failing = !writable;
        let thread = std::thread::Builder::new().name("sfc-retain".into()).spawn(move || {
            let mut written = false;
            while let Ok(mut job) = rx.recv() {
                // Only the newest values matter.
                let mut last = false;
                while let Ok(next) = rx.try_recv() {
                    if matches!(job, Job::Last { .. }) {
                        break;
                    }
                    job = next;
                }
                let (scan, values) = match job {
                    Job::Write { scan, values } => (scan, values),
                    Job::Last { scan, values } => {
                        last = true;
                        (scan, values)
                    }
                };
                let text = file_text(&pou, scan, &leaves, &values);
                match write_durably(&path, text.as_bytes()) {
                    Ok(()) if failing => {
                        failing = false;
                        notice(format!("retain: {} written{}", path.display(), if written { " again" } else { "" }));
                        written = true;
                    }
                    Ok(()) => written = true,
                    Err(e) if !failing => {
                        failing = true;
                        notice(format!("warning: retain: cannot write {}: {e}", path.display()));
                    }
                    Err(_) => {}
                }
                if last {
                    return;
                }
            }
        })?;
        Ok(Writer { tx, thread: Some(thread), last: None })
    }

    /// Hands over `values` (after scan `scan`) when they differ from the last ones.
    pub fn offer(&mut self, scan: u64, values: Vec<Value>) {
        if self.last.as_ref() == Some(&values) {
            return;
        }
        self.last = Some(values.clone());
        let _ = self.tx.send(Job::Write { scan, values });
    }

    /// Writes `values` a last time and waits for the file to be on disk.
    pub fn finish(mut self, scan: u64, values: Vec<Value>) {
        let _ = self.tx.send(Job::Last { scan, values });
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_is_zlibs() {
        assert_eq!(crc32(b""), 0);
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn files_round_trip_and_damage_is_seen() {
        let leaves = vec![
            Retained { name: "Washes".into(), ty: Type::UDInt, slot: 0, persistent: false },
            Retained { name: "Level".into(), ty: Type::Real, slot: 1, persistent: true },
            Retained { name: "T".into(), ty: Type::Time, slot: 2, persistent: false },
        ];
        let values = vec![Value::Int(7), Value::Real(f64::NAN), Value::Time(1_500_000)];
        let text = file_text("P", 42, &leaves, &values);
        let f = parse_file(&text).unwrap();
        assert_eq!((f.pou.as_str(), f.scan, f.values.len()), ("P", 42, 3));
        assert_eq!(decode(&f.values[0].value, &Type::UDInt), Some(Value::Int(7)));
        assert!(matches!(decode(&f.values[1].value, &Type::Real), Some(Value::Real(r)) if r.is_nan()));
        assert_eq!(decode(&f.values[2].value, &Type::Time), Some(Value::Time(1_500_000)));
        assert!(f.values[1].persistent && !f.values[0].persistent);
        let damaged = text.replacen("42", "43", 1);
        assert!(parse_file(&damaged).unwrap_err().contains("checksum"));
        assert!(parse_file(&text[..text.len() / 2]).is_err());
        assert!(parse_file("").is_err());
    }
}
