//! Opening: each SFC POU of checked IEC text as a document. With a saved layout
//! (`sfc.graph`) that agrees with the text, the document is rebuilt from it; otherwise the
//! chart is laid out (`layout.rs`), keeping the positions stored in `sfc.x`/`sfc.y` (PLCopen
//! import), `sfc.jump`, `sfc.actionblock` and `sfc.comment`.

use crate::graph::{self, Role};
use crate::layout::{self, Model};
use crate::loose;
use crate::pragma;
use crate::readback::Probe;
use crate::region;
use crate::sidecar::{self, End, Sidecar};
use crate::write::as_read;
use crate::{ActionDef, Association, ChartTarget, Connection, EditorDoc, Element, ElementKind, PouKind};
use sfc_model::{Chart, Target};
use sfc_render::LayoutKind;
use sfc_syntax::ast;
use sfc_syntax::attr_value::{Loose, LOOSE};
use std::collections::{HashMap, HashSet};

/// One chart as read from the text, before it becomes a document.
pub struct ReadChart<'a> {
    pub chart: &'a Chart,
    pub pou_kind: PouKind,
    pub target: ChartTarget,
    pub description: String,
    pub declarations: String,
    pub steps: Vec<Element>,
    pub step_stored: Vec<bool>,
    pub step_assocs: Vec<Vec<Association>>,
    /// `sfc.actionblock`: `x y w h n` per block.
    pub step_blocks: Vec<Option<Vec<[f64; 5]>>>,
    pub transitions: Vec<Element>,
    pub transition_stored: Vec<bool>,
    /// `sfc.jump`: target name and position per jump.
    pub jumps: Vec<Option<Vec<(String, f64, f64)>>>,
    pub actions: Vec<ActionDef>,
    pub comments: Vec<Element>,
    /// The comments after the last element.
    pub trailing_comments: Vec<String>,
    pub graph: Option<String>,
    pub attributes: Vec<crate::OtherAttribute>,
    /// `sfc.loose`: transitions drawn but not connected on both sides (from another tool).
    pub loose: Vec<Loose>,
}

/// The element of the text a comment belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Owner {
    Step(usize),
    Transition(usize),
    Action(usize),
    Trailing,
}

/// The comments of a POU that no text of the document holds (see the crate docs), by the
/// element they belong to, in source order: comments in the declarations, a condition or an
/// action are part of that text; every other one belongs to the element it is inside of, the
/// element whose line it ends, or else the element after it.
fn comments_by_owner(text: &str, chart: &Chart, holder: &Holder, trivia: &[ast::Trivia]) -> Vec<(Owner, String)> {
    let (start, end) = (holder.start, holder.end);
    let mut anchors: Vec<(u32, u32, Owner)> = Vec::new();
    anchors.extend(chart.steps.iter().enumerate().map(|(k, s)| (s.span.start, s.span.end, Owner::Step(k))));
    anchors.extend(chart.transitions.iter().enumerate().map(|(k, t)| (t.span.start, t.span.end, Owner::Transition(k))));
    anchors.extend(chart.actions.iter().enumerate().map(|(k, a)| (a.span.start, a.span.end, Owner::Action(k))));
    anchors.sort_by_key(|a| (a.0, a.1));
    let mut held: Vec<Option<(usize, usize)>> = vec![holder.declarations];
    held.extend(chart.transitions.iter().map(|t| region::condition_range(text, &t.condition)));
    held.extend(chart.actions.iter().map(|a| Some((a.span.start as usize, a.span.end as usize))));
    let mut out = Vec::new();
    for t in trivia.iter().filter(|t| region::is_comment(t)) {
        let at = t.span.start;
        if at < start || t.span.end > end || held.iter().any(|r| region::within(t, *r)) {
            continue;
        }
        // The element whose line the comment ends (only white space between them).
        let trailed = anchors.iter().rev().find(|a| a.1 <= at).filter(|a| {
            !t.own_line
                && text.get(a.1 as usize..at as usize).is_some_and(|gap| gap.trim().is_empty() && !gap.contains('\n'))
        });
        let owner = trailed
            .or_else(|| anchors.iter().find(|a| a.0 <= at && at < a.1))
            .or_else(|| anchors.iter().find(|a| a.0 > at))
            .map_or(Owner::Trailing, |a| a.2);
        out.push((owner, t.text.clone()));
    }
    out
}

fn chart_target(attrs: &[ast::Attribute]) -> ChartTarget {
    match pragma::raw(attrs, "sfc.target").and_then(|v| Target::from_name(v.trim())) {
        Some(Target::Atmt) => ChartTarget::Atmt,
        Some(Target::Eatmt) => ChartTarget::Eatmt,
        _ => ChartTarget::Blank,
    }
}

/// The properties every step and transition may carry in attributes.
fn common(attrs: &[ast::Attribute], kind: ElementKind, name: &str) -> (Element, bool) {
    let x = pragma::number(attrs, "sfc.x");
    let y = pragma::number(attrs, "sfc.y");
    let (dw, dh) = match kind {
        ElementKind::Step => layout::step_size(name),
        _ => (layout::TRANSITION_W, layout::TRANSITION_H),
    };
    let e = Element {
        kind: Some(kind),
        name: name.to_string(),
        x: x.unwrap_or(0.0),
        y: y.unwrap_or(0.0),
        w: pragma::number(attrs, "sfc.w").or_else(|| pragma::number(attrs, "sfc.width")).unwrap_or(dw),
        h: pragma::number(attrs, "sfc.h").or_else(|| pragma::number(attrs, "sfc.height")).unwrap_or(dh),
        tag: pragma::raw(attrs, "sfc.tag").and_then(|v| v.trim().parse::<u32>().ok()),
        description: pragma::text(attrs, "sfc.description").unwrap_or_default(),
        background: pragma::text(attrs, "sfc.background"),
        foreground: pragma::text(attrs, "sfc.foreground"),
        line_width: pragma::number(attrs, "sfc.linewidth"),
        hide_label: pragma::flag(attrs, "sfc.hidelabel"),
        ..Element::default()
    };
    (e, x.is_some() && y.is_some())
}

