//! The standard function blocks on virtual time: TON, TOF, TP, CTU, CTD, CTUD (and the
//! CTU_DINT-style variants), R_TRIG, F_TRIG, SR, RS.
//!
//! An instance is laid out like a user block: its parameters in the order of
//! `sfc_st::stdlib::std_function_block`, then hidden state slots. Timers count from the scan in
//! which they first see their input (`semantics.md`, "Timers on virtual time"): `ET` is
//! `now − start`, clamped to `PT`, and TON's `Q` is `ET ≥ PT`.

use super::rt::*;
use super::{Ctx, Layout, VarSlot};
use crate::value::Value;
use sfc_st::Type;

/// A standard function block type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StdFb {
    Ton,
    Tof,
    Tp,
    /// Counters, with the representation of their count type.
    Ctu(W),
    Ctd(W),
    Ctud(W),
    RTrig,
    FTrig,
    Sr,
    Rs,
}

impl StdFb {
    /// The block called `name` (upper-case), if it is a standard one.
    pub(crate) fn from_name(name: &str) -> Option<StdFb> {
        let params = sfc_st::stdlib::std_function_block(name)?;
        let upper = name.to_ascii_uppercase();
        let count = params.iter().find(|(n, _, _)| *n == "CV").map(|(_, _, t)| W::of(t)).unwrap_or(W::I16);
        let stem = upper.split('_').next().unwrap_or("");
        Some(match (upper.as_str(), stem) {
            ("TON", _) => StdFb::Ton,
            ("TOF", _) => StdFb::Tof,
            ("TP", _) => StdFb::Tp,
            ("R_TRIG", _) => StdFb::RTrig,
            ("F_TRIG", _) => StdFb::FTrig,
            ("SR", _) => StdFb::Sr,
            ("RS", _) => StdFb::Rs,
            (_, "CTU") => StdFb::Ctu(count),
            (_, "CTD") => StdFb::Ctd(count),
            (_, "CTUD") => StdFb::Ctud(count),
            _ => return None,
        })
    }

    /// Hidden state after the parameters: `(name, default)`.
    fn hidden(self) -> &'static [(&'static str, HiddenInit)] {
        match self {
            StdFb::Ton | StdFb::Tof | StdFb::Tp => {
                &[("start", HiddenInit::Time), ("running", HiddenInit::Bool), ("prev", HiddenInit::Bool)]
            }
            StdFb::Ctu(_) | StdFb::Ctd(_) => &[("prev", HiddenInit::Bool)],
            StdFb::Ctud(_) => &[("prev_cu", HiddenInit::Bool), ("prev_cd", HiddenInit::Bool)],
            StdFb::RTrig | StdFb::FTrig => &[("m", HiddenInit::Bool)],
            StdFb::Sr | StdFb::Rs => &[],
        }
    }
}

#[derive(Clone, Copy)]
enum HiddenInit {
    Bool,
    Time,
}

/// The layout of an instance of standard block `name` (parameters as variables, hidden state
/// counted in the size) and its initial slot values.
pub(crate) fn std_layout(name: &str) -> Option<(Layout, Vec<Value>)> {
    let kind = StdFb::from_name(name)?;
    let params = sfc_st::stdlib::std_function_block(name)?;
    let mut vars = Vec::new();
    let mut template = Vec::new();
    for (i, (n, k, ty)) in params.into_iter().enumerate() {
        template.push(default_value(&ty));
        vars.push(VarSlot {
            name: n.to_string(),
            ty,
            kind: k,
            offset: i as u32,
            size: 1,
            location: None,
            implicit: false,
            retain: false,
            persistent: false,
        });
    }
    for (_, h) in kind.hidden() {
        template.push(match h {
            HiddenInit::Bool => Value::Bool(false),
            HiddenInit::Time => Value::Time(0),
        });
    }
    Some((Layout { vars, size: template.len() as u32 }, template))
}

#[inline]
fn b(m: &[Value], i: usize) -> bool {
    bool_of(&m[i])
}

#[inline]
fn t(m: &[Value], i: usize) -> i64 {
    int_of(&m[i])
}

/// Runs one call of the instance at absolute slot `ib`.
pub(crate) fn run(kind: StdFb, ctx: &mut Ctx<'_>, ib: usize) {
    let timer = matches!(kind, StdFb::Ton | StdFb::Tof | StdFb::Tp);
    if timer && ctx.prog.matiec_time && ib + 4 < ctx.mem.len() {
        // MatIEC's packed timespecs (`crate::timespec`): the timer runs on µs.
        use crate::timespec::Timespec as Ts;
        for k in [1, 3, 4] {
            if let Value::Time(v) = ctx.mem[ib + k] {
                ctx.mem[ib + k] = Value::Time(Ts::unpack(v).to_us());
            }
        }
        run_us(kind, ctx, ib);
        for k in [1, 3, 4] {
            if let Value::Time(v) = ctx.mem[ib + k] {
                ctx.mem[ib + k] = Value::Time(Ts::from_us(v).pack());
            }
        }
        return;
    }
    run_us(kind, ctx, ib);
}

