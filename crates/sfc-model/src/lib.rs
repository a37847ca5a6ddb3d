//! The chart model of sfc: lowers each SFC POU of a parsed file into a [`Chart`], resolves names,
//! type-checks conditions and action bodies, and validates structure and target rules.
//! [`check_source`] is the one entry point the CLI, the server and the tests use.

pub mod chart;
mod code;
mod latch;
pub mod lower;
pub mod supervision;
pub mod vendor;
mod objects;
pub mod validate;

pub use chart::*;
pub use validate::{condition_input, ConditionInput, Limits};

use sfc_diagnostics::{Diagnostic, SourceFile, Span};
use sfc_syntax::ast;
use std::collections::HashMap;

/// What `sfc check` was asked for.
#[derive(Debug, Clone, Default)]
pub struct CheckOptions {
    /// Overrides each POU's `sfc.target` attribute.
    pub target: Option<Target>,
    /// `--nstep`: ATMT/EATMT state limit override.
    pub nstep: Option<u32>,
    /// `--ntr`: ATMT/EATMT rule limit override.
    pub ntr: Option<u32>,
    /// Run the reachability and guard analysis (once it exists in `sfc-analysis`).
    pub analysis: bool,
    /// Keep the type of every checked expression in [`Checked::expr_types`] (the simulator
    /// needs them for integer widths); off by default, so plain checking does not pay for it.
    pub keep_types: bool,
    /// ATMT/EATMT with `--flatten`: a chart whose situations can hold several active steps is
    /// compiled into one automaton, so the target rules flattening replaces
    /// ([`FLATTENING_REPLACES`]) are not checked for it.
    pub flatten: bool,
}

/// The ATMT/EATMT rules that flattening replaces by its own (state and rule counts, AND
/// branches, step tags): not checked for a chart that is flattened.
pub const FLATTENING_REPLACES: [&str; 4] = ["SFC0401", "SFC0403", "SFC0404", "SFC0409"];

/// The result of checking one file.
#[derive(Debug, Clone)]
pub struct Checked {
    pub file: SourceFile,
    /// The parsed file; the conditions and action bodies of SFC POUs have moved into `charts`,
    /// so large charts are not held twice.
    pub unit: ast::SourceUnit,
    /// One chart per SFC POU, in file order.
    pub charts: Vec<Chart>,
    /// The charts of actions written in SFC (CODESYS's SFC actions), in file order: each names
    /// its POU (`item`, `pou`) and its action ([`Chart::action`]). In the POU's AST such an
    /// action's body is left as an empty `ActionBody::Sfc`.
    pub action_charts: Vec<Chart>,
    /// Every diagnostic, sorted by position.
    pub diagnostics: Vec<Diagnostic>,
    /// With [`CheckOptions::keep_types`]: the type the checker gave each ST expression and IL
    /// operand, by span (see `sfc_st::Checker::expr_type`); empty otherwise.
    pub expr_types: HashMap<Span, sfc_st::Type>,
}

impl Checked {
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(|d| d.is_error())
    }
}

/// Parses, lowers and validates one file. `file_id` goes into every span.
pub fn check_source(file_id: u32, name: &str, text: &str, opts: &CheckOptions) -> Checked {
    check_parsed(file_id, name, text, sfc_syntax::parse(file_id, text), opts)
}

/// A parsed file to check: owned, or shared with another thread that reads the same parse (the
/// language server's index worker). The type check reads a shared tree where it is; lowering
/// moves conditions and action bodies out of it, so it then takes the tree over, or a copy when
/// the other reader still holds it.
#[derive(Debug, Clone)]
pub enum Tree {
    Owned(ast::SourceUnit),
    Shared(std::sync::Arc<ast::SourceUnit>),
}

impl From<ast::SourceUnit> for Tree {
    fn from(unit: ast::SourceUnit) -> Self {
        Tree::Owned(unit)
    }
}

impl From<std::sync::Arc<ast::SourceUnit>> for Tree {
    fn from(unit: std::sync::Arc<ast::SourceUnit>) -> Self {
        Tree::Shared(unit)
    }
}

