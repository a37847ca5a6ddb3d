//! Saving: a document as the IEC text of its POU in the canonical style of `sfc fmt`, with the
//! `sfc.*` attributes of its steps and transitions and one `sfc.graph` attribute for the rest.

use crate::graph::{self, Derived, Role};
use crate::pragma::{self, escape, line, num};
use crate::readback::Probe;
use crate::sidecar::{self, ActEntry, End, Entry, Sidecar, Wire};
use crate::{
    ActionDef, ChartTarget, EditorDoc, Element, ElementKind, Language, OtherAttribute, PouKind, Problem, Written,
};
use sfc_diagnostics::Severity;
use sfc_syntax::attr_value::{Loose, LOOSE};
use std::collections::HashMap;

const IND: &str = "    ";

/// What a step or transition reads back as once written: the fields the text holds.
pub fn as_read(e: &Element, probe: &mut Probe) -> Element {
    let mut r = Element {
        id: e.id.clone(),
        kind: e.kind,
        x: e.x,
        y: e.y,
        w: e.w,
        h: e.h,
        name: e.name.clone(),
        tag: e.tag,
        description: e.description.clone(),
        background: e.background.clone(),
        foreground: e.foreground.clone(),
        line_width: e.line_width,
        hide_label: e.hide_label,
        ..Element::default()
    };
    if matches!(e.kind, Some(ElementKind::Step | ElementKind::Transition)) {
        r.comments = probe.comments(&e.comments);
    }
    match e.kind {
        Some(ElementKind::Step) => {
            r.attributes = pragma::readable(&e.attributes, pragma::STEP);
            r.initial = e.initial;
            r.timeout = e.timeout.clone();
            r.is_final = e.is_final;
            r.step_actions = e.step_actions.iter().filter_map(|a| probe.step_action(a)).collect();
        }
        Some(ElementKind::Transition) => {
            r.attributes = pragma::readable(&e.attributes, pragma::TRANSITION);
            let (_, cond, lang) = probe.condition(e.condition.as_deref(), e.condition_language);
            r.condition = cond;
            r.condition_language = lang;
            r.priority = e.priority;
        }
        _ => {}
    }
    r
}

/// The target's attribute value.
pub fn target_name(t: ChartTarget) -> &'static str {
    match t {
        ChartTarget::Blank => "blank",
        ChartTarget::Atmt => "atmt",
        ChartTarget::Eatmt => "eatmt",
    }
}

fn problem(code: &'static str, element: &str, message: impl Into<String>) -> Problem {
    Problem { code, severity: Severity::Error, element: element.to_string(), message: message.into() }
}

/// The comments that can be written, each on its own line (see [`Probe::is_comment`]).
fn comment_lines(list: &[String], probe: &mut Probe, out: &mut String) {
    for c in list.iter().filter(|c| probe.is_comment(c)) {
        out.push_str(IND);
        out.push_str(c);
        out.push('\n');
    }
}

/// The attributes every step and transition of the text carries, in a fixed order.
fn element_attributes(e: &Element, out: &mut String, extra: &[(&str, String)]) {
    for (name, v) in [("sfc.x", e.x), ("sfc.y", e.y), ("sfc.w", e.w), ("sfc.h", e.h)] {
        out.push_str(&line(IND, name, &num(v)));
    }
    for (name, v) in extra {
        out.push_str(&line(IND, name, v));
    }
    if let Some(t) = e.tag {
        out.push_str(&line(IND, "sfc.tag", &t.to_string()));
    }
    if e.kind == Some(ElementKind::Step) {
        if let Some(t) = &e.timeout {
            out.push_str(&line(IND, "sfc.timeout", &escape(t)));
        }
        if e.is_final {
            out.push_str(&line(IND, "sfc.final", "true"));
        }
    }
    if !e.description.is_empty() {
        out.push_str(&line(IND, "sfc.description", &escape(&e.description)));
    }
    if let Some(c) = &e.background {
        out.push_str(&line(IND, "sfc.background", &escape(c)));
    }
    if let Some(c) = &e.foreground {
        out.push_str(&line(IND, "sfc.foreground", &escape(c)));
    }
    if let Some(w) = e.line_width {
        out.push_str(&line(IND, "sfc.linewidth", &num(w)));
    }
    if e.hide_label {
        out.push_str(&line(IND, "sfc.hidelabel", "true"));
    }
    let known = if e.kind == Some(ElementKind::Step) { pragma::STEP } else { pragma::TRANSITION };
    out.push_str(&pragma::write_others(IND, &e.attributes, known));
}

