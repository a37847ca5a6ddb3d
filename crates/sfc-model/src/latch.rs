//! SFC0219: an output that a non-stored action sets TRUE and nothing ever sets back.
//!
//! ```text
//! STEP S2: Show(N); END_STEP
//! ACTION Show: Visible := TRUE; END_ACTION      (* Visible stays TRUE after S2 is left *)
//! ```
//!
//! An N (or L, D) action looks as if its effect lasted while the step is active, but an
//! assignment in its body is stored in the variable: once S2 has been active, `Visible` is TRUE
//! for good unless something else writes it. The rule fires only when nothing in the POU can:
//! no other assignment, no IL store or reset, no output binding of a call, no association of
//! the variable itself as an action.

use crate::chart::{ActionTarget, Chart, Qualifier};
use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{self, ActionBody, ExprKind, LiteralKind, StmtKind};
use std::collections::HashMap;

/// How one place in the POU writes a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Write {
    /// `x := TRUE`, IL `S x`.
    True,
    /// Anything else: another value, `NOT x`, a store, a reset, an output binding.
    Other,
}

/// `(upper-case name, write, span, action index)` for every whole-variable write in the
/// chart's action bodies.
fn writes(chart: &Chart) -> Vec<(String, Write, Span, usize)> {
    let mut out = Vec::new();
    for (i, a) in chart.actions.iter().enumerate() {
        match &a.body {
            ActionBody::St(stmts) => st_writes(stmts, i, &mut out),
            ActionBody::Il(body) => il_writes(&body.instructions, i, &mut out),
            // Runs its own chart, whose steps name the POU's actions (checked with them).
            ActionBody::Sfc(_) => {}
        }
    }
    out
}

fn name_of(e: &ast::Expr) -> Option<&ast::Ident> {
    match &e.kind {
        ExprKind::Name(id) => Some(id),
        ExprKind::Paren(inner) => name_of(inner),
        _ => None,
    }
}

fn is_true(e: &ast::Expr) -> bool {
    match &e.kind {
        ExprKind::Literal(l) => matches!(l.kind, LiteralKind::Bool(true)),
        ExprKind::Paren(inner) => is_true(inner),
        _ => false,
    }
}

fn call_outputs(e: &ast::Expr, action: usize, out: &mut Vec<(String, Write, Span, usize)>) {
    if let ExprKind::Call { args, .. } = &e.kind {
        for a in args.iter().filter(|a| a.output) {
            if let Some(id) = a.value.as_ref().and_then(name_of) {
                out.push((id.text.to_ascii_uppercase(), Write::Other, id.span, action));
            }
        }
    }
}

fn st_writes(stmts: &[ast::Stmt], action: usize, out: &mut Vec<(String, Write, Span, usize)>) {
    for s in stmts {
        match &s.kind {
            StmtKind::Assign { target, value } => {
                if let Some(id) = name_of(target) {
                    let w = if is_true(value) { Write::True } else { Write::Other };
                    out.push((id.text.to_ascii_uppercase(), w, s.span, action));
                }
            }
            StmtKind::Call(call) => call_outputs(call, action, out),
            StmtKind::If { branches, else_body } => {
                for (_, body) in branches {
                    st_writes(body, action, out);
                }
                if let Some(body) = else_body {
                    st_writes(body, action, out);
                }
            }
            StmtKind::Case { arms, else_body, .. } => {
                for arm in arms {
                    st_writes(&arm.body, action, out);
                }
                if let Some(body) = else_body {
                    st_writes(body, action, out);
                }
            }
            StmtKind::For { var, body, .. } => {
                out.push((var.text.to_ascii_uppercase(), Write::Other, var.span, action));
                st_writes(body, action, out);
            }
            StmtKind::While { body, .. } | StmtKind::Repeat { body, .. } => st_writes(body, action, out),
            StmtKind::Exit | StmtKind::Return | StmtKind::Empty | StmtKind::RefAssign { .. } => {}
        }
    }
}

