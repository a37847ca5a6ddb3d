//! A checked chart file → a SimaticML document holding each chart as an S7-GRAPH function block
//! (`sfc build --target simaticml`, `docs/targets.md`, "simaticml").
//!
//! The inverse of the import: what the import keeps in `sfc.s7graph.*` attributes (numbers,
//! GRAPH names, block properties, the branch pins and jumps, the action rows with their tokens,
//! interlocks, supervisions, permanent instructions, event actions) is written back, so
//! `import(export(import(x)))` is `import(x)`. A chart written in IEC text gets numbers in
//! declaration order, branches from its divergences and jumps for its transitions back, and
//! action rows for the associations GRAPH can hold; what GRAPH cannot hold is an error (SFC0830,
//! nothing written), what it runs differently a warning (SFC0831). `xml.rs` writes the XML,
//! `net.rs` the LAD networks, `chart.rs` the sequences.

mod chart;
mod net;
mod xml;

use net::Operands;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::{Chart, Checked};
use sfc_syntax::ast::{self, Attribute, Initializer, Item, TypeSpecKind, VarKind};
use std::collections::HashMap;
use xml::W;

/// An attribute's value, unescaped.
pub(crate) fn attr(attrs: &[Attribute], key: &str) -> Option<String> {
    attrs
        .iter()
        .rev()
        .find(|a| a.name.eq_ignore_ascii_case(key))
        .map(|a| sfc_syntax::attr_value::unescape(a.value.as_deref().unwrap_or("")))
}

/// What one export collects.
pub(crate) struct Out {
    pub errors: Vec<Diagnostic>,
    pub notes: Vec<Diagnostic>,
    /// The rules the chart being written was made for (its POU's `sfc.dialect`): a behaviour
    /// warning says only what S7-GRAPH changes against them.
    pub source: sfc_model::RunRules,
}

impl Out {
    pub fn error(&mut self, at: Span, msg: impl Into<String>) {
        self.errors.push(Diagnostic::error("SFC0830", at, msg));
    }
    pub fn warn(&mut self, at: Span, msg: impl Into<String>) {
        self.notes.push(Diagnostic::warning("SFC0831", at, msg));
    }
}

/// Writes the charts of `checked` (only `pou` when given) as a SimaticML document holding each chart as an S7-GRAPH function block; the notes say what changed
/// on the way, the error what the format cannot express (located in the checked text).
pub fn export(checked: &Checked, pou: Option<&str>) -> Result<(String, Vec<Diagnostic>), Vec<Diagnostic>> {
    // sfc's supervision (sfc.timeout, SFCError, SFCQuitError) becomes permanent instructions.
    let note = |c: &Chart, steps: &str| {
        let mut d = Diagnostic::warning(
            "SFC0831",
            c.name_span,
            format!("the maximum time (sfc.timeout) of {steps} is written as permanent instructions: S7-GRAPH has no SFCError"),
        );
        d.notes.push(
            "before the sequencer `SFCQuitError` clears `SFCError`; after it, a step active longer than its time sets `SFCError` once per activation (flags `<Step>_Overdue`), as sfc does; `SFCErrorStep` is not written. GRAPH's own supervision (T_MAX) would hold the step instead".into(),
        );
        d
    };
    sfc_model::supervision::export_lowered(checked, sfc_model::supervision::Style::Permanent, pou, note, |c, notes| {
        write(c, pou, notes)
    })
}

