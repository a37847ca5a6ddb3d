//! The `sfc.graph` attribute: everything of a document the IEC text cannot hold, as compact
//! JSON. Steps and transitions of the text are referred to by name (their properties are in
//! the text and their own attributes); every other block is stored whole; connections refer to
//! blocks by their position in the document.

use crate::pragma;
use crate::{ActionDef, Element, OtherAttribute, Point};
use serde::{Deserialize, Serialize};

/// The attribute's name.
pub const NAME: &str = "sfc.graph";
/// The format version of the assembled JSON (`v`).
pub const VERSION: u32 = 1;
/// `v` of the attribute as written since the layout is one element per line: the attribute
/// holds everything but the blocks and connections, each block is one `sfc.graph.e` attribute
/// and each connection one `sfc.graph.c` attribute, in document order, so moving or editing one
/// block changes one line of the file. An attribute with `v` 1 holds everything (read still).
pub const SPLIT: u32 = 2;
/// One block of a split layout.
pub const ENTRY: &str = "sfc.graph.e";
/// One connection of a split layout.
pub const WIRE: &str = "sfc.graph.c";

/// The layout's attribute lines: `sfc.graph` with `v` 2, then one line per block and per
/// connection.
pub fn write(car: &Sidecar) -> String {
    let mut head = serde_json::to_value(car).unwrap_or_default();
    if let Some(o) = head.as_object_mut() {
        o.remove("e");
        o.remove("c");
        o.insert("v".into(), SPLIT.into());
    }
    let mut out = pragma::line("", NAME, &pragma::escape(&head.to_string()));
    for e in &car.e {
        out.push_str(&pragma::line("", ENTRY, &pragma::escape(&serde_json::to_string(e).unwrap_or_default())));
    }
    for c in &car.c {
        out.push_str(&pragma::line("", WIRE, &pragma::escape(&serde_json::to_string(c).unwrap_or_default())));
    }
    out
}

/// `text` with every layout attribute of the older form (`sfc.graph` with `v` 1, everything on
/// one line) written in today's form, one line per block and connection, indented alike; a
/// line that does not read as a layout stays as it is.
pub fn split_old(text: &str) -> String {
    const HEAD: &str = "{attribute 'sfc.graph' := '";
    let mut out = String::with_capacity(text.len());
    for line in text.split_inclusive('\n') {
        let body = line.trim_end_matches(['\n', '\r']);
        let rest = body.trim_start();
        let indent = body.get(..body.len() - rest.len()).unwrap_or("");
        let car = rest
            .strip_prefix(HEAD)
            .and_then(|r| r.strip_suffix("'}"))
            .and_then(|v| serde_json::from_str::<Sidecar>(&pragma::unescape(v)).ok())
            .filter(|car| car.v == VERSION);
        let Some(car) = car else {
            out.push_str(line);
            continue;
        };
        let end = line.get(body.len()..).filter(|e| !e.is_empty()).unwrap_or("\n");
        for l in write(&car).lines() {
            out.push_str(indent);
            out.push_str(l);
            out.push_str(end);
        }
    }
    out
}

/// The layout of a POU's attributes as one JSON text (`v` 1), from either form; `None`
/// without one, or when a split line does not read (the chart is then laid out afresh).
pub fn read(attrs: &[sfc_syntax::ast::Attribute]) -> Option<String> {
    let raw = pragma::text(attrs, NAME)?;
    let mut head: serde_json::Value = match serde_json::from_str(&raw) {
        Ok(v) => v,
        Err(_) => return Some(raw),
    };
    if head.get("v").and_then(serde_json::Value::as_u64) != Some(u64::from(SPLIT)) {
        return Some(raw);
    }
    let list = |name: &str| -> Option<Vec<serde_json::Value>> {
        pragma::all(attrs, name).iter().map(|v| serde_json::from_str(v).ok()).collect()
    };
    let (e, c) = (list(ENTRY)?, list(WIRE)?);
    let o = head.as_object_mut()?;
    o.insert("v".into(), VERSION.into());
    o.insert("e".into(), e.into());
    o.insert("c".into(), c.into());
    Some(head.to_string())
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Sidecar {
    pub v: u32,
    /// The POU name as typed, when the text holds another one (it was no valid name).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pou: Option<String>,
    /// The declarations as typed, when they read back differently.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decl: Option<String>,
    /// The POU's other attributes as typed, when some cannot be written.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub attrs: Option<Vec<OtherAttribute>>,
    /// The actions, when any of them is not in the text as typed (absent: the text's actions).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub acts: Option<Vec<ActEntry>>,
    /// The comments after the last element as typed, when some cannot be written.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tc: Option<Vec<String>>,
    /// The blocks, in document order.
    pub e: Vec<Entry>,
    /// The connections, in document order.
    pub c: Vec<Wire>,
}

/// One block.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Entry {
    /// A step of the text, by name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub s: Option<String>,
    /// A transition of the text, by name (empty: unnamed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t: Option<String>,
    /// A step or transition as typed, when the text reads back differently (a condition that
    /// does not parse, say); used when the text still reads as this element would.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub o: Option<Element>,
    /// An action block whose associations are the next `n` associations of the step at block
    /// position `st` in the text (the element without id, step and associations).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub a: Option<Element>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n: Option<usize>,
    /// The action block's place and size are its step's `ab`-th `sfc.actionblock` entry (the
    /// element then has none of its own), so moving a step with its action blocks changes
    /// the step's lines only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ab: Option<usize>,
    /// Any other block, whole (without id; an action block's step as `st` or `sr`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x: Option<Element>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub st: Option<usize>,
    /// An action block's step that is no block of the document.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sr: Option<String>,
}

/// One action.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct ActEntry {
    /// An action of the text, by name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n: Option<String>,
    /// The action as typed, when the text reads back differently.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub o: Option<ActionDef>,
    /// An action the text cannot hold (no valid or a duplicate name).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x: Option<ActionDef>,
}

/// A block by its position in the document, or a reference to a block that is not there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum End {
    At(usize),
    Missing(String),
}

impl Default for End {
    fn default() -> Self {
        End::At(0)
    }
}

/// One connection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Wire {
    pub s: End,
    #[serde(skip_serializing_if = "is_zero")]
    pub sp: u32,
    pub t: End,
    #[serde(skip_serializing_if = "is_zero")]
    pub tp: u32,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub w: Vec<Point>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub col: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lw: Option<f64>,
}

fn is_zero(v: &u32) -> bool {
    *v == 0
}
