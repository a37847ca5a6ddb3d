//! ST expressions as words: names, members (`S.X`, `S.T`, `A.Q`, FB outputs, fields, bits),
//! indices, the operators with IEC widths and two's-complement wrap, and the standard
//! functions that have a bit-level meaning. What has none (REAL, strings) is a free value.

use super::{int_sort, Enc, Slot, VarEntry};
use crate::aig::Lit;
use crate::word::Word;
use sfc_diagnostics::Span;
use sfc_st::Type;
use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, Ident, LiteralKind, UnaryOp};

/// A symbolic value.
#[derive(Debug, Clone)]
pub enum SV {
    Bool(Lit),
    /// An integer-like value in the width of its type.
    Int(Word, Type),
    /// An integer constant written without a type: it takes the type of its context.
    Untyped(i128),
    /// `S.T` of a step of chart `c`, kept symbolic so comparisons with constants stay exact.
    StepTime {
        c: usize,
        s: usize,
    },
    /// A value the model does not hold bit by bit (REAL, STRING, …).
    Opaque(Type),
    /// An aggregate place (array, structure, function block) read as a whole.
    Agg(Slot, Type),
}

/// An error in an expression the model cannot make sense of (used for property expressions;
/// chart code is checked already).
#[derive(Debug, Clone)]
pub struct ExprError {
    pub span: Span,
    pub message: String,
}

pub type R<T> = Result<T, ExprError>;

fn err<T>(span: Span, message: impl Into<String>) -> R<T> {
    Err(ExprError { span, message: message.into() })
}

/// Where code runs: an instance (its variables, its chart's steps and actions).
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    pub inst: usize,
    /// Use the checker's recorded expression types (chart code); property expressions infer.
    pub recorded: bool,
}

/// A place that can be read or written.
#[derive(Debug, Clone)]
pub enum PlaceRef {
    Slot(Slot, Type),
    /// An array element chosen by a symbolic index: `(selected, element)` pairs.
    Dyn(Vec<(Lit, Slot)>, Type),
    /// Bit `n` of an integer register.
    Bit(usize, usize),
    StepX(usize, usize),
    StepT(usize, usize),
    ActQ(usize, usize),
    ActA(usize, usize),
}

impl SV {
    pub fn ty(&self) -> Type {
        match self {
            SV::Bool(_) => Type::Bool,
            SV::Int(_, t) => t.clone(),
            SV::Untyped(_) => Type::DInt,
            SV::StepTime { .. } => Type::Time,
            SV::Opaque(t) | SV::Agg(_, t) => t.clone(),
        }
    }
}

pub(crate) fn is_cmp(op: BinaryOp) -> bool {
    matches!(op, BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge)
}

fn timey(t: &Type) -> bool {
    t.is_duration() || t.is_date()
}

/// The IEC result type of `l op r` (the simulator's rule when the checker recorded none).
pub(crate) fn result_type(op: BinaryOp, l: &Type, r: &Type) -> Option<Type> {
    use BinaryOp as B;
    match op {
        B::Eq | B::Ne | B::Lt | B::Gt | B::Le | B::Ge | B::AndThen | B::OrElse => Some(Type::Bool),
        B::Add | B::Sub | B::Mul | B::Div if timey(l) || timey(r) => {
            let (a, b) = (l.base(), r.base());
            match op {
                B::Add | B::Sub if a.is_duration() && b.is_duration() => Type::common(a, b),
                B::Add | B::Sub if matches!(a, Type::TimeOfDay | Type::DateAndTime) && b.is_duration() => {
                    Some(a.clone())
                }
                B::Sub if a == b && a.is_date() => Some(Type::Time),
                B::Mul | B::Div if a.is_duration() => Some(a.clone()),
                B::Mul if b.is_duration() => Some(b.clone()),
                _ => None,
            }
        }
        B::Pow => Some(Type::LReal),
        _ => Type::common(l.base(), r.base()),
    }
}

impl<'a> Enc<'a> {
    fn recorded(&self, f: &Frame, e: &Expr) -> Option<Type> {
        if !f.recorded {
            return None;
        }
        self.checked.expr_types.get(&e.span).filter(|t| !t.is_error()).cloned()
    }

    /// A free value of type `ty` (standing for something the model does not hold).
    pub fn free_value(&mut self, ty: &Type, why: &str) -> SV {
        match int_sort(ty) {
            Some((1, _)) if ty.is_bool() => SV::Bool(self.fresh(why, 1, false, None).bits[0]),
            Some((w, s)) => SV::Int(self.fresh(why, w, s, None), ty.clone()),
            None => SV::Opaque(ty.clone()),
        }
    }

    /// Converts a value to a boolean literal (an opaque value becomes free).
    pub fn to_bool(&mut self, v: SV, span: Span) -> R<Lit> {
        Ok(match v {
            SV::Bool(l) => l,
            SV::Untyped(0) => Lit::FALSE,
            SV::Untyped(1) => Lit::TRUE,
            SV::Opaque(t) if t.is_bool() => self.fresh("a value not modelled", 1, false, None).bits[0],
            SV::Opaque(t) => {
                self.note(format!("a `{t}` value is not modelled bit by bit; conditions on it are free"));
                self.fresh("a value not modelled", 1, false, None).bits[0]
            }
            other => return err(span, format!("expected a BOOL value, found `{}`", other.ty())),
        })
    }

    /// The value as a word of type `to` (implicit conversion: widening, wrap).
    pub fn coerce(&mut self, v: SV, to: &Type, span: Span) -> R<SV> {
        let Some((w, _)) = int_sort(to) else {
            return Ok(match v {
                SV::Agg(s, t) => SV::Agg(s, t),
                _ => SV::Opaque(to.clone()),
            });
        };
        if to.is_bool() {
            return Ok(SV::Bool(self.to_bool(v, span)?));
        }
        Ok(match v {
            SV::Bool(l) => SV::Int(Word::from_bit(l, w), to.base().clone()),
            SV::Untyped(c) => SV::Int(Word::constant(c, w), to.base().clone()),
            SV::Int(word, from) => {
                let (_, fs) = int_sort(&from).unwrap_or((word.width(), false));
                if from.is_duration() == to.is_duration() || !timey(&from) && !timey(to) {
                    SV::Int(word.resize(w, fs), to.base().clone())
                } else {
                    // TIME ↔ integer without a conversion function: the checker refuses it.
                    SV::Int(word.resize(w, fs), to.base().clone())
                }
            }
            SV::StepTime { c, s } => {
                let word = self.step_time_value(c, s, false);
                SV::Int(word.resize(w, true), to.base().clone())
            }
            SV::Opaque(_) | SV::Agg(..) => self.free_value(to, "a value not modelled"),
        })
    }