/// The action written in SFC of a chart document (see [`ActionDef::chart`]) as the action its
/// text is: the chart written the way a POU's is, its elements the action's body and its POU
/// attributes (`sfc.graph`, `sfc.comment`, …) the action's attributes. The problems of the
/// chart are named after the action; a condition that does not parse is SFC0101 (it would be
/// written FALSE).
pub fn flat_action(a: &ActionDef, pou_attributes: &[OtherAttribute], probe: &mut Probe) -> (ActionDef, Vec<Problem>) {
    let Some(chart) = &a.chart else { return (a.clone(), Vec::new()) };
    let dialect: Vec<OtherAttribute> =
        pou_attributes.iter().filter(|x| x.name.eq_ignore_ascii_case("sfc.dialect")).cloned().collect();
    let mut attributes = dialect.clone();
    attributes.extend(chart.attributes.iter().filter(|x| !x.name.eq_ignore_ascii_case("sfc.dialect")).cloned());
    let doc = EditorDoc {
        pou: "P".to_string(),
        pou_kind: PouKind::Program,
        target: ChartTarget::Blank,
        description: String::new(),
        declarations: String::new(),
        body: None,
        body_language: Language::St,
        actions: Vec::new(),
        attributes,
        ..(**chart).clone()
    };
    let written = write(&doc);
    let mut problems = Vec::new();
    for p in written.problems {
        let typed = chart
            .elements
            .iter()
            .find(|e| e.id == p.element)
            .and_then(|e| e.condition.as_deref())
            .is_some_and(|c| !c.trim().is_empty());
        let (code, message) = if p.code == "SFC0217" && typed {
            let name = chart.elements.iter().find(|e| e.id == p.element).map(|e| e.name.clone()).unwrap_or_default();
            let which = if name.is_empty() { "a transition".to_string() } else { format!("`{name}`") };
            ("SFC0101", format!("action `{}`: the condition of {which} does not parse", a.name))
        } else {
            (p.code, format!("action `{}`: {}", a.name, p.message))
        };
        problems.push(Problem { code, message, ..p });
    }
    // Lines before the header are the chart's attributes; those between it and the end, its
    // elements.
    let mut attrs = Vec::new();
    let mut body = Vec::new();
    let mut in_body = false;
    for l in written.text.lines() {
        if !in_body {
            if l.starts_with("PROGRAM ") {
                in_body = true;
            } else if let Some(x) = attribute_of_line(l) {
                let skip = ["sfc.target", "sfc.description", "sfc.dialect"];
                if !skip.iter().any(|n| x.name.eq_ignore_ascii_case(n)) {
                    attrs.push(x);
                }
            }
        } else if l != "END_PROGRAM" {
            body.push(l);
        }
    }
    let mut flat = ActionDef {
        name: a.name.clone(),
        language: Language::St,
        body: crate::region::dedent(&body.join("\n")),
        description: a.description.clone(),
        attributes: attrs,
        comments: a.comments.clone(),
        chart: None,
    };
    // The body as it reads back, so that the text alone says it.
    let read = probe.action(&flat).1;
    if !read.body.is_empty() {
        flat.body = read.body;
    }
    (flat, problems)
}

