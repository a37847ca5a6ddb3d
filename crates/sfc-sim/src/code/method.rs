//! Methods and properties of function blocks (CODESYS object orientation): a call runs the
//! method's code on the instance's frame, where its variables have slots that take their
//! initial values again at every call (docs/sim.md, "Methods and properties").
//!
//! A class is compiled whole for each block: the methods it inherits (`EXTENDS`) are compiled
//! again for its frame, so a call `M()` or `THIS^.M()` in inherited code runs the override the
//! instance's own block declares, and `SUPER^.M()` the base's.

use super::call::{copy_out, run_inits, Param};
use super::compile::InitOp;
use super::convert::coerce;
use super::place::{Loc, PlaceC, Sink};
use super::rt::fault;
use super::rt::*;
use super::texpr::{CExpr, TExpr};
use super::unit::{Cx, MethodKind, C};
use super::{Ctx, Place};
use crate::value::Value;
use sfc_diagnostics::Span;
use sfc_st::Type;
use sfc_syntax::ast::{Arg, Expr, ExprKind, Ident, VarKind};
use std::sync::Arc;

/// Whom a call's base names: the instance, its POU, and for `SUPER^` the POU whose code calls.
pub(crate) struct Target {
    pub inst: PlaceC,
    pub pou: usize,
    /// `SUPER^`: the base of this POU's class is searched, not the instance's.
    pub sup_of: Option<usize>,
}

/// A compiled call of a method on an instance.
struct MethodCall {
    slot: LocFn,
    pou: usize,
    k: usize,
    /// (offset, scalar value, aggregate value, size)
    inputs: Vec<(usize, ValFn, Option<AggFn>, usize)>,
    copies_in: Vec<(usize, AggFn)>,
    /// (offset, size, sink, negated)
    copies_out: Vec<(usize, usize, Sink, bool)>,
    span: Span,
    name: String,
}

impl MethodCall {
    /// Runs the call; the instance's frame base.
    fn invoke(&self, c: &mut Ctx<'_>, b: usize) -> R<usize> {
        c.budget.charge(self.span)?;
        let depth = CALL_DEPTH.with(|d| d.get());
        if depth >= MAX_CALL_DEPTH {
            return Err(fault(format!("calls of `{}` nested too deeply (recursion?)", self.name), self.span));
        }
        CALL_DEPTH.with(|d| d.set(depth + 1));
        let r = self.inner(c, b);
        CALL_DEPTH.with(|d| d.set(depth));
        r
    }

    fn inner(&self, c: &mut Ctx<'_>, b: usize) -> R<usize> {
        let ib = (self.slot)(c, b)?;
        // The arguments are the caller's values, taken before the method's variables are fresh.
        let mut vals: Vec<(usize, Vec<Value>)> = Vec::with_capacity(self.inputs.len() + self.copies_in.len());
        for (off, f, agg, size) in &self.inputs {
            match agg {
                None => vals.push((*off, vec![f(c, b)?])),
                Some(a) => vals.push((*off, a(c, b)?.into_iter().take(*size).collect())),
            }
        }
        for (off, a) in &self.copies_in {
            vals.push((*off, a(c, b)?));
        }
        let prog = c.prog;
        let code = &prog.pous[self.pou].methods[self.k];
        for op in &code.init {
            match op {
                InitOp::Nested { pou, offset } => run_inits(c, *pou, ib + *offset as usize)?,
                InitOp::Run(f) => f(c, ib)?,
            }
        }
        for (off, v) in vals {
            for (i, x) in v.into_iter().enumerate() {
                c.mem[ib + off + i] = x;
            }
        }
        (code.body)(c, ib).map_err(Box::new)?;
        copy_out(c, b, ib, &self.copies_out)?;
        Ok(ib)
    }
}

impl Cx<'_, '_> {
    /// The POU whose code this is: a method's declaring block, or the POU.
    fn code_owner(&self) -> Option<usize> {
        if self.owner.is_some() {
            return self.owner;
        }
        match (self.meta(), self.method) {
            (Some(m), Some(k)) => m.methods.get(k).map(|mm| mm.owner),
            _ => self.pou,
        }
    }

