//! Reading helpers over `roxmltree`: elements by local name (the three PLCopen namespaces share
//! their element names), attributes, positions, and text decoded from the raw XML with a map back
//! to byte offsets, so that text copied into the generated IEC source stays located exactly.

use roxmltree::Node;
use std::ops::Range;

/// The element children of `n` with local name `name`.
pub fn children<'a, 'i: 'a>(n: Node<'a, 'i>, name: &'a str) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    n.children().filter(move |c| c.is_element() && c.tag_name().name() == name)
}

/// The first element child of `n` with local name `name`.
pub fn child<'a, 'i: 'a>(n: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    n.children().find(|c| c.is_element() && c.tag_name().name() == name)
}

/// All element children.
pub fn elements<'a, 'i: 'a>(n: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    n.children().filter(|c| c.is_element())
}

/// An attribute without namespace, by local name.
pub fn attr<'a>(n: Node<'a, '_>, name: &str) -> Option<&'a str> {
    n.attributes().find(|a| a.name() == name && a.namespace().is_none()).map(|a| a.value())
}

/// The byte range of an attribute's value in the source.
pub fn attr_range(n: Node, name: &str) -> Option<Range<u32>> {
    n.attributes().find(|a| a.name() == name && a.namespace().is_none()).map(|a| {
        let r = a.range_value();
        r.start as u32..r.end as u32
    })
}

/// An attribute read as a number.
pub fn num(n: Node, name: &str) -> Option<f64> {
    attr(n, name).and_then(|v| v.trim().parse::<f64>().ok()).filter(|v| v.is_finite())
}

/// `true`/`1` (XML Schema boolean).
pub fn flag(n: Node, name: &str) -> bool {
    matches!(attr(n, name).map(str::trim), Some("true") | Some("1"))
}

/// The `x`, `y` of a `position` or `relPosition` element.
pub fn xy(n: Node) -> Option<(f64, f64)> {
    Some((num(n, "x")?, num(n, "y")?))
}

/// The `position` child of an element.
pub fn position(n: Node) -> Option<(f64, f64)> {
    child(n, "position").and_then(xy)
}

/// The range of an element's start tag name, `<step` (what diagnostics about the element point
/// at: one line, the element's start).
pub fn anchor(n: Node) -> Range<u32> {
    let r = n.range();
    let len = 1 + n.tag_name().name().len() + prefix_len(n);
    r.start as u32..(r.start + len).min(r.end) as u32
}

fn prefix_len(n: Node) -> usize {
    // `<xhtml:p`: the qualified name may carry a prefix; find it from the source.
    let doc = n.document();
    let src = doc.input_text();
    let r = n.range();
    let tag = src.get(r.start + 1..r.end).unwrap_or("");
    let qname_len = tag.find(|c: char| c.is_whitespace() || c == '>' || c == '/').unwrap_or(tag.len());
    qname_len.saturating_sub(n.tag_name().name().len())
}

/// The byte range of an element's content: between its start tag and its end tag.
pub fn content_range(n: Node) -> Option<Range<usize>> {
    let src = n.document().input_text();
    let r = n.range();
    let raw = src.get(r.clone())?;
    if raw.ends_with("/>") && !raw.contains("</") {
        return None;
    }
    // End of the start tag: the first `>` outside quoted attribute values.
    let mut quote: Option<u8> = None;
    let mut start = None;
    for (i, b) in raw.bytes().enumerate() {
        match quote {
            Some(q) if b == q => quote = None,
            Some(_) => {}
            None if b == b'"' || b == b'\'' => quote = Some(b),
            None if b == b'>' => {
                start = Some(i + 1);
                break;
            }
            None => {}
        }
    }
    let start = start?;
    let end = raw.rfind("</")?;
    (start <= end).then(|| r.start + start..r.start + end)
}

/// One stretch of decoded text that is a byte-for-byte copy of the source.
#[derive(Debug, Clone, Copy)]
pub struct Run {
    pub text: u32,
    pub raw: u32,
    pub len: u32,
}

/// Text read from the XML, with where each byte came from: bytes inside `runs` are exact copies
/// of the source; any other byte (an entity, a normalised line break) maps to `anchor`.
#[derive(Debug, Clone, Default)]
pub struct XText {
    pub text: String,
    pub runs: Vec<Run>,
    pub anchor: Range<u32>,
}

impl XText {
    /// Text made up by the importer, located at `anchor`.
    pub fn synthetic(text: impl Into<String>, anchor: Range<u32>) -> XText {
        XText { text: text.into(), runs: Vec::new(), anchor }
    }

    /// Appends another piece of text (a paragraph break, another paragraph).
    pub fn push(&mut self, other: &XText) {
        let base = self.text.len() as u32;
        self.text.push_str(&other.text);
        self.runs.extend(other.runs.iter().map(|r| Run { text: r.text + base, ..*r }));
    }

    pub fn push_str(&mut self, s: &str) {
        self.text.push_str(s);
    }

