//! TIA Portal SimaticML → sfc text: the S7-GRAPH function blocks of an Openness export.
//!
//! One `SW.Blocks.FB` whose `ProgrammingLanguage` is GRAPH becomes one `FUNCTION_BLOCK` marked
//! `{attribute 'sfc.dialect' := 'graph'}`: its interface as VAR blocks (`interface.rs`), the
//! steps, transitions, branches and jumps of its sequences as IEC steps and transitions, the
//! actions as action associations (`chart.rs`), the LAD/FBD networks of transitions,
//! interlocks, supervisions and permanent instructions as ST (`flgnet.rs`), the DB operands the
//! networks use as a file-level `VAR_GLOBAL` (`operand.rs`). What IEC text cannot hold is kept
//! in `sfc.s7graph.*` attributes. Every element is read by its local name, so the GRAPH
//! namespaces v1 to v6 and GraphVersion 2.0 to 6.0 are read alike. `docs/dev/s7graph.md` holds
//! the research this is built on.

mod chart;
pub mod export;
mod flgnet;
mod interface;
mod operand;

use roxmltree::Node;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_xmlmap::xml::{anchor, child, children, elements};
use sfc_xmlmap::{Emitter, SourceMap};
use std::collections::{HashMap, HashSet};
use std::ops::Range;

/// The result of importing one SimaticML file.
#[derive(Debug, Clone, Default)]
pub struct Output {
    /// The generated sfc text.
    pub text: String,
    /// Where each part of `text` came from in the XML.
    pub map: SourceMap,
    /// Problems of the import, located in the XML.
    pub diagnostics: Vec<Diagnostic>,
}

/// Whether `root` is the document element of a SimaticML export (`<Document>` holding
/// `Engineering` or `DocumentInfo`, or a `SW.Blocks.*` element).
pub fn is_simaticml(root: roxmltree::Node) -> bool {
    root.tag_name().name() == "Document"
        && root.children().any(|c| {
            c.is_element() && matches!(c.tag_name().name(), "Engineering" | "DocumentInfo")
                || c.tag_name().name().starts_with("SW.Blocks.")
        })
}

/// Imports a SimaticML file (`xml`, diagnostics in file `file`). Never panics.
pub fn import(file: u32, xml: &str) -> Output {
    let doc = match sfc_xmlmap::parse(file, xml) {
        Ok(d) => d,
        Err(d) => return Output { diagnostics: vec![d], ..Output::default() },
    };
    let root = doc.root_element();
    let mut cx = Cx::new(file);
    let blocks: Vec<Node> = elements(root).filter(|n| n.tag_name().name().starts_with("SW.Blocks.")).collect();
    let graphs: Vec<Node> = blocks.iter().copied().filter(|b| is_graph_block(*b)).collect();
    if graphs.is_empty() {
        let held: Vec<String> = blocks.iter().map(|b| describe_block(*b)).collect();
        let what = if held.is_empty() { "no block".to_string() } else { held.join(", ") };
        cx.diag("SFC0740", anchor(root), format!("this TIA Portal export holds no S7-GRAPH block: it holds {what}"))
            .notes
            .push(
                "sfc reads the GRAPH function blocks of a SimaticML export (ProgrammingLanguage GRAPH); \
                 export the GRAPH FB from TIA Portal (Openness `Export`), or give sfc the chart in IEC 61131-3 text"
                    .into(),
            );
        return Output { diagnostics: cx.diags, ..Output::default() };
    }
    for b in blocks.iter().filter(|b| !is_graph_block(**b)) {
        cx.diag("SFC0740", anchor(*b), format!("{} is not an S7-GRAPH block and is not imported", describe_block(*b)));
    }
    let engineering = child(root, "Engineering").and_then(|e| e.attribute("version")).map(str::to_string);
    let mut em = Emitter::new(anchor(root));
    let mut pous = Vec::new();
    for b in graphs {
        cx.reset_pou();
        let pou = chart::block(&mut cx, b, engineering.as_deref());
        pous.push(pou);
    }
    // The file-level parts first: the globals the networks use, the types of STRUCT members.
    for t in std::mem::take(&mut cx.types) {
        em.frag(&t);
        em.str("\n");
    }
    operand::write_globals(&mut cx, &mut em);
    for (i, p) in pous.into_iter().enumerate() {
        if i > 0 {
            em.str("\n");
        }
        em.append(p);
    }
    let (text, map) = em.finish();
    Output { text, map, diagnostics: cx.diags }
}

/// Whether a `SW.Blocks.*` element is a GRAPH block.
fn is_graph_block(b: Node) -> bool {
    block_language(b).as_deref() == Some("GRAPH")
}

fn block_language(b: Node) -> Option<String> {
    let attrs = child(b, "AttributeList")?;
    child(attrs, "ProgrammingLanguage").and_then(|l| l.text()).map(|t| t.trim().to_string())
}

