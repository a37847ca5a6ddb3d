//! SFC bodies: the graph of steps, transitions, divergences, convergences, jumps and macro steps,
//! turned into `STEP`/`TRANSITION`/`ACTION` text.
//!
//! PLCopen stores each link on the consumer (`connectionPointIn/connection@refLocalId` names the
//! producer), so a transition's preceding steps are found by walking up through selection
//! divergences and simultaneous convergences, and its following steps by walking down the
//! consumers through simultaneous divergences, selection convergences and jumps.
//!
//! Order: steps and transitions are written in document order, except that the transitions
//! hanging on one selection divergence are put in left-to-right order of their branch, since
//! declaration order decides between simultaneously true branches. Beremiz tells branches apart
//! only by wire positions: the x where a transition's wire leaves the divergence. CODESYS and
//! TwinCAT write every position as (0, 0): such a body has no layout, and document order stays.

use super::{action_body, attr_xtext, element_attrs, element_attrs_without, network, own_data, Ctx};
use crate::attrs::{self, Loose, CODESYS_SFC_ELEMENT, STEP_ACTION_GUIDS};
use crate::emit::Frag;
use crate::xml::{self, anchor, attr, attr_range, child, children, elements, XText};
use roxmltree::Node;
use std::collections::{HashMap, HashSet};
use std::ops::Range;

/// How deep macro steps may nest.
const MAX_MACRO_DEPTH: usize = 16;

struct Conn {
    r: u64,
    /// The producer end of the wire, when positions are given.
    last: Option<(f64, f64)>,
    range: Range<u32>,
}

struct El<'a, 'i> {
    n: Node<'a, 'i>,
    kind: &'a str,
    /// Input points in order, each with its connections.
    ins: Vec<Vec<Conn>>,
}

/// A step as it will be written.
struct OutStep {
    key: Vec<usize>,
    name: Frag,
    initial: bool,
    attrs: Vec<(String, String)>,
    /// `ENTRY_ACTION := …;` lines (CODESYS's step actions).
    step_actions: Vec<Frag>,
    assocs: Vec<Frag>,
    anchor: Range<u32>,
}

enum Cond {
    St(XText),
    Il(XText),
    Net(Frag),
}

struct OutTrans {
    key: Vec<usize>,
    name: Option<Frag>,
    priority: Option<Frag>,
    from: Vec<Frag>,
    to: Vec<Frag>,
    cond: Cond,
    negated: bool,
    attrs: Vec<(String, String)>,
    anchor: Range<u32>,
    /// With a layout: the selection divergence the transition hangs on (its document key) and
    /// the x where its wire leaves the divergence; alternatives of one divergence are ordered
    /// left to right by it.
    branch: Option<(Vec<usize>, f64)>,
}

struct InlineAction<'a, 'i> {
    /// Name of the step whose action block holds it, and its number there.
    step: String,
    k: usize,
    name: String,
    action: Node<'a, 'i>,
    body: Node<'a, 'i>,
}

/// One SFC graph (a POU body or a macro step's body) imported.
struct Graph {
    steps: Vec<OutStep>,
    trans: Vec<OutTrans>,
    loose: Vec<Loose>,
    entry: Option<Frag>,
    exit: Option<Frag>,
}

struct Importer<'p, 'a, 'i> {
    /// Each SFC body's elements read as a network once, for all its wired conditions.
    nets: HashMap<roxmltree::NodeId, std::rc::Rc<network::Net<'a, 'i>>>,
    inline: Vec<InlineAction<'a, 'i>>,
    /// Per step name: how many inline actions it has so far.
    inline_count: HashMap<String, usize>,
    named_conditions: &'p [Node<'a, 'i>],
    referenced: HashSet<String>,
}

/// Writes the chart of an SFC POU and its actions.
pub(super) fn chart<'a, 'i>(cx: &mut Ctx, sfc: Node<'a, 'i>, actions: &[Node<'a, 'i>], named: &[Node<'a, 'i>]) {
    chart_of(cx, sfc, actions, named, false)
}

/// Writes the steps and transitions of an action written in SFC (CODESYS's SFC action): its
/// associations name the POU's actions, so it declares none itself.
pub(super) fn action_chart(cx: &mut Ctx, sfc: Node) {
    chart_of(cx, sfc, &[], &[], true)
}

