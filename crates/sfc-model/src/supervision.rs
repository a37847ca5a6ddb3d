//! sfc's step supervision written out for a vendor that has none.
//!
//! A step's maximum time (`sfc.timeout`, CODESYS's "Maximum time") sets the chart control
//! variable `SFCError` when the step has been active longer (`S.T > timeout`, once per
//! activation), and `SFCQuitError` TRUE at the start of a call clears it (docs/sim.md, "Chart
//! control variables"). Neither S7-GRAPH nor Logix has these: S7-GRAPH's supervision holds the
//! step, a Logix step's alarm `AH` does not latch. So that a converted chart runs as the
//! original, [`lower`] writes the supervision as code the target runs:
//! - `SFCError` (an output) and `SFCQuitError` (an input) are declared where the POU does not
//!   declare them, and one BOOL `<Step>_Overdue` per supervised step remembers that its
//!   activation has reported;
//! - [`Style::Permanent`] (S7-GRAPH): a permanent instruction before the sequencer
//!   acknowledges, one after it supervises each step, in declaration order, as the `graph`
//!   profile does;
//! - [`Style::StepActions`] (Logix): every step gets a first N action that acknowledges and,
//!   for a supervised step, supervises it, as the `logix` profile does before the actions.
//!
//! The generated declarations and actions are appended to a copy of the file's text (after
//! everything the user wrote, so every span of the user's text stays valid) and parsed from
//! there, so exporters that copy an action's text find it.

use crate::chart::{ActionNode, ActionTarget, Association, Chart, Qualifier};
use crate::Checked;
use sfc_diagnostics::{Diagnostic, SourceFile, Span};
use sfc_syntax::ast;
use std::collections::HashSet;

/// Where the target runs the supervision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Permanent instructions before and after the sequencer (S7-GRAPH).
    Permanent,
    /// A first action of every step (Logix).
    StepActions,
}

/// The chart with its supervision written as code.
pub struct Lowered {
    pub checked: Checked,
    /// Per chart written (by [`Chart::item`]): the steps whose `sfc.timeout` became code, with
    /// the span of their name in the user's text.
    pub steps: Vec<(usize, Vec<(String, Span)>)>,
}

