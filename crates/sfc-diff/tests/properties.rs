//! Property tests on random charts and random edits (issue 35): `diff(a, edit(a))` names
//! exactly the edit; `merge(base, edit1(base), edit2(base))` with the edits on different
//! elements equals applying both and has no conflict; the same element edited both ways (a
//! condition, a step's name, a transition's target) is a conflict naming it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use proptest::prelude::*;
use sfc_diff::{diff, merge::merge, Kind};

const NAMES: &[&str] = &["Idle", "Fill", "Heat", "Mix", "Drain", "Rinse", "Dry", "Check"];
const VARS: &[&str] = &["a", "NOT b", "a AND b", "n > 3", "c OR n = 0", "NOT (a OR c)", "n <= 7 AND b"];

#[derive(Debug, Clone, PartialEq)]
enum Cond {
    Var(usize),
    /// `Step.T > T#Ns`
    Time(usize, u32),
}

#[derive(Debug, Clone)]
struct Step {
    name: String,
    x: i32,
    y: i32,
    action: Option<usize>,
}

#[derive(Debug, Clone)]
struct Tr {
    name: String,
    from: usize,
    to: usize,
    cond: Cond,
}

#[derive(Debug, Clone)]
struct Chart {
    steps: Vec<Step>,
    trs: Vec<Tr>,
}

impl Chart {
    fn text(&self) -> String {
        let mut t = String::from("PROGRAM Plant\n    VAR\n        a, b, c : BOOL;\n        n : INT;\n    END_VAR\n");
        let cond = |c: &Cond| match c {
            Cond::Var(v) => VARS[*v].to_string(),
            Cond::Time(s, secs) => format!("{}.T > T#{secs}s", self.steps[*s].name),
        };
        for (i, s) in self.steps.iter().enumerate() {
            t.push_str(&format!("\n    {{attribute 'sfc.x' := '{}'}}\n    {{attribute 'sfc.y' := '{}'}}\n", s.x, s.y));
            let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
            match s.action {
                None => t.push_str(&format!("    {kw} {}: END_STEP\n", s.name)),
                Some(k) => t.push_str(&format!("    {kw} {}:\n        A{k}(N);\n    END_STEP\n", s.name)),
            }
        }
        for tr in &self.trs {
            t.push_str(&format!(
                "\n    TRANSITION {} FROM {} TO {}\n        := {};\n    END_TRANSITION\n",
                tr.name,
                self.steps[tr.from].name,
                self.steps[tr.to].name,
                cond(&tr.cond)
            ));
        }
        for k in 0..3 {
            t.push_str(&format!("\n    ACTION A{k}:\n        n := n + {};\n    END_ACTION\n", k + 1));
        }
        t.push_str("END_PROGRAM\n");
        t
    }
}

#[derive(Debug, Clone)]
enum Edit {
    Rename(usize, String),
    Move(usize, i32),
    Condition(usize, Cond),
    Rewire(usize, usize),
    Add(usize, usize, usize),
    Remove(usize),
    Action(usize, usize),
}

/// What an edit touches: the step or transition (by name in the base).
fn touches(c: &Chart, e: &Edit) -> String {
    match e {
        Edit::Rename(i, _) | Edit::Move(i, _) | Edit::Action(i, _) => format!("step {}", c.steps[*i].name),
        Edit::Condition(j, _) | Edit::Rewire(j, _) | Edit::Remove(j) => format!("transition {}", c.trs[*j].name),
        Edit::Add(..) => "new".into(),
    }
}

/// `edit` applied; `side` makes added names differ between the two sides of a merge.
fn apply(c: &Chart, e: &Edit, side: &str) -> Chart {
    let mut c = c.clone();
    match e {
        Edit::Rename(i, n) => c.steps[*i].name = n.clone(),
        Edit::Move(i, dx) => c.steps[*i].x += dx,
        Edit::Condition(j, cond) => c.trs[*j].cond = cond.clone(),
        Edit::Rewire(j, to) => c.trs[*j].to = *to,
        Edit::Add(from, to, v) => {
            c.trs.push(Tr { name: format!("New{side}"), from: *from, to: *to, cond: Cond::Var(*v) })
        }
        Edit::Remove(j) => {
            c.trs.remove(*j);
        }
        Edit::Action(i, k) => c.steps[*i].action = Some(*k),
    }
    c
}

