//! Calls: function block instances (standard, ST/IL, SFC), user FUNCTIONs (a fresh frame at
//! the end of memory per call), standard functions, actions.
//!
//! VAR_IN_OUT parameters are passed by copy-in/copy-out: the caller's variable is copied into
//! the parameter before the call and back after it.

use super::convert::coerce;
use super::place::{read, sink, write, Loc, PlaceC, Sink};
use super::rt::*;
use super::stdfb::StdFb;
use super::texpr::{CExpr, TExpr};
use super::unit::{Cx, Sym, C};
use super::{Ctx, Place, PouBody};
use crate::value::Value;
use sfc_diagnostics::Span;
use sfc_st::Type;
use sfc_syntax::ast::{Arg, Expr, ExprKind, Ident, Literal, LiteralKind, VarKind};
use std::sync::Arc;

/// A parameter of a called POU: name, kind, frame offset, type.
#[derive(Clone)]
pub(crate) struct Param {
    pub name: String,
    pub kind: VarKind,
    pub offset: u32,
    pub ty: Type,
}

/// Arguments bound to parameters.
pub(crate) struct Bound<'e> {
    /// (parameter, value)
    pub(crate) inputs: Vec<(Param, &'e Expr)>,
    /// (parameter, caller's variable)
    pub(crate) in_outs: Vec<(Param, &'e Expr)>,
    /// (parameter, target, negated)
    pub(crate) outputs: Vec<(Param, &'e Expr, bool)>,
    pub(crate) en: Option<&'e Expr>,
    pub(crate) eno: Option<(&'e Expr, bool)>,
}

/// Runs the body of POU `p` on the frame at `base` (one scan of its chart for an SFC block).
pub(crate) fn run_pou(ctx: &mut Ctx<'_>, p: usize, base: usize) -> R<()> {
    let prog = ctx.prog;
    // An edge-triggered input reads TRUE in the call in which the value passed rose (R_EDGE)
    // or fell (F_EDGE) since the previous call, as an R_TRIG/F_TRIG on it would.
    for &(x, prev, rising) in &prog.pous[p].edges {
        let now = bool_of(&ctx.mem[base + x as usize]);
        let before = bool_of(&ctx.mem[base + prev as usize]);
        ctx.mem[base + prev as usize] = Value::Bool(now);
        ctx.mem[base + x as usize] = Value::Bool(if rising { now && !before } else { !now && before });
    }
    match &prog.pous[p].body {
        PouBody::Code(b) => b(ctx, base).map_err(Box::new),
        PouBody::Chart(cc) => {
            let idx = int_of(&ctx.mem[base + cc.chart_slot as usize]);
            crate::engine::run_chart(ctx, idx.max(0) as usize).map_err(Box::new)
        }
    }
}

/// Runs action `k` of POU `p` on the frame at `base`: a chart's action body, or an action of a
/// POU that is no chart (`Act();` inside the POU, `inst.Act();` from outside).
pub(crate) fn run_action(ctx: &mut Ctx<'_>, p: usize, k: usize, base: usize) -> R<()> {
    let prog = ctx.prog;
    let pou = &prog.pous[p];
    let body = match &pou.body {
        PouBody::Chart(cc) => cc.bodies.get(k),
        PouBody::Code(_) => pou.actions.get(k),
    };
    match body {
        Some(b) => b(ctx, base).map_err(Box::new),
        None => Ok(()),
    }
}

/// Runs the initial-value code of POU `p` on the frame at `base` (nested instances included).
pub(crate) fn run_inits(ctx: &mut Ctx<'_>, p: usize, base: usize) -> R<()> {
    let prog = ctx.prog;
    for op in &prog.support.inits[p] {
        match op {
            super::compile::InitOp::Nested { pou, offset } => run_inits(ctx, *pou, base + *offset as usize)?,
            super::compile::InitOp::Run(f) => f(ctx, base)?,
        }
    }
    Ok(())
}

impl Cx<'_, '_> {
    /// The parameters of the function block type or function `name`.
    fn params_of_fb(&self, fb: &str) -> Option<Vec<Param>> {
        if let Some(i) = self.u.fb_pou(fb) {
            return Some(self.pou_params(i));
        }
        let list = sfc_st::stdlib::std_function_block(fb)?;
        Some(
            list.into_iter()
                .enumerate()
                .map(|(i, (n, k, t))| Param { name: n.to_string(), kind: k, offset: i as u32, ty: t })
                .collect(),
        )
    }

    fn pou_params(&self, i: usize) -> Vec<Param> {
        self.u.pous[i]
            .layout
            .vars
            .iter()
            .filter(|v| matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::InOut))
            .map(|v| Param { name: v.name.clone(), kind: v.kind, offset: v.offset, ty: v.ty.clone() })
            .collect()
    }

    /// Binds `args` to `params` of `owner` (named in messages) of type `ty` (a standard block's
    /// name, for CODESYS's names of its inputs).
    pub(crate) fn bind<'e>(
        &self,
        owner: &str,
        ty: &str,
        params: &[Param],
        args: &'e [Arg],
        span: Span,
    ) -> C<Bound<'e>> {
        let positional: Vec<&Param> =
            params.iter().filter(|p| matches!(p.kind, VarKind::Input | VarKind::InOut)).collect();
        let mut b = Bound { inputs: Vec::new(), in_outs: Vec::new(), outputs: Vec::new(), en: None, eno: None };
        for (i, a) in args.iter().enumerate() {
            if let Some(n) = &a.name {
                if n.is("EN") && !a.output {
                    b.en = a.value.as_ref();
                    continue;
                }
                if n.is("ENO") && a.output {
                    b.eno = a.value.as_ref().map(|v| (v, a.negated));
                    continue;
                }
            }
            let p = match &a.name {
                Some(n) => {
                    // CODESYS's names of RS's and SR's inputs are IEC 61131-3's.
                    let n = sfc_st::stdlib::param_alias(ty, &n.text).unwrap_or(&n.text);
                    params.iter().find(|p| p.name.eq_ignore_ascii_case(n))
                }
                None => positional.get(i).copied(),
            };
            let Some(p) = p else {
                return Err(self.error(a.span, format!("`{owner}` has no such parameter")));
            };
            let Some(v) = &a.value else { continue };
            match (p.kind, a.output) {
                (VarKind::Output, true) => b.outputs.push((p.clone(), v, a.negated)),
                (VarKind::InOut, false) => b.in_outs.push((p.clone(), v)),
                (VarKind::Input, false) => b.inputs.push((p.clone(), v)),
                _ => return Err(self.error(a.span, format!("wrong binding of `{}` of `{owner}`", p.name))),
            }
        }
        let _ = span;
        Ok(b)
    }

    /// A `=>` target as a sink of the parameter's value (`NOT` for negated bindings).
    fn out_writer(&self, param_place: PlaceC, target: &Expr, negated: bool) -> C<StmtFn> {
        let t = self.place(target)?;
        let psize = self.u.type_size(&param_place.ty);
        let mut v = read(param_place, psize);
        if negated {
            v = super::ops::not(v, target.span)?;
        }
        let v = coerce(v, &t.ty, target.span)?;
        let size = self.u.type_size(&t.ty);
        Ok(write(t, v, size))
    }

    /// `inst(IN := x, Q => y)` for an instance at `inst`.
    pub(crate) fn fb_call(&self, name: &Ident, inst: PlaceC, args: &[Arg], span: Span) -> C<StmtFn> {
        let Type::FunctionBlock(fb) = inst.ty.clone() else {
            return Err(self.error(name.span, format!("`{}` is not a function block instance", name.text)));
        };
        let params = self.params_of_fb(&fb).ok_or_else(|| self.error(name.span, format!("unknown block `{fb}`")))?;
        let bound = self.bind(&name.text, &fb, &params, args, span)?;
        let param_place = |p: &Param| PlaceC::new(inst.loc.clone().offset(p.offset), p.ty.clone());
        let mut pre: Vec<StmtFn> = Vec::new();
        let mut post: Vec<StmtFn> = Vec::new();
        for (p, v) in &bound.inputs {
            let val = self.expr_as(v, &p.ty)?;
            pre.push(write(param_place(p), val, self.u.type_size(&p.ty)));
        }
        for (p, v) in &bound.in_outs {
            let caller = self.place(v)?;
            let size = self.u.type_size(&p.ty);
            let cur = read(caller.clone(), size);
            pre.push(write(param_place(p), coerce(cur, &p.ty, v.span)?, size));
            let back = read(param_place(p), size);
            post.push(write(caller.clone(), coerce(back, &caller.ty, v.span)?, size));
        }
        for (p, target, negated) in &bound.outputs {
            post.push(self.out_writer(param_place(p), target, *negated)?);
        }
        let en = match bound.en {
            Some(e) => Some(self.cond(e)?),
            None => None,
        };
        let eno = match bound.eno {
            Some((t, neg)) => {
                let Sink::One(s) = sink(self.place(t)?, 1) else { return Err(self.error(t.span, "ENO must be BOOL")) };
                Some((s, neg))
            }
            None => None,
        };
        let run: RunFb = match self.u.fb_pou(&fb) {
            Some(i) => RunFb::User(i),
            None => {
                RunFb::Std(StdFb::from_name(&fb).ok_or_else(|| self.error(name.span, format!("unknown block `{fb}`")))?)
            }
        };
        let slot = inst.loc.slot_fn();
        Ok(Box::new(move |c, b| {
            if let Some(en) = &en {
                if !en(c, b)? {
                    if let Some((s, neg)) = &eno {
                        s(c, b, Value::Bool(*neg))?;
                    }
                    return Ok(Flow::Next);
                }
            }
            for s in &pre {
                s(c, b)?;
            }
            let ib = slot(c, b)?;
            match run {
                RunFb::Std(k) => super::stdfb::run(k, c, ib),
                RunFb::User(p) => {
                    c.budget.charge(span)?;
                    run_pou(c, p, ib)?
                }
            }
            for s in &post {
                s(c, b)?;
            }
            if let Some((s, neg)) = &eno {
                s(c, b, Value::Bool(!*neg))?;
            }
            Ok(Flow::Next)
        }))
    }

    /// `inst.Act();`: action `Act` of the function block type of `inst`, run on the instance.
    fn member_call(&self, base: &Expr, member: &Ident, args: &[Arg], span: Span) -> C<StmtFn> {
        if let Some(f) = self.interface_stmt(base, member, args, span)? {
            return Ok(f);
        }
        if let Some((t, k)) = self.member_method(base, member)? {
            return self.method_stmt(t, k, args, span);
        }
        let inst = self.place(base)?;
        let Type::FunctionBlock(fb) = inst.ty.clone() else {
            return Err(self.error(base.span, "an action is called on a function block instance"));
        };
        let action =
            self.u.fb_pou(&fb).and_then(|p| match self.u.pous[p].names.get(&member.text.to_ascii_uppercase()) {
                Some(Sym::Action(k)) => Some((p, *k)),
                _ => None,
            });
        let Some((p, k)) = action else {
            // `inst.Inner(…)`: the instance `Inner` inside `inst` is called.
            let inner = self.member(base, member)?;
            if matches!(inner.ty, Type::FunctionBlock(_)) {
                return self.fb_call(member, inner, args, span);
            }
            return Err(self.error(member.span, format!("`{fb}` has no action `{}`", member.text)));
        };
        let flags = self.action_flags(p, k, args, span)?;
        let slot = inst.loc.slot_fn();
        Ok(Box::new(move |c, b| {
            c.budget.charge(span)?;
            let ib = slot(c, b)?;
            for (off, v) in &flags {
                let x = v(c, b)?;
                c.mem[ib + *off as usize] = x;
            }
            run_action(c, p, k, ib)?;
            Ok(Flow::Next)
        }))
    }

    /// The chart flags a call of action `k` of POU `p` sets (`Act(SFCReset := TRUE)`, an
    /// action written in SFC): each flag's offset in the POU's frame and its value.
    fn action_flags(&self, p: usize, k: usize, args: &[Arg], span: Span) -> C<Vec<(u32, ValFn)>> {
        if args.is_empty() {
            return Ok(Vec::new());
        }
        let m = &self.u.pous[p];
        let name = match m.chart {
            Some(c) => self.u.charts[c].actions.get(k).map(|a| a.name.clone()),
            None => super::compile::pou_actions(self.u, p).get(k).map(|a| a.name.text.clone()),
        }
        .unwrap_or_default();
        let sub = m
            .subs
            .iter()
            .find(|s| self.u.charts[s.chart].action.as_deref().is_some_and(|a| a.eq_ignore_ascii_case(&name)));
        let Some(sub) = sub else {
            return Err(self.error(span, format!("action `{name}` takes no arguments")));
        };
        let mut out = Vec::new();
        for a in args {
            let flag = a.name.as_ref().map(|n| n.text.to_ascii_uppercase()).unwrap_or_default();
            let off = match flag.as_str() {
                "SFCINIT" => Some(sub.control.init),
                "SFCRESET" => sub.control.reset,
                "SFCPAUSE" => Some(sub.control.pause),
                "SFCQUITERROR" => Some(sub.control.quit_error),
                _ => None,
            };
            let (Some(off), Some(v), false) = (off, &a.value, a.output) else {
                return Err(self.error(a.span, format!("a call of action `{name}` sets only its chart's flags")));
            };
            let v = self.expr_as(v, &Type::Bool)?;
            out.push((off, v.value()));
        }
        Ok(out)
    }

    /// A call used as a statement.
    pub(crate) fn call_stmt(&self, e: &Expr) -> C<StmtFn> {
        if let ExprKind::MemberCall { base, member, args } = &e.kind {
            return self.member_call(base, member, args, e.span);
        }
        let ExprKind::Call { callee, args } = &e.kind else {
            let v = self.expr(e, None)?;
            let f = v.value();
            return Ok(Box::new(move |c, b| {
                f(c, b)?;
                Ok(Flow::Next)
            }));
        };
        if callee.text == "SUPER^" {
            return self.super_body(e.span);
        }
        match self.lookup(&callee.text) {
            Some(Sym::Var { place, ty, .. }) if matches!(ty, Type::FunctionBlock(_)) => {
                self.fb_call(callee, PlaceC::new(Loc::Static(place), ty), args, e.span)
            }
            Some(Sym::Action(a)) => {
                let p = self.pou.ok_or_else(|| self.error(e.span, "an action outside a POU"))?;
                let span = e.span;
                let flags = self.action_flags(p, a, args, span)?;
                Ok(Box::new(move |c, b| {
                    c.budget.charge(span)?;
                    for (off, v) in &flags {
                        let x = v(c, b)?;
                        c.mem[b + *off as usize] = x;
                    }
                    run_action(c, p, a, b)?;
                    Ok(Flow::Next)
                }))
            }
            None if self.own_method(callee).is_some() => {
                let (t, k) = self.own_method(callee).expect("a method");
                self.method_stmt(t, k, args, e.span)
            }
            _ => {
                let v = self.call_value_at(callee, args, e.span)?;
                let f = v.value();
                Ok(Box::new(move |c, b| {
                    f(c, b)?;
                    Ok(Flow::Next)
                }))
            }
        }
    }

    /// A call used as a value (the call spans `span`): a user FUNCTION or a standard function.
    pub(crate) fn call_value_at(&self, callee: &Ident, args: &[Arg], span: Span) -> C<TExpr> {
        if let Some(Sym::Var { .. } | Sym::Step(_) | Sym::Action(_) | Sym::Return) = self.lookup(&callee.text) {
            return Err(self.error(callee.span, format!("`{}` is not a function", callee.text)));
        }
        let builtin = self.lookup(&callee.text).is_none() && self.u.function(&callee.text).is_none();
        // `SIZEOF(x)`, `SIZEOF(T)` (CODESYS): the bytes of the type on a CODESYS target, a
        // constant (sfc_st::Type::byte_size).
        if builtin && callee.is("SIZEOF") {
            let [Arg { value: Some(v), .. }] = args else {
                return Err(self.error(span, "`SIZEOF` takes one variable or type"));
            };
            let ty = match &v.kind {
                ExprKind::Name(id) if self.lookup(&id.text).is_none() => self.u.env.named_type(&id.text),
                _ => self.recorded(v),
            };
            let ty = ty.ok_or_else(|| self.error(v.span, "`SIZEOF` of what has no type"))?;
            let Some(n) = ty.byte_size() else {
                return Err(self.error(
                    v.span,
                    format!("`SIZEOF` of `{ty}` is not simulated (the layout of a function block instance is the PLC compiler's)"),
                ));
            };
            let rt = self.recorded_at(span).unwrap_or_else(|| Type::sizeof_type(Some(n)));
            return Ok(super::expr::untyped_const(super::expr::Untyped::Int(i128::from(n)), &rt));
        }
        // `LOWER_BOUND(a, d)`, `UPPER_BOUND(a, d)`: a bound of the array's type, a constant.
        if builtin && (callee.is("LOWER_BOUND") || callee.is("UPPER_BOUND")) {
            let (Some(Type::Array { dims, .. }), Some(d)) =
                (args.first().and_then(|a| a.value.as_ref()).and_then(|a| self.recorded(a)), args.get(1))
            else {
                return Err(self.error(span, format!("`{}` takes an array and a dimension", callee.text)));
            };
            let k = d.value.as_ref().and_then(super::expr::untyped);
            let Some(super::expr::Untyped::Int(k)) = k else {
                return Err(self.error(span, "the dimension is a constant"));
            };
            let Some(&(lo, hi)) = usize::try_from(k).ok().and_then(|k| k.checked_sub(1)).and_then(|k| dims.get(k))
            else {
                return Err(self.error(span, "no such dimension"));
            };
            let v = if callee.is("LOWER_BOUND") { lo } else { hi };
            return Ok(super::expr::untyped_const(super::expr::Untyped::Int(i128::from(v)), &Type::DInt));
        }
        // `__ISVALIDREF(r)` (CODESYS): whether the reference designates something.
        if builtin && callee.is("__ISVALIDREF") {
            let [Arg { value: Some(Expr { kind: ExprKind::Name(id), .. }), .. }] = args else {
                return Err(self.error(span, "`__ISVALIDREF` takes one reference"));
            };
            let Some(Sym::Var { place, .. }) = self.lookup(&id.text) else {
                return Err(self.error(id.span, format!("`{}` is not a variable", id.text)));
            };
            let at = Loc::Static(place).slot_fn();
            let f: BoolFn = Box::new(move |c, b| {
                let s = at(c, b)?;
                Ok(int_of(&c.mem[s]) != 0)
            });
            return Ok(TExpr::new(CExpr::Bool(f), Type::Bool, false));
        }
        // `ADR(x)` (CODESYS), `REF(x)` (IEC): the slot of `x` plus one.
        if (callee.is("ADR") || callee.is("REF")) && builtin {
            let [Arg { value: Some(v), .. }] = args else {
                return Err(self.error(span, "`ADR` takes one variable"));
            };
            // `ADR('text')`: the literal, in a slot of its own.
            if let ExprKind::Literal(Literal { kind: LiteralKind::String { value, wide }, .. }) = &v.kind {
                let ty = if *wide { Type::WString { len: None } } else { Type::String { len: None } };
                let p = self.literal_slot(Value::Str(Arc::from(value.as_str())), &ty);
                let at = p.loc.slot_fn();
                let f: IntFn = Box::new(move |c, b| Ok(at(c, b)? as i64 + 1));
                return Ok(TExpr::new(CExpr::Int(f), Type::Pointer(Box::new(ty)), false));
            }
            let p = self.place(v)?;
            let ty = Type::Pointer(Box::new(p.ty.clone()));
            let at = p.loc.slot_fn();
            let f: IntFn = Box::new(move |c, b| Ok(at(c, b)? as i64 + 1));
            return Ok(TExpr::new(CExpr::Int(f), ty, false));
        }
        if let Some((t, k)) = self.lookup(&callee.text).is_none().then(|| self.own_method(callee)).flatten() {
            return self.method_value(t, k, args, span);
        }
        if let Some(fi) = self.u.function(&callee.text) {
            return self.func_call(fi, args, span);
        }
        if let Some(f) = sfc_st::stdlib::std_function(&callee.text) {
            return self.std_call(&f, args, span);
        }
        Err(self.error(callee.span, format!("unknown function `{}`", callee.text)))
    }

    /// A standard function called with ST arguments.
    fn std_call(&self, f: &sfc_st::stdlib::StdFunction, args: &[Arg], span: Span) -> C<TExpr> {
        use sfc_st::stdlib::{ParamType, ReturnType};
        let rt = self.u.types.get(&span).filter(|t| !t.is_error()).cloned();
        let mut bound: Vec<(usize, &Expr)> = Vec::new();
        let mut en = None;
        let mut positional = 0usize;
        for a in args {
            if let Some(n) = &a.name {
                if n.is("EN") && !a.output {
                    en = a.value.as_ref();
                    continue;
                }
                if n.is("ENO") && a.output {
                    continue;
                }
            }
            let idx = match &a.name {
                None => {
                    positional += 1;
                    positional - 1
                }
                Some(n) => f
                    .param_index(&n.text)
                    .ok_or_else(|| self.error(n.span, format!("`{}` has no input `{}`", f.name, n.text)))?,
            };
            if let Some(v) = &a.value {
                bound.push((idx, v));
            }
        }
        bound.sort_by_key(|(i, _)| *i);
        let ret_same = f.ret == ReturnType::Same;
        let mut vals = Vec::new();
        for (i, v) in bound {
            let hint = match f.param_type(i) {
                Some(ParamType::Fixed(t)) => Some(t.clone()),
                Some(ParamType::Same(_)) if ret_same || f.operator.is_some() => rt.clone(),
                _ => None,
            };
            let mut x = self.expr(v, hint.as_ref())?;
            if let Some(ParamType::Fixed(t)) = f.param_type(i) {
                x = coerce(x, t, v.span)?;
            }
            vals.push(x);
        }
        let out = super::stdfn::apply(f, vals, rt, span)?;
        match en {
            None => Ok(out),
            Some(en) => {
                let g = self.cond(en)?;
                let ty = out.ty.clone();
                let dflt = default_value(&ty);
                let f = out.value();
                let v: ValFn = Box::new(move |c, b| if g(c, b)? { f(c, b) } else { Ok(dflt.clone()) });
                Ok(TExpr::from_val(ty, v, false))
            }
        }
    }

    /// A call of user FUNCTION `fi`: a fresh frame is appended to memory for the call and
    /// removed after it.
    pub(crate) fn func_call(&self, fi: usize, args: &[Arg], span: Span) -> C<TExpr> {
        let m = &self.u.pous[fi];
        let params = self.pou_params(fi);
        let bound = self.bind(m.name(), m.name(), &params, args, span)?;
        if bound.en.is_some() || bound.eno.is_some() {
            return Err(self.error(span, "EN/ENO on a user function call"));
        }
        let mut inputs = Vec::new();
        for (p, v) in &bound.inputs {
            inputs.push((p.clone(), self.expr_as(v, &p.ty)?));
        }
        let (copies_in, copies_out) = self.copies(&bound)?;
        self.make_call(fi, inputs, copies_in, copies_out, span)
    }

    /// The copies of a call's in-outs into its frame, and of its in-outs and outputs back to
    /// the caller's variables (a function's or a method's: copy-in/copy-out).
    pub(crate) fn copies(&self, bound: &Bound<'_>) -> C<(Vec<(usize, AggFn)>, Vec<(usize, usize, Sink, bool)>)> {
        let mut copies_in: Vec<(usize, AggFn)> = Vec::new();
        let mut copies_out: Vec<(usize, usize, Sink, bool)> = Vec::new();
        for (p, v) in &bound.in_outs {
            let caller = self.place(v)?;
            let size = self.u.type_size(&p.ty);
            copies_in.push((p.offset as usize, read(caller.clone(), size).agg()));
            copies_out.push((p.offset as usize, size as usize, sink(caller, size), false));
        }
        for (p, t, neg) in &bound.outputs {
            let target = self.place(t)?;
            let size = self.u.type_size(&p.ty);
            copies_out.push((p.offset as usize, size as usize, sink(target, size), *neg));
        }
        Ok((copies_in, copies_out))
    }

    /// The value of input `p` of a call, as its frame receives it: (offset, scalar value,
    /// aggregate value, size).
    pub(crate) fn input_slot(&self, p: &Param, x: TExpr) -> (usize, ValFn, Option<AggFn>, usize) {
        let size = self.u.type_size(&p.ty) as usize;
        if kind_of(&p.ty) == Kind::Agg {
            (p.offset as usize, Box::new(|_, _| Ok(Value::default())), Some(x.agg()), size)
        } else {
            (p.offset as usize, x.value(), None, size)
        }
    }

    /// A call of user FUNCTION `fi` with positional values (IL: the current result first).
    pub(crate) fn func_call_values(&self, fi: usize, vals: Vec<TExpr>, span: Span) -> C<TExpr> {
        let params: Vec<Param> =
            self.pou_params(fi).into_iter().filter(|p| matches!(p.kind, VarKind::Input | VarKind::InOut)).collect();
        if params.len() != vals.len() {
            return Err(self.error(span, "wrong number of inputs"));
        }
        let mut inputs = Vec::new();
        for (p, v) in params.into_iter().zip(vals) {
            let v = coerce(v, &p.ty, span)?;
            inputs.push((p, v));
        }
        self.make_call(fi, inputs, Vec::new(), Vec::new(), span)
    }

    fn make_call(
        &self,
        fi: usize,
        inputs: Vec<(Param, TExpr)>,
        copies_in: Vec<(usize, AggFn)>,
        copies_out: Vec<(usize, usize, Sink, bool)>,
        span: Span,
    ) -> C<TExpr> {
        let m = &self.u.pous[fi];
        let (roff, rty) = m.result.clone().ok_or_else(|| self.error(span, "the function has no result"))?;
        let rsize = self.u.type_size(&rty) as usize;
        let ins: Vec<(usize, ValFn, Option<AggFn>, usize)> =
            inputs.into_iter().map(|(p, x)| self.input_slot(&p, x)).collect();
        let name = m.name().to_string();
        let call = std::sync::Arc::new(FnCall { idx: fi, inputs: ins, copies_in, copies_out, span, name });
        let r = roff as usize;
        let e = match kind_of(&rty) {
            Kind::Bool => CExpr::Bool(Box::new(move |c, b| call.invoke(c, b, |s| bool_of(&s[r])))),
            Kind::Int => CExpr::Int(Box::new(move |c, b| call.invoke(c, b, |s| int_of(&s[r])))),
            Kind::Real => CExpr::Real(Box::new(move |c, b| call.invoke(c, b, |s| real_of(&s[r])))),
            Kind::Str => CExpr::Str(Box::new(move |c, b| call.invoke(c, b, |s| str_of(&s[r])))),
            Kind::Agg => CExpr::Agg(Box::new(move |c, b| call.invoke(c, b, |s| s[r..r + rsize].to_vec()))),
        };
        Ok(TExpr::new(e, rty, false))
    }
}

