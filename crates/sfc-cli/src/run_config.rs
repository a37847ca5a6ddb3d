//! The run configuration of `sfc run --config plant.toml` (`docs/runtime.md`, "Run
//! configuration"): the settings of a plant's runtime in one file, so a service unit needs no
//! long command line. Options given on the command line win over the file.
//!
//! ```toml
//! chart = "carwash.st"     # relative to this file
//! period = "T#10ms"
//! watchdog = "T#50ms"
//!
//! [modbus]
//! address = "0.0.0.0:502"
//! max_clients = 32
//!
//! [safe]
//! Blower = true
//! ```
//!
//! Each section is read by its own function from [`SECTIONS`]; a later section (an `[opcua]`
//! server) is one more entry there. Unknown keys and sections are errors, located in the file.

use sfc_sim::parse_time;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Duration;
use toml_edit::{Item, TableLike};

/// Everything a run configuration can set; `None` where the file is silent.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunConfig {
    /// The file itself (for messages).
    pub file: PathBuf,
    pub chart: Option<PathBuf>,
    pub pou: Option<String>,
    pub period: Option<String>,
    /// The simulator's profile (`--profile`); without it the file's vendor chooses.
    pub profile: Option<sfc_sim::Profile>,
    pub watchdog: Option<String>,
    pub realtime: Option<bool>,
    /// `wait` or `exit`.
    pub on_fault: Option<String>,
    pub modbus: ModbusSection,
    pub monitor: MonitorSection,
    pub retain: RetainSection,
    pub opcua: OpcuaSection,
    /// `NAME = value` of `[safe]`, the value as IEC literal text.
    pub safe: Vec<(String, String)>,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModbusSection {
    pub address: Option<String>,
    pub max_clients: Option<usize>,
    pub idle_timeout: Option<Duration>,
    pub word_order: Option<String>,
    /// `reset = true`: holding register and coil 40000 reset the chart.
    pub reset: Option<bool>,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct MonitorSection {
    pub address: Option<String>,
    pub token_file: Option<PathBuf>,
    pub allow_origins: Option<Vec<String>>,
    pub allow_hosts: Vec<String>,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct RetainSection {
    pub file: Option<PathBuf>,
    pub interval: Option<Duration>,
    /// `enabled = false` keeps no file.
    pub enabled: Option<bool>,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct OpcuaSection {
    /// `opc.tcp://127.0.0.1:4840`
    pub endpoint: Option<String>,
    pub allow_none: Option<bool>,
    pub anonymous_read: Option<bool>,
    pub pki_dir: Option<PathBuf>,
    /// `min_publish = "T#10ms"`: the shortest publishing and sampling interval granted.
    pub min_publish: Option<Duration>,
    /// `[[opcua.user]]`: name, argon2 password hash, role (`None` when not given).
    pub users: Vec<OpcuaUserEntry>,
}

/// One `[[opcua.user]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct OpcuaUserEntry {
    pub name: String,
    pub password_hash: String,
    /// `read`, `operate` or `admin`; `None` when the entry has no `role`.
    pub role: Option<sfc_runtime::OpcuaRole>,
}

/// The file being read: its text (for positions), name and directory (for relative paths).
struct Src<'a> {
    text: &'a str,
    name: String,
    dir: PathBuf,
}

type R<T> = Result<T, String>;

impl Src<'_> {
    fn err(&self, span: Option<Range<usize>>, message: impl std::fmt::Display) -> String {
        match span {
            Some(s) => {
                let before = &self.text[..s.start.min(self.text.len())];
                let line = before.matches('\n').count() + 1;
                let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
                format!("{}:{line}:{column}: {message}", self.name)
            }
            None => format!("{}: {message}", self.name),
        }
    }
    fn string(&self, key: &str, item: &Item) -> R<String> {
        item.as_str().map(str::to_string).ok_or_else(|| self.err(item.span(), format!("`{key}` must be a string")))
    }
    fn time(&self, key: &str, item: &Item) -> R<Duration> {
        let s = self.string(key, item)?;
        match parse_time(&s) {
            Some(t) if t > 0 => Ok(Duration::from_micros(t as u64)),
            Some(_) => Err(self.err(item.span(), format!("`{key}` must be positive, found `{s}`"))),
            None => Err(self.err(item.span(), format!("`{key}`: `{s}` is not a TIME literal (write e.g. \"T#10ms\")"))),
        }
    }
    fn bool(&self, key: &str, item: &Item) -> R<bool> {
        item.as_bool().ok_or_else(|| self.err(item.span(), format!("`{key}` must be true or false")))
    }
    fn path(&self, key: &str, item: &Item) -> R<PathBuf> {
        Ok(self.dir.join(self.string(key, item)?))
    }
    fn strings(&self, key: &str, item: &Item) -> R<Vec<String>> {
        let a = item.as_array().ok_or_else(|| self.err(item.span(), format!("`{key}` must be an array of strings")))?;
        a.iter()
            .map(|v| v.as_str().map(str::to_string).ok_or_else(|| self.err(v.span(), format!("`{key}` holds strings"))))
            .collect()
    }
    fn unknown(&self, table: &dyn TableLike, key: &str, known: &[&str], where_: &str) -> String {
        let span = table.key(key).and_then(|k| k.span());
        self.err(span, format!("unknown key `{key}` in {where_} (known: {})", known.join(", ")))
    }
}

