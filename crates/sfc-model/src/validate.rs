//! Structural rules of a lowered chart (SFC02xx) and the ATMT/EATMT target rules (SFC04xx).

use crate::chart::*;
use sfc_diagnostics::Diagnostic;
use sfc_syntax::ast::{self, ExprKind};

/// Structural validation: initial steps per network, connections, ways out, unused actions,
/// duplicate transitions.
pub fn structure(chart: &Chart, source: &str, diags: &mut Vec<Diagnostic>) {
    if chart.steps.is_empty() {
        return;
    }
    let initial = chart.initial_steps();
    let adj = chart.adjacency();
    if initial.is_empty() {
        diags.push(
            Diagnostic::error("SFC0201", chart.name_span, format!("chart `{}` has no initial step", chart.pou))
                .with_element(&chart.pou)
                .with_note("mark the step the sequence starts in with INITIAL_STEP"),
        );
    }
    for net in chart.networks() {
        let inits: Vec<StepId> = net.iter().copied().filter(|&s| chart.steps[s].initial).collect();
        for &extra in inits.iter().skip(1) {
            let first = &chart.steps[inits[0]];
            let s = &chart.steps[extra];
            diags.push(
                Diagnostic::error(
                    "SFC0202",
                    s.name_span,
                    format!("`{}` is a second initial step in the network of `{}`", s.name, first.name),
                )
                .with_element(&s.name)
                .with_label(first.name_span, "first initial step")
                .with_note("a connected network of steps has exactly one initial step"),
            );
        }
        let connected = net.len() > 1 || !adj.outgoing[net[0]].is_empty() || !adj.incoming[net[0]].is_empty();
        if inits.is_empty() && !initial.is_empty() && connected {
            let s = &chart.steps[net[0]];
            let names: Vec<&str> = net.iter().take(4).map(|&i| chart.steps[i].name.as_str()).collect();
            diags.push(
                Diagnostic::error(
                    "SFC0201",
                    s.name_span,
                    format!("the network of steps {} has no initial step", names.join(", ")),
                )
                .with_element(&s.name)
                .with_note("it is not connected to any initial step, so it can never become active"),
            );
        }
    }
    for (i, s) in chart.steps.iter().enumerate() {
        let out = &adj.outgoing[i];
        let inc = &adj.incoming[i];
        if !s.initial && out.is_empty() && inc.is_empty() {
            diags.push(
                Diagnostic::error(
                    "SFC0203",
                    s.name_span,
                    format!("step `{}` is not connected to any transition", s.name),
                )
                .with_element(&s.name),
            );
        } else if out.is_empty()
            && !s.is_final
            && (!inc.is_empty() || chart.steps.len() > 1)
            && !(s.initial && inc.is_empty())
        {
            diags.push(
                Diagnostic::warning("SFC0213", s.name_span, format!("step `{}` has no outgoing transition", s.name))
                    .with_element(&s.name)
                    .with_note(
                        "the sequence ends here; if that is intended, mark it with {attribute 'sfc.final' := 'true'}",
                    ),
            );
        }
    }
    // Duplicate transitions: same steps and the same condition text.
    let cond_text = |t: &TransitionNode| -> Option<String> {
        let span = match &t.condition {
            ast::Condition::St(e) => e.span,
            ast::Condition::Il(b) => b.span,
            ast::Condition::Missing => return None,
        };
        let s = source.get(span.range())?;
        Some(s.split_whitespace().collect::<String>().to_ascii_uppercase())
    };
    let mut seen: std::collections::HashMap<(Vec<StepId>, Vec<StepId>, String), TransitionId> =
        std::collections::HashMap::new();
    for (j, b) in chart.transitions.iter().enumerate() {
        let Some(text) = cond_text(b) else { continue };
        if b.from.is_empty() {
            continue;
        }
        match seen.entry((sorted(&b.from), sorted(&b.to), text)) {
            std::collections::hash_map::Entry::Occupied(first) => {
                let a = &chart.transitions[*first.get()];
                diags.push(
                    Diagnostic::warning(
                        "SFC0215",
                        b.header_span,
                        format!("transition `{}` repeats transition `{}`", b.name, a.name),
                    )
                    .with_element(&b.name)
                    .with_label(a.header_span, "same steps and condition here"),
                );
            }
            std::collections::hash_map::Entry::Vacant(v) => {
                v.insert(j);
            }
        }
    }
}

