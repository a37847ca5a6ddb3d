//! Putting one POU back into a PLCopen XML file: the `pou` element of that name is replaced by
//! the export of the new POU text, and every other byte of the file stays as it was (the other
//! POUs in FBD, LD or ST as their tool drew them, the headers, the instances, vendor data).
//! The editor's save goes through [`crate::patch_pou`], which changes the old `pou` element in
//! place when it can and falls back to this.

use crate::export::export_pou;
use crate::xml::{attr, child, children};
use sfc_diagnostics::Diagnostic;
use sfc_model::Checked;

/// The XHTML namespace the export's `xhtml:p` elements use.
const XHTML: &str = "http://www.w3.org/1999/xhtml";

/// Where a POU `name` lies in a PLCopen file: its byte range, and the indentation of its line.
fn find_pou(doc: &roxmltree::Document, name: &str) -> Option<(std::ops::Range<usize>, String)> {
    let src = doc.input_text();
    let node = doc.descendants().find(|n| {
        n.is_element()
            && n.tag_name().name() == "pou"
            && attr(*n, "name").is_some_and(|v| v.trim().eq_ignore_ascii_case(name.trim()))
    })?;
    let r = node.range();
    let line_start = src[..r.start].rfind('\n').map_or(0, |i| i + 1);
    let indent = &src[line_start..r.start];
    let indent = if indent.chars().all(|c| c == ' ' || c == '\t') { indent.to_string() } else { String::new() };
    Some((r, indent))
}

/// The export's `pou` element re-indented by `indent` (its first line not, it takes the
/// place of the old element's first line), with the XHTML prefix declared on it when the file
/// does not declare it at its root.
fn fit(pou_xml: &str, indent: &str, declare_xhtml: bool) -> String {
    let mut out = String::new();
    // Lines inside CDATA (code) are content: they are not indented.
    let mut in_cdata = false;
    for (k, line) in pou_xml.trim_end().lines().enumerate() {
        if k > 0 {
            out.push('\n');
            if !in_cdata {
                out.push_str(indent);
            }
        }
        out.push_str(line);
        let mut rest = line;
        loop {
            let next = if in_cdata { rest.find("]]>") } else { rest.find("<![CDATA[") };
            match next {
                Some(i) => {
                    rest = &rest[i + if in_cdata { 3 } else { 9 }..];
                    in_cdata = !in_cdata;
                }
                None => break,
            }
        }
    }
    if declare_xhtml {
        if let Some(end) = out.find('>') {
            let at = if out[..end].ends_with('/') { end - 1 } else { end };
            out.insert_str(at, &format!(" xmlns:xhtml=\"{XHTML}\""));
        }
    }
    out
}

/// `xml` with its POU `replacing` replaced by the POU of `checked` (a checked text holding
/// that one POU, named as it is now), or added to the file's `pous` when the file has no such
/// POU. Fails with the errors that keep the POU from being exported, or with a message when
/// `xml` is not a PLCopen project.
pub fn splice_pou(xml: &str, replacing: &str, checked: &Checked) -> Result<String, SpliceError> {
    let pou_xml = export_pou(checked).map_err(SpliceError::Diagnostics)?;
    let opts = roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(xml, opts)
        .map_err(|e| SpliceError::NotAProject(format!("the file is not well-formed XML: {e}")))?;
    let root = doc.root_element();
    if root.tag_name().name() != "project" {
        return Err(SpliceError::NotAProject("the file is not a PLCopen project".into()));
    }
    let declare_xhtml = root.lookup_prefix(XHTML) != Some("xhtml");
    if let Some((range, indent)) = find_pou(&doc, replacing) {
        let mut out = String::with_capacity(xml.len() + pou_xml.len());
        out.push_str(&xml[..range.start]);
        out.push_str(&fit(&pou_xml, &indent, declare_xhtml));
        out.push_str(&xml[range.end..]);
        return Ok(out);
    }
    // A new POU: after the last one, or as the content of an empty `pous`.
    let pous = child(root, "types").and_then(|t| child(t, "pous"));
    let Some(pous) = pous else {
        return Err(SpliceError::NotAProject("the file has no `types/pous` to add the POU to".into()));
    };
    let last = children(pous, "pou").last();
    let src = doc.input_text();
    let mut out = String::with_capacity(xml.len() + pou_xml.len());
    match last {
        Some(p) => {
            let r = p.range();
            let line_start = src[..r.start].rfind('\n').map_or(0, |i| i + 1);
            let indent = src[line_start..r.start].to_string();
            out.push_str(&xml[..r.end]);
            out.push('\n');
            out.push_str(&indent);
            out.push_str(&fit(&pou_xml, &indent, declare_xhtml));
            out.push_str(&xml[r.end..]);
        }
        None => {
            let r = pous.range();
            let raw = &xml[r.clone()];
            let line_start = src[..r.start].rfind('\n').map_or(0, |i| i + 1);
            let indent = format!("{}  ", &src[line_start..r.start]);
            let body = format!("\n{indent}{}\n{}", fit(&pou_xml, &indent, declare_xhtml), &src[line_start..r.start]);
            out.push_str(&xml[..r.start]);
            if raw.ends_with("/>") {
                out.push_str(raw.trim_end_matches("/>").trim_end());
                out.push('>');
                out.push_str(&body);
                out.push_str("</pous>");
            } else {
                let close = raw.rfind("</").unwrap_or(raw.len());
                out.push_str(&raw[..close]);
                out.push_str(&body);
                out.push_str(&raw[close..]);
            }
            out.push_str(&xml[r.end..]);
        }
    }
    Ok(out)
}

/// Why a POU could not be put into a file.
#[derive(Debug, Clone)]
pub enum SpliceError {
    /// The POU cannot be exported; located in its text.
    Diagnostics(Vec<Diagnostic>),
    /// The file is not a PLCopen project one can add a POU to.
    NotAProject(String),
}