/// `{attribute 'name' := 'value'}` or `{attribute 'name'}` as written by [`line`].
fn attribute_of_line(l: &str) -> Option<OtherAttribute> {
    let rest = l.trim().strip_prefix("{attribute '")?.strip_suffix('}')?;
    let (name, value) = rest.split_once('\'')?;
    let value = value.trim();
    let value = if value.is_empty() {
        None
    } else {
        Some(value.strip_prefix(":=")?.trim().strip_prefix('\'')?.strip_suffix('\'')?.to_string())
    };
    Some(OtherAttribute { name: name.to_string(), value })
}

/// Writes a document; see [`crate::to_text`].
pub fn write(doc: &EditorDoc) -> Written {
    if doc.body.is_some() {
        return write_text_pou(doc);
    }
    let mut probe = Probe::for_attributes(&doc.attributes);
    let d = graph::derive(doc, &mut probe);
    let mut problems = d.problems.clone();
    let mut car = Sidecar { v: sidecar::VERSION, ..Sidecar::default() };

    // The POU's name and declarations.
    let pou_name = if probe.is_name(&doc.pou) {
        doc.pou.clone()
    } else {
        problems.push(problem("SFC0101", "", format!("`{}` is not a valid POU name", doc.pou)));
        car.pou = Some(doc.pou.clone());
        "Unnamed".to_string()
    };
    let (decl_text, decl_read) = probe.declarations(&doc.declarations);
    if decl_read != doc.declarations {
        car.decl = Some(doc.declarations.clone());
        if decl_text.is_empty() && !doc.declarations.trim().is_empty() {
            problems.push(problem("SFC0101", "", "the declarations do not parse; they are kept in the layout only"));
        }
    }

    // Actions.
    let (actions_text, acts, plain_acts) = write_actions(doc, &mut probe, &mut problems);
    if !plain_acts {
        car.acts = Some(acts);
    }

    // Action blocks: the associations of a step of the text, in block order.
    let mut step_assocs: HashMap<usize, Vec<String>> = HashMap::new();
    let mut step_blocks: HashMap<usize, Vec<String>> = HashMap::new();
    let mut entries: Vec<Entry> = Vec::with_capacity(doc.elements.len());
    for (i, e) in doc.elements.iter().enumerate() {
        let entry = match d.roles[i] {
            Role::Step(_) => {
                let r = as_read(e, &mut probe);
                let (st, sr) = step_ref(&d, e);
                Entry { s: Some(e.name.clone()), o: (r != *e).then(|| bare(e)), st, sr, ..Entry::default() }
            }
            Role::Transition(_) => {
                let r = as_read(e, &mut probe);
                let typed = e.condition.as_deref().map(str::trim);
                if r.condition.as_deref() == Some("FALSE") && typed != Some("FALSE") {
                    problems.push(problem(
                        "SFC0217",
                        &e.id,
                        "the condition is missing or does not parse; the text holds FALSE until it is fixed",
                    ));
                }
                let (st, sr) = step_ref(&d, e);
                Entry { t: Some(e.name.clone()), o: (r != *e).then(|| bare(e)), st, sr, ..Entry::default() }
            }
            Role::Other => other_entry(doc, &d, i, &mut probe, &mut step_assocs, &mut step_blocks, &mut problems),
        };
        entries.push(entry);
    }
    car.e = entries;
    if probe.comments(&doc.trailing_comments) != doc.trailing_comments {
        car.tc = Some(doc.trailing_comments.clone());
    }
    // A wire on its automatic route is saved without waypoints (opening routes it again), so
    // moving a block does not change the lines of its wires.
    let automatic = crate::layout::on_automatic_route(doc, &d);
    car.c = doc
        .connections
        .iter()
        .enumerate()
        .map(|(k, c)| Wire {
            s: end(&d, &c.source),
            sp: c.source_pin,
            t: end(&d, &c.target),
            tp: c.target_pin,
            w: if automatic.get(k).copied().unwrap_or(false) { Vec::new() } else { c.waypoints.clone() },
            col: c.color.clone(),
            lw: c.line_width,
        })
        .collect();

    // Jumps drawn below each transition of the text, for PLCopen export.
    let mut jumps: HashMap<usize, Vec<String>> = HashMap::new();
    for (&j, &s) in &d.jump_targets {
        if let Some(t) = jump_source(doc, &d, j) {
            let e = &doc.elements[j];
            jumps.entry(t).or_default().push(format!("{} {} {}", doc.elements[s].name, num(e.x), num(e.y)));
        }
    }

    // The text.
    let mut out = String::new();
    out.push_str(&line("", "sfc.target", target_name(doc.target)));
    if !doc.description.is_empty() {
        out.push_str(&line("", "sfc.description", &escape(&doc.description)));
    }
    for e in doc.elements.iter().filter(|e| e.kind == Some(ElementKind::Text)) {
        let v = format!("{} {} {} {}\n{}", num(e.x), num(e.y), num(e.w), num(e.h), e.text.as_deref().unwrap_or(""));
        out.push_str(&line("", "sfc.comment", &escape(&v)));
    }
    // Transitions not connected on both sides, which the text cannot hold, for other tools
    // (the PLCopen export draws them); `sfc.graph` keeps them for the editor.
    for (i, e) in doc.elements.iter().enumerate() {
        if e.kind != Some(ElementKind::Transition) || !matches!(d.roles[i], Role::Other) {
            continue;
        }
        let (mut from, mut to) = (Vec::new(), Vec::new());
        // Ends by block position (ids may repeat in a document being edited).
        for c in &doc.connections {
            let (Some(&s), Some(&t)) = (d.by_id.get(&c.source), d.by_id.get(&c.target)) else { continue };
            let (other, list) = if t == i {
                (s, &mut from)
            } else if s == i {
                (t, &mut to)
            } else {
                continue;
            };
            if let Some(s) = doc.elements.get(other) {
                if s.kind == Some(ElementKind::Step) && probe.is_name(&s.name) {
                    list.push(s.name.clone());
                }
            }
        }
        let loose = Loose {
            rect: Some([e.x, e.y, e.w, e.h]),
            from,
            to,
            name: if probe.is_name(&e.name) { e.name.clone() } else { String::new() },
            condition: e.condition.clone().unwrap_or_default().replace('\r', ""),
        };
        out.push_str(&line("", LOOSE, &escape(&loose.write())));
    }
    if pragma::readable(&doc.attributes, pragma::POU) != doc.attributes {
        car.attrs = Some(doc.attributes.clone());
    }
    out.push_str(&pragma::write_others("", &doc.attributes, pragma::POU));
    out.push_str(&sidecar::write(&car));
    let kind = match doc.pou_kind {
        PouKind::Program => "PROGRAM",
        PouKind::FunctionBlock => "FUNCTION_BLOCK",
    };
    out.push_str(&format!("{kind} {pou_name}\n"));
    out.push_str(&decl_text);

    let mut blocks: Vec<String> = Vec::new();
    let step_text = |k: usize, probe: &mut Probe| -> String {
        let i = d.steps[k];
        let e = &doc.elements[i];
        let mut t = String::new();
        comment_lines(&e.comments, probe, &mut t);
        let extra: Vec<(&str, String)> =
            step_blocks.get(&i).map(|b| vec![("sfc.actionblock", b.join(";"))]).unwrap_or_default();
        element_attributes(e, &mut t, &extra);
        let kw = if e.initial { "INITIAL_STEP" } else { "STEP" };
        let none = Vec::new();
        let assocs = step_assocs.get(&i).unwrap_or(&none);
        let step_actions: Vec<String> = e.step_actions.iter().filter_map(|a| probe.step_action(a)).collect();
        match step_actions.len() + assocs.len() {
            0 => t.push_str(&format!("{IND}{kw} {}: END_STEP\n", e.name)),
            _ => {
                t.push_str(&format!("{IND}{kw} {}:\n", e.name));
                for a in step_actions.iter().chain(assocs) {
                    t.push_str(&format!("{IND}{IND}{a};\n"));
                }
                t.push_str(&format!("{IND}END_STEP\n"));
            }
        }
        t
    };
    let transition_text = |k: usize, probe: &mut Probe| -> String {
        let tt = &d.transitions[k];
        let e = &doc.elements[tt.element];
        let mut t = String::new();
        comment_lines(&e.comments, probe, &mut t);
        let extra: Vec<(&str, String)> =
            jumps.get(&tt.element).map(|j| vec![("sfc.jump", j.join(";"))]).unwrap_or_default();
        element_attributes(e, &mut t, &extra);
        t.push_str(IND);
        t.push_str("TRANSITION");
        if !e.name.is_empty() {
            t.push(' ');
            t.push_str(&e.name);
        }
        if let Some(p) = e.priority {
            t.push_str(&format!(" (PRIORITY := {p})"));
        }
        let list = |l: &[usize]| {
            let names: Vec<&str> = l.iter().map(|&s| doc.elements[s].name.as_str()).collect();
            if names.len() == 1 {
                names[0].to_string()
            } else {
                format!("({})", names.join(", "))
            }
        };
        t.push_str(&format!(" FROM {} TO {}", list(&tt.from), list(&tt.to)));
        let (fragment, _, _) = probe.condition(e.condition.as_deref(), e.condition_language);
        t.push_str(&fragment);
        t.push_str(&format!("{IND}END_TRANSITION\n"));
        t
    };
    // Steps in order, each followed by the transitions (in order) whose steps are all written.
    let step_pos: HashMap<usize, usize> = d.steps.iter().enumerate().map(|(k, &i)| (i, k)).collect();
    let ready_after: Vec<usize> = d
        .transitions
        .iter()
        .map(|t| t.from.iter().filter_map(|s| step_pos.get(s)).copied().max().unwrap_or(0))
        .collect();
    let mut next_t = 0;
    for k in 0..d.steps.len() {
        blocks.push(step_text(k, &mut probe));
        while next_t < d.transitions.len() && ready_after[next_t] <= k {
            blocks.push(transition_text(next_t, &mut probe));
            next_t += 1;
        }
    }
    while next_t < d.transitions.len() {
        blocks.push(transition_text(next_t, &mut probe));
        next_t += 1;
    }
    blocks.extend(actions_text);
    let mut trailing = String::new();
    comment_lines(&doc.trailing_comments, &mut probe, &mut trailing);
    if blocks.is_empty() {
        problems.push(problem("SFC0201", "", "the chart has no step: its text has no SFC body"));
    } else if !decl_text.is_empty() {
        out.push('\n');
    }
    if !trailing.is_empty() {
        blocks.push(trailing);
    }
    out.push_str(&blocks.join("\n"));
    out.push_str(match doc.pou_kind {
        PouKind::Program => "END_PROGRAM\n",
        PouKind::FunctionBlock => "END_FUNCTION_BLOCK\n",
    });
    Written { text: out, problems }
}

