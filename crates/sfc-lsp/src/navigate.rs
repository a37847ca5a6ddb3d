//! Go to definition, find references and rename, within a POU and across the files of the
//! workspace.
//!
//! A name is either *local* (a variable, step, action, transition, method or property of one
//! POU, or a variable of a method or accessor) or *global* (a POU, a type, an enumerated value,
//! a global variable and the `VAR_EXTERNAL` declarations that refer to it): global names are
//! matched by name over every file of the workspace. A member of a block (a method, property,
//! action or variable of a FUNCTION_BLOCK or PROGRAM) is local, but reached from other POUs and
//! files as `inst.Member` (the block of `inst`'s type, or one it extends), `THIS^.Member` and
//! `SUPER^.Member`, and inside blocks extending it by its name alone: a [`Resolver`] finds
//! those, and references of a member look at every file.

use crate::index::{FileIndex, MemberBase, MemberUse, Occurrence, Symbol, SymbolKind};
use crate::workspace::{Analysis, Workspace};
use lsp_types::{Location, Range, TextEdit, Uri, WorkspaceEdit};
use sfc_diagnostics::Span;
use sfc_syntax::ast::{PouKind, VarKind};
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

/// Whether a symbol of file `ix` can be named outside its POU: as `inst.Name` (a method,
/// property, action or variable of a FUNCTION_BLOCK or PROGRAM), by a block inheriting it, or
/// as a formal parameter of a call (`Start(s := 1)`, `F(a := 1)`).
fn is_member(ix: &FileIndex, s: &Symbol) -> bool {
    let block = s.pou.and_then(|p| ix.pous.get(p)).is_some_and(|p| p.kind != PouKind::Function);
    let parameter = matches!(&s.kind, SymbolKind::Variable(v)
        if matches!(v.section, VarKind::Input | VarKind::Output | VarKind::InOut));
    if s.pou.is_none() || s.scope.is_some() || !block {
        return s.pou.is_some() && parameter;
    }
    match &s.kind {
        SymbolKind::Method | SymbolKind::Property | SymbolKind::Action => true,
        SymbolKind::Variable(v) => !v.implicit && v.section != VarKind::External,
        _ => false,
    }
}

/// The identity of symbol `id` of a file.
pub fn identity_of(uri: &Uri, ix: &FileIndex, id: usize) -> Option<Identity> {
    let s = ix.symbol(id)?;
    Some(if is_global(s) { Identity::Global(s.key()) } else { Identity::Local(uri.as_str().to_string(), id) })
}

/// A symbol of a file: its URI, its analysis, its index there.
pub type Target = (Uri, Arc<Analysis>, usize);

/// Finds what names stand for when the answer may be in another file: the members of blocks
/// (`inst.M`, `THIS^.M`, `SUPER^.M`) and the names a block inherits (`EXTENDS`). A block is
/// looked for in the file first, then in the workspace (listed once, when first needed).
pub struct Resolver<'w> {
    ws: &'w mut Workspace,
    files: Option<Vec<(Uri, Arc<Analysis>)>>,
}

/// How many blocks an `EXTENDS` chain is followed through (a cycle is an error of the text).
const MAX_EXTENDS: usize = 16;

