//! Lowering an SFC POU from the AST into a [`Chart`], with the structural rules that need only
//! names: one namespace, declared steps and actions, qualifiers and durations, attributes.

use crate::chart::*;
use rustc_hash::{FxHashMap as HashMap, FxHashSet};
use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{self, ExprKind, LiteralKind};

/// What the lowering needs to know about the POU's variables.
pub struct VarInfo {
    /// Declared name as written.
    pub name: String,
    pub span: Span,
    /// The type name as written when it is a plain named type (`BOOL`, `TIME`, `TON`, …).
    pub type_name: Option<String>,
}

/// Variables declared by a POU, in declaration order.
pub fn pou_variables(pou: &ast::Pou) -> Vec<VarInfo> {
    let mut out = Vec::new();
    for b in &pou.var_blocks {
        for d in &b.decls {
            let type_name = match &d.ty.kind {
                ast::TypeSpecKind::Named(id) => Some(id.text.to_ascii_uppercase()),
                ast::TypeSpecKind::String { wide, .. } => Some(if *wide { "WSTRING" } else { "STRING" }.to_string()),
                _ => None,
            };
            for n in &d.names {
                out.push(VarInfo { name: n.text.clone(), span: n.span, type_name: type_name.clone() });
            }
        }
    }
    out
}

/// Attributes sfc knows; unknown `sfc.*` ones are reported as likely misspellings.
const KNOWN_ATTRIBUTES: &[&str] = &[
    "sfc.tag",
    "sfc.timeout",
    "sfc.min_time",
    "sfc.target",
    "sfc.final",
    // The safe value of an output (`sfc run`, docs/runtime.md): written on a fault or a stop.
    "sfc.safe",
    // Diagnostics of a mechanism (docs/sim.md, "Error records"): a variable's terminal label,
    // the instance's error-code variable and its activation bit.
    "sfc.terminal",
    "sfc.error_code",
    "sfc.activation",
    "sfc.x",
    "sfc.y",
    "sfc.width",
    "sfc.height",
    "sfc.description",
    "sfc.background",
    "sfc.foreground",
    "sfc.linewidth",
    "sfc.hidelabel",
    "sfc.font",
    "sfc.align",
    "sfc.pins",
    "sfc.bends",
    "sfc.label",
    "sfc.name",
    // Written by the PLCopen import (`sfc-plcopen`, see its `attrs` module): size, foreign
    // addData, action block and jump positions, condition references, inline actions, comments.
    "sfc.w",
    "sfc.h",
    "sfc.adddata",
    "sfc.actionblock",
    "sfc.jump",
    "sfc.reference",
    "sfc.inline",
    "sfc.comment",
    // Also the PLCopen import's: the file's headers and foreign project data (on its first POU),
    // a POU kept as written (why, and its XML).
    "sfc.fileheader",
    "sfc.contentheader",
    "sfc.projectdata",
    "sfc.verbatim",
    "sfc.pouxml",
    // A POU whose identifiers follow CODESYS's rules (doubled or trailing underscores).
    "sfc.dialect",
    // Transitions drawn but not connected on both sides (PLCopen import and editor), which the
    // chart does not hold (`sfc_syntax::attr_value::Loose`).
    "sfc.loose",
    // Written by the editor (`sfc-doc`): the blocks, connections and bends the text cannot hold;
    // the build output of an "IEC 61131-3" chart (a blank one), kept for the editor's toolbar.
    "sfc.graph",
    "sfc.graph.e",
    "sfc.graph.c",
    "sfc.build",
];

/// Prefixes of the attributes in which an import keeps what IEC text cannot hold of a vendor's
/// format: Studio 5000 L5X (`sfc-l5x`) and TIA Portal S7-GRAPH (`sfc-simaticml`).
pub const VENDOR_PREFIXES: &[&str] = &["sfc.logix.", "sfc.s7graph."];

/// The values `sfc.build` may take: the outputs `sfc build` makes of a blank chart.
const BUILD_OUTPUTS: &[&str] = &["st", "stl", "plcopen", "svg", "text"];

fn attr<'a>(attrs: &'a [ast::Attribute], name: &str) -> Option<&'a ast::Attribute> {
    attrs.iter().rev().find(|a| a.name.eq_ignore_ascii_case(name))
}