/// A step or transition stored as typed, without its id (ids are derived again on open) and
/// with its (meaningless) `step` reference in the entry's `st`/`sr`.
fn bare(e: &Element) -> Element {
    Element { id: String::new(), step: e.step.as_ref().map(|_| String::new()), ..e.clone() }
}

/// A block's `step` reference as a block position, or as a dangling reference.
fn step_ref(d: &Derived, e: &Element) -> (Option<usize>, Option<String>) {
    match e.step.as_ref().map(|s| d.by_id.get(s).copied().ok_or_else(|| graph::dangling(s))) {
        Some(Ok(s)) => (Some(s), None),
        Some(Err(raw)) => (None, Some(raw)),
        None => (None, None),
    }
}

fn end(d: &Derived, id: &str) -> End {
    match d.by_id.get(id) {
        Some(&i) => End::At(i),
        None => End::Missing(graph::dangling(id)),
    }
}

/// The transition of the text a jump follows (directly or through a simultaneous divergence).
fn jump_source(doc: &EditorDoc, d: &Derived, j: usize) -> Option<usize> {
    let mut at = j;
    for _ in 0..2 {
        let c = (*d.ins.get(at)?.first()?)?;
        let src = *d.by_id.get(&doc.connections[c].source)?;
        match d.roles[src] {
            Role::Transition(_) => return Some(src),
            _ if doc.elements[src].kind == Some(ElementKind::SimultaneousDivergence) => at = src,
            _ => return None,
        }
    }
    None
}

