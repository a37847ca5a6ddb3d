//! Witnesses: an engine's path (the inputs of every scan) completed into a run of the whole
//! model, written as a scenario file whose failing expectation is the property itself
//! (`always`/`never` over the run, `within` after the trigger), and replayed in the simulator.

use crate::aig::Aig;
use crate::compile::{Compiled, Origin, Signal};
use crate::model::Model;
use crate::props::{Bound, Kind, PropertyFile};
use crate::sat;
use crate::system::System;
use sfc_sim::format_time;
use sfc_st::Type;
use std::path::Path;

/// A run of the model that violates (or reaches) a property.
#[derive(Debug, Clone)]
pub struct Witness {
    /// Per scan: the inputs to set before it (name, TOML value), only those that change.
    pub sets: Vec<Vec<(String, String)>>,
    /// The scan in which the property fails (or the goal is met): the last scan of the run.
    pub last: usize,
    /// For responses: the scan of the trigger.
    pub trigger: Option<usize>,
    /// The active steps of the top chart after the last scan.
    pub active_end: Vec<String>,
}

/// What replaying a witness in the simulator showed.
#[derive(Debug, Clone)]
pub struct Replay {
    /// The simulator reproduces the violation (or reaches the situation).
    pub confirmed: bool,
    /// The scenario's failures, or why it could not run.
    pub detail: Vec<String>,
}

fn reg_value(m: &Model, sys: &System, state: &[bool], r: usize) -> Option<i128> {
    let reg = &m.regs[r];
    let mut bits = vec![None; reg.stored];
    for (k, sv) in sys.state.iter().enumerate() {
        if sv.reg == r {
            bits[sv.bit] = Some(state[k]);
        }
    }
    // Constant registers hold their initial value.
    if bits.iter().all(Option::is_none) {
        return Some(reg.init);
    }
    let mut v: i128 = 0;
    for (i, b) in bits.iter().enumerate() {
        if b.unwrap_or(false) && i < 127 {
            v |= 1 << i;
        }
    }
    let signed = reg.range.map_or(reg.signed, |(lo, _)| lo < 0);
    if signed && reg.stored > 0 && reg.stored < 127 && (v >> (reg.stored - 1)) & 1 == 1 {
        v -= 1 << reg.stored;
    }
    Some(v)
}

/// A value of type `ty` as a TOML value of a scenario's `set`.
pub fn toml_value(ty: &Type, v: i128) -> String {
    if ty.is_bool() {
        return (v != 0).to_string();
    }
    if ty.is_duration() {
        return format!("\"{}\"", format_time(v as i64));
    }
    if let Type::Enum { values, .. } = ty {
        if let Some((n, _)) = values.iter().find(|(_, o)| *o as i128 == v) {
            return format!("\"{n}\"");
        }
    }
    v.to_string()
}

/// A TOML basic string.
pub fn toml_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A key of a TOML table (bare when possible).
fn toml_key(k: &str) -> String {
    if !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
        k.to_string()
    } else {
        toml_string(k)
    }
}

