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

/// One diagnostic located in `files`; `doc` is the chart it concerns, when known; `pou` the POU
/// of the file it lies in (the page scopes the Error list by it).
pub fn diag_json(d: &Diagnostic, files: &[SourceFile], doc: Option<&EditorDoc>, pou: Option<&str>) -> Value {
    let mut out = Map::new();
    if let Value::Object(m) = sfc_diagnostics::to_json_value(d, files) {
        for (k, v) in m {
            out.insert(camel(&k), v);
        }
    }
    out.insert("title".into(), json!(title(d.code)));
    let ids = match (doc, &d.element) {
        (Some(doc), Some(element)) => element_blocks(doc, element),
        _ => Vec::new(),
    };
    out.insert("elementIds".into(), json!(ids));
    if let (Some(doc), Some(Witness::Firing(names))) = (doc, &d.witness) {
        let fired: Vec<String> = names.iter().flat_map(|n| sfc_doc::element_ids(doc, n)).collect();
        out.insert("witnessIds".into(), json!(fired));
    }
    if let Some(pou) = pou {
        out.insert("pou".into(), json!(pou));
    }
    Value::Object(out)
}

/// The blocks of a chart element: a step or transition by name; for an action, the action
/// blocks whose rows name it.
fn element_blocks(doc: &EditorDoc, element: &str) -> Vec<String> {
    let ids = sfc_doc::element_ids(doc, element);
    if !ids.is_empty() {
        return ids;
    }
    doc.elements
        .iter()
        .filter(|e| e.kind == Some(sfc_doc::ElementKind::ActionBlock))
        .filter(|e| e.associations.iter().any(|a| a.action.eq_ignore_ascii_case(element)))
        .map(|e| e.id.clone())
        .collect()
}

/// A problem of a document (something it cannot say in IEC text): on its block, named after
/// it, and located in `text` (the document as written, in the file `file`): at the step's or
/// transition's declaration, or at the `sfc.graph` attribute that holds the drawing.
pub fn problem_json(p: &Problem, doc: &EditorDoc, file: &str, text: &str) -> Value {
    let block = doc.elements.iter().find(|e| e.id == p.element);
    let element = block.filter(|e| !e.name.is_empty()).map(|e| e.name.clone());
    let (line, column) = locate(text, block);
    json!({
        "code": p.code,
        "severity": p.severity.as_str(),
        "message": p.message,
        "title": title(p.code),
        "file": file,
        "line": line,
        "column": column,
        "endLine": line,
        "endColumn": column,
        "element": element,
        "elementIds": [p.element],
        "notes": [],
        "witness": null,
        "pou": doc.pou,
    })
}

/// Where a block is said in `text` (1-based line and column): a named step or transition at its
/// keyword, anything else (or a block the text does not hold) at the `sfc.graph` attribute; the
/// first line when neither is found.
fn locate(text: &str, block: Option<&sfc_doc::Element>) -> (usize, usize) {
    use sfc_doc::ElementKind;
    let named =
        block.filter(|e| !e.name.is_empty() && matches!(e.kind, Some(ElementKind::Step | ElementKind::Transition)));
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let column = line.len() - trimmed.len() + 1;
        let upper = trimmed.to_ascii_uppercase();
        if let Some(e) = named {
            let name = e.name.to_ascii_uppercase();
            let keyword = if e.kind == Some(ElementKind::Step) {
                upper.strip_prefix("INITIAL_STEP ").or_else(|| upper.strip_prefix("STEP "))
            } else {
                upper.strip_prefix("TRANSITION ")
            };
            if keyword.is_some_and(|rest| {
                rest.strip_prefix(&name).is_some_and(|r| r.is_empty() || r.starts_with([' ', ':', '(']))
            }) {
                return (i + 1, column);
            }
        }
    }
    // Not in the text (a block the text cannot hold yet, or an unnamed one): the drawing.
    text.lines()
        .enumerate()
        .find(|(_, l)| l.trim_start().starts_with("{attribute 'sfc.graph'"))
        .map_or((1, 1), |(i, l)| (i + 1, l.len() - l.trim_start().len() + 1))
}

