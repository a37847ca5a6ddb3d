//! One GRAPH block as a `FUNCTION_BLOCK`: block properties as attributes, the interface, the
//! sequences (steps, transitions, branches, connections) as IEC steps and transitions, the
//! actions, interlocks, supervisions and permanent instructions.

use crate::flgnet;
use crate::interface;
use crate::operand::{tokens_to_st, Place};
use crate::{all_texts, Cx};
use roxmltree::Node;
use sfc_syntax::attr_value::escape;
use sfc_xmlmap::names::{is_ident, sanitize};
use sfc_xmlmap::xml::{anchor, attr_range, child, children, elements};
use sfc_xmlmap::{Emitter, Frag};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::ops::Range;

/// The value range of attribute `name` of `n`, or its start tag.
pub(crate) fn attr_or(n: Node, name: &str) -> Range<u32> {
    attr_range(n, name).unwrap_or_else(|| anchor(n))
}

/// Attributes of an element, written before it.
type Attrs = Vec<(String, String)>;

fn write_attrs(em: &mut Emitter, attrs: &Attrs, indent: &str) {
    for (k, v) in attrs {
        em.str(&format!("{indent}{{attribute '{k}' := '{}'}}\n", escape(v)));
    }
}

/// Block properties that matter for GRAPH's execution: (element, attribute, TIA's default).
const PROPERTIES: &[(&str, &str, &str)] = &[
    ("AcknowledgeErrorsRequired", "sfc.s7graph.ack_required", "true"),
    ("SkipSteps", "sfc.s7graph.skip_steps", "false"),
    ("LockOperatingMode", "sfc.s7graph.lock_mode", "false"),
    ("PermanentILProcessingInMANMode", "sfc.s7graph.il_in_man", "false"),
    ("WithAlarmHandling", "sfc.s7graph.alarms", "true"),
];

#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, PartialOrd, Ord)]
enum Pin {
    In(i64),
    Out(i64),
}

#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
enum Ref {
    Step(i64),
    Trans(i64),
    Branch(i64, Pin),
    End,
}

struct Conn {
    from: Ref,
    to: Ref,
    jump: bool,
    at: Range<u32>,
}

struct StepI<'a, 'i> {
    node: Node<'a, 'i>,
    number: i64,
    name: String,
    init: bool,
}

struct TransI<'a, 'i> {
    node: Node<'a, 'i>,
    number: i64,
    name: String,
}

/// What one transition joins, found by following the connections through branches.
#[derive(Default)]
struct Links {
    from: Vec<i64>,
    to: Vec<i64>,
    /// Sequence ends it leads to (each becomes a final step).
    ends: usize,
    jump: bool,
    /// The `Out` pin of the alternative divergence it hangs on (its place from the left).
    out: i64,
    /// The branch pins passed, for the export (`alt 1 out 0`).
    path: Vec<String>,
    /// Why it cannot be imported.
    problems: Vec<String>,
    ok: bool,
}

fn int_attr(n: Node, name: &str) -> Option<i64> {
    n.attribute(name).and_then(|v| v.trim().parse::<i64>().ok())
}

fn node_ref(cx: &mut Cx, n: Node) -> Option<Ref> {
    let e = elements(n).next()?;
    let r = match e.tag_name().name() {
        "StepRef" => Ref::Step(int_attr(e, "Number")?),
        "TransitionRef" => Ref::Trans(int_attr(e, "Number")?),
        "BranchRef" => {
            let b = int_attr(e, "Number")?;
            match (int_attr(e, "In"), int_attr(e, "Out")) {
                (Some(i), None) => Ref::Branch(b, Pin::In(i)),
                (None, Some(o)) => Ref::Branch(b, Pin::Out(o)),
                _ => {
                    cx.diag("SFC0748", anchor(e), "a branch reference needs exactly one of `In` and `Out`");
                    return None;
                }
            }
        }
        "EndConnection" => Ref::End,
        other => {
            cx.diag("SFC0748", anchor(e), format!("`{other}` is not a connection end"));
            return None;
        }
    };
    Some(r)
}

