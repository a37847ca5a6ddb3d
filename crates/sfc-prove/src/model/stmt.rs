//! ST statements (assignments, IF, CASE, FOR/WHILE/REPEAT unrolled, EXIT, RETURN), calls of
//! function block instances (standard blocks on virtual time, user blocks, SFC blocks), user
//! FUNCTIONs (inlined with a fresh frame) and actions.

use super::expr::{ExprError, Frame, PlaceRef, R, SV};
use super::{int_sort, Enc, InstKind, Role, Slot, StdFb, VarEntry};
use crate::aig::Lit;
use crate::word::Word;
use sfc_diagnostics::Span;
use sfc_st::Type;
use sfc_syntax::ast::{ActionBody, Arg, CaseLabel, Condition, Expr, ExprKind, Ident, Stmt, StmtKind, VarKind};

/// Iterations a FOR loop is unrolled at most.
const MAX_UNROLL: usize = 2048;
/// Iterations a WHILE or REPEAT loop is unrolled at most.
const MAX_UNROLL_WHILE: usize = 256;
/// Nesting of calls at most.
const MAX_DEPTH: u32 = 32;

impl<'a> Enc<'a> {
    fn frame(&self, inst: usize) -> Frame {
        Frame { inst, recorded: true }
    }

    /// Runs the ST or IL body of a POU instance (not a chart).
    pub(crate) fn run_body(&mut self, inst: usize) {
        let InstKind::User(p) = self.insts[inst].kind else { return };
        let ast = self.pous[p].ast;
        let f = self.frame(inst);
        let saved_ret = self.returned;
        self.returned = Lit::FALSE;
        match &ast.body {
            sfc_syntax::ast::Body::St(stmts) => self.exec_list(&f, stmts),
            sfc_syntax::ast::Body::Il(il) => self.exec_il(&f, il),
            sfc_syntax::ast::Body::Sfc(_) => {
                if let Some(c) = self.insts[inst].chart {
                    self.run_chart(c);
                }
            }
        }
        self.returned = saved_ret;
    }

    /// Runs the body of action `name` on instance `inst`: its statements, or for an action
    /// written in SFC one scan of its chart.
    pub(crate) fn run_action(&mut self, inst: usize, name: &str, body: &ActionBody) {
        let f = self.frame(inst);
        let saved_ret = self.returned;
        self.returned = Lit::FALSE;
        match body {
            ActionBody::St(stmts) => self.exec_list(&f, stmts),
            ActionBody::Il(il) => self.exec_il(&f, il),
            ActionBody::Sfc(_) => match self.action_chart(inst, name) {
                Some(c) => self.run_chart(c),
                None => {
                    self.refused.get_or_insert(format!("the chart of action `{name}` is missing"));
                }
            },
        }
        self.returned = saved_ret;
    }

    /// The chart of action `name` (written in SFC) of instance `inst`.
    pub(crate) fn action_chart(&self, inst: usize, name: &str) -> Option<usize> {
        self.insts[inst]
            .subs
            .iter()
            .copied()
            .find(|&c| self.charts[c].action.as_deref().is_some_and(|a| a.eq_ignore_ascii_case(name)))
    }

    /// Action `name` of instance `inst`: the actions of its POU's chart, or for a POU whose
    /// body is not a chart, the POU's actions.
    pub(crate) fn action_of(&self, inst: usize, name: &str) -> Option<(String, &'a ActionBody)> {
        if let Some(c) = self.insts[inst].chart {
            let chart = self.chart_of(c);
            return chart.action(name).map(|a| (chart.actions[a].name.clone(), &chart.actions[a].body));
        }
        let super::InstKind::User(p) = self.insts[inst].kind else { return None };
        let ast: &'a sfc_syntax::ast::Pou = self.pous[p].ast;
        ast.actions.iter().find(|a| a.name.is(name)).map(|a| (a.name.text.clone(), &a.body))
    }

    /// Runs a step action (`ENTRY_ACTION := A;`, …) as the call `A();` or `inst.A();`. What
    /// cannot be modelled makes what the instance holds free.
    pub(crate) fn run_step_action(&mut self, inst: usize, sa: &sfc_syntax::ast::StepAction) {
        let f = self.frame(inst);
        let r = match sa.call() {
            Some(call) => self.call_stmt(&f, &call),
            None => Err(ExprError { span: sa.span, message: "the step action names no action".into() }),
        };
        if let Err(e) = r {
            let (line, _) = line_col(&self.checked.file.text, sa.span.start as usize);
            self.note(format!(
                "the step action at line {line} is not modelled ({}); the variables of its POU instance and the globals are free after it",
                e.message
            ));
            self.havoc_instance(inst);
        }
    }

    /// Makes every variable of instance `inst` (nested instances included) and every global
    /// free.
    pub(crate) fn havoc_instance(&mut self, inst: usize) {
        let mut leaves = Vec::new();
        for v in self.insts[inst].vars.clone().iter().chain(self.globals.clone().iter()) {
            self.slot_leaves_deep(&v.slot, &mut leaves);
        }
        leaves.sort_unstable();
        leaves.dedup();
        for r in leaves {
            let reg = self.regs[r].clone();
            if reg.role == Role::Temp {
                continue;
            }
            let w = self.fresh(format!("{} (not modelled)", reg.name), reg.full, reg.signed, None);
            self.write_reg(r, w);
        }
    }

    /// A transition condition; what the model cannot evaluate becomes a free condition.
    pub(crate) fn guard(&mut self, inst: usize, _c: usize, cond: &Condition, name: &str) -> Lit {
        let f = self.frame(inst);
        let r = match cond {
            Condition::St(e) => self.eval_bool(&f, e),
            Condition::Il(il) => self.il_condition(&f, il),
            Condition::Missing => Ok(Lit::FALSE),
        };
        match r {
            Ok(l) => l,
            Err(e) => {
                self.note(format!("the condition of `{name}` is not modelled ({}); it is free", e.message));
                self.fresh(format!("condition of {name}"), 1, false, None).bits[0]
            }
        }
    }