    /// The word of an integer value in its own width.
    fn word_of(&mut self, v: SV, ty: &Type, span: Span) -> R<Word> {
        match self.coerce(v, ty, span)? {
            SV::Int(w, _) => Ok(w),
            SV::Bool(l) => Ok(Word::from_bit(l, 1)),
            _ => err(span, format!("`{ty}` values are not modelled")),
        }
    }

    /// `S.T` as a TIME word. `compared`: the value is only compared with values the counter's
    /// bound exceeds (exact); otherwise the step is marked as read inexactly.
    pub fn step_time_value(&mut self, c: usize, s: usize, compared: bool) -> Word {
        let key = {
            let ch = &self.charts[c];
            let name = &self.chart_of(c).steps[s].name;
            super::chart::ChartEnc::time_key(&ch.path, name)
        };
        self.note_time_read(c, s, &key);
        let Some(count) = self.step_time_count(c, s) else {
            self.note("a step time the model does not count is free");
            return self.fresh("step time", 64, true, None);
        };
        if !compared {
            self.learned.inexact.insert(key.clone());
            let n = self.learned.need.entry(key.clone()).or_insert(0);
            *n = (*n).max(1);
        }
        let period = self.setup.period as i128;
        let cw = count.resize(64, false);
        let p = Word::constant(period, 64);
        let t = self.ops().mul(&cw, &p);
        if !compared && self.plan.inexact.contains(&key) {
            // Beyond the bound the real time is larger than the counter says.
            let reg = self.charts[c].t[s].unwrap_or(0);
            let bound = self.regs[reg].range.map_or(0, |r| r.1);
            let b = Word::constant(bound, count.width());
            let sat = self.ops().eq(&count, &b);
            if sat != Lit::FALSE {
                self.note(format!(
                    "`{}.T` is used in arithmetic: beyond {} scans its value is free (at least that long)",
                    self.chart_of(c).steps[s].name,
                    bound
                ));
                let free = self.fresh("step time beyond its bound", 64, true, None);
                let min = Word::constant(bound * period, 64);
                let ok = {
                    let lt = self.ops().slt(&free, &min);
                    lt.not()
                };
                let cond = self.g.implies(sat, ok);
                self.constraints.push(cond);
                return self.ops().ite(sat, &free, &t);
            }
        }
        t
    }

    /// Records where a step time is read: only in a guard of a transition leaving the step, or
    /// elsewhere.
    fn note_time_read(&mut self, c: usize, s: usize, key: &str) {
        let own = self.guard_of.is_some_and(|(gc, t)| gc == c && self.chart_of(c).transitions[t].from.contains(&s));
        if !own {
            self.learned.time_read_elsewhere.insert(key.to_string());
        }
    }

    /// Evaluates an expression. `expected`: the type the context wants (for untyped constants).
    pub fn eval(&mut self, f: &Frame, e: &Expr, expected: Option<&Type>) -> R<SV> {
        match &e.kind {
            ExprKind::Literal(lit) => {
                let rec = self.recorded(f, e);
                let prefix = lit.type_prefix.as_deref().and_then(Type::elementary);
                Ok(match &lit.kind {
                    LiteralKind::Int(v) => match rec.or(prefix) {
                        Some(t) if int_sort(&t).is_some() && !t.is_bool() => {
                            let (w, _) = int_sort(&t).unwrap_or((64, true));
                            SV::Int(Word::constant(*v, w), t.base().clone())
                        }
                        Some(t) if t.is_bool() => SV::Bool(Lit::from_bool(*v != 0)),
                        Some(t) if t.is_real() => SV::Opaque(t),
                        _ => SV::Untyped(*v),
                    },
                    LiteralKind::Real(_) => SV::Opaque(rec.filter(|t| t.is_real()).unwrap_or(Type::LReal)),
                    LiteralKind::Bool(b) => SV::Bool(Lit::from_bool(*b)),
                    LiteralKind::Duration(us) => {
                        let t = rec.filter(Type::is_duration).unwrap_or(Type::Time);
                        SV::Int(Word::constant(*us as i128, 64), t)
                    }
                    LiteralKind::String { wide, .. } => {
                        SV::Opaque(if *wide { Type::WString { len: None } } else { Type::String { len: None } })
                    }
                    LiteralKind::Date(d) => SV::Int(Word::constant(*d as i128 * 86_400_000_000, 64), Type::Date),
                    LiteralKind::TimeOfDay(us) => SV::Int(Word::constant(*us as i128, 64), Type::TimeOfDay),
                    LiteralKind::DateAndTime(us) => SV::Int(Word::constant(*us as i128, 64), Type::DateAndTime),
                    LiteralKind::Enum(v) => {
                        let ty = rec.filter(Type::is_enum).or_else(|| {
                            lit.type_prefix.as_deref().and_then(|p| self.env.type_def(p)).map(|d| d.ty.clone())
                        });
                        match ty.as_ref().and_then(|t| t.enum_value(&v.text).map(|n| (t.clone(), n))) {
                            Some((t, n)) => {
                                let (w, _) = int_sort(&t).unwrap_or((64, true));
                                SV::Int(Word::constant(n as i128, w), t)
                            }
                            None => return err(e.span, format!("unknown enumerated value `{}`", lit.text)),
                        }
                    }
                })
            }
            ExprKind::Name(id) => self.eval_name(f, id, e, expected),
            ExprKind::Paren(inner) => self.eval(f, inner, expected),
            ExprKind::Member { .. } | ExprKind::Index { .. } | ExprKind::Address(_) => {
                let p = self.place(f, e)?;
                self.read_place(&p, e.span)
            }
            ExprKind::Unary { op, operand } => {
                let v = self.eval(f, operand, expected)?;
                match op {
                    UnaryOp::Plus => Ok(v),
                    UnaryOp::Not => match v {
                        SV::Bool(l) => Ok(SV::Bool(l.not())),
                        SV::Int(w, t) => {
                            let n = self.ops().not(&w);
                            Ok(SV::Int(n, t))
                        }
                        SV::Untyped(c) => Ok(SV::Untyped(!c)),
                        SV::Opaque(t) if t.is_bool() => Ok(SV::Opaque(t)),
                        other => err(e.span, format!("NOT on `{}`", other.ty())),
                    },
                    UnaryOp::Neg => {
                        if let SV::Untyped(c) = v {
                            return Ok(SV::Untyped(-c));
                        }
                        let t = self.recorded(f, e).unwrap_or_else(|| v.ty());
                        if int_sort(&t).is_none() {
                            return Ok(SV::Opaque(t));
                        }
                        let w = self.word_of(v, &t, e.span)?;
                        let n = self.ops().neg(&w);
                        Ok(SV::Int(n, t.base().clone()))
                    }
                }
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let l = self.eval(f, lhs, None)?;
                let lt = match &l {
                    SV::Untyped(_) => None,
                    v => Some(v.ty()),
                };
                let r = self.eval(f, rhs, lt.as_ref().or(expected))?;
                let rt = if is_cmp(*op) { None } else { self.recorded(f, e) };
                self.binary(*op, l, r, rt, expected, e.span)
            }
            ExprKind::Call { callee, args } => self.call_value(f, callee, args, e.span, expected),
            ExprKind::MemberCall { member, .. } => {
                err(e.span, format!("the call of the action `{}` of an instance cannot be modelled", member.text))
            }
            ExprKind::Deref(_) => err(e.span, "pointers and references cannot be modelled"),
            ExprKind::Error => err(e.span, "the expression has a syntax error"),
        }
    }