fn sorted(v: &[StepId]) -> Vec<StepId> {
    let mut v = v.to_vec();
    v.sort_unstable();
    v
}

/// Limits of a REX automaton block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    pub states: u32,
    pub conditions: u32,
    pub rules: u32,
}

impl Limits {
    /// The block's limits, with `--nstep` / `--ntr` overrides.
    pub fn of(target: Target, nstep: Option<u32>, ntr: Option<u32>) -> Limits {
        let base = match target {
            Target::Atmt => Limits { states: 16, conditions: 16, rules: 64 },
            _ => Limits { states: 256, conditions: 256, rules: 1024 },
        };
        Limits { states: nstep.unwrap_or(base.states), conditions: base.conditions, rules: ntr.unwrap_or(base.rules) }
    }
}

/// An ATMT/EATMT condition input: its index and whether it is negated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConditionInput {
    pub index: u32,
    pub negated: bool,
}

impl ConditionInput {
    /// The code in the transition table: the index, or `1000 + index` when negated.
    pub fn code(self) -> u32 {
        if self.negated {
            1000 + self.index
        } else {
            self.index
        }
    }
}

/// `C3` → 3 (ATMT names its inputs C0…C15, EATMT c0…c255; identifiers are case-insensitive).
fn input_index(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(['c', 'C'])?;
    if rest.is_empty() || !rest.chars().all(|c| c.is_ascii_digit()) || (rest.len() > 1 && rest.starts_with('0')) {
        return None;
    }
    rest.parse().ok()
}

/// Reads a transition condition as one ATMT/EATMT input, if it is one.
pub fn condition_input(cond: &ast::Condition, target: Target) -> Option<ConditionInput> {
    let ast::Condition::St(e) = cond else { return None };
    fn strip(e: &ast::Expr) -> &ast::Expr {
        match &e.kind {
            ExprKind::Paren(i) => strip(i),
            _ => e,
        }
    }
    let e = strip(e);
    let (negated, inner) = match &e.kind {
        ExprKind::Unary { op: ast::UnaryOp::Not, operand } => (true, strip(operand)),
        _ => (false, e),
    };
    let index = match &inner.kind {
        ExprKind::Name(n) => input_index(&n.text)?,
        // EATMT `cX.Y` = 16·X + Y
        ExprKind::Member { base, member } if target == Target::Eatmt => {
            let ExprKind::Name(n) = &base.kind else { return None };
            let x = input_index(&n.text)?;
            let y: u32 = member.text.parse().ok().filter(|y| *y < 16)?;
            16 * x + y
        }
        _ => return None,
    };
    Some(ConditionInput { index, negated })
}

