//! Operands: the `Access` elements of a network and the operands written in action tokens, as
//! IEC names. A global operand the file does not declare (`"DB".a.b`, `"Tag"`, a global
//! constant) is declared at file level under a flat name (`DB_a_b`: the path's parts joined by
//! `_`, repaired as an IEC name, numbered if two paths give the same name), with the type its
//! first use implies and a warning that says so.

use crate::{Cx, Global};
use roxmltree::Node;
use sfc_xmlmap::names::{is_ident, sanitize};
use sfc_xmlmap::xml::{anchor, child, children};
use sfc_xmlmap::{Emitter, Frag};
use std::ops::Range;

/// Where an operand is read: a transition condition is IEC code (only `X` and `T` of a step are
/// IEC step members); interlocks, supervisions and actions are kept for the graph profile.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Place {
    Transition,
    Kept,
}

/// The IEC type of a SIMATIC comparator's `SrcType` or an elementary SIMATIC type, if known.
pub(crate) fn iec_elementary(t: &str) -> Option<&'static str> {
    Some(match t.trim().to_ascii_lowercase().as_str() {
        "bool" => "BOOL",
        "byte" => "BYTE",
        "word" => "WORD",
        "dword" => "DWORD",
        "lword" => "LWORD",
        "sint" => "SINT",
        "int" => "INT",
        "dint" => "DINT",
        "lint" => "LINT",
        "usint" => "USINT",
        "uint" => "UINT",
        "udint" => "UDINT",
        "ulint" => "ULINT",
        "real" => "REAL",
        "lreal" => "LREAL",
        "time" => "TIME",
        "ltime" => "LTIME",
        "date" => "DATE",
        "time_of_day" | "tod" => "TIME_OF_DAY",
        "date_and_time" | "dt" => "DATE_AND_TIME",
        "char" => "CHAR",
        "wchar" => "WCHAR",
        "string" => "STRING",
        "wstring" => "WSTRING",
        _ => return None,
    })
}

/// A global operand by its TIA spelling: its IEC name, declared on first use.
pub(crate) fn global(
    cx: &mut Cx,
    origin: &str,
    parts: &[String],
    ty: &str,
    why: &str,
    at: Range<u32>,
    constant: bool,
) -> String {
    if let Some(&i) = cx.global_index.get(origin) {
        if !cx.pou_globals.contains(&i) {
            cx.pou_globals.push(i);
        }
        return cx.globals.get(i).map(|g| g.name.clone()).unwrap_or_default();
    }
    cx.pou_globals.push(cx.globals.len());
    let base = sanitize(&parts.join("_"));
    let mut name = base.clone();
    let mut k = 0;
    // Not the name of a global already, nor of a variable, step or action of the block.
    while cx.file_names.contains(&name.to_ascii_uppercase()) || cx.used.contains(&name.to_ascii_uppercase()) {
        k += 1;
        name = format!("{base}_{k}");
    }
    cx.file_names.insert(name.to_ascii_uppercase());
    cx.global_index.insert(origin.to_string(), cx.globals.len());
    cx.globals.push(Global {
        name: name.clone(),
        ty: ty.to_string(),
        why: why.to_string(),
        origin: origin.to_string(),
        at,
        constant,
    });
    name
}

/// Writes the file-level `VAR_GLOBAL` of the operands used, each with its warning.
pub(crate) fn write_globals(cx: &mut Cx, em: &mut Emitter) {
    if cx.globals.is_empty() {
        return;
    }
    let globals = cx.globals.clone();
    em.str("VAR_GLOBAL\n");
    for g in &globals {
        em.open(g.at.clone());
        let origin = g.origin.replace("*)", "* )").replace("(*", "( *");
        em.str(&format!("    {} : {}; (* {} *)\n", g.name, g.ty, origin));
        em.close();
        let what = if g.constant { "global constant" } else { "global operand" };
        let d = cx.diag(
            "SFC0744",
            g.at.clone(),
            format!(
                "the {what} {} is not declared in this file: declared as `{} : {}` ({})",
                g.origin, g.name, g.ty, g.why
            ),
        );
        if g.constant {
            d.notes.push("its value is not in the export: it starts at its type's default value".into());
        } else {
            d.notes.push(
                "its data block or tag table is not in the export; declare it in the PLC tags to be sure of its type"
                    .into(),
            );
        }
    }
    em.str("END_VAR\n\n");
}

