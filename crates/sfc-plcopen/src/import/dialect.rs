//! Vendor dialects of Structured Text in imported bodies (CODESYS, e!COCKPIT, TwinCAT).
//!
//! What has an IEC 61131-3 meaning is mapped as the code is copied ([`map`]): `Enum.Value` is
//! `Enum#Value`, `GVL.X` (a variable of a named global variable list) is `X`, `Standard.TON`
//! (a standard block through its library's namespace) is `TON`. What has none (pointers, `ADR`,
//! `__POUNAME`, library namespaces) is found before the
//! POU is written ([`reasons`]): the POU is then kept as written and not analysed (a note), and
//! never an error that blocks the rest of the file.

use super::Ctx;
use crate::xml::{self, attr, child, elements, XText};
use roxmltree::Node;
use sfc_syntax::lexer::{lex, TokenKind};

/// Operators and built-ins of CODESYS ST that IEC 61131-3 lacks.
const VENDOR_WORDS: &[&str] = &["ADRINST", "BITADR", "XSIZEOF", "INDEXOF", "NEW", "DELETE"];

/// CODESYS built-ins with doubled underscores that sfc analyses.
const KNOWN_BUILTINS: &[&str] = &["__ISVALIDREF"];

/// Why the POU `p` cannot be analysed, if it cannot: its first vendor construct, in words.
pub(super) fn reasons(cx: &Ctx, p: Node) -> Option<String> {
    for t in code_texts(p) {
        if let Some(r) = code_reason(cx, &t) {
            return Some(r);
        }
    }
    None
}

/// Every piece of code text of a POU: ST and IL bodies (the POU's, its actions' and
/// transitions', inline conditions), and the expressions of FBD/LD variables.
pub(super) fn code_texts(p: Node) -> Vec<String> {
    let mut out = Vec::new();
    for e in p.descendants().filter(|e| e.is_element()) {
        match e.tag_name().name() {
            "ST" | "IL" => out.push(xml::formatted_text(e).text),
            "expression" => out.push(xml::text_of(e).text),
            _ => {}
        }
    }
    out
}

/// The identifiers of a text, upper-case.
pub(super) fn identifiers(text: &str, out: &mut std::collections::HashSet<String>) {
    let (toks, _) = lex(0, text);
    for t in toks.iter().filter(|t| t.kind == TokenKind::Ident) {
        out.insert(text[t.start as usize..t.end as usize].to_ascii_uppercase());
    }
}

fn code_reason(cx: &Ctx, text: &str) -> Option<String> {
    let (toks, _) = lex(0, text);
    let sig: Vec<_> = toks.iter().filter(|t| !t.kind.is_trivia() && t.kind != TokenKind::Eof).collect();
    let word = |i: usize| sig.get(i).map(|t| &text[t.start as usize..t.end as usize]).unwrap_or("");
    for (i, t) in sig.iter().enumerate() {
        let w = word(i);
        match t.kind {
            TokenKind::Unknown if w == "^" => return Some("it dereferences a pointer (`p^`)".into()),
            TokenKind::Unknown => return Some(format!("it uses `{w}`, which is not IEC 61131-3")),
            TokenKind::Ident => {
                let up = w.to_ascii_uppercase();
                let next = sig.get(i + 1).map(|t| t.kind);
                let prev = i.checked_sub(1).and_then(|k| sig.get(k)).map(|t| t.kind);
                if up.starts_with("__") && !KNOWN_BUILTINS.contains(&up.as_str()) {
                    return Some(format!("it uses `{w}`, a CODESYS built-in"));
                }
                if prev != Some(TokenKind::Dot)
                    && next == Some(TokenKind::LParen)
                    && VENDOR_WORDS.contains(&up.as_str())
                    && !cx.used.contains(&up)
                {
                    return Some(format!("it calls `{w}`, a CODESYS operator"));
                }
                // `A.B` where `A` names nothing of the POU or the file: a namespace, which
                // IEC 61131-3 cannot reach. (A program's variable, `Main.X`, is reachable: the
                // program's one instance is a global named after it.)
                if next == Some(TokenKind::Dot)
                    && prev != Some(TokenKind::Dot)
                    && !cx.used.contains(&up)
                    && !cx.global_names.contains(&up)
                    && !cx.gvl_names.contains(&up)
                    && !cx.enum_types.contains(&up)
                    && !cx.programs.contains(&up)
                    && sig.get(i + 2).is_some_and(|t| t.kind == TokenKind::Ident)
                    && map_type(&format!("{w}.{}", word(i + 2))).is_none()
                {
                    return Some(format!(
                        "it uses `{w}.{}`, and `{w}` is declared nowhere in the file (a namespace or another program)",
                        word(i + 2)
                    ));
                }
            }
            _ => {}
        }
    }
    None
}

