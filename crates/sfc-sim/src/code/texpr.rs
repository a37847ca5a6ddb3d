//! Compiled expressions: one closure per expression, typed by the shape of its result so that
//! BOOL, integer and TIME code runs without boxing values.

use super::rt::*;
use super::{Ctx, Layout, Program};
use crate::engine::ScanSink;
use crate::value::Value;
use sfc_st::Type;
use std::sync::Arc;

/// A compiled expression by the shape of its result.
pub(crate) enum CExpr {
    Bool(BoolFn),
    Int(IntFn),
    Real(RealFn),
    Str(StrFn),
    Agg(AggFn),
}

/// A compiled expression with its IEC type.
pub(crate) struct TExpr {
    pub e: CExpr,
    pub ty: Type,
    /// Its value does not depend on memory (it can be folded at compile time).
    pub constant: bool,
    /// A constant or a slot read at a fixed place: operators read it directly instead of
    /// calling `e` (one call less on the hot path).
    pub leaf: Option<Leaf>,
}

/// A value an operator can read without calling a closure.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Leaf {
    /// The slot at frame offset.
    Local(usize),
    /// The absolute slot.
    Global(usize),
    Int(i64),
    Bool(bool),
    Real(f64),
}

#[inline(always)]
pub(crate) fn leaf_int(l: Leaf, c: &Ctx<'_>, b: usize) -> i64 {
    match l {
        Leaf::Local(o) => int_of(&c.mem[b + o]),
        Leaf::Global(g) => int_of(&c.mem[g]),
        Leaf::Int(v) => v,
        Leaf::Bool(x) => i64::from(x),
        Leaf::Real(r) => r as i64,
    }
}

#[inline(always)]
pub(crate) fn leaf_bool(l: Leaf, c: &Ctx<'_>, b: usize) -> bool {
    match l {
        Leaf::Local(o) => bool_of(&c.mem[b + o]),
        Leaf::Global(g) => bool_of(&c.mem[g]),
        Leaf::Bool(x) => x,
        Leaf::Int(v) => v != 0,
        Leaf::Real(r) => r != 0.0,
    }
}

#[inline(always)]
pub(crate) fn leaf_real(l: Leaf, c: &Ctx<'_>, b: usize) -> f64 {
    match l {
        Leaf::Local(o) => real_of(&c.mem[b + o]),
        Leaf::Global(g) => real_of(&c.mem[g]),
        Leaf::Real(r) => r,
        Leaf::Int(v) => v as f64,
        Leaf::Bool(x) => f64::from(u8::from(x)),
    }
}

/// An operand: a leaf read directly, or a closure.
pub(crate) enum Opd<T> {
    Leaf(Leaf),
    F(Fx<T>),
}