/// Reports unknown and misplaced `sfc.*` attributes; `allowed` lists those meaningful here.
/// `sfc.build` belongs where `sfc.target` does (before a POU), and its value is checked there.
pub fn check_attributes(attrs: &[ast::Attribute], allowed: &[&str], what: &str, diags: &mut Vec<Diagnostic>) {
    for a in attrs {
        let lname = a.name.to_ascii_lowercase();
        if !lname.starts_with("sfc.") {
            continue;
        }
        let meaningful = match lname.as_str() {
            "sfc.build" => allowed.contains(&"sfc.target"),
            "sfc.tag" | "sfc.timeout" | "sfc.min_time" | "sfc.target" | "sfc.final" | "sfc.safe" | "sfc.terminal"
            | "sfc.error_code" | "sfc.activation" => allowed.contains(&lname.as_str()),
            _ => true,
        };
        // What an import keeps of a vendor's format for its export (`sfc.logix.*` of an L5X
        // file, `sfc.s7graph.*` of a TIA Portal file) is known by its prefix.
        let vendor = VENDOR_PREFIXES.iter().any(|p| lname.starts_with(p));
        if lname == "sfc.conflict" {
            let v = a.value.as_deref().map(sfc_syntax::attr_value::unescape).unwrap_or_default();
            let key = v.lines().next().unwrap_or("");
            let element = match key.split_once(':') {
                Some((kind, name)) => format!("{kind} `{name}`"),
                None => key.to_string(),
            };
            diags.push(Diagnostic::error(
                "SFC0605",
                a.span,
                format!("unresolved merge conflict: {element} was changed both ways; take ours or theirs"),
            ));
        } else if !vendor && !KNOWN_ATTRIBUTES.contains(&lname.as_str()) {
            diags.push(Diagnostic::warning("SFC0602", a.span, format!("unknown attribute `{}`", a.name)));
        } else if !meaningful {
            diags.push(Diagnostic::warning(
                "SFC0603",
                a.span,
                format!("attribute `{}` has no meaning on {what}", a.name),
            ));
        } else if lname == "sfc.build" {
            build_attr(a, diags);
        }
    }
}

/// Checks the attributes of the variable declarations of `block`: `sfc.safe` is meaningful
/// there, and its value must be one literal (`FALSE`, `0`, `-5`, `2.5`, `T#0s`, `'text'`);
/// whether it fits the variable's type is checked by `sfc run`, which uses it.
pub fn check_variable_attributes(block: &ast::VarBlock, file_id: u32, diags: &mut Vec<Diagnostic>) {
    for d in &block.decls {
        check_attributes(
            &d.attributes,
            &["sfc.safe", "sfc.terminal", "sfc.error_code", "sfc.activation"],
            "a variable",
            diags,
        );
        let Some(a) = attr(&d.attributes, "sfc.safe") else { continue };
        let v = a.value.as_deref().unwrap_or("").trim();
        if !is_one_literal(file_id, v) {
            diags.push(Diagnostic::error(
                "SFC0601",
                a.span,
                format!("`sfc.safe` is one literal such as 'FALSE', '0' or 'T#0s', found {v:?}"),
            ));
        }
    }
}

/// Whether `text` is a single literal, optionally negative.
fn is_one_literal(file_id: u32, text: &str) -> bool {
    use sfc_syntax::lexer::TokenKind as K;
    let (tokens, errors) = sfc_syntax::lexer::lex(file_id, text);
    if !errors.is_empty() {
        return false;
    }
    let toks: Vec<_> = tokens.iter().filter(|t| t.kind != K::Whitespace && t.kind != K::Eof).collect();
    match toks.as_slice() {
        [t] if t.kind == K::Ident => {
            ["TRUE", "FALSE"].iter().any(|b| b.eq_ignore_ascii_case(&text[t.start as usize..t.end as usize]))
        }
        [t] => matches!(t.kind, K::Int | K::Real | K::Typed | K::String | K::WString),
        [m, t] => m.kind == K::Minus && matches!(t.kind, K::Int | K::Real | K::Typed),
        _ => false,
    }
}

