//! Putting a saved POU back into its file: the POU (with the attribute pragmas before it) is
//! replaced, everything else is kept byte for byte.

use sfc_syntax::ast::Item;

/// See [`crate::holds_pou`].
pub fn holds_pou(file_text: &str, name: &str) -> bool {
    if file_text.trim().is_empty() {
        return false;
    }
    let (unit, _) = sfc_syntax::parse(0, file_text);
    unit.items.iter().any(|item| matches!(item, Item::Pou(p) if p.name.text.eq_ignore_ascii_case(name)))
}

/// See [`crate::splice_replacing`]. `kept`: the names of the attributes the POU's new text holds.
pub fn splice(file_text: &str, pou: &str, pou_text: &str, kept: &[String]) -> String {
    if file_text.trim().is_empty() {
        return pou_text.to_string();
    }
    let (unit, _) = sfc_syntax::parse(0, file_text);
    let found = unit.items.iter().find_map(|item| match item {
        Item::Pou(p) if p.name.text.eq_ignore_ascii_case(pou) => Some(p),
        _ => None,
    });
    let Some(p) = found else {
        let mut out = file_text.to_string();
        if !out.ends_with('\n') {
            out.push('\n');
        }
        out.push('\n');
        out.push_str(pou_text);
        return out;
    };
    let mut start = p.attributes.iter().map(|a| a.span.start).chain([p.span.start]).min().unwrap_or(0) as usize;
    let end = (p.span.end as usize).min(file_text.len());
    start = start.min(end);
    // From the start of the line when only white space precedes the POU on it.
    let line = file_text[..start].rfind('\n').map(|i| i + 1).unwrap_or(0);
    if file_text[line..start].chars().all(|c| c == ' ' || c == '\t') {
        start = line;
    }
    // Attribute pragmas of other tools stay with the POU (unless the document holds them).
    let foreign: String = p
        .attributes
        .iter()
        .filter(|a| !a.name.to_ascii_lowercase().starts_with("sfc."))
        .filter(|a| !kept.iter().any(|k| k.eq_ignore_ascii_case(&a.name)))
        .filter_map(|a| file_text.get(a.span.start as usize..a.span.end as usize))
        .map(|t| format!("{t}\n"))
        .collect();
    let body = pou_text.strip_suffix('\n').unwrap_or(pou_text);
    let mut out = String::with_capacity(file_text.len() + pou_text.len());
    out.push_str(&file_text[..start]);
    out.push_str(&foreign);
    out.push_str(body);
    out.push_str(&file_text[end..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const POU: &str = "PROGRAM B\n    INITIAL_STEP S: END_STEP\nEND_PROGRAM\n";

    #[test]
    fn replaces_the_pou_and_its_attributes_only() {
        let file = "(* head *)\nPROGRAM A\n    INITIAL_STEP X: END_STEP\nEND_PROGRAM\n\n{attribute 'sfc.target' := 'atmt'}\n{attribute 'other' := '1'}\nprogram b\n    INITIAL_STEP Old: END_STEP\nEND_PROGRAM\n(* tail *)\n";
        let out = splice(file, "B", POU, &[]);
        assert_eq!(
            out,
            "(* head *)\nPROGRAM A\n    INITIAL_STEP X: END_STEP\nEND_PROGRAM\n\n{attribute 'other' := '1'}\nPROGRAM B\n    INITIAL_STEP S: END_STEP\nEND_PROGRAM\n(* tail *)\n"
        );
    }

    #[test]
    fn replaces_a_renamed_pou_by_its_old_name() {
        let file = "PROGRAM A\n    INITIAL_STEP X: END_STEP\nEND_PROGRAM\n\nPROGRAM Old\n    INITIAL_STEP O: END_STEP\nEND_PROGRAM\n";
        let out = splice(file, "old", POU, &[]);
        assert_eq!(out, "PROGRAM A\n    INITIAL_STEP X: END_STEP\nEND_PROGRAM\n\nPROGRAM B\n    INITIAL_STEP S: END_STEP\nEND_PROGRAM\n");
        assert!(holds_pou(file, "OLD"));
        assert!(!holds_pou(file, "B"));
        assert!(!holds_pou("", "B"));
    }

    #[test]
    fn appends_when_missing_and_fills_an_empty_file() {
        assert_eq!(splice("", "B", POU, &[]), POU);
        assert_eq!(splice("  \n", "B", POU, &[]), POU);
        assert_eq!(splice("TYPE T : INT; END_TYPE", "B", POU, &[]), format!("TYPE T : INT; END_TYPE\n\n{POU}"));
    }
}
