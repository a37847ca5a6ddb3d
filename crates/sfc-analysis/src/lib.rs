//! The analyzer: what can happen in a chart under the `iec` semantics with guards as free
//! inputs (net analysis), what the guards allow (guard analysis), and whether a net finding can
//! really be reached once the guards are taken into account (replay in the simulator).
//!
//! [`check_source`] is `sfc check`: the front end's checks, then, when the file has no errors
//! and analysis is on, [`analyze_chart`] for every SFC POU. Findings are ordinary diagnostics
//! (codes `SFC0501`–`SFC0509`) with a witness: a firing sequence for net findings, an input
//! valuation for guard findings.

pub mod guard;
pub mod net;
pub mod replay;

use guard::{GuardContext, GuardFinding, GuardFindingKind};
use net::{Method, NetOptions, NetReport};
use replay::{Goal, ReplayFailure, ReplayOptions};
use sfc_diagnostics::{Diagnostic, Severity, Span, Witness};
use sfc_model::{Chart, CheckOptions, Checked, StepId, TransitionId};

/// How much work the analysis may do.
#[derive(Debug, Clone)]
pub struct Options {
    pub net: NetOptions,
    /// Replay net findings in the simulator (confirmed / possible).
    pub confirm: bool,
    pub replay: ReplayOptions,
    /// At most this many net findings per chart are replayed; the others say so.
    pub max_replays: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options { net: NetOptions::default(), confirm: true, replay: ReplayOptions::default(), max_replays: 32 }
    }
}

/// `sfc check` on one file: [`sfc_model::check_source`], then the analysis of every chart when
/// `opts.analysis` is set and the file has no errors (an erroneous chart has no meaning to
/// prove things about; its errors come first).
pub fn check_source(file_id: u32, name: &str, text: &str, opts: &CheckOptions) -> Checked {
    check_parsed(file_id, name, text, sfc_syntax::parse(file_id, text), opts)
}

/// [`check_source`] of a text already parsed (`parsed` is `sfc_syntax::parse(file_id, text)`,
/// the tree owned or shared: [`sfc_model::Tree`]).
pub fn check_parsed(
    file_id: u32,
    name: &str,
    text: &str,
    parsed: (impl Into<sfc_model::Tree>, Vec<sfc_diagnostics::Diagnostic>),
    opts: &CheckOptions,
) -> Checked {
    let analysis = opts.analysis;
    let model_opts = CheckOptions { keep_types: opts.keep_types || analysis, ..opts.clone() };
    let mut checked = sfc_model::check_parsed(file_id, name, text, parsed, &model_opts);
    if analysis && !checked.has_errors() {
        let mut found = Vec::new();
        for chart in checked.charts.iter().chain(&checked.action_charts) {
            found.extend(analyze_chart(&checked, chart, &Options::default()));
        }
        checked.diagnostics.extend(found);
        sfc_diagnostics::sort(&mut checked.diagnostics);
    }
    checked
}

/// Every analysis finding about `chart`, a chart of `checked` (checked with `keep_types`, so
/// the guard analysis knows the types of the guards' operands).
pub fn analyze_chart(checked: &Checked, chart: &Chart, opts: &Options) -> Vec<Diagnostic> {
    let report = net::analyze_net(chart, &opts.net);
    let mut out = net_diagnostics(checked, chart, &report, opts);
    let together = |a: StepId, b: StepId| report.concurrency.together(a, b);
    let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
    for f in guard::analyze_guards(chart, &cx) {
        out.push(guard_diagnostic(chart, &f));
    }
    out
}

/// The situation a lock-up witness reaches in the whole chart: a lock-up is a situation of one
/// network, and the witness fires only that network's transitions (replay fires nothing else),
/// so the other networks are still in their initial steps.
pub fn lockup_goal(chart: &Chart, situation: &[StepId]) -> Goal {
    let mut steps: Vec<StepId> = situation.to_vec();
    for net in chart.networks() {
        if !net.iter().any(|s| situation.contains(s)) {
            steps.extend(net.iter().copied().filter(|&s| chart.steps[s].initial));
        }
    }
    steps.sort_unstable();
    steps.dedup();
    Goal::Situation(steps)
}

fn names(chart: &Chart, witness: &[TransitionId]) -> Vec<String> {
    witness.iter().map(|&t| chart.transitions[t].name.clone()).collect()
}