fn chart_of<'a, 'i>(
    cx: &mut Ctx,
    sfc: Node<'a, 'i>,
    actions: &[Node<'a, 'i>],
    named: &[Node<'a, 'i>],
    in_action: bool,
) {
    let mut imp = Importer {
        nets: HashMap::new(),
        inline: Vec::new(),
        inline_count: HashMap::new(),
        named_conditions: named,
        referenced: HashSet::new(),
    };
    // A flattened macro body brings steps drawn on another canvas: the chart then keeps no
    // layout, and an export lays it out afresh.
    let macros = elements(sfc).any(|e| e.tag_name().name() == "macroStep" && child(e, "body").is_some());
    let layout = has_layout(sfc) && !macros;
    let g = graph(cx, &mut imp, sfc, layout, 0, Vec::new());

    let mut g = g;
    cx.loose.append(&mut g.loose);
    // Function block calls of condition networks run in an action stored in the initial step.
    let compute = std::mem::take(&mut cx.compute);
    let mut compute_action = None;
    if !compute.is_empty() && in_action {
        cx.diag(
            "SFC0705",
            anchor(sfc),
            "the function blocks wired into the conditions of an action written in SFC are not imported",
        );
    } else if !compute.is_empty() {
        let first_initial =
            g.steps.iter().enumerate().filter(|(_, s)| s.initial).min_by(|a, b| a.1.key.cmp(&b.1.key)).map(|(i, _)| i);
        match first_initial.and_then(|i| g.steps.get_mut(i)) {
            Some(s) => {
                let name = cx.fresh_name("COMPUTE_FUNCTION_BLOCKS");
                s.assocs.push(Frag::plain(format!("        {name}(S);\n")));
                // The association belongs to the step's (last) action block.
                if layout {
                    match s.attrs.iter_mut().find(|(k, _)| k == attrs::ACTIONBLOCK) {
                        Some(slot) => {
                            let mut blocks: Vec<String> = slot.1.split(';').map(str::to_string).collect();
                            if let Some(last) = blocks.last_mut() {
                                let mut parts: Vec<String> = last.split_whitespace().map(str::to_string).collect();
                                if let Some(n) = parts.last_mut() {
                                    *n = (n.parse::<usize>().unwrap_or(0) + 1).to_string();
                                }
                                *last = parts.join(" ");
                            }
                            slot.1 = blocks.join(";");
                        }
                        None => {
                            let num = |k: &str| s.attrs.iter().find(|a| a.0 == k).and_then(|a| a.1.parse::<f64>().ok());
                            let (x, y, w) = (
                                num(attrs::X).unwrap_or(0.0),
                                num(attrs::Y).unwrap_or(0.0),
                                num(attrs::W).unwrap_or(0.0),
                            );
                            let v = format!("{} {} 200 30 1", attrs::fmt_num(x + w + 30.0), attrs::fmt_num(y));
                            let at = s
                                .attrs
                                .iter()
                                .take_while(|(k, _)| [attrs::X, attrs::Y, attrs::W, attrs::H].contains(&k.as_str()))
                                .count();
                            s.attrs.insert(at, (attrs::ACTIONBLOCK.to_string(), v));
                        }
                    }
                }
                compute_action = Some(name);
            }
            None => {
                cx.diag(
                    "SFC0705",
                    anchor(sfc),
                    "the function blocks wired into conditions need an initial step to be called from; they are not imported",
                );
            }
        }
    }

    // Order: steps and transitions by document key; alternatives sorted left to right.
    enum Item {
        Step(usize),
        Trans(usize),
    }
    let mut items: Vec<(Vec<usize>, Item)> = Vec::new();
    for (i, s) in g.steps.iter().enumerate() {
        items.push((s.key.clone(), Item::Step(i)));
    }
    for (i, t) in g.trans.iter().enumerate() {
        items.push((t.key.clone(), Item::Trans(i)));
    }
    items.sort_by(|a, b| a.0.cmp(&b.0));
    let mut order: Vec<usize> =
        items.iter().filter_map(|(_, it)| if let Item::Trans(t) = it { Some(*t) } else { None }).collect();
    let mut groups: HashMap<&[usize], Vec<usize>> = HashMap::new();
    for (slot, &t) in order.iter().enumerate() {
        if let Some((div, _)) = g.trans.get(t).and_then(|t| t.branch.as_ref()) {
            groups.entry(div.as_slice()).or_default().push(slot);
        }
    }
    let branch_x = |t: usize| g.trans.get(t).and_then(|t| t.branch.as_ref()).map(|b| b.1).unwrap_or(0.0);
    let mut new_order = order.clone();
    for slots in groups.values().filter(|s| s.len() > 1) {
        let mut members: Vec<usize> = slots.iter().filter_map(|&s| order.get(s).copied()).collect();
        members.sort_by(|&a, &b| branch_x(a).total_cmp(&branch_x(b)));
        for (slot, t) in slots.iter().zip(members) {
            if let Some(o) = new_order.get_mut(*slot) {
                *o = t;
            }
        }
    }
    order = new_order;
    let mut next_t = 0;
    for (_, it) in &items {
        match it {
            Item::Step(s) => {
                if let Some(step) = g.steps.get(*s) {
                    write_step(cx, step);
                }
            }
            Item::Trans(_) => {
                if let Some(t) = order.get(next_t).and_then(|&t| g.trans.get(t)) {
                    write_transition(cx, t);
                }
                next_t += 1;
            }
        }
    }

    // Actions of the POU, then the inline ones.
    write_actions(cx, actions);
    if let Some(name) = compute_action {
        cx.em.open(anchor(sfc));
        cx.em.str(&format!("    ACTION {name}:\n"));
        for f in &compute {
            cx.em.frag(f);
        }
        cx.em.str("    END_ACTION\n\n");
        cx.em.close();
    }
    // Inline actions in the order of their steps, then of their place in the step's blocks, so
    // the order does not depend on where the action blocks lie in the document.
    let mut inline = std::mem::take(&mut imp.inline);
    let step_pos: HashMap<String, usize> = items
        .iter()
        .filter_map(
            |(_, it)| if let Item::Step(s) = it { Some(g.steps.get(*s)?.name.text.to_ascii_uppercase()) } else { None },
        )
        .enumerate()
        .map(|(i, n)| (n, i))
        .collect();
    inline.sort_by_key(|ia| (step_pos.get(&ia.step.to_ascii_uppercase()).copied().unwrap_or(usize::MAX), ia.k));
    if in_action {
        for ia in inline {
            cx.diag(
                "SFC0705",
                anchor(ia.action),
                format!("the inline action of step `{}` in an action written in SFC is not imported", ia.step),
            );
        }
        return;
    }
    for ia in inline {
        cx.em.open(anchor(ia.action));
        let mut list = vec![(attrs::INLINE.to_string(), "true".to_string())];
        list.extend(element_attrs(ia.action));
        cx.attributes(&list, "    ");
        cx.em.str(&format!("    ACTION {}:\n", ia.name));
        action_body(cx, ia.body, "        ");
        cx.em.str("    END_ACTION\n\n");
        cx.em.close();
    }
    for t in named {
        let n = attr(*t, "name").unwrap_or("").trim().to_ascii_uppercase();
        if !imp.referenced.contains(&n) {
            cx.diag(
                "SFC0710",
                anchor(*t),
                format!("transition condition `{}` is never referenced", attr(*t, "name").unwrap_or("")),
            );
        }
    }
}