    /// `THIS` or `SUPER` in `THIS^`/`SUPER^`.
    fn self_ref(e: &Expr) -> Option<bool> {
        let ExprKind::Deref(inner) = &e.kind else { return None };
        let ExprKind::Name(id) = &inner.kind else { return None };
        if id.is("THIS") {
            Some(false)
        } else if id.is("SUPER") {
            Some(true)
        } else {
            None
        }
    }

    /// The instance a member access or call names (`inst.`, `THIS^.`, `SUPER^.`), when it is
    /// one of a user function block.
    pub(crate) fn target(&self, base: &Expr) -> C<Option<Target>> {
        if let Some(sup) = Self::self_ref(base) {
            let p = self.pou.ok_or_else(|| self.error(base.span, "`THIS^` outside a function block"))?;
            let name = self.u.pous[p].name().to_ascii_uppercase();
            let inst = PlaceC::new(Loc::Static(Place::Local(0)), Type::FunctionBlock(name));
            return Ok(Some(Target { inst, pou: p, sup_of: if sup { self.code_owner() } else { None } }));
        }
        let Some(Type::FunctionBlock(fb)) = self.recorded(base) else { return Ok(None) };
        let Some(p) = self.u.fb_pou(&fb) else { return Ok(None) };
        let m = &self.u.pous[p];
        if m.methods.is_empty() {
            return Ok(None);
        }
        let inst = self.place(base)?;
        Ok(Some(Target { inst, pou: p, sup_of: None }))
    }

    /// The method (or accessor) `name` an instance of POU `p` runs (index into its methods):
    /// the one its class declares or inherits; with `sup_of`, the one the base of that POU's
    /// class has.
    fn find_method(&self, t: &Target, name: &str, kind: MethodKind) -> Option<usize> {
        let class = match t.sup_of {
            None => t.pou,
            Some(o) => self.u.fb_pou(self.u.pous[o].iface.base.as_deref()?)?,
        };
        let iface = &self.u.pous[class].iface;
        let owner = match kind {
            MethodKind::Method => &iface.method(name)?.owner,
            MethodKind::Get | MethodKind::Set => &iface.property(name)?.owner,
        };
        let owner = self.u.fb_pou(owner)?;
        self.u.pous[t.pou]
            .methods
            .iter()
            .position(|mm| mm.kind == kind && mm.owner == owner && mm.sig.name.eq_ignore_ascii_case(name))
    }

    /// The method `M` of `base.M(…)`, if `base` is an instance whose block has one.
    pub(crate) fn member_method(&self, base: &Expr, member: &Ident) -> C<Option<(Target, usize)>> {
        let Some(t) = self.target(base)? else { return Ok(None) };
        Ok(self.find_method(&t, &member.text, MethodKind::Method).map(|k| (t, k)))
    }

    /// The method `M` of `M(…)` in a block's own code (`THIS^.M(…)`).
    pub(crate) fn own_method(&self, name: &Ident) -> Option<(Target, usize)> {
        let p = self.pou?;
        let m = &self.u.pous[p];
        if m.methods.is_empty() {
            return None;
        }
        let inst = PlaceC::new(Loc::Static(Place::Local(0)), Type::FunctionBlock(m.name().to_ascii_uppercase()));
        let t = Target { inst, pou: p, sup_of: None };
        self.find_method(&t, &name.text, MethodKind::Method).map(|k| (t, k))
    }

    /// The property `P` of `base.P`, or of `P` in a block's own code (`base` `None`).
    pub(crate) fn property(&self, base: Option<&Expr>, name: &Ident) -> C<Option<Target>> {
        let t = match base {
            Some(b) => self.target(b)?,
            None => self.pou.filter(|&p| !self.u.pous[p].methods.is_empty()).map(|p| Target {
                inst: PlaceC::new(
                    Loc::Static(Place::Local(0)),
                    Type::FunctionBlock(self.u.pous[p].name().to_ascii_uppercase()),
                ),
                pou: p,
                sup_of: None,
            }),
        };
        Ok(t.filter(|t| {
            let class = match t.sup_of {
                None => Some(t.pou),
                Some(o) => self.u.pous[o].iface.base.as_deref().and_then(|b| self.u.fb_pou(b)),
            };
            class.is_some_and(|c| self.u.pous[c].iface.property(&name.text).is_some())
        }))
    }

