//! The chart and its ST/IL code compiled to a bit-level transition relation of one scan under
//! the semantics of `semantics.md` in the `iec` or `codesys` profile (and the simulator's
//! documented choices, `docs/sim.md`: step actions, actions written in SFC).
//!
//! The state is a list of registers: every variable of the simulated POU and of its nested
//! instances (arrays and structures flattened), the hidden state of standard function blocks,
//! and, per SFC instance, the step flags, step times (counted in scans), supervision flags and
//! the ACTION_CONTROL state of every action. One transition of the system is one scan: the
//! inputs of the scan are free (within `[assume]`), the POU runs once, and the registers take
//! their values after the scan. The state before scan 0 holds the declared initial values.
//!
//! What cannot be modelled bit-precisely (REAL, strings, loops beyond the unrolling bound, …)
//! becomes a free value: an over-approximation, listed in [`Model::notes`]. A `holds` stays a
//! proof; a violation found through such a value is caught by the witness replay in the
//! simulator.

pub mod chart;
pub(crate) mod expr;
pub(crate) mod il;
pub(crate) mod stmt;

use crate::aig::{Aig, Lit};
use crate::word::{bits_for, Ops, Word};
use sfc_diagnostics::Span;
use sfc_model::{Chart, Checked};
use sfc_st::{Type, TypeEnv, VarInfo};
use sfc_syntax::ast::{Item, Pou, PouKind, VarKind};
use std::collections::{BTreeMap, HashMap, HashSet};

/// Longest bound for a step time or timer counter, in scans (beyond, the value saturates and
/// the model says so).
pub const MAX_COUNT: u64 = 1 << 22;

/// What a register holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Role {
    /// A variable of the POU (or of a nested instance, or a global): its path.
    Var { input: bool },
    /// State the engine keeps: step flags and times, action control, timers.
    Hidden,
    /// A frame of a FUNCTION call: not part of the state.
    Temp,
    /// Property monitors and bookkeeping (added by the property compiler).
    Monitor,
}

/// One register of the state.
#[derive(Debug, Clone)]
pub struct Reg {
    /// `Start`, `Rev.KM1`, `Cells[2]`, or a description of hidden state.
    pub name: String,
    /// The IEC type of the value (BOOL for flags; UDINT for counters).
    pub ty: Type,
    /// Width of the value as computed (the type's width).
    pub full: usize,
    pub signed: bool,
    /// Width stored in the state (smaller when the value range is known).
    pub stored: usize,
    /// The value range the stored width holds, when narrower than the type.
    pub range: Option<(i128, i128)>,
    /// The range is the user's (`ranges`): leaving it is a violation of its own.
    pub obligation: bool,
    pub init: i128,
    pub role: Role,
    /// Never written by any code: it keeps its initial value (a parameter).
    pub constant: bool,
}

/// A free input of the scan: a variable's new value, or a free value standing for something
/// that is not modelled.
#[derive(Debug, Clone)]
pub struct InputVar {
    pub name: String,
    /// The register it feeds (variables), or none (abstractions).
    pub reg: Option<usize>,
    pub lits: Vec<Lit>,
    pub signed: bool,
}

/// A runtime fault of the scan (division by zero, index out of range, subrange violation).
#[derive(Debug, Clone)]
pub struct FaultSite {
    pub cond: Lit,
    pub message: String,
    pub span: Span,
}

/// A storage place: a register, an opaque (unmodelled) value, or an aggregate.
#[derive(Debug, Clone)]
pub enum Slot {
    Leaf(usize),
    Opaque(Type),
    Array { dims: Vec<(i64, i64)>, elem: Type, items: Vec<Slot> },
    Struct { ty: Type, fields: Vec<(String, Slot)> },
    Fb(usize),
}

/// A declared variable of an instance.
#[derive(Debug, Clone)]
pub struct VarEntry {
    pub name: String,
    pub kind: VarKind,
    pub ty: Type,
    pub slot: Slot,
    pub location: Option<String>,
    pub implicit: bool,
}

/// The standard function blocks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StdFb {
    Ton,
    Tof,
    Tp,
    Ctu,
    Ctd,
    Ctud,
    RTrig,
    FTrig,
    Sr,
    Rs,
}

impl StdFb {
    pub fn from_name(name: &str) -> Option<StdFb> {
        sfc_st::stdlib::std_function_block(name)?;
        let upper = name.to_ascii_uppercase();
        let stem = upper.split('_').next().unwrap_or("");
        Some(match (upper.as_str(), stem) {
            ("TON", _) => StdFb::Ton,
            ("TOF", _) => StdFb::Tof,
            ("TP", _) => StdFb::Tp,
            ("R_TRIG", _) => StdFb::RTrig,
            ("F_TRIG", _) => StdFb::FTrig,
            ("SR", _) => StdFb::Sr,
            ("RS", _) => StdFb::Rs,
            (_, "CTU") => StdFb::Ctu,
            (_, "CTD") => StdFb::Ctd,
            (_, "CTUD") => StdFb::Ctud,
            _ => return None,
        })
    }
}

