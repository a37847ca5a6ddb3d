//! The source text of the parts of a POU the editor shows as text: declarations, conditions,
//! action bodies and associations, cut from the file and dedented. Opening a file and checking
//! what a saved document reads back as (`readback.rs`) use the same functions, so both agree.

use crate::{Association, Language};
use sfc_diagnostics::Span;
use sfc_syntax::ast;

/// The text of a span (empty when it does not lie in `text`).
pub fn slice(text: &str, span: Span) -> &str {
    text.get(span.start as usize..span.end as usize).unwrap_or("")
}

/// Where the line holding `at` starts, when only white space precedes `at` on it; `at` otherwise.
fn line_start_if_blank(text: &str, at: usize) -> usize {
    let at = at.min(text.len());
    let start = text[..at].rfind('\n').map(|i| i + 1).unwrap_or(0);
    if text[start..at].chars().all(|c| c == ' ' || c == '\t') {
        start
    } else {
        at
    }
}

/// A block of lines as the editor shows it: the blank rest of the line it starts on and the
/// white space before the closing keyword are dropped, and the common indentation is removed.
pub fn dedent(region: &str) -> String {
    let mut r = region;
    if let Some(nl) = r.find('\n') {
        if r[..nl].trim().is_empty() {
            r = &r[nl + 1..];
        }
    }
    if let Some(nl) = r.rfind('\n') {
        if r[nl + 1..].trim().is_empty() {
            r = &r[..nl];
        }
    } else if r.trim().is_empty() {
        return String::new();
    }
    let r = r.strip_suffix('\r').unwrap_or(r);
    let lines: Vec<&str> = r.split('\n').collect();
    let indent = lines
        .iter()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.chars().take_while(|c| *c == ' ' || *c == '\t').count())
        .min()
        .unwrap_or(0);
    lines.iter().map(|l| if l.trim().is_empty() { "" } else { char_skip(l, indent) }).collect::<Vec<_>>().join("\n")
}

fn char_skip(s: &str, n: usize) -> &str {
    match s.char_indices().nth(n) {
        Some((i, _)) => &s[i..],
        None => "",
    }
}

/// Indents every non-blank line of `block` by `indent` (blank lines stay empty).
pub fn indent(block: &str, indent: &str) -> String {
    block
        .split('\n')
        .map(|l| if l.trim().is_empty() { String::new() } else { format!("{indent}{l}") })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Where the POU's declarations lie in `text` (byte offsets), when it has any.
pub fn declarations_range(text: &str, pou: &ast::Pou) -> Option<(usize, usize)> {
    let (first, last) = (pou.var_blocks.first()?, pou.var_blocks.last()?);
    let end = (last.span.end as usize).min(text.len());
    Some((line_start_if_blank(text, first.span.start as usize).min(end), end))
}

/// The POU's `VAR … END_VAR` blocks (with the comments between them), dedented.
pub fn declarations(text: &str, pou: &ast::Pou) -> String {
    match declarations_range(text, pou) {
        Some((start, end)) => dedent(text.get(start..end).unwrap_or("")),
        None => String::new(),
    }
}

/// Where a transition's condition text lies in `text` (byte offsets), when it has one.
pub fn condition_range(text: &str, condition: &ast::Condition) -> Option<(usize, usize)> {
    match condition {
        ast::Condition::St(e) => Some((e.span.start as usize, e.span.end as usize)),
        ast::Condition::Il(b) => Some((line_start_if_blank(text, b.span.start as usize), b.span.end as usize)),
        ast::Condition::Missing => None,
    }
}

/// A transition's condition as written: the ST expression, or the IL instructions dedented.
pub fn condition(text: &str, condition: &ast::Condition) -> (Option<String>, Language) {
    let range = condition_range(text, condition);
    let cut = |(start, end): (usize, usize)| text.get(start..end).unwrap_or("");
    match (condition, range) {
        (ast::Condition::St(_), Some(r)) => (Some(cut(r).to_string()), Language::St),
        (ast::Condition::Il(_), Some(r)) => (Some(dedent(cut(r))), Language::Il),
        _ => (None, Language::St),
    }
}

/// Whether a comment lies in a range (the text it belongs to).
pub fn within(t: &ast::Trivia, range: Option<(usize, usize)>) -> bool {
    range.is_some_and(|(start, end)| start <= t.span.start as usize && t.span.end as usize <= end)
}

/// Whether a trivia is a comment (pragmas are read as attributes).
pub fn is_comment(t: &ast::Trivia) -> bool {
    matches!(t.kind, ast::TriviaKind::BlockComment | ast::TriviaKind::LineComment)
}

/// An action's body: the text between `ACTION name:` and `END_ACTION`, dedented.
pub fn action_body(text: &str, span: Span, name_span: Span) -> String {
    let whole = slice(text, span);
    let rel_name_end = (name_span.end.saturating_sub(span.start)) as usize;
    let Some(after_name) = whole.get(rel_name_end..) else { return String::new() };
    let body_start = match after_name.find(':') {
        Some(i) if after_name[..i].trim().is_empty() => rel_name_end + i + 1,
        _ => rel_name_end,
    };
    let end =
        if whole.len() >= 10 && whole.get(whole.len() - 10..).is_some_and(|k| k.eq_ignore_ascii_case("END_ACTION")) {
            whole.len() - 10
        } else {
            whole.len()
        };
    dedent(whole.get(body_start..end.max(body_start)).unwrap_or(""))
}

/// The language of an action's body.
pub fn action_language(body: &ast::ActionBody) -> Language {
    match body {
        ast::ActionBody::Il(_) => Language::Il,
        // An action written in SFC is edited as its text for now (its steps and transitions).
        ast::ActionBody::St(_) | ast::ActionBody::Sfc(_) => Language::St,
    }
}

/// An association as the editor shows it (qualifier and duration as written).
pub fn association(text: &str, a: &ast::ActionAssociation) -> Association {
    Association {
        qualifier: a.qualifier.as_ref().map(|q| q.text.clone()).unwrap_or_default(),
        duration: a.duration.as_ref().map(|d| slice(text, d.span).to_string()),
        action: a.action.text.clone(),
        indicator: if a.indicators.is_empty() {
            None
        } else {
            Some(a.indicators.iter().map(|i| i.text.as_str()).collect::<Vec<_>>().join(", "))
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dedent_drops_the_frame_of_a_block() {
        assert_eq!(
            dedent("\n        a := 1;\n        IF b THEN\n            c();\n        END_IF;\n    "),
            "a := 1;\nIF b THEN\n    c();\nEND_IF;"
        );
        assert_eq!(dedent(" "), "");
        assert_eq!(dedent(""), "");
        assert_eq!(dedent("x := 1;"), "x := 1;");
        assert_eq!(dedent("\n    a;\n\n    b;\n"), "a;\n\nb;");
    }

    #[test]
    fn indent_leaves_blank_lines_empty() {
        assert_eq!(indent("a\n\n  b", "    "), "    a\n\n      b");
    }
}
