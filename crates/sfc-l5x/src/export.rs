//! A checked chart file → an L5X file (a controller export) holding each chart as an SFC routine.
//!
//! The inverse of the import: what the import kept in `sfc.logix.*` attributes (IDs, the
//! elements' XML attributes, links, branches, text boxes, tag data, condition lines, `[:=]`
//! lines, the controller's SFC settings) is written back, so `import(export(import(x)))` gives
//! the text of `import(x)`. A chart whose stored IDs or links no longer fit its text (or that
//! never had any) gets fresh IDs in Studio's canonical order (`docs/dev/logix-sfc.md` §2.10),
//! links, branches and, without positions on every element, a top-down layout on Studio's
//! 20-unit grid. What Logix cannot hold is a located SFC0820 error (nothing is written); what
//! runs differently on a Logix controller is a located SFC0821 warning.

use crate::st::{self, Elements, StepInfo, Tok};
use sfc_diagnostics::{Diagnostic, Severity, Span};
use sfc_model::{ActionTarget, Chart, Checked, Duration, LastScan, Qualifier};
use sfc_syntax::ast;
use sfc_syntax::attr_value::unescape;
use sfc_xmlmap::XText;
use std::collections::{BTreeMap, HashMap, HashSet};

/// Writes the charts of `checked` (only `pou` when given) as an L5X file (a controller export) holding each chart as an SFC routine; the notes say what changed
/// on the way, the error what the format cannot express (located in the checked text).
pub fn export(checked: &Checked, pou: Option<&str>) -> Result<(String, Vec<Diagnostic>), Vec<Diagnostic>> {
    // sfc's supervision (sfc.timeout, SFCError, SFCQuitError) becomes a first action per step.
    let note = |c: &Chart, steps: &str| {
        let mut d = Diagnostic::new(
            "SFC0821",
            c.name_span,
            format!("the maximum time (sfc.timeout) of {steps} is written as actions: Logix has no SFCError"),
        )
        .with_note(
            "each step's first action `<Step>_Supervision` (N) clears `SFCError` while `SFCQuitError` is TRUE and, in a \
             step active longer than its time, sets it once per activation (flags `<Step>_Overdue`), as sfc does in the \
             `logix` profile before the actions; `SFCErrorStep` is not written. A step's `LimitHigh` alarm (`AH`) would \
             not latch"
                .to_string(),
        );
        d.severity = Severity::Warning;
        d
    };
    sfc_model::supervision::export_lowered(checked, sfc_model::supervision::Style::StepActions, pou, note, |c, notes| {
        write(c, pou, notes)
    })
}

fn write(
    checked: &Checked,
    pou: Option<&str>,
    notes: Vec<Diagnostic>,
) -> Result<(String, Vec<Diagnostic>), Vec<Diagnostic>> {
    let mut ex = Ex { checked, errors: Vec::new(), notes };
    let charts: Vec<&Chart> =
        checked.charts.iter().filter(|c| pou.is_none_or(|p| c.pou.eq_ignore_ascii_case(p))).collect();
    if charts.is_empty() {
        let at = checked.charts.first().map_or(Span::new(0, 0, 0), |c| c.name_span);
        return Err(vec![Diagnostic::error("SFC0820", at, "the file has no SFC POU to write as an L5X SFC routine")]);
    }
    for ac in &checked.action_charts {
        if charts.iter().any(|c| c.item == ac.item) {
            ex.error(
                ac.name_span,
                format!(
                    "the action `{}` is written in SFC: an L5X SFC routine's actions are ST",
                    ac.action.as_deref().unwrap_or("")
                ),
            );
        }
    }
    if pou.is_none() {
        for it in &checked.unit.items {
            if let ast::Item::Pou(p) = it {
                if !checked.charts.iter().any(|c| c.pou.eq_ignore_ascii_case(&p.name.text)) {
                    let mut d = Diagnostic::new(
                        "SFC0821",
                        p.name.span,
                        format!(
                            "the {} `{}` is not written: the L5X export writes the SFC programs",
                            p.kind.keyword(),
                            p.name.text
                        ),
                    )
                    .with_note(
                        "a chart that calls it or whose variables it drives runs without it in Studio 5000".to_string(),
                    );
                    d.severity = Severity::Warning;
                    ex.notes.push(d);
                }
            }
        }
    }
    let mut routines = Vec::new();
    for c in &charts {
        if let Some(r) = ex.chart(c) {
            routines.push(r);
        }
    }
    let first_attrs = charts.first().and_then(|c| ex.pou(c)).map(|p| p.attributes.clone()).unwrap_or_default();
    let data_types = ex.data_types();
    let globals = ex.globals();
    if !ex.errors.is_empty() {
        return Err(ex.errors);
    }
    // The controller: its settings from the first chart's POU.
    let get = |k: &str| attr(&first_attrs, k);
    let mut out = String::from("\u{feff}<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>\n");
    let rev = get("sfc.logix.rev").unwrap_or_else(|| "33.01".into());
    let major = rev.split('.').next().unwrap_or("33").to_string();
    let ctrl = charts.first().map_or_else(|| "Controller".to_string(), |c| c.pou.clone());
    out.push_str(&format!(
        "<RSLogix5000Content SchemaRevision=\"1.0\" SoftwareRevision=\"{}\" TargetName=\"{}\" TargetType=\"Controller\" ContainsContext=\"false\" ExportOptions=\"NoRawData L5KData DecoratedData ForceProtectedEncoding AllProjDocTrans\">\n",
        esc(&rev),
        esc(&ctrl)
    ));
    let mut settings = String::new();
    for (xml_name, key, default) in crate::DEFAULT_SETTINGS {
        settings.push_str(&format!(" {xml_name}=\"{}\"", esc(&get(key).unwrap_or_else(|| default.to_string()))));
    }
    if let Some(f) = get("sfc.logix.forces") {
        settings.push_str(&format!(" SFCForcesEnabled=\"{}\"", esc(&f)));
    }
    out.push_str(&format!(
        "<Controller Use=\"Target\" Name=\"{}\" MajorRev=\"{}\"{settings}>\n",
        esc(&ctrl),
        esc(&major)
    ));
    out.push_str("<DataTypes>\n");
    out.push_str(&data_types);
    out.push_str("</DataTypes>\n<Tags>\n");
    out.push_str(&globals);
    out.push_str("</Tags>\n<Programs>\n");
    // One Program per program name, its routines in order.
    let mut programs: Vec<(String, Vec<Routine>)> = Vec::new();
    for r in routines {
        match programs.iter_mut().find(|(p, _)| p == &r.program) {
            Some((_, list)) => list.push(r),
            None => programs.push((r.program.clone(), vec![r])),
        }
    }
    for (name, list) in &programs {
        let main = list
            .iter()
            .find(|r| r.main)
            .map(|r| format!(" MainRoutineName=\"{}\"", esc(&r.routine)))
            .unwrap_or_default();
        out.push_str(&format!(
            "<Program Name=\"{}\" TestEdits=\"false\"{main} Disabled=\"false\" UseAsFolder=\"false\">\n<Tags>\n",
            esc(name)
        ));
        let mut tags: Vec<&(String, String)> = list.iter().flat_map(|r| &r.tags).collect();
        // Studio sorts tags by name; the variables' own order is kept when it is not sorted.
        let vars: Vec<&(String, String)> = list.iter().flat_map(|r| &r.vars).collect();
        let sorted = vars.windows(2).all(|w| match w {
            [a, b] => a.0.to_ascii_uppercase() <= b.0.to_ascii_uppercase(),
            _ => true,
        });
        if sorted {
            tags.extend(vars);
            tags.sort_by_key(|t| t.0.to_ascii_uppercase());
        } else {
            tags.sort_by_key(|t| t.0.to_ascii_uppercase());
            let mut all = vars;
            all.extend(tags);
            tags = all;
        }
        for t in tags {
            out.push_str(&t.1);
        }
        out.push_str("</Tags>\n<Routines>\n");
        for r in list {
            out.push_str(&r.xml);
        }
        out.push_str("</Routines>\n</Program>\n");
    }
    out.push_str("</Programs>\n<Tasks>\n<Task Name=\"MainTask\" Type=\"CONTINUOUS\" Priority=\"10\" Watchdog=\"500\" DisableUpdateOutputs=\"false\" InhibitTask=\"false\">\n<ScheduledPrograms>\n");
    for (name, _) in &programs {
        out.push_str(&format!("<ScheduledProgram Name=\"{}\"/>\n", esc(name)));
    }
    out.push_str("</ScheduledPrograms>\n</Task>\n</Tasks>\n</Controller>\n</RSLogix5000Content>\n");
    Ok((out, ex.notes))
}

/// One SFC routine and its program's tags.
struct Routine {
    program: String,
    routine: String,
    main: bool,
    /// Tags of the chart's elements (name, XML).
    tags: Vec<(String, String)>,
    /// Tags of the POU's variables.
    vars: Vec<(String, String)>,
    xml: String,
}

struct Ex<'a> {
    checked: &'a Checked,
    errors: Vec<Diagnostic>,
    notes: Vec<Diagnostic>,
}

/// The value of attribute `name` (unescaped), the last one written.
fn attr(list: &[ast::Attribute], name: &str) -> Option<String> {
    list.iter().rev().find(|a| a.name.eq_ignore_ascii_case(name)).and_then(|a| a.value.as_deref()).map(unescape)
}

fn all_attrs(list: &[ast::Attribute], name: &str) -> Vec<String> {
    list.iter().filter(|a| a.name.eq_ignore_ascii_case(name)).filter_map(|a| a.value.as_deref()).map(unescape).collect()
}

/// XML attribute text.
fn esc(s: &str) -> String {
    sfc_xmlmap::xml::escape_attr(s)
}

fn cdata(s: &str) -> String {
    format!("<![CDATA[{}]]>", s.replace("]]>", "]]]]><![CDATA[>"))
}

fn description(text: &str) -> String {
    format!("<Description>\n{}\n</Description>\n", cdata(text))
}