/// `Standard.TON` → `TON`: a standard block or function reached through a library namespace.
pub(super) fn map_type(name: &str) -> Option<&str> {
    let (_, last) = name.rsplit_once('.')?;
    (sfc_st::stdlib::std_function_block(last).is_some() || sfc_st::stdlib::std_function(last).is_some()).then_some(last)
}

/// `t` with the variables named by a chart word renamed as their declarations are
/// ([`Ctx::renamed`]), then mapped by [`map_dots`].
pub(super) fn map(cx: &Ctx, t: &XText) -> XText {
    if cx.verbatim || cx.renamed.is_empty() {
        return map_dots(cx, t);
    }
    let text = &t.text;
    let (toks, _) = lex(0, text);
    let mut out = XText { anchor: t.anchor.clone(), ..Default::default() };
    let mut at = 0usize;
    for k in toks.iter().filter(|k| k.kind == TokenKind::Ident) {
        let word = &text[k.start as usize..k.end as usize];
        if let Some(new) = cx.renamed.get(&word.to_ascii_uppercase()) {
            out.push(&t.slice(at..k.start as usize));
            out.push(&XText::synthetic(new.clone(), t.anchor.clone()));
            at = k.end as usize;
        }
    }
    if at == 0 {
        return map_dots(cx, t);
    }
    out.push(&t.slice(at..text.len()));
    map_dots(cx, &out)
}

/// Code copied from the XML with CODESYS spellings that have an IEC meaning rewritten:
/// `Enum.Value` → `Enum#Value`, `GVL.X` → `X`, `Standard.TON` → `TON`, and the partial access
/// of a bit, `w.%X3` (IEC 61131-3 3rd edition, which CODESYS also writes), → `w.3`.
fn map_dots(cx: &Ctx, t: &XText) -> XText {
    if cx.verbatim
        || !t.text.contains('.')
        || (cx.enum_types.is_empty()
            && cx.gvl_names.is_empty()
            && !t.text.contains("tandard")
            && !t.text.contains(".%"))
    {
        return t.clone();
    }
    let text = &t.text;
    let (toks, _) = lex(0, text);
    let sig: Vec<_> = toks.iter().filter(|k| !k.kind.is_trivia() && k.kind != TokenKind::Eof).collect();
    let mut out = XText { anchor: t.anchor.clone(), ..Default::default() };
    let mut at = 0usize;
    let mut i = 0;
    while let (Some(&a), Some(&dot), Some(&b)) = (sig.get(i), sig.get(i + 1), sig.get(i + 2)) {
        let prev_dot = i.checked_sub(1).and_then(|k| sig.get(k)).is_some_and(|t| t.kind == TokenKind::Dot);
        let adjacent = a.end == dot.start && dot.end == b.start;
        // `w.%X3` → `w.3`: a bit of a variable (the partial access of a byte, word or double
        // word, `%B`/`%W`/`%D`, has no IEC 61131-2 spelling and is left as written).
        if dot.kind == TokenKind::Dot && b.kind == TokenKind::Address && dot.end == b.start {
            let bw = &text[b.start as usize..b.end as usize];
            let bit = bw.get(2..).unwrap_or("");
            if bw.len() > 2 && bw[..2].eq_ignore_ascii_case("%X") && bit.bytes().all(|c| c.is_ascii_digit()) {
                out.push(&t.slice(at..b.start as usize));
                out.push(&XText::synthetic(bit.to_string(), t.anchor.clone()));
                at = b.end as usize;
                i += 2;
                continue;
            }
        }
        if a.kind == TokenKind::Ident
            && dot.kind == TokenKind::Dot
            && b.kind == TokenKind::Ident
            && !prev_dot
            && adjacent
        {
            let aw = &text[a.start as usize..a.end as usize];
            let bw = &text[b.start as usize..b.end as usize];
            let up = aw.to_ascii_uppercase();
            let local = cx.used.contains(&up);
            let replacement = if local {
                None
            } else if cx.enum_types.contains(&up) {
                Some((a.start as usize, b.end as usize, format!("{aw}#{bw}")))
            } else if (cx.gvl_names.contains(&up) && !cx.global_names.contains(&up))
                || (up == "STANDARD" && map_type(&format!("{aw}.{bw}")).is_some())
            {
                // `GVL.X` is `X`; `Standard.TON` is `TON`.
                Some((a.start as usize, dot.end as usize, String::new()))
            } else {
                None
            };
            if let Some((s, e, r)) = replacement {
                out.push(&t.slice(at..s));
                out.push(&XText::synthetic(r, t.anchor.clone()));
                at = e;
                i += 2;
                continue;
            }
        }
        i += 1;
    }
    if at == 0 {
        return t.clone();
    }
    out.push(&t.slice(at..text.len()));
    out
}