    /// The part `range` of this text (byte offsets into `text`, on char boundaries).
    pub fn slice(&self, range: Range<usize>) -> XText {
        let (s, e) = (range.start as u32, range.end as u32);
        let runs = self
            .runs
            .iter()
            .filter_map(|r| {
                let a = r.text.max(s);
                let b = (r.text + r.len).min(e);
                (a < b).then(|| Run { text: a - s, raw: r.raw + (a - r.text), len: b - a })
            })
            .collect();
        XText { text: self.text.get(range).unwrap_or("").to_string(), runs, anchor: self.anchor.clone() }
    }

    /// Without leading and trailing white space.
    pub fn trim(&self) -> XText {
        let t = self.text.trim_start();
        let start = self.text.len() - t.len();
        let end = start + t.trim_end().len();
        self.slice(start..end)
    }
}

/// The text content of an element: its text and CDATA children (comments and processing
/// instructions skipped; the text of nested elements included), decoded from the source so that
/// every copied stretch is located exactly.
pub fn text_of(n: Node) -> XText {
    let anchor = anchor(n);
    let Some(range) = content_range(n) else {
        return XText { text: String::new(), runs: Vec::new(), anchor };
    };
    let src = n.document().input_text();
    let expected: String = n.descendants().filter(|d| d.is_text()).filter_map(|d| d.text()).collect();
    if let Some(mut t) = decode(src, range.clone()) {
        if t.text == expected {
            t.anchor = anchor;
            return t;
        }
    }
    XText { text: expected, runs: Vec::new(), anchor }
}

/// Decodes the raw content `range` of `src` as XML character data: CDATA sections, the five
/// predefined entities, character references, line-break normalisation; markup inside (child
/// tags, comments, processing instructions) is skipped, so the result is the concatenation of
/// the descendant text. `None` when something cannot be decoded (an unknown entity).
fn decode(src: &str, range: Range<usize>) -> Option<XText> {
    let raw = src.get(range.clone())?;
    let base = range.start as u32;
    let mut out = XText::default();
    let mut i = 0usize;
    let bytes = raw.as_bytes();
    // Start of the pending literal run (raw offset) and its text offset.
    let mut run_start: Option<(usize, usize)> = None;
    fn close(out: &mut XText, run: &mut Option<(usize, usize)>, raw_end: usize, base: u32) {
        if let Some((rs, ts)) = run.take() {
            if raw_end > rs {
                out.runs.push(Run { text: ts as u32, raw: base + rs as u32, len: (raw_end - rs) as u32 });
            }
        }
    }
    while i < bytes.len() {
        let rest = &raw[i..];
        if rest.starts_with("<![CDATA[") {
            close(&mut out, &mut run_start, i, base);
            let body_start = i + 9;
            let end = raw[body_start..].find("]]>").map(|e| body_start + e)?;
            let body = &raw[body_start..end];
            // Line breaks inside CDATA are normalised too.
            push_literal(&mut out, body, body_start, base);
            i = end + 3;
        } else if rest.starts_with("<!--") {
            close(&mut out, &mut run_start, i, base);
            i += rest.find("-->").map(|e| e + 3)?;
        } else if rest.starts_with('<') {
            close(&mut out, &mut run_start, i, base);
            // A tag or a processing instruction: skip to its end, respecting quotes.
            let mut quote: Option<u8> = None;
            let mut j = i + 1;
            while let Some(&b) = bytes.get(j) {
                match quote {
                    Some(q) if b == q => quote = None,
                    Some(_) => {}
                    None if b == b'"' || b == b'\'' => quote = Some(b),
                    None if b == b'>' => break,
                    None => {}
                }
                j += 1;
            }
            i = j + 1;
        } else if rest.starts_with('&') {
            close(&mut out, &mut run_start, i, base);
            let semi = rest.find(';')?;
            let name = &rest[1..semi];
            let c = match name {
                "lt" => '<',
                "gt" => '>',
                "amp" => '&',
                "quot" => '"',
                "apos" => '\'',
                _ if name.starts_with("#x") => char::from_u32(u32::from_str_radix(&name[2..], 16).ok()?)?,
                _ if name.starts_with('#') => char::from_u32(name[1..].parse().ok()?)?,
                _ => return None,
            };
            out.text.push(c);
            i += semi + 1;
        } else if rest.starts_with('\r') {
            close(&mut out, &mut run_start, i, base);
            out.text.push('\n');
            i += if rest.starts_with("\r\n") { 2 } else { 1 };
        } else {
            if run_start.is_none() {
                run_start = Some((i, out.text.len()));
            }
            let ch = rest.chars().next()?;
            out.text.push(ch);
            i += ch.len_utf8();
        }
    }
    close(&mut out, &mut run_start, bytes.len(), base);
    Some(out)
}