fn numbers(s: &str) -> Option<Vec<f64>> {
    s.split_whitespace().map(|p| p.parse::<f64>().ok().filter(|v| v.is_finite())).collect()
}

/// What holds a chart in the text: a POU's body, or an action written in SFC.
pub struct Holder<'a> {
    /// The attribute pragmas before the POU (or the action): the chart's own (`sfc.graph`, …).
    pub attributes: &'a [ast::Attribute],
    /// The chart's elements as parsed (their associations as written).
    pub elements: &'a [ast::SfcElement],
    /// Where the holder's text lies; comments outside belong to others.
    pub start: u32,
    pub end: u32,
    /// The declarations' range (their comments are part of them).
    pub declarations: Option<(usize, usize)>,
    /// An action's chart: its actions are the POU's, listed in the POU's document.
    pub action: bool,
}

impl<'a> Holder<'a> {
    /// A POU whose body is the chart.
    pub fn pou(text: &str, pou: &'a ast::Pou) -> Holder<'a> {
        Holder {
            attributes: &pou.attributes,
            elements: pou.body.sfc().unwrap_or(&[]),
            start: pou.attributes.iter().map(|a| a.span.start).chain([pou.span.start]).min().unwrap_or(0),
            end: pou.span.end,
            declarations: region::declarations_range(text, pou),
            action: false,
        }
    }

    /// An action written in SFC (`action` as parsed, before the checker took its elements).
    pub fn action(action: &'a ast::Action) -> Holder<'a> {
        Holder {
            attributes: &action.attributes,
            elements: action.body.sfc().unwrap_or(&[]),
            start: action.span.start,
            end: action.span.end,
            declarations: None,
            action: true,
        }
    }
}

/// Reads one chart of a checked file (`trivia`: the file's comments and pragmas).
pub fn read<'a>(text: &str, chart: &'a Chart, pou: &ast::Pou, trivia: &[ast::Trivia]) -> ReadChart<'a> {
    read_in(text, chart, pou, &Holder::pou(text, pou), trivia)
}

/// Reads the chart `holder` holds, of the POU `pou`.
pub fn read_in<'a>(
    text: &str,
    chart: &'a Chart,
    pou: &ast::Pou,
    holder: &Holder,
    trivia: &[ast::Trivia],
) -> ReadChart<'a> {
    let ast_steps: HashMap<(u32, u32), &ast::Step> = holder
        .elements
        .iter()
        .filter_map(|e| match e {
            ast::SfcElement::Step(s) => Some(((s.span.start, s.span.end), s)),
            _ => None,
        })
        .collect();
    let mut steps = Vec::new();
    let mut step_stored = Vec::new();
    let mut step_assocs = Vec::new();
    let mut step_blocks = Vec::new();
    for s in &chart.steps {
        let (mut e, stored) = common(&s.attributes, ElementKind::Step, &s.name);
        e.initial = s.initial;
        e.timeout = pragma::text(&s.attributes, "sfc.timeout");
        e.is_final = pragma::flag(&s.attributes, "sfc.final");
        e.attributes = pragma::others(&s.attributes, pragma::STEP);
        e.step_actions = s.step_actions.iter().map(|a| format!("{} := {}", a.kind.keyword(), a.name())).collect();
        steps.push(e);
        step_stored.push(stored);
        let assocs = ast_steps
            .get(&(s.span.start, s.span.end))
            .map(|a| a.associations.iter().map(|x| region::association(text, x)).collect())
            .unwrap_or_default();
        step_assocs.push(assocs);
        step_blocks.push(pragma::raw(&s.attributes, "sfc.actionblock").and_then(|v| {
            pragma::unescape(v)
                .split(';')
                .map(|b| numbers(b).filter(|n| n.len() == 5).map(|n| [n[0], n[1], n[2], n[3], n[4]]))
                .collect::<Option<Vec<_>>>()
        }));
    }
    let mut transitions = Vec::new();
    let mut transition_stored = Vec::new();
    let mut jumps = Vec::new();
    for t in &chart.transitions {
        let name = if t.named { t.name.as_str() } else { "" };
        let (mut e, stored) = common(&t.attributes, ElementKind::Transition, name);
        let (cond, lang) = region::condition(text, &t.condition);
        e.condition = cond;
        e.condition_language = lang;
        e.priority = t.priority.and_then(|p| u32::try_from(p).ok());
        e.attributes = pragma::others(&t.attributes, pragma::TRANSITION);
        transitions.push(e);
        transition_stored.push(stored);
        jumps.push(pragma::raw(&t.attributes, "sfc.jump").map(|v| {
            pragma::unescape(v)
                .split(';')
                .filter_map(|j| {
                    let mut it = j.split_whitespace();
                    let name = it.next()?.to_string();
                    let x = it.next()?.parse::<f64>().ok().filter(|v| v.is_finite())?;
                    let y = it.next()?.parse::<f64>().ok().filter(|v| v.is_finite())?;
                    Some((name, x, y))
                })
                .collect()
        }));
    }
    let mut actions: Vec<ActionDef> = chart
        .actions
        .iter()
        .map(|a| ActionDef {
            name: a.name.clone(),
            language: region::action_language(&a.body),
            body: region::action_body(text, a.span, a.name_span),
            description: pragma::text(&a.attributes, "sfc.description").unwrap_or_default(),
            attributes: pragma::others(&a.attributes, pragma::ACTION),
            comments: Vec::new(),
            chart: None,
        })
        .collect();
    if holder.action {
        actions.clear();
    }
    let mut trailing_comments = Vec::new();
    for (owner, c) in comments_by_owner(text, chart, holder, trivia) {
        let list = match owner {
            Owner::Step(k) => steps.get_mut(k).map(|e| &mut e.comments),
            Owner::Transition(k) => transitions.get_mut(k).map(|e| &mut e.comments),
            Owner::Action(k) => actions.get_mut(k).map(|a| &mut a.comments),
            Owner::Trailing => None,
        };
        list.unwrap_or(&mut trailing_comments).push(c);
    }
    let attrs = holder.attributes;
    let comments = pragma::all(attrs, "sfc.comment")
        .into_iter()
        .filter_map(|v| {
            let (head, body) = v.split_once('\n').unwrap_or((v.as_str(), ""));
            let n = numbers(head).filter(|n| n.len() == 4)?;
            Some(Element {
                kind: Some(ElementKind::Text),
                x: n[0],
                y: n[1],
                w: n[2],
                h: n[3],
                text: Some(body.to_string()),
                ..Element::default()
            })
        })
        .collect();
    ReadChart {
        chart,
        pou_kind: if pou.kind == ast::PouKind::FunctionBlock { PouKind::FunctionBlock } else { PouKind::Program },
        target: chart_target(if holder.action { &pou.attributes } else { attrs }),
        // An action's description is the action's (its entry in the POU's document).
        description: if holder.action {
            String::new()
        } else {
            pragma::text(attrs, "sfc.description").unwrap_or_default()
        },
        declarations: if holder.action { String::new() } else { region::declarations(text, pou) },
        steps,
        step_stored,
        step_assocs,
        step_blocks,
        transitions,
        transition_stored,
        jumps,
        actions,
        comments,
        trailing_comments,
        graph: sidecar::read(attrs),
        // An action's chart is read and written in its POU's dialect (`sfc.dialect`, not
        // written into the action: see `write::flat_action`).
        attributes: if holder.action {
            let dialect = pou.attributes.iter().filter(|a| a.name.eq_ignore_ascii_case("sfc.dialect"));
            let own = attrs.iter().filter(|a| !a.name.eq_ignore_ascii_case("sfc.dialect")).cloned().collect::<Vec<_>>();
            let list: Vec<ast::Attribute> = dialect.cloned().chain(own).collect();
            pragma::others(&list, &[pragma::POU, pragma::ACTION].concat())
        } else {
            pragma::others(attrs, pragma::POU)
        },
        loose: pragma::all(attrs, LOOSE).iter().filter_map(|v| Loose::read(v)).collect(),
    }
}