/// `<STContent>` with one `Line` per line, as Studio writes them.
fn st_content(lines: &[String]) -> String {
    let mut o = String::from("<STContent>\n");
    for (i, l) in lines.iter().enumerate() {
        o.push_str(&format!("<Line Number=\"{i}\">\n{}\n</Line>\n", cdata(l)));
    }
    o.push_str("</STContent>\n");
    o
}

/// `ID="0" X="200" …` (as the import keeps them) → pairs.
fn parse_attrs(s: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = s;
    while let Some(eq) = rest.find("=\"") {
        let name = rest.get(..eq).unwrap_or("").trim().to_string();
        let after = rest.get(eq + 2..).unwrap_or("");
        let Some(end) = after.find('"') else { break };
        out.push((name, after.get(..end).unwrap_or("").to_string()));
        rest = after.get(end + 1..).unwrap_or("");
    }
    out
}

fn set(list: &mut Vec<(String, String)>, k: &str, v: String) {
    match list.iter_mut().find(|(n, _)| n == k) {
        Some(e) => e.1 = v,
        None => list.push((k.to_string(), v)),
    }
}

fn long_qualifier(q: Qualifier) -> &'static str {
    match q {
        Qualifier::N => "NonStored",
        Qualifier::S => "Stored",
        Qualifier::R => "Reset",
        Qualifier::L => "TimeLimited",
        Qualifier::D => "TimeDelayed",
        Qualifier::P => "Pulse",
        Qualifier::P1 => "PulseRisingEdge",
        Qualifier::P0 => "PulseFallingEdge",
        Qualifier::SL => "StoredTimeLimited",
        Qualifier::SD => "StoredTimeDelayed",
        Qualifier::DS => "TimeDelayedStored",
    }
}

/// The IEC qualifier a Logix spelling stands for.
fn qualifier_of(s: &str) -> Option<Qualifier> {
    Qualifier::ALL.into_iter().find(|q| long_qualifier(*q) == s || q.name() == s)
}

/// The XML element of a tag.
fn tag_xml(name: &str, ty: &str, desc: Option<&str>, data: &str) -> String {
    let radix = if matches!(ty, "SFC_STEP" | "SFC_ACTION" | "SFC_STOP" | "TIMER" | "COUNTER" | "CONTROL") {
        String::new()
    } else {
        " Radix=\"Decimal\"".to_string()
    };
    let mut o = format!(
        "<Tag Name=\"{}\" TagType=\"Base\" DataType=\"{}\"{radix} Constant=\"false\" ExternalAccess=\"Read/Write\">\n",
        esc(name),
        esc(ty)
    );
    if let Some(d) = desc {
        o.push_str(&description(d));
    }
    o.push_str(data);
    o.push_str("</Tag>\n");
    o
}

fn l5k(v: &str) -> String {
    format!("<Data Format=\"L5K\">\n{}\n</Data>\n", cdata(v))
}

fn status_hex(v: i64) -> String {
    let h = format!("{:08X}", v as u32);
    format!(
        "16#{}_{}",
        h.get(..4).unwrap_or("0000").to_ascii_lowercase(),
        h.get(4..).unwrap_or("0000").to_ascii_lowercase()
    )
}

/// The decorated data of an SFC tag with its preset (and its L5K data when kept).
fn sfc_tag_data(ty: &str, pre: i64, kept: Option<&str>) -> String {
    let fields: Vec<i64> = kept
        .and_then(|k| k.trim().strip_prefix('['))
        .and_then(|k| k.strip_suffix(']'))
        .map(|k| k.split(',').filter_map(|v| v.trim().parse().ok()).collect())
        .unwrap_or_default();
    let status = fields.first().copied().unwrap_or(2_097_152);
    let mut o = kept.map(l5k).unwrap_or_default();
    o.push_str(&format!("<Data Format=\"Decorated\">\n<Structure DataType=\"{ty}\">\n"));
    o.push_str(&format!(
        "<DataValueMember Name=\"Status\" DataType=\"DINT\" Radix=\"Hex\" Value=\"{}\"/>\n",
        status_hex(status)
    ));
    let bit =
        |n: &str, v: bool| format!("<DataValueMember Name=\"{n}\" DataType=\"BOOL\" Value=\"{}\"/>\n", u8::from(v));
    let dint = |n: &str, v: i64| {
        format!("<DataValueMember Name=\"{n}\" DataType=\"DINT\" Radix=\"Decimal\" Value=\"{v}\"/>\n")
    };
    let pause = status & (1 << 21) != 0;
    match ty {
        "SFC_STEP" => {
            for b in ["X", "FS", "SA", "LS", "DN", "OV", "AlarmEn", "AlarmLow", "AlarmHigh", "Reset"] {
                o.push_str(&bit(b, false));
            }
            o.push_str(&bit("PauseTimer", pause));
            o.push_str(&dint("PRE", pre));
            for d in ["T", "TMax", "Count", "LimitLow", "LimitHigh"] {
                o.push_str(&dint(d, 0));
            }
        }
        "SFC_ACTION" => {
            o.push_str(&bit("A", false));
            o.push_str(&bit("Q", false));
            o.push_str(&bit("PauseTimer", pause));
            o.push_str(&dint("PRE", pre));
            o.push_str(&dint("T", 0));
            o.push_str(&dint("Count", 0));
        }
        _ => {
            o.push_str(&bit("X", false));
            o.push_str(&bit("Reset", false));
            o.push_str(&dint("Count", 0));
        }
    }
    o.push_str("</Structure>\n</Data>\n");
    o
}

/// A duration in ms, when it is whole milliseconds.
fn duration_ms(text: &str) -> Option<i64> {
    let (_, body) = text.split_once('#')?;
    let us = sfc_syntax::literal::decode_duration(body, Span::new(0, 0, 0)).ok()?;
    (us % 1000 == 0).then_some(us / 1000)
}

