//! Checked IEC text → PLCopen TC6 v2.01 XML.
//!
//! The export reads the parsed file (`Checked::unit`) for declarations and non-SFC bodies, the
//! charts for SFC bodies, and copies code (conditions, bodies, initial values) from the source
//! text by span, so comments inside bodies survive. The output is deterministic: no clock, fixed
//! number formatting (the file header's date is a fixed one).

mod config;
mod sfc;

use crate::attrs;
use crate::xml::escape_attr;
use quick_xml::events::{BytesCData, BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::Checked;
use sfc_syntax::ast;

/// The XML being written.
pub(crate) struct X {
    w: Writer<Vec<u8>>,
    /// The comments of the source (`(* … *)`, `// …`) not written yet, with their spans.
    comments: Vec<(Span, String, bool)>,
    /// The comments of the element being written: its raw comments and their text.
    pending: Option<(String, String)>,
    /// CODESYS `data` fragments the next `add_data` writes (a POU's methods and properties),
    /// replacing foreign ones of the same kinds.
    objects: Vec<String>,
}

impl X {
    fn new() -> X {
        X { w: Writer::new_with_indent(Vec::new(), b' ', 2), comments: Vec::new(), pending: None, objects: Vec::new() }
    }

    fn tag(name: &str, attrs: &[(&str, String)]) -> BytesStart<'static> {
        let mut content = name.to_string();
        for (k, v) in attrs {
            content.push_str(&format!(" {k}=\"{}\"", escape_attr(v)));
        }
        BytesStart::from_content(content, name.len())
    }

    /// `<name a="…">`; writing into a `Vec` cannot fail.
    pub fn open(&mut self, name: &str, attrs: &[(&str, String)]) {
        let _ = self.w.write_event(Event::Start(X::tag(name, attrs)));
    }

    pub fn close(&mut self, name: &str) {
        let _ = self.w.write_event(Event::End(BytesEnd::new(name.to_string())));
    }

    pub fn empty(&mut self, name: &str, attrs: &[(&str, String)]) {
        let _ = self.w.write_event(Event::Empty(X::tag(name, attrs)));
    }

    /// `<name><xhtml:p><![CDATA[text]]></xhtml:p></name>`, as Beremiz writes formatted text.
    pub fn formatted(&mut self, name: &str, text: &str) {
        self.open(name, &[]);
        self.open("xhtml:p", &[]);
        for part in BytesCData::escaped(text) {
            let _ = self.w.write_event(Event::CData(part));
        }
        self.close("xhtml:p");
        self.close(name);
    }

    /// Text content, escaped.
    pub fn text(&mut self, t: &str) {
        let _ = self.w.write_event(Event::Text(quick_xml::events::BytesText::new(t)));
    }

    /// An XML fragment written as it is (a foreign `addData` element kept by the import).
    pub fn raw(&mut self, fragment: &str) {
        let _ = self.w.write_indent();
        use std::io::Write;
        let _ = self.w.get_mut().write_all(fragment.as_bytes());
    }

    fn finish(self) -> String {
        let mut s = String::from_utf8(self.w.into_inner()).unwrap_or_default();
        s.push('\n');
        s
    }

    /// Takes the comments of the source, to write each with the element it belongs to.
    pub fn with_comments(&mut self, unit: &ast::SourceUnit) {
        self.comments = unit
            .trivia
            .iter()
            .filter(|t| matches!(t.kind, ast::TriviaKind::BlockComment | ast::TriviaKind::LineComment))
            .map(|t| (t.span, t.text.clone(), false))
            .collect();
    }

    /// The comments that belong to the element at `span` of `src` (those right before it, with
    /// nothing but white space and attribute pragmas between, and one ending its last line)
    /// become its pending comments: `add_data` keeps them verbatim, `documentation` writes
    /// their text when the element has no description of its own.
    pub fn take_comments(&mut self, src: &str, span: Span) {
        self.pending = None;
        let mut taken: Vec<usize> = Vec::new();
        // Leading: walk back from the element over white space, pragmas and comments.
        let mut bound = span.start as usize;
        for k in (0..self.comments.len()).rev() {
            let (c, _, used) = &self.comments[k];
            if *used || c.end as usize > bound {
                continue;
            }
            let gap = src.get(c.end as usize..bound).unwrap_or("x");
            if !only_blank_or_pragmas(gap) {
                break;
            }
            taken.push(k);
            bound = c.start as usize;
        }
        taken.reverse();
        // Trailing: a comment after the element on its last line.
        if let Some(k) = self.comments.iter().position(|(c, _, used)| !used && c.start >= span.end) {
            let gap = src.get(span.end as usize..self.comments[k].0.start as usize).unwrap_or("x");
            if gap.chars().all(|ch| ch == ' ' || ch == '\t' || ch == ';') {
                taken.push(k);
            }
        }
        if taken.is_empty() {
            return;
        }
        let mut raw = Vec::new();
        let mut plain = Vec::new();
        for k in taken {
            self.comments[k].2 = true;
            let t = self.comments[k].1.clone();
            let inner = t
                .strip_prefix("(*")
                .and_then(|x| x.strip_suffix("*)"))
                .or_else(|| t.strip_prefix("/*").and_then(|x| x.strip_suffix("*/")))
                .or_else(|| t.strip_prefix("//"))
                .unwrap_or(&t);
            plain.push(inner.trim().to_string());
            raw.push(t);
        }
        self.pending = Some((raw.join("\n"), plain.join("\n")));
    }

    /// `position` with `x`, `y`.
    pub fn position(&mut self, name: &str, x: f64, y: f64) {
        self.empty(name, &[("x", attrs::fmt_num(x)), ("y", attrs::fmt_num(y))]);
    }
}

