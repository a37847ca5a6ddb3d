//! A deliberately simple reference implementation of `semantics.md` (profile `iec`) for the
//! charts of the differential test: BOOL inputs, guards over inputs and step times, BOOL
//! variables and counting bodies as actions. It shares no code with the engine: the active set
//! is a `Vec<bool>`, the scan is a direct transcription of steps 1–8, and ACTION_CONTROL is the
//! per-qualifier function block of IEC 61131-3 (2nd ed. 2.6.4.5) written out by hand.

#![allow(dead_code)]

use std::fmt::Write as _;

/// An action qualifier.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Qual {
    N,
    R,
    S,
    L,
    D,
    P,
    SD,
    DS,
    SL,
    P1,
    P0,
}

impl Qual {
    pub const ALL: [Qual; 11] =
        [Qual::N, Qual::R, Qual::S, Qual::L, Qual::D, Qual::P, Qual::SD, Qual::DS, Qual::SL, Qual::P1, Qual::P0];
    /// The qualifiers of BOOL variables used as actions in the generated charts.
    pub const FOR_VARIABLES: [Qual; 9] =
        [Qual::N, Qual::R, Qual::S, Qual::L, Qual::D, Qual::P, Qual::SD, Qual::DS, Qual::SL];

    pub fn name(self) -> &'static str {
        match self {
            Qual::N => "N",
            Qual::R => "R",
            Qual::S => "S",
            Qual::L => "L",
            Qual::D => "D",
            Qual::P => "P",
            Qual::SD => "SD",
            Qual::DS => "DS",
            Qual::SL => "SL",
            Qual::P1 => "P1",
            Qual::P0 => "P0",
        }
    }

    /// L, D, SD, DS and SL take a duration (and can contend).
    pub fn timed(self) -> bool {
        matches!(self, Qual::L | Qual::D | Qual::SD | Qual::DS | Qual::SL)
    }

    fn index(self) -> usize {
        Qual::ALL.iter().position(|q| *q == self).unwrap()
    }
}

/// One action association of a step.
#[derive(Debug, Clone, PartialEq)]
pub struct Assoc {
    pub action: usize,
    pub qual: Qual,
    /// µs; only for timed qualifiers.
    pub duration: i64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    pub name: String,
    pub initial: bool,
    pub assocs: Vec<Assoc>,
}

/// A transition condition.
#[derive(Debug, Clone, PartialEq)]
pub enum Guard {
    True,
    /// `i<n>`
    Input(usize),
    /// `Step.T >= T#<us>us` (printed in ms when whole)
    StepTime(usize, i64),
    /// `Step.X`
    StepFlag(usize),
    /// A BOOL variable used as an action, read as a variable (its previous scan's `Q`).
    Variable(usize),
    /// `Action.Q` (`false`) or `Action.A` (`true`) of an action with a body.
    ActionFlag(usize, bool),
    Not(Box<Guard>),
    And(Box<Guard>, Box<Guard>),
    Or(Box<Guard>, Box<Guard>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Transition {
    pub name: String,
    pub from: Vec<usize>,
    pub to: Vec<usize>,
    pub priority: Option<u32>,
    pub guard: Guard,
}

/// What an action is.
#[derive(Debug, Clone, PartialEq)]
pub enum ActionKind {
    /// A BOOL output variable used as an action: it gets `Q`.
    Variable,
    /// An ACTION whose body is `<counter> := <counter> + 1; <qcopy> := <name>.Q;`.
    Body { counter: String, qcopy: String },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    pub name: String,
    pub kind: ActionKind,
}

/// A chart of the differential test, kept as data and printed as IEC 61131-3 text.
#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    pub pou: String,
    /// Inputs `i0 … i<n-1>`.
    pub inputs: usize,
    /// In declaration order.
    pub steps: Vec<Step>,
    /// In declaration order.
    pub transitions: Vec<Transition>,
    /// In declaration order (variables are declared in this order too).
    pub actions: Vec<Action>,
}

fn time_literal(us: i64) -> String {
    if us % 1000 == 0 {
        format!("T#{}ms", us / 1000)
    } else {
        format!("T#{}us", us)
    }
}

impl Chart {
    /// The guard as ST text, fully parenthesised.
    pub fn guard_text(&self, g: &Guard) -> String {
        match g {
            Guard::True => "TRUE".into(),
            Guard::Input(i) => format!("i{i}"),
            Guard::StepTime(s, us) => format!("{}.T >= {}", self.steps[*s].name, time_literal(*us)),
            Guard::StepFlag(s) => format!("{}.X", self.steps[*s].name),
            Guard::Variable(a) => self.actions[*a].name.clone(),
            Guard::ActionFlag(a, is_a) => format!("{}.{}", self.actions[*a].name, if *is_a { "A" } else { "Q" }),
            Guard::Not(a) => format!("NOT ({})", self.guard_text(a)),
            Guard::And(a, b) => format!("({}) AND ({})", self.guard_text(a), self.guard_text(b)),
            Guard::Or(a, b) => format!("({}) OR ({})", self.guard_text(a), self.guard_text(b)),
        }
    }