    /// Runs statements; one the model cannot encode makes what it writes free.
    pub(crate) fn exec_list(&mut self, f: &Frame, stmts: &[Stmt]) {
        for s in stmts {
            if let Err(e) = self.exec(f, s) {
                let (line, _) = line_col(&self.checked.file.text, s.span.start as usize);
                self.note(format!(
                    "the statement at line {line} is not modelled ({}); what it writes is free",
                    e.message
                ));
                self.havoc_stmt(f, s);
            }
        }
    }

    fn exec(&mut self, f: &Frame, s: &Stmt) -> R<()> {
        match &s.kind {
            StmtKind::Assign { target, value } => {
                let p = self.place(f, target)?;
                let ty = self.place_type(&p);
                let v = self.eval(f, value, Some(&ty))?;
                self.write_place(&p, v, value.span)
            }
            StmtKind::Call(e) => self.call_stmt(f, e),
            StmtKind::If { branches, else_body } => {
                let pc = self.pc;
                let mut rem = pc;
                for (c, body) in branches {
                    self.pc = rem;
                    let cond = self.eval_bool(f, c)?;
                    let taken = self.g.and(rem, cond);
                    self.pc = taken;
                    if taken != Lit::FALSE {
                        self.exec_list(f, body);
                    }
                    rem = self.g.and(rem, cond.not());
                }
                if let Some(b) = else_body {
                    self.pc = rem;
                    if rem != Lit::FALSE {
                        self.exec_list(f, b);
                    }
                }
                self.pc = pc;
                Ok(())
            }
            StmtKind::Case { selector, arms, else_body } => {
                let sel = self.eval(f, selector, None)?;
                let sty = sel.ty();
                let pc = self.pc;
                let mut rem = pc;
                for arm in arms {
                    let mut m = Lit::FALSE;
                    for l in &arm.labels {
                        let hit = match l {
                            CaseLabel::Value(v) => {
                                let lv = self.eval(f, v, Some(&sty))?;
                                let c = self.compare(sfc_syntax::ast::BinaryOp::Eq, sel.clone(), lv, v.span)?;
                                self.to_bool(c, v.span)?
                            }
                            CaseLabel::Range(a, b) => {
                                let av = self.eval(f, a, Some(&sty))?;
                                let bv = self.eval(f, b, Some(&sty))?;
                                let ge = self.compare(sfc_syntax::ast::BinaryOp::Ge, sel.clone(), av, a.span)?;
                                let le = self.compare(sfc_syntax::ast::BinaryOp::Le, sel.clone(), bv, b.span)?;
                                let ge = self.to_bool(ge, a.span)?;
                                let le = self.to_bool(le, b.span)?;
                                self.g.and(ge, le)
                            }
                        };
                        m = self.g.or(m, hit);
                    }
                    let taken = self.g.and(rem, m);
                    self.pc = taken;
                    if taken != Lit::FALSE {
                        self.exec_list(f, &arm.body);
                    }
                    rem = self.g.and(rem, m.not());
                }
                if let Some(b) = else_body {
                    self.pc = rem;
                    if rem != Lit::FALSE {
                        self.exec_list(f, b);
                    }
                }
                self.pc = pc;
                Ok(())
            }
            StmtKind::For { var, from, to, by, body } => self.exec_for(f, var, from, to, by.as_deref(), body, s.span),
            StmtKind::While { cond, body } => {
                let saved_exit = self.exited;
                self.exited = Lit::FALSE;
                let pc = self.pc;
                let mut live = pc;
                let mut n = 0;
                loop {
                    self.pc = live;
                    let c = self.eval_bool(f, cond)?;
                    let go = self.active_with(c);
                    if go == Lit::FALSE || self.cannot_iterate(go, n) {
                        break;
                    }
                    if n >= MAX_UNROLL_WHILE {
                        self.loop_beyond_bound(f, body, go, s.span);
                        break;
                    }
                    self.pc = go;
                    self.exec_list(f, body);
                    live = go;
                    n += 1;
                }
                self.pc = pc;
                self.exited = saved_exit;
                Ok(())
            }
            StmtKind::Repeat { body, until } => {
                let saved_exit = self.exited;
                self.exited = Lit::FALSE;
                let pc = self.pc;
                let mut live = pc;
                let mut n = 0;
                loop {
                    if n >= MAX_UNROLL_WHILE {
                        let go = self.active_with(Lit::TRUE);
                        self.pc = live;
                        if go != Lit::FALSE {
                            self.loop_beyond_bound(f, body, go, s.span);
                        }
                        break;
                    }
                    self.pc = live;
                    self.exec_list(f, body);
                    let c = self.eval_bool(f, until)?;
                    let again = self.active_with(c.not());
                    if again == Lit::FALSE || self.cannot_iterate(again, n) {
                        break;
                    }
                    live = again;
                    n += 1;
                }
                self.pc = pc;
                self.exited = saved_exit;
                Ok(())
            }
            StmtKind::Exit => {
                let a = self.active();
                self.exited = self.g.or(self.exited, a);
                Ok(())
            }
            StmtKind::Return => {
                let a = self.active();
                self.returned = self.g.or(self.returned, a);
                Ok(())
            }
            StmtKind::Empty => Ok(()),
            StmtKind::RefAssign { .. } => {
                Err(ExprError { span: s.span, message: "references cannot be modelled".into() })
            }
        }
    }

    /// Whether a loop cannot run iteration `n` (its condition `go` is unsatisfiable), asked of
    /// the SAT solver every few iterations once the loop runs longer than constants decide.
    fn cannot_iterate(&mut self, go: Lit, n: usize) -> bool {
        (n >= 4 && (n.is_power_of_two() || n.is_multiple_of(16))) && !crate::sat::satisfiable(&self.g, go)
    }

    /// `pc ∧ cond` for the loop test (the statement-level active condition).
    fn active_with(&mut self, c: Lit) -> Lit {
        let a = self.active();
        self.g.and(a, c)
    }