impl Ex<'_> {
    fn error(&mut self, at: Span, msg: String) {
        self.errors.push(Diagnostic::error("SFC0820", at, format!("{msg}: not expressible in an L5X SFC routine")));
    }

    fn warn(&mut self, at: Span, element: &str, msg: String, note: &str) {
        let mut d = Diagnostic::new("SFC0821", at, msg).with_element(element).with_note(note.to_string());
        d.severity = Severity::Warning;
        self.notes.push(d);
    }

    fn text(&self, s: Span) -> &str {
        self.checked.file.text.get(s.start as usize..s.end as usize).unwrap_or("")
    }

    fn pou(&self, c: &Chart) -> Option<&ast::Pou> {
        match self.checked.unit.items.get(c.item) {
            Some(ast::Item::Pou(p)) => Some(p),
            _ => None,
        }
    }

    /// Logix's spelling of an IEC type, or an error.
    fn logix_type(&mut self, ty: &ast::TypeSpec) -> Option<(String, String)> {
        // (DataType, Dimensions)
        match &ty.kind {
            ast::TypeSpecKind::Named(n) => {
                let up = n.key();
                let t = match up.as_str() {
                    "BOOL" | "SINT" | "INT" | "DINT" | "LINT" | "USINT" | "UINT" | "UDINT" | "ULINT" | "REAL"
                    | "LREAL" | "BYTE" | "WORD" | "DWORD" | "LWORD" | "TIMER" | "COUNTER" | "CONTROL" => up,
                    // A TIME is a DINT of milliseconds in Logix.
                    "TIME" => "DINT".into(),
                    _ if self.udt_names().contains(&up) => n.text.clone(),
                    _ => {
                        self.error(ty.span, format!("the type `{}`", n.text));
                        return None;
                    }
                };
                Some((t, String::new()))
            }
            ast::TypeSpecKind::String { wide: false, .. } => Some(("STRING".into(), String::new())),
            ast::TypeSpecKind::Array { ranges, element } => {
                let mut dims = Vec::new();
                for (lo, hi) in ranges {
                    let lo: Option<i64> = self.text(lo.span).trim().parse().ok();
                    let hi: Option<i64> = self.text(hi.span).trim().parse().ok();
                    match (lo, hi) {
                        (Some(0), Some(h)) if h >= 0 => dims.push((h + 1).to_string()),
                        _ => {
                            self.error(ty.span, "an array whose index does not run from 0".into());
                            return None;
                        }
                    }
                }
                let (t, _) = self.logix_type(element)?;
                dims.reverse();
                Some((t, dims.join(" ")))
            }
            _ => {
                self.error(ty.span, format!("the type `{}`", self.text(ty.span)));
                None
            }
        }
    }

    fn udt_names(&self) -> HashSet<String> {
        let mut s = HashSet::new();
        for it in &self.checked.unit.items {
            if let ast::Item::Types(b) = it {
                for d in &b.decls {
                    s.insert(d.name.key());
                }
            }
        }
        s
    }

    fn data_types(&mut self) -> String {
        let mut out = String::new();
        let items: Vec<ast::TypeBlock> = self
            .checked
            .unit
            .items
            .iter()
            .filter_map(|i| match i {
                ast::Item::Types(b) => Some(b.clone()),
                _ => None,
            })
            .collect();
        for b in &items {
            for d in &b.decls {
                let builtin = ["TIMER", "COUNTER", "CONTROL"].contains(&d.name.key().as_str());
                let ast::TypeSpecKind::Struct(members) = &d.spec.kind else {
                    self.error(d.span, format!("the type `{}` (Logix has structures only)", d.name.text));
                    continue;
                };
                if builtin {
                    continue;
                }
                out.push_str(&format!(
                    "<DataType Name=\"{}\" Family=\"NoFamily\" Class=\"User\">\n<Members>\n",
                    esc(&d.name.text)
                ));
                let mut host: Option<(String, u32)> = None;
                let mut hosts = 0;
                for m in members {
                    let Some((t, dims)) = self.logix_type(&m.ty) else { continue };
                    for n in &m.names {
                        if t == "BOOL" && dims.is_empty() {
                            let (h, bit) = match &host {
                                Some((h, b)) if *b < 7 => (h.clone(), b + 1),
                                _ => {
                                    let h = format!("ZZZZZZZZZZ{}{hosts}", d.name.text);
                                    hosts += 1;
                                    out.push_str(&format!("<Member Name=\"{}\" DataType=\"SINT\" Dimension=\"0\" Radix=\"Decimal\" Hidden=\"true\" ExternalAccess=\"Read/Write\"/>\n", esc(&h)));
                                    (h, 0)
                                }
                            };
                            out.push_str(&format!("<Member Name=\"{}\" DataType=\"BIT\" Dimension=\"0\" Radix=\"Decimal\" Hidden=\"false\" Target=\"{}\" BitNumber=\"{bit}\" ExternalAccess=\"Read/Write\"/>\n", esc(&n.text), esc(&h)));
                            host = Some((h, bit));
                        } else {
                            let dim = if dims.is_empty() { "0".to_string() } else { dims.clone() };
                            out.push_str(&format!("<Member Name=\"{}\" DataType=\"{}\" Dimension=\"{}\" Radix=\"Decimal\" Hidden=\"false\" ExternalAccess=\"Read/Write\"/>\n", esc(&n.text), esc(&t), esc(&dim)));
                        }
                    }
                }
                out.push_str("</Members>\n</DataType>\n");
            }
        }
        out
    }

    /// The members of a structure type (built in or the file's), as Logix names them.
    fn members(&self, ty: &str) -> Vec<(String, String)> {
        let up = ty.to_ascii_uppercase();
        if let Some((_, m)) = crate::tags::STRUCTS.iter().find(|(n, _)| *n == up) {
            return m.iter().map(|(a, b)| ((*a).to_string(), (*b).to_string())).collect();
        }
        for it in &self.checked.unit.items {
            if let ast::Item::Types(b) = it {
                for d in b.decls.iter().filter(|d| d.name.key() == up) {
                    if let ast::TypeSpecKind::Struct(ms) = &d.spec.kind {
                        return ms
                            .iter()
                            .flat_map(|m| m.names.iter().map(move |n| (n.text.clone(), m.ty.clone())))
                            .map(|(n, t)| (n, self.text(t.span).trim().to_ascii_uppercase()))
                            .collect();
                    }
                }
            }
        }
        Vec::new()
    }

    /// A literal as Logix writes a value (BOOL as 0/1, TIME as ms).
    fn value(&mut self, text: &str, at: Span) -> Option<String> {
        let t = text.trim();
        let up = t.to_ascii_uppercase();
        let v = match up.as_str() {
            "TRUE" => "1".to_string(),
            "FALSE" => "0".to_string(),
            _ if up.starts_with("T#") || up.starts_with("TIME#") => match duration_ms(t) {
                Some(ms) => ms.to_string(),
                None => {
                    self.error(at, format!("the duration `{t}` (not whole milliseconds)"));
                    return None;
                }
            },
            _ => {
                let body =
                    t.split_once('#').map_or(t, |(k, v)| if k.chars().all(|c| c.is_ascii_digit()) { t } else { v });
                body.to_string()
            }
        };
        let based = v.split_once('#').is_some_and(|(b, d)| {
            matches!(b, "2" | "8" | "16") && !d.is_empty() && d.chars().all(|c| c.is_ascii_hexdigit() || c == '_')
        });
        let number = based || v.replace('_', "").parse::<f64>().is_ok_and(f64::is_finite);
        let string = v.len() >= 2 && v.starts_with('\'') && v.ends_with('\'');
        if !number && !string {
            self.error(at, format!("the initial value `{t}` (a tag's value is a literal)"));
            return None;
        }
        Some(v)
    }

    /// A variable as a tag: its decorated data from the initial value.
    fn var_tag(&mut self, d: &ast::VarDecl, name: &ast::Ident) -> Option<String> {
        let (ty, dims) = self.logix_type(&d.ty)?;
        let desc = attr(&d.attributes, "sfc.description");
        let mut data = String::new();
        let init = d.init.as_ref();
        if !dims.is_empty() {
            let mut o = format!("<Tag Name=\"{}\" TagType=\"Base\" DataType=\"{}\" Dimensions=\"{}\" Radix=\"Decimal\" Constant=\"false\" ExternalAccess=\"Read/Write\">\n", esc(&name.text), esc(&ty), esc(&dims));
            if let Some(dd) = &desc {
                o.push_str(&description(dd));
            }
            if let Some(ast::Initializer::Array { elements, span }) = init {
                let vals: Vec<String> = self
                    .text(*span)
                    .trim()
                    .trim_start_matches('[')
                    .trim_end_matches(']')
                    .split(',')
                    .map(|s| s.trim().to_string())
                    .collect();
                let _ = elements;
                let mut ok = Vec::new();
                for v in &vals {
                    if v.contains('(') {
                        self.error(*span, "a repeated array initial value".into());
                        return None;
                    }
                    ok.push(self.value(v, *span)?);
                }
                o.push_str(&format!(
                    "<Data Format=\"Decorated\">\n<Array DataType=\"{}\" Dimensions=\"{}\" Radix=\"Decimal\">\n",
                    esc(&ty),
                    esc(&dims)
                ));
                for (i, v) in ok.iter().enumerate() {
                    o.push_str(&format!("<Element Index=\"[{i}]\" Value=\"{}\"/>\n", esc(v)));
                }
                o.push_str("</Array>\n</Data>\n");
            }
            o.push_str("</Tag>\n");
            return Some(o);
        }
        match init {
            Some(ast::Initializer::Expr(e)) => {
                let src = self.text(e.span).to_string();
                let v = self.value(&src, e.span)?;
                data.push_str(&l5k(&v));
                data.push_str(&format!("<Data Format=\"Decorated\">\n<DataValue DataType=\"{}\" Radix=\"Decimal\" Value=\"{}\"/>\n</Data>\n", esc(&ty), esc(&v)));
            }
            Some(ast::Initializer::Struct { fields, span }) => {
                let members = self.members(&ty);
                data.push_str(&format!("<Data Format=\"Decorated\">\n<Structure DataType=\"{}\">\n", esc(&ty)));
                for (f, i) in fields {
                    let ast::Initializer::Expr(e) = i else {
                        self.error(*span, "a nested structure initial value".into());
                        return None;
                    };
                    let src = self.text(e.span).to_string();
                    let v = self.value(&src, e.span)?;
                    let mt = members
                        .iter()
                        .find(|(n, _)| n.eq_ignore_ascii_case(&f.text))
                        .map_or("DINT".to_string(), |m| m.1.clone());
                    if mt == "BOOL" {
                        data.push_str(&format!(
                            "<DataValueMember Name=\"{}\" DataType=\"BOOL\" Value=\"{}\"/>\n",
                            esc(&f.text),
                            esc(&v)
                        ));
                    } else {
                        data.push_str(&format!(
                            "<DataValueMember Name=\"{}\" DataType=\"{}\" Radix=\"Decimal\" Value=\"{}\"/>\n",
                            esc(&f.text),
                            esc(&mt),
                            esc(&v)
                        ));
                    }
                }
                data.push_str("</Structure>\n</Data>\n");
            }
            Some(ast::Initializer::Array { span, .. }) => {
                self.error(*span, "an array initial value of a variable that is no array".into());
                return None;
            }
            None => {}
        }
        Some(tag_xml(&name.text, &ty, desc.as_deref(), &data))
    }

    fn globals(&mut self) -> String {
        let mut out = String::new();
        let blocks: Vec<ast::VarBlock> = self
            .checked
            .unit
            .items
            .iter()
            .filter_map(|i| match i {
                ast::Item::Globals(b) => Some(b.clone()),
                _ => None,
            })
            .collect();
        for b in &blocks {
            for d in &b.decls {
                for n in &d.names {
                    if let Some(t) = self.var_tag(d, n) {
                        out.push_str(&t);
                    }
                }
            }
        }
        out
    }

    /// The source text of a transition's condition as the text writes it (comments kept).
    fn condition_text(&self, t: &sfc_model::TransitionNode) -> Option<String> {
        let ast::Condition::St(e) = &t.condition else { return None };
        let text = &self.checked.file.text;
        let from = e.span.start as usize;
        let rest = text.get(e.span.end as usize..)?;
        let end_kw = rest.to_ascii_uppercase().find("END_TRANSITION").unwrap_or(rest.len());
        let tail = rest.get(..end_kw)?;
        let semi = tail.rfind(';').unwrap_or(tail.len());
        Some(text.get(from..e.span.end as usize + semi)?.trim().to_string())
    }

    /// The lines of an action's ST body as written in the text (indentation of the block removed).
    fn body_lines(&self, a: &sfc_model::ActionNode, logix: bool) -> Vec<String> {
        let whole = self.text(a.span);
        let from = (a.name_span.end.saturating_sub(a.span.start)) as usize;
        let rest = whole.get(from..).unwrap_or("");
        let rest = rest.trim_start().strip_prefix(':').unwrap_or(rest);
        let end = rest.to_ascii_uppercase().rfind("END_ACTION").unwrap_or(rest.len());
        let body = rest.get(..end).unwrap_or("");
        let mut lines: Vec<&str> = body.split('\n').map(|l| l.trim_end_matches('\r')).collect();
        if lines.first().is_some_and(|l| l.trim().is_empty()) {
            lines.remove(0);
        }
        while lines.last().is_some_and(|l| l.trim().is_empty()) {
            lines.pop();
        }
        let indent = lines
            .iter()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.len() - l.trim_start_matches(' ').len())
            .min()
            .unwrap_or(0);
        let cut = if logix { indent.min(8) } else { indent };
        lines
            .iter()
            .map(|l| l.get(cut.min(l.len() - l.trim_start_matches(' ').len())..).unwrap_or("").to_string())
            .collect()
    }

    fn chart(&mut self, c: &Chart) -> Option<Routine> {
        let pou = self.pou(c)?.clone();
        let pa = &pou.attributes;
        let logix = attr(pa, "sfc.dialect").is_some_and(|d| d.eq_ignore_ascii_case("logix"));
        // The rules the chart was written for, against Logix's: only what differs is said.
        let source = sfc_model::RunRules::of(attr(pa, "sfc.dialect").as_deref(), c);
        let n_err = self.errors.len();
        let target = sfc_model::RunRules::of(Some("logix"), c);
        if let Some(why) = sfc_model::RunRules::order_change(source, target) {
            self.warn(
                c.name_span,
                &pou.name.text,
                format!("the chart is written for Studio 5000, whose call differs from {}'s", source.name),
                &why,
            );
        }
        // A chart function block (an S7-GRAPH block, a CODESYS FB) becomes a program: called
        // once per cycle, as such a block usually is, it runs as the program's routine does.
        let block = pou.kind == ast::PouKind::FunctionBlock;
        if block {
            self.warn(
                pou.name.span,
                &pou.name.text,
                format!("the FUNCTION_BLOCK `{}` is written as a program whose SFC routine is the chart", pou.name.text),
                "an L5X SFC routine belongs to a program, which a task runs once per scan: the block's instances become one \
                 program; its inputs, outputs and in-outs become the program's parameters (connect the InOut ones in the program's properties)",
            );
        } else if pou.kind != ast::PouKind::Program {
            self.error(
                pou.name.span,
                format!("the {} `{}` (an L5X SFC routine is a program's routine)", pou.kind.keyword(), pou.name.text),
            );
        }
        let (program, routine) = match attr(pa, "sfc.logix.routine")
            .and_then(|r| r.split_once('/').map(|(a, b)| (a.to_string(), b.to_string())))
        {
            Some(x) => x,
            None => (c.pou.clone(), c.pou.clone()),
        };
        // Variables → program tags.
        let mut vars = Vec::new();
        let mut inferred: Vec<String> = Vec::new();
        for b in &pou.var_blocks {
            let usage = match b.kind {
                ast::VarKind::Var | ast::VarKind::Temp | ast::VarKind::External => "",
                // A program's parameters (Studio 5000 v24 and later).
                ast::VarKind::Input if pou.kind == ast::PouKind::Program || block => " Usage=\"Input\"",
                ast::VarKind::Output if pou.kind == ast::PouKind::Program || block => " Usage=\"Output\"",
                ast::VarKind::InOut if pou.kind == ast::PouKind::Program || block => " Usage=\"InOut\"",
                _ => {
                    self.error(
                        b.span,
                        format!("a `{}` block (an SFC routine's tags are its program's)", b.kind.keyword()),
                    );
                    continue;
                }
            };
            if b.kind == ast::VarKind::External {
                continue;
            }
            for d in &b.decls {
                if attr(&d.attributes, "sfc.logix.inferred").is_some() {
                    // Not declared in the file it came from: left undeclared again.
                    inferred.extend(d.names.iter().map(|n| n.text.clone()));
                    continue;
                }
                if let Some(target) = attr(&d.attributes, "sfc.logix.alias") {
                    for n in &d.names {
                        vars.push((n.text.clone(), format!("<Tag Name=\"{}\" TagType=\"Alias\" Radix=\"Decimal\" AliasFor=\"{}\" ExternalAccess=\"Read/Write\">\n</Tag>\n", esc(&n.text), esc(&target))));
                    }
                    continue;
                }
                if let ast::TypeSpecKind::Named(n) = &d.ty.kind {
                    if n.is("TIME") && !logix {
                        self.notes.push(
                            Diagnostic::new("SFC0821", d.span, format!("the TIME variable{} `{}` is written as a DINT tag of milliseconds", if d.names.len() > 1 { "s" } else { "" }, d.names.iter().map(|n| n.text.as_str()).collect::<Vec<_>>().join("`, `")))
                                .with_note("Logix has no TIME type: a step's `.T` and a timer's preset are DINT milliseconds, and so are the TIME literals the chart compares them with".to_string()),
                        );
                        if let Some(last) = self.notes.last_mut() {
                            last.severity = Severity::Note;
                        }
                    }
                }
                let usage = match attr(&d.attributes, "sfc.logix.usage") {
                    Some(u) if usage.is_empty() => format!(" Usage=\"{}\"", esc(&u)),
                    _ => usage.to_string(),
                };
                for n in &d.names {
                    if b.kind == ast::VarKind::InOut {
                        // A reference to the tag connected to it: no data of its own.
                        if let Some((ty, dims)) = self.logix_type(&d.ty) {
                            let dims = if dims.is_empty() { String::new() } else { format!(" Dimensions=\"{}\"", esc(&dims)) };
                            let desc = attr(&d.attributes, "sfc.description").map(|t| description(&t)).unwrap_or_default();
                            vars.push((n.text.clone(), format!("<Tag Name=\"{}\" TagType=\"Base\" DataType=\"{}\"{dims} Usage=\"InOut\" Constant=\"false\" ExternalAccess=\"Read/Write\">\n{desc}</Tag>\n", esc(&n.text), esc(&ty))));
                        }
                        continue;
                    }
                    if let Some(t) = self.var_tag(d, n) {
                        vars.push((n.text.clone(), t.replacen(" Constant=", &format!("{usage} Constant="), 1)));
                    }
                }
            }
        }
        if !inferred.is_empty() {
            let mut d = Diagnostic::new(
                "SFC0821",
                pou.name.span,
                format!(
                    "the tags {} are not written: the L5X import declared them from their use",
                    inferred.join(", ")
                ),
            )
            .with_note(
                "the file they came from (a program export) did not hold them; Studio's project must".to_string(),
            );
            d.severity = Severity::Note;
            self.notes.push(d);
        }
        let el = elements(c);
        // Logix tag names have at most 40 characters.
        let long: Vec<(Span, &str)> = c
            .steps
            .iter()
            .map(|s| (s.name_span, s.name.as_str()))
            .chain(c.transitions.iter().map(|t| (t.header_span, t.name.as_str())))
            .chain(c.actions.iter().map(|a| (a.name_span, a.name.as_str())))
            .chain(vars.iter().map(|(n, _)| (pou.name.span, n.as_str())))
            .filter(|(_, n)| n.len() > 40)
            .collect();
        for (at, n) in long {
            self.error(at, format!("the name `{n}` (a Logix tag name has at most 40 characters)"));
        }
        let layout = layout(c);
        let ids = self.ids(c, &layout);
        let names = attr(pa, "sfc.logix.names");
        let mut xml = format!("<Routine Name=\"{}\" Type=\"SFC\">\n", esc(&routine));
        if let Some(d) = attr(pa, "sfc.description") {
            xml.push_str(&description(&d));
        }
        let mut content = String::from("<SFCContent");
        if let Some(s) = attr(pa, "sfc.logix.sheet") {
            let (size, orient) = s.split_once('|').unwrap_or((s.as_str(), ""));
            content.push_str(&format!(" SheetSize=\"{}\" SheetOrientation=\"{}\"", esc(size), esc(orient)));
        } else {
            content.push_str(" SheetSize=\"Letter - 8.5 x 11 in\" SheetOrientation=\"Landscape\"");
        }
        let nm: Vec<String> = match &names {
            Some(n) => n.split('|').map(str::to_string).collect(),
            None => ["Step", "Tran", "Action", "Stop"].map(str::to_string).to_vec(),
        };
        for (k, v) in ["StepName", "TransitionName", "ActionName", "StopName"].iter().zip(&nm) {
            content.push_str(&format!(" {k}=\"{}\"", esc(v)));
        }
        content.push_str(">\n");
        let mut tags: Vec<(String, String)> = Vec::new();
        // Which association writes an action's body: the first.
        let mut owner: HashMap<String, (usize, usize)> = HashMap::new();
        for (si, s) in c.steps.iter().enumerate() {
            for (ai, a) in s.associations.iter().enumerate() {
                owner.entry(a.action.to_ascii_uppercase()).or_insert((si, ai));
            }
        }
        let mut action_pre: HashMap<String, i64> = HashMap::new();
        let mut next_id = ids.next;
        // Steps and stops.
        for (si, s) in c.steps.iter().enumerate() {
            let stop = attr(&s.attributes, "sfc.logix.stop").is_some();
            if !s.step_actions.is_empty() || s.interlock.is_some() || s.supervision.is_some() {
                self.error(
                    s.name_span,
                    format!("the step `{}` has step actions, an interlock or a supervision", s.name),
                );
            }
            let mut at = parse_attrs(&attr(&s.attributes, "sfc.logix.attrs").unwrap_or_default());
            if !ids.kept || at.is_empty() {
                let (x, y) = layout.step.get(si).copied().unwrap_or((200, 100));
                at = if stop {
                    vec![
                        ("ID".into(), String::new()),
                        ("X".into(), x.to_string()),
                        ("Y".into(), y.to_string()),
                        ("HideDesc".into(), "false".into()),
                        ("DescX".into(), (x + 40).to_string()),
                        ("DescY".into(), (y - 20).to_string()),
                        ("DescWidth".into(), "0".into()),
                    ]
                } else {
                    vec![
                        ("ID".into(), String::new()),
                        ("X".into(), x.to_string()),
                        ("Y".into(), y.to_string()),
                        ("HideDesc".into(), "false".into()),
                        ("DescX".into(), (x + 40).to_string()),
                        ("DescY".into(), (y - 20).to_string()),
                        ("DescWidth".into(), "0".into()),
                        ("InitialStep".into(), "false".into()),
                        ("PresetUsesExpr".into(), "false".into()),
                        ("LimitHighUsesExpr".into(), "false".into()),
                        ("LimitLowUsesExpr".into(), "false".into()),
                        ("ShowActions".into(), "true".into()),
                    ]
                };
            }
            if let Some(id) = ids.step.get(si) {
                set(&mut at, "ID", id.to_string());
            }
            if ids.kept {
                for (k, key) in [("X", "sfc.x"), ("Y", "sfc.y")] {
                    if let Some(v) = attr(&s.attributes, key) {
                        set(&mut at, k, v);
                    }
                }
            }
            if !stop {
                set(&mut at, "InitialStep", if s.initial { "true" } else { "false" }.into());
            } else if s.initial {
                self.error(s.name_span, format!("the initial step `{}` marked as a stop", s.name));
            }
            let kind = if stop { "Stop" } else { "Step" };
            content.push_str(&format!("<{kind}{}", start_attrs(&at, &s.name)));
            let pre = attr(&s.attributes, "sfc.logix.preset").and_then(|p| p.parse::<i64>().ok()).unwrap_or(0);
            let desc = attr(&s.attributes, "sfc.description");
            let kept = attr(&s.attributes, "sfc.logix.tag");
            tags.push((
                s.name.clone(),
                tag_xml(
                    &s.name,
                    if stop { "SFC_STOP" } else { "SFC_STEP" },
                    desc.as_deref(),
                    &if stop {
                        sfc_tag_data("SFC_STOP", 0, kept.as_deref())
                    } else {
                        sfc_tag_data("SFC_STEP", pre, kept.as_deref())
                    },
                ),
            ));
            let mut inner = String::new();
            if let Some(e) = attr(&s.attributes, "sfc.logix.preset_expr") {
                inner.push_str(&format!(
                    "<Preset>\n{}</Preset>\n",
                    st_content(&e.split('\n').map(str::to_string).collect::<Vec<_>>())
                ));
            }
            for (key, el_name) in [("sfc.logix.limithigh", "LimitHigh"), ("sfc.logix.limitlow", "LimitLow")] {
                if let Some(e) = attr(&s.attributes, key) {
                    inner.push_str(&format!(
                        "<{el_name}>\n{}</{el_name}>\n",
                        st_content(&e.split('\n').map(str::to_string).collect::<Vec<_>>())
                    ));
                }
            }
            if stop && !s.associations.is_empty() {
                self.error(s.name_span, format!("the stop `{}` has actions", s.name));
            }
            for (ai, a) in s.associations.iter().enumerate() {
                let up = a.action.to_ascii_uppercase();
                let is_owner = owner.get(&up) == Some(&(si, ai));
                let ActionTarget::Action(idx) = a.target else {
                    // IEC's Boolean action: the variable follows the association's Q. With N it
                    // is an N action setting it and a P0 action clearing it in the step's last
                    // scan (P0 executes then under every last-scan setting), when no other step
                    // active at the same time drives it.
                    let shared = c.steps.iter().enumerate().any(|(o, st)| {
                        o != si && st.associations.iter().any(|b| b.action.eq_ignore_ascii_case(&a.action))
                    });
                    let parallel = c.transitions.iter().any(|t| t.to.len() > 1 || t.from.len() > 1)
                        || c.steps.iter().filter(|s| s.initial).count() > 1;
                    let delay = match (a.qualifier, &a.duration) {
                        (Qualifier::N, None) => None,
                        (Qualifier::D, Some(Duration::Literal(us))) if us % 1000 == 0 => Some(us / 1000),
                        (Qualifier::D, Some(Duration::Variable(v))) if self.constant_time(&pou, c, v).is_some() => {
                            self.constant_time(&pou, c, v)
                        }
                        _ => {
                            self.error(a.span, format!("the association `{}({})` of a BOOL variable (IEC's Boolean action: Logix has it as an N or D association, set by the action and cleared by a P0 action)", a.action, a.qualifier.name()));
                            continue;
                        }
                    };
                    if shared && parallel {
                        self.error(a.span, format!("the BOOL variable `{}` associated with steps that may be active together (a P0 action clearing it would clear it for both)", a.action));
                        continue;
                    }
                    let on = if delay.is_some() { "TimeDelayed" } else { "NonStored" };
                    for (suffix, q, value) in [("", on, "1"), ("_Off", "PulseFallingEdge", "0")] {
                        let mut name = format!("{}_{}{suffix}", s.name, a.action);
                        while c.steps.iter().any(|x| x.name.eq_ignore_ascii_case(&name))
                            || c.actions.iter().any(|x| x.name.eq_ignore_ascii_case(&name))
                            || c.transitions.iter().any(|x| x.name.eq_ignore_ascii_case(&name))
                            || tags.iter().any(|(x, _)| x.eq_ignore_ascii_case(&name))
                            || vars.iter().any(|(x, _)| x.eq_ignore_ascii_case(&name))
                        {
                            name.push('_');
                        }
                        next_id += 1;
                        inner.push_str(&format!(
                            "<Action ID=\"{}\" Operand=\"{}\" Qualifier=\"{q}\" IsBoolean=\"false\" PresetUsesExpr=\"false\">\n<Body>\n{}</Body>\n</Action>\n",
                            next_id - 1,
                            esc(&name),
                            st_content(&[format!("{} := {value};", a.action)])
                        ));
                        let pre = if value == "1" { delay.unwrap_or(0) } else { 0 };
                        tags.push((
                            name.clone(),
                            tag_xml(&name, "SFC_ACTION", None, &sfc_tag_data("SFC_ACTION", pre, None)),
                        ));
                    }
                    continue;
                };
                if !a.indicators.is_empty() {
                    self.error(a.span, format!("the indicator of `{}`", a.action));
                }
                let Some(node) = c.actions.get(idx) else { continue };
                let mut aat = if is_owner {
                    parse_attrs(&attr(&node.attributes, "sfc.logix.attrs").unwrap_or_default())
                } else {
                    Vec::new()
                };
                if !ids.kept || aat.is_empty() {
                    aat = vec![
                        ("ID".into(), String::new()),
                        ("Qualifier".into(), String::new()),
                        ("IsBoolean".into(), "false".into()),
                        ("PresetUsesExpr".into(), "false".into()),
                    ];
                }
                let id = if is_owner { ids.action.get(&up).copied() } else { None };
                let id = id.unwrap_or_else(|| {
                    next_id += 1;
                    next_id - 1
                });
                set(&mut aat, "ID", id.to_string());
                let stored_q =
                    attr(&node.attributes, "sfc.logix.qualifier").filter(|q| qualifier_of(q) == Some(a.qualifier));
                let written_q = aat
                    .iter()
                    .find(|(k, _)| k == "Qualifier")
                    .map(|(_, v)| v.clone())
                    .filter(|q| qualifier_of(q) == Some(a.qualifier));
                let q = if is_owner { stored_q.or(written_q) } else { None }
                    .unwrap_or_else(|| long_qualifier(a.qualifier).to_string());
                set(&mut aat, "Qualifier", q);
                let boolean = attr(&node.attributes, "sfc.logix.boolean").is_some();
                let preset_expr = attr(&node.attributes, "sfc.logix.preset_expr");
                match &a.duration {
                    Some(Duration::Literal(us)) => {
                        if us % 1000 != 0 {
                            self.error(a.span, format!("the duration of `{}` is not whole milliseconds", a.action));
                        }
                        if preset_expr.is_none() {
                            let ms = us / 1000;
                            if action_pre.get(&up).is_some_and(|p| *p != ms) {
                                self.error(
                                    a.span,
                                    format!(
                                        "`{}` is associated with two durations (one SFC_ACTION tag, one preset)",
                                        a.action
                                    ),
                                );
                            }
                            action_pre.insert(up.clone(), ms);
                        }
                    }
                    Some(Duration::Variable(v)) => match self.constant_time(&pou, c, v) {
                        Some(ms) if preset_expr.is_none() => {
                            action_pre.insert(up.clone(), ms);
                        }
                        _ => self.error(a.span, format!("the duration `{v}` of `{}`, a variable the chart writes (a preset expression the round trip and the `logix` profile do not keep)", a.action)),
                    },
                    None => {}
                }
                if a.qualifier == Qualifier::P && !logix {
                    self.warn(a.span, &s.name, format!("`{}(P)` executes when {} is activated and again when it is left, on Logix", a.action, s.name), "IEC's P executes in the scan its step is entered and once more (its final run, Q FALSE) in the next scan; Logix's P executes once on activation and once on deactivation");
                }
                let dont_scan = c.logix.last_scan != LastScan::ProgrammaticReset;
                if !logix && source.final_run && dont_scan && matches!(a.qualifier, Qualifier::N | Qualifier::L | Qualifier::D) {
                    let note = format!("{} runs an action once more, with Q FALSE, after it stops (its final run); a Logix controller set to \"Don't scan\" (Studio 5000's default) executes only P and P0 actions in a step's last scan: clear what the action set in a P0 action, or choose \"Programmatic reset\" (`sfc.logix.lastscan`)", source.name);
                    self.warn(a.span, &s.name, format!("`{}` does not execute again when it stops, on Logix ({})", a.action, c.logix.last_scan.name()), &note);
                }
                set(&mut aat, "IsBoolean", if boolean { "true" } else { "false" }.into());
                set(&mut aat, "PresetUsesExpr", if preset_expr.is_some() { "true" } else { "false" }.into());
                inner.push_str(&format!("<Action{}>\n", start_attrs(&aat, &a.action)));
                if let Some(e) = &preset_expr {
                    inner.push_str(&format!("<Preset>\n{}</Preset>\n", st_content(std::slice::from_ref(e))));
                }
                let reset_of_stored = a.qualifier == Qualifier::R;
                if is_owner && !boolean && !reset_of_stored {
                    let lines = match &node.body {
                        ast::ActionBody::St(_) => {
                            let nra: HashSet<usize> = attr(&node.attributes, "sfc.logix.nra")
                                .unwrap_or_default()
                                .split(',')
                                .filter_map(|v| v.trim().parse().ok())
                                .collect();
                            self.body_lines(node, logix)
                                .iter()
                                .enumerate()
                                .map(|(i, l)| {
                                    let l = to_logix(l, &el, c, self, node.name_span);
                                    if nra.contains(&i) {
                                        nra_line(&l)
                                    } else {
                                        l
                                    }
                                })
                                .collect()
                        }
                        _ => {
                            self.error(node.name_span, format!("the action `{}` is not written in ST", node.name));
                            Vec::new()
                        }
                    };
                    inner.push_str(&format!("<Body>\n{}</Body>\n", st_content(&lines)));
                }
                inner.push_str("</Action>\n");
                if is_owner || !tags.iter().any(|(n, _)| n.eq_ignore_ascii_case(&a.action)) {
                    let pre = action_pre.get(&up).copied().unwrap_or(0);
                    let kept = attr(&node.attributes, "sfc.logix.tag");
                    let desc = attr(&node.attributes, "sfc.description");
                    tags.retain(|(n, _)| !n.eq_ignore_ascii_case(&a.action));
                    tags.push((
                        node.name.clone(),
                        tag_xml(
                            &node.name,
                            "SFC_ACTION",
                            desc.as_deref(),
                            &sfc_tag_data("SFC_ACTION", pre, kept.as_deref()),
                        ),
                    ));
                }
            }
            if inner.is_empty() {
                content.push_str("/>\n");
            } else {
                content.push_str(">\n");
                content.push_str(&inner);
                content.push_str(&format!("</{kind}>\n"));
            }
        }
        for a in &c.actions {
            if !owner.contains_key(&a.name.to_ascii_uppercase()) {
                self.error(
                    a.name_span,
                    format!("the action `{}` is associated with no step (a Logix action belongs to a step)", a.name),
                );
            }
        }
        // Transitions.
        for (ti, t) in c.transitions.iter().enumerate() {
            let mut at = parse_attrs(&attr(&t.attributes, "sfc.logix.attrs").unwrap_or_default());
            if !ids.kept || at.is_empty() {
                let (x, y) = layout.trans.get(ti).copied().unwrap_or((200, 220));
                at = vec![
                    ("ID".into(), String::new()),
                    ("X".into(), x.to_string()),
                    ("Y".into(), y.to_string()),
                    ("HideDesc".into(), "false".into()),
                    ("DescX".into(), (x + 60).to_string()),
                    ("DescY".into(), (y - 20).to_string()),
                    ("DescWidth".into(), "0".into()),
                ];
            }
            if let Some(id) = ids.trans.get(ti) {
                set(&mut at, "ID", id.to_string());
            }
            if ids.kept {
                for (k, key) in [("X", "sfc.x"), ("Y", "sfc.y")] {
                    if let Some(v) = attr(&t.attributes, key) {
                        set(&mut at, k, v);
                    }
                }
            }
            let lines = match &t.condition {
                ast::Condition::St(_) => {
                    let text = self.condition_text(t).unwrap_or_default();
                    match attr(&t.attributes, "sfc.logix.lines") {
                        Some(l) if import_condition(&l, &el) == text => l.split('\n').map(str::to_string).collect(),
                        _ => to_logix(&text, &el, c, self, t.header_span)
                            .split('\n')
                            .map(str::to_string)
                            .collect::<Vec<_>>(),
                    }
                }
                _ => {
                    self.error(t.header_span, format!("the condition of `{}` is not ST", t.name));
                    Vec::new()
                }
            };
            if !source.first_call_tests && t.from.iter().all(|&s| c.steps.get(s).is_some_and(|s| s.initial)) {
                let literal_false = matches!(&t.condition, ast::Condition::St(e) if self.text(e.span).trim().eq_ignore_ascii_case("FALSE"));
                if !literal_false {
                    let note = format!("{} tests no transition in its first scan; a Logix controller executes the initial step and then tests its transitions in the same first call", source.name);
                    self.warn(t.header_span, &t.name, format!("{} is already tested in the first call on Logix", t.name), &note);
                }
            }
            content.push_str(&format!(
                "<Transition{}>\n<Condition>\n{}</Condition>\n</Transition>\n",
                start_attrs(&at, &t.name),
                st_content(&lines)
            ));
            tags.push((t.name.clone(), tag_xml(&t.name, "BOOL", attr(&t.attributes, "sfc.description").as_deref(), &(l5k("0") + "<Data Format=\"Decorated\">\n<DataValue DataType=\"BOOL\" Radix=\"Decimal\" Value=\"0\"/>\n</Data>\n"))));
        }
        // Branches and text boxes (in the order the import met them), then the links.
        if ids.kept {
            for a in &pa.iter().collect::<Vec<_>>() {
                let v = a.value.as_deref().map(unescape).unwrap_or_default();
                match a.name.as_str() {
                    "sfc.logix.branch" => content.push_str(&branch_xml(&v)),
                    "sfc.logix.textbox" | "sfc.logix.attachment" | "sfc.logix.sbrret" => {
                        content.push_str(&v);
                        content.push('\n');
                    }
                    _ => {}
                }
            }
            for l in attr(pa, "sfc.logix.links").unwrap_or_default().split(',').filter(|l| !l.is_empty()) {
                let hidden = l.ends_with('h');
                let (f, t) = l.trim_end_matches('h').split_once('>').unwrap_or(("", ""));
                content.push_str(&format!("<DirectedLink FromID=\"{f}\" ToID=\"{t}\" Show=\"{}\"/>\n", !hidden));
            }
        } else {
            content.push_str(&ids.branches);
            // Text boxes last, with IDs after every other element's (Studio's order).
            for (next, tb) in (ids.next..).zip(all_attrs(pa, "sfc.logix.textbox")) {
                let tb = match tb
                    .find(" ID=\"")
                    .and_then(|i| tb.get(i + 5..).and_then(|r| r.find('"')).map(|e| (i, i + 5 + e)))
                {
                    Some((a, z)) => format!("{} ID=\"{next}{}", tb.get(..a).unwrap_or(""), tb.get(z..).unwrap_or("")),
                    None => tb,
                };
                content.push_str(&tb);
                content.push('\n');
            }
            for (f, t) in &ids.links {
                content.push_str(&format!("<DirectedLink FromID=\"{f}\" ToID=\"{t}\" Show=\"true\"/>\n"));
            }
        }
        content.push_str("</SFCContent>\n");
        xml.push_str(&content);
        xml.push_str("</Routine>\n");
        if self.errors.len() > n_err {
            return None;
        }
        let main = attr(pa, "sfc.logix.main").is_some() || !logix;
        Some(Routine { program, routine, main, tags, vars, xml })
    }

    /// The initial value in ms of a TIME variable of the POU that nothing in the chart writes
    /// (a duration named by a variable is written as its value).
    fn constant_time(&self, pou: &ast::Pou, c: &Chart, name: &str) -> Option<i64> {
        let d = pou
            .var_blocks
            .iter()
            .filter(|b| matches!(b.kind, ast::VarKind::Var))
            .flat_map(|b| &b.decls)
            .find(|d| d.names.iter().any(|n| n.is(name)))?;
        let Some(ast::Initializer::Expr(e)) = &d.init else { return None };
        let ms = duration_ms(self.text(e.span).trim())?;
        for a in &c.actions {
            let body = self.text(a.span);
            let toks = st::tokens(body);
            let sig: Vec<&str> = toks
                .iter()
                .filter(|t| !matches!(t.kind, Tok::Space | Tok::Comment))
                .filter_map(|t| body.get(t.range.clone()))
                .collect();
            if sig.windows(2).any(|w| matches!(w, [n, ":="] if n.eq_ignore_ascii_case(name))) {
                return None;
            }
        }
        Some(ms)
    }

    /// The IDs of the chart's elements: the stored ones when they still fit the text, else
    /// fresh ones (with branches and links).
    fn ids(&self, c: &Chart, layout: &Layout) -> Ids {
        let pa = self.pou(c).map(|p| p.attributes.as_slice()).unwrap_or_default();
        if let Some(ids) = stored_ids(c, pa).filter(|ids| links_fit(c, pa, ids)) {
            return ids;
        }
        fresh_ids(c, layout)
    }
}