/// The text of a span of the source.
pub(crate) fn slice(src: &str, span: Span) -> &str {
    let s = (span.start as usize).min(src.len());
    let e = (span.end as usize).min(src.len()).max(s);
    src.get(s..e).unwrap_or("")
}

/// Lines of a block of code without blank lines at either end and without the indentation
/// common to its lines. `first_col` is the column where the first line starts in the source
/// (its indentation was cut off by the span).
pub(crate) fn dedent(text: &str, first_col: usize) -> String {
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| if i == 0 { format!("{}{}", " ".repeat(first_col), l) } else { l.to_string() })
        .collect();
    let mut lo = 0;
    let mut hi = lines.len();
    while lo < hi && lines[lo].trim().is_empty() {
        lo += 1;
    }
    while hi > lo && lines[hi - 1].trim().is_empty() {
        hi -= 1;
    }
    let body = &lines[lo..hi];
    let common = body
        .iter()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.len() - l.trim_start_matches([' ', '\t']).len())
        .min()
        .unwrap_or(0);
    body.iter().map(|l| l.get(common..).unwrap_or("").trim_end().to_string()).collect::<Vec<_>>().join("\n")
}

/// The column of byte `at` on its line, when only white space precedes it there.
pub(crate) fn column_if_leading(src: &str, at: usize) -> usize {
    let at = at.min(src.len());
    let line_start = src[..at].rfind('\n').map_or(0, |i| i + 1);
    let before = &src[line_start..at];
    if before.trim().is_empty() {
        before.len()
    } else {
        0
    }
}

/// A TIME in microseconds written canonically: `T#` then the non-zero units `d h m s ms us`.
pub fn fmt_duration(us: i64) -> String {
    if us == 0 {
        return "T#0s".into();
    }
    let neg = us < 0;
    let mut rest = us.unsigned_abs();
    let mut out = String::from(if neg { "T#-" } else { "T#" });
    for (unit, size) in
        [("d", 86_400_000_000u64), ("h", 3_600_000_000), ("m", 60_000_000), ("s", 1_000_000), ("ms", 1_000), ("us", 1)]
    {
        let n = rest / size;
        rest %= size;
        if n > 0 {
            out.push_str(&format!("{n}{unit}"));
        }
    }
    out
}

/// Attributes of an element written natively or into `addData`: returns the description and
/// writes nothing; see [`X::add_data`].
pub(crate) fn description(list: &[ast::Attribute]) -> Option<String> {
    attrs::get(list, attrs::DESCRIPTION).map(attrs::unescape).filter(|d| !d.trim().is_empty())
}

impl X {
    /// `<addData>` with the foreign data kept by the import and our own data: every `sfc.*`
    /// attribute not in `native` (those written in PLCopen's own elements for this element),
    /// plus `extra` entries (`<name value="…"/>`).
    pub fn add_data(&mut self, list: &[ast::Attribute], extra: &[(&str, Vec<(&str, String)>)], native: &[&str]) {
        let mut extra = extra.to_vec();
        if let Some((raw, _)) = &self.pending {
            extra.push(("comments", vec![("text", raw.clone())]));
        }
        let extra = extra.as_slice();
        let objects = std::mem::take(&mut self.objects);
        // Methods and properties written from the text replace those the import carried.
        let has_objects = !objects.is_empty();
        let replaced = |f: &String| {
            has_objects
                && ["/method\"", "/property\"", "/pouinheritance\""]
                    .iter()
                    .any(|k| f.split('>').next().unwrap_or("").contains(k))
        };
        let foreign: Vec<String> =
            attrs::all(list, attrs::ADDDATA).map(attrs::unescape).filter(|f| !replaced(f)).chain(objects).collect();
        let own: Vec<&ast::Attribute> = list
            .iter()
            .filter(|a| a.name.to_ascii_lowercase().starts_with("sfc."))
            .filter(|a| !a.name.eq_ignore_ascii_case(attrs::ADDDATA))
            .filter(|a| !native.iter().any(|n| n.eq_ignore_ascii_case(&a.name)))
            .collect();
        if foreign.is_empty() && own.is_empty() && extra.is_empty() {
            return;
        }
        self.open("addData", &[]);
        for f in &foreign {
            if well_formed(f) {
                self.raw(f);
            }
        }
        if !own.is_empty() || !extra.is_empty() {
            self.open("data", &[("name", attrs::DATA_NAME.to_string()), ("handleUnknown", "preserve".to_string())]);
            self.open("attributes", &[("xmlns", attrs::DATA_NS.to_string())]);
            for a in own {
                self.empty("attribute", &[("name", a.name.clone()), ("value", a.value.clone().unwrap_or_default())]);
            }
            for (name, list) in extra {
                let owned: Vec<(&str, String)> = list.to_vec();
                self.empty(name, &owned);
            }
            self.close("attributes");
            self.close("data");
        }
        self.close("addData");
    }

    /// `<documentation>` from `sfc.description`.
    pub fn documentation(&mut self, list: &[ast::Attribute]) {
        let pending = self.pending.take();
        if let Some(d) = description(list) {
            self.formatted("documentation", &d);
        } else if let Some((_, text)) = pending.filter(|p| !p.1.trim().is_empty()) {
            self.formatted("documentation", &text);
        }
    }
}

/// White space and attribute pragmas only (what may lie between a comment and its element).
fn only_blank_or_pragmas(gap: &str) -> bool {
    let mut depth = 0;
    gap.chars().all(|c| match c {
        '{' => {
            depth += 1;
            true
        }
        '}' => {
            depth -= 1;
            true
        }
        _ if depth > 0 => true,
        c => c.is_whitespace(),
    })
}

/// Elementary types the schema names as elements.
const XSD_ELEMENTARY: &[&str] = &[
    "BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "REAL",
    "LREAL", "TIME", "DATE", "DT", "TOD",
];

