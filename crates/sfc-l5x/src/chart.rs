//! One `<Routine Type="SFC">`: steps, actions, transitions, stops, and the topology that the
//! branches, legs and directed links draw, as sfc text.

use crate::st::{self, Elements, Mapped, StepInfo, Use};
use crate::Ctx;
use roxmltree::Node;
use sfc_xmlmap::xml::{anchor, attr, attr_range, child, children, elements, serialize, text_of};
use sfc_xmlmap::{Frag, XText};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::ops::Range;

/// The tag data of the chart's elements (SFC_STEP, SFC_ACTION, SFC_STOP tags), by upper name.
#[derive(Default)]
pub(crate) struct SfcTags {
    pub pre: HashMap<String, i64>,
    pub l5k: HashMap<String, String>,
    /// The tags' descriptions (of every tag: a transition's is its BOOL tag's).
    pub desc: HashMap<String, String>,
}

/// One step (or stop) as written.
pub(crate) struct StepOut {
    pub name: Frag,
    pub initial: bool,
    pub anchor: Range<u32>,
    pub attrs: Vec<(String, String)>,
    /// `Action(Q[, T#…])` lines.
    pub assoc: Vec<Frag>,
}

pub(crate) struct TransOut {
    pub name: Frag,
    pub priority: Option<usize>,
    pub from: Vec<String>,
    pub to: Vec<String>,
    pub cond: Frag,
    pub anchor: Range<u32>,
    pub attrs: Vec<(String, String)>,
}

pub(crate) struct ActionOut {
    pub name: Frag,
    pub anchor: Range<u32>,
    pub attrs: Vec<(String, String)>,
    pub body: Vec<Frag>,
}

/// A chart ready to be written.
pub(crate) struct ChartOut {
    pub attrs: Vec<(String, String)>,
    pub steps: Vec<StepOut>,
    pub transitions: Vec<TransOut>,
    pub actions: Vec<ActionOut>,
    /// Identifiers the code uses, how, where.
    pub idents: Vec<(String, Use, Range<u32>)>,
    /// Upper-case names of the chart's elements (steps, stops, transitions, actions).
    pub names: HashSet<String>,
    /// Upper-case names of the transitions.
    pub transition_names: HashSet<String>,
}

/// What a routine element is, by ID.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
    Step,
    Stop,
    Transition,
    /// A branch's own ID, with its index in `branches`.
    Branch(usize),
    /// A leg, with its branch's index.
    Leg(usize),
}

struct Branch {
    selection: bool,
    diverge: bool,
    user_priority: bool,
    legs: Vec<u64>,
    id: u64,
    anchor: Range<u32>,
}

/// A branch a walk went through: selection?, divergence?, where.
type Via = (bool, bool, Range<u32>);

/// Bound on the walks through branches and legs of one routine (a file may link them in cycles
/// or make every transition's walk long): past it the links are not followed further.
const MAX_WALK: usize = 2_000_000;

fn qualifier(q: &str) -> Option<(&'static str, bool)> {
    // (IEC qualifier, needs a time)
    Some(match q.trim() {
        "NonStored" | "N" => ("N", false),
        "Stored" | "S" => ("S", false),
        "Reset" | "R" => ("R", false),
        "TimeLimited" | "L" => ("L", true),
        "TimeDelayed" | "D" => ("D", true),
        "Pulse" | "P" => ("P", false),
        "PulseRisingEdge" | "P1" => ("P1", false),
        "PulseFallingEdge" | "P0" => ("P0", false),
        "StoredTimeLimited" | "SL" => ("SL", true),
        "StoredTimeDelayed" | "SD" => ("SD", true),
        "TimeDelayedStored" | "DS" => ("DS", true),
        _ => return None,
    })
}

/// The lines of an `STContent` (each `Line`'s text without the line breaks Studio writes around
/// its CDATA), joined by line breaks, and each line's `Number`.
pub(crate) fn st_lines(content: Option<Node>) -> (XText, Vec<String>) {
    let mut out = XText { anchor: content.map(anchor).unwrap_or_default(), ..Default::default() };
    let mut numbers = Vec::new();
    for (i, l) in content.into_iter().flat_map(|c| children(c, "Line")).enumerate() {
        if i > 0 {
            out.push_str("\n");
        }
        let t = text_of(l);
        let s = t.text.as_str();
        let start = s.len() - s.trim_start_matches(['\r', '\n']).len();
        let end = s.trim_end_matches(['\r', '\n']).len().max(start);
        out.push(&t.slice(start..end));
        numbers.push(attr(l, "Number").unwrap_or("").to_string());
    }
    (out, numbers)
}

