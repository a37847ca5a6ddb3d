//! Semantic tokens: steps, actions and transitions get token types of their own, distinct from
//! variables, so an editor colours the chart's names apart from the data.

use crate::index::SymbolKind as Kind;
use crate::workspace::Analysis;
use lsp_types::{SemanticToken, SemanticTokenModifier, SemanticTokenType, SemanticTokensLegend};
use sfc_diagnostics::Span;

/// Token types, in legend order.
pub const TYPES: &[&str] = &[
    "step",
    "action",
    "transition",
    "variable",
    "parameter",
    "type",
    "function",
    "enumMember",
    "qualifier",
    "namespace",
    "method",
    "property",
    "interface",
];
/// Token modifiers, in legend order (bits).
pub const MODIFIERS: &[&str] = &["declaration", "readonly", "defaultLibrary", "initial"];

pub fn legend() -> SemanticTokensLegend {
    SemanticTokensLegend {
        token_types: TYPES.iter().map(|t| SemanticTokenType::new(t)).collect(),
        token_modifiers: MODIFIERS.iter().map(|m| SemanticTokenModifier::new(m)).collect(),
    }
}

fn type_index(name: &str) -> u32 {
    TYPES.iter().position(|t| *t == name).unwrap_or(0) as u32
}

fn classify(kind: &Kind) -> (&'static str, u32) {
    match kind {
        Kind::Step(s) => ("step", if s.initial { 8 } else { 0 }),
        Kind::Action => ("action", 0),
        Kind::Transition(_) => ("transition", 0),
        Kind::Variable(v) => {
            let mods = if v.constant { 2 } else { 0 } | if v.implicit { 4 } else { 0 };
            match v.section {
                sfc_syntax::ast::VarKind::Input | sfc_syntax::ast::VarKind::InOut => ("parameter", mods),
                _ => ("variable", mods),
            }
        }
        Kind::Type => ("type", 0),
        Kind::Pou(sfc_syntax::ast::PouKind::Function) => ("function", 0),
        Kind::Pou(_) => ("namespace", 0),
        Kind::EnumValue => ("enumMember", 0),
        Kind::Method => ("method", 0),
        Kind::Property => ("property", 0),
        Kind::Interface => ("interface", 0),
    }
}

/// The tokens of a document, delta-encoded (lines and UTF-16 columns, as the protocol wants).
pub fn semantic_tokens(a: &Analysis) -> Vec<SemanticToken> {
    let ix = &a.index;
    let mut raw: Vec<(Span, u32, u32)> = Vec::new();
    for s in ix.symbols.iter().filter(|s| s.is_written()) {
        let (t, m) = classify(&s.kind);
        raw.push((s.name_span, type_index(t), m | 1));
    }
    for o in &ix.occurrences {
        let resolved = ix.resolve(o).and_then(|id| ix.symbol(id));
        let (t, m) = match resolved {
            Some(s) => classify(&s.kind),
            None if sfc_st::stdlib::std_function_block(&o.key).is_some() => ("type", 4),
            None if sfc_st::stdlib::std_function(&o.key).is_some() => ("function", 4),
            None => continue,
        };
        raw.push((o.span, type_index(t), m));
    }
    for q in &ix.qualifiers {
        raw.push((q.span, type_index("qualifier"), 0));
    }
    raw.sort_by_key(|(s, _, _)| (s.start, s.end));
    raw.dedup_by_key(|(s, _, _)| s.start);
    let mut out = Vec::with_capacity(raw.len());
    let (mut line, mut col) = (0u32, 0u32);
    for (span, ty, mods) in raw {
        let start = a.lines.position(&a.text, span.start);
        let end = a.lines.position(&a.text, span.end);
        if end.line != start.line || end.character <= start.character {
            continue;
        }
        let delta_line = start.line - line;
        let delta_start = if delta_line == 0 { start.character - col } else { start.character };
        out.push(SemanticToken {
            delta_line,
            delta_start,
            length: end.character - start.character,
            token_type: ty,
            token_modifiers_bitset: mods,
        });
        line = start.line;
        col = start.character;
    }
    out
}