/// Writes the content of a `type`/`baseType`/`returnType` element.
pub(crate) fn write_type(x: &mut X, src: &str, t: &ast::TypeSpec) {
    match &t.kind {
        // TC6's `pointer`; a reference as CODESYS names it, by its text.
        ast::TypeSpecKind::Indirect { kind: ast::Indirection::Pointer, target } => {
            x.open("pointer", &[]);
            x.open("baseType", &[]);
            write_type(x, src, target);
            x.close("baseType");
            x.close("pointer");
        }
        ast::TypeSpecKind::Indirect { .. } => x.empty("derived", &[("name", slice(src, t.span).trim().to_string())]),
        ast::TypeSpecKind::Named(id) => {
            let upper = id.text.to_ascii_uppercase();
            let upper = match upper.as_str() {
                "DATE_AND_TIME" => "DT".to_string(),
                "TIME_OF_DAY" => "TOD".to_string(),
                _ => upper,
            };
            if XSD_ELEMENTARY.contains(&upper.as_str()) {
                x.empty(&upper, &[]);
            } else if upper == "STRING" || upper == "WSTRING" {
                x.empty(&upper.to_ascii_lowercase(), &[]);
            } else {
                x.empty("derived", &[("name", id.text.clone())]);
            }
        }
        ast::TypeSpecKind::String { wide, length } => {
            let name = if *wide { "wstring" } else { "string" };
            match length {
                Some(l) => x.empty(name, &[("length", slice(src, l.span).trim().to_string())]),
                None => x.empty(name, &[]),
            }
        }
        ast::TypeSpecKind::Array { ranges, element } => {
            x.open("array", &[]);
            for (lo, hi) in ranges {
                x.empty(
                    "dimension",
                    &[
                        ("lower", slice(src, lo.span).trim().to_string()),
                        ("upper", slice(src, hi.span).trim().to_string()),
                    ],
                );
            }
            x.open("baseType", &[]);
            write_type(x, src, element);
            x.close("baseType");
            x.close("array");
        }
        ast::TypeSpecKind::Subrange { base, low, high } => {
            let unsigned = ["USINT", "UINT", "UDINT", "ULINT", "BYTE", "WORD", "DWORD", "LWORD"]
                .iter()
                .any(|u| base.text.eq_ignore_ascii_case(u));
            let name = if unsigned { "subrangeUnsigned" } else { "subrangeSigned" };
            x.open(name, &[]);
            x.empty(
                "range",
                &[
                    ("lower", slice(src, low.span).trim().to_string()),
                    ("upper", slice(src, high.span).trim().to_string()),
                ],
            );
            x.open("baseType", &[]);
            write_type(x, src, &ast::TypeSpec { kind: ast::TypeSpecKind::Named(base.clone()), span: base.span });
            x.close("baseType");
            x.close(name);
        }
        ast::TypeSpecKind::Enum { base, values } => {
            x.open("enum", &[]);
            x.open("values", &[]);
            for (name, v) in values {
                match v {
                    Some(e) => x.empty(
                        "value",
                        &[("name", name.text.clone()), ("value", slice(src, e.span).trim().to_string())],
                    ),
                    None => x.empty("value", &[("name", name.text.clone())]),
                }
            }
            x.close("values");
            if let Some(b) = base {
                x.open("baseType", &[]);
                write_type(x, src, &ast::TypeSpec { kind: ast::TypeSpecKind::Named(b.clone()), span: b.span });
                x.close("baseType");
            }
            x.close("enum");
        }
        ast::TypeSpecKind::Struct(decls) => {
            x.open("struct", &[]);
            for d in decls {
                write_variables(x, src, d, None);
            }
            x.close("struct");
        }
        ast::TypeSpecKind::Error => x.empty("BOOL", &[]),
    }
}

/// Writes the content of an `initialValue`/`value` element.
pub(crate) fn write_value(x: &mut X, src: &str, v: &ast::Initializer) {
    match v {
        ast::Initializer::Expr(e) => x.empty("simpleValue", &[("value", slice(src, e.span).trim().to_string())]),
        ast::Initializer::Array { elements, .. } => {
            x.open("arrayValue", &[]);
            for el in elements {
                let rep: Vec<(&str, String)> = match &el.repeat {
                    Some(r) => vec![("repetitionValue", slice(src, r.span).trim().to_string())],
                    None => Vec::new(),
                };
                x.open("value", &rep);
                match &el.value {
                    Some(inner) => write_value(x, src, inner),
                    None => x.empty("simpleValue", &[]),
                }
                x.close("value");
            }
            x.close("arrayValue");
        }
        ast::Initializer::Struct { fields, .. } => {
            x.open("structValue", &[]);
            for (name, inner) in fields {
                x.open("value", &[("member", name.text.clone())]);
                write_value(x, src, inner);
                x.close("value");
            }
            x.close("structValue");
        }
    }
}

/// One `variable` element per name of a declaration (`a, b : INT` gives two).
pub(crate) fn write_variables(x: &mut X, src: &str, d: &ast::VarDecl, kind: Option<ast::VarKind>) {
    let names: Vec<String> =
        if d.names.is_empty() { vec![String::new()] } else { d.names.iter().map(|n| n.text.clone()).collect() };
    for name in names {
        let mut a: Vec<(&str, String)> = vec![("name", name)];
        if let Some(loc) = &d.location {
            a.push(("address", loc.text.clone()));
        }
        x.open("variable", &a);
        x.open("type", &[]);
        write_type(x, src, &d.ty);
        x.close("type");
        if let Some(init) = &d.init {
            x.open("initialValue", &[]);
            write_value(x, src, init);
            x.close("initialValue");
        }
        let mut extra: Vec<(&str, Vec<(&str, String)>)> = Vec::new();
        if kind == Some(ast::VarKind::Access) {
            extra.push((
                "access",
                vec![
                    ("path", d.access_path.clone().unwrap_or_default()),
                    ("mode", d.access_mode.clone().unwrap_or_default()),
                ],
            ));
        }
        x.take_comments(src, d.span);
        x.add_data(&d.attributes, &extra, &[attrs::DESCRIPTION]);
        x.documentation(&d.attributes);
        x.close("variable");
    }
}