fn chart() -> impl Strategy<Value = Chart> {
    (3usize..7, proptest::collection::vec((0usize..8, 0usize..8, 0usize..VARS.len()), 0..3), any::<u64>()).prop_map(
        |(n, extra, seed)| {
            let steps: Vec<Step> = (0..n)
                .map(|i| Step {
                    name: NAMES[i].to_string(),
                    x: 100 + 40 * (i as i32 % 2),
                    y: 40 + 120 * i as i32,
                    action: (seed >> i & 1 == 1).then_some(i % 3),
                })
                .collect();
            let mut trs: Vec<Tr> = (0..n)
                .map(|i| Tr {
                    name: format!("T{i}"),
                    from: i,
                    to: (i + 1) % n,
                    cond: if seed >> (8 + i) & 1 == 1 { Cond::Time(i, 2 + i as u32) } else { Cond::Var(i % VARS.len()) },
                })
                .collect();
            for (k, (f, t, v)) in extra.into_iter().enumerate() {
                trs.push(Tr { name: format!("X{k}"), from: f % n, to: t % n, cond: Cond::Var(v) });
            }
            Chart { steps, trs }
        },
    )
}

/// A random edit of `c` that changes something.
fn edit(c: &Chart, pick: (u8, usize, usize, usize)) -> Option<Edit> {
    let (kind, a, b, v) = pick;
    let (ns, nt) = (c.steps.len(), c.trs.len());
    let e = match kind % 7 {
        0 => Edit::Rename(a % ns, format!("{}{}", ["Zeta", "Omega", "Kappa"][b % 3], a % ns)),
        1 => Edit::Move(a % ns, 40 + 20 * (b as i32 % 3)),
        2 => {
            let j = a % nt;
            let cond = Cond::Var(v % VARS.len());
            if c.trs[j].cond == cond {
                return None;
            }
            Edit::Condition(j, cond)
        }
        3 => {
            let j = a % nt;
            let to = b % ns;
            if c.trs[j].to == to {
                return None;
            }
            Edit::Rewire(j, to)
        }
        4 => Edit::Add(a % ns, b % ns, v % VARS.len()),
        5 => {
            let extra: Vec<usize> = (0..nt).filter(|&j| c.trs[j].name.starts_with('X')).collect();
            Edit::Remove(*extra.get(a % extra.len().max(1))?)
        }
        _ => {
            let i = a % ns;
            if c.steps[i].action.is_some() {
                return None;
            }
            Edit::Action(i, b % 3)
        }
    };
    Some(e)
}

fn check(text: &str) -> sfc_model::Checked {
    // Random rewiring may leave steps no initial step reaches (SFC0201): the chart still
    // reads, which is all a diff needs.
    let c = sfc_model::check_source(0, "plant.st", text, &Default::default());
    assert!(!c.diagnostics.iter().any(|d| d.code.starts_with("SFC01")), "{text}\n{:?}", c.diagnostics);
    c
}