/// A section: its name, its keys, and the function that reads it.
type Section = (&'static str, &'static [&'static str], fn(&Src<'_>, &dyn TableLike, &mut RunConfig) -> R<()>);

/// The sections a run configuration may have. A new server of `sfc run` adds its own here.
const SECTIONS: &[Section] = &[
    ("modbus", &["address", "max_clients", "idle_timeout", "word_order", "reset"], modbus_section),
    ("monitor", &["address", "token_file", "allow_origins", "allow_hosts"], monitor_section),
    ("retain", &["file", "interval", "enabled"], retain_section),
    ("safe", &[], safe_section),
    ("opcua", &["endpoint", "allow_none", "anonymous_read", "pki_dir", "min_publish", "user"], opcua_section),
];

const TOP_KEYS: &[&str] = &["chart", "pou", "period", "profile", "watchdog", "realtime", "on_fault"];

fn modbus_section(src: &Src<'_>, t: &dyn TableLike, c: &mut RunConfig) -> R<()> {
    for (key, item) in t.iter() {
        match key {
            "address" => c.modbus.address = Some(src.string(key, item)?),
            "max_clients" => {
                let n = item
                    .as_integer()
                    .filter(|n| *n >= 1)
                    .ok_or_else(|| src.err(item.span(), "`max_clients` must be a whole number of at least 1"))?;
                c.modbus.max_clients = Some(n as usize);
            }
            "idle_timeout" => c.modbus.idle_timeout = Some(src.time(key, item)?),
            "word_order" => {
                let s = src.string(key, item)?;
                if sfc_runtime::io::WordOrder::from_name(&s).is_none() {
                    return Err(src.err(item.span(), format!("`word_order` is \"big\" or \"little\", found \"{s}\"")));
                }
                c.modbus.word_order = Some(s);
            }
            "reset" => c.modbus.reset = Some(src.bool(key, item)?),
            _ => return Err(src.unknown(t, key, SECTIONS[0].1, "[modbus]")),
        }
    }
    Ok(())
}

fn monitor_section(src: &Src<'_>, t: &dyn TableLike, c: &mut RunConfig) -> R<()> {
    for (key, item) in t.iter() {
        match key {
            "address" => c.monitor.address = Some(src.string(key, item)?),
            "token_file" => c.monitor.token_file = Some(src.path(key, item)?),
            "allow_origins" => c.monitor.allow_origins = Some(src.strings(key, item)?),
            "allow_hosts" => c.monitor.allow_hosts = src.strings(key, item)?,
            _ => return Err(src.unknown(t, key, SECTIONS[1].1, "[monitor]")),
        }
    }
    Ok(())
}

fn retain_section(src: &Src<'_>, t: &dyn TableLike, c: &mut RunConfig) -> R<()> {
    for (key, item) in t.iter() {
        match key {
            "file" => c.retain.file = Some(src.path(key, item)?),
            "interval" => c.retain.interval = Some(src.time(key, item)?),
            "enabled" => c.retain.enabled = Some(src.bool(key, item)?),
            _ => return Err(src.unknown(t, key, SECTIONS[2].1, "[retain]")),
        }
    }
    Ok(())
}