    /// A BOOL condition.
    pub fn eval_bool(&mut self, f: &Frame, e: &Expr) -> R<Lit> {
        let v = self.eval(f, e, Some(&Type::Bool))?;
        self.to_bool(v, e.span)
    }

    fn eval_name(&mut self, f: &Frame, id: &Ident, e: &Expr, expected: Option<&Type>) -> R<SV> {
        if let Some(p) = self.lookup_var(f, &id.text) {
            let p = PlaceRef::Slot(p.slot.clone(), p.ty.clone());
            return self.read_place(&p, e.span);
        }
        if self.find_step(f.inst, &id.text).is_some() {
            return err(id.span, format!("`{}` is a step; read `{0}.X`", id.text));
        }
        if let Some(c) = self.insts[f.inst].chart {
            let chart = self.chart_of(c);
            if chart.action(&id.text).is_some() {
                return err(id.span, format!("`{}` is an action; read `{0}.Q`", id.text));
            }
        }
        // An enumerated value.
        let ty = self
            .recorded(f, e)
            .filter(|t| t.enum_value(&id.text).is_some())
            .or_else(|| expected.filter(|t| t.enum_value(&id.text).is_some()).cloned())
            .or_else(|| self.enum_type_with(f, &id.text));
        match ty {
            Some(t) => {
                let n = t.enum_value(&id.text).unwrap_or(0);
                let (w, _) = int_sort(&t).unwrap_or((64, true));
                Ok(SV::Int(Word::constant(n as i128, w), t))
            }
            None => err(id.span, format!("unknown name `{}`", id.text)),
        }
    }

    fn enum_type_with(&self, f: &Frame, name: &str) -> Option<Type> {
        for v in &self.insts[f.inst].vars {
            let t = match &v.ty {
                Type::Array { elem, .. } => elem.as_ref(),
                t => t,
            };
            if t.enum_value(name).is_some() {
                return Some(t.clone());
            }
        }
        self.env.enum_types_with_value(name).first().cloned()
    }

    /// A variable visible in the frame: function temporaries, the instance, globals.
    pub fn lookup_var(&self, f: &Frame, name: &str) -> Option<VarEntry> {
        if let Some(fr) = self.frames.last() {
            if let Some(v) = fr.iter().find(|v| v.name.eq_ignore_ascii_case(name)) {
                return Some(v.clone());
            }
        }
        self.insts[f.inst]
            .vars
            .iter()
            .find(|v| v.name.eq_ignore_ascii_case(name))
            .or_else(|| self.globals.iter().find(|g| g.name.eq_ignore_ascii_case(name)))
            .cloned()
    }

    /// Resolves an expression that denotes a place.
    pub fn place(&mut self, f: &Frame, e: &Expr) -> R<PlaceRef> {
        match &e.kind {
            ExprKind::Name(id) => match self.lookup_var(f, &id.text) {
                Some(v) => Ok(PlaceRef::Slot(v.slot, v.ty)),
                None => err(id.span, format!("`{}` is not a variable", id.text)),
            },
            ExprKind::Paren(inner) => self.place(f, inner),
            ExprKind::Address(a) => {
                let key = a.text.to_ascii_uppercase();
                let found = self.insts[f.inst]
                    .vars
                    .iter()
                    .chain(self.globals.iter())
                    .find(|v| v.location.as_deref().is_some_and(|l| l.eq_ignore_ascii_case(&key)))
                    .cloned();
                match found {
                    Some(v) => Ok(PlaceRef::Slot(v.slot, v.ty)),
                    None => {
                        // An address no variable declares: a free input (area I) or a cell of
                        // memory the model creates on first sight.
                        let ty = match a.size.to_ascii_uppercase() {
                            'B' => Type::Byte,
                            'W' => Type::Word,
                            'D' => Type::DWord,
                            'L' => Type::LWord,
                            _ => Type::Bool,
                        };
                        self.note(format!("direct address `{}` used in code without a declaration is free", a.text));
                        let v = self.free_value(&ty, &a.text);
                        let r = self.new_reg(format!("{} (address)", a.text), ty.clone(), super::Role::Temp, 0, None);
                        if let SV::Int(w, _) = &v {
                            self.mem[r] = w.clone();
                        } else if let SV::Bool(l) = v {
                            self.mem[r] = Word::from_bit(l, 1);
                        }
                        Ok(PlaceRef::Slot(Slot::Leaf(r), ty))
                    }
                }
            }
            ExprKind::Member { base, member } => self.member_place(f, base, member),
            ExprKind::Index { base, indices } => self.index_place(f, base, indices, e.span),
            _ => err(e.span, "the expression is not a variable"),
        }
    }

    /// Step `name` of instance `inst`, as the simulator finds it in the POU's namespace: a step
    /// of its chart, else of the charts of its actions written in SFC in the file's order
    /// (`(chart, step)`).
    pub fn find_step(&self, inst: usize, name: &str) -> Option<(usize, usize)> {
        let i = &self.insts[inst];
        i.chart.into_iter().chain(i.subs.iter().copied()).find_map(|c| self.chart_of(c).step(name).map(|s| (c, s)))
    }

