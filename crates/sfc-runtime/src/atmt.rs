//! The ATMT/EATMT adapter: serves the monitor protocol for a REX ATMT/EATMT block running
//! elsewhere, from its transition table and a stream of `state condition_bits` lines
//! (`docs/runtime.md`, "ATMT adapter").
//!
//! Each line is one observation ("scan") of the block: its state index (decimal) and its
//! condition inputs as bits, `0x…` hexadecimal or a binary string (`0b…`, or only `0`/`1`),
//! written like a number: input 0 is the least significant (rightmost) bit. Steps are named
//! from the chart when one is given (`sfc.tag` state numbers → step names), else `S0…`;
//! transitions are the chart's, else `R0…` by rule position.

use crate::board::{reply_err, reply_ok, BreakOp, BreakTarget, ChartInfo, Command, Hub, Request, ScanState, VarInfo};
use crate::jitter::ScanStats;
use crate::RunReport;
use sfc_diagnostics::{render_human, RenderOptions};
use sfc_sim::Value;
use std::collections::BTreeMap;
use std::io::BufRead;
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// The longest bit string accepted (EATMT has 256 inputs; this leaves room).
const MAX_BITS: usize = 4096;

/// One rule of the table, with the transition it stands for.
#[derive(Debug, Clone, PartialEq)]
pub struct AtmtRule {
    pub state: u32,
    /// The input index; `1000 + index` when negated.
    pub condition: u32,
    pub next: u32,
    pub name: String,
}

impl AtmtRule {
    fn input(&self) -> u32 {
        self.condition % 1000
    }
    fn holds(&self, bits: &[bool]) -> bool {
        let b = bits.get(self.input() as usize).copied().unwrap_or(false);
        if self.condition >= 1000 {
            !b
        } else {
            b
        }
    }
}

/// A transition table with names.
#[derive(Debug, Clone, PartialEq)]
pub struct AtmtModel {
    pub pou: String,
    /// Step name of each state number.
    pub steps: Vec<String>,
    /// Rules in table order (the order the block tests them).
    pub rules: Vec<AtmtRule>,
}

impl AtmtModel {
    /// A table line `N[s c n;…][t …]` (as `sfc build --target atmt` writes it).
    pub fn from_table(text: &str) -> Result<AtmtModel, String> {
        let line = text.trim();
        let (rules, timeouts) = sfc_codegen::atmt::parse_table(line)
            .ok_or("not a transition table: expected `N[s c n;…][t0 … tM-1]` with N rules")?;
        let m = rules.iter().map(|r| r.state.max(r.next) as usize + 1).max().unwrap_or(1).max(timeouts.len());
        if m > sfc_codegen::atmt::MAX_STATE_NUMBERS {
            return Err(format!("the table uses state {}, more than an ATMT block has", m - 1));
        }
        Ok(AtmtModel {
            pou: "ATMT".into(),
            steps: (0..m).map(|s| format!("S{s}")).collect(),
            rules: rules
                .iter()
                .enumerate()
                .map(|(i, r)| AtmtRule { state: r.state, condition: r.condition, next: r.next, name: format!("R{i}") })
                .collect(),
        })
    }

