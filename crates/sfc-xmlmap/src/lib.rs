//! What every importer of another tool's XML needs: located text read from the XML
//! ([`xml::XText`], element and attribute ranges) and the generated IEC text written together
//! with its [`emit::SourceMap`] back into the XML, so that every diagnostic of the generated text
//! is reported at the XML line and column of the element it concerns.
//!
//! Shared by `sfc-plcopen` (PLCopen TC6), `sfc-l5x` (Studio 5000 L5X) and `sfc-simaticml`
//! (TIA Portal SimaticML), which each write sfc text from their format.

pub mod emit;
pub mod names;
pub mod xml;

pub use emit::{Emitter, Frag, MapEntry, SourceMap};
pub use xml::XText;

/// Parses XML as the importers do (no DTD), or returns the located SFC0701 error.
pub fn parse(file: u32, src: &str) -> Result<roxmltree::Document<'_>, sfc_diagnostics::Diagnostic> {
    let opts = roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() };
    roxmltree::Document::parse_with_options(src, opts).map_err(|e| {
        let pos = e.pos();
        let at = xml::offset_of(src, pos.row, pos.col);
        let end = (at as usize + src.get(at as usize..).and_then(|r| r.chars().next()).map_or(0, char::len_utf8)) as u32;
        sfc_diagnostics::Diagnostic::new(
            "SFC0701",
            sfc_diagnostics::Span::new(file, at, end),
            format!("malformed XML: {e}"),
        )
    })
}