/// The ATMT/EATMT rules: limits, no AND branches, no actions, one input per condition, tags.
pub fn target_rules(chart: &Chart, limits: Limits, diags: &mut Vec<Diagnostic>) {
    let target = chart.target;
    if !matches!(target, Target::Atmt | Target::Eatmt) {
        return;
    }
    let tname = target.name().to_ascii_uppercase();
    if chart.steps.len() as u32 > limits.states {
        // Reported on the first step beyond the limit, so the editor can point at it.
        let s = &chart.steps[limits.states as usize];
        diags.push(
            Diagnostic::error(
                "SFC0401",
                s.name_span,
                format!(
                    "{tname} allows at most {} states: step `{}` is step number {} of {}",
                    limits.states,
                    s.name,
                    limits.states + 1,
                    chart.steps.len()
                ),
            )
            .with_element(&s.name),
        );
    }
    if chart.transitions.len() as u32 > limits.rules {
        diags.push(
            Diagnostic::error(
                "SFC0403",
                chart.name_span,
                format!(
                    "{tname} allows at most {} rules, chart `{}` has {} transitions",
                    limits.rules,
                    chart.pou,
                    chart.transitions.len()
                ),
            )
            .with_element(&chart.pou),
        );
    }
    for t in &chart.transitions {
        if t.from.len() > 1 || t.to.len() > 1 {
            let what = if t.to.len() > 1 { "divergence" } else { "convergence" };
            diags.push(
                Diagnostic::error(
                    "SFC0404",
                    t.header_span,
                    format!("{tname} has one active state: the simultaneous {what} of `{}` is not supported", t.name),
                )
                .with_element(&t.name)
                .with_note("`sfc build --flatten` compiles every reachable situation into one state"),
            );
        }
    }
    for s in &chart.steps {
        for a in &s.associations {
            diags.push(
                Diagnostic::error(
                    "SFC0405",
                    a.span,
                    format!("{tname} charts have no actions: remove `{}` from step `{}`", a.action, s.name),
                )
                .with_element(&s.name),
            );
        }
    }
    for a in &chart.actions {
        diags.push(
            Diagnostic::error(
                "SFC0405",
                a.name_span,
                format!("{tname} charts have no actions: remove action `{}`", a.name),
            )
            .with_element(&a.name),
        );
    }
    // Conditions.
    let mut used = std::collections::BTreeSet::new();
    for t in &chart.transitions {
        let span = match &t.condition {
            ast::Condition::St(e) => e.span,
            ast::Condition::Il(b) => b.span,
            ast::Condition::Missing => continue,
        };
        let example = if target == Target::Atmt { "`C3`" } else { "`c3`, `c1.2` or `NOT c3`" };
        match condition_input(&t.condition, target) {
            None => diags.push(
                Diagnostic::error(
                    "SFC0406",
                    span,
                    format!("the condition of `{}` must be a single {tname} input such as {example}", t.name),
                )
                .with_element(&t.name),
            ),
            Some(ci) => {
                let max = limits.conditions;
                if ci.index >= max {
                    diags.push(
                        Diagnostic::error(
                            "SFC0402",
                            span,
                            format!(
                                "{tname} has condition inputs 0 to {}, `{}` uses input {}",
                                max - 1,
                                t.name,
                                ci.index
                            ),
                        )
                        .with_element(&t.name),
                    );
                }
                if ci.negated && target == Target::Atmt {
                    diags.push(
                        Diagnostic::error(
                            "SFC0407",
                            span,
                            format!("ATMT cannot negate a condition (in `{}`); use EATMT", t.name),
                        )
                        .with_element(&t.name),
                    );
                }
                if let Some(tag) = t.tag {
                    if tag != ci.index {
                        diags.push(
                            Diagnostic::error(
                                "SFC0408",
                                t.header_span,
                                format!(
                                    "transition `{}` has tag {tag} but its condition is input {}",
                                    t.name, ci.index
                                ),
                            )
                            .with_element(&t.name),
                        );
                    }
                }
                used.insert(ci.index);
            }
        }
    }
    if used.len() as u32 > limits.conditions {
        diags.push(Diagnostic::error(
            "SFC0402",
            chart.name_span,
            format!(
                "{tname} allows at most {} conditions, chart `{}` uses {}",
                limits.conditions,
                chart.pou,
                used.len()
            ),
        ));
    }
    // State tags.
    let numbers = chart.state_numbers();
    let mut first_with_tag = std::collections::HashMap::new();
    for (i, s) in chart.steps.iter().enumerate() {
        if let Some(tag) = s.tag {
            first_with_tag.entry(tag).or_insert(i);
        }
    }
    for (i, s) in chart.steps.iter().enumerate() {
        if let Some(tag) = s.tag {
            if tag >= limits.states {
                diags.push(
                    Diagnostic::error(
                        "SFC0409",
                        s.name_span,
                        format!("step `{}` has tag {tag}, beyond the {} states of {tname}", s.name, limits.states),
                    )
                    .with_element(&s.name),
                );
            }
            if let Some(&j) = first_with_tag.get(&tag).filter(|&&j| j != i) {
                diags.push(
                    Diagnostic::error(
                        "SFC0409",
                        s.name_span,
                        format!("steps `{}` and `{}` have the same tag {tag}", chart.steps[j].name, s.name),
                    )
                    .with_element(&s.name)
                    .with_label(chart.steps[j].name_span, "tag first used here"),
                );
            }
        }
        if s.initial && numbers[i] != 0 {
            let note = if s.tag.is_some() {
                "remove its tag (an untagged initial step is state 0) or give it {attribute 'sfc.tag' := '0'}"
                    .to_string()
            } else if let Some(z) = chart.steps.iter().find(|z| z.tag == Some(0)) {
                format!("step `{}` is tagged 0; remove that tag", z.name)
            } else {
                "only one initial step can be state 0: a chart with several networks needs --flatten".to_string()
            };
            diags.push(
                Diagnostic::error(
                    "SFC0409",
                    s.name_span,
                    format!("the initial step `{}` must be state 0, it is state {}", s.name, numbers[i]),
                )
                .with_element(&s.name)
                .with_note(note),
            );
        }
    }
}