fn var_list_name(kind: ast::VarKind) -> &'static str {
    match kind {
        ast::VarKind::Var => "localVars",
        ast::VarKind::Input => "inputVars",
        ast::VarKind::Output => "outputVars",
        ast::VarKind::InOut => "inOutVars",
        ast::VarKind::Global => "globalVars",
        ast::VarKind::External => "externalVars",
        ast::VarKind::Access => "accessVars",
        ast::VarKind::Temp => "tempVars",
    }
}

/// A `VAR … END_VAR` block as a varList element named `name`.
pub(crate) fn write_var_block(x: &mut X, src: &str, b: &ast::VarBlock, name: &str) {
    let mut a: Vec<(&str, String)> = Vec::new();
    if b.constant {
        a.push(("constant", "true".into()));
    }
    match b.retain {
        Some(ast::Retain::Retain) => a.push(("retain", "true".into())),
        Some(ast::Retain::NonRetain) => a.push(("nonretain", "true".into())),
        None => {}
    }
    if b.persistent {
        a.push(("persistent", "true".into()));
    }
    x.open(name, &a);
    for d in &b.decls {
        write_variables(x, src, d, Some(b.kind));
    }
    x.close(name);
}

/// The text of a non-SFC POU body: between the declarations and the END keyword.
fn pou_body_text(src: &str, pou: &ast::Pou) -> String {
    let mut start = pou.name.span.end;
    if let Some(rt) = &pou.return_type {
        start = start.max(rt.span.end);
    }
    for b in &pou.var_blocks {
        start = start.max(b.span.end);
    }
    let kw = pou.kind.end_keyword();
    let end = pou.span.end.saturating_sub(kw.len() as u32);
    let mut end = if slice(src, Span::new(0, end, pou.span.end)).eq_ignore_ascii_case(kw) { end } else { pou.span.end };
    // The actions after the statements are written as the POU's `actions`, its methods and
    // properties as CODESYS data.
    // (The first action's attributes are written before its ACTION keyword, and are its own.)
    if let Some(first) = pou.actions.first() {
        end = end.min(first.attributes.iter().map(|a| a.span.start).fold(first.span.start, u32::min));
    }
    for (span, attributes) in pou
        .methods
        .iter()
        .map(|m| (m.span, &m.attributes))
        .chain(pou.properties.iter().map(|p| (p.span, &p.attributes)))
    {
        end = end.min(attributes.iter().map(|a| a.span.start).fold(span.start, u32::min));
    }
    let text = slice(src, Span::new(0, start, end.max(start)));
    dedent(text, 0)
}

/// `<body><ST>` of a method or accessor, as CODESYS writes it (an `xhtml` element of its own
/// namespace: the fragment stands alone in `addData`).
fn write_code_body(x: &mut X, text: &str) {
    x.open("body", &[]);
    x.open("ST", &[]);
    x.open("xhtml", &[("xmlns", "http://www.w3.org/1999/xhtml".into())]);
    x.text(text);
    x.close("xhtml");
    x.close("ST");
    x.close("body");
}

/// The statements of a method or property accessor spanning `span`, after its declarations
/// and before its END keyword.
fn code_text(src: &str, after: u32, span: Span, blocks: &[ast::VarBlock], end_kw: &str) -> String {
    let start = blocks.iter().map(|b| b.span.end).fold(after, u32::max);
    let end = span.end.saturating_sub(end_kw.len() as u32);
    let end = if slice(src, Span::new(0, end, span.end)).eq_ignore_ascii_case(end_kw) { end } else { span.end };
    dedent(slice(src, Span::new(0, start, end.max(start))), 0)
}

/// `<interface>` of a method or accessor: its result, variables and access modifiers.
fn write_code_interface(
    x: &mut X,
    src: &str,
    ret: Option<&ast::TypeSpec>,
    blocks: &[ast::VarBlock],
    modifiers: &[ast::Ident],
) {
    x.open("interface", &[]);
    if let Some(rt) = ret {
        x.open("returnType", &[]);
        write_type(x, src, rt);
        x.close("returnType");
    }
    for b in blocks {
        write_var_block(x, src, b, var_list_name(b.kind));
    }
    let flags: Vec<(&str, String)> = ["Public", "Private", "Protected", "Internal", "Abstract", "Final"]
        .into_iter()
        .filter(|k| modifiers.iter().any(|m| m.is(k)))
        .map(|k| (k, "true".to_string()))
        .collect();
    if !flags.is_empty() {
        x.open("addData", &[]);
        x.open(
            "data",
            &[
                ("name", "http://www.3s-software.com/plcopenxml/accessmodifiers".into()),
                ("handleUnknown", "implementation".into()),
            ],
        );
        x.empty("AccessModifiers", &flags);
        x.close("data");
        x.close("addData");
    }
    x.close("interface");
}

