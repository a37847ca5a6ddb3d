//! What of object orientation the checker cannot analyse: a block extending one the file does
//! not analyse (a library's block, or one kept as written), whose inherited variables and
//! methods are unknown. Such a POU is kept as written (a block others may name, as an import's
//! kept POU is) with one note that names why; nothing of it is lost, and the other POUs of the
//! file are checked as usual. Methods, properties, interfaces (and calls through them),
//! `EXTENDS` (with overriding), `IMPLEMENTS`, `THIS^`, `SUPER^`, pointers (`POINTER TO`, `ADR`,
//! `p^`) and references (`REFERENCE TO`, `REF=`) are checked by sfc-st and simulated.

use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{self, Item};

/// Whether `unit` holds anything [`keep_objects`] would keep as written.
pub(crate) fn any(unit: &ast::SourceUnit) -> bool {
    unit.items.iter().any(|i| matches!(i, Item::Pou(p) if p.extends.is_some()))
}

/// Replaces every POU extending a block the file does not analyse by a block kept as written,
/// with a note (SFC0104) naming why.
pub(crate) fn keep_objects(unit: &mut ast::SourceUnit, text: &str, diags: &mut Vec<Diagnostic>) {
    // Why each POU is kept, by upper-case name: those extending a kept one, transitively.
    let mut why: std::collections::HashMap<String, (String, Span)> = std::collections::HashMap::new();
    // A block extending one the file does not analyse (kept as written, or not declared in the
    // file: a library's) is kept too: its inherited variables and methods are unknown.
    let analysed: std::collections::HashSet<String> = unit
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Pou(p) => Some(p.name.key()),
            _ => None,
        })
        .collect();
    loop {
        let mut more = Vec::new();
        for i in &unit.items {
            let Item::Pou(p) = i else { continue };
            let Some(b) = &p.extends else { continue };
            if why.contains_key(&p.name.key()) {
                continue;
            }
            if why.contains_key(&b.key()) {
                more.push((p.name.key(), (format!("it extends `{}`, which is kept as written", b.text), b.span)));
            } else if !analysed.contains(&b.key()) {
                let what = format!("it extends `{}`, which the file does not declare (a library's block?)", b.text);
                more.push((p.name.key(), (what, b.span)));
            }
        }
        if more.is_empty() {
            break;
        }
        why.extend(more);
    }
    for item in unit.items.iter_mut() {
        let (keyword, name, attributes, span, why) = match item {
            Item::Pou(p) => match why.remove(&p.name.key()) {
                Some(why) => (p.kind.keyword(), p.name.clone(), p.attributes.clone(), p.span, why),
                None => continue,
            },
            _ => continue,
        };
        let line = 1 + text.get(..why.1.start as usize).unwrap_or("").matches('\n').count();
        diags.push(
            Diagnostic::note_diag(
                "SFC0104",
                name.span,
                format!("`{keyword} {}` is kept as written, not analysed", name.text),
            )
            .with_note(format!("not analysed: {} (line {line})", why.0)),
        );
        *item = Item::Verbatim(ast::Verbatim {
            keyword: keyword.to_string(),
            attributes,
            name: Some(name),
            text: text.get(span.start as usize..span.end as usize).unwrap_or("").to_string(),
            span,
        });
    }
}