#[derive(Clone, Copy)]
enum RunFb {
    Std(StdFb),
    User(usize),
}

struct FnCall {
    idx: usize,
    /// (offset, scalar value, aggregate value, size)
    inputs: Vec<(usize, ValFn, Option<AggFn>, usize)>,
    copies_in: Vec<(usize, AggFn)>,
    /// (offset, size, sink, negated)
    copies_out: Vec<(usize, usize, Sink, bool)>,
    span: Span,
    name: String,
}

impl FnCall {
    fn invoke<T>(&self, c: &mut Ctx<'_>, b: usize, get: impl Fn(&[Value]) -> T) -> R<T> {
        c.budget.charge(self.span)?;
        let depth = CALL_DEPTH.with(|d| d.get());
        if depth >= MAX_CALL_DEPTH {
            return Err(fault(format!("calls of `{}` nested too deeply (recursion?)", self.name), self.span));
        }
        CALL_DEPTH.with(|d| d.set(depth + 1));
        let prog = c.prog;
        let fbase = c.mem.len();
        c.mem.extend_from_slice(&prog.support.templates[self.idx]);
        let r = self.inner(c, b, fbase, &get);
        c.mem.truncate(fbase);
        CALL_DEPTH.with(|d| d.set(depth));
        r
    }

    fn inner<T>(&self, c: &mut Ctx<'_>, b: usize, fbase: usize, get: &impl Fn(&[Value]) -> T) -> R<T> {
        run_inits(c, self.idx, fbase)?;
        for (off, f, agg, size) in &self.inputs {
            match agg {
                None => {
                    let v = f(c, b)?;
                    c.mem[fbase + off] = v;
                }
                Some(a) => {
                    let vals = a(c, b)?;
                    for (i, v) in vals.into_iter().take(*size).enumerate() {
                        c.mem[fbase + off + i] = v;
                    }
                }
            }
        }
        for (off, a) in &self.copies_in {
            let vals = a(c, b)?;
            for (i, v) in vals.into_iter().enumerate() {
                c.mem[fbase + off + i] = v;
            }
        }
        run_pou(c, self.idx, fbase)?;
        copy_out(c, b, fbase, &self.copies_out)?;
        Ok(get(&c.mem[fbase..]))
    }
}

/// After a call of a function or method whose frame is at `fbase`: its outputs and in-outs
/// `(offset, size, sink, negated)` written to the caller's variables (frame `b`).
pub(crate) fn copy_out(c: &mut Ctx<'_>, b: usize, fbase: usize, copies_out: &[(usize, usize, Sink, bool)]) -> R<()> {
    for (off, size, s, neg) in copies_out {
        match s {
            Sink::One(f) => {
                let mut v = c.mem[fbase + off].clone();
                if *neg {
                    v = Value::Bool(!bool_of(&v));
                }
                f(c, b, v)?;
            }
            Sink::Many(f) => {
                let v = c.mem[fbase + off..fbase + off + size].to_vec();
                f(c, b, v)?;
            }
        }
    }
    Ok(())
}

/// The place of an instance given by name (for `CAL`).
pub(crate) fn static_place(place: Place, ty: Type) -> PlaceC {
    PlaceC::new(Loc::Static(place), ty)
}