    /// The parameters of method `k` of POU `p`, at their slots in the instance's frame.
    fn method_params(&self, p: usize, k: usize) -> Vec<Param> {
        let mm = &self.u.pous[p].methods[k];
        mm.sig
            .vars
            .iter()
            .zip(&mm.vars)
            .filter(|(v, _)| matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::InOut))
            .map(|(v, s)| Param { name: v.name.clone(), kind: v.kind, offset: s.offset, ty: v.ty.clone() })
            .collect()
    }

    fn compile_call(&self, t: Target, k: usize, args: &[Arg], span: Span) -> C<MethodCall> {
        let params = self.method_params(t.pou, k);
        let name = self.u.pous[t.pou].methods[k].sig.name.clone();
        let bound = self.bind(&name, &name, &params, args, span)?;
        if bound.en.is_some() || bound.eno.is_some() {
            return Err(self.error(span, "EN/ENO on a method call"));
        }
        let mut inputs = Vec::new();
        for (p, v) in &bound.inputs {
            let x = self.expr_as(v, &p.ty)?;
            inputs.push(self.input_slot(p, x));
        }
        let (copies_in, copies_out) = self.copies(&bound)?;
        Ok(MethodCall { slot: t.inst.loc.slot_fn(), pou: t.pou, k, inputs, copies_in, copies_out, span, name })
    }

    /// A method call used as a statement.
    pub(crate) fn method_stmt(&self, t: Target, k: usize, args: &[Arg], span: Span) -> C<StmtFn> {
        let call = self.compile_call(t, k, args, span)?;
        Ok(Box::new(move |c, b| {
            call.invoke(c, b)?;
            Ok(Flow::Next)
        }))
    }

    /// A method call used as a value: its result.
    pub(crate) fn method_value(&self, t: Target, k: usize, args: &[Arg], span: Span) -> C<TExpr> {
        let pou = t.pou;
        let call = self.compile_call(t, k, args, span)?;
        self.result_of(pou, k, call, span)
    }

    /// The value of a call: the slot of the method's result after it ran.
    fn result_of(&self, pou: usize, k: usize, call: MethodCall, span: Span) -> C<TExpr> {
        let mm = &self.u.pous[pou].methods[k];
        let Some(rt) = mm.sig.return_type.clone() else {
            return Err(self.error(span, format!("method `{}` returns no value", mm.sig.name)));
        };
        let r = mm.vars.last().map(|s| s.offset as usize).unwrap_or(0);
        let run: LocFn = Arc::new(move |c, b| Ok(call.invoke(c, b)? + r));
        Ok(self.result_at(rt, run))
    }

    /// The value of type `rt` in the slot `run` returns, after running what it runs.
    fn result_at(&self, rt: Type, run: LocFn) -> TExpr {
        let rsize = self.u.type_size(&rt) as usize;
        let e = match kind_of(&rt) {
            Kind::Bool => CExpr::Bool(Box::new(move |c, b| {
                let s = run(c, b)?;
                Ok(bool_of(&c.mem[s]))
            })),
            Kind::Int => CExpr::Int(Box::new(move |c, b| {
                let s = run(c, b)?;
                Ok(int_of(&c.mem[s]))
            })),
            Kind::Real => CExpr::Real(Box::new(move |c, b| {
                let s = run(c, b)?;
                Ok(real_of(&c.mem[s]))
            })),
            Kind::Str => CExpr::Str(Box::new(move |c, b| {
                let s = run(c, b)?;
                Ok(str_of(&c.mem[s]))
            })),
            Kind::Agg => CExpr::Agg(Box::new(move |c, b| {
                let s = run(c, b)?;
                Ok(c.mem[s..s + rsize].to_vec())
            })),
        };
        TExpr::new(e, rt, false)
    }

    /// A property read: its GET run on the instance, then its result.
    pub(crate) fn property_get(&self, t: Target, name: &Ident) -> C<TExpr> {
        let Some(k) = self.find_method(&t, &name.text, MethodKind::Get) else {
            return Err(self.error(name.span, format!("property `{}` has no GET", name.text)));
        };
        let pou = t.pou;
        let call = self.compile_call(t, k, &[], name.span)?;
        self.result_of(pou, k, call, name.span)
    }

    /// A property write: its SET run on the instance with the value.
    pub(crate) fn property_set(&self, t: Target, name: &Ident, value: &Expr, span: Span) -> C<StmtFn> {
        let Some(k) = self.find_method(&t, &name.text, MethodKind::Set) else {
            return Err(self.error(name.span, format!("property `{}` has no SET", name.text)));
        };
        let mm = &self.u.pous[t.pou].methods[k];
        let (Some(v), Some(slot)) = (mm.sig.vars.first(), mm.vars.first()) else {
            return Err(self.error(name.span, "a SET without its value"));
        };
        let (off, ty) = (slot.offset as usize, v.ty.clone());
        let x = self.expr(value, Some(&ty))?;
        let x = coerce(x, &ty, value.span)?;
        let param = Param { name: v.name.clone(), kind: VarKind::Input, offset: off as u32, ty };
        let mut call = self.compile_call(t, k, &[], span)?;
        call.inputs.push(self.input_slot(&param, x));
        Ok(Box::new(move |c, b| {
            call.invoke(c, b)?;
            Ok(Flow::Next)
        }))
    }

    /// `SUPER^()`: the body of the base of the class whose code this is, compiled for this
    /// frame.
    pub(crate) fn super_body(&self, span: Span) -> C<StmtFn> {
        let base = self
            .code_owner()
            .and_then(|o| self.u.pous[o].iface.base.as_deref())
            .and_then(|b| self.u.fb_pou(b))
            .ok_or_else(|| self.error(span, "`SUPER^()` in a block that extends none"))?;
        let cx = Cx { u: self.u, pou: self.pou, method: None, owner: Some(base) };
        let body = match &self.u.pous[base].ast.body {
            sfc_syntax::ast::Body::St(stmts) => cx.stmt_list(stmts)?,
            _ => return Err(self.error(span, "`SUPER^()` of a base block whose body is not ST")),
        };
        Ok(Box::new(move |c, b| {
            c.budget.charge(span)?;
            for s in &body {
                if s(c, b)? == Flow::Return {
                    break;
                }
            }
            Ok(Flow::Next)
        }))
    }

    /// `THIS^.x` and `SUPER^.x`: the block's own variable `x`, not a method's.
    pub(crate) fn self_member(&self, base: &Expr, member: &Ident) -> C<Option<PlaceC>> {
        if Self::self_ref(base).is_none() {
            return Ok(None);
        }
        let cx = Cx { u: self.u, pou: self.pou, method: None, owner: None };
        let e = Expr { kind: ExprKind::Name(member.clone()), span: member.span };
        cx.place(&e).map(Some)
    }
}

