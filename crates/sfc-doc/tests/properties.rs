//! Properties on random input: block-structured charts (sequences, selection and simultaneous
//! branches, loops) survive `open` → `to_text` → `open` with their FROM/TO sets and reach a
//! fixed point; arbitrary documents, however broken, save without panicking as text that
//! parses and open again to the same document (ids normalised).

use proptest::prelude::*;
use sfc_doc::{
    normalize_ids, open, to_text, Association, Connection, EditorDoc, Element, ElementKind, Language, OtherAttribute,
    Point,
};

/// A random chart built from choices: `(FROM, TO)` per transition over steps `S0…`.
struct Chart {
    steps: usize,
    transitions: Vec<(Vec<usize>, Vec<usize>)>,
    choices: Vec<u8>,
    at: usize,
}

impl Chart {
    fn pick(&mut self, n: u8) -> u8 {
        let c = self.choices.get(self.at).copied().unwrap_or(0) % n;
        self.at += 1;
        c
    }
    fn step(&mut self) -> usize {
        self.steps += 1;
        self.steps - 1
    }
    fn seq(&mut self, start: usize, depth: u32) -> usize {
        let mut cur = start;
        for _ in 0..1 + self.pick(3) {
            match self.pick(if depth < 3 && self.steps < 40 { 4 } else { 1 }) {
                0 => {
                    let s = self.step();
                    self.transitions.push((vec![cur], vec![s]));
                    cur = s;
                }
                1 => {
                    let mut ends = Vec::new();
                    for _ in 0..2 + self.pick(2) {
                        let s = self.step();
                        self.transitions.push((vec![cur], vec![s]));
                        ends.push(self.seq(s, depth + 1));
                    }
                    let j = self.step();
                    for e in ends {
                        self.transitions.push((vec![e], vec![j]));
                    }
                    cur = j;
                }
                2 => {
                    let firsts: Vec<usize> = (0..2 + self.pick(2)).map(|_| self.step()).collect();
                    self.transitions.push((vec![cur], firsts.clone()));
                    let ends: Vec<usize> = firsts.iter().map(|&f| self.seq(f, depth + 1)).collect();
                    let j = self.step();
                    self.transitions.push((ends, vec![j]));
                    cur = j;
                }
                _ => {
                    self.transitions.push((vec![cur], vec![start]));
                    let s = self.step();
                    self.transitions.push((vec![cur], vec![s]));
                    cur = s;
                }
            }
        }
        cur
    }
    fn text(choices: Vec<u8>) -> String {
        let mut c = Chart { steps: 0, transitions: Vec::new(), choices, at: 0 };
        let init = c.step();
        let end = c.seq(init, 0);
        if c.pick(2) == 0 {
            c.transitions.push((vec![end], vec![init]));
        }
        let mut out = String::from("PROGRAM P\n");
        out.push_str(Chart::comment(c.pick(6)));
        out.push_str("    VAR\n        go : BOOL;\n    END_VAR\n\n");
        for s in 0..c.steps {
            let kw = if s == 0 { "INITIAL_STEP" } else { "STEP" };
            out.push_str(Chart::comment(c.pick(6)));
            if c.pick(3) == 0 {
                let inner = Chart::comment(c.pick(6));
                out.push_str(&format!("    {kw} S{s}:\n{inner}        Act(N);\n    END_STEP"));
            } else {
                out.push_str(&format!("    {kw} S{s}: END_STEP"));
            }
            // A comment ending the step's line.
            out.push_str(if c.pick(4) == 0 { " // after the step\n\n" } else { "\n\n" });
        }
        let list = |l: &[usize]| {
            let names: Vec<String> = l.iter().map(|s| format!("S{s}")).collect();
            if names.len() == 1 {
                names[0].clone()
            } else {
                format!("({})", names.join(", "))
            }
        };
        let transitions = c.transitions.clone();
        for (k, (from, to)) in transitions.iter().enumerate() {
            let name = if c.pick(2) == 0 { format!(" T_{k}") } else { String::new() };
            out.push_str(Chart::comment(c.pick(6)));
            out.push_str(&format!(
                "    TRANSITION{name} FROM {} TO {}\n        := go;\n    END_TRANSITION\n\n",
                list(from),
                list(to)
            ));
        }
        out.push_str(Chart::comment(c.pick(6)));
        out.push_str("    ACTION Act:\n        go := NOT go;\n    END_ACTION\n");
        out.push_str(Chart::comment(c.pick(6)));
        out.push_str("END_PROGRAM\n");
        out
    }
    /// Nothing, or comment lines as a user writes them between elements.
    fn comment(choice: u8) -> &'static str {
        match choice {
            0 => "    (* fill the tank *)\n",
            1 => "    // a line comment\n    (* and a block\n       comment over two lines *)\n",
            _ => "",
        }
    }
}

