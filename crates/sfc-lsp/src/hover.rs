//! Hover: what a name is (a variable's type, section, initial value and address; a step's
//! actions and transitions; a transition's steps and priority) and what a qualifier does.

use crate::index::{FileIndex, Symbol, SymbolKind};
use crate::navigate::{self, Identity};
use crate::workspace::{Analysis, Workspace};
use lsp_types::{Hover, HoverContents, MarkupContent, MarkupKind, Uri};
use std::sync::Arc;

/// What each action qualifier does (IEC 61131-3, as `semantics.md` runs it).
pub const QUALIFIERS: &[(&str, &str, &str)] = &[
    ("N", "non-stored", "The action is active while the step is active."),
    ("R", "reset", "Resets a stored action (S, SD, DS, SL): overrides every other qualifier and cancels pending timers."),
    ("S", "set (stored)", "The action becomes active and stays active after the step is left, until an R resets it."),
    ("L", "time limited", "Active while the step is active, for at most the given time."),
    ("D", "time delayed", "Active once the step has been active for the given time, while it stays active."),
    ("P", "pulse", "Active for one scan when the step becomes active (the rising edge)."),
    ("SD", "stored and time delayed", "Stored when the step becomes active; the action starts after the given time, even if the step was left, until an R."),
    ("DS", "delayed and stored", "If the step stays active for the given time, the action is stored and stays active until an R."),
    ("SL", "stored and time limited", "Stored when the step becomes active; active for at most the given time, or until an R."),
    ("P1", "pulse, rising edge", "The body runs once when the step becomes active (with `Q` FALSE)."),
    ("P0", "pulse, falling edge", "The body runs once when the step is left (with `Q` FALSE)."),
];

/// The hover text of a qualifier.
pub fn qualifier_text(name: &str) -> Option<String> {
    let (q, title, what) = QUALIFIERS.iter().find(|(q, _, _)| q.eq_ignore_ascii_case(name))?;
    let timed = matches!(*q, "L" | "D" | "SD" | "DS" | "SL");
    let usage = if timed { format!("`Action({q}, T#5s)`") } else { format!("`Action({q})`") };
    Some(format!("**qualifier {q}** — {title}\n\n{what}\n\n{usage}"))
}

pub fn hover(ws: &mut Workspace, uri: &Uri, a: &Arc<Analysis>, offset: u32) -> Option<Hover> {
    if let Some(q) = a.index.qualifier_at(offset) {
        let text = qualifier_text(&q.name)?;
        return Some(markdown(text, Some(a.range(q.span))));
    }
    let (identity, span) = navigate::identity_at(ws, uri, a, offset)?;
    let decls = navigate::declarations(ws, uri, a, &identity);
    let Some(found) = decls.first() else {
        if let Identity::Global(key) = &identity {
            return standard_hover(key).map(|t| markdown(t, Some(a.range(span))));
        }
        return None;
    };
    let s = found.symbol()?;
    let mut text = describe(&found.analysis.index, s);
    if found.uri != *uri {
        let path = crate::workspace::path_of(&found.uri);
        let line = found.analysis.range(s.name_span).start.line + 1;
        text.push_str(&format!("\n\n*declared in `{}`, line {line}*", path.display()));
    }
    Some(markdown(text, Some(a.range(span))))
}

fn markdown(value: String, range: Option<lsp_types::Range>) -> Hover {
    Hover { contents: HoverContents::Markup(MarkupContent { kind: MarkupKind::Markdown, value }), range }
}

fn standard_hover(key: &str) -> Option<String> {
    if let Some(fb) = sfc_st::stdlib::std_function_block(key) {
        let params: Vec<String> = fb.iter().map(|(n, k, t)| format!("{} {n} : {t}", k.keyword())).collect();
        return Some(format!("**standard function block {key}**\n\n```\n{}\n```", params.join("\n")));
    }
    if sfc_st::stdlib::std_function(key).is_some() {
        return Some(format!("**standard function {key}**"));
    }
    sfc_st::Type::elementary(key).map(|t| format!("**elementary type {t}**"))
}