/// Checks the value of a POU's `sfc.build` (the editor's build output of an IEC chart).
fn build_attr(a: &ast::Attribute, diags: &mut Vec<Diagnostic>) {
    let v = a.value.as_deref().unwrap_or("").trim();
    if !BUILD_OUTPUTS.iter().any(|b| b.eq_ignore_ascii_case(v)) {
        diags.push(Diagnostic::error(
            "SFC0601",
            a.span,
            format!("`sfc.build` is one of 'st', 'stl', 'plcopen', 'svg', 'text', found {v:?}"),
        ));
    }
}

fn tag_attr(attrs: &[ast::Attribute], diags: &mut Vec<Diagnostic>) -> Option<u32> {
    let a = attr(attrs, "sfc.tag")?;
    match a.value.as_deref().map(str::trim).and_then(|v| v.parse::<u32>().ok()) {
        Some(v) => Some(v),
        None => {
            diags.push(Diagnostic::error(
                "SFC0601",
                a.span,
                format!("`sfc.tag` must be a non-negative integer, found {:?}", a.value.as_deref().unwrap_or("")),
            ));
            None
        }
    }
}

/// A step's duration attribute (`sfc.timeout`, `sfc.min_time`).
fn duration_attr(attrs: &[ast::Attribute], name: &str, diags: &mut Vec<Diagnostic>) -> Option<i64> {
    let a = attr(attrs, name)?;
    let v = a.value.as_deref().unwrap_or("").trim();
    let parsed = match v.split_once('#') {
        Some((p, body)) if ["T", "TIME"].iter().any(|k| p.eq_ignore_ascii_case(k)) => {
            sfc_syntax::literal::decode_duration(body, a.span).ok()
        }
        _ => None,
    };
    match parsed {
        Some(us) if us >= 0 => Some(us),
        _ => {
            diags.push(Diagnostic::error(
                "SFC0601",
                a.span,
                format!("`{name}` must be a non-negative duration such as 'T#8.1s', found {v:?}"),
            ));
            None
        }
    }
}

fn final_attr(attrs: &[ast::Attribute], diags: &mut Vec<Diagnostic>) -> bool {
    let Some(a) = attr(attrs, "sfc.final") else { return false };
    match a.value.as_deref().map(|v| v.trim().to_ascii_lowercase()) {
        None => true,
        Some(v) if v == "true" => true,
        Some(v) if v == "false" => false,
        Some(v) => {
            diags.push(Diagnostic::error("SFC0601", a.span, format!("`sfc.final` is 'true' or 'false', found {v:?}")));
            false
        }
    }
}

/// The target named by a POU's `sfc.target` attribute.
pub fn target_attr(attrs: &[ast::Attribute], diags: &mut Vec<Diagnostic>) -> Option<Target> {
    let a = attr(attrs, "sfc.target")?;
    let v = a.value.as_deref().unwrap_or("").trim();
    match Target::from_name(v) {
        Some(t) => Some(t),
        None => {
            diags.push(Diagnostic::error(
                "SFC0601",
                a.span,
                format!("`sfc.target` is one of 'blank', 'atmt', 'eatmt', found {v:?}"),
            ));
            None
        }
    }
}

/// A declared name in the POU's single namespace.
struct Declared {
    span: Span,
    kind: &'static str,
    /// Declared by another chart of the POU (its body or another action's chart).
    elsewhere: bool,
}

/// The actions of a POU that is no chart: each name once in the POU's namespace (SFC0206, as
/// a chart's names).
pub fn check_pou_actions(pou: &ast::Pou, diags: &mut Vec<Diagnostic>) {
    let mut names: HashMap<String, Declared> = HashMap::default();
    for v in pou_variables(pou) {
        names.entry(v.name.to_ascii_uppercase()).or_insert(Declared {
            span: v.span,
            kind: "a variable",
            elsewhere: false,
        });
    }
    for a in &pou.actions {
        let key = a.name.text.to_ascii_uppercase();
        if let Some(prev) = names.get(&key) {
            diags.push(
                Diagnostic::error(
                    "SFC0206",
                    a.name.span,
                    format!("`{}` is already declared as {} in this POU", a.name.text, prev.kind),
                )
                .with_element(&a.name.text)
                .with_label(prev.span, "first declared here")
                .with_note("variables and actions share one case-insensitive namespace"),
            );
        } else {
            names.insert(key, Declared { span: a.name.span, kind: "an action", elsewhere: false });
        }
    }
}