impl Witness {
    /// Completes `trace` (inputs of the property's cone, per scan) into a run of the whole
    /// model: the other inputs keep their values where the assumptions allow.
    pub fn build(
        m: &Model,
        full: &System,
        trace: &[Vec<(u32, bool)>],
        c: &Compiled,
        _file: &PropertyFile,
        _period: i64,
    ) -> Result<Witness, String> {
        let mut state = full.init_state();
        let mut sets = Vec::new();
        let var_slot: std::collections::HashMap<u32, usize> =
            full.state.iter().enumerate().filter_map(|(k, s)| full.g.var_of(s.lit).map(|v| (v, k))).collect();
        for (scan, fixed) in trace.iter().enumerate() {
            // Defaults: every variable input keeps the value it has in memory.
            let mut inputs: Vec<(u32, bool)> = Vec::new();
            for iv in &m.inputs {
                let keep = iv.reg.and_then(|r| reg_value(m, full, &state, r)).unwrap_or(0);
                for (b, l) in iv.lits.iter().enumerate() {
                    if let Some(v) = full.g.var_of(*l) {
                        inputs.push((v, b < 127 && (keep >> b) & 1 == 1));
                    }
                }
            }
            let fixed_map: std::collections::HashMap<u32, bool> = fixed.iter().copied().collect();
            for (v, b) in inputs.iter_mut() {
                if let Some(&f) = fixed_map.get(v) {
                    *b = f;
                }
            }
            let table = full.eval(&state, &inputs);
            let inputs = if Aig::value(&table, full.constraint) {
                inputs
            } else {
                let st: Vec<(u32, bool)> =
                    full.state.iter().zip(&state).filter_map(|(s, &b)| full.g.var_of(s.lit).map(|v| (v, b))).collect();
                let got = sat::complete_inputs(full, &st, fixed)
                    .ok_or_else(|| format!("the assumptions exclude every input in scan {scan}"))?;
                let got_map: std::collections::HashMap<u32, bool> = got.into_iter().collect();
                inputs.into_iter().map(|(v, b)| (v, got_map.get(&v).copied().unwrap_or(b))).collect()
            };
            let table = full.eval(&state, &inputs);
            if !Aig::value(&table, full.constraint) {
                return Err(format!("the completed inputs violate the assumptions in scan {scan}"));
            }
            // The `set` entries: inputs whose value differs from memory.
            let input_map: std::collections::HashMap<u32, bool> = inputs.iter().copied().collect();
            let mut scan_sets = Vec::new();
            for iv in &m.inputs {
                let Some(r) = iv.reg else { continue };
                let mut v: i128 = 0;
                for (b, l) in iv.lits.iter().enumerate() {
                    let bit = full.g.var_of(*l).and_then(|x| input_map.get(&x).copied()).unwrap_or(false);
                    if bit && b < 127 {
                        v |= 1 << b;
                    }
                }
                if iv.signed && !iv.lits.is_empty() && iv.lits.len() < 127 && (v >> (iv.lits.len() - 1)) & 1 == 1 {
                    v -= 1 << iv.lits.len();
                }
                let before = if scan == 0 { Some(m.regs[r].init) } else { reg_value(m, full, &state, r) };
                if before != Some(v) || scan == 0 {
                    scan_sets.push((m.regs[r].name.clone(), toml_value(&m.regs[r].ty, v)));
                }
            }
            sets.push(scan_sets);
            state = full.state.iter().map(|s| Aig::value(&table, s.next)).collect();
            let _ = &var_slot;
        }
        // The property must hold where the engine said: check it on the completed run.
        let table = full.eval(&state, &[]);
        let reached = match c.signal {
            Signal::Safety { bad } => Aig::value(&table, bad),
            Signal::Reach { goal, from_initial: true } => Aig::value(&table, goal),
            Signal::Reach { .. } => true,
        };
        if !reached {
            return Err("the completed run does not show the engine's result".into());
        }
        let last = trace.len().saturating_sub(1);
        let trigger = match (&c.origin, c.scans) {
            (Origin::User(_), Some(n)) => Some(last.saturating_sub(n as usize)),
            _ => None,
        };
        // The active steps of every chart, named as the simulator names them (`Step`,
        // `Rev.Step`, `Cyl.ACT_Extend.Step`).
        let mut active_end = Vec::new();
        for ch in &m.charts {
            for &r in &ch.x {
                if reg_value(m, full, &state, r) == Some(1) {
                    active_end.push(m.regs[r].name.trim_end_matches(".X").to_string());
                }
            }
        }
        Ok(Witness { sets, last, trigger, active_end })
    }