fn write(
    checked: &Checked,
    pou: Option<&str>,
    notes: Vec<Diagnostic>,
) -> Result<(String, Vec<Diagnostic>), Vec<Diagnostic>> {
    let mut out = Out {
        errors: Vec::new(),
        notes,
        source: sfc_model::RunRules { name: "IEC 61131-3", final_run: true, first_call_tests: false, actions_first: false },
    };
    let charts: Vec<&Chart> =
        checked.charts.iter().filter(|c| pou.is_none_or(|p| c.pou.eq_ignore_ascii_case(p))).collect();
    if charts.is_empty() {
        let at = Span::new(checked.unit.span.file, 0, 0);
        let msg = match pou {
            Some(p) => format!("`{p}` is no chart of this file: nothing to write as an S7-GRAPH block"),
            None => "the file holds no chart: nothing to write as an S7-GRAPH block".to_string(),
        };
        return Err(vec![Diagnostic::error("SFC0830", at, msg)]);
    }
    for c in checked.action_charts.iter().filter(|c| charts.iter().any(|x| x.item == c.item)) {
        out.error(
            c.name_span,
            format!(
                "the action `{}` is written in SFC, which an S7-GRAPH block cannot hold (GRAPH actions are rows of instructions)",
                c.action.as_deref().unwrap_or("")
            ),
        );
    }
    if pou.is_none() {
        for (i, item) in checked.unit.items.iter().enumerate() {
            let Item::Pou(p) = item else { continue };
            if !checked.charts.iter().any(|c| c.item == i) {
                let mut d = Diagnostic::error(
                    "SFC0830",
                    p.name.span,
                    format!("`{}` is not a chart: an S7-GRAPH export holds GRAPH blocks only", p.name.text),
                );
                d.notes.push("`--pou NAME` writes one chart of the file".into());
                out.errors.push(d);
            }
        }
    }
    for c in &charts {
        for mut d in sfc_model::vendor::logix_step_counts(checked, c, "an S7-GRAPH block") {
            d.code = "SFC0830".into();
            out.errors.push(d);
        }
    }
    let globals = file_globals(checked);
    let pous: Vec<&ast::Pou> = charts
        .iter()
        .filter_map(|c| match checked.unit.items.get(c.item) {
            Some(Item::Pou(p)) => Some(p),
            _ => None,
        })
        .collect();
    let tia = pous.iter().find_map(|p| attr(&p.attributes, "sfc.s7graph.tia")).unwrap_or_else(|| "V17".into());
    let mut w = W::new();
    w.s.push_str("\u{feff}<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    w.open("Document", &[]);
    w.empty("Engineering", &[("version", tia)]);
    let mut id = 0u32;
    // Block numbers: the kept ones, the others the lowest free ones (TIA numbers FBs uniquely).
    let taken: Vec<String> = pous.iter().filter_map(|p| attr(&p.attributes, "sfc.s7graph.number")).collect();
    let mut free = 0u32;
    for (chart, p) in charts.iter().zip(pous.iter()) {
        let ops = operands(checked, p, chart, &globals);
        let number = attr(&p.attributes, "sfc.s7graph.number").unwrap_or_else(|| loop {
            free += 1;
            if !taken.contains(&free.to_string()) {
                break free.to_string();
            }
        });
        chart::block(&mut w, &mut out, checked, p, chart, &ops, &number, &mut id);
    }
    w.close("Document");
    if out.errors.is_empty() {
        Ok((w.s, out.notes))
    } else {
        out.errors.sort_by_key(|d| (d.span.start, d.span.end));
        Err(out.errors)
    }
}

/// The file's globals (upper-case name → (TIA spelling from the import's comment, type)).
fn file_globals(checked: &Checked) -> HashMap<String, (String, String)> {
    let mut g = HashMap::new();
    for item in &checked.unit.items {
        let Item::Globals(b) = item else { continue };
        for d in &b.decls {
            let ty = type_name(&d.ty);
            let comment = trailing_comment(checked, d.span);
            for n in &d.names {
                let origin =
                    comment.clone().filter(|c| c.starts_with('"')).unwrap_or_else(|| format!("\"{}\"", n.text));
                g.insert(n.text.to_ascii_uppercase(), (origin, ty.clone()));
            }
        }
    }
    g
}

fn operands(checked: &Checked, p: &ast::Pou, chart: &Chart, globals: &HashMap<String, (String, String)>) -> Operands {
    let _ = checked;
    let mut ops = Operands::default();
    for b in &p.var_blocks {
        for d in &b.decls {
            for n in &d.names {
                if b.kind == VarKind::External {
                    // A global: the import's spelling when the file declares it, else a PLC tag.
                    let g = globals
                        .get(&n.text.to_ascii_uppercase())
                        .cloned()
                        .unwrap_or_else(|| (format!("\"{}\"", n.text), type_name(&d.ty)));
                    ops.globals.insert(n.text.to_ascii_uppercase(), g);
                    continue;
                }
                ops.vars.insert(n.text.to_ascii_uppercase(), type_name(&d.ty));
            }
        }
    }
    // Globals the file declares and the POU reads without VAR_EXTERNAL.
    for (k, g) in globals {
        if !ops.vars.contains_key(k) {
            ops.globals.entry(k.clone()).or_insert_with(|| g.clone());
        }
    }
    for s in &chart.steps {
        let raw = attr(&s.attributes, "sfc.s7graph.name").unwrap_or_else(|| s.name.clone());
        ops.steps.insert(s.name.to_ascii_uppercase(), raw);
    }
    for t in &chart.transitions {
        let raw = attr(&t.attributes, "sfc.s7graph.name").unwrap_or_else(|| t.name.clone());
        if let ast::Condition::St(c) = &t.condition {
            ops.tt.push((sfc_syntax::print::expr(c), raw.clone()));
        }
        ops.transitions.insert(t.name.to_ascii_uppercase(), raw);
    }
    ops
}

/// A type's name in upper case (`INT`, `MYSTRUCT`); other kinds as an empty name.
fn type_name(t: &ast::TypeSpec) -> String {
    match &t.kind {
        TypeSpecKind::Named(id) => id.text.to_ascii_uppercase(),
        TypeSpecKind::String { wide, .. } => if *wide { "WSTRING" } else { "STRING" }.into(),
        _ => String::new(),
    }
}

/// The text of the comment after a declaration on its line (`(* … *)`, `// …`), trimmed.
pub(crate) fn trailing_comment(checked: &Checked, span: Span) -> Option<String> {
    let text = &checked.file.text;
    let t = checked.unit.trivia.iter().find(|t| {
        matches!(t.kind, ast::TriviaKind::BlockComment | ast::TriviaKind::LineComment)
            && t.span.start >= span.end
            && text.get(span.end as usize..t.span.start as usize).is_some_and(|between| !between.contains('\n'))
    })?;
    let s = t.text.trim();
    let s = s.strip_prefix("(*").and_then(|s| s.strip_suffix("*)")).or_else(|| s.strip_prefix("//")).unwrap_or(s);
    Some(s.trim().to_string())
}

/// GRAPH's standard parameters, as TIA writes them: (section, name, type, comment).
const STANDARD: &[(&str, &str, &str, &str)] = &[
    ("Input", "OFF_SQ", "Bool", "Turn sequence off"),
    ("Input", "INIT_SQ", "Bool", "Set sequence to initial state"),
    ("Input", "ACK_EF", "Bool", "Acknowledge all errors and faults"),
    ("Input", "S_PREV", "Bool", "Output previous step in parameter S_NO"),
    ("Input", "S_NEXT", "Bool", "Indicate next step in parameter S_NO"),
    ("Input", "SW_AUTO", "Bool", "Automatic mode"),
    ("Input", "SW_TAP", "Bool", "Semiautomatic/switch with transition"),
    ("Input", "SW_TOP", "Bool", "Semiautomatic/ignore transition"),
    ("Input", "SW_MAN", "Bool", "Manual mode"),
    ("Input", "S_SEL", "Int", "Select step to be output to S_NO"),
    ("Input", "S_ON", "Bool", "Activate step indicated in S_NO"),
    ("Input", "S_OFF", "Bool", "Deactivate step indicated in S_NO"),
    ("Input", "T_PUSH", "Bool", "Enable transition to switch in semi automatic mode"),
    ("Output", "S_NO", "Int", "Display step number"),
    ("Output", "S_MORE", "Bool", "Other steps are active"),
    ("Output", "S_ACTIVE", "Bool", "Step indicated in S_NO is active"),
    ("Output", "ERR_FLT", "Bool", "Interlock or supervision group error"),
    ("Output", "AUTO_ON", "Bool", "Automatic mode is active"),
    ("Output", "TAP_ON", "Bool", "Semiautomatic mode with transition is active"),
    ("Output", "TOP_ON", "Bool", "Semiautomatic mode ignoring transition is active"),
    ("Output", "MAN_ON", "Bool", "Manual mode is active"),
];

/// The interface's namespace version for a GRAPH namespace (`v5` → `v4`, as TIA pairs them).
fn interface_ns(graph_ns: &str) -> &'static str {
    match graph_ns {
        "v1" => "v2",
        "v2" | "v3" | "v4" => "v3",
        "v5" => "v4",
        _ => "v5",
    }
}

