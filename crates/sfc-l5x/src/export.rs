//! A checked chart file → an L5X file (a controller export) holding each chart as an SFC routine.

use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::Checked;

/// Writes the charts of `checked` (only `pou` when given) as an L5X file (a controller export) holding each chart as an SFC routine; the notes say what changed
/// on the way, the error what the format cannot express (located in the checked text).
pub fn export(checked: &Checked, pou: Option<&str>) -> Result<(String, Vec<Diagnostic>), Vec<Diagnostic>> {
    let _ = pou;
    let at = checked.charts.first().map_or(Span::new(0, 0, 0), |c| c.name_span);
    Err(vec![Diagnostic::error("SFC0820", at, "the L5X export is not written yet")])
}