/// Builds the chart of an SFC POU. `file` and `item` locate it; `target` is the effective target.
/// The transition conditions and action bodies move from the AST into the chart (the AST keeps
/// `Condition::Missing` and empty bodies in their place), so large charts are not held twice.
pub fn lower(
    file: u32,
    item: usize,
    pou: &ast::Pou,
    elements: &mut [ast::SfcElement],
    target: Target,
    diags: &mut Vec<Diagnostic>,
) -> Chart {
    lower_chart(file, item, pou, elements, target, ChartOf::default(), diags)
}

/// Which chart of a POU is lowered: its body (the default), or an action written in SFC.
#[derive(Default)]
pub struct ChartOf {
    /// The action written in SFC; `None` for the POU's body.
    pub action: Option<String>,
    /// The action's name and whole span (the chart's `name_span` and `span`).
    pub spans: Option<(Span, Span)>,
    /// Names of the POU declared before this chart (other charts' steps, the actions), which
    /// its names must not reuse: `(name, span, "a step" | "an action")`.
    pub taken: Vec<(String, Span, &'static str)>,
    /// For an action's chart: the POU's actions (the chart declares none of its own).
    pub actions: Vec<ActionNode>,
    /// Actions named by the associations of the POU's other charts (not "never used").
    pub mentioned: FxHashSet<String>,
}

/// The actions a chart's steps name, in associations and as step actions (upper case).
pub fn mentioned_actions(elements: &[ast::SfcElement]) -> FxHashSet<String> {
    let mut out = FxHashSet::default();
    for e in elements {
        if let ast::SfcElement::Step(s) = e {
            out.extend(s.associations.iter().map(|a| a.action.key()));
            out.extend(s.step_actions.iter().map(|a| a.name().to_ascii_uppercase()));
        }
    }
    out
}

/// [`lower`] of one chart of a POU (see [`ChartOf`]).
pub fn lower_chart(
    file: u32,
    item: usize,
    pou: &ast::Pou,
    elements: &mut [ast::SfcElement],
    target: Target,
    of: ChartOf,
    diags: &mut Vec<Diagnostic>,
) -> Chart {
    let vars = pou_variables(pou);
    let mut names: HashMap<String, Declared> = HashMap::default();
    // Clashes between two variables are the type checker's (it checks every POU's
    // declarations); here variables only seed the namespace that chart names must not reuse.
    for v in &vars {
        names.entry(v.name.to_ascii_uppercase()).or_insert(Declared {
            span: v.span,
            kind: "a variable",
            elsewhere: false,
        });
    }
    for (name, span, kind) in &of.taken {
        names.entry(name.to_ascii_uppercase()).or_insert(Declared { span: *span, kind, elsewhere: true });
    }
    let mut declare = |name: &str, span: Span, kind: &'static str, diags: &mut Vec<Diagnostic>| -> bool {
        if name.is_empty() {
            return false;
        }
        let key = name.to_ascii_uppercase();
        if let Some(prev) = names.get(&key).filter(|p| p.elsewhere && p.kind == "a step" && kind == "a step") {
            // A step of another chart of the POU: real TwinCAT projects repeat step names across
            // a POU's SFC actions, each chart keeping its own step.
            diags.push(
                Diagnostic::warning(
                    "SFC0220",
                    span,
                    format!("`{name}` is also a step of another chart of this POU; `{name}.X` in code means the first"),
                )
                .with_element(name)
                .with_label(prev.span, "first declared here")
                .with_note("CODESYS's documentation asks for step names unique within the POU"),
            );
            names.insert(key, Declared { span, kind, elsewhere: false });
            return true;
        }
        if let Some(prev) = names.get(&key) {
            diags.push(
                Diagnostic::error(
                    "SFC0206",
                    span,
                    format!("`{name}` is already declared as {} in this POU", prev.kind),
                )
                .with_element(name)
                .with_label(prev.span, "first declared here")
                .with_note("variables, steps, actions and transitions share one case-insensitive namespace"),
            );
            false
        } else {
            names.insert(key, Declared { span, kind, elsewhere: false });
            true
        }
    };
    let var_type: HashMap<String, Option<String>> =
        vars.iter().map(|v| (v.name.to_ascii_uppercase(), v.type_name.clone())).collect();