/// The element's attributes as written (`ID="0" X="200" …`), but `Operand`.
fn attrs_of(n: Node) -> String {
    n.attributes()
        .filter(|a| a.name() != "Operand")
        .map(|a| format!("{}=\"{}\"", a.name(), a.value()))
        .collect::<Vec<_>>()
        .join(" ")
}

fn id_of(cx: &mut Ctx, n: Node) -> Option<u64> {
    let id = attr(n, "ID").and_then(|v| v.trim().parse::<u64>().ok());
    if id.is_none() {
        cx.diag(
            "SFC0725",
            attr_range(n, "ID").unwrap_or_else(|| anchor(n)),
            format!("`{}` has no numeric ID: it is not imported", n.tag_name().name()),
        );
    }
    id
}

fn register<'a, 'i>(
    cx: &mut Ctx,
    kinds: &mut HashMap<u64, (Kind, Node<'a, 'i>)>,
    id: u64,
    k: Kind,
    n: Node<'a, 'i>,
) -> bool {
    if kinds.contains_key(&id) {
        cx.diag(
            "SFC0725",
            attr_range(n, "ID").unwrap_or_else(|| anchor(n)),
            format!("the ID {id} is used twice: this `{}` is not imported", n.tag_name().name()),
        );
        return false;
    }
    kinds.insert(id, (k, n));
    true
}