fn run_us(kind: StdFb, ctx: &mut Ctx<'_>, ib: usize) {
    let now = ctx.now;
    let m: &mut [Value] = &mut ctx.mem[..];
    if ib >= m.len() {
        return;
    }
    match kind {
        // IN PT Q ET | start running prev
        StdFb::Ton => {
            let pt = t(m, ib + 1);
            if !b(m, ib) {
                m[ib + 2] = Value::Bool(false);
                m[ib + 3] = Value::Time(0);
                m[ib + 5] = Value::Bool(false);
            } else {
                if !b(m, ib + 5) {
                    m[ib + 5] = Value::Bool(true);
                    m[ib + 4] = Value::Time(now);
                }
                let el = now.saturating_sub(t(m, ib + 4));
                m[ib + 2] = Value::Bool(el >= pt);
                m[ib + 3] = Value::Time(el.min(pt.max(0)));
            }
            m[ib + 6] = Value::Bool(b(m, ib));
        }
        StdFb::Tof => {
            let pt = t(m, ib + 1);
            if b(m, ib) {
                m[ib + 2] = Value::Bool(true);
                m[ib + 3] = Value::Time(0);
                m[ib + 5] = Value::Bool(false);
            } else if b(m, ib + 2) {
                if !b(m, ib + 5) {
                    m[ib + 5] = Value::Bool(true);
                    m[ib + 4] = Value::Time(now);
                }
                let el = now.saturating_sub(t(m, ib + 4));
                if el >= pt {
                    m[ib + 2] = Value::Bool(false);
                    m[ib + 5] = Value::Bool(false);
                    m[ib + 3] = Value::Time(pt.max(0));
                } else {
                    m[ib + 3] = Value::Time(el);
                }
            }
            m[ib + 6] = Value::Bool(b(m, ib));
        }
        StdFb::Tp => {
            let pt = t(m, ib + 1);
            let input = b(m, ib);
            let prev = b(m, ib + 6);
            if b(m, ib + 5) {
                let el = now.saturating_sub(t(m, ib + 4));
                if el >= pt {
                    m[ib + 5] = Value::Bool(false);
                    m[ib + 2] = Value::Bool(false);
                    m[ib + 3] = Value::Time(pt.max(0));
                } else {
                    m[ib + 2] = Value::Bool(true);
                    m[ib + 3] = Value::Time(el);
                }
            } else if input && !prev {
                m[ib + 4] = Value::Time(now);
                m[ib + 3] = Value::Time(0);
                let pulse = pt > 0;
                m[ib + 5] = Value::Bool(pulse);
                m[ib + 2] = Value::Bool(pulse);
            }
            if !b(m, ib + 5) && !input {
                m[ib + 3] = Value::Time(0);
            }
            m[ib + 6] = Value::Bool(input);
        }
        // CU R PV Q CV | prev
        StdFb::Ctu(w) => {
            let (cu, r, pv) = (b(m, ib), b(m, ib + 1), t(m, ib + 2));
            let mut cv = t(m, ib + 4);
            if r {
                cv = 0;
            } else if cu && !b(m, ib + 5) && w.wide(cv) < w.max() {
                cv = w.wrap(cv.wrapping_add(1));
            }
            m[ib + 3] = Value::Bool(w.wide(cv) >= w.wide(pv));
            m[ib + 4] = Value::Int(cv);
            m[ib + 5] = Value::Bool(cu);
        }
        // CD LD PV Q CV | prev
        StdFb::Ctd(w) => {
            let (cd, ld, pv) = (b(m, ib), b(m, ib + 1), t(m, ib + 2));
            let mut cv = t(m, ib + 4);
            if ld {
                cv = pv;
            } else if cd && !b(m, ib + 5) && w.wide(cv) > w.min() {
                cv = w.wrap(cv.wrapping_sub(1));
            }
            m[ib + 3] = Value::Bool(w.wide(cv) <= 0);
            m[ib + 4] = Value::Int(cv);
            m[ib + 5] = Value::Bool(cd);
        }
        // CU CD R LD PV QU QD CV | prev_cu prev_cd
        StdFb::Ctud(w) => {
            let (cu, cd, r, ld, pv) = (b(m, ib), b(m, ib + 1), b(m, ib + 2), b(m, ib + 3), t(m, ib + 4));
            let up = cu && !b(m, ib + 8);
            let down = cd && !b(m, ib + 9);
            let mut cv = t(m, ib + 7);
            if r {
                cv = 0;
            } else if ld {
                cv = pv;
            } else if !(up && down) {
                if up && w.wide(cv) < w.max() {
                    cv = w.wrap(cv.wrapping_add(1));
                } else if down && w.wide(cv) > w.min() {
                    cv = w.wrap(cv.wrapping_sub(1));
                }
            }
            m[ib + 5] = Value::Bool(w.wide(cv) >= w.wide(pv));
            m[ib + 6] = Value::Bool(w.wide(cv) <= 0);
            m[ib + 7] = Value::Int(cv);
            m[ib + 8] = Value::Bool(cu);
            m[ib + 9] = Value::Bool(cd);
        }
        // CLK Q | M (the previous CLK)
        StdFb::RTrig => {
            let clk = b(m, ib);
            m[ib + 1] = Value::Bool(clk && !b(m, ib + 2));
            m[ib + 2] = Value::Bool(clk);
        }
        StdFb::FTrig => {
            let clk = b(m, ib);
            m[ib + 1] = Value::Bool(!clk && b(m, ib + 2));
            m[ib + 2] = Value::Bool(clk);
        }
        // S1 R Q1: set dominant
        StdFb::Sr => {
            let q = b(m, ib) || (!b(m, ib + 1) && b(m, ib + 2));
            m[ib + 2] = Value::Bool(q);
        }
        // S R1 Q1: reset dominant
        StdFb::Rs => {
            let q = !b(m, ib + 1) && (b(m, ib) || b(m, ib + 2));
            m[ib + 2] = Value::Bool(q);
        }
    }
}

/// The type of parameter `name` of standard block `fb`, with its offset.
pub(crate) fn std_param(fb: &str, name: &str) -> Option<(u32, Type, sfc_syntax::ast::VarKind)> {
    let params = sfc_st::stdlib::std_function_block(fb)?;
    params
        .into_iter()
        .enumerate()
        .find(|(_, (n, _, _))| n.eq_ignore_ascii_case(name))
        .map(|(i, (_, k, t))| (i as u32, t, k))
}