    // Steps and actions first (transitions and associations refer to them in any order).
    let mut steps: Vec<StepNode> = Vec::new();
    let mut step_index: HashMap<String, StepId> = HashMap::default();
    let mut action_index: HashMap<String, ActionId> = HashMap::default();
    let is_action_chart = of.action.is_some();
    let mut actions: Vec<ActionNode> = of.actions;
    for (k, a) in actions.iter().enumerate() {
        action_index.insert(a.name.to_ascii_uppercase(), k);
    }
    for el in elements.iter_mut() {
        match el {
            ast::SfcElement::Step(s) => {
                check_attributes(
                    &s.attributes,
                    &["sfc.tag", "sfc.timeout", "sfc.min_time", "sfc.final"],
                    "a step",
                    diags,
                );
                let fresh = declare(&s.name.text, s.name.span, "a step", diags);
                let node = StepNode {
                    name: s.name.text.clone(),
                    initial: s.initial,
                    associations: Vec::new(),
                    step_actions: s.step_actions.clone(),
                    tag: tag_attr(&s.attributes, diags),
                    timeout: duration_attr(&s.attributes, "sfc.timeout", diags),
                    min_time: duration_attr(&s.attributes, "sfc.min_time", diags),
                    is_final: final_attr(&s.attributes, diags),
                    interlock: step_condition(s, "sfc.s7graph.interlock"),
                    supervision: step_condition(s, "sfc.s7graph.supervision"),
                    attributes: s.attributes.clone(),
                    name_span: s.name.span,
                    span: s.span,
                };
                if fresh {
                    step_index.insert(s.name.key(), steps.len());
                    steps.push(node);
                } else if s.name.text.is_empty() {
                    // A step whose name failed to parse: nothing to refer to.
                } else if let std::collections::hash_map::Entry::Vacant(e) = step_index.entry(s.name.key()) {
                    // Clashes with a variable or an action: keep it so its transitions resolve,
                    // the duplicate-name error has been reported.
                    e.insert(steps.len());
                    steps.push(node);
                }
            }
            ast::SfcElement::Action(a) => {
                check_attributes(&a.attributes, &[], "an action", diags);
                let fresh = declare(&a.name.text, a.name.span, "an action", diags);
                if fresh || (!a.name.text.is_empty() && !action_index.contains_key(&a.name.key())) {
                    action_index.insert(a.name.key(), actions.len());
                    actions.push(ActionNode {
                        name: a.name.text.clone(),
                        body: std::mem::replace(&mut a.body, ast::ActionBody::St(Vec::new())),
                        attributes: a.attributes.clone(),
                        name_span: a.name.span,
                        span: a.span,
                    });
                }
            }
            ast::SfcElement::Transition(_) => {}
        }
    }

    // Actions of instances associated with steps (`Motor.Stop(S)`, CODESYS): each an action
    // of the chart whose body calls it, under its qualified name.
    for el in elements.iter() {
        let ast::SfcElement::Step(s) = el else { continue };
        for a in &s.associations {
            let Some(call) = a.instance_call() else { continue };
            if action_index.contains_key(&a.action.key()) {
                continue;
            }
            action_index.insert(a.action.key(), actions.len());
            actions.push(ActionNode {
                name: a.action.text.clone(),
                body: ast::ActionBody::St(vec![ast::Stmt {
                    kind: ast::StmtKind::Call(Box::new(call)),
                    span: a.action.span,
                }]),
                attributes: Vec::new(),
                name_span: a.action.span,
                span: a.action.span,
            });
        }
    }

    // Associations.
    let action_names: Vec<String> = actions.iter().map(|a| a.name.clone()).collect();
    for el in elements.iter() {
        let ast::SfcElement::Step(s) = el else { continue };
        let Some(&sid) = step_index.get(&s.name.key()) else { continue };
        if steps[sid].span != s.span {
            continue; // a duplicate step declaration: its associations were not lowered
        }
        for a in &s.associations {
            if let Some(assoc) = lower_association(a, &action_index, &action_names, &var_type, diags) {
                steps[sid].associations.push(assoc);
            }
        }
    }