fn structure(text: &str) -> Vec<(Vec<String>, Vec<String>)> {
    let checked = sfc_model::check_source(0, "p", text, &Default::default());
    let c = &checked.charts[0];
    let names = |l: &[usize]| {
        let mut v: Vec<String> = l.iter().map(|&s| c.steps[s].name.clone()).collect();
        v.sort();
        v
    };
    c.transitions.iter().map(|t| (names(&t.from), names(&t.to))).collect()
}

fn pick<T: Clone + std::fmt::Debug + 'static>(pool: &'static [T]) -> impl Strategy<Value = T> {
    proptest::sample::select(pool)
}

const KINDS: &[Option<ElementKind>] = &[
    Some(ElementKind::Step),
    Some(ElementKind::Step),
    Some(ElementKind::Transition),
    Some(ElementKind::Transition),
    Some(ElementKind::SelectionDivergence),
    Some(ElementKind::SelectionConvergence),
    Some(ElementKind::SimultaneousDivergence),
    Some(ElementKind::SimultaneousConvergence),
    Some(ElementKind::Jump),
    Some(ElementKind::Text),
    Some(ElementKind::ActionBlock),
    None,
];
const NAMES: &[&str] = &["S1", "S2", "s1", "Go", "", "bad name", "END_STEP", "X_1", "go"];
const IDS: &[&str] = &["a", "b", "c", "d", "e", "f", "g", "step:S1", "b1", "zz"];
const CONDITIONS: &[Option<&str>] =
    &[None, Some("go"), Some("go AND"), Some(""), Some("LD go"), Some(" go "), Some("go (* c *)")];

fn element() -> impl Strategy<Value = Element> {
    (
        (pick(KINDS), pick(NAMES), pick(IDS), any::<bool>(), pick(CONDITIONS), any::<bool>()),
        (proptest::option::of(0u32..5), pick(NAMES), (-50i32..500, -50i32..500), 0u8..4),
        proptest::collection::vec(
            (pick(&["N", "D", "", "P1"]), pick(&[None, Some("T#1s"), Some("x")]), pick(NAMES)),
            0..3,
        ),
    )
        .prop_map(|((kind, name, id, initial, cond, il), (pins, target, (x, y), extra), assocs)| Element {
            id: id.to_string(),
            kind,
            x: f64::from(x) + if extra == 1 { 0.5 } else { 0.0 },
            y: f64::from(y),
            w: 40.0,
            h: 20.0,
            name: name.to_string(),
            initial,
            tag: (extra == 2).then_some(4),
            timeout: (extra == 3).then(|| "T#1s".to_string()),
            description: if extra == 1 { "it's $ {}".to_string() } else { String::new() },
            pins,
            target: Some(target.to_string()),
            condition: cond.map(str::to_string),
            condition_language: if il { Language::Il } else { Language::St },
            priority: (extra == 3).then_some(1),
            text: (extra == 0).then(|| "label\nline".to_string()),
            step: Some(pick_id(x)),
            attributes: others(y),
            comments: comments(x.wrapping_add(y)),
            associations: assocs
                .into_iter()
                .map(|(q, d, a)| Association {
                    qualifier: q.to_string(),
                    duration: d.map(str::to_string),
                    action: a.to_string(),
                    indicator: None,
                })
                .collect(),
            ..Element::default()
        })
}

/// Attributes the editor keeps as read: plain ones, ones it reads into fields, ones that
/// cannot be written.
fn others(seed: i32) -> Vec<OtherAttribute> {
    let a = |n: &str, v: Option<&str>| OtherAttribute { name: n.to_string(), value: v.map(str::to_string) };
    match seed.rem_euclid(7) {
        0 => vec![a("sfc.adddata", Some("<data name=$27x$27/>"))],
        1 => vec![a("sfc.x", Some("5")), a("qualified_only", None)],
        2 => vec![a("it's", None)],
        3 => vec![a("other", Some("a'b")), a("sfc.inline", Some("true"))],
        _ => Vec::new(),
    }
}

/// Comments as an editor document may hold them: ones the text can hold, ones it cannot
/// (unterminated, two in one, not a comment at all), none.
fn comments(seed: i32) -> Vec<String> {
    let list: &[&str] = match seed.rem_euclid(9) {
        0 => &["(* fill the tank *)"],
        1 => &["// one line", "(* two\n       lines *)"],
        2 => &["(* open"],
        3 => &["(* a *) (* b *)", "// ok"],
        4 => &["not a comment", "// x\ny"],
        5 => &["{attribute 'x'}", "(**)"],
        _ => &[],
    };
    list.iter().map(|c| c.to_string()).collect()
}

