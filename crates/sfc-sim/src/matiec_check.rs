//! `sfc check --profile matiec`: warnings on the elements whose behaviour under MatIEC (Beremiz,
//! OpenPLC v3) differs from `iec` in a way the chart can observe, one code per difference
//! (`SFC0901`–`SFC0908`, see `sfc check --explain`). The rules follow what the `matiec` engine
//! path (`engine/matiec.rs`) transcribes from MatIEC's generated C.

use crate::timespec::Timespec;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::{ActionTarget, Chart, Duration, Qualifier};
use sfc_syntax::ast::{BinaryOp, Condition, Expr, ExprKind, LiteralKind};

/// The differences of every chart of a checked file; `source` is the file's text.
pub fn differences(charts: &[Chart], source: &str) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for c in charts {
        chart(c, source, &mut out);
    }
    out
}

fn target_key(c: &Chart, a: &sfc_model::Association) -> String {
    match a.target {
        ActionTarget::Action(id) => format!("action:{}", c.actions[id].name.to_ascii_uppercase()),
        ActionTarget::Variable => format!("var:{}", a.action.to_ascii_uppercase()),
    }
}

fn chart(c: &Chart, _source: &str, out: &mut Vec<Diagnostic>) {
    let step_name = |s: usize| c.steps[s].name.as_str();
    // SFC0901: scan 0 tests the transitions of the initial steps.
    for t in &c.transitions {
        if tested_at_start(c, t) {
            let steps: Vec<&str> = t.from.iter().map(|&s| step_name(s)).collect();
            out.push(
                Diagnostic::warning(
                    "SFC0901",
                    t.header_span,
                    format!("{} is already tested in scan 0 under MatIEC", t.name),
                )
                .with_element(&t.name)
                .with_note(format!(
                    "IEC runs only the actions of {} in scan 0; MatIEC also fires {} then if its condition holds, \
                     so {} is left before its actions ever run",
                    steps.join(", "),
                    t.name,
                    steps.join(", ")
                )),
            );
        }
    }
    // SFC0902: every TRUE unprioritised alternative fires, and unprioritised ones tested before a
    // prioritised one fire with it.
    let order = crate::engine::matiec_test_order(c);
    for (i, &ti) in order.iter().enumerate() {
        let t = &c.transitions[ti as usize];
        for &tj in &order[..i] {
            let earlier = &c.transitions[tj as usize];
            let shared: Vec<usize> = t.from.iter().copied().filter(|s| earlier.from.contains(s)).collect();
            if shared.is_empty() || t.priority.is_some() && earlier.priority.is_some() {
                continue;
            }
            // An earlier prioritised transition clears the step at once: a later one cannot fire.
            if earlier.priority.is_some() {
                continue;
            }
            out.push(
                Diagnostic::warning(
                    "SFC0902",
                    t.header_span,
                    format!("{} fires together with {} under MatIEC when both are TRUE", t.name, earlier.name),
                )
                .with_element(&t.name)
                .with_note(format!(
                    "both leave {}; IEC fires only {} (explicit PRIORITY first, then declaration order), MatIEC fires \
                     every TRUE transition whose steps are active when it is tested",
                    step_name(shared[0]),
                    if earlier.priority.is_none() && t.priority.is_some() { &t.name } else { &earlier.name }
                )),
            );
            break;
        }
    }
    // SFC0903: a guard reading `S.X` of a step that a prioritised transition tested before it
    // may already have cleared.
    for (i, &ti) in order.iter().enumerate() {
        let t = &c.transitions[ti as usize];
        let Condition::St(e) = &t.condition else { continue };
        let mut reads = Vec::new();
        step_flags(e, &mut reads);
        for (name, span) in reads {
            let Some(s) = c.steps.iter().position(|st| st.name.eq_ignore_ascii_case(&name)) else { continue };
            if let Some(&tp) = order[..i].iter().find(|&&tp| {
                let p = &c.transitions[tp as usize];
                p.priority.is_some() && p.from.contains(&s)
            }) {
                let p = &c.transitions[tp as usize];
                out.push(
                    Diagnostic::warning(
                        "SFC0903",
                        span,
                        format!("{name}.X is read after {} may have cleared it under MatIEC", p.name),
                    )
                    .with_element(&t.name)
                    .with_note(format!(
                        "{} has a PRIORITY: when it fires, MatIEC clears {name} at once, so {} sees {name}.X FALSE in \
                         the same scan (IEC: every condition sees the situation at the start of the scan)",
                        p.name, t.name
                    )),
                );
            }
        }
    }
    // Associations, in MatIEC's writing order (steps in declaration order).
    let mut seen: Vec<(String, usize, Qualifier)> = Vec::new();
    for (s, step) in c.steps.iter().enumerate() {
        for a in &step.associations {
            let key = target_key(c, a);
            let is_var = a.target == ActionTarget::Variable;
            let earlier: Vec<&(String, usize, Qualifier)> =
                seen.iter().filter(|(k, st, _)| *k == key && *st != s).collect();
            // SFC0904: a later association writes FALSE over an earlier one's TRUE.
            let writes_true = |q: Qualifier| {
                matches!(q, Qualifier::N | Qualifier::L | Qualifier::D | Qualifier::P | Qualifier::P1 | Qualifier::P0)
            };
            if let Some((_, es, eq)) = earlier.iter().find(|(_, _, q)| writes_true(*q)) {
                let when = match a.qualifier {
                    Qualifier::N | Qualifier::D => Some(format!("in the scan {} is left", step.name)),
                    Qualifier::L => {
                        Some(format!("while {} is active past its time and in the scan it is left", step.name))
                    }
                    Qualifier::P | Qualifier::P1 => Some(format!("in every scan {} is not just activated", step.name)),
                    Qualifier::P0 => Some(format!("in every scan {} is not just left", step.name)),
                    _ => None,
                };
                if let Some(when) = when {
                    out.push(
                        Diagnostic::warning(
                            "SFC0904",
                            a.span,
                            format!(
                                "this {} association of {} on {} switches it off {} under MatIEC",
                                a.qualifier.name(),
                                a.action,
                                step.name,
                                when
                            ),
                        )
                        .with_element(&step.name)
                        .with_note(format!(
                            "MatIEC writes the associations one after the other, steps in declaration order; this one \
                             writes FALSE after {}({}) on {} wrote TRUE (IEC ORs the associations)",
                            a.action,
                            eq.name(),
                            step_name(*es)
                        )),
                    );
                }
            }
            // SFC0905: R does not stop an action's continuous associations.
            if a.qualifier == Qualifier::R && !is_var {
                let others: Vec<&sfc_model::Association> = c
                    .steps
                    .iter()
                    .flat_map(|st| &st.associations)
                    .filter(|b| target_key(c, b) == key && writes_true(b.qualifier))
                    .collect();
                if let Some(b) = others.first() {
                    out.push(
                        Diagnostic::warning(
                            "SFC0905",
                            a.span,
                            format!(
                                "R on {} does not stop {} of {} under MatIEC",
                                step.name,
                                b.qualifier.name(),
                                a.action
                            ),
                        )
                        .with_element(&step.name)
                        .with_note(
                            "MatIEC's R only clears the stored flag (S, SD, DS, SL); an N, L, D, P association keeps \
                             running the action (IEC: R overrides every qualifier)",
                        ),
                    );
                }
            }
            // SFC0906: timed associations that start on activation / use the step's timer.
            let dur = a.duration.as_ref().map(|d| match d {
                Duration::Literal(us) => *us,
                Duration::Variable(_) => -1,
            });
            let msg = match a.qualifier {
                Qualifier::SD | Qualifier::DS | Qualifier::SL if step.initial => {
                    Some(format!("{} on the initial step {} never acts under MatIEC", a.qualifier.name(), step.name))
                }
                Qualifier::SD | Qualifier::DS if dur == Some(0) => {
                    Some(format!("{} with T#0s never acts under MatIEC", a.qualifier.name()))
                }
                Qualifier::SL if dur == Some(0) => Some("SL with T#0s stays stored until R under MatIEC".to_string()),
                Qualifier::L | Qualifier::D
                    if c.transitions.iter().any(|t| t.from.contains(&s) && t.to.contains(&s)) =>
                {
                    Some(format!("{} restarts when {} loops to itself under MatIEC", a.qualifier.name(), step.name))
                }
                _ => None,
            };
            if let Some(m) = msg {
                out.push(Diagnostic::warning("SFC0906", a.span, m).with_element(&step.name).with_note(
                    "MatIEC starts SD, DS and SL on the step's activation edge (an initial step has none) and counts \
                     them down from the duration (T#0s: SD never sets, SL never resets); L and D compare the step's \
                     own time, which a self-loop restarts",
                ));
            }
            // SFC0908: P1/P0 on a BOOL variable set it for one scan.
            if is_var && matches!(a.qualifier, Qualifier::P1 | Qualifier::P0) {
                out.push(
                    Diagnostic::warning(
                        "SFC0908",
                        a.span,
                        format!(
                            "{}({}) sets {} TRUE for one scan under MatIEC",
                            a.action,
                            a.qualifier.name(),
                            a.action
                        ),
                    )
                    .with_element(&step.name)
                    .with_note(format!(
                        "MatIEC treats {} as a pulse that writes the variable; IEC runs P1/P0 with Q FALSE, so a BOOL \
                         variable used as the action stays FALSE",
                        a.qualifier.name()
                    )),
                );
            }
            // SFC0907 (durations): L/D with a whole-second duration act one scan longer / later.
            if matches!(a.qualifier, Qualifier::L | Qualifier::D) {
                if let Some(Duration::Literal(us)) = &a.duration {
                    if *us > 0 && us % 1_000_000 == 0 {
                        out.push(time_warning(
                            a.span,
                            &step.name,
                            format!(
                                "{} {} acts one scan {} under MatIEC when the scan period divides one second",
                                a.qualifier.name(),
                                sfc_syntax_time(*us),
                                if a.qualifier == Qualifier::L { "longer" } else { "later" }
                            ),
                        ));
                    }
                }
            }
            seen.push((key, s, a.qualifier));
        }
    }
    // SFC0907: step-time comparisons with literals that MatIEC computes differently.
    for t in &c.transitions {
        let Condition::St(e) = &t.condition else { continue };
        let mut found = Vec::new();
        time_compares(e, &mut found);
        for (op, lit, span) in found {
            let Some(ts) = Timespec::from_literal(&lit) else { continue };
            let us = sfc_sim_us(&lit);
            let truncated = ts.sec * 1_000_000_000 + ts.nsec != us * 1000;
            let whole = us > 0 && us % 1_000_000 == 0;
            let m = match op {
                BinaryOp::Gt | BinaryOp::Le | BinaryOp::Eq | BinaryOp::Ne if truncated => Some(format!(
                    "{lit} is {}.{:09} s in MatIEC's C: this comparison changes one scan earlier under MatIEC",
                    ts.sec, ts.nsec
                )),
                BinaryOp::Ge | BinaryOp::Lt | BinaryOp::Eq | BinaryOp::Ne if whole => Some(format!(
                    "a step time of exactly {lit} compares below {lit} under MatIEC (whole seconds are not carried)"
                )),
                _ => None,
            };
            if let Some(m) = m {
                out.push(time_warning(span, &t.name, m));
            }
        }
    }
}