    /// The table of an SFC chart with target `atmt` or `eatmt` (a chart without a target is
    /// read as `atmt`), with its step and transition names. Errors are rendered diagnostics.
    pub fn from_chart(name: &str, text: &str, pou: Option<&str>) -> Result<AtmtModel, String> {
        let checked = sfc_model::check_source(0, name, text, &sfc_model::CheckOptions::default());
        let render = |diags: &[sfc_diagnostics::Diagnostic]| {
            diags
                .iter()
                .filter(|d| d.is_error())
                .map(|d| render_human(d, std::slice::from_ref(&checked.file), RenderOptions::default()))
                .collect::<Vec<_>>()
                .join("\n")
        };
        if checked.has_errors() {
            return Err(render(&checked.diagnostics));
        }
        let chart = match pou {
            Some(p) => checked.charts.iter().find(|c| c.pou.eq_ignore_ascii_case(p)),
            None if checked.charts.len() == 1 => checked.charts.first(),
            None => None,
        }
        .ok_or_else(|| match pou {
            Some(p) => format!("{name}: no SFC POU named `{p}`"),
            None => format!("{name}: {} SFC POUs: choose one with --pou", checked.charts.len()),
        })?;
        let target = match chart.target {
            sfc_model::Target::Blank => sfc_model::Target::Atmt,
            t => t,
        };
        let limits = sfc_model::Limits::of(target, None, None);
        let table = sfc_codegen::atmt::build_table(chart, target, limits, false).map_err(|d| render(&d))?;
        let (rules, _) = sfc_codegen::atmt::parse_table(&table.text).ok_or("internal: unreadable table")?;
        let numbers = chart.state_numbers();
        let mut steps: Vec<String> = (0..table.states).map(|s| format!("S{s}")).collect();
        for (s, step) in chart.steps.iter().enumerate() {
            if let Some(slot) = numbers.get(s).and_then(|&n| steps.get_mut(n as usize)) {
                *slot = step.name.clone();
            }
        }
        // The rules in table order, each named by its transition: build_table sorts by state,
        // then explicit priority, then declaration order.
        let mut named: Vec<(u32, (u8, i64, usize), String)> = Vec::new();
        for (i, t) in chart.transitions.iter().enumerate() {
            let (Some(&from), Some(_)) = (t.from.first(), t.to.first()) else { continue };
            let key = match t.priority {
                Some(p) => (0u8, p, i),
                None => (1u8, 0, i),
            };
            let Some(&number) = numbers.get(from) else { continue };
            named.push((number, key, t.name.clone()));
        }
        named.sort_by_key(|r| (r.0, r.1));
        if named.len() != rules.len() {
            return Err(format!("{name}: the table has {} rules for {} transitions", rules.len(), named.len()));
        }
        Ok(AtmtModel {
            pou: chart.pou.clone(),
            steps,
            rules: rules
                .iter()
                .zip(named)
                .map(|(r, n)| AtmtRule { state: r.state, condition: r.condition, next: r.next, name: n.2 })
                .collect(),
        })
    }

    /// The condition inputs the rules read, ascending.
    pub fn inputs(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.rules.iter().map(AtmtRule::input).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// What the monitor's `hello` describes: steps, rules as transitions, and the variables
    /// `state` and `c<i>` for each input read.
    pub fn info(&self) -> ChartInfo {
        let mut variables = vec![VarInfo {
            name: "state".into(),
            ty: "UDINT".into(),
            location: None,
            safe: None,
            section: crate::board::Section::Local,
        }];
        variables.extend(self.inputs().into_iter().map(|i| VarInfo {
            name: format!("c{i}"),
            ty: "BOOL".into(),
            location: None,
            safe: None,
            section: crate::board::Section::Input,
        }));
        ChartInfo {
            runtime: "atmt",
            profile: None,
            pou: self.pou.clone(),
            period: 0,
            steps: self.steps.iter().enumerate().map(|(i, s)| (s.clone(), i == 0)).collect(),
            transitions: self.rules.iter().map(|r| (r.name.clone(), vec![r.state], vec![r.next])).collect(),
            variables,
            control: false,
            charts: Vec::new(),
            actions: Vec::new(),
        }
    }
}

/// Parses one line: `Ok(None)` for a blank line or a `#` comment.
pub fn parse_line(line: &str) -> Result<Option<(u32, Vec<bool>)>, String> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(None);
    }
    let mut fields = line.split_whitespace();
    let (Some(state), Some(bits), None) = (fields.next(), fields.next(), fields.next()) else {
        return Err(format!("expected `state condition_bits`, found `{}`", clip(line)));
    };
    let state: u32 = state.parse().map_err(|_| format!("`{}` is not a state number", clip(state)))?;
    Ok(Some((state, parse_bits(bits)?)))
}

fn clip(s: &str) -> String {
    s.chars().take(40).collect()
}

