//! The chart a document draws: which blocks are IEC steps and transitions, and each
//! transition's FROM and TO steps, read through divergences, convergences and jumps. Saving
//! (`write.rs`), the consistency check of a saved layout (`open.rs`), the layout and the
//! element ids all use this one reading, so they agree.

use crate::readback::Probe;
use crate::{EditorDoc, Element, ElementKind, Problem};
use sfc_diagnostics::Severity;
use std::collections::HashMap;

/// Branch pins beyond this are not read (a bar with more is reported).
pub const MAX_PINS: u32 = 1024;

/// Number of input and output pins of a block (see the table in the crate docs).
pub fn pin_counts(e: &Element) -> (u32, u32) {
    let n = e.pins.unwrap_or(2).clamp(2, MAX_PINS);
    match e.kind {
        Some(ElementKind::Step | ElementKind::Transition) => (1, 1),
        Some(ElementKind::SelectionDivergence | ElementKind::SimultaneousDivergence) => (1, n),
        Some(ElementKind::SelectionConvergence | ElementKind::SimultaneousConvergence) => (n, 1),
        Some(ElementKind::Jump) => (1, 0),
        _ => (0, 0),
    }
}

/// Whether an output of `from` may feed an input of `to`: the pairs of the contract, plus a
/// selection divergence feeding a simultaneous convergence and a simultaneous divergence
/// feeding a selection convergence or a jump (IEC draws those when one step's branch joins a
/// simultaneous transition, or one branch of a simultaneous divergence re-enters a step that
/// has other predecessors).
pub fn valid_pair(from: ElementKind, to: ElementKind) -> bool {
    use ElementKind::*;
    matches!(
        (from, to),
        (Step, Transition | SelectionDivergence | SimultaneousConvergence)
            | (SelectionDivergence, Transition | SimultaneousConvergence)
            | (SimultaneousConvergence, Transition)
            | (Transition, Step | SimultaneousDivergence | SelectionConvergence | Jump)
            | (SimultaneousDivergence, Step | SelectionConvergence | Jump)
            | (SelectionConvergence, Step)
    )
}

/// What a block becomes in the text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The k-th step of the text.
    Step(usize),
    /// The k-th transition of the text.
    Transition(usize),
    /// Only in the layout attribute (bars, jumps, labels, action blocks, and steps or
    /// transitions that cannot be written yet).
    Other,
}

/// A transition of the text: its block and its FROM/TO steps (block indices, pin order).
#[derive(Debug, Clone, PartialEq)]
pub struct TextTransition {
    pub element: usize,
    pub from: Vec<usize>,
    pub to: Vec<usize>,
}

/// The reading of a document.
#[derive(Debug, Clone)]
pub struct Derived {
    pub roles: Vec<Role>,
    /// Text steps, as block indices, in block order.
    pub steps: Vec<usize>,
    pub transitions: Vec<TextTransition>,
    /// First block with each id.
    pub by_id: HashMap<String, usize>,
    /// The connections read (others are reported and ignored), as indices into
    /// `doc.connections`.
    pub used: Vec<bool>,
    /// Per block: the connection on each input and output pin.
    pub ins: Vec<Vec<Option<usize>>>,
    pub outs: Vec<Vec<Option<usize>>>,
    /// Per jump block: the text step it targets.
    pub jump_targets: HashMap<usize, usize>,
    pub problems: Vec<Problem>,
}

fn problem(code: &'static str, element: &str, message: impl Into<String>) -> Problem {
    Problem { code, severity: Severity::Error, element: element.to_string(), message: message.into() }
}

fn kind_name(k: Option<ElementKind>) -> &'static str {
    match k {
        Some(ElementKind::Step) => "a step",
        Some(ElementKind::Transition) => "a transition",
        Some(ElementKind::SelectionDivergence) => "a selection divergence",
        Some(ElementKind::SelectionConvergence) => "a selection convergence",
        Some(ElementKind::SimultaneousDivergence) => "a simultaneous divergence",
        Some(ElementKind::SimultaneousConvergence) => "a simultaneous convergence",
        Some(ElementKind::Jump) => "a jump",
        Some(ElementKind::Text) => "a text",
        Some(ElementKind::ActionBlock) => "an action block",
        None => "a block without a kind",
    }
}