/// The document of a chart read from text, with canonical ids.
pub fn document(r: &ReadChart) -> EditorDoc {
    let mut probe = Probe::for_attributes(&r.attributes);
    match from_sidecar(r, &mut probe) {
        Some(mut doc) => {
            // Wires saved on their automatic route have no waypoints: routed again.
            let d = graph::derive(&doc, &mut probe);
            layout::route_empty(&mut doc, &d);
            let d = graph::derive(&doc, &mut probe);
            graph::normalize(&doc, &d)
        }
        None => {
            let mut doc = laid_out(r, &mut probe);
            add_loose(&mut doc, &r.loose);
            let d = graph::derive(&doc, &mut probe);
            // Blocks an import stacked at one place are laid side by side, and loose pieces
            // the new layout put blocks under go beside the chart.
            let spread = loose::spread_duplicates(&mut doc);
            let lone = loose::loose_blocks(&doc, &d);
            let covered = {
                use crate::drawing::Rect;
                let chart: Vec<Rect> = (0..doc.elements.len())
                    .filter(|&i| !lone[i] && doc.elements[i].kind.is_some())
                    .map(|i| Rect::of(&doc.elements[i]))
                    .collect();
                (0..doc.elements.len())
                    .any(|i| lone[i] && chart.iter().any(|c| c.overlaps(&Rect::of(&doc.elements[i]))))
            };
            if covered {
                loose::place_beside(&mut doc, &d, &lone);
            }
            let mut moved = spread;
            if covered {
                moved.extend((0..lone.len()).filter(|&i| lone[i]));
            }
            if !moved.is_empty() {
                loose::route_of(&mut doc, &d, &moved);
            }
            graph::normalize(&doc, &d)
        }
    }
}

/// Draws the transitions of `sfc.loose` (a chart being drawn in another tool): each at its
/// stored position (or right of the chart), wired to the steps it was wired to where their pin
/// is still free. They stay outside the chart until the user connects them (SFC0204).
fn add_loose(doc: &mut EditorDoc, loose: &[Loose]) {
    let right = doc.elements.iter().map(|e| e.x + e.w).fold(0.0, f64::max);
    for (k, l) in loose.iter().enumerate() {
        let id = format!("#loose{k}");
        let (x, y) = match l.rect {
            Some([x, y, w, _]) => (x + w / 2.0 - layout::TRANSITION_W / 2.0, y),
            None => (right + 80.0, 40.0 + 80.0 * k as f64),
        };
        doc.elements.push(Element {
            id: id.clone(),
            kind: Some(ElementKind::Transition),
            x,
            y,
            w: layout::TRANSITION_W,
            h: layout::TRANSITION_H,
            name: l.name.clone(),
            condition: Some(l.condition.clone()),
            ..Element::default()
        });
        let step = |doc: &EditorDoc, name: &str| {
            doc.elements
                .iter()
                .find(|e| e.kind == Some(ElementKind::Step) && e.name.eq_ignore_ascii_case(name))
                .map(|e| e.id.clone())
        };
        let mut wires = Vec::new();
        for s in l.from.iter().filter_map(|n| step(doc, n)) {
            if wires.is_empty() && !doc.connections.iter().any(|c| c.source == s) {
                wires.push((s, id.clone()));
            }
        }
        for s in l.to.iter().filter_map(|n| step(doc, n)) {
            if !doc.connections.iter().any(|c| c.target == s) && !wires.iter().any(|w| w.0 == id) {
                wires.push((id.clone(), s));
            }
        }
        for (source, target) in wires {
            let n = doc.connections.len();
            doc.connections.push(Connection { id: format!("#cl{n}"), source, target, ..Connection::default() });
        }
    }
}

