//! SARIF 2.1.0 (OASIS Static Analysis Results Interchange Format), what GitHub code scanning,
//! GitLab and IDEs read: one run of `sfc`, the registry of codes as rules, one result per
//! diagnostic. Columns are Unicode code points (`columnKind`), as everywhere in sfc.

use crate::{Diagnostic, Severity, SourceFile, Witness, CODES};
use serde_json::{json, Map, Value};

/// The tool as SARIF names it.
#[derive(Debug, Clone)]
pub struct SarifTool<'a> {
    pub name: &'a str,
    /// `0.1.0 (abc1234 2026-11-27)`.
    pub version: &'a str,
    /// The semantic version alone (`0.1.0`).
    pub semantic_version: &'a str,
    /// The project's home page, when it has one.
    pub information_uri: Option<&'a str>,
}

/// A problem of the run itself (a file that could not be read), for
/// `invocations[0].toolExecutionNotifications`.
#[derive(Debug, Clone)]
pub struct SarifNotification {
    pub message: String,
    /// The file it concerns, if any.
    pub file: Option<String>,
}

fn level(s: Severity) -> &'static str {
    match s {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Note => "note",
    }
}

/// A file name as a SARIF URI reference: relative paths stay relative (resolved against
/// `%SRCROOT%`, the directory sfc ran in), absolute ones become `file://` URIs; characters
/// outside RFC 3986's unreserved set and `/` are percent-encoded.
pub fn sarif_uri(name: &str) -> (String, bool) {
    let path = name.replace('\\', "/");
    let absolute = path.starts_with('/');
    let mut out = String::with_capacity(path.len() + 8);
    if absolute {
        out.push_str("file://");
    }
    for b in path.bytes() {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' | b'/' => out.push(char::from(b)),
            _ => out.push_str(&format!("%{b:02X}")),
        }
    }
    (out, !absolute)
}

/// Adds `key: value` to a JSON object (a no-op on anything else).
fn set(v: &mut Value, key: &str, value: Value) {
    if let Some(obj) = v.as_object_mut() {
        obj.insert(key.to_string(), value);
    }
}

fn location(uri: &str, relative: bool) -> Value {
    let mut loc = json!({ "uri": uri });
    if relative {
        set(&mut loc, "uriBaseId", json!("%SRCROOT%"));
    }
    loc
}

fn region(file: &SourceFile, span: crate::Span) -> Value {
    let start = file.line_col(span.start);
    let end = file.line_col(span.end);
    // SARIF's endColumn is exclusive, like ours; an empty span still marks one column.
    let end_column = if end.line == start.line && end.column <= start.column { start.column + 1 } else { end.column };
    json!({ "startLine": start.line, "startColumn": start.column, "endLine": end.line, "endColumn": end_column })
}