    fn loop_beyond_bound(&mut self, f: &Frame, body: &[Stmt], go: Lit, span: Span) {
        let (line, _) = line_col(&self.checked.file.text, span.start as usize);
        self.note(format!(
            "the loop at line {line} is unrolled {MAX_UNROLL} times; beyond, what its body writes is free"
        ));
        let pc = self.pc;
        self.pc = go;
        for s in body {
            self.havoc_stmt(f, s);
        }
        self.pc = pc;
    }

    #[allow(clippy::too_many_arguments)]
    fn exec_for(
        &mut self,
        f: &Frame,
        var: &Ident,
        from: &Expr,
        to: &Expr,
        by: Option<&Expr>,
        body: &[Stmt],
        span: Span,
    ) -> R<()> {
        let Some(v) = self.lookup_var(f, &var.text) else {
            return Err(ExprError { span: var.span, message: format!("`{}` is not a variable", var.text) });
        };
        let Slot::Leaf(r) = v.slot else {
            return Err(ExprError { span: var.span, message: "the FOR variable is not modelled".into() });
        };
        let ty = v.ty.clone();
        let (_, signed) = int_sort(&ty).unwrap_or((16, true));
        let start = self.eval(f, from, Some(&ty))?;
        let start = self.coerce(start, &ty, from.span)?;
        let end = self.eval(f, to, Some(&ty))?;
        let end = self.coerce(end, &ty, to.span)?;
        let step = match by {
            Some(e) => {
                let s = self.eval(f, e, Some(&ty))?;
                self.coerce(s, &ty, e.span)?
            }
            None => SV::Int(Word::constant(1, int_sort(&ty).map_or(16, |x| x.0)), ty.base().clone()),
        };
        let (SV::Int(start, _), SV::Int(end, _), SV::Int(step, _)) = (start, end, step) else {
            return Err(ExprError { span, message: "FOR bounds are not integers".into() });
        };
        self.write_reg(r, start);
        let saved_exit = self.exited;
        self.exited = Lit::FALSE;
        let pc = self.pc;
        let neg = if signed { *step.bits.last().unwrap_or(&Lit::FALSE) } else { Lit::FALSE };
        let mut live = pc;
        let mut n = 0;
        loop {
            self.pc = live;
            let i = self.mem[r].clone();
            let past_up = self.ops().lt(&end, &i, signed);
            let past_down = self.ops().lt(&i, &end, signed);
            let past = self.g.ite(neg, past_down, past_up);
            let go = self.active_with(past.not());
            if go == Lit::FALSE || self.cannot_iterate(go, n) {
                break;
            }
            if n >= MAX_UNROLL {
                self.loop_beyond_bound(f, body, go, span);
                break;
            }
            self.pc = go;
            self.exec_list(f, body);
            // The increment happens unless EXIT or RETURN.
            let cur = self.mem[r].clone();
            let next = self.ops().add(&cur, &step);
            self.write_reg(r, next);
            live = go;
            n += 1;
        }
        self.pc = pc;
        self.exited = saved_exit;
        Ok(())
    }

    /// Makes everything a statement may write free (for statements the model cannot encode).
    pub(crate) fn havoc_stmt(&mut self, f: &Frame, s: &Stmt) {
        match &s.kind {
            StmtKind::Assign { target, .. } => self.havoc_target(f, target),
            StmtKind::Call(e) => match &e.kind {
                ExprKind::Call { callee, args } => {
                    for a in args {
                        if let (true, Some(v)) = (a.output, &a.value) {
                            self.havoc_target(f, v);
                        }
                    }
                    if let Some(v) = self.lookup_var(f, &callee.text) {
                        let mut leaves = Vec::new();
                        self.slot_leaves_deep(&v.slot, &mut leaves);
                        for r in leaves {
                            let reg = self.regs[r].clone();
                            let w = self.fresh(format!("{} (not modelled)", reg.name), reg.full, reg.signed, None);
                            self.write_reg(r, w);
                        }
                    } else if sfc_st::stdlib::std_function(&callee.text).is_none() {
                        // An action, a method of the instance, a user function: what it may
                        // write is the instance's and the globals.
                        self.havoc_instance(f.inst);
                    }
                }
                ExprKind::MemberCall { base, args, .. } => {
                    for a in args {
                        if let (true, Some(v)) = (a.output, &a.value) {
                            self.havoc_target(f, v);
                        }
                    }
                    // A method or action of the instance: the instance and the globals.
                    match self.place(f, base) {
                        Ok(PlaceRef::Slot(Slot::Fb(i), _)) => self.havoc_instance(i),
                        _ => self.havoc_instance(f.inst),
                    }
                }
                _ => {}
            },
            StmtKind::If { branches, else_body } => {
                for (_, b) in branches {
                    b.iter().for_each(|s| self.havoc_stmt(f, s));
                }
                if let Some(b) = else_body {
                    b.iter().for_each(|s| self.havoc_stmt(f, s));
                }
            }
            StmtKind::Case { arms, else_body, .. } => {
                for a in arms {
                    a.body.iter().for_each(|s| self.havoc_stmt(f, s));
                }
                if let Some(b) = else_body {
                    b.iter().for_each(|s| self.havoc_stmt(f, s));
                }
            }
            StmtKind::For { var, body, .. } => {
                let e = Expr { kind: ExprKind::Name(var.clone()), span: var.span };
                self.havoc_target(f, &e);
                body.iter().for_each(|s| self.havoc_stmt(f, s));
            }
            StmtKind::While { body, .. } | StmtKind::Repeat { body, .. } => {
                body.iter().for_each(|s| self.havoc_stmt(f, s));
            }
            _ => {}
        }
    }

    fn havoc_target(&mut self, f: &Frame, target: &Expr) {
        let Ok(p) = self.place(f, target) else { return };
        let mut leaves = Vec::new();
        match &p {
            PlaceRef::Slot(s, _) => self.slot_leaves_deep(s, &mut leaves),
            PlaceRef::Dyn(c, _) => c.iter().for_each(|(_, s)| self.slot_leaves_deep(s, &mut leaves)),
            PlaceRef::Bit(r, _) => leaves.push(*r),
            _ => {}
        }
        for r in leaves {
            let reg = self.regs[r].clone();
            let w = self.fresh(format!("{} (not modelled)", reg.name), reg.full, reg.signed, None);
            self.write_reg(r, w);
        }
    }

