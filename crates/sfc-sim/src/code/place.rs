//! Places (where a variable, element, field or parameter lives) and the compiled reads and
//! writes of them.

use super::rt::*;
use super::texpr::{leaf_bool, leaf_int, leaf_real, CExpr, Leaf, TExpr};
use super::{Ctx, Place};
use crate::value::Value;
use sfc_diagnostics::Span;
use sfc_st::Type;
use std::sync::Arc;

/// Where a place is: fixed at compile time, or computed (array elements with a variable index).
#[derive(Clone)]
pub(crate) enum Loc {
    Static(Place),
    Dyn(LocFn),
}

impl Loc {
    pub(crate) fn offset(self, k: u32) -> Loc {
        if k == 0 {
            return self;
        }
        match self {
            Loc::Static(Place::Local(o)) => Loc::Static(Place::Local(o + k)),
            Loc::Static(Place::Global(g)) => Loc::Static(Place::Global(g + k)),
            Loc::Dyn(f) => Loc::Dyn(Arc::new(move |c, b| Ok(f(c, b)? + k as usize))),
        }
    }

    /// The absolute slot, as a closure.
    pub(crate) fn slot_fn(self) -> LocFn {
        match self {
            Loc::Static(Place::Local(o)) => Arc::new(move |_, b| Ok(b + o as usize)),
            Loc::Static(Place::Global(g)) => Arc::new(move |_, _| Ok(g as usize)),
            Loc::Dyn(f) => f,
        }
    }
}

/// A compiled place with its type; `bit` for bit access `w.3` (then `ty` is BOOL) and partial
/// access `d.%B1` (the lowest bit of the part; `bits` wide, `ty` BYTE, WORD or DWORD).
#[derive(Clone)]
pub(crate) struct PlaceC {
    pub loc: Loc,
    pub ty: Type,
    pub bit: Option<u32>,
    /// Width of the bit string holding the bit.
    pub bit_w: W,
    /// How many bits from `bit` the place is: 1 for a bit.
    pub bits: u32,
}

impl PlaceC {
    pub(crate) fn new(loc: Loc, ty: Type) -> PlaceC {
        PlaceC { loc, ty, bit: None, bit_w: W::I64, bits: 1 }
    }
}

/// `old` with the `bits` bits from `shift` replaced by the low bits of `x`.
fn put_bits(old: i64, shift: u32, bits: u32, x: i64) -> i64 {
    let mask: u64 = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
    let cleared = (old as u64) & !(mask << shift);
    (cleared | (((x as u64) & mask) << shift)) as i64
}

fn reader<T, G>(loc: Loc, get: G) -> Fx<T>
where
    T: 'static,
    G: Fn(&Value) -> T + Copy + Send + Sync + 'static,
{
    match loc {
        Loc::Static(Place::Local(o)) => {
            let o = o as usize;
            Box::new(move |c, b| Ok(get(&c.mem[b + o])))
        }
        Loc::Static(Place::Global(g)) => {
            let g = g as usize;
            Box::new(move |c, _| Ok(get(&c.mem[g])))
        }
        Loc::Dyn(f) => Box::new(move |c, b| {
            let s = f(c, b)?;
            Ok(get(&c.mem[s]))
        }),
    }
}

