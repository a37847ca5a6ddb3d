//! Logix tags and data types as IEC declarations: elementary types, the Logix structures TIMER,
//! COUNTER and CONTROL, user-defined types (`<DataTypes>`), arrays (`Dimensions`), initial
//! values from the decorated data.

use crate::Ctx;
use roxmltree::Node;
use sfc_xmlmap::xml::{anchor, attr, attr_range, child, children, elements, text_of};
use std::collections::BTreeSet;
use std::ops::Range;

/// Logix's elementary types that IEC 61131-3 has under the same name.
const ELEMENTARY: &[&str] = &[
    "BOOL", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "REAL", "LREAL", "BYTE", "WORD", "DWORD",
    "LWORD",
];

/// Logix's predefined structures sfc declares in a TYPE block, with their members.
pub(crate) const STRUCTS: &[(&str, &[(&str, &str)])] = &[
    ("TIMER", &[("PRE", "DINT"), ("ACC", "DINT"), ("EN", "BOOL"), ("TT", "BOOL"), ("DN", "BOOL")]),
    (
        "COUNTER",
        &[
            ("PRE", "DINT"),
            ("ACC", "DINT"),
            ("CU", "BOOL"),
            ("CD", "BOOL"),
            ("DN", "BOOL"),
            ("OV", "BOOL"),
            ("UN", "BOOL"),
        ],
    ),
    (
        "CONTROL",
        &[
            ("LEN", "DINT"),
            ("POS", "DINT"),
            ("EN", "BOOL"),
            ("EU", "BOOL"),
            ("DN", "BOOL"),
            ("EM", "BOOL"),
            ("ER", "BOOL"),
            ("UL", "BOOL"),
            ("IN", "BOOL"),
            ("FD", "BOOL"),
        ],
    ),
];

/// The chart's own tag types: not variables.
pub(crate) const SFC_TYPES: &[&str] = &["SFC_STEP", "SFC_ACTION", "SFC_STOP"];

/// One variable to declare.
#[derive(Debug, Clone)]
pub(crate) struct Var {
    pub name: String,
    /// Where the name is in the XML (the `Name` attribute).
    pub name_at: Range<u32>,
    /// The whole `<Tag>` start.
    pub anchor: Range<u32>,
    pub ty: String,
    pub init: Option<String>,
    pub attrs: Vec<(String, String)>,
    /// A program parameter's `Usage` (Studio 5000 v24 and later): `Input`, `Output` or
    /// `InOut`, declared as VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT (a `Public` one is a VAR with
    /// `sfc.logix.usage`).
    pub usage: Option<String>,
}

/// The data types of the file: user-defined names (upper case) and which of the predefined
/// structures are used.
#[derive(Default)]
pub(crate) struct Types {
    pub udts: BTreeSet<String>,
    pub used_structs: BTreeSet<&'static str>,
    /// Members of the user-defined structures, by upper-case name.
    pub members: std::collections::HashMap<String, Vec<(String, String)>>,
}

/// An IEC type for Logix data type `dt` (`None`: sfc cannot declare it).
pub(crate) fn iec_type(types: &mut Types, dt: &str) -> Option<String> {
    let up = dt.trim().to_ascii_uppercase();
    if ELEMENTARY.contains(&up.as_str()) {
        return Some(up);
    }
    if up == "BIT" {
        return Some("BOOL".into());
    }
    if up == "STRING" {
        return Some("STRING[82]".into());
    }
    if let Some((n, _)) = STRUCTS.iter().find(|(n, _)| *n == up) {
        types.used_structs.insert(n);
        return Some((*n).to_string());
    }
    if types.udts.contains(&up) && sfc_syntax::keywords::is_identifier(dt.trim()) {
        return Some(dt.trim().to_string());
    }
    None
}

/// `ARRAY [0..a-1, 0..b-1] OF ty` for Logix `Dimensions="a b"` (or `a,b`); `ty` when empty or 0.
pub(crate) fn with_dims(ty: &str, dims: Option<&str>) -> Option<String> {
    let d: Vec<u64> = dims
        .unwrap_or("")
        .split([' ', ','])
        .filter(|p| !p.trim().is_empty())
        .map(|p| p.trim().parse::<u64>().ok())
        .collect::<Option<Vec<_>>>()?;
    let d: Vec<u64> = d.into_iter().filter(|&n| n > 0).collect();
    if d.is_empty() {
        return Some(ty.to_string());
    }
    if d.len() > 3 || d.iter().any(|&n| n > 1_000_000) {
        return None;
    }
    let ranges: Vec<String> = d.iter().map(|n| format!("0..{}", n - 1)).collect();
    Some(format!("ARRAY [{}] OF {ty}", ranges.join(", ")))
}

