//! The block interface: `Input`, `Output`, `InOut`, `Static`, `Temp` and `Constant` sections
//! as VAR blocks, SIMATIC types as IEC types, `StartValue` as initial values. GRAPH's system
//! members (the `Base` section, `RT_DATA`, one `G7_StepPlus_Vn` per step and one
//! `G7_TransitionPlus_Vn` per transition) are the chart's runtime data, not variables: they are
//! not written, and what they hold is compared with the chart (step and transition numbers,
//! `T_MAX`/`T_WARN`) by the caller.

use crate::operand::{iec_elementary, literal};
use crate::Cx;
use roxmltree::Node;
use sfc_xmlmap::names::{is_ident, sanitize};
use sfc_xmlmap::xml::{anchor, child, children};
use sfc_xmlmap::{Emitter, Frag};
use std::collections::HashMap;
use std::ops::Range;

/// The `SNO`, `T_MAX` and `T_WARN` start values of a step structure, and its start tag.
pub(crate) type StepData = (Option<String>, Option<String>, Option<String>, Range<u32>);

/// What the system members hold, by the name of the step or transition they belong to.
#[derive(Default)]
pub(crate) struct System {
    /// Step name → (`SNO`, `T_MAX`, `T_WARN` start values, the member's start tag).
    pub steps: HashMap<String, StepData>,
    /// Transition name → (`TNO` start value, the member's start tag).
    pub transitions: HashMap<String, (Option<String>, Range<u32>)>,
    /// The other system members not written (`RT_DATA`, `Base`'s members).
    pub dropped: Vec<String>,
}

/// Reads the interface and writes its VAR blocks at `indent`.
pub(crate) fn write(cx: &mut Cx, iface: Node, fb: &str, em: &mut Emitter, indent: &str) -> System {
    let mut sys = System::default();
    let Some(sections) = child(iface, "Sections") else { return sys };
    for s in children(sections, "Section") {
        let name = s.attribute("Name").unwrap_or("");
        if name == "Base" {
            for m in s.descendants().filter(|d| d.is_element() && d.tag_name().name() == "Member") {
                sys.dropped.push(m.attribute("Name").unwrap_or("").to_string());
            }
            continue;
        }
        let kw = match name {
            "Input" => "VAR_INPUT",
            "Output" => "VAR_OUTPUT",
            "InOut" => "VAR_IN_OUT",
            "Static" => "VAR",
            "Temp" => "VAR_TEMP",
            "Constant" => "VAR CONSTANT",
            _ => {
                cx.diag("SFC0752", anchor(s), format!("the interface section `{name}` is not imported"));
                continue;
            }
        };
        let mut plain = Vec::new();
        let mut retain = Vec::new();
        for m in children(s, "Member") {
            let ty = m.attribute("Datatype").unwrap_or("");
            let mname = m.attribute("Name").unwrap_or("").to_string();
            if ty.starts_with("G7_StepPlus") {
                sys.steps
                    .insert(mname, (sub_start(m, "SNO"), sub_start(m, "T_MAX"), sub_start(m, "T_WARN"), anchor(m)));
                continue;
            }
            if ty.starts_with("G7_TransitionPlus") {
                sys.transitions.insert(mname, (sub_start(m, "TNO"), anchor(m)));
                continue;
            }
            if ty.starts_with("G7_") {
                sys.dropped.push(mname);
                continue;
            }
            if m.attribute("Remanence") == Some("Retain") && kw == "VAR" {
                retain.push(m);
            } else {
                plain.push(m);
            }
        }
        for (kw, members) in [(kw, plain), ("VAR RETAIN", retain)] {
            if members.is_empty() {
                continue;
            }
            em.open(anchor(s));
            em.str(&format!("{indent}{kw}\n"));
            for m in members {
                member(cx, m, fb, em, &format!("{indent}    "));
            }
            em.str(&format!("{indent}END_VAR\n"));
            em.close();
        }
    }
    sys
}

