//! Type checking of Structured Text expressions and statements, transition conditions, action
//! associations and initial values.
//!
//! Every check returns a [`Type`]; after reporting a problem it returns [`Type::Error`], which
//! every later check accepts silently, so one mistake gives one diagnostic.

use crate::scope::{Scope, Sym};
use crate::suggest::closest;
use crate::types::{Generic, Type};
use crate::value::{const_eval, Value};
use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{
    ActionAssociation, ActionBody, BinaryOp, CaseLabel, Condition, DirectAddress, Expr, ExprKind, Ident, Initializer,
    Literal, LiteralKind, Stmt, StmtKind, UnaryOp, VarKind,
};
use std::collections::HashMap;

/// Nesting deeper than this is refused: the parser caps expressions at 256 levels but not
/// postfix chains (`a.b.c…`, `a[1][1]…`), and this keeps the checker within a 2 MiB stack.
const MAX_DEPTH: u32 = 300;

/// A numeric constant written without a type (`5`, `-1.5`, `2 * 3`): IEC's ANY_INT/ANY_REAL
/// literal, which takes its type from the context.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Untyped {
    /// An integer constant; `None` when its value overflowed or divided by zero.
    Int(Option<i128>),
    Real(Option<f64>),
}

/// How an untyped constant fits a type.
pub(crate) enum Fit {
    Fits,
    /// The value does not fit; the message says why.
    OutOfRange(String),
    /// The type cannot hold a constant of this kind at all.
    WrongKind,
}

/// One operand of an operator or of a generic function, checked or still untyped.
pub(crate) struct Operand<'x> {
    pub(crate) expr: &'x Expr,
    /// `None` for an untyped constant.
    pub(crate) ty: Option<Type>,
    pub(crate) untyped: Option<Untyped>,
}

/// Checks the code of one POU against its [`Scope`], collecting diagnostics.
pub struct Checker<'s, 'e> {
    pub(crate) scope: &'s mut Scope<'e>,
    diags: Vec<Diagnostic>,
    element: Option<String>,
    pub(crate) in_guard: bool,
    loop_depth: u32,
    depth: u32,
    too_deep: bool,
    /// The type of every checked expression, by span, for the simulator and the analyzer;
    /// filled only after [`Checker::keep_types`] (plain checking does not pay for it).
    types: HashMap<Span, Type>,
    keep_types: bool,
    /// The code is CODESYS's (its POU is marked `{attribute 'sfc.dialect' := 'codesys'}`):
    /// CODESYS's typing rules apply where they are wider than IEC 61131-3's (`NOT` of an
    /// integer is its bitwise complement; an integer argument of another integer type is
    /// converted implicitly).
    pub(crate) codesys: bool,
    /// The POU is an S7-GRAPH block's (`{attribute 'sfc.dialect' := 'graph'}`): its steps have
    /// `U` (the time without disturbance) besides `X` and `T`.
    pub(crate) graph: bool,
    /// The POU is a Studio 5000 SFC routine's (`{attribute 'sfc.dialect' := 'logix'}`): its
    /// steps have Logix's `Count` (DINT, how many times the step became active) and its scan
    /// bits `FS`, `SA`, `LS`, and `TMax` (DINT ms, its longest activation).
    pub(crate) logix: bool,
}

impl<'s, 'e> Checker<'s, 'e> {
    /// Applies CODESYS's typing rules (see [`Checker::codesys`]'s field).
    pub fn set_codesys(&mut self, on: bool) {
        self.codesys = on;
    }

    /// Gives steps S7-GRAPH's `U` (see [`Checker::graph`]'s field).
    pub fn set_graph(&mut self, on: bool) {
        self.graph = on;
    }

    /// Gives steps Logix's `Count` (see [`Checker::logix`]'s field).
    pub fn set_logix(&mut self, on: bool) {
        self.logix = on;
    }

    /// A checker for code in `scope`.
    pub fn new(scope: &'s mut Scope<'e>) -> Self {
        let diags = std::mem::take(&mut scope.pending);
        Checker {
            scope,
            diags,
            element: None,
            in_guard: false,
            loop_depth: 0,
            depth: 0,
            too_deep: false,
            types: HashMap::new(),
            keep_types: false,
            codesys: false,
            graph: false,
            logix: false,
        }
    }

    /// Records the type of every expression checked from now on (see [`Checker::expr_type`]).
    pub fn keep_types(&mut self) {
        self.keep_types = true;
    }

    /// The chart element (step, transition, action) that following diagnostics concern.
    pub fn set_element(&mut self, element: Option<String>) {
        self.element = element;
    }