/// Whether the body carries a real layout (CODESYS and TwinCAT write every position as 0, 0).
fn has_layout(sfc: Node) -> bool {
    elements(sfc)
        .filter(|e| matches!(e.tag_name().name(), "step" | "transition" | "macroStep"))
        .filter_map(xml::position)
        .any(|(x, y)| x != 0.0 || y != 0.0)
}

fn conns(cp: Node) -> Vec<Conn> {
    children(cp, "connection")
        .map(|c| Conn {
            r: attr(c, "refLocalId").and_then(|v| v.trim().parse().ok()).unwrap_or(u64::MAX),
            last: children(c, "position").filter_map(xml::xy).last(),
            range: anchor(c),
        })
        .collect()
}

fn graph<'a, 'i>(
    cx: &mut Ctx,
    imp: &mut Importer<'_, 'a, 'i>,
    sfc: Node<'a, 'i>,
    layout: bool,
    depth: usize,
    key_prefix: Vec<usize>,
) -> Graph {
    let mut els: Vec<El> = Vec::new();
    let mut ids: HashMap<u64, usize> = HashMap::new();
    for n in elements(sfc) {
        let kind = n.tag_name().name();
        let ins: Vec<Vec<Conn>> = children(n, "connectionPointIn").map(conns).collect();
        if let Some(id) = attr(n, "localId").and_then(|v| v.trim().parse::<u64>().ok()) {
            if ids.insert(id, els.len()).is_some() {
                cx.diag(
                    "SFC0706",
                    attr_range(n, "localId").unwrap_or_else(|| anchor(n)),
                    format!("localId {id} is used twice"),
                );
            }
        }
        els.push(El { n, kind, ins });
    }
    // Consumers of each element, in document order; those of a simultaneous divergence left to
    // right by the divergence output their wire leaves from (the order of the steps it
    // activates), when every wire has positions.
    let mut consumers: Vec<Vec<usize>> = vec![Vec::new(); els.len()];
    let mut wire_x: Vec<Vec<Option<f64>>> = vec![Vec::new(); els.len()];
    for (i, e) in els.iter().enumerate() {
        for c in e.ins.iter().flatten() {
            // `ids` holds positions in `els`, which `consumers` and `wire_x` have too.
            let Some(&p) = ids.get(&c.r) else { continue };
            if let (Some(cs), Some(xs)) = (consumers.get_mut(p), wire_x.get_mut(p)) {
                if !cs.contains(&i) {
                    cs.push(i);
                    xs.push(c.last.map(|l| l.0));
                }
            }
        }
    }
    for ((list, xs), e) in consumers.iter_mut().zip(&wire_x).zip(&els) {
        if e.kind == "simultaneousDivergence" && xs.iter().all(Option::is_some) {
            let mut pairs: Vec<(usize, f64)> = list.iter().copied().zip(xs.iter().map(|x| x.unwrap_or(0.0))).collect();
            pairs.sort_by(|a, b| a.1.total_cmp(&b.1));
            *list = pairs.into_iter().map(|p| p.0).collect();
        }
    }

    let mut g = Graph { steps: Vec::new(), trans: Vec::new(), loose: Vec::new(), entry: None, exit: None };
    // Step names by element (macro steps: their entry and exit steps).
    let mut step_in: HashMap<usize, Frag> = HashMap::new();
    let mut step_out: HashMap<usize, Frag> = HashMap::new();
    let mut macro_entry: HashMap<String, Frag> = HashMap::new();
    let mut first_step: Option<(usize, Frag)> = None;
    for (i, e) in els.iter().enumerate() {
        let mut key = key_prefix.clone();
        key.push(i);
        match e.kind {
            "step" => {
                let (step_actions, imported) = step_actions(cx, e.n);
                let name = cx.name(e.n, "name", "step");
                let mut list = Vec::new();
                if layout {
                    list.extend(geometry(e.n));
                }
                // The step actions are in the text: their attributes leave the kept addData
                // (an export writes them back from the text).
                list.extend(element_attrs_without(e.n, &|n| imported.contains(&n.id())));
                if first_step.is_none() {
                    first_step = Some((i, name.clone()));
                }
                step_in.insert(i, name.clone());
                step_out.insert(i, name.clone());
                g.steps.push(OutStep {
                    key,
                    name,
                    initial: xml::flag(e.n, "initialStep"),
                    attrs: list,
                    step_actions,
                    assocs: Vec::new(),
                    anchor: anchor(e.n),
                });
            }
            "macroStep" => {
                let body = child(e.n, "body").and_then(|b| child(b, "SFC"));
                let label = attr(e.n, "name").unwrap_or("").to_string();
                let flattened = match body {
                    Some(b) if depth < MAX_MACRO_DEPTH => {
                        let sub = graph(cx, imp, b, layout && has_layout(b), depth + 1, key.clone());
                        match (sub.entry.clone(), sub.exit.clone()) {
                            (Some(en), Some(ex)) => {
                                cx.diag(
                                    "SFC0709",
                                    anchor(e.n),
                                    format!(
                                        "macro step `{label}` is flattened: its body runs from step `{}` to step `{}`; \
                                         the chart's layout is not kept",
                                        en.text, ex.text
                                    ),
                                );
                                step_in.insert(i, en.clone());
                                step_out.insert(i, ex);
                                if !label.is_empty() {
                                    macro_entry.insert(label.to_ascii_uppercase(), en);
                                }
                                g.steps.extend(sub.steps);
                                g.trans.extend(sub.trans);
                                g.loose.extend(sub.loose);
                                true
                            }
                            _ => {
                                cx.diag(
                                    "SFC0705",
                                    anchor(e.n),
                                    format!("macro step `{label}` has a body without steps"),
                                );
                                false
                            }
                        }
                    }
                    Some(_) => {
                        cx.diag("SFC0705", anchor(e.n), "macro steps are nested too deeply");
                        false
                    }
                    None => {
                        cx.diag(
                            "SFC0705",
                            anchor(e.n),
                            format!("macro step `{label}` has no SFC body; it is imported as a plain step"),
                        );
                        false
                    }
                };
                if !flattened {
                    let name = cx.name(e.n, "name", "macro step");
                    step_in.insert(i, name.clone());
                    step_out.insert(i, name.clone());
                    let mut list = Vec::new();
                    if layout {
                        list.extend(geometry(e.n));
                    }
                    list.extend(element_attrs(e.n));
                    g.steps.push(OutStep {
                        key,
                        name,
                        initial: false,
                        attrs: list,
                        step_actions: Vec::new(),
                        assocs: Vec::new(),
                        anchor: anchor(e.n),
                    });
                }
            }
            _ => {}
        }
    }

    // Entry and exit of a macro body: the initial step (or the first step nothing leads to),
    // and the first step that leads nowhere.
    if depth > 0 {
        let is_step = |i: usize| els.get(i).is_some_and(|e| matches!(e.kind, "step" | "macroStep"));
        let entry = els
            .iter()
            .enumerate()
            .find(|(i, e)| is_step(*i) && xml::flag(e.n, "initialStep"))
            .or_else(|| els.iter().enumerate().find(|(i, e)| is_step(*i) && e.ins.iter().all(|c| c.is_empty())))
            .map(|(i, _)| i)
            .or(first_step.as_ref().map(|f| f.0));
        let exit = els
            .iter()
            .enumerate()
            .find(|(i, _)| {
                is_step(*i)
                    && !consumers
                        .get(*i)
                        .is_some_and(|cs| cs.iter().any(|&c| els.get(c).is_some_and(|e| e.kind != "actionBlock")))
            })
            .map(|(i, _)| i);
        g.entry = entry.and_then(|i| step_in.get(&i).cloned());
        g.exit = exit.and_then(|i| step_out.get(&i).cloned());
        // Inside a macro, the entry step is not an initial step of the chart.
        for s in &mut g.steps {
            if s.key.len() == key_prefix.len() + 1 {
                s.initial = false;
            }
        }
    }

    // Transitions.
    for (i, e) in els.iter().enumerate() {
        if e.kind != "transition" {
            continue;
        }
        let mut key = key_prefix.clone();
        key.push(i);
        let at = anchor(e.n);
        // Preceding steps.
        let mut from: Vec<Frag> = Vec::new();
        let mut seen = HashSet::new();
        let mut branch = None;
        if let Some(first) = e.ins.first() {
            if let Some(c) = first.first().filter(|_| layout) {
                if let Some(&p) =
                    ids.get(&c.r).filter(|&&p| els.get(p).is_some_and(|e| e.kind == "selectionDivergence"))
                {
                    let x = c.last.map(|l| l.0).or_else(|| xml::position(e.n).map(|p| p.0)).unwrap_or(0.0);
                    let mut div = key_prefix.clone();
                    div.push(p);
                    branch = Some((div, x));
                }
            }
            for c in first {
                up(cx, &els, &ids, c, &step_out, &mut from, &mut seen, 0);
            }
        }
        // Following steps.
        let mut to: Vec<Frag> = Vec::new();
        let mut jumps: Vec<String> = Vec::new();
        let mut seen = HashSet::new();
        down(cx, &els, &consumers, i, &step_in, &macro_entry, &mut to, &mut jumps, &mut seen, 0, layout);
        if from.is_empty() || to.is_empty() {
            // A chart being drawn: IEC text cannot hold the transition, the POU's `sfc.loose`
            // attribute does (the editor draws it, the export writes it back).
            let side = match (from.is_empty(), to.is_empty()) {
                (true, true) => "to any step",
                (true, false) => "to a preceding step",
                _ => "to a following step",
            };
            cx.diag(
                "SFC0706",
                at.clone(),
                format!(
                    "the transition is not connected {side}; it is kept in the drawing (`sfc.loose`), not in the chart"
                ),
            );
            let (cond, negated, name, _) = condition(cx, imp, sfc, e.n);
            let condition = match cond {
                Cond::St(x) | Cond::Il(x) => x.text.trim().to_string(),
                Cond::Net(f) => f.text,
            };
            let rect = xml::position(e.n)
                .map(|p| [p.0, p.1, xml::num(e.n, "width").unwrap_or(20.0), xml::num(e.n, "height").unwrap_or(2.0)]);
            g.loose.push(Loose {
                rect,
                from: from.iter().map(|f| f.text.clone()).collect(),
                to: to.iter().map(|f| f.text.clone()).collect(),
                name: name.map(|n| n.text).unwrap_or_default(),
                condition: if negated { format!("NOT ({condition})") } else { condition },
            });
            continue;
        }
        let mut list = Vec::new();
        if layout {
            list.extend(geometry(e.n));
            if !jumps.is_empty() {
                list.push((attrs::JUMP.to_string(), jumps.join(";")));
            }
        }
        let priority = attr(e.n, "priority").map(str::trim).filter(|p| !p.is_empty()).map(|p| {
            if p.parse::<u64>().is_err() {
                cx.diag(
                    "SFC0705",
                    attr_range(e.n, "priority").unwrap_or_else(|| at.clone()),
                    format!("priority `{p}` is not a number"),
                );
            }
            Frag::located(p, attr_range(e.n, "priority").unwrap_or_else(|| at.clone()))
        });
        let (cond, negated, name, reference) = condition(cx, imp, sfc, e.n);
        if let Some(r) = reference {
            list.push((attrs::REFERENCE.to_string(), r));
        }
        list.extend(element_attrs(e.n));
        g.trans.push(OutTrans { key, name, priority, from, to, cond, negated, attrs: list, anchor: at, branch });
    }

    // Action blocks.
    for e in els.iter().filter(|e| e.kind == "actionBlock") {
        let step = e.ins.first().and_then(|c| c.first()).and_then(|c| ids.get(&c.r)).copied();
        let target =
            step.filter(|&s| els.get(s).is_some_and(|e| e.kind == "step")).and_then(|s| step_in.get(&s).cloned());
        let Some(step_name) = target else {
            cx.diag(
                "SFC0706",
                anchor(e.n),
                "the action block is not connected to a step; its actions are not imported",
            );
            continue;
        };
        let Some(si) = g.steps.iter().position(|s| s.name.text.eq_ignore_ascii_case(&step_name.text)) else { continue };
        let mut count = 0;
        for a in children(e.n, "action") {
            if let Some(f) = association(cx, imp, a, &step_name.text) {
                if let Some(s) = g.steps.get_mut(si) {
                    s.assocs.push(f);
                }
                count += 1;
            }
        }
        if layout {
            let pos = xml::position(e.n).unwrap_or((0.0, 0.0));
            let v = format!(
                "{} {} {} {} {count}",
                attrs::fmt_num(pos.0),
                attrs::fmt_num(pos.1),
                attrs::fmt_num(xml::num(e.n, "width").unwrap_or(0.0)),
                attrs::fmt_num(xml::num(e.n, "height").unwrap_or(0.0))
            );
            let Some(s) = g.steps.get_mut(si) else { continue };
            match s.attrs.iter_mut().find(|(k, _)| k == attrs::ACTIONBLOCK) {
                Some(slot) => {
                    slot.1.push(';');
                    slot.1.push_str(&v);
                }
                None => {
                    // Right after the geometry, so the attribute order does not depend on where
                    // the block lies in the document.
                    let at = s
                        .attrs
                        .iter()
                        .take_while(|(k, _)| [attrs::X, attrs::Y, attrs::W, attrs::H].contains(&k.as_str()))
                        .count();
                    s.attrs.insert(at, (attrs::ACTIONBLOCK.to_string(), v));
                }
            }
        }
    }
    for e in els.iter() {
        match e.kind {
            "step"
            | "macroStep"
            | "transition"
            | "actionBlock"
            | "jumpStep"
            | "selectionDivergence"
            | "selectionConvergence"
            | "simultaneousDivergence"
            | "simultaneousConvergence"
            | "comment" => {}
            // FBD/LD elements wired into conditions are read by `network::condition`.
            "block" | "inVariable" | "outVariable" | "inOutVariable" | "contact" | "coil" | "leftPowerRail"
            | "rightPowerRail" | "connector" | "continuation" => {}
            "addData" | "documentation" => {}
            other => {
                cx.diag("SFC0710", anchor(e.n), format!("`{other}` in an SFC body is not imported"));
            }
        }
    }
    g
}

