//! Rendering of diagnostics: the rustc-like human form and the JSON contract.

use crate::{Diagnostic, Severity, SourceFile, Span, Witness};
use serde_json::{json, Map, Value};
use std::fmt::Write;

/// Options of the human renderer.
#[derive(Debug, Clone, Copy, Default)]
pub struct RenderOptions {
    /// ANSI colours (only when writing to a terminal).
    pub color: bool,
}

struct Style {
    on: bool,
}

impl Style {
    fn paint(&self, code: &str, text: &str) -> String {
        if self.on {
            format!("\x1b[{code}m{text}\x1b[0m")
        } else {
            text.to_string()
        }
    }
    fn severity(&self, sev: Severity, text: &str) -> String {
        let code = match sev {
            Severity::Error => "1;31",
            Severity::Warning => "1;33",
            Severity::Note => "1;32",
        };
        self.paint(code, text)
    }
    fn blue(&self, text: &str) -> String {
        self.paint("1;34", text)
    }
    fn bold(&self, text: &str) -> String {
        self.paint("1", text)
    }
}

fn file_of(files: &[SourceFile], span: Span) -> Option<&SourceFile> {
    files.get(span.file as usize)
}

/// Renders one diagnostic like rustc:
///
/// ```text
/// error[SFC0303]: transition condition is not BOOL
///  --> chart.st:12:8
///    |
/// 12 |     := Level;
///    |        ^^^^^ this expression is INT
///    |
///    = note: …
/// ```
pub fn render_human(diag: &Diagnostic, files: &[SourceFile], opts: RenderOptions) -> String {
    let st = Style { on: opts.color };
    let mut out = String::new();
    let sev = diag.severity.as_str();
    let _ = writeln!(
        out,
        "{}{} {}",
        st.severity(diag.severity, &format!("{sev}[{}]", diag.code)),
        st.bold(":"),
        st.bold(&visible(&diag.message))
    );
    // Width of the line-number gutter: the largest line number shown.
    let mut max_line = 1;
    for span in std::iter::once(diag.span).chain(diag.labels.iter().map(|l| l.span)) {
        if let Some(f) = file_of(files, span) {
            max_line = max_line.max(f.line_col(span.end).line);
        }
    }
    let width = max_line.to_string().len();
    let pad = " ".repeat(width);
    if let Some(file) = file_of(files, diag.span) {
        let lc = file.line_col(diag.span.start);
        let _ = writeln!(out, "{pad}{} {}:{}:{}", st.blue("-->"), visible(&file.name), lc.line, lc.column);
        let _ = writeln!(out, "{pad} {}", st.blue("|"));
        // Snippets of this file in source order (like rustc), with `...` between distant lines;
        // labels in other files follow, each under its own `:::` header.
        let mut local: Vec<(crate::Span, char, Severity, &str)> = vec![(diag.span, '^', diag.severity, "")];
        local.extend(
            diag.labels
                .iter()
                .filter(|l| l.span.file == diag.span.file)
                .map(|l| (l.span, '-', Severity::Note, l.message.as_str())),
        );
        local.sort_by_key(|(sp, ..)| sp.start);
        // One rendering per source line: every mark on a line goes under that line once.
        let mut lines: Vec<(u32, Vec<Mark>)> = Vec::new();
        for (sp, mark, sev, msg) in local {
            let line = file.line_col(sp.start).line;
            let m = Mark { span: sp, mark, sev, label: msg };
            match lines.last_mut() {
                Some((l, marks)) if *l == line => marks.push(m),
                _ => lines.push((line, vec![m])),
            }
        }
        let mut last_line: Option<u32> = None;
        for (line, marks) in &lines {
            if let Some(prev) = last_line {
                if *line > prev + 1 {
                    let _ = writeln!(out, "{}", st.blue("..."));
                }
            }
            snippet(&mut out, &st, file, *line, marks, width);
            last_line = Some(*line);
        }
        for label in diag.labels.iter().filter(|l| l.span.file != diag.span.file) {
            if let Some(lf) = file_of(files, label.span) {
                let lc = lf.line_col(label.span.start);
                let _ = writeln!(out, "{pad}{} {}:{}:{}", st.blue(":::"), visible(&lf.name), lc.line, lc.column);
                let line = lf.line_col(label.span.start).line;
                let mark = Mark { span: label.span, mark: '-', sev: Severity::Note, label: &label.message };
                snippet(&mut out, &st, lf, line, &[mark], width);
            }
        }
    }
    if let Some(element) = &diag.element {
        if !diag.message.contains(element.as_str()) {
            let _ = writeln!(out, "{pad} {} {}: {}", st.blue("="), st.bold("element"), visible(element));
        }
    }
    for note in &diag.notes {
        // A note that says how to fix the problem is a `help` line, as in rustc.
        let (kind, text) = match note.strip_prefix("help: ") {
            Some(help) => ("help", help),
            None => ("note", note.as_str()),
        };
        let _ = writeln!(out, "{pad} {} {}: {}", st.blue("="), st.bold(kind), visible(text));
    }
    if let Some(w) = &diag.witness {
        let text = match w {
            Witness::Firing(ts) if ts.is_empty() => "the initial situation".to_string(),
            Witness::Firing(ts) => ts.join(" -> "),
            Witness::Valuation(vs) => vs.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", "),
        };
        let _ = writeln!(out, "{pad} {} {}: {text}", st.blue("="), st.bold("witness"));
    }
    out
}