    /// The scope, with the usage recorded so far.
    pub fn scope(&self) -> &Scope<'e> {
        self.scope
    }

    /// The diagnostics reported so far.
    pub fn diagnostics(&self) -> &[Diagnostic] {
        &self.diags
    }

    /// The type the checker gave the expression with this span (every checked ST expression
    /// and IL operand; an untyped constant expression such as `2 * 3` is recorded as a whole,
    /// with the type the context gave it). Integer arithmetic wraps in these types.
    pub fn expr_type(&self, span: Span) -> Option<&Type> {
        self.types.get(&span)
    }

    /// Takes the table of expression types (see [`Checker::expr_type`]).
    pub fn take_expr_types(&mut self) -> HashMap<Span, Type> {
        std::mem::take(&mut self.types)
    }

    pub(crate) fn record(&mut self, span: Span, ty: &Type) {
        if !self.keep_types {
            return;
        }
        self.types.insert(span, ty.clone());
    }

    pub(crate) fn diagnostics_mut(&mut self) -> &mut Vec<Diagnostic> {
        &mut self.diags
    }

    /// Ends checking and hands over the diagnostics.
    pub fn finish(self) -> Vec<Diagnostic> {
        self.diags
    }

    pub(crate) fn report(&mut self, mut d: Diagnostic) {
        if d.element.is_none() {
            d.element = self.element.clone();
        }
        self.diags.push(d);
    }

    pub(crate) fn error(&mut self, code: &'static str, span: Span, message: impl Into<String>) {
        self.report(Diagnostic::new(code, span, message));
    }

    // -----------------------------------------------------------------------------------------
    // Entry points for chart code

    /// Checks a transition condition: a BOOL expression (SFC0303) without side effects
    /// (SFC0305). Returns its type.
    pub fn check_guard(&mut self, expr: &Expr) -> Type {
        let was = std::mem::replace(&mut self.in_guard, true);
        let ty = self.check_expr(expr, Some(&Type::Bool));
        self.in_guard = was;
        if !ty.is_bool() && !ty.is_error() {
            let what = self.phrase(expr, &ty);
            self.error("SFC0303", expr.span, format!("transition condition is {what}, expected `BOOL`"));
        }
        ty
    }

    /// Checks a condition attached to a step (S7-GRAPH's interlock or supervision): a BOOL
    /// expression (SFC0303) without side effects (SFC0305).
    pub fn check_step_condition(&mut self, c: &sfc_syntax::ast::StepCondition) -> Type {
        let was = std::mem::replace(&mut self.in_guard, true);
        let ty = self.check_expr(&c.expr, Some(&Type::Bool));
        self.in_guard = was;
        if !ty.is_bool() && !ty.is_error() {
            let what = self.phrase(&c.expr, &ty);
            self.error("SFC0303", c.expr.span, format!("the step condition `{}` is {what}, expected `BOOL`", c.attribute));
        }
        ty
    }

    /// Checks a transition condition in either language (nothing to check when missing).
    pub fn check_condition(&mut self, cond: &Condition) -> Type {
        match cond {
            Condition::St(e) => self.check_guard(e),
            Condition::Il(il) => self.check_il_guard(il),
            Condition::Missing => Type::Error,
        }
    }

    /// Checks an action body in either language.
    pub fn check_action_body(&mut self, body: &ActionBody) {
        match body {
            ActionBody::St(stmts) => self.check_stmts(stmts),
            ActionBody::Il(il) => self.check_il(il),
            // Its elements are checked as a chart (`check_unit`).
            ActionBody::Sfc(_) => {}
        }
    }

    /// Checks the duration of a timed action association: a TIME value (SFC0311).
    pub fn check_duration(&mut self, expr: &Expr) -> Type {
        let ty = self.check_expr(expr, Some(&Type::Time));
        if !ty.is_duration() && !ty.is_error() {
            let what = self.phrase(expr, &ty);
            self.error("SFC0311", expr.span, format!("action duration is {what}, expected `TIME`"));
        }
        ty
    }

    /// Checks an indicator variable of an action association: a declared BOOL variable
    /// (SFC0312).
    pub fn check_indicator(&mut self, name: &Ident) {
        match self.scope.resolve(&name.text) {
            Some(sym @ (Sym::Local(_) | Sym::Global(_))) => {
                self.scope.mark(sym, false);
                let ty = self.scope.var_info(sym).map(|v| v.ty.clone()).unwrap_or(Type::Error);
                if !ty.is_bool() && !ty.is_error() {
                    self.error(
                        "SFC0312",
                        name.span,
                        format!("indicator `{}` is `{ty}`, expected a `BOOL` variable", name.text),
                    );
                }
            }
            Some(Sym::Step(_)) => {
                self.error("SFC0312", name.span, format!("indicator `{}` is a step, not a BOOL variable", name.text))
            }
            Some(Sym::Action(_)) => {
                self.error("SFC0312", name.span, format!("indicator `{}` is an action, not a BOOL variable", name.text))
            }
            Some(Sym::Return) => {}
            None => self.undeclared(name),
        }
    }

    /// Checks an action association of a step: records the use of the action (or of the BOOL
    /// variable used as an action, which the chart writes), checks its duration and
    /// indicators. Whether the action exists is the chart model's check (SFC0207).
    pub fn check_association(&mut self, assoc: &ActionAssociation) {
        if let Some(call) = assoc.instance_call() {
            // `Motor.Stop(S)`: the action of an instance, called while the association is active.
            self.call_stmt(&call);
        }
        match self.scope.resolve(&assoc.action.text) {
            Some(sym @ Sym::Action(_)) => self.scope.mark(sym, false),
            Some(sym @ (Sym::Local(_) | Sym::Global(_))) => self.scope.mark(sym, true),
            _ => {}
        }
        if let Some(d) = &assoc.duration {
            self.check_duration(d);
        }
        for ind in &assoc.indicators {
            self.check_indicator(ind);
        }
    }

    /// Checks the initial values of the scope's own variables (and, for a globals-only
    /// scope, of the globals).
    pub fn check_declarations(&mut self) {
        let vars: Vec<(String, Type, Initializer)> = if self.scope.pou_name().is_some() {
            self.scope.vars().iter().filter_map(|v| v.init.clone().map(|i| (v.name.clone(), v.ty.clone(), i))).collect()
        } else {
            let env = self.scope.env();
            env.globals().iter().filter_map(|v| v.init.clone().map(|i| (v.name.clone(), v.ty.clone(), i))).collect()
        };
        for (name, ty, init) in &vars {
            self.check_initializer(init, ty, name);
        }
    }

    /// Checks the PRIORITY of a transition: a constant integer ≥ 0.
    pub fn check_priority(&mut self, expr: &Expr) {
        let t = self.check_expr(expr, Some(&Type::DInt));
        if t.is_error() {
            return;
        }
        if !t.is_integer() {
            let p = self.phrase(expr, &t);
            self.error("SFC0302", expr.span, format!("type mismatch: the priority is {p}, expected an integer"));
            return;
        }
        match const_eval(expr, &*self.scope).and_then(Value::as_int) {
            Some(v) if v < 0 => self.error("SFC0315", expr.span, format!("the priority {v} is negative")),
            Some(_) => {}
            None => self.error("SFC0302", expr.span, "the priority must be a constant"),
        }
    }

    /// Checks an initial value against the declared type of `name`.
    pub fn check_initializer(&mut self, init: &Initializer, ty: &Type, name: &str) {
        if ty.is_error() || !self.enter(init.span()) {
            return;
        }
        self.initializer_inner(init, ty, name);
        self.leave();
    }

    fn initializer_inner(&mut self, init: &Initializer, ty: &Type, name: &str) {
        match init {
            Initializer::Expr(e) => {
                let t = self.check_expr(e, Some(ty));
                if !t.assignable_to(ty) {
                    let what = self.phrase(e, &t);
                    self.error(
                        "SFC0302",
                        e.span,
                        format!("type mismatch: the initial value of `{name}` is {what}, expected `{ty}`"),
                    );
                }
            }
            Initializer::Array { elements, span } => {
                let Type::Array { dims, elem } = ty else {
                    self.error(
                        "SFC0302",
                        *span,
                        format!("type mismatch: an array initial value for `{name}` of type `{ty}`"),
                    );
                    return;
                };
                let capacity = dims
                    .iter()
                    .map(|(lo, hi)| i128::from(*hi) - i128::from(*lo) + 1)
                    .fold(1i128, |acc, n| acc.saturating_mul(n));
                let mut count: i128 = 0;
                for el in elements {
                    let times = match &el.repeat {
                        None => 1,
                        Some(r) => match const_eval(r, &*self.scope) {
                            Some(Value::Int(n)) if n >= 0 => n,
                            _ => {
                                self.error("SFC0315", r.span, "a repetition count must be a constant integer ≥ 0");
                                continue;
                            }
                        },
                    };
                    count = count.saturating_add(times);
                    if let Some(v) = &el.value {
                        self.check_initializer(v, elem, name);
                    }
                }
                if count > capacity {
                    self.error(
                        "SFC0315",
                        *span,
                        format!("`{name}` has {capacity} elements, but {count} initial values are given"),
                    );
                }
            }
            Initializer::Struct { fields, span } => {
                let env = self.scope.env();
                for (field, value) in fields {
                    let fty = match ty {
                        Type::Struct { .. } => ty.field(&field.text).cloned(),
                        Type::FunctionBlock(_) => env
                            .fb_of(ty)
                            .and_then(|fb| fb.var(&field.text))
                            .filter(|v| matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::Var))
                            .map(|v| v.ty.clone()),
                        _ => {
                            self.error(
                                "SFC0302",
                                *span,
                                format!("type mismatch: a structure initial value for `{name}` of type `{ty}`"),
                            );
                            return;
                        }
                    };
                    match fty {
                        Some(fty) => self.check_initializer(value, &fty, &format!("{name}.{}", field.text)),
                        None => self.error("SFC0309", field.span, format!("`{ty}` has no member `{}`", field.text)),
                    }
                }
            }
        }
    }

    // -----------------------------------------------------------------------------------------
    // Statements

    /// Checks a statement list (an action body or a POU body).
    pub fn check_stmts(&mut self, stmts: &[Stmt]) {
        for s in stmts {
            self.check_stmt(s);
        }
    }

    fn check_stmt(&mut self, stmt: &Stmt) {
        if !self.enter(stmt.span) {
            return;
        }
        self.stmt_inner(stmt);
        self.leave();
    }

    fn stmt_inner(&mut self, stmt: &Stmt) {
        match &stmt.kind {
            StmtKind::RefAssign { target, value } => self.ref_assign(target, value),
            StmtKind::Assign { target, value } => {
                let tt = self.target(target);
                let vt = self.check_expr(value, Some(&tt));
                if !self.assignable(&vt, &tt) {
                    let what = self.phrase(value, &vt);
                    let msg = match &target.kind {
                        ExprKind::Name(id) => {
                            format!("type mismatch: cannot assign {what} to `{tt}` variable `{}`", id.text)
                        }
                        _ => format!("type mismatch: cannot assign {what} to `{}` (`{tt}`)", expr_text(target)),
                    };
                    self.error("SFC0302", value.span, msg);
                }
            }
            StmtKind::Call(e) => self.call_stmt(e),
            StmtKind::If { branches, else_body } => {
                for (i, (cond, body)) in branches.iter().enumerate() {
                    self.condition(cond, if i == 0 { "IF" } else { "ELSIF" });
                    self.check_stmts(body);
                }
                if let Some(body) = else_body {
                    self.check_stmts(body);
                }
            }
            StmtKind::Case { selector, arms, else_body } => {
                self.case(selector, arms);
                if let Some(body) = else_body {
                    self.check_stmts(body);
                }
            }
            StmtKind::For { var, from, to, by, body } => {
                self.for_loop(var, from, to, by.as_deref());
                self.loop_depth += 1;
                self.check_stmts(body);
                self.loop_depth -= 1;
            }
            StmtKind::While { cond, body } => {
                self.condition(cond, "WHILE");
                self.loop_depth += 1;
                self.check_stmts(body);
                self.loop_depth -= 1;
            }
            StmtKind::Repeat { body, until } => {
                self.loop_depth += 1;
                self.check_stmts(body);
                self.loop_depth -= 1;
                self.condition(until, "UNTIL");
            }
            StmtKind::Exit => {
                if self.loop_depth == 0 {
                    self.error("SFC0314", stmt.span, "`EXIT` outside a loop: it only leaves FOR, WHILE or REPEAT");
                }
            }
            StmtKind::Return | StmtKind::Empty => {}
        }
    }

    fn condition(&mut self, cond: &Expr, what: &str) {
        let t = self.check_expr(cond, Some(&Type::Bool));
        if !t.is_bool() && !t.is_error() {
            let p = self.phrase(cond, &t);
            self.error("SFC0302", cond.span, format!("type mismatch: the {what} condition is {p}, expected `BOOL`"));
        }
    }

    fn case(&mut self, selector: &Expr, arms: &[sfc_syntax::ast::CaseArm]) {
        let st = self.check_expr(selector, None);
        let sel_ok = st.is_error() || st.is_integer() || st.is_enum();
        if !sel_ok {
            let p = self.phrase(selector, &st);
            self.error(
                "SFC0302",
                selector.span,
                format!("type mismatch: the CASE selector is {p}, expected an integer or an enumeration"),
            );
        }
        let label_ty = if sel_ok { st } else { Type::Error };
        let mut seen: Vec<(i128, i128, Span)> = Vec::new();
        for arm in arms {
            for label in &arm.labels {
                let (range, span) = match label {
                    CaseLabel::Value(e) => (self.case_label(e, &label_ty).map(|v| (v, v)), e.span),
                    CaseLabel::Range(a, b) => {
                        let lo = self.case_label(a, &label_ty);
                        let hi = self.case_label(b, &label_ty);
                        let span = a.span.to(b.span);
                        match (lo, hi) {
                            (Some(lo), Some(hi)) if lo > hi => {
                                self.error("SFC0315", span, format!("the CASE range {lo}..{hi} is empty"));
                                (None, span)
                            }
                            (Some(lo), Some(hi)) => (Some((lo, hi)), span),
                            _ => (None, span),
                        }
                    }
                };
                if let Some((lo, hi)) = range {
                    if let Some((_, _, prev)) = seen.iter().find(|(a, b, _)| lo <= *b && *a <= hi) {
                        let d = Diagnostic::new("SFC0319", span, "this CASE label repeats a value of an earlier one")
                            .with_label(*prev, "earlier label");
                        self.report(d);
                    } else {
                        seen.push((lo, hi, span));
                    }
                }
            }
            self.check_stmts(&arm.body);
        }
    }

    /// Checks one CASE label; its integer value (or enum ordinal) for overlap detection.
    fn case_label(&mut self, e: &Expr, sel: &Type) -> Option<i128> {
        let t = self.check_expr(e, Some(sel));
        if sel.is_error() || t.is_error() {
            return None;
        }
        if sel.is_enum() {
            if &t != sel {
                let p = self.phrase(e, &t);
                self.error(
                    "SFC0302",
                    e.span,
                    format!("type mismatch: the CASE label is {p}, but the selector is `{sel}`"),
                );
                return None;
            }
            let name = match &e.kind {
                ExprKind::Name(id) => Some(id.text.as_str()),
                ExprKind::Literal(Literal { kind: LiteralKind::Enum(id), .. }) => Some(id.text.as_str()),
                _ => None,
            };
            return name.and_then(|n| sel.enum_value(n)).map(i128::from);
        }
        if !t.assignable_to(sel) {
            let p = self.phrase(e, &t);
            self.error("SFC0302", e.span, format!("type mismatch: the CASE label is {p}, but the selector is `{sel}`"));
            return None;
        }
        match const_eval(e, &*self.scope).and_then(Value::as_int) {
            Some(v) => Some(v),
            None => {
                self.error("SFC0302", e.span, "a CASE label must be a constant");
                None
            }
        }
    }

    fn for_loop(&mut self, var: &Ident, from: &Expr, to: &Expr, by: Option<&Expr>) {
        let vt = match self.scope.resolve(&var.text) {
            Some(sym @ (Sym::Local(_) | Sym::Global(_))) => {
                self.scope.mark(sym, false);
                self.scope.mark(sym, true);
                let info = self.scope.var_info(sym);
                let constant = info.is_some_and(|v| v.constant);
                let ty = info.map(|v| v.ty.clone()).unwrap_or(Type::Error);
                if constant {
                    self.error("SFC0308", var.span, format!("the FOR variable `{}` is a constant", var.text));
                    Type::Error
                } else if !ty.is_integer() && !ty.is_error() {
                    self.error(
                        "SFC0302",
                        var.span,
                        format!("type mismatch: the FOR variable `{}` is `{ty}`, expected an integer type", var.text),
                    );
                    Type::Error
                } else {
                    ty
                }
            }
            Some(_) => {
                self.error("SFC0302", var.span, format!("the FOR variable `{}` must be an integer variable", var.text));
                Type::Error
            }
            None => {
                self.undeclared(var);
                Type::Error
            }
        };
        for (e, what) in [(Some(from), "start"), (Some(to), "end"), (by, "step")] {
            let Some(e) = e else { continue };
            let t = self.check_expr(e, Some(&vt));
            if vt.is_error() || t.is_error() {
                continue;
            }
            if !t.assignable_to(&vt) {
                let p = self.phrase(e, &t);
                self.error("SFC0302", e.span, format!("type mismatch: the FOR {what} is {p}, expected `{vt}`"));
            } else if what == "step" && const_eval(e, &*self.scope).and_then(Value::as_int) == Some(0) {
                self.error("SFC0315", e.span, "the FOR step is 0, so the loop never ends");
            }
        }
    }

    // -----------------------------------------------------------------------------------------
    // Assignment targets

    /// Checks an expression that is written to; returns its type.
    pub(crate) fn target(&mut self, e: &Expr) -> Type {
        if !self.enter(e.span) {
            return Type::Error;
        }
        let t = self.target_inner(e);
        self.record(e.span, &t);
        self.leave();
        t
    }

    fn target_inner(&mut self, e: &Expr) -> Type {
        match &e.kind {
            ExprKind::Name(id) => match self.scope.resolve(&id.text) {
                Some(sym @ (Sym::Local(_) | Sym::Global(_))) => {
                    self.scope.mark(sym, true);
                    let Some(info) = self.scope.var_info(sym) else { return Type::Error };
                    if info.constant {
                        let d =
                            Diagnostic::new("SFC0308", e.span, format!("cannot assign to the constant `{}`", id.text))
                                .with_label(info.span, "declared CONSTANT here");
                        self.report(d);
                        return Type::Error;
                    }
                    match &info.ty {
                        Type::Reference(t) => t.as_ref().clone(),
                        t => t.clone(),
                    }
                }
                Some(Sym::Return) => {
                    self.scope.mark(Sym::Return, true);
                    self.scope.return_type().cloned().unwrap_or(Type::Error)
                }
                Some(Sym::Step(_)) => {
                    self.error(
                        "SFC0304",
                        e.span,
                        format!("step `{}` cannot be assigned: the chart maintains `{0}.X` and `{0}.T`", id.text),
                    );
                    Type::Error
                }
                Some(Sym::Action(_)) => {
                    self.error("SFC0308", e.span, format!("`{}` is an action, not a variable", id.text));
                    Type::Error
                }
                None => {
                    if let Some(p) = self.own_property(&id.text) {
                        return self.property_access(&p, id, true);
                    }
                    if !self.scope.enum_types_with_value(&id.text).is_empty() {
                        self.error("SFC0308", e.span, format!("cannot assign to the enumerated value `{}`", id.text));
                    } else {
                        self.undeclared(id);
                    }
                    Type::Error
                }
            },
            ExprKind::Member { base, member } => self.member(base, member, true),
            ExprKind::Index { base, indices } => self.index(base, indices, true),
            ExprKind::Deref(inner) if self.this_type(inner).is_none() => self.deref(inner),
            ExprKind::Address(a) => address_type(a),
            ExprKind::Error => Type::Error,
            ExprKind::Literal(_) => {
                self.error("SFC0308", e.span, "cannot assign to a literal");
                Type::Error
            }
            _ => {
                self.check_expr(e, None);
                self.error("SFC0308", e.span, "cannot assign to an expression; the target must be a variable");
                Type::Error
            }
        }
    }

    // -----------------------------------------------------------------------------------------
    // Expressions

    /// Enters one nesting level; false (after one SFC0103) when the AST is too deep.
    pub(crate) fn enter(&mut self, span: Span) -> bool {
        if self.depth >= MAX_DEPTH {
            if !self.too_deep {
                self.too_deep = true;
                self.error("SFC0103", span, "code nested too deeply to check");
            }
            return false;
        }
        self.depth += 1;
        true
    }

    pub(crate) fn leave(&mut self) {
        self.depth = self.depth.saturating_sub(1);
    }

    /// Checks an expression and returns its type. `expected` is the type the context wants
    /// (the assignment target, the other operand): untyped constants and enumerated values
    /// take it; the caller still compares the result with what it needs.
    pub fn check_expr(&mut self, expr: &Expr, expected: Option<&Type>) -> Type {
        if !self.enter(expr.span) {
            return Type::Error;
        }
        let t = self.expr_inner(expr, expected);
        self.record(expr.span, &t);
        self.leave();
        t
    }

    fn expr_inner(&mut self, e: &Expr, expected: Option<&Type>) -> Type {
        if let Some(u) = untyped(e) {
            return self.untyped_type(u, e, expected);
        }
        match &e.kind {
            ExprKind::Literal(lit) => self.literal(lit, e.span, None),
            ExprKind::Name(id) => self.name_value(id, expected),
            ExprKind::Address(a) => address_type(a),
            ExprKind::Member { base, member } => self.member(base, member, false),
            ExprKind::Index { base, indices } => self.index(base, indices, false),
            ExprKind::Call { callee, args } => self.call_value(callee, args, e.span, expected),
            ExprKind::MemberCall { base, member, args } => {
                // A method of a block kept as written: accepted, not typed.
                let bt = self.check_expr(base, None);
                if bt.is_error() {
                    self.check_args_loosely(args);
                    return Type::Error;
                }
                if let Some(m) = self.scope.env().method_of(&bt, &member.text).cloned() {
                    return self.method_call(&m, args, e.span, true);
                }
                self.member_call_stmt(base, member, args, e.span);
                if matches!(bt, Type::Interface(_)) {
                    return Type::Error; // no such method: reported
                }
                self.error(
                    "SFC0302",
                    e.span,
                    format!("an action call has no value; call `{}` as a statement", member.text),
                );
                Type::Error
            }
            ExprKind::Unary { op, operand } => self.unary(*op, operand, e, expected),
            ExprKind::Binary { op, lhs, rhs } => self.binary(*op, lhs, rhs, e.span, expected),
            ExprKind::Paren(inner) => self.check_expr(inner, expected),
            // `THIS^` and `SUPER^`; other dereferences are not typed (sfc-model keeps a POU
            // dereferencing a pointer as written before it is checked).
            ExprKind::Deref(inner) => self.deref(inner),
            ExprKind::Error => Type::Error,
        }
    }

    /// The type an untyped constant takes in a context.
    fn untyped_type(&mut self, u: Untyped, e: &Expr, expected: Option<&Type>) -> Type {
        if let Some(t) = expected.filter(|t| !t.is_error()) {
            match fit(u, t) {
                Fit::Fits => return t.clone(),
                Fit::OutOfRange(msg) => {
                    self.error("SFC0315", e.span, msg);
                    return Type::Error;
                }
                Fit::WrongKind => {}
            }
        }
        self.natural_type(u, e.span)
    }

    /// The type of an untyped constant without context: DINT, LINT or ULINT by size, LREAL.
    pub(crate) fn natural_type(&mut self, u: Untyped, span: Span) -> Type {
        match u {
            Untyped::Real(_) => Type::LReal,
            Untyped::Int(Some(v)) => {
                for t in [Type::DInt, Type::LInt, Type::ULInt] {
                    if t.int_range().is_some_and(|(lo, hi)| lo <= v && v <= hi) {
                        return t;
                    }
                }
                self.error("SFC0315", span, format!("the constant {v} does not fit any integer type"));
                Type::Error
            }
            Untyped::Int(None) => {
                self.error("SFC0315", span, "the constant expression overflows or divides by zero");
                Type::Error
            }
        }
    }

    /// A literal, typed by its prefix or its kind; `negate` for a typed literal under unary
    /// minus (so `-SINT#128` is in range).
    fn literal(&mut self, lit: &Literal, span: Span, negate: Option<bool>) -> Type {
        let prefix = lit.type_prefix.as_deref();
        match &lit.kind {
            LiteralKind::Int(v) => {
                let Some(prefix) = prefix else { return Type::DInt };
                let Some(ty) = self.prefix_type(prefix, span) else { return Type::Error };
                let value = if negate == Some(true) { v.checked_neg() } else { Some(*v) };
                match fit(Untyped::Int(value), &ty) {
                    Fit::Fits => ty,
                    Fit::OutOfRange(msg) => {
                        self.error("SFC0315", span, msg);
                        Type::Error
                    }
                    Fit::WrongKind => {
                        self.error(
                            "SFC0302",
                            span,
                            format!("type mismatch: `{}` is not a valid `{ty}` literal", lit.text),
                        );
                        Type::Error
                    }
                }
            }
            LiteralKind::Real(r) => {
                let Some(prefix) = prefix else { return Type::LReal };
                let Some(ty) = self.prefix_type(prefix, span) else { return Type::Error };
                match fit(Untyped::Real(Some(*r)), &ty) {
                    Fit::Fits => ty,
                    Fit::OutOfRange(msg) => {
                        self.error("SFC0315", span, msg);
                        Type::Error
                    }
                    Fit::WrongKind => {
                        self.error(
                            "SFC0302",
                            span,
                            format!("type mismatch: `{}` is not a valid `{ty}` literal", lit.text),
                        );
                        Type::Error
                    }
                }
            }
            LiteralKind::Bool(_) => Type::Bool,
            LiteralKind::String { wide, .. } => {
                if *wide {
                    Type::WString { len: None }
                } else {
                    Type::String { len: None }
                }
            }
            LiteralKind::Duration(_) => {
                if prefix.is_some_and(|p| p.starts_with('L')) {
                    Type::LTime
                } else {
                    Type::Time
                }
            }
            LiteralKind::Date(_) => Type::Date,
            LiteralKind::TimeOfDay(_) => Type::TimeOfDay,
            LiteralKind::DateAndTime(_) => Type::DateAndTime,
            LiteralKind::Enum(value) => {
                let Some(prefix) = prefix else { return self.name_value(value, None) };
                let Some(ty) = self.prefix_type(prefix, span) else { return Type::Error };
                if !ty.is_enum() {
                    self.error("SFC0302", span, format!("type mismatch: `{prefix}` is not an enumerated type"));
                    return Type::Error;
                }
                if ty.enum_value(&value.text).is_none() {
                    let names = enum_names(&ty);
                    let mut d = Diagnostic::new(
                        "SFC0309",
                        value.span,
                        format!("the enumeration `{ty}` has no value `{}`", value.text),
                    );
                    if let Some(s) = closest(&value.text, names.iter().map(String::as_str)) {
                        d = d.with_note(format!("did you mean `{s}`?"));
                    }
                    self.report(d);
                    return Type::Error;
                }
                ty
            }
        }
    }

    /// The type named by a literal prefix (`INT#`, `Colour#`).
    fn prefix_type(&mut self, prefix: &str, span: Span) -> Option<Type> {
        if let Some(t) = Type::elementary(prefix) {
            return Some(t);
        }
        if let Some(def) = self.scope.env().type_def(prefix) {
            return Some(def.ty.clone());
        }
        self.error("SFC0313", span, format!("unknown type `{prefix}`"));
        None
    }

    /// A name read as a value.
    fn name_value(&mut self, id: &Ident, expected: Option<&Type>) -> Type {
        match self.scope.resolve(&id.text) {
            Some(sym @ (Sym::Local(_) | Sym::Global(_))) => {
                self.scope.mark(sym, false);
                // A reference is read as what it designates.
                match self.scope.var_info(sym).map(|v| v.ty.clone()).unwrap_or(Type::Error) {
                    Type::Reference(t) => *t,
                    t => t,
                }
            }
            Some(Sym::Return) => {
                self.scope.mark(Sym::Return, false);
                self.scope.return_type().cloned().unwrap_or(Type::Error)
            }
            Some(Sym::Step(_)) => {
                self.error(
                    "SFC0301",
                    id.span,
                    format!("`{0}` is a step, not a variable; its activity flag is `{0}.X`", id.text),
                );
                Type::Error
            }
            Some(Sym::Action(_)) => {
                self.error(
                    "SFC0301",
                    id.span,
                    format!("`{0}` is an action, not a variable; its state is `{0}.Q`", id.text),
                );
                Type::Error
            }
            None => {
                if let Some(p) = self.own_property(&id.text) {
                    return self.property_access(&p, id, false);
                }
                if let Some(t) = expected.filter(|t| t.enum_value(&id.text).is_some()) {
                    return t.clone();
                }
                if let Some(t) = self.scope.enum_types_with_value(&id.text).into_iter().next() {
                    return t;
                }
                // `THIS` (CODESYS): a pointer to the block's own instance.
                if id.is("THIS") {
                    let this = Expr { kind: ExprKind::Name(id.clone()), span: id.span };
                    if let Some(t) = self.this_type(&this) {
                        return Type::Pointer(Box::new(t));
                    }
                }
                self.undeclared(id);
                Type::Error
            }
        }
    }

    /// The block `THIS^` (the POU whose code this is) or `SUPER^` (its base) stands for.
    pub(crate) fn this_type(&self, inner: &Expr) -> Option<Type> {
        let ExprKind::Name(id) = &inner.kind else { return None };
        let pou = self.scope.pou_name()?;
        let env = self.scope.env();
        let fb = env.function_block(pou)?;
        if id.is("THIS") {
            return Some(Type::FunctionBlock(fb.name.to_ascii_uppercase()));
        }
        if id.is("SUPER") {
            let base = env.function_block(fb.base.as_deref()?)?;
            return Some(Type::FunctionBlock(base.name.to_ascii_uppercase()));
        }
        None
    }

    /// `p^`: what the pointer `p` points to (`THIS^`, `SUPER^`: the block itself).
    fn deref(&mut self, inner: &Expr) -> Type {
        if let Some(t) = self.this_type(inner) {
            return t;
        }
        match self.check_expr(inner, None) {
            Type::Pointer(t) => *t,
            Type::Error => Type::Error,
            t => {
                let what = self.phrase(inner, &t);
                self.error("SFC0302", inner.span, format!("`^` dereferences a pointer, but this is {what}"));
                Type::Error
            }
        }
    }

    /// `r REF= x`: `r` a `REFERENCE TO T`, `x` a variable of type `T`.
    pub(crate) fn ref_assign(&mut self, target: &Expr, value: &Expr) {
        let ty = match &target.kind {
            ExprKind::Name(id) => match self.scope.resolve(&id.text) {
                Some(sym @ (Sym::Local(_) | Sym::Global(_))) => {
                    self.scope.mark(sym, true);
                    self.scope.var_info(sym).map(|v| v.ty.clone())
                }
                _ => {
                    self.check_expr(target, None);
                    None
                }
            },
            _ => {
                self.check_expr(target, None);
                None
            }
        };
        let vt = self.check_expr(value, None);
        match ty {
            Some(Type::Reference(t)) => {
                let place = matches!(
                    value.kind,
                    ExprKind::Name(_) | ExprKind::Member { .. } | ExprKind::Index { .. } | ExprKind::Deref(_)
                );
                if !place {
                    self.error(
                        "SFC0308",
                        value.span,
                        "`REF=` makes a reference designate a variable; this is no variable",
                    );
                } else if !vt.is_error() && vt != *t {
                    let what = self.phrase(value, &vt);
                    self.error(
                        "SFC0302",
                        value.span,
                        format!("type mismatch: the reference designates a `{t}`, but this is {what}"),
                    );
                }
            }
            Some(Type::Error) | None => {}
            Some(t) => self.error(
                "SFC0302",
                target.span,
                format!("`REF=` sets a REFERENCE TO variable, but `{}` is `{t}`", expr_text(target)),
            ),
        }
    }

    /// `SIZEOF(x)`, `SIZEOF(T)` (CODESYS): the bytes `x` or a `T` takes ([`Type::byte_size`]),
    /// a constant of the smallest unsigned type holding it.
    pub(crate) fn sizeof(&mut self, args: &[sfc_syntax::ast::Arg], span: Span) -> Type {
        let [sfc_syntax::ast::Arg { value: Some(v), name: None, .. }] = args else {
            self.error("SFC0307", span, "`SIZEOF` takes one variable or type");
            self.check_args_loosely(args);
            return Type::Error;
        };
        let t = match &v.kind {
            ExprKind::Name(id) if self.scope.resolve(&id.text).is_none() => match self.scope.env().named_type(&id.text)
            {
                Some(t) => t,
                None => self.check_expr(v, None),
            },
            _ => self.check_expr(v, None),
        };
        if t.is_error() {
            return Type::Error;
        }
        Type::sizeof_type(t.byte_size())
    }

    /// `LOWER_BOUND(a, d)`, `UPPER_BOUND(a, d)` (IEC 61131-3 3rd edition): a bound of dimension
    /// `d` (from 1, a constant) of array `a`, a DINT. Returns the bound when known.
    pub(crate) fn bound(&mut self, name: &Ident, args: &[sfc_syntax::ast::Arg], span: Span) -> Option<i64> {
        let [sfc_syntax::ast::Arg { value: Some(a), name: None, .. }, sfc_syntax::ast::Arg { value: Some(d), name: None, .. }] =
            args
        else {
            self.error("SFC0307", span, format!("`{}` takes an array and a dimension", name.text));
            self.check_args_loosely(args);
            return None;
        };
        let at = self.check_expr(a, None);
        self.check_expr(d, Some(&Type::DInt));
        let dims = match at {
            Type::Array { dims, .. } => dims,
            Type::Error => return None,
            t => {
                let p = self.phrase(a, &t);
                self.error("SFC0310", a.span, format!("`{}` takes an array, but this is {p}", name.text));
                return None;
            }
        };
        let k = match untyped(d) {
            Some(Untyped::Int(Some(k))) if k >= 1 && (k as usize) <= dims.len() => k as usize,
            _ => {
                self.error(
                    "SFC0315",
                    d.span,
                    format!("the dimension is a constant from 1 to {} (the array's dimensions)", dims.len()),
                );
                return None;
            }
        };
        let (lo, hi) = dims[k - 1];
        Some(if name.is("LOWER_BOUND") { lo } else { hi })
    }

    /// `__ISVALIDREF(r)` (CODESYS): whether a `REFERENCE TO` variable (a pointer, an interface)
    /// designates something.
    pub(crate) fn is_valid_ref(&mut self, args: &[sfc_syntax::ast::Arg], span: Span) -> Type {
        let [sfc_syntax::ast::Arg { value: Some(v), name: None, .. }] = args else {
            self.error("SFC0307", span, "`__ISVALIDREF` takes one reference");
            self.check_args_loosely(args);
            return Type::Bool;
        };
        let t = match &v.kind {
            ExprKind::Name(id) => match self.scope.resolve(&id.text) {
                Some(sym @ (Sym::Local(_) | Sym::Global(_))) => {
                    self.scope.mark(sym, false);
                    self.scope.var_info(sym).map(|v| v.ty.clone())
                }
                _ => None,
            },
            _ => None,
        };
        match t {
            Some(Type::Reference(_) | Type::Pointer(_) | Type::Interface(_) | Type::Error) => {}
            _ => {
                self.check_expr(v, None);
                self.error(
                    "SFC0302",
                    v.span,
                    "`__ISVALIDREF` takes a variable declared `REFERENCE TO` (or a pointer or an interface)",
                );
            }
        }
        Type::Bool
    }

    /// `ADR(x)`: the address of a variable, a `POINTER TO` its type; of a string literal (CODESYS
    /// keeps the literal in memory), a `POINTER TO STRING`.
    pub(crate) fn adr(&mut self, args: &[sfc_syntax::ast::Arg], span: Span) -> Type {
        let [arg] = args else {
            self.error("SFC0307", span, "`ADR` takes one variable");
            self.check_args_loosely(args);
            return Type::Error;
        };
        let Some(v) = &arg.value else { return Type::Error };
        if let ExprKind::Literal(sfc_syntax::ast::Literal {
            kind: sfc_syntax::ast::LiteralKind::String { wide, .. },
            ..
        }) = &v.kind
        {
            let t = if *wide { Type::WString { len: None } } else { Type::String { len: None } };
            self.record(v.span, &t);
            return Type::Pointer(Box::new(t));
        }
        let t = self.check_expr(v, None);
        if !matches!(v.kind, ExprKind::Name(_) | ExprKind::Member { .. } | ExprKind::Index { .. } | ExprKind::Deref(_))
        {
            self.error("SFC0308", v.span, "`ADR` takes the address of a variable; this is no variable");
            return Type::Error;
        }
        if t.is_error() {
            return Type::Error;
        }
        Type::Pointer(Box::new(t))
    }

    /// Whether a value of type `from` may be assigned to a variable of type `to`: as
    /// [`Type::assignable_to`], and an instance or interface to an interface it implements.
    pub(crate) fn assignable(&self, from: &Type, to: &Type) -> bool {
        match to {
            Type::Interface(i) if matches!(from, Type::FunctionBlock(_) | Type::Interface(_)) => {
                self.scope.env().converts_to_interface(from, i)
            }
            // CODESYS assigns an address to a pointer of any type (`pByte := ADR(aBuffer)`).
            Type::Pointer(_) if matches!(from, Type::Pointer(_)) => true,
            _ => from.assignable_to(to),
        }
    }

    /// A property of the POU whose code this is, named without `THIS^.`.
    fn own_property(&self, name: &str) -> Option<crate::env::PropSig> {
        let env = self.scope.env();
        env.function_block(self.scope.pou_name()?)?.property(name).cloned()
    }

    /// A property read (its GET) or written (its SET): its type.
    fn property_access(&mut self, p: &crate::env::PropSig, at: &Ident, write: bool) -> Type {
        let (has, what) = if write { (p.set.is_some(), "SET") } else { (p.get.is_some(), "GET") };
        if !has {
            self.error(
                "SFC0308",
                at.span,
                format!("property `{}` has no {what}; it cannot be {}", p.name, if write { "written" } else { "read" }),
            );
            return Type::Error;
        }
        p.ty.clone()
    }

    /// A call of method `m` (`inst.M(…)`, `THIS^.M(…)`, `M(…)` in its block); its value when
    /// `value` (an error for a method without result).
    pub(crate) fn method_call(
        &mut self,
        m: &crate::env::MethodSig,
        args: &[sfc_syntax::ast::Arg],
        span: Span,
        value: bool,
    ) -> Type {
        let f = m.as_function();
        self.bind_method_args(&f, args, span);
        match (&m.return_type, value) {
            (Some(t), _) => t.clone(),
            (None, true) => {
                self.error("SFC0302", span, format!("method `{}` returns no value", m.name));
                Type::Error
            }
            (None, false) => Type::Error,
        }
    }

    /// Reports an undeclared name, suggesting a declared one within edit distance 2.
    pub(crate) fn undeclared(&mut self, id: &Ident) {
        let env = self.scope.env();
        let mut d = if env.function(&id.text).is_some() || crate::stdlib::std_function(&id.text).is_some() {
            Diagnostic::new("SFC0301", id.span, format!("`{0}` is a function; call it as `{0}(…)`", id.text))
        } else {
            Diagnostic::new("SFC0301", id.span, format!("undeclared variable `{}`", id.text))
        };
        // Only a variable stands for a variable: `C0` does not suggest the step `S0`.
        if let Some(s) = closest(&id.text, self.scope.variable_names()) {
            d = d.with_note(format!("did you mean `{s}`?"));
        }
        self.report(d);
    }

    /// `base.member`: step and action flags, structure fields, function block parameters and
    /// bit access (`w.3`).
    fn member(&mut self, base: &Expr, member: &Ident, write: bool) -> Type {
        if let ExprKind::Name(id) = &base.kind {
            match self.scope.resolve(&id.text) {
                Some(sym @ Sym::Step(_)) => {
                    self.scope.mark(sym, false);
                    let step = self.scope.chart_name(sym).to_string();
                    // S7-GRAPH's steps also have `U`, their time without disturbance.
                    let members: &[(&str, Type)] = if self.graph {
                        &[("X", Type::Bool), ("T", Type::Time), ("U", Type::Time)]
                    } else if self.logix {
                        &[
                            ("X", Type::Bool),
                            ("T", Type::Time),
                            ("Count", Type::DInt),
                            ("FS", Type::Bool),
                            ("SA", Type::Bool),
                            ("LS", Type::Bool),
                            ("TMax", Type::DInt),
                        ]
                    } else {
                        &[("X", Type::Bool), ("T", Type::Time)]
                    };
                    return self.chart_member(&step, "step", member, members, write);
                }
                Some(sym @ Sym::Action(_)) => {
                    self.scope.mark(sym, false);
                    let action = self.scope.chart_name(sym).to_string();
                    return self.chart_member(
                        &action,
                        "action",
                        member,
                        &[("Q", Type::Bool), ("A", Type::Bool)],
                        write,
                    );
                }
                None => {
                    // CODESYS's implicit `_<action>.x` (executed) and `_<action>._x` (active).
                    if let Some(sym @ Sym::Action(_)) = id.text.strip_prefix('_').and_then(|a| self.scope.resolve(a)) {
                        self.scope.mark(sym, false);
                        let action = format!("_{}", self.scope.chart_name(sym));
                        return self.chart_member(
                            &action,
                            "action",
                            member,
                            &[("x", Type::Bool), ("_x", Type::Bool)],
                            write,
                        );
                    }
                }
                _ => {}
            }
        }
        // `THIS^.x := …` writes the block's own variable: the base is not a target itself.
        let base_ty = if write && !matches!(base.kind, ExprKind::Deref(_)) {
            self.target(base)
        } else {
            self.check_expr(base, None)
        };
        if base_ty.is_error() {
            return Type::Error;
        }
        // Partial access `w.%X3`, `d.%W1` (IEC 61131-3 3rd edition): a bit, byte, word or
        // double word of a bit string or integer.
        if let Some(rest) = member.text.strip_prefix('%') {
            let size = match rest.chars().next().map(|c| c.to_ascii_uppercase()) {
                Some('X') => Some((1, Type::Bool)),
                Some('B') => Some((8, Type::Byte)),
                Some('W') => Some((16, Type::Word)),
                Some('D') => Some((32, Type::DWord)),
                Some('L') => Some((64, Type::LWord)),
                _ => None,
            };
            let width = base_ty.bit_width().filter(|_| base_ty.is_integer() || base_ty.is_bit());
            let index: Option<u32> = rest.get(1..).and_then(|i| i.parse().ok());
            return match (size, width, index) {
                (Some((bits, ty)), Some(w), Some(i)) if bits < w && (i + 1) * bits <= w => ty,
                (Some(_), Some(_), Some(_)) => {
                    self.error(
                        "SFC0315",
                        member.span,
                        format!("partial access `.{}` is out of range for `{base_ty}`", member.text),
                    );
                    Type::Error
                }
                _ => {
                    self.error(
                        "SFC0309",
                        member.span,
                        format!(
                            "partial access `.{}` needs a bit string or an integer wider than it, not `{base_ty}`",
                            member.text
                        ),
                    );
                    Type::Error
                }
            };
        }
        // Bit access `w.3`.
        if !member.text.is_empty() && member.text.bytes().all(|b| b.is_ascii_digit()) {
            let width = base_ty.bit_width().filter(|_| base_ty.is_integer() || base_ty.is_bit());
            let Some(width) = width.filter(|w| *w > 1) else {
                self.error(
                    "SFC0309",
                    member.span,
                    format!("bit access `.{}` needs a bit string or an integer, not `{base_ty}`", member.text),
                );
                return Type::Error;
            };
            let bit: Option<u32> = member.text.parse().ok();
            if bit.is_none_or(|b| b >= width) {
                self.error(
                    "SFC0315",
                    member.span,
                    format!("bit {} is out of range for `{base_ty}` (0..{})", member.text, width - 1),
                );
                return Type::Error;
            }
            return Type::Bool;
        }
        match &base_ty {
            Type::Struct { fields, .. } => match base_ty.field(&member.text) {
                Some(t) => t.clone(),
                None => {
                    let mut d =
                        Diagnostic::new("SFC0309", member.span, format!("`{base_ty}` has no field `{}`", member.text));
                    if let Some(s) = closest(&member.text, fields.iter().map(|(n, _)| n.as_str())) {
                        d = d.with_note(format!("did you mean `{s}`?"));
                    }
                    self.report(d);
                    Type::Error
                }
            },
            Type::Interface(name) => {
                let env = self.scope.env();
                let Some(itf) = env.interface(name) else { return Type::Error };
                if let Some(p) = itf.property(&member.text) {
                    let p = p.clone();
                    return self.property_access(&p, member, write);
                }
                let mut d = Diagnostic::new(
                    "SFC0309",
                    member.span,
                    format!("interface `{}` has no property `{}`", itf.name, member.text),
                );
                if itf.method(&member.text).is_some() {
                    d = d.with_note(format!(
                        "`{}` is a method: call it, `{}.{}(…)`",
                        member.text,
                        expr_text(base),
                        member.text
                    ));
                } else if let Some(s) = closest(&member.text, itf.properties.iter().map(|p| p.name.as_str())) {
                    d = d.with_note(format!("did you mean `{s}`?"));
                }
                self.report(d);
                Type::Error
            }
            Type::FunctionBlock(fb_name) => {
                let env = self.scope.env();
                let Some(fb) = env.function_block(fb_name) else { return Type::Error };
                if let Some(p) = fb.property(&member.text) {
                    let p = p.clone();
                    return self.property_access(&p, member, write);
                }
                // `THIS^.x`: every variable of the block itself.
                let this = matches!(&base.kind, ExprKind::Deref(_));
                let Some(param) = fb.var(&member.text) else {
                    let mut d = Diagnostic::new(
                        "SFC0309",
                        member.span,
                        format!("function block `{}` has no parameter `{}`", fb.name, member.text),
                    );
                    let params = fb.vars.iter().filter(|v| matches!(v.kind, VarKind::Input | VarKind::Output));
                    if let Some(s) = closest(&member.text, params.map(|v| v.name.as_str())) {
                        d = d.with_note(format!("did you mean `{s}`?"));
                    }
                    self.report(d);
                    return Type::Error;
                };
                // A program's variables are reachable from any code (`Main.X`, CODESYS): its
                // one instance is a global (see `TypeEnv::is_reached`).
                if fb.kind == sfc_syntax::ast::PouKind::Program || this {
                    return param.ty.clone();
                }
                match param.kind {
                    VarKind::Input => param.ty.clone(),
                    VarKind::Output if !write => param.ty.clone(),
                    VarKind::Output => {
                        self.error(
                            "SFC0308",
                            member.span,
                            format!(
                                "`{}.{}` is an output of `{}`; only the block writes it",
                                expr_text(base),
                                param.name,
                                fb.name
                            ),
                        );
                        Type::Error
                    }
                    VarKind::InOut => {
                        self.error(
                            "SFC0309",
                            member.span,
                            format!(
                                "`{}` is an in-out of function block `{}`; it refers to the caller's variable, use that",
                                param.name, fb.name
                            ),
                        );
                        Type::Error
                    }
                    // CODESYS and TwinCAT let a local variable of an instance be read from
                    // outside (IEC 61131-3 does not): a warning, and the value is read.
                    _ if !write && param.kind == VarKind::Var => {
                        self.report(
                            Diagnostic::warning(
                                "SFC0322",
                                member.span,
                                format!(
                                    "`{}` is internal to function block `{}`; reading it from outside is CODESYS, not IEC 61131-3",
                                    param.name, fb.name
                                ),
                            )
                            .with_note("give the block an output for it to keep the chart portable"),
                        );
                        param.ty.clone()
                    }
                    _ => {
                        self.error(
                            "SFC0309",
                            member.span,
                            format!(
                                "`{}` is internal to function block `{}`; only inputs and outputs are accessible",
                                param.name, fb.name
                            ),
                        );
                        Type::Error
                    }
                }
            }
            _ => {
                self.error("SFC0309", member.span, format!("`{base_ty}` has no member `{}`", member.text));
                Type::Error
            }
        }
    }

    fn chart_member(&mut self, owner: &str, what: &str, member: &Ident, members: &[(&str, Type)], write: bool) -> Type {
        // CODESYS's `<step>._x` (active in the next cycle) and `<step>._t` read as `X` and `T`
        // (docs/sim.md, "The `codesys` profile").
        let alias = match member.text.to_ascii_uppercase().as_str() {
            "_X" if what == "step" => Some("X"),
            "_T" if what == "step" => Some("T"),
            _ => None,
        };
        let found = members.iter().find(|(n, _)| member.is(n) || alias.is_some_and(|a| a == *n));
        let Some((name, ty)) = found else {
            let list = members.iter().map(|(n, _)| format!("`.{n}`")).collect::<Vec<_>>().join(" and ");
            self.error(
                "SFC0309",
                member.span,
                format!("{what} `{owner}` has no member `{}`; {what}s have {list}", member.text),
            );
            return Type::Error;
        };
        if write {
            self.error(
                "SFC0304",
                member.span,
                format!("`{owner}.{name}` is maintained by the chart and cannot be written"),
            );
            return Type::Error;
        }
        ty.clone()
    }

    /// `base[i, j]`.
    fn index(&mut self, base: &Expr, indices: &[Expr], write: bool) -> Type {
        // `THIS^.x := …` writes the block's own variable: the base is not a target itself.
        let base_ty = if write && !matches!(base.kind, ExprKind::Deref(_)) {
            self.target(base)
        } else {
            self.check_expr(base, None)
        };
        // CODESYS's pointer indexing: `p[i]` is the `i`-th element of the pointed type from `p`.
        if let Type::Pointer(t) = &base_ty {
            if let [i] = indices {
                let it = self.check_expr(i, Some(&Type::DInt));
                if !it.is_error() && !it.is_integer() {
                    self.error("SFC0302", i.span, format!("type mismatch: an index is an integer, not `{it}`"));
                }
                return (**t).clone();
            }
        }
        let dims = match &base_ty {
            Type::Array { dims, .. } => Some(dims.clone()),
            _ => None,
        };
        if dims.is_none() && !base_ty.is_error() {
            self.error("SFC0310", base.span, format!("`{}` is not an array (it is `{base_ty}`)", expr_text(base)));
        }
        if let Some(dims) = &dims {
            if dims.len() != indices.len() {
                let span =
                    indices.first().map(|f| indices.iter().fold(f.span, |s, e| s.to(e.span))).unwrap_or(base.span);
                self.error(
                    "SFC0310",
                    span,
                    format!(
                        "`{}` has {} dimension{}, but {} ind{} given",
                        expr_text(base),
                        dims.len(),
                        if dims.len() == 1 { "" } else { "s" },
                        indices.len(),
                        if indices.len() == 1 { "ex is" } else { "ices are" }
                    ),
                );
            }
        }
        let mut ok = true;
        for (i, idx) in indices.iter().enumerate() {
            let bounds = dims.as_ref().and_then(|d| d.get(i)).copied();
            if let Some(Untyped::Int(v)) = untyped(idx) {
                if let (Some(v), Some((lo, hi))) = (v, bounds) {
                    if v < i128::from(lo) || v > i128::from(hi) {
                        self.error("SFC0315", idx.span, format!("index {v} is out of range {lo}..{hi}"));
                        ok = false;
                    }
                }
                continue;
            }
            let t = self.check_expr(idx, Some(&Type::DInt));
            if !t.is_integer() && !t.is_error() {
                let p = self.phrase(idx, &t);
                self.error("SFC0302", idx.span, format!("type mismatch: an array index is {p}, expected an integer"));
                ok = false;
                continue;
            }
            if let (Some(Value::Int(v)), Some((lo, hi))) = (const_eval(idx, &*self.scope), bounds) {
                if v < i128::from(lo) || v > i128::from(hi) {
                    self.error("SFC0315", idx.span, format!("index {v} is out of range {lo}..{hi}"));
                    ok = false;
                }
            }
        }
        match base_ty {
            Type::Array { elem, .. } if ok && dims.as_ref().is_some_and(|d| d.len() == indices.len()) => *elem,
            _ => Type::Error,
        }
    }

    fn unary(&mut self, op: UnaryOp, operand: &Expr, e: &Expr, expected: Option<&Type>) -> Type {
        match op {
            UnaryOp::Neg | UnaryOp::Plus => {
                // A typed literal under minus: check the negative value (`-SINT#128` fits).
                if let ExprKind::Literal(lit @ Literal { type_prefix: Some(_), .. }) = &operand.kind {
                    if matches!(lit.kind, LiteralKind::Int(_)) {
                        let t = self.literal(lit, operand.span, Some(op == UnaryOp::Neg));
                        return self.require_signed(op, t, e);
                    }
                }
                let t = self.check_expr(operand, expected);
                self.require_signed(op, t, e)
            }
            UnaryOp::Not => {
                let t = self.check_expr(operand, expected.filter(|t| t.is_bit()));
                // CODESYS: the bitwise complement of an integer.
                if self.codesys && t.is_integer() {
                    return t;
                }
                if !t.is_bit() && !t.is_error() {
                    let p = self.phrase(operand, &t);
                    self.error(
                        "SFC0302",
                        e.span,
                        format!("type mismatch: `NOT` needs BOOL or a bit string, but the operand is {p}"),
                    );
                    return Type::Error;
                }
                t
            }
        }
    }

    fn require_signed(&mut self, op: UnaryOp, t: Type, e: &Expr) -> Type {
        if t.is_error() || t.is_num() || t.is_duration() {
            return t;
        }
        let sym = if op == UnaryOp::Neg { "-" } else { "+" };
        self.error("SFC0302", e.span, format!("type mismatch: unary `{sym}` needs a number or a duration, not `{t}`"));
        Type::Error
    }

    /// Checks an operand, leaving untyped constants for [`Checker::combine`] to type.
    pub(crate) fn operand<'x>(&mut self, e: &'x Expr, hint: Option<&Type>) -> Operand<'x> {
        match untyped(e) {
            Some(u) => Operand { expr: e, ty: None, untyped: Some(u) },
            None => Operand { expr: e, ty: Some(self.check_expr(e, hint)), untyped: None },
        }
    }

    fn binary(&mut self, op: BinaryOp, lhs: &Expr, rhs: &Expr, span: Span, expected: Option<&Type>) -> Type {
        let hint = if is_comparison(op) { None } else { expected };
        let l = self.operand(lhs, hint);
        // The other operand's type lets an enumerated value or a constant on the right adapt.
        let r_hint = l.ty.clone().filter(|t| !t.is_error() && !t.is_duration() && !t.is_date());
        let r = self.operand(rhs, r_hint.as_ref().or(hint));
        if let Some(t) = self.pointer_arithmetic(op, &l, &r) {
            return t;
        }
        self.combine(op, vec![l, r], span, expected, &format!("operator `{}`", op.symbol()))
    }

    /// CODESYS's pointer arithmetic: `p + n`, `n + p`, `p - n` (a pointer moved by `n` bytes)
    /// and `p - q` (the bytes between two pointers, a `LINT`).
    fn pointer_arithmetic(&mut self, op: BinaryOp, l: &Operand<'_>, r: &Operand<'_>) -> Option<Type> {
        let is_ptr = |o: &Operand<'_>| matches!(o.ty.as_ref().map(Type::base), Some(Type::Pointer(_)));
        let is_int = |o: &Operand<'_>| {
            matches!(o.untyped, Some(Untyped::Int(_))) || o.ty.as_ref().is_some_and(|t| t.is_integer() || t.is_bit())
        };
        let ptr = |o: &Operand<'_>| o.ty.clone().unwrap_or(Type::Error);
        match op {
            BinaryOp::Add if is_ptr(l) && is_int(r) => Some(ptr(l)),
            BinaryOp::Add if is_int(l) && is_ptr(r) => Some(ptr(r)),
            BinaryOp::Sub if is_ptr(l) && is_int(r) => Some(ptr(l)),
            BinaryOp::Sub if is_ptr(l) && is_ptr(r) => Some(Type::LInt),
            _ => None,
        }
    }

    /// Types an operator (or an operator-like standard function such as `ADD`) applied to
    /// operands: finds their common type, types the untyped constants, checks the class.
    pub(crate) fn combine(
        &mut self,
        op: BinaryOp,
        ops: Vec<Operand<'_>>,
        span: Span,
        expected: Option<&Type>,
        what: &str,
    ) -> Type {
        if ops.iter().any(|o| o.ty.as_ref().is_some_and(Type::is_error)) {
            return Type::Error;
        }
        let temporal = ops.iter().any(|o| o.ty.as_ref().is_some_and(|t| t.is_duration() || t.is_date()));
        match op {
            BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Div if temporal => {
                self.time_arith(op, ops, span, what)
            }
            BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Div => {
                self.unify(&ops, Generic::AnyNum, expected, what)
            }
            BinaryOp::Mod => self.unify(&ops, Generic::AnyInt, expected, what),
            BinaryOp::Pow => self.power(ops, expected, what),
            BinaryOp::And | BinaryOp::Or | BinaryOp::Xor => self.unify(&ops, Generic::AnyBit, expected, what),
            BinaryOp::AndThen | BinaryOp::OrElse => {
                for o in &ops {
                    let t = match (&o.ty, o.untyped) {
                        (Some(t), _) => t.clone(),
                        (None, Some(u)) => {
                            let t = self.untyped_type(u, o.expr, Some(&Type::Bool));
                            self.record(o.expr.span, &t);
                            t
                        }
                        (None, None) => Type::Error,
                    };
                    if !t.is_bool() && !t.is_error() {
                        let p = self.phrase(o.expr, &t);
                        self.error(
                            "SFC0302",
                            o.expr.span,
                            format!("type mismatch: {what} needs BOOL operands, but this is {p}"),
                        );
                        return Type::Error;
                    }
                }
                Type::Bool
            }
            BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge => {
                let enums: Vec<&Type> = ops.iter().filter_map(|o| o.ty.as_ref()).filter(|t| t.is_enum()).collect();
                if let Some(first) = enums.first() {
                    let all_same = ops.iter().all(|o| o.ty.as_ref() == Some(*first));
                    if all_same && matches!(op, BinaryOp::Eq | BinaryOp::Ne) {
                        return Type::Bool;
                    }
                    if !all_same {
                        let other = ops.iter().find(|o| o.ty.as_ref() != Some(*first));
                        if let Some(o) = other {
                            let p = match &o.ty {
                                Some(t) => self.phrase(o.expr, t),
                                None => untyped_phrase(o.untyped),
                            };
                            let msg = format!("type mismatch: {what} cannot compare `{first}` with {p}");
                            self.error("SFC0302", span, msg);
                            return Type::Error;
                        }
                    }
                    self.error(
                        "SFC0302",
                        span,
                        format!("type mismatch: {what} cannot order enumerated values of `{first}`"),
                    );
                    return Type::Error;
                }
                match self.unify(&ops, Generic::AnyElementary, None, what) {
                    Type::Error => Type::Error,
                    _ => Type::Bool,
                }
            }
        }
    }

    /// The common type of the operands, of class `class`.
    pub(crate) fn unify(&mut self, ops: &[Operand<'_>], class: Generic, expected: Option<&Type>, what: &str) -> Type {
        let mut common: Option<Type> = None;
        for o in ops {
            let Some(t) = &o.ty else { continue };
            if t.is_error() {
                return Type::Error;
            }
            let t = if class.admits(t) {
                t.base().clone()
            } else if let Some(r) = real_promotion(t).filter(|_| class == Generic::AnyReal) {
                r
            } else {
                let p = self.phrase(o.expr, t);
                self.error(
                    "SFC0302",
                    o.expr.span,
                    format!("type mismatch: {what} needs {} operands, but this is {p}", class.name()),
                );
                return Type::Error;
            };
            common = match common {
                None => Some(t),
                Some(prev) => match Type::common(&prev, &t) {
                    Some(c) => Some(c),
                    None => {
                        self.error(
                            "SFC0302",
                            o.expr.span,
                            format!("type mismatch: {what} cannot combine `{prev}` and `{t}`"),
                        );
                        return Type::Error;
                    }
                },
            };
        }
        let untyped_ops: Vec<(&Expr, Untyped)> = ops.iter().filter_map(|o| o.untyped.map(|u| (o.expr, u))).collect();
        let mut t = match common {
            Some(t) => t,
            None => {
                // Only constants: the context decides, else their natural type.
                let from_context = expected
                    .map(Type::base)
                    .filter(|t| class.admits(t) && !t.is_error())
                    .filter(|t| untyped_ops.iter().all(|(_, u)| matches!(fit(*u, t), Fit::Fits)));
                match from_context {
                    Some(t) => t.clone(),
                    None => {
                        let mut acc: Option<Type> = None;
                        for (e, u) in &untyped_ops {
                            let n = self.natural_type(*u, e.span);
                            if n.is_error() {
                                return Type::Error;
                            }
                            acc = Some(match acc {
                                None => n,
                                Some(a) => Type::common(&a, &n).unwrap_or(Type::LReal),
                            });
                        }
                        let t = acc.unwrap_or(Type::Error);
                        for (e, _) in &untyped_ops {
                            self.record(e.span, &t);
                        }
                        if !class.admits(&t) {
                            if let Some((e, u)) = untyped_ops.first() {
                                let p = untyped_phrase(Some(*u));
                                self.error(
                                    "SFC0302",
                                    e.span,
                                    format!("type mismatch: {what} needs {} operands, but this is {p}", class.name()),
                                );
                            }
                            return Type::Error;
                        }
                        return t;
                    }
                }
            }
        };
        for (e, u) in &untyped_ops {
            match fit(*u, &t) {
                Fit::Fits => {}
                Fit::OutOfRange(msg) => {
                    self.error("SFC0315", e.span, msg);
                    return Type::Error;
                }
                Fit::WrongKind => {
                    // A real constant with integer operands makes the operation real when the
                    // integers widen into a real type (`i * 1.5` is REAL for an INT `i`).
                    if let (Untyped::Real(_), Some(r)) = (u, real_promotion(&t)) {
                        if class.admits(&r) {
                            t = r;
                            continue;
                        }
                    }
                    let p = untyped_phrase(Some(*u));
                    self.error("SFC0302", e.span, format!("type mismatch: {what} cannot combine `{t}` and {p}"));
                    return Type::Error;
                }
            }
        }
        for (e, _) in &untyped_ops {
            self.record(e.span, &t);
        }
        t
    }

    /// `+ - * /` when a duration or a date is involved (IEC 61131-3 table 30).
    fn time_arith(&mut self, op: BinaryOp, ops: Vec<Operand<'_>>, span: Span, what: &str) -> Type {
        // More than two operands (ADD(t1, t2, t3)): fold from the left.
        for o in &ops {
            if let (None, Some(u)) = (&o.ty, o.untyped) {
                self.record(o.expr.span, &quiet_natural(u));
            }
        }
        let mut iter = ops.into_iter();
        let Some(first) = iter.next() else { return Type::Error };
        let mut acc_ty = first.ty.clone();
        let mut acc_untyped = first.untyped;
        let first_expr = first.expr;
        for next in iter {
            let l = acc_ty.clone();
            let r = next.ty.clone();
            let num = |t: &Option<Type>, u: Option<Untyped>| u.is_some() || t.as_ref().is_some_and(Type::is_num);
            use Type::*;
            let result: Option<Type> = match (op, l.as_ref().map(Type::base), r.as_ref().map(Type::base)) {
                (BinaryOp::Add | BinaryOp::Sub, Some(a), Some(b)) if a.is_duration() && b.is_duration() => {
                    Type::common(a, b)
                }
                (BinaryOp::Add | BinaryOp::Sub, Some(TimeOfDay), Some(b)) if b.is_duration() => Some(TimeOfDay),
                (BinaryOp::Add | BinaryOp::Sub, Some(DateAndTime), Some(b)) if b.is_duration() => Some(DateAndTime),
                (BinaryOp::Sub, Some(Date), Some(Date)) => Some(Time),
                (BinaryOp::Sub, Some(TimeOfDay), Some(TimeOfDay)) => Some(Time),
                (BinaryOp::Sub, Some(DateAndTime), Some(DateAndTime)) => Some(Time),
                (BinaryOp::Mul | BinaryOp::Div, Some(a), _) if a.is_duration() && num(&r, next.untyped) => {
                    Some(a.clone())
                }
                (BinaryOp::Mul, _, Some(b)) if b.is_duration() && num(&l, acc_untyped) => Some(b.clone()),
                _ => None,
            };
            match result {
                Some(t) => {
                    acc_ty = Some(t);
                    acc_untyped = None;
                }
                None => {
                    let lp = match &l {
                        Some(t) => format!("`{t}`"),
                        None => untyped_phrase(acc_untyped),
                    };
                    let rp = match &r {
                        Some(t) => format!("`{t}`"),
                        None => untyped_phrase(next.untyped),
                    };
                    self.error(
                        "SFC0302",
                        first_expr.span.to(next.expr.span).to(span),
                        format!("type mismatch: {what} is not defined for {lp} and {rp}"),
                    );
                    return Type::Error;
                }
            }
        }
        acc_ty.unwrap_or(Type::Error)
    }

    /// `a ** b`: a real base (integers widen into a real), any numeric exponent.
    fn power(&mut self, ops: Vec<Operand<'_>>, expected: Option<&Type>, what: &str) -> Type {
        let mut iter = ops.iter();
        let (Some(base), Some(exp)) = (iter.next(), iter.next()) else { return Type::Error };
        let base_ty = match (&base.ty, base.untyped) {
            (Some(t), _) if t.is_real() => t.base().clone(),
            (Some(t), _) => match real_promotion(t) {
                Some(r) => r,
                None => {
                    let p = self.phrase(base.expr, t);
                    self.error(
                        "SFC0302",
                        base.expr.span,
                        format!("type mismatch: {what} needs a real base, but it is {p}"),
                    );
                    return Type::Error;
                }
            },
            (None, _) => expected.map(Type::base).filter(|t| t.is_real()).cloned().unwrap_or(Type::LReal),
        };
        if base.ty.is_none() {
            self.record(base.expr.span, &base_ty);
        }
        if let (None, Some(u)) = (&exp.ty, exp.untyped) {
            self.record(exp.expr.span, &quiet_natural(u));
        }
        if let Some(t) = &exp.ty {
            if !t.is_num() && !t.is_error() {
                let p = self.phrase(exp.expr, t);
                self.error(
                    "SFC0302",
                    exp.expr.span,
                    format!("type mismatch: {what} needs a numeric exponent, but it is {p}"),
                );
                return Type::Error;
            }
        }
        base_ty
    }

    /// Describes the type of an expression for a message: "`INT`", or "an integer constant"
    /// for an untyped literal (whose DINT default would mislead).
    pub(crate) fn phrase(&self, e: &Expr, t: &Type) -> String {
        match untyped(e) {
            Some(u)
                if !matches!(t, Type::Error)
                    && (t == &Type::DInt || t == &Type::LInt || t == &Type::ULInt || t == &Type::LReal) =>
            {
                untyped_phrase(Some(u))
            }
            _ => format!("`{t}`"),
        }
    }
}