/// `0x1F`, `0b101`, `101` → bits, index 0 = least significant.
pub fn parse_bits(s: &str) -> Result<Vec<bool>, String> {
    let (digits, radix) = if let Some(h) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        (h, 16)
    } else if let Some(b) = s.strip_prefix("0b").or_else(|| s.strip_prefix("0B")) {
        (b, 2)
    } else {
        (s, 2)
    };
    if digits.is_empty() {
        return Err(format!("`{}` has no digits", clip(s)));
    }
    let per = if radix == 16 { 4 } else { 1 };
    if digits.len() * per > MAX_BITS {
        return Err(format!("more than {MAX_BITS} condition bits"));
    }
    let mut bits = Vec::with_capacity(digits.len() * per);
    for c in digits.chars().rev() {
        let d = c.to_digit(radix).ok_or_else(|| {
            format!(
                "`{}` is not {}",
                clip(s),
                if radix == 16 { "hexadecimal" } else { "a binary string (0/1, or 0x… for hex)" }
            )
        })?;
        for k in 0..per {
            bits.push(d >> k & 1 == 1);
        }
    }
    Ok(bits)
}

/// Where the lines come from.
pub enum LineSource {
    /// Any reader (standard input); the run ends at its end.
    Reader(Box<dyn BufRead + Send>),
    /// A TCP listener: one connection after the other, until the run is stopped.
    Listen(std::net::TcpListener),
}

/// The observed block, shared by the line reader and the command thread.
#[derive(Default)]
struct Observed {
    breakpoints: BTreeMap<BreakTarget, bool>,
}

pub(crate) struct Adapter {
    pub model: AtmtModel,
    pub hub: Arc<Hub>,
    pub source: LineSource,
}

impl Adapter {
    /// Reads lines until the source ends or the run stops; the commands are served on their
    /// own thread meanwhile.
    pub fn run(self, rx: Receiver<Request>) -> RunReport {
        let shared = Arc::new(Mutex::new(Observed::default()));
        let cmd = {
            let shared = shared.clone();
            let hub = self.hub.clone();
            std::thread::Builder::new().name("sfc-atmt-commands".into()).spawn(move || commands(rx, &hub, &shared))
        };
        let mut obs = Observer {
            model: &self.model,
            hub: &self.hub,
            shared: &shared,
            prev: None,
            entered_at: 0,
            scan: 0,
            start: Instant::now(),
            line: 0,
            stats: ScanStats::default(),
        };
        match self.source {
            LineSource::Reader(r) => obs.read(r),
            LineSource::Listen(l) => {
                let _ = l.set_nonblocking(true);
                while !self.hub.stopping() {
                    match l.accept() {
                        Ok((stream, _)) => {
                            let _ = stream.set_nonblocking(false);
                            let _ = stream.set_read_timeout(Some(std::time::Duration::from_millis(200)));
                            obs.read(Box::new(std::io::BufReader::new(stream)));
                        }
                        Err(_) => std::thread::sleep(std::time::Duration::from_millis(50)),
                    }
                }
            }
        }
        {
            let mut b = self.hub.lock();
            b.push_halt(true, "end".into());
        }
        // The command thread ends when the hub drops its sender (Runtime::wait).
        drop(cmd);
        RunReport { stats: obs.stats, ..RunReport::default() }
    }
}

struct Observer<'a> {
    model: &'a AtmtModel,
    hub: &'a Hub,
    shared: &'a Mutex<Observed>,
    prev: Option<(u32, Vec<bool>)>,
    entered_at: i64,
    scan: u64,
    start: Instant,
    line: u64,
    stats: ScanStats,
}