/// The entry of a block that is not a step or transition of the text; records the
/// associations of action blocks that belong to a step of the text.
fn other_entry(
    doc: &EditorDoc,
    d: &Derived,
    i: usize,
    probe: &mut Probe,
    step_assocs: &mut HashMap<usize, Vec<String>>,
    step_blocks: &mut HashMap<usize, Vec<String>>,
    problems: &mut Vec<Problem>,
) -> Entry {
    let e = &doc.elements[i];
    if e.kind == Some(ElementKind::ActionBlock) {
        let step = match step_ref(d, e).0 {
            Some(s) if matches!(d.roles[s], Role::Step(_)) => Some(s),
            _ => {
                problems.push(problem(
                    "SFC0205",
                    &e.id,
                    "the action block belongs to no step of the chart; its actions are kept in the layout only",
                ));
                None
            }
        };
        if let Some(s) = step {
            let texts: Option<Vec<String>> = e.associations.iter().map(|a| probe.association(a)).collect();
            match texts {
                Some(texts) => {
                    let n = texts.len();
                    step_assocs.entry(s).or_default().extend(texts);
                    let blocks = step_blocks.entry(s).or_default();
                    let ab = blocks.len();
                    blocks.push(format!("{} {} {} {} {n}", num(e.x), num(e.y), num(e.w), num(e.h)));
                    // Its place is in the step's `sfc.actionblock`.
                    let a = Element {
                        id: String::new(),
                        step: None,
                        associations: Vec::new(),
                        x: 0.0,
                        y: 0.0,
                        w: 0.0,
                        h: 0.0,
                        ..e.clone()
                    };
                    return Entry { a: Some(a), n: Some(n), st: Some(s), ab: Some(ab), ..Entry::default() };
                }
                None => problems.push(problem(
                    "SFC0209",
                    &e.id,
                    "an association of the action block cannot be written (check its action name, qualifier, duration and indicator); the block is kept in the layout only",
                )),
            }
        }
    }
    let (st, sr) = step_ref(d, e);
    Entry { x: Some(bare(e)), st, sr, ..Entry::default() }
}