/// A scalar value of the decorated data as an IEC literal of type `ty`.
fn literal(ty: &str, v: &str) -> Option<String> {
    let v = v.trim();
    if ty == "BOOL" {
        return match v {
            "0" => Some("FALSE".into()),
            "1" => Some("TRUE".into()),
            _ => None,
        };
    }
    if ty.starts_with("STRING") {
        return (v.len() >= 2 && v.starts_with('\'') && v.ends_with('\'')).then(|| v.to_string());
    }
    let real = matches!(ty, "REAL" | "LREAL");
    let ok = if real {
        v.parse::<f64>().is_ok_and(f64::is_finite)
    } else {
        let body = v.trim_start_matches('-');
        let (base, digits) = match body.split_once('#') {
            Some((b, d)) => (b.parse::<u32>().ok().filter(|b| [2, 8, 16].contains(b)), d),
            None => (Some(10), body),
        };
        base.is_some_and(|b| {
            let d: String = digits.chars().filter(|c| *c != '_').collect();
            !d.is_empty() && i128::from_str_radix(&d, b).is_ok() && !(v.starts_with('-') && b != 10)
        })
    };
    if !ok {
        return None;
    }
    if real && !v.contains(['.', 'e', 'E']) {
        return Some(format!("{v}.0"));
    }
    Some(v.to_string())
}

/// The initial value of a tag from its decorated data (`Ok(None)`: none given; `Err(())`: given
/// but not simple enough to write).
fn initial(types: &Types, base: &str, data: Node) -> Result<Option<String>, ()> {
    let Some(first) = elements(data).next() else { return Ok(None) };
    match first.tag_name().name() {
        "DataValue" => literal(base, attr(first, "Value").unwrap_or("")).map(Some).ok_or(()),
        "Structure" if base.starts_with("STRING") => {
            let d = children(first, "DataValueMember").find(|m| attr(*m, "Name") == Some("DATA")).ok_or(())?;
            literal(base, text_of(d).text.trim()).map(Some).ok_or(())
        }
        "Structure" => {
            let members = struct_members(types, base);
            let mut parts = Vec::new();
            for m in elements(first) {
                if m.tag_name().name() != "DataValueMember" {
                    return Err(());
                }
                let name = attr(m, "Name").unwrap_or("");
                let ty = members.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)).map(|(_, t)| t.clone()).ok_or(())?;
                let v = literal(&ty, attr(m, "Value").unwrap_or("")).ok_or(())?;
                parts.push(format!("{name} := {v}"));
            }
            Ok((!parts.is_empty()).then(|| format!("({})", parts.join(", "))))
        }
        "Array" => {
            let ty = attr(first, "DataType").unwrap_or("").to_ascii_uppercase();
            let ty = if ty == "BIT" { "BOOL".to_string() } else { ty };
            let mut parts = Vec::new();
            for e in children(first, "Element") {
                if parts.len() >= 10_000 {
                    return Err(());
                }
                parts.push(literal(&ty, attr(e, "Value").ok_or(())?).ok_or(())?);
            }
            Ok((!parts.is_empty()).then(|| format!("[{}]", parts.join(", "))))
        }
        _ => Err(()),
    }
}

/// The members of a structure type (predefined or user-defined, from `types`).
fn struct_members(types: &Types, base: &str) -> Vec<(String, String)> {
    let up = base.to_ascii_uppercase();
    if let Some((_, m)) = STRUCTS.iter().find(|(n, _)| *n == up) {
        return m.iter().map(|(a, b)| ((*a).to_string(), (*b).to_string())).collect();
    }
    types.members.get(&up).cloned().unwrap_or_default()
}