/// The start tag's attributes with `Operand` after `Y` (or `ID`), as Studio writes them; a
/// step's long tag wraps before `LimitLowUsesExpr`.
fn start_attrs(at: &[(String, String)], operand: &str) -> String {
    let mut o = String::new();
    let after = if at.iter().any(|(k, _)| k == "Y") { "Y" } else { "ID" };
    let mut placed = false;
    for (k, v) in at {
        if k == "LimitLowUsesExpr" {
            o.push('\n');
        }
        o.push_str(&format!(" {k}=\"{}\"", esc(v)));
        if k == after {
            o.push_str(&format!(" Operand=\"{}\"", esc(operand)));
            placed = true;
        }
    }
    if !placed {
        o.push_str(&format!(" Operand=\"{}\"", esc(operand)));
    }
    o
}

fn branch_xml(v: &str) -> String {
    let p: Vec<&str> = v.split(';').collect();
    let g = |i: usize| p.get(i).copied().unwrap_or("");
    let mut o = format!("<Branch ID=\"{}\"", esc(g(0)));
    if !g(1).is_empty() {
        o.push_str(&format!(" Y=\"{}\"", esc(g(1))));
    }
    o.push_str(&format!(" BranchType=\"{}\" BranchFlow=\"{}\"", esc(g(2)), esc(g(3))));
    if !g(4).is_empty() {
        o.push_str(&format!(" Priority=\"{}\"", esc(g(4))));
    }
    o.push_str(">\n");
    for l in g(5).split(',').filter(|l| !l.is_empty()) {
        o.push_str(&format!("<Leg ID=\"{}\"/>\n", esc(l)));
    }
    o.push_str("</Branch>\n");
    o
}

