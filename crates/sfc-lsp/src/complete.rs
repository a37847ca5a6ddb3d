//! Completion that knows where the cursor is: step names after FROM and TO, qualifiers inside
//! an association, `.X`/`.T` after a step and `.Q`/`.A` after an action (and the parameters
//! of a function block instance), names in scope by kind in code, type names in declarations,
//! snippets for STEP, TRANSITION and ACTION blocks between chart elements, and keywords.

use crate::hover::QUALIFIERS;
use crate::index::{FileIndex, SymbolKind};
use crate::text::Shift;
use crate::workspace::{Analysis, View};
use lsp_types::{
    CompletionItem, CompletionItemKind, CompletionItemLabelDetails, Documentation, InsertTextFormat, MarkupContent,
    MarkupKind,
};
use sfc_syntax::ast::VarKind;
use sfc_syntax::lexer::{Token, TokenKind};

/// Where the cursor is, as far as completion cares.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Context {
    /// After `name.`.
    Member(String),
    /// After FROM or TO: a step.
    StepLink,
    /// The qualifier of an association `Action(|`.
    Qualifier,
    /// The duration of a timed association `Action(L, |`.
    Duration,
    /// An indicator variable `Action(N, |` or after the duration.
    Indicator,
    /// The action of an association, in a step's body.
    Association,
    /// A type, after `:` in a declaration.
    Type,
    /// Code: a condition, an action body, an initial value.
    Code,
    /// Between the elements of a chart.
    ChartBody,
    /// Outside any POU.
    TopLevel,
}

fn upper(text: &str, t: &Token) -> String {
    text.get(t.start as usize..t.end as usize).unwrap_or("").to_ascii_uppercase()
}

/// The completion context at `offset`.
pub fn context(a: &Analysis, offset: u32) -> Context {
    context_in(&a.index, &a.text, Shift(&[]), offset)
}

/// The completion context at `offset` of `text`, with the index of an earlier version of it
/// and the edits made since (`shift`).
fn context_in(index: &FileIndex, text: &str, shift: Shift<'_>, offset: u32) -> Context {
    let Some(pou) = index.pou_at(shift.backward(offset)) else { return Context::TopLevel };
    // Lex from the start of the element before the cursor: enough to see the context, and
    // cheap in a long file.
    let pou_start = index.pous.get(pou).map_or(0, |p| shift.forward(p.span.start));
    let anchor = index
        .pou_symbols(pou)
        .map(|(_, s)| shift.forward(s.span.start))
        .filter(|&s| s <= offset && s >= pou_start)
        .max()
        .unwrap_or(pou_start);
    let anchor = anchor.min(offset);
    let piece = text.get(anchor as usize..offset as usize).unwrap_or("");
    let (tokens, _) = sfc_syntax::lexer::lex(0, piece);
    let mut toks: Vec<Token> = tokens.into_iter().filter(|t| !t.kind.is_trivia() && t.kind != TokenKind::Eof).collect();
    // The word being typed is not context.
    if toks.last().is_some_and(|t| t.kind == TokenKind::Ident && t.end as usize == piece.len()) {
        toks.pop();
    }
    // In a comment or a string: nothing.
    if let Some(last) = sfc_syntax::lexer::lex(0, piece).0.iter().rev().find(|t| t.kind != TokenKind::Eof) {
        let open_comment = matches!(last.kind, TokenKind::BlockComment) && !piece.ends_with("*)");
        let line_comment = last.kind == TokenKind::LineComment && last.end as usize == piece.len();
        let string = matches!(last.kind, TokenKind::String | TokenKind::WString) && last.end as usize == piece.len();
        if open_comment || line_comment || string {
            return Context::Code;
        }
    }
    if let [.., before, dot] = toks.as_slice() {
        if dot.kind == TokenKind::Dot && before.kind == TokenKind::Ident {
            return Context::Member(piece.get(before.start as usize..before.end as usize).unwrap_or("").to_string());
        }
    }
    // The last keyword that opens or closes a block says where we are.
    let structural = [
        "STEP",
        "INITIAL_STEP",
        "END_STEP",
        "TRANSITION",
        "END_TRANSITION",
        "ACTION",
        "END_ACTION",
        "VAR",
        "VAR_INPUT",
        "VAR_OUTPUT",
        "VAR_IN_OUT",
        "VAR_GLOBAL",
        "VAR_EXTERNAL",
        "VAR_TEMP",
        "VAR_ACCESS",
        "END_VAR",
    ];
    let last_kw = toks
        .iter()
        .enumerate()
        .rev()
        .find(|(_, t)| t.kind == TokenKind::Ident && structural.contains(&upper(piece, t).as_str()));
    let in_sfc = index.pous.get(pou).is_some_and(|p| p.sfc);
    let Some((at, kw)) = last_kw else {
        // At the start of a POU's body (or its header).
        return if in_sfc && toks.is_empty() { Context::ChartBody } else { Context::Code };
    };
    let after = toks.get(at + 1..).unwrap_or(&[]);
    match upper(piece, kw).as_str() {
        "STEP" | "INITIAL_STEP" => {
            let Some(colon) = after.iter().position(|t| t.kind == TokenKind::Colon) else { return Context::Code };
            let body = after.get(colon + 1..).unwrap_or(&[]);
            // Inside the parentheses of the last association?
            let open = body.iter().rposition(|t| t.kind == TokenKind::LParen);
            let close = body.iter().rposition(|t| t.kind == TokenKind::RParen);
            match (open, close) {
                (Some(o), c) if c.is_none_or(|c| c < o) => {
                    let inside = body.get(o + 1..).unwrap_or(&[]);
                    let commas = inside.iter().filter(|t| t.kind == TokenKind::Comma).count();
                    let timed = inside
                        .first()
                        .is_some_and(|q| matches!(upper(piece, q).as_str(), "L" | "D" | "SD" | "DS" | "SL"));
                    match (commas, timed) {
                        (0, _) => Context::Qualifier,
                        (1, true) => Context::Duration,
                        _ => Context::Indicator,
                    }
                }
                _ => Context::Association,
            }
        }
        "TRANSITION" => {
            let assign = after.iter().position(|t| matches!(t.kind, TokenKind::Assign | TokenKind::Colon));
            if assign.is_some() {
                return Context::Code;
            }
            let link =
                after.iter().any(|t| t.kind == TokenKind::Ident && matches!(upper(piece, t).as_str(), "FROM" | "TO"));
            let priority = after.iter().any(|t| upper(piece, t) == "PRIORITY")
                && !after.iter().any(|t| t.kind == TokenKind::RParen);
            if priority {
                Context::Code
            } else if link {
                Context::StepLink
            } else {
                Context::Code
            }
        }
        "ACTION" => Context::Code,
        "END_STEP" | "END_TRANSITION" | "END_ACTION" => Context::ChartBody,
        "END_VAR" => {
            if in_sfc {
                Context::ChartBody
            } else {
                Context::Code
            }
        }
        _ => {
            // In a VAR block: after `:` comes a type, after `:=` a value.
            let last_colon = after.iter().rposition(|t| t.kind == TokenKind::Colon);
            let last_semi = after.iter().rposition(|t| t.kind == TokenKind::Semi);
            let last_assign = after.iter().rposition(|t| t.kind == TokenKind::Assign);
            match (last_colon, last_semi, last_assign) {
                (Some(c), s, asg) if s.is_none_or(|s| s < c) && asg.is_none_or(|x| x < c) => Context::Type,
                (_, s, Some(x)) if s.is_none_or(|s| s < x) => Context::Code,
                _ => Context::TopLevel,
            }
        }
    }
}