/// The natural type of an untyped constant, without reporting (LINT when it is too large to
/// say more).
pub(crate) fn quiet_natural(u: Untyped) -> Type {
    match u {
        Untyped::Real(_) => Type::LReal,
        Untyped::Int(Some(v)) if i32::try_from(v).is_ok() => Type::DInt,
        Untyped::Int(Some(v)) if u64::try_from(v).is_ok() && i64::try_from(v).is_err() => Type::ULInt,
        Untyped::Int(_) => Type::LInt,
    }
}

/// "an integer constant" / "a real constant".
pub(crate) fn untyped_phrase(u: Option<Untyped>) -> String {
    match u {
        Some(Untyped::Real(_)) => "a real constant".to_string(),
        _ => "an integer constant".to_string(),
    }
}

fn is_comparison(op: BinaryOp) -> bool {
    matches!(op, BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge)
}

/// The real type an integer widens into (REAL for 8- and 16-bit, LREAL for 32-bit).
pub(crate) fn real_promotion(t: &Type) -> Option<Type> {
    let t = t.base();
    if !t.is_integer() {
        return None;
    }
    [Type::Real, Type::LReal].into_iter().find(|r| t.widens_to(r))
}

/// Recognises an untyped numeric constant expression and folds its value.
pub(crate) fn untyped(e: &Expr) -> Option<Untyped> {
    untyped_at(e, 0)
}