/// Writes the block; returns its emitter (text and map).
pub(crate) fn block(cx: &mut Cx, b: Node, engineering: Option<&str>) -> Emitter {
    let mut em = Emitter::new(anchor(b));
    let Some(al) = child(b, "AttributeList") else {
        cx.diag("SFC0740", anchor(b), "the block has no `AttributeList`");
        return em;
    };
    let text = |n: &str| child(al, n).and_then(|e| e.text()).map(|t| t.trim().to_string());
    let raw_name = text("Name").unwrap_or_default();
    let name_at = child(al, "Name").map(anchor).unwrap_or_else(|| anchor(b));
    let graph = b.descendants().find(|d| d.is_element() && d.tag_name().name() == "Graph");

    // Steps and transitions first: their names are taken before the variables'.
    let mut steps: Vec<StepI> = Vec::new();
    let mut trans: Vec<TransI> = Vec::new();
    let sequences: Vec<Node> = graph.map(|g| children(g, "Sequence").collect()).unwrap_or_default();
    let mut seen_steps = HashSet::new();
    let mut seen_trans = HashSet::new();
    for seq in &sequences {
        for s in child(*seq, "Steps").into_iter().flat_map(|s| children(s, "Step")) {
            let Some(number) = int_attr(s, "Number") else {
                cx.diag("SFC0748", anchor(s), "the step has no `Number`; it is not imported");
                continue;
            };
            if !seen_steps.insert(number) {
                cx.diag("SFC0748", anchor(s), format!("step number {number} is used twice; this step is not imported"));
                continue;
            }
            let raw = s.attribute("Name").unwrap_or("").to_string();
            let name = iec_name(cx, s, &raw, "step", &format!("S{number}"));
            cx.steps.insert(raw, name.clone());
            steps.push(StepI { node: s, number, name, init: sfc_xmlmap::xml::flag(s, "Init") });
        }
        for t in child(*seq, "Transitions").into_iter().flat_map(|s| children(s, "Transition")) {
            let Some(number) = int_attr(t, "Number") else {
                cx.diag("SFC0748", anchor(t), "the transition has no `Number`; it is not imported");
                continue;
            };
            if !seen_trans.insert(number) {
                cx.diag(
                    "SFC0748",
                    anchor(t),
                    format!("transition number {number} is used twice; this transition is not imported"),
                );
                continue;
            }
            let raw = t.attribute("Name").unwrap_or("").to_string();
            let name = iec_name(cx, t, &raw, "transition", &format!("T{number}"));
            cx.transitions.insert(raw, name.clone());
            trans.push(TransI { node: t, number, name });
        }
    }

    // The POU's attributes.
    let fb_base = if is_ident(&raw_name) {
        raw_name.clone()
    } else if raw_name.trim().is_empty() {
        format!("GRAPH_FB{}", text("Number").unwrap_or_default().trim())
    } else {
        sanitize(&raw_name)
    };
    let fb = fb_base.clone();
    cx.file_names.insert(fb.to_ascii_uppercase());
    let mut attrs: Attrs = vec![("sfc.dialect".into(), "graph".into())];
    if let Some(v) = text("GraphVersion") {
        attrs.push(("sfc.s7graph.version".into(), v));
    }
    if let Some(ns) = graph.and_then(|g| g.tag_name().namespace()) {
        let v = ns.rsplit('/').next().unwrap_or("");
        attrs.push(("sfc.s7graph.ns".into(), if v.starts_with('v') { v.to_string() } else { "v1".into() }));
    }
    if let Some(e) = engineering {
        attrs.push(("sfc.s7graph.tia".into(), e.to_string()));
    }
    if let Some(n) = text("Number") {
        attrs.push(("sfc.s7graph.number".into(), n));
    }
    if fb != raw_name {
        attrs.push(("sfc.s7graph.name".into(), raw_name.clone()));
        cx.diag("SFC0753", name_at.clone(), format!("the block name `{raw_name}` is imported as `{fb}`"));
    }
    let mut assumed = Vec::new();
    for (el, key, default) in PROPERTIES {
        match text(el) {
            Some(v) => attrs.push(((*key).into(), v.to_ascii_lowercase())),
            None => {
                attrs.push(((*key).into(), (*default).into()));
                assumed.push(format!("{el} = {default}"));
            }
        }
    }
    if let Some(l) = text("LanguageInNetworks") {
        attrs.push(("sfc.s7graph.language".into(), l));
    }
    if !assumed.is_empty() {
        cx.diag(
            "SFC0741",
            anchor(al),
            format!(
                "the export does not give the GRAPH block properties {}: TIA Portal's defaults are assumed",
                assumed.join(", ")
            ),
        )
        .notes
        .push("an export made with `ExportOptions.WithDefaults` writes them".into());
    }
    if let Some(c) = b
        .descendants()
        .find(|d| {
            d.is_element()
                && d.tag_name().name() == "MultilingualText"
                && d.attribute("CompositionName") == Some("Title")
        })
        .and_then(crate::first_text)
    {
        attrs.push(("sfc.s7graph.title".into(), c));
    }
    write_attrs(&mut em, &attrs, "");
    em.open(name_at.clone());
    em.str(&format!("FUNCTION_BLOCK {fb}\n"));
    em.close();

    // The interface.
    let sys = match child(al, "Interface") {
        Some(i) => interface::write(cx, i, &fb, &mut em, "    "),
        None => interface::System::default(),
    };
    compare_system(cx, &sys, &steps, &trans);
    // The globals the POU uses are declared VAR_EXTERNAL here, once they are known.
    let externals_at = em.out.len();

    let Some(graph) = graph else {
        cx.diag("SFC0740", anchor(b), "the GRAPH block has no `Graph` network source; no chart is imported");
        em.str("END_FUNCTION_BLOCK\n");
        return em;
    };
    if sequences.is_empty() {
        cx.diag("SFC0748", anchor(graph), "the graph has no `Sequence`");
    }

    let mut kept = Kept::default();
    let mut actions: Vec<(Frag, Attrs, String)> = Vec::new();

    // Topology, sequence by sequence (branch numbers are the sequence's own).
    let mut links: HashMap<i64, Links> = HashMap::new();
    for seq in &sequences {
        let mut branches: HashMap<i64, (String, Range<u32>)> = HashMap::new();
        for br in child(*seq, "Branches").into_iter().flat_map(|s| children(s, "Branch")) {
            if let Some(n) = int_attr(br, "Number") {
                branches.insert(n, (br.attribute("Type").unwrap_or("").to_string(), anchor(br)));
            }
        }
        let mut conns = Vec::new();
        for c in child(*seq, "Connections").into_iter().flat_map(|s| children(s, "Connection")) {
            let (Some(f), Some(t)) = (child(c, "NodeFrom"), child(c, "NodeTo")) else {
                cx.diag("SFC0748", anchor(c), "the connection needs `NodeFrom` and `NodeTo`");
                continue;
            };
            let (Some(from), Some(to)) = (node_ref(cx, f), node_ref(cx, t)) else { continue };
            let jump = child(c, "LinkType").and_then(|l| l.text()).is_some_and(|t| t.trim() == "Jump");
            conns.push(Conn { from, to, jump, at: anchor(c) });
        }
        check_refs(cx, &conns, &seen_steps, &seen_trans, &branches);
        for t in &trans {
            if !conns.iter().any(|c| c.from == Ref::Trans(t.number) || c.to == Ref::Trans(t.number)) {
                continue;
            }
            let l = topology(cx, t, &conns, &branches);
            links.insert(t.number, l);
        }
    }

    let step_name: HashMap<i64, String> = steps.iter().map(|s| (s.number, s.name.clone())).collect();
    let mut end_steps: Vec<(String, Range<u32>, String)> = Vec::new();
    // Priorities: the outgoing transitions of a step, leftmost (`Out` 0) first, then by number.
    let mut outgoing: BTreeMap<i64, Vec<(i64, i64)>> = BTreeMap::new();
    for t in &trans {
        if let Some(l) = links.get(&t.number).filter(|l| l.ok) {
            if let [s] = l.from.as_slice() {
                outgoing.entry(*s).or_default().push((l.out, t.number));
            }
        }
    }
    let mut priority: HashMap<i64, usize> = HashMap::new();
    for list in outgoing.values_mut() {
        list.sort();
        if list.len() > 1 {
            for (i, (_, n)) in list.iter().enumerate() {
                priority.insert(*n, i + 1);
            }
        }
    }

    // The transitions' conditions, for the steps' interlocks and supervisions that read a
    // transition's `TT` (their diagnostics come when the transitions are written).
    let before = cx.diags.len();
    for t in &trans {
        if let Some(Some(Some(c))) =
            child(t.node, "FlgNet").map(|f| flgnet::condition(cx, f, "TrCoil", Place::Transition))
        {
            cx.conditions.insert(t.name.to_ascii_uppercase(), c.text);
        }
    }
    cx.diags.truncate(before);

    // Steps.
    em.str("\n");
    for s in &steps {
        step(cx, &mut em, s, &mut kept, &mut actions);
    }

    // Transitions.
    for t in &trans {
        let Some(l) = links.get(&t.number) else {
            cx.diag(
                "SFC0748",
                anchor(t.node),
                format!("the transition `{}` is connected to nothing; it is not imported", t.name),
            );
            continue;
        };
        if !l.ok {
            continue;
        }
        let mut to: Vec<String> = l.to.iter().filter_map(|n| step_name.get(n).cloned()).collect();
        for _ in 0..l.ends {
            let end = cx.fresh(&format!("{}_End", t.name));
            cx.diag(
                "SFC0747",
                anchor(t.node),
                format!("the sequence ends after transition `{}`: imported as the final step `{end}`", t.name),
            )
            .notes
            .push("IEC text has no transition to nothing; the step is marked `sfc.s7graph.end` (written back as an EndConnection) and `sfc.final`".into());
            end_steps.push((end.clone(), anchor(t.node), t.name.clone()));
            to.push(end);
        }
        let from: Vec<String> = l.from.iter().filter_map(|n| step_name.get(n).cloned()).collect();
        let mut ta: Attrs = vec![("sfc.s7graph.number".into(), t.number.to_string())];
        let raw = t.node.attribute("Name").unwrap_or("");
        if raw != t.name {
            ta.push(("sfc.s7graph.name".into(), raw.to_string()));
        }
        if l.jump {
            ta.push(("sfc.s7graph.jump".into(), to.join(", ")));
        }
        if !l.path.is_empty() {
            ta.push(("sfc.s7graph.branch".into(), l.path.join("; ")));
        }
        if let Some(c) = child(t.node, "Comment").and_then(all_texts) {
            ta.push(("sfc.s7graph.comment".into(), c));
        }
        if let Some(c) = child(t.node, "TransitionName").and_then(all_texts) {
            ta.push(("sfc.s7graph.title".into(), c));
        }
        let lang = t.node.attribute("ProgrammingLanguage").unwrap_or("LAD");
        if lang != "LAD" {
            ta.push(("sfc.s7graph.language".into(), lang.to_string()));
        }
        let cond = match child(t.node, "FlgNet") {
            Some(f) => match flgnet::condition(cx, f, "TrCoil", Place::Transition) {
                Some(Some(c)) => c,
                Some(None) => Frag::located("TRUE", anchor(f)),
                None => Frag::located("FALSE", anchor(f)),
            },
            None if matches!(lang, "LAD" | "FBD") => {
                cx.diag(
                    "SFC0754",
                    anchor(t.node),
                    format!(
                        "the transition `{}` has no network: imported as TRUE, as GRAPH's empty transition",
                        t.name
                    ),
                );
                Frag::located("TRUE", anchor(t.node))
            }
            None => {
                cx.diag(
                    "SFC0743",
                    anchor(t.node),
                    format!(
                        "the transition `{}` is written in {lang}, which sfc does not read: imported as FALSE",
                        t.name
                    ),
                );
                Frag::located("FALSE", anchor(t.node))
            }
        };
        em.open(anchor(t.node));
        write_attrs(&mut em, &ta, "    ");
        let prio = priority.get(&t.number).map(|p| format!(" (PRIORITY := {p})")).unwrap_or_default();
        em.str(&format!("    TRANSITION {}{prio} FROM {} TO {}\n        := ", t.name, list(&from), list(&to)));
        em.frag(&cond);
        em.str(";\n    END_TRANSITION\n\n");
        em.close();
    }
    for (end, at, after) in &end_steps {
        em.open(at.clone());
        write_attrs(
            &mut em,
            &vec![("sfc.s7graph.end".into(), after.clone()), ("sfc.final".into(), "true".into())],
            "    ",
        );
        em.str(&format!("    STEP {end}: END_STEP\n\n"));
        em.close();
    }

    // Permanent instructions.
    for (el, which) in [("PreOperations", "pre"), ("PostOperations", "post")] {
        let Some(ops) = child(graph, el) else { continue };
        for (k, op) in children(ops, "PermanentOperation").enumerate() {
            let Some(flg) = child(op, "FlgNet") else { continue };
            let Some(stmts) = flgnet::statements(cx, flg, Place::Kept) else { continue };
            if stmts.is_empty() {
                continue;
            }
            let name = cx.fresh(&format!("{}_{}", which.to_ascii_uppercase(), k + 1));
            let mut body = Frag::default();
            for s in stmts {
                body.push_str("        ");
                body.push(&s);
                body.push_str("\n");
            }
            let mut a: Attrs = vec![("sfc.s7graph.permanent".into(), which.into())];
            if let Some(t) = child(op, "Title").and_then(all_texts) {
                a.push(("sfc.s7graph.title".into(), t));
            }
            kept.permanent += 1;
            actions.push((body.locate(anchor(op)), a, name));
        }
    }

    // Action bodies.
    for (body, a, name) in actions {
        em.open(body.marks.first().map(|m| m.xml.clone()).unwrap_or(0..0));
        write_attrs(&mut em, &a, "    ");
        em.str(&format!("    ACTION {name}:\n"));
        em.frag(&body);
        em.str("    END_ACTION\n\n");
        em.close();
    }
    em.str("END_FUNCTION_BLOCK\n");
    let mut ext = String::new();
    for i in cx.pou_globals.clone() {
        if let Some(g) = cx.globals.get(i) {
            ext.push_str(&format!("        {} : {};\n", g.name, g.ty));
        }
    }
    if !ext.is_empty() {
        em.insert(externals_at, &format!("    VAR_EXTERNAL\n{ext}    END_VAR\n"));
    }

    kept.report(cx, anchor(graph));
    em
}