/// Writes the block interface: the sections of the POU's VAR blocks, GRAPH's standard
/// parameters the POU does not declare, and the system members (RT_DATA, one structure per
/// step and per transition).
#[allow(clippy::too_many_arguments)]
pub(crate) fn interface(
    w: &mut W,
    out: &mut Out,
    checked: &Checked,
    p: &ast::Pou,
    ns: &str,
    gv: &str,
    steps: &[(String, i64, Option<String>, Option<String>)],
    transitions: &[(String, i64)],
) {
    w.open("Interface", &[]);
    w.open(
        "Sections",
        &[("xmlns", format!("http://www.siemens.com/automation/Openness/SW/Interface/{}", interface_ns(ns)))],
    );
    w.open("Section", &[("Name", "Base".into())]);
    w.open("Sections", &[("Datatype", "GRAPH_BASE".into()), ("Version", "1.0".into())]);
    for s in ["Input", "Output", "InOut", "Static"] {
        w.empty("Section", &[("Name", s.into())]);
    }
    w.close("Sections");
    w.close("Section");
    let declared: std::collections::HashSet<String> = p
        .var_blocks
        .iter()
        .flat_map(|b| b.decls.iter().flat_map(|d| d.names.iter().map(|n| n.text.to_ascii_uppercase())))
        .collect();
    let mut added = Vec::new();
    let ver = gv.split('.').next().unwrap_or("6");
    for section in ["Input", "Output", "InOut", "Static", "Temp", "Constant"] {
        let mut body = W::new();
        for (sec, name, ty, comment) in STANDARD {
            if *sec == section && !declared.contains(*name) {
                added.push(*name);
                let start = if *ty == "Bool" { "false" } else { "0" };
                body.open("Member", &[("Name", (*name).into()), ("Datatype", (*ty).into())]);
                body.texts("Comment", comment);
                body.leaf("StartValue", &[], start);
                body.close("Member");
            }
        }
        for b in &p.var_blocks {
            let sec = match (b.kind, b.constant) {
                (VarKind::Input, _) => "Input",
                (VarKind::Output, _) => "Output",
                (VarKind::InOut, _) => "InOut",
                (VarKind::Var, true) => "Constant",
                (VarKind::Var, false) => "Static",
                (VarKind::Temp, _) => "Temp",
                (VarKind::External, _) => continue,
                (k, _) => {
                    if section == "Input" {
                        out.error(
                            b.span,
                            format!("a {} block cannot be written in a GRAPH block's interface", k.keyword()),
                        );
                    }
                    continue;
                }
            };
            if sec != section {
                continue;
            }
            let retain = b.retain == Some(ast::Retain::Retain) && sec == "Static";
            for d in &b.decls {
                member(&mut body, out, checked, d, retain);
            }
        }
        if section == "Static" {
            body.open(
                "Member",
                &[("Name", "RT_DATA".into()), ("Datatype", format!("G7_RTDataPlus_V{ver}")), ("Version", "1.0".into())],
            );
            body.texts("Comment", "Internal data area");
            body.close("Member");
            for (name, no, tmax, twarn) in steps {
                body.open(
                    "Member",
                    &[("Name", name.clone()), ("Datatype", format!("G7_StepPlus_V{ver}")), ("Version", "1.0".into())],
                );
                body.open("Sections", &[]);
                body.open("Section", &[("Name", "None".into())]);
                sys(&mut body, "SNO", "Int", &no.to_string());
                if let Some(t) = tmax {
                    sys(&mut body, "T_MAX", "Time", t);
                }
                if let Some(t) = twarn {
                    sys(&mut body, "T_WARN", "Time", t);
                }
                body.close("Section");
                body.close("Sections");
                body.close("Member");
            }
            for (name, no) in transitions {
                body.open(
                    "Member",
                    &[
                        ("Name", name.clone()),
                        ("Datatype", format!("G7_TransitionPlus_V{ver}")),
                        ("Version", "1.0".into()),
                    ],
                );
                body.open("Sections", &[]);
                body.open("Section", &[("Name", "None".into())]);
                sys(&mut body, "TNO", "Int", &no.to_string());
                body.close("Section");
                body.close("Sections");
                body.close("Member");
            }
        }
        if body.s.is_empty() {
            w.empty("Section", &[("Name", section.into())]);
        } else {
            w.open("Section", &[("Name", section.into())]);
            for line in body.s.lines() {
                w.raw(line);
            }
            w.close("Section");
        }
    }
    w.close("Sections");
    w.close("Interface");
    if !added.is_empty() && attr(&p.attributes, "sfc.dialect").as_deref() != Some("graph") {
        out.notes.push(Diagnostic::warning(
            "SFC0831",
            p.name.span,
            format!("GRAPH's standard parameters are added to the interface: {}", added.join(", ")),
        ));
    }
}

