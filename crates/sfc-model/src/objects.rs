//! What of object orientation the checker and the simulator do not know yet: interfaces (and
//! calls through them) and `THIS^` passed on. The parser reads and the printer writes them; a POU that holds one
//! is kept as written (a block others may name, as an import's kept POU is) with one note that
//! names the first such construct and its line, and so is a block extending a kept one; nothing
//! of it is lost, and the other POUs of the file are checked as usual. Methods, properties,
//! `EXTENDS` (with overriding), `IMPLEMENTS`, `THIS^.x`, `SUPER^.M()`, pointers (`POINTER TO`,
//! `ADR`, `p^`) and references (`REFERENCE TO`, `REF=`) are checked by sfc-st and simulated.

use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{self, Item, Pou};
use sfc_syntax::lexer::{lex, TokenKind};

/// Whether `unit` holds anything [`keep_objects`] would keep as written.
pub(crate) fn any(unit: &ast::SourceUnit, text: &str) -> bool {
    unit.items.iter().any(|i| match i {
        Item::Interface(_) => true,
        Item::Pou(p) => p.extends.is_some() || first_construct(p, text).is_some(),
        _ => false,
    })
}

/// Replaces every interface, and every POU holding a construct the checker does not know yet,
/// by a block kept as written, with a note (SFC0104) naming why.
pub(crate) fn keep_objects(unit: &mut ast::SourceUnit, text: &str, diags: &mut Vec<Diagnostic>) {
    // Why each POU is kept, by upper-case name; then those extending a kept one, transitively.
    let mut why: std::collections::HashMap<String, (String, Span)> = std::collections::HashMap::new();
    for i in &unit.items {
        if let Item::Pou(p) = i {
            if let Some(w) = first_construct(p, text) {
                why.insert(p.name.key(), w);
            }
        }
    }
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
            Item::Interface(i) => (
                "INTERFACE",
                i.name.clone(),
                i.attributes.clone(),
                i.span,
                (
                    "an interface: sfc reads and prints it, and does not type-check or simulate calls through interfaces yet"
                        .to_string(),
                    i.name.span,
                ),
            ),
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

/// The first construct of `p` the checker does not know yet, in words, with its span.
fn first_construct(p: &Pou, text: &str) -> Option<(String, Span)> {
    // `THIS^` passed on as a value: found in the POU's tokens.
    let body = text.get(p.span.start as usize..p.span.end as usize)?;
    // Most POUs hold none: no second lexing of them.
    if !body.contains('^') {
        return None;
    }
    let (toks, _) = lex(p.span.file, body);
    let sig: Vec<_> = toks.iter().filter(|t| !t.kind.is_trivia()).collect();
    for (k, t) in sig.iter().enumerate() {
        if t.kind != TokenKind::Caret {
            continue;
        }
        let at = Span::new(p.span.file, p.span.start + t.start, p.span.start + t.end);
        let before = k.checked_sub(1).and_then(|j| sig.get(j)).map_or("", |b| &body[b.start as usize..b.end as usize]);
        let after = sig.get(k + 1).map_or("", |n| &body[n.start as usize..n.end as usize]);
        // `THIS^.x`, `THIS^.M()`, `SUPER^.M()`, `SUPER^()`: the block itself, typed and simulated.
        if before.eq_ignore_ascii_case("THIS") && after != "." {
            return Some((
                "it passes `THIS^` on; sfc does not type-check or simulate references to blocks yet".into(),
                at,
            ));
        }
    }
    None
}