/// `a` or `(a, b)`.
fn list(names: &[String]) -> String {
    match names {
        [one] => one.clone(),
        _ => format!("({})", names.join(", ")),
    }
}

/// The IEC name of a step or transition (`fallback` when the GRAPH name gives none).
fn iec_name(cx: &mut Cx, n: Node, raw: &str, what: &str, fallback: &str) -> String {
    let base = if is_ident(raw) {
        raw.to_string()
    } else if raw.trim().is_empty() {
        fallback.to_string()
    } else {
        sanitize(raw)
    };
    let name = cx.fresh(&base);
    if name != raw {
        cx.diag("SFC0753", attr_or(n, "Name"), format!("the {what} `{raw}` is imported as `{name}`")).notes.push(
            "GRAPH names may hold spaces and punctuation, IEC names may not; the original is kept in `sfc.s7graph.name`"
                .into(),
        );
    }
    name
}

/// Compares the system members' start values with the chart (they must agree; TIA writes
/// them from the steps and transitions).
fn compare_system(cx: &mut Cx, sys: &interface::System, steps: &[StepI], trans: &[TransI]) {
    for s in steps {
        let raw = s.node.attribute("Name").unwrap_or("");
        let Some((sno, tmax, twarn, at)) = sys.steps.get(raw) else { continue };
        let want = [
            ("SNO", sno, Some(s.number.to_string())),
            ("T_MAX", tmax, s.node.attribute("MaximumStepTime").map(str::to_string)),
            ("T_WARN", twarn, s.node.attribute("WarningTime").map(str::to_string)),
        ];
        for (m, have, want) in want {
            if let (Some(h), Some(w)) = (have, want) {
                if !h.eq_ignore_ascii_case(&w) {
                    cx.diag(
                        "SFC0749",
                        at.clone(),
                        format!("the step structure `{raw}` has {m} = {h}, but the step says {w}; the step's value is imported"),
                    );
                }
            }
        }
    }
    for t in trans {
        let raw = t.node.attribute("Name").unwrap_or("");
        if let Some((Some(tno), at)) = sys.transitions.get(raw) {
            if tno.trim() != t.number.to_string() {
                cx.diag(
                    "SFC0749",
                    at.clone(),
                    format!(
                        "the transition structure `{raw}` has TNO = {tno}, but the transition is number {}",
                        t.number
                    ),
                );
            }
        }
    }
    let names: HashSet<&str> = steps
        .iter()
        .map(|s| s.node.attribute("Name").unwrap_or(""))
        .chain(trans.iter().map(|t| t.node.attribute("Name").unwrap_or("")))
        .collect();
    for (n, (_, _, _, at)) in &sys.steps {
        if !names.contains(n.as_str()) {
            cx.diag(
                "SFC0749",
                at.clone(),
                format!("the step structure `{n}` belongs to no step of the graph; it is not imported"),
            );
        }
    }
    let numbers: HashSet<String> = trans.iter().map(|t| t.number.to_string()).collect();
    for (n, (tno, at)) in &sys.transitions {
        // TIA V14 writes some structures without the name's blanks: the number still tells.
        if !names.contains(n.as_str()) && !tno.as_ref().is_some_and(|t| numbers.contains(t.trim())) {
            cx.diag(
                "SFC0749",
                at.clone(),
                format!("the transition structure `{n}` belongs to no transition of the graph; it is not imported"),
            );
        }
    }
}

