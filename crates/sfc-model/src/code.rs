//! Type checking of the ST and IL code of every POU (conditions, action bodies, POU bodies,
//! declarations) by `sfc-st`, fitted to the chart targets.

use crate::chart::{Chart, Target};
use sfc_diagnostics::{Diagnostic, Span};
use sfc_st::Type;
use sfc_syntax::ast;
use std::collections::HashMap;

/// Type-checks the whole file. Runs on the intact AST, before lowering moves the SFC code into
/// the charts. With `keep_types`, also returns the type of every checked expression by span
/// (for the simulator); otherwise the table is empty.
pub fn check_unit(unit: &ast::SourceUnit, keep_types: bool) -> (Vec<Diagnostic>, HashMap<Span, Type>) {
    if keep_types {
        sfc_st::check_unit_typed(unit)
    } else {
        (sfc_st::check_unit(unit), HashMap::new())
    }
}

/// Drops type diagnostics inside the conditions of ATMT/EATMT charts: there a condition is one
/// implicit input (`C3`, `c1.2`, `NOT c5`) and the target rules (SFC04xx) judge it.
pub fn fit_to_targets(diags: Vec<Diagnostic>, charts: &[Chart]) -> Vec<Diagnostic> {
    let spans: Vec<sfc_diagnostics::Span> = charts
        .iter()
        .filter(|c| matches!(c.target, Target::Atmt | Target::Eatmt))
        .flat_map(|c| c.transitions.iter())
        .filter_map(|t| match &t.condition {
            ast::Condition::St(e) => Some(e.span),
            ast::Condition::Il(b) => Some(b.span),
            ast::Condition::Missing => None,
        })
        .collect();
    if spans.is_empty() {
        return diags;
    }
    diags
        .into_iter()
        .filter(|d| !spans.iter().any(|s| s.file == d.span.file && s.start <= d.span.start && d.span.end <= s.end))
        .collect()
}