/// `sfc.x`, `sfc.y`, `sfc.w`, `sfc.h` of an element, as written in the file.
fn geometry(n: Node) -> Vec<(String, String)> {
    let mut out = Vec::new();
    if let Some(p) = child(n, "position") {
        for (k, a) in [(attrs::X, "x"), (attrs::Y, "y")] {
            if let Some(v) = xml::num(p, a) {
                out.push((k.to_string(), attrs::fmt_num(v)));
            }
        }
    }
    for (k, a) in [(attrs::W, "width"), (attrs::H, "height")] {
        if let Some(v) = xml::num(n, a) {
            out.push((k.to_string(), attrs::fmt_num(v)));
        }
    }
    out
}

/// Walks up from a transition's input to the steps before it.
#[allow(clippy::too_many_arguments)]
fn up(
    cx: &mut Ctx,
    els: &[El],
    ids: &HashMap<u64, usize>,
    c: &Conn,
    step_out: &HashMap<usize, Frag>,
    out: &mut Vec<Frag>,
    seen: &mut HashSet<usize>,
    depth: usize,
) {
    let Some(&p) = ids.get(&c.r) else {
        cx.diag("SFC0706", c.range.clone(), format!("the connection refers to localId {}, which does not exist", c.r));
        return;
    };
    if !seen.insert(p) || depth > 256 {
        return;
    }
    let Some(el) = els.get(p) else { return };
    match el.kind {
        "step" | "macroStep" => {
            if let Some(n) = step_out.get(&p) {
                if !out.iter().any(|f| f.text.eq_ignore_ascii_case(&n.text)) {
                    out.push(Frag::located(n.text.clone(), c.range.clone()));
                }
            }
        }
        "selectionDivergence" => {
            for cc in el.ins.iter().flatten() {
                up(cx, els, ids, cc, step_out, out, seen, depth + 1);
            }
        }
        // A parallel branch that ends in a jump (CODESYS draws it into the convergence) does
        // not converge: the steps before the transition are the other branches' last steps.
        "simultaneousConvergence" => {
            for cc in el.ins.iter().flatten().filter(|cc| !is_jump(els, ids, cc)) {
                up(cx, els, ids, cc, step_out, out, seen, depth + 1);
            }
        }
        // CODESYS draws a branch that ends in a jump into the convergence below it: the jump
        // does not flow on, so a convergence whose one other input is a step is that step.
        "selectionConvergence" => {
            let flowing: Vec<&Conn> = el.ins.iter().flatten().filter(|cc| !is_jump(els, ids, cc)).collect();
            if let [one] = flowing[..] {
                up(cx, els, ids, one, step_out, out, seen, depth + 1);
            } else {
                cx.diag(
                    "SFC0706",
                    c.range.clone(),
                    String::from("a transition must follow a step, not a `selectionConvergence`"),
                );
            }
        }
        other => {
            cx.diag("SFC0706", c.range.clone(), format!("a transition must follow a step, not a `{other}`"));
        }
    }
}