/// `[opcua]` and its `[[opcua.user]]` entries (`name`, `password_hash`).
fn opcua_section(src: &Src<'_>, t: &dyn TableLike, c: &mut RunConfig) -> R<()> {
    for (key, item) in t.iter() {
        match key {
            "endpoint" => c.opcua.endpoint = Some(src.string(key, item)?),
            "allow_none" => c.opcua.allow_none = Some(src.bool(key, item)?),
            "anonymous_read" => c.opcua.anonymous_read = Some(src.bool(key, item)?),
            "pki_dir" => c.opcua.pki_dir = Some(src.path(key, item)?),
            "min_publish" => c.opcua.min_publish = Some(src.time(key, item)?),
            "user" => {
                let users = item.as_array_of_tables().ok_or_else(|| {
                    src.err(item.span(), "users are `[[opcua.user]]` entries with `name` and `password_hash`")
                })?;
                for u in users.iter() {
                    let (mut name, mut hash, mut role) = (None, None, None);
                    for (k, v) in u.iter() {
                        match k {
                            "name" => name = Some(src.string(k, v)?),
                            "password_hash" => {
                                let h = src.string(k, v)?;
                                if !h.starts_with("$argon2") {
                                    return Err(src.err(
                                        v.span(),
                                        "`password_hash` must be an argon2 hash (make one with `sfc run --hash-password`), \
                                         not a password",
                                    ));
                                }
                                hash = Some(h);
                            }
                            "role" => {
                                let r = src.string(k, v)?;
                                role = Some(sfc_runtime::OpcuaRole::from_name(&r).ok_or_else(|| {
                                    src.err(
                                        v.span(),
                                        format!(
                                            "`role` is \"read\" (read and subscribe), \"operate\" (also write \
                                             inputs and memory) or \"admin\" (also Halt, Continue, Reset), found \"{r}\""
                                        ),
                                    )
                                })?);
                            }
                            _ => return Err(src.unknown(u, k, &["name", "password_hash", "role"], "[[opcua.user]]")),
                        }
                    }
                    match (name, hash) {
                        (Some(name), Some(password_hash)) => {
                            c.opcua.users.push(OpcuaUserEntry { name, password_hash, role })
                        }
                        _ => return Err(src.err(u.span(), "an `[[opcua.user]]` needs `name` and `password_hash`")),
                    }
                }
            }
            _ => return Err(src.unknown(t, key, SECTIONS[4].1, "[opcua]")),
        }
    }
    Ok(())
}

/// `[safe]`: `Name = false`, `Speed = 0`, `Level = 2.5`, `Delay = "T#1s"`, `Mode = "Auto"`.
fn safe_section(src: &Src<'_>, t: &dyn TableLike, c: &mut RunConfig) -> R<()> {
    for (key, item) in t.iter() {
        let text = match item.as_value() {
            Some(toml_edit::Value::Boolean(b)) => if *b.value() { "TRUE" } else { "FALSE" }.to_string(),
            Some(toml_edit::Value::Integer(i)) => i.value().to_string(),
            Some(toml_edit::Value::Float(f)) => format!("{:?}", f.value()),
            Some(toml_edit::Value::String(s)) => s.value().clone(),
            _ => {
                return Err(
                    src.err(item.span(), format!("the safe value of `{key}` must be a boolean, a number or a string"))
                )
            }
        };
        c.safe.push((key.to_string(), text));
    }
    Ok(())
}

/// Reads the run configuration at `path`.
pub fn load(path: &Path) -> R<RunConfig> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    parse(&text, path)
}

