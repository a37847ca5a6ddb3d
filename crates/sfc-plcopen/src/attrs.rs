//! The `sfc.*` attributes this crate reads and writes, and how their values are written.
//!
//! | attribute | on | holds |
//! |---|---|---|
//! | `sfc.x`, `sfc.y`, `sfc.w`, `sfc.h` | step, transition | position (top left) and size, PLCopen units |
//! | `sfc.description` | POU, variable, step, transition, action | the PLCopen `documentation` text |
//! | `sfc.adddata` | POU, variable, step, transition, action | foreign `addData` `<data>` elements, as XML |
//! | `sfc.actionblock` | step | `x y w h n` per action block (n = its number of associations), `;`-separated |
//! | `sfc.jump` | transition | `Target x y` per successor drawn as a jump, `;`-separated |
//! | `sfc.reference` | transition | the name of the `transitions` entry the condition came from |
//! | `sfc.inline` | action | `true`: written inline in its action block |
//! | `sfc.comment` | POU | one comment box of the SFC body: `x y w h` then a line break and the text |
//! | `sfc.loose` | POU | one transition not connected on both sides ([`Loose`]), which the chart cannot hold |
//!
//! Those are written in PLCopen's own elements where the element has them (a position, a
//! `documentation`, an inline action, a `reference` condition). Every other attribute (`sfc.tag`,
//! `sfc.timeout`, `sfc.final`, `sfc.target`, editor attributes, and any of the above that could
//! not be written natively) travels in the element's `addData` under [`DATA_NAME`] and comes
//! back from there on import. Attribute pragmas have no
//! escape syntax and end at a quote, so values that may hold any text are written with IEC
//! string escapes (`$$`, `$27` for a quote, `$N`, `$R`, `$T`) and read back with [`unescape`].

pub const X: &str = "sfc.x";
pub const Y: &str = "sfc.y";
pub const W: &str = "sfc.w";
pub const H: &str = "sfc.h";
pub const DESCRIPTION: &str = "sfc.description";
pub const ADDDATA: &str = "sfc.adddata";
pub const ACTIONBLOCK: &str = "sfc.actionblock";
pub const JUMP: &str = "sfc.jump";
pub const REFERENCE: &str = "sfc.reference";
pub const INLINE: &str = "sfc.inline";
pub const COMMENT: &str = "sfc.comment";
pub const GVL: &str = "sfc.gvl";
pub const VERBATIM: &str = "sfc.verbatim";
/// `codesys`: the POU's names follow CODESYS's rules (doubled or trailing underscores).
pub const DIALECT: &str = "sfc.dialect";
pub const POUXML: &str = "sfc.pouxml";
pub const FILEHEADER: &str = "sfc.fileheader";
pub const CONTENTHEADER: &str = "sfc.contentheader";
pub const PROJECTDATA: &str = "sfc.projectdata";

/// The `name` of the `addData/data` element that carries the other `sfc.*` attributes.
pub const DATA_NAME: &str = "urn:sfc-toolchain:attributes";
/// The namespace of its content.
pub const DATA_NS: &str = "urn:sfc-toolchain:attributes";

pub use sfc_syntax::attr_value::{escape, unescape, Loose, LOOSE};

/// A number as PLCopen writes it (`xsd:decimal`): integers without a fraction.
pub fn fmt_num(v: f64) -> String {
    if !v.is_finite() {
        return "0".into();
    }
    let r = (v * 1000.0).round() / 1000.0;
    if r.fract() == 0.0 && r.abs() < 1e15 {
        format!("{}", r as i64)
    } else {
        let s = format!("{r:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The value of the last attribute `name` (case-insensitive), unescaped.
pub fn get<'a>(attrs: &'a [sfc_syntax::ast::Attribute], name: &str) -> Option<&'a str> {
    attrs.iter().rev().find(|a| a.name.eq_ignore_ascii_case(name)).and_then(|a| a.value.as_deref())
}

/// Every value of attribute `name`, in order.
pub fn all<'a>(attrs: &'a [sfc_syntax::ast::Attribute], name: &'a str) -> impl Iterator<Item = &'a str> + 'a {
    attrs.iter().filter(move |a| a.name.eq_ignore_ascii_case(name)).filter_map(|a| a.value.as_deref())
}

/// A numeric attribute.
pub fn get_num(attrs: &[sfc_syntax::ast::Attribute], name: &str) -> Option<f64> {
    get(attrs, name).and_then(|v| v.trim().parse::<f64>().ok()).filter(|v| v.is_finite())
}

/// CODESYS's data name of an SFC element's properties (a step's step actions among them).
pub const CODESYS_SFC_ELEMENT: &str = "http://www.3s-software.com/plcopenxml/sfc/element";

/// The GUIDs of CODESYS's step actions in a step's `sfc/element` properties, with the word the
/// text writes each with.
pub const STEP_ACTION_GUIDS: [(&str, sfc_syntax::ast::StepActionKind); 3] = [
    ("a6b08bd8-b696-47e3-9cbf-7408b61c9ff8", sfc_syntax::ast::StepActionKind::Entry),
    ("700a583f-b4d4-43e4-8c14-629c7cd3bec8", sfc_syntax::ast::StepActionKind::Main),
    ("a2621e18-7de3-4ea6-ae6d-89e9e0b7befd", sfc_syntax::ast::StepActionKind::Exit),
];