    /// Every register under a slot, function block instances included.
    pub(crate) fn slot_leaves_deep(&self, s: &Slot, out: &mut Vec<usize>) {
        match s {
            Slot::Leaf(r) => out.push(*r),
            Slot::Array { items, .. } => items.iter().for_each(|i| self.slot_leaves_deep(i, out)),
            Slot::Struct { fields, .. } => fields.iter().for_each(|(_, i)| self.slot_leaves_deep(i, out)),
            Slot::Fb(i) => {
                for v in &self.insts[*i].vars {
                    self.slot_leaves_deep(&v.slot, out);
                }
            }
            Slot::Opaque(_) => {}
        }
    }

    pub(crate) fn place_type(&self, p: &PlaceRef) -> Type {
        match p {
            PlaceRef::Slot(_, t) | PlaceRef::Dyn(_, t) => t.clone(),
            PlaceRef::Bit(..) | PlaceRef::StepX(..) | PlaceRef::ActQ(..) | PlaceRef::ActA(..) => Type::Bool,
            PlaceRef::StepT(..) => Type::Time,
        }
    }

    /// Writes a value to a place under the current path condition (assignment semantics:
    /// implicit conversion, subrange check).
    pub(crate) fn write_place(&mut self, p: &PlaceRef, v: SV, span: Span) -> R<()> {
        match p {
            PlaceRef::Slot(Slot::Leaf(r), ty) => {
                let r = *r;
                let v = self.coerce(v, ty, span)?;
                let w = match v {
                    SV::Bool(l) => Word::from_bit(l, 1),
                    SV::Int(w, _) => w,
                    _ => return Ok(()),
                };
                if let Type::Subrange { lo, hi, .. } = ty {
                    let (_, signed) = int_sort(ty).unwrap_or((64, true));
                    let ok = self.ops().in_range(&w, signed, *lo as i128, *hi as i128);
                    let (lo, hi) = (*lo, *hi);
                    self.fault(ok.not(), format!("subrange violation: the value is outside {lo}..{hi}"), span);
                }
                self.write_reg(r, w);
                Ok(())
            }
            PlaceRef::Slot(Slot::Opaque(t), _) => {
                if int_sort(t).is_some() {
                    self.note(format!("writes to a `{t}` the model does not hold are ignored"));
                }
                Ok(())
            }
            PlaceRef::Slot(dst, ty) => match v {
                SV::Agg(src, _) => {
                    let mut a = Vec::new();
                    let mut b = Vec::new();
                    self.slot_leaves_deep(dst, &mut a);
                    self.slot_leaves_deep(&src, &mut b);
                    if a.len() != b.len() {
                        return Err(ExprError { span, message: format!("copying `{ty}` values of different shapes") });
                    }
                    let vals: Vec<Word> = b.iter().map(|&r| self.mem[r].clone()).collect();
                    for (r, w) in a.into_iter().zip(vals) {
                        self.write_reg(r, w);
                    }
                    Ok(())
                }
                _ => {
                    let mut a = Vec::new();
                    self.slot_leaves_deep(dst, &mut a);
                    for r in a {
                        let reg = self.regs[r].clone();
                        let w = self.fresh(format!("{} (not modelled)", reg.name), reg.full, reg.signed, None);
                        self.write_reg(r, w);
                    }
                    self.note(format!("an assignment of a `{ty}` value the model does not hold makes the target free"));
                    Ok(())
                }
            },
            PlaceRef::Dyn(cands, ty) => {
                let pc = self.pc;
                for (sel, s) in cands.clone() {
                    self.pc = self.g.and(pc, sel);
                    self.write_place(&PlaceRef::Slot(s, ty.clone()), v.clone(), span)?;
                }
                self.pc = pc;
                Ok(())
            }
            PlaceRef::Bit(r, n) => {
                let b = self.to_bool(v, span)?;
                let mut w = self.mem[*r].clone();
                if *n < w.bits.len() {
                    w.bits[*n] = b;
                }
                self.write_reg(*r, w);
                Ok(())
            }
            _ => Err(ExprError { span, message: "step and action flags cannot be written".into() }),
        }
    }

    /// A call used as a statement: a function block instance, an action (`A();`,
    /// `inst.A();`, with the chart flags of an action written in SFC: `A(SFCReset := x)`), or
    /// a function.
    pub(crate) fn call_stmt(&mut self, f: &Frame, e: &Expr) -> R<()> {
        if let ExprKind::MemberCall { base, member, args } = &e.kind {
            // The instance, or each instance a computed index may select (`Cells[i].Act()`).
            let cands = match self.place(f, base) {
                Ok(PlaceRef::Slot(slot, _)) => vec![(Lit::TRUE, slot)],
                Ok(PlaceRef::Dyn(cands, _)) => cands,
                _ => Vec::new(),
            };
            let mut insts = Vec::new();
            for (sel, slot) in cands {
                let Slot::Fb(inst) = slot else {
                    return Err(ExprError {
                        span: base.span,
                        message: "the instance of this call is not modelled".into(),
                    });
                };
                insts.push((sel, inst));
            }
            if insts.is_empty() {
                return Err(ExprError { span: base.span, message: "the instance of this call is not modelled".into() });
            }
            let pc = self.pc;
            for (sel, inst) in insts {
                self.pc = self.g.and(pc, sel);
                if self.pc == Lit::FALSE {
                    continue;
                }
                let r = self.call_member(f, inst, member, args, e.span);
                self.pc = pc;
                r?;
            }
            self.pc = pc;
            return Ok(());
        }
        let ExprKind::Call { callee, args } = &e.kind else {
            self.eval(f, e, None)?;
            return Ok(());
        };
        if let Some(v) = self.lookup_var(f, &callee.text) {
            if let Type::FunctionBlock(_) = &v.ty {
                return self.fb_call(f, &v.slot, args, e.span, callee);
            }
        }
        if let Some((name, body)) = self.action_of(f.inst, &callee.text) {
            return self.call_action(f, f.inst, &name, body, args, e.span);
        }
        self.call_value(f, callee, args, e.span, None)?;
        Ok(())
    }

