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
}

impl X {
    fn new() -> X {
        X { w: Writer::new_with_indent(Vec::new(), b' ', 2) }
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
        let foreign: Vec<String> = attrs::all(list, attrs::ADDDATA).map(attrs::unescape).collect();
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
            if roxmltree::Document::parse(&format!("<r>{f}</r>")).is_ok() {
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
        if let Some(d) = description(list) {
            self.formatted("documentation", &d);
        }
    }
}

/// Elementary types the schema names as elements.
const XSD_ELEMENTARY: &[&str] = &[
    "BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "REAL",
    "LREAL", "TIME", "DATE", "DT", "TOD",
];

/// Writes the content of a `type`/`baseType`/`returnType` element.
pub(crate) fn write_type(x: &mut X, src: &str, t: &ast::TypeSpec) {
    match &t.kind {
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
    let end = if slice(src, Span::new(0, end, pou.span.end)).eq_ignore_ascii_case(kw) { end } else { pou.span.end };
    let text = slice(src, Span::new(0, start, end.max(start)));
    dedent(text, 0)
}

/// Whether an error keeps the file from being exported faithfully: lexical and syntax errors
/// leave holes in the tree, chart errors (an undeclared step or action, an unknown qualifier)
/// leave connections and associations out of the chart. Type errors (an unknown library type, a
/// condition that is not BOOL) do not change what is written, so such files are exported.
fn blocks_export(d: &Diagnostic) -> bool {
    d.is_error() && ["SFC00", "SFC01", "SFC02"].iter().any(|p| d.code.starts_with(p))
}

/// Exports a checked file as a PLCopen TC6 v2.01 project. Fails with the errors that keep it
/// from being written faithfully (see [`blocks_export`]).
pub fn export(checked: &Checked) -> Result<String, Vec<Diagnostic>> {
    let errors: Vec<Diagnostic> = checked.diagnostics.iter().filter(|d| blocks_export(d)).cloned().collect();
    if !errors.is_empty() {
        return Err(errors);
    }
    let src = checked.file.text.as_str();
    let unit = &checked.unit;
    let mut x = X::new();
    let _ = x.w.write_event(Event::Decl(BytesDecl::new("1.0", Some("utf-8"), None)));
    x.open(
        "project",
        &[
            ("xmlns", crate::import::NAMESPACES[0].to_string()),
            ("xmlns:xhtml", "http://www.w3.org/1999/xhtml".to_string()),
            ("xmlns:xsd", "http://www.w3.org/2001/XMLSchema".to_string()),
        ],
    );
    x.empty(
        "fileHeader",
        &[
            ("companyName", "sfc".into()),
            ("productName", "sfc".into()),
            ("productVersion", env!("CARGO_PKG_VERSION").into()),
            ("creationDateTime", "1970-01-01T00:00:00".into()),
        ],
    );
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

    x.open("types", &[]);
    x.open("dataTypes", &[]);
    for item in &unit.items {
        if let ast::Item::Types(tb) = item {
            for d in &tb.decls {
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
        if let ast::Item::Pou(pou) = item {
            let chart = checked.charts.iter().find(|c| c.item == i);
            write_pou(&mut x, src, pou, chart);
        }
    }
    x.close("pous");
    x.close("types");

    config::write_instances(&mut x, src, unit);
    x.close("project");
    Ok(x.finish())
}

fn write_pou(x: &mut X, src: &str, pou: &ast::Pou, chart: Option<&sfc_model::Chart>) {
    let kind = match pou.kind {
        ast::PouKind::Program => "program",
        ast::PouKind::FunctionBlock => "functionBlock",
        ast::PouKind::Function => "function",
    };
    x.open("pou", &[("name", pou.name.text.clone()), ("pouType", kind.into())]);
    if pou.return_type.is_some() || !pou.var_blocks.is_empty() {
        x.open("interface", &[]);
        if let Some(rt) = &pou.return_type {
            x.open("returnType", &[]);
            write_type(x, src, rt);
            x.close("returnType");
        }
        for b in &pou.var_blocks {
            write_var_block(x, src, b, var_list_name(b.kind));
        }
        x.close("interface");
    }
    match (&pou.body, chart) {
        (ast::Body::Sfc(_), Some(chart)) => sfc::write_chart(x, src, pou, chart),
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
    x.add_data(&pou.attributes, &[], &[attrs::DESCRIPTION, attrs::COMMENT]);
    x.documentation(&pou.attributes);
    x.close("pou");
}