/// A line with its `:=` written as `[:=]` (the import kept which lines had one).
fn nra_line(l: &str) -> String {
    let mut o = String::new();
    for t in st::tokens(l) {
        let s = l.get(t.range.clone()).unwrap_or("");
        if t.kind == Tok::Assign {
            o.push_str("[:=]");
        } else {
            o.push_str(s);
        }
    }
    o
}

/// What the ST mapping of the import needs to know of the chart.
fn elements(c: &Chart) -> Elements {
    let mut el = Elements::default();
    for s in &c.steps {
        let up = s.name.to_ascii_uppercase();
        if attr(&s.attributes, "sfc.logix.stop").is_some() {
            el.stops.insert(up, s.name.clone());
            continue;
        }
        let pre = attr(&s.attributes, "sfc.logix.preset").and_then(|p| p.parse().ok()).unwrap_or(0);
        let pre_expr = attr(&s.attributes, "sfc.logix.preset_expr")
            .map(|e| st::map(&XText::synthetic(e.trim(), 0..0), &Elements::default()).frag);
        el.steps.insert(up, StepInfo { name: s.name.clone(), pre: Some(pre), pre_expr });
    }
    for a in &c.actions {
        el.actions.insert(a.name.to_ascii_uppercase(), a.name.clone());
    }
    el
}