    fn member_place(&mut self, f: &Frame, base: &Expr, member: &Ident) -> R<PlaceRef> {
        if let ExprKind::Name(id) = &base.kind {
            if self.lookup_var(f, &id.text).is_none() {
                if let Some((c, s)) = self.find_step(f.inst, &id.text) {
                    return match member.text.to_ascii_uppercase().as_str() {
                        "X" => Ok(PlaceRef::StepX(c, s)),
                        "T" => Ok(PlaceRef::StepT(c, s)),
                        _ => err(member.span, format!("steps have no member `{}` (X or T)", member.text)),
                    };
                }
                if let Some(c) = self.insts[f.inst].chart {
                    let chart = self.chart_of(c);
                    if let Some(a) = chart.action(&id.text) {
                        return match member.text.to_ascii_uppercase().as_str() {
                            "Q" => Ok(PlaceRef::ActQ(c, a)),
                            "A" => Ok(PlaceRef::ActA(c, a)),
                            _ => err(member.span, format!("actions have no member `{}` (Q or A)", member.text)),
                        };
                    }
                }
            }
        }
        // `Inst.Step.X` / `Inst.Action.Q` of a nested chart instance (readable by properties).
        if let ExprKind::Member { base: inner, member: elem } = &base.kind {
            if let Ok(PlaceRef::Slot(Slot::Fb(i), _)) = self.place(f, inner) {
                let m = member.text.to_ascii_uppercase();
                if let Some((c, s)) = self.find_step(i, &elem.text) {
                    match m.as_str() {
                        "X" => return Ok(PlaceRef::StepX(c, s)),
                        "T" => return Ok(PlaceRef::StepT(c, s)),
                        _ => {}
                    }
                }
                if let Some(c) = self.insts[i].chart {
                    let chart = self.chart_of(c);
                    if let Some(a) = chart.action(&elem.text) {
                        match m.as_str() {
                            "Q" => return Ok(PlaceRef::ActQ(c, a)),
                            "A" => return Ok(PlaceRef::ActA(c, a)),
                            _ => {}
                        }
                    }
                }
            }
        }
        let pb = self.place(f, base)?;
        let (slot, ty) = match pb {
            PlaceRef::Slot(s, t) => (s, t),
            PlaceRef::Dyn(cands, t) => {
                // A member of a dynamically indexed element: the same member of each candidate.
                let mut out = Vec::new();
                let mut mty = None;
                for (sel, s) in cands {
                    let (ms, mt) = self.member_of_slot(&s, &t, member)?;
                    mty = Some(mt);
                    out.push((sel, ms));
                }
                return Ok(PlaceRef::Dyn(out, mty.unwrap_or(Type::Bool)));
            }
            _ => return err(member.span, format!("no member `{}` here", member.text)),
        };
        if !member.text.is_empty() && member.text.bytes().all(|b| b.is_ascii_digit()) {
            let bit: usize = member.text.parse().unwrap_or(0);
            return match slot {
                Slot::Leaf(r) => Ok(PlaceRef::Bit(r, bit)),
                _ => err(member.span, "bit access on a value the model does not hold"),
            };
        }
        let (s, t) = self.member_of_slot(&slot, &ty, member)?;
        Ok(PlaceRef::Slot(s, t))
    }

    fn member_of_slot(&mut self, slot: &Slot, ty: &Type, member: &Ident) -> R<(Slot, Type)> {
        match slot {
            Slot::Struct { fields, .. } => {
                let ft = ty.field(&member.text).cloned().unwrap_or(Type::Bool);
                match fields.iter().find(|(n, _)| n.eq_ignore_ascii_case(&member.text)) {
                    Some((_, s)) => Ok((s.clone(), ft)),
                    None => err(member.span, format!("`{ty}` has no field `{}`", member.text)),
                }
            }
            Slot::Fb(i) => {
                let inst = &self.insts[*i];
                match inst.vars.iter().find(|v| v.name.eq_ignore_ascii_case(&member.text)) {
                    Some(v) => Ok((v.slot.clone(), v.ty.clone())),
                    None => err(member.span, format!("`{ty}` has no member `{}`", member.text)),
                }
            }
            Slot::Opaque(t) => {
                let mt = match t {
                    Type::Struct { .. } => t.field(&member.text).cloned().unwrap_or(Type::Bool),
                    Type::FunctionBlock(n) => self
                        .env
                        .function_block(n)
                        .and_then(|fb| fb.var(&member.text).map(|v| v.ty.clone()))
                        .unwrap_or(Type::Bool),
                    _ => Type::Bool,
                };
                Ok((Slot::Opaque(mt.clone()), mt))
            }
            _ => err(member.span, format!("`{ty}` has no member `{}`", member.text)),
        }
    }

    fn index_place(&mut self, f: &Frame, base: &Expr, indices: &[Expr], span: Span) -> R<PlaceRef> {
        let pb = self.place(f, base)?;
        let PlaceRef::Slot(slot, ty) = pb else {
            return err(base.span, "nested dynamic indexing is not modelled");
        };
        let Slot::Array { dims, elem, items } = slot else {
            if let Slot::Opaque(Type::Array { elem, .. }) = &slot {
                return Ok(PlaceRef::Slot(Slot::Opaque((**elem).clone()), (**elem).clone()));
            }
            return err(base.span, format!("`{ty}` is not an array"));
        };
        if dims.len() != indices.len() {
            return err(span, "wrong number of indices");
        }
        // Row-major strides.
        let mut strides = vec![1i64; dims.len()];
        for k in (0..dims.len().saturating_sub(1)).rev() {
            let (lo, hi) = dims[k + 1];
            strides[k] = strides[k + 1] * (hi - lo + 1);
        }
        // Per dimension: a constant index, or a symbolic one.
        let mut per_dim: Vec<Result<i64, Word>> = Vec::new();
        for (i, ix) in indices.iter().enumerate() {
            let v = self.eval(f, ix, Some(&Type::DInt))?;
            let (lo, hi) = dims[i];
            let w = match v {
                SV::Untyped(c) => Word::constant(c, 65),
                SV::Int(w, t) => {
                    let s = int_sort(&t).is_none_or(|x| x.1);
                    w.resize(65, s)
                }
                other => return err(ix.span, format!("an index must be an integer, found `{}`", other.ty())),
            };
            match w.as_const(true) {
                Some(c) => {
                    if (c as i64) < lo || (c as i64) > hi {
                        return err(ix.span, format!("index {c} is out of range {lo}..{hi}"));
                    }
                    per_dim.push(Ok(c as i64));
                }
                None => {
                    let ok = self.ops().in_range(&w, true, lo as i128, hi as i128);
                    self.fault(ok.not(), format!("array index is out of range {lo}..{hi}"), ix.span);
                    per_dim.push(Err(w));
                }
            }
        }
        if per_dim.iter().all(|d| d.is_ok()) {
            let mut k = 0i64;
            for (d, v) in per_dim.iter().enumerate() {
                if let Ok(c) = v {
                    k += (c - dims[d].0) * strides[d];
                }
            }
            let s = items.get(k as usize).cloned().unwrap_or(Slot::Opaque(elem.clone()));
            return Ok(PlaceRef::Slot(s, elem));
        }
        let mut cands = Vec::new();
        for (k, item) in items.iter().enumerate() {
            let mut rem = k as i64;
            let mut sel = Lit::TRUE;
            for d in 0..dims.len() {
                let coord = rem / strides[d];
                rem %= strides[d];
                let value = dims[d].0 + coord;
                match &per_dim[d] {
                    Ok(c) => {
                        if *c != value {
                            sel = Lit::FALSE;
                        }
                    }
                    Err(w) => {
                        let cw = Word::constant(value as i128, w.width());
                        let eq = self.ops().eq(w, &cw);
                        sel = self.g.and(sel, eq);
                    }
                }
                if sel == Lit::FALSE {
                    break;
                }
            }
            if sel != Lit::FALSE {
                cands.push((sel, item.clone()));
            }
        }
        Ok(PlaceRef::Dyn(cands, elem))
    }