/// The start value of a member of a system structure (`SNO`, `T_MAX`).
fn sub_start(m: Node, name: &str) -> Option<String> {
    m.descendants()
        .filter(|d| d.is_element() && d.tag_name().name() == "Member" && d.attribute("Name") == Some(name))
        .find_map(|d| child(d, "StartValue").and_then(|v| v.text()).map(|t| t.trim().to_string()))
}

fn member(cx: &mut Cx, m: Node, fb: &str, em: &mut Emitter, indent: &str) {
    let at = anchor(m);
    let raw = m.attribute("Name").unwrap_or("");
    let base = if is_ident(raw) {
        raw.to_string()
    } else if raw.trim().is_empty() {
        "Unnamed".to_string()
    } else {
        sanitize(raw)
    };
    let name = cx.fresh(&base);
    if name != raw {
        cx.diag(
            "SFC0753",
            crate::chart::attr_or(m, "Name"),
            format!("the variable `{raw}` is imported as `{name}`, and so are its uses"),
        );
    }
    cx.vars.insert(raw.to_string(), name.clone());
    let ty = type_of(cx, m, fb, &name);
    em.open(at);
    em.str(&format!("{indent}{name} : "));
    em.frag(&ty);
    if let Some(v) = child(m, "StartValue").and_then(|v| v.text()) {
        let v = v.trim();
        if !v.is_empty() {
            let dt = m.attribute("Datatype").unwrap_or("");
            em.str(" := ");
            em.str(&literal(v, dt));
        }
    }
    if children(m, "Subelement").any(|s| child(s, "StartValue").is_some()) {
        match array_start(m) {
            Some(init) if child(m, "StartValue").is_none() => {
                em.str(" := ");
                em.str(&init);
            }
            _ => {
                cx.diag(
                    "SFC0752",
                    anchor(m),
                    format!("the start values of elements of `{raw}` are not imported (the elements start at their type's default)"),
                )
                .notes
                .push("sfc writes the start values of a one-dimensional array of an elementary type; this member is another kind".into());
            }
        }
    }
    em.str(";");
    if let Some(c) = child(m, "Comment").and_then(crate::first_text) {
        em.str(&format!(" (* {} *)", c.replace("*)", "* )").replace("(*", "( *").replace('\n', " ")));
    }
    em.str("\n");
    em.close();
}

/// The longest array whose element start values are written (`[v1, v2, …]`).
const MAX_ARRAY_INIT: i64 = 4096;

/// `[10, 20, 0, 40]` from the `Subelement` start values of a one-dimensional array of an
/// elementary type (`Array[1..4] of Int`, paths `1`, `2`, `4`): elements without a value get
/// their type's zero, up to the last one given.
fn array_start(m: Node) -> Option<String> {
    let dt = m.attribute("Datatype")?.trim();
    let inner = dt.strip_prefix("Array[").or_else(|| dt.strip_prefix("array["))?;
    let (dims, rest) = inner.split_once(']')?;
    let (lo, hi) = dims.split_once("..")?;
    let (lo, hi) = (lo.trim().parse::<i64>().ok()?, hi.trim().parse::<i64>().ok()?);
    if dims.contains(',') || hi < lo || hi - lo >= MAX_ARRAY_INIT {
        return None;
    }
    let elem = rest.trim().strip_prefix("of ").or_else(|| rest.trim().strip_prefix("Of "))?.trim();
    let ty = iec_elementary(elem)?;
    let zero = match ty {
        "BOOL" => "FALSE",
        "REAL" | "LREAL" => "0.0",
        "TIME" => "T#0s",
        "LTIME" => "LTIME#0s",
        t if t.contains("INT") || t.ends_with("WORD") || t == "BYTE" => "0",
        _ => return None,
    };
    let mut values: Vec<String> = Vec::new();
    for sub in children(m, "Subelement") {
        let Some(v) = child(sub, "StartValue").and_then(|v| v.text()) else { continue };
        let i = sub.attribute("Path")?.trim().parse::<i64>().ok()?;
        if i < lo || i > hi {
            return None;
        }
        let at = usize::try_from(i - lo).ok()?;
        if values.len() <= at {
            values.resize(at + 1, zero.to_string());
        }
        *values.get_mut(at)? = literal(v.trim(), elem);
    }
    Some(format!("[{}]", values.join(", ")))
}