/// A POU's methods and properties as CODESYS writes them (`data` of its `addData`, named
/// `…/plcopenxml/method` and `…/plcopenxml/property`), for [`X::add_data`].
fn object_fragments(src: &str, pou: &ast::Pou) -> Vec<String> {
    const NS: &str = "http://www.3s-software.com/plcopenxml/";
    let mut out = Vec::new();
    for m in &pou.methods {
        let mut x = X::new();
        x.open("data", &[("name", format!("{NS}method")), ("handleUnknown", "implementation".into())]);
        x.open("Method", &[("name", m.name.text.clone())]);
        write_code_interface(&mut x, src, m.return_type.as_ref(), &m.var_blocks, &m.modifiers);
        let after = m.return_type.as_ref().map_or(m.name.span.end, |t| t.span.end);
        write_code_body(&mut x, &code_text(src, after, m.span, &m.var_blocks, "END_METHOD"));
        x.empty("addData", &[]);
        x.close("Method");
        x.close("data");
        out.push(x.finish());
    }
    for p in &pou.properties {
        let mut x = X::new();
        x.open("data", &[("name", format!("{NS}property")), ("handleUnknown", "implementation".into())]);
        x.open("Property", &[("name", p.name.text.clone())]);
        write_code_interface(&mut x, src, Some(&p.ty), &[], &p.modifiers);
        for (tag, acc, kw) in [("GetAccessor", &p.get, "END_GET"), ("SetAccessor", &p.set, "END_SET")] {
            let Some(a) = acc else { continue };
            x.open(tag, &[]);
            write_code_interface(&mut x, src, None, &a.var_blocks, &a.modifiers);
            // The accessor's keyword (GET/SET) starts its span.
            write_code_body(&mut x, &code_text(src, a.span.start + 3, a.span, &a.var_blocks, kw));
            x.empty("addData", &[]);
            x.close(tag);
        }
        x.empty("addData", &[]);
        x.close("Property");
        x.close("data");
        out.push(x.finish());
    }
    out
}

/// An interface as CODESYS writes it in the project's `addData`: `data[@name=…/interface]`
/// holding `Interface` with its `Methods` and `Properties` (prototypes: their interfaces only)
/// and its bases as `Inheritance/Extends` in its `addData`.
fn interface_fragment(src: &str, i: &ast::Interface) -> String {
    const NS: &str = "http://www.3s-software.com/plcopenxml/";
    let mut x = X::new();
    x.open("data", &[("name", format!("{NS}interface")), ("handleUnknown", "implementation".into())]);
    x.open("Interface", &[("name", i.name.text.clone())]);
    if !i.methods.is_empty() {
        x.open("Methods", &[]);
        for m in &i.methods {
            x.open("Method", &[("name", m.name.text.clone())]);
            write_code_interface(&mut x, src, m.return_type.as_ref(), &m.var_blocks, &m.modifiers);
            x.empty("addData", &[]);
            x.close("Method");
        }
        x.close("Methods");
    }
    if !i.properties.is_empty() {
        x.open("Properties", &[]);
        for p in &i.properties {
            x.open("Property", &[("name", p.name.text.clone())]);
            write_code_interface(&mut x, src, Some(&p.ty), &[], &p.modifiers);
            for (tag, acc) in [("GetAccessor", &p.get), ("SetAccessor", &p.set)] {
                let Some(a) = acc else { continue };
                x.open(tag, &[]);
                write_code_interface(&mut x, src, None, &a.var_blocks, &a.modifiers);
                x.empty("addData", &[]);
                x.close(tag);
            }
            x.empty("addData", &[]);
            x.close("Property");
        }
        x.close("Properties");
    }
    if i.extends.is_empty() {
        x.empty("addData", &[]);
    } else {
        x.open("addData", &[]);
        x.open("data", &[("name", format!("{NS}interfaceinheritance")), ("handleUnknown", "implementation".into())]);
        x.open("Inheritance", &[]);
        for e in &i.extends {
            x.open("Extends", &[]);
            x.text(&e.text);
            x.close("Extends");
        }
        x.close("Inheritance");
        x.close("data");
        x.close("addData");
    }
    x.close("Interface");
    x.close("data");
    x.finish()
}

/// The `actions` of a POU that is no chart (CODESYS's actions of a function block), each with
/// its body as written.
fn write_pou_actions(x: &mut X, src: &str, actions: &[ast::Action], subs: &[&sfc_model::Chart]) {
    if actions.is_empty() {
        return;
    }
    x.open("actions", &[]);
    for a in actions {
        x.open("action", &[("name", a.name.text.clone())]);
        let sub = subs.iter().find(|c| a.body.sfc().is_some() && c.action.as_deref() == Some(&a.name.text));
        match sub {
            Some(sub) => {
                let none = (Default::default(), Default::default());
                sfc::write_sfc(x, src, sub, &a.attributes, &none.0, &none.1);
            }
            None => {
                x.open("body", &[]);
                x.formatted(sfc::body_lang(&a.body), &sfc::action_body_text(src, a.name.span, a.span));
                x.close("body");
            }
        }
        x.add_data(&a.attributes, &[], &[attrs::DESCRIPTION, attrs::COMMENT, attrs::LOOSE]);
        x.documentation(&a.attributes);
        x.close("action");
    }
    x.close("actions");
}

/// Whether an error keeps the file from being exported faithfully: lexical and syntax errors
/// leave holes in the tree, chart errors (an undeclared step or action, an unknown qualifier)
/// leave connections and associations out of the chart. Type errors (an unknown library type, a
/// condition that is not BOOL) do not change what is written, so such files are exported.
fn blocks_export(d: &Diagnostic) -> bool {
    // A second initial step in a network (which Beremiz, MatIEC and OpenPLC run), no initial
    // step or a step connected to nothing (a chart being drawn) are written as drawn: the chart
    // stays complete.
    // A bound or length that is no constant (SFC0105) is written as it is, as text.
    d.is_error()
        && !["SFC0201", "SFC0202", "SFC0203", "SFC0105"].contains(&d.code)
        && ["SFC00", "SFC01", "SFC02"].iter().any(|p| d.code.starts_with(p))
}

/// Exports a checked file as a PLCopen TC6 v2.01 project. Fails with the errors that keep it
/// from being written faithfully (see [`blocks_export`]) outside every POU; see
/// [`export_with`] for a POU with such errors.
pub fn export(checked: &Checked) -> Result<String, Vec<Diagnostic>> {
    export_with(checked, None).map(|(text, _)| text)
}