/// Connections naming steps, transitions or branches that do not exist.
fn check_refs(
    cx: &mut Cx,
    conns: &[Conn],
    steps: &HashSet<i64>,
    trans: &HashSet<i64>,
    branches: &HashMap<i64, (String, Range<u32>)>,
) {
    for c in conns {
        for r in [c.from, c.to] {
            let missing = match r {
                Ref::Step(n) => (!steps.contains(&n)).then(|| format!("step {n}")),
                Ref::Trans(n) => (!trans.contains(&n)).then(|| format!("transition {n}")),
                Ref::Branch(n, _) => (!branches.contains_key(&n)).then(|| format!("branch {n}")),
                Ref::End => None,
            };
            if let Some(m) = missing {
                cx.diag("SFC0748", c.at.clone(), format!("the connection names {m}, which the sequence does not have"));
            }
        }
    }
}

/// How deep branches may nest when following connections (bounds the work on any input).
const MAX_DEPTH: usize = 64;

/// The steps before and after transition `t`, through branches.
fn topology(cx: &mut Cx, t: &TransI, conns: &[Conn], branches: &HashMap<i64, (String, Range<u32>)>) -> Links {
    let mut l = Links { ok: true, ..Links::default() };
    let topo = Topo { conns, branches };
    let me = Ref::Trans(t.number);
    for c in conns.iter().filter(|c| c.to == me) {
        topo.back(c.from, &mut l, 0);
    }
    for c in conns.iter().filter(|c| c.from == me) {
        if c.jump {
            l.jump = true;
        }
        topo.fwd(c.to, &mut l, 0);
    }
    l.from.sort();
    l.from.dedup();
    l.to.sort();
    l.to.dedup();
    if l.from.is_empty() {
        l.problems.push("no step leads to it".to_string());
    }
    if l.to.is_empty() && l.ends == 0 {
        l.problems.push("it leads to no step".to_string());
    }
    if let Some(p) = l.problems.first().cloned() {
        l.ok = false;
        cx.diag("SFC0748", anchor(t.node), format!("the transition `{}` cannot be imported: {p}", t.name))
            .notes
            .push("GRAPH links a step to its transitions directly or through an alternative divergence (AltBegin) or a simultaneous convergence (SimEnd), and a transition to its steps directly, through an AltEnd or a SimBegin, or ends the sequence (EndConnection)".into());
    }
    l
}