    fn step_list(&self, steps: &[usize]) -> String {
        let names: Vec<&str> = steps.iter().map(|&s| self.steps[s].name.as_str()).collect();
        if names.len() == 1 {
            names[0].to_string()
        } else {
            format!("({})", names.join(", "))
        }
    }

    /// The chart as a PROGRAM in IEC 61131-3 text.
    pub fn text(&self) -> String {
        let mut o = String::new();
        writeln!(o, "PROGRAM {}", self.pou).unwrap();
        o.push_str("    VAR_INPUT\n");
        for i in 0..self.inputs {
            writeln!(o, "        i{i} : BOOL;").unwrap();
        }
        o.push_str("    END_VAR\n    VAR_OUTPUT\n");
        for a in &self.actions {
            match &a.kind {
                ActionKind::Variable => writeln!(o, "        {} : BOOL;", a.name).unwrap(),
                ActionKind::Body { counter, qcopy } => {
                    writeln!(o, "        {counter} : INT;").unwrap();
                    writeln!(o, "        {qcopy} : BOOL;").unwrap();
                }
            }
        }
        o.push_str("    END_VAR\n");
        for s in &self.steps {
            let kw = if s.initial { "INITIAL_STEP" } else { "STEP" };
            if s.assocs.is_empty() {
                writeln!(o, "\n    {kw} {}: END_STEP", s.name).unwrap();
                continue;
            }
            writeln!(o, "\n    {kw} {}:", s.name).unwrap();
            for a in &s.assocs {
                let name = &self.actions[a.action].name;
                if a.qual.timed() {
                    writeln!(o, "        {name}({}, {});", a.qual.name(), time_literal(a.duration)).unwrap();
                } else {
                    writeln!(o, "        {name}({});", a.qual.name()).unwrap();
                }
            }
            o.push_str("    END_STEP\n");
        }
        for t in &self.transitions {
            let prio = t.priority.map(|p| format!(" (PRIORITY := {p})")).unwrap_or_default();
            writeln!(
                o,
                "\n    TRANSITION {}{prio} FROM {} TO {}\n        := {};\n    END_TRANSITION",
                t.name,
                self.step_list(&t.from),
                self.step_list(&t.to),
                self.guard_text(&t.guard)
            )
            .unwrap();
        }
        for a in &self.actions {
            if let ActionKind::Body { counter, qcopy } = &a.kind {
                writeln!(
                    o,
                    "\n    ACTION {}:\n        {counter} := {counter} + 1;\n        {qcopy} := {}.Q;\n    END_ACTION",
                    a.name, a.name
                )
                .unwrap();
            }
        }
        o.push_str("END_PROGRAM\n");
        o
    }
}

/// A runtime event, as the reference reports it.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum RefEvent {
    Conflict {
        step: String,
        transitions: Vec<String>,
    },
    Unsafe {
        step: String,
        transitions: Vec<String>,
    },
    /// `steps[0]` / `qualifiers[0]` is the winner; then the associations ignored, text order.
    Contention {
        action: String,
        steps: Vec<String>,
        qualifiers: Vec<String>,
    },
}