impl Types {
    /// Reads the `<DataTypes>` of the controller: user-defined structures (their names first, so
    /// members may name each other).
    pub(crate) fn read(cx: &mut Ctx, dts: Option<Node>) -> Vec<Udt> {
        let list: Vec<Node> = dts.into_iter().flat_map(|d| children(d, "DataType")).collect();
        for d in &list {
            if let Some(n) = attr(*d, "Name") {
                cx.types.udts.insert(n.trim().to_ascii_uppercase());
            }
        }
        let mut out = Vec::new();
        for d in list {
            let name = attr(d, "Name").unwrap_or("").trim().to_string();
            let at = attr_range(d, "Name").unwrap_or_else(|| anchor(d));
            if !sfc_syntax::keywords::is_identifier(&name) {
                cx.diag(
                    "SFC0722",
                    at,
                    format!("the data type `{name}` is not imported: its name is no IEC 61131-3 identifier"),
                );
                cx.types.udts.remove(&name.to_ascii_uppercase());
                continue;
            }
            let mut members = Vec::new();
            let mut broken = false;
            for m in child(d, "Members").into_iter().flat_map(|ms| children(ms, "Member")) {
                if attr(m, "Hidden") == Some("true") {
                    continue;
                }
                let mname = attr(m, "Name").unwrap_or("").trim();
                let mdt = attr(m, "DataType").unwrap_or("");
                let ty = iec_type(&mut cx.types, mdt).and_then(|t| with_dims(&t, attr(m, "Dimension")));
                match ty {
                    Some(t) if sfc_syntax::keywords::is_identifier(mname) => members.push((mname.to_string(), t)),
                    _ => {
                        cx.diag(
                            "SFC0722",
                            attr_range(m, "DataType").unwrap_or_else(|| anchor(m)),
                            format!("the member `{mname}` of `{name}` (type `{mdt}`) is not imported"),
                        )
                        .notes
                        .push("sfc declares Logix's elementary types, STRING, TIMER, COUNTER, CONTROL, arrays of them and the file's own structures".into());
                        broken = true;
                    }
                }
            }
            if members.is_empty() && broken {
                cx.types.udts.remove(&name.to_ascii_uppercase());
                continue;
            }
            cx.types.members.insert(name.to_ascii_uppercase(), members.clone());
            out.push((name, anchor(d), members));
        }
        out
    }
}

/// A user-defined structure: name, where, members (name, IEC type).
pub(crate) type Udt = (String, Range<u32>, Vec<(String, String)>);

/// What a `<Tag>` is.
pub(crate) enum TagKind {
    /// A variable to declare.
    Var(Var),
    /// A tag of the chart's own elements (SFC_STEP, SFC_ACTION, SFC_STOP): its data.
    Sfc { name: String, ty: String, pre: Option<i64>, l5k: Option<String>, desc: Option<String> },
    /// An alias: declared from its use.
    Alias { name: String, target: String, at: Range<u32> },
    /// Not declared (reported).
    Skipped { name: String },
}

