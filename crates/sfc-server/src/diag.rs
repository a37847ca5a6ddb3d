//! Diagnostics as the editor receives them (`Diag` in `web/src/api.ts`): the JSON of
//! `sfc check --format json` with camelCase keys, plus the code's title, the ids of the blocks
//! concerned and, for a firing-sequence witness, the ids of the transitions fired.

use serde_json::{json, Map, Value};
use sfc_diagnostics::{Diagnostic, SourceFile, Span, Witness};
use sfc_doc::{EditorDoc, Problem};

/// The title of a code from the registry (empty for a code it does not know).
fn title(code: &str) -> &'static str {
    sfc_diagnostics::explain(code).map_or("", |i| i.title)
}

/// `end_line` → `endLine`.
fn camel(key: &str) -> String {
    let mut out = String::with_capacity(key.len());
    let mut upper = false;
    for c in key.chars() {
        if c == '_' {
            upper = true;
        } else if upper {
            out.extend(c.to_uppercase());
            upper = false;
        } else {
            out.push(c);
        }
    }
    out
}

/// One diagnostic located in `files`; `doc` is the chart it concerns, when known.
pub fn diag_json(d: &Diagnostic, files: &[SourceFile], doc: Option<&EditorDoc>) -> Value {
    let mut out = Map::new();
    if let Value::Object(m) = sfc_diagnostics::to_json_value(d, files) {
        for (k, v) in m {
            out.insert(camel(&k), v);
        }
    }
    out.insert("title".into(), json!(title(d.code)));
    let ids = match (doc, &d.element) {
        (Some(doc), Some(element)) => sfc_doc::element_ids(doc, element),
        _ => Vec::new(),
    };
    out.insert("elementIds".into(), json!(ids));
    if let (Some(doc), Some(Witness::Firing(names))) = (doc, &d.witness) {
        let fired: Vec<String> = names.iter().flat_map(|n| sfc_doc::element_ids(doc, n)).collect();
        out.insert("witnessIds".into(), json!(fired));
    }
    Value::Object(out)
}

/// A problem of a document (something it cannot say in IEC text), located on its block.
pub fn problem_json(p: &Problem) -> Value {
    json!({
        "code": p.code,
        "severity": p.severity.as_str(),
        "message": p.message,
        "title": title(p.code),
        "file": "",
        "line": 1,
        "column": 1,
        "endLine": 1,
        "endColumn": 1,
        "element": null,
        "elementIds": [p.element],
        "notes": [],
        "witness": null,
    })
}

/// The POU each span of a file's text lies in: `(span, name)` for every POU of the text.
pub fn pou_spans(text: &str) -> Vec<(Span, String)> {
    let (unit, _) = sfc_syntax::parse(0, text);
    unit.items
        .iter()
        .filter_map(|item| match item {
            sfc_syntax::ast::Item::Pou(p) => Some((p.span, p.name.text.clone())),
            _ => None,
        })
        .collect()
}

/// The chart among `charts` that a diagnostic located in the text (`span`) concerns: the one
/// whose POU holds the span (none when that POU is not among them, e.g. a function), or the only
/// chart when the span lies in no POU or the diagnostic has none in the text.
pub fn chart_of<'a>(charts: &'a [EditorDoc], pous: &[(Span, String)], span: Option<Span>) -> Option<&'a EditorDoc> {
    let pou = span.and_then(|span| pous.iter().find(|(s, _)| s.start <= span.start && span.start <= s.end));
    match (pou, charts) {
        (Some((_, name)), _) => charts.iter().find(|c| c.pou.eq_ignore_ascii_case(name)),
        (None, [only]) => Some(only),
        (None, _) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_camel_case_with_title() {
        let f = SourceFile::new("a.st", "PROGRAM P\nEND_PROGRAM\n");
        let d = Diagnostic::new("SFC0101", Span::new(0, 10, 21), "syntax error here").with_note("a note");
        let v = diag_json(&d, &[f], None);
        assert_eq!(v["endLine"], 2);
        assert_eq!(v["endColumn"], 12);
        assert_eq!(v["line"], 2);
        assert!(v.get("end_line").is_none());
        assert_eq!(v["title"], "syntax error");
        assert_eq!(v["elementIds"], json!([]));
        assert_eq!(v["notes"], json!(["a note"]));
        assert!(v.get("witnessIds").is_none());
    }

    #[test]
    fn pou_of_a_span() {
        let text = "PROGRAM A\nEND_PROGRAM\nPROGRAM B\nEND_PROGRAM\n";
        let pous = pou_spans(text);
        assert_eq!(pous.iter().map(|p| p.1.as_str()).collect::<Vec<_>>(), ["A", "B"]);
        assert!(pous[1].0.start >= 22);
    }

    #[test]
    fn chart_of_a_diagnostic() {
        let doc = |pou: &str| -> EditorDoc {
            serde_json::from_value(json!({
                "pou": pou, "pouKind": "program", "target": "blank", "elements": [], "connections": []
            }))
            .unwrap()
        };
        let text = "PROGRAM A\nEND_PROGRAM\nFUNCTION F : INT\nEND_FUNCTION\nPROGRAM B\nEND_PROGRAM\n";
        let pous = pou_spans(text);
        let at = |needle: &str| {
            let i = text.find(needle).unwrap() as u32;
            Some(Span::new(0, i, i + 1))
        };
        let two = [doc("A"), doc("B")];
        assert_eq!(chart_of(&two, &pous, at("PROGRAM B")).map(|d| d.pou.as_str()), Some("B"));
        assert_eq!(chart_of(&two, &pous, at("PROGRAM A")).map(|d| d.pou.as_str()), Some("A"));
        assert!(chart_of(&two, &pous, at("FUNCTION")).is_none());
        assert!(chart_of(&two, &pous, None).is_none());
        let one = [doc("B")];
        assert!(chart_of(&one, &pous, at("FUNCTION")).is_none(), "not the only chart's");
        assert_eq!(chart_of(&one, &pous, None).map(|d| d.pou.as_str()), Some("B"));
    }
}