fn time_warning(span: Span, element: &str, message: String) -> Diagnostic {
    Diagnostic::warning("SFC0907", span, message).with_element(element).with_note(
        "MatIEC converts TIME literals with x86-64 long double arithmetic and truncates (T#4ms = 3.999999 ms), \
         and its step time keeps {0 s, 1 000 000 000 ns} at a whole second, which compares below T#1s",
    )
}

fn sfc_syntax_time(us: i64) -> String {
    crate::value::format_time(us)
}

fn sfc_sim_us(lit: &str) -> i64 {
    crate::value::parse_time(lit).unwrap_or(0)
}

/// Whether a condition needs some step time above zero (`S.T >= T#20ms AND …`): FALSE in scan 0,
/// where every step time is zero.
/// A transition that leaves initial steps only and may be TRUE from the start (not a literal
/// FALSE, not waiting for a step time): a profile that tests transitions in the first scan may
/// fire it there.
pub(crate) fn tested_at_start(c: &Chart, t: &sfc_model::TransitionNode) -> bool {
    let literal_false = matches!(&t.condition, Condition::St(Expr { kind: ExprKind::Literal(l), .. })
        if matches!(l.kind, LiteralKind::Bool(false)));
    let waits = matches!(&t.condition, Condition::St(e) if waits_for_time(e));
    !literal_false && !waits && t.from.iter().all(|&s| c.steps[s].initial)
}