/// The POUs of a file's text and the SFC elements in them, to find what a diagnostic located
/// in the text concerns.
#[derive(Debug, Default)]
pub struct PouSpans {
    /// `(span, name)` of every POU.
    pub pous: Vec<(Span, String)>,
    /// `(span, name)` of every step, transition and action of an SFC body, as the model names
    /// them (an unnamed transition `T<n>`, n its position among the POU's transitions).
    pub elements: Vec<(Span, String)>,
    /// Every POU as the project tree lists it (`PouEntry` of the contract).
    pub tree: Vec<Value>,
}

impl PouSpans {
    /// The name of the POU whose text holds `span`.
    pub fn pou_at(&self, span: Span) -> Option<&str> {
        self.pous.iter().find(|(s, _)| s.start <= span.start && span.start <= s.end).map(|(_, n)| n.as_str())
    }

    /// The chart element whose text holds `span`: the innermost step, transition or action.
    pub fn element_at(&self, span: Span) -> Option<&str> {
        self.elements
            .iter()
            .filter(|(s, _)| s.start <= span.start && span.end <= s.end.max(span.start))
            .min_by_key(|(s, _)| s.end - s.start)
            .map(|(_, n)| n.as_str())
    }
}

/// The POU each span of a file's text lies in, its SFC elements, and the project tree.
pub fn pou_spans(text: &str) -> PouSpans {
    use sfc_syntax::ast::{ActionBody, Body, Item, PouKind, SfcElement};
    let (unit, _) = sfc_syntax::parse(0, text);
    let mut out = PouSpans::default();
    for item in &unit.items {
        let Item::Pou(p) = item else { continue };
        out.pous.push((p.span, p.name.text.clone()));
        let mut k = 0;
        let mut transitions = Vec::new();
        for e in p.body.sfc().unwrap_or(&[]) {
            let name = match e {
                SfcElement::Step(s) => s.name.text.clone(),
                SfcElement::Transition(t) => {
                    k += 1;
                    let name = t.name.as_ref().map_or_else(|| format!("T{k}"), |n| n.text.clone());
                    transitions.push(name.clone());
                    name
                }
                SfcElement::Action(a) => a.name.text.clone(),
            };
            out.elements.push((e.span(), name));
        }
        let actions: Vec<Value> =
            p.actions().map(|a| json!({"name": a.name.text, "sfc": matches!(a.body, ActionBody::Sfc(_))})).collect();
        out.tree.push(json!({
            "name": p.name.text,
            "kind": match p.kind {
                PouKind::Program => "program",
                PouKind::FunctionBlock => "functionBlock",
                PouKind::Function => "function",
            },
            "language": match p.body {
                Body::Sfc(_) => "SFC",
                Body::St(_) => "ST",
                Body::Il(_) => "IL",
            },
            "chart": p.has_chart(),
            "actions": actions,
            "transitions": transitions,
        }));
    }
    out
}

/// The chart among `charts` that a diagnostic located in the text (`span`) concerns: the one
/// whose POU holds the span (none when that POU is not among them, e.g. a function), or the only
/// chart when the span lies in no POU or the diagnostic has none in the text.
pub fn chart_of<'a>(charts: &'a [EditorDoc], pous: &PouSpans, span: Option<Span>) -> Option<&'a EditorDoc> {
    let pou = span.and_then(|span| pous.pous.iter().find(|(s, _)| s.start <= span.start && span.start <= s.end));
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
        let v = diag_json(&d, &[f], None, None);
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
        assert_eq!(pous.pous.iter().map(|p| p.1.as_str()).collect::<Vec<_>>(), ["A", "B"]);
        assert!(pous.pous[1].0.start >= 22);
        let text =
            "PROGRAM A\nINITIAL_STEP S: END_STEP\nTRANSITION FROM S TO S := x AND ; END_TRANSITION\nEND_PROGRAM\n";
        let pous = pou_spans(text);
        let at = text.find(" ;").unwrap() as u32 + 1;
        assert_eq!(pous.element_at(Span::new(0, at, at + 1)), Some("T1"));
        let at = text.find("S:").unwrap() as u32;
        assert_eq!(pous.element_at(Span::new(0, at, at + 1)), Some("S"));
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
