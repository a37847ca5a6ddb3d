//! Property test: random charts (sequences, selection and simultaneous branches, loops, IL and
//! ST conditions, named and prioritised transitions, actions and Boolean variables with every
//! qualifier, attributes, with or without stored positions) export to XML that passes the
//! schema and import back to the same model; exporting the import again gives the same XML.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;
use common::*;
use proptest::prelude::*;
use std::fmt::Write;

#[derive(Debug, Clone)]
struct Spec {
    steps: usize,
    /// (kind, a, b, c): 0 selection a→b, 1 simultaneous divergence a→(b, c), 2 simultaneous
    /// convergence (b, c)→a.
    extra: Vec<(u8, usize, usize, usize)>,
    conditions: Vec<u8>,
    named: Vec<bool>,
    priority: Vec<Option<u8>>,
    /// (step, qualifier, target)
    assocs: Vec<(usize, u8, u8)>,
    tags: bool,
    descriptions: Vec<u8>,
    /// Positions for every step and transition.
    layout: Option<Vec<(i16, i16)>>,
}

const CONDITIONS: &[&str] =
    &["a", "NOT a", "a AND b", "b OR c", "(a OR b) AND NOT c", "Level > 10", "S0.T >= T#1s", "TRUE"];
const QUALIFIERS: &[&str] = &["N", "R", "S", "L", "D", "P", "SD", "DS", "SL", "P1", "P0"];
const DESCRIPTIONS: &[&str] = &["", "Fill the tank", "two$Nlines", "say $27hello$27", "50$$ full"];

fn render(spec: &Spec) -> String {
    let n = spec.steps;
    let mut s = String::new();
    let _ = writeln!(s, "PROGRAM Random\n    VAR_INPUT\n        a : BOOL;\n        b : BOOL;\n        c : BOOL;\n        Level : INT;\n    END_VAR");
    let _ = writeln!(s, "    VAR_OUTPUT\n        Q0 : BOOL;\n        Q1 : BOOL;\n        Count : INT;\n    END_VAR\n    VAR\n        Dur : TIME := T#2s;\n    END_VAR\n");
    // Transitions: a ring through every step, then the extra ones.
    let mut trans: Vec<(Vec<usize>, Vec<usize>)> = (0..n).map(|i| (vec![i], vec![(i + 1) % n])).collect();
    for &(kind, a, b, c) in &spec.extra {
        let (a, b, c) = (a % n, b % n, c % n);
        let t = match kind % 3 {
            0 => (vec![a], vec![b]),
            1 if b != c => (vec![a], vec![b, c]),
            2 if b != c => (vec![b, c], vec![a]),
            _ => continue,
        };
        // Two transitions between the same steps are reported (SFC0215) when their conditions
        // are the same; keep one per pair of step lists.
        let key = |t: &(Vec<usize>, Vec<usize>)| {
            let (mut f, mut to) = t.clone();
            f.sort();
            to.sort();
            (f, to)
        };
        if !trans.iter().any(|u| key(u) == key(&t)) {
            trans.push(t);
        }
    }
    let mut pos = spec.layout.clone().unwrap_or_default().into_iter().cycle();
    let mut layout = |s: &mut String| {
        if spec.layout.is_some() {
            if let Some((x, y)) = pos.next() {
                let _ = writeln!(s, "    {{attribute 'sfc.x' := '{x}'}}\n    {{attribute 'sfc.y' := '{y}'}}");
            }
        }
    };
    for i in 0..n {
        layout(&mut s);
        if spec.tags {
            let _ = writeln!(s, "    {{attribute 'sfc.tag' := '{i}'}}");
        }
        if let Some(&d) = spec.descriptions.get(i) {
            let d = DESCRIPTIONS[d as usize % DESCRIPTIONS.len()];
            if !d.is_empty() {
                let _ = writeln!(s, "    {{attribute 'sfc.description' := '{d}'}}");
            }
        }
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        let mine: Vec<&(usize, u8, u8)> = spec.assocs.iter().filter(|a| a.0 % n == i).collect();
        if mine.is_empty() {
            let _ = writeln!(s, "    {kw} S{i}: END_STEP\n");
        } else {
            let _ = writeln!(s, "    {kw} S{i}:");
            for &&(_, q, t) in &mine {
                let q = QUALIFIERS[q as usize % QUALIFIERS.len()];
                let target = ["A0", "A1", "Q0", "Q1"][t as usize % 4];
                let timed = ["L", "D", "SD", "DS", "SL"].contains(&q);
                let d = if timed {
                    if t % 2 == 0 {
                        ", T#1s500ms"
                    } else {
                        ", Dur"
                    }
                } else {
                    ""
                };
                let _ = writeln!(s, "        {target}({q}{d});");
            }
            let _ = writeln!(s, "    END_STEP\n");
        }
    }
    for (k, (from, to)) in trans.iter().enumerate() {
        layout(&mut s);
        let list = |l: &[usize]| {
            let names: Vec<String> = l.iter().map(|i| format!("S{i}")).collect();
            if names.len() > 1 {
                format!("({})", names.join(", "))
            } else {
                names.join("")
            }
        };
        let name = if spec.named.get(k).copied().unwrap_or(false) { format!("TR{k} ") } else { String::new() };
        let prio = match spec.priority.get(k).copied().flatten() {
            Some(p) => format!("(PRIORITY := {p}) "),
            None => String::new(),
        };
        let c = spec.conditions.get(k).copied().unwrap_or(0);
        if c % 5 == 4 {
            let _ = writeln!(
                s,
                "    TRANSITION {name}{prio}FROM {} TO {}:\n        LD   a\n        ANDN b\n    END_TRANSITION\n",
                list(from),
                list(to)
            );
        } else {
            let cond = CONDITIONS[c as usize % CONDITIONS.len()];
            let _ = writeln!(
                s,
                "    TRANSITION {name}{prio}FROM {} TO {}\n        := {cond};\n    END_TRANSITION\n",
                list(from),
                list(to)
            );
        }
    }
    let _ = writeln!(s, "    ACTION A0:\n        Count := Count + 1; (* counts *)\n    END_ACTION\n");
    let _ = writeln!(s, "    ACTION A1:\n        LD   a\n        ST   Q1\n    END_ACTION\nEND_PROGRAM");
    s
}

