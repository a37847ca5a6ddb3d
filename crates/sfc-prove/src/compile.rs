//! Properties compiled into the scan: assumptions become constraints on each scan's inputs,
//! each property a state predicate (`bad` for safety, `goal` for reachability), responses get a
//! monitor (the oldest pending trigger and its age in scans), ranges of variables and runtime
//! faults become properties of their own.

use crate::aig::Lit;
use crate::model::expr::{ExprError, Frame};
use crate::model::{Enc, Hooks, Role};
use crate::props::{locate_in_string, Bound, Kind, PropExpr, PropertyFile, PropsError};
use crate::word::Word;
use sfc_st::Type;

/// Where a checked property comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Origin {
    /// `[[property]]` number `k` of the file.
    User(usize),
    /// A `ranges` entry of a variable the code writes: leaving the range is a violation.
    Range { reg: usize, lo: i128, hi: i128 },
    /// No runtime error (division by zero, index out of range, subrange violation).
    Fault,
}

/// What the engines check for one property.
#[derive(Debug, Clone)]
pub enum Signal {
    /// A state predicate that must never hold (after scan 0 on).
    Safety { bad: Lit },
    /// A state predicate to reach: from every reachable state (AG EF) or from the initial one.
    Reach { goal: Lit, from_initial: bool },
}

#[derive(Debug, Clone)]
pub struct Compiled {
    pub name: String,
    pub origin: Origin,
    pub signal: Signal,
    /// For responses: the bound in scans.
    pub scans: Option<u64>,
}

/// The hooks that compile a property file into the encoding.
pub struct PropertyHooks<'p> {
    pub file: &'p PropertyFile,
    pub period: i64,
    pub out: Vec<Compiled>,
    pub errors: Vec<PropsError>,
    /// The register "a runtime fault stopped the run in the previous scan".
    pub stopped: Option<usize>,
}

impl<'p> PropertyHooks<'p> {
    pub fn new(file: &'p PropertyFile, period: i64) -> Self {
        PropertyHooks { file, period, out: Vec::new(), errors: Vec::new(), stopped: None }
    }

    fn error(&mut self, x: &PropExpr, e: ExprError) {
        let err = locate_in_string(&self.file.path, &self.file.text, &x.src, e.span.start as usize, e.message);
        if !self.errors.contains(&err) {
            self.errors.push(err);
        }
    }

    /// A property expression as a literal (errors recorded, FALSE returned).
    fn cond(&mut self, e: &mut Enc<'_>, x: &PropExpr) -> Lit {
        let f = Frame { inst: e.top, recorded: false };
        match e.eval_bool(&f, &x.expr) {
            Ok(l) => l,
            Err(err) => {
                self.error(x, err);
                Lit::FALSE
            }
        }
    }

    /// Evaluates `x` on the state `cur` (the registers before the scan).
    fn cond_on(&mut self, e: &mut Enc<'_>, cur: &[Word], x: &PropExpr) -> Lit {
        let mut mem = cur.to_vec();
        // Registers created after `cur` (monitors, temporaries) keep their current words.
        mem.extend(e.mem[cur.len()..].iter().cloned());
        std::mem::swap(&mut e.mem, &mut mem);
        let l = self.cond(e, x);
        std::mem::swap(&mut e.mem, &mut mem);
        // Keep registers created while evaluating.
        if mem.len() > e.mem.len() {
            let extra: Vec<Word> = mem[e.mem.len()..].to_vec();
            e.mem.extend(extra);
        }
        l
    }
}