/// The actions of a document as text (each with its comments and attributes), their entries of
/// the layout attribute, and whether the text alone says them all.
fn write_actions(
    doc: &EditorDoc,
    probe: &mut Probe,
    problems: &mut Vec<Problem>,
) -> (Vec<String>, Vec<ActEntry>, bool) {
    let mut actions_text = Vec::new();
    let mut acts = Vec::new();
    let mut plain_acts = true;
    let mut action_names: HashMap<String, ()> = HashMap::new();
    let flat: Vec<ActionDef> = doc
        .actions
        .iter()
        .map(|a| {
            let (f, p) = flat_action(a, &doc.attributes, probe);
            problems.extend(p);
            f
        })
        .collect();
    for a in &flat {
        let key = a.name.to_ascii_uppercase();
        if !probe.is_name(&a.name) || action_names.contains_key(&key) {
            let why = if action_names.contains_key(&key) { "another action has this name" } else { "no valid name" };
            problems.push(problem(
                "SFC0206",
                &a.name,
                format!("action `{}`: {why}; it is kept in the layout only", a.name),
            ));
            acts.push(ActEntry { x: Some(a.clone()), ..ActEntry::default() });
            plain_acts = false;
            continue;
        }
        action_names.insert(key, ());
        let (text, read) = probe.action(a);
        let mut entry = ActEntry { n: Some(a.name.clone()), ..ActEntry::default() };
        if read != *a {
            if read.body.is_empty() && !a.body.trim().is_empty() {
                problems.push(problem("SFC0101", &a.name, format!("the body of action `{}` does not parse", a.name)));
            }
            entry.o = Some(a.clone());
            plain_acts = false;
        }
        let mut t = String::new();
        comment_lines(&a.comments, probe, &mut t);
        if !a.description.is_empty() {
            t.push_str(&line(IND, "sfc.description", &escape(&a.description)));
        }
        t.push_str(&pragma::write_others(IND, &a.attributes, pragma::ACTION));
        t.push_str(&text);
        actions_text.push(t);
        acts.push(entry);
    }
    (actions_text, acts, plain_acts)
}