/// What an instance is.
#[derive(Debug, Clone)]
pub enum InstKind {
    /// The simulated POU or a user function block (index into [`Enc::pous`]).
    User(usize),
    /// A standard block with its hidden registers (timers: running, elapsed scans; counters
    /// and triggers: edge memories).
    Std(StdFb, Vec<usize>),
}

/// An instance of a POU in memory (the top POU, nested function blocks).
#[derive(Debug, Clone)]
pub struct Inst {
    pub kind: InstKind,
    /// Path from the top (`""` for the top).
    pub path: String,
    pub vars: Vec<VarEntry>,
    /// The SFC state of the instance, when its POU is a chart.
    pub chart: Option<usize>,
    /// The charts of its POU's actions written in SFC (in the file's order).
    pub subs: Vec<usize>,
}

/// A POU of the file.
pub struct PouInfo<'a> {
    pub ast: &'a Pou,
    pub iface: sfc_st::PouInterface,
    /// Index into `Checked::charts` for an SFC POU.
    pub chart: Option<usize>,
    /// Its actions written in SFC: indices of their charts ([`chart::chart_at`]).
    pub subs: Vec<usize>,
}

/// Settings of the encoding that earlier passes found.
#[derive(Debug, Clone, Default)]
pub struct Plan {
    /// The last pass: counters exist only where a bound was learned.
    pub final_pass: bool,
    /// Registers no code writes (they keep their initial value).
    pub constants: HashSet<String>,
    /// Per counter (`chart/step` key or timer register name): the saturation bound in scans.
    pub bounds: HashMap<String, u64>,
    /// Step times read outside comparisons with constants.
    pub inexact: HashSet<String>,
    /// Step times only the step's own outgoing guards read: kept at 0 while it is inactive.
    pub dead_inactive: HashSet<String>,
}

/// What a pass of the encoding learns for the next one.
#[derive(Debug, Clone, Default)]
pub struct Learned {
    pub written: HashSet<usize>,
    /// Step times read somewhere other than the guards of their own step's transitions.
    pub time_read_elsewhere: HashSet<String>,
    /// Per counter key: the largest constant (µs) it is compared with, and the thresholds (scans).
    pub need: HashMap<String, u64>,
    pub inexact: HashSet<String>,
}

/// The scan period and the POU chosen.
#[derive(Debug, Clone)]
pub struct Setup {
    pub period: i64,
    pub pou: String,
    /// Extra free inputs (`[assume] inputs`), upper-case paths.
    pub extra_inputs: Vec<String>,
    /// Value ranges from `[assume] ranges` by upper-case path.
    pub ranges: HashMap<String, (i128, i128)>,
    /// `iec` or `codesys` (the others are refused before encoding).
    pub profile: sfc_sim::Profile,
}

/// The encoder: builds the one-scan relation into an AIG.
pub struct Enc<'a> {
    pub g: Aig,
    pub checked: &'a Checked,
    pub env: TypeEnv,
    pub pous: Vec<PouInfo<'a>>,
    pub setup: Setup,
    pub plan: Plan,
    pub learned: Learned,
    pub regs: Vec<Reg>,
    /// Current-state literals per register (stored width), or constants.
    pub latch: Vec<Vec<Lit>>,
    /// Symbolic memory during the scan: the full-width value of every register.
    pub mem: Vec<Word>,
    pub insts: Vec<Inst>,
    pub globals: Vec<VarEntry>,
    pub charts: Vec<chart::ChartEnc>,
    pub inputs: Vec<InputVar>,
    /// Conditions the environment must respect (assumptions), over state and inputs.
    pub constraints: Vec<Lit>,
    /// Path condition of the statement being encoded.
    pub pc: Lit,
    /// FALSE once a fault stopped the scan.
    pub alive: Lit,
    /// Set by RETURN / EXIT in the current body / loop.
    pub returned: Lit,
    pub exited: Lit,
    pub faults: Vec<FaultSite>,
    pub notes: BTreeMap<String, ()>,
    /// Initial values from the simulator, by path.
    pub initial: Initial<'a>,
    pub top: usize,
    /// Nesting of user FB / function calls (recursion guard).
    pub depth: u32,
    /// Function-call frames: the temporary variables of the innermost call.
    pub frames: Vec<Vec<VarEntry>>,
    /// The register of the global scan counter's "first scan" flag (the top instance started).
    pub scanned: usize,
    /// The guard being encoded: (chart, transition).
    pub guard_of: Option<(usize, usize)>,
    /// Implicit control inputs held FALSE (not read by the chart).
    pub held: std::cell::RefCell<Vec<String>>,
    /// The charts whose call is being encoded (a chart that runs itself is refused).
    pub running: Vec<usize>,
    /// Why the chart cannot be proved, found while encoding.
    pub refused: Option<String>,
    /// Runs of charts encoded so far in this scan.
    pub chart_runs: usize,
}

/// The result of encoding: the transition system of one scan.
pub struct Model {
    pub g: Aig,
    pub regs: Vec<Reg>,
    pub latch: Vec<Vec<Lit>>,
    /// Next-state literals per register (stored width).
    pub next: Vec<Vec<Lit>>,
    pub inputs: Vec<InputVar>,
    pub constraint: Lit,
    /// Per register with a user range: the literal "the value computed in this scan is outside
    /// the range" (a transition signal).
    pub range_exits: Vec<(usize, Lit)>,
    pub faults: Vec<FaultSite>,
    pub notes: Vec<String>,
    pub scanned: usize,
    pub top: usize,
    pub insts: Vec<Inst>,
    pub charts: Vec<chart::ChartEnc>,
    pub pou: String,
}