    /// Reads a place.
    pub fn read_place(&mut self, p: &PlaceRef, span: Span) -> R<SV> {
        Ok(match p {
            PlaceRef::Slot(Slot::Leaf(r), ty) => {
                let w = self.mem[*r].clone();
                if ty.is_bool() {
                    SV::Bool(w.bits[0])
                } else {
                    SV::Int(w, ty.base().clone())
                }
            }
            PlaceRef::Slot(Slot::Opaque(t), _) => match int_sort(t) {
                Some(_) => self.free_value(t, "a value not modelled"),
                None => SV::Opaque(t.clone()),
            },
            PlaceRef::Slot(s, t) => SV::Agg(s.clone(), t.clone()),
            PlaceRef::Dyn(cands, ty) => {
                if int_sort(ty).is_none() {
                    return Ok(SV::Opaque(ty.clone()));
                }
                let mut acc: Option<SV> = None;
                for (sel, s) in cands.iter().rev() {
                    let v = self.read_place(&PlaceRef::Slot(s.clone(), ty.clone()), span)?;
                    acc = Some(match acc {
                        None => v,
                        Some(prev) => self.ite_sv(*sel, v, prev, ty, span)?,
                    });
                }
                match acc {
                    Some(v) => v,
                    None => self.free_value(ty, "out-of-range element"),
                }
            }
            PlaceRef::Bit(r, n) => {
                let w = &self.mem[*r];
                SV::Bool(w.bits.get(*n).copied().unwrap_or(Lit::FALSE))
            }
            PlaceRef::StepX(c, s) => SV::Bool(self.step_x(*c, *s)),
            PlaceRef::StepT(c, s) => SV::StepTime { c: *c, s: *s },
            PlaceRef::ActQ(c, a) => SV::Bool(self.bool_reg(self.charts[*c].q[*a])),
            PlaceRef::ActA(c, a) => SV::Bool(self.bool_reg(self.charts[*c].a[*a])),
        })
    }

    /// `if c then a else b` of two values of type `ty`.
    pub fn ite_sv(&mut self, c: Lit, a: SV, b: SV, ty: &Type, span: Span) -> R<SV> {
        if ty.is_bool() {
            let x = self.to_bool(a, span)?;
            let y = self.to_bool(b, span)?;
            return Ok(SV::Bool(self.g.ite(c, x, y)));
        }
        if int_sort(ty).is_none() {
            return Ok(SV::Opaque(ty.clone()));
        }
        let x = self.word_of(a, ty, span)?;
        let y = self.word_of(b, ty, span)?;
        let w = self.ops().ite(c, &x, &y);
        Ok(SV::Int(w, ty.base().clone()))
    }

    /// A binary operator (the simulator's `ops::binary`).
    pub fn binary(
        &mut self,
        op: BinaryOp,
        l: SV,
        r: SV,
        rt: Option<Type>,
        expected: Option<&Type>,
        span: Span,
    ) -> R<SV> {
        use BinaryOp as B;
        // Untyped constants fold.
        if let (SV::Untyped(a), SV::Untyped(b)) = (&l, &r) {
            let (a, b) = (*a, *b);
            let v = match op {
                B::Add => Some(a.wrapping_add(b)),
                B::Sub => Some(a.wrapping_sub(b)),
                B::Mul => Some(a.wrapping_mul(b)),
                B::Div if b != 0 => Some(a / b),
                B::Mod if b != 0 => Some(a % b),
                _ => None,
            };
            if let (Some(v), None) = (v, &rt) {
                return Ok(SV::Untyped(v));
            }
        }
        if is_cmp(op) {
            return self.compare(op, l, r, span);
        }
        match op {
            B::AndThen | B::OrElse => {
                let a = self.to_bool(l, span)?;
                let b = self.to_bool(r, span)?;
                return Ok(SV::Bool(if op == B::AndThen { self.g.and(a, b) } else { self.g.or(a, b) }));
            }
            B::Pow => return Ok(SV::Opaque(Type::LReal)),
            _ => {}
        }
        // Types of the operands (untyped constants take the other side's).
        let lt = match &l {
            SV::Untyped(_) => None,
            v => Some(v.ty()),
        };
        let rty = match &r {
            SV::Untyped(_) => None,
            v => Some(v.ty()),
        };
        let (lt, rty) = match (lt, rty) {
            (Some(a), Some(b)) => (a, b),
            (Some(a), None) => (a.clone(), a),
            (None, Some(b)) => (b.clone(), b),
            (None, None) => {
                let t = rt.clone().or_else(|| expected.cloned()).unwrap_or(Type::DInt);
                (t.clone(), t)
            }
        };
        if matches!(op, B::Add | B::Sub | B::Mul | B::Div) && (timey(&lt) || timey(&rty)) {
            return self.time_arith(op, l, r, &lt, &rty, rt, span);
        }
        let t = match rt.or_else(|| result_type(op, &lt, &rty)) {
            Some(t) => t,
            None => return err(span, format!("operator `{}` on `{lt}` and `{rty}`", op.symbol())),
        };
        if t.is_real() || int_sort(&t).is_none() {
            return Ok(SV::Opaque(t));
        }
        if t.is_bool() {
            let a = self.to_bool(l, span)?;
            let b = self.to_bool(r, span)?;
            return Ok(SV::Bool(match op {
                B::And => self.g.and(a, b),
                B::Or => self.g.or(a, b),
                B::Xor => self.g.xor(a, b),
                _ => return err(span, format!("operator `{}` on BOOL", op.symbol())),
            }));
        }
        let (_, signed) = int_sort(&t).unwrap_or((64, true));
        let a = self.word_of(l, &t, span)?;
        let b = self.word_of(r, &t, span)?;
        let mut o = self.ops();
        let w = match op {
            B::And => o.bitwise(&a, &b, |g, x, y| g.and(x, y)),
            B::Or => o.bitwise(&a, &b, |g, x, y| g.or(x, y)),
            B::Xor => o.bitwise(&a, &b, |g, x, y| g.xor(x, y)),
            B::Add => o.add(&a, &b),
            B::Sub => o.sub(&a, &b),
            B::Mul => o.mul(&a, &b),
            B::Div | B::Mod => {
                let zero = o.is_zero(&b);
                let (q, rm) = if signed { o.sdivrem(&a, &b) } else { o.udivrem(&a, &b) };
                drop(o);
                let what = if op == B::Div { "division by zero" } else { "MOD by zero" };
                self.fault(zero, what, span);
                if op == B::Div {
                    q
                } else {
                    rm
                }
            }
            _ => return err(span, format!("operator `{}` on `{t}`", op.symbol())),
        };
        Ok(SV::Int(w, t.base().clone()))
    }