fn empty_doc(r: &ReadChart) -> EditorDoc {
    EditorDoc {
        pou: r.chart.pou.clone(),
        pou_kind: r.pou_kind,
        target: r.target,
        description: r.description.clone(),
        declarations: r.declarations.clone(),
        body: None,
        body_language: crate::Language::St,
        actions: r.actions.clone(),
        elements: Vec::new(),
        connections: Vec::new(),
        attributes: r.attributes.clone(),
        trailing_comments: r.trailing_comments.clone(),
    }
}

/// The document as saved, when the saved layout describes the chart of the text.
fn from_sidecar(r: &ReadChart, probe: &mut Probe) -> Option<EditorDoc> {
    let car: Sidecar = serde_json::from_str(r.graph.as_deref()?).ok()?;
    if car.v != sidecar::VERSION || !r.step_stored.iter().chain(&r.transition_stored).all(|&s| s) {
        return None;
    }
    let n = car.e.len();
    // Which step / transition of the text each entry is.
    let mut step_of = vec![None; n];
    let mut transition_of = vec![None; n];
    let (mut ns, mut nt) = (0, 0);
    for (i, en) in car.e.iter().enumerate() {
        if let Some(name) = &en.s {
            if r.steps.get(ns)?.name != *name {
                return None;
            }
            step_of[i] = Some(ns);
            ns += 1;
        } else if let Some(name) = &en.t {
            if r.transitions.get(nt)?.name != *name {
                return None;
            }
            transition_of[i] = Some(nt);
            nt += 1;
        }
    }
    if ns != r.steps.len() || nt != r.transitions.len() {
        return None;
    }
    let tmp = |i: usize| format!("#{i}");
    let mut cursor = vec![0usize; r.steps.len()];
    let mut elements = Vec::with_capacity(n);
    for (i, en) in car.e.iter().enumerate() {
        let restore = |mut x: Element| -> Option<Element> {
            match (en.st, &en.sr) {
                (Some(s), _) if s < n && x.step.is_some() => x.step = Some(tmp(s)),
                (None, Some(raw)) if x.step.is_some() => x.step = Some(raw.clone()),
                (None, None) if x.step.as_deref().is_none_or(|s| s.is_empty()) => x.step = None,
                _ => return None,
            }
            Some(x)
        };
        let typed = match &en.o {
            Some(o) => Some(restore(o.clone())?),
            None => None,
        };
        let e = if let Some(k) = step_of[i] {
            chosen(&r.steps[k], typed.as_ref(), probe)
        } else if let Some(k) = transition_of[i] {
            chosen(&r.transitions[k], typed.as_ref(), probe)
        } else if let Some(a) = &en.a {
            let k = step_of.get(en.st?).copied().flatten()?;
            let count = en.n?;
            let list = &r.step_assocs[k];
            let assocs = list.get(cursor[k]..cursor[k].checked_add(count)?)?.to_vec();
            cursor[k] += count;
            let mut block = a.clone();
            if let Some(j) = en.ab {
                let g = r.step_blocks.get(k)?.as_ref()?.get(j)?;
                if g[4] != count as f64 {
                    return None;
                }
                (block.x, block.y, block.w, block.h) = (g[0], g[1], g[2], g[3]);
            }
            Element { kind: Some(ElementKind::ActionBlock), step: Some(tmp(en.st?)), associations: assocs, ..block }
        } else if let Some(x) = &en.x {
            restore(x.clone())?
        } else {
            return None;
        };
        elements.push(Element { id: tmp(i), ..e });
    }
    if cursor.iter().zip(&r.step_assocs).any(|(c, a)| *c != a.len()) {
        return None;
    }
    let end = |e: &End| -> Option<String> {
        match e {
            End::At(i) if *i < n => Some(tmp(*i)),
            End::At(_) => None,
            End::Missing(raw) => Some(raw.clone()),
        }
    };
    let connections = car
        .c
        .iter()
        .map(|w| {
            Some(Connection {
                id: String::new(),
                source: end(&w.s)?,
                source_pin: w.sp,
                target: end(&w.t)?,
                target_pin: w.tp,
                waypoints: w.w.clone(),
                color: w.col.clone(),
                line_width: w.lw,
            })
        })
        .collect::<Option<Vec<_>>>()?;
    let mut doc = EditorDoc { elements, connections, ..empty_doc(r) };
    if let Some(p) = &car.pou {
        if r.chart.pou == "Unnamed" {
            doc.pou = p.clone();
        }
    }
    if let Some(attrs) = &car.attrs {
        if pragma::readable(attrs, pragma::POU) == r.attributes {
            doc.attributes = attrs.clone();
        }
    }
    if let Some(tc) = &car.tc {
        if probe.comments(tc) == r.trailing_comments {
            doc.trailing_comments = tc.clone();
        }
    }
    if let Some(decl) = &car.decl {
        if probe.declarations(decl).1 == r.declarations {
            doc.declarations = decl.clone();
        }
    }
    if let Some(acts) = &car.acts {
        doc.actions = actions(r, acts, probe).unwrap_or_else(|| r.actions.clone());
    }

    // The graph must say what the text says.
    let d = graph::derive(&doc, probe);
    for (i, role) in d.roles.iter().enumerate() {
        let agrees = match role {
            Role::Step(k) => step_of[i] == Some(*k),
            Role::Transition(k) => transition_of[i] == Some(*k),
            Role::Other => step_of[i].is_none() && transition_of[i].is_none(),
        };
        if !agrees {
            return None;
        }
    }
    let step_index: HashMap<usize, usize> = (0..n).filter_map(|i| step_of[i].map(|k| (i, k))).collect();
    for (k, t) in d.transitions.iter().enumerate() {
        let model = &r.chart.transitions[k];
        let set = |l: &[usize]| l.iter().filter_map(|i| step_index.get(i)).copied().collect::<HashSet<usize>>();
        let (from, to) = (set(&t.from), set(&t.to));
        if from != model.from.iter().copied().collect() || to != model.to.iter().copied().collect() {
            return None;
        }
    }
    Some(doc)
}