fn item(label: &str, kind: CompletionItemKind, detail: String) -> CompletionItem {
    CompletionItem { label: label.to_string(), kind: Some(kind), detail: Some(detail), ..CompletionItem::default() }
}

fn snippet(label: &str, body: &str, detail: &str) -> CompletionItem {
    CompletionItem {
        label: label.to_string(),
        kind: Some(CompletionItemKind::SNIPPET),
        detail: Some(detail.to_string()),
        insert_text: Some(body.to_string()),
        insert_text_format: Some(InsertTextFormat::SNIPPET),
        ..CompletionItem::default()
    }
}

fn keyword(k: &str) -> CompletionItem {
    item(k, CompletionItemKind::KEYWORD, "keyword".into())
}

/// The completion items at `offset`.
pub fn complete(a: &Analysis, offset: u32) -> Vec<CompletionItem> {
    complete_in(&a.index, &a.text, Shift(&[]), offset)
}

/// The completion items at `offset` of the current text of `view` (which may carry the index
/// of an earlier version: names declared since are missing until it is analysed again).
pub fn complete_view(view: &View, offset: u32) -> Vec<CompletionItem> {
    complete_in(&view.analysis.index, &view.text, view.shift(), offset)
}

fn complete_in(ix: &FileIndex, text: &str, shift: Shift<'_>, offset: u32) -> Vec<CompletionItem> {
    let pou = ix.pou_at(shift.backward(offset));
    let ctx = context_in(ix, text, shift, offset);
    let mut out = Vec::new();
    let names = |out: &mut Vec<CompletionItem>, want: &dyn Fn(&SymbolKind) -> bool| {
        let locals = pou.map(|p| ix.pou_symbols(p).collect::<Vec<_>>()).unwrap_or_default();
        for (_, s) in locals.into_iter().chain(ix.globals()) {
            if want(&s.kind) && s.is_written() || (want(&s.kind) && matches!(s.kind, SymbolKind::Variable(_))) {
                out.push(symbol_item(ix, s));
            }
        }
    };
    match ctx {
        Context::Member(base) => {
            let key = base.to_ascii_uppercase();
            let Some(s) = ix.lookup(pou, &key).and_then(|id| ix.symbol(id)) else { return out };
            match &s.kind {
                SymbolKind::Step(_) => {
                    out.push(item("X", CompletionItemKind::FIELD, "BOOL — the step is active".into()));
                    out.push(item("T", CompletionItemKind::FIELD, "TIME — how long the step has been active".into()));
                }
                SymbolKind::Action => {
                    out.push(item("Q", CompletionItemKind::FIELD, "BOOL — the action is active".into()));
                    out.push(item("A", CompletionItemKind::FIELD, "BOOL — the body runs in this scan".into()));
                }
                SymbolKind::Variable(v) => {
                    let ty = v.type_name.clone().unwrap_or_default();
                    if let Some(params) = sfc_st::stdlib::std_function_block(&ty) {
                        for (n, k, t) in params {
                            out.push(item(n, CompletionItemKind::FIELD, format!("{} {t}", k.keyword())));
                        }
                    } else if let Some(fb) = ix.pous.iter().position(|p| p.name.eq_ignore_ascii_case(&ty)) {
                        for (_, m) in ix.pou_symbols(fb) {
                            if let SymbolKind::Variable(mv) = &m.kind {
                                if matches!(mv.section, VarKind::Input | VarKind::Output | VarKind::InOut) {
                                    out.push(item(
                                        &m.name,
                                        CompletionItemKind::FIELD,
                                        format!("{} {}", mv.section.keyword(), mv.ty),
                                    ));
                                }
                            }
                        }
                    }
                }
                _ => {}
            }
        }
        Context::StepLink => names(&mut out, &|k| matches!(k, SymbolKind::Step(_))),
        Context::Qualifier => {
            for (q, title, what) in QUALIFIERS {
                let mut it = item(q, CompletionItemKind::ENUM_MEMBER, title.to_string());
                it.documentation = Some(Documentation::MarkupContent(MarkupContent {
                    kind: MarkupKind::Markdown,
                    value: what.to_string(),
                }));
                if matches!(*q, "L" | "D" | "SD" | "DS" | "SL") {
                    it.insert_text = Some(format!("{q}, T#${{1:1s}}"));
                    it.insert_text_format = Some(InsertTextFormat::SNIPPET);
                }
                // Keep the standard's order.
                it.sort_text = Some(format!("{:02}", out.len()));
                out.push(it);
            }
        }
        Context::Duration => {
            out.push(snippet("T#", "T#${1:1s}", "a duration literal"));
            names(&mut out, &|k| matches!(k, SymbolKind::Variable(v) if v.ty.eq_ignore_ascii_case("TIME")));
        }
        Context::Indicator => {
            names(&mut out, &|k| matches!(k, SymbolKind::Variable(v) if v.ty.eq_ignore_ascii_case("BOOL")));
        }
        Context::Association => {
            names(&mut out, &|k| {
                matches!(k, SymbolKind::Action)
                    || matches!(k, SymbolKind::Variable(v) if v.ty.eq_ignore_ascii_case("BOOL") && !v.implicit)
            });
            out.push(snippet("Action(N);", "${1:Action}(${2|N,S,R,P,P1,P0|});", "an action association"));
            out.push(snippet("Action(L, T#…);", "${1:Action}(${2|L,D,SD,DS,SL|}, T#${3:1s});", "a timed association"));
        }
        Context::Type => {
            for t in ELEMENTARY {
                out.push(item(t, CompletionItemKind::TYPE_PARAMETER, "elementary type".into()));
            }
            for fb in sfc_st::stdlib::STD_FUNCTION_BLOCK_NAMES {
                out.push(item(fb, CompletionItemKind::CLASS, "standard function block".into()));
            }
            for (_, s) in ix.globals() {
                if matches!(s.kind, SymbolKind::Type | SymbolKind::Pou(sfc_syntax::ast::PouKind::FunctionBlock)) {
                    out.push(symbol_item(ix, s));
                }
            }
            out.push(snippet("ARRAY", "ARRAY [${1:1}..${2:10}] OF ${3:INT}", "array type"));
            out.push(snippet("STRING", "STRING[${1:80}]", "string type"));
        }
        Context::Code => {
            names(&mut out, &|k| {
                matches!(k, SymbolKind::Variable(_) | SymbolKind::Step(_) | SymbolKind::Action | SymbolKind::EnumValue)
                    || matches!(k, SymbolKind::Pou(sfc_syntax::ast::PouKind::Function))
            });
            for f in sfc_st::stdlib::STD_FUNCTION_NAMES {
                let mut it = item(f, CompletionItemKind::FUNCTION, "standard function".into());
                it.sort_text = Some(format!("z{f}"));
                out.push(it);
            }
            for k in CODE_KEYWORDS {
                out.push(keyword(k));
            }
        }
        Context::ChartBody => {
            out.push(snippet("STEP", "STEP ${1:Name}:\n\t$0\nEND_STEP", "a step"));
            out.push(snippet("INITIAL_STEP", "INITIAL_STEP ${1:Init}:\n\t$0\nEND_STEP", "the initial step"));
            out.push(snippet(
                "TRANSITION",
                "TRANSITION ${1:Name} FROM ${2:Step1} TO ${3:Step2}\n\t:= ${4:TRUE};\nEND_TRANSITION",
                "a transition",
            ));
            out.push(snippet("ACTION", "ACTION ${1:Name}:\n\t$0\nEND_ACTION", "an action with an ST body"));
            for k in ["END_PROGRAM", "END_FUNCTION_BLOCK", "VAR", "VAR_INPUT", "VAR_OUTPUT"] {
                out.push(keyword(k));
            }
        }
        Context::TopLevel => {
            out.push(snippet(
                "PROGRAM",
                "PROGRAM ${1:Name}\n\tVAR_INPUT\n\t\t${2:Start} : BOOL;\n\tEND_VAR\n\n\tINITIAL_STEP Init:\n\tEND_STEP\n$0\nEND_PROGRAM",
                "a program with a chart",
            ));
            out.push(snippet(
                "FUNCTION_BLOCK",
                "FUNCTION_BLOCK ${1:Name}\n\t$0\nEND_FUNCTION_BLOCK",
                "a function block",
            ));
            out.push(snippet("TYPE", "TYPE\n\t${1:Name} : ${2:INT};\nEND_TYPE", "a type declaration"));
            for k in [
                "VAR",
                "VAR_INPUT",
                "VAR_OUTPUT",
                "VAR_IN_OUT",
                "VAR_GLOBAL",
                "VAR_EXTERNAL",
                "END_VAR",
                "CONSTANT",
                "RETAIN",
                "AT",
            ] {
                out.push(keyword(k));
            }
        }
    }
    out
}