fn step_list(chart: &Chart, steps: &[StepId]) -> String {
    steps.iter().map(|&s| chart.steps[s].name.as_str()).collect::<Vec<_>>().join(", ")
}

/// Replays a witness and turns the outcome into notes: `confirmed` with the input schedule, or
/// `possible` with the reason.
struct Confirmer<'a> {
    checked: &'a Checked,
    chart: &'a Chart,
    opts: &'a Options,
    done: usize,
    /// Runaway scans met while replaying (SFC0510), one per location.
    runaways: Vec<Diagnostic>,
}

impl Confirmer<'_> {
    fn notes(&mut self, witness: &[TransitionId], goal: &Goal) -> Vec<String> {
        if !self.opts.confirm {
            return Vec::new();
        }
        if self.done >= self.opts.max_replays {
            return vec![format!(
                "not replayed in the simulator (only the first {} findings of a chart are)",
                self.opts.max_replays
            )];
        }
        self.done += 1;
        let file = &self.checked.file;
        match replay::replay(&file.name, &file.text, self.chart, witness, goal, &self.opts.replay) {
            Ok(schedule) => {
                let mut notes =
                    vec!["confirmed: the simulator follows the witness with this input schedule:".to_string()];
                notes.extend(schedule.describe(self.chart).into_iter().map(|l| format!("  {l}")));
                notes
            }
            Err(ReplayFailure::NotSimulatable(why)) => {
                vec![format!("possible: the chart cannot be simulated to confirm it ({why})")]
            }
            Err(ReplayFailure::Blocked { index, reason }) => vec![format!(
                "possible: with the real guards the simulator cannot fire `{}` (step {} of the witness): {reason}",
                witness.get(index).map(|&t| self.chart.transitions[t].name.as_str()).unwrap_or("?"),
                index + 1
            )],
            Err(ReplayFailure::Budget { index }) => vec![format!(
                "possible: no input schedule firing `{}` (step {} of the witness) was found within the search budget",
                witness.get(index).map(|&t| self.chart.transitions[t].name.as_str()).unwrap_or("?"),
                index + 1
            )],
            Err(ReplayFailure::Runaway { index, error }) => {
                if !self.runaways.iter().any(|d| d.span == error.span) {
                    self.runaways.push(
                        Diagnostic::new(
                            "SFC0510",
                            error.span,
                            format!(
                                "runaway scan: replaying a witness, the simulator spent {} loop iterations, jumps and calls in one scan here",
                                replay::REPLAY_SCAN_BUDGET
                            ),
                        )
                        .with_element(self.chart.pou.clone())
                        .with_note(error.message.clone()),
                    );
                }
                vec![format!(
                    "possible: the replay stopped trying to fire `{}` (step {} of the witness): a scan ran away at line {}, column {}",
                    witness.get(index).map(|&t| self.chart.transitions[t].name.as_str()).unwrap_or("?"),
                    index + 1,
                    error.line,
                    error.column
                )]
            }
        }
    }
}

