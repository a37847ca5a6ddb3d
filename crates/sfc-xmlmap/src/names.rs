//! IEC 61131-3 names for what another tool's XML names freely (`Z-Achse MA05 Pos1`,
//! `compr. air release 1`): every importer repairs names the same way.

pub use sfc_syntax::keywords::{is_identifier as is_ident, sanitize_identifier as sanitize};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repaired_names_are_identifiers() {
        for raw in ["", "_", "()", "Z-Achse MA05 Pos1", "1st step", "STEP", "a__b_", "Größe"] {
            let s = sanitize(raw);
            assert!(is_ident(&s), "{raw:?} gave {s:?}");
        }
        assert_eq!(sanitize("Z-Achse MA05 Pos1"), "Z_Achse_MA05_Pos1");
    }
}