fn il_writes(instructions: &[ast::IlInstruction], action: usize, out: &mut Vec<(String, Write, Span, usize)>) {
    for ins in instructions {
        if let Some(nested) = &ins.nested {
            il_writes(nested, action, out);
        }
        let Some(op) = &ins.op else { continue };
        let op = op.text.to_ascii_uppercase();
        for operand in &ins.operands {
            match op.as_str() {
                "S" => {
                    if let Some(id) = name_of(operand) {
                        out.push((id.text.to_ascii_uppercase(), Write::True, ins.span, action));
                    }
                }
                "ST" | "STN" | "R" => {
                    if let Some(id) = name_of(operand) {
                        out.push((id.text.to_ascii_uppercase(), Write::Other, ins.span, action));
                    }
                }
                _ => call_outputs(operand, action, out),
            }
        }
    }
}

/// The BOOL outputs of a POU: `VAR_OUTPUT`, or located at `%Q`. Upper-case name → declared
/// spelling.
fn outputs(pou: &ast::Pou) -> HashMap<String, String> {
    let mut out = HashMap::new();
    for b in &pou.var_blocks {
        for d in &b.decls {
            let is_bool = matches!(&d.ty.kind, ast::TypeSpecKind::Named(id) if id.is("BOOL"));
            let located_q = d.location.as_ref().is_some_and(|l| l.area.eq_ignore_ascii_case(&'Q'));
            if is_bool && (b.kind == ast::VarKind::Output || located_q) {
                for n in &d.names {
                    out.insert(n.text.to_ascii_uppercase(), n.text.clone());
                }
            }
        }
    }
    out
}

/// SFC0219 for every output of `pou` latched by a non-stored action of `chart`.
pub fn latched_outputs(pou: &ast::Pou, chart: &Chart, diags: &mut Vec<Diagnostic>) {
    let outputs = outputs(pou);
    if outputs.is_empty() {
        return;
    }
    let writes = writes(chart);
    // An output associated as an action follows Q every scan: it is reset by the chart itself.
    let associated: Vec<String> = chart
        .steps
        .iter()
        .flat_map(|s| &s.associations)
        .filter(|a| a.target == ActionTarget::Variable)
        .map(|a| a.action.to_ascii_uppercase())
        .collect();
    let mut reported: Vec<String> = Vec::new();
    for (name, w, span, action) in &writes {
        let Some(declared) = outputs.get(name) else { continue };
        if *w != Write::True || reported.contains(name) || associated.contains(name) {
            continue;
        }
        if writes.iter().any(|(n, w, _, _)| n == name && *w == Write::Other) {
            continue;
        }
        let Some(act) = chart.actions.get(*action) else { continue };
        // The steps that run this action without storing it (N, L, D).
        let steps: Vec<(&str, Qualifier)> = chart
            .steps
            .iter()
            .flat_map(|s| s.associations.iter().map(move |a| (s, a)))
            .filter(|(_, a)| a.target == ActionTarget::Action(*action))
            .filter(|(_, a)| matches!(a.qualifier, Qualifier::N | Qualifier::L | Qualifier::D))
            .map(|(s, a)| (s.name.as_str(), a.qualifier))
            .collect();
        let Some((step, qualifier)) = steps.first() else { continue };
        reported.push(name.clone());
        diags.push(
            Diagnostic::warning(
                "SFC0219",
                *span,
                format!(
                    "`{declared}` is set TRUE by action `{}` ({} in step {step}) and nothing sets it back: it stays TRUE after {step} is left",
                    act.name,
                    qualifier.name()
                ),
            )
            .with_element(&act.name)
            .with_note(format!("no statement of `{}` writes anything else to `{declared}`", chart.pou))
            .with_note(format!(
                "help: associate the output itself (`{declared}({})`) so it follows the step, or reset it: `{declared} := FALSE` in another step, an R association, or `IF NOT {}.Q THEN {declared} := FALSE; END_IF` for the action's last run",
                qualifier.name(),
                act.name
            )),
        );
    }
}