pub(crate) fn int_sort(ty: &Type) -> Option<(usize, bool)> {
    let t = ty.base();
    Some(match t {
        Type::Bool => (1, false),
        Type::SInt => (8, true),
        Type::Int => (16, true),
        Type::DInt => (32, true),
        Type::LInt => (64, true),
        Type::USInt | Type::Byte => (8, false),
        Type::UInt | Type::Word => (16, false),
        Type::UDInt | Type::DWord => (32, false),
        Type::ULInt | Type::LWord => (64, false),
        Type::Time | Type::LTime | Type::Date | Type::TimeOfDay | Type::DateAndTime => (64, true),
        Type::Enum { base: Some(b), .. } => return int_sort(b),
        Type::Enum { base: None, .. } => (64, true),
        _ => return None,
    })
}

/// The natural range of values of a type with a known width, when narrower than the width.
fn type_range(ty: &Type) -> Option<(i128, i128)> {
    match ty {
        Type::Subrange { lo, hi, .. } => Some((*lo as i128, *hi as i128)),
        Type::Enum { values, .. } if !values.is_empty() => {
            let lo = values.iter().map(|(_, v)| *v).min().unwrap_or(0) as i128;
            let hi = values.iter().map(|(_, v)| *v).max().unwrap_or(0) as i128;
            Some((lo.min(0), hi.max(0)))
        }
        _ => None,
    }
}

impl<'a> Enc<'a> {
    pub fn note(&mut self, s: impl Into<String>) {
        self.notes.insert(s.into(), ());
    }