    /// The scenario file text and the line of the entry that states the property;
    /// `chart` as the scenario names it (relative to the witness file).
    #[allow(clippy::too_many_arguments)]
    pub fn scenario(
        &self,
        chart: &str,
        pou: &str,
        period: i64,
        profile: sfc_sim::Profile,
        c: &Compiled,
        file: &PropertyFile,
        own_name: &str,
    ) -> (String, u32) {
        let t = |k: usize| format_time(k as i64 * period);
        let mut head = String::new();
        let (what, check) = describe(c, file, m_range_name(c), period);
        head.push_str(&format!(
            "# Witness for the property {} of {}, found by `sfc prove`.\n",
            toml_string(&c.name),
            file_name(&file.path)
        ));
        head.push_str(&format!("# {what}\n"));
        match check {
            Check::Trap(_) | Check::Reached(_) => head.push_str(&format!("# Replay it with `sfc test {own_name}`.\n")),
            _ => head.push_str(&format!(
                "# Replay it with `sfc test {own_name}`: the expectation that fails is the property itself.\n"
            )),
        }
        head.push_str(&format!("chart = {}\n", toml_string(chart)));
        head.push_str(&format!("pou = {}\n", toml_string(pou)));
        head.push_str(&format!("period = \"{}\"\n", format_time(period)));
        if profile != sfc_sim::Profile::Iec {
            head.push_str(&format!("profile = \"{}\"\n", profile.name()));
        }
        head.push_str(&format!("scans = {}\n", self.last + 1));
        // The property's entries: (scan, text); the last one is the property itself.
        let active = self.active_end.iter().map(|s| toml_string(s)).collect::<Vec<_>>().join(", ");
        let own: Vec<(usize, String)> = match &check {
            Check::Always(e) | Check::Never(e) => vec![(
                0,
                format!(
                    "# The property over the whole run: it fails after scan {} ({}).\n[[at]]\ntime = \"T#0s\"\nto = \"{}\"\n{} = {}\n",
                    self.last,
                    t(self.last),
                    t(self.last),
                    if matches!(check, Check::Always(_)) { "always" } else { "never" },
                    toml_string(e)
                ),
            )],
            Check::Response { after, expect, within } => {
                // The property itself, with its triggers up to the one that is not answered (an
                // earlier unanswered trigger would have made a shorter witness).
                let k = self.trigger.unwrap_or(0);
                vec![(
                    0,
                    format!(
                        "# The trigger rises in scan {k} ({}) and the response does not follow within {}.\n[[at]]\ntime = \"T#0s\"\nto = \"{}\"\nafter = {}\nwithin = \"{}\"\nexpect = {}\n",
                        t(k),
                        format_time(*within),
                        t(k),
                        toml_string(after),
                        format_time(*within),
                        toml_string(expect)
                    ),
                )]
            }
            Check::Fault => vec![(
                self.last,
                format!(
                    "# The run stops with a runtime error in scan {} ({}).\n[[at]]\ntime = \"{}\"\nexpect = {{ active = [{active}] }}\n",
                    self.last,
                    t(self.last),
                    t(self.last)
                ),
            )],
            Check::Reached(goal) => vec![(
                self.last,
                format!(
                    "# The goal is reached after scan {} ({}).\n[[at]]\ntime = \"{}\"\nexpect = {}\n",
                    self.last,
                    t(self.last),
                    t(self.last),
                    toml_string(goal)
                ),
            )],
            Check::Trap(goal) => vec![(
                self.last,
                format!(
                    "# After scan {} ({}) the chart is in a situation from which no input sequence makes\n# {} TRUE again: the run reaches it.\n[[at]]\ntime = \"{}\"\nexpect = {{ active = [{active}] }}\n",
                    self.last,
                    t(self.last),
                    goal,
                    t(self.last)
                ),
            )],
        };
        // Entries in time order: the inputs of a scan first, then what is checked from it.
        let mut out = head;
        let mut own_line = 0u32;
        let mut pending = own.into_iter().peekable();
        for (k, sets) in self.sets.iter().enumerate() {
            if !sets.is_empty() {
                let items: Vec<String> = sets.iter().map(|(n, v)| format!("{} = {v}", toml_key(n))).collect();
                out.push_str(&format!("\n[[at]]\ntime = \"{}\"\nset = {{ {} }}\n", t(k), items.join(", ")));
            }
            while pending.peek().is_some_and(|(s, _)| *s == k) {
                let (_, text) = pending.next().unwrap_or_default();
                out.push('\n');
                let at = text.lines().position(|l| l == "[[at]]").unwrap_or(0);
                own_line = out.lines().count() as u32 + at as u32 + 1;
                out.push_str(&text);
            }
        }
        for (_, text) in pending {
            out.push('\n');
            let at = text.lines().position(|l| l == "[[at]]").unwrap_or(0);
            own_line = out.lines().count() as u32 + at as u32 + 1;
            out.push_str(&text);
        }
        (out, own_line)
    }
}

enum Check {
    Always(String),
    Never(String),
    Response { after: String, expect: String, within: i64 },
    Fault,
    Trap(String),
    Reached(String),
}

fn m_range_name(c: &Compiled) -> Option<&str> {
    match &c.origin {
        Origin::Range { .. } => c.name.strip_prefix("range of ").and_then(|s| s.split(" (").next()),
        _ => None,
    }
}

fn file_name(p: &str) -> String {
    Path::new(p).file_name().map_or_else(|| p.to_string(), |f| f.to_string_lossy().into_owned())
}

