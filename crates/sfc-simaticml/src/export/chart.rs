//! One chart as an `SW.Blocks.FB` whose network source is a GRAPH: block attributes, the
//! interface, the sequences (steps with their action rows, interlocks and supervisions;
//! transitions; branches; connections), the permanent instructions and the alarm settings.

use super::net::{Net, Operands, Src};
use super::xml::W;
use super::{attr, Out};
use sfc_diagnostics::Span;
use sfc_model::chart::{ActionTarget, Duration, Qualifier};
use sfc_model::{Chart, Checked};
use sfc_syntax::ast::{self, ActionBody, Condition, Expr, ExprKind, LiteralKind, StmtKind};
use std::collections::{BTreeMap, HashMap, HashSet};

/// Block properties: (element, attribute, default).
const PROPERTIES: &[(&str, &str, &str)] = &[
    ("AcknowledgeErrorsRequired", "sfc.s7graph.ack_required", "true"),
    ("SkipSteps", "sfc.s7graph.skip_steps", "false"),
    ("LockOperatingMode", "sfc.s7graph.lock_mode", "false"),
    ("PermanentILProcessingInMANMode", "sfc.s7graph.il_in_man", "false"),
    ("WithAlarmHandling", "sfc.s7graph.alarms", "true"),
];

/// One row of a step's action table.
#[derive(Clone)]
struct Row {
    qualifier: String,
    event: Option<String>,
    interlock: bool,
    tokens: String,
}

/// How a transition is reached from its steps.
#[derive(Clone)]
enum Back {
    Direct(usize),
    Alt { b: i64, out: i64, step: usize },
    SimEnd { b: i64, steps: Vec<usize> },
}

/// Where a transition leads.
#[derive(Clone)]
enum Fwd {
    Direct { step: usize, jump: bool },
    End,
    AltEnd { b: i64, inp: i64, step: usize },
    Sim { b: i64, steps: Vec<usize> },
}

fn number(attrs: &[ast::Attribute]) -> Option<i64> {
    attr(attrs, "sfc.s7graph.number").and_then(|n| n.trim().parse().ok())
}