    pub fn ops(&mut self) -> Ops<'_> {
        Ops { g: &mut self.g }
    }

    /// A new register; its current-state literals are fresh variables (or its initial value
    /// when the plan says nothing writes it).
    pub fn new_reg(&mut self, name: String, ty: Type, role: Role, init: i128, range: Option<(i128, i128)>) -> usize {
        let (full, signed) = int_sort(&ty).unwrap_or((1, false));
        let user = self.setup.ranges.get(&name.to_ascii_uppercase()).copied();
        let obligation = user.is_some() && role != Role::Var { input: true };
        let range = user.or(range).or_else(|| type_range(&ty));
        let (stored, range) = match range {
            Some((lo, hi)) if full > 1 => {
                let w = bits_for(lo, hi);
                if w < full {
                    (w, Some((lo, hi)))
                } else {
                    (full, Some((lo, hi)))
                }
            }
            _ => (full, None),
        };
        let constant = role == (Role::Var { input: false }) && self.plan.constants.contains(&name.to_ascii_uppercase());
        let idx = self.regs.len();
        let lits: Vec<Lit> = if constant || role == Role::Temp {
            Word::constant(init, stored).bits
        } else {
            (0..stored).map(|_| self.g.new_var()).collect()
        };
        let stored_signed = range.map_or(signed, |(lo, _)| lo < 0);
        let word = Word { bits: lits.clone() }.resize(full, stored_signed);
        self.regs.push(Reg { name, ty, full, signed, stored, range, obligation, init, role, constant });
        self.latch.push(lits);
        self.mem.push(word);
        idx
    }

    /// Whether register `r` stores its value signed (two's complement in the stored width).
    pub fn stored_signed(&self, r: usize) -> bool {
        let reg = &self.regs[r];
        reg.range.map_or(reg.signed, |(lo, _)| lo < 0)
    }

    /// A fresh free input word (an abstraction or a variable's new value).
    pub fn fresh(&mut self, name: impl Into<String>, width: usize, signed: bool, reg: Option<usize>) -> Word {
        let lits: Vec<Lit> = (0..width).map(|_| self.g.new_var()).collect();
        self.inputs.push(InputVar { name: name.into(), reg, lits: lits.clone(), signed });
        Word { bits: lits }
    }

    /// The literal under which a write or a fault of the current statement happens.
    pub fn active(&mut self) -> Lit {
        let a = self.g.and(self.pc, self.alive);
        let b = self.g.and(a, self.returned.not());
        self.g.and(b, self.exited.not())
    }

    /// Writes a full-width word to register `r` under the current path condition.
    pub fn write_reg(&mut self, r: usize, w: Word) {
        let act = self.active();
        let old = self.mem[r].clone();
        let w = w.resize(old.width(), self.regs[r].signed);
        let new = self.ops().ite(act, &w, &old);
        if new != old {
            self.learned.written.insert(r);
        }
        self.mem[r] = new;
    }

    /// Writes register `r` regardless of the path condition (engine bookkeeping that the
    /// caller already conditioned).
    pub fn set_reg(&mut self, r: usize, w: Word) {
        let old_w = self.mem[r].width();
        let w = w.resize(old_w, self.regs[r].signed);
        if w != self.mem[r] {
            self.learned.written.insert(r);
        }
        self.mem[r] = w;
    }

    pub fn bool_reg(&self, r: usize) -> Lit {
        self.mem[r].bits[0]
    }

    /// A runtime fault when `cond` holds in the current statement: the scan stops there.
    pub fn fault(&mut self, cond: Lit, message: impl Into<String>, span: Span) {
        let act = self.active();
        let f = self.g.and(act, cond);
        if f == Lit::FALSE {
            return;
        }
        self.faults.push(FaultSite { cond: f, message: message.into(), span });
        self.alive = self.g.and(self.alive, f.not());
    }

    fn init_value(&self, path: &str, ty: &Type) -> i128 {
        match (self.initial)(path) {
            Some(sfc_sim::Value::Bool(b)) => b as i128,
            Some(sfc_sim::Value::Int(i)) | Some(sfc_sim::Value::Time(i)) => {
                let v = i as i128;
                match int_sort(ty) {
                    Some((64, false)) => v & ((1i128 << 64) - 1),
                    _ => v,
                }
            }
            _ => match ty {
                Type::Subrange { lo, .. } => *lo as i128,
                Type::Enum { values, .. } => values.first().map_or(0, |(_, v)| *v as i128),
                _ => 0,
            },
        }
    }

    /// Lays out a value of `ty` at `path`; `input` marks free variables.
    pub fn layout(&mut self, path: &str, ty: &Type, role: Role, depth: u32) -> Slot {
        if depth > 64 {
            self.note(format!("`{path}`: nesting too deep; its value is free"));
            return Slot::Opaque(ty.clone());
        }
        match ty {
            Type::Array { dims, elem } => {
                let count: i64 = dims.iter().map(|(lo, hi)| (hi - lo + 1).max(0)).product();
                if count > 4096 {
                    self.note(format!(
                        "`{path}`: arrays of more than 4096 elements are not modelled; its elements are free"
                    ));
                    return Slot::Opaque(ty.clone());
                }
                let mut items = Vec::with_capacity(count as usize);
                let mut idx: Vec<i64> = dims.iter().map(|d| d.0).collect();
                for _ in 0..count {
                    let name = format!(
                        "{path}[{}]",
                        idx.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(", ").replace(", ", ",")
                    );
                    items.push(self.layout(&name, elem, role.clone(), depth + 1));
                    for k in (0..dims.len()).rev() {
                        idx[k] += 1;
                        if idx[k] <= dims[k].1 {
                            break;
                        }
                        idx[k] = dims[k].0;
                    }
                }
                Slot::Array { dims: dims.clone(), elem: (**elem).clone(), items }
            }
            Type::Struct { fields, .. } => {
                let fields = fields
                    .iter()
                    .map(|(n, t)| (n.clone(), self.layout(&format!("{path}.{n}"), t, role.clone(), depth + 1)))
                    .collect();
                Slot::Struct { ty: ty.clone(), fields }
            }
            Type::FunctionBlock(name) => {
                let inst = self.instantiate_fb(name, path, depth + 1);
                match inst {
                    Some(i) => Slot::Fb(i),
                    None => {
                        self.note(format!("`{path}`: function block `{name}` is not modelled; its outputs are free"));
                        Slot::Opaque(ty.clone())
                    }
                }
            }
            t if int_sort(t).is_some() => {
                let init = self.init_value(path, t);
                let r = self.new_reg(path.to_string(), t.clone(), role, init, None);
                Slot::Leaf(r)
            }
            _ => Slot::Opaque(ty.clone()),
        }
    }

    /// A nested instance of function block type `name` at `path`.
    fn instantiate_fb(&mut self, name: &str, path: &str, depth: u32) -> Option<usize> {
        // A PROGRAM is one instance, the global named after it (`Other.X` from any code; its
        // body runs where code calls it).
        let user = |p: &PouInfo<'_>| matches!(p.ast.kind, PouKind::FunctionBlock | PouKind::Program);
        if let Some(p) = self.pous.iter().position(|p| user(p) && p.ast.name.is(name)) {
            return Some(self.instantiate_user(p, path, depth));
        }
        let kind = StdFb::from_name(name)?;
        let params = sfc_st::stdlib::std_function_block(name)?;
        let idx = self.insts.len();
        self.insts.push(Inst {
            kind: InstKind::Std(kind, Vec::new()),
            path: path.to_string(),
            vars: Vec::new(),
            chart: None,
            subs: Vec::new(),
        });
        let mut vars = Vec::new();
        for (n, k, ty) in params {
            let p = format!("{path}.{n}");
            let slot = self.layout(&p, &ty, Role::Var { input: false }, depth + 1);
            vars.push(VarEntry { name: n.to_string(), kind: k, ty, slot, location: None, implicit: false });
        }
        let hidden = match kind {
            StdFb::Ton | StdFb::Tof | StdFb::Tp => {
                let running = self.new_reg(format!("{path} (timer running)"), Type::Bool, Role::Hidden, 0, None);
                let count =
                    self.counter_reg(&format!("{path} (timer elapsed)"), &format!("{path}#timer").to_ascii_uppercase());
                let prev = self.new_reg(format!("{path} (IN memory)"), Type::Bool, Role::Hidden, 0, None);
                vec![running, count, prev]
            }
            StdFb::Ctu | StdFb::Ctd | StdFb::RTrig | StdFb::FTrig => {
                vec![self.new_reg(format!("{path} (edge memory)"), Type::Bool, Role::Hidden, 0, None)]
            }
            StdFb::Ctud => vec![
                self.new_reg(format!("{path} (CU memory)"), Type::Bool, Role::Hidden, 0, None),
                self.new_reg(format!("{path} (CD memory)"), Type::Bool, Role::Hidden, 0, None),
            ],
            StdFb::Sr | StdFb::Rs => Vec::new(),
        };
        self.insts[idx].kind = InstKind::Std(kind, hidden);
        self.insts[idx].vars = vars;
        Some(idx)
    }

    /// A counter register (scans) for `key`, saturating at the plan's bound.
    pub fn counter_reg(&mut self, name: &str, key: &str) -> usize {
        let bound = self.counter_bound(key);
        self.new_reg(name.to_string(), Type::UDInt, Role::Hidden, 0, Some((0, bound as i128)))
    }

    /// The saturation bound of counter `key` (the plan's, or a provisional one in early passes).
    pub fn counter_bound(&self, key: &str) -> u64 {
        self.plan.bounds.get(key).copied().unwrap_or(MAX_COUNT).clamp(1, MAX_COUNT)
    }

    /// An instance of user POU `p` (the top POU, or a FUNCTION_BLOCK) at `path`.
    pub fn instantiate_user(&mut self, p: usize, path: &str, depth: u32) -> usize {
        let idx = self.insts.len();
        self.insts.push(Inst {
            kind: InstKind::User(p),
            path: path.to_string(),
            vars: Vec::new(),
            chart: None,
            subs: Vec::new(),
        });
        let top = path.is_empty();
        let iface_vars: Vec<VarInfo> = self.pous[p].iface.vars.clone();
        let mut vars = Vec::new();
        for v in &iface_vars {
            let full = if top { v.name.clone() } else { format!("{path}.{}", v.name) };
            // Globals seen through VAR_EXTERNAL / a PROGRAM's VAR_GLOBAL are the file's globals.
            if matches!(v.kind, VarKind::External | VarKind::Global) {
                if let Some(g) = self.globals.iter().find(|g| g.name.eq_ignore_ascii_case(&v.name)) {
                    vars.push(VarEntry { name: v.name.clone(), ..g.clone() });
                    continue;
                }
            }
            let input = top && self.is_free_input(v, &full);
            let slot = self.layout(&full, &v.ty, Role::Var { input }, depth + 1);
            vars.push(VarEntry {
                name: v.name.clone(),
                kind: v.kind,
                ty: v.ty.clone(),
                slot,
                location: v.location.as_ref().map(|l| l.text.clone()),
                implicit: v.implicit,
            });
        }
        self.insts[idx].vars = vars;
        if let Some(c) = self.pous[p].chart {
            let ch = chart::ChartEnc::new(self, idx, c, path);
            self.charts.push(ch);
            self.insts[idx].chart = Some(self.charts.len() - 1);
        }
        // The charts of its actions written in SFC, in the frame of this instance, named
        // `path.Action` as the simulator names them.
        for c in self.pous[p].subs.clone() {
            let action = chart::chart_at(self.checked, c).action.clone().unwrap_or_default();
            let cpath = if top { action } else { format!("{path}.{action}") };
            let ch = chart::ChartEnc::new(self, idx, c, &cpath);
            self.charts.push(ch);
            let k = self.charts.len() - 1;
            self.insts[idx].subs.push(k);
        }
        idx
    }

    /// Whether a variable of the top POU is a free input of every scan.
    fn is_free_input(&self, v: &VarInfo, path: &str) -> bool {
        let key = path.to_ascii_uppercase();
        if self.setup.extra_inputs.contains(&key) {
            return true;
        }
        if v.implicit || sfc_st::is_sfc_control_variable(&v.name) {
            // SFCInit, SFCPause, SFCQuitError: free when the chart's own code reads them;
            // otherwise they are the caller's and held FALSE (said in the report).
            let free = v.kind == VarKind::Input && self.code_reads(&v.name);
            if !free && v.kind == VarKind::Input {
                self.held.borrow_mut().push(v.name.clone());
            }
            return free;
        }
        match v.kind {
            VarKind::Input | VarKind::InOut => true,
            _ => v.location.as_ref().is_some_and(|l| l.area.eq_ignore_ascii_case(&'I')),
        }
    }

    /// Whether the code of the top POU (its chart's conditions and actions, or its body) names
    /// `name`.
    fn code_reads(&self, name: &str) -> bool {
        let top = self.pous.iter().position(|p| p.ast.name.is(&self.setup.pou));
        let Some(p) = top else { return false };
        let mut found = false;
        let mut visit = |id: &sfc_syntax::ast::Ident| found |= id.is(name);
        let charts = self.pous[p].chart.into_iter().chain(self.pous[p].subs.iter().copied());
        for c in charts {
            let chart = chart::chart_at(self.checked, c);
            for t in &chart.transitions {
                match &t.condition {
                    sfc_syntax::ast::Condition::St(e) => names_in_expr(e, &mut visit),
                    sfc_syntax::ast::Condition::Il(il) => names_in_il(&il.instructions, &mut visit),
                    sfc_syntax::ast::Condition::Missing => {}
                }
            }
            for a in &chart.actions {
                match &a.body {
                    sfc_syntax::ast::ActionBody::St(s) => names_in_stmts(s, &mut visit),
                    sfc_syntax::ast::ActionBody::Il(il) => names_in_il(&il.instructions, &mut visit),
                    sfc_syntax::ast::ActionBody::Sfc(_) => {}
                }
            }
        }
        found
    }

    /// Every register that is a free input of the top POU, with its path.
    pub fn input_regs(&self) -> Vec<usize> {
        (0..self.regs.len()).filter(|&r| self.regs[r].role == Role::Var { input: true }).collect()
    }

    /// Leaf registers of a slot, in layout order.
    pub fn leaves(slot: &Slot, out: &mut Vec<usize>) {
        match slot {
            Slot::Leaf(r) => out.push(*r),
            Slot::Array { items, .. } => items.iter().for_each(|s| Enc::leaves(s, out)),
            Slot::Struct { fields, .. } => fields.iter().for_each(|(_, s)| Enc::leaves(s, out)),
            Slot::Opaque(_) | Slot::Fb(_) => {}
        }
    }
}