/// A step or transition as read, or as typed when the text still reads as it would.
fn chosen(read: &Element, typed: Option<&Element>, probe: &mut Probe) -> Element {
    match typed {
        Some(o) if as_read(o, probe) == *read => o.clone(),
        _ => read.clone(),
    }
}

fn actions(r: &ReadChart, acts: &[sidecar::ActEntry], probe: &mut Probe) -> Option<Vec<ActionDef>> {
    let mut k = 0;
    let mut out = Vec::new();
    for a in acts {
        if let Some(name) = &a.n {
            let read = r.actions.get(k)?;
            if read.name != *name {
                return None;
            }
            k += 1;
            out.push(match &a.o {
                Some(o) if probe.action(o).1 == *read => o.clone(),
                _ => read.clone(),
            });
        } else {
            out.push(a.x.clone()?);
        }
    }
    (k == r.actions.len()).then_some(out)
}

/// The chart laid out afresh (stored positions kept): steps, transitions, the bars their
/// FROM/TO lists need, jumps where the layout draws them, action blocks and comments.
// Steps and transitions are numbered as in the chart; parallel tables are indexed by them.
#[allow(clippy::needless_range_loop)]
fn laid_out(r: &ReadChart, probe: &mut Probe) -> EditorDoc {
    let chart = r.chart;
    let lay = sfc_render::layout_with(chart, &sfc_render::LayoutOptions::default());
    let (ns, nt) = (chart.steps.len(), chart.transitions.len());
    let step_x = |s: usize| lay.steps.get(s).map(|g| g.rect.x + g.rect.w / 2.0).unwrap_or(0.0);
    let trans_x = |t: usize| lay.transitions.get(t).map(|g| g.x).unwrap_or(0.0);

    // Successors drawn as jumps: stored ones, else the layout's.
    let mut jump_at: HashMap<(usize, usize), Option<(f64, f64)>> = HashMap::new();
    for (t, tr) in chart.transitions.iter().enumerate() {
        if let Some(list) = &r.jumps[t] {
            for (name, x, y) in list {
                if let Some(s) = chart.step(name).filter(|s| tr.to.contains(s)) {
                    jump_at.insert((t, s), Some((*x, *y)));
                }
            }
        }
    }
    if lay.kind != LayoutKind::Stored {
        for j in &lay.jumps {
            if r.jumps.get(j.transition).is_some_and(|l| l.is_none()) {
                jump_at.entry((j.transition, j.target)).or_insert(None);
            }
        }
    }
    let jump_x = |t: usize, s: usize| match jump_at.get(&(t, s)) {
        Some(Some((x, _))) => *x,
        Some(None) => {
            lay.jumps.iter().find(|j| j.transition == t && j.target == s).map(|j| j.tip.x).unwrap_or(trans_x(t))
        }
        None => step_x(s),
    };
    let adj = chart.adjacency();
    let sorted = |mut v: Vec<usize>, key: &dyn Fn(usize) -> f64| {
        v.sort_by(|a, b| key(*a).total_cmp(&key(*b)));
        v
    };
    let outgoing: Vec<Vec<usize>> = adj.outgoing.iter().map(|o| sorted(o.clone(), &trans_x)).collect();
    let incoming: Vec<Vec<usize>> = (0..ns)
        .map(|s| {
            sorted(adj.incoming[s].iter().copied().filter(|&t| !jump_at.contains_key(&(t, s))).collect(), &trans_x)
        })
        .collect();
    let froms: Vec<Vec<usize>> = chart.transitions.iter().map(|t| sorted(t.from.clone(), &step_x)).collect();
    let tos: Vec<Vec<usize>> =
        chart.transitions.iter().enumerate().map(|(t, tr)| sorted(tr.to.clone(), &|s| jump_x(t, s))).collect();

    let mut doc = empty_doc(r);
    let mut keep = Vec::new();
    let mut step_of = Vec::new();
    let mut transition_of = Vec::new();
    let mut push = |doc: &mut EditorDoc, e: Element, k: bool, s: Option<usize>, t: Option<usize>| -> String {
        let id = format!("#{}", doc.elements.len());
        doc.elements.push(Element { id: id.clone(), ..e });
        keep.push(k);
        step_of.push(s);
        transition_of.push(t);
        id
    };
    let step_ids: Vec<String> =
        (0..ns).map(|s| push(&mut doc, r.steps[s].clone(), r.step_stored[s], Some(s), None)).collect();
    let trans_ids: Vec<String> =
        (0..nt).map(|t| push(&mut doc, r.transitions[t].clone(), r.transition_stored[t], None, Some(t))).collect();
    let bar = |kind: ElementKind, pins: usize| Element {
        kind: Some(kind),
        pins: Some(pins as u32),
        h: layout::BAR_H,
        ..Element::default()
    };
    let mut sel_conv = vec![None; ns];
    let mut sel_div = vec![None; ns];
    for s in 0..ns {
        if incoming[s].len() > 1 {
            sel_conv[s] =
                Some(push(&mut doc, bar(ElementKind::SelectionConvergence, incoming[s].len()), false, None, None));
        }
        if outgoing[s].len() > 1 {
            sel_div[s] =
                Some(push(&mut doc, bar(ElementKind::SelectionDivergence, outgoing[s].len()), false, None, None));
        }
    }
    let mut sim_conv = vec![None; nt];
    let mut sim_div = vec![None; nt];
    for t in 0..nt {
        if froms[t].len() > 1 {
            sim_conv[t] =
                Some(push(&mut doc, bar(ElementKind::SimultaneousConvergence, froms[t].len()), false, None, None));
        }
        if tos[t].len() > 1 {
            sim_div[t] =
                Some(push(&mut doc, bar(ElementKind::SimultaneousDivergence, tos[t].len()), false, None, None));
        }
    }
    let mut jump_ids: HashMap<(usize, usize), String> = HashMap::new();
    for t in 0..nt {
        for &s in &tos[t] {
            if let Some(at) = jump_at.get(&(t, s)) {
                let (x, y) = at.unwrap_or((0.0, 0.0));
                let e = Element {
                    kind: Some(ElementKind::Jump),
                    target: Some(chart.steps[s].name.clone()),
                    x,
                    y,
                    w: layout::JUMP_SIZE,
                    h: layout::JUMP_SIZE,
                    ..Element::default()
                };
                jump_ids.insert((t, s), push(&mut doc, e, at.is_some(), None, None));
            }
        }
    }
    for s in 0..ns {
        let assocs = &r.step_assocs[s];
        // Each block's count must be a whole number of this step's associations, all shown.
        let fits = |b: &Vec<[f64; 5]>| {
            let mut total = 0usize;
            for n in b {
                if n[4] < 0.0 || n[4].fract() != 0.0 || n[4] > assocs.len() as f64 {
                    return false;
                }
                total += n[4] as usize;
            }
            !b.is_empty() && total == assocs.len()
        };
        let stored = r.step_blocks[s].as_ref().filter(|b| fits(b));
        match stored {
            Some(blocks) => {
                let mut from = 0;
                for b in blocks {
                    let count = b[4].max(0.0) as usize;
                    let e = Element {
                        kind: Some(ElementKind::ActionBlock),
                        x: b[0],
                        y: b[1],
                        w: b[2],
                        h: b[3],
                        step: Some(step_ids[s].clone()),
                        associations: assocs[from..from + count].to_vec(),
                        ..Element::default()
                    };
                    from += count;
                    push(&mut doc, e, true, None, None);
                }
            }
            None if !assocs.is_empty() => {
                let e = Element {
                    kind: Some(ElementKind::ActionBlock),
                    step: Some(step_ids[s].clone()),
                    associations: assocs.clone(),
                    ..Element::default()
                };
                push(&mut doc, e, false, None, None);
            }
            None => {}
        }
    }
    for c in &r.comments {
        push(&mut doc, c.clone(), true, None, None);
    }

    // Connections: bars to their step or transition, then every FROM and TO link.
    let mut wires: Vec<(String, u32, String, u32)> = Vec::new();
    for s in 0..ns {
        if let Some(b) = &sel_conv[s] {
            wires.push((b.clone(), 0, step_ids[s].clone(), 0));
        }
        if let Some(b) = &sel_div[s] {
            wires.push((step_ids[s].clone(), 0, b.clone(), 0));
        }
    }
    for t in 0..nt {
        if let Some(b) = &sim_conv[t] {
            wires.push((b.clone(), 0, trans_ids[t].clone(), 0));
        }
        if let Some(b) = &sim_div[t] {
            wires.push((trans_ids[t].clone(), 0, b.clone(), 0));
        }
    }
    let pos = |l: &[usize], x: usize| l.iter().position(|&y| y == x).unwrap_or(0) as u32;
    for t in 0..nt {
        for &s in &froms[t] {
            let src = match &sel_div[s] {
                Some(b) => (b.clone(), pos(&outgoing[s], t)),
                None => (step_ids[s].clone(), 0),
            };
            let dst = match &sim_conv[t] {
                Some(b) => (b.clone(), pos(&froms[t], s)),
                None => (trans_ids[t].clone(), 0),
            };
            wires.push((src.0, src.1, dst.0, dst.1));
        }
        for &s in &tos[t] {
            let src = match &sim_div[t] {
                Some(b) => (b.clone(), pos(&tos[t], s)),
                None => (trans_ids[t].clone(), 0),
            };
            let dst = match (jump_ids.get(&(t, s)), &sel_conv[s]) {
                (Some(j), _) => (j.clone(), 0),
                (None, Some(b)) => (b.clone(), pos(&incoming[s], t)),
                (None, None) => (step_ids[s].clone(), 0),
            };
            wires.push((src.0, src.1, dst.0, dst.1));
        }
    }
    doc.connections = wires
        .into_iter()
        .enumerate()
        .map(|(k, (source, source_pin, target, target_pin))| Connection {
            id: format!("#c{k}"),
            source,
            source_pin,
            target,
            target_pin,
            ..Connection::default()
        })
        .collect();

    let d = graph::derive(&doc, probe);
    let only_labels_kept = doc.elements.iter().zip(&keep).all(|(e, k)| !k || e.kind == Some(ElementKind::Text));
    // Blocks with a stored place keep it; every other block is where the structured layout
    // puts it when nothing is stored (so a file that stores the place of a few blocks only,
    // as a save that changed only those writes it, opens as it was drawn), and the wires are
    // routed again.
    let stored: Vec<(usize, (f64, f64, f64, f64))> = doc
        .elements
        .iter()
        .enumerate()
        .filter(|(i, e)| keep.get(*i).copied().unwrap_or(false) && e.kind != Some(ElementKind::Text))
        .map(|(i, e)| (i, (e.x, e.y, e.w, e.h)))
        .collect();
    if lay.kind == LayoutKind::Structured && structured(&mut doc, &d, chart, &step_of, &transition_of) {
        if !only_labels_kept {
            for (i, g) in stored {
                if let Some(e) = doc.elements.get_mut(i) {
                    (e.x, e.y, e.w, e.h) = g;
                }
            }
            layout::route_all(&mut doc, &d);
        }
        return doc;
    }
    layout::place(&mut doc, &d, &Model { step_of: &step_of, transition_of: &transition_of }, &lay, &keep);
    doc
}

