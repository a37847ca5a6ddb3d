//! Values of `sfc.*` attribute pragmas: IEC string escapes (a pragma value ends at a quote and
//! a pragma at `}`), numbers that read back exactly, and lookups on parsed attributes.
//!
//! `escape`/`unescape` are the same as `sfc-plcopen`'s `attrs` module (copied: sfc-doc does not
//! depend on the PLCopen crate), so either crate reads what the other writes.

use crate::OtherAttribute;
use sfc_syntax::ast::Attribute;

/// The attributes the editor reads into a step's fields (every other one is kept as read).
pub const STEP: &[&str] = &[
    "sfc.x",
    "sfc.y",
    "sfc.w",
    "sfc.h",
    "sfc.width",
    "sfc.height",
    "sfc.actionblock",
    "sfc.tag",
    "sfc.timeout",
    "sfc.final",
    "sfc.description",
    "sfc.background",
    "sfc.foreground",
    "sfc.linewidth",
    "sfc.hidelabel",
];
/// The attributes the editor reads into a transition's fields.
pub const TRANSITION: &[&str] = &[
    "sfc.x",
    "sfc.y",
    "sfc.w",
    "sfc.h",
    "sfc.width",
    "sfc.height",
    "sfc.jump",
    "sfc.tag",
    "sfc.description",
    "sfc.background",
    "sfc.foreground",
    "sfc.linewidth",
    "sfc.hidelabel",
];
/// The attributes the editor reads into an action's fields.
pub const ACTION: &[&str] = &["sfc.description"];
/// The attributes the editor reads into the document (before the POU).
pub const POU: &[&str] =
    &["sfc.target", "sfc.description", "sfc.comment", "sfc.graph", "sfc.graph.e", "sfc.graph.c", "sfc.loose"];

pub use sfc_syntax::attr_value::{escape, unescape};

/// A number written so that parsing it gives back the same `f64` (shortest round-trip form,
/// integers without a fraction).
pub fn num(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    format!("{v}")
}

/// The raw value of the last attribute `name` (case-insensitive); `Some("")` for a pragma
/// without a value.
pub fn raw<'a>(attrs: &'a [Attribute], name: &str) -> Option<&'a str> {
    attrs.iter().rev().find(|a| a.name.eq_ignore_ascii_case(name)).map(|a| a.value.as_deref().unwrap_or(""))
}

/// The unescaped text value of the last attribute `name`.
pub fn text(attrs: &[Attribute], name: &str) -> Option<String> {
    raw(attrs, name).map(unescape)
}

/// A finite number.
pub fn number(attrs: &[Attribute], name: &str) -> Option<f64> {
    raw(attrs, name).and_then(|v| v.trim().parse::<f64>().ok()).filter(|v| v.is_finite())
}

/// `'true'` (or no value at all) is true.
pub fn flag(attrs: &[Attribute], name: &str) -> bool {
    raw(attrs, name).is_some_and(|v| v.trim().is_empty() || v.trim().eq_ignore_ascii_case("true"))
}

/// Every value of attribute `name`, unescaped, in order.
pub fn all(attrs: &[Attribute], name: &str) -> Vec<String> {
    attrs
        .iter()
        .filter(|a| a.name.eq_ignore_ascii_case(name))
        .filter_map(|a| a.value.as_deref())
        .map(unescape)
        .collect()
}

/// One `{attribute 'name' := 'value'}` line (the value must already be escaped where needed).
pub fn line(indent: &str, name: &str, value: &str) -> String {
    format!("{indent}{{attribute '{name}' := '{value}'}}\n")
}

/// The attributes of a list that the editor does not read into fields, in order.
pub fn others(attrs: &[Attribute], known: &[&str]) -> Vec<OtherAttribute> {
    attrs
        .iter()
        .filter(|a| !known.iter().any(|k| a.name.eq_ignore_ascii_case(k)))
        .map(|a| OtherAttribute { name: a.name.clone(), value: a.value.clone() })
        .collect()
}

/// Whether an attribute can be written so that it reads back as [`others`] gives it: a name
/// and value without quotes or line breaks, and a name the editor does not read into a field.
fn writable(a: &OtherAttribute, known: &[&str]) -> bool {
    let bad = |s: &str| s.contains(['\'', '\n', '\r']);
    !a.name.is_empty()
        && !bad(&a.name)
        && !a.name.contains(['{', '}'])
        && a.name.trim() == a.name
        && !a.value.as_deref().is_some_and(bad)
        && !known.iter().any(|k| a.name.eq_ignore_ascii_case(k))
}

/// What a list of other attributes reads back as once written.
pub fn readable(list: &[OtherAttribute], known: &[&str]) -> Vec<OtherAttribute> {
    list.iter().filter(|a| writable(a, known)).cloned().collect()
}

/// The pragmas of the writable attributes of a list.
pub fn write_others(indent: &str, list: &[OtherAttribute], known: &[&str]) -> String {
    let mut out = String::new();
    for a in list.iter().filter(|a| writable(a, known)) {
        match &a.value {
            Some(v) => out.push_str(&line(indent, &a.name, v)),
            None => out.push_str(&format!("{indent}{{attribute '{}'}}\n", a.name)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_round_trip() {
        for v in ["", "plain", "it's", "a}b{c", "$1 $N", "two\nlines\r\tx", "ü €"] {
            let e = escape(v);
            assert!(!e.contains('\'') && !e.contains('}') && !e.contains('\n'), "{e}");
            assert_eq!(unescape(&e), v);
        }
    }

    #[test]
    fn numbers_read_back_exactly() {
        for v in [0.0, 1.0, -3.0, 0.1, 123.456789, 1e-7, 1e300, -0.0] {
            let s = num(v);
            assert_eq!(s.parse::<f64>().unwrap(), v, "{s}");
        }
        assert_eq!(num(120.0), "120");
    }
}