/// Reads the chart a document draws.
pub fn derive(doc: &EditorDoc, probe: &mut Probe) -> Derived {
    let n = doc.elements.len();
    let mut problems = Vec::new();
    let mut by_id: HashMap<String, usize> = HashMap::new();
    for (i, e) in doc.elements.iter().enumerate() {
        if by_id.contains_key(&e.id) {
            problems.push(problem("SFC0206", &e.id, format!("the id `{}` is used by another block too", e.id)));
        } else {
            by_id.insert(e.id.clone(), i);
        }
        if e.kind.is_none() {
            problems.push(problem("SFC0205", &e.id, "the block has no kind"));
        }
        if e.pins.is_some_and(|p| p > MAX_PINS) {
            problems.push(problem("SFC0205", &e.id, format!("a bar has at most {MAX_PINS} branch pins")));
        }
    }
    let counts: Vec<(u32, u32)> = doc.elements.iter().map(pin_counts).collect();
    let mut ins: Vec<Vec<Option<usize>>> = counts.iter().map(|c| vec![None; c.0 as usize]).collect();
    let mut outs: Vec<Vec<Option<usize>>> = counts.iter().map(|c| vec![None; c.1 as usize]).collect();
    let mut used = vec![false; doc.connections.len()];
    for (ci, c) in doc.connections.iter().enumerate() {
        let (Some(&s), Some(&t)) = (by_id.get(&c.source), by_id.get(&c.target)) else {
            let missing = if by_id.contains_key(&c.source) { &c.target } else { &c.source };
            problems.push(problem(
                "SFC0205",
                &c.id,
                format!("the connection ends at `{missing}`, which is not in the chart"),
            ));
            continue;
        };
        let (sk, tk) = (doc.elements[s].kind, doc.elements[t].kind);
        if c.source_pin >= counts[s].1 || c.target_pin >= counts[t].0 {
            problems.push(problem(
                "SFC0205",
                &c.id,
                format!(
                    "the connection uses output pin {} of {} and input pin {} of {}, which do not exist",
                    c.source_pin,
                    kind_name(sk),
                    c.target_pin,
                    kind_name(tk)
                ),
            ));
            continue;
        }
        if s == t || !matches!((sk, tk), (Some(a), Some(b)) if valid_pair(a, b)) {
            problems.push(problem(
                "SFC0205",
                &c.id,
                format!("{} cannot be connected to {}", kind_name(sk), kind_name(tk)),
            ));
            continue;
        }
        let (sp, tp) = (c.source_pin as usize, c.target_pin as usize);
        if outs[s][sp].is_some() || ins[t][tp].is_some() {
            problems.push(problem("SFC0205", &c.id, "a pin holds at most one connection"));
            continue;
        }
        outs[s][sp] = Some(ci);
        ins[t][tp] = Some(ci);
        used[ci] = true;
    }
    // Bars must have every pin connected to say something in the text.
    for (i, e) in doc.elements.iter().enumerate() {
        let bar = matches!(
            e.kind,
            Some(
                ElementKind::SelectionDivergence
                    | ElementKind::SelectionConvergence
                    | ElementKind::SimultaneousDivergence
                    | ElementKind::SimultaneousConvergence
            )
        );
        if bar && (ins[i].iter().chain(outs[i].iter()).any(Option::is_none)) {
            problems.push(problem("SFC0205", &e.id, format!("{} has an unconnected pin", kind_name(e.kind))));
        }
    }

    // Text steps: a name the text can hold, not taken by an earlier step.
    let mut roles = vec![Role::Other; n];
    let mut steps = Vec::new();
    let mut step_names: HashMap<String, usize> = HashMap::new();
    for (i, e) in doc.elements.iter().enumerate() {
        if e.kind != Some(ElementKind::Step) {
            continue;
        }
        if !probe.is_name(&e.name) {
            let m = if e.name.is_empty() {
                "the step has no name; it is kept in the layout only".to_string()
            } else {
                format!("`{}` is not a valid step name; the step is kept in the layout only", e.name)
            };
            problems.push(problem("SFC0101", &e.id, m));
            continue;
        }
        let key = e.name.to_ascii_uppercase();
        if step_names.contains_key(&key) {
            problems.push(problem(
                "SFC0206",
                &e.id,
                format!("another step is named `{}`; this one is kept in the layout only", e.name),
            ));
            continue;
        }
        step_names.insert(key, i);
        roles[i] = Role::Step(steps.len());
        steps.push(i);
    }
    let mut jump_targets = HashMap::new();
    for (i, e) in doc.elements.iter().enumerate() {
        if e.kind != Some(ElementKind::Jump) {
            continue;
        }
        let target = e.target.as_deref().unwrap_or("");
        match step_names.get(&target.to_ascii_uppercase()) {
            Some(&s) => {
                jump_targets.insert(i, s);
            }
            None => problems.push(problem("SFC0212", &e.id, format!("the jump goes to `{target}`, which is no step"))),
        }
    }

    let step_roles = roles.clone();
    let r = Reader { doc, roles: &step_roles, ins: &ins, outs: &outs, jump_targets: &jump_targets, by_id: &by_id };
    let mut transitions = Vec::new();
    let mut transition_names: HashMap<String, usize> = HashMap::new();
    for (i, e) in doc.elements.iter().enumerate() {
        if e.kind != Some(ElementKind::Transition) {
            continue;
        }
        let mut from = Vec::new();
        r.up(i, &mut from);
        let mut to = Vec::new();
        r.down(i, &mut to);
        for list in [&mut from, &mut to] {
            let mut seen = Vec::new();
            list.retain(|s| {
                let fresh = !seen.contains(s);
                seen.push(*s);
                fresh
            });
            if seen.len() != list.len() {
                problems.push(problem("SFC0216", &e.id, "the transition reaches one step twice on one side"));
            }
        }
        if !e.name.is_empty() && !probe.is_name(&e.name) {
            problems.push(problem(
                "SFC0101",
                &e.id,
                format!("`{}` is not a valid transition name; the transition is kept in the layout only", e.name),
            ));
            continue;
        }
        if !e.name.is_empty() && transition_names.contains_key(&e.name.to_ascii_uppercase()) {
            problems.push(problem(
                "SFC0206",
                &e.id,
                format!("another transition is named `{}`; this one is kept in the layout only", e.name),
            ));
            continue;
        }
        if from.is_empty() || to.is_empty() {
            let side = if from.is_empty() { "no step before it" } else { "no step after it" };
            problems.push(problem(
                "SFC0204",
                &e.id,
                format!("the transition has {side}; it is kept in the layout only until it is connected"),
            ));
            continue;
        }
        if !e.name.is_empty() {
            transition_names.insert(e.name.to_ascii_uppercase(), i);
        }
        roles[i] = Role::Transition(transitions.len());
        transitions.push(TextTransition { element: i, from, to });
    }
    Derived { roles, steps, transitions, by_id, used, ins, outs, jump_targets, problems }
}