/// Lays the document out with the structured layout in the editor's units (`structured.rs`)
/// and routes its wires; `false` (nothing changed) when the chart or the document's bars do not
/// fit it.
fn structured(
    doc: &mut EditorDoc,
    d: &graph::Derived,
    chart: &sfc_model::Chart,
    step_of: &[Option<usize>],
    transition_of: &[Option<usize>],
) -> bool {
    let Some(tree) = sfc_render::structure::recover(chart) else { return false };
    let invert = |of: &[Option<usize>], n: usize| -> Option<Vec<usize>> {
        let mut out = vec![usize::MAX; n];
        for (i, k) in of.iter().enumerate() {
            if let Some(k) = *k {
                *out.get_mut(k)? = i;
            }
        }
        out.iter().all(|&i| i != usize::MAX).then_some(out)
    };
    let (Some(steps), Some(transitions)) =
        (invert(step_of, chart.steps.len()), invert(transition_of, chart.transitions.len()))
    else {
        return false;
    };
    if !crate::structured::place(doc, d, &tree, &steps, &transitions) {
        return false;
    }
    clear_text_labels(doc);
    layout::route_all(doc, d);
    true
}

/// Text labels (comments) keep their place unless the new layout put a block or a label under
/// them; those move to a column right of the drawing, one below the other.
fn clear_text_labels(doc: &mut EditorDoc) {
    use crate::drawing::{labels, Rect};
    let texts: Vec<usize> =
        (0..doc.elements.len()).filter(|&i| doc.elements[i].kind == Some(ElementKind::Text)).collect();
    if texts.is_empty() {
        return;
    }
    let mut taken: Vec<Rect> = doc
        .elements
        .iter()
        .filter(|e| e.kind.is_some() && e.kind != Some(ElementKind::Text))
        .map(Rect::of)
        .chain(labels(doc).into_iter().map(|l| l.rect))
        .collect();
    let right = taken.iter().map(|r| r.right()).fold(0.0, f64::max);
    let mut column_y = taken.iter().map(|r| r.y).fold(f64::INFINITY, f64::min).min(40.0);
    let column_x = ((right + 40.0) / 10.0).ceil() * 10.0;
    for i in texts {
        let r = Rect::of(&doc.elements[i]);
        if taken.iter().any(|t| t.overlaps(&r)) {
            let e = &mut doc.elements[i];
            e.x = column_x;
            e.y = column_y;
            column_y = ((column_y + e.h + 20.0) / 10.0).ceil() * 10.0;
            taken.push(Rect::of(e));
        } else {
            taken.push(r);
        }
    }
}