/// A POU whose body is ST or IL ([`EditorDoc::body`]): its attributes, header, declarations,
/// body and actions, without the chart's attributes (a POU in ST is no chart).
fn write_text_pou(doc: &EditorDoc) -> Written {
    let mut probe = Probe::for_attributes(&doc.attributes);
    let mut problems = Vec::new();
    if !doc.elements.is_empty() {
        problems.push(problem(
            "SFC0101",
            "",
            format!("the body of `{}` is text, not a chart: its blocks cannot be written", doc.pou),
        ));
    }
    let pou_name = if probe.is_name(&doc.pou) {
        doc.pou.clone()
    } else {
        problems.push(problem("SFC0101", "", format!("`{}` is not a valid POU name", doc.pou)));
        "Unnamed".to_string()
    };
    let (decl_text, decl_read) = probe.declarations(&doc.declarations);
    if decl_read != doc.declarations && decl_text.is_empty() && !doc.declarations.trim().is_empty() {
        problems.push(problem("SFC0101", "", "the declarations do not parse"));
    }
    let (actions_text, acts, _) = write_actions(doc, &mut probe, &mut problems);
    for a in acts.iter().filter_map(|e| e.x.as_ref()) {
        problems.push(problem("SFC0101", &a.name, format!("action `{}` cannot be written", a.name)));
    }
    let mut out = String::new();
    if !doc.description.is_empty() {
        out.push_str(&line("", "sfc.description", &escape(&doc.description)));
    }
    out.push_str(&pragma::write_others("", &doc.attributes, pragma::POU));
    let kind = match doc.pou_kind {
        PouKind::Program => "PROGRAM",
        PouKind::FunctionBlock => "FUNCTION_BLOCK",
    };
    out.push_str(&format!("{kind} {pou_name}\n"));
    out.push_str(&decl_text);
    let body = doc.body.as_deref().unwrap_or("");
    let mut blocks = Vec::new();
    if !body.trim().is_empty() {
        blocks.push(format!("{}\n", crate::region::indent(body.trim_end(), IND)));
    }
    blocks.extend(actions_text);
    let mut trailing = String::new();
    comment_lines(&doc.trailing_comments, &mut probe, &mut trailing);
    if !trailing.is_empty() {
        blocks.push(trailing);
    }
    if !blocks.is_empty() && !decl_text.is_empty() {
        out.push('\n');
    }
    out.push_str(&blocks.join("\n"));
    out.push_str(match doc.pou_kind {
        PouKind::Program => "END_PROGRAM\n",
        PouKind::FunctionBlock => "END_FUNCTION_BLOCK\n",
    });
    Written { text: out, problems }
}