/// What the property compiler adds to a scan: assumptions once the inputs are applied, and
/// property signals and monitors once the scan is done.
pub trait Hooks<'a> {
    fn after_inputs(&mut self, e: &mut Enc<'a>);
    /// `cur`: the state before the scan (register words); `range_exits`: per register with a
    /// range, the literal "this scan leaves the range".
    fn after_scan(&mut self, e: &mut Enc<'a>, cur: &[Word], range_exits: &[(usize, Lit)]);
}

/// Initial values of variables by path, from the simulator.
pub type Initial<'a> = &'a dyn Fn(&str) -> Option<sfc_sim::Value>;

/// Encodes one pass.
pub fn encode<'a>(
    checked: &'a Checked,
    setup: &Setup,
    plan: &Plan,
    initial: Initial<'a>,
    hooks: &mut dyn Hooks<'a>,
) -> Result<(Model, Learned), String> {
    let (env, _) = TypeEnv::from_unit(&checked.unit);
    let mut pous = Vec::new();
    for (i, item) in checked.unit.items.iter().enumerate() {
        let Item::Pou(p) = item else { continue };
        let Some(iface) = env.interface_of(p).cloned() else { continue };
        let chart = checked.charts.iter().position(|c| c.item == i);
        let subs = (0..checked.action_charts.len())
            .filter(|&k| checked.action_charts[k].item == i)
            .map(|k| checked.charts.len() + k)
            .collect();
        pous.push(PouInfo { ast: p, iface, chart, subs });
    }
    let top_pou = pous
        .iter()
        .position(|p| p.ast.name.is(&setup.pou) && p.ast.kind != PouKind::Function)
        .ok_or_else(|| format!("no PROGRAM or FUNCTION_BLOCK named `{}`", setup.pou))?;
    // What the model does not encode yet is refused rather than proved without it.
    let uses = sfc_model::dependencies(&checked.unit, &checked.file.text, &setup.pou);
    if let Some((c, s)) = checked
        .charts
        .iter()
        .chain(&checked.action_charts)
        .filter(|c| uses.contains(&c.pou.to_ascii_uppercase()))
        .flat_map(|c| c.steps.iter().map(move |s| (c, s)))
        .find(|(_, s)| s.min_time.is_some())
    {
        return Err(format!(
            "step `{}.{}` has a minimum time (`sfc.min_time`), which `prove` does not model yet",
            c.pou, s.name
        ));
    }
    // CODESYS's SFC flags that act only when declared (docs/sim.md, "Chart control variables").
    for item in &checked.unit.items {
        let Item::Pou(p) = item else { continue };
        if !uses.contains(&p.name.text.to_ascii_uppercase()) || !checked.charts.iter().any(|c| p.name.is(&c.pou)) {
            continue;
        }
        let flags = ["SFCReset", "SFCEnableLimit", "SFCErrorPOU", "SFCTrans", "SFCTip", "SFCTipMode"];
        if let Some(f) = p
            .var_blocks
            .iter()
            .flat_map(|b| b.decls.iter().flat_map(|d| d.names.iter()))
            .find_map(|n| flags.iter().find(|f| n.is(f)))
        {
            return Err(format!(
                "`{}` declares `{f}`, one of CODESYS's SFC flags, which `prove` does not model yet",
                p.name.text
            ));
        }
    }
    let mut e = Enc {
        g: Aig::new(),
        checked,
        env,
        pous,
        setup: setup.clone(),
        plan: plan.clone(),
        learned: Learned::default(),
        regs: Vec::new(),
        latch: Vec::new(),
        mem: Vec::new(),
        insts: Vec::new(),
        globals: Vec::new(),
        charts: Vec::new(),
        inputs: Vec::new(),
        constraints: Vec::new(),
        pc: Lit::TRUE,
        alive: Lit::TRUE,
        returned: Lit::FALSE,
        exited: Lit::FALSE,
        faults: Vec::new(),
        notes: BTreeMap::new(),
        initial,
        top: 0,
        depth: 0,
        frames: Vec::new(),
        scanned: 0,
        guard_of: None,
        held: Default::default(),
        running: Vec::new(),
        refused: None,
        chart_runs: 0,
    };
    // Globals of the file. The simulated PROGRAM is the global named after it: that global is
    // the top instance itself (`Main.X` in a function block is the top's `X`).
    let globals: Vec<VarInfo> = e.env.globals().to_vec();
    let top_is_program = e.pous[top_pou].ast.kind == PouKind::Program;
    let mut top_global = None;
    for v in &globals {
        let located_input = v.location.as_ref().is_some_and(|l| l.area.eq_ignore_ascii_case(&'I'));
        let extra = e.setup.extra_inputs.iter().any(|n| n.eq_ignore_ascii_case(&v.name));
        let is_top = top_is_program
            && top_global.is_none()
            && v.name.eq_ignore_ascii_case(&e.pous[top_pou].ast.name.text)
            && matches!(&v.ty, Type::FunctionBlock(n) if n.eq_ignore_ascii_case(&e.pous[top_pou].ast.name.text));
        let slot = if is_top {
            top_global = Some(e.globals.len());
            Slot::Opaque(v.ty.clone())
        } else {
            e.layout(&v.name, &v.ty, Role::Var { input: located_input || extra }, 0)
        };
        e.globals.push(VarEntry {
            name: v.name.clone(),
            kind: v.kind,
            ty: v.ty.clone(),
            slot,
            location: v.location.as_ref().map(|l| l.text.clone()),
            implicit: false,
        });
    }
    e.scanned = e.new_reg("(scan 0 done)".into(), Type::Bool, Role::Hidden, 0, None);
    e.top = e.instantiate_user(top_pou, "", 0);
    if let Some(k) = top_global {
        e.globals[k].slot = Slot::Fb(e.top);
    }
    let cur: Vec<Word> = e.mem.clone();
    e.scan(hooks)?;
    if let Some(why) = e.refused.take() {
        return Err(why);
    }
    let scanned = e.scanned;
    e.set_reg(scanned, Word::constant(1, 1));
    // Range checks of the values computed in this scan.
    let mut range_exits = Vec::new();
    for r in 0..e.regs.len() {
        let reg = e.regs[r].clone();
        if let Some((lo, hi)) = reg.range {
            if reg.role != (Role::Var { input: true }) && reg.role != Role::Temp && !reg.constant {
                let w = e.mem[r].clone();
                let ok = e.ops().in_range(&w, reg.signed, lo, hi);
                if ok != Lit::TRUE {
                    range_exits.push((r, ok.not()));
                }
            }
        }
    }
    // The stored value of a register with a range is in that range in every state that has a
    // successor (a state where a range was left has none): say so, it helps induction.
    for r in 0..e.regs.len() {
        let reg = e.regs[r].clone();
        let skip = reg.constant || reg.role == Role::Temp || reg.role == (Role::Var { input: true });
        if let (Some((lo, hi)), false) = (reg.range, skip) {
            if r < cur.len() && reg.stored < 127 {
                let signed = reg.range.is_some_and(|(l, _)| l < 0);
                let storable = if signed {
                    (-(1i128 << (reg.stored - 1)), (1i128 << (reg.stored - 1)) - 1)
                } else {
                    (0, (1i128 << reg.stored) - 1)
                };
                if storable.0 < lo || storable.1 > hi {
                    let ok = e.ops().in_range(&cur[r], reg.signed, lo, hi);
                    e.constraints.push(ok);
                }
            }
        }
    }
    hooks.after_scan(&mut e, &cur, &range_exits);
    let mut next = Vec::with_capacity(e.regs.len());
    for r in 0..e.regs.len() {
        let reg = &e.regs[r];
        let stored = if reg.role == Role::Temp || reg.constant {
            e.latch[r].clone()
        } else {
            e.mem[r].bits[..reg.stored].to_vec()
        };
        next.push(stored);
    }
    let held = e.held.borrow().join(", ");
    if !held.is_empty() {
        e.notes.insert(
            format!("{held} held FALSE: the chart's code does not read them (name them in [assume] inputs to make them free)"),
            (),
        );
    }
    let constraint = e.g.and_all(e.constraints.clone());
    let learned = std::mem::take(&mut e.learned);
    let model = Model {
        g: e.g,
        regs: e.regs,
        latch: e.latch,
        next,
        inputs: e.inputs,
        constraint,
        range_exits,
        faults: e.faults,
        notes: e.notes.into_keys().collect(),
        scanned,
        top: e.top,
        insts: e.insts,
        charts: e.charts,
        pou: setup.pou.clone(),
    };
    Ok((model, learned))
}