/// The connections and branches of one sequence, followed from a transition.
struct Topo<'c> {
    conns: &'c [Conn],
    branches: &'c HashMap<i64, (String, Range<u32>)>,
}

impl Topo<'_> {
    fn kind(&self, b: i64) -> &str {
        self.branches.get(&b).map(|x| x.0.as_str()).unwrap_or("")
    }

    /// Whether the walk may go one branch deeper (else the problem is recorded).
    fn deeper(l: &mut Links, depth: usize) -> bool {
        if depth > MAX_DEPTH {
            l.problems.push("its branches nest too deep or form a cycle".into());
        }
        depth <= MAX_DEPTH
    }

    /// The steps before a transition, through AltBegin and SimEnd.
    fn back(&self, r: Ref, l: &mut Links, depth: usize) {
        if !Topo::deeper(l, depth) {
            return;
        }
        match r {
            Ref::Step(s) => l.from.push(s),
            Ref::Branch(b, Pin::Out(o)) => {
                match self.kind(b) {
                    "AltBegin" => {
                        if depth == 0 {
                            l.out = o;
                        }
                        l.path.push(format!("alt {b} out {o}"));
                    }
                    "SimEnd" => l.path.push(format!("simend {b}")),
                    other => {
                        l.problems.push(format!("it follows a branch of type `{other}` (branch {b})"));
                        return;
                    }
                }
                for c in self.conns.iter().filter(|c| matches!(c.to, Ref::Branch(x, Pin::In(_)) if x == b)) {
                    self.back(c.from, l, depth + 1);
                }
            }
            Ref::Trans(n) => l.problems.push(format!("it follows transition {n} directly")),
            Ref::End | Ref::Branch(_, Pin::In(_)) => l.problems.push("a connection into it starts at no step".into()),
        }
    }

    /// The steps after a transition, through AltEnd and SimBegin, and the sequence ends.
    fn fwd(&self, r: Ref, l: &mut Links, depth: usize) {
        if !Topo::deeper(l, depth) {
            return;
        }
        match r {
            Ref::Step(s) => l.to.push(s),
            Ref::End => l.ends += 1,
            Ref::Branch(b, Pin::In(i)) => {
                match self.kind(b) {
                    "AltEnd" => l.path.push(format!("altend {b} in {i}")),
                    "SimBegin" => l.path.push(format!("sim {b}")),
                    other => {
                        l.problems.push(format!("it leads into a branch of type `{other}` (branch {b})"));
                        return;
                    }
                }
                for c in self.conns.iter().filter(|c| matches!(c.from, Ref::Branch(x, Pin::Out(_)) if x == b)) {
                    if c.jump {
                        l.jump = true;
                    }
                    self.fwd(c.to, l, depth + 1);
                }
            }
            Ref::Trans(n) => l.problems.push(format!("it leads to transition {n} directly")),
            Ref::Branch(_, Pin::Out(_)) => l.problems.push("a connection from it ends at no step".into()),
        }
    }
}

/// What IEC simulation does not run, counted for the one warning of the file.
#[derive(Default)]
struct Kept {
    interlocks: usize,
    supervisions: usize,
    events: usize,
    c_flags: usize,
    permanent: usize,
    unsimulated: usize,
}