impl Tree {
    fn unit(&self) -> &ast::SourceUnit {
        match self {
            Tree::Owned(u) => u,
            Tree::Shared(u) => u,
        }
    }

    fn into_owned(self) -> ast::SourceUnit {
        match self {
            Tree::Owned(u) => u,
            Tree::Shared(u) => std::sync::Arc::try_unwrap(u).unwrap_or_else(|u| (*u).clone()),
        }
    }
}

/// [`check_source`] of a text already parsed: `parsed` is what `sfc_syntax::parse(file_id,
/// text)` returned (the language server parses a version once for its index and its check),
/// the tree owned or shared ([`Tree`]).
pub fn check_parsed(
    file_id: u32,
    name: &str,
    text: &str,
    parsed: (impl Into<Tree>, Vec<Diagnostic>),
    opts: &CheckOptions,
) -> Checked {
    let mut tree: Tree = parsed.0.into();
    let mut diags = parsed.1;
    if objects::any(tree.unit()) {
        let mut unit = tree.into_owned();
        objects::keep_objects(&mut unit, text, &mut diags);
        tree = Tree::Owned(unit);
    }
    let (type_diags, expr_types) = code::check_unit(tree.unit(), opts.keep_types);
    let mut unit = tree.into_owned();
    // The names code calls (`Act();`, `inst.Act();`, `Main.Act();`): an action called so is used
    // (by name: a call from another POU is not resolved here).
    let mut called: rustc_hash::FxHashSet<String> = rustc_hash::FxHashSet::default();
    for item in &unit.items {
        if let ast::Item::Pou(p) = item {
            sfc_syntax::visit::pou_exprs(p, &mut |e| match &e.kind {
                ast::ExprKind::Call { callee, .. } => {
                    called.insert(callee.key());
                }
                ast::ExprKind::MemberCall { member, .. } => {
                    called.insert(member.key());
                }
                _ => {}
            });
        }
    }
    let mut charts = Vec::new();
    let mut action_charts = Vec::new();
    for (i, item) in unit.items.iter_mut().enumerate() {
        if let ast::Item::Globals(block) = item {
            lower::check_variable_attributes(block, file_id, &mut diags);
        }
        let ast::Item::Pou(pou) = item else { continue };
        for block in &pou.var_blocks {
            lower::check_variable_attributes(block, file_id, &mut diags);
        }
        lower::check_attributes(&pou.attributes, &["sfc.target"], "a POU", &mut diags);
        let attr_target = lower::target_attr(&pou.attributes, &mut diags);
        let target = opts.target.or(attr_target).unwrap_or(Target::Blank);
        lower::check_pou_actions(pou, &mut diags);
        let mut body = std::mem::replace(&mut pou.body, ast::Body::St(Vec::new()));
        let mut inner = take_action_charts(&mut body, &mut pou.actions);
        let mut mentioned: rustc_hash::FxHashSet<String> =
            inner.iter().flat_map(|(_, e)| lower::mentioned_actions(e)).collect();
        mentioned.extend(called.iter().cloned());
        let mut main: Option<usize> = None;
        if let ast::Body::Sfc(elements) = &mut body {
            let of = lower::ChartOf { mentioned, ..Default::default() };
            let chart = lower::lower_chart(file_id, i, pou, elements, target, of, &mut diags);
            validate::structure(&chart, text, &mut diags);
            latch::latched_outputs(pou, &chart, &mut diags);
            let limits = Limits::of(target, opts.nstep, opts.ntr);
            let mut rules = Vec::new();
            validate::target_rules(&chart, limits, &mut rules);
            if opts.flatten && chart.several_active_steps() {
                rules.retain(|d| !FLATTENING_REPLACES.contains(&d.code));
            }
            diags.extend(rules);
            main = Some(charts.len());
            charts.push(chart);
        }
        // The charts of the actions written in SFC: their names join the POU's namespace after
        // the body's, and their steps name the POU's actions.
        let mut taken: Vec<(String, Span, &'static str)> = Vec::new();
        if let Some(c) = main {
            taken.extend(charts[c].steps.iter().map(|s| (s.name.clone(), s.name_span, "a step")));
            taken.extend(charts[c].actions.iter().map(|a| (a.name.clone(), a.name_span, "an action")));
        }
        taken.extend(pou.actions.iter().map(|a| (a.name.text.clone(), a.name.span, "an action")));
        for ((action, name_span, span), elements) in inner.iter_mut() {
            let wanted = lower::mentioned_actions(elements);
            let actions: Vec<ActionNode> = match main {
                Some(c) => charts[c]
                    .actions
                    .iter()
                    .filter(|a| wanted.contains(&a.name.to_ascii_uppercase()))
                    .cloned()
                    .collect(),
                None => pou
                    .actions
                    .iter()
                    .filter(|a| wanted.contains(&a.name.key()))
                    .map(|a| ActionNode {
                        name: a.name.text.clone(),
                        body: a.body.clone(),
                        attributes: a.attributes.clone(),
                        name_span: a.name.span,
                        span: a.span,
                    })
                    .collect(),
            };
            let of = lower::ChartOf {
                action: Some(action.clone()),
                spans: Some((*name_span, *span)),
                taken: taken.clone(),
                actions,
                ..Default::default()
            };
            let chart = lower::lower_chart(file_id, i, pou, elements, target, of, &mut diags);
            validate::structure(&chart, text, &mut diags);
            taken.extend(chart.steps.iter().map(|s| (s.name.clone(), s.name_span, "a step")));
            action_charts.push(chart);
        }
        pou.body = body;
    }
    diags.extend(code::fit_to_targets(type_diags, &charts));
    bang_outside_eatmt(file_id, text, &charts, &mut diags);
    sfc_diagnostics::sort(&mut diags);
    diags.dedup();
    Checked { file: SourceFile::new(name, text), unit, charts, action_charts, diagnostics: diags, expr_types }
}

/// An action written in SFC: its name, the name's span and its whole span.
type ActionChart = (String, Span, Span);

/// Takes the charts of a POU's actions written in SFC out of the AST, as `(action, elements)`
/// in declaration order, leaving an empty `ActionBody::Sfc` in their place.
fn take_action_charts(body: &mut ast::Body, actions: &mut [ast::Action]) -> Vec<(ActionChart, Vec<ast::SfcElement>)> {
    let in_chart = body.sfc_mut().into_iter().flatten().filter_map(|e| match e {
        ast::SfcElement::Action(a) => Some(a),
        _ => None,
    });
    in_chart
        .chain(actions.iter_mut())
        .filter_map(|a| match &mut a.body {
            ast::ActionBody::Sfc(e) => Some(((a.name.text.clone(), a.name.span, a.span), std::mem::take(e))),
            _ => None,
        })
        .collect()
}

/// `!c5` is the EATMT spelling of a negated input; anywhere else it is not IEC 61131-3.
fn bang_outside_eatmt(file_id: u32, text: &str, charts: &[Chart], diags: &mut Vec<Diagnostic>) {
    // A binary file (SFC0012) has no tokens worth reporting.
    if !text.contains('!') || diags.iter().any(|d| d.code == "SFC0012") {
        return;
    }
    let (tokens, _) = sfc_syntax::lexer::lex(file_id, text);
    for t in tokens.iter().filter(|t| t.kind == sfc_syntax::lexer::TokenKind::Bang) {
        let in_eatmt_condition = charts.iter().filter(|c| c.target == Target::Eatmt).any(|c| {
            c.transitions.iter().any(|tr| match &tr.condition {
                ast::Condition::St(e) => e.span.start <= t.start && t.end <= e.span.end,
                _ => false,
            })
        });
        if !in_eatmt_condition {
            diags.push(
                Diagnostic::error("SFC0101", Span::new(file_id, t.start, t.end), "`!` is not IEC 61131-3: write NOT")
                    .with_note("`!c5` is accepted only in the conditions of an EATMT chart"),
            );
        }
    }
}

/// The POUs `pou` depends on, itself included (upper-case names): the POUs of the file whose
/// names occur in its text (instances of function blocks, calls of functions), transitively.
pub fn dependencies(unit: &ast::SourceUnit, text: &str, pou: &str) -> std::collections::HashSet<String> {
    use std::collections::{HashMap, HashSet};
    let mut spans: HashMap<String, Span> = HashMap::new();
    for item in &unit.items {
        match item {
            ast::Item::Pou(p) => {
                spans.entry(p.name.text.to_ascii_uppercase()).or_insert(p.span);
            }
            // An interface is depended on by the blocks implementing it and the code naming it.
            ast::Item::Interface(i) => {
                spans.entry(i.name.text.to_ascii_uppercase()).or_insert(i.span);
            }
            // A POU kept as written is depended on like any other.
            ast::Item::Verbatim(v)
                if matches!(v.keyword.as_str(), "PROGRAM" | "FUNCTION_BLOCK" | "FUNCTION" | "INTERFACE") =>
            {
                if let Some(n) = &v.name {
                    spans.entry(n.text.to_ascii_uppercase()).or_insert(v.span);
                }
            }
            _ => {}
        }
    }
    let mut out = HashSet::new();
    let mut todo = vec![pou.to_ascii_uppercase()];
    while let Some(name) = todo.pop() {
        if !out.insert(name.clone()) {
            continue;
        }
        let Some(span) = spans.get(&name) else { continue };
        let body = text.get(span.start as usize..span.end as usize).unwrap_or("");
        let (toks, _) = sfc_syntax::lexer::lex(0, body);
        for t in toks.iter().filter(|t| t.kind == sfc_syntax::lexer::TokenKind::Ident) {
            let w = body[t.start as usize..t.end as usize].to_ascii_uppercase();
            if spans.contains_key(&w) && !out.contains(&w) {
                todo.push(w);
            }
        }
    }
    out
}

/// The errors of a checked file that concern the POU `pou`: those inside it or inside a POU it
/// depends on, and those outside every POU (types, globals). An error in an unrelated POU does
/// not keep `pou` from being simulated or built.
pub fn errors_for(checked: &Checked, pou: &str) -> Vec<Diagnostic> {
    let deps = dependencies(&checked.unit, &checked.file.text, pou);
    let pou_spans: Vec<(String, Span)> = checked
        .unit
        .items
        .iter()
        .filter_map(|i| match i {
            ast::Item::Pou(p) => Some((p.name.text.to_ascii_uppercase(), p.span)),
            ast::Item::Interface(i) => Some((i.name.text.to_ascii_uppercase(), i.span)),
            _ => None,
        })
        .collect();
    checked
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .filter(|d| {
            match pou_spans.iter().find(|(_, s)| s.start <= d.span.start && d.span.start < s.end.max(s.start + 1)) {
                Some((name, _)) => deps.contains(name),
                None => true,
            }
        })
        .cloned()
        .collect()
}

/// Leaves out of `checked` every POU with an error that `pou` does not depend on (it becomes a
/// block kept as written, so item numbers stay), so the rest can be compiled; returns whether
/// any was left out.
pub fn set_aside_unrelated(checked: &mut Checked, pou: &str) -> bool {
    set_aside(checked, pou, false)
}

/// Leaves out of `checked` every POU that `pou` does not depend on, with an error or not (a
/// simulation of `pou` runs only what it uses, so what it cannot run elsewhere in the file does
/// not stop it); returns whether any was left out.
pub fn set_aside_unused(checked: &mut Checked, pou: &str) -> bool {
    set_aside(checked, pou, true)
}

fn set_aside(checked: &mut Checked, pou: &str, all: bool) -> bool {
    let mut deps = dependencies(&checked.unit, &checked.file.text, pou);
    if all {
        // The file's global variables and types may name blocks too (a global instance): those
        // stay, with what they use. (A configuration's program instances are the runtime's.)
        let text = &checked.file.text;
        let mut outside = String::new();
        for item in &checked.unit.items {
            let span = match item {
                ast::Item::Globals(b) => b.span,
                ast::Item::Types(t) => t.span,
                _ => continue,
            };
            outside.push_str(text.get(span.start as usize..span.end as usize).unwrap_or(""));
            outside.push('\n');
        }
        let (toks, _) = sfc_syntax::lexer::lex(0, &outside);
        let names: std::collections::HashSet<String> = toks
            .iter()
            .filter(|t| t.kind == sfc_syntax::lexer::TokenKind::Ident)
            .map(|t| outside[t.start as usize..t.end as usize].to_ascii_uppercase())
            .collect();
        let pous: Vec<String> = checked
            .unit
            .items
            .iter()
            .filter_map(|i| match i {
                ast::Item::Pou(p) if names.contains(&p.name.text.to_ascii_uppercase()) => Some(p.name.text.clone()),
                _ => None,
            })
            .collect();
        for name in pous {
            deps.extend(dependencies(&checked.unit, text, &name));
        }
    }
    let errors: Vec<Span> = checked.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.span).collect();
    let mut any = false;
    for item in checked.unit.items.iter_mut() {
        let ast::Item::Pou(p) = item else { continue };
        if deps.contains(&p.name.text.to_ascii_uppercase()) {
            continue;
        }
        if !all && !errors.iter().any(|e| p.span.start <= e.start && e.start < p.span.end) {
            continue;
        }
        let text = checked.file.text.get(p.span.start as usize..p.span.end as usize).unwrap_or("").to_string();
        *item = ast::Item::Verbatim(ast::Verbatim {
            keyword: p.kind.keyword().to_string(),
            attributes: p.attributes.clone(),
            name: Some(p.name.clone()),
            text,
            span: p.span,
        });
        any = true;
    }
    if any {
        let kept: std::collections::HashSet<usize> = checked
            .unit
            .items
            .iter()
            .enumerate()
            .filter(|(_, i)| matches!(i, ast::Item::Pou(_)))
            .map(|(k, _)| k)
            .collect();
        checked.charts.retain(|c| kept.contains(&c.item));
        checked.action_charts.retain(|c| kept.contains(&c.item));
        checked.diagnostics.retain(|d| !d.is_error() || errors_for_span(&checked.unit, d.span));
    }
    any
}