fn describe(c: &Compiled, file: &PropertyFile, range_var: Option<&str>, period: i64) -> (String, Check) {
    match &c.origin {
        Origin::User(k) => {
            let p = &file.properties[*k];
            match &p.kind {
                Kind::Always(x) => (format!("always {}", x.src.text), Check::Always(x.src.text.clone())),
                Kind::Never(x) => (format!("never {}", x.src.text), Check::Never(x.src.text.clone())),
                Kind::Response { after, expect, bound } => {
                    let within = match bound {
                        Bound::Time(t) => *t,
                        Bound::Scans(n) => *n as i64 * period,
                    };
                    (
                        format!(
                            "after {} rises, {} holds within {}",
                            after.src.text,
                            expect.src.text,
                            format_time(within)
                        ),
                        Check::Response { after: after.src.text.clone(), expect: expect.src.text.clone(), within },
                    )
                }
                Kind::Reachable { goal, from_initial: true } => (
                    format!("{} is reached from the initial situation", goal.src.text),
                    Check::Reached(goal.src.text.clone()),
                ),
                Kind::Reachable { goal, .. } => {
                    (format!("{} can always be reached again", goal.src.text), Check::Trap(goal.src.text.clone()))
                }
            }
        }
        Origin::Range { reg: _, lo, hi } => {
            let v = range_var.unwrap_or("?").to_string();
            let fmt = |x: i128| -> String {
                if c.name.contains("T#") {
                    format_time(x as i64)
                } else {
                    x.to_string()
                }
            };
            let e = format!("{v} >= {} AND {v} <= {}", fmt(*lo), fmt(*hi));
            (format!("{v} stays within {}..{}", fmt(*lo), fmt(*hi)), Check::Always(e))
        }
        Origin::Fault => ("no runtime error stops the run".into(), Check::Fault),
    }
}

/// Replays a witness scenario (its text) in the simulator.
/// What a replayed witness must show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expect {
    /// Its last expectation (the property) fails.
    Fails,
    /// The run stops with a runtime error in its last scan.
    Fault,
    /// It passes (a situation reached).
    Passes,
}

impl Expect {
    pub fn of(c: &Compiled) -> Expect {
        match (&c.origin, &c.signal) {
            (Origin::Fault, _) => Expect::Fault,
            (_, Signal::Safety { .. }) => Expect::Fails,
            (_, Signal::Reach { .. }) => Expect::Passes,
        }
    }
}

/// The file name of the witness of property `name` of `chart` (`door.st` →
/// `door.never-both-directions.witness.toml`).
pub fn file_name_for(chart: &str, name: &str) -> String {
    let stem = Path::new(chart).file_stem().map_or_else(|| "chart".to_string(), |s| s.to_string_lossy().into_owned());
    let mut slug = String::new();
    for ch in name.chars() {
        if ch.is_ascii_alphanumeric() {
            slug.push(ch.to_ascii_lowercase());
        } else if !slug.ends_with('-') {
            slug.push('-');
        }
    }
    let slug = slug.trim_matches('-');
    let slug = if slug.is_empty() { "property" } else { slug };
    format!("{stem}.{slug}.witness.toml")
}

/// Replays the witness `scenario` (named `file`, not yet written) in the simulator.
pub fn replay(
    chart_name: &str,
    chart_text: &str,
    file: &str,
    scenario: &str,
    own_line: u32,
    violation: Expect,
) -> Replay {
    // The scenario names the chart by file name, resolved beside the witness file, as if it
    // were written beside the chart (the default); failures name the witness file.
    let path = Path::new(chart_name).parent().unwrap_or(Path::new("")).join(file);
    let s = match sfc_sim::scenario::load_text(&path, scenario, Some(chart_text)) {
        Ok(s) => s,
        Err(e) => return Replay { confirmed: false, detail: vec![e.to_string()] },
    };
    let out = sfc_sim::scenario::run(&s, None);
    let mut detail = out.failures.clone();
    if let Some(e) = &out.error {
        detail.push(e.clone());
    }
    let total = s.total_scans();
    let confirmed = match violation {
        Expect::Fault => out.error.is_some() && out.scans == total,
        Expect::Fails => {
            // The property's own entry must be the one that fails.
            out.failures.iter().any(|f| f.contains(&format!(":{own_line}:")))
        }
        Expect::Passes => out.passed(),
    };
    Replay { confirmed, detail }
}

/// A value of a scenario's `set` (TOML text) as JSON.
pub fn json_value(toml: &str) -> serde_json::Value {
    match toml {
        "true" => serde_json::Value::Bool(true),
        "false" => serde_json::Value::Bool(false),
        t if t.starts_with('"') && t.ends_with('"') && t.len() >= 2 => {
            serde_json::Value::String(t[1..t.len() - 1].to_string())
        }
        t => t.parse::<i64>().map_or_else(|_| serde_json::Value::String(t.to_string()), |n| serde_json::json!(n)),
    }
}