impl Kept {
    fn report(&self, cx: &mut Cx, at: Range<u32>) {
        let parts: Vec<String> = [
            (self.interlocks, "interlock(s)"),
            (self.supervisions, "supervision(s)"),
            (self.events, "action(s) bound to an event IEC has no counterpart for (V1 V0 L1 L0 A1 R1)"),
            (self.c_flags, "interlock-dependent (C) action(s)"),
            (self.permanent, "permanent pre/post instruction(s)"),
            (self.unsimulated, "action(s) whose GRAPH instruction IEC cannot execute (CALL, ON/OFF, timers)"),
        ]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, w)| format!("{n} {w}"))
        .collect();
        if parts.is_empty() {
            return;
        }
        cx.diag(
            "SFC0742",
            at,
            format!(
                "kept in `sfc.s7graph.*` attributes, which only the `graph` profile simulates: {}",
                parts.join(", ")
            ),
        )
        .notes
        .push(
            "the chart runs with the `graph` profile unless another is chosen: it simulates the interlocks, the \
             supervisions, the interlock-dependent actions, the actions bound to V1 V0 L1 L0 A1 and the permanent \
             instructions (docs/sim.md, \"The `graph` profile\"); R1 actions and GRAPH's CALL, ON/OFF and timer \
             instructions are kept and not run by any profile yet; under another profile (iec) none of them act"
                .into(),
        );
    }
}

/// A step's action associations and attributes, gathered before the step is written (the
/// association's GRAPH data goes into the step's attributes `sfc.s7graph.action<k>.*`, `k` its
/// row in the GRAPH action table: sfc text has no attributes on associations).
struct Assocs {
    lines: Vec<Frag>,
    attrs: Attrs,
    /// The associations that depend on the step's interlock (GRAPH's "C"), by action name.
    interlocked: Vec<String>,
}

impl Assocs {
    fn push(&mut self, k: usize, line: String, at: Range<u32>, assoc: &Attrs) {
        if assoc.iter().any(|(key, v)| key == "sfc.s7graph.interlock" && v == "true") {
            self.interlocked.push(line.split('(').next().unwrap_or("").trim().to_string());
        }
        for (key, v) in assoc {
            let short = key.trim_start_matches("sfc.s7graph.");
            self.attrs.push((format!("sfc.s7graph.action{k}.{short}"), v.clone()));
        }
        self.lines.push(Frag::located(line, at));
    }
}

/// Writes one step with its action associations; named actions go to `actions`.
fn step(cx: &mut Cx, em: &mut Emitter, s: &StepI, kept: &mut Kept, actions: &mut Vec<(Frag, Attrs, String)>) {
    let n = s.node;
    let mut a: Attrs = vec![("sfc.s7graph.number".into(), s.number.to_string())];
    let raw = n.attribute("Name").unwrap_or("");
    if raw != s.name {
        a.push(("sfc.s7graph.name".into(), raw.to_string()));
    }
    if let Some(v) = n.attribute("MaximumStepTime") {
        a.push(("sfc.s7graph.max_time".into(), v.to_string()));
    }
    if let Some(v) = n.attribute("WarningTime") {
        a.push(("sfc.s7graph.warn_time".into(), v.to_string()));
    }
    if let Some(c) = child(n, "Comment").and_then(all_texts) {
        a.push(("sfc.s7graph.comment".into(), c));
    }
    if let Some(c) = child(n, "StepName").and_then(all_texts) {
        a.push(("sfc.s7graph.title".into(), c));
    }
    if let Some(c) = child(n, "Actions").and_then(|x| child(x, "Title")).and_then(all_texts) {
        a.push(("sfc.s7graph.actions_title".into(), c));
    }
    for (outer, inner, coil, key) in [
        ("Interlocks", "Interlock", "IlCoil", "sfc.s7graph.interlock"),
        ("Supervisions", "Supervision", "SvCoil", "sfc.s7graph.supervision"),
    ] {
        let Some(net) = child(n, outer).and_then(|x| child(x, inner)) else { continue };
        let Some(flg) = child(net, "FlgNet") else {
            let lang = net.attribute("ProgrammingLanguage").unwrap_or("LAD");
            if !matches!(lang, "LAD" | "FBD") {
                cx.diag(
                    "SFC0743",
                    anchor(net),
                    format!(
                        "the {} is written in {lang}, which sfc does not read: it is not imported",
                        inner.to_ascii_lowercase()
                    ),
                );
            }
            continue;
        };
        if let Some(Some(f)) = flgnet::condition(cx, flg, coil, Place::Kept) {
            let (_, errs) = sfc_syntax::parse_expression(cx.file, &f.text);
            if errs.iter().any(|d| d.is_error()) {
                cx.diag(
                    "SFC0750",
                    anchor(net),
                    format!("the {} `{}` is not a valid ST expression", inner.to_ascii_lowercase(), f.text),
                );
            }
            if key.ends_with("interlock") {
                kept.interlocks += 1;
            } else {
                kept.supervisions += 1;
            }
            a.push((key.into(), f.text.clone()));
            if let Some(t) = child(net, "AlarmText").and_then(all_texts) {
                a.push((format!("{key}.alarm"), t));
            }
        }
    }
    let mut out = Assocs { lines: Vec::new(), attrs: a, interlocked: Vec::new() };
    let mut k = 0;
    for act in child(n, "Actions").into_iter().flat_map(|x| children(x, "Action")) {
        let Some(text) = action_text(cx, act) else { continue };
        k += 1;
        action(cx, &mut out, s, act, k, &text, kept, actions);
    }
    // The `graph` profile gates these associations with the step's interlock.
    if !out.interlocked.is_empty() {
        out.attrs.push(("sfc.s7graph.interlocked".into(), out.interlocked.join(", ")));
    }
    em.open(anchor(n));
    write_attrs(em, &out.attrs, "    ");
    let kw = if s.init { "INITIAL_STEP" } else { "STEP" };
    em.str(&format!("    {kw} {}:\n", s.name));
    for l in &out.lines {
        em.str("        ");
        em.frag(l);
        em.str("\n");
    }
    em.str("    END_STEP\n\n");
    em.close();
}

