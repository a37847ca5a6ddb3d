//! Go to definition, find references and rename, within a POU and across the files of the
//! workspace.
//!
//! A name is either *local* (a variable, step, action or transition of one POU) or *global* (a
//! POU, a type, an enumerated value, a global variable and the `VAR_EXTERNAL` declarations that
//! refer to it): global names are matched by name over every file of the workspace.

use crate::index::{FileIndex, Symbol, SymbolKind};
use crate::workspace::{Analysis, Workspace};
use lsp_types::{Location, Range, TextEdit, Uri, WorkspaceEdit};
use sfc_diagnostics::Span;
use sfc_syntax::ast::VarKind;
use std::collections::HashMap;
use std::sync::Arc;

/// Which declared thing a name stands for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Identity {
    /// A symbol of one POU: the file's URI and the symbol's index.
    Local(String, usize),
    /// A workspace-level name (upper case).
    Global(String),
}

fn is_global(s: &Symbol) -> bool {
    s.pou.is_none() || matches!(&s.kind, SymbolKind::Variable(v) if v.section == VarKind::External)
}

/// The identity of symbol `id` of a file.
pub fn identity_of(uri: &Uri, ix: &FileIndex, id: usize) -> Option<Identity> {
    let s = ix.symbol(id)?;
    Some(if is_global(s) { Identity::Global(s.key()) } else { Identity::Local(uri.as_str().to_string(), id) })
}

/// What the name at `offset` stands for, with the span of the name under the cursor.
pub fn identity_at(uri: &Uri, a: &Analysis, offset: u32) -> Option<(Identity, Span)> {
    if let Some(id) = a.index.declaration_at(offset) {
        let s = a.index.symbol(id)?;
        return Some((identity_of(uri, &a.index, id)?, s.name_span));
    }
    let o = a.index.occurrence_at(offset)?;
    let id = match a.index.lookup(o.pou, &o.key) {
        Some(id) => identity_of(uri, &a.index, id)?,
        None => Identity::Global(o.key.clone()),
    };
    Some((id, o.span))
}

/// A symbol found somewhere in the workspace.
pub struct Found {
    pub uri: Uri,
    pub analysis: Arc<Analysis>,
    pub id: usize,
}

impl Found {
    pub fn symbol(&self) -> Option<&Symbol> {
        self.analysis.index.symbol(self.id)
    }
}

/// The declarations of an identity: the local symbol, or every workspace-level declaration of
/// the name (file-level ones first, the current file first).
pub fn declarations(ws: &mut Workspace, uri: &Uri, a: &Arc<Analysis>, identity: &Identity) -> Vec<Found> {
    match identity {
        Identity::Local(_, id) => vec![Found { uri: uri.clone(), analysis: a.clone(), id: *id }],
        Identity::Global(key) => {
            let mut files = vec![(uri.clone(), a.clone())];
            if a.index.lookup_global(key).is_none() {
                files.extend(ws.files().into_iter().filter(|(u, _)| u != uri));
            }
            let mut top = Vec::new();
            let mut external = Vec::new();
            for (u, fa) in files {
                for (id, s) in fa.index.symbols.iter().enumerate() {
                    if s.key() != *key || !is_global(s) {
                        continue;
                    }
                    let f = Found { uri: u.clone(), analysis: fa.clone(), id };
                    if s.pou.is_none() {
                        top.push(f);
                    } else {
                        external.push(f);
                    }
                }
            }
            if top.is_empty() {
                external
            } else {
                top
            }
        }
    }
}

/// Every place an identity is written: (uri, span, is_declaration).
pub fn references(
    ws: &mut Workspace,
    uri: &Uri,
    a: &Arc<Analysis>,
    identity: &Identity,
) -> Vec<(Uri, Arc<Analysis>, Span, bool)> {
    let mut out = Vec::new();
    match identity {
        Identity::Local(_, id) => {
            let Some(s) = a.index.symbol(*id) else { return out };
            if s.is_written() {
                out.push((uri.clone(), a.clone(), s.name_span, true));
            }
            let key = s.key();
            for o in &a.index.occurrences {
                if o.key == key && o.pou == s.pou && a.index.lookup(o.pou, &o.key) == Some(*id) {
                    out.push((uri.clone(), a.clone(), o.span, false));
                }
            }
        }
        Identity::Global(key) => {
            let mut files = ws.files();
            if !files.iter().any(|(u, _)| u == uri) {
                files.insert(0, (uri.clone(), a.clone()));
            }
            for (u, fa) in files {
                for s in fa.index.symbols.iter().filter(|s| s.key() == *key && is_global(s) && s.is_written()) {
                    out.push((u.clone(), fa.clone(), s.name_span, true));
                }
                for o in fa.index.occurrences.iter().filter(|o| o.key == *key) {
                    let global = match fa.index.lookup(o.pou, &o.key) {
                        Some(id) => fa.index.symbol(id).is_some_and(is_global),
                        None => true,
                    };
                    if global {
                        out.push((u.clone(), fa.clone(), o.span, false));
                    }
                }
            }
        }
    }
    out.sort_by(|x, y| (x.0.as_str(), x.2.start).cmp(&(y.0.as_str(), y.2.start)));
    out.dedup_by(|x, y| x.0 == y.0 && x.2 == y.2);
    out
}

