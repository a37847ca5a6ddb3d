//! PLCopen TC6 XML import and export.
//!
//! **Import** turns a PLCopen project (namespaces v2.01 `tc6_0201`, v2.0 `tc6_0200` and v1.0
//! `tc6.xsd`; files written by Beremiz, CODESYS, TwinCAT) into textual IEC 61131-3 in the
//! dialect the rest of the toolchain checks, plus a [`SourceMap`] from the generated text back
//! to the XML, so every diagnostic is reported at the XML line and column of the element it
//! concerns ([`check_xml`]). What IEC text has no syntax for is kept in `sfc.*` attribute pragmas
//! (layout, documentation, foreign `addData`, see [`attrs`]); FBD and LD networks (POU and action
//! bodies, wired transition conditions) are translated to ST; macro steps are flattened. What
//! cannot be represented is reported on its element (SFC07xx), never dropped silently.
//!
//! **Export** ([`export`]) writes a checked file as a PLCopen TC6 v2.01 project that validates
//! against the schema and that Beremiz opens: SFC bodies as graphical elements (positions from
//! the `sfc.x`/`sfc.y`/`sfc.w`/`sfc.h` attributes when every step and transition has them, else a
//! simple structured layout), ST and IL in `<xhtml:p><![CDATA[…]]></xhtml:p>` as Beremiz writes
//! them, and every other `sfc.*` attribute in `addData`, so that export then import gives the
//! same charts.

pub mod attrs;
pub(crate) use sfc_xmlmap::emit;
// Export writes a chart that has been checked, through tables it builds itself (elements by
// position, found through its own id maps); the workspace lints apply to it except unchecked
// indexing, about 120 places not yet rewritten with `get`. The import, which reads other
// tools' files, has no such exception.
#[allow(clippy::indexing_slicing)]
mod export;
mod import;
mod patch;
mod splice;
pub(crate) use sfc_xmlmap::xml;

pub use emit::{MapEntry, SourceMap};
pub use export::{export, export_pou, export_with, fmt_duration, SOURCE_DATA};
pub use import::NAMESPACES;
pub use patch::{patch_pou, Patched};
pub use splice::{splice_pou, SpliceError};

use sfc_diagnostics::{Diagnostic, Label, SourceFile};
use sfc_model::{check_source, CheckOptions, Checked};

/// The result of importing one XML file.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The XML file (diagnostics of the import are located in it).
    pub xml: SourceFile,
    /// The generated IEC 61131-3 text.
    pub text: String,
    /// Problems of the import itself, located in the XML.
    pub diagnostics: Vec<Diagnostic>,
    /// Where each part of `text` came from in the XML.
    pub map: SourceMap,
    /// The tool of the CODESYS family that wrote the file (its header or CODESYS's `addData`
    /// say so), `None` for any other (Beremiz, OpenPLC, sfc's own export of an IEC chart).
    pub vendor: Option<Vendor>,
}

/// A tool whose export sfc recognises ([`Imported::vendor`], [`vendor`]) and whose rules for
/// running SFC one of the simulator's profiles follows: the CODESYS family (CODESYS, TwinCAT,
/// e!COCKPIT: PLCopen XML, profile `codesys`), Studio 5000 (L5X, profile `logix`) and TIA
/// Portal (SimaticML S7-GRAPH blocks, profile `graph`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Vendor {
    /// CODESYS V3 (`productName="CODESYS"`, or only CODESYS's `addData`).
    Codesys,
    /// Beckhoff TwinCAT 3 (`TwinCAT PLC Control`, Beckhoff Automation).
    TwinCat,
    /// WAGO e!COCKPIT.
    ECockpit,
    /// Rockwell Studio 5000 Logix Designer (an L5X export, or text converted from one: its
    /// POUs are marked `{attribute 'sfc.dialect' := 'logix'}`).
    Studio5000,
    /// Siemens TIA Portal (a SimaticML export of an S7-GRAPH block, or text converted from one:
    /// its POUs are marked `{attribute 'sfc.dialect' := 'graph'}`).
    TiaPortal,
}

impl Vendor {
    /// The tool's name as its maker writes it.
    pub fn name(self) -> &'static str {
        match self {
            Vendor::Codesys => "CODESYS",
            Vendor::TwinCat => "TwinCAT",
            Vendor::ECockpit => "e!COCKPIT",
            Vendor::Studio5000 => "Studio 5000",
            Vendor::TiaPortal => "TIA Portal",
        }
    }

    /// Whether the tool is of the CODESYS family (it runs SFC by CODESYS's rules).
    pub fn is_codesys_family(self) -> bool {
        !matches!(self, Vendor::Studio5000 | Vendor::TiaPortal)
    }
}