impl<'a> Hooks<'a> for PropertyHooks<'_> {
    fn after_inputs(&mut self, e: &mut Enc<'a>) {
        for x in &self.file.assume {
            let l = self.cond(e, x);
            e.constraints.push(l);
        }
    }

    fn after_scan(&mut self, e: &mut Enc<'a>, cur: &[Word], range_exits: &[(usize, Lit)]) {
        let scanned = cur[e.scanned].bits[0];
        // Runtime faults stop the run: the faulting scan's state is checked, it has no successor.
        let any_fault = e.g.or_all(e.faults.iter().map(|f| f.cond));
        let mut healthy = Lit::TRUE;
        if any_fault != Lit::FALSE {
            let r = e.new_reg("(runtime fault)".into(), Type::Bool, Role::Monitor, 0, None);
            e.set_reg(r, Word::from_bit(any_fault, 1));
            let stopped = e.latch[r][0];
            self.stopped = Some(r);
            healthy = stopped.not();
            self.out.push(Compiled {
                name: "no runtime error".into(),
                origin: Origin::Fault,
                signal: Signal::Safety { bad: stopped },
                scans: None,
            });
        }
        // Ranges: the user's are properties; the types' (enumerations) are the model's assumption.
        let mut in_range = Lit::TRUE;
        let mut user_ranges = Vec::new();
        for &(r, exit) in range_exits {
            let reg = e.regs[r].clone();
            if !matches!(reg.role, Role::Var { .. }) {
                continue;
            }
            if reg.obligation {
                let v = e.new_reg(format!("({} left its range)", reg.name), Type::Bool, Role::Monitor, 0, None);
                e.set_reg(v, Word::from_bit(exit, 1));
                let left = e.latch[v][0];
                in_range = e.g.and(in_range, left.not());
                let (lo, hi) = reg.range.unwrap_or((0, 0));
                user_ranges.push((r, left, lo, hi));
            } else {
                e.constraints.push(exit.not());
            }
        }
        for (r, left, lo, hi) in user_ranges {
            let name = e.regs[r].name.clone();
            let shown =
                |v: i128| if e.regs[r].ty.is_duration() { sfc_sim::format_time(v as i64) } else { v.to_string() };
            self.out.push(Compiled {
                name: format!("range of {name} ({}..{})", shown(lo), shown(hi)),
                origin: Origin::Range { reg: r, lo, hi },
                signal: Signal::Safety { bad: left },
                scans: None,
            });
        }
        // No successor after a fault or once a range is left.
        let ok = e.g.and(healthy, in_range);
        e.constraints.push(ok);
        let live = e.g.and(scanned, in_range);
        for (k, p) in self.file.properties.iter().enumerate() {
            let (signal, scans) = match &p.kind {
                Kind::Always(x) => {
                    let v = self.cond_on(e, cur, x);
                    (Signal::Safety { bad: e.g.and(live, v.not()) }, None)
                }
                Kind::Never(x) => {
                    let v = self.cond_on(e, cur, x);
                    (Signal::Safety { bad: e.g.and(live, v) }, None)
                }
                Kind::Reachable { goal, from_initial } => {
                    let v = self.cond_on(e, cur, goal);
                    (Signal::Reach { goal: e.g.and(live, v), from_initial: *from_initial }, None)
                }
                Kind::Response { after, expect, bound } => {
                    let n: u64 = match bound {
                        Bound::Scans(n) => *n,
                        Bound::Time(t) => (*t / self.period.max(1)) as u64,
                    };
                    let n = n.min(crate::model::MAX_COUNT);
                    // Trigger and response on the state after this scan (the memory now).
                    let a_now = self.cond(e, after);
                    let x_now = self.cond(e, expect);
                    let prev = e.new_reg(format!("({} trigger memory)", p.name), Type::Bool, Role::Monitor, 0, None);
                    let pending = e.new_reg(format!("({} pending)", p.name), Type::Bool, Role::Monitor, 0, None);
                    let age = e.new_reg(
                        format!("({} scans waiting)", p.name),
                        Type::UDInt,
                        Role::Monitor,
                        0,
                        Some((0, n.max(1) as i128)),
                    );
                    let prev_c = e.latch[prev][0];
                    let pend_c = e.latch[pending][0];
                    let age_w = e.mem[age].clone();
                    let trig = e.g.and(a_now, prev_c.not());
                    let waiting = e.g.or(pend_c, trig);
                    let pend_n = e.g.and(waiting, x_now.not());
                    let keep = e.g.and(pend_c, x_now.not());
                    let one = Word::constant(1, age_w.width());
                    let inc = e.sat_inc(&age_w, &one, age);
                    let zero = Word::constant(0, age_w.width());
                    let age_n = e.ops().ite(keep, &inc, &zero);
                    e.set_reg(prev, Word::from_bit(a_now, 1));
                    e.set_reg(pending, Word::from_bit(pend_n, 1));
                    e.set_reg(age, age_n);
                    // Violated once a trigger has waited `n` scans without the response.
                    let nw = Word::constant(n as i128, age_w.width());
                    let at_n = e.ops().ult(&age_w, &nw).not();
                    let bad = e.g.and(pend_c, at_n);
                    (Signal::Safety { bad: e.g.and(in_range, bad) }, Some(n))
                }
            };
            self.out.push(Compiled { name: p.name.clone(), origin: Origin::User(k), signal, scans });
        }
    }
}