/// The `data` name under which an export keeps, in a POU's `addData`, the text of a POU it could
/// not write as PLCopen (it has errors that keep its chart from being whole); the import reads
/// that text back as it is.
pub const SOURCE_DATA: &str = "https://sfc.invalid/plcopen/source";

/// [`export`] that never refuses a POU for its own errors: a POU with errors that keep it from
/// being written faithfully is written as it was read (its element of `original`, the PLCopen
/// file the checked text was imported from) or, without one, with its text kept in its
/// `addData` ([`SOURCE_DATA`]) for the import to read back. Each such POU gets a note
/// (SFC0716), returned beside the project.
pub fn export_with(checked: &Checked, original: Option<&str>) -> Result<(String, Vec<Diagnostic>), Vec<Diagnostic>> {
    let unit = &checked.unit;
    let item_span = |it: &ast::Item| match it {
        ast::Item::Pou(p) => Some(p.span),
        _ => None,
    };
    let blocking: Vec<&Diagnostic> = checked.diagnostics.iter().filter(|d| blocks_export(d)).collect();
    let inside =
        |d: &Diagnostic, s: sfc_diagnostics::Span| s.start <= d.span.start && d.span.start < s.end.max(s.start + 1);
    let outside: Vec<Diagnostic> = blocking
        .iter()
        .filter(|d| !unit.items.iter().filter_map(item_span).any(|s| inside(d, s)))
        .map(|d| (*d).clone())
        .collect();
    if !outside.is_empty() {
        return Err(outside);
    }
    let original_doc = original.and_then(|o| roxmltree::Document::parse(o).ok());
    let mut notes = Vec::new();
    let src = checked.file.text.as_str();
    let unit = &checked.unit;
    let mut x = X::new();
    x.with_comments(unit);
    let _ = x.w.write_event(Event::Decl(BytesDecl::new("1.0", Some("utf-8"), None)));
    x.open(
        "project",
        &[
            ("xmlns", crate::import::NAMESPACES[0].to_string()),
            ("xmlns:xhtml", "http://www.w3.org/1999/xhtml".to_string()),
            ("xmlns:xsd", "http://www.w3.org/2001/XMLSchema".to_string()),
        ],
    );
    // The headers of an imported file travel on its first POU (`sfc.fileheader`,
    // `sfc.contentheader`), as does the project's foreign `addData` (`sfc.projectdata`).
    let header = |name: &str| -> Option<String> {
        unit.items.iter().find_map(|it| {
            let list = match it {
                ast::Item::Pou(p) => &p.attributes,
                ast::Item::Verbatim(v) => &v.attributes,
                _ => return None,
            };
            attrs::get(list, name).map(attrs::unescape).filter(|v| well_formed(v))
        })
    };
    match header(attrs::FILEHEADER).and_then(|h| file_header(&h)) {
        Some(a) => x.empty("fileHeader", &a.iter().map(|(k, v)| (k.as_str(), v.clone())).collect::<Vec<_>>()),
        None => x.empty(
            "fileHeader",
            &[
                ("companyName", "sfc".into()),
                ("productName", "sfc".into()),
                ("productVersion", env!("CARGO_PKG_VERSION").into()),
                ("creationDateTime", "1970-01-01T00:00:00".into()),
            ],
        ),
    }
    match header(attrs::CONTENTHEADER).filter(|h| h.contains("coordinateInfo")) {
        Some(h) => x.raw(&h),
        None => {
            let stem = checked.file.name.rsplit(['/', '\\']).next().unwrap_or("project");
            let stem = stem.split('.').next().filter(|s| !s.is_empty()).unwrap_or("project");
            x.open("contentHeader", &[("name", stem.to_string())]);
            x.open("coordinateInfo", &[]);
            for l in ["fbd", "ld", "sfc"] {
                x.open(l, &[]);
                x.empty("scaling", &[("x", "0".into()), ("y", "0".into())]);
                x.close(l);
            }
            x.close("coordinateInfo");
            x.close("contentHeader");
        }
    }

    x.open("types", &[]);
    x.open("dataTypes", &[]);
    for item in &unit.items {
        if let ast::Item::Types(tb) = item {
            for d in &tb.decls {
                if is_library_alias(d) {
                    continue;
                }
                x.open("dataType", &[("name", d.name.text.clone())]);
                x.open("baseType", &[]);
                write_type(&mut x, src, &d.spec);
                x.close("baseType");
                if let Some(init) = &d.init {
                    x.open("initialValue", &[]);
                    write_value(&mut x, src, init);
                    x.close("initialValue");
                }
                x.close("dataType");
            }
        }
    }
    x.close("dataTypes");
    x.open("pous", &[]);
    for (i, item) in unit.items.iter().enumerate() {
        match item {
            ast::Item::Pou(pou) => {
                if let Some(first) = blocking.iter().find(|d| inside(d, pou.span)) {
                    let from = write_as_read(&mut x, src, pou, original_doc.as_ref());
                    notes.push(
                        Diagnostic::warning(
                            "SFC0716",
                            pou.name.span,
                            format!("`{}` has errors, so it is written {from}", pou.name.text),
                        )
                        .with_note(format!("the first: {}", first.message)),
                    );
                    continue;
                }
                let chart = checked.charts.iter().find(|c| c.item == i);
                write_pou(&mut x, src, pou, chart, &action_charts(checked, i));
            }
            ast::Item::Verbatim(v) => write_verbatim_pou(&mut x, v),
            _ => {}
        }
    }
    x.close("pous");
    x.close("types");

    config::write_instances(&mut x, src, unit);
    // The interfaces, as CODESYS keeps them: in the project's `addData`, before what an import
    // carried over.
    let interfaces: Vec<String> = unit
        .items
        .iter()
        .filter_map(|i| match i {
            ast::Item::Interface(i) => Some(interface_fragment(src, i)),
            _ => None,
        })
        .collect();
    let data = header(attrs::PROJECTDATA);
    if !interfaces.is_empty() || data.is_some() {
        x.open("addData", &[]);
        for f in &interfaces {
            x.raw(f);
        }
        if let Some(data) = data {
            x.raw(&data);
        }
        x.close("addData");
    }
    x.close("project");
    Ok((x.finish(), notes))
}