/// What one reference scan did.
#[derive(Debug, Clone, PartialEq)]
pub struct RefRecord {
    pub scan: u64,
    pub active: Vec<String>,
    pub fired: Vec<String>,
    pub events: Vec<RefEvent>,
}

/// An on-delay timer on virtual time: elapsed counts from the scan the input was first seen
/// TRUE; `Q = elapsed >= PT`.
#[derive(Debug, Clone, Default)]
struct Ton {
    since: Option<i64>,
}

impl Ton {
    fn run(&mut self, input: bool, now: i64, pt: i64) -> bool {
        if input {
            let since = *self.since.get_or_insert(now);
            now - since >= pt
        } else {
            self.since = None;
            false
        }
    }
}

/// The ACTION_CONTROL function block of one action.
#[derive(Debug, Clone, Default)]
struct ActionControl {
    s_ff: bool,
    sd_ff: bool,
    ds_ff: bool,
    sl_ff: bool,
    l_tmr: Ton,
    d_tmr: Ton,
    sd_tmr: Ton,
    ds_tmr: Ton,
    sl_tmr: Ton,
    p_prev: bool,
    p1_prev: bool,
    p0_prev: bool,
    q_prev: bool,
    /// The last duration given to each timed qualifier (indexed by `Qual::index`).
    pt: [i64; 11],
    q: bool,
    a: bool,
}

impl ActionControl {
    /// One call of the block: `input[q]` is the OR of the flags of the steps associating the
    /// action with qualifier `q` (contention already applied).
    fn call(&mut self, input: [bool; 11], now: i64) {
        let i = |q: Qual| input[q.index()];
        let pt = |q: Qual| self.pt[q.index()];
        let r = i(Qual::R);
        // RS flip-flops are reset-dominant: Q1 := NOT R1 AND (S OR Q1).
        self.s_ff = !r && (i(Qual::S) || self.s_ff);
        // Every timer is called every scan (a timer not called would not see its input fall).
        let l_done = self.l_tmr.run(i(Qual::L), now, pt(Qual::L));
        let l = i(Qual::L) && !l_done;
        let d = self.d_tmr.run(i(Qual::D), now, pt(Qual::D));
        let p = i(Qual::P) && !self.p_prev;
        self.p_prev = i(Qual::P);
        self.sd_ff = !r && (i(Qual::SD) || self.sd_ff);
        let sd = self.sd_tmr.run(self.sd_ff, now, pt(Qual::SD));
        let ds_delay = self.ds_tmr.run(i(Qual::DS), now, pt(Qual::DS));
        self.ds_ff = !r && (ds_delay || self.ds_ff);
        self.sl_ff = !r && (i(Qual::SL) || self.sl_ff);
        let sl_done = self.sl_tmr.run(self.sl_ff, now, pt(Qual::SL));
        let sl = self.sl_ff && !sl_done;
        let q = !r && (i(Qual::N) || self.s_ff || l || d || p || sd || self.ds_ff || sl);
        let p1 = i(Qual::P1) && !self.p1_prev;
        let p0 = !i(Qual::P0) && self.p0_prev;
        self.p1_prev = i(Qual::P1);
        self.p0_prev = i(Qual::P0);
        // Written as semantics.md states it: A = Q OR (Q fell this scan) OR P1/P0 pulse.
        #[allow(clippy::nonminimal_bool)]
        let a = q || (self.q_prev && !q) || p1 || p0;
        self.a = a;
        self.q = q;
        self.q_prev = q;
    }
}