/// See [`crate::auto_layout`]: the chart the document's text describes is laid out, and the
/// document's own blocks are placed on that layout (text labels, and steps or transitions the
/// text cannot hold yet, stay where they are).
pub fn auto_layout(doc: &EditorDoc) -> EditorDoc {
    let mut probe = Probe::for_attributes(&doc.attributes);
    let d = graph::derive(doc, &mut probe);
    let mut out = doc.clone();
    for c in &mut out.connections {
        c.waypoints.clear();
    }
    let written = crate::write::write(doc);
    let checked = sfc_model::check_source(0, "", &written.text, &sfc_model::CheckOptions::default());
    let Some(chart) = checked.charts.first() else { return out };
    if chart.steps.len() != d.steps.len() || chart.transitions.len() != d.transitions.len() {
        return out;
    }
    let mut chart = chart.clone();
    let positional = |a: &ast::Attribute| ["sfc.x", "sfc.y"].iter().any(|n| a.name.eq_ignore_ascii_case(n));
    for s in &mut chart.steps {
        s.attributes.retain(|a| !positional(a));
    }
    for t in &mut chart.transitions {
        t.attributes.retain(|a| !positional(a));
    }
    let lay = sfc_render::layout_with(&chart, &sfc_render::LayoutOptions::default());
    let step_of: Vec<Option<usize>> =
        d.roles.iter().map(|r| if let Role::Step(k) = r { Some(*k) } else { None }).collect();
    let transition_of: Vec<Option<usize>> =
        d.roles.iter().map(|r| if let Role::Transition(k) = r { Some(*k) } else { None }).collect();
    let keep: Vec<bool> = doc
        .elements
        .iter()
        .zip(&d.roles)
        .map(|(e, r)| {
            e.kind == Some(ElementKind::Text)
                || (*r == Role::Other && matches!(e.kind, Some(ElementKind::Step | ElementKind::Transition)))
        })
        .collect();
    // Loose pieces (blocks not wired to the chart) take no part in the chart's layout: they
    // are hidden from it (no kind: no outline, no obstacle) and put beside it afterwards.
    let lone = loose::loose_blocks(doc, &d);
    let kinds: Vec<Option<ElementKind>> = out.elements.iter().map(|e| e.kind).collect();
    for (e, l) in out.elements.iter_mut().zip(&lone) {
        if *l {
            e.kind = None;
        }
    }
    let only_labels_kept =
        out.elements.iter().zip(&keep).zip(&lone).all(|((e, k), l)| !k || *l || e.kind == Some(ElementKind::Text));
    if !(only_labels_kept
        && lay.kind == LayoutKind::Structured
        && structured(&mut out, &d, &chart, &step_of, &transition_of))
    {
        layout::place(&mut out, &d, &Model { step_of: &step_of, transition_of: &transition_of }, &lay, &keep);
        clear_text_labels(&mut out);
        layout::route_all(&mut out, &d);
    }
    for (e, k) in out.elements.iter_mut().zip(kinds) {
        e.kind = k;
    }
    if lone.iter().any(|&l| l) {
        loose::place_beside(&mut out, &d, &lone);
        let pieces: Vec<usize> = (0..lone.len()).filter(|&i| lone[i]).collect();
        loose::route_of(&mut out, &d, &pieces);
    }
    out
}