/// Whether an error at `span` is in a POU still analysed or outside every POU.
fn errors_for_span(unit: &ast::SourceUnit, span: Span) -> bool {
    !unit
        .items
        .iter()
        .any(|i| matches!(i, ast::Item::Verbatim(v) if v.span.start <= span.start && span.start < v.span.end))
}

#[cfg(test)]
mod tree_tests {
    use super::*;
    use std::sync::Arc;

    /// A shared tree checks as an owned one does, whether the other reader still holds it (the
    /// checker copies it) or has let go (the checker takes it over); the other reader's tree is
    /// left whole.
    #[test]
    fn a_shared_tree_checks_as_an_owned_one() {
        let text = "PROGRAM P\nVAR x : BOOL; i : INT; END_VAR\nINITIAL_STEP S1: A(N); END_STEP\nSTEP S2: B(Q); END_STEP\n\
                    TRANSITION FROM S1 TO S2 := x AND i; END_TRANSITION\nTRANSITION FROM S2 TO S3 := TRUE; END_TRANSITION\n\
                    ACTION A: i := i + 1; y := 2; END_ACTION\nEND_PROGRAM\n";
        let opts = CheckOptions { keep_types: true, ..CheckOptions::default() };
        let owned = check_parsed(0, "t.st", text, sfc_syntax::parse(0, text), &opts);
        assert!(owned.has_errors());
        let (unit, parse_diags) = sfc_syntax::parse(0, text);
        let whole = unit.clone();
        let held = Arc::new(unit);
        let shared = check_parsed(0, "t.st", text, (held.clone(), parse_diags.clone()), &opts);
        assert_eq!(*held, whole);
        let alone = check_parsed(0, "t.st", text, (Arc::new(whole), parse_diags), &opts);
        for c in [&shared, &alone] {
            assert_eq!(c.diagnostics, owned.diagnostics);
            assert_eq!(c.unit, owned.unit);
            assert_eq!(c.charts, owned.charts);
            assert_eq!(c.expr_types, owned.expr_types);
        }
    }
}