/// The condition the import makes of Logix lines (as `chart::condition` does).
fn import_condition(lines: &str, el: &Elements) -> String {
    let trimmed = lines.trim();
    let toks = st::tokens(trimmed);
    let last = toks.iter().rev().find(|t| !matches!(t.kind, Tok::Space | Tok::Comment));
    let text = match last.filter(|t| trimmed.get(t.range.clone()) == Some(";")) {
        Some(t) => {
            format!("{} {}", trimmed.get(..t.range.start).unwrap_or(""), trimmed.get(t.range.end..).unwrap_or(""))
        }
        None => trimmed.to_string(),
    };
    st::map(&XText::synthetic(text.trim(), 0..0), el).frag.text.trim().to_string()
}

/// IEC ST → Logix ST: `TIME_TO_DINT(S.T)` → `S.T`, `(S.T >= T#<preset>ms)` → `S.DN`, TIME
/// literals → DINT milliseconds. Everything else is copied.
fn to_logix(src: &str, el: &Elements, _c: &Chart, ex: &mut Ex, at: Span) -> String {
    let toks = st::tokens(src);
    let sig: Vec<(usize, &str, Tok)> = toks
        .iter()
        .enumerate()
        .filter(|(_, t)| !matches!(t.kind, Tok::Space | Tok::Comment))
        .map(|(i, t)| (i, src.get(t.range.clone()).unwrap_or(""), t.kind))
        .collect();
    let mut out = String::new();
    let mut skip_to: Option<usize> = None;
    for (i, t) in toks.iter().enumerate() {
        if skip_to.is_some_and(|s| i <= s) {
            continue;
        }
        let s = src.get(t.range.clone()).unwrap_or("");
        let pos = sig.iter().position(|(j, _, _)| *j == i);
        let w = |k: usize| pos.and_then(|p| sig.get(p + k)).map_or("", |x| x.1);
        let idx = |k: usize| pos.and_then(|p| sig.get(p + k)).map_or(i, |x| x.0);
        if t.kind == Tok::Ident
            && s.eq_ignore_ascii_case("TIME_TO_DINT")
            && w(1) == "("
            && w(3) == "."
            && w(4).eq_ignore_ascii_case("T")
            && w(5) == ")"
            && el.steps.contains_key(&w(2).to_ascii_uppercase())
        {
            out.push_str(&format!("{}.T", w(2)));
            skip_to = Some(idx(5));
            continue;
        }
        if s == "(" && w(2) == "." && w(3).eq_ignore_ascii_case("T") && w(4) == ">" && w(5) == "=" && w(7) == ")" {
            if let Some(si) = el.steps.get(&w(1).to_ascii_uppercase()) {
                let lit = w(6);
                if si.pre_expr.is_none() && lit.eq_ignore_ascii_case(&format!("T#{}ms", si.pre.unwrap_or(0))) {
                    out.push_str(&format!("{}.DN", w(1)));
                    skip_to = Some(idx(7));
                    continue;
                }
            }
        }
        // The timer's overflow, as the import writes it.
        if s == "(" && w(2) == "." && w(3).eq_ignore_ascii_case("T") && w(4) == ">" && w(6) == ")" {
            if el.steps.contains_key(&w(1).to_ascii_uppercase())
                && w(5).eq_ignore_ascii_case(&format!("T#{}ms", crate::st::OV_MS))
            {
                out.push_str(&format!("{}.OV", w(1)));
                skip_to = Some(idx(6));
                continue;
            }
        }
        if t.kind == Tok::Number && s.contains('#') {
            let (k, _) = s.split_once('#').unwrap_or(("", ""));
            let k = k.to_ascii_uppercase();
            if matches!(k.as_str(), "T" | "TIME" | "LT" | "LTIME") {
                match duration_ms(s) {
                    Some(ms) => out.push_str(&ms.to_string()),
                    None => {
                        ex.error(at, format!("the duration `{s}` is not whole milliseconds"));
                        out.push_str(s);
                    }
                }
                continue;
            }
        }
        out.push_str(s);
    }
    out
}