/// Appends literal text (CDATA content) at raw offset `at`, normalising `\r\n` and `\r`.
fn push_literal(out: &mut XText, body: &str, at: usize, base: u32) {
    let mut seg_start = 0;
    let bytes = body.as_bytes();
    let mut i = 0;
    while i <= bytes.len() {
        if i == bytes.len() || bytes.get(i) == Some(&b'\r') {
            if i > seg_start {
                out.runs.push(Run {
                    text: out.text.len() as u32,
                    raw: base + (at + seg_start) as u32,
                    len: (i - seg_start) as u32,
                });
                out.text.push_str(&body[seg_start..i]);
            }
            if i == bytes.len() {
                break;
            }
            out.text.push('\n');
            i += if bytes.get(i + 1) == Some(&b'\n') { 2 } else { 1 };
            seg_start = i;
            continue;
        }
        i += 1;
    }
}

/// The text of a `formattedText` element (`documentation`, `ST`, `IL`, `content`): XHTML
/// paragraphs (`xhtml:p`, `div`, …) joined by line breaks, `br` as a line break, or plain text
/// (PLCopen v1.0 writes `<ST>IX1 = FALSE</ST>`).
pub fn formatted_text(n: Node) -> XText {
    formatted(n, 0)
}

fn formatted(n: Node, depth: usize) -> XText {
    let blocks: Vec<Node> = elements(n).collect();
    if blocks.is_empty() {
        return text_of(n);
    }
    let mut out = XText { anchor: anchor(n), ..Default::default() };
    for (i, b) in blocks.iter().enumerate() {
        if i > 0 {
            out.push_str("\n");
        }
        if b.tag_name().name() == "br" {
            continue;
        }
        let inner: Vec<Node> = elements(*b).collect();
        if depth < MAX_NESTING && inner.iter().any(|c| c.tag_name().name() == "br" || c.tag_name().name() == "p") {
            out.push(&formatted(*b, depth + 1));
        } else {
            out.push(&text_of(*b));
        }
    }
    out
}

/// Byte offset of a 1-based row and column (columns count characters) in `src`.
pub fn offset_of(src: &str, row: u32, col: u32) -> u32 {
    let mut line = 1u32;
    let mut start = 0usize;
    if row > 1 {
        for (i, b) in src.bytes().enumerate() {
            if b == b'\n' {
                line += 1;
                if line == row {
                    start = i + 1;
                    break;
                }
            }
        }
        if line < row {
            return src.len() as u32;
        }
    }
    let mut off = start;
    for (k, (i, ch)) in src[start..].char_indices().enumerate() {
        if k + 1 >= col as usize || ch == '\n' {
            off = start + i;
            return off as u32;
        }
        off = start + i + ch.len_utf8();
    }
    off as u32
}

/// Serialises an element subtree as a self-contained XML fragment: every element and attribute
/// carries the namespace declarations it needs, so the fragment stays valid wherever it is
/// written back (its original ancestors may have declared the prefixes it used).
///
/// The element itself is written without a namespace declaration: it takes the namespace of
/// the place it is written to (a PLCopen `addData/data` element, in whichever PLCopen version).
pub fn serialize(n: Node) -> String {
    serialize_without(n, &|_| false)
}

/// [`serialize`] leaving out the elements `skip` names (and what they hold).
pub fn serialize_without(n: Node, skip: &dyn Fn(Node) -> bool) -> String {
    let mut out = String::new();
    ser(n, n.tag_name().namespace(), &mut out, 0, skip);
    out
}

/// How deep [`serialize`] and [`formatted_text`] follow nested elements (deeper content is
/// dropped, so no input can exhaust the stack).
const MAX_NESTING: usize = 128;

fn ser(n: Node, parent_ns: Option<&str>, out: &mut String, depth: usize, skip: &dyn Fn(Node) -> bool) {
    if depth > MAX_NESTING || skip(n) {
        return;
    }
    if n.is_text() {
        out.push_str(&escape_text(n.text().unwrap_or("")));
        return;
    }
    if !n.is_element() {
        return;
    }
    let name = n.tag_name().name();
    let ns = n.tag_name().namespace();
    out.push('<');
    out.push_str(name);
    if ns != parent_ns {
        out.push_str(&format!(" xmlns=\"{}\"", escape_attr(ns.unwrap_or(""))));
    }
    let mut k = 0;
    for a in n.attributes() {
        match a.namespace() {
            Some(ans) => {
                out.push_str(&format!(
                    " xmlns:a{k}=\"{}\" a{k}:{}=\"{}\"",
                    escape_attr(ans),
                    a.name(),
                    escape_attr(a.value())
                ));
                k += 1;
            }
            None => out.push_str(&format!(" {}=\"{}\"", a.name(), escape_attr(a.value()))),
        }
    }
    if n.children().next().is_none() {
        out.push_str("/>");
        return;
    }
    out.push('>');
    for c in n.children() {
        ser(c, ns, out, depth + 1, skip);
    }
    out.push_str("</");
    out.push_str(name);
    out.push('>');
}

pub fn escape_text(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

pub fn escape_attr(s: &str) -> String {
    escape_text(s).replace('"', "&quot;").replace('\n', "&#10;").replace('\r', "&#13;").replace('\t', "&#9;")
}