    // Unused actions: judged on the associations as written, so an association rejected for
    // another reason (say an unknown qualifier) does not also make its action "unused".
    if !matches!(target, Target::Atmt | Target::Eatmt) && !is_action_chart {
        let mut mentioned = mentioned_actions(elements);
        mentioned.extend(of.mentioned);
        for action in &actions {
            // S7-GRAPH's permanent instructions run in every call without a step, and its event
            // actions when their step's event occurs.
            let permanent = attr(&action.attributes, "sfc.s7graph.permanent").is_some()
                || attr(&action.attributes, "sfc.s7graph.event").is_some();
            if !permanent && !mentioned.contains(&action.name.to_ascii_uppercase()) {
                diags.push(
                    Diagnostic::warning("SFC0214", action.name_span, format!("action `{}` is never used", action.name))
                        .with_element(&action.name),
                );
            }
        }
    }

    // Transitions, with names `T<n>` for unnamed ones.
    let mut transitions: Vec<TransitionNode> = Vec::new();
    let mut position = 0;
    let mut pending_unnamed: Vec<(usize, usize)> = Vec::new(); // (transition index, position)
    for el in elements.iter_mut() {
        let ast::SfcElement::Transition(t) = el else { continue };
        position += 1;
        check_attributes(&t.attributes, &["sfc.tag"], "a transition", diags);
        let resolve = |list: &[ast::Ident], diags: &mut Vec<Diagnostic>| -> Vec<StepId> {
            let mut out: Vec<StepId> = Vec::new();
            for id in list {
                match step_index.get(&id.key()) {
                    Some(&s) => {
                        if out.contains(&s) {
                            diags.push(
                                Diagnostic::error("SFC0216", id.span, format!("step `{}` is listed twice", id.text))
                                    .with_element(&id.text),
                            );
                        } else {
                            out.push(s);
                        }
                    }
                    None => {
                        let mut d = Diagnostic::error("SFC0208", id.span, format!("undeclared step `{}`", id.text))
                            .with_element(&id.text);
                        if let Some(s) = closest(&id.text, steps.iter().map(|s| s.name.as_str())) {
                            d = d.with_note(format!("did you mean `{s}`?"));
                        }
                        diags.push(d);
                    }
                }
            }
            out
        };
        let from = resolve(&t.from, diags);
        let to = resolve(&t.to, diags);
        let priority = t.priority.as_ref().and_then(|p| match &p.kind {
            ExprKind::Literal(ast::Literal { kind: LiteralKind::Int(v), .. }) if *v >= 0 && *v <= i64::MAX as i128 => {
                Some(*v as i64)
            }
            _ => {
                diags.push(Diagnostic::error("SFC0101", p.span, "PRIORITY must be a non-negative integer literal"));
                None
            }
        });
        let header_end = match &t.condition {
            ast::Condition::St(e) => e.span.start,
            ast::Condition::Il(b) => b.span.start,
            ast::Condition::Missing => t.span.end,
        };
        let header_span = Span::new(t.span.file, t.span.start, header_end.max(t.span.start));
        let name = match &t.name {
            Some(n) => {
                declare(&n.text, n.span, "a transition", diags);
                n.text.clone()
            }
            None => {
                pending_unnamed.push((transitions.len(), position));
                String::new()
            }
        };
        transitions.push(TransitionNode {
            name,
            named: t.name.is_some(),
            priority,
            from,
            to,
            condition: std::mem::replace(&mut t.condition, ast::Condition::Missing),
            tag: tag_attr(&t.attributes, diags),
            attributes: t.attributes.clone(),
            header_span,
            span: t.span,
        });
    }
    // Unnamed transitions: `T<n>`, or the first free `T<n>_1`, `T<n>_2`, … when taken.
    for (idx, pos) in pending_unnamed {
        let base = format!("T{pos}");
        let mut candidate = base.clone();
        let mut k = 0;
        while names.contains_key(&candidate.to_ascii_uppercase()) {
            k += 1;
            candidate = format!("{base}_{k}");
        }
        names.insert(
            candidate.to_ascii_uppercase(),
            Declared { span: transitions[idx].span, kind: "a transition", elsewhere: false },
        );
        transitions[idx].name = candidate;
    }