/// What an `Access` reads, as an IEC operand located at the `Access` element. `ty`/`why`: the
/// type its use implies (for a global declared from its use). `None` after a located error.
pub(crate) fn access(cx: &mut Cx, a: Node, ty: &str, why: &str, place: Place) -> Option<Frag> {
    let at = anchor(a);
    let scope = a.attribute("Scope").unwrap_or("");
    match scope {
        "GlobalVariable" | "LocalVariable" => {
            let Some(sym) = child(a, "Symbol") else {
                cx.diag("SFC0743", at, format!("the {scope} access has no `Symbol`"));
                return None;
            };
            let mut parts: Vec<(String, Vec<String>)> = Vec::new();
            for c in children(sym, "Component") {
                let name = c.attribute("Name").unwrap_or("").to_string();
                let mut idx = Vec::new();
                if c.attribute("AccessModifier").is_some_and(|m| m == "Array") {
                    for i in children(c, "Access") {
                        let v = access(cx, i, "DINT", "an array index", place)?;
                        idx.push(v.text);
                    }
                }
                parts.push((name, idx));
            }
            if parts.is_empty() {
                cx.diag("SFC0743", at, format!("the {scope} access names nothing"));
                return None;
            }
            if scope == "GlobalVariable" {
                let origin = origin_of(&parts);
                let mut flat = Vec::new();
                for (n, idx) in &parts {
                    flat.push(n.clone());
                    for i in idx {
                        if !i.bytes().all(|b| b.is_ascii_digit() || b == b'-') {
                            cx.diag(
                                "SFC0743",
                                at,
                                format!("{origin}: an index that is not a constant cannot be imported (the DB is declared as flat variables)"),
                            );
                            return None;
                        }
                        flat.push(i.clone());
                    }
                }
                let name = global(cx, &origin, &flat, ty, why, at.clone(), false);
                Some(Frag::located(name, at))
            } else {
                local(cx, &parts, at, place)
            }
        }
        "LiteralConstant" | "TypedConstant" => {
            let c = child(a, "Constant");
            let v = c.and_then(|c| child(c, "ConstantValue")).and_then(|v| v.text()).unwrap_or("").trim();
            let t = c.and_then(|c| child(c, "ConstantType")).and_then(|v| v.text()).unwrap_or("").trim();
            if v.is_empty() {
                cx.diag("SFC0743", at, "the constant has no value");
                return None;
            }
            Some(Frag::located(literal(v, t), at))
        }
        "GlobalConstant" | "LocalConstant" => {
            let n = child(a, "Constant").and_then(|c| c.attribute("Name")).unwrap_or("").to_string();
            if n.is_empty() {
                cx.diag("SFC0743", at, "the constant has no name");
                return None;
            }
            if scope == "LocalConstant" {
                return local(cx, &[(n, Vec::new())], at, place);
            }
            let origin = format!("\"{n}\"");
            let name = global(cx, &origin, &[n], ty, why, at.clone(), true);
            Some(Frag::located(name, at))
        }
        other => {
            cx.diag("SFC0743", at, format!("an operand of scope `{other}` cannot be imported"))
                .notes
                .push("sfc reads global and local variables and constants; absolute addresses and indirect accesses are not read".into());
            None
        }
    }
}