fn net_diagnostics(checked: &Checked, chart: &Chart, report: &NetReport, opts: &Options) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    let mut confirm = Confirmer { checked, chart, opts, done: 0, runaways: Vec::new() };
    for u in &report.unsafe_steps {
        let step = &chart.steps[u.step];
        let tr = &chart.transitions[u.transition];
        let mut d = Diagnostic::error(
            "SFC0501",
            step.name_span,
            format!("unsafe chart: `{}` can be activated while it is already active", step.name),
        )
        .with_element(step.name.clone())
        .with_label(tr.header_span, format!("`{}` activates `{}` again", tr.name, step.name))
        .with_witness(Witness::Firing(names(chart, &u.witness)));
        for n in confirm.notes(&u.witness, &Goal::Unsafe(u.step)) {
            d = d.with_note(n);
        }
        out.push(d);
    }
    for &s in &report.unreachable {
        let step = &chart.steps[s];
        out.push(
            Diagnostic::error("SFC0502", step.name_span, format!("step `{}` is unreachable", step.name))
                .with_element(step.name.clone())
                .with_note("no firing sequence from the initial situation activates it, whatever the guards"),
        );
    }
    for &t in &report.dead {
        let tr = &chart.transitions[t];
        let d = Diagnostic::error("SFC0503", tr.header_span, format!("transition `{}` can never be enabled", tr.name))
            .with_element(tr.name.clone());
        let d = if tr.from.len() > 1 {
            d.with_note(format!("its preceding steps {} are never active together", step_list(chart, &tr.from)))
        } else {
            d.with_note("its preceding step is never active")
        };
        out.push(d);
    }
    for l in &report.lockups {
        // Located at the first active step that has a way out (it waits for ever).
        let waiting = l
            .situation
            .iter()
            .copied()
            .find(|&s| chart.transitions.iter().any(|t| t.from.contains(&s)))
            .or(l.situation.first().copied());
        let Some(at) = waiting else { continue };
        let step = &chart.steps[at];
        let mut d = Diagnostic::error(
            "SFC0504",
            step.name_span,
            format!(
                "lock-up: in the situation {{{}}} no transition can ever be enabled",
                step_list(chart, &l.situation)
            ),
        )
        .with_element(step.name.clone())
        .with_witness(Witness::Firing(names(chart, &l.witness)));
        for n in confirm.notes(&l.witness, &lockup_goal(chart, &l.situation)) {
            d = d.with_note(n);
        }
        out.push(d);
    }
    if !report.complete {
        let states = match &report.method {
            Method::Explicit { states } => format!("{states} situations"),
            Method::Symbolic { states } => format!("{states:.0} situations"),
            _ => "the state budget".to_string(),
        };
        out.push(
            Diagnostic::new(
                "SFC0509",
                chart.name_span,
                format!("analysis of `{}` stopped after {states}: the absence of findings is not proven", chart.pou),
            )
            .with_element(chart.pou.clone()),
        );
    }
    out.append(&mut confirm.runaways);
    out
}

fn guard_diagnostic(chart: &Chart, f: &GuardFinding) -> Diagnostic {
    let witness = Witness::Valuation(f.witness.clone());
    match &f.kind {
        GuardFindingKind::NonExclusive { first, second, explicit_priority } => {
            let (a, b) = (&chart.transitions[*first], &chart.transitions[*second]);
            let shared: Vec<StepId> = a.from.iter().copied().filter(|s| b.from.contains(s)).collect();
            let mut d = Diagnostic::warning(
                "SFC0505",
                b.header_span,
                format!(
                    "`{}` and `{}` leaving {} can be true in the same scan",
                    a.name,
                    b.name,
                    shared.first().map(|&s| format!("`{}`", chart.steps[s].name)).unwrap_or_else(|| "one step".into())
                ),
            )
            .with_element(b.name.clone())
            .with_label(a.header_span, format!("`{}` is also true", a.name))
            .with_witness(witness);
            if *explicit_priority {
                d = d.with_severity(Severity::Note).with_note("their PRIORITY decides which one fires");
            } else {
                d = d.with_note(format!(
                    "without PRIORITY, declaration order decides silently: `{}` fires, `{}` does not",
                    a.name, b.name
                ));
            }
            d
        }
        GuardFindingKind::Incomplete { step } => {
            let st = &chart.steps[*step];
            Diagnostic::note_diag(
                "SFC0506",
                st.name_span,
                format!("no transition leaving `{}` is true for some inputs: the step waits", st.name),
            )
            .with_element(st.name.clone())
            .with_witness(witness)
        }
        GuardFindingKind::AlwaysTrue { transition } => {
            let tr = &chart.transitions[*transition];
            let d = Diagnostic::warning(
                "SFC0507",
                condition_span(tr),
                format!("the condition of `{}` is always true when its step is active", tr.name),
            )
            .with_element(tr.name.clone());
            with_valuation(d, f)
        }
        GuardFindingKind::AlwaysFalse { transition } => {
            let tr = &chart.transitions[*transition];
            let d = Diagnostic::warning(
                "SFC0508",
                condition_span(tr),
                format!("the condition of `{}` is never true when its step is active: it never fires", tr.name),
            )
            .with_element(tr.name.clone());
            with_valuation(d, f)
        }
    }
}

fn with_valuation(d: Diagnostic, f: &GuardFinding) -> Diagnostic {
    if f.witness.is_empty() {
        d
    } else {
        d.with_witness(Witness::Valuation(f.witness.clone()))
    }
}

fn condition_span(tr: &sfc_model::TransitionNode) -> Span {
    match &tr.condition {
        sfc_syntax::ast::Condition::St(e) => e.span,
        _ => tr.header_span,
    }
}