/// The reference simulation of one chart.
pub struct Reference<'c> {
    chart: &'c Chart,
    period: i64,
    next_scan: u64,
    x: Vec<bool>,
    t: Vec<i64>,
    inputs: Vec<bool>,
    controls: Vec<ActionControl>,
    /// Per action: the BOOL variable (for `Variable`) or the counter / copied Q (for `Body`).
    pub vars: Vec<bool>,
    pub counters: Vec<i64>,
    pub qcopies: Vec<bool>,
}

impl<'c> Reference<'c> {
    pub fn new(chart: &'c Chart, period: i64) -> Self {
        let n = chart.actions.len();
        Reference {
            chart,
            period,
            next_scan: 0,
            x: vec![false; chart.steps.len()],
            t: vec![0; chart.steps.len()],
            inputs: vec![false; chart.inputs],
            controls: vec![ActionControl::default(); n],
            vars: vec![false; n],
            counters: vec![0; n],
            qcopies: vec![false; n],
        }
    }

    /// Writes an input (applied in step 1 of the next scan).
    pub fn set(&mut self, input: usize, value: bool) {
        self.inputs[input] = value;
    }

    pub fn q(&self, action: usize) -> bool {
        self.controls[action].q
    }

    pub fn a(&self, action: usize) -> bool {
        self.controls[action].a
    }

    pub fn step_time(&self, step: usize) -> i64 {
        self.t[step]
    }

    fn guard(&self, g: &Guard) -> bool {
        match g {
            Guard::True => true,
            Guard::Input(i) => self.inputs[*i],
            Guard::StepTime(s, us) => self.t[*s] >= *us,
            Guard::StepFlag(s) => self.x[*s],
            Guard::Variable(a) => self.vars[*a],
            Guard::ActionFlag(a, is_a) => {
                if *is_a {
                    self.controls[*a].a
                } else {
                    self.controls[*a].q
                }
            }
            Guard::Not(a) => !self.guard(a),
            Guard::And(a, b) => {
                let (a, b) = (self.guard(a), self.guard(b));
                a && b
            }
            Guard::Or(a, b) => {
                let (a, b) = (self.guard(a), self.guard(b));
                a || b
            }
        }
    }