fn pick_id(seed: i32) -> String {
    IDS[seed.unsigned_abs() as usize % IDS.len()].to_string()
}

fn connection() -> impl Strategy<Value = Connection> {
    (pick(IDS), 0u32..3, pick(IDS), 0u32..3, any::<bool>()).prop_map(|(s, sp, t, tp, bent)| Connection {
        id: format!("{s}-{t}"),
        source: s.to_string(),
        source_pin: sp,
        target: t.to_string(),
        target_pin: tp,
        waypoints: if bent { vec![Point { x: 1.0, y: 2.0 }, Point { x: 1.0, y: 30.5 }] } else { Vec::new() },
        color: bent.then(|| "#123456".to_string()),
        line_width: None,
    })
}

fn document() -> impl Strategy<Value = EditorDoc> {
    (
        proptest::collection::vec(element(), 0..14),
        proptest::collection::vec(connection(), 0..16),
        proptest::collection::vec(
            (pick(&["Act", "act", "bad name", "B"]), pick(&["x := 1;", "x := ;", "", "LD x\nST x", " y;"])),
            0..3,
        ),
        pick(&[
            "VAR\n    go : BOOL;\nEND_VAR",
            "",
            "VAR x : END_VAR",
            "  VAR\nEND_VAR",
            "VAR\nEND_VAR\n(* trailing *)",
        ]),
        pick(&["P", "bad name", ""]),
    )
        .prop_map(|(mut elements, connections, actions, decl, pou)| {
            // Unique ids for some blocks so that connections find them.
            for (i, e) in elements.iter_mut().enumerate() {
                if i % 3 != 0 {
                    e.id = IDS[i % IDS.len()].to_string();
                }
            }
            EditorDoc {
                pou: pou.to_string(),
                pou_kind: sfc_doc::PouKind::Program,
                target: sfc_doc::ChartTarget::Blank,
                description: String::new(),
                declarations: decl.to_string(),
                body: None,
                body_language: Language::St,
                actions: actions
                    .into_iter()
                    .map(|(n, b)| sfc_doc::ActionDef {
                        name: n.to_string(),
                        language: Language::St,
                        body: b.to_string(),
                        description: String::new(),
                        attributes: others(b.len() as i32),
                        comments: comments(b.len() as i32),
                        chart: None,
                    })
                    .collect(),
                attributes: others(elements.len() as i32 + 1),
                trailing_comments: comments(connections.len() as i32),
                elements,
                connections,
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn block_structured_charts_keep_their_structure(choices in proptest::collection::vec(any::<u8>(), 0..60)) {
        let text = Chart::text(choices);
        let opened = open(0, "p", &text);
        prop_assert_eq!(opened.charts.len(), 1);
        let d = &opened.charts[0];
        let saved = to_text(d);
        prop_assert!(saved.problems.is_empty(), "{:?}", saved.problems);
        prop_assert_eq!(structure(&saved.text), structure(&text), "{}", text);
        let again = open(0, "p", &saved.text);
        prop_assert_eq!(again.charts.len(), 1);
        prop_assert!(again.charts[0] == *d, "{}\n{}", text, saved.text);
        // Every comment of the original is in the saved text, as often.
        for k in ["(* fill the tank *)", "// a line comment", "// after the step", "comment over two lines *)"] {
            prop_assert_eq!(saved.text.matches(k).count(), text.matches(k).count(), "{}\n{}", text, saved.text);
        }
        prop_assert_eq!(to_text(&again.charts[0]).text, saved.text);
    }

    #[test]
    fn any_document_saves_and_opens_again(doc in document()) {
        let saved = to_text(&doc);
        let (_, diags) = sfc_syntax::parse(0, &saved.text);
        prop_assert!(diags.is_empty(), "{:?}\n{}", diags, saved.text);
        let again = open(0, "p", &saved.text);
        if saved.problems.iter().any(|p| p.code == "SFC0201") {
            prop_assert!(again.charts.is_empty());
        } else {
            prop_assert_eq!(again.charts.len(), 1, "{}", saved.text);
            let expected = normalize_ids(&doc);
            prop_assert!(
                again.charts[0] == expected,
                "{}\n{}\n{}",
                saved.text,
                serde_json::to_string(&expected).unwrap(),
                serde_json::to_string(&again.charts[0]).unwrap()
            );
            prop_assert_eq!(to_text(&again.charts[0]).text, saved.text);
        }
    }
}
