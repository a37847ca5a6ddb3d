//! Copying Structured Text action bodies into the generated POU.
//!
//! A body is copied as written (comments included), re-indented. The names it uses mean the
//! same in the generated POU: `S.X` / `S.T` read the generated step variables (a structure
//! with the fields `X` and `T`), `A.Q` / `A.A` the outputs of the action's control block, so
//! no reference needs rewriting. The one statement that changes meaning is `RETURN`: in an
//! action it ends the action, in the generated POU it would end the whole scan. The body is
//! therefore wrapped in `REPEAT … UNTIL TRUE END_REPEAT` and each `RETURN` becomes `EXIT`;
//! inside a loop of the body it sets a flag first, and every loop that contains a `RETURN` is
//! followed by `IF flag THEN EXIT; END_IF;`, so the exit propagates out to the wrapper.

use sfc_syntax::ast::{Stmt, StmtKind};

/// Byte range of the statements of an action in the source: after the `:` that follows the
/// name, up to the `END_ACTION` keyword.
pub(crate) fn action_body_range(src: &str, name_end: u32, span_end: u32) -> Option<(usize, usize)> {
    let end = (span_end as usize).min(src.len());
    let start = name_end as usize;
    let head = src.get(start..end)?;
    let colon = start + head.find(':')? + 1;
    let upper = src.get(colon..end)?.to_ascii_uppercase();
    let stop = colon + upper.rfind("END_ACTION")?;
    Some((colon, stop))
}

/// The statements of a body as lines, common indentation removed.
pub(crate) fn body_lines(
    src: &str,
    range: (usize, usize),
    stmts: &[Stmt],
    return_flag: &mut dyn FnMut() -> String,
) -> Vec<String> {
    let (start, end) = range;
    let mut edits: Vec<(usize, usize, String)> = Vec::new();
    let has_return = stmts.iter().any(contains_return);
    let mut flag_used = false;
    let mut flag = String::new();
    if has_return {
        let mut flag_name = || {
            if flag.is_empty() {
                flag = return_flag();
            }
            flag.clone()
        };
        collect(stmts, src, 0, &mut edits, &mut flag_name, &mut flag_used);
    }
    edits.sort_by_key(|e| e.0);
    let mut text = String::new();
    let mut pos = start;
    for (s, e, r) in edits {
        if s < pos || e > end {
            continue;
        }
        text.push_str(&src[pos..s]);
        text.push_str(&r);
        pos = e;
    }
    text.push_str(&src[pos..end]);
    let lines = reindent(&text, column_of(src, start));
    if !has_return {
        return lines;
    }
    let mut out = Vec::new();
    if flag_used {
        out.push(format!("{flag} := FALSE;"));
    }
    out.push("REPEAT (* the action body; EXIT leaves it as RETURN does *)".to_string());
    out.extend(lines.into_iter().map(|l| if l.is_empty() { l } else { format!("    {l}") }));
    out.push("UNTIL TRUE END_REPEAT;".to_string());
    out
}

fn contains_return(s: &Stmt) -> bool {
    match &s.kind {
        StmtKind::Return => true,
        StmtKind::If { branches, else_body } => {
            branches.iter().any(|(_, b)| b.iter().any(contains_return))
                || else_body.iter().flatten().any(contains_return)
        }
        StmtKind::Case { arms, else_body, .. } => {
            arms.iter().any(|a| a.body.iter().any(contains_return)) || else_body.iter().flatten().any(contains_return)
        }
        StmtKind::For { body, .. } | StmtKind::While { body, .. } | StmtKind::Repeat { body, .. } => {
            body.iter().any(contains_return)
        }
        _ => false,
    }
}

/// The edits for the RETURNs of `stmts` at loop depth `loops`.
fn collect(
    stmts: &[Stmt],
    src: &str,
    loops: u32,
    edits: &mut Vec<(usize, usize, String)>,
    flag: &mut dyn FnMut() -> String,
    flag_used: &mut bool,
) {
    for s in stmts {
        match &s.kind {
            StmtKind::Return => {
                let r = if loops == 0 {
                    "EXIT;".to_string()
                } else {
                    *flag_used = true;
                    format!("{} := TRUE; EXIT;", flag())
                };
                edits.push((s.span.start as usize, s.span.end as usize, r));
            }
            StmtKind::If { branches, else_body } => {
                for (_, b) in branches {
                    collect(b, src, loops, edits, flag, flag_used);
                }
                if let Some(b) = else_body {
                    collect(b, src, loops, edits, flag, flag_used);
                }
            }
            StmtKind::Case { arms, else_body, .. } => {
                for a in arms {
                    collect(&a.body, src, loops, edits, flag, flag_used);
                }
                if let Some(b) = else_body {
                    collect(b, src, loops, edits, flag, flag_used);
                }
            }
            StmtKind::For { body, .. } | StmtKind::While { body, .. } | StmtKind::Repeat { body, .. }
                if body.iter().any(contains_return) =>
            {
                collect(body, src, loops + 1, edits, flag, flag_used);
                let end = s.span.end as usize;
                let semi = if src[..end.min(src.len())].trim_end().ends_with(';') { "" } else { ";" };
                edits.push((end, end, format!("{semi} IF {} THEN EXIT; END_IF;", flag())));
            }
            _ => {}
        }
    }
}

/// The column (in characters) of byte offset `at` in its line.
fn column_of(src: &str, at: usize) -> usize {
    let line_start = src[..at.min(src.len())].rfind('\n').map_or(0, |i| i + 1);
    src[line_start..at.min(src.len())].chars().count()
}

/// Splits `text` into lines, drops leading and trailing blank lines and removes the common
/// indentation. `first_col` is the column the text starts at in the source (the first line's
/// own indentation is counted from there).
pub(crate) fn reindent(text: &str, first_col: usize) -> Vec<String> {
    let mut lines: Vec<(usize, String)> = Vec::new();
    for (i, l) in text.split('\n').enumerate() {
        let l = l.trim_end_matches('\r').trim_end();
        let lead = l.len() - l.trim_start().len();
        let indent = if i == 0 { first_col + lead } else { lead };
        lines.push((indent, l.trim_start().to_string()));
    }
    while lines.first().is_some_and(|l| l.1.is_empty()) {
        lines.remove(0);
    }
    while lines.last().is_some_and(|l| l.1.is_empty()) {
        lines.pop();
    }
    let common = lines.iter().filter(|l| !l.1.is_empty()).map(|l| l.0).min().unwrap_or(0);
    lines
        .into_iter()
        .map(|(ind, l)| if l.is_empty() { l } else { format!("{}{l}", " ".repeat(ind - common)) })
        .collect()
}