fn untyped_at(e: &Expr, depth: u32) -> Option<Untyped> {
    if depth > MAX_DEPTH {
        return None;
    }
    match &e.kind {
        ExprKind::Literal(Literal { kind: LiteralKind::Int(v), type_prefix: None, .. }) => Some(Untyped::Int(Some(*v))),
        ExprKind::Literal(Literal { kind: LiteralKind::Real(r), type_prefix: None, .. }) => {
            Some(Untyped::Real(Some(*r)))
        }
        ExprKind::Paren(inner) => untyped_at(inner, depth + 1),
        ExprKind::Unary { op: UnaryOp::Neg, operand } => match untyped_at(operand, depth + 1)? {
            Untyped::Int(v) => Some(Untyped::Int(v.and_then(i128::checked_neg))),
            Untyped::Real(v) => Some(Untyped::Real(v.map(|r| -r))),
        },
        ExprKind::Unary { op: UnaryOp::Plus, operand } => untyped_at(operand, depth + 1),
        ExprKind::Binary { op, lhs, rhs }
            if matches!(op, BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Div | BinaryOp::Mod) =>
        {
            let a = untyped_at(lhs, depth + 1)?;
            let b = untyped_at(rhs, depth + 1)?;
            match (a, b) {
                (Untyped::Int(x), Untyped::Int(y)) => {
                    let v = match (x, y) {
                        (Some(x), Some(y)) => match op {
                            BinaryOp::Add => x.checked_add(y),
                            BinaryOp::Sub => x.checked_sub(y),
                            BinaryOp::Mul => x.checked_mul(y),
                            BinaryOp::Div => x.checked_div(y),
                            _ => x.checked_rem(y),
                        },
                        _ => None,
                    };
                    Some(Untyped::Int(v))
                }
                // MOD is for integers only: leave `1.5 MOD 2` to the checker to report.
                _ if *op == BinaryOp::Mod => None,
                (a, b) => {
                    let f = |u: Untyped| match u {
                        Untyped::Int(v) => v.map(|v| v as f64),
                        Untyped::Real(v) => v,
                    };
                    let v = match (f(a), f(b)) {
                        (Some(x), Some(y)) => match op {
                            BinaryOp::Add => Some(x + y),
                            BinaryOp::Sub => Some(x - y),
                            BinaryOp::Mul => Some(x * y),
                            _ => Some(x / y),
                        },
                        _ => None,
                    };
                    Some(Untyped::Real(v))
                }
            }
        }
        _ => None,
    }
}