/// The SARIF log of one `sfc check` run. `cwd_uri` is the `file://` URI of the directory the
/// relative file names are relative to (ends with `/`).
pub fn render_sarif(
    diags: &[Diagnostic],
    files: &[SourceFile],
    tool: &SarifTool<'_>,
    cwd_uri: &str,
    notifications: &[SarifNotification],
) -> String {
    let rules: Vec<Value> = CODES
        .iter()
        .map(|c| {
            json!({
                "id": c.code,
                "name": rule_name(c.title),
                "shortDescription": { "text": c.title },
                "fullDescription": { "text": c.explanation },
                "help": { "text": c.explanation },
                "defaultConfiguration": { "level": level(c.severity) },
                "properties": { "tags": [category(c.code)] },
            })
        })
        .collect();
    let mut artifacts: Vec<String> = Vec::new();
    let mut artifact_index = |name: &str| -> usize {
        match artifacts.iter().position(|a| a == name) {
            Some(i) => i,
            None => {
                artifacts.push(name.to_string());
                artifacts.len() - 1
            }
        }
    };
    let mut results = Vec::new();
    for d in diags {
        let mut result = Map::new();
        result.insert("ruleId".into(), json!(d.code));
        if let Some(i) = CODES.iter().position(|c| c.code == d.code) {
            result.insert("ruleIndex".into(), json!(i));
        }
        result.insert("level".into(), json!(level(d.severity)));
        let mut text = d.message.clone();
        for n in &d.notes {
            text.push_str(&format!("\n{n}"));
        }
        result.insert("message".into(), json!({ "text": text }));
        if let Some(file) = files.get(d.span.file as usize) {
            let (uri, relative) = sarif_uri(&file.name);
            let mut artifact = location(&uri, relative);
            set(&mut artifact, "index", json!(artifact_index(&file.name)));
            let mut loc =
                json!({ "physicalLocation": { "artifactLocation": artifact, "region": region(file, d.span) } });
            if let Some(e) = &d.element {
                set(&mut loc, "logicalLocations", json!([{ "name": e, "kind": "element" }]));
            }
            result.insert("locations".into(), json!([loc]));
            let related: Vec<Value> = d
                .labels
                .iter()
                .enumerate()
                .filter_map(|(i, l)| {
                    let lf = files.get(l.span.file as usize)?;
                    let (uri, relative) = sarif_uri(&lf.name);
                    Some(json!({
                        "id": i,
                        "physicalLocation": { "artifactLocation": location(&uri, relative), "region": region(lf, l.span) },
                        "message": { "text": l.message },
                    }))
                })
                .collect();
            if !related.is_empty() {
                result.insert("relatedLocations".into(), json!(related));
            }
        }
        let mut props = Map::new();
        props.insert("severity".into(), json!(d.severity.as_str()));
        if !d.notes.is_empty() {
            props.insert("notes".into(), json!(d.notes));
        }
        match &d.witness {
            Some(Witness::Firing(ts)) => {
                props.insert("witness".into(), json!(ts));
            }
            Some(Witness::Valuation(vs)) => {
                let obj: Map<String, Value> = vs.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
                props.insert("witness".into(), Value::Object(obj));
            }
            None => {}
        }
        result.insert("properties".into(), Value::Object(props));
        results.push(Value::Object(result));
    }
    let artifacts: Vec<Value> = artifacts
        .iter()
        .map(|name| {
            let (uri, relative) = sarif_uri(name);
            json!({ "location": location(&uri, relative) })
        })
        .collect();
    let notifications: Vec<Value> = notifications
        .iter()
        .map(|n| {
            let mut v = json!({ "level": "error", "message": { "text": n.message } });
            if let Some(f) = &n.file {
                let (uri, relative) = sarif_uri(f);
                set(
                    &mut v,
                    "locations",
                    json!([{ "physicalLocation": { "artifactLocation": location(&uri, relative) } }]),
                );
            }
            v
        })
        .collect();
    let mut driver = json!({
        "name": tool.name,
        "version": tool.version,
        "semanticVersion": tool.semantic_version,
        "rules": rules,
    });
    if let Some(uri) = tool.information_uri {
        set(&mut driver, "informationUri", json!(uri));
    }
    let log = json!({
        "$schema": "https://docs.oasis-open.org/sarif/sarif/v2.1.0/os/schemas/sarif-schema-2.1.0.json",
        "version": "2.1.0",
        "runs": [{
            "tool": { "driver": driver },
            "invocations": [{
                "executionSuccessful": notifications.is_empty(),
                "toolExecutionNotifications": notifications,
            }],
            "originalUriBaseIds": { "%SRCROOT%": { "uri": cwd_uri } },
            "artifacts": artifacts,
            "columnKind": "unicodeCodePoints",
            "results": results,
        }],
    });
    format!("{log:#}")
}

/// `unterminated comment` → `UnterminatedComment` (SARIF's rule name is an identifier).
fn rule_name(title: &str) -> String {
    title
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(|w| {
            let mut cs = w.chars();
            cs.next().map_or(String::new(), |f| f.to_ascii_uppercase().to_string() + cs.as_str())
        })
        .collect()
}

/// The range a code belongs to (`codes.rs`).
fn category(code: &str) -> &'static str {
    match code.get(3..5) {
        Some("00") => "lexical",
        Some("01") => "syntax",
        Some("02") => "structure",
        Some("03") => "names and types",
        Some("04") => "ATMT/EATMT",
        Some("05") => "analysis",
        Some("06") => "attributes",
        Some("07") => "PLCopen import",
        Some("08") => "code generation",
        _ => "other",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Span;

    #[test]
    fn uris_and_names() {
        assert_eq!(sarif_uri("examples/tank tank.st"), ("examples/tank%20tank.st".to_string(), true));
        assert_eq!(sarif_uri("/abs/č.st"), ("file:///abs/%C4%8D.st".to_string(), false));
        assert_eq!(rule_name("step without a way out"), "StepWithoutAWayOut");
        assert_eq!(category("SFC0501"), "analysis");
    }

    #[test]
    fn one_result_per_diagnostic() {
        let f = SourceFile::new("a.st", "PROGRAM P\n  x := 1;\nEND_PROGRAM\n");
        let d = Diagnostic::new("SFC0301", Span::new(0, 12, 13), "undeclared variable `x`").with_element("T1");
        let tool = SarifTool { name: "sfc", version: "0.1.0", semantic_version: "0.1.0", information_uri: None };
        let v: Value = serde_json::from_str(&render_sarif(&[d], &[f], &tool, "file:///w/", &[])).unwrap();
        let run = &v["runs"][0];
        assert_eq!(v["version"], "2.1.0");
        assert_eq!(run["results"][0]["ruleId"], "SFC0301");
        assert_eq!(
            run["tool"]["driver"]["rules"][run["results"][0]["ruleIndex"].as_u64().unwrap() as usize]["id"],
            "SFC0301"
        );
        let region = &run["results"][0]["locations"][0]["physicalLocation"]["region"];
        assert_eq!((region["startLine"].as_u64(), region["startColumn"].as_u64()), (Some(2), Some(3)));
        assert_eq!(run["results"][0]["locations"][0]["logicalLocations"][0]["name"], "T1");
        assert_eq!(run["invocations"][0]["executionSuccessful"], true);
    }
}