    /// `inst.Member(…)`: action `Member` of the instance, or the instance `Member` inside it.
    fn call_member(&mut self, f: &Frame, inst: usize, member: &Ident, args: &[Arg], span: Span) -> R<()> {
        if let Some((name, body)) = self.action_of(inst, &member.text) {
            return self.call_action(f, inst, &name, body, args, span);
        }
        // `inst.Inner(…)`: the instance `Inner` inside `inst` is called.
        let inner = self.insts[inst].vars.iter().find(|v| v.name.eq_ignore_ascii_case(&member.text)).cloned();
        if let Some(v) = inner.filter(|v| matches!(v.ty, Type::FunctionBlock(_))) {
            return self.fb_call(f, &v.slot, args, span, member);
        }
        Err(ExprError {
            span: member.span,
            message: format!("the call of `{}` of an instance cannot be modelled", member.text),
        })
    }

    /// A call of action `name` of instance `inst` from code in frame `f`: the chart flags it
    /// sets (evaluated in the caller), then its body.
    fn call_action(
        &mut self,
        f: &Frame,
        inst: usize,
        name: &str,
        body: &ActionBody,
        args: &[Arg],
        span: Span,
    ) -> R<()> {
        if self.depth > MAX_DEPTH {
            // Refused rather than made free: an action may move charts (its own, written in
            // SFC, or those of instances it calls), which no free value stands for.
            self.refused.get_or_insert(format!("actions call each other more than {MAX_DEPTH} deep (`{name}`)"));
            return Ok(());
        }
        if !args.is_empty() {
            let Some(c) = self.action_chart(inst, name) else {
                return Err(ExprError { span, message: format!("action `{name}` takes no arguments") });
            };
            let flags = self.charts[c].flags.clone();
            let mut sets = Vec::new();
            for a in args {
                let flag = a.name.as_ref().map(|n| n.text.to_ascii_uppercase()).unwrap_or_default();
                let r = match flag.as_str() {
                    "SFCINIT" => flags.init,
                    "SFCRESET" => flags.reset,
                    "SFCPAUSE" => flags.pause,
                    "SFCQUITERROR" => flags.quit,
                    _ => None,
                };
                let (Some(r), Some(v), false) = (r, &a.value, a.output) else {
                    return Err(ExprError {
                        span: a.span,
                        message: format!("a call of action `{name}` sets only its chart's flags"),
                    });
                };
                let l = self.eval_bool(f, v)?;
                sets.push((r, l));
            }
            for (r, l) in sets {
                self.write_reg(r, Word::from_bit(l, 1));
            }
        }
        self.depth += 1;
        self.run_action(inst, name, body);
        self.depth -= 1;
        Ok(())
    }