fn spec() -> impl Strategy<Value = Spec> {
    (2usize..9)
        .prop_flat_map(|steps| {
            (
                Just(steps),
                prop::collection::vec((0u8..3, 0usize..9, 0usize..9, 0usize..9), 0..5),
                prop::collection::vec(any::<u8>(), 16),
                prop::collection::vec(prop::bool::weighted(0.3), 16),
                prop::collection::vec(prop::option::weighted(0.2, 0u8..5), 16),
                prop::collection::vec((0usize..9, any::<u8>(), any::<u8>()), 0..6),
                any::<bool>(),
                prop::collection::vec(any::<u8>(), 0..9),
                prop::option::of(prop::collection::vec((-200i16..2000, -200i16..2000), 1..30)),
            )
        })
        .prop_map(|(steps, extra, conditions, named, priority, assocs, tags, descriptions, layout)| Spec {
            steps,
            extra,
            conditions,
            named,
            priority,
            assocs,
            tags,
            descriptions,
            layout,
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]
    #[test]
    fn random_charts_round_trip(spec in spec()) {
        let text = render(&spec);
        let checked = check_text("random.st", &text);
        prop_assert!(!checked.diagnostics.iter().any(|d| d.is_error()), "generated chart has errors: {:?}\n{}", checked.diagnostics, text);
        let xml = sfc_plcopen::export(&checked).map_err(|e| TestCaseError::fail(format!("{e:?}")))?;
        if let Some(r) = xmllint(&xml) {
            prop_assert!(r.is_ok(), "schema: {:?}\n{}", r, xml);
        }
        let (_, again, diags) = sfc_plcopen::check_xml(0, "random.xml", &xml, &opts());
        prop_assert!(!diags.iter().any(|d| d.is_error()), "{:?}", diags);
        let same = same_model(&checked, &again, true);
        prop_assert!(same.is_ok(), "{}\n--- text\n{}\n--- imported\n{}", same.unwrap_err(), text, again.file.text);
        let xml2 = sfc_plcopen::export(&again).map_err(|e| TestCaseError::fail(format!("{e:?}")))?;
        prop_assert_eq!(xml, xml2);
    }
}
