//! IEC 61131-3 names for what another tool's XML names freely (`Z-Achse MA05 Pos1`,
//! `compr. air release 1`): every importer repairs names the same way.

use sfc_syntax::keywords::cannot_name;

/// Whether `s` is an IEC identifier (letters, digits, single underscores, not a keyword).
pub fn is_ident(s: &str) -> bool {
    let b = s.as_bytes();
    !b.is_empty()
        && b.first().is_some_and(|c| c.is_ascii_alphabetic() || *c == b'_')
        && b.iter().all(|c| c.is_ascii_alphanumeric() || *c == b'_')
        && !s.contains("__")
        && !s.ends_with('_')
        && !cannot_name(s)
}

/// A usable identifier made from `s` (invalid characters become `_`).
pub fn sanitize(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        let c = if c.is_ascii_alphanumeric() { c } else { '_' };
        if c == '_' && (out.is_empty() || out.ends_with('_')) {
            continue;
        }
        out.push(c);
    }
    while out.ends_with('_') {
        out.pop();
    }
    if out.is_empty() {
        // Nothing usable (`""`, `"_"`, `"()"`): `X`, not `X_`, which is no identifier.
        return "X".to_string();
    }
    if out.as_bytes().first().is_some_and(u8::is_ascii_digit) || cannot_name(&out) {
        out.insert_str(0, "X_");
    }
    out
}

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