/// Whether the connection `c` comes from a jump.
fn is_jump(els: &[El], ids: &HashMap<u64, usize>, c: &Conn) -> bool {
    ids.get(&c.r).and_then(|&k| els.get(k)).is_some_and(|e| e.kind == "jumpStep")
}

/// Walks down from a transition to the steps after it (through simultaneous divergences,
/// selection convergences and jumps).
#[allow(clippy::too_many_arguments)]
fn down(
    cx: &mut Ctx,
    els: &[El],
    consumers: &[Vec<usize>],
    from: usize,
    step_in: &HashMap<usize, Frag>,
    macro_entry: &HashMap<String, Frag>,
    out: &mut Vec<Frag>,
    jumps: &mut Vec<String>,
    seen: &mut HashSet<usize>,
    depth: usize,
    layout: bool,
) {
    if depth > 256 {
        return;
    }
    for &c in consumers.get(from).map_or(&[][..], Vec::as_slice) {
        if !seen.insert(c) {
            continue;
        }
        let Some(e) = els.get(c) else { continue };
        match e.kind {
            "step" | "macroStep" => {
                if let Some(n) = step_in.get(&c) {
                    if !out.iter().any(|f| f.text.eq_ignore_ascii_case(&n.text)) {
                        out.push(Frag::located(n.text.clone(), anchor(e.n)));
                    }
                }
            }
            "jumpStep" => {
                let target = attr(e.n, "targetName").unwrap_or("").trim().to_string();
                let range = attr_range(e.n, "targetName").unwrap_or_else(|| anchor(e.n));
                let f = match macro_entry.get(&target.to_ascii_uppercase()) {
                    Some(en) => en.clone().locate(range),
                    None if cx.is_name(&target) => {
                        let mut f = Frag::plain(target.clone());
                        if attr_is_exact(cx, e.n, "targetName", &target) {
                            f.marks.push(crate::emit::MapEntry {
                                text: 0..target.len() as u32,
                                xml: range,
                                exact: true,
                            });
                        } else {
                            f = f.locate(range);
                        }
                        f
                    }
                    None => cx.name(e.n, "targetName", "jump target"),
                };
                if layout {
                    let pos = xml::position(e.n).unwrap_or((0.0, 0.0));
                    jumps.push(format!("{} {} {}", f.text, attrs::fmt_num(pos.0), attrs::fmt_num(pos.1)));
                }
                if !out.iter().any(|g| g.text.eq_ignore_ascii_case(&f.text)) {
                    out.push(f);
                }
            }
            "simultaneousDivergence" | "selectionConvergence" => {
                down(cx, els, consumers, c, step_in, macro_entry, out, jumps, seen, depth + 1, layout);
            }
            "actionBlock" => {}
            other => {
                cx.diag("SFC0706", anchor(e.n), format!("a `{other}` cannot follow a transition"));
            }
        }
    }
}

