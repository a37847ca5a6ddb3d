//! Code actions: apply a "did you mean" suggestion, mark a step `sfc.final`, give the
//! alternatives leaving a step explicit priorities (keeping the order they fire in today),
//! declare an undeclared variable.

use crate::check::DiagnosticData;
use crate::index::{FileIndex, SymbolKind};
use crate::workspace::Analysis;
use lsp_types::{CodeAction, CodeActionKind, CodeActionOrCommand, NumberOrString, Range, TextEdit, Uri, WorkspaceEdit};
use sfc_diagnostics::Span;
use sfc_syntax::ast::VarKind;
use std::collections::HashMap;

// `Uri` caches its parsed parts in cells, which clippy takes for a key that may change; its
// hash and equality are those of its text, which never changes.
#[allow(clippy::mutable_key_type)]
fn action(
    title: String,
    kind: CodeActionKind,
    uri: &Uri,
    edits: Vec<TextEdit>,
    diag: Option<&lsp_types::Diagnostic>,
) -> CodeActionOrCommand {
    let mut changes = HashMap::new();
    changes.insert(uri.clone(), edits);
    CodeActionOrCommand::CodeAction(CodeAction {
        title,
        kind: Some(kind),
        diagnostics: diag.map(|d| vec![d.clone()]),
        edit: Some(WorkspaceEdit { changes: Some(changes), ..WorkspaceEdit::default() }),
        is_preferred: diag.map(|_| true),
        ..CodeAction::default()
    })
}

fn code_of(d: &lsp_types::Diagnostic) -> &str {
    match &d.code {
        Some(NumberOrString::String(s)) => s,
        _ => "",
    }
}