struct Reader<'a> {
    doc: &'a EditorDoc,
    roles: &'a [Role],
    ins: &'a [Vec<Option<usize>>],
    outs: &'a [Vec<Option<usize>>],
    jump_targets: &'a HashMap<usize, usize>,
    by_id: &'a HashMap<String, usize>,
}

impl Reader<'_> {
    fn kind(&self, i: usize) -> Option<ElementKind> {
        self.doc.elements.get(i).and_then(|e| e.kind)
    }
    fn source(&self, i: usize, pin: usize) -> Option<usize> {
        let c = (*self.ins[i].get(pin)?)?;
        Some(self.idx(&self.doc.connections[c].source))
    }
    fn target(&self, i: usize, pin: usize) -> Option<usize> {
        let c = (*self.outs[i].get(pin)?)?;
        Some(self.idx(&self.doc.connections[c].target))
    }
    fn idx(&self, id: &str) -> usize {
        // Connections are only recorded on pins when both ends exist.
        self.by_id.get(id).copied().unwrap_or(usize::MAX)
    }
    fn text_step(&self, i: usize, out: &mut Vec<usize>) {
        if matches!(self.roles.get(i), Some(Role::Step(_))) {
            out.push(i);
        }
    }
    /// The steps before a transition.
    fn up(&self, t: usize, out: &mut Vec<usize>) {
        let Some(src) = self.source(t, 0) else { return };
        match self.kind(src) {
            Some(ElementKind::Step) => self.text_step(src, out),
            Some(ElementKind::SelectionDivergence) => self.above_divergence(src, out),
            Some(ElementKind::SimultaneousConvergence) => {
                for pin in 0..self.ins[src].len() {
                    match self.source(src, pin) {
                        Some(s) if self.kind(s) == Some(ElementKind::Step) => self.text_step(s, out),
                        Some(s) if self.kind(s) == Some(ElementKind::SelectionDivergence) => {
                            self.above_divergence(s, out)
                        }
                        _ => {}
                    }
                }
            }
            _ => {}
        }
    }
    fn above_divergence(&self, d: usize, out: &mut Vec<usize>) {
        if let Some(s) = self.source(d, 0).filter(|&s| self.kind(s) == Some(ElementKind::Step)) {
            self.text_step(s, out);
        }
    }
    /// The steps after a transition.
    fn down(&self, t: usize, out: &mut Vec<usize>) {
        let Some(dst) = self.target(t, 0) else { return };
        match self.kind(dst) {
            Some(ElementKind::SimultaneousDivergence) => {
                for pin in 0..self.outs[dst].len() {
                    if let Some(d) = self.target(dst, pin) {
                        self.entry(d, out);
                    }
                }
            }
            _ => self.entry(dst, out),
        }
    }
    /// The step a branch enters: directly, through a selection convergence, or by a jump.
    fn entry(&self, d: usize, out: &mut Vec<usize>) {
        match self.kind(d) {
            Some(ElementKind::Step) => self.text_step(d, out),
            Some(ElementKind::Jump) => out.extend(self.jump_targets.get(&d).copied()),
            Some(ElementKind::SelectionConvergence) => {
                if let Some(s) = self.target(d, 0).filter(|&s| self.kind(s) == Some(ElementKind::Step)) {
                    self.text_step(s, out);
                }
            }
            _ => {}
        }
    }
}