    /// Runs one scan.
    pub fn scan(&mut self) -> RefRecord {
        let chart = self.chart;
        let k = self.next_scan;
        self.next_scan += 1;
        let now = k as i64 * self.period;
        let mut events = Vec::new();
        let mut fired = Vec::new();
        if k == 0 {
            // Initialisation: X := initial steps, all T := 0, no transition.
            for (s, step) in chart.steps.iter().enumerate() {
                self.x[s] = step.initial;
                self.t[s] = 0;
            }
        } else {
            // 2. Time.
            for s in 0..chart.steps.len() {
                if self.x[s] {
                    self.t[s] += self.period;
                }
            }
            // 3. Enabled and true, on one snapshot.
            let enabled: Vec<usize> = (0..chart.transitions.len())
                .filter(|&j| {
                    let tr = &chart.transitions[j];
                    tr.from.iter().all(|&s| self.x[s]) && self.guard(&tr.guard)
                })
                .collect();
            // 4. Conflicts: explicit priorities ascending (ties by declaration), then the rest.
            let mut order: Vec<usize> =
                enabled.iter().copied().filter(|&j| chart.transitions[j].priority.is_some()).collect();
            order.sort_by_key(|&j| (chart.transitions[j].priority.unwrap(), j));
            order.extend(enabled.iter().copied().filter(|&j| chart.transitions[j].priority.is_none()));
            let mut consumed = vec![false; chart.steps.len()];
            let mut accepted = vec![false; chart.transitions.len()];
            for j in order {
                let tr = &chart.transitions[j];
                if tr.from.iter().all(|&s| !consumed[s]) {
                    accepted[j] = true;
                    for &s in &tr.from {
                        consumed[s] = true;
                    }
                }
            }
            for (s, step) in chart.steps.iter().enumerate() {
                let unprioritised: Vec<String> = enabled
                    .iter()
                    .filter(|&&j| chart.transitions[j].priority.is_none() && chart.transitions[j].from.contains(&s))
                    .map(|&j| chart.transitions[j].name.clone())
                    .collect();
                if unprioritised.len() >= 2 {
                    events.push(RefEvent::Conflict { step: step.name.clone(), transitions: unprioritised });
                }
            }
            // 5. Fire all accepted transitions together.
            let mut left = vec![false; chart.steps.len()];
            let mut entered_by: Vec<Vec<String>> = vec![Vec::new(); chart.steps.len()];
            for (j, tr) in chart.transitions.iter().enumerate() {
                if !accepted[j] {
                    continue;
                }
                fired.push(tr.name.clone());
                for &s in &tr.from {
                    left[s] = true;
                }
                for &s in &tr.to {
                    entered_by[s].push(tr.name.clone());
                }
            }
            for (s, step) in chart.steps.iter().enumerate() {
                let entered = !entered_by[s].is_empty();
                if entered && ((self.x[s] && !left[s]) || entered_by[s].len() >= 2) {
                    events.push(RefEvent::Unsafe { step: step.name.clone(), transitions: entered_by[s].clone() });
                }
            }
            for s in 0..chart.steps.len() {
                if !entered_by[s].is_empty() {
                    self.x[s] = true;
                    self.t[s] = 0;
                } else if left[s] {
                    self.x[s] = false;
                }
            }
        }
        // 6. Action control, on X'.
        for (ai, action) in chart.actions.iter().enumerate() {
            let mut input = [false; 11];
            let mut timed: Vec<(usize, &Assoc)> = Vec::new();
            for (s, step) in chart.steps.iter().enumerate() {
                for assoc in step.assocs.iter().filter(|a| a.action == ai) {
                    if !self.x[s] {
                        continue;
                    }
                    if assoc.qual.timed() {
                        timed.push((s, assoc));
                    } else {
                        input[assoc.qual.index()] = true;
                    }
                }
            }
            if let Some(&(ws, winner)) = timed.first() {
                let differs = |a: &Assoc| a.qual != winner.qual || a.duration != winner.duration;
                let losers: Vec<&(usize, &Assoc)> = timed.iter().filter(|(_, a)| differs(a)).collect();
                if !losers.is_empty() {
                    let mut steps = vec![chart.steps[ws].name.clone()];
                    let mut quals = vec![winner.qual.name().to_string()];
                    for (s, a) in &losers {
                        steps.push(chart.steps[*s].name.clone());
                        quals.push(a.qual.name().to_string());
                    }
                    events.push(RefEvent::Contention { action: action.name.clone(), steps, qualifiers: quals });
                }
                input[winner.qual.index()] = true;
                self.controls[ai].pt[winner.qual.index()] = winner.duration;
            }
            // A stored SD/SL timer running after its step was left keeps the last duration its
            // qualifier was given (the differential charts give one duration per action, so
            // this equals the single T input of the standard block).
            self.controls[ai].call(input, now);
            if action.kind == ActionKind::Variable {
                self.vars[ai] = self.controls[ai].q;
            }
        }
        // 7. Action bodies, in declaration order.
        for (ai, action) in chart.actions.iter().enumerate() {
            if let ActionKind::Body { .. } = action.kind {
                if self.controls[ai].a {
                    self.counters[ai] += 1;
                    self.qcopies[ai] = self.controls[ai].q;
                }
            }
        }
        // 8. Outputs.
        let mut active: Vec<String> =
            chart.steps.iter().enumerate().filter(|(s, _)| self.x[*s]).map(|(_, st)| st.name.clone()).collect();
        active.sort();
        RefRecord { scan: k, active, fired, events }
    }
}