/// Reads the chart of `routine` (its `SFCContent`).
pub(crate) fn read(cx: &mut Ctx, content: Node, tags: &SfcTags) -> ChartOut {
    let mut out = ChartOut {
        attrs: Vec::new(),
        steps: Vec::new(),
        transitions: Vec::new(),
        actions: Vec::new(),
        idents: Vec::new(),
        names: HashSet::new(),
        transition_names: HashSet::new(),
    };
    let sheet = [attr(content, "SheetSize"), attr(content, "SheetOrientation")];
    if sheet.iter().any(Option::is_some) {
        out.attrs.push(("sfc.logix.sheet".into(), sheet.map(|v| v.unwrap_or("")).join("|")));
    }
    let names = ["StepName", "TransitionName", "ActionName", "StopName"].map(|k| attr(content, k));
    if names.iter().any(Option::is_some) {
        out.attrs.push(("sfc.logix.names".into(), names.map(|v| v.unwrap_or("")).join("|")));
    }
    // Every element by ID.
    let mut kinds: HashMap<u64, (Kind, Node)> = HashMap::new();
    let mut branches: Vec<Branch> = Vec::new();
    let mut ordered: Vec<(u64, Kind, Node)> = Vec::new();
    for e in elements(content) {
        let name = e.tag_name().name();
        let kind = match name {
            "Step" => Kind::Step,
            "Stop" => Kind::Stop,
            "Transition" => Kind::Transition,
            "Branch" => Kind::Branch(branches.len()),
            "DirectedLink" => continue,
            "TextBox" | "Attachment" | "SbrRet" => {
                let key = match name {
                    "TextBox" => "sfc.logix.textbox",
                    "Attachment" => "sfc.logix.attachment",
                    _ => "sfc.logix.sbrret",
                };
                // As written in the file (CDATA and line breaks included), for the way back.
                let raw = e.document().input_text().get(e.range()).map_or_else(|| serialize(e), str::to_string);
                out.attrs.push((key.into(), raw));
                if name == "TextBox" {
                    // The editor draws it as a text label where Studio had it.
                    let num = |k: &str| attr(e, k).and_then(|v| v.trim().parse::<f64>().ok()).filter(|v| v.is_finite());
                    let text = child(e, "Text").map(|t| text_of(t).text.trim().to_string()).unwrap_or_default();
                    if let (Some(x), Some(y)) = (num("X"), num("Y")) {
                        let w = num("Width").filter(|w| *w > 0.0).unwrap_or(200.0);
                        let h = 20.0 * (text.lines().count().max(1) as f64 + 1.0);
                        out.attrs.push(("sfc.comment".into(), format!("{x} {y} {w} {h}\n{text}")));
                    }
                }
                if name == "SbrRet" {
                    cx.diag(
                        "SFC0722",
                        anchor(e),
                        "the SFC subroutine parameters (`SbrRet`) are kept for the way back, not simulated",
                    );
                }
                continue;
            }
            other => {
                cx.diag("SFC0722", anchor(e), format!("the element `{other}` of an SFC routine is not imported"));
                continue;
            }
        };
        let Some(id) = id_of(cx, e) else { continue };
        if let Kind::Branch(bi) = kind {
            let bt = attr(e, "BranchType").unwrap_or("");
            let bf = attr(e, "BranchFlow").unwrap_or("");
            if !matches!(bt, "Selection" | "Simultaneous") || !matches!(bf, "Diverge" | "Converge") {
                cx.diag(
                    "SFC0727",
                    anchor(e),
                    format!(
                        "a branch of type `{bt}` and flow `{bf}` is not known; read as a selection {}",
                        if bf == "Converge" { "convergence" } else { "divergence" }
                    ),
                );
            }
            if !register(cx, &mut kinds, id, kind, e) {
                continue;
            }
            let mut legs = Vec::new();
            for l in children(e, "Leg") {
                let Some(lid) = id_of(cx, l) else { continue };
                if register(cx, &mut kinds, lid, Kind::Leg(bi), l) {
                    legs.push(lid);
                }
                if attr(l, "Force").is_some_and(|f| f != "NoForce") {
                    cx.diag(
                        "SFC0722",
                        attr_range(l, "Force").unwrap_or_else(|| anchor(l)),
                        "a forced leg is imported without its force",
                    );
                }
            }
            let user_priority = attr(e, "Priority") == Some("UserDefined");
            branches.push(Branch {
                selection: bt != "Simultaneous",
                diverge: bf != "Converge",
                user_priority,
                legs,
                id,
                anchor: anchor(e),
            });
            out.attrs.push((
                "sfc.logix.branch".into(),
                format!(
                    "{id};{};{bt};{bf};{};{}",
                    attr(e, "Y").unwrap_or(""),
                    attr(e, "Priority").unwrap_or(""),
                    children(e, "Leg").filter_map(|l| attr(l, "ID")).collect::<Vec<_>>().join(",")
                ),
            ));
            continue;
        }
        if register(cx, &mut kinds, id, kind, e) {
            ordered.push((id, kind, e));
        }
    }
    // Links.
    let mut succ: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    let mut pred: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    let mut link_list = Vec::new();
    for l in children(content, "DirectedLink") {
        let f = attr(l, "FromID").and_then(|v| v.trim().parse::<u64>().ok());
        let t = attr(l, "ToID").and_then(|v| v.trim().parse::<u64>().ok());
        let (Some(f), Some(t)) = (f, t) else {
            cx.diag("SFC0725", anchor(l), "a directed link without numeric `FromID` and `ToID` is not imported");
            continue;
        };
        for (end, which) in [(f, "FromID"), (t, "ToID")] {
            if !kinds.contains_key(&end) {
                cx.diag(
                    "SFC0725",
                    attr_range(l, which).unwrap_or_else(|| anchor(l)),
                    format!("the link names ID {end}, which no element of the routine has"),
                );
            }
        }
        if !kinds.contains_key(&f) || !kinds.contains_key(&t) {
            continue;
        }
        let hidden = attr(l, "Show") == Some("false");
        link_list.push(format!("{f}>{t}{}", if hidden { "h" } else { "" }));
        succ.entry(f).or_default().push(t);
        pred.entry(t).or_default().push(f);
    }
    // Branches are junctions: a diverge is entered by its ID and left by its legs, a converge
    // entered by its legs and left by its ID.
    for b in &branches {
        for &l in &b.legs {
            let (a, z) = if b.diverge { (b.id, l) } else { (l, b.id) };
            succ.entry(a).or_default().push(z);
            pred.entry(z).or_default().push(a);
        }
    }
    if !link_list.is_empty() {
        out.attrs.push(("sfc.logix.links".into(), link_list.join(",")));
    }
    // Names of steps, stops, actions (for the ST mapping and the text).
    let mut el = Elements { renamed: cx.renamed.clone(), ..Elements::default() };
    let mut names_by_id: HashMap<u64, String> = HashMap::new();
    let mut x_of: HashMap<u64, f64> = HashMap::new();
    for &(id, k, e) in &ordered {
        if let Some(x) = attr(e, "X").and_then(|v| v.trim().parse::<f64>().ok()) {
            x_of.insert(id, x);
        }
        if !matches!(k, Kind::Step | Kind::Stop | Kind::Transition) {
            continue;
        }
        let name = cx.operand_name(e, if k == Kind::Transition { "transition" } else { "step" });
        let up = name.text.to_ascii_uppercase();
        if !out.names.insert(up.clone()) {
            cx.diag(
                "SFC0725",
                attr_range(e, "Operand").unwrap_or_else(|| anchor(e)),
                format!("`{}` names two elements of the chart", name.text),
            );
        }
        names_by_id.insert(id, name.text.clone());
        if k == Kind::Transition {
            out.transition_names.insert(up.clone());
        }
        match k {
            Kind::Step => {
                let pre_expr = if attr(e, "PresetUsesExpr") == Some("true") {
                    let (x, _) = st_lines(child(e, "Preset").and_then(|p| child(p, "STContent")));
                    Some(x)
                } else {
                    None
                };
                // The expression is Logix ST too (tags renamed; tags it reads declared from use).
                let pre_expr = pre_expr.map(|x| {
                    let m = st::map(&x.trim(), &Elements { renamed: cx.renamed.clone(), ..Elements::default() });
                    cx.problems(&m.problems);
                    out.idents.extend(m.idents);
                    m.frag
                });
                el.steps.insert(
                    up.clone(),
                    StepInfo { name: name.text.clone(), pre: tags.pre.get(&up).copied(), pre_expr },
                );
            }
            Kind::Stop => {
                el.stops.insert(up, name.text.clone());
            }
            _ => {}
        }
        for a in children(e, "Action") {
            if let Some(op) = attr(a, "Operand") {
                if sfc_syntax::keywords::is_identifier(op.trim()) {
                    el.actions.insert(op.trim().to_ascii_uppercase(), op.trim().to_string());
                    if !matches!(attr(a, "Qualifier").map(str::trim), Some("Reset" | "R")) {
                        el.stored.insert(op.trim().to_ascii_uppercase());
                    }
                }
            }
        }
    }
    let step_like = |id: u64| matches!(kinds.get(&id), Some((Kind::Step | Kind::Stop, _)));
    let is_trans = |id: u64| matches!(kinds.get(&id), Some((Kind::Transition, _)));
    let budget = std::cell::Cell::new(MAX_WALK);
    // Walks through junctions from `id` (forward or backward) to the steps and transitions.
    let walk = |id: u64, fwd: bool| -> (Vec<u64>, Vec<Via>) {
        let edges = if fwd { &succ } else { &pred };
        let mut found = Vec::new();
        let mut via = Vec::new();
        let mut seen = HashSet::new();
        let mut stack: Vec<u64> = edges.get(&id).cloned().unwrap_or_default().into_iter().rev().collect();
        while let Some(v) = stack.pop() {
            // One budget for the whole routine: a file can make every walk long.
            if budget.get() == 0 {
                break;
            }
            budget.set(budget.get() - 1);
            if !seen.insert(v) {
                continue;
            }
            match kinds.get(&v) {
                Some((Kind::Branch(b) | Kind::Leg(b), _)) => {
                    if let Some(br) = branches.get(*b) {
                        via.push((br.selection, br.diverge, br.anchor.clone()));
                    }
                    for w in edges.get(&v).into_iter().flatten().rev() {
                        stack.push(*w);
                    }
                }
                Some(_) => found.push(v),
                None => {}
            }
        }
        (found, via)
    };
    // Transitions: what precedes and follows each.
    let mut outgoing: BTreeMap<u64, Vec<(u64, f64, usize)>> = BTreeMap::new();
    let mut trans_ends: HashMap<u64, (Vec<u64>, Vec<u64>)> = HashMap::new();
    for &(id, k, e) in &ordered {
        if k != Kind::Transition {
            continue;
        }
        let (before, via_b) = walk(id, false);
        let (after, via_a) = walk(id, true);
        let here = anchor(e);
        let from: Vec<u64> = before.iter().copied().filter(|&v| step_like(v)).collect();
        let to: Vec<u64> = after.iter().copied().filter(|&v| step_like(v)).collect();
        if before.iter().chain(&after).any(|&v| is_trans(v)) {
            cx.diag(
                "SFC0725",
                here.clone(),
                format!(
                    "the transition `{}` is linked to another transition without a step between them",
                    names_by_id.get(&id).map_or("", String::as_str)
                ),
            );
        }
        if via_b.iter().any(|(sel, div, _)| *sel && !*div && from.len() > 1) {
            cx.diag(
                "SFC0725",
                here.clone(),
                "a selection convergence above a transition: its legs are read as one simultaneous convergence",
            )
            .notes
            .push("Studio places a selection convergence between the last transitions of its legs and a step".into());
        }
        if via_a.iter().any(|(sel, div, _)| *sel && *div && to.len() > 1) {
            cx.diag(
                "SFC0725",
                here.clone(),
                "a selection divergence below a transition: its legs are read as one simultaneous divergence",
            )
            .notes
            .push("Studio places a selection divergence between a step and the first transitions of its legs".into());
        }
        // The leg order of a selection divergence the transition hangs on, for ties.
        let leg_index = pred.get(&id).into_iter().flatten().find_map(|p| match kinds.get(p) {
            Some((Kind::Leg(b), _)) => branches.get(*b).and_then(|br| br.legs.iter().position(|l| l == p)),
            _ => None,
        });
        for &s in &from {
            outgoing.entry(s).or_default().push((
                id,
                x_of.get(&id).copied().unwrap_or(0.0),
                leg_index.unwrap_or(usize::MAX),
            ));
        }
        trans_ends.insert(id, (from, to));
    }
    if budget.get() == 0 {
        cx.diag("SFC0725", anchor(content), "the routine's branches and links are too many to follow: some transitions are imported without their steps");
    }
    // Selection priorities: left to right by X, ties by leg order; a user order is the legs'.
    let mut priority: HashMap<u64, usize> = HashMap::new();
    for (s, list) in &mut outgoing {
        if list.len() < 2 {
            continue;
        }
        let user = pred.get(list.first().map_or(&0, |t| &t.0)).into_iter().flatten().any(|p| match kinds.get(p) {
            Some((Kind::Leg(b), _)) => branches.get(*b).is_some_and(|br| br.user_priority),
            _ => false,
        });
        if user {
            list.sort_by_key(|t| t.2);
            if let Some((_, n)) = kinds.get(s) {
                cx.diag("SFC0720", anchor(*n), format!("the selection divergence below `{}` has user-defined priorities: read in the order of its legs", names_by_id.get(s).map_or("", String::as_str)))
                    .notes
                    .push("where Studio keeps a user order in L5X is not confirmed; the legs' order is the best reading".into());
            }
        } else {
            list.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.2.cmp(&b.2)).then(a.0.cmp(&b.0)));
        }
        for (i, t) in list.iter().enumerate() {
            priority.insert(t.0, i + 1);
        }
    }
    // Steps and stops.
    let mut actions_seen: HashMap<String, usize> = HashMap::new();
    for &(id, k, e) in &ordered {
        if !matches!(k, Kind::Step | Kind::Stop) {
            continue;
        }
        let name = cx.operand_name(e, "step");
        let up = name.text.to_ascii_uppercase();
        let initial = k == Kind::Step && attr(e, "InitialStep") == Some("true");
        let mut attrs = Vec::new();
        for (key, v) in [("sfc.x", attr(e, "X")), ("sfc.y", attr(e, "Y"))] {
            if let Some(v) = v.filter(|v| v.trim().parse::<f64>().is_ok_and(f64::is_finite)) {
                attrs.push((key.to_string(), v.trim().to_string()));
            }
        }
        attrs.push(("sfc.logix.attrs".into(), attrs_of(e)));
        if k == Kind::Stop {
            attrs.push(("sfc.logix.stop".into(), "true".into()));
            attrs.push(("sfc.final".into(), "true".into()));
        }
        if let Some(l) = tags.l5k.get(&up) {
            attrs.push(("sfc.logix.tag".into(), l.clone()));
        }
        if let Some(d) = tags.desc.get(&up) {
            attrs.push(("sfc.description".into(), d.clone()));
        }
        if let Some(p) = tags.pre.get(&up).filter(|p| **p != 0) {
            attrs.push(("sfc.logix.preset".into(), p.to_string()));
        }
        if k == Kind::Step && attr(e, "PresetUsesExpr") == Some("true") {
            let (x, _) = st_lines(child(e, "Preset").and_then(|p| child(p, "STContent")));
            attrs.push(("sfc.logix.preset_expr".into(), x.text.clone()));
            cx.diag("SFC0726", attr_range(e, "PresetUsesExpr").unwrap_or_else(|| anchor(e)), format!("the preset of `{}` is an expression: `.DN` compares the step's time with it in every scan", name.text))
                .notes
                .push("when Studio evaluates a preset expression is not confirmed; the expression is kept in `sfc.logix.preset_expr`".into());
        }
        for which in ["LimitHigh", "LimitLow"] {
            if attr(e, &format!("{which}UsesExpr")) == Some("true") {
                let (x, _) = st_lines(child(e, which).and_then(|p| child(p, "STContent")));
                attrs.push((format!("sfc.logix.{}", which.to_ascii_lowercase()), x.text.clone()));
            }
        }
        if k == Kind::Stop && succ.get(&id).is_some_and(|v| !v.is_empty()) {
            cx.diag(
                "SFC0725",
                anchor(e),
                format!("the stop `{}` has a link below it; a stop ends its path", name.text),
            );
        }
        let mut assoc = Vec::new();
        for a in children(e, "Action") {
            if let Some((f, act)) = action(cx, a, tags, &el, &mut actions_seen, &mut out) {
                assoc.push(f);
                if let Some(act) = act {
                    out.actions.push(act);
                }
            }
        }
        out.steps.push(StepOut { name, initial, anchor: anchor(e), attrs, assoc });
    }
    if !out.steps.iter().any(|s| s.initial) {
        cx.diag("SFC0725", anchor(content), "the chart has no initial step (`InitialStep=\"true\"`)");
    }
    // Transitions.
    for &(id, k, e) in &ordered {
        if k != Kind::Transition {
            continue;
        }
        let name = cx.operand_name(e, "transition");
        let (from, to) = trans_ends.remove(&id).unwrap_or_default();
        let names = |v: &[u64]| v.iter().filter_map(|i| names_by_id.get(i).cloned()).collect::<Vec<_>>();
        let (from, to) = (names(&from), names(&to));
        let mut attrs = Vec::new();
        for (key, v) in [("sfc.x", attr(e, "X")), ("sfc.y", attr(e, "Y"))] {
            if let Some(v) = v.filter(|v| v.trim().parse::<f64>().is_ok_and(f64::is_finite)) {
                attrs.push((key.to_string(), v.trim().to_string()));
            }
        }
        attrs.push(("sfc.logix.attrs".into(), attrs_of(e)));
        if let Some(d) = tags.desc.get(&name.text.to_ascii_uppercase()) {
            attrs.push(("sfc.description".into(), d.clone()));
        }
        if attr(e, "Force").is_some_and(|f| f != "NoForce") {
            cx.diag(
                "SFC0722",
                attr_range(e, "Force").unwrap_or_else(|| anchor(e)),
                "a forced transition is imported without its force",
            );
        }
        let content_node = child(e, "Condition").and_then(|c| child(c, "STContent"));
        let (x, numbers) = st_lines(content_node);
        let cond = condition(cx, e, &x, &el, &mut out);
        if numbers.len() > 1 || x.text.contains(';') {
            attrs.push(("sfc.logix.lines".into(), x.text.clone()));
        }
        if from.is_empty() || to.is_empty() {
            let side = if from.is_empty() { "no step above it" } else { "no step below it" };
            cx.diag(
                "SFC0725",
                anchor(e),
                format!("the transition `{}` has {side}: it is kept in `sfc.loose`, not in the chart", name.text),
            );
            let loose = sfc_syntax::attr_value::Loose {
                rect: None,
                from: from.clone(),
                to: to.clone(),
                name: name.text.clone(),
                condition: cond.text.clone(),
            };
            out.attrs.push((sfc_syntax::attr_value::LOOSE.into(), loose.write()));
            continue;
        }
        out.transitions.push(TransOut {
            name,
            priority: priority.get(&id).copied(),
            from,
            to,
            cond,
            anchor: anchor(e),
            attrs,
        });
    }
    out
}