/// Reads one `<Tag>`.
pub(crate) fn tag(cx: &mut Ctx, t: Node) -> TagKind {
    let name = attr(t, "Name").unwrap_or("").trim().to_string();
    let name_at = attr_range(t, "Name").unwrap_or_else(|| anchor(t));
    let dt = attr(t, "DataType").unwrap_or("");
    let l5k =
        children(t, "Data").find(|d| attr(*d, "Format") == Some("L5K")).map(|d| text_of(d).text.trim().to_string());
    if SFC_TYPES.iter().any(|s| s.eq_ignore_ascii_case(dt)) {
        let pre = decorated(t)
            .and_then(|d| elements(d).next())
            .into_iter()
            .flat_map(|s| children(s, "DataValueMember"))
            .find(|m| attr(*m, "Name") == Some("PRE"))
            .and_then(|m| attr(m, "Value"))
            .and_then(|v| v.trim().parse::<i64>().ok())
            .or_else(|| l5k_pre(l5k.as_deref()));
        return TagKind::Sfc { name, ty: dt.to_ascii_uppercase(), pre, l5k, desc: description(t) };
    }
    match attr(t, "TagType").unwrap_or("Base") {
        "Alias" => {
            return TagKind::Alias { name, target: attr(t, "AliasFor").unwrap_or("").to_string(), at: name_at };
        }
        "Base" => {}
        other => {
            let other = other.to_string();
            cx.diag(
                "SFC0722",
                attr_range(t, "TagType").unwrap_or_else(|| anchor(t)),
                format!("the {other} tag `{name}` is declared as a plain variable: sfc does not exchange tags between controllers"),
            );
        }
    }
    let logix_name = name.bytes().next().is_some_and(|c| c.is_ascii_alphabetic() || c == b'_')
        && name.bytes().all(|c| c.is_ascii_alphanumeric() || c == b'_');
    if !sfc_syntax::keywords::is_identifier(&name) && !logix_name {
        cx.diag("SFC0722", name_at, format!("the tag `{name}` is not imported: its name is no IEC 61131-3 identifier"));
        return TagKind::Skipped { name };
    }
    let name = if sfc_syntax::keywords::is_identifier(&name) {
        name
    } else {
        // A Logix name IEC reserves (`Constant`, `Step`) or spells otherwise (`A__B`): renamed,
        // and its uses in the chart alike.
        let fixed = sfc_syntax::keywords::sanitize_identifier(&name);
        let d = cx.diag("SFC0704", name_at.clone(), format!("`{name}` is not an IEC 61131-3 identifier; the tag is imported as `{fixed}`, and so are its uses in the chart"));
        d.severity = sfc_diagnostics::Severity::Warning;
        d.notes.push(
            "identifiers are letters, digits and single underscores, start with a letter, and are not keywords".into(),
        );
        cx.renamed.insert(name.to_ascii_uppercase(), fixed.clone());
        fixed
    };
    let Some(base) = iec_type(&mut cx.types, dt) else {
        cx.diag(
            "SFC0722",
            attr_range(t, "DataType").unwrap_or_else(|| anchor(t)),
            format!("the tag `{name}` of type `{dt}` is not imported"),
        )
        .notes
        .push("sfc declares Logix's elementary types, STRING, TIMER, COUNTER, CONTROL, arrays of them and the file's own structures; Add-On Instructions and module types are not imported".into());
        return TagKind::Skipped { name };
    };
    let Some(ty) = with_dims(&base, attr(t, "Dimensions")) else {
        cx.diag(
            "SFC0722",
            attr_range(t, "Dimensions").unwrap_or(name_at),
            format!("the dimensions of the tag `{name}` are not imported"),
        );
        return TagKind::Skipped { name };
    };
    let mut attrs = Vec::new();
    if let Some(text) = description(t) {
        attrs.push(("sfc.description".to_string(), text));
    }
    let init = match decorated(t) {
        Some(d) => match initial(&cx.types, &base, d) {
            Ok(v) => v,
            Err(()) => {
                cx.diag(
                    "SFC0722",
                    anchor(d),
                    format!("the initial value of `{name}` is not imported: it is not a simple literal"),
                );
                None
            }
        },
        None => {
            // A STRING's value is its own `Data Format="String"`; a scalar's, the L5K data.
            let string = children(t, "Data").find(|d| attr(*d, "Format") == Some("String"));
            let (data, at) = match string {
                Some(d) => (Some(text_of(d).text.trim().to_string()), anchor(d)),
                None => (l5k.clone(), anchor(t)),
            };
            let value = data.as_deref().filter(|v| !v.is_empty()).map(|v| literal(&base, v).filter(|_| base == ty));
            if value.as_ref().is_some_and(Option::is_none) {
                cx.diag(
                    "SFC0722",
                    at,
                    format!("the initial value of `{name}` is not imported: it is not a simple literal"),
                );
            }
            value.flatten()
        }
    };
    let usage = match attr(t, "Usage") {
        Some(u @ ("Input" | "Output" | "InOut")) => Some(u.to_string()),
        Some(other) => {
            attrs.push(("sfc.logix.usage".to_string(), other.to_string()));
            None
        }
        None => None,
    };
    TagKind::Var(Var { name, name_at, anchor: anchor(t), ty, init, attrs, usage })
}

fn decorated<'a, 'i>(t: Node<'a, 'i>) -> Option<Node<'a, 'i>> {
    children(t, "Data").find(|d| attr(*d, "Format") == Some("Decorated"))
}

/// The second value of an L5K structure `[status,PRE,…]`.
fn l5k_pre(l5k: Option<&str>) -> Option<i64> {
    let inner = l5k?.trim().strip_prefix('[')?.strip_suffix(']')?;
    inner.split(',').nth(1)?.trim().parse().ok()
}

/// The text of an element's `<Description>`, when it has one.
pub(crate) fn description(n: Node) -> Option<String> {
    let text = text_of(child(n, "Description")?).text.trim().to_string();
    (!text.is_empty()).then_some(text)
}