fn pick() -> impl Strategy<Value = (u8, usize, usize, usize)> {
    (any::<u8>(), 0usize..64, 0usize..64, 0usize..64)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn the_diff_names_exactly_the_edit(c in chart(), p in pick()) {
        let Some(e) = edit(&c, p) else { return Ok(()) };
        let d = diff(&check(&c.text()), &check(&apply(&c, &e, "").text()));
        let names: Vec<String> = d.changes.iter().map(|x| format!("{} {} {} {}", x.kind.name(), x.element, x.name, x.what)).collect();
        match &e {
            Edit::Move(..) => {
                prop_assert!(d.changes.is_empty(), "{names:?}");
                prop_assert_eq!(d.layout.len(), 1);
            }
            _ => {
                prop_assert_eq!(d.changes.len(), 1, "{:?}: {:?}", e, names);
                let x = &d.changes[0];
                let expected = match &e {
                    Edit::Rename(i, n) => (Kind::Renamed, "step", c.steps[*i].name.clone(), Some(n.clone())),
                    Edit::Condition(j, _) => (Kind::Changed, "transition", c.trs[*j].name.clone(), None),
                    Edit::Rewire(j, _) => (Kind::Changed, "transition", c.trs[*j].name.clone(), None),
                    Edit::Add(..) => (Kind::Added, "transition", "New".to_string(), None),
                    Edit::Remove(j) => (Kind::Removed, "transition", c.trs[*j].name.clone(), None),
                    Edit::Action(i, _) => (Kind::Changed, "step", c.steps[*i].name.clone(), None),
                    Edit::Move(..) => unreachable!(),
                };
                prop_assert_eq!((x.kind, x.element, x.name.clone()), (expected.0, expected.1, expected.2), "{:?}", names);
                if let Some(n) = expected.3 {
                    prop_assert_eq!(x.new.clone(), Some(n));
                }
                let what = match &e {
                    Edit::Condition(..) => "condition",
                    Edit::Rewire(..) => "steps",
                    Edit::Action(..) => "actions",
                    _ => "",
                };
                prop_assert_eq!(x.what.as_str(), what);
            }
        }
    }

    #[test]
    fn edits_of_different_elements_merge_as_both_applied(c in chart(), p1 in pick(), p2 in pick()) {
        let (Some(e1), Some(e2)) = (edit(&c, p1), edit(&c, p2)) else { return Ok(()) };
        let (t1, t2) = (touches(&c, &e1), touches(&c, &e2));
        if t1 == t2 && t1 != "new" {
            return Ok(());
        }
        // Removing a transition the other side changes is a conflict, not this property.
        let ours = apply(&c, &e1, "Ours");
        let theirs = apply(&c, &e2, "Theirs");
        // Both applied: the second edit's indices are the base's, so it is applied by name.
        let both = apply_both(&c, &e1, &e2);
        let m = merge(&c.text(), &ours.text(), &theirs.text());
        prop_assert!(m.conflicts.is_empty(), "{:?} / {:?}: {:?}\n{}", e1, e2, m.conflicts, m.text);
        let d = diff(&check(&m.text), &check(&both.text()));
        prop_assert!(d.equal() && d.layout.is_empty(), "{:?} / {:?}: {}\n{}", e1, e2, d.text(true), m.text);
    }

    #[test]
    fn the_same_element_changed_both_ways_is_a_conflict(c in chart(), a in 0usize..64, v1 in 0usize..64, v2 in 0usize..64) {
        let j = a % c.trs.len();
        let (c1, c2) = (Cond::Var(v1 % VARS.len()), Cond::Var(v2 % VARS.len()));
        if c1 == c2 || c.trs[j].cond == c1 || c.trs[j].cond == c2 {
            return Ok(());
        }
        let ours = apply(&c, &Edit::Condition(j, c1), "");
        let theirs = apply(&c, &Edit::Condition(j, c2), "");
        let m = merge(&c.text(), &ours.text(), &theirs.text());
        prop_assert_eq!(m.conflicts.len(), 1, "{:?}", m.conflicts);
        prop_assert_eq!(m.conflicts[0].name.clone(), format!("transition {}", c.trs[j].name));
        // The file still reads: ours, marked.
        let (_, diags) = sfc_syntax::parse(0, &m.text);
        prop_assert!(diags.is_empty());
        prop_assert!(m.text.contains("sfc.conflict"));
        // A step renamed both ways, differently, too.
        let i = a % c.steps.len();
        let ours = apply(&c, &Edit::Rename(i, "Left".into()), "");
        let theirs = apply(&c, &Edit::Rename(i, "Right".into()), "");
        let m = merge(&c.text(), &ours.text(), &theirs.text());
        prop_assert!(m.conflicts.iter().any(|x| x.name == format!("step {}", c.steps[i].name)), "{:?}", m.conflicts);
    }
}

/// Both edits applied to the base; an edit of the second side addresses the base's elements,
/// which the first edit keeps in place (a removed transition shifts the others: by name).
fn apply_both(c: &Chart, e1: &Edit, e2: &Edit) -> Chart {
    let one = apply(c, e1, "Ours");
    let e2 = match e2 {
        Edit::Condition(j, x) => Edit::Condition(index(&one, &c.trs[*j].name), x.clone()),
        Edit::Rewire(j, x) => Edit::Rewire(index(&one, &c.trs[*j].name), *x),
        Edit::Remove(j) => Edit::Remove(index(&one, &c.trs[*j].name)),
        other => other.clone(),
    };
    apply(&one, &e2, "Theirs")
}

fn index(c: &Chart, name: &str) -> usize {
    c.trs.iter().position(|t| t.name == name).unwrap()
}

/// A conflict resolved either way gives a chart without marks: ours, or theirs.
#[test]
fn a_conflict_is_resolved_by_taking_a_side() {
    let base = "PROGRAM P\n    VAR\n        a, b : BOOL;\n    END_VAR\n    INITIAL_STEP S1: END_STEP\n    STEP S2: END_STEP\n    TRANSITION T1 FROM S1 TO S2\n        := a;\n    END_TRANSITION\n    TRANSITION T2 FROM S2 TO S1\n        := b;\n    END_TRANSITION\nEND_PROGRAM\n";
    let ours = base.replace(":= a;", ":= a AND b;");
    let theirs = base.replace(":= a;", ":= a OR b;");
    let m = merge(base, &ours, &theirs);
    assert_eq!(m.conflicts.len(), 1);
    let marked = sfc_diff::merge::conflicts_of(
        &match sfc_syntax::parse(0, &m.text).0.items.remove(0) {
            sfc_syntax::ast::Item::Pou(p) => p,
            _ => unreachable!(),
        }
        .attributes,
    );
    assert_eq!(marked.len(), 1);
    assert_eq!(marked[0].0, "transition:T1");
    let kept = sfc_diff::merge::resolve(&m.text, "P", "transition:T1", false).unwrap();
    assert_eq!(kept, ours);
    let taken = sfc_diff::merge::resolve(&m.text, "P", "transition:T1", true).unwrap();
    assert_eq!(taken, theirs);
    assert!(sfc_diff::merge::resolve(&m.text, "P", "transition:T2", true).is_err());
}