fn sys(w: &mut W, name: &str, ty: &str, v: &str) {
    w.open("Member", &[("Name", name.into()), ("Datatype", ty.into())]);
    w.leaf("StartValue", &[], v);
    w.close("Member");
}

/// The SIMATIC `Datatype` of a type, or an error message. A STRUCT type of the file is written
/// inline (`Struct`, `members` its declarations).
fn datatype<'a>(checked: &'a Checked, t: &ast::TypeSpec) -> Result<(String, Option<&'a [ast::VarDecl]>), String> {
    match &t.kind {
        TypeSpecKind::Named(id) => {
            if let Some(s) = net::simatic_type(&id.text) {
                return Ok((s.into(), None));
            }
            let up = id.text.to_ascii_uppercase();
            let fb = match up.as_str() {
                "TON" | "TOF" | "TP" => Some(format!("{up}_TIME")),
                "CTU" | "CTD" | "CTUD" => Some(format!("{up}_INT")),
                "R_TRIG" | "F_TRIG" => Some(up.clone()),
                _ => None,
            };
            if let Some(f) = fb {
                return Ok((f, None));
            }
            for item in &checked.unit.items {
                let Item::Types(b) = item else { continue };
                for d in &b.decls {
                    if d.name.text.eq_ignore_ascii_case(&id.text) {
                        return match &d.spec.kind {
                            TypeSpecKind::Struct(m) => Ok(("Struct".into(), Some(m.as_slice()))),
                            _ => datatype(checked, &d.spec),
                        };
                    }
                }
            }
            Ok((format!("\"{}\"", id.text), None))
        }
        TypeSpecKind::String { wide, length } => {
            let base = if *wide { "WString" } else { "String" };
            Ok(match length {
                Some(l) => (format!("{base}[{}]", sfc_syntax::print::expr(l)), None),
                None => (base.into(), None),
            })
        }
        TypeSpecKind::Array { ranges, element } => {
            let (e, m) = datatype(checked, element)?;
            if m.is_some() {
                return Err("an array of a structure cannot be written yet".into());
            }
            let dims: Vec<String> = ranges
                .iter()
                .map(|(a, b)| format!("{}..{}", sfc_syntax::print::expr(a), sfc_syntax::print::expr(b)))
                .collect();
            Ok((format!("Array[{}] of {e}", dims.join(", ")), None))
        }
        _ => Err("this kind of type cannot be written in a GRAPH block's interface".into()),
    }
}