/// Whether an untyped constant fits a type.
pub(crate) fn fit(u: Untyped, t: &Type) -> Fit {
    let t_base = t.base();
    match u {
        Untyped::Int(v) => {
            if t_base.is_real() {
                return Fit::Fits;
            }
            if t_base.is_bool() {
                return match v {
                    Some(0 | 1) => Fit::Fits,
                    _ => Fit::WrongKind,
                };
            }
            // A pointer is set to, and compared with, 0 (none).
            if matches!(t_base, Type::Pointer(_) | Type::Interface(_)) {
                return if v == Some(0) { Fit::Fits } else { Fit::WrongKind };
            }
            let Some((lo, hi)) = t.int_range() else { return Fit::WrongKind };
            match v {
                Some(v) if lo <= v && v <= hi => Fit::Fits,
                Some(v) => Fit::OutOfRange(format!("the constant {v} is out of range for `{t}` ({lo}..{hi})")),
                None => Fit::OutOfRange("the constant expression overflows or divides by zero".to_string()),
            }
        }
        Untyped::Real(v) => match t_base {
            Type::LReal => Fit::Fits,
            Type::Real => match v {
                Some(r) if r.is_finite() && r.abs() > f64::from(f32::MAX) => {
                    Fit::OutOfRange(format!("the constant {r} is out of range for `REAL`"))
                }
                _ => Fit::Fits,
            },
            _ => Fit::WrongKind,
        },
    }
}