impl std::fmt::Display for Vendor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The tool of the CODESYS family that wrote a PLCopen XML file, without importing it (`None`
/// for another tool's file, or text that is not a PLCopen project).
pub fn vendor(xml: &str) -> Option<Vendor> {
    let opts = roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(xml, opts).ok()?;
    let root = doc.root_element();
    (root.tag_name().name() == "project").then(|| import::vendor(root)).flatten()
}

/// The tool of the CODESYS family whose export an IEC text was converted from (`sfc build X.xml
/// --target text` keeps the export's `fileHeader` as `{attribute 'sfc.fileheader' := …}` and
/// marks its POUs `{attribute 'sfc.dialect' := 'codesys'}`), or of Studio 5000 for a text
/// converted from an L5X export (POUs marked `{attribute 'sfc.dialect' := 'logix'}`); `None` for
/// any other text.
pub fn text_vendor(text: &str) -> Option<Vendor> {
    if text.contains("{attribute 'sfc.dialect' := 'logix'}") {
        return Some(Vendor::Studio5000);
    }
    if text.contains("{attribute 'sfc.dialect' := 'graph'}") {
        return Some(Vendor::TiaPortal);
    }
    const KEY: &str = "{attribute 'sfc.fileheader' := '";
    if let Some(start) = text.find(KEY).map(|i| i + KEY.len()) {
        let rest = &text[start..];
        let end = rest.find("'}")?;
        let header = sfc_syntax::attr_value::unescape(&rest[..end]);
        return vendor(&format!("<project xmlns=\"http://www.plcopen.org/xml/tc6_0200\">{header}</project>"))
            .or_else(|| text.contains("{attribute 'sfc.dialect' := 'codesys'}").then_some(Vendor::Codesys));
    }
    text.contains("{attribute 'sfc.dialect' := 'codesys'}").then_some(Vendor::Codesys)
}

/// Imports a PLCopen XML file. `file_id` goes into the spans of the diagnostics (which point
/// into `xml`). Never panics: malformed XML gives one located SFC0701 error and empty text.
pub fn import(file_id: u32, name: &str, xml: &str) -> Imported {
    let (text, map, mut diagnostics, vendor) = import::run(file_id, xml);
    sfc_diagnostics::sort(&mut diagnostics);
    Imported { xml: SourceFile::new(name, xml), text, diagnostics, map, vendor }
}

/// Imports and checks a PLCopen XML file: returns the XML file, the check of the generated text,
/// and every diagnostic (the import's and the check's) located in the XML file `file_id`.
pub fn check_xml(file_id: u32, name: &str, xml: &str, opts: &CheckOptions) -> (SourceFile, Checked, Vec<Diagnostic>) {
    let imported = import(file_id, name, xml);
    let checked = check_source(file_id, &format!("{name} (imported)"), &imported.text, opts);
    let diags = with_check(&imported, &checked.diagnostics, file_id);
    (imported.xml, checked, diags)
}

/// The import's diagnostics with those of a check of the generated text (`checked`, in file
/// `file_id`), moved to the XML, sorted and without repeats.
pub fn with_check(imported: &Imported, checked: &[Diagnostic], file_id: u32) -> Vec<Diagnostic> {
    let mut diags = imported.diagnostics.clone();
    let import_failed = imported.diagnostics.iter().any(Diagnostic::is_error);
    for d in checked {
        // "Nothing to check" (SFC0106) is about the generated text: when the import failed, its
        // error says why; otherwise the project holds no POU, which is what is said.
        if d.code == "SFC0106" {
            if import_failed {
                continue;
            }
            let mut d = relocate(d, &imported.map, file_id);
            d.message = "nothing to check: the project holds no POU".to_string();
            diags.push(d);
            continue;
        }
        diags.push(relocate(d, &imported.map, file_id));
    }
    sfc_diagnostics::sort(&mut diags);
    diags.dedup();
    diags
}

/// A diagnostic of the generated text, moved to the XML through the source map.
pub fn relocate(d: &Diagnostic, map: &SourceMap, file_id: u32) -> Diagnostic {
    let mut out = d.clone();
    if d.span.file == file_id {
        out.span = map.span_to_xml(d.span, file_id);
    }
    out.labels = d
        .labels
        .iter()
        .map(|l| Label {
            span: if l.span.file == file_id { map.span_to_xml(l.span, file_id) } else { l.span },
            message: l.message.clone(),
        })
        .collect();
    out
}