fn attr_is_exact(cx: &Ctx, n: Node, name: &str, value: &str) -> bool {
    attr_range(n, name).is_some_and(|r| super::attr_is_raw(cx.src, &r, value))
}

/// One `action` of an action block as an association `Name(Q, T#1s, Indicator);`.
fn association<'a, 'i>(cx: &mut Ctx, imp: &mut Importer<'_, 'a, 'i>, a: Node<'a, 'i>, step: &str) -> Option<Frag> {
    let at = anchor(a);
    let name = if let Some(r) = child(a, "reference") {
        // `Motor.ACT_Stop`: an action of an instance (CODESYS), kept qualified.
        let raw = attr(r, "name").unwrap_or("").trim();
        if raw.contains('.') && raw.split('.').all(|p| cx.is_name(p)) {
            Frag::located(raw.to_string(), attr_range(r, "name").unwrap_or_else(|| anchor(r)))
        } else {
            cx.name(r, "name", "action")
        }
    } else if let Some(body) = child(a, "inline") {
        let k = imp.inline_count.entry(step.to_ascii_uppercase()).or_insert(0);
        *k += 1;
        let k = *k;
        let name = cx.fresh_name(&format!("{step}_INLINE{k}"));
        imp.inline.push(InlineAction { step: step.to_string(), k, name: name.clone(), action: a, body });
        Frag::located(name, at.clone())
    } else {
        cx.diag("SFC0705", at, "the action has neither a reference nor an inline body; it is not imported");
        return None;
    };
    let mut f = Frag::plain("        ");
    f.push(&name);
    f.push_str("(");
    match attr_xtext(cx, a, "qualifier") {
        Some(q) => f.push(&Frag::from_xtext(&q.trim())),
        None => f.push_str("N"),
    }
    if let Some(d) = attr_xtext(cx, a, "duration").map(|d| d.trim()).filter(|d| !d.text.is_empty()) {
        f.push_str(", ");
        f.push(&Frag::from_xtext(&d));
    }
    if let Some(i) = attr_xtext(cx, a, "indicator").map(|d| d.trim()).filter(|d| !d.text.is_empty()) {
        f.push_str(", ");
        f.push(&Frag::from_xtext(&i));
    }
    f.push_str(");\n");
    Some(f.locate(at))
}

