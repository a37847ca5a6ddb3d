//! Code generation from the chart model: REX ATMT/EATMT transition tables (`atmt`), IEC
//! Structured Text (`st`) and Siemens S7-200 statement list (`stl`).

pub mod atmt;
pub mod st;
pub mod stl;

use sfc_diagnostics::Diagnostic;
use sfc_model::{Chart, Checked};

/// SFC0806 for what the code generators do not generate yet and must not leave out: the
/// charts of the POU's actions written in SFC (`checked`'s, when given) and the step actions
/// of `chart`'s steps (CODESYS's). `target` names the output in the message.
pub fn codesys_actions(checked: Option<&Checked>, chart: &Chart, target: &str) -> Vec<Diagnostic> {
    let mut out: Vec<Diagnostic> = checked
        .into_iter()
        .flat_map(|c| c.action_charts.iter())
        .filter(|c| c.item == chart.item)
        .map(|c| {
            let action = c.action.as_deref().unwrap_or_default();
            Diagnostic::error(
                "SFC0806",
                c.name_span,
                format!("`{}.{action}` is an action written in SFC, which {target} does not generate yet", c.pou),
            )
            .with_element(action)
        })
        .collect();
    // CODESYS's SFC flags that act only when declared (docs/sim.md, "Chart control variables").
    let flags = ["SFCReset", "SFCEnableLimit", "SFCErrorPOU", "SFCTrans", "SFCTip", "SFCTipMode"];
    if let Some(sfc_syntax::ast::Item::Pou(p)) = checked.and_then(|c| c.unit.items.get(chart.item)) {
        for d in p.var_blocks.iter().flat_map(|b| b.decls.iter()).flat_map(|d| d.names.iter()) {
            if let Some(f) = flags.iter().find(|f| d.is(f)) {
                out.push(
                    Diagnostic::error(
                        "SFC0806",
                        d.span,
                        format!("`{f}` is one of CODESYS's SFC flags, which {target} does not generate yet"),
                    )
                    .with_element(*f),
                );
            }
        }
    }
    if let Some(c) = checked {
        out.extend(sfc_model::vendor::logix_step_counts(c, chart, target));
    }
    for s in &chart.steps {
        if s.min_time.is_some() {
            out.push(
                Diagnostic::error(
                    "SFC0806",
                    s.name_span,
                    format!(
                        "step `{}` has a minimum time (`sfc.min_time`), which {target} does not generate yet",
                        s.name
                    ),
                )
                .with_element(&s.name),
            );
        }
        if let Some(a) = s.step_actions.first() {
            out.push(
                Diagnostic::error(
                    "SFC0806",
                    a.span,
                    format!("step `{}` has step actions (CODESYS), which {target} does not generate yet", s.name),
                )
                .with_element(&s.name),
            );
        }
    }
    out
}