/// `text` safe to print on a terminal: control characters (a binary file's bytes, an escape
/// sequence in a comment) shown as their Unicode control pictures (`␛`, `␀`), one cell each as
/// the character they replace, so the carets stay under their columns.
fn visible(text: &str) -> std::borrow::Cow<'_, str> {
    let hidden = |c: char| c.is_control() && c != '\t';
    if !text.chars().any(hidden) {
        return std::borrow::Cow::Borrowed(text);
    }
    text.chars()
        .map(|c| match c as u32 {
            n @ 0..=0x1F if c != '\t' => char::from_u32(0x2400 + n).unwrap_or('\u{FFFD}'),
            0x7F => '\u{2421}',
            _ if hidden(c) => '\u{FFFD}',
            _ => c,
        })
        .collect::<String>()
        .into()
}

/// One underline under a source line: the primary span (`^`) or a label (`-`).
struct Mark<'a> {
    span: Span,
    mark: char,
    sev: Severity,
    label: &'a str,
}

/// Prints source line `line` once, then its marks: all of them on one row, with the label of
/// the rightmost labelled mark at its end; every other labelled mark gets a row of its own.
fn snippet(out: &mut String, st: &Style, file: &SourceFile, line: u32, marks: &[Mark<'_>], width: usize) {
    let pad = " ".repeat(width);
    let line_text = file.line_text(line);
    let shown = visible(&line_text.replace('\t', "    ")).into_owned();
    let _ = writeln!(out, "{} {} {}", st.blue(&format!("{line:>width$}")), st.blue("|"), shown);
    // Columns account for tabs expanded to four spaces.
    let cells = |span: Span| -> (usize, usize) {
        let start = file.line_col(span.start);
        let end = file.line_col(span.end);
        let col = (start.column as usize).saturating_sub(1);
        let indent = line_text.chars().take(col).map(|c| if c == '\t' { 4 } else { 1 }).sum::<usize>();
        let len = if end.line == start.line {
            let n = (end.column.saturating_sub(start.column)) as usize;
            line_text.chars().skip(col).take(n).map(|c| if c == '\t' { 4 } else { 1 }).sum::<usize>().max(1)
        } else {
            shown.chars().count().saturating_sub(indent).max(1)
        };
        (indent, len)
    };
    let paint = |m: &Mark<'_>, text: &str| if m.mark == '^' { st.severity(m.sev, text) } else { st.blue(text) };
    // The combined row: each mark at its columns (the primary one wins where they overlap).
    let placed: Vec<(usize, usize, &Mark<'_>)> = marks.iter().map(|m| (cells(m.span).0, cells(m.span).1, m)).collect();
    let row_end = placed.iter().map(|(i, l, _)| i + l).max().unwrap_or(0);
    let mut row = String::new();
    let mut col = 0;
    while col < row_end {
        let here = placed.iter().filter(|(i, l, _)| *i <= col && col < i + l).min_by_key(|(_, _, m)| m.mark != '^');
        match here {
            Some((_, _, m)) => {
                let mut run = 1;
                while col + run < row_end {
                    let next = placed
                        .iter()
                        .filter(|(i, l, _)| *i <= col + run && col + run < i + l)
                        .min_by_key(|(_, _, m)| m.mark != '^');
                    match next {
                        Some((_, _, n)) if std::ptr::eq(*n, *m) => run += 1,
                        _ => break,
                    }
                }
                row.push_str(&paint(m, &m.mark.to_string().repeat(run)));
                col += run;
            }
            None => {
                row.push(' ');
                col += 1;
            }
        }
    }
    // The label of the rightmost mark goes at the end of the row; the labels of marks further
    // left hang below them on connector lines, as rustc draws them.
    let rightmost = placed.iter().map(|(i, l, _)| i + l).max().unwrap_or(0);
    let mut hanging: Vec<(usize, &Mark<'_>)> = Vec::new();
    let mut inline = String::new();
    for (i, l, m) in &placed {
        if m.label.is_empty() {
            continue;
        }
        if i + l == rightmost && inline.is_empty() {
            inline = format!(" {}", visible(m.label));
        } else {
            hanging.push((*i, m));
        }
    }
    let _ = writeln!(out, "{pad} {} {row}{inline}", st.blue("|"));
    hanging.sort_by_key(|(i, _)| *i);
    // `|` under the first `upto` hanging marks; returns the text and its visible width (the
    // text holds colour codes).
    let connectors = |upto: usize| -> (String, usize) {
        let (mut line, mut width) = (String::new(), 0);
        for (i, m) in hanging.iter().take(upto) {
            line.push_str(&" ".repeat(i.saturating_sub(width)));
            line.push_str(&paint(m, "|"));
            width = i + 1;
        }
        (line, width)
    };
    if !hanging.is_empty() {
        let _ = writeln!(out, "{pad} {} {}", st.blue("|"), connectors(hanging.len()).0);
    }
    for k in (0..hanging.len()).rev() {
        let Some((i, m)) = hanging.get(k) else { continue };
        let (line, width) = connectors(k);
        let gap = " ".repeat(i.saturating_sub(width));
        let _ = writeln!(out, "{pad} {} {line}{gap}{}", st.blue("|"), paint(m, &visible(m.label)));
    }
}

/// One diagnostic as the JSON object of `interfaces.md`.
pub fn to_json_value(diag: &Diagnostic, files: &[SourceFile]) -> Value {
    let (file, start, end) = match file_of(files, diag.span) {
        Some(f) => (f.name.clone(), f.line_col(diag.span.start), f.line_col(diag.span.end)),
        None => (String::new(), crate::LineCol { line: 1, column: 1 }, crate::LineCol { line: 1, column: 1 }),
    };
    let witness = match &diag.witness {
        None => Value::Null,
        Some(Witness::Firing(ts)) => json!(ts),
        Some(Witness::Valuation(vs)) => {
            let mut m = Map::new();
            for (k, v) in vs {
                m.insert(k.clone(), v.clone());
            }
            Value::Object(m)
        }
    };
    json!({
        "code": diag.code,
        "severity": diag.severity.as_str(),
        "message": diag.message,
        "file": file,
        "line": start.line,
        "column": start.column,
        "end_line": end.line,
        "end_column": end.column,
        "element": diag.element,
        "notes": diag.notes,
        "witness": witness,
    })
}

/// All diagnostics as one pretty-printed JSON array.
pub fn render_json(diags: &[Diagnostic], files: &[SourceFile]) -> String {
    let arr: Vec<Value> = diags.iter().map(|d| to_json_value(d, files)).collect();
    // `{:#}` is the pretty form of `to_string_pretty`, without its impossible error.
    format!("{:#}", Value::Array(arr))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn human_form_points_at_the_span() {
        let f = SourceFile::new("a.st", "PROGRAM P\n  x := 1;\nEND_PROGRAM\n");
        let d = Diagnostic::new("SFC0301", Span::new(0, 12, 13), "undeclared variable `x`")
            .with_note("declare it in a VAR block");
        let s = render_human(&d, &[f], RenderOptions::default());
        assert_eq!(
            s,
            "error[SFC0301]: undeclared variable `x`\n --> a.st:2:3\n  |\n2 |   x := 1;\n  |   ^\n  = note: declare it in a VAR block\n"
        );
    }

    #[test]
    fn one_rendering_per_source_line() {
        let f = SourceFile::new("a.st", "PROGRAM P VAR x : INT; END_PROGRAM\n");
        let d = Diagnostic::error("SFC0102", Span::new(0, 23, 34), "missing `END_VAR`")
            .with_label(Span::new(0, 10, 13), "opened here");
        let s = render_human(&d, &[f], RenderOptions::default());
        assert_eq!(
            s,
            "error[SFC0102]: missing `END_VAR`\n --> a.st:1:24\n  |\n1 | PROGRAM P VAR x : INT; END_PROGRAM\n  |           ---          ^^^^^^^^^^^\n  |           |\n  |           opened here\n"
        );
        // A label right of the primary span stays on the row.
        let f = SourceFile::new("a.st", "ab cd\n");
        let d = Diagnostic::error("SFC0206", Span::new(0, 0, 2), "twice").with_label(Span::new(0, 3, 5), "first here");
        let s = render_human(&d, &[f], RenderOptions::default());
        assert!(s.ends_with("1 | ab cd\n  | ^^ -- first here\n"), "{s}");
        assert_eq!(s.matches("ab cd").count(), 1);
    }

    #[test]
    fn control_characters_never_reach_the_terminal() {
        // An escape sequence that would turn the terminal red, and a NUL, in the line shown.
        let f = SourceFile::new("a.st", "  x \u{1b}[31mRED\0 := 1;\n");
        let d = Diagnostic::error("SFC0101", Span::new(0, 14, 16), "found `\u{1b}[`").with_note("a\u{7}b");
        let s = render_human(&d, &[f], RenderOptions::default());
        assert!(!s.chars().any(|c| c.is_control() && c != '\n'), "{s:?}");
        assert!(s.contains("1 |   x ␛[31mRED␀ := 1;\n  |               ^^\n"), "{s}");
        assert!(s.contains("found `␛[`") && s.contains("note: a␇b"), "{s}");
    }

    #[test]
    fn json_has_contract_keys() {
        let f = SourceFile::new("a.st", "ab\ncd");
        let d = Diagnostic::new("SFC0201", Span::new(0, 3, 5), "no initial step").with_element("Main");
        let v = to_json_value(&d, &[f]);
        assert_eq!(v["line"], 2);
        assert_eq!(v["column"], 1);
        assert_eq!(v["end_line"], 2);
        assert_eq!(v["end_column"], 3);
        assert_eq!(v["element"], "Main");
        assert_eq!(v["witness"], Value::Null);
        assert_eq!(v["severity"], "error");
    }
}
