//! The outline: POUs (and types, globals) at the top; inside a POU its variables by section,
//! then its steps in declaration order, each with the transitions that leave it (so the outline
//! shows the step structure), then the actions, the methods and the properties, each method
//! and property with the variables of its code.

use crate::index::{Symbol, SymbolKind as Kind};
use crate::workspace::Analysis;
#[allow(deprecated)] // `DocumentSymbol::deprecated` must be written out.
use lsp_types::{DocumentSymbol, SymbolKind};

#[allow(deprecated)]
fn node(a: &Analysis, s: &Symbol, kind: SymbolKind, detail: Option<String>) -> DocumentSymbol {
    DocumentSymbol {
        name: s.name.clone(),
        detail,
        kind,
        tags: None,
        deprecated: None,
        range: a.range(s.span),
        selection_range: a.range(if s.name_span.start >= s.span.start && s.name_span.end <= s.span.end {
            s.name_span
        } else {
            s.span
        }),
        children: None,
    }
}

pub fn document_symbols(a: &Analysis) -> Vec<DocumentSymbol> {
    let ix = &a.index;
    let mut out = Vec::new();
    for (_, s) in ix.globals() {
        let entry = match &s.kind {
            Kind::Pou(k) => {
                let Some(p) = ix.pous.iter().position(|p| p.name_span == s.name_span) else { continue };
                let mut n = node(a, s, SymbolKind::MODULE, Some(k.keyword().to_string()));
                n.children = Some(pou_children(a, p));
                n
            }
            Kind::Type => node(a, s, SymbolKind::STRUCT, Some("type".into())),
            Kind::Interface => node(a, s, SymbolKind::INTERFACE, Some("interface".into())),
            Kind::EnumValue => continue,
            Kind::Variable(v) => node(a, s, SymbolKind::VARIABLE, Some(format!("{} {}", v.section.keyword(), v.ty))),
            _ => continue,
        };
        out.push(entry);
    }
    out
}

fn pou_children(a: &Analysis, pou: usize) -> Vec<DocumentSymbol> {
    let ix = &a.index;
    let syms: Vec<&Symbol> = ix.pou_symbols(pou).map(|(_, s)| s).collect();
    let mut out = Vec::new();
    for s in syms.iter().filter(|s| matches!(&s.kind, Kind::Variable(v) if !v.implicit)) {
        if let Kind::Variable(v) = &s.kind {
            let kind = if v.constant { SymbolKind::CONSTANT } else { SymbolKind::VARIABLE };
            let mut detail = format!("{} {}", v.section.keyword(), v.ty);
            if let Some(at) = &v.at {
                detail.push_str(&format!(" AT {at}"));
            }
            out.push(node(a, s, kind, Some(detail)));
        }
    }
    let transitions: Vec<&&Symbol> = syms.iter().filter(|s| matches!(s.kind, Kind::Transition(_))).collect();
    let mut placed = vec![false; transitions.len()];
    for s in syms.iter() {
        let Kind::Step(st) = &s.kind else { continue };
        let mut detail = if st.initial { "initial step".to_string() } else { "step".to_string() };
        if st.is_final {
            detail.push_str(", final");
        }
        if !st.associations.is_empty() {
            let acts: Vec<String> = st
                .associations
                .iter()
                .map(|x| format!("{}({})", x.action, x.qualifier.clone().unwrap_or_else(|| "N".into())))
                .collect();
            detail.push_str(&format!(" — {}", acts.join(", ")));
        }
        let mut n = node(a, s, SymbolKind::EVENT, Some(detail));
        let mut children = Vec::new();
        for (i, t) in transitions.iter().enumerate() {
            let Kind::Transition(d) = &t.kind else { continue };
            let first_from = d.from.first().is_some_and(|f| f.eq_ignore_ascii_case(&s.name));
            if first_from && !placed.get(i).copied().unwrap_or(true) {
                if let Some(p) = placed.get_mut(i) {
                    *p = true;
                }
                children.push(transition_node(a, t));
            }
        }
        if !children.is_empty() {
            n.children = Some(children);
        }
        out.push(n);
    }
    for (i, t) in transitions.iter().enumerate() {
        if !placed.get(i).copied().unwrap_or(false) {
            out.push(transition_node(a, t));
        }
    }
    for s in syms.iter().filter(|s| matches!(s.kind, Kind::Action)) {
        out.push(node(a, s, SymbolKind::METHOD, Some("action".into())));
    }
    for (id, s) in ix.pou_symbols(pou) {
        let mut n = match s.kind {
            Kind::Method => node(a, s, SymbolKind::METHOD, Some("method".into())),
            Kind::Property => node(a, s, SymbolKind::PROPERTY, Some("property".into())),
            _ => continue,
        };
        let vars: Vec<DocumentSymbol> = ix
            .scopes
            .iter()
            .filter(|sc| sc.owner == id)
            .flat_map(|sc| sc.symbols.iter().filter_map(|&v| ix.symbol(v)))
            .filter_map(|v| match &v.kind {
                Kind::Variable(d) => {
                    Some(node(a, v, SymbolKind::VARIABLE, Some(format!("{} {}", d.section.keyword(), d.ty))))
                }
                _ => None,
            })
            .collect();
        if !vars.is_empty() {
            n.children = Some(vars);
        }
        out.push(n);
    }
    out
}

fn transition_node(a: &Analysis, t: &Symbol) -> DocumentSymbol {
    let detail = match &t.kind {
        Kind::Transition(d) => {
            let prio = d.priority.as_ref().map(|p| format!(" (PRIORITY {p})")).unwrap_or_default();
            format!("{} → {}{prio}", d.from.join(", "), d.to.join(", "))
        }
        _ => String::new(),
    };
    node(a, t, SymbolKind::OPERATOR, Some(detail))
}