/// The text of an action's tokens (`None`: an empty action, the table's closing row).
fn action_text(cx: &mut Cx, act: Node) -> Option<String> {
    let mut t = String::new();
    for e in elements(act) {
        match e.tag_name().name() {
            "Token" => t.push_str(e.attribute("Text").unwrap_or("")),
            "Blank" => t.push_str(&" ".repeat(int_attr(e, "Num").unwrap_or(1).clamp(1, 64) as usize)),
            "NewLine" => t.push('\n'),
            "Access" => {
                if let Some(f) = crate::operand::access(cx, e, "BOOL", "BOOL from an action", Place::Kept) {
                    t.push_str(&f.text);
                }
            }
            _ => {}
        }
    }
    let trimmed = t.trim();
    (!trimmed.is_empty()).then(|| trimmed.to_string())
}

/// Splits `a , b` at its top-level comma.
fn split_comma(s: &str) -> Option<(&str, &str)> {
    let mut depth = 0i32;
    let mut quote = None;
    for (i, c) in s.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '(' | '[') => depth += 1,
            (None, ')' | ']') => depth -= 1,
            (None, ',') if depth == 0 => return Some((s.get(..i)?.trim(), s.get(i + 1..)?.trim())),
            _ => {}
        }
    }
    None
}

#[allow(clippy::too_many_arguments)]
fn action(
    cx: &mut Cx,
    em: &mut Assocs,
    s: &StepI,
    act: Node,
    k: usize,
    text: &str,
    kept: &mut Kept,
    actions: &mut Vec<(Frag, Attrs, String)>,
) {
    let at = anchor(act);
    let q = act.attribute("Qualifier").unwrap_or("").trim().to_ascii_uppercase();
    let q = if q.is_empty() { "N".to_string() } else { q };
    let event = act.attribute("Event").unwrap_or("").trim().to_ascii_uppercase();
    let c_flag = sfc_xmlmap::xml::flag(act, "Interlock");
    // The association's qualifier for the event, or None when IEC has no such event.
    let iec_event = match event.as_str() {
        "" => Some(None),
        "S1" => Some(Some("P1")),
        "S0" => Some(Some("P0")),
        _ => None,
    };
    let mut assoc: Attrs = Vec::new();
    if c_flag {
        assoc.push(("sfc.s7graph.interlock".into(), "true".into()));
        kept.c_flags += 1;
    }
    if !event.is_empty() {
        assoc.push(("sfc.s7graph.event".into(), event.clone()));
    }
    assoc.push(("sfc.s7graph.qualifier".into(), q.clone()));
    assoc.push(("sfc.s7graph.tokens".into(), text.to_string()));
    let lines: Vec<&str> = text.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
    let one_line = lines.len() == 1;
    let is_call = text.trim_start().to_ascii_uppercase().starts_with("CALL");

    // A plain operand: a Boolean action of IEC (N; D/L with a time), when no event binds it.
    let plain = |t: &str| !t.contains(":=") && !t.contains(',') && !t.contains(' ') && !t.contains('(');
    if iec_event == Some(None) && one_line && !is_call {
        let line = lines.first().copied().unwrap_or("");
        let timed = matches!(q.as_str(), "D" | "L");
        if (q == "N" && plain(line)) || (timed && split_comma(line).is_some_and(|(o, _)| plain(o))) {
            let (op, time) = if timed { split_comma(line).unwrap_or((line, "")) } else { (line, "") };
            let Ok(name) = tokens_to_st(cx, op, at.clone(), "BOOL", &format!("BOOL from a GRAPH {q} action")) else {
                cx.diag("SFC0746", at, format!("the action `{text}` cannot be read"));
                return;
            };
            if name.contains('.') || !is_ident(&name) {
                // A member (`#"Step".X`, `"DB".a` as a struct) is not an action name: use a body.
                named(cx, em, s, act, k, &q, None, &format!("{name} := TRUE;"), assoc, actions);
                return;
            }
            if timed {
                let Ok(t) =
                    tokens_to_st(cx, time, at.clone(), "TIME", &format!("TIME from the time of a GRAPH {q} action"))
                else {
                    cx.diag("SFC0746", at, format!("the time of action `{text}` cannot be read"));
                    return;
                };
                em.push(k, format!("{name}({q}, {t});"), at, &assoc);
            } else {
                em.push(k, format!("{name}(N);"), at, &assoc);
            }
            cx.action_names.insert(name);
            return;
        }
    }

    // Everything else is a named action with an ST body.
    let (body, iec) = match q.as_str() {
        "N" if is_call => {
            cx.diag(
                "SFC0745",
                at.clone(),
                format!(
                    "the block call `{text}` is kept but not executed: its instance and block are not in the export"
                ),
            );
            kept.unsimulated += 1;
            (format!("(* {} *)", comment_safe(text)), "N")
        }
        "N" | "S" | "R" => {
            let mut body = String::new();
            for line in &lines {
                let is_assign = line.contains(":=");
                let ty = if is_assign { assign_type(line) } else { "BOOL" };
                let st = match tokens_to_st(cx, line, at.clone(), ty, &format!("{ty} from a GRAPH action")) {
                    Ok(s) => s,
                    Err(e) => {
                        cx.diag("SFC0746", at, format!("the action `{text}` cannot be read: {e}"));
                        return;
                    }
                };
                let stmt = if is_assign {
                    format!("{};", st.trim_end_matches(';'))
                } else {
                    match q.as_str() {
                        "R" => format!("{st} := FALSE;"),
                        _ => format!("{st} := TRUE;"),
                    }
                };
                if !body.is_empty() {
                    body.push('\n');
                }
                body.push_str(&stmt);
            }
            if q != "N" && lines.iter().any(|l| l.contains(":=")) {
                cx.diag("SFC0745", at.clone(), format!("a GRAPH {q} action with an assignment is imported as the assignment, run while the step is active"));
            }
            (body, "N")
        }
        "D" | "L" => {
            cx.diag(
                "SFC0746",
                at.clone(),
                format!("the {q} action `{text}` needs an operand and a time (`operand , T#5S`) and no event"),
            );
            return;
        }
        "CU" | "CD" | "CR" | "CS" => {
            let (op, v) = split_comma(text).unwrap_or((text, "0"));
            let Ok(o) = tokens_to_st(cx, op, at.clone(), "INT", "INT from a GRAPH counter action") else {
                cx.diag("SFC0746", at, format!("the counter action `{text}` cannot be read"));
                return;
            };
            let v =
                tokens_to_st(cx, v, at.clone(), "INT", "INT from a counter's preset").unwrap_or_else(|_| "0".into());
            let body = match q.as_str() {
                "CU" => format!("{o} := {o} + 1;"),
                "CD" => format!("{o} := {o} - 1;"),
                "CR" => format!("{o} := 0;"),
                _ => format!("{o} := {v};"),
            };
            cx.diag(
                "SFC0745",
                at.clone(),
                format!("the GRAPH counter action {q} `{text}` is imported as `{body}` on an integer"),
            )
            .notes
            .push("GRAPH's counters are S7 counters (0 to 999, a status bit); the IEC text counts an INT".into());
            (body, "N")
        }
        "ON" | "OFF" | "TD" | "TF" | "TL" | "TR" => {
            let what = if q == "ON" || q == "OFF" { "activates or deactivates a step" } else { "runs a GRAPH timer" };
            cx.diag(
                "SFC0745",
                at.clone(),
                format!("the {q} action `{text}` {what}, which IEC actions cannot do: it is kept but not executed"),
            );
            kept.unsimulated += 1;
            (format!("(* {q} {} *)", comment_safe(text)), "N")
        }
        other => {
            cx.diag("SFC0746", at, format!("the action qualifier `{other}` is unknown; the action is not imported"));
            return;
        }
    };
    let (errs_ok, body) = (check_body(cx, &body), body);
    if !errs_ok {
        cx.diag("SFC0750", at.clone(), format!("the action `{text}` does not give valid ST: `{body}`"));
    }
    let qual = match iec_event {
        Some(None) => Some(iec),
        Some(Some(p)) => Some(p),
        None => {
            kept.events += 1;
            None
        }
    };
    named(cx, em, s, act, k, &q, qual, &body, assoc, actions);
}