impl<'w> Resolver<'w> {
    pub fn new(ws: &'w mut Workspace) -> Resolver<'w> {
        Resolver { ws, files: None }
    }

    /// The files of the workspace.
    fn files(&mut self) -> &[(Uri, Arc<Analysis>)] {
        let ws = &mut *self.ws;
        self.files.get_or_insert_with(|| ws.files())
    }

    /// Every file of the workspace, `uri` first with the analysis `a` (it may not be open or
    /// under a workspace folder).
    pub fn all_files(&mut self, uri: &Uri, a: &Arc<Analysis>) -> Vec<(Uri, Arc<Analysis>)> {
        let mut out = vec![(uri.clone(), a.clone())];
        out.extend(self.files().iter().filter(|(u, _)| u != uri).cloned());
        out
    }

    /// The POU named `name`: in file `uri` itself, else the first of the workspace.
    fn pou(&mut self, uri: &Uri, a: &Arc<Analysis>, name: &str) -> Option<(Uri, Arc<Analysis>, usize)> {
        let find = |fa: &Analysis| fa.index.pous.iter().position(|p| p.name.eq_ignore_ascii_case(name));
        if let Some(p) = find(a) {
            return Some((uri.clone(), a.clone(), p));
        }
        self.files().iter().filter(|(u, _)| u != uri).find_map(|(u, fa)| Some((u.clone(), fa.clone(), find(fa)?)))
    }

    /// The member `key` of POU `pou` of a file, its own or inherited (`EXTENDS`).
    fn member_of(&mut self, uri: &Uri, a: &Arc<Analysis>, pou: usize, key: &str) -> Option<Target> {
        let (mut u, mut fa, mut p) = (uri.clone(), a.clone(), pou);
        for _ in 0..MAX_EXTENDS {
            if let Some(id) = fa.index.lookup_local(p, key) {
                return Some((u, fa, id));
            }
            let base = fa.index.pous.get(p)?.extends.clone()?;
            (u, fa, p) = self.pou(&u, &fa, &base)?;
        }
        None
    }

    /// What `key` stands for in the code of POU `pou` (in scope `scope`) of a file: a name of
    /// the method or accessor, of the POU, one its block inherits, then a file-level name of
    /// the file (None: not one of those).
    fn name(
        &mut self,
        uri: &Uri,
        a: &Arc<Analysis>,
        pou: Option<usize>,
        scope: Option<usize>,
        key: &str,
    ) -> Option<Target> {
        let own = scope.and_then(|sc| a.index.lookup_scoped(sc, key)).or_else(|| a.index.lookup_local(pou?, key));
        if let Some(id) = own {
            return Some((uri.clone(), a.clone(), id));
        }
        if let Some(base) = pou.and_then(|p| a.index.pous.get(p)).and_then(|e| e.extends.clone()) {
            if let Some((u, fa, bp)) = self.pou(uri, a, &base) {
                if let Some(t) = self.member_of(&u, &fa, bp, key) {
                    return Some(t);
                }
            }
        }
        a.index.lookup_global(key).map(|id| (uri.clone(), a.clone(), id))
    }

    /// What a use of a name in file `uri` stands for (None: a name of no file of the
    /// workspace, or one declared in another file).
    pub fn occurrence(&mut self, uri: &Uri, a: &Arc<Analysis>, o: &Occurrence) -> Option<Target> {
        self.name(uri, a, o.pou, o.scope, &o.key)
    }

    /// The member of a block that `m` names (None: the member of a step, an action's `Q`, a
    /// standard block's output, a name whose type is no block of the workspace).
    pub fn member(&mut self, uri: &Uri, a: &Arc<Analysis>, m: &MemberUse) -> Option<Target> {
        self.member_in(uri, a, m.pou, m.scope, &m.base, &m.key)
    }

    /// The member `key` of what `base` stands for in the code of POU `pou` (scope `scope`).
    fn member_in(
        &mut self,
        uri: &Uri,
        a: &Arc<Analysis>,
        pou: Option<usize>,
        scope: Option<usize>,
        base: &MemberBase,
        key: &str,
    ) -> Option<Target> {
        let (u, fa, p) = match base {
            MemberBase::Name(name) => {
                let found = match self.name(uri, a, pou, scope, name) {
                    Some(t) => Some(t),
                    // A global variable of another file.
                    None => self
                        .files()
                        .iter()
                        .filter(|(u, _)| u != uri)
                        .find_map(|(u, fa)| fa.index.lookup_global(key).map(|id| (u.clone(), fa.clone(), id))),
                };
                let (bu, ba, id) = found?;
                match &ba.index.symbol(id)?.kind {
                    SymbolKind::Variable(v) => {
                        let ty = v.type_name.clone()?;
                        self.pou(uri, a, &ty)?
                    }
                    SymbolKind::Pou(_) => {
                        let span = ba.index.symbol(id)?.name_span;
                        let p = ba.index.pous.iter().position(|e| e.name_span == span)?;
                        (bu, ba, p)
                    }
                    _ => return None,
                }
            }
            MemberBase::This => (uri.clone(), a.clone(), pou?),
            MemberBase::Super => {
                let base = a.index.pous.get(pou?)?.extends.clone()?;
                self.pou(uri, a, &base)?
            }
            MemberBase::CallOf(callee) => {
                let called = match self.name(uri, a, pou, scope, callee) {
                    Some(t) => t,
                    // A function of another file.
                    None => {
                        let (pu, pa, p) = self.pou(uri, a, callee)?;
                        let span = pa.index.pous.get(p)?.name_span;
                        let id = pa.index.symbols.iter().position(|s| s.pou.is_none() && s.name_span == span)?;
                        (pu, pa, id)
                    }
                };
                return self.parameter(uri, a, called, key);
            }
            MemberBase::CallOfMember(base, member) => {
                let called = self.member_in(uri, a, pou, scope, base, member)?;
                return self.parameter(uri, a, called, key);
            }
        };
        self.member_of(&u, &fa, p, key)
    }

    /// The formal parameter `key` of what a call in file `uri` calls: a variable of a method,
    /// of the block of an instance, of a function.
    fn parameter(&mut self, uri: &Uri, a: &Arc<Analysis>, called: Target, key: &str) -> Option<Target> {
        let (u, fa, id) = called;
        let s = fa.index.symbol(id)?;
        match &s.kind {
            SymbolKind::Method => {
                let sc = fa.index.scopes.iter().position(|sc| sc.owner == id)?;
                let v = fa.index.lookup_scoped(sc, key)?;
                Some((u, fa, v))
            }
            SymbolKind::Variable(v) => {
                let ty = v.type_name.clone()?;
                let (pu, pa, p) = self.pou(uri, a, &ty)?;
                self.member_of(&pu, &pa, p, key)
            }
            SymbolKind::Pou(_) => {
                let p = fa.index.pous.iter().position(|e| e.name_span == s.name_span)?;
                let v = fa.index.lookup_local(p, key)?;
                Some((u, fa, v))
            }
            _ => None,
        }
    }
}

/// The file of a local identity's URI: `a` when it is `uri`'s, else the workspace's.
fn file_of(ws: &mut Workspace, uri: &Uri, a: &Arc<Analysis>, of: &str) -> Option<(Uri, Arc<Analysis>)> {
    if of == uri.as_str() {
        return Some((uri.clone(), a.clone()));
    }
    let u: Uri = of.parse().ok()?;
    let fa = ws.analysis(&u)?;
    Some((u, fa))
}

/// What the name at `offset` stands for, with the span of the name under the cursor.
pub fn identity_at(ws: &mut Workspace, uri: &Uri, a: &Arc<Analysis>, offset: u32) -> Option<(Identity, Span)> {
    if let Some(id) = a.index.declaration_at(offset) {
        let s = a.index.symbol(id)?;
        return Some((identity_of(uri, &a.index, id)?, s.name_span));
    }
    let mut r = Resolver::new(ws);
    if let Some(m) = a.index.member_at(offset) {
        // A member that is none of a block of the workspace (`S1.X`, `Timer.Q`) is no name.
        let (u, fa, id) = r.member(uri, a, m)?;
        return Some((identity_of(&u, &fa.index, id)?, m.span));
    }
    let o = a.index.occurrence_at(offset)?;
    let id = match r.occurrence(uri, a, o) {
        Some((u, fa, id)) => identity_of(&u, &fa.index, id)?,
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
        Identity::Local(of, id) => match file_of(ws, uri, a, of) {
            Some((u, fa)) if fa.index.symbol(*id).is_some() => vec![Found { uri: u, analysis: fa, id: *id }],
            _ => Vec::new(),
        },
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
        Identity::Local(of, id) => {
            let Some((su, sa)) = file_of(ws, uri, a, of) else { return out };
            let Some(s) = sa.index.symbol(*id) else { return out };
            if s.is_written() {
                out.push((su.clone(), sa.clone(), s.name_span, true));
            }
            let key = s.key();
            if is_member(&sa.index, s) {
                // Used by name in its block and those extending it, as a member anywhere.
                let mut r = Resolver::new(ws);
                let is_it = |t: Option<Target>| t.is_some_and(|(u, _, i)| u == su && i == *id);
                for (fu, fa) in r.all_files(uri, a) {
                    for o in fa.index.occurrences.iter().filter(|o| o.key == key) {
                        if is_it(r.occurrence(&fu, &fa, o)) {
                            out.push((fu.clone(), fa.clone(), o.span, false));
                        }
                    }
                    for m in fa.index.members.iter().filter(|m| m.key == key) {
                        if is_it(r.member(&fu, &fa, m)) {
                            out.push((fu.clone(), fa.clone(), m.span, false));
                        }
                    }
                }
            } else {
                for o in &sa.index.occurrences {
                    if o.key == key && o.pou == s.pou && sa.index.resolve(o) == Some(*id) {
                        out.push((su.clone(), sa.clone(), o.span, false));
                    }
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
                    let global = match fa.index.resolve(o) {
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
#[allow(clippy::mutable_key_type)] // `Uri`: see `actions::action`.
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
    if let Identity::Local(of, id) = identity {
        let (_, sa) = file_of(ws, uri, a, of).ok_or("the symbol is gone")?;
        local_rename_allowed(&sa.index, *id, new_name)?;
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
    if let Identity::Local(of, id) = identity {
        if let Some((su, sa)) = file_of(ws, uri, a, of) {
            if let Some(s) = sa.index.symbol(*id) {
                if matches!(s.kind, SymbolKind::Step(_) | SymbolKind::Transition(_)) {
                    let edits = graph_edits(&sa, s, new_name);
                    changes.entry(su).or_default().extend(edits);
                }
            }
        }
    }
    Ok(WorkspaceEdit { changes: Some(changes), ..WorkspaceEdit::default() })
}

/// Why symbol `id` of a POU cannot be renamed `new_name` in its file, if it cannot: an implicit
/// name, a name of the same namespace, a use the new name would capture, a method's variable
/// hiding the new name or hidden by it.
fn local_rename_allowed(ix: &FileIndex, id: usize, new_name: &str) -> Result<(), String> {
    let new_key = new_name.to_ascii_uppercase();
    let s = ix.symbol(id).ok_or("the symbol is gone")?;
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
    let Some(p) = s.pou else { return Ok(()) };
    let pou = ix.pous.get(p).map(|e| e.name.as_str()).unwrap_or("");
    if let Some(sc) = s.scope {
        // A variable of a method or accessor: its namespace, inside the POU's.
        let owner = ix.scopes.get(sc).and_then(|e| ix.symbol(e.owner)).map(|o| o.name.as_str()).unwrap_or("");
        if let Some(other) = ix.lookup_scoped(sc, &new_key).filter(|o| *o != id) {
            let o = ix.symbol(other).ok_or("the symbol is gone")?;
            return Err(format!("`{}` is already a variable of `{owner}`", o.name));
        }
        if let Some(other) = ix.lookup_local(p, &new_key) {
            let o = ix.symbol(other).ok_or("the symbol is gone")?;
            return Err(format!(
                "`{}` is already a {} of `{pou}`: the variable of `{owner}` would hide it",
                o.name,
                o.kind.noun()
            ));
        }
        if ix.occurrences.iter().any(|o| o.scope == Some(sc) && o.key == new_key) {
            return Err(format!("`{new_name}` already names something used in `{owner}`; the rename would capture it"));
        }
        return Ok(());
    }
    if let Some(other) = ix.lookup_local(p, &new_key).filter(|o| *o != id) {
        let o = ix.symbol(other).ok_or("the symbol is gone")?;
        return Err(format!(
            "`{}` is already a {} of `{pou}`: variables, steps, actions, transitions, methods and properties share one namespace (case-insensitive)",
            o.name,
            o.kind.noun()
        ));
    }
    // A use of the new name that is no variable of a method would mean the renamed symbol.
    let captured = ix
        .occurrences
        .iter()
        .filter(|o| o.pou == Some(p) && o.key == new_key && ix.resolve(o) != Some(id))
        .any(|o| o.scope.is_none_or(|sc| ix.lookup_scoped(sc, &new_key).is_none()));
    if captured {
        return Err(format!("`{new_name}` already names something used in this POU; the rename would capture it"));
    }
    // A method using the symbol with a variable of the new name would hide it.
    let key = s.key();
    for (sc, e) in ix.scopes.iter().enumerate().filter(|(_, e)| e.pou == p) {
        let used = ix.occurrences.iter().any(|o| o.scope == Some(sc) && o.key == key && ix.resolve(o) == Some(id));
        if used && ix.lookup_scoped(sc, &new_key).is_some() {
            let owner = ix.symbol(e.owner).map(|o| o.name.as_str()).unwrap_or("");
            return Err(format!("`{owner}` uses `{}` and has a variable `{new_name}`, which would hide it", s.name));
        }
    }
    Ok(())
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
    for attr in item.attributes.iter().filter(|at| at.name.starts_with("sfc.graph")) {
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
pub fn prepare_rename(ws: &mut Workspace, uri: &Uri, a: &Arc<Analysis>, offset: u32) -> Result<Range, String> {
    let (identity, span) = identity_at(ws, uri, a, offset).ok_or("no name here")?;
    if let Identity::Local(of, id) = &identity {
        let (_, sa) = file_of(ws, uri, a, of).ok_or("no name here")?;
        let s = sa.index.symbol(*id).ok_or("no name here")?;
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
    use super::*;
    use crate::workspace::Document;

    /// A function block with a method, a property and an action, used from another POU.
    const MOTOR: &str = "FUNCTION_BLOCK Motor
  VAR_INPUT speed : INT; END_VAR
  VAR_OUTPUT on : BOOL; END_VAR
  VAR count : INT; tmp : INT; END_VAR
  METHOD Start : BOOL
    VAR_INPUT s : INT; END_VAR
    VAR tmp : INT; END_VAR
    tmp := s + speed; count := count + 1; on := TRUE; Start := TRUE;
  END_METHOD
  PROPERTY Running : BOOL
    GET Running := on; END_GET
    SET on := Running; END_SET
  END_PROPERTY
  count := 0; tmp := 1;
  ACTION Reset:
    count := 0; Start(s := 1); THIS^.Start(s := 2);
  END_ACTION
END_FUNCTION_BLOCK
";

    const MAIN: &str = "PROGRAM Main
  VAR m : Motor; ok : BOOL; END_VAR
  m(speed := 3);
  ok := m.Start(s := 5);
  IF m.Running THEN m.Reset(); END_IF
  m.Running := FALSE;
END_PROGRAM
";

    fn analysis(text: &str) -> Arc<Analysis> {
        Arc::new(Analysis::new(Arc::new(text.to_string())))
    }

    fn uri(name: &str) -> Uri {
        format!("file:///sfc-lsp-test/{name}").parse().unwrap()
    }

    /// The offset of the `n`-th `needle` in `text`, plus `delta`.
    fn at(text: &str, needle: &str, n: usize, delta: u32) -> u32 {
        text.match_indices(needle).nth(n).unwrap_or_else(|| panic!("`{needle}` #{n}")).0 as u32 + delta
    }

    /// Where go to definition leads from `offset`: (file name, offset of the declared name).
    fn definition(ws: &mut Workspace, u: &Uri, a: &Arc<Analysis>, offset: u32) -> Vec<(String, u32)> {
        let Some((identity, _)) = identity_at(ws, u, a, offset) else { return Vec::new() };
        declarations(ws, u, a, &identity)
            .iter()
            .map(|f| (f.uri.as_str().rsplit('/').next().unwrap().to_string(), f.symbol().unwrap().name_span.start))
            .collect()
    }

    /// The text of each file after a rename from `offset` (files unchanged left out).
    fn renamed(
        ws: &mut Workspace,
        u: &Uri,
        a: &Arc<Analysis>,
        offset: u32,
        new_name: &str,
    ) -> Result<HashMap<String, String>, String> {
        let (identity, _) = identity_at(ws, u, a, offset).ok_or("no name")?;
        prepare_rename(ws, u, a, offset)?;
        let edit = rename(ws, u, a, &identity, new_name)?;
        let mut out = HashMap::new();
        for (fu, mut edits) in edit.changes.unwrap() {
            let fa = ws.analysis(&fu).unwrap_or_else(|| a.clone());
            let mut text = fa.text.to_string();
            edits.sort_by_key(|e| std::cmp::Reverse((e.range.start.line, e.range.start.character)));
            for e in edits {
                let (s, en) = fa.lines.offsets(&fa.text, e.range);
                text.replace_range(s as usize..en as usize, &e.new_text);
            }
            out.insert(fu.as_str().rsplit('/').next().unwrap().to_string(), text);
        }
        Ok(out)
    }

    /// One file holding both POUs, not open in any workspace.
    fn one_file() -> (Workspace, Uri, Arc<Analysis>, String) {
        let text = format!("{MOTOR}\n{MAIN}");
        (Workspace::new(Vec::new()), uri("one.st"), analysis(&text), text)
    }

    #[test]
    fn definition_of_method_variables_block_variables_and_members() {
        let (mut ws, u, a, t) = one_file();
        let here = |n: &str, k: usize| ("one.st".to_string(), at(&t, n, k, 0));
        let mut def = |offset| definition(&mut ws, &u, &a, offset);
        // The method's own `tmp` and `s`, not the block's `tmp`.
        assert_eq!(def(at(&t, "tmp := s", 0, 1)), [here("tmp : INT; END_VAR\n    tmp", 0)]);
        assert_eq!(def(at(&t, "s + speed", 0, 0)), [here("s : INT", 0)]);
        // The block's variables, used in the method and in the body.
        assert_eq!(def(at(&t, "speed;", 0, 2)), [here("speed : INT", 0)]);
        assert_eq!(def(at(&t, "count + 1", 0, 2)), [here("count : INT", 0)]);
        assert_eq!(def(at(&t, "tmp := 1", 0, 0)), [here("tmp : INT; END_VAR\n  METHOD", 0)]);
        // The method: its result, called in the block's action, through THIS^, and on an instance.
        let method = || here("Start : BOOL", 0);
        for offset in [
            at(&t, "Start := TRUE", 0, 0),
            at(&t, "Start(s := 1)", 0, 2),
            at(&t, "THIS^.Start", 0, 6),
            at(&t, "m.Start", 0, 2),
            at(&t, "m.Start", 0, 7),
        ] {
            assert_eq!(def(offset), [method()], "at {offset}");
        }
        // The property (read and written) and the action of an instance.
        let property = || here("Running : BOOL", 0);
        assert_eq!(def(at(&t, "m.Running THEN", 0, 3)), [property()]);
        assert_eq!(def(at(&t, "m.Running :=", 0, 3)), [property()]);
        assert_eq!(def(at(&t, "GET Running", 0, 5)), [property()]);
        assert_eq!(def(at(&t, "on := Running", 0, 7)), [property()]);
        assert_eq!(def(at(&t, "m.Reset", 0, 3)), [here("Reset:", 0)]);
        // The formal parameters of calls: the method's.
        assert_eq!(def(at(&t, "(s := 1)", 0, 1)), [here("s : INT", 0)]);
        assert_eq!(def(at(&t, "(s := 5)", 0, 1)), [here("s : INT", 0)]);
        // The instance itself is still its variable.
        assert_eq!(def(at(&t, "m.Reset", 0, 0)), [here("m : Motor", 0)]);
        // Hover says whose variable it is, and what a member is.
        let hover = |ws: &mut Workspace, offset| match crate::hover::hover(ws, &u, &a, offset).unwrap().contents {
            lsp_types::HoverContents::Markup(m) => m.value,
            other => panic!("{other:?}"),
        };
        let h = hover(&mut ws, at(&t, "tmp := s", 0, 0));
        assert!(h.contains("variable of `Motor.Start`"), "{h}");
        let h = hover(&mut ws, at(&t, "m.Start", 0, 3));
        assert!(h.starts_with("**method Start**"), "{h}");
    }

    #[test]
    fn rename_a_method_from_its_declaration_or_any_call() {
        let (mut ws, u, a, t) = one_file();
        let expect = t
            .replace("METHOD Start", "METHOD Launch")
            .replace("Start := TRUE", "Launch := TRUE")
            .replace("Start(s := 1)", "Launch(s := 1)")
            .replace("THIS^.Start", "THIS^.Launch")
            .replace("m.Start", "m.Launch");
        for offset in [
            at(&t, "METHOD Start", 0, 7),
            at(&t, "Start := TRUE", 0, 1),
            at(&t, "Start(s := 1)", 0, 0),
            at(&t, "THIS^.Start", 0, 8),
            at(&t, "m.Start", 0, 2),
        ] {
            let out = renamed(&mut ws, &u, &a, offset, "Launch").unwrap();
            assert_eq!(out["one.st"], expect, "from {offset}");
        }
        // The name is taken in the block's namespace.
        let clash = renamed(&mut ws, &u, &a, at(&t, "m.Start", 0, 2), "count").unwrap_err();
        assert!(clash.contains("`count` is already a variable of `Motor`"), "{clash}");
    }

    #[test]
    fn rename_variables_of_a_method_and_of_its_block() {
        let (mut ws, u, a, t) = one_file();
        // The method's `tmp`: only in the method; the block's `tmp` stays.
        let out = renamed(&mut ws, &u, &a, at(&t, "tmp := s", 0, 0), "sum").unwrap();
        let expect = t.replace("VAR tmp : INT", "VAR sum : INT").replace("tmp := s", "sum := s");
        assert_eq!(out["one.st"], expect);
        // The block's `count`: in its body, its method and its action.
        let out = renamed(&mut ws, &u, &a, at(&t, "count : INT", 0, 0), "n").unwrap();
        assert_eq!(out["one.st"], t.replace("count", "n"));
        // The block's `speed`, used in the method and as a parameter of the instance's call.
        let out = renamed(&mut ws, &u, &a, at(&t, "s + speed", 0, 5), "rpm").unwrap();
        assert_eq!(out["one.st"], t.replace("speed", "rpm"));
        // A parameter of the method: also where calls name it.
        let out = renamed(&mut ws, &u, &a, at(&t, "s + speed", 0, 0), "setpoint").unwrap();
        assert_eq!(
            out["one.st"],
            t.replace("s : INT", "setpoint : INT")
                .replace("s + speed", "setpoint + speed")
                .replace("(s :=", "(setpoint :=")
        );
        // A method's variable cannot take a name the method uses or hide one of the block.
        let e = renamed(&mut ws, &u, &a, at(&t, "tmp := s", 0, 0), "count").unwrap_err();
        assert!(e.contains("would hide it"), "{e}");
        let e = renamed(&mut ws, &u, &a, at(&t, "s : INT", 0, 0), "tmp").unwrap_err();
        assert!(e.contains("`tmp` is already a variable of `Start`"), "{e}");
        // Nor can a block's variable take the name of a variable of a method using it.
        let e = renamed(&mut ws, &u, &a, at(&t, "count : INT", 0, 0), "s").unwrap_err();
        assert!(e.contains("`Start` uses `count` and has a variable `s`"), "{e}");
    }

    #[test]
    fn rename_a_property_and_an_action_with_their_uses() {
        let (mut ws, u, a, t) = one_file();
        let out = renamed(&mut ws, &u, &a, at(&t, "m.Running :=", 0, 2), "Active").unwrap();
        assert_eq!(out["one.st"], t.replace("Running", "Active"));
        let out = renamed(&mut ws, &u, &a, at(&t, "GET Running", 0, 4), "Active").unwrap();
        assert_eq!(out["one.st"], t.replace("Running", "Active"));
        let out = renamed(&mut ws, &u, &a, at(&t, "m.Reset", 0, 2), "Clear").unwrap();
        assert_eq!(out["one.st"], t.replace("Reset", "Clear"));
    }

    /// The block in one open file, its users in another: both are renamed.
    #[test]
    fn members_across_the_files_of_the_workspace() {
        let mut ws = Workspace::new(Vec::new());
        let (mu, pu) = (uri("motor.st"), uri("main.st"));
        ws.open.insert(mu.as_str().into(), Document::new(mu.clone(), "sfc".into(), 1, MOTOR.into()));
        ws.open.insert(pu.as_str().into(), Document::new(pu.clone(), "sfc".into(), 1, MAIN.into()));
        let a = ws.analysis(&pu).unwrap();
        let def = definition(&mut ws, &pu, &a, at(MAIN, "m.Start", 0, 3));
        assert_eq!(def, [("motor.st".to_string(), at(MOTOR, "Start : BOOL", 0, 0))]);
        let out = renamed(&mut ws, &pu, &a, at(MAIN, "m.Running", 0, 2), "Active").unwrap();
        assert_eq!(out["main.st"], MAIN.replace("Running", "Active"));
        assert_eq!(out["motor.st"], MOTOR.replace("Running", "Active"));
        // From the declaration, in the other file.
        let ma = ws.analysis(&mu).unwrap();
        let out = renamed(&mut ws, &mu, &ma, at(MOTOR, "METHOD Start", 0, 7), "Launch").unwrap();
        assert_eq!(out["main.st"], MAIN.replace("Start", "Launch"));
        let refs = references(
            &mut ws,
            &mu,
            &ma,
            &Identity::Local(mu.as_str().into(), ma.index.declaration_at(at(MOTOR, "Reset:", 0, 0)).unwrap()),
        );
        assert_eq!(refs.len(), 2, "the action and `m.Reset()`");
    }

    /// `SUPER^.M` is the base's method; a method the block inherits is found by its name and
    /// on instances of the derived block.
    #[test]
    fn inherited_members_and_super() {
        let t = "FUNCTION_BLOCK Base\n  VAR n : INT; END_VAR\n  METHOD Add\n    VAR_INPUT k : INT; END_VAR\n    n := n + k;\n  END_METHOD\n  METHOD Clear\n    n := 0;\n  END_METHOD\nEND_FUNCTION_BLOCK\n\
FUNCTION_BLOCK Derived EXTENDS Base\n  METHOD Add\n    VAR_INPUT k : INT; END_VAR\n    SUPER^.Add(k := k); Clear();\n  END_METHOD\nEND_FUNCTION_BLOCK\n\
PROGRAM P\n  VAR d : Derived; END_VAR\n  d.Add(k := 1); d.Clear();\nEND_PROGRAM\n";
        let mut ws = Workspace::new(Vec::new());
        let (u, a) = (uri("ext.st"), analysis(t));
        let file = |o: u32| vec![("ext.st".to_string(), o)];
        assert_eq!(definition(&mut ws, &u, &a, at(t, "SUPER^.Add", 0, 8)), file(at(t, "Add", 0, 0)));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "d.Add", 0, 2)), file(at(t, "Add", 1, 0)));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "Clear()", 0, 0)), file(at(t, "Clear", 0, 0)));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "d.Clear", 0, 2)), file(at(t, "Clear", 0, 0)));
        let out = renamed(&mut ws, &u, &a, at(t, "METHOD Clear", 0, 7), "Zero").unwrap();
        assert_eq!(out["ext.st"], t.replace("Clear", "Zero"));
    }

    /// `text` with the identifier `old` (whole words only) replaced.
    fn replace_word(text: &str, old: &str, new: &str) -> String {
        let ident = |c: Option<char>| c.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
        let mut out = String::new();
        let mut last = 0;
        for (i, _) in text.match_indices(old) {
            let (before, after) = (text[..i].chars().next_back(), text[i + old.len()..].chars().next());
            if !ident(before) && !ident(after) {
                out.push_str(&text[last..i]);
                out.push_str(new);
                last = i + old.len();
            }
        }
        out.push_str(&text[last..]);
        out
    }

    /// The errors `sfc check` finds in a text.
    fn errors(text: &str) -> Vec<String> {
        let opts = sfc_model::CheckOptions::default();
        let (_, _, diags) = sfc_driver::check_text(0, "t.st", text, sfc_driver::FileKind::Iec, &opts);
        diags.iter().filter(|d| d.is_error()).map(|d| d.message.clone()).collect()
    }

    /// The fixture of methods, an action, a property and EXTENDS: each rename leaves a text
    /// that checks.
    #[test]
    fn renames_in_the_methods_fixture_keep_it_valid() {
        let t = include_str!("../../../tests/fixtures/valid/methods_actions_extends.st");
        assert_eq!(errors(t), Vec::<String>::new());
        let mut ws = Workspace::new(Vec::new());
        let (u, a) = (uri("fixture.st"), analysis(t));
        let file = |o: u32| vec![("fixture.st".to_string(), o)];
        // Inherited members of an instance of the derived block; the override on the instance.
        assert_eq!(definition(&mut ws, &u, &a, at(t, "Belt.ACT_Count", 0, 5)), file(at(t, "ACT_Count:", 0, 0)));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "Belt.Parts", 0, 5)), file(at(t, "PROPERTY Parts", 0, 9)));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "Belt.Add", 0, 5)), file(at(t, "METHOD Add", 1, 7)));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "SUPER^.Add", 0, 7)), file(at(t, "METHOD Add", 0, 7)));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "(Count := Count)", 0, 1)), file(at(t, "Count : INT", 0, 0)));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "(Count := Count)", 0, 10)), file(at(t, "Count : INT", 1, 0)));
        for (from, new_name, changed) in [
            (at(t, "nParts : INT", 0, 0), "nCount", "nParts"),
            (at(t, "Belt.Parts", 1, 5), "PartCount", "Parts"),
            (at(t, "Belt.ACT_Count", 0, 5), "ACT_Tally", "ACT_Count"),
            (at(t, "METHOD PUBLIC Reset", 0, 14), "Clear", "Reset"),
        ] {
            let out = renamed(&mut ws, &u, &a, from, new_name).unwrap();
            let text = &out["fixture.st"];
            assert_eq!(*text, replace_word(t, changed, new_name), "{changed}");
            assert_eq!(errors(text), Vec::<String>::new(), "{changed}");
        }
        // The derived block's `Add`: its declaration and the call on the instance.
        let out = renamed(&mut ws, &u, &a, at(t, "Belt.Add", 0, 5), "Append").unwrap();
        let text = &out["fixture.st"];
        assert!(text.contains("METHOD Append") && text.contains("Belt.Append(2)") && text.contains("SUPER^.Add("));
        assert_eq!(errors(text), Vec::<String>::new());
    }

    /// Half-typed members and bases that are no block give nothing, without panicking.
    #[test]
    fn half_typed_members() {
        let t = "FUNCTION_BLOCK F EXTENDS F\n  VAR x : INT; END_VAR\n  METHOD M\n    SUPER^.x := 1;\n    THIS^. x.; y.z; M.\nEND_FUNCTION_BLOCK\nPROGRAM P VAR f : F; END_VAR f.q := 1; f.x.y := 2; P.f.x := 3; END_PROGRAM\n";
        let mut ws = Workspace::new(Vec::new());
        let (u, a) = (uri("half.st"), analysis(t));
        for offset in 0..t.len() as u32 {
            if let Some((identity, _)) = identity_at(&mut ws, &u, &a, offset) {
                let _ = declarations(&mut ws, &u, &a, &identity);
                let _ = references(&mut ws, &u, &a, &identity);
            }
            let _ = prepare_rename(&mut ws, &u, &a, offset);
        }
        // `SUPER^.x` through a block extending itself: the chain is cut.
        assert_eq!(definition(&mut ws, &u, &a, at(t, "SUPER^.x", 0, 7)), file_x(t));
        assert_eq!(definition(&mut ws, &u, &a, at(t, "P.f", 0, 2)), [("half.st".to_string(), at(t, "f : F", 0, 0))]);
        assert!(definition(&mut ws, &u, &a, at(t, "f.q", 0, 2)).is_empty());
    }

    fn file_x(t: &str) -> Vec<(String, u32)> {
        vec![("half.st".to_string(), at(t, "x : INT", 0, 0))]
    }

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