// ---------------------------------------------------------------------------------------------
// Interfaces: a variable of an interface type designates an instance of a block implementing
// it. Its value is the instance's frame slot plus one in the low 40 bits and the block (its
// POU index plus one) above, 0 for none; a call through it runs the method of the instance's
// own block (docs/sim.md, "Interfaces").

const ITF_SHIFT: u32 = 40;

/// The value of an interface designating the instance at `slot` of block `pou`.
fn itf_value(slot: usize, pou: usize) -> i64 {
    ((pou as i64 + 1) << ITF_SHIFT) | (slot as i64 + 1)
}

/// The instance's slot and block an interface value designates; `None` for none (0).
fn itf_target(v: i64) -> Option<(usize, usize)> {
    if v <= 0 {
        return None;
    }
    let slot = (v & ((1i64 << ITF_SHIFT) - 1)) - 1;
    let pou = (v >> ITF_SHIFT) - 1;
    (slot >= 0 && pou >= 0).then_some((slot as usize, pou as usize))
}

/// The instance (slot, block) the interface in slot `at` designates, a fault for none.
fn designated(c: &Ctx<'_>, at: usize, span: Span) -> R<(usize, usize)> {
    match itf_target(int_of(&c.mem[at])) {
        Some((slot, pou)) if slot < c.mem.len() => Ok((slot, pou)),
        Some(_) => Err(fault("an interface designates no instance", span)),
        None => Err(fault("an interface that designates nothing (0) is used", span)),
    }
}

