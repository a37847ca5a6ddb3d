//! Every expression of a POU, outermost first: for checks that look for one shape anywhere in
//! the code (a program reached into as `Main.X`, a pointer dereferenced) without a walker of
//! their own. Nesting is bounded by the parser's depth limits.

use crate::ast::*;

/// Calls `f` on every expression of `pou`: initial values, statements, IL operands, transition
/// conditions and priorities, durations and step actions of its charts, its actions', methods'
/// and properties' code. Each expression is visited, then its parts.
pub fn pou_exprs(pou: &Pou, f: &mut dyn FnMut(&Expr)) {
    var_blocks(&pou.var_blocks, f);
    body(&pou.body, f);
    for a in &pou.actions {
        action_body(&a.body, f);
    }
    for m in &pou.methods {
        var_blocks(&m.var_blocks, f);
        body(&m.body, f);
    }
    for p in &pou.properties {
        for acc in [&p.get, &p.set].into_iter().flatten() {
            var_blocks(&acc.var_blocks, f);
            body(&acc.body, f);
        }
    }
}

fn var_blocks(blocks: &[VarBlock], f: &mut dyn FnMut(&Expr)) {
    for d in blocks.iter().flat_map(|b| &b.decls) {
        if let Some(i) = &d.init {
            initializer(i, f);
        }
    }
}

fn initializer(i: &Initializer, f: &mut dyn FnMut(&Expr)) {
    match i {
        Initializer::Expr(e) => expr(e, f),
        Initializer::Array { elements, .. } => {
            for el in elements {
                if let Some(r) = &el.repeat {
                    expr(r, f);
                }
                if let Some(v) = &el.value {
                    initializer(v, f);
                }
            }
        }
        Initializer::Struct { fields, .. } => fields.iter().for_each(|(_, v)| initializer(v, f)),
    }
}

fn body(b: &Body, f: &mut dyn FnMut(&Expr)) {
    match b {
        Body::St(s) => stmts(s, f),
        Body::Il(il) => instructions(&il.instructions, f),
        Body::Sfc(elements) => sfc(elements, f),
    }
}

fn action_body(b: &ActionBody, f: &mut dyn FnMut(&Expr)) {
    match b {
        ActionBody::St(s) => stmts(s, f),
        ActionBody::Il(il) => instructions(&il.instructions, f),
        ActionBody::Sfc(elements) => sfc(elements, f),
    }
}

fn sfc(elements: &[SfcElement], f: &mut dyn FnMut(&Expr)) {
    for e in elements {
        match e {
            SfcElement::Step(s) => {
                for a in &s.associations {
                    if let Some(d) = &a.duration {
                        expr(d, f);
                    }
                }
                for sa in &s.step_actions {
                    expr(&sa.action, f);
                }
            }
            SfcElement::Transition(t) => {
                if let Some(p) = &t.priority {
                    expr(p, f);
                }
                match &t.condition {
                    Condition::St(c) => expr(c, f),
                    Condition::Il(il) => instructions(&il.instructions, f),
                    Condition::Missing => {}
                }
            }
            SfcElement::Action(a) => action_body(&a.body, f),
        }
    }
}

fn instructions(list: &[IlInstruction], f: &mut dyn FnMut(&Expr)) {
    for i in list {
        i.operands.iter().for_each(|e| expr(e, f));
        if let Some(n) = &i.nested {
            instructions(n, f);
        }
        if let Some(args) = &i.call_args {
            args.iter().filter_map(|a| a.value.as_ref()).for_each(|e| expr(e, f));
        }
    }
}

fn stmts(list: &[Stmt], f: &mut dyn FnMut(&Expr)) {
    for s in list {
        match &s.kind {
            StmtKind::Assign { target, value } | StmtKind::RefAssign { target, value } => {
                expr(target, f);
                expr(value, f);
            }
            StmtKind::Call(c) => expr(c, f),
            StmtKind::If { branches, else_body } => {
                for (c, b) in branches {
                    expr(c, f);
                    stmts(b, f);
                }
                if let Some(b) = else_body {
                    stmts(b, f);
                }
            }
            StmtKind::Case { selector, arms, else_body } => {
                expr(selector, f);
                for arm in arms {
                    for l in &arm.labels {
                        match l {
                            CaseLabel::Value(v) => expr(v, f),
                            CaseLabel::Range(a, b) => {
                                expr(a, f);
                                expr(b, f);
                            }
                        }
                    }
                    stmts(&arm.body, f);
                }
                if let Some(b) = else_body {
                    stmts(b, f);
                }
            }
            StmtKind::For { from, to, by, body, .. } => {
                expr(from, f);
                expr(to, f);
                if let Some(b) = by {
                    expr(b, f);
                }
                stmts(body, f);
            }
            StmtKind::While { cond, body } => {
                expr(cond, f);
                stmts(body, f);
            }
            StmtKind::Repeat { body, until } => {
                stmts(body, f);
                expr(until, f);
            }
            StmtKind::Exit | StmtKind::Return | StmtKind::Empty => {}
        }
    }
}

/// `e`, then its parts.
pub fn expr(e: &Expr, f: &mut dyn FnMut(&Expr)) {
    f(e);
    match &e.kind {
        ExprKind::Literal(_) | ExprKind::Name(_) | ExprKind::Address(_) | ExprKind::Error => {}
        ExprKind::Member { base, .. } | ExprKind::Paren(base) | ExprKind::Deref(base) => expr(base, f),
        ExprKind::Unary { operand, .. } => expr(operand, f),
        ExprKind::Index { base, indices } => {
            expr(base, f);
            indices.iter().for_each(|i| expr(i, f));
        }
        ExprKind::Call { args, .. } => args.iter().filter_map(|a| a.value.as_ref()).for_each(|v| expr(v, f)),
        ExprKind::MemberCall { base, args, .. } => {
            expr(base, f);
            args.iter().filter_map(|a| a.value.as_ref()).for_each(|v| expr(v, f));
        }
        ExprKind::Binary { lhs, rhs, .. } => {
            expr(lhs, f);
            expr(rhs, f);
        }
    }
}
