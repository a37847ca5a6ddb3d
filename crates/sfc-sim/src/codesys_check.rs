//! `sfc check --profile codesys`: warnings on the elements whose behaviour under CODESYS (and
//! TwinCAT, e!COCKPIT) differs from `iec` in a way the chart can observe, or that CODESYS
//! refuses, one code per difference (`SFC0911`–`SFC0913`, see `sfc check --explain`). The rules
//! are the `codesys` profile's (docs/sim.md, "The `codesys` profile").

use sfc_diagnostics::Diagnostic;
use sfc_model::{ActionTarget, Chart};

/// The differences of the charts of a checked file: `charts` are the POUs' charts,
/// `action_charts` the charts of their actions written in SFC.
pub fn differences(charts: &[Chart], action_charts: &[Chart]) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for c in charts.iter().chain(action_charts) {
        chart(c, &mut out);
    }
    levels(charts, action_charts, &mut out);
    out
}

fn chart(c: &Chart, out: &mut Vec<Diagnostic>) {
    // SFC0911: PRIORITY is ignored; the first declared TRUE alternative wins.
    for (i, t) in c.transitions.iter().enumerate() {
        if t.priority.is_none() {
            continue;
        }
        let rivals: Vec<&str> = c
            .transitions
            .iter()
            .enumerate()
            .filter(|&(j, o)| j != i && o.from.iter().any(|s| t.from.contains(s)))
            .map(|(_, o)| o.name.as_str())
            .collect();
        if rivals.is_empty() {
            continue;
        }
        out.push(
            Diagnostic::warning(
                "SFC0911",
                t.header_span,
                format!("the PRIORITY of {} is ignored under CODESYS", t.name),
            )
            .with_element(&t.name)
            .with_note(format!(
                "CODESYS has no transition priorities: of {} and {}, the first TRUE one from the left (declared \
                     first) fires",
                t.name,
                rivals.join(", ")
            )),
        );
    }
    // SFC0912: the first call tests the initial steps' transitions.
    for t in &c.transitions {
        if crate::matiec_check::tested_at_start(c, t) {
            let steps: Vec<&str> = t.from.iter().map(|&s| c.steps[s].name.as_str()).collect();
            out.push(
                Diagnostic::warning(
                    "SFC0912",
                    t.header_span,
                    format!("{} is already tested in the first call under CODESYS", t.name),
                )
                .with_element(&t.name)
                .with_note(format!(
                    "IEC tests no transition in scan 0; CODESYS runs the actions of {} and then tests {} in the same \
                     first call, so {} may be active for one call only",
                    steps.join(", "),
                    t.name,
                    steps.join(", ")
                )),
            );
        }
    }
}

/// SFC0913: an IEC action associated both in a POU's chart and in the chart of one of its
/// actions written in SFC, which CODESYS refuses ("Processing order in SFC": the same IEC action
/// at different levels of a chart gives unpredictable results, so CODESYS reports an error).
fn levels(charts: &[Chart], action_charts: &[Chart], out: &mut Vec<Diagnostic>) {
    for top in charts {
        let subs: Vec<&Chart> = action_charts.iter().filter(|a| a.item == top.item).collect();
        for sub in &subs {
            for step in &sub.steps {
                for a in step.associations.iter().filter(|a| a.target != ActionTarget::Variable) {
                    let in_top = top
                        .steps
                        .iter()
                        .flat_map(|s| s.associations.iter())
                        .any(|b| b.target != ActionTarget::Variable && b.action.eq_ignore_ascii_case(&a.action));
                    if in_top {
                        let owner = sub.action.as_deref().unwrap_or_default();
                        out.push(
                            Diagnostic::warning(
                                "SFC0913",
                                a.span,
                                format!(
                                    "`{}` is associated in `{}`'s chart and in the chart of its action `{owner}`: \
                                     CODESYS refuses this",
                                    a.action, top.pou
                                ),
                            )
                            .with_element(&step.name)
                            .with_note(
                                "CODESYS reports an error when one IEC action is used at different levels of a \
                                 chart; here it runs in each chart, with a control block per chart",
                            ),
                        );
                    }
                }
            }
        }
    }
}
