//! Studio 5000 L5X → sfc text: the SFC routines of an L5X export (controller, program or
//! routine export) with the program's and controller's tags and data types.

use sfc_diagnostics::Diagnostic;
use sfc_xmlmap::SourceMap;

/// The result of importing one L5X file.
#[derive(Debug, Clone, Default)]
pub struct Output {
    /// The generated sfc text.
    pub text: String,
    /// Where each part of `text` came from in the XML.
    pub map: SourceMap,
    /// Problems of the import, located in the XML.
    pub diagnostics: Vec<Diagnostic>,
}

/// Whether `root` is the document element of an L5X export.
pub fn is_l5x(root: roxmltree::Node) -> bool {
    root.tag_name().name() == "RSLogix5000Content"
}

/// Imports an L5X file (`xml`, diagnostics in file `file`). Never panics.
pub fn import(file: u32, xml: &str) -> Output {
    let _ = (file, xml);
    Output::default()
}