impl<'a> Enc<'a> {
    /// One scan of the top POU: inputs, then its body (chart or code).
    fn scan(&mut self, hooks: &mut dyn Hooks<'a>) -> Result<(), String> {
        // Inputs: every free variable takes a fresh value.
        for r in self.input_regs() {
            let reg = self.regs[r].clone();
            let stored_signed = self.stored_signed(r);
            let w = self.fresh(reg.name.clone(), reg.stored, stored_signed, Some(r));
            if let Some((lo, hi)) = reg.range {
                let full = w.resize(reg.full, stored_signed);
                let ok = self.ops().in_range(&full, reg.signed, lo, hi);
                self.constraints.push(ok);
            }
            let full = w.resize(reg.full, stored_signed);
            self.set_reg(r, full);
        }
        hooks.after_inputs(self);
        // Timers count the scan boundary.
        self.tick_timers();
        let top = self.top;
        match self.insts[top].chart {
            Some(c) => self.run_chart(c),
            None => self.run_body(top),
        }
        Ok(())
    }

    /// Elapsed-time counters of standard timers advance by one scan at every scan boundary.
    fn tick_timers(&mut self) {
        for i in 0..self.insts.len() {
            if let InstKind::Std(StdFb::Ton | StdFb::Tof | StdFb::Tp, hidden) = &self.insts[i].kind {
                let (running, count) = (hidden[0], hidden[1]);
                let run = self.bool_reg(running);
                let c = self.mem[count].clone();
                let inc = self.sat_inc(&c, &Word::constant(1, c.width()), count);
                let w = self.ops().ite(run, &inc, &c);
                self.set_reg(count, w);
            }
        }
        for c in 0..self.charts.len() {
            self.tick_chart_timers(c);
        }
    }