/// A transition's condition: Logix lines as one expression (a trailing `;` dropped).
fn condition(cx: &mut Ctx, e: Node, x: &XText, el: &Elements, out: &mut ChartOut) -> Frag {
    let trimmed = x.trim();
    let mut body = trimmed.text.as_str();
    // The last `;` (outside comments: Studio accepts `f1;` and `f1; // done`).
    let toks = st::tokens(body);
    let last = toks.iter().rev().find(|t| !matches!(t.kind, st::Tok::Space | st::Tok::Comment));
    let cut = last.filter(|t| body.get(t.range.clone()) == Some(";")).map(|t| t.range.clone());
    let cond_x = match cut {
        Some(r) => {
            let mut c = trimmed.slice(0..r.start);
            let rest = trimmed.slice(r.end..body.len());
            c.push_str(" ");
            c.push(&rest);
            c
        }
        None => trimmed.clone(),
    };
    body = cond_x.text.as_str();
    let meaningful = st::tokens(body).iter().any(|t| !matches!(t.kind, st::Tok::Space | st::Tok::Comment));
    let at = child(e, "Condition").map(anchor).unwrap_or_else(|| anchor(e));
    if !meaningful {
        cx.diag("SFC0729", at, "the transition's condition is empty: imported as FALSE")
            .notes
            .push("Studio does not verify a chart with an empty condition".into());
        return Frag::located("FALSE", anchor(e));
    }
    let m: Mapped = st::map(&cond_x.trim(), el);
    if let Some(a) = m.assigns.first() {
        cx.diag(
            "SFC0729",
            a.clone(),
            "a transition's condition is a BOOL expression, not an assignment: imported as FALSE",
        )
        .notes
        .push("Studio's verification refuses this condition too".into());
        return Frag::located("FALSE", anchor(e));
    }
    cx.problems(&m.problems);
    out.idents.extend(m.idents);
    let mut f = m.frag;
    f.atomic = false;
    f
}