/// Reads a place.
pub(crate) fn read(p: PlaceC, size: u32) -> TExpr {
    if let Some(bit) = p.bit {
        let f = reader(p.loc, int_of);
        if p.bits > 1 {
            let mask: u64 = (1u64 << p.bits.min(63)) - 1;
            let e = CExpr::Int(Box::new(move |c, b| Ok(((f(c, b)? as u64 >> bit) & mask) as i64)));
            return TExpr::new(e, p.ty, false);
        }
        let e = CExpr::Bool(Box::new(move |c, b| Ok((f(c, b)? as u64 >> bit) & 1 != 0)));
        return TExpr::new(e, Type::Bool, false);
    }
    let leaf = match (&p.loc, kind_of(&p.ty)) {
        (_, Kind::Str | Kind::Agg) => None,
        (Loc::Static(Place::Local(o)), _) => Some(Leaf::Local(*o as usize)),
        (Loc::Static(Place::Global(g)), _) => Some(Leaf::Global(*g as usize)),
        (Loc::Dyn(_), _) => None,
    };
    let e = match kind_of(&p.ty) {
        Kind::Bool => CExpr::Bool(reader(p.loc, bool_of)),
        Kind::Int => CExpr::Int(reader(p.loc, int_of)),
        Kind::Real => CExpr::Real(reader(p.loc, real_of)),
        Kind::Str => CExpr::Str(reader(p.loc, str_of)),
        Kind::Agg => {
            let f = p.loc.slot_fn();
            let n = size as usize;
            CExpr::Agg(Box::new(move |c, b| {
                let s = f(c, b)?;
                Ok(c.mem[s..s + n].to_vec())
            }))
        }
    };
    TExpr { leaf, ..TExpr::new(e, p.ty, false) }
}