/// Numbers from the attributes, the others numbered after the largest.
fn numbers(list: &[Option<i64>]) -> Vec<i64> {
    let mut next = list.iter().flatten().max().copied().unwrap_or(0);
    list.iter()
        .map(|n| {
            n.unwrap_or_else(|| {
                next += 1;
                next
            })
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn block(
    w: &mut W,
    out: &mut Out,
    checked: &Checked,
    p: &ast::Pou,
    chart: &Chart,
    ops: &Operands,
    fb_number: &str,
    id: &mut u32,
) {
    let pa = &p.attributes;
    out.source = sfc_model::RunRules::of(super::attr(pa, "sfc.dialect").as_deref(), chart);
    let graph = sfc_model::RunRules::of(Some("graph"), chart);
    if let Some(why) = sfc_model::RunRules::order_change(out.source, graph) {
        out.warn(chart.name_span, format!("the chart is written for S7-GRAPH, whose call differs from {}'s: {why}", out.source.name));
    }
    // The first call: S7-GRAPH switches no transition in it (as IEC's scan 0).
    if out.source.first_call_tests {
        for t in chart.transitions.iter().filter(|t| t.from.iter().all(|&s| chart.steps.get(s).is_some_and(|s| s.initial))) {
            let literal_false = matches!(&t.condition, ast::Condition::St(e) if matches!(&e.kind, ast::ExprKind::Literal(l) if matches!(l.kind, ast::LiteralKind::Bool(false))));
            if !literal_false {
                out.warn(
                    t.header_span,
                    format!(
                        "{} is tested in the first call under {}'s rules, not in S7-GRAPH's first call",
                        t.name, out.source.name
                    ),
                );
            }
        }
    }
    // A chart the import wrote numbers every step and transition; its topology and action rows
    // are in its attributes. Any other chart (also one written by hand in the graph dialect) is
    // laid out from its structure.
    let imported = chart.transitions.iter().any(|t| number(&t.attributes).is_some())
        || chart.steps.iter().any(|s| number(&s.attributes).is_some());
    if p.kind == ast::PouKind::Program {
        out.notes.push(sfc_diagnostics::Diagnostic::warning(
            "SFC0831",
            p.name.span,
            format!("the PROGRAM `{}` is written as a GRAPH function block (S7-GRAPH blocks are FBs): it runs when an instance of it is called", p.name.text),
        ));
    } else if p.kind != ast::PouKind::FunctionBlock {
        out.error(p.name.span, "only a PROGRAM or FUNCTION_BLOCK chart can be written as an S7-GRAPH block");
    }
    let gv = attr(pa, "sfc.s7graph.version").unwrap_or_else(|| "6.0".into());
    let ns = attr(pa, "sfc.s7graph.ns").unwrap_or_else(|| "v5".into());
    let name = attr(pa, "sfc.s7graph.name").unwrap_or_else(|| p.name.text.clone());

    // Steps: the sequence ends the import made (`sfc.s7graph.end`) are EndConnections.
    let end: Vec<bool> = chart.steps.iter().map(|s| attr(&s.attributes, "sfc.s7graph.end").is_some()).collect();
    let step_no = numbers(&chart.steps.iter().map(|s| number(&s.attributes)).collect::<Vec<_>>());
    let trans_no = numbers(&chart.transitions.iter().map(|t| number(&t.attributes)).collect::<Vec<_>>());
    let raw_step = |i: usize| {
        chart
            .steps
            .get(i)
            .map(|s| attr(&s.attributes, "sfc.s7graph.name").unwrap_or_else(|| s.name.clone()))
            .unwrap_or_default()
    };
    let raw_trans = |i: usize| {
        chart
            .transitions
            .get(i)
            .map(|t| attr(&t.attributes, "sfc.s7graph.name").unwrap_or_else(|| t.name.clone()))
            .unwrap_or_default()
    };

    // A BOOL variable held by N (or D, L) in one step and set or reset in another: IEC combines
    // the associations into one action control, GRAPH runs each row on its own.
    let mut quals: HashMap<String, (bool, bool)> = HashMap::new();
    for s in &chart.steps {
        for a in s.associations.iter().filter(|a| a.target == ActionTarget::Variable) {
            let e = quals.entry(a.action.to_ascii_uppercase()).or_default();
            match a.qualifier {
                Qualifier::S | Qualifier::R => e.1 = true,
                _ => e.0 = true,
            }
        }
    }
    for s in &chart.steps {
        for a in s.associations.iter().filter(|a| a.target == ActionTarget::Variable) {
            if quals.get(&a.action.to_ascii_uppercase()) == Some(&(true, true))
                && matches!(a.qualifier, Qualifier::S | Qualifier::R)
            {
                out.warn(
                    a.span,
                    format!(
                        "`{}` is held by N in one step and {} here: IEC keeps one action control for it, S7-GRAPH runs each row on its own (an N row resets it when its step is left, whatever this row set)",
                        a.action,
                        if a.qualifier == Qualifier::S { "set by S" } else { "reset by R" }
                    ),
                );
            }
        }
        if let Some(t) = s.min_time {
            let _ = t;
            out.error(s.name_span, "a step's minimum time (sfc.min_time) has no counterpart in S7-GRAPH; write it into the following transitions (`S.T >= t`)");
        }
        if !s.step_actions.is_empty() {
            out.error(s.name_span, "step actions (ENTRY_ACTION, …) cannot be written in an S7-GRAPH step");
        }
    }

    // Topology.
    let (back, fwd) = if imported { topology_kept(out, chart, &end) } else { topology_iec(out, chart) };

    // Sequences: the steps joined by transitions, in the order of their first step.
    let n = chart.steps.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while let Some(&q) = p.get(r) {
            if q == r {
                break;
            }
            r = q;
        }
        if let Some(v) = p.get_mut(x) {
            *v = r;
        }
        r
    }
    for t in &chart.transitions {
        for &a in t.from.iter().chain(t.to.iter()) {
            if let Some(&b) = t.from.first() {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    if let Some(v) = parent.get_mut(ra) {
                        *v = rb;
                    }
                }
            }
        }
    }
    let mut seq_of_root: Vec<usize> = Vec::new();
    let mut step_seq = vec![0usize; n];
    for i in 0..n {
        let r = find(&mut parent, i);
        if end.get(i).copied().unwrap_or(false) {
            continue;
        }
        let k = match seq_of_root.iter().position(|&x| x == r) {
            Some(k) => k,
            None => {
                seq_of_root.push(r);
                seq_of_root.len() - 1
            }
        };
        if let Some(v) = step_seq.get_mut(i) {
            *v = k;
        }
    }

    // Interface data of the system members.
    let sys_steps: Vec<(String, i64, Option<String>, Option<String>)> = chart
        .steps
        .iter()
        .enumerate()
        .filter(|(i, _)| !end.get(*i).copied().unwrap_or(false))
        .map(|(i, s)| {
            (
                raw_step(i),
                step_no.get(i).copied().unwrap_or(0),
                attr(&s.attributes, "sfc.s7graph.max_time"),
                attr(&s.attributes, "sfc.s7graph.warn_time"),
            )
        })
        .collect();
    let sys_trans: Vec<(String, i64)> =
        (0..chart.transitions.len()).map(|i| (raw_trans(i), trans_no.get(i).copied().unwrap_or(0))).collect();

    w.open("SW.Blocks.FB", &[("ID", id.to_string())]);
    *id += 1;
    w.open("AttributeList", &[]);
    let props: Vec<(&str, String)> =
        PROPERTIES.iter().map(|(el, key, def)| (*el, attr(pa, key).unwrap_or_else(|| (*def).into()))).collect();
    let prop = |el: &str| props.iter().find(|(e, _)| *e == el).map(|(_, v)| v.clone()).unwrap_or_default();
    w.leaf("AcknowledgeErrorsRequired", &[], &prop("AcknowledgeErrorsRequired"));
    w.leaf("GraphVersion", &[], &gv);
    super::interface(w, out, checked, p, &ns, &gv, &sys_steps, &sys_trans);
    if let Some(l) = attr(pa, "sfc.s7graph.language") {
        w.leaf("LanguageInNetworks", &[], &l);
    }
    w.leaf("LockOperatingMode", &[], &prop("LockOperatingMode"));
    w.leaf("Name", &[], &name);
    w.leaf("Number", &[], fb_number);
    w.leaf("PermanentILProcessingInMANMode", &[], &prop("PermanentILProcessingInMANMode"));
    w.leaf("ProgrammingLanguage", &[], "GRAPH");
    w.leaf("SkipSteps", &[], &prop("SkipSteps"));
    w.leaf("WithAlarmHandling", &[], &prop("WithAlarmHandling"));
    w.close("AttributeList");
    w.open("ObjectList", &[]);
    w.open("SW.Blocks.CompileUnit", &[("ID", id.to_string()), ("CompositionName", "CompileUnits".into())]);
    *id += 1;
    w.open("AttributeList", &[]);
    w.open("NetworkSource", &[]);
    w.open("Graph", &[("xmlns", format!("http://www.siemens.com/automation/Openness/SW/NetworkSource/Graph/{ns}"))]);

    permanent(w, out, chart, ops, "pre");

    // Event actions the import kept unassociated, by step.
    let mut events: HashMap<String, Vec<Row>> = HashMap::new();
    let mut event_at: HashMap<String, Span> = HashMap::new();
    for a in &chart.actions {
        if let Some(s) = attr(&a.attributes, "sfc.s7graph.step") {
            // Written by hand (no tokens kept): the body's assignments are the row.
            let tokens = match attr(&a.attributes, "sfc.s7graph.tokens") {
                Some(t) => t,
                None => match assignments(ops, &a.body) {
                    Ok(t) => t,
                    Err(m) => {
                        out.error(
                            a.name_span,
                            format!("the event action `{}` cannot be written as a GRAPH action row: {m}", a.name),
                        );
                        continue;
                    }
                },
            };
            event_at.entry(s.to_ascii_uppercase()).or_insert(a.name_span);
            events.entry(s.to_ascii_uppercase()).or_default().push(Row {
                qualifier: attr(&a.attributes, "sfc.s7graph.qualifier").unwrap_or_else(|| "N".into()),
                event: attr(&a.attributes, "sfc.s7graph.event"),
                interlock: attr(&a.attributes, "sfc.s7graph.interlock").as_deref() == Some("true"),
                tokens,
            });
        }
    }

    for (k, _) in seq_of_root.iter().enumerate() {
        w.open("Sequence", &[]);
        w.open("Steps", &[]);
        for (i, s) in chart.steps.iter().enumerate() {
            if end.get(i).copied().unwrap_or(false) || step_seq.get(i) != Some(&k) {
                continue;
            }
            let mut a = vec![
                ("Number", step_no.get(i).copied().unwrap_or(0).to_string()),
                ("Init", s.initial.to_string()),
                ("Name", raw_step(i)),
            ];
            if let Some(t) = attr(&s.attributes, "sfc.s7graph.max_time") {
                a.push(("MaximumStepTime", t));
            }
            if let Some(t) = attr(&s.attributes, "sfc.s7graph.warn_time") {
                a.push(("WarningTime", t));
            }
            w.open("Step", &a);
            if let Some(t) = attr(&s.attributes, "sfc.s7graph.title") {
                w.texts("StepName", &t);
            }
            if let Some(t) = attr(&s.attributes, "sfc.s7graph.comment") {
                w.texts("Comment", &t);
            }
            w.open("Actions", &[]);
            if let Some(t) = attr(&s.attributes, "sfc.s7graph.actions_title") {
                w.texts("Title", &t);
            }
            let kept = s.attributes.iter().any(|a| a.name.starts_with("sfc.s7graph.action"));
            let step_events = events.remove(&s.name.to_ascii_uppercase()).unwrap_or_default();
            let rows = if kept {
                let rows = kept_rows(s, step_events);
                // The kept rows are the step's associations only if nobody changed them since.
                let associated = rows.iter().filter(|r| matches!(r.event.as_deref(), None | Some("S1" | "S0"))).count();
                if associated != s.associations.len() {
                    out.error(
                        s.name_span,
                        format!(
                            "the step `{}` has {} association(s) but its kept GRAPH action rows (sfc.s7graph.action<k>.*) give {associated}: remove those attributes to write the associations anew",
                            s.name,
                            s.associations.len()
                        ),
                    );
                }
                rows
            } else {
                let mut rows = iec_rows(out, chart, s, ops);
                rows.extend(step_events);
                rows
            };
            for r in rows {
                let mut a = Vec::new();
                if let Some(e) = &r.event {
                    a.push(("Event", e.clone()));
                }
                if r.interlock {
                    a.push(("Interlock", "true".to_string()));
                }
                a.push(("Qualifier", r.qualifier.clone()));
                w.open("Action", &a);
                for t in tokens(&r.tokens) {
                    w.empty("Token", &[("Text", t)]);
                }
                w.empty("Token", &[("Text", "\n".into())]);
                w.close("Action");
            }
            w.empty("Action", &[]);
            w.close("Actions");
            for (outer, inner, coil, key) in [
                ("Supervisions", "Supervision", "SvCoil", "sfc.s7graph.supervision"),
                ("Interlocks", "Interlock", "IlCoil", "sfc.s7graph.interlock"),
            ] {
                w.open(outer, &[]);
                w.open(inner, &[("ProgrammingLanguage", "LAD".into())]);
                let cond = attr(&s.attributes, key);
                let mut net = Net::new(ops);
                net.kept = true;
                let src = match &cond {
                    Some(c) => {
                        let (e, errs) = sfc_syntax::parse_expression(s.name_span.file, c);
                        if errs.iter().any(|d| d.is_error()) {
                            out.error(
                                s.name_span,
                                format!("the {} `{c}` is not an ST expression", inner.to_ascii_lowercase()),
                            );
                            Src::Rail
                        } else {
                            net.chain(&e, Src::Rail).unwrap_or_else(|m| {
                                out.error(
                                    s.name_span,
                                    format!("the {} of step `{}`: {m}", inner.to_ascii_lowercase(), s.name),
                                );
                                Src::Rail
                            })
                        }
                    }
                    None => Src::Rail,
                };
                net.coil(coil, src);
                net.write(w);
                if let Some(t) = attr(&s.attributes, &format!("{key}.alarm")) {
                    w.texts("AlarmText", &t);
                }
                w.close(inner);
                w.close(outer);
            }
            w.close("Step");
        }
        w.close("Steps");

        // Transitions of this sequence (by their first step).
        let in_seq = |t: &sfc_model::chart::TransitionNode| {
            t.from.first().is_some_and(|&f| step_seq.get(f) == Some(&k) && !end.get(f).copied().unwrap_or(false))
        };
        w.open("Transitions", &[]);
        for (i, t) in chart.transitions.iter().enumerate() {
            if !in_seq(t) {
                continue;
            }
            let lang = attr(&t.attributes, "sfc.s7graph.language").unwrap_or_else(|| "LAD".into());
            w.open(
                "Transition",
                &[
                    ("IsMissing", "false".into()),
                    ("Name", raw_trans(i)),
                    ("Number", trans_no.get(i).copied().unwrap_or(0).to_string()),
                    ("ProgrammingLanguage", lang),
                ],
            );
            if let Some(c) = attr(&t.attributes, "sfc.s7graph.title") {
                w.texts("TransitionName", &c);
            }
            if let Some(c) = attr(&t.attributes, "sfc.s7graph.comment") {
                w.texts("Comment", &c);
            }
            let mut net = Net::new(ops);
            let src = match &t.condition {
                Condition::St(e) => net.chain(e, Src::Rail).unwrap_or_else(|m| {
                    out.error(t.header_span, format!("the condition of transition `{}`: {m}", t.name));
                    Src::Rail
                }),
                _ => {
                    out.error(t.header_span, "a condition in IL cannot be written as a GRAPH transition");
                    Src::Rail
                }
            };
            net.coil("TrCoil", src);
            net.write(w);
            w.close("Transition");
        }
        w.close("Transitions");

        // Branches and connections.
        let mut branches: BTreeMap<i64, (&str, i64)> = BTreeMap::new();
        let mut conns: Vec<(String, String, bool)> = Vec::new();
        let mut seen = HashSet::new();
        let sref = |i: usize| format!("<StepRef Number=\"{}\" />", step_no.get(i).copied().unwrap_or(0));
        let bref = |b: i64, pin: &str, x: i64| format!("<BranchRef Number=\"{b}\" {pin}=\"{x}\" />");
        let mut add = |from: String, to: String, jump: bool| {
            if seen.insert((from.clone(), to.clone())) {
                conns.push((from, to, jump));
            }
        };
        let card = |m: &mut BTreeMap<i64, (&'static str, i64)>, b: i64, kind: &'static str, pins: i64| {
            let e = m.entry(b).or_insert((kind, 0));
            e.1 = e.1.max(pins);
        };
        for (i, t) in chart.transitions.iter().enumerate() {
            if !in_seq(t) {
                continue;
            }
            let tref = format!("<TransitionRef Number=\"{}\" />", trans_no.get(i).copied().unwrap_or(0));
            match back.get(i) {
                Some(Back::Direct(s)) => add(sref(*s), tref.clone(), false),
                Some(Back::Alt { b, out: o, step }) => {
                    card(&mut branches, *b, "AltBegin", o + 1);
                    add(sref(*step), bref(*b, "In", 0), false);
                    add(bref(*b, "Out", *o), tref.clone(), false);
                }
                Some(Back::SimEnd { b, steps }) => {
                    card(&mut branches, *b, "SimEnd", steps.len() as i64);
                    for (k, s) in steps.iter().enumerate() {
                        add(sref(*s), bref(*b, "In", k as i64), false);
                    }
                    add(bref(*b, "Out", 0), tref.clone(), false);
                }
                None => {}
            }
            match fwd.get(i) {
                Some(Fwd::Direct { step, jump }) => add(tref.clone(), sref(*step), *jump),
                Some(Fwd::End) => add(tref.clone(), "<EndConnection />".into(), false),
                Some(Fwd::AltEnd { b, inp, step }) => {
                    card(&mut branches, *b, "AltEnd", inp + 1);
                    add(tref.clone(), bref(*b, "In", *inp), false);
                    add(bref(*b, "Out", 0), sref(*step), false);
                }
                Some(Fwd::Sim { b, steps }) => {
                    card(&mut branches, *b, "SimBegin", steps.len() as i64);
                    add(tref.clone(), bref(*b, "In", 0), false);
                    for (k, s) in steps.iter().enumerate() {
                        add(bref(*b, "Out", k as i64), sref(*s), false);
                    }
                }
                None => {}
            }
        }
        if branches.is_empty() {
            w.empty("Branches", &[]);
        } else {
            w.open("Branches", &[]);
            for (b, (kind, c)) in &branches {
                w.empty(
                    "Branch",
                    &[("Number", b.to_string()), ("Type", (*kind).into()), ("Cardinality", c.to_string())],
                );
            }
            w.close("Branches");
        }
        w.open("Connections", &[]);
        for (from, to, jump) in conns {
            w.open("Connection", &[]);
            w.raw(&format!("<NodeFrom>{from}</NodeFrom>"));
            w.raw(&format!("<NodeTo>{to}</NodeTo>"));
            w.leaf("LinkType", &[], if jump { "Jump" } else { "Direct" });
            w.close("Connection");
        }
        w.close("Connections");
        w.close("Sequence");
    }

    for (step, _) in events {
        let at = event_at.get(&step).copied().unwrap_or(chart.name_span);
        out.error(at, format!("the event action's step `{step}` (sfc.s7graph.step) is no step of the chart"));
    }
    permanent(w, out, chart, ops, "post");
    w.open("AlarmsSettings", &[]);
    w.open("AlarmSupervisionCategories", &[]);
    for i in 1..=8 {
        w.empty("AlarmSupervisionCategory", &[("Id", i.to_string()), ("DisplayClass", "0".into())]);
    }
    w.close("AlarmSupervisionCategories");
    w.empty("AlarmInterlockCategory", &[("Id", "1".into())]);
    w.empty("AlarmWarningCategory", &[("Id", "2".into())]);
    w.close("AlarmsSettings");
    w.close("Graph");
    w.close("NetworkSource");
    w.leaf("ProgrammingLanguage", &[], "GRAPH");
    w.close("AttributeList");
    w.close("SW.Blocks.CompileUnit");
    if let Some(t) = attr(pa, "sfc.s7graph.title") {
        w.open("MultilingualText", &[("ID", id.to_string()), ("CompositionName", "Title".into())]);
        *id += 1;
        w.open("ObjectList", &[]);
        w.open("MultilingualTextItem", &[("ID", id.to_string()), ("CompositionName", "Items".into())]);
        *id += 1;
        w.open("AttributeList", &[]);
        w.leaf("Culture", &[], "en-US");
        w.leaf("Text", &[], &t);
        w.close("AttributeList");
        w.close("MultilingualTextItem");
        w.close("ObjectList");
        w.close("MultilingualText");
    }
    w.close("ObjectList");
    w.close("SW.Blocks.FB");
}

/// Tokens as TIA writes them: each run of non-blank characters, each run of blanks, each line
/// break (the caller ends the row with one).
fn tokens(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    let mut blank = false;
    for c in text.chars() {
        if c == '\n' {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            out.push("\n".into());
            continue;
        }
        let b = c == ' ' || c == '\t';
        if !cur.is_empty() && b != blank {
            out.push(std::mem::take(&mut cur));
        }
        blank = b;
        cur.push(c);
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// A step's rows from the import's attributes (`sfc.s7graph.action<k>.*`), the event actions
/// the import kept unassociated filling the rows between.
fn kept_rows(s: &sfc_model::chart::StepNode, events: Vec<Row>) -> Vec<Row> {
    let mut rows: BTreeMap<usize, Row> = BTreeMap::new();
    for a in &s.attributes {
        let Some(rest) = a.name.strip_prefix("sfc.s7graph.action") else { continue };
        let Some((k, field)) = rest.split_once('.') else { continue };
        let Ok(k) = k.parse::<usize>() else { continue };
        let v = sfc_syntax::attr_value::unescape(a.value.as_deref().unwrap_or(""));
        let r = rows.entry(k).or_insert(Row {
            qualifier: "N".into(),
            event: None,
            interlock: false,
            tokens: String::new(),
        });
        match field {
            "qualifier" => r.qualifier = v,
            "event" => r.event = Some(v),
            "interlock" => r.interlock = v == "true",
            "tokens" => r.tokens = v,
            _ => {}
        }
    }
    let mut events = events.into_iter();
    let mut out = Vec::new();
    let last = rows.keys().max().copied().unwrap_or(0);
    for k in 1..=last {
        match rows.remove(&k) {
            Some(r) => out.push(r),
            None => {
                if let Some(e) = events.next() {
                    out.push(e);
                }
            }
        }
    }
    out.extend(events);
    out
}

/// `T#2S` for a duration in microseconds.
fn time_literal(us: i64) -> String {
    if us % 1_000_000 == 0 {
        format!("T#{}S", us / 1_000_000)
    } else {
        format!("T#{}MS", us / 1000)
    }
}

/// GRAPH's spelling of an operand of the POU: `#x` for a variable, `"DB".x` for a global.
fn operand_text(ops: &Operands, name: &str) -> String {
    let up = name.to_ascii_uppercase();
    if let Some((origin, _)) = ops.globals.get(&up) {
        return origin.clone();
    }
    if let Some(raw) = ops.steps.get(&up) {
        return format!("#\"{raw}\"");
    }
    format!("#{name}")
}

/// An expression with GRAPH's operand syntax (`#x`, `"DB".a`, `#"Step".T`).
fn graph_expr(ops: &Operands, e: &Expr) -> String {
    let text = sfc_syntax::print::expr(e);
    let mut out = String::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while let Some(&c) = chars.get(i) {
        if c == '\'' || c == '"' {
            let start = i;
            i += 1;
            while chars.get(i).is_some_and(|&x| x != c) {
                i += 1;
            }
            i += 1;
            out.extend(chars.get(start..i.min(chars.len())).unwrap_or_default());
            continue;
        }
        if c.is_alphabetic() || c == '_' {
            let start = i;
            while chars.get(i).is_some_and(|x| x.is_alphanumeric() || *x == '_') {
                i += 1;
            }
            let word: String = chars.get(start..i).unwrap_or_default().iter().collect();
            let prev = start.checked_sub(1).and_then(|p| chars.get(p)).copied();
            let typed = chars.get(i) == Some(&'#');
            if prev != Some('.')
                && !typed
                && (ops.vars.contains_key(&word.to_ascii_uppercase())
                    || ops.globals.contains_key(&word.to_ascii_uppercase())
                    || ops.steps.contains_key(&word.to_ascii_uppercase()))
            {
                out.push_str(&operand_text(ops, &word));
            } else {
                out.push_str(&word);
                if typed {
                    // A typed literal: copy it to its end.
                    while chars.get(i).is_some_and(|x| x.is_alphanumeric() || matches!(*x, '#' | '_' | '.' | ':' | '-'))
                    {
                        out.push(chars.get(i).copied().unwrap_or(' '));
                        i += 1;
                    }
                }
            }
            continue;
        }
        out.push(c);
        i += 1;
    }
    out
}

/// Whether every name `e` reads is one GRAPH can write in an action row (a variable of the
/// block, a global, a step); calls and other forms are refused.
fn names(ops: &Operands, e: &Expr) -> Result<(), String> {
    match &e.kind {
        ExprKind::Literal(_) => Ok(()),
        ExprKind::Name(id) => {
            let up = id.text.to_ascii_uppercase();
            if ops.vars.contains_key(&up) || ops.globals.contains_key(&up) || ops.steps.contains_key(&up) {
                Ok(())
            } else {
                Err(format!("`{}` is no variable of the block", id.text))
            }
        }
        ExprKind::Member { base, .. } => names(ops, base),
        ExprKind::Index { base, indices } => {
            names(ops, base)?;
            indices.iter().try_for_each(|i| names(ops, i))
        }
        ExprKind::Unary { operand, .. } | ExprKind::Paren(operand) => names(ops, operand),
        ExprKind::Binary { lhs, rhs, .. } => {
            names(ops, lhs)?;
            names(ops, rhs)
        }
        _ => Err(format!("`{}` cannot be written in a GRAPH action row", sfc_syntax::print::expr(e))),
    }
}

/// A named action's body as GRAPH assignment lines, or why it cannot be one.
fn assignments(ops: &Operands, body: &ActionBody) -> Result<String, String> {
    let ActionBody::St(stmts) = body else {
        return Err("its body is not ST".into());
    };
    let mut lines = Vec::new();
    for s in stmts {
        match &s.kind {
            StmtKind::Assign { target, value } => {
                names(ops, target)?;
                names(ops, value)?;
                lines.push(format!("{} := {}", graph_expr(ops, target), graph_expr(ops, value)))
            }
            StmtKind::Empty => {}
            _ => {
                return Err(
                    "its body holds statements other than assignments (GRAPH action rows are assignments)".into()
                )
            }
        }
    }
    if lines.is_empty() {
        return Err("its body is empty".into());
    }
    Ok(lines.join("\n"))
}

fn push(rows: &mut Vec<Row>, names: &mut Vec<String>, name: &str, r: Row) {
    rows.push(r);
    names.push(name.to_string());
}

/// The rows of a step of an IEC chart, from its associations.
fn iec_rows(out: &mut Out, chart: &Chart, s: &sfc_model::chart::StepNode, ops: &Operands) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut assoc_of_rows: Vec<String> = Vec::new();
    let row = |q: &str, ev: Option<&str>, t: String| Row {
        qualifier: q.into(),
        event: ev.map(str::to_string),
        interlock: false,
        tokens: t,
    };
    for a in &s.associations {
        let q = a.qualifier;
        match a.target {
            ActionTarget::Variable => {
                let op = operand_text(ops, &a.action);
                match (q, &a.duration) {
                    (Qualifier::N | Qualifier::S | Qualifier::R, _) => {
                        push(&mut rows, &mut assoc_of_rows, &a.action, row(q.name(), None, op))
                    }
                    (Qualifier::D | Qualifier::L, Some(Duration::Literal(us))) => push(
                        &mut rows,
                        &mut assoc_of_rows,
                        &a.action,
                        row(q.name(), None, format!("{op} , {}", time_literal(*us))),
                    ),
                    (Qualifier::D | Qualifier::L, Some(Duration::Variable(v))) => push(
                        &mut rows,
                        &mut assoc_of_rows,
                        &a.action,
                        row(q.name(), None, format!("{op} , {}", operand_text(ops, v))),
                    ),
                    (Qualifier::P1 | Qualifier::P0 | Qualifier::P, _) => {
                        let ev = if q == Qualifier::P0 { "S0" } else { "S1" };
                        push(&mut rows, &mut assoc_of_rows, &a.action, row("N", Some(ev), format!("{op} := TRUE")));
                        out.warn(a.span, format!("the pulse association of `{}` is written as an assignment in the step's {ev} event (TRUE once, not reset after)", a.action));
                    }
                    _ => out.error(
                        a.span,
                        format!("the qualifier {} on a variable cannot be written as a GRAPH action", q.name()),
                    ),
                }
            }
            ActionTarget::Action(id) => {
                let Some(act) = chart.actions.get(id) else { continue };
                let body = match assignments(ops, &act.body) {
                    Ok(b) => b,
                    Err(m) => {
                        out.error(
                            a.span,
                            format!("the action `{}` cannot be written as GRAPH action rows: {m}", act.name),
                        );
                        continue;
                    }
                };
                match q {
                    Qualifier::N => {
                        push(&mut rows, &mut assoc_of_rows, &a.action, row("N", None, body));
                        if out.source.final_run {
                            let who = out.source.name;
                            out.warn(a.span, format!("S7-GRAPH does not run the N action `{}` once more when its step is left, as {who} does", act.name));
                        }
                    }
                    Qualifier::P1 => push(&mut rows, &mut assoc_of_rows, &a.action, row("N", Some("S1"), body)),
                    Qualifier::P => {
                        let how = if out.source.name == "Studio 5000" { "Logix's P also runs when the step is left" } else { "without the final run with Q FALSE" };
                        out.warn(a.span, format!("the P action `{}` is written as an S1 (step activated) event action: S7-GRAPH runs it once ({how})", act.name));
                        push(&mut rows, &mut assoc_of_rows, &a.action, row("N", Some("S1"), body))
                    }
                    Qualifier::P0 => push(&mut rows, &mut assoc_of_rows, &a.action, row("N", Some("S0"), body)),
                    _ => out.error(
                        a.span,
                        format!("the {} association of the action `{}` cannot be written in S7-GRAPH (its rows hold N/S/R/D/L on operands and assignments)", q.name(), act.name),
                    ),
                }
            }
        }
    }
    // Interlock-dependent associations (GRAPH's C), as the `graph` profile reads them.
    let gated: Vec<String> = attr(&s.attributes, "sfc.s7graph.interlocked")
        .map(|l| l.split(',').map(|x| x.trim().to_ascii_uppercase()).collect())
        .unwrap_or_default();
    for (r, a) in rows.iter_mut().zip(assoc_of_rows.iter()) {
        if gated.contains(&a.to_ascii_uppercase()) {
            r.interlock = true;
        }
    }
    rows
}

/// The permanent instructions (`sfc.s7graph.permanent` actions) before or after the sequences.
fn permanent(w: &mut W, out: &mut Out, chart: &Chart, ops: &Operands, which: &str) {
    let el = if which == "pre" { "PreOperations" } else { "PostOperations" };
    let mut list: Vec<(usize, &sfc_model::chart::ActionNode)> = Vec::new();
    for a in &chart.actions {
        if attr(&a.attributes, "sfc.s7graph.permanent").as_deref() != Some(which) {
            continue;
        }
        let k = a.name.rsplit('_').next().and_then(|n| n.parse::<usize>().ok()).unwrap_or(list.len() + 1);
        list.push((k, a));
    }
    list.sort_by_key(|(k, _)| *k);
    w.open(el, &[]);
    let mut pos = 1;
    for (k, a) in list {
        while pos < k {
            w.empty("PermanentOperation", &[("ProgrammingLanguage", "LAD".into())]);
            pos += 1;
        }
        pos += 1;
        w.open("PermanentOperation", &[("ProgrammingLanguage", "LAD".into())]);
        if let Some(t) = attr(&a.attributes, "sfc.s7graph.title") {
            w.texts("Title", &t);
        }
        let mut net = Net::new(ops);
        let ActionBody::St(stmts) = &a.body else {
            out.error(a.name_span, "a permanent instruction must be ST assignments");
            continue;
        };
        for s in stmts {
            let r = match &s.kind {
                StmtKind::Assign { target, value } => {
                    net.chain(value, Src::Rail).and_then(|src| net.assign("Coil", target, src))
                }
                StmtKind::If { branches, else_body: None } if branches.len() == 1 => {
                    let set = branches.first().and_then(|(c, body)| match body.as_slice() {
                        [ast::Stmt { kind: StmtKind::Assign { target, value }, .. }] => match &value.kind {
                            ExprKind::Literal(l) => match l.kind {
                                LiteralKind::Bool(b) => Some((c, target, b)),
                                _ => None,
                            },
                            _ => None,
                        },
                        _ => None,
                    });
                    match set {
                        Some((c, target, b)) => net
                            .chain(c, Src::Rail)
                            .and_then(|src| net.assign(if b { "SCoil" } else { "RCoil" }, target, src)),
                        None => Err("an IF that is not `IF c THEN x := TRUE|FALSE; END_IF;`".into()),
                    }
                }
                StmtKind::Empty => Ok(()),
                _ => Err("a statement other than an assignment or a set/reset".into()),
            };
            if let Err(m) = r {
                out.error(
                    s.span,
                    format!("the permanent instruction `{}` cannot be written as a LAD network: {m}", a.name),
                );
            }
        }
        net.write(w);
        w.close("PermanentOperation");
    }
    if pos == 1 {
        w.empty("PermanentOperation", &[("ProgrammingLanguage", "LAD".into())]);
    }
    w.close(el);
}

/// The topology the import recorded (`sfc.s7graph.branch`, `sfc.s7graph.jump`).
fn topology_kept(out: &mut Out, chart: &Chart, end: &[bool]) -> (Vec<Back>, Vec<Fwd>) {
    let mut back = Vec::new();
    let mut fwd = Vec::new();
    for t in &chart.transitions {
        let path = attr(&t.attributes, "sfc.s7graph.branch").unwrap_or_default();
        let jump = attr(&t.attributes, "sfc.s7graph.jump").is_some();
        let mut b = None;
        let mut f = None;
        for item in path.split(';').map(str::trim).filter(|s| !s.is_empty()) {
            let w: Vec<&str> = item.split_whitespace().collect();
            let num = |i: usize| w.get(i).and_then(|x| x.parse::<i64>().ok()).unwrap_or(0);
            match w.first().copied() {
                Some("alt") if b.is_none() => {
                    b = Some(Back::Alt { b: num(1), out: num(3), step: t.from.first().copied().unwrap_or(0) })
                }
                Some("simend") if b.is_none() => b = Some(Back::SimEnd { b: num(1), steps: t.from.clone() }),
                Some("altend") if f.is_none() => {
                    f = Some(Fwd::AltEnd { b: num(1), inp: num(3), step: t.to.first().copied().unwrap_or(0) })
                }
                Some("sim") if f.is_none() => f = Some(Fwd::Sim { b: num(1), steps: t.to.clone() }),
                _ => out.error(
                    t.header_span,
                    format!("the branch path `{item}` of transition `{}` cannot be written back", t.name),
                ),
            }
        }
        if b.is_none() {
            if let Some(&f) = t.from.first() {
                let outs = chart.transitions.iter().filter(|x| x.from.contains(&f)).count();
                if outs > 1 && t.from.len() == 1 {
                    out.error(
                        t.header_span,
                        format!("transition `{}` leaves a step with several transitions but has no kept branch (sfc.s7graph.branch): number the chart's new elements or remove the chart's sfc.s7graph.number attributes to lay it out anew", t.name),
                    );
                }
            }
        }
        let b = b.unwrap_or_else(|| Back::Direct(t.from.first().copied().unwrap_or(0)));
        let f = f.unwrap_or_else(|| match t.to.first() {
            Some(&s) if end.get(s).copied().unwrap_or(false) => Fwd::End,
            Some(&s) => Fwd::Direct { step: s, jump },
            None => Fwd::End,
        });
        if matches!(b, Back::Direct(_)) && t.from.len() > 1 || matches!(f, Fwd::Direct { .. }) && t.to.len() > 1 {
            out.error(t.header_span, format!("transition `{}` joins several steps without a recorded branch", t.name));
        }
        back.push(b);
        fwd.push(f);
    }
    (back, fwd)
}

/// The topology of an IEC chart: an AltBegin per step with several outgoing transitions (its
/// `Out` pins in PRIORITY order), an AltEnd per step several transitions lead to straight down,
/// SimBegin/SimEnd per simultaneous divergence/convergence, a Jump per transition back to a step
/// declared at or before one it leaves.
fn topology_iec(out: &mut Out, chart: &Chart) -> (Vec<Back>, Vec<Fwd>) {
    let n = chart.transitions.len();
    let mut outgoing: Vec<Vec<usize>> = vec![Vec::new(); chart.steps.len()];
    for (i, t) in chart.transitions.iter().enumerate() {
        for &s in &t.from {
            if let Some(v) = outgoing.get_mut(s) {
                v.push(i);
            }
        }
    }
    for list in &mut outgoing {
        list.sort_by_key(|&i| (chart.transitions.get(i).and_then(|t| t.priority).unwrap_or(i64::MAX), i));
    }
    let is_jump: Vec<bool> = chart
        .transitions
        .iter()
        .map(|t| match t.to.as_slice() {
            [s] => t.from.iter().any(|f| s <= f),
            _ => false,
        })
        .collect();
    let mut incoming: Vec<Vec<usize>> = vec![Vec::new(); chart.steps.len()];
    for (i, t) in chart.transitions.iter().enumerate() {
        if let [s] = t.to.as_slice() {
            if !is_jump.get(i).copied().unwrap_or(false) {
                if let Some(v) = incoming.get_mut(*s) {
                    v.push(i);
                }
            }
        }
    }
    let mut next = 0i64;
    let mut alt_of_step: HashMap<usize, i64> = HashMap::new();
    let mut altend_of_step: HashMap<usize, i64> = HashMap::new();
    let mut back = Vec::with_capacity(n);
    let mut fwd = Vec::with_capacity(n);
    for (i, t) in chart.transitions.iter().enumerate() {
        let b = match t.from.as_slice() {
            [s] => {
                let outs = outgoing.get(*s).cloned().unwrap_or_default();
                if outs.len() > 1 {
                    let b = *alt_of_step.entry(*s).or_insert_with(|| {
                        next += 1;
                        next
                    });
                    let o = outs.iter().position(|&x| x == i).unwrap_or(0) as i64;
                    Back::Alt { b, out: o, step: *s }
                } else {
                    Back::Direct(*s)
                }
            }
            steps => {
                if steps.iter().any(|s| outgoing.get(*s).is_some_and(|o| o.len() > 1)) {
                    out.error(t.header_span, format!("transition `{}` closes a simultaneous branch from a step that also has other transitions, which S7-GRAPH cannot draw", t.name));
                }
                next += 1;
                Back::SimEnd { b: next, steps: steps.to_vec() }
            }
        };
        let f = match t.to.as_slice() {
            [s] => {
                let ins = incoming.get(*s).cloned().unwrap_or_default();
                let jump = is_jump.get(i).copied().unwrap_or(false);
                if !jump && ins.len() > 1 {
                    let b = *altend_of_step.entry(*s).or_insert_with(|| {
                        next += 1;
                        next
                    });
                    let inp = ins.iter().position(|&x| x == i).unwrap_or(0) as i64;
                    Fwd::AltEnd { b, inp, step: *s }
                } else {
                    Fwd::Direct { step: *s, jump }
                }
            }
            [] => Fwd::End,
            steps => {
                next += 1;
                Fwd::Sim { b: next, steps: steps.to_vec() }
            }
        };
        back.push(b);
        fwd.push(f);
    }
    (back, fwd)
}