/// An action: its association line, and its declaration unless one with the same name was
/// written already.
fn action(
    cx: &mut Ctx,
    a: Node,
    tags: &SfcTags,
    el: &Elements,
    seen: &mut HashMap<String, usize>,
    out: &mut ChartOut,
) -> Option<(Frag, Option<ActionOut>)> {
    let name = cx.operand_name(a, "action");
    let up = name.text.to_ascii_uppercase();
    let q_raw = attr(a, "Qualifier").unwrap_or("NonStored");
    let (q, timed) = match qualifier(q_raw) {
        Some(q) => q,
        None => {
            cx.diag(
                "SFC0727",
                attr_range(a, "Qualifier").unwrap_or_else(|| anchor(a)),
                format!("the qualifier `{q_raw}` is not known: read as N (NonStored)"),
            );
            ("N", false)
        }
    };
    let boolean = attr(a, "IsBoolean") == Some("true");
    let expr = attr(a, "PresetUsesExpr") == Some("true");
    let mut attrs = vec![("sfc.logix.attrs".to_string(), attrs_of(a))];
    let mut line = Frag::default();
    line.push(&name);
    line.push_str(&format!("({q}"));
    if timed {
        let ms = if expr {
            let (x, _) = st_lines(child(a, "Preset").and_then(|p| child(p, "STContent")));
            attrs.push(("sfc.logix.preset_expr".into(), x.text.trim().to_string()));
            cx.diag("SFC0726", attr_range(a, "PresetUsesExpr").unwrap_or_else(|| anchor(a)), format!("the preset of the {q} action `{}` is an expression: its time is written T#0ms", name.text))
                .notes
                .push("an IEC association takes a duration literal or a TIME variable; the expression is kept in `sfc.logix.preset_expr` for the `logix` profile".into());
            0
        } else {
            match tags.pre.get(&up) {
                Some(p) => *p,
                None => {
                    cx.diag(
                        "SFC0721",
                        attr_range(a, "Operand").unwrap_or_else(|| anchor(a)),
                        format!(
                            "the {q} action `{}` has no SFC_ACTION tag in the file: its preset is taken as 0 ms",
                            name.text
                        ),
                    );
                    0
                }
            }
        };
        line.push_str(&format!(", T#{ms}ms"));
    }
    line.push_str(");");
    let line = line.locate(anchor(a));
    // The spelling an export writes back: Logix's P (two executions) and the short spellings.
    if q == "P" || q_raw.len() <= 2 {
        attrs.push(("sfc.logix.qualifier".into(), q_raw.to_string()));
    }
    if let Some(l) = tags.l5k.get(&up) {
        attrs.push(("sfc.logix.tag".into(), l.clone()));
    }
    if boolean {
        attrs.push(("sfc.logix.boolean".into(), "true".into()));
    }
    if let Some(d) = tags.desc.get(&up) {
        attrs.push(("sfc.description".into(), d.clone()));
    }
    if q == "R" && el.stored.contains(&up) {
        // IEC's reading: the Reset action names the stored action it resets.
        return Some((line, None));
    }
    if seen.contains_key(&up) {
        cx.diag(
            "SFC0727",
            attr_range(a, "Operand").unwrap_or_else(|| anchor(a)),
            format!(
                "a second action of the chart is `{}`: its body is written once, and this association runs it",
                name.text
            ),
        );
        return Some((line, None));
    }
    if q == "R" {
        cx.diag("SFC0720", attr_range(a, "Operand").unwrap_or_else(|| anchor(a)), format!("the Reset action `{}` names no other action of the chart: it resets only itself", name.text))
            .notes
            .push("in IEC 61131-3 an R association names the stored action it resets; how Studio names the target of a Reset action in L5X is not confirmed".into());
    }
    seen.insert(up.clone(), seen.len());
    if !out.names.insert(up) {
        cx.diag(
            "SFC0725",
            attr_range(a, "Operand").unwrap_or_else(|| anchor(a)),
            format!("`{}` names an action and another element of the chart", name.text),
        );
    }
    let mut body = Vec::new();
    if !boolean {
        let (x, numbers) = st_lines(child(a, "Body").and_then(|b| child(b, "STContent")));
        let m = st::map(&x, el);
        cx.problems(&m.problems);
        out.idents.extend(m.idents);
        if !m.nra_lines.is_empty() {
            let lines: Vec<String> =
                m.nra_lines.iter().map(|i| numbers.get(*i).cloned().unwrap_or_else(|| i.to_string())).collect();
            attrs.push(("sfc.logix.nra".into(), lines.join(",")));
        }
        // One line of text per line of the body; blank lines at the end dropped.
        let mut lines: Vec<Frag> = split_lines(&m.frag);
        while lines.last().is_some_and(|l| l.text.trim().is_empty()) {
            lines.pop();
        }
        body = lines;
    } else if child(a, "Body").is_some_and(|b| !text_of(b).text.trim().is_empty()) {
        cx.diag(
            "SFC0722",
            anchor(a),
            format!(
                "the Boolean action `{}` has a body: a Boolean action only sets its Q bit, the body is not imported",
                name.text
            ),
        );
    }
    Some((line, Some(ActionOut { name, anchor: anchor(a), attrs, body })))
}

/// Splits a fragment at its line breaks (each part keeps its marks).
fn split_lines(f: &Frag) -> Vec<Frag> {
    let mut out = Vec::new();
    let mut start = 0usize;
    let text = &f.text;
    let ends: Vec<usize> = text.match_indices('\n').map(|(i, _)| i).chain(std::iter::once(text.len())).collect();
    for end in ends {
        let mut part = Frag::plain(text.get(start..end).unwrap_or(""));
        for m in &f.marks {
            let (s, e) = (m.text.start as usize, m.text.end as usize);
            let (a, b) = (s.max(start), e.min(end));
            if a < b || (s == e && s >= start && s <= end) {
                let xml = if m.exact {
                    let off = (a - s) as u32;
                    m.xml.start + off..m.xml.start + off + (b - a) as u32
                } else {
                    m.xml.clone()
                };
                part.marks.push(sfc_xmlmap::MapEntry {
                    text: (a - start) as u32..(b - start) as u32,
                    xml,
                    exact: m.exact,
                });
            }
        }
        out.push(part);
        start = end + 1;
    }
    out
}