/// The document of an action written in SFC (`action` as parsed), its chart `chart`.
pub fn action_document(
    text: &str,
    chart: &Chart,
    pou: &ast::Pou,
    action: &ast::Action,
    trivia: &[ast::Trivia],
) -> EditorDoc {
    document(&read_in(text, chart, pou, &Holder::action(action), trivia))
}

/// The document of a POU whose body is ST or IL (it holds actions written in SFC): its body as
/// text, its actions; no blocks. Comments outside the declarations, the body and the actions
/// belong to the action after them, or else trail.
pub fn text_document(text: &str, pou: &ast::Pou, trivia: &[ast::Trivia]) -> EditorDoc {
    let decl = region::declarations_range(text, pou);
    // The body lies between the declarations (or the header's line) and the first action.
    let header_end = {
        let after = pou.name.span.end as usize;
        text.get(after..).and_then(|r| r.find('\n')).map_or(after, |i| after + i + 1)
    };
    let start = decl.map_or(header_end, |d| d.1).min(pou.span.end as usize);
    let action_start = |a: &ast::Action| a.attributes.iter().map(|x| x.span.start).chain([a.span.start]).min();
    let keyword_end = {
        let kw = match pou.kind {
            ast::PouKind::Program => "END_PROGRAM",
            ast::PouKind::FunctionBlock => "END_FUNCTION_BLOCK",
            ast::PouKind::Function => "END_FUNCTION",
        };
        let end = pou.span.end as usize;
        let whole = text.get(..end).unwrap_or("");
        if whole.len() >= kw.len() && whole[whole.len() - kw.len()..].eq_ignore_ascii_case(kw) {
            end - kw.len()
        } else {
            end
        }
    };
    let first_action = pou.actions.iter().filter_map(action_start).min().map(|a| a as usize);
    // Comments before the first action stay in the body, as written.
    let end = first_action.unwrap_or(keyword_end).max(start).min(text.len());
    let body_text = text.get(start..end).unwrap_or("");
    let language = match &pou.body {
        ast::Body::Il(_) => crate::Language::Il,
        _ => crate::Language::St,
    };
    let mut actions: Vec<ActionDef> = pou
        .actions
        .iter()
        .map(|a| ActionDef {
            name: a.name.text.clone(),
            language: region::action_language(&a.body),
            body: region::action_body(text, a.span, a.name.span),
            description: pragma::text(&a.attributes, "sfc.description").unwrap_or_default(),
            attributes: pragma::others(&a.attributes, pragma::ACTION),
            comments: Vec::new(),
            chart: None,
        })
        .collect();
    // Comments between the actions (not inside one) belong to the next one, or trail.
    let mut trailing_comments = Vec::new();
    for t in trivia.iter().filter(|t| region::is_comment(t)) {
        let (a, b) = (t.span.start as usize, t.span.end as usize);
        if a < end
            || b > keyword_end
            || pou.actions.iter().any(|x| x.span.start as usize <= a && b <= x.span.end as usize)
        {
            continue;
        }
        match pou.actions.iter().position(|x| action_start(x).is_some_and(|s| s as usize >= b)) {
            Some(k) => actions[k].comments.push(t.text.clone()),
            None => trailing_comments.push(t.text.clone()),
        }
    }
    EditorDoc {
        pou: pou.name.text.clone(),
        pou_kind: if pou.kind == ast::PouKind::FunctionBlock { PouKind::FunctionBlock } else { PouKind::Program },
        target: ChartTarget::Blank,
        description: pragma::text(&pou.attributes, "sfc.description").unwrap_or_default(),
        declarations: region::declarations(text, pou),
        body: Some(region::dedent(body_text).trim_start_matches('\n').trim_end().to_string()),
        body_language: language,
        actions,
        elements: Vec::new(),
        connections: Vec::new(),
        attributes: pragma::others(&pou.attributes, pragma::POU),
        trailing_comments,
    }
}