fn waits_for_time(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Paren(x) => waits_for_time(x),
        ExprKind::Binary { op: BinaryOp::And | BinaryOp::AndThen, lhs, rhs } => {
            waits_for_time(lhs) || waits_for_time(rhs)
        }
        ExprKind::Binary { op: op @ (BinaryOp::Ge | BinaryOp::Gt), lhs, rhs } => {
            let step_time =
                matches!(&lhs.kind, ExprKind::Member { member, .. } if member.text.eq_ignore_ascii_case("T"));
            let lit = match &rhs.kind {
                ExprKind::Literal(l) => match l.kind {
                    LiteralKind::Duration(us) => Some(us),
                    _ => None,
                },
                _ => None,
            };
            step_time && lit.is_some_and(|us| us > 0 || *op == BinaryOp::Gt)
        }
        _ => false,
    }
}

/// `S.X` reads in a guard: (step name, span).
fn step_flags(e: &Expr, out: &mut Vec<(String, Span)>) {
    match &e.kind {
        ExprKind::Member { base, member } if member.text.eq_ignore_ascii_case("X") => {
            if let ExprKind::Name(n) = &base.kind {
                out.push((n.text.clone(), e.span));
            }
        }
        ExprKind::Unary { operand, .. } => step_flags(operand, out),
        ExprKind::Binary { lhs, rhs, .. } => {
            step_flags(lhs, out);
            step_flags(rhs, out);
        }
        ExprKind::Paren(x) => step_flags(x, out),
        _ => {}
    }
}

