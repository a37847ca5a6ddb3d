//! The editor's document: one SFC POU as blocks with pins and the connections between them, the
//! way the SFC Editor draws it, and its conversion to and from textual SFC.
//!
//! CONTRACT (shared with `sfc-server` and `web/src/doc.ts`; the JSON form is camelCase):
//!
//! * Block kinds and their pins (inputs on the top edge, outputs on the bottom edge, numbered
//!   left to right from 0):
//!
//!   | kind | inputs | outputs |
//!   |---|---|---|
//!   | `step` | 1 | 1 |
//!   | `transition` | 1 | 1 |
//!   | `selectionDivergence`, `simultaneousDivergence` | 1 | `pins` (≥ 2) |
//!   | `selectionConvergence`, `simultaneousConvergence` | `pins` (≥ 2) | 1 |
//!   | `jump` | 1 | 0 |
//!   | `text`, `actionBlock` | 0 | 0 |
//!
//! * Pin positions are those of the canvas (`web/src/diagram/geometry.ts`): a single pin in
//!   the middle of its edge; the branch pins of a bar equidistant from 10 units after its left
//!   end to 10 units before its right end, each offset rounded to the grid of 10.
//! * A connection goes from an output pin to an input pin of another block; every pin holds at
//!   most one connection. Valid pairs: step → transition, step → selection divergence,
//!   step → simultaneous convergence, selection divergence → transition,
//!   selection divergence → simultaneous convergence, simultaneous convergence → transition,
//!   transition → step, transition → simultaneous divergence, transition → selection
//!   convergence, transition → jump, simultaneous divergence → step, simultaneous divergence →
//!   selection convergence, simultaneous divergence → jump, selection convergence → step.
//! * An action block belongs to the step whose element id is in `step`; its rows are the step's
//!   action associations, in order.
//! * Element ids are unique in a document and stable while it is edited; a document opened
//!   from text gets ids derived from declaration order (`step:NAME`, `transition:NAME` or
//!   `transition#K` for unnamed ones, `b1`, `b2`, … for the other blocks).
//!
//! Saving writes the POU as textual SFC with `sfc.*` attribute pragmas (see `docs/editor.md`);
//! opening that text again gives back an equal document (lossless round trip).
//!
//! Comments: those inside the declarations, a condition or an action body are part of that
//! text. Every other comment of the POU (between elements, inside a step's or transition's
//! header or association list, between the POU header and the declarations) belongs to the
//! element after it (`Element::comments`, `ActionDef::comments`), those after the last element
//! to `EditorDoc::trailing_comments`. A comment that ends the line of an element (after
//! `END_STEP`, say) belongs to that element. Saving writes an element's comments on their own
//! lines right before it.

use serde::{Deserialize, Serialize};

/// The whole chart of one SFC POU as the editor shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase")]
pub struct EditorDoc {
    /// The POU's name.
    pub pou: String,
    pub pou_kind: PouKind,
    /// The target device (`sfc.target` before the POU).
    pub target: ChartTarget,
    #[serde(default, skip_serializing_if = "String::is_empty")]
    #[cfg_attr(test, ts(as = "Option<String>", optional))]
    pub description: String,
    /// The POU's declarations (its `VAR … END_VAR` blocks) verbatim, as written between the POU
    /// header line and its first SFC element.
    #[serde(default)]
    pub declarations: String,
    /// The POU's body when it is not a chart (ST statements or IL instructions, dedented): a
    /// FUNCTION_BLOCK or PROGRAM written in ST or IL that holds actions written in SFC (added to
    /// the contract by sfc-doc). Such a document has no blocks; its actions' charts are edited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub body: Option<String>,
    #[serde(default, skip_serializing_if = "is_st")]
    #[cfg_attr(test, ts(as = "Option<Language>", optional))]
    pub body_language: Language,
    /// Named actions with their bodies, in declaration order.
    #[serde(default)]
    pub actions: Vec<ActionDef>,
    pub elements: Vec<Element>,
    pub connections: Vec<Connection>,
    /// Attribute pragmas before the POU that the editor does not edit (added to the contract by
    /// sfc-doc: kept so that saving does not drop them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<OtherAttribute>>", optional))]
    pub attributes: Vec<OtherAttribute>,
    /// The comments after the chart's last element, before `END_PROGRAM` / `END_FUNCTION_BLOCK`
    /// (each whole, delimiters included, in order).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<String>>", optional))]
    pub trailing_comments: Vec<String>,
}