impl Observer<'_> {
    /// The step of a state number the block reported (`S<n>` for a number the table lacks).
    fn step_name(&self, state: u32) -> String {
        self.model.steps.get(state as usize).cloned().unwrap_or_else(|| format!("S{state}"))
    }

    fn read(&mut self, mut r: Box<dyn BufRead + Send>) {
        let mut buf = String::new();
        loop {
            if self.hub.stopping() {
                return;
            }
            // A line longer than this is cut there (and judged as garbage).
            match std::io::Read::take(&mut r, 8192).read_line(&mut buf) {
                Ok(0) => {
                    if !buf.is_empty() {
                        self.line += 1;
                        self.observe(&std::mem::take(&mut buf));
                    }
                    return;
                }
                Ok(_) => {
                    self.line += 1;
                    self.observe(&std::mem::take(&mut buf));
                }
                Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {
                    // Keep a partial line: read_line appended what it got.
                    continue;
                }
                Err(e) if e.kind() == std::io::ErrorKind::InvalidData => {
                    buf.clear();
                    self.line += 1;
                    self.event(
                        serde_json::json!({"kind": "error", "message": format!("line {}: not UTF-8", self.line)}),
                    );
                }
                Err(_) => return,
            }
        }
    }

    fn event(&self, j: serde_json::Value) {
        self.hub.lock().push_event(j);
    }

    fn observe(&mut self, line: &str) {
        let (state, bits) = match parse_line(line) {
            Ok(Some(x)) => x,
            Ok(None) => return,
            Err(e) => {
                return self.event(serde_json::json!({"kind": "error", "message": format!("line {}: {e}", self.line)}))
            }
        };
        if state as usize >= self.model.steps.len() {
            return self.event(serde_json::json!({"kind": "error",
                "message": format!("line {}: state {state} is not a state of the table (0..{})", self.line, self.model.steps.len() - 1)}));
        }
        let now = self.start.elapsed().as_micros() as i64;
        let mut fired = Vec::new();
        let mut entered = false;
        let mut events = Vec::new();
        match &self.prev {
            None => entered = true,
            Some((p, pbits)) if *p != state => {
                entered = true;
                // The block took the first true rule of its state: judge by the inputs it saw
                // on the previous line, else on this one.
                let rule = [pbits, &bits].into_iter().find_map(|b| {
                    self.model
                        .rules
                        .iter()
                        .position(|r| r.state == *p && r.holds(b))
                        .filter(|&i| self.model.rules.get(i).is_some_and(|r| r.next == state))
                });
                match rule {
                    Some(i) => fired.push(i as u32),
                    None => events.push(serde_json::json!({"kind": "jump", "from": self.step_name(*p),
                        "to": self.step_name(state), "line": self.line})),
                }
            }
            Some(_) => {}
        }
        if entered {
            self.entered_at = now;
        }
        let guards = self
            .model
            .rules
            .iter()
            .enumerate()
            .filter(|(_, r)| r.state == state)
            .map(|(i, r)| (i as u32, Some(r.holds(&bits))))
            .collect();
        let mut values = vec![Value::Int(i64::from(state))];
        values.extend(
            self.model.inputs().into_iter().map(|i| Value::Bool(bits.get(i as usize).copied().unwrap_or(false))),
        );
        let st = ScanState {
            scan: self.scan,
            time: now,
            key: true,
            base: 0,
            clocks: Vec::new(),
            active: vec![(state, now - self.entered_at)],
            fired: fired.clone(),
            guards,
            guards_known: true,
            values,
            forced: Vec::new(),
            // The adapter knows neither actions nor the times of steps left.
            actions: Vec::new(),
            times: Vec::new(),
        };
        {
            let obs = self.shared.lock().unwrap_or_else(|e| e.into_inner());
            if entered && obs.breakpoints.get(&BreakTarget::Step(state)) == Some(&true) {
                events
                    .push(serde_json::json!({"kind": "breakpoint", "step": self.step_name(state), "scan": self.scan}));
            }
            for &t in &fired {
                if obs.breakpoints.get(&BreakTarget::Transition(t)) == Some(&true) {
                    let rule = self.model.rules.get(t as usize).map(|r| r.name.clone());
                    events.push(serde_json::json!({"kind": "breakpoint", "transition": rule, "scan": self.scan}));
                }
            }
        }
        self.stats.scans += 1;
        self.scan += 1;
        self.prev = Some((state, bits));
        let mut b = self.hub.lock();
        for e in events {
            b.push_event(e);
        }
        b.push_state(Arc::new(st), drop);
        b.stats = serde_json::json!({"scans": self.stats.scans, "lines": self.line});
    }
}