    /// `c + d` saturating at the bound of counter register `r`.
    pub fn sat_inc(&mut self, c: &Word, d: &Word, r: usize) -> Word {
        let (_, hi) = self.regs[r].range.unwrap_or((0, MAX_COUNT as i128));
        let w = c.width();
        let wide = c.resize(w + 1, false);
        let dw = d.resize(w + 1, false);
        let sum = self.ops().add(&wide, &dw);
        let max = Word::constant(hi, w + 1);
        let over = self.ops().ult(&max, &sum);
        let r = self.ops().ite(over, &max, &sum);
        r.resize(w, false)
    }

    /// The POU the instance runs, and its chart in `Checked::charts`.
    pub fn chart_of(&self, c: usize) -> &'a Chart {
        let idx = self.charts[c].chart;
        chart::chart_at(self.checked, idx)
    }
}

/// Every identifier an expression names.
pub(crate) fn names_in_expr(e: &sfc_syntax::ast::Expr, f: &mut dyn FnMut(&sfc_syntax::ast::Ident)) {
    use sfc_syntax::ast::ExprKind;
    match &e.kind {
        ExprKind::Name(id) => f(id),
        ExprKind::Member { base, .. } => names_in_expr(base, f),
        ExprKind::Index { base, indices } => {
            names_in_expr(base, f);
            indices.iter().for_each(|i| names_in_expr(i, f));
        }
        ExprKind::Call { callee, args } => {
            f(callee);
            for a in args {
                if let Some(v) = &a.value {
                    names_in_expr(v, f);
                }
            }
        }
        ExprKind::Unary { operand, .. } => names_in_expr(operand, f),
        ExprKind::Binary { lhs, rhs, .. } => {
            names_in_expr(lhs, f);
            names_in_expr(rhs, f);
        }
        ExprKind::Paren(inner) => names_in_expr(inner, f),
        _ => {}
    }
}