fn comment_safe(t: &str) -> String {
    t.replace("*)", "* )").replace("(*", "( *")
}

fn check_body(cx: &Cx, body: &str) -> bool {
    let (_, errs) = sfc_syntax::parse_statements(cx.file, body);
    !errs.iter().any(|d| d.is_error())
}

/// The type an assignment's target has, from its value (`:= 1` INT, `:= TRUE` BOOL).
fn assign_type(line: &str) -> &'static str {
    let v = line.split(":=").nth(1).unwrap_or("").trim().trim_end_matches(';').trim();
    let up = v.to_ascii_uppercase();
    if up == "TRUE" || up == "FALSE" {
        "BOOL"
    } else if up.starts_with("T#") || up.starts_with("TIME#") {
        "TIME"
    } else if v.parse::<i64>().is_ok() {
        "INT"
    } else if v.parse::<f64>().is_ok() {
        "REAL"
    } else {
        "BOOL"
    }
}

/// A named action `<Step>_<Q><k>` with `body`, associated with `qual` (None: kept, not
/// associated, because IEC has no counterpart of its event).
#[allow(clippy::too_many_arguments)]
fn named(
    cx: &mut Cx,
    em: &mut Assocs,
    s: &StepI,
    act: Node,
    k: usize,
    q: &str,
    qual: Option<&str>,
    body: &str,
    assoc: Attrs,
    actions: &mut Vec<(Frag, Attrs, String)>,
) {
    let at = anchor(act);
    let name = cx.fresh(&format!("{}_{q}{k}", s.name));
    let mut b = Frag::default();
    for line in body.lines() {
        b.push_str(&format!("        {line}\n"));
    }
    match qual {
        Some(qual) => {
            em.push(k, format!("{name}({qual});"), at.clone(), &assoc);
            actions.push((b.locate(at), Vec::new(), name));
        }
        None => {
            let mut a = assoc;
            a.insert(0, ("sfc.s7graph.step".into(), s.name.clone()));
            actions.push((b.locate(at), a, name));
        }
    }
}