/// The enumerated types declared in a project (`dataType` with an `enum` base type).
pub(super) fn enum_types(root: Node) -> std::collections::HashSet<String> {
    root.descendants()
        .filter(|d| d.is_element() && d.tag_name().name() == "dataType")
        .filter(|d| child(*d, "baseType").is_some_and(|b| elements(b).any(|e| e.tag_name().name() == "enum")))
        .filter_map(|d| attr(d, "name").map(|n| n.trim().to_ascii_uppercase()))
        .collect()
}

/// Whether the POU `p` names something as CODESYS allows and IEC 61131-3 does not
/// ([`super::is_codesys_ident`]): a variable, step, action, transition or jump target, or an
/// identifier of its code.
pub(super) fn codesys_names(p: Node) -> bool {
    let named = p.descendants().filter(|e| e.is_element()).any(|e| {
        let key = if e.tag_name().name() == "jumpStep" { "targetName" } else { "name" };
        attr(e, key).is_some_and(|n| super::is_codesys_ident(n.trim()))
    });
    named || {
        let mut ids = std::collections::HashSet::new();
        for t in code_texts(p) {
            identifiers(&t, &mut ids);
        }
        ids.iter().any(|i| super::is_codesys_ident(i))
    }
}

/// Whether the project `root` was written by CODESYS or a tool built on it (TwinCAT,
/// e!COCKPIT): its file header names one, or it holds CODESYS's `addData`.
pub(super) fn codesys_file(root: Node) -> bool {
    vendor(root).is_some()
}

/// Which tool of the CODESYS family wrote the project `root`, if one did: the product or company
/// its `fileHeader` names (TwinCAT's exports say `TwinCAT PLC Control` and `Beckhoff
/// Automation GmbH`, e!COCKPIT's `e!COCKPIT` and `WAGO`, CODESYS's `CODESYS`), or else
/// CODESYS's `addData` (`http://www.3s-software.com/plcopenxml/...`), which every tool built on
/// CODESYS writes.
pub(super) fn vendor(root: Node) -> Option<crate::Vendor> {
    use crate::Vendor;
    let header = child(root, "fileHeader")
        .map(|h| format!("{} {}", attr(h, "productName").unwrap_or(""), attr(h, "companyName").unwrap_or("")))
        .unwrap_or_default()
        .to_ascii_uppercase();
    if ["TWINCAT", "BECKHOFF"].iter().any(|k| header.contains(k)) {
        return Some(Vendor::TwinCat);
    }
    if header.contains("E!COCKPIT") {
        return Some(Vendor::ECockpit);
    }
    if ["CODESYS", "3S-SMART"].iter().any(|k| header.contains(k)) {
        return Some(Vendor::Codesys);
    }
    root.descendants()
        .any(|d| {
            d.is_element()
                && d.tag_name().name() == "data"
                && attr(d, "name").is_some_and(|n| n.contains("3s-software.com"))
        })
        .then_some(Vendor::Codesys)
}