/// `"DB".a[3].b`: how TIA writes a global path.
fn origin_of(parts: &[(String, Vec<String>)]) -> String {
    let mut s = String::new();
    for (i, (n, idx)) in parts.iter().enumerate() {
        if i > 0 {
            s.push('.');
        }
        if is_plain(n) && i > 0 {
            s.push_str(n);
        } else {
            s.push('"');
            s.push_str(n);
            s.push('"');
        }
        if !idx.is_empty() {
            s.push('[');
            s.push_str(&idx.join(","));
            s.push(']');
        }
    }
    s
}

fn is_plain(n: &str) -> bool {
    n.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_') && n.bytes().next().is_some_and(|b| !b.is_ascii_digit())
}

/// A SIMATIC constant as an IEC literal (`true` → `TRUE`, a typed value keeps its text).
pub(crate) fn literal(v: &str, ty: &str) -> String {
    match v.to_ascii_lowercase().as_str() {
        "true" => return "TRUE".into(),
        "false" => return "FALSE".into(),
        _ => {}
    }
    if ty.eq_ignore_ascii_case("bool") {
        return if v == "1" { "TRUE".into() } else { "FALSE".into() };
    }
    v.to_string()
}

/// A local access (`#var.a`, `#"Step".U`): a variable of the block, or a member of a step or a
/// transition of the chart.
fn local(cx: &mut Cx, parts: &[(String, Vec<String>)], at: Range<u32>, place: Place) -> Option<Frag> {
    let (first, idx0) = parts.first()?;
    let member = parts.get(1).map(|(m, _)| m.clone());
    if let Some(step) = cx.steps.get(first).cloned() {
        let m = member.unwrap_or_else(|| "X".into()).to_ascii_uppercase();
        if place == Place::Transition && m != "X" && m != "T" {
            if m == "U" {
                cx.diag(
                    "SFC0751",
                    at.clone(),
                    format!("`{first}.U` (step time without disturbance) is read as `{step}.T` in the IEC condition"),
                )
                .notes
                .push("no profile simulates disturbances yet, so a step's time without disturbance is its time".into());
                return Some(Frag::located(format!("{step}.T"), at));
            }
            cx.diag(
                "SFC0751",
                at.clone(),
                format!("`{first}.{m}` is GRAPH runtime data of a step, which an IEC transition condition cannot read"),
            )
            .notes
            .push("IEC steps have `.X` (active) and `.T` (time since activation)".into());
        }
        return Some(Frag::located(format!("{step}.{m}"), at));
    }
    if let Some(tr) = cx.transitions.get(first).cloned() {
        let m = member.unwrap_or_else(|| "TT".into()).to_ascii_uppercase();
        // `TT` ("transition satisfied") is its condition being TRUE: written as the condition.
        if m == "TT" && place != Place::Transition {
            if let Some(c) = cx.conditions.get(&tr.to_ascii_uppercase()) {
                return Some(Frag::located(format!("({c})"), at));
            }
        }
        if place == Place::Transition {
            cx.diag(
                "SFC0751",
                at.clone(),
                format!("`{first}.{m}` is GRAPH runtime data of a transition, which an IEC transition condition cannot read"),
            );
        }
        return Some(Frag::located(format!("{tr}.{m}"), at));
    }
    let mut s =
        cx.vars.get(first).cloned().unwrap_or_else(|| if is_ident(first) { first.clone() } else { sanitize(first) });
    push_index(&mut s, idx0);
    for (n, idx) in parts.iter().skip(1) {
        s.push('.');
        s.push_str(&if is_ident(n) { n.clone() } else { sanitize(n) });
        push_index(&mut s, idx);
    }
    Some(Frag::located(s, at))
}

fn push_index(s: &mut String, idx: &[String]) {
    if !idx.is_empty() {
        s.push('[');
        s.push_str(&idx.join(", "));
        s.push(']');
    }
}