/// Stores a leaf value through a static place.
fn leaf_storer<T, G, P>(loc: &Loc, l: Leaf, get: G, put: P) -> Option<StmtFn>
where
    T: 'static,
    G: Fn(Leaf, &Ctx<'_>, usize) -> T + Copy + Send + Sync + 'static,
    P: Fn(T) -> Value + Copy + Send + Sync + 'static,
{
    match loc {
        Loc::Static(Place::Local(o)) => {
            let o = *o as usize;
            Some(Box::new(move |c, b| {
                let x = get(l, c, b);
                c.mem[b + o] = put(x);
                Ok(Flow::Next)
            }))
        }
        Loc::Static(Place::Global(g)) => {
            let g = *g as usize;
            Some(Box::new(move |c, b| {
                let x = get(l, c, b);
                c.mem[g] = put(x);
                Ok(Flow::Next)
            }))
        }
        Loc::Dyn(_) => None,
    }
}

/// Stores `v` through `loc`; `put` makes the slot value.
fn storer<T, P>(loc: Loc, val: Fx<T>, put: P) -> StmtFn
where
    T: 'static,
    P: Fn(T) -> Value + Copy + Send + Sync + 'static,
{
    match loc {
        Loc::Static(Place::Local(o)) => {
            let o = o as usize;
            Box::new(move |c, b| {
                let x = val(c, b)?;
                c.mem[b + o] = put(x);
                Ok(Flow::Next)
            })
        }
        Loc::Static(Place::Global(g)) => {
            let g = g as usize;
            Box::new(move |c, b| {
                let x = val(c, b)?;
                c.mem[g] = put(x);
                Ok(Flow::Next)
            })
        }
        Loc::Dyn(f) => Box::new(move |c, b| {
            let x = val(c, b)?;
            let s = f(c, b)?;
            c.mem[s] = put(x);
            Ok(Flow::Next)
        }),
    }
}

/// Writes `v` (already of the place's type, see `coerce`) to the place.
pub(crate) fn write(p: PlaceC, v: TExpr, size: u32) -> StmtFn {
    if let (Some(bit), true) = (p.bit, p.bits > 1) {
        let (val, w, bits, slot) = (v.int(), p.bit_w, p.bits, p.loc.slot_fn());
        return Box::new(move |c, b| {
            let x = val(c, b)?;
            let s = slot(c, b)?;
            let new = put_bits(int_of(&c.mem[s]), bit, bits, x);
            c.mem[s] = Value::Int(w.wrap(new));
            Ok(Flow::Next)
        });
    }
    if let Some(bit) = p.bit {
        let val = v.bool();
        let w = p.bit_w;
        let slot = p.loc.slot_fn();
        return Box::new(move |c, b| {
            let x = val(c, b)?;
            let s = slot(c, b)?;
            let old = int_of(&c.mem[s]);
            let new = if x { old | (1i64 << bit) } else { old & !(1i64 << bit) };
            c.mem[s] = match c.mem[s] {
                Value::Time(_) => Value::Time(new),
                _ => Value::Int(w.wrap(new)),
            };
            Ok(Flow::Next)
        });
    }
    if let Some(l) = v.leaf {
        let fast = match (kind_of(&p.ty), v.kind()) {
            (Kind::Bool, Kind::Bool) => leaf_storer(&p.loc, l, leaf_bool, Value::Bool),
            (Kind::Int, Kind::Int) if p.ty.is_duration() => leaf_storer(&p.loc, l, leaf_int, Value::Time),
            (Kind::Int, Kind::Int) => leaf_storer(&p.loc, l, leaf_int, Value::Int),
            (Kind::Real, Kind::Real) => leaf_storer(&p.loc, l, leaf_real, Value::Real),
            _ => None,
        };
        if let Some(f) = fast {
            return f;
        }
    }
    match kind_of(&p.ty) {
        Kind::Bool => storer(p.loc, v.bool(), Value::Bool),
        Kind::Int if p.ty.is_duration() => storer(p.loc, v.int(), Value::Time),
        Kind::Int => storer(p.loc, v.int(), Value::Int),
        Kind::Real => storer(p.loc, v.real(), Value::Real),
        Kind::Str => storer(p.loc, v.str(), Value::Str),
        Kind::Agg => {
            let val = v.agg();
            let slot = p.loc.slot_fn();
            let n = size as usize;
            Box::new(move |c, b| {
                let vals = val(c, b)?;
                let s = slot(c, b)?;
                for (i, x) in vals.into_iter().take(n).enumerate() {
                    c.mem[s + i] = x;
                }
                Ok(Flow::Next)
            })
        }
    }
}

type ManySinkFn = Box<dyn Fn(&mut Ctx<'_>, usize, Vec<Value>) -> R<()> + Send + Sync>;

/// Stores values computed elsewhere (copy-out of function outputs and in-outs).
pub(crate) enum Sink {
    One(SinkFn),
    Many(ManySinkFn),
}

/// A sink writing to `p`.
pub(crate) fn sink(p: PlaceC, size: u32) -> Sink {
    let ty = p.ty.clone();
    let slot = p.loc.slot_fn();
    if let Some(bit) = p.bit {
        let (w, bits) = (p.bit_w, p.bits);
        return Sink::One(Box::new(move |c, b, v| {
            let s = slot(c, b)?;
            let old = int_of(&c.mem[s]);
            let new = if bits > 1 {
                put_bits(old, bit, bits, int_of(&v))
            } else if bool_of(&v) {
                old | (1i64 << bit)
            } else {
                old & !(1i64 << bit)
            };
            c.mem[s] = Value::Int(w.wrap(new));
            Ok(())
        }));
    }
    if kind_of(&ty) == Kind::Agg {
        let n = size as usize;
        return Sink::Many(Box::new(move |c, b, vals| {
            let s = slot(c, b)?;
            for (i, x) in vals.into_iter().take(n).enumerate() {
                c.mem[s + i] = x;
            }
            Ok(())
        }));
    }
    let len = string_len(&ty);
    Sink::One(Box::new(move |c, b, v| {
        let s = slot(c, b)?;
        let v = match (v, len) {
            (Value::Str(x), Some(n)) => Value::Str(truncate(x, n)),
            (v, _) => to_slot(&ty, v),
        };
        c.mem[s] = v;
        Ok(())
    }))
}

/// Range check of a subrange target.
pub(crate) fn check_subrange(v: TExpr, lo: i64, hi: i64, span: Span) -> TExpr {
    let ty = v.ty.clone();
    let constant = v.constant;
    let f = v.int();
    let e = CExpr::Int(Box::new(move |c, b| {
        let x = f(c, b)?;
        if x < lo || x > hi {
            return Err(fault(format!("subrange violation: {x} is outside {lo}..{hi}"), span));
        }
        Ok(x)
    }));
    TExpr::new(e, ty, constant).fold()
}