/// Writes a POU that has errors as it was read: its element of the original PLCopen file, or
/// its interface with its text in `addData` ([`SOURCE_DATA`]). Says which, for the note.
fn write_as_read(x: &mut X, src: &str, pou: &ast::Pou, original: Option<&roxmltree::Document>) -> &'static str {
    let found = original.and_then(|doc| {
        doc.descendants().find(|n| {
            n.is_element()
                && n.tag_name().name() == "pou"
                && n.attribute("name").is_some_and(|v| v.trim().eq_ignore_ascii_case(&pou.name.text))
        })
    });
    if let Some(n) = found {
        x.raw(&crate::xml::serialize(n));
        return "as it was read from the PLCopen file";
    }
    let kind = match pou.kind {
        ast::PouKind::Program => "program",
        ast::PouKind::FunctionBlock => "functionBlock",
        ast::PouKind::Function => "function",
    };
    x.open("pou", &[("name", pou.name.text.clone()), ("pouType", kind.into())]);
    if let Some(rt) = &pou.return_type {
        x.open("interface", &[]);
        x.open("returnType", &[]);
        write_type(x, src, rt);
        x.close("returnType");
        x.close("interface");
    }
    x.open("body", &[]);
    x.formatted("ST", "");
    x.close("body");
    x.open("addData", &[]);
    x.open("data", &[("name", SOURCE_DATA.to_string()), ("handleUnknown", "discard".to_string())]);
    // From its first attribute pragma, so they travel with it.
    let start = pou.attributes.iter().map(|a| a.span.start).min().unwrap_or(pou.span.start).min(pou.span.start);
    x.formatted("text", src.get(start as usize..pou.span.end as usize).unwrap_or(""));
    x.close("data");
    x.close("addData");
    x.close("pou");
    "with its text in its addData (for sfc to read back), not as a chart"
}

/// The attributes of a kept `fileHeader`, made valid for v2.01: the required ones present,
/// `creationDateTime` an `xs:dateTime` (v1.0 files write `2007-07-07 11:58:26`).
pub(crate) fn file_header(fragment: &str) -> Option<Vec<(String, String)>> {
    let doc = roxmltree::Document::parse(fragment).ok()?;
    let h = doc.root_element();
    const KNOWN: &[&str] = &[
        "companyName",
        "companyURL",
        "productName",
        "productVersion",
        "productRelease",
        "creationDateTime",
        "contentDescription",
    ];
    let mut out: Vec<(String, String)> = Vec::new();
    for name in KNOWN {
        let v = h.attribute(*name).map(str::to_string);
        let v = match (*name, v) {
            ("creationDateTime", Some(d)) => Some(date_time(&d)),
            ("creationDateTime", None) => Some("1970-01-01T00:00:00".into()),
            ("companyName" | "productName" | "productVersion", None) => Some(String::new()),
            (_, v) => v,
        };
        if let Some(v) = v {
            out.push((name.to_string(), v));
        }
    }
    Some(out)
}

/// The `pou` element of the first POU of a checked text (for putting one POU back into a file,
/// see [`crate::splice_pou`]). Fails with the errors that keep it from being written
/// faithfully, or when the text holds no POU.
pub fn export_pou(checked: &Checked) -> Result<String, Vec<Diagnostic>> {
    let errors: Vec<Diagnostic> = checked.diagnostics.iter().filter(|d| blocks_export(d)).cloned().collect();
    if !errors.is_empty() {
        return Err(errors);
    }
    let src = checked.file.text.as_str();
    let mut x = X::new();
    x.with_comments(&checked.unit);
    for (i, item) in checked.unit.items.iter().enumerate() {
        if let ast::Item::Pou(pou) = item {
            let chart = checked.charts.iter().find(|c| c.item == i);
            write_pou(&mut x, src, pou, chart, &action_charts(checked, i));
            return Ok(x.finish());
        }
    }
    Err(vec![Diagnostic::new("SFC0702", Span::new(0, 0, 0), "the text holds no POU to export")])
}

/// The coordinate info sfc writes (no scaling).
pub(crate) const COORDINATE_INFO: &str = "<coordinateInfo><fbd><scaling x=\"0\" y=\"0\"/></fbd><ld><scaling x=\"0\" y=\"0\"/></ld><sfc><scaling x=\"0\" y=\"0\"/></sfc></coordinateInfo>";

/// A `fileHeader` as the import keeps it: the attributes of [`file_header`], in its order.
pub(crate) fn canonical_file_header(fragment: &str) -> Option<String> {
    let list = file_header(fragment)?;
    let a: Vec<String> = list.iter().map(|(k, v)| format!("{k}=\"{}\"", escape_attr(v))).collect();
    Some(format!("<fileHeader {}/>", a.join(" ")))
}

/// `2007-07-07 11:58:26` → `2007-07-07T11:58:26`; anything else that is not an `xs:dateTime`
/// becomes the fixed date of sfc's own files.
fn date_time(d: &str) -> String {
    let d = d.trim().replacen(' ', "T", 1);
    let b = d.as_bytes();
    let ok = b.len() >= 19
        && b[4] == b'-'
        && b[7] == b'-'
        && b[10] == b'T'
        && b[13] == b':'
        && b[16] == b':'
        && [0, 1, 2, 3, 5, 6, 8, 9, 11, 12, 14, 15, 17, 18].iter().all(|&i| b[i].is_ascii_digit());
    if ok {
        d
    } else {
        "1970-01-01T00:00:00".into()
    }
}