    Chart {
        file,
        item,
        pou: pou.name.text.clone(),
        pou_kind: pou.kind,
        action: of.action,
        target,
        steps,
        transitions,
        actions,
        name_span: of.spans.map_or(pou.name.span, |s| s.0),
        span: of.spans.map_or(pou.span, |s| s.1),
        logix: logix_settings(&pou.attributes, diags),
        s7graph: graph_settings(&pou.attributes, diags),
    }
}

/// The S7-GRAPH block settings of a POU (`sfc.s7graph.ack_required`), with SFC0601 for a value
/// that is not a Boolean.
fn graph_settings(attrs: &[ast::Attribute], diags: &mut Vec<Diagnostic>) -> crate::GraphSettings {
    let mut out = crate::GraphSettings::default();
    if let Some(a) = attr(attrs, "sfc.s7graph.ack_required") {
        match a.value.as_deref().map(str::trim) {
            Some(v) if v.eq_ignore_ascii_case("true") => out.ack_required = true,
            Some(v) if v.eq_ignore_ascii_case("false") => out.ack_required = false,
            v => diags.push(Diagnostic::error(
                "SFC0601",
                a.span,
                format!("`sfc.s7graph.ack_required` is 'true' or 'false', found {:?}", v.unwrap_or("")),
            )),
        }
    }
    out
}

/// The Studio 5000 execution settings of a POU (`sfc.logix.exec`, `sfc.logix.lastscan`, as the
/// L5X import writes them), with SFC0601 for a value Logix does not have.
fn logix_settings(attrs: &[ast::Attribute], diags: &mut Vec<Diagnostic>) -> crate::LogixSettings {
    let mut out = crate::LogixSettings::default();
    if let Some(a) = attr(attrs, "sfc.logix.exec") {
        match a.value.as_deref().map(str::trim) {
            Some(v) if v.eq_ignore_ascii_case("CurrentActive") => out.until_false = false,
            Some(v) if v.eq_ignore_ascii_case("UntilFalse") => out.until_false = true,
            v => diags.push(Diagnostic::error(
                "SFC0601",
                a.span,
                format!("`sfc.logix.exec` is 'CurrentActive' or 'UntilFalse', found {:?}", v.unwrap_or("")),
            )),
        }
    }
    if let Some(a) = attr(attrs, "sfc.logix.lastscan") {
        let v = a.value.as_deref().map(str::trim).unwrap_or("");
        match [crate::LastScan::DontScan, crate::LastScan::ProgrammaticReset, crate::LastScan::AutomaticReset]
            .into_iter()
            .find(|l| l.name().eq_ignore_ascii_case(v))
        {
            Some(l) => {
                out.last_scan = l;
                if l == crate::LastScan::AutomaticReset {
                    diags.push(
                        Diagnostic::warning(
                            "SFC0604",
                            a.span,
                            "\"Automatic reset\" is simulated as \"Don't scan\": its postscan mode is not simulated",
                        )
                        .with_note(
                            "in a step's last scan only P and P0 actions execute, and the tags on the left of \
                             non-retentive assignments `[:=]` are not cleared; for ST bodies without `[:=]` the two \
                             settings agree",
                        ),
                    );
                }
            }
            None => diags.push(Diagnostic::error(
                "SFC0601",
                a.span,
                format!("`sfc.logix.lastscan` is 'DontScan', 'ProgrammaticReset' or 'AutomaticReset', found {v:?}"),
            )),
        }
    }
    out
}

/// The last condition `name` of a step ([`ast::STEP_CONDITIONS`]).
fn step_condition(s: &ast::Step, name: &str) -> Option<ast::Expr> {
    s.conditions.iter().rev().find(|c| c.attribute.eq_ignore_ascii_case(name)).map(|c| c.expr.clone())
}