/// The description of a symbol, in Markdown.
pub fn describe(ix: &FileIndex, s: &Symbol) -> String {
    // A variable of a method or accessor: `Block.Method`.
    let owner = s.scope.and_then(|sc| ix.scopes.get(sc)).and_then(|sc| ix.symbol(sc.owner));
    let pou_name = s.pou.and_then(|p| ix.pous.get(p)).map(|p| match owner {
        Some(o) => format!("{}.{}", p.name, o.name),
        None => p.name.clone(),
    });
    match &s.kind {
        SymbolKind::Variable(v) => {
            let mut decl = format!("{} : {}", s.name, v.ty);
            if let Some(at) = &v.at {
                decl = format!("{} AT {at} : {}", s.name, v.ty);
            }
            if let Some(i) = &v.init {
                decl.push_str(&format!(" := {i}"));
            }
            let mut section = v.section.keyword().to_string();
            if v.constant {
                section.push_str(" CONSTANT");
            }
            match v.retain {
                Some(sfc_syntax::ast::Retain::Retain) => section.push_str(" RETAIN"),
                Some(sfc_syntax::ast::Retain::NonRetain) => section.push_str(" NON_RETAIN"),
                None => {}
            }
            let mut out = format!("```iecst\n{decl}\n```\n\n");
            let owner = match &pou_name {
                Some(p) => format!(" of `{p}`"),
                None => " (global)".to_string(),
            };
            out.push_str(&format!("variable{owner}, section `{section}`"));
            if v.implicit {
                out.push_str("\n\nImplicit control variable of every chart (see `docs/sim.md`).");
            }
            if let Some(at) = &v.at {
                out.push_str(&format!("\n\nlocated at `{at}`"));
            }
            out
        }
        SymbolKind::Step(st) => {
            let mut kind = if st.initial { "initial step".to_string() } else { "step".to_string() };
            if st.is_final {
                kind.push_str(", final (`sfc.final`)");
            }
            let mut out = format!("**{kind} {}**", s.name);
            if let Some(p) = &pou_name {
                out.push_str(&format!(" of `{p}`"));
            }
            if let Some(t) = &st.timeout {
                out.push_str(&format!("\n\nsupervision time `{t}`"));
            }
            if let Some(t) = &st.min_time {
                out.push_str(&format!("\n\nminimum time `{t}`"));
            }
            if let Some(t) = &st.tag {
                out.push_str(&format!("\n\nstate tag {t}"));
            }
            out.push_str("\n\nactions: ");
            if st.associations.is_empty() {
                out.push_str("none");
            } else {
                let list: Vec<String> = st
                    .associations
                    .iter()
                    .map(|a| {
                        let mut parts = vec![a.qualifier.clone().unwrap_or_else(|| "N".into())];
                        parts.extend(a.duration.clone());
                        parts.extend(a.indicators.clone());
                        format!("`{}({})`", a.action, parts.join(", "))
                    })
                    .collect();
                out.push_str(&list.join(", "));
            }
            let key = s.key();
            let (mut incoming, mut outgoing) = (Vec::new(), Vec::new());
            for (_, t) in s.pou.map(|p| ix.pou_symbols(p).collect::<Vec<_>>()).unwrap_or_default() {
                if let SymbolKind::Transition(d) = &t.kind {
                    if d.to.iter().any(|n| n.eq_ignore_ascii_case(&key)) {
                        incoming.push(format!("`{}` from {}", t.name, d.from.join(", ")));
                    }
                    if d.from.iter().any(|n| n.eq_ignore_ascii_case(&key)) {
                        let prio = d.priority.as_ref().map(|p| format!(", PRIORITY {p}")).unwrap_or_default();
                        outgoing.push(format!("`{}` to {}{prio} when `{}`", t.name, d.to.join(", "), d.condition));
                    }
                }
            }
            let list = |v: &[String]| if v.is_empty() { "none".to_string() } else { v.join("; ") };
            out.push_str(&format!("\n\nincoming: {}\n\noutgoing: {}", list(&incoming), list(&outgoing)));
            out
        }
        SymbolKind::Transition(t) => {
            let mut out = format!("**transition {}**", s.name);
            if !t.named {
                out.push_str(" (unnamed)");
            }
            out.push_str(&format!("\n\nFROM {} TO {}", t.from.join(", "), t.to.join(", ")));
            match &t.priority {
                Some(p) => out.push_str(&format!("\n\nPRIORITY {p} (lower fires first)")),
                None => {
                    // The order among the alternatives leaving the same step.
                    let alternatives = s.pou.map(|p| alternatives(ix, p, &t.from)).unwrap_or_default();
                    if alternatives.len() > 1 {
                        let rank = alternatives.iter().position(|n| n.eq_ignore_ascii_case(&s.name)).unwrap_or(0) + 1;
                        out.push_str(&format!(
                            "\n\nno PRIORITY: number {rank} of {} alternatives in declaration order",
                            alternatives.len()
                        ));
                    } else {
                        out.push_str("\n\nno PRIORITY");
                    }
                }
            }
            if !t.condition.is_empty() {
                out.push_str(&format!("\n\n```iecst\n{}\n```", t.condition));
            }
            out
        }
        SymbolKind::Action => {
            let mut out = format!("**action {}**", s.name);
            let key = s.key();
            let mut uses = Vec::new();
            for (_, st) in s.pou.map(|p| ix.pou_symbols(p).collect::<Vec<_>>()).unwrap_or_default() {
                if let SymbolKind::Step(d) = &st.kind {
                    for a in d.associations.iter().filter(|a| a.action.eq_ignore_ascii_case(&key)) {
                        uses.push(format!("`{}` ({})", st.name, a.qualifier.clone().unwrap_or_else(|| "N".into())));
                    }
                }
            }
            out.push_str(&format!(
                "\n\nassociated with: {}\n\n`{}.Q` is TRUE while it is active, `{}.A` while its body runs",
                if uses.is_empty() { "no step".into() } else { uses.join(", ") },
                s.name,
                s.name
            ));
            out
        }
        SymbolKind::Pou(k) => format!("**{} {}**", k.keyword(), s.name),
        SymbolKind::Method => {
            format!("**method {0}**\n\nruns on an instance: `inst.{0}(…)`, or `{0}(…)` in its block", s.name)
        }
        SymbolKind::Property => {
            format!("**property {0}**\n\nread through its GET (`inst.{0}`), written through its SET", s.name)
        }
        SymbolKind::Interface => format!("**interface {}**", s.name),
        SymbolKind::Type => format!("**type {}**", s.name),
        SymbolKind::EnumValue => format!("**enumerated value {}**", s.name),
    }
}

/// The transitions leaving the steps `from` in the order they are tried without PRIORITY.
fn alternatives(ix: &FileIndex, pou: usize, from: &[String]) -> Vec<String> {
    ix.pou_symbols(pou)
        .filter_map(|(_, t)| match &t.kind {
            SymbolKind::Transition(d) if d.from.iter().any(|f| from.iter().any(|g| g.eq_ignore_ascii_case(f))) => {
                Some(t.name.clone())
            }
            _ => None,
        })
        .collect()
}
