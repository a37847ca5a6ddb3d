//! What a vendor's chart reads that other targets do not have.

use crate::{Chart, Checked};

/// SFC0806 for the `Count`, `FS`, `SA`, `LS` or `TMax` of a step read by a Studio 5000 chart
/// (`sfc.dialect 'logix'`), which IEC 61131-3's steps do not have: every place a condition or an action of `chart` reads one.
pub fn logix_step_counts(checked: &Checked, chart: &Chart, target: &str) -> Vec<sfc_diagnostics::Diagnostic> {
    let Some(sfc_syntax::ast::Item::Pou(p)) = checked.unit.items.get(chart.item) else { return Vec::new() };
    if !sfc_st::is_dialect(p, "logix") {
        return Vec::new();
    }
    let text = &checked.file.text;
    let spans = chart
        .transitions
        .iter()
        .map(|t| t.span)
        .chain(chart.actions.iter().map(|a| a.span));
    let mut out = Vec::new();
    for span in spans {
        let Some(part) = text.get(span.start as usize..span.end as usize) else { continue };
        let upper = part.to_ascii_uppercase();
        for (s, member) in chart.steps.iter().flat_map(|s| ["Count", "FS", "SA", "LS", "TMax"].map(|m| (s, m))) {
            let pat = format!("{}.{}", s.name.to_ascii_uppercase(), member.to_ascii_uppercase());
            let mut from = 0;
            while let Some(k) = upper.get(from..).and_then(|r| r.find(&pat)).map(|k| k + from) {
                from = k + pat.len();
                let before = upper.get(..k).and_then(|r| r.chars().next_back());
                let after = upper.get(from..).and_then(|r| r.chars().next());
                let word = |c: Option<char>| c.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
                if word(before) || word(after) {
                    continue;
                }
                let at = sfc_diagnostics::Span::new(span.file, span.start + k as u32, span.start + from as u32);
                out.push(
                    sfc_diagnostics::Diagnostic::error(
                        "SFC0806",
                        at,
                        format!(
                            "`{}.{member}` is a Studio 5000 step member ({}), which {target} has no counterpart for yet",
                            s.name,
                            match member {
                                "Count" => "how many times the step became active",
                                "TMax" => "the longest time the step was active",
                                _ => "a scan bit of the step",
                            }
                        ),
                    )
                    .with_element(&s.name),
                );
            }
        }
    }
    out
}