/// The ids `open` gives: `step:NAME` and `transition:NAME` / `transition#K` for the steps and
/// transitions of the text, `b1`, `b2`, … for every other block in order; connections `c1`,
/// `c2`, … in order.
pub fn canonical_ids(doc: &EditorDoc, d: &Derived) -> (Vec<String>, Vec<String>) {
    let mut other = 0;
    let ids = doc
        .elements
        .iter()
        .zip(&d.roles)
        .map(|(e, role)| match role {
            Role::Step(_) => format!("step:{}", e.name),
            Role::Transition(k) if e.name.is_empty() => format!("transition#{k}"),
            Role::Transition(_) => format!("transition:{}", e.name),
            Role::Other => {
                other += 1;
                format!("b{other}")
            }
        })
        .collect();
    let conns = (1..=doc.connections.len()).map(|k| format!("c{k}")).collect();
    (ids, conns)
}

/// What a reference to a block that is not in the document becomes: a name no canonical id
/// can take, so it never starts to designate a block.
pub fn dangling(id: &str) -> String {
    if id.starts_with("missing:") {
        id.to_string()
    } else {
        format!("missing:{id}")
    }
}

/// The document with the ids `open` would give it (see [`canonical_ids`]); references to
/// blocks follow, references to missing blocks become [`dangling`]. Wires are as `open` gives
/// them: a straight wire kept as its two pins (as the canvas keeps it) has no waypoints, a
/// wire without waypoints that is not straight runs on its automatic route (the canvas draws
/// it so).
pub fn normalize(doc: &EditorDoc, d: &Derived) -> EditorDoc {
    let (ids, conn_ids) = canonical_ids(doc, d);
    let routes = crate::layout::canonical_routes(doc, d);
    let map = |old: &str| -> String {
        match d.by_id.get(old) {
            Some(&i) => ids[i].clone(),
            None => dangling(old),
        }
    };
    let mut out = doc.clone();
    for (e, id) in out.elements.iter_mut().zip(&ids) {
        e.id = id.clone();
        if let Some(s) = e.step.as_mut() {
            *s = map(s);
        }
    }
    for (k, (c, id)) in out.connections.iter_mut().zip(conn_ids).enumerate() {
        if let Some(Some(w)) = routes.get(k) {
            c.waypoints = w.clone();
        }
        c.id = id;
        c.source = map(&c.source);
        c.target = map(&c.target);
    }
    out
}

/// See [`crate::element_ids`].
pub fn element_ids(doc: &EditorDoc, element: &str, probe: &mut Probe) -> Vec<String> {
    let d = derive(doc, probe);
    let mut out: Vec<String> = doc
        .elements
        .iter()
        .filter(|e| matches!(e.kind, Some(ElementKind::Step | ElementKind::Transition)))
        .filter(|e| !e.name.is_empty() && e.name.eq_ignore_ascii_case(element))
        .map(|e| e.id.clone())
        .collect();
    if out.is_empty() {
        // Unnamed transitions are `T<n>` (n their position among the transitions), or the
        // first free `T<n>_k`, as the model names them.
        let mut taken: std::collections::HashSet<String> = doc
            .elements
            .iter()
            .filter(|e| matches!(e.kind, Some(ElementKind::Step | ElementKind::Transition)))
            .map(|e| e.name.to_ascii_uppercase())
            .chain(doc.actions.iter().map(|a| a.name.to_ascii_uppercase()))
            .collect();
        for (k, t) in d.transitions.iter().enumerate() {
            let e = &doc.elements[t.element];
            if !e.name.is_empty() {
                continue;
            }
            let base = format!("T{}", k + 1);
            let mut name = base.clone();
            let mut n = 0;
            while taken.contains(&name.to_ascii_uppercase()) {
                n += 1;
                name = format!("{base}_{n}");
            }
            taken.insert(name.to_ascii_uppercase());
            if name.eq_ignore_ascii_case(element) {
                out.push(e.id.clone());
            }
        }
    }
    out.extend(
        doc.elements
            .iter()
            .filter(|e| e.kind == Some(ElementKind::ActionBlock))
            .filter(|e| e.associations.iter().any(|a| a.action.eq_ignore_ascii_case(element)))
            .map(|e| e.id.clone()),
    );
    out
}