/// An attribute pragma the editor does not edit, kept as read (`{attribute 'name' := 'value'}`,
/// the value as written between the quotes): foreign PLCopen `addData`, condition references,
/// inline actions, other tools' attributes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", default)]
pub struct OtherAttribute {
    pub name: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub value: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase")]
pub enum PouKind {
    Program,
    FunctionBlock,
}

/// `sfc.target`: what the chart is built for (seed 001: Blank, ATMT, EATMT).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase")]
pub enum ChartTarget {
    #[default]
    Blank,
    Atmt,
    Eatmt,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(test, derive(ts_rs::TS))]
pub enum Language {
    #[default]
    #[serde(rename = "ST")]
    St,
    #[serde(rename = "IL")]
    Il,
}

/// A named action: `ACTION name: … END_ACTION`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase")]
pub struct ActionDef {
    pub name: String,
    #[serde(default)]
    #[cfg_attr(test, ts(as = "Option<Language>", optional))]
    pub language: Language,
    /// The statements (ST) or instructions (IL), without the `ACTION`/`END_ACTION` lines.
    pub body: String,
    #[serde(default, skip_serializing_if = "String::is_empty")]
    #[cfg_attr(test, ts(as = "Option<String>", optional))]
    pub description: String,
    /// Attribute pragmas the editor does not edit (see [`OtherAttribute`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<OtherAttribute>>", optional))]
    pub attributes: Vec<OtherAttribute>,
    /// The comments written before the action in the text (each whole, delimiters included).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<String>>", optional))]
    pub comments: Vec<String>,
    /// An action written in SFC (CODESYS's SFC action): its chart as a document of its own
    /// (`pou` the POU's name, no declarations or actions of its own; its steps name the POU's
    /// actions). When present, saving writes the action's body from it (`body` is the text it
    /// wrote when opened); the attributes of the chart (its layout) travel in the chart.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(as = "Option<EditorDoc>", optional))]
    pub chart: Option<Box<EditorDoc>>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase")]
pub enum ElementKind {
    Step,
    Transition,
    SelectionDivergence,
    SelectionConvergence,
    SimultaneousDivergence,
    SimultaneousConvergence,
    Jump,
    Text,
    ActionBlock,
}

/// One block. Fields that do not apply to a kind stay at their defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", default)]
pub struct Element {
    pub id: String,
    #[cfg_attr(test, ts(type = "ElementKind"))]
    pub kind: Option<ElementKind>,
    /// Top-left corner and size, in canvas units (1 unit = 1 CSS pixel at zoom 1).
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
    /// Step or transition name (empty for an unnamed transition and for other blocks).
    #[serde(skip_serializing_if = "String::is_empty")]
    #[cfg_attr(test, ts(as = "Option<String>", optional))]
    pub name: String,
    /// Steps: the initial step.
    #[serde(skip_serializing_if = "is_false")]
    #[cfg_attr(test, ts(as = "Option<bool>", optional))]
    pub initial: bool,
    /// `sfc.tag`: state number of a step, condition index of a transition.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub tag: Option<u32>,
    /// `sfc.timeout` of a step, an IEC duration literal (`T#8.1s`).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub timeout: Option<String>,
    /// Shown as the tooltip.
    #[serde(skip_serializing_if = "String::is_empty")]
    #[cfg_attr(test, ts(as = "Option<String>", optional))]
    pub description: String,
    /// CSS colours (`#rrggbb`).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub background: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub foreground: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub line_width: Option<f64>,
    #[serde(skip_serializing_if = "is_false")]
    #[cfg_attr(test, ts(as = "Option<bool>", optional))]
    pub hide_label: bool,
    /// Steps: `sfc.final`, a step intentionally without a way out (added to the contract by
    /// sfc-doc so files using it keep it when saved from the editor).
    #[serde(rename = "final", skip_serializing_if = "is_false")]
    #[cfg_attr(test, ts(as = "Option<bool>", optional))]
    pub is_final: bool,
    /// Divergences and convergences: the number of branch pins (≥ 2).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub pins: Option<u32>,
    /// Jumps: the name of the target step.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub target: Option<String>,
    /// Transitions: the condition, an ST expression (language ST) or IL instructions (IL).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub condition: Option<String>,
    #[serde(skip_serializing_if = "is_st")]
    #[cfg_attr(test, ts(as = "Option<Language>", optional))]
    pub condition_language: Language,
    /// Transitions: explicit `PRIORITY`.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub priority: Option<u32>,
    /// Text labels: the text, its alignment (`left`, `center`, `right`) and CSS font.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub text: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional, type = "\"left\" | \"center\" | \"right\""))]
    pub align: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub font: Option<String>,
    /// Action blocks: the id of the step they belong to, and the associations.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub step: Option<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<Association>>", optional))]
    pub associations: Vec<Association>,
    /// Steps: CODESYS's step actions as written (`ENTRY_ACTION := Init_entry`,
    /// `STEP_ACTION := Motor.ACT_Run`, `EXIT_ACTION := …`), in order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<String>>", optional))]
    pub step_actions: Vec<String>,
    /// Steps and transitions: attribute pragmas the editor does not edit (see
    /// [`OtherAttribute`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<OtherAttribute>>", optional))]
    pub attributes: Vec<OtherAttribute>,
    /// Steps and transitions: the comments written before the element in the text (each whole,
    /// delimiters included, in order); on other blocks they travel in the layout attribute.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<String>>", optional))]
    pub comments: Vec<String>,
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn is_st(l: &Language) -> bool {
    *l == Language::St
}

/// One row of an action block: `qualifier[, duration] action` with optional indicator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", default)]
pub struct Association {
    /// `N`, `R`, `S`, `L`, `D`, `P`, `P0`, `P1`, `SD`, `DS`, `SL`.
    pub qualifier: String,
    /// A duration literal or a TIME variable, for the timed qualifiers.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub duration: Option<String>,
    /// The action name (or a BOOL variable).
    pub action: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub indicator: Option<String>,
}

/// A wire from an output pin to an input pin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", default)]
pub struct Connection {
    pub id: String,
    pub source: String,
    pub source_pin: u32,
    pub target: String,
    pub target_pin: u32,
    /// The whole orthogonal polyline, both ends included, absolute; empty: the editor routes it.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(test, ts(as = "Option<Vec<Point>>", optional))]
    pub waypoints: Vec<Point>,
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub color: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub line_width: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[cfg_attr(test, derive(ts_rs::TS))]
pub struct Point {
    pub x: f64,
    pub y: f64,
}

// ---- The API used by `sfc-server` (signatures are the contract; bodies are sfc-doc's) ----

use sfc_diagnostics::{Diagnostic, Severity, SourceFile};

pub mod drawing;
mod graph;
mod layout;
mod loose;
mod open;
mod pragma;
mod readback;
mod region;
pub mod route;
mod sidecar;
mod keep;
mod splice;
mod structured;
mod svg;

#[cfg(test)]
mod contracts;
mod write;

/// A file opened in the editor.
#[derive(Debug, Clone)]
pub struct Opened {
    /// One document per SFC POU, in file order.
    pub charts: Vec<EditorDoc>,
    /// The check's diagnostics, located in `file` (the IEC text given to [`open`]).
    pub diagnostics: Vec<Diagnostic>,
    pub file: SourceFile,
}

/// Opens IEC text (PLCopen XML is imported to text by the caller first): one document per SFC
/// POU. Blocks get the positions stored in the text; a chart without them is laid out.
///
/// Element ids are re-derived on every open (see [`normalize_ids`]): a document saved with
/// [`to_text`] and opened again equals `normalize_ids` of the saved document, and a document
/// that `open` returned is already normalised, so for it the round trip is exact equality.
pub fn open(file_id: u32, name: &str, text: &str) -> Opened {
    let checked = sfc_model::check_source(file_id, name, text, &sfc_model::CheckOptions::default());
    // The checker takes the elements of actions written in SFC out of its tree: their
    // associations as written come from a parse of their own.
    let parsed = (!checked.action_charts.is_empty()).then(|| sfc_syntax::parse(file_id, text).0);
    let parsed_action = |chart: &sfc_model::Chart| {
        parsed.as_ref()?.items.iter().find_map(|item| match item {
            sfc_syntax::ast::Item::Pou(p) => p.actions().find(|a| a.name.span == chart.name_span),
            _ => None,
        })
    };
    // The POUs with a chart: their body, or actions written in SFC (a POU in ST that holds
    // them opens too, its body as text), in file order.
    let mut items: Vec<usize> = checked.charts.iter().chain(&checked.action_charts).map(|c| c.item).collect();
    items.sort_unstable();
    items.dedup();
    let mut charts = Vec::new();
    for item in items {
        let Some(sfc_syntax::ast::Item::Pou(pou)) = checked.unit.items.get(item) else { continue };
        // A FUNCTION cannot hold a chart (SFC0218 says so); the editor has no document for it.
        if pou.kind == sfc_syntax::ast::PouKind::Function {
            continue;
        }
        let trivia = &checked.unit.trivia;
        let mut doc = match checked.charts.iter().find(|c| c.item == item) {
            Some(chart) => open::document(&open::read(text, chart, pou, trivia)),
            None => open::text_document(text, pou, trivia),
        };
        for chart in checked.action_charts.iter().filter(|c| c.item == item) {
            let (Some(name), Some(action)) = (&chart.action, parsed_action(chart)) else { continue };
            let Some(def) = doc.actions.iter_mut().find(|a| a.name.eq_ignore_ascii_case(name)) else { continue };
            let mut sub = open::action_document(text, chart, pou, action, trivia);
            sub.pou = doc.pou.clone();
            // The chart's attributes (its layout) are the chart's; the action keeps the rest.
            def.attributes.clear();
            def.chart = Some(Box::new(sub));
            // Its body is the one the chart writes, so a document `open` returned reads back
            // equal once saved.
            let mut probe = readback::Probe::for_attributes(&doc.attributes);
            def.body = write::flat_action(def, &doc.attributes, &mut probe).0.body;
        }
        charts.push(doc);
    }
    Opened { charts, diagnostics: checked.diagnostics, file: checked.file }
}

/// Something in a document that cannot be said in IEC text as drawn (a dangling pin, a
/// transition with no step before it, a jump to no step…), located on a block.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Problem {
    /// Stable code from the `SFC02xx` range (see `sfc_diagnostics::codes`), or SFC0101 for a
    /// name or text the IEC syntax does not accept.
    pub code: &'static str,
    pub severity: Severity,
    /// The id of the block or connection.
    pub element: String,
    pub message: String,
}

/// A document written as text.
#[derive(Debug, Clone)]
pub struct Written {
    /// The POU as textual SFC with `sfc.*` pragmas, from its attributes to `END_PROGRAM` /
    /// `END_FUNCTION_BLOCK` (with a final line break). Never lossy: what IEC text cannot hold
    /// (blocks not yet connected, bends, text labels) travels in pragmas.
    pub text: String,
    pub problems: Vec<Problem>,
}

/// Writes a document as the text of its POU.
pub fn to_text(doc: &EditorDoc) -> Written {
    write::write(doc)
}

/// `file_text` with the POU named `doc.pou` replaced by the document's text (appended at the
/// end when the file has no such POU); everything else in the file is kept byte for byte.
pub fn splice(file_text: &str, doc: &EditorDoc) -> String {
    splice_replacing(file_text, doc, &doc.pou)
}

/// [`splice`] for a POU renamed in the editor: the POU named `replacing` (the name it had when
/// opened) is replaced by the document, whose name may differ; appended when the file has no
/// such POU.
///
/// Only what changed is rewritten (`keep`): every element the document did not change keeps
/// its bytes (comments, spacing, no layout pragmas where the file had none); a moved block
/// changes its position lines only. Where that cannot be done so that the file reads back as
/// the document, the POU is replaced whole.
pub fn splice_replacing(file_text: &str, doc: &EditorDoc, replacing: &str) -> String {
    let written = to_text(doc).text;
    if let Some(kept) = keep::keep(file_text, replacing, &written) {
        return kept;
    }
    let kept: Vec<String> = doc.attributes.iter().map(|a| a.name.clone()).collect();
    splice::splice(file_text, replacing, &written, &kept)
}

/// `text` (IEC text, as `sfc fmt` prints it) with the editor's layout attributes of an older
/// save (`sfc.graph` on one line) written one element per line, as the editor writes them now.
pub fn split_layout(text: &str) -> String {
    sidecar::split_old(text)
}

/// Whether IEC text holds a POU named `name` (compared as IEC does, ignoring case).
pub fn holds_pou(file_text: &str, name: &str) -> bool {
    splice::holds_pou(file_text, name)
}

/// The document drawn as a standalone SVG file, as the canvas draws it (`sfc build --target
/// svg` and the editor's export agree).
pub fn svg(doc: &EditorDoc) -> String {
    svg::svg(doc)
}

/// Positions every block and routes every connection again (the structured layout of
/// `sfc-render`); names, properties and connectivity are kept.
pub fn auto_layout(doc: &EditorDoc) -> EditorDoc {
    open::auto_layout(doc)
}

/// The ids of the blocks a diagnostic's `element` (a step, transition or action name) designates:
/// the step or transition, or the action blocks that use the action.
pub fn element_ids(doc: &EditorDoc, element: &str) -> Vec<String> {
    graph::element_ids(doc, element, &mut readback::Probe::for_attributes(&doc.attributes))
}

/// A new chart (seed 001 "New…"): the POU `name` for `target` with one initial step `Init`.
pub fn blank(name: &str, target: ChartTarget) -> EditorDoc {
    let (w, h) = layout::step_size("Init");
    EditorDoc {
        pou: name.to_string(),
        pou_kind: PouKind::Program,
        target,
        description: String::new(),
        declarations: "VAR\nEND_VAR".to_string(),
        body: None,
        body_language: Language::St,
        actions: Vec::new(),
        elements: vec![Element {
            id: "step:Init".to_string(),
            kind: Some(ElementKind::Step),
            x: 100.0,
            y: 40.0,
            w,
            h,
            name: "Init".to_string(),
            initial: true,
            ..Element::default()
        }],
        connections: Vec::new(),
        attributes: Vec::new(),
        trailing_comments: Vec::new(),
    }
}

/// The document with the element ids [`open`] derives: `step:NAME` and `transition:NAME` (or
/// `transition#K`, K its 0-based index among the transitions of the text) for the steps and
/// transitions the text holds, `b1`, `b2`, … for every other block and `c1`, `c2`, … for the
/// connections, in document order. References follow; references to missing blocks become
/// `missing:ID`.
pub fn normalize_ids(doc: &EditorDoc) -> EditorDoc {
    let mut probe = readback::Probe::for_attributes(&doc.attributes);
    let d = graph::derive(doc, &mut probe);
    graph::normalize(doc, &d)
}

/// The problems [`to_text`] reports for a document, without writing it.
pub fn problems(doc: &EditorDoc) -> Vec<Problem> {
    graph::derive(doc, &mut readback::Probe::for_attributes(&doc.attributes)).problems
}