/// IDs and, for fresh ones, the branches and links.
#[derive(Default)]
struct Ids {
    kept: bool,
    step: Vec<u64>,
    trans: Vec<u64>,
    /// The first association's action ID, by upper name.
    action: HashMap<String, u64>,
    next: u64,
    branches: String,
    links: Vec<(u64, u64)>,
}

fn id_in(list: &[ast::Attribute]) -> Option<u64> {
    parse_attrs(&attr(list, "sfc.logix.attrs")?).into_iter().find(|(k, _)| k == "ID").and_then(|(_, v)| v.parse().ok())
}

/// The stored IDs, when every element has one and the stored links and branches still draw the
/// text's FROM/TO.
fn stored_ids(c: &Chart, pa: &[ast::Attribute]) -> Option<Ids> {
    c.steps.first()?;
    let mut ids = Ids { kept: true, ..Ids::default() };
    let mut used = HashSet::new();
    for s in &c.steps {
        let id = id_in(&s.attributes)?;
        ids.step.push(id);
        // Two elements with one ID (a copy in the editor): fresh IDs.
        if !used.insert(id) {
            return None;
        }
    }
    for t in &c.transitions {
        let id = id_in(&t.attributes)?;
        ids.trans.push(id);
        if !used.insert(id) {
            return None;
        }
    }
    for a in &c.actions {
        let id = id_in(&a.attributes)?;
        ids.action.insert(a.name.to_ascii_uppercase(), id);
        if !used.insert(id) {
            return None;
        }
    }
    // IDs past every one the routine holds (branches, legs, text boxes too) for the actions of
    // second associations.
    let mut max = used.iter().max().copied().unwrap_or(0);
    for key in ["sfc.logix.branch", "sfc.logix.links", "sfc.logix.textbox", "sfc.logix.attachment", "sfc.logix.sbrret"]
    {
        for v in all_attrs(pa, key) {
            for n in v.split(|ch: char| !ch.is_ascii_digit()).filter_map(|n| n.parse::<u64>().ok()) {
                if n < 1 << 32 {
                    max = max.max(n);
                }
            }
        }
    }
    ids.next = max + 1;
    Some(ids)
}

/// Checks the stored links of the POU against the chart's topology.
fn links_fit(c: &Chart, pa: &[ast::Attribute], ids: &Ids) -> bool {
    let Some(links) = attr(pa, "sfc.logix.links") else { return false };
    let mut succ: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    let mut pred: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    for l in links.split(',').filter(|l| !l.is_empty()) {
        let Some((f, t)) = l.trim_end_matches('h').split_once('>') else { return false };
        let (Ok(f), Ok(t)) = (f.parse::<u64>(), t.parse::<u64>()) else { return false };
        succ.entry(f).or_default().push(t);
        pred.entry(t).or_default().push(f);
    }
    let mut junction = HashSet::new();
    for b in all_attrs(pa, "sfc.logix.branch") {
        let p: Vec<&str> = b.split(';').collect();
        let Some(id) = p.first().and_then(|v| v.parse::<u64>().ok()) else { return false };
        let diverge = p.get(3).copied() != Some("Converge");
        junction.insert(id);
        for l in p.get(5).copied().unwrap_or("").split(',').filter_map(|v| v.parse::<u64>().ok()) {
            junction.insert(l);
            let (a, z) = if diverge { (id, l) } else { (l, id) };
            succ.entry(a).or_default().push(z);
            pred.entry(z).or_default().push(a);
        }
    }
    let step_of: HashMap<u64, usize> = ids.step.iter().enumerate().map(|(i, id)| (*id, i)).collect();
    // Every link between elements the chart still has.
    let known = |v: &u64| junction.contains(v) || ids.step.contains(v) || ids.trans.contains(v);
    if !succ.iter().all(|(f, ts)| known(f) && ts.iter().all(known)) {
        return false;
    }
    let walk = |id: u64, edges: &BTreeMap<u64, Vec<u64>>| -> Vec<usize> {
        let mut found = Vec::new();
        let mut seen = HashSet::new();
        let mut stack: Vec<u64> = edges.get(&id).cloned().unwrap_or_default();
        while let Some(v) = stack.pop() {
            if !seen.insert(v) || seen.len() > 100_000 {
                continue;
            }
            if junction.contains(&v) {
                stack.extend(edges.get(&v).into_iter().flatten());
            } else if let Some(s) = step_of.get(&v) {
                found.push(*s);
            }
        }
        found.sort_unstable();
        found
    };
    c.transitions.iter().zip(&ids.trans).all(|(t, id)| {
        let mut from = t.from.clone();
        let mut to = t.to.clone();
        from.sort_unstable();
        to.sort_unstable();
        walk(*id, &pred) == from && walk(*id, &succ) == to
    })
}