/// The condition of a transition: the text, whether it is negated, the transition's name (from
/// `inline@name` or our `addData`), and the `transitions` entry it refers to.
fn condition<'a, 'i>(
    cx: &mut Ctx,
    imp: &mut Importer<'_, 'a, 'i>,
    sfc: Node<'a, 'i>,
    t: Node<'a, 'i>,
) -> (Cond, bool, Option<Frag>, Option<String>) {
    let at = anchor(t);
    let mut name = own_data(t, "name")
        .and_then(|n| attr(n, "value"))
        .filter(|v| cx.is_name(v) && !cx.used.contains(&v.to_ascii_uppercase()))
        .map(|v| Frag::located(v, at.clone()));
    if let Some(n) = &name {
        cx.used.insert(n.text.to_ascii_uppercase());
    }
    let Some(c) = child(t, "condition") else {
        cx.diag("SFC0708", at.clone(), "the transition has no condition; imported as FALSE");
        return (Cond::Net(Frag::located("FALSE", at)), false, name, None);
    };
    let negated = xml::flag(c, "negated");
    if let Some(inline) = child(c, "inline") {
        if let Some(n) = attr(inline, "name").map(str::trim).filter(|n| !n.is_empty()) {
            if cx.is_name(n) && cx.used.contains(&n.to_ascii_uppercase()) {
                cx.diag(
                    "SFC0710",
                    attr_range(inline, "name").unwrap_or_else(|| anchor(inline)),
                    format!("`{n}` already names something else in the POU; the transition is imported without a name"),
                );
            } else if cx.is_name(n) {
                cx.used.insert(n.to_ascii_uppercase());
                let mut f = Frag::plain(n);
                if let Some(r) = attr_range(inline, "name").filter(|r| super::attr_is_raw(cx.src, r, n)) {
                    f.marks.push(crate::emit::MapEntry { text: 0..n.len() as u32, xml: r, exact: true });
                }
                name = Some(f);
            } else {
                cx.diag(
                    "SFC0710",
                    attr_range(inline, "name").unwrap_or_else(|| anchor(inline)),
                    format!("`{n}` is not an IEC 61131-3 identifier; the transition is imported without a name"),
                );
            }
        }
        let cond = body_condition(cx, inline, name.as_ref().map(|n| n.text.clone()).unwrap_or_default().as_str());
        return (cond, negated, name, None);
    }
    if let Some(r) = child(c, "reference") {
        let rname = attr(r, "name").unwrap_or("").trim().to_string();
        imp.referenced.insert(rname.to_ascii_uppercase());
        let target = imp
            .named_conditions
            .iter()
            .find(|n| attr(**n, "name").is_some_and(|v| v.trim().eq_ignore_ascii_case(&rname)));
        let Some(target) = target else {
            cx.diag(
                "SFC0708",
                attr_range(r, "name").unwrap_or_else(|| anchor(r)),
                format!("no transition condition named `{rname}` in the POU's `transitions`; imported as FALSE"),
            );
            return (Cond::Net(Frag::located("FALSE", anchor(r))), negated, name, None);
        };
        let cond = match child(*target, "body") {
            Some(b) => body_condition(cx, b, &rname),
            None => {
                cx.diag(
                    "SFC0708",
                    anchor(*target),
                    format!("transition condition `{rname}` has no body; imported as FALSE"),
                );
                Cond::Net(Frag::located("FALSE", anchor(*target)))
            }
        };
        return (cond, negated, name, Some(attrs::escape(&rname)));
    }
    if let Some(cp) = child(c, "connectionPointIn") {
        let net = imp.nets.entry(sfc.id()).or_insert_with(|| std::rc::Rc::new(network::parse(sfc))).clone();
        let f = network::condition(cx, &net, cp, &at);
        return (Cond::Net(f), negated, name, None);
    }
    // TC6 v1.0 wires a condition without `connectionPointIn`: `<condition><connection …/>`.
    if child(c, "connection").is_some() {
        let net = imp.nets.entry(sfc.id()).or_insert_with(|| std::rc::Rc::new(network::parse(sfc))).clone();
        let f = network::condition(cx, &net, c, &at);
        return (Cond::Net(f), negated, name, None);
    }
    cx.diag("SFC0708", anchor(c), "the condition is empty; imported as FALSE");
    (Cond::Net(Frag::located("FALSE", anchor(c))), negated, name, None)
}

/// The condition held in a `body` (an inline condition or a named one): an ST expression (or
/// `Name := expression;`), IL (a trailing `ST Name` dropped), or an FBD/LD network assigning
/// the name.
fn body_condition(cx: &mut Ctx, body: Node, name: &str) -> Cond {
    let Some(l) = elements(body).find(|e| ["IL", "ST", "FBD", "LD", "SFC"].contains(&e.tag_name().name())) else {
        cx.diag("SFC0708", anchor(body), "the condition body has no IL, ST, FBD or LD; imported as FALSE");
        return Cond::Net(Frag::located("FALSE", anchor(body)));
    };
    match l.tag_name().name() {
        "ST" => {
            let t = super::dialect::map(cx, &xml::formatted_text(l)).trim();
            Cond::St(st_expression(&t, name))
        }
        "IL" => {
            let t = xml::formatted_text(l).trim();
            Cond::Il(il_condition(&t, name))
        }
        "SFC" => {
            cx.diag(
                "SFC0705",
                anchor(l),
                "a transition condition written in SFC cannot be imported; imported as FALSE",
            );
            Cond::Net(Frag::located("FALSE", anchor(l)))
        }
        _ => {
            let owner = body.parent().filter(|p| p.is_element()).map(anchor).unwrap_or_else(|| anchor(body));
            Cond::Net(network::transition_body(cx, l, name, &owner))
        }
    }
}

/// The expression of an ST condition: `x AND y`, `x AND y;`, `Name := x AND y;`, or Beremiz's
/// form of a named condition, `:= x AND y;`.
fn st_expression(t: &XText, name: &str) -> XText {
    let (tokens, _) = sfc_syntax::lexer::lex(0, &t.text);
    let sig: Vec<_> =
        tokens.iter().filter(|k| !k.kind.is_trivia() && k.kind != sfc_syntax::lexer::TokenKind::Eof).collect();
    let mut start = 0usize;
    let mut end = t.text.len();
    use sfc_syntax::lexer::TokenKind;
    match sig.as_slice() {
        [first, ..] if first.kind == TokenKind::Assign => start = first.end as usize,
        [id, assign, ..]
            if id.kind == TokenKind::Ident
                && assign.kind == TokenKind::Assign
                && (name.is_empty()
                    || t.text
                        .get(id.start as usize..id.end as usize)
                        .is_some_and(|w| w.eq_ignore_ascii_case(name))) =>
        {
            start = assign.end as usize
        }
        _ => {}
    }
    if let Some(last) = sig.last() {
        if last.kind == sfc_syntax::lexer::TokenKind::Semi && last.start as usize >= start {
            end = last.start as usize;
        }
    }
    t.slice(start..end).trim()
}

/// IL text of a condition without a final `ST Name` (how a named IL condition stores its
/// result).
fn il_condition(t: &XText, name: &str) -> XText {
    let text = &t.text;
    let trimmed = text.trim_end();
    if let Some(nl) = trimmed.rfind('\n') {
        let last: Vec<&str> = trimmed[nl + 1..].split_whitespace().collect();
        if let [op, operand] = last.as_slice() {
            if op.eq_ignore_ascii_case("ST") && (name.is_empty() || operand.eq_ignore_ascii_case(name)) {
                return t.slice(0..nl);
            }
        }
    }
    t.clone()
}

