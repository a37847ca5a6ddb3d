//! `sfc check --profile logix`: warnings on the elements whose behaviour on a Logix 5000
//! controller (Studio 5000) differs from `iec` in a way the chart can observe, one code per
//! difference (`SFC0921`–`SFC0923`, see `sfc check --explain`). The rules are the `logix`
//! profile's (docs/sim.md, "The `logix` profile"); a conversion to L5X lists the same ones.

use sfc_diagnostics::Diagnostic;
use sfc_model::{ActionTarget, Chart, LastScan, Qualifier};

/// The differences of the charts of a checked file (the POUs' charts and those of their
/// actions written in SFC).
pub fn differences(charts: &[Chart], action_charts: &[Chart]) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for c in charts.iter().chain(action_charts) {
        chart(c, &mut out);
    }
    out
}

fn chart(c: &Chart, out: &mut Vec<Diagnostic>) {
    // SFC0921: the first call tests the initial steps' transitions.
    for t in &c.transitions {
        if crate::matiec_check::tested_at_start(c, t) {
            let steps: Vec<&str> = t.from.iter().map(|&s| c.steps[s].name.as_str()).collect();
            out.push(
                Diagnostic::warning("SFC0921", t.header_span, format!("{} is already tested in the first call on Logix", t.name))
                    .with_element(&t.name)
                    .with_note(format!(
                        "IEC tests no transition in scan 0; a Logix controller executes {} and then tests {} in the \
                         same first call",
                        steps.join(", "),
                        t.name
                    )),
            );
        }
    }
    let dont_scan = c.logix.last_scan != LastScan::ProgrammaticReset;
    for step in &c.steps {
        for a in &step.associations {
            // SFC0922: P executes when its step is activated and again when it is left.
            if a.qualifier == Qualifier::P {
                out.push(
                    Diagnostic::warning(
                        "SFC0922",
                        a.span,
                        format!("`{}(P)` executes when {} is activated and again when it is left, on Logix", a.action, step.name),
                    )
                    .with_element(&step.name)
                    .with_note(
                        "IEC's P executes in the scan its step is entered and once more (its final run, Q FALSE) in \
                         the next scan; Logix's P executes once on activation and once on deactivation",
                    ),
                );
            }
            // SFC0923: an action that stops does not execute again ("Don't scan").
            let stops_later = matches!(a.qualifier, Qualifier::N | Qualifier::L | Qualifier::D)
                && matches!(a.target, ActionTarget::Action(_));
            if dont_scan && stops_later {
                out.push(
                    Diagnostic::warning(
                        "SFC0923",
                        a.span,
                        format!("`{}` does not execute again when it stops, on Logix ({})", a.action, c.logix.last_scan.name()),
                    )
                    .with_element(&step.name)
                    .with_note(
                        "IEC runs an action once more, with Q FALSE, after it stops (its final run); a Logix controller \
                         set to \"Don't scan\" (Studio 5000's default) executes only P and P0 actions in a step's last \
                         scan: clear what the action set in a P0 action, or choose \"Programmatic reset\" \
                         (`sfc.logix.lastscan`)",
                    ),
                );
            }
        }
    }
}