    /// TIME and date arithmetic (IEC 61131-3 table 30).
    #[allow(clippy::too_many_arguments)]
    fn time_arith(&mut self, op: BinaryOp, l: SV, r: SV, lt: &Type, rty: &Type, rt: Option<Type>, span: Span) -> R<SV> {
        let Some(res) = rt.or_else(|| result_type(op, lt, rty)) else {
            return err(span, format!("operator `{}` on `{lt}` and `{rty}`", op.symbol()));
        };
        match op {
            BinaryOp::Add | BinaryOp::Sub => {
                if res.base() == &Type::TimeOfDay {
                    return Ok(self.free_value(&res, "TIME_OF_DAY arithmetic"));
                }
                let a = self.word_of(l, lt, span)?.resize(64, true);
                let b = self.word_of(r, rty, span)?.resize(64, true);
                let w = if op == BinaryOp::Add { self.ops().add(&a, &b) } else { self.ops().sub(&a, &b) };
                Ok(SV::Int(w, res.base().clone()))
            }
            _ => {
                let (d, dt, n, nt) = if timey(lt) { (l, lt, r, rty) } else { (r, rty, l, lt) };
                if nt.is_real() {
                    return Ok(self.free_value(&res, "TIME times REAL"));
                }
                let a = self.word_of(d, dt, span)?.resize(64, true);
                let nt = if matches!(n, SV::Untyped(_)) { Type::LInt } else { nt.clone() };
                let (_, ns) = int_sort(&nt).unwrap_or((64, true));
                let b = self.word_of(n, &nt, span)?.resize(64, ns);
                let w = if op == BinaryOp::Mul {
                    self.ops().mul(&a, &b)
                } else {
                    let zero = self.ops().is_zero(&b);
                    self.fault(zero, "division by zero", span);
                    self.ops().sdivrem(&a, &b).0
                };
                Ok(SV::Int(w, res.base().clone()))
            }
        }
    }

    /// `= <> < > <= >=`.
    pub fn compare(&mut self, op: BinaryOp, l: SV, r: SV, span: Span) -> R<SV> {
        use BinaryOp as B;
        // A step time against a constant: a threshold on its counter.
        let flipped = |op: BinaryOp| match op {
            B::Lt => B::Gt,
            B::Gt => B::Lt,
            B::Le => B::Ge,
            B::Ge => B::Le,
            o => o,
        };
        if let SV::StepTime { c, s } = l {
            return self.compare_step_time(op, c, s, r, span);
        }
        if let SV::StepTime { c, s } = r {
            return self.compare_step_time(flipped(op), c, s, l, span);
        }
        let lt = match &l {
            SV::Untyped(_) => None,
            v => Some(v.ty()),
        };
        let rty = match &r {
            SV::Untyped(_) => None,
            v => Some(v.ty()),
        };
        let ct = match (&lt, &rty) {
            (Some(a), Some(b)) => {
                Type::common(a, b).or_else(|| (int_sort(a).is_some() && int_sort(b).is_some()).then(|| a.clone()))
            }
            (Some(a), None) | (None, Some(a)) => Some(a.clone()),
            (None, None) => {
                if let (SV::Untyped(a), SV::Untyped(b)) = (&l, &r) {
                    let v = match op {
                        B::Eq => a == b,
                        B::Ne => a != b,
                        B::Lt => a < b,
                        B::Gt => a > b,
                        B::Le => a <= b,
                        _ => a >= b,
                    };
                    return Ok(SV::Bool(Lit::from_bool(v)));
                }
                None
            }
        };
        let Some(ct) = ct else {
            return err(span, format!("comparing `{}` with `{}`", l.ty(), r.ty()));
        };
        if int_sort(&ct).is_none() {
            self.note(format!("comparisons of `{ct}` values are not modelled; their results are free"));
            return Ok(SV::Bool(self.fresh("comparison not modelled", 1, false, None).bits[0]));
        }
        if ct.is_bool() {
            let a = self.to_bool(l, span)?;
            let b = self.to_bool(r, span)?;
            let v = match op {
                B::Eq => self.g.xnor(a, b),
                B::Ne => self.g.xor(a, b),
                B::Lt => self.g.and(a.not(), b),
                B::Gt => self.g.and(a, b.not()),
                B::Le => self.g.or(a.not(), b),
                _ => self.g.or(a, b.not()),
            };
            return Ok(SV::Bool(v));
        }
        let (_, signed) = int_sort(&ct).unwrap_or((64, true));
        let a = self.word_of(l, &ct, span)?;
        let b = self.word_of(r, &ct, span)?;
        let mut o = self.ops();
        let v = match op {
            B::Eq => o.eq(&a, &b),
            B::Ne => o.eq(&a, &b).not(),
            B::Lt => o.lt(&a, &b, signed),
            B::Gt => o.lt(&b, &a, signed),
            B::Le => o.lt(&b, &a, signed).not(),
            _ => o.lt(&a, &b, signed).not(),
        };
        Ok(SV::Bool(v))
    }