impl Cx<'_, '_> {
    /// `itf := inst`, `itf := THIS^`, an instance passed to an interface input: the value
    /// designating it. `None` when `e` is no instance of a user block.
    pub(crate) fn interface_value(&self, e: &Expr, itf: &Type) -> C<Option<TExpr>> {
        let Some(Type::FunctionBlock(fb)) = self.recorded(e) else { return Ok(None) };
        let (at, pou) = match Self::self_ref(e) {
            Some(_) => {
                let p = self.pou.ok_or_else(|| self.error(e.span, "`THIS^` outside a function block"))?;
                (Loc::Static(Place::Local(0)).slot_fn(), p)
            }
            None => {
                let p = self.u.fb_pou(&fb).ok_or_else(|| {
                    self.error(
                        e.span,
                        format!("an interface designates an instance of `{fb}`, which is no block of the file"),
                    )
                })?;
                (self.place(e)?.loc.slot_fn(), p)
            }
        };
        let f: IntFn = Box::new(move |c, b| Ok(itf_value(at(c, b)?, pou)));
        Ok(Some(TExpr::new(CExpr::Int(f), itf.clone(), false)))
    }

    /// The blocks of the file implementing interface `itf`.
    fn implementers(&self, itf: &str) -> Vec<usize> {
        let mut out: Vec<usize> = self
            .u
            .pou_index
            .values()
            .copied()
            .filter(|&p| self.u.pous[p].kind() != sfc_syntax::ast::PouKind::Function)
            .filter(|&p| {
                let ty = Type::FunctionBlock(self.u.pous[p].name().to_ascii_uppercase());
                self.u.env.converts_to_interface(&ty, itf)
            })
            .collect();
        out.sort_unstable();
        out
    }

    /// For `base.M(…)` or `base.P` where `base` is an interface: the slot of the interface and
    /// a target per implementing block, its instance found through the interface.
    fn interface_targets(&self, base: &Expr) -> C<Option<(LocFn, Vec<Target>)>> {
        let Some(Type::Interface(itf)) = self.recorded(base) else { return Ok(None) };
        let at = self.place(base)?.loc.slot_fn();
        let span = base.span;
        let targets = self
            .implementers(&itf)
            .into_iter()
            .map(|p| {
                let at = at.clone();
                let inst: LocFn = Arc::new(move |c, b| {
                    let s = at(c, b)?;
                    Ok(designated(c, s, span)?.0)
                });
                let ty = Type::FunctionBlock(self.u.pous[p].name().to_ascii_uppercase());
                Target { inst: PlaceC::new(Loc::Dyn(inst), ty), pou: p, sup_of: None }
            })
            .collect();
        Ok(Some((at, targets)))
    }

    /// Runs, for the instance the interface in slot `at` designates, the code compiled for its
    /// block (`calls` by POU); the slot the code returns.
    fn dispatch(at: LocFn, calls: Vec<(usize, LocFn)>, span: Span, what: String) -> LocFn {
        Arc::new(move |c, b| {
            let s = at(c, b)?;
            let (_, pou) = designated(c, s, span)?;
            match calls.iter().find(|(p, _)| *p == pou) {
                Some((_, run)) => run(c, b),
                None => Err(fault(format!("the instance an interface designates has no {what}"), span)),
            }
        })
    }