/// Reads a run configuration's text (`path` names it in messages and anchors relative paths).
pub fn parse(text: &str, path: &Path) -> R<RunConfig> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")).to_path_buf();
    let src = Src { text, name: path.display().to_string(), dir };
    let doc = toml_edit::Document::parse(text.to_string())
        .map_err(|e| src.err(e.span(), format!("TOML syntax error: {}", e.message().trim())))?;
    let mut c = RunConfig { file: path.to_path_buf(), ..Default::default() };
    let root = doc.as_table();
    for (key, item) in root.iter() {
        if let Some((name, _, read)) = SECTIONS.iter().find(|s| s.0 == key) {
            let t = item
                .as_table_like()
                .ok_or_else(|| src.err(item.span(), format!("`{name}` must be a section ([{name}])")))?;
            read(&src, t, &mut c)?;
            continue;
        }
        match key {
            "chart" => c.chart = Some(src.path(key, item)?),
            "pou" => c.pou = Some(src.string(key, item)?),
            "period" => {
                src.time(key, item)?;
                c.period = Some(src.string(key, item)?);
            }
            "watchdog" => {
                src.time(key, item)?;
                c.watchdog = Some(src.string(key, item)?);
            }
            "profile" => {
                let s = src.string(key, item)?;
                c.profile = Some(sfc_sim::Profile::from_name(&s).ok_or_else(|| {
                    src.err(
                        item.span(),
                        format!("unknown profile \"{s}\" (expected iec, matiec, codesys, grafcet, logix or graph)"),
                    )
                })?);
            }
            "realtime" => c.realtime = Some(src.bool(key, item)?),
            "on_fault" => {
                let s = src.string(key, item)?;
                if s != "wait" && s != "exit" {
                    return Err(src.err(item.span(), format!("`on_fault` is \"wait\" or \"exit\", found \"{s}\"")));
                }
                c.on_fault = Some(s);
            }
            _ => {
                let mut known: Vec<&str> = TOP_KEYS.to_vec();
                known.extend(SECTIONS.iter().map(|s| s.0));
                return Err(src.unknown(root, key, &known, "the run configuration"));
            }
        }
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_configuration() {
        let text = r#"
chart = "carwash.st"
period = "T#5ms"
watchdog = "T#50ms"
realtime = true
on_fault = "exit"

[modbus]
address = "127.0.0.1:1502"
max_clients = 8
idle_timeout = "T#30s"
word_order = "little"

[monitor]
address = "127.0.0.1:9002"
token_file = "token.txt"
allow_origins = ["http://127.0.0.1:8080"]

[retain]
file = "state/carwash.retain"
interval = "T#500ms"

[safe]
Blower = true
Speed = -5
Delay = "T#1s"
"#;
        let c = parse(text, Path::new("/etc/sfc/plant.toml")).unwrap();
        assert_eq!(c.chart, Some(PathBuf::from("/etc/sfc/carwash.st")));
        assert_eq!(
            (c.period.as_deref(), c.watchdog.as_deref(), c.realtime),
            (Some("T#5ms"), Some("T#50ms"), Some(true))
        );
        assert_eq!(c.modbus.max_clients, Some(8));
        assert_eq!(c.modbus.idle_timeout, Some(Duration::from_secs(30)));
        assert_eq!(c.monitor.token_file, Some(PathBuf::from("/etc/sfc/token.txt")));
        assert_eq!(c.retain.file, Some(PathBuf::from("/etc/sfc/state/carwash.retain")));
        assert_eq!(c.retain.interval, Some(Duration::from_millis(500)));
        assert_eq!(
            c.safe,
            vec![("Blower".into(), "TRUE".into()), ("Speed".into(), "-5".into()), ("Delay".into(), "T#1s".into())]
        );
    }

    #[test]
    fn an_opcua_section_with_users() {
        let text = "[opcua]\nendpoint = \"opc.tcp://127.0.0.1:4840\"\npki_dir = \"pki\"\nanonymous_read = true\n\n\
                    min_publish = \"T#20ms\"\n\
                    [[opcua.user]]\nname = \"scada\"\npassword_hash = \"$argon2id$v=19$m=19456,t=2,p=1$c2FsdA$aGFzaA\"\n\
                    [[opcua.user]]\nname = \"hmi\"\npassword_hash = \"$argon2id$v=19$m=19456,t=2,p=1$c2FsdA$aGFzaA\"\n\
                    role = \"read\"\n";
        let c = parse(text, Path::new("/etc/sfc/plant.toml")).unwrap();
        assert_eq!(c.opcua.endpoint.as_deref(), Some("opc.tcp://127.0.0.1:4840"));
        assert_eq!(c.opcua.pki_dir, Some(PathBuf::from("/etc/sfc/pki")));
        assert_eq!(c.opcua.anonymous_read, Some(true));
        assert_eq!(c.opcua.min_publish, Some(Duration::from_millis(20)));
        assert_eq!(c.opcua.users.len(), 2);
        assert_eq!((c.opcua.users[0].name.as_str(), c.opcua.users[0].role), ("scada", None));
        assert_eq!(
            (c.opcua.users[1].name.as_str(), c.opcua.users[1].role),
            ("hmi", Some(sfc_runtime::OpcuaRole::Read))
        );
        let e = parse(
            "[[opcua.user]]\nname = \"s\"\npassword_hash = \"$argon2id$x\"\nrole = \"root\"\n",
            Path::new("p.toml"),
        )
        .unwrap_err();
        assert!(e.starts_with("p.toml:4:8:") && e.contains("\"operate\""), "{e}");
        // A password where its hash belongs is refused, located.
        let e =
            parse("[[opcua.user]]\nname = \"scada\"\npassword_hash = \"secret\"\n", Path::new("p.toml")).unwrap_err();
        assert!(e.starts_with("p.toml:3:") && e.contains("argon2"), "{e}");
        let e = parse("[[opcua.user]]\nname = \"scada\"\n", Path::new("p.toml")).unwrap_err();
        assert!(e.contains("needs `name` and `password_hash`"), "{e}");
    }

    #[test]
    fn mistakes_are_located() {
        let e = parse("period = \"T#5ms\"\nperiode = 1\n", Path::new("p.toml")).unwrap_err();
        assert!(e.starts_with("p.toml:2:1: unknown key `periode`"), "{e}");
        let e = parse("[modbus]\nmax_clients = 0\n", Path::new("p.toml")).unwrap_err();
        assert!(e.starts_with("p.toml:2:15:"), "{e}");
        let e = parse("watchdog = \"50ms\"\n", Path::new("p.toml")).unwrap_err();
        assert!(e.contains("not a TIME literal"), "{e}");
        let e = parse("[opcua]\nport = 4840\n", Path::new("p.toml")).unwrap_err();
        assert!(e.starts_with("p.toml:2:1: unknown key `port` in [opcua]"), "{e}");
        let e = parse("[modbus\n", Path::new("p.toml")).unwrap_err();
        assert!(e.contains("TOML syntax error"), "{e}");
    }
}