/// Comparisons of `S.T` with a TIME literal, normalised to `S.T op literal`.
fn time_compares(e: &Expr, out: &mut Vec<(BinaryOp, String, Span)>) {
    let step_time =
        |x: &Expr| matches!(&x.kind, ExprKind::Member { member, .. } if member.text.eq_ignore_ascii_case("T"));
    let literal = |x: &Expr| match &x.kind {
        ExprKind::Literal(l) if matches!(l.kind, LiteralKind::Duration(_)) => Some(l.text.clone()),
        _ => None,
    };
    match &e.kind {
        ExprKind::Binary { op, lhs, rhs } => {
            let flipped = match op {
                BinaryOp::Gt => BinaryOp::Lt,
                BinaryOp::Lt => BinaryOp::Gt,
                BinaryOp::Ge => BinaryOp::Le,
                BinaryOp::Le => BinaryOp::Ge,
                o => *o,
            };
            if step_time(lhs) {
                if let Some(l) = literal(rhs) {
                    out.push((*op, l, e.span));
                }
            } else if step_time(rhs) {
                if let Some(l) = literal(lhs) {
                    out.push((flipped, l, e.span));
                }
            }
            time_compares(lhs, out);
            time_compares(rhs, out);
        }
        ExprKind::Unary { operand, .. } => time_compares(operand, out),
        ExprKind::Paren(x) => time_compares(x, out),
        _ => {}
    }
}