pub fn location(uri: &Uri, a: &Analysis, span: Span) -> Location {
    Location::new(uri.clone(), a.range(span))
}

/// Words a new name may not be besides the language's own (`sfc_syntax::keywords`): the
/// access modes of VAR_ACCESS and the string types.
const MORE_KEYWORDS: &[&str] = &["READ_ONLY", "READ_WRITE", "STRING", "WSTRING"];

/// Why `name` cannot be a new name, if it cannot (IEC 61131-3 identifier rules, keywords,
/// standard names).
pub fn invalid_name(name: &str) -> Option<String> {
    let mut chars = name.chars();
    let first_ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    if !first_ok || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Some(format!(
            "`{name}` is not an IEC 61131-3 identifier (letters, digits and `_`, not starting with a digit)"
        ));
    }
    if name.contains("__") || name.ends_with('_') {
        return Some(format!("`{name}` is not an IEC 61131-3 identifier (no double `_`, no `_` at the end)"));
    }
    if sfc_syntax::keywords::cannot_name(name) || MORE_KEYWORDS.iter().any(|k| k.eq_ignore_ascii_case(name)) {
        return Some(format!("`{name}` is a keyword"));
    }
    if sfc_st::Type::elementary(name).is_some()
        || sfc_st::stdlib::std_function(name).is_some()
        || sfc_st::stdlib::std_function_block(name).is_some()
    {
        return Some(format!("`{name}` is a standard type, function or function block"));
    }
    None
}

/// The edits of a rename, or why it is refused.
pub fn rename(
    ws: &mut Workspace,
    uri: &Uri,
    a: &Arc<Analysis>,
    identity: &Identity,
    new_name: &str,
) -> Result<WorkspaceEdit, String> {
    if let Some(why) = invalid_name(new_name) {
        return Err(why);
    }
    let new_key = new_name.to_ascii_uppercase();
    if let Identity::Local(_, id) = identity {
        let s = a.index.symbol(*id).ok_or("the symbol is gone")?;
        match &s.kind {
            SymbolKind::Transition(t) if !t.named => {
                return Err(format!(
                    "the transition is unnamed (`{}` is its implicit name): name it in the text first",
                    s.name
                ))
            }
            SymbolKind::Variable(v) if v.implicit => {
                return Err(format!("`{}` is a control variable of every chart and cannot be renamed", s.name))
            }
            _ => {}
        }
        if let Some(p) = s.pou {
            if let Some(other) = a.index.lookup_local(p, &new_key).filter(|o| o != id) {
                let o = a.index.symbol(other).ok_or("the symbol is gone")?;
                let pou = a.index.pous.get(p).map(|e| e.name.as_str()).unwrap_or("");
                return Err(format!(
                    "`{}` is already a {} of `{pou}`: variables, steps, actions and transitions share one namespace (case-insensitive)",
                    o.name,
                    o.kind.noun()
                ));
            }
            if a.index.occurrences.iter().any(|o| o.pou == Some(p) && o.key == new_key) {
                return Err(format!(
                    "`{new_name}` already names something used in this POU; the rename would capture it"
                ));
            }
        }
    }
    let refs = references(ws, uri, a, identity);
    if refs.is_empty() {
        return Err("nothing to rename here".into());
    }
    if let Identity::Global(key) = identity {
        if key == &new_key {
            // Only the spelling changes.
        } else {
            for (_, fa, span, _) in &refs {
                if let Some(p) = fa.index.pou_at(span.start).filter(|_| fa.index.lookup_global(&new_key).is_none()) {
                    if let Some(other) = fa.index.lookup_local(p, &new_key) {
                        let o = fa.index.symbol(other).ok_or("the symbol is gone")?;
                        return Err(format!(
                            "`{}` is already a {} of a POU that uses this name",
                            o.name,
                            o.kind.noun()
                        ));
                    }
                }
            }
            for (_, fa) in ws.files() {
                if let Some(other) = fa.index.lookup_global(&new_key) {
                    let o = fa.index.symbol(other).ok_or("the symbol is gone")?;
                    return Err(format!("`{}` is already a {} of the workspace", o.name, o.kind.noun()));
                }
            }
        }
    }
    let mut changes: HashMap<Uri, Vec<TextEdit>> = HashMap::new();
    for (u, fa, span, _) in &refs {
        changes.entry(u.clone()).or_default().push(TextEdit::new(fa.range(*span), new_name.to_string()));
    }
    // The editor's layout (`sfc.graph`) names steps and transitions: keep it in step.
    if let Identity::Local(_, id) = identity {
        if let Some(s) = a.index.symbol(*id) {
            if matches!(s.kind, SymbolKind::Step(_) | SymbolKind::Transition(_)) {
                let edits = graph_edits(a, s, new_name);
                changes.entry(uri.clone()).or_default().extend(edits);
            }
        }
    }
    Ok(WorkspaceEdit { changes: Some(changes), ..WorkspaceEdit::default() })
}