/// The IEC type of a member (a STRUCT member gets a TYPE of its own, `<FB>_<member>`).
fn type_of(cx: &mut Cx, m: Node, fb: &str, name: &str) -> Frag {
    let at = anchor(m);
    let dt = m.attribute("Datatype").unwrap_or("").trim();
    if dt.eq_ignore_ascii_case("Struct") {
        let tname = format!("{fb}_{name}");
        let mut t = Frag::located(format!("TYPE {tname} :\nSTRUCT\n"), at.clone());
        for sub in children(m, "Member") {
            let sname_raw = sub.attribute("Name").unwrap_or("");
            let sname = if is_ident(sname_raw) { sname_raw.to_string() } else { sanitize(sname_raw) };
            let sty = type_of(cx, sub, fb, &format!("{name}_{sname}"));
            let mut line = Frag::plain(format!("    {sname} : "));
            line.push(&sty);
            if let Some(v) = child(sub, "StartValue").and_then(|v| v.text()) {
                line.push_str(&format!(" := {}", literal(v.trim(), sub.attribute("Datatype").unwrap_or(""))));
            }
            line.push_str(";\n");
            t.push(&line.locate(anchor(sub)));
        }
        t.push_str("END_STRUCT;\nEND_TYPE\n");
        cx.file_names.insert(tname.to_ascii_uppercase());
        cx.types.push(t);
        return Frag::located(tname, at);
    }
    Frag::located(type_text(cx, dt, at.clone()), at)
}

/// A SIMATIC type name as an IEC type.
fn type_text(cx: &mut Cx, dt: &str, at: Range<u32>) -> String {
    if let Some(t) = iec_elementary(dt) {
        return t.to_string();
    }
    let lower = dt.to_ascii_lowercase();
    for (p, iec) in [("string[", "STRING["), ("wstring[", "WSTRING[")] {
        if lower.starts_with(p) {
            return format!("{iec}{}", dt.get(p.len()..).unwrap_or(""));
        }
    }
    if lower.starts_with("array[") {
        if let Some(close) = dt.find(']') {
            let dims = dt.get(6..close).unwrap_or("");
            let rest = dt.get(close + 1..).unwrap_or("").trim();
            let elem = rest.strip_prefix("of ").or_else(|| rest.strip_prefix("Of ")).unwrap_or(rest).trim();
            let elem = type_text(cx, elem, at);
            return format!("ARRAY[{}] OF {elem}", dims.replace(' ', ""));
        }
    }
    let known = match dt.trim_matches('"').to_ascii_uppercase().as_str() {
        "TON" | "TON_TIME" => Some("TON"),
        "TOF" | "TOF_TIME" => Some("TOF"),
        "TP" | "TP_TIME" => Some("TP"),
        "CTU" | "CTU_INT" => Some("CTU"),
        "CTD" | "CTD_INT" => Some("CTD"),
        "CTUD" | "CTUD_INT" => Some("CTUD"),
        "R_TRIG" => Some("R_TRIG"),
        "F_TRIG" => Some("F_TRIG"),
        _ => None,
    };
    if let Some(k) = known {
        return k.to_string();
    }
    if dt.eq_ignore_ascii_case("IEC_TIMER") {
        cx.diag(
            "SFC0752",
            at,
            "the SIMATIC type `IEC_TIMER` is imported as `TON` (the instance's calls tell TON, TOF or TP apart)",
        );
        return "TON".into();
    }
    let name = sanitize(dt.trim_matches('"'));
    cx.diag(
        "SFC0752",
        at,
        format!("the data type {dt} is not in this file: the member is declared with the type `{name}`, which must be declared for sfc to check it"),
    );
    name
}