fn lower_association(
    a: &ast::ActionAssociation,
    action_index: &HashMap<String, ActionId>,
    action_names: &[String],
    var_type: &HashMap<String, Option<String>>,
    diags: &mut Vec<Diagnostic>,
) -> Option<Association> {
    let mut ok = true;
    let target = match action_index.get(&a.action.key()) {
        Some(&id) => ActionTarget::Action(id),
        None => match var_type.get(&a.action.key()) {
            Some(Some(t)) if t == "BOOL" => ActionTarget::Variable,
            Some(t) => {
                diags.push(
                    Diagnostic::error(
                        "SFC0207",
                        a.action.span,
                        format!(
                            "`{}` is a variable of type {}, and only BOOL variables can be used as actions",
                            a.action.text,
                            t.as_deref().unwrap_or("a non-elementary type")
                        ),
                    )
                    .with_element(&a.action.text),
                );
                return None;
            }
            None => {
                let mut d =
                    Diagnostic::error("SFC0207", a.action.span, format!("undeclared action `{}`", a.action.text))
                        .with_element(&a.action.text);
                let candidates = action_names.iter().map(String::as_str);
                if let Some(s) = closest(&a.action.text, candidates) {
                    d = d.with_note(format!("did you mean `{s}`?"));
                } else {
                    d = d.with_note(
                        "declare it with `ACTION name: … END_ACTION`, or declare a BOOL variable of that name",
                    );
                }
                diags.push(d);
                ok = false;
                ActionTarget::Variable
            }
        },
    };
    let qualifier = match &a.qualifier {
        None => Qualifier::N,
        Some(q) => match Qualifier::from_name(&q.text) {
            Some(q) => q,
            None => {
                diags.push(
                    Diagnostic::error("SFC0209", q.span, format!("unknown action qualifier `{}`", q.text))
                        .with_element(&a.action.text)
                        .with_note("the qualifiers are N, R, S, L, D, P, SD, DS, SL, P1 and P0"),
                );
                return None;
            }
        },
    };
    // Whether a duration variable is TIME and an indicator BOOL is the type checker's to say
    // (SFC0311, SFC0312); here they are only recorded.
    let duration = match (&a.duration, qualifier.is_timed()) {
        (None, true) => {
            diags.push(
                Diagnostic::error(
                    "SFC0210",
                    a.span,
                    format!(
                        "qualifier {} needs a duration, e.g. `{}({}, T#5s)`",
                        qualifier.name(),
                        a.action.text,
                        qualifier.name()
                    ),
                )
                .with_element(&a.action.text),
            );
            return None;
        }
        (Some(d), false) => {
            diags.push(
                Diagnostic::error("SFC0211", d.span, format!("qualifier {} takes no duration", qualifier.name()))
                    .with_element(&a.action.text),
            );
            return None;
        }
        (None, false) => None,
        (Some(d), true) => match &d.kind {
            ExprKind::Literal(ast::Literal { kind: LiteralKind::Duration(us), .. }) => Some(Duration::Literal(*us)),
            ExprKind::Name(n) if matches!(var_type.get(&n.key()), Some(Some(t)) if t == "TIME" || t == "LTIME") => {
                Some(Duration::Variable(n.text.clone()))
            }
            _ => return None,
        },
    };
    let indicators: Vec<String> = a
        .indicators
        .iter()
        .filter(|ind| matches!(var_type.get(&ind.key()), Some(Some(t)) if t == "BOOL"))
        .map(|ind| ind.text.clone())
        .collect();
    if !ok {
        return None;
    }
    Some(Association { action: a.action.text.clone(), target, qualifier, duration, indicators, span: a.span })
}

/// The first candidate (in the given order) at the smallest edit distance, at most 2, from
/// `name` (case-insensitive); deterministic because callers pass declaration order.
pub fn closest<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let n = name.to_ascii_uppercase();
    let mut best: Option<(usize, &str)> = None;
    for c in candidates {
        let d = edit_distance(&n, &c.to_ascii_uppercase());
        if d <= 2 && d < n.len() && best.map(|b| d < b.0).unwrap_or(true) {
            best = Some((d, c));
        }
    }
    best.map(|b| b.1)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut cur = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            cur[j] = (prev[j] + 1).min(cur[j - 1] + 1).min(prev[j - 1] + cost);
        }
        prev = cur;
    }
    prev[b.len()]
}