    /// `itf.M(…)`: the method of the designated instance's block; its result slot (or 0).
    fn interface_call(
        &self,
        base: &Expr,
        member: &Ident,
        args: &[Arg],
        span: Span,
    ) -> C<Option<(LocFn, Option<Type>)>> {
        let Some((at, targets)) = self.interface_targets(base)? else { return Ok(None) };
        let Some(Type::Interface(itf)) = self.recorded(base) else { return Ok(None) };
        let rt = self.u.env.interface(&itf).and_then(|i| i.method(&member.text)).and_then(|m| m.return_type.clone());
        let mut calls = Vec::new();
        for t in targets {
            let Some(k) = self.find_method(&t, &member.text, MethodKind::Method) else { continue };
            let pou = t.pou;
            let mm = &self.u.pous[pou].methods[k];
            let r = if rt.is_some() { mm.vars.last().map(|s| s.offset as usize).unwrap_or(0) } else { 0 };
            let call = self.compile_call(t, k, args, span)?;
            calls.push((pou, Arc::new(move |c: &mut Ctx<'_>, b: usize| Ok(call.invoke(c, b)? + r)) as LocFn));
        }
        Ok(Some((Self::dispatch(at, calls, span, format!("method `{}`", member.text)), rt)))
    }

    /// `itf.M(…)` as a statement, when `base` is an interface.
    pub(crate) fn interface_stmt(&self, base: &Expr, member: &Ident, args: &[Arg], span: Span) -> C<Option<StmtFn>> {
        let Some((run, _)) = self.interface_call(base, member, args, span)? else { return Ok(None) };
        Ok(Some(Box::new(move |c, b| {
            run(c, b)?;
            Ok(Flow::Next)
        })))
    }

    /// `itf.M(…)` as a value, when `base` is an interface.
    pub(crate) fn interface_method_value(
        &self,
        base: &Expr,
        member: &Ident,
        args: &[Arg],
        span: Span,
    ) -> C<Option<TExpr>> {
        let Some((run, rt)) = self.interface_call(base, member, args, span)? else { return Ok(None) };
        let rt = rt.ok_or_else(|| self.error(span, format!("method `{}` returns no value", member.text)))?;
        Ok(Some(self.result_at(rt, run)))
    }

    /// `itf.P` read, when `base` is an interface: the GET of the designated instance's block.
    pub(crate) fn interface_get(&self, base: &Expr, name: &Ident) -> C<Option<TExpr>> {
        let Some((at, targets)) = self.interface_targets(base)? else { return Ok(None) };
        let Some(Type::Interface(itf)) = self.recorded(base) else { return Ok(None) };
        let ty = self.u.env.interface(&itf).and_then(|i| i.property(&name.text)).map(|p| p.ty.clone());
        let Some(ty) = ty else { return Ok(None) };
        let mut calls = Vec::new();
        for t in targets {
            let Some(k) = self.find_method(&t, &name.text, MethodKind::Get) else { continue };
            let pou = t.pou;
            let r = self.u.pous[pou].methods[k].vars.last().map(|s| s.offset as usize).unwrap_or(0);
            let call = self.compile_call(t, k, &[], name.span)?;
            calls.push((pou, Arc::new(move |c: &mut Ctx<'_>, b: usize| Ok(call.invoke(c, b)? + r)) as LocFn));
        }
        let run = Self::dispatch(at, calls, name.span, format!("property `{}` with GET", name.text));
        Ok(Some(self.result_at(ty, run)))
    }

    /// `itf.P := v`, when `base` is an interface: the SET of the designated instance's block.
    pub(crate) fn interface_set(&self, base: &Expr, name: &Ident, value: &Expr, span: Span) -> C<Option<StmtFn>> {
        let Some((at, targets)) = self.interface_targets(base)? else { return Ok(None) };
        let mut calls: Vec<(usize, LocFn)> = Vec::new();
        for t in targets {
            if self.find_method(&t, &name.text, MethodKind::Set).is_none() {
                continue;
            }
            let pou = t.pou;
            let set = self.property_set(t, name, value, span)?;
            calls.push((pou, Arc::new(move |c: &mut Ctx<'_>, b: usize| set(c, b).map(|_| 0usize)) as LocFn));
        }
        let run = Self::dispatch(at, calls, span, format!("property `{}` with SET", name.text));
        Ok(Some(Box::new(move |c, b| {
            run(c, b)?;
            Ok(Flow::Next)
        })))
    }
}