fn symbol_item(ix: &FileIndex, s: &crate::index::Symbol) -> CompletionItem {
    let (kind, detail) = match &s.kind {
        SymbolKind::Variable(v) => (
            CompletionItemKind::VARIABLE,
            format!(
                "{} {}{}",
                v.section.keyword(),
                v.ty,
                v.at.as_ref().map(|a| format!(" AT {a}")).unwrap_or_default()
            ),
        ),
        SymbolKind::Step(st) => {
            (CompletionItemKind::EVENT, if st.initial { "initial step".into() } else { "step".into() })
        }
        SymbolKind::Action => (CompletionItemKind::METHOD, "action".into()),
        SymbolKind::Method => (CompletionItemKind::METHOD, "method".into()),
        SymbolKind::Property => (CompletionItemKind::PROPERTY, "property".into()),
        SymbolKind::Interface => (CompletionItemKind::INTERFACE, "interface".into()),
        SymbolKind::Transition(_) => (CompletionItemKind::OPERATOR, "transition".into()),
        SymbolKind::Pou(k) => (CompletionItemKind::MODULE, k.keyword().to_string()),
        SymbolKind::Type => (CompletionItemKind::STRUCT, "type".into()),
        SymbolKind::EnumValue => (CompletionItemKind::ENUM_MEMBER, "enumerated value".into()),
    };
    let mut it = item(&s.name, kind, detail.clone());
    it.label_details = Some(CompletionItemLabelDetails { detail: None, description: Some(detail) });
    let _ = ix;
    it
}

const ELEMENTARY: &[&str] = &[
    "BOOL",
    "SINT",
    "INT",
    "DINT",
    "LINT",
    "USINT",
    "UINT",
    "UDINT",
    "ULINT",
    "REAL",
    "LREAL",
    "TIME",
    "LTIME",
    "DATE",
    "TIME_OF_DAY",
    "TOD",
    "DATE_AND_TIME",
    "DT",
    "STRING",
    "WSTRING",
    "BYTE",
    "WORD",
    "DWORD",
    "LWORD",
];

const CODE_KEYWORDS: &[&str] = &[
    "AND",
    "OR",
    "XOR",
    "NOT",
    "MOD",
    "TRUE",
    "FALSE",
    "IF",
    "THEN",
    "ELSIF",
    "ELSE",
    "END_IF",
    "CASE",
    "OF",
    "END_CASE",
    "FOR",
    "TO",
    "BY",
    "DO",
    "END_FOR",
    "WHILE",
    "END_WHILE",
    "REPEAT",
    "UNTIL",
    "END_REPEAT",
    "EXIT",
    "RETURN",
];