fn start_value(e: &ast::Expr) -> String {
    match &e.kind {
        ast::ExprKind::Literal(l) => match l.kind {
            ast::LiteralKind::Bool(b) if l.type_prefix.is_none() => b.to_string(),
            _ => l.text.clone(),
        },
        _ => sfc_syntax::print::expr(e),
    }
}

fn member(w: &mut W, out: &mut Out, checked: &Checked, d: &ast::VarDecl, retain: bool) {
    if let Some(l) = &d.location {
        out.warn(
            d.span,
            format!(
                "a GRAPH block's interface has no addresses: `{}` is written without `AT {}` (connect the block's parameter or a PLC tag to it)",
                d.names.iter().map(|n| n.text.as_str()).collect::<Vec<_>>().join(", "),
                l.text
            ),
        );
    }
    let (dt, members) = match datatype(checked, &d.ty) {
        Ok(x) => x,
        Err(m) => {
            out.error(d.ty.span, m);
            return;
        }
    };
    let comment = trailing_comment(checked, d.span);
    for n in &d.names {
        let mut a = vec![("Name", n.text.clone()), ("Datatype", dt.clone())];
        if retain {
            a.push(("Remanence", "Retain".into()));
        }
        let mut inner = W::new();
        if let Some(c) = &comment {
            inner.texts("Comment", c);
        }
        if let Some(ms) = members {
            for m in ms {
                member(&mut inner, out, checked, m, false);
            }
        }
        match &d.init {
            None => {}
            Some(Initializer::Expr(e)) => inner.leaf("StartValue", &[], &start_value(e)),
            Some(Initializer::Array { elements, span }) => {
                let lo = match &d.ty.kind {
                    TypeSpecKind::Array { ranges, .. } if ranges.len() == 1 => {
                        ranges.first().and_then(|(a, _)| sfc_syntax::print::expr(a).parse::<i64>().ok())
                    }
                    _ => None,
                };
                let Some(lo) = lo else {
                    out.error(*span, "the initial values of this array cannot be written");
                    return;
                };
                for (i, el) in elements.iter().enumerate() {
                    match (&el.repeat, &el.value) {
                        (None, Some(Initializer::Expr(e))) => {
                            inner.open("Subelement", &[("Path", (lo + i as i64).to_string())]);
                            inner.leaf("StartValue", &[], &start_value(e));
                            inner.close("Subelement");
                        }
                        _ => {
                            out.error(el.span, "a repeated or nested initial value cannot be written");
                            return;
                        }
                    }
                }
            }
            Some(Initializer::Struct { span, .. }) => {
                out.error(*span, "the initial value of a structure cannot be written");
                return;
            }
        }
        if members.is_some() && d.init.is_none() {
            // The members' own start values were written with them.
        }
        if inner.s.is_empty() {
            w.empty("Member", &a);
        } else {
            w.open("Member", &a);
            for line in inner.s.lines() {
                w.raw(line);
            }
            w.close("Member");
        }
    }
}