/// The text of an action's tokens with GRAPH's operand syntax made IEC: `"DB".a.b` becomes the
/// global's name, `#"Step".U` becomes `Step.U`, `#var` becomes `var`. `ty`: the type a global
/// operand's use implies. `Err` with a message when the text cannot be read.
pub(crate) fn tokens_to_st(cx: &mut Cx, text: &str, at: Range<u32>, ty: &str, why: &str) -> Result<String, String> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while let Some(&c) = chars.get(i) {
        match c {
            '\'' => {
                let start = i;
                i += 1;
                while chars.get(i).is_some_and(|&c| c != '\'') {
                    i += 1;
                }
                if chars.get(i).is_none() {
                    return Err("a string is not closed".into());
                }
                i += 1;
                out.extend(chars.get(start..i).unwrap_or_default());
            }
            '"' | '#' => {
                let is_local = c == '#';
                if is_local {
                    i += 1;
                }
                let mut parts: Vec<(String, Vec<String>)> = Vec::new();
                loop {
                    let name = if chars.get(i) == Some(&'"') {
                        let start = i + 1;
                        i += 1;
                        while chars.get(i).is_some_and(|&c| c != '"') {
                            i += 1;
                        }
                        if chars.get(i).is_none() {
                            return Err("a quoted name is not closed".into());
                        }
                        let n: String = chars.get(start..i).unwrap_or_default().iter().collect();
                        i += 1;
                        n
                    } else {
                        let start = i;
                        while chars.get(i).is_some_and(|c| c.is_alphanumeric() || *c == '_') {
                            i += 1;
                        }
                        chars.get(start..i).unwrap_or_default().iter().collect()
                    };
                    if name.is_empty() {
                        return Err(format!("`{c}` is not followed by a name"));
                    }
                    let mut idx = Vec::new();
                    if chars.get(i) == Some(&'[') {
                        let start = i + 1;
                        while chars.get(i).is_some_and(|&c| c != ']') {
                            i += 1;
                        }
                        if chars.get(i).is_none() {
                            return Err("an index is not closed".into());
                        }
                        let inner: String = chars.get(start..i).unwrap_or_default().iter().collect();
                        idx = inner.split(',').map(|s| s.trim().to_string()).collect();
                        i += 1;
                    }
                    parts.push((name, idx));
                    // `.member` continues the path; `..` (a range) and `.5` (a number) do not.
                    let next = chars.get(i + 1).copied();
                    if chars.get(i) == Some(&'.') && next.is_some_and(|n| n == '"' || n.is_alphabetic() || n == '_') {
                        i += 1;
                        continue;
                    }
                    break;
                }
                let text = if is_local {
                    local(cx, &parts, at.clone(), Place::Kept).map(|f| f.text).unwrap_or_default()
                } else {
                    let origin = origin_of(&parts);
                    let mut flat = Vec::new();
                    for (n, idx) in &parts {
                        flat.push(n.clone());
                        for x in idx {
                            if !x.bytes().all(|b| b.is_ascii_digit()) {
                                return Err(format!("{origin}: an index that is not a constant cannot be imported"));
                            }
                            flat.push(x.clone());
                        }
                    }
                    global(cx, &origin, &flat, ty, why, at.clone(), false)
                };
                out.push_str(&text);
            }
            c if c.is_alphanumeric() || c == '_' => {
                // A word, or a typed literal (`T#5S`, `16#FF`, `INT#3`): copied as it is.
                let start = i;
                while chars.get(i).is_some_and(|c| c.is_alphanumeric() || *c == '_') {
                    i += 1;
                }
                if chars.get(i) == Some(&'#') {
                    i += 1;
                    while chars.get(i).is_some_and(|c| c.is_alphanumeric() || matches!(*c, '_' | '.' | ':' | '-')) {
                        i += 1;
                    }
                }
                out.extend(chars.get(start..i).unwrap_or_default());
            }
            _ => {
                out.push(c);
                i += 1;
            }
        }
    }
    Ok(out)
}