/// Renames a step or transition inside the POU's `sfc.graph` attribute (`"s":"Name"`,
/// `"t":"Name"`).
fn graph_edits(a: &Analysis, s: &Symbol, new_name: &str) -> Vec<TextEdit> {
    let Some(pou) = s.pou.and_then(|p| a.index.pous.get(p)) else { return Vec::new() };
    let key = if matches!(s.kind, SymbolKind::Step(_)) { "\"s\":\"" } else { "\"t\":\"" };
    let mut edits = Vec::new();
    let Some(item) = a.unit.items.iter().find_map(|i| match i {
        sfc_syntax::ast::Item::Pou(p) if p.span == pou.span => Some(p),
        _ => None,
    }) else {
        return edits;
    };
    for attr in item.attributes.iter().filter(|at| at.name == "sfc.graph") {
        let text = a.text.get(attr.span.range()).unwrap_or("");
        let mut from = 0;
        while let Some(i) = text.get(from..).and_then(|t| t.find(key)) {
            let start = from + i + key.len();
            let end = start + s.name.len();
            let quoted_end = text.get(end..end + 1) == Some("\"");
            if quoted_end && text.get(start..end).is_some_and(|n| n.eq_ignore_ascii_case(&s.name)) {
                let span = Span::new(0, attr.span.start + start as u32, attr.span.start + end as u32);
                edits.push(TextEdit::new(a.range(span), new_name.to_string()));
            }
            from = end;
        }
    }
    edits
}

/// The range of the name under the cursor, if it can be renamed.
pub fn prepare_rename(uri: &Uri, a: &Analysis, offset: u32) -> Result<Range, String> {
    let (identity, span) = identity_at(uri, a, offset).ok_or("no name here")?;
    if let Identity::Local(_, id) = &identity {
        let s = a.index.symbol(*id).ok_or("no name here")?;
        if !s.is_written() {
            return Err(match &s.kind {
                SymbolKind::Transition(_) => {
                    format!("the transition is unnamed (`{}`): name it in the text first", s.name)
                }
                _ => format!("`{}` is implicit and cannot be renamed", s.name),
            });
        }
    }
    if let Identity::Global(key) = &identity {
        if sfc_st::Type::elementary(key).is_some()
            || sfc_st::stdlib::std_function_block(key).is_some()
            || sfc_st::stdlib::std_function(key).is_some()
        {
            return Err(format!("`{key}` is a standard name"));
        }
    }
    Ok(a.range(span))
}

#[cfg(test)]
mod tests {
    use super::invalid_name;

    /// A new name is checked against the language's own words (one list, in sfc-syntax), so
    /// the words of methods and properties are refused too.
    #[test]
    fn keywords_are_not_new_names() {
        for k in ["END_METHOD", "end_property", "IF", "FROM", "READ_WRITE", "STRING"] {
            assert!(invalid_name(k).is_some_and(|w| w.contains("keyword")), "{k}");
        }
        assert_eq!(invalid_name("Extend_Cylinder"), None);
    }
}
