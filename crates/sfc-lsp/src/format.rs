//! Formatting: `sfc fmt`'s canonical layout (through the driver), sent as the smallest line
//! edits so the editor keeps the cursor and folds; a range request applies only the edits that
//! touch the selected lines.

use crate::text::LineIndex;
use lsp_types::{Position, Range, TextEdit};

/// Why a document cannot be formatted.
pub fn format_error(e: &sfc_driver::FormatError) -> String {
    match e {
        sfc_driver::FormatError::Xml => "PLCopen XML is not formatted: `sfc fmt` rewrites IEC text only".into(),
        sfc_driver::FormatError::Syntax { file, diagnostics } => {
            let first = diagnostics.first().map(|d| {
                let lc = file.line_col(d.span.start);
                format!(" (first at line {}, column {}: {})", lc.line, lc.column, d.message)
            });
            format!(
                "not formatted: the file has {} syntax error{}{}",
                diagnostics.len(),
                if diagnostics.len() == 1 { "" } else { "s" },
                first.unwrap_or_default()
            )
        }
    }
}

/// The edits that turn `text` into its canonical layout; with `lines` (0-based, inclusive),
/// only those that touch these lines.
pub fn format(name: &str, text: &str, lines: Option<(u32, u32)>) -> Result<Vec<TextEdit>, String> {
    let formatted = sfc_driver::format(name, text).map_err(|e| format_error(&e))?;
    Ok(edits(text, &formatted, lines))
}

fn edits(old: &str, new: &str, lines: Option<(u32, u32)>) -> Vec<TextEdit> {
    let index = LineIndex::new(old);
    let diff = similar::TextDiff::configure().algorithm(similar::Algorithm::Myers).diff_lines(old, new);
    let new_lines: Vec<&str> = diff.new_slices().to_vec();
    let mut out = Vec::new();
    for op in diff.grouped_ops(0).into_iter().flatten() {
        let (tag, old_range, new_range) = op.as_tag_tuple();
        if tag == similar::DiffTag::Equal {
            continue;
        }
        if let Some((first, last)) = lines {
            let (a, b) = (old_range.start as u32, old_range.end as u32);
            let touches = if a == b { first <= a && a <= last + 1 } else { a <= last && b > first };
            if !touches {
                continue;
            }
        }
        let start = Position::new(old_range.start as u32, 0);
        let end = if old_range.end as u32 >= index.line_count() {
            index.position(old, old.len() as u32)
        } else {
            Position::new(old_range.end as u32, 0)
        };
        let replacement: String = new_lines.get(new_range).unwrap_or(&[]).concat();
        out.push(TextEdit::new(Range::new(start, end), replacement));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(text: &str, edits: &[TextEdit]) -> String {
        let mut t = text.to_string();
        let mut sorted = edits.to_vec();
        sorted.sort_by_key(|e| std::cmp::Reverse((e.range.start.line, e.range.start.character)));
        for e in sorted {
            let idx = LineIndex::new(&t);
            let (s, en) = idx.offsets(&t, e.range);
            t.replace_range(s as usize..en as usize, &e.new_text);
        }
        t
    }

    #[test]
    fn full_and_range() {
        let text = "PROGRAM P\n    VAR\n        a : BOOL;\n    END_VAR\n\n    INITIAL_STEP S1 :   END_STEP\n\n    STEP S2:END_STEP\n\n    TRANSITION FROM S1 TO S2\n        := a;\n    END_TRANSITION\n\n    TRANSITION FROM S2 TO S1\n        := NOT a;\n    END_TRANSITION\nEND_PROGRAM\n";
        let canonical = sfc_driver::format("a.st", text).unwrap();
        let all = format("a.st", text, None).unwrap();
        assert_eq!(all.len(), 2, "{all:?}");
        assert_eq!(apply(text, &all), canonical);
        // Only line 5 (0-based): the initial step; S2 stays as written.
        let some = format("a.st", text, Some((5, 5))).unwrap();
        let partly = apply(text, &some);
        assert!(partly.contains("STEP S2:END_STEP"), "{partly}");
        assert!(partly.contains("    INITIAL_STEP S1: END_STEP\n"), "{partly}");
        assert!(format("a.st", "PROGRAM P VAR", None).unwrap_err().contains("syntax error"));
    }
}