/// `the LAD FB "Motor"`, `the DB "Settings"`.
fn describe_block(b: Node) -> String {
    let kind = b.tag_name().name().trim_start_matches("SW.Blocks.");
    let name = child(b, "AttributeList").and_then(|a| child(a, "Name")).and_then(|n| n.text()).unwrap_or("");
    match block_language(b) {
        Some(l) if !l.is_empty() && l != "DB" => format!("the {l} {kind} \"{name}\""),
        _ => format!("the {kind} \"{name}\""),
    }
}

/// One global operand the networks use (`"DB".a.b`), declared at file level.
#[derive(Debug, Clone)]
pub(crate) struct Global {
    /// The IEC name it is declared as.
    pub name: String,
    /// Its type, inferred from its first use.
    pub ty: String,
    /// How the type was inferred.
    pub why: String,
    /// How TIA writes it (`"DB".a.b`).
    pub origin: String,
    /// Where it is first used.
    pub at: Range<u32>,
    /// A global constant (`Constant Name=…`): its value is not in the file.
    pub constant: bool,
}

/// The state of one import.
pub(crate) struct Cx {
    pub file: u32,
    pub diags: Vec<Diagnostic>,
    /// Globals by their TIA spelling.
    pub globals: Vec<Global>,
    pub global_index: HashMap<String, usize>,
    /// Upper-case names taken at file level (globals, types).
    pub file_names: HashSet<String>,
    /// Upper-case names taken in the POU being written.
    pub used: HashSet<String>,
    /// Step names (as GRAPH writes them) → their IEC names, in the POU being written.
    pub steps: HashMap<String, String>,
    /// Transition names → their IEC names.
    pub transitions: HashMap<String, String>,
    /// Transition IEC names (upper case) → their conditions as ST, for an interlock or a
    /// supervision that reads a transition's `TT` ("satisfied": its condition is TRUE).
    pub conditions: HashMap<String, String>,
    /// Interface member names → their IEC names.
    pub vars: HashMap<String, String>,
    /// The globals the POU being written uses (indices into `globals`).
    pub pou_globals: Vec<usize>,
    /// Variables used as Boolean actions in the POU being written.
    pub action_names: HashSet<String>,
    /// TYPE blocks of STRUCT members.
    pub types: Vec<sfc_xmlmap::Frag>,
}

impl Cx {
    fn new(file: u32) -> Cx {
        Cx {
            file,
            diags: Vec::new(),
            globals: Vec::new(),
            global_index: HashMap::new(),
            file_names: HashSet::new(),
            used: HashSet::new(),
            steps: HashMap::new(),
            transitions: HashMap::new(),
            conditions: HashMap::new(),
            vars: HashMap::new(),
            pou_globals: Vec::new(),
            action_names: HashSet::new(),
            types: Vec::new(),
        }
    }

    fn reset_pou(&mut self) {
        self.used.clear();
        self.steps.clear();
        self.transitions.clear();
        self.vars.clear();
        self.pou_globals.clear();
        self.action_names.clear();
    }

    pub fn diag(&mut self, code: &'static str, at: Range<u32>, msg: impl Into<String>) -> &mut Diagnostic {
        self.diags.push(Diagnostic::new(code, Span::new(self.file, at.start, at.end), msg));
        self.diags.last_mut().unwrap_or_else(|| unreachable!("a diagnostic was just pushed"))
    }

    /// `base`, or `base_1`, `base_2`, … : a name not yet used in the POU (nor at file level).
    pub fn fresh(&mut self, base: &str) -> String {
        let mut name = base.to_string();
        let mut k = 0;
        while self.used.contains(&name.to_ascii_uppercase()) || self.file_names.contains(&name.to_ascii_uppercase()) {
            k += 1;
            name = format!("{base}_{k}");
        }
        self.used.insert(name.to_ascii_uppercase());
        name
    }
}

/// The first `MultiLanguageText` (or `MultilingualTextItem/Text`) of a text element, trimmed.
pub(crate) fn first_text(n: Node) -> Option<String> {
    let t = n
        .descendants()
        .filter(|d| d.is_element() && matches!(d.tag_name().name(), "MultiLanguageText" | "Text"))
        .filter_map(|d| d.text())
        .map(str::trim)
        .find(|t| !t.is_empty())?;
    Some(t.to_string())
}

/// The texts of a multilingual element as `lang: text` lines (one language: just the text).
pub(crate) fn all_texts(n: Node) -> Option<String> {
    let items: Vec<(String, String)> = children(n, "MultiLanguageText")
        .filter_map(|m| {
            let t = m.text()?.trim();
            (!t.is_empty()).then(|| (m.attribute("Lang").unwrap_or("").to_string(), t.to_string()))
        })
        .collect();
    match items.as_slice() {
        [] => None,
        [(_, t)] => Some(t.clone()),
        _ => Some(items.iter().map(|(l, t)| format!("{l}: {t}")).collect::<Vec<_>>().join("\n")),
    }
}