/// Fresh IDs in Studio's canonical order: steps (by name) each followed by its actions, then
/// transitions (by name), then branches each followed by its legs, then stops; links from the
/// chart's FROM/TO.
fn fresh_ids(c: &Chart, layout: &Layout) -> Ids {
    let mut ids =
        Ids { kept: false, step: vec![0; c.steps.len()], trans: vec![0; c.transitions.len()], ..Ids::default() };
    let mut next = 0u64;
    let is_stop = |s: &sfc_model::StepNode| attr(&s.attributes, "sfc.logix.stop").is_some();
    let mut order: Vec<usize> = (0..c.steps.len()).filter(|&i| c.steps.get(i).is_some_and(|s| !is_stop(s))).collect();
    order.sort_by_key(|&i| c.steps.get(i).map(|s| s.name.to_ascii_uppercase()));
    let mut action_ids: Vec<(String, u64)> = Vec::new();
    for &i in &order {
        if let Some(s) = ids.step.get_mut(i) {
            *s = next;
        }
        next += 1;
        for a in c.steps.get(i).map(|s| s.associations.as_slice()).unwrap_or_default() {
            let up = a.action.to_ascii_uppercase();
            if !ids.action.contains_key(&up) {
                ids.action.insert(up.clone(), next);
                action_ids.push((up, next));
                next += 1;
            } else {
                // Later associations take IDs after every element (see `next`).
            }
        }
    }
    let mut torder: Vec<usize> = (0..c.transitions.len()).collect();
    torder.sort_by_key(|&i| c.transitions.get(i).map(|t| t.name.to_ascii_uppercase()));
    for &i in &torder {
        if let Some(t) = ids.trans.get_mut(i) {
            *t = next;
        }
        next += 1;
    }
    // Branches: selection divergences (a step with several outgoing transitions), selection
    // convergences (several incoming), simultaneous divergences (a transition to several
    // steps), simultaneous convergences (from several).
    let n = c.steps.len();
    let outgoing: Vec<Vec<usize>> = (0..n)
        .map(|s| {
            let mut v = c.outgoing(s);
            v.sort_by_key(|&t| (c.transitions.get(t).and_then(|t| t.priority).unwrap_or(0), t));
            v
        })
        .collect();
    let incoming: Vec<Vec<usize>> = (0..n).map(|s| c.incoming(s)).collect();
    let mut branches = String::new();
    // (branch kind, owner) → legs by partner
    let mut leg: HashMap<(u8, usize, usize), u64> = HashMap::new();
    let mut bid: HashMap<(u8, usize), u64> = HashMap::new();
    let add = |kind: u8,
               y: i64,
               owner: usize,
               partners: &[usize],
               next: &mut u64,
               branches: &mut String,
               leg: &mut HashMap<(u8, usize, usize), u64>,
               bid: &mut HashMap<(u8, usize), u64>| {
        let (bt, bf) = match kind {
            0 => ("Selection", "Diverge"),
            1 => ("Selection", "Converge"),
            2 => ("Simultaneous", "Diverge"),
            _ => ("Simultaneous", "Converge"),
        };
        let id = *next;
        *next += 1;
        bid.insert((kind, owner), id);
        let prio = if kind == 0 { " Priority=\"Default\"" } else { "" };
        branches.push_str(&format!("<Branch ID=\"{id}\" Y=\"{y}\" BranchType=\"{bt}\" BranchFlow=\"{bf}\"{prio}>\n"));
        for &p in partners {
            branches.push_str(&format!("<Leg ID=\"{}\"/>\n", *next));
            leg.insert((kind, owner, p), *next);
            *next += 1;
        }
        branches.push_str("</Branch>\n");
    };
    for s in 0..n {
        if let Some(o) = outgoing.get(s).filter(|o| o.len() > 1) {
            let y = layout.step.get(s).map_or(0, |p| p.1) + 60;
            add(0, y, s, o, &mut next, &mut branches, &mut leg, &mut bid);
        }
        if let Some(o) = incoming.get(s).filter(|o| o.len() > 1) {
            let y = layout.step.get(s).map_or(0, |p| p.1) - 60;
            add(1, y, s, o, &mut next, &mut branches, &mut leg, &mut bid);
        }
    }
    for (ti, t) in c.transitions.iter().enumerate() {
        if t.to.len() > 1 {
            let y = layout.trans.get(ti).map_or(0, |p| p.1) + 60;
            add(2, y, ti, &t.to, &mut next, &mut branches, &mut leg, &mut bid);
        }
        if t.from.len() > 1 {
            let y = layout.trans.get(ti).map_or(0, |p| p.1) - 60;
            add(3, y, ti, &t.from, &mut next, &mut branches, &mut leg, &mut bid);
        }
    }
    for (i, s) in c.steps.iter().enumerate() {
        if is_stop(s) {
            if let Some(x) = ids.step.get_mut(i) {
                *x = next;
            }
            next += 1;
        }
    }
    let step_id = |s: usize| ids.step.get(s).copied().unwrap_or(0);
    let trans_id = |t: usize| ids.trans.get(t).copied().unwrap_or(0);
    let mut links = Vec::new();
    for (ti, t) in c.transitions.iter().enumerate() {
        for &s in &t.from {
            let src = if outgoing.get(s).is_some_and(|o| o.len() > 1) {
                leg.get(&(0, s, ti)).copied().unwrap_or(0)
            } else {
                step_id(s)
            };
            let dst = if t.from.len() > 1 { leg.get(&(3, ti, s)).copied().unwrap_or(0) } else { trans_id(ti) };
            links.push((src, dst));
        }
        for &s in &t.to {
            let src = if t.to.len() > 1 { leg.get(&(2, ti, s)).copied().unwrap_or(0) } else { trans_id(ti) };
            let dst = if incoming.get(s).is_some_and(|o| o.len() > 1) {
                leg.get(&(1, s, ti)).copied().unwrap_or(0)
            } else {
                step_id(s)
            };
            links.push((src, dst));
        }
        if let Some(b) = bid.get(&(2, ti)) {
            links.push((trans_id(ti), *b));
        }
        if let Some(b) = bid.get(&(3, ti)) {
            links.push((*b, trans_id(ti)));
        }
    }
    for s in 0..n {
        if let Some(b) = bid.get(&(0, s)) {
            links.push((step_id(s), *b));
        }
        if let Some(b) = bid.get(&(1, s)) {
            links.push((*b, step_id(s)));
        }
    }
    links.sort_unstable();
    links.dedup();
    ids.branches = branches;
    ids.links = links;
    ids.next = next;
    ids
}

/// Positions: the stored ones when every step and transition has `sfc.x`/`sfc.y`, else a
/// top-down layout on a 20-unit grid (steps by depth from the initial steps, transitions below
/// their steps, the branches of a selection side by side in priority order).
struct Layout {
    step: Vec<(i64, i64)>,
    trans: Vec<(i64, i64)>,
}

fn layout(c: &Chart) -> Layout {
    let pos = |a: &[ast::Attribute]| -> Option<(i64, i64)> {
        let x = attr(a, "sfc.x")?.trim().parse::<f64>().ok()?;
        let y = attr(a, "sfc.y")?.trim().parse::<f64>().ok()?;
        Some((x.round() as i64, y.round() as i64))
    };
    let sp: Option<Vec<_>> = c.steps.iter().map(|s| pos(&s.attributes)).collect();
    let tp: Option<Vec<_>> = c.transitions.iter().map(|t| pos(&t.attributes)).collect();
    if let (Some(step), Some(trans)) = (sp, tp) {
        return Layout { step, trans };
    }
    let n = c.steps.len();
    let mut depth: Vec<Option<usize>> = vec![None; n];
    let mut col: Vec<i64> = vec![0; n];
    let mut queue: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
    let mut next_col = 0i64;
    for (i, s) in c.steps.iter().enumerate() {
        if s.initial {
            if let Some(d) = depth.get_mut(i) {
                *d = Some(0);
            }
            if let Some(x) = col.get_mut(i) {
                *x = next_col;
            }
            next_col += 1;
            queue.push_back(i);
        }
    }
    loop {
        while let Some(s) = queue.pop_front() {
            let d = depth.get(s).copied().flatten().unwrap_or(0);
            let base = col.get(s).copied().unwrap_or(0);
            let mut out = c.outgoing(s);
            out.sort_by_key(|&t| (c.transitions.get(t).and_then(|t| t.priority).unwrap_or(0), t));
            let mut k = 0i64;
            for t in out {
                for &z in c.transitions.get(t).map(|t| t.to.as_slice()).unwrap_or_default() {
                    if depth.get(z).copied().flatten().is_none() {
                        if let Some(dz) = depth.get_mut(z) {
                            *dz = Some(d + 1);
                        }
                        if let Some(x) = col.get_mut(z) {
                            *x = base + k;
                        }
                        k += 1;
                        queue.push_back(z);
                    }
                }
            }
        }
        // Steps not reached from an initial step: a column of their own.
        match depth.iter().position(Option::is_none) {
            Some(i) => {
                if let Some(d) = depth.get_mut(i) {
                    *d = Some(0);
                }
                next_col = col.iter().max().copied().unwrap_or(0) + 1;
                if let Some(x) = col.get_mut(i) {
                    *x = next_col;
                }
                queue.push_back(i);
            }
            None => break,
        }
    }
    let step: Vec<(i64, i64)> = (0..n)
        .map(|i| {
            (
                200 + 300 * col.get(i).copied().unwrap_or(0),
                100 + 240 * depth.get(i).copied().flatten().unwrap_or(0) as i64,
            )
        })
        .collect();
    let trans = c
        .transitions
        .iter()
        .map(|t| {
            let from: Vec<(i64, i64)> = t.from.iter().filter_map(|&s| step.get(s).copied()).collect();
            let to: Vec<(i64, i64)> = t.to.iter().filter_map(|&s| step.get(s).copied()).collect();
            let y = from.iter().map(|p| p.1).max().unwrap_or(100) + 120;
            // Under the step it leads to when that is beside its step (a selection's legs).
            let x = match (from.first(), to.first()) {
                (Some(f), Some(z)) if t.to.len() == 1 && t.from.len() == 1 && z.1 > f.1 => z.0,
                (Some(f), _) => f.0,
                _ => 200,
            };
            (x, y)
        })
        .collect();
    Layout { step, trans }
}