    /// `inst(IN := x, Q => y)`.
    pub(crate) fn fb_call(&mut self, f: &Frame, slot: &Slot, args: &[Arg], span: Span, name: &Ident) -> R<()> {
        let Slot::Fb(inst) = *slot else {
            // An instance the model does not hold: its output bindings become free.
            for a in args {
                if let (true, Some(v)) = (a.output, &a.value) {
                    self.havoc_target(f, v);
                }
            }
            return Ok(());
        };
        let params: Vec<VarEntry> = self.insts[inst]
            .vars
            .iter()
            .filter(|v| matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::InOut))
            .cloned()
            .collect();
        let positional: Vec<VarEntry> =
            params.iter().filter(|p| matches!(p.kind, VarKind::Input | VarKind::InOut)).cloned().collect();
        let mut inputs = Vec::new();
        let mut in_outs = Vec::new();
        let mut outputs = Vec::new();
        let mut en = None;
        let mut eno = None;
        for (i, a) in args.iter().enumerate() {
            if let Some(n) = &a.name {
                if n.is("EN") && !a.output {
                    en = a.value.as_ref();
                    continue;
                }
                if n.is("ENO") && a.output {
                    eno = a.value.as_ref().map(|v| (v, a.negated));
                    continue;
                }
            }
            let p = match &a.name {
                Some(n) => params.iter().find(|p| p.name.eq_ignore_ascii_case(&n.text)).cloned(),
                None => positional.get(i).cloned(),
            };
            let Some(p) = p else {
                return Err(ExprError { span: a.span, message: format!("`{}` has no such parameter", name.text) });
            };
            let Some(v) = &a.value else { continue };
            match (p.kind, a.output) {
                (VarKind::Output, true) => outputs.push((p, v, a.negated)),
                (VarKind::InOut, false) => in_outs.push((p, v)),
                (VarKind::Input, false) => inputs.push((p, v)),
                _ => return Err(ExprError { span: a.span, message: format!("wrong binding of `{}`", p.name) }),
            }
        }
        let pc = self.pc;
        if let Some(en) = en {
            let g = self.eval_bool(f, en)?;
            if let Some((t, neg)) = eno {
                let tp = self.place(f, t)?;
                self.pc = self.g.and(pc, g.not());
                self.write_place(&tp, SV::Bool(Lit::from_bool(neg)), t.span)?;
            }
            self.pc = self.g.and(pc, g);
        }
        let mut given: Vec<(String, Word)> = Vec::new();
        for (p, v) in &inputs {
            let val = self.eval(f, v, Some(&p.ty))?;
            if let Ok(SV::Int(w, _)) = self.coerce(val.clone(), &p.ty, v.span) {
                given.push((p.name.to_ascii_uppercase(), w));
            }
            self.write_place(&PlaceRef::Slot(p.slot.clone(), p.ty.clone()), val, v.span)?;
        }
        let mut back = Vec::new();
        for (p, v) in &in_outs {
            let caller = self.place(f, v)?;
            let val = self.read_place(&caller, v.span)?;
            self.write_place(&PlaceRef::Slot(p.slot.clone(), p.ty.clone()), val, v.span)?;
            back.push((p.clone(), caller, v.span));
        }
        if self.depth > MAX_DEPTH {
            return Err(ExprError { span, message: "function blocks call each other too deeply".into() });
        }
        self.depth += 1;
        match self.insts[inst].kind.clone() {
            InstKind::Std(k, hidden) => self.run_std_fb(inst, k, &hidden, &given),
            InstKind::User(_) => self.run_body(inst),
        }
        self.depth -= 1;
        for (p, caller, sp) in back {
            let val = self.read_place(&PlaceRef::Slot(p.slot.clone(), p.ty.clone()), sp)?;
            self.write_place(&caller, val, sp)?;
        }
        for (p, target, negated) in outputs {
            let tp = self.place(f, target)?;
            let mut val = self.read_place(&PlaceRef::Slot(p.slot.clone(), p.ty.clone()), target.span)?;
            if negated {
                val = match val {
                    SV::Bool(l) => SV::Bool(l.not()),
                    SV::Int(w, t) => SV::Int(self.ops().not(&w), t),
                    o => o,
                };
            }
            self.write_place(&tp, val, target.span)?;
        }
        if let Some((t, neg)) = eno {
            let tp = self.place(f, t)?;
            self.write_place(&tp, SV::Bool(Lit::from_bool(!neg)), t.span)?;
        }
        self.pc = pc;
        Ok(())
    }

    fn param_reg(&self, inst: usize, name: &str) -> Option<usize> {
        self.insts[inst].vars.iter().find(|v| v.name.eq_ignore_ascii_case(name)).and_then(|v| match v.slot {
            Slot::Leaf(r) => Some(r),
            _ => None,
        })
    }

    /// One call of a standard function block (the simulator's `stdfb::run`).
    /// `given`: the values this call binds to inputs (what the block sees when it runs; the
    /// registers merge them with their old values under the call's path condition).
    fn run_std_fb(&mut self, inst: usize, kind: StdFb, hidden: &[usize], given: &[(String, Word)]) {
        let p = |e: &Enc<'_>, n: &str| e.param_reg(inst, n);
        let b = |e: &Enc<'_>, r: Option<usize>| r.map_or(Lit::FALSE, |r| e.mem[r].bits[0]);
        let period = self.setup.period;
        match kind {
            StdFb::Ton | StdFb::Tof | StdFb::Tp => {
                let (running, count) = (hidden[0], hidden[1]);
                let (inr, ptr, qr, etr) = (p(self, "IN"), p(self, "PT"), p(self, "Q"), p(self, "ET"));
                let (Some(ptr), Some(qr), Some(etr)) = (ptr, qr, etr) else { return };
                let input = b(self, inr);
                let pt =
                    given.iter().find(|(n, _)| n == "PT").map_or_else(|| self.mem[ptr].clone(), |(_, w)| w.clone());
                // The bound of the elapsed counter: the largest PT.
                let key = format!("{}#timer", self.insts[inst].path).to_ascii_uppercase();
                let (_, hi) = pt.bounds(true);
                let need = if hi <= 0 {
                    1
                } else {
                    ((hi + period as i128 - 1) / period as i128).min(super::MAX_COUNT as i128) as u64
                };
                let n = self.learned.need.entry(key).or_insert(0);
                *n = (*n).max(need);
                let run = self.bool_reg(running);
                let cw = self.mem[count].clone();
                let zero = Word::constant(0, cw.width());
                let pt0 = {
                    let neg = *pt.bits.last().unwrap_or(&Lit::FALSE);
                    self.ops().ite(neg, &Word::constant(0, 64), &pt)
                };
                let el_time = |e: &mut Enc<'_>, c: &Word| -> Word {
                    let cw = c.resize(64, false);
                    let pw = Word::constant(period as i128, 64);
                    e.ops().mul(&cw, &pw)
                };
                match kind {
                    StdFb::Ton => {
                        let el = self.ops().ite(run, &cw, &zero);
                        let ge = self.elapsed_ge(&el, &pt, period, count);
                        let q = self.g.and(input, ge);
                        let elt = el_time(self, &el);
                        let et_on = self.ops().ite(ge, &pt0, &elt);
                        let et = self.ops().ite(input, &et_on, &Word::constant(0, 64));
                        self.write_reg(qr, Word::from_bit(q, 1));
                        self.write_reg(etr, et);
                        self.write_reg(running, Word::from_bit(input, 1));
                        let nc = self.ops().ite(input, &el, &zero);
                        self.write_reg(count, nc);
                    }
                    StdFb::Tof => {
                        let q_old = self.bool_reg(qr);
                        let pc = self.pc;
                        // IN: Q, ET = 0, not running.
                        self.pc = self.g.and(pc, input);
                        self.write_reg(qr, Word::constant(1, 1));
                        self.write_reg(etr, Word::constant(0, 64));
                        self.write_reg(running, Word::constant(0, 1));
                        // Falling: time the delay.
                        let off = self.g.and(input.not(), q_old);
                        self.pc = self.g.and(pc, off);
                        if self.pc != Lit::FALSE {
                            let el = self.ops().ite(run, &cw, &zero);
                            let ge = self.elapsed_ge(&el, &pt, period, count);
                            let elt = el_time(self, &el);
                            let et = self.ops().ite(ge, &pt0, &elt);
                            self.write_reg(etr, et);
                            self.write_reg(qr, Word::from_bit(ge.not(), 1));
                            self.write_reg(running, Word::from_bit(ge.not(), 1));
                            self.write_reg(count, el);
                        }
                        self.pc = pc;
                    }
                    _ => {
                        // TP
                        let prev = hidden[2];
                        let prev_v = self.bool_reg(prev);
                        let pc = self.pc;
                        let el = cw.clone();
                        self.pc = self.g.and(pc, run);
                        if self.pc != Lit::FALSE {
                            let ge = self.elapsed_ge(&el, &pt, period, count);
                            let elt = el_time(self, &el);
                            let et = self.ops().ite(ge, &pt0, &elt);
                            self.write_reg(etr, et);
                            self.write_reg(qr, Word::from_bit(ge.not(), 1));
                            self.write_reg(running, Word::from_bit(ge.not(), 1));
                        }
                        let start = {
                            let rise = self.g.and(input, prev_v.not());
                            self.g.and(run.not(), rise)
                        };
                        self.pc = self.g.and(pc, start);
                        if self.pc != Lit::FALSE {
                            let pos = {
                                let z = Word::constant(0, 64);
                                self.ops().lt(&z, &pt, true)
                            };
                            self.write_reg(count, zero.clone());
                            self.write_reg(etr, Word::constant(0, 64));
                            self.write_reg(running, Word::from_bit(pos, 1));
                            self.write_reg(qr, Word::from_bit(pos, 1));
                        }
                        self.pc = pc;
                        let run_now = self.bool_reg(running);
                        let idle = self.g.and(run_now.not(), input.not());
                        self.pc = self.g.and(pc, idle);
                        self.write_reg(etr, Word::constant(0, 64));
                        self.pc = pc;
                        self.write_reg(prev, Word::from_bit(input, 1));
                    }
                }
            }
            StdFb::Ctu | StdFb::Ctd | StdFb::Ctud => {
                let cvr = p(self, "CV");
                let pvr = p(self, "PV");
                let (Some(cvr), Some(pvr)) = (cvr, pvr) else { return };
                let ty = self.regs[cvr].ty.clone();
                let (w, signed) = int_sort(&ty).unwrap_or((16, true));
                let (min, max) = ty.int_range().unwrap_or((-(1 << 15), (1 << 15) - 1));
                let cv = self.mem[cvr].clone();
                let pv = self.mem[pvr].clone();
                let one = Word::constant(1, w);
                let inc = self.ops().add(&cv, &one);
                let dec = self.ops().sub(&cv, &one);
                let below_max = {
                    let m = Word::constant(max, w);
                    self.ops().lt(&cv, &m, signed)
                };
                let above_min = {
                    let m = Word::constant(min, w);
                    self.ops().lt(&m, &cv, signed)
                };
                let zero = Word::constant(0, w);
                let (new, mems): (Word, Vec<(usize, Lit)>) = match kind {
                    StdFb::Ctu => {
                        let cu = b(self, p(self, "CU"));
                        let r = b(self, p(self, "R"));
                        let up = {
                            let a = self.g.and(cu, self.mem[hidden[0]].bits[0].not());
                            self.g.and(a, below_max)
                        };
                        let v = self.ops().ite(up, &inc, &cv);
                        (self.ops().ite(r, &zero, &v), vec![(hidden[0], cu)])
                    }
                    StdFb::Ctd => {
                        let cd = b(self, p(self, "CD"));
                        let ld = b(self, p(self, "LD"));
                        let down = {
                            let a = self.g.and(cd, self.mem[hidden[0]].bits[0].not());
                            self.g.and(a, above_min)
                        };
                        let v = self.ops().ite(down, &dec, &cv);
                        (self.ops().ite(ld, &pv, &v), vec![(hidden[0], cd)])
                    }
                    _ => {
                        let cu = b(self, p(self, "CU"));
                        let cd = b(self, p(self, "CD"));
                        let r = b(self, p(self, "R"));
                        let ld = b(self, p(self, "LD"));
                        let up = self.g.and(cu, self.mem[hidden[0]].bits[0].not());
                        let down = self.g.and(cd, self.mem[hidden[1]].bits[0].not());
                        let both = self.g.and(up, down);
                        let do_up = {
                            let a = self.g.and(up, below_max);
                            self.g.and(a, both.not())
                        };
                        let do_down = {
                            let a = self.g.and(down, above_min);
                            let b2 = self.g.and(a, both.not());
                            self.g.and(b2, do_up.not())
                        };
                        let v = self.ops().ite(do_up, &inc, &cv);
                        let v = self.ops().ite(do_down, &dec, &v);
                        let v = self.ops().ite(ld, &pv, &v);
                        (self.ops().ite(r, &zero, &v), vec![(hidden[0], cu), (hidden[1], cd)])
                    }
                };
                let ge_pv = self.ops().lt(&new, &pv, signed).not();
                let le_0 = self.ops().lt(&zero, &new, signed).not();
                self.write_reg(cvr, new);
                match kind {
                    StdFb::Ctu => {
                        if let Some(q) = p(self, "Q") {
                            self.write_reg(q, Word::from_bit(ge_pv, 1));
                        }
                    }
                    StdFb::Ctd => {
                        if let Some(q) = p(self, "Q") {
                            self.write_reg(q, Word::from_bit(le_0, 1));
                        }
                    }
                    _ => {
                        if let Some(q) = p(self, "QU") {
                            self.write_reg(q, Word::from_bit(ge_pv, 1));
                        }
                        if let Some(q) = p(self, "QD") {
                            self.write_reg(q, Word::from_bit(le_0, 1));
                        }
                    }
                }
                for (r, v) in mems {
                    self.write_reg(r, Word::from_bit(v, 1));
                }
            }
            StdFb::RTrig | StdFb::FTrig => {
                let clk = b(self, p(self, "CLK"));
                let m = self.bool_reg(hidden[0]);
                let q = if kind == StdFb::RTrig { self.g.and(clk, m.not()) } else { self.g.and(clk.not(), m) };
                if let Some(qr) = p(self, "Q") {
                    self.write_reg(qr, Word::from_bit(q, 1));
                }
                self.write_reg(hidden[0], Word::from_bit(clk, 1));
            }
            StdFb::Sr | StdFb::Rs => {
                let Some(q1) = p(self, "Q1") else { return };
                let q = self.bool_reg(q1);
                let v = if kind == StdFb::Sr {
                    let s1 = b(self, p(self, "S1"));
                    let r = b(self, p(self, "R"));
                    let hold = self.g.and(r.not(), q);
                    self.g.or(s1, hold)
                } else {
                    let s = b(self, p(self, "S"));
                    let r1 = b(self, p(self, "R1"));
                    let o = self.g.or(s, q);
                    self.g.and(r1.not(), o)
                };
                self.write_reg(q1, Word::from_bit(v, 1));
            }
        }
    }

    /// A call of user FUNCTION `p`: a fresh frame of temporaries, inlined.
    pub(crate) fn call_function(&mut self, f: &Frame, p: usize, args: &[Arg], span: Span) -> R<SV> {
        if self.depth > MAX_DEPTH {
            return Err(ExprError { span, message: "functions call each other too deeply (recursion?)".into() });
        }
        let iface = self.pous[p].iface.clone();
        let ast = self.pous[p].ast;
        let fname = ast.name.text.clone();
        // The frame: every variable of the function, plus its result.
        let mut vars = Vec::new();
        for v in &iface.vars {
            let slot = self.temp_layout(&format!("{fname}.{}", v.name), &v.ty);
            vars.push(VarEntry {
                name: v.name.clone(),
                kind: v.kind,
                ty: v.ty.clone(),
                slot,
                location: None,
                implicit: false,
            });
        }
        let ret_ty = iface.return_type.clone().unwrap_or(Type::Bool);
        let ret_slot = self.temp_layout(&format!("{fname} (result)"), &ret_ty);
        vars.push(VarEntry {
            name: fname.clone(),
            kind: VarKind::Var,
            ty: ret_ty.clone(),
            slot: ret_slot.clone(),
            location: None,
            implicit: false,
        });
        // Declared initial values (constants only; others start at the type's default).
        for v in &iface.vars {
            if let (Some(sfc_syntax::ast::Initializer::Expr(e)), Some(entry)) =
                (&v.init, vars.iter().find(|x| x.name.eq_ignore_ascii_case(&v.name)).cloned())
            {
                let callee_frame = Frame { inst: f.inst, recorded: false };
                self.frames.push(vars.clone());
                let val = self.eval(&callee_frame, e, Some(&v.ty));
                self.frames.pop();
                if let Ok(val) = val {
                    let pc = self.pc;
                    self.pc = Lit::TRUE;
                    let saved = (self.returned, self.exited);
                    self.returned = Lit::FALSE;
                    self.exited = Lit::FALSE;
                    let _ = self.write_place(&PlaceRef::Slot(entry.slot.clone(), entry.ty.clone()), val, e.span);
                    (self.returned, self.exited) = saved;
                    self.pc = pc;
                }
            }
        }
        // Bind the arguments in the caller's frame.
        let positional: Vec<VarEntry> =
            vars.iter().filter(|v| matches!(v.kind, VarKind::Input | VarKind::InOut)).cloned().collect();
        let mut back = Vec::new();
        for (i, a) in args.iter().enumerate() {
            let target = match &a.name {
                Some(n) => vars.iter().find(|v| v.name.eq_ignore_ascii_case(&n.text)).cloned(),
                None => positional.get(i).cloned(),
            };
            let Some(t) = target else {
                return Err(ExprError { span: a.span, message: format!("`{fname}` has no such parameter") });
            };
            let Some(v) = &a.value else { continue };
            if a.output {
                back.push((t, v.clone(), a.negated));
                continue;
            }
            let val = self.eval(f, v, Some(&t.ty))?;
            self.write_place(&PlaceRef::Slot(t.slot.clone(), t.ty.clone()), val, v.span)?;
            if t.kind == VarKind::InOut {
                back.push((t, v.clone(), false));
            }
        }
        // The body, in the function's frame.
        self.frames.push(vars.clone());
        self.depth += 1;
        let callee = Frame { inst: f.inst, recorded: true };
        let saved_ret = self.returned;
        self.returned = Lit::FALSE;
        match &ast.body {
            sfc_syntax::ast::Body::St(stmts) => self.exec_list(&callee, stmts),
            sfc_syntax::ast::Body::Il(il) => self.exec_il(&callee, il),
            sfc_syntax::ast::Body::Sfc(_) => {}
        }
        self.returned = saved_ret;
        self.depth -= 1;
        self.frames.pop();
        let result = self.read_place(&PlaceRef::Slot(ret_slot, ret_ty), span)?;
        for (t, v, neg) in back {
            let tp = self.place(f, &v)?;
            let mut val = self.read_place(&PlaceRef::Slot(t.slot.clone(), t.ty.clone()), v.span)?;
            if neg {
                if let SV::Bool(l) = val {
                    val = SV::Bool(l.not());
                }
            }
            self.write_place(&tp, val, v.span)?;
        }
        Ok(result)
    }

    /// Temporary registers for a function's frame, at the type's default value.
    fn temp_layout(&mut self, path: &str, ty: &Type) -> Slot {
        match ty {
            Type::Array { dims, elem } => {
                let count: i64 = dims.iter().map(|(lo, hi)| (hi - lo + 1).max(0)).product();
                if count > 1024 {
                    return Slot::Opaque(ty.clone());
                }
                let items = (0..count).map(|k| self.temp_layout(&format!("{path}[{k}]"), elem)).collect();
                Slot::Array { dims: dims.clone(), elem: (**elem).clone(), items }
            }
            Type::Struct { fields, .. } => Slot::Struct {
                ty: ty.clone(),
                fields: fields.iter().map(|(n, t)| (n.clone(), self.temp_layout(&format!("{path}.{n}"), t))).collect(),
            },
            t if int_sort(t).is_some() => {
                let init = match t {
                    Type::Subrange { lo, .. } => *lo as i128,
                    Type::Enum { values, .. } => values.first().map_or(0, |(_, v)| *v as i128),
                    _ => 0,
                };
                Slot::Leaf(self.new_reg(path.to_string(), t.clone(), Role::Temp, init, None))
            }
            _ => Slot::Opaque(ty.clone()),
        }
    }
}

/// 1-based line and column of a byte offset.
pub(crate) fn line_col(text: &str, offset: usize) -> (u32, u32) {
    let offset = offset.min(text.len());
    let before = &text.as_bytes()[..offset];
    let line = before.iter().filter(|b| **b == b'\n').count() as u32 + 1;
    let start = before.iter().rposition(|b| *b == b'\n').map_or(0, |p| p + 1);
    (line, (offset - start) as u32 + 1)
}