/// The type of a direct address by its size prefix.
pub(crate) fn address_type(a: &DirectAddress) -> Type {
    match a.size.to_ascii_uppercase() {
        'B' => Type::Byte,
        'W' => Type::Word,
        'D' => Type::DWord,
        'L' => Type::LWord,
        _ => Type::Bool,
    }
}

fn enum_names(t: &Type) -> Vec<String> {
    match t {
        Type::Enum { values, .. } => values.iter().map(|(n, _)| n.clone()).collect(),
        _ => Vec::new(),
    }
}

/// The source-like text of a name path (`a.b[1]`), for messages.
pub(crate) fn expr_text(e: &Expr) -> String {
    let mut out = String::new();
    write_expr_text(e, &mut out, 0);
    out
}

fn write_expr_text(e: &Expr, out: &mut String, depth: u32) {
    if depth > 16 {
        out.push('…');
        return;
    }
    match &e.kind {
        ExprKind::Name(id) => out.push_str(&id.text),
        ExprKind::Address(a) => out.push_str(&a.text),
        ExprKind::Literal(l) => out.push_str(&l.text),
        ExprKind::Member { base, member } => {
            write_expr_text(base, out, depth + 1);
            out.push('.');
            out.push_str(&member.text);
        }
        ExprKind::Index { base, indices } => {
            write_expr_text(base, out, depth + 1);
            out.push('[');
            for (i, idx) in indices.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_expr_text(idx, out, depth + 1);
            }
            out.push(']');
        }
        ExprKind::Paren(inner) => {
            out.push('(');
            write_expr_text(inner, out, depth + 1);
            out.push(')');
        }
        ExprKind::Call { callee, .. } => {
            out.push_str(&callee.text);
            out.push_str("(…)");
        }
        _ => out.push_str("expression"),
    }
}