/// Whether a kept XML fragment is well-formed (a hand edit may have broken it: then it is not
/// written, rather than writing a broken file).
/// Whether `fragment` is well-formed XML where the export writes it: inside the document, whose
/// root declares the `xhtml` and `xsd` prefixes (a method's documentation uses `xhtml:p`).
fn well_formed(fragment: &str) -> bool {
    roxmltree::Document::parse(&format!(
        "<r xmlns:xhtml=\"http://www.w3.org/1999/xhtml\" xmlns:xsd=\"http://www.w3.org/2001/XMLSchema\">{fragment}</r>"
    ))
    .is_ok()
}

/// A declaration of a Beremiz svghmi library type as the library has it (`HMI_BOOL : BOOL`, which
/// the import adds when a file uses it undeclared): not written, since the library declares it
/// and Beremiz would refuse a second declaration.
fn is_library_alias(d: &ast::TypeDecl) -> bool {
    let base = match &d.spec.kind {
        ast::TypeSpecKind::Named(b) => b.text.to_ascii_uppercase(),
        ast::TypeSpecKind::String { wide: false, length: None } => "STRING".to_string(),
        _ => return false,
    };
    d.init.is_none() && crate::import::library_alias(&d.name.text) == Some(base.as_str())
}

/// A POU kept as written: the XML it was imported from, as it was (`sfc.pouxml`); one written
/// as text, with its declarations and its body as text. An import's opaque stand-in for a type
/// declared elsewhere (`sfc.verbatim` = `opaque`) is not written.
fn write_verbatim_pou(x: &mut X, v: &ast::Verbatim) {
    if !matches!(v.keyword.as_str(), "PROGRAM" | "FUNCTION_BLOCK" | "FUNCTION") {
        return;
    }
    if attrs::get(&v.attributes, attrs::VERBATIM).is_some_and(|w| w.trim() == "opaque") {
        return;
    }
    if let Some(xml) = attrs::get(&v.attributes, attrs::POUXML).map(attrs::unescape).filter(|t| well_formed(t)) {
        x.raw(&xml);
        return;
    }
    let (unit, _) = sfc_syntax::parse(0, &v.text);
    if let Some(ast::Item::Pou(p)) = unit.items.first() {
        let mut p = p.clone();
        p.attributes = v.attributes.clone();
        let checked = sfc_model::check_source(0, "", &v.text, &sfc_model::CheckOptions::default());
        let chart = checked.charts.first().filter(|_| matches!(p.body, ast::Body::Sfc(_)));
        write_pou(x, &checked.file.text, &p, chart, &action_charts(&checked, 0));
    }
}

/// The charts of the actions written in SFC of item `i`.
fn action_charts(checked: &Checked, i: usize) -> Vec<&sfc_model::Chart> {
    checked.action_charts.iter().filter(|c| c.item == i).collect()
}

fn write_pou(x: &mut X, src: &str, pou: &ast::Pou, chart: Option<&sfc_model::Chart>, subs: &[&sfc_model::Chart]) {
    let kind = match pou.kind {
        ast::PouKind::Program => "program",
        ast::PouKind::FunctionBlock => "functionBlock",
        ast::PouKind::Function => "function",
    };
    x.open("pou", &[("name", pou.name.text.clone()), ("pouType", kind.into())]);
    if pou.return_type.is_some() || !pou.var_blocks.is_empty() || pou.extends.is_some() || !pou.implements.is_empty() {
        x.open("interface", &[]);
        if let Some(rt) = &pou.return_type {
            x.open("returnType", &[]);
            write_type(x, src, rt);
            x.close("returnType");
        }
        for b in &pou.var_blocks {
            write_var_block(x, src, b, var_list_name(b.kind));
        }
        if pou.extends.is_some() || !pou.implements.is_empty() {
            x.open("addData", &[]);
            x.open(
                "data",
                &[
                    ("name", "http://www.3s-software.com/plcopenxml/pouinheritance".into()),
                    ("handleUnknown", "implementation".into()),
                ],
            );
            x.open("Inheritance", &[]);
            if let Some(b) = &pou.extends {
                x.open("Extends", &[]);
                x.text(&b.text);
                x.close("Extends");
            }
            for i in &pou.implements {
                x.open("Implements", &[]);
                x.text(&i.text);
                x.close("Implements");
            }
            x.close("Inheritance");
            x.close("data");
            x.close("addData");
        }
        x.close("interface");
    }
    write_pou_actions(x, src, &pou.actions, subs);
    match (&pou.body, chart) {
        (ast::Body::Sfc(_), Some(chart)) => sfc::write_chart(x, src, pou, chart, subs),
        (ast::Body::Il(_), _) => {
            x.open("body", &[]);
            x.formatted("IL", &pou_body_text(src, pou));
            x.close("body");
        }
        _ => {
            x.open("body", &[]);
            x.formatted("ST", &pou_body_text(src, pou));
            x.close("body");
        }
    }
    x.take_comments(src, Span::new(pou.span.file, pou.span.start, pou.name.span.end));
    // Its methods and properties go into the POU's own `addData` (not an action's).
    x.objects = object_fragments(src, pou);
    x.add_data(
        &pou.attributes,
        &[],
        &[
            attrs::DESCRIPTION,
            attrs::COMMENT,
            attrs::LOOSE,
            attrs::FILEHEADER,
            attrs::CONTENTHEADER,
            attrs::PROJECTDATA,
        ],
    );
    x.documentation(&pou.attributes);
    x.close("pou");
}