fn write_step(cx: &mut Ctx, s: &OutStep) {
    cx.em.open(s.anchor.clone());
    cx.attributes(&s.attrs, "    ");
    cx.em.str(if s.initial { "    INITIAL_STEP " } else { "    STEP " });
    cx.em.frag(&s.name);
    if s.assocs.is_empty() && s.step_actions.is_empty() {
        cx.em.str(": END_STEP\n\n");
    } else {
        cx.em.str(":\n");
        for a in s.step_actions.iter().chain(&s.assocs) {
            cx.em.frag(a);
        }
        cx.em.str("    END_STEP\n\n");
    }
    cx.em.close();
}

fn write_list(cx: &mut Ctx, list: &[Frag]) {
    if list.len() > 1 {
        cx.em.str("(");
    }
    for (i, f) in list.iter().enumerate() {
        if i > 0 {
            cx.em.str(", ");
        }
        cx.em.frag(f);
    }
    if list.len() > 1 {
        cx.em.str(")");
    }
}

fn write_transition(cx: &mut Ctx, t: &OutTrans) {
    cx.em.open(t.anchor.clone());
    cx.attributes(&t.attrs, "    ");
    cx.em.str("    TRANSITION ");
    if let Some(n) = &t.name {
        cx.em.frag(n);
        cx.em.str(" ");
    }
    if let Some(p) = &t.priority {
        cx.em.str("(PRIORITY := ");
        cx.em.frag(p);
        cx.em.str(") ");
    }
    cx.em.str("FROM ");
    write_list(cx, &t.from);
    cx.em.str(" TO ");
    write_list(cx, &t.to);
    match &t.cond {
        Cond::Il(il) => {
            cx.em.str(":\n");
            cx.em.lines(il, "        ");
            if t.negated {
                cx.em.str("        NOT\n");
            }
        }
        Cond::St(x) => {
            cx.em.str("\n        := ");
            if t.negated {
                cx.em.str("NOT (");
            }
            write_expression(cx, x);
            if t.negated {
                cx.em.str(")");
            }
            cx.em.str(";\n");
        }
        Cond::Net(f) => {
            cx.em.str("\n        := ");
            let f = if t.negated { f.clone().not() } else { f.clone() };
            cx.em.frag(&f);
            cx.em.str(";\n");
        }
    }
    cx.em.str("    END_TRANSITION\n\n");
    cx.em.close();
}

/// An expression copied from the XML, its later lines indented under the first.
fn write_expression(cx: &mut Ctx, x: &XText) {
    if x.text.trim().is_empty() {
        cx.em.frag(&Frag::located("FALSE", x.anchor.clone()));
        cx.diag("SFC0708", x.anchor.clone(), "the condition is empty; imported as FALSE");
        return;
    }
    let mut start = 0;
    let text = &x.text;
    let mut first = true;
    for (i, b) in text.bytes().enumerate().chain(std::iter::once((text.len(), b'\n'))) {
        if b == b'\n' {
            let line = x.slice(start..i);
            let line = if first { line } else { line.trim() };
            if !first {
                cx.em.str("\n           ");
            }
            cx.em.xtext(&XText { text: line.text.trim_end().to_string(), ..line });
            first = false;
            start = i + 1;
        }
    }
}

/// The `action`s of a POU as `ACTION name: … END_ACTION` (with their attributes), in document
/// order: a chart's, or those after the statements of a POU that is no chart.
pub(crate) fn write_actions(cx: &mut Ctx, actions: &[Node]) {
    for a in actions {
        cx.em.open(anchor(*a));
        let list = element_attrs(*a);
        cx.attributes(&list, "    ");
        let name = cx.name(*a, "name", "action");
        cx.em.str("    ACTION ");
        cx.em.frag(&name);
        cx.em.str(":\n");
        match child(*a, "body") {
            Some(b) => action_body(cx, b, "        "),
            None => {
                cx.diag("SFC0705", anchor(*a), "the action has no body");
            }
        }
        cx.em.str("    END_ACTION\n\n");
        cx.em.close();
    }
}

/// CODESYS's step actions (entry, main, exit) of a step, properties by GUID: the lines
/// `ENTRY_ACTION := Name;` and the property elements they come from. A value that is no
/// action name (`Name` or `instance.Action`) is said and stays in the step's addData.
fn step_actions(cx: &mut Ctx, step: Node) -> (Vec<Frag>, Vec<roxmltree::NodeId>) {
    let props = children(step, "addData")
        .flat_map(|a| children(a, "data"))
        .filter(|d| attr(*d, "name") == Some(CODESYS_SFC_ELEMENT))
        .flat_map(|d| d.descendants().filter(|n| n.is_element() && n.tag_name().name() == "attribute"));
    let mut lines = Vec::new();
    let mut taken = Vec::new();
    for p in props.collect::<Vec<_>>() {
        let Some((_, kind)) =
            STEP_ACTION_GUIDS.iter().find(|(g, _)| attr(p, "guid").is_some_and(|v| v.eq_ignore_ascii_case(g)))
        else {
            continue;
        };
        let action = p.text().unwrap_or("").trim();
        if action.is_empty() {
            taken.push(p.id());
            continue;
        }
        if !action.split('.').all(|p| cx.is_name(p)) {
            cx.diag(
                "SFC0704",
                anchor(p),
                format!(
                    "the {} action `{action}` of step `{}` is no action name; it is kept in the step's data and does not run",
                    kind.word(),
                    attr(step, "name").unwrap_or("?").trim()
                ),
            );
            continue;
        }
        lines.push(Frag::located(format!("        {} := {action};\n", kind.keyword()), anchor(p)));
        taken.push(p.id());
    }
    (lines, taken)
}