/// Every identifier statements name.
pub(crate) fn names_in_stmts(list: &[sfc_syntax::ast::Stmt], f: &mut dyn FnMut(&sfc_syntax::ast::Ident)) {
    use sfc_syntax::ast::{CaseLabel, StmtKind};
    for s in list {
        match &s.kind {
            StmtKind::Assign { target, value } => {
                names_in_expr(target, f);
                names_in_expr(value, f);
            }
            StmtKind::Call(e) => names_in_expr(e, f),
            StmtKind::If { branches, else_body } => {
                for (c, b) in branches {
                    names_in_expr(c, f);
                    names_in_stmts(b, f);
                }
                if let Some(b) = else_body {
                    names_in_stmts(b, f);
                }
            }
            StmtKind::Case { selector, arms, else_body } => {
                names_in_expr(selector, f);
                for a in arms {
                    for l in &a.labels {
                        match l {
                            CaseLabel::Value(v) => names_in_expr(v, f),
                            CaseLabel::Range(x, y) => {
                                names_in_expr(x, f);
                                names_in_expr(y, f);
                            }
                        }
                    }
                    names_in_stmts(&a.body, f);
                }
                if let Some(b) = else_body {
                    names_in_stmts(b, f);
                }
            }
            StmtKind::For { var, from, to, by, body } => {
                f(var);
                names_in_expr(from, f);
                names_in_expr(to, f);
                if let Some(b) = by {
                    names_in_expr(b, f);
                }
                names_in_stmts(body, f);
            }
            StmtKind::While { cond, body } | StmtKind::Repeat { body, until: cond } => {
                names_in_expr(cond, f);
                names_in_stmts(body, f);
            }
            _ => {}
        }
    }
}

/// Every identifier an instruction list names.
pub(crate) fn names_in_il(list: &[sfc_syntax::ast::IlInstruction], f: &mut dyn FnMut(&sfc_syntax::ast::Ident)) {
    for i in list {
        i.operands.iter().for_each(|o| names_in_expr(o, f));
        if let Some(n) = &i.nested {
            names_in_il(n, f);
        }
        if let Some(args) = &i.call_args {
            for a in args {
                if let Some(v) = &a.value {
                    names_in_expr(v, f);
                }
            }
        }
    }
}