/// Serves breakpoints; the block cannot be halted, stepped or forced from here.
fn commands(rx: Receiver<Request>, hub: &Hub, shared: &Mutex<Observed>) {
    let info = &hub.info;
    let name = |t: BreakTarget| match t {
        BreakTarget::Step(s) => ("step", info.steps.get(s as usize).map(|s| s.0.clone()).unwrap_or_default()),
        BreakTarget::Transition(t) => {
            ("transition", info.transitions.get(t as usize).map(|t| t.0.clone()).unwrap_or_default())
        }
    };
    while let Ok(r) = rx.recv() {
        let mut obs = shared.lock().unwrap_or_else(|e| e.into_inner());
        let result: Result<(), String> = match r.command {
            Command::Breakpoint { op: BreakOp::DeleteAll, .. } => {
                obs.breakpoints.clear();
                Ok(())
            }
            Command::Breakpoint { target: None, .. } => Err("name a step or transition".into()),
            Command::Breakpoint { op: BreakOp::Set, target: Some(t) } => {
                obs.breakpoints.insert(t, true);
                Ok(())
            }
            Command::Breakpoint { op, target: Some(t) } => match obs.breakpoints.get_mut(&t) {
                None => Err(format!("no breakpoint on {} `{}`", name(t).0, name(t).1)),
                Some(e) => {
                    match op {
                        BreakOp::Disable => *e = false,
                        BreakOp::Enable => *e = true,
                        _ => {
                            obs.breakpoints.remove(&t);
                        }
                    }
                    Ok(())
                }
            },
            Command::Breakpoints => Ok(()),
            Command::Explain { step } => Err(format!(
                "the ATMT adapter sees only the block's state and condition bits, not its guards: it cannot explain `{step}`"
            )),
            Command::Mechanisms => Err(
                "the ATMT adapter sees one block's state and condition bits: it has no mechanisms to list".into(),
            ),
            Command::Timing => Err(
                "the ATMT adapter keeps no time analysis: the block's own step times are not reported to it".into(),
            ),
            _ => {
                Err("the ATMT adapter observes a block running elsewhere: it cannot halt, step, force or write".into())
            }
        };
        let list: Vec<serde_json::Value> = obs
            .breakpoints
            .iter()
            .map(|(&t, &enabled)| {
                let (kind, n) = name(t);
                serde_json::json!({"kind": kind, "name": n, "enabled": enabled})
            })
            .collect();
        let line = match result {
            Ok(()) => reply_ok(&r.id, serde_json::Value::Array(list)),
            Err(e) => reply_err(&r.id, e),
        };
        let _ = r.reply.try_send(line);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_are_written_like_numbers() {
        assert_eq!(parse_bits("0x5").unwrap(), vec![true, false, true, false]);
        assert_eq!(parse_bits("110").unwrap(), vec![false, true, true]);
        assert_eq!(parse_bits("0b1").unwrap(), vec![true]);
        assert!(parse_bits("12").is_err());
        assert!(parse_bits("0x").is_err());
        assert!(parse_bits("0xg").is_err());
        assert_eq!(parse_line("  # comment").unwrap(), None);
        assert_eq!(parse_line("3 0x1").unwrap(), Some((3, vec![true, false, false, false])));
        assert!(parse_line("3").is_err());
        assert!(parse_line("x 1").is_err());
        assert!(parse_line("1 1 1").is_err());
    }

    #[test]
    fn tables_name_states_and_rules() {
        let m = AtmtModel::from_table("2[0 1 1;1 1002 0][0 1.5]").unwrap();
        assert_eq!(m.steps, vec!["S0", "S1"]);
        assert_eq!(m.rules[1], AtmtRule { state: 1, condition: 1002, next: 0, name: "R1".into() });
        assert!(m.rules[1].holds(&[false, false, false]));
        assert!(AtmtModel::from_table("3[0 1 1][0]").is_err());
    }
}