/// The code actions for a range, given the diagnostics the client sends with the request.
pub fn code_actions(
    uri: &Uri,
    a: &Analysis,
    range: Range,
    diagnostics: &[lsp_types::Diagnostic],
) -> Vec<CodeActionOrCommand> {
    let mut out = Vec::new();
    let ix = &a.index;
    let mut offered_final = Vec::new();
    let mut offered_priority = Vec::new();
    for d in diagnostics.iter().filter(|d| d.source.as_deref() == Some("sfc")) {
        let data: DiagnosticData = d.data.clone().and_then(|v| serde_json::from_value(v).ok()).unwrap_or_default();
        let (start, end) = a.lines.offsets(&a.text, d.range);
        let written = a.text.get(start as usize..end as usize).unwrap_or("");
        let is_name = !written.is_empty() && written.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if is_name {
            for s in &data.suggestions {
                out.push(action(
                    format!("Replace `{written}` with `{s}`"),
                    CodeActionKind::QUICKFIX,
                    uri,
                    vec![TextEdit::new(d.range, s.clone())],
                    Some(d),
                ));
            }
        }
        let pou = ix.pou_at(start);
        match code_of(d) {
            "SFC0213" | "SFC0504" => {
                let step = data.element.clone().or_else(|| is_name.then(|| written.to_string()));
                if let Some(edit) = step.as_deref().and_then(|s| final_edit(a, pou, s)) {
                    offered_final.push(step.clone().unwrap_or_default().to_ascii_uppercase());
                    out.push(action(
                        format!("Mark step `{}` as final (sfc.final)", step.unwrap_or_default()),
                        CodeActionKind::QUICKFIX,
                        uri,
                        vec![edit],
                        Some(d),
                    ));
                }
            }
            "SFC0505" => {
                let steps = data
                    .element
                    .as_deref()
                    .and_then(|t| pou.and_then(|p| ix.lookup_local(p, &t.to_ascii_uppercase())))
                    .and_then(|id| match &ix.symbol(id)?.kind {
                        SymbolKind::Transition(t) => Some(t.from.clone()),
                        _ => None,
                    })
                    .unwrap_or_default();
                for step in steps {
                    if let Some(edits) = pou.and_then(|p| priority_edits(a, p, &step)) {
                        offered_priority.push(step.to_ascii_uppercase());
                        out.push(action(
                            format!("Add PRIORITY to the alternatives leaving `{step}` (in the order they fire now)"),
                            CodeActionKind::QUICKFIX,
                            uri,
                            edits,
                            Some(d),
                        ));
                    }
                }
            }
            "SFC0301" => {
                let name = d.message.split('`').nth(1).unwrap_or(written).to_string();
                if let Some(p) = pou {
                    let ty = guess_type(a, start, end);
                    for section in [VarKind::Var, VarKind::Input, VarKind::Output] {
                        if let Some(edit) = declare_edit(a, p, &name, ty, section) {
                            out.push(action(
                                format!("Declare `{name} : {ty}` in {}", section.keyword()),
                                CodeActionKind::QUICKFIX,
                                uri,
                                vec![edit],
                                (section == VarKind::Var).then_some(d),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    // On a step's name: the same two refactorings without a diagnostic.
    let at = a.lines.offset(&a.text, range.start);
    if let Some(s) = ix.declaration_at(at).and_then(|id| ix.symbol(id)) {
        if let (SymbolKind::Step(st), Some(p)) = (&s.kind, s.pou) {
            if !st.is_final && !offered_final.contains(&s.key()) {
                if let Some(edit) = final_edit(a, Some(p), &s.name) {
                    out.push(action(
                        format!("Mark step `{}` as final (sfc.final)", s.name),
                        CodeActionKind::REFACTOR_REWRITE,
                        uri,
                        vec![edit],
                        None,
                    ));
                }
            }
            if !offered_priority.contains(&s.key()) {
                if let Some(edits) = priority_edits(a, p, &s.name) {
                    out.push(action(
                        format!("Add PRIORITY to the alternatives leaving `{}` (in the order they fire now)", s.name),
                        CodeActionKind::REFACTOR_REWRITE,
                        uri,
                        edits,
                        None,
                    ));
                }
            }
        }
    }
    out
}

/// The indentation of the line holding `offset`.
fn indent_at(text: &str, offset: u32) -> String {
    let start = text.get(..offset as usize).and_then(|t| t.rfind('\n')).map_or(0, |i| i + 1);
    text.get(start..).unwrap_or("").chars().take_while(|c| *c == ' ' || *c == '\t').collect()
}

/// `{attribute 'sfc.final' := 'true'}` before step `name`.
fn final_edit(a: &Analysis, pou: Option<usize>, name: &str) -> Option<TextEdit> {
    let ix = &a.index;
    let s = ix.symbol(ix.lookup_local(pou?, &name.to_ascii_uppercase())?)?;
    match &s.kind {
        SymbolKind::Step(st) if !st.is_final => {}
        _ => return None,
    }
    let indent = indent_at(&a.text, s.span.start);
    let pos = a.lines.position(&a.text, s.span.start);
    Some(TextEdit::new(Range::new(pos, pos), format!("{{attribute 'sfc.final' := 'true'}}\n{indent}")))
}

/// Explicit priorities for the transitions leaving `step` that have none, numbered after the
/// highest one given, in declaration order: the order in which they fire does not change
/// (explicit priorities first, then declaration order; `semantics.md`).
fn priority_edits(a: &Analysis, pou: usize, step: &str) -> Option<Vec<TextEdit>> {
    let ix: &FileIndex = &a.index;
    let leaving: Vec<_> = ix
        .pou_symbols(pou)
        .filter_map(|(_, s)| match &s.kind {
            SymbolKind::Transition(t) if t.from.iter().any(|f| f.eq_ignore_ascii_case(step)) => Some(t),
            _ => None,
        })
        .collect();
    if leaving.len() < 2 || leaving.iter().all(|t| t.priority.is_some()) {
        return None;
    }
    let mut next = leaving.iter().filter_map(|t| t.priority.as_ref()?.trim().parse::<i64>().ok()).max().unwrap_or(0);
    let mut edits = Vec::new();
    for t in leaving.iter().filter(|t| t.priority.is_none()) {
        next += 1;
        let pos = a.lines.position(&a.text, t.priority_insert);
        edits.push(TextEdit::new(Range::new(pos, pos), format!(" (PRIORITY := {next})")));
    }
    Some(edits)
}

/// A type for a new variable from how it is used: BOOL unless the code around says otherwise.
fn guess_type(a: &Analysis, start: u32, end: u32) -> &'static str {
    let line_end = a.text.get(end as usize..).and_then(|t| t.find('\n')).map_or(a.text.len(), |i| end as usize + i);
    let line_start = a.text.get(..start as usize).and_then(|t| t.rfind('\n')).map_or(0, |i| i + 1);
    let after = a.text.get(end as usize..line_end).unwrap_or("").trim_start();
    let before = a.text.get(line_start..start as usize).unwrap_or("").trim_end();
    let near = format!("{} {}", before.rsplit(['(', ';']).next().unwrap_or(""), after);
    let upper = near.to_ascii_uppercase();
    if upper.contains("T#") || upper.contains("TIME#") {
        "TIME"
    } else if ["<", ">", "+", "-", "*", "/"].iter().any(|op| near.contains(op)) {
        "INT"
    } else if after.starts_with(":=") {
        let value = after.trim_start_matches(":=").trim_start();
        if value.starts_with(|c: char| c.is_ascii_digit()) {
            "INT"
        } else {
            "BOOL"
        }
    } else {
        "BOOL"
    }
}

/// Adds `name : ty;` to the POU's first block of `section`, or a new block after the header.
fn declare_edit(a: &Analysis, pou: usize, name: &str, ty: &str, section: VarKind) -> Option<TextEdit> {
    let p = a.index.pous.get(pou)?;
    let text = a.text.as_str();
    let decl = format!("{name} : {ty};");
    if let Some((_, span)) = p.var_blocks.iter().find(|(k, _)| *k == section) {
        let block = text.get(span.range())?;
        let end_var = span.start + block.to_ascii_uppercase().rfind("END_VAR")? as u32;
        let indent = indent_at(text, end_var);
        let line_start = end_var - indent.len() as u32;
        let own_line = text.get(line_start as usize..end_var as usize).is_some_and(|s| s.trim().is_empty())
            && line_start > span.start;
        let (at, insert) = if own_line {
            // The indentation of the declarations, or one level deeper than END_VAR.
            let inner = format!("{indent}    ");
            (line_start, format!("{inner}{decl}\n"))
        } else {
            (end_var, format!("{decl} "))
        };
        let pos = a.lines.position(text, at);
        return Some(TextEdit::new(Range::new(pos, pos), insert));
    }
    // A new block after the header (after the last block when there are blocks).
    let after = p.var_blocks.iter().map(|(_, s)| s.end).max().unwrap_or(p.header_end);
    let indent = indent_at(text, p.name_span.start);
    let inner = format!("{indent}    ");
    let pos = a.lines.position(text, after);
    let _ = Span::default();
    Some(TextEdit::new(
        Range::new(pos, pos),
        format!("\n{inner}{}\n{inner}    {decl}\n{inner}END_VAR", section.keyword()),
    ))
}