pub(crate) fn bool_fn<F: Fn(&mut Ctx<'_>, usize) -> R<bool> + Send + Sync + 'static>(f: F) -> BoolFn {
    Box::new(f)
}
pub(crate) fn int_fn<F: Fn(&mut Ctx<'_>, usize) -> R<i64> + Send + Sync + 'static>(f: F) -> IntFn {
    Box::new(f)
}
pub(crate) fn real_fn<F: Fn(&mut Ctx<'_>, usize) -> R<f64> + Send + Sync + 'static>(f: F) -> RealFn {
    Box::new(f)
}

/// Builds `|x, y| body` over two operands, reading leaves directly (4 specialisations).
macro_rules! opd2 {
    ($mk:path, $a:expr, $b:expr, $ga:path, $gb:path, |$x:ident, $y:ident| $body:expr) => {
        match ($a, $b) {
            ($crate::code::texpr::Opd::Leaf(l1), $crate::code::texpr::Opd::Leaf(l2)) => $mk(move |c, base| {
                let $x = $ga(l1, c, base);
                let $y = $gb(l2, c, base);
                $body
            }),
            ($crate::code::texpr::Opd::Leaf(l1), $crate::code::texpr::Opd::F(f2)) => $mk(move |c, base| {
                let $x = $ga(l1, c, base);
                let $y = f2(c, base)?;
                $body
            }),
            ($crate::code::texpr::Opd::F(f1), $crate::code::texpr::Opd::Leaf(l2)) => $mk(move |c, base| {
                let $x = f1(c, base)?;
                let $y = $gb(l2, c, base);
                $body
            }),
            ($crate::code::texpr::Opd::F(f1), $crate::code::texpr::Opd::F(f2)) => $mk(move |c, base| {
                let $x = f1(c, base)?;
                let $y = f2(c, base)?;
                $body
            }),
        }
    };
}
pub(crate) use opd2;

/// Builds `|x| body` over one operand.
macro_rules! opd1 {
    ($mk:path, $a:expr, $g:path, |$x:ident| $body:expr) => {
        match $a {
            $crate::code::texpr::Opd::Leaf(l) => $mk(move |c, base| {
                let $x = $g(l, c, base);
                $body
            }),
            $crate::code::texpr::Opd::F(f) => $mk(move |c, base| {
                let $x = f(c, base)?;
                $body
            }),
        }
    };
}
pub(crate) use opd1;

/// Runs `f` against an empty memory (for folding constants at compile time).
pub(crate) fn with_scratch_ctx<T>(f: impl FnOnce(&mut Ctx<'_>) -> T) -> T {
    let prog =
        Program { pous: Vec::new(), globals: Layout::default(), support: Default::default(), matiec_time: false };
    let mut mem = Vec::new();
    let mut charts = Vec::new();
    let mut sink = ScanSink::default();
    let mut ctx = Ctx {
        mem: &mut mem,
        prog: &prog,
        charts: &mut charts,
        sink: &mut sink,
        now: 0,
        scan: 0,
        profile: Default::default(),
        budget: Default::default(),
    };
    f(&mut ctx)
}

impl TExpr {
    pub(crate) fn new(e: CExpr, ty: Type, constant: bool) -> TExpr {
        TExpr { e, ty, constant, leaf: None }
    }

    pub(crate) fn int_opd(self) -> Opd<i64> {
        match self.leaf {
            Some(l) if self.kind() == Kind::Int => Opd::Leaf(l),
            _ => Opd::F(self.int()),
        }
    }

    pub(crate) fn bool_opd(self) -> Opd<bool> {
        match self.leaf {
            Some(l) if self.kind() == Kind::Bool => Opd::Leaf(l),
            _ => Opd::F(self.bool()),
        }
    }

    pub(crate) fn real_opd(self) -> Opd<f64> {
        match self.leaf {
            Some(l) if self.kind() == Kind::Real => Opd::Leaf(l),
            _ => Opd::F(self.real()),
        }
    }

    pub(crate) fn kind(&self) -> Kind {
        match self.e {
            CExpr::Bool(_) => Kind::Bool,
            CExpr::Int(_) => Kind::Int,
            CExpr::Real(_) => Kind::Real,
            CExpr::Str(_) => Kind::Str,
            CExpr::Agg(_) => Kind::Agg,
        }
    }

    /// A constant of type `ty` (the value is converted to the type's representation).
    pub(crate) fn constant(v: Value, ty: Type) -> TExpr {
        let mut leaf = None;
        let e = match kind_of(&ty) {
            Kind::Bool => {
                let b = bool_of(&v);
                leaf = Some(Leaf::Bool(b));
                CExpr::Bool(Box::new(move |_, _| Ok(b)))
            }
            Kind::Int => {
                let i = int_of(&v);
                leaf = Some(Leaf::Int(i));
                CExpr::Int(Box::new(move |_, _| Ok(i)))
            }
            Kind::Real => {
                let r = real_of(&v);
                leaf = Some(Leaf::Real(r));
                CExpr::Real(Box::new(move |_, _| Ok(r)))
            }
            Kind::Str => {
                let s = str_of(&v);
                CExpr::Str(Box::new(move |_, _| Ok(s.clone())))
            }
            Kind::Agg => {
                let one = vec![v];
                CExpr::Agg(Box::new(move |_, _| Ok(one.clone())))
            }
        };
        TExpr { e, ty, constant: true, leaf }
    }

    /// A generic value computation viewed as an expression of type `ty`.
    pub(crate) fn from_val(ty: Type, f: ValFn, constant: bool) -> TExpr {
        let e = match kind_of(&ty) {
            Kind::Bool => CExpr::Bool(Box::new(move |c, b| Ok(bool_of(&f(c, b)?)))),
            Kind::Int => CExpr::Int(Box::new(move |c, b| Ok(int_of(&f(c, b)?)))),
            Kind::Real => CExpr::Real(Box::new(move |c, b| Ok(real_of(&f(c, b)?)))),
            Kind::Str => CExpr::Str(Box::new(move |c, b| Ok(str_of(&f(c, b)?)))),
            Kind::Agg => CExpr::Agg(Box::new(move |c, b| Ok(vec![f(c, b)?]))),
        };
        TExpr::new(e, ty, constant).fold()
    }

    /// Evaluates a constant expression now; `None` when it is not constant or faults.
    pub(crate) fn const_value(&self) -> Option<Value> {
        if !self.constant {
            return None;
        }
        with_scratch_ctx(|ctx| match &self.e {
            CExpr::Bool(f) => f(ctx, 0).ok().map(Value::Bool),
            CExpr::Int(f) => f(ctx, 0).ok().map(|i| int_value(self.ty.is_duration(), i)),
            CExpr::Real(f) => f(ctx, 0).ok().map(Value::Real),
            CExpr::Str(f) => f(ctx, 0).ok().map(Value::Str),
            CExpr::Agg(_) => None,
        })
    }

    /// Replaces a constant expression by its value (a fault is left to happen at run time).
    pub(crate) fn fold(self) -> TExpr {
        if !self.constant || self.kind() == Kind::Agg {
            return self;
        }
        match self.const_value() {
            Some(v) => TExpr::constant(v, self.ty),
            None => self,
        }
    }

    pub(crate) fn bool(self) -> BoolFn {
        match self.e {
            CExpr::Bool(f) => f,
            CExpr::Int(f) => Box::new(move |c, b| Ok(f(c, b)? != 0)),
            CExpr::Real(f) => Box::new(move |c, b| Ok(f(c, b)? != 0.0)),
            CExpr::Str(_) | CExpr::Agg(_) => Box::new(|_, _| Ok(false)),
        }
    }

    pub(crate) fn int(self) -> IntFn {
        match self.e {
            CExpr::Int(f) => f,
            CExpr::Bool(f) => Box::new(move |c, b| Ok(i64::from(f(c, b)?))),
            CExpr::Real(f) => Box::new(move |c, b| Ok(f(c, b)? as i64)),
            CExpr::Str(_) | CExpr::Agg(_) => Box::new(|_, _| Ok(0)),
        }
    }

    pub(crate) fn real(self) -> RealFn {
        let w = W::of(&self.ty);
        match self.e {
            CExpr::Real(f) => f,
            CExpr::Int(f) => Box::new(move |c, b| Ok(w.to_f64(f(c, b)?))),
            CExpr::Bool(f) => Box::new(move |c, b| Ok(f64::from(u8::from(f(c, b)?)))),
            CExpr::Str(_) | CExpr::Agg(_) => Box::new(|_, _| Ok(0.0)),
        }
    }

    pub(crate) fn str(self) -> StrFn {
        match self.e {
            CExpr::Str(f) => f,
            _ => Box::new(|_, _| Ok(Arc::from(""))),
        }
    }

    pub(crate) fn agg(self) -> AggFn {
        match self.e {
            CExpr::Agg(f) => f,
            other => {
                let v = TExpr::new(other, self.ty, self.constant).value();
                Box::new(move |c, b| Ok(vec![v(c, b)?]))
            }
        }
    }

    /// The result as a generic slot value of its type.
    pub(crate) fn value(self) -> ValFn {
        let time = self.ty.is_duration();
        match self.e {
            CExpr::Bool(f) => Box::new(move |c, b| Ok(Value::Bool(f(c, b)?))),
            CExpr::Int(f) if time => Box::new(move |c, b| Ok(Value::Time(f(c, b)?))),
            CExpr::Int(f) => Box::new(move |c, b| Ok(Value::Int(f(c, b)?))),
            CExpr::Real(f) => Box::new(move |c, b| Ok(Value::Real(f(c, b)?))),
            CExpr::Str(f) => Box::new(move |c, b| Ok(Value::Str(f(c, b)?))),
            CExpr::Agg(f) => Box::new(move |c, b| Ok(f(c, b)?.into_iter().next().unwrap_or_default())),
        }
    }
}