/// Writes the supervision of the charts (of `pou`, or all) that have a step with `sfc.timeout`;
/// `None` when none has.
pub fn lower(checked: &Checked, style: Style, pou: Option<&str>) -> Option<Lowered> {
    let wanted = |c: &Chart| c.action.is_none() && pou.is_none_or(|p| c.pou.eq_ignore_ascii_case(p));
    if !checked.charts.iter().any(|c| wanted(c) && c.steps.iter().any(|s| s.timeout.is_some())) {
        return None;
    }
    let mut out = checked.clone();
    let mut text = out.file.text.clone();
    text.push_str("\n\n(* sfc: the supervision of the steps' maximum times (sfc.timeout), written for the target *)\n");
    let mut steps_out = Vec::new();
    for c in out.charts.iter_mut() {
        if !wanted(c) || !c.steps.iter().any(|s| s.timeout.is_some()) {
            continue;
        }
        let file = c.name_span.file;
        let Some(ast::Item::Pou(p)) = out.unit.items.get_mut(c.item) else { continue };
        let mut taken: HashSet<String> = HashSet::new();
        for b in &p.var_blocks {
            for d in &b.decls {
                taken.extend(d.names.iter().map(ast::Ident::key));
            }
        }
        let declared = |n: &str| taken.contains(&n.to_ascii_uppercase());
        let mut outputs = Vec::new();
        let mut inputs = Vec::new();
        if !declared("SFCError") {
            outputs.push("SFCError".to_string());
        }
        if !declared("SFCQuitError") {
            inputs.push("SFCQuitError".to_string());
        }
        taken.extend(c.steps.iter().map(|s| s.name.to_ascii_uppercase()));
        taken.extend(c.transitions.iter().map(|t| t.name.to_ascii_uppercase()));
        taken.extend(c.actions.iter().map(|a| a.name.to_ascii_uppercase()));
        let mut fresh = |base: String| {
            let mut n = base.clone();
            let mut k = 1;
            while taken.contains(&n.to_ascii_uppercase()) {
                k += 1;
                n = format!("{base}{k}");
            }
            taken.insert(n.to_ascii_uppercase());
            n
        };
        // The supervised steps, their flags and their checks.
        let mut checks = Vec::new();
        let mut flags = Vec::new();
        let mut supervised = Vec::new();
        for s in c.steps.iter_mut() {
            let Some(limit) = s.timeout.take() else {
                checks.push(None);
                continue;
            };
            s.attributes.retain(|a| !a.name.eq_ignore_ascii_case("sfc.timeout"));
            let flag = fresh(format!("{}_Overdue", s.name));
            let over = format!("{0}.X AND {0}.T > {1}", s.name, literal(limit));
            checks.push(Some(format!(
                "IF {over} AND NOT {flag} THEN\n    SFCError := TRUE;\nEND_IF;\n{flag} := {over};\n"
            )));
            flags.push(flag);
            supervised.push((s.name.clone(), s.name_span));
        }
        // The declarations.
        for (kind, names) in [(ast::VarKind::Output, outputs), (ast::VarKind::Input, inputs), (ast::VarKind::Var, flags)] {
            if names.is_empty() {
                continue;
            }
            let start = text.len();
            text.push_str(kind.keyword());
            text.push('\n');
            let mut decls = Vec::new();
            for n in names {
                let at = text.len();
                text.push_str(&format!("    {n} : BOOL;\n"));
                let name = ast::Ident::new(n.clone(), span(file, at + 4, at + 4 + n.len()));
                let ty_at = at + 4 + n.len() + 3;
                let ty = ast::TypeSpec {
                    kind: ast::TypeSpecKind::Named(ast::Ident::new("BOOL", span(file, ty_at, ty_at + 4))),
                    span: span(file, ty_at, ty_at + 4),
                };
                decls.push(ast::VarDecl {
                    names: vec![name],
                    location: None,
                    access_path: None,
                    access_mode: None,
                    ty,
                    init: None,
                    edge: None,
                    attributes: Vec::new(),
                    span: span(file, at + 4, text.len() - 1),
                });
            }
            text.push_str("END_VAR\n");
            p.var_blocks.push(ast::VarBlock {
                kind,
                constant: false,
                retain: None,
                persistent: false,
                decls,
                span: span(file, start, text.len() - 1),
            });
        }
        // The actions.
        const ACK: &str = "IF SFCQuitError THEN\n    SFCError := FALSE;\nEND_IF;\n";
        let add = |c: &mut Chart, text: &mut String, name: String, body: String, attrs: Vec<(String, String)>| {
            let start = text.len();
            text.push_str(&format!("ACTION {name}:\n"));
            let name_span = span(file, start + 7, start + 7 + name.len());
            let body_at = text.len();
            text.push_str(&body);
            text.push_str("END_ACTION\n");
            let padded = format!("{}{body}", " ".repeat(body_at));
            let (stmts, _) = sfc_syntax::parse_statements(file, &padded);
            let whole = span(file, start, text.len() - 1);
            c.actions.push(ActionNode {
                name: name.clone(),
                body: ast::ActionBody::St(stmts),
                attributes: attrs
                    .into_iter()
                    .map(|(k, v)| ast::Attribute { name: k, value: Some(v), span: whole })
                    .collect(),
                name_span,
                span: whole,
            });
            (c.actions.len() - 1, name_span)
        };
        match style {
            Style::Permanent => {
                let perm = |w: &str| vec![("sfc.s7graph.permanent".to_string(), w.to_string())];
                let ack = fresh("SFC_Acknowledge_0".into());
                add(c, &mut text, ack, ACK.to_string(), perm("pre"));
                let sup = fresh("SFC_Supervision_0".into());
                let body: String = checks.iter().flatten().cloned().collect();
                add(c, &mut text, sup, body, perm("post"));
            }
            Style::StepActions => {
                for i in 0..c.steps.len() {
                    let Some(s) = c.steps.get(i) else { continue };
                    let name = fresh(format!("{}_Supervision", s.name));
                    let body = format!("{ACK}{}", checks.get(i).cloned().flatten().unwrap_or_default());
                    let (id, at) = add(c, &mut text, name.clone(), body, Vec::new());
                    if let Some(s) = c.steps.get_mut(i) {
                        s.associations.insert(
                            0,
                            Association {
                                action: name,
                                target: ActionTarget::Action(id),
                                qualifier: Qualifier::N,
                                duration: None,
                                indicators: Vec::new(),
                                span: at,
                            },
                        );
                    }
                }
            }
        }
        steps_out.push((c.item, supervised));
    }
    out.file = SourceFile::new(out.file.name.clone(), text);
    Some(Lowered { checked: out, steps: steps_out })
}

/// What an exporter returns: the file and its notes, or the errors.
pub type Exported = Result<(String, Vec<Diagnostic>), Vec<Diagnostic>>;

/// Runs an exporter (`write`, given the notes so far) on `checked` with the supervision written
/// as `style` says; `note` words the warning for a chart and the names of its supervised steps.
/// Nothing is said about the generated code itself: its notes are dropped, and an error in it
/// is put on the chart's name.
pub fn export_lowered(
    checked: &Checked,
    style: Style,
    pou: Option<&str>,
    note: impl Fn(&Chart, &str) -> Diagnostic,
    write: impl FnOnce(&Checked, Vec<Diagnostic>) -> Exported,
) -> Exported {
    let Some(lowered) = lower(checked, style, pou) else {
        return write(checked, Vec::new());
    };
    let mut notes = Vec::new();
    for (item, steps) in &lowered.steps {
        if let Some(c) = checked.charts.iter().find(|c| c.item == *item && c.action.is_none()) {
            let names: Vec<&str> = steps.iter().map(|(n, _)| n.as_str()).collect();
            notes.push(note(c, &names.join(", ")));
        }
    }
    let end = checked.file.text.len() as u32;
    let at = checked.charts.first().map_or(Span::new(0, 0, 0), |c| c.name_span);
    match write(&lowered.checked, notes) {
        Ok((text, notes)) => Ok((text, notes.into_iter().filter(|d| d.span.start < end).collect())),
        Err(errors) => Err(errors
            .into_iter()
            .map(|mut d| {
                if d.span.start >= end {
                    d.message = format!("the supervision written for sfc.timeout: {}", d.message);
                    d.span = at;
                }
                d
            })
            .collect()),
    }
}

fn span(file: u32, start: usize, end: usize) -> Span {
    Span::new(file, start as u32, end as u32)
}

/// A duration in microseconds as an IEC literal, in milliseconds where whole.
fn literal(us: i64) -> String {
    if us % 1000 == 0 {
        format!("T#{}ms", us / 1000)
    } else {
        format!("T#{us}us")
    }
}