    /// `S.T op other`, exact with a saturating counter whose bound exceeds every value
    /// `other` can take.
    fn compare_step_time(&mut self, op: BinaryOp, c: usize, s: usize, other: SV, span: Span) -> R<SV> {
        use BinaryOp as B;
        let key = {
            let name = self.chart_of(c).steps[s].name.clone();
            super::chart::ChartEnc::time_key(&self.charts[c].path, &name)
        };
        self.note_time_read(c, s, &key);
        let period = self.setup.period as i128;
        let ow = self.word_of(other, &Type::Time, span)?;
        if let Some(k) = ow.as_const(true) {
            let need = (k.max(-1)).div_euclid(period) + 1;
            let n = self.learned.need.entry(key.clone()).or_insert(0);
            *n = (*n).max(need.clamp(1, super::MAX_COUNT as i128) as u64);
            if let Some(count) = self.step_time_count(c, s) {
                let reg = self.charts[c].t[s].unwrap_or(0);
                let bound = self.regs[reg].range.map_or(0, |r| r.1);
                // T ≥ k ⇔ count ≥ ⌈k/Δ⌉;  T > k ⇔ count ≥ ⌊k/Δ⌋ + 1;  T = k ⇔ Δ | k ∧ count = k/Δ.
                let ge_k = |e: &mut Enc<'_>, th: i128| -> Lit {
                    if th <= 0 {
                        Lit::TRUE
                    } else if th > bound {
                        Lit::FALSE
                    } else {
                        let cw = Word::constant(th, count.width());
                        e.ops().ult(&count, &cw).not()
                    }
                };
                let ceil = if k <= 0 { 0 } else { (k + period - 1) / period };
                let v = match op {
                    B::Ge => ge_k(self, ceil),
                    B::Lt => ge_k(self, ceil).not(),
                    B::Gt => ge_k(self, need),
                    B::Le => ge_k(self, need).not(),
                    B::Eq | B::Ne => {
                        let eq = if k < 0 || k % period != 0 || k / period >= bound {
                            Lit::FALSE
                        } else {
                            let cw = Word::constant(k / period, count.width());
                            self.ops().eq(&count, &cw)
                        };
                        if op == B::Eq {
                            eq
                        } else {
                            eq.not()
                        }
                    }
                    _ => Lit::FALSE,
                };
                return Ok(SV::Bool(v));
            }
        } else {
            // Compared with a variable: the bound must exceed the largest value it can take.
            let (_, hi) = ow.bounds(true);
            let need = (hi.max(-1)).div_euclid(period) + 1;
            let n = self.learned.need.entry(key.clone()).or_insert(0);
            if need > super::MAX_COUNT as i128 {
                self.learned.inexact.insert(key);
                *n = super::MAX_COUNT;
            } else {
                *n = (*n).max(need.max(1) as u64);
            }
        }
        let t = self.step_time_value(c, s, true);
        self.compare(op, SV::Int(t, Type::Time), SV::Int(ow, Type::Time), span)
    }

    /// A function call used as a value.
    pub fn call_value(
        &mut self,
        f: &Frame,
        callee: &Ident,
        args: &[sfc_syntax::ast::Arg],
        span: Span,
        expected: Option<&Type>,
    ) -> R<SV> {
        if let Some(p) = self
            .pous
            .iter()
            .position(|p| p.ast.kind == sfc_syntax::ast::PouKind::Function && p.ast.name.is(&callee.text))
        {
            return self.call_function(f, p, args, span);
        }
        if let Some(sf) = sfc_st::stdlib::std_function(&callee.text) {
            return self.call_std(f, &sf, args, span, expected);
        }
        err(callee.span, format!("unknown function `{}`", callee.text))
    }

    /// The standard functions with a bit-level meaning; the others give free values.
    fn call_std(
        &mut self,
        f: &Frame,
        sf: &sfc_st::stdlib::StdFunction,
        args: &[sfc_syntax::ast::Arg],
        span: Span,
        expected: Option<&Type>,
    ) -> R<SV> {
        use sfc_st::stdlib::ParamType;
        let rt = if f.recorded { self.checked.expr_types.get(&span).filter(|t| !t.is_error()).cloned() } else { None };
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
                Some(n) => match sf.param_index(&n.text) {
                    Some(i) => i,
                    None => return err(n.span, format!("`{}` has no input `{}`", sf.name, n.text)),
                },
            };
            if let Some(v) = &a.value {
                bound.push((idx, v));
            }
        }
        bound.sort_by_key(|(i, _)| *i);
        let mut vals = Vec::new();
        for (i, v) in &bound {
            let hint = match sf.param_type(*i) {
                Some(ParamType::Fixed(t)) => Some(t.clone()),
                Some(ParamType::Same(_)) => rt.clone().or_else(|| expected.cloned()),
                _ => None,
            };
            let mut x = self.eval(f, v, hint.as_ref())?;
            if let Some(ParamType::Fixed(t)) = sf.param_type(*i) {
                x = self.coerce(x, t, v.span)?;
            }
            vals.push(x);
        }
        let name = sf.name.as_str();
        let mut out = self.apply_std(sf, name, vals, rt.clone(), expected, span)?;
        if let Some(en) = en {
            let g = self.eval_bool(f, en)?;
            let ty = out.ty();
            let dflt = match int_sort(&ty) {
                Some(_) if ty.is_bool() => SV::Bool(Lit::FALSE),
                Some((w, _)) => SV::Int(Word::constant(0, w), ty.base().clone()),
                None => SV::Opaque(ty.clone()),
            };
            out = self.ite_sv(g, out, dflt, &ty, span)?;
        }
        Ok(out)
    }

    fn same_type(vals: &[SV], expected: Option<&Type>) -> Type {
        let mut t: Option<Type> = None;
        for v in vals {
            if let SV::Untyped(_) = v {
                continue;
            }
            let vt = v.ty();
            t = Some(match t {
                None => vt.base().clone(),
                Some(p) => Type::common(&p, &vt).unwrap_or(p),
            });
        }
        t.or_else(|| expected.cloned()).unwrap_or(Type::DInt)
    }

    fn apply_std(
        &mut self,
        sf: &sfc_st::stdlib::StdFunction,
        name: &str,
        vals: Vec<SV>,
        rt: Option<Type>,
        expected: Option<&Type>,
        span: Span,
    ) -> R<SV> {
        if let Some(op) = sf.operator {
            let mut it = vals.into_iter();
            let Some(mut acc) = it.next() else { return err(span, format!("`{name}` needs inputs")) };
            if is_cmp(op) {
                // GT(a, b, c) = a > b AND b > c.
                let rest: Vec<SV> = it.collect();
                let mut result = Lit::TRUE;
                let mut prev = acc;
                for v in rest {
                    let c = self.compare(op, prev, v.clone(), span)?;
                    let c = self.to_bool(c, span)?;
                    result = self.g.and(result, c);
                    prev = v;
                }
                return Ok(SV::Bool(result));
            }
            for v in it {
                acc = self.binary(op, acc, v, rt.clone(), expected, span)?;
            }
            return Ok(acc);
        }
        let t_same = Self::same_type(&vals, rt.as_ref().or(expected));
        let n = vals.len();
        let arg = |k: usize| -> R<SV> {
            vals.get(k).cloned().ok_or(ExprError { span, message: format!("`{name}` needs {} inputs", k + 1) })
        };
        match name {
            "NOT" => {
                let a = arg(0)?;
                let t = rt.clone().unwrap_or_else(|| a.ty());
                let a = self.coerce(a, &t, span)?;
                match a {
                    SV::Bool(l) => Ok(SV::Bool(l.not())),
                    SV::Int(w, t) => Ok(SV::Int(self.ops().not(&w), t)),
                    o => Ok(o),
                }
            }
            "MOVE" => {
                let a = arg(0)?;
                let t = rt.clone().unwrap_or_else(|| a.ty());
                self.coerce(a, &t, span)
            }
            "ABS" => {
                let a = arg(0)?;
                let t = rt.clone().unwrap_or_else(|| a.ty());
                match int_sort(&t) {
                    Some((_, true)) if !t.is_real() => {
                        let w = self.word_of(a, &t, span)?;
                        let neg = self.ops().neg(&w);
                        let sign = *w.bits.last().unwrap_or(&Lit::FALSE);
                        Ok(SV::Int(self.ops().ite(sign, &neg, &w), t.base().clone()))
                    }
                    Some(_) => self.coerce(a, &t, span),
                    None => Ok(SV::Opaque(t)),
                }
            }
            "SEL" => {
                let g = arg(0)?;
                let g = self.to_bool(g, span)?;
                let (a, b) = (arg(1)?, arg(2)?);
                let t = rt.clone().unwrap_or_else(|| Self::same_type(&[a.clone(), b.clone()], expected));
                let a = self.coerce(a, &t, span)?;
                let b = self.coerce(b, &t, span)?;
                self.ite_sv(g, b, a, &t, span)
            }
            "MUX" => {
                let k = arg(0)?;
                let kw = self.word_of(k, &Type::DInt, span)?;
                let ins: Vec<SV> = vals[1..].to_vec();
                let t = rt.clone().unwrap_or_else(|| Self::same_type(&ins, expected));
                let mut acc = None;
                let mut in_range = Lit::FALSE;
                for (i, v) in ins.into_iter().enumerate().rev() {
                    let v = self.coerce(v, &t, span)?;
                    let cw = Word::constant(i as i128, kw.width());
                    let sel = self.ops().eq(&kw, &cw);
                    in_range = self.g.or(in_range, sel);
                    acc = Some(match acc {
                        None => v,
                        Some(prev) => self.ite_sv(sel, v, prev, &t, span)?,
                    });
                }
                self.fault(in_range.not(), "MUX: selector out of range", span);
                acc.ok_or(ExprError { span, message: "MUX needs inputs".into() })
            }
            "MIN" | "MAX" => {
                let t = t_same.clone();
                if int_sort(&t).is_none() || t.is_real() {
                    return Ok(SV::Opaque(t));
                }
                let (_, signed) = int_sort(&t).unwrap_or((64, true));
                let mut it = vals.into_iter();
                let first = it.next().ok_or(ExprError { span, message: format!("`{name}` needs inputs") })?;
                let mut acc = self.word_of(first, &t, span)?;
                for v in it {
                    let w = self.word_of(v, &t, span)?;
                    let lt = self.ops().lt(&w, &acc, signed);
                    let pick = if name == "MIN" { lt } else { self.ops().lt(&acc, &w, signed) };
                    acc = self.ops().ite(pick, &w, &acc);
                }
                if t.is_bool() {
                    return Ok(SV::Bool(acc.bits[0]));
                }
                Ok(SV::Int(acc, t.base().clone()))
            }
            "LIMIT" => {
                let t = t_same.clone();
                if int_sort(&t).is_none() || t.is_real() || n < 3 {
                    return Ok(SV::Opaque(t));
                }
                let (_, signed) = int_sort(&t).unwrap_or((64, true));
                let mn = self.word_of(arg(0)?, &t, span)?;
                let x = self.word_of(arg(1)?, &t, span)?;
                let mx = self.word_of(arg(2)?, &t, span)?;
                let below = self.ops().lt(&x, &mn, signed);
                let v = self.ops().ite(below, &mn, &x);
                let above = self.ops().lt(&mx, &v, signed);
                let v = self.ops().ite(above, &mx, &v);
                Ok(SV::Int(v, t.base().clone()))
            }
            "SHL" | "SHR" | "ROL" | "ROR" => {
                let a = arg(0)?;
                let k = arg(1)?;
                let t = rt.clone().unwrap_or_else(|| a.ty());
                let Some((bits, _)) = int_sort(&t) else { return Ok(SV::Opaque(t)) };
                let w = self.word_of(a, &t, span)?;
                let kw = match k {
                    SV::Untyped(c) => Word::constant(c, 32),
                    other => {
                        let kt = other.ty();
                        self.word_of(other, &kt, span)?
                    }
                };
                let out = match kw.as_const(true) {
                    Some(c) => {
                        let c = c.clamp(0, 1 << 20) as usize;
                        match name {
                            "SHL" => self.ops().shl(&w, c),
                            "SHR" => self.ops().shr(&w, c),
                            "ROL" => self.ops().rotate(&w, c, true),
                            _ => self.ops().rotate(&w, c, false),
                        }
                    }
                    None if name == "SHL" || name == "SHR" => {
                        let neg = *kw.bits.last().unwrap_or(&Lit::FALSE);
                        let amount = self.ops().ite(neg, &Word::constant(0, kw.width()), &kw);
                        self.ops().shift(&w, &amount, name == "SHL")
                    }
                    None => return Ok(self.free_value(&t, "rotation by a variable amount")),
                };
                let _ = bits;
                if t.is_bool() {
                    return Ok(SV::Bool(out.bits[0]));
                }
                Ok(SV::Int(out, t.base().clone()))
            }
            "TRUNC" => {
                let t = rt.clone().unwrap_or(Type::DInt);
                Ok(self.free_value(&t, "TRUNC of a REAL"))
            }
            _ => {
                if let Some((from, to)) = conversion_types(name) {
                    let a = arg(0)?;
                    let from = from.unwrap_or_else(|| a.ty());
                    let to = rt.clone().filter(|_| name.starts_with("TO_")).unwrap_or(to);
                    return self.convert(a, &from, &to, span);
                }
                let t = rt.clone().unwrap_or_else(|| match &sf.ret {
                    sfc_st::stdlib::ReturnType::Fixed(t) => t.clone(),
                    sfc_st::stdlib::ReturnType::FromContext(_, d) => d.clone(),
                    sfc_st::stdlib::ReturnType::Same => t_same.clone(),
                });
                if int_sort(&t).is_some() {
                    self.note(format!("standard function `{name}` is not modelled; its results are free"));
                }
                Ok(self.free_value(&t, name))
            }
        }
    }

    /// An explicit conversion `<from>_TO_<to>` (integers, BOOL, TIME in milliseconds).
    fn convert(&mut self, v: SV, from: &Type, to: &Type, span: Span) -> R<SV> {
        let (Some((_, fs)), Some((tw, _))) = (int_sort(from), int_sort(to)) else {
            return Ok(self.free_value(to, "a conversion involving REAL or STRING"));
        };
        if from.is_date() || to.is_date() {
            return Ok(self.free_value(to, "a DATE conversion"));
        }
        let a = match v {
            SV::Untyped(c) => Word::constant(c, 64),
            other => {
                let w = self.word_of(other, from, span)?;
                w.resize(64, fs)
            }
        };
        if to.is_bool() {
            let z = self.ops().is_zero(&a);
            return Ok(SV::Bool(z.not()));
        }
        let w = match (from.is_duration(), to.is_duration()) {
            (true, false) => {
                // µs → ms, truncating toward zero.
                let k = Word::constant(1000, 64);
                self.ops().sdivrem(&a, &k).0
            }
            (false, true) => {
                let k = Word::constant(1000, 64);
                self.ops().mul(&a, &k)
            }
            _ => a,
        };
        Ok(SV::Int(w.resize(tw, true), to.base().clone()))
    }
}

/// `INT_TO_DINT` → (Some(INT), DINT); `TO_DINT` → (None, DINT).
fn conversion_types(name: &str) -> Option<(Option<Type>, Type)> {
    if let Some(rest) = name.strip_prefix("TO_") {
        return Some((None, Type::elementary(rest)?));
    }
    let (a, b) = name.split_once("_TO_")?;
    let from = Type::elementary(a)?;
    let to = Type::elementary(b)?;
    Some((Some(from), to))
}
