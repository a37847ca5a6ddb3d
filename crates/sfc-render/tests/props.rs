//! Property tests of the layout: random block-structured charts get the structured layout and
//! random nets get some layout, and either way every step and transition is drawn once, no
//! boxes or texts overlap, no line runs through one, and the lines connect exactly the links
//! of the net (`common::check_layout`).

mod common;

use common::check_layout;
use proptest::prelude::*;
use sfc_model::{check_source, Chart, CheckOptions};
use sfc_render::{layout, svg, LayoutKind, SvgOptions};

/// A small deterministic generator (xorshift), so one proptest seed gives one chart.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// A net under construction: step names are `S<i>`, transitions `T<i>`.
struct Net {
    steps: usize,
    transitions: Vec<(Vec<usize>, Vec<usize>)>,
    /// Associations per step, to give some steps action blocks.
    actions: Vec<usize>,
}

impl Net {
    fn step(&mut self, rng: &mut Rng) -> usize {
        self.steps += 1;
        self.actions.push(if rng.below(3) == 0 { 1 + rng.below(3) } else { 0 });
        self.steps - 1
    }
    fn link(&mut self, from: Vec<usize>, to: Vec<usize>) {
        self.transitions.push((from, to));
    }

    fn source(&self, rng: &mut Rng) -> String {
        let mut s = String::from(
            "PROGRAM Random\nVAR\n    a : BOOL;\n    b : BOOL;\n    LongerVariableName : BOOL;\n    Out : BOOL;\nEND_VAR\n",
        );
        let conditions = ["a", "NOT b", "a AND b", "LongerVariableName OR a AND NOT b", "S0.T > T#1s"];
        for i in 0..self.steps {
            let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
            s.push_str(&format!("{kw} S{i}:\n"));
            for k in 0..self.actions[i] {
                let assoc = ["Out(N)", "Out(S)", "Out(D, T#2s)", "Out(L, T#500ms)"][(i + k) % 4];
                s.push_str(&format!("    {assoc};\n"));
            }
            s.push_str("END_STEP\n");
        }
        let list = |v: &[usize]| {
            let names: Vec<String> = v.iter().map(|i| format!("S{i}")).collect();
            if names.len() == 1 {
                names[0].clone()
            } else {
                format!("({})", names.join(", "))
            }
        };
        for (i, (from, to)) in self.transitions.iter().enumerate() {
            let c = conditions[rng.below(conditions.len())];
            s.push_str(&format!("TRANSITION T{i} FROM {} TO {} := {c}; END_TRANSITION\n", list(from), list(to)));
        }
        s.push_str("END_PROGRAM\n");
        s
    }
}

/// Extends a sequence from step `cur` by a few elements (steps, selections that meet again or
/// loop back to a step on the way here, simultaneous branches that join again) and returns its
/// last step. `path` holds the steps on the way here (not those of sibling branches).
fn block(net: &mut Net, rng: &mut Rng, mut cur: usize, depth: usize, path: &mut Vec<usize>) -> usize {
    let n = 1 + rng.below(3);
    for _ in 0..n {
        path.push(cur);
        match if depth >= 3 { 0 } else { rng.below(4) } {
            1 => {
                let conv = net.step(rng);
                let k = 2 + rng.below(2);
                for i in 0..k {
                    match if i == 0 { 1 } else { rng.below(3) } {
                        0 => net.link(vec![cur], vec![conv]),
                        1 => {
                            let h = net.step(rng);
                            net.link(vec![cur], vec![h]);
                            let mark = path.len();
                            let last = block(net, rng, h, depth + 1, path);
                            path.truncate(mark);
                            net.link(vec![last], vec![conv]);
                        }
                        _ => {
                            // A loop back to a step on the way here.
                            let target = path[rng.below(path.len())];
                            net.link(vec![cur], vec![target]);
                        }
                    }
                }
                cur = conv;
            }
            2 => {
                let k = 2 + rng.below(2);
                let heads: Vec<usize> = (0..k).map(|_| net.step(rng)).collect();
                net.link(vec![cur], heads.clone());
                let mark = path.len();
                let lasts: Vec<usize> = heads
                    .iter()
                    .map(|&h| {
                        let last = block(net, rng, h, depth + 1, path);
                        path.truncate(mark);
                        last
                    })
                    .collect();
                let next = net.step(rng);
                net.link(lasts, vec![next]);
                cur = next;
            }
            _ => {
                let next = net.step(rng);
                net.link(vec![cur], vec![next]);
                cur = next;
            }
        }
    }
    cur
}

fn chart_of(source: &str) -> Chart {
    let checked = check_source(0, "random.st", source, &CheckOptions::default());
    checked.charts.into_iter().next().expect("one chart")
}

fn structured_chart(seed: u64) -> (String, Chart) {
    let mut rng = Rng(seed | 1);
    let mut net = Net { steps: 0, transitions: Vec::new(), actions: Vec::new() };
    let first = net.step(&mut rng);
    let last = block(&mut net, &mut rng, first, 0, &mut Vec::new());
    if rng.below(4) != 0 {
        net.link(vec![last], vec![first]);
    }
    let source = net.source(&mut rng);
    let chart = chart_of(&source);
    (source, chart)
}

fn random_net(seed: u64, steps: usize, transitions: usize) -> (String, Chart) {
    let mut rng = Rng(seed | 1);
    let mut net = Net { steps: 0, transitions: Vec::new(), actions: Vec::new() };
    for _ in 0..steps {
        net.step(&mut rng);
    }
    let pick = |rng: &mut Rng| {
        let wide = rng.below(3) == 0;
        let k = 1 + rng.below(if wide { 3 } else { 1 });
        let mut v: Vec<usize> = Vec::new();
        for _ in 0..k {
            let s = rng.below(steps);
            if !v.contains(&s) {
                v.push(s);
            }
        }
        v
    };
    for _ in 0..transitions {
        let from = pick(&mut rng);
        let to = pick(&mut rng);
        net.link(from, to);
    }
    let source = net.source(&mut rng);
    let chart = chart_of(&source);
    (source, chart)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn block_structured_charts_get_the_structured_layout(seed in any::<u64>()) {
        let (source, chart) = structured_chart(seed);
        let l = layout(&chart);
        prop_assert_eq!(l.kind, LayoutKind::Structured, "{}", source);
        if let Err(e) = check_layout(&chart, &l) {
            prop_assert!(false, "{}\n{}", e, source);
        }
        prop_assert!(svg(&chart, &l, &SvgOptions::default()).ends_with("</svg>\n"));
    }

    #[test]
    fn random_nets_lay_out_completely(seed in any::<u64>(), steps in 1usize..12, transitions in 0usize..16) {
        let (source, chart) = random_net(seed, steps, transitions);
        let l = layout(&chart);
        if let Err(e) = check_layout(&chart, &l) {
            prop_assert!(false, "{:?}: {}\n{}", l.kind, e, source);
        }
        let out = svg(&chart, &l, &SvgOptions::default());
        prop_assert!(!out.contains("NaN") && !out.contains("inf"));
    }
}

/// Long and deeply nested charts lay out without exhausting the stack: sequences are followed
/// in loops, and nesting beyond the structured layout's limit falls back to the layered one.
#[test]
fn long_and_deep_charts() {
    let mut net = Net { steps: 0, transitions: Vec::new(), actions: Vec::new() };
    let mut rng = Rng(7);
    let first = net.step(&mut rng);
    let mut cur = first;
    for i in 0..3000 {
        let next = net.step(&mut rng);
        net.link(vec![cur], vec![next]);
        if i % 10 == 0 {
            net.link(vec![cur], vec![first]);
        }
        cur = next;
    }
    net.link(vec![cur], vec![first]);
    let chart = chart_of(&net.source(&mut rng));
    let l = layout(&chart);
    assert_eq!(l.kind, LayoutKind::Structured);
    assert_eq!(l.steps.len(), 3001);
    assert!(l.jumps.len() >= 300);

    // 100 selections nested in each other.
    let mut net = Net { steps: 0, transitions: Vec::new(), actions: Vec::new() };
    let first = net.step(&mut rng);
    let mut cur = first;
    let mut convs = Vec::new();
    for _ in 0..100 {
        let a = net.step(&mut rng);
        let conv = net.step(&mut rng);
        net.link(vec![cur], vec![a]);
        net.link(vec![cur], vec![conv]);
        convs.push(conv);
        cur = a;
    }
    for conv in convs.into_iter().rev() {
        net.link(vec![cur], vec![conv]);
        cur = conv;
    }
    let chart = chart_of(&net.source(&mut rng));
    let l = layout(&chart);
    assert_eq!(l.kind, LayoutKind::Layered);
    check_layout(&chart, &l).unwrap();
}

/// Charts with stored coordinates keep them; a chart where one element lacks them is laid out
/// by structure instead.
#[test]
fn stored_coordinates_are_used_only_when_complete() {
    let with = |attrs_on_all: bool| {
        format!(
            "PROGRAM P\nVAR a : BOOL; END_VAR\n\
             {{attribute 'sfc.x' := '300'}} {{attribute 'sfc.y' := '40'}}\nINITIAL_STEP A: END_STEP\n\
             {{attribute 'sfc.x' := '300'}} {{attribute 'sfc.y' := '140'}}\nSTEP B: END_STEP\n\
             {}\nTRANSITION T1 FROM A TO B := a; END_TRANSITION\n\
             {{attribute 'sfc.x' := '-50'}} {{attribute 'sfc.y' := '110'}}\nTRANSITION T2 FROM B TO A := NOT a; END_TRANSITION\n\
             END_PROGRAM\n",
            if attrs_on_all { "{attribute 'sfc.x' := '312'} {attribute 'sfc.y' := '100.5'}" } else { "" }
        )
    };
    let chart = chart_of(&with(true));
    let l = layout(&chart);
    assert_eq!(l.kind, LayoutKind::Stored);
    // Everything is moved right by the same amount so that T2 (at x = -50) is visible.
    let dx = l.steps[0].rect.x - 300.0;
    assert!(dx > 0.0);
    assert_eq!(l.steps[1].rect.x, 300.0 + dx);
    assert_eq!(l.steps[0].rect.y, 40.0);
    assert_eq!(l.transitions[0].x, 312.0 + 12.0 + dx);
    assert!(l.wires.iter().any(|w| w.upward_arrow), "T2 leads back up");
    let chart = chart_of(&with(false));
    assert_eq!(layout(&chart).kind, LayoutKind::Structured);
}

/// `Chart` has public fields: a hand-made chart with links to steps that do not exist, links
/// named twice, or no steps at all still lays out and draws, without panicking.
#[test]
fn hand_made_charts_never_panic() {
    let source = std::fs::read_to_string(common::repo_dir().join("examples/traffic/traffic.st")).expect("example");
    let mut chart = chart_of(&source);
    chart.transitions[0].to.push(999);
    let first = chart.transitions[1].from[0];
    chart.transitions[1].from.push(first);
    chart.transitions[2].to.clear();
    chart.transitions[3].from.clear();
    let l = layout(&chart);
    assert_eq!(l.steps.len(), chart.steps.len());
    assert_eq!(l.transitions.len(), chart.transitions.len());
    assert!(svg(&chart, &l, &SvgOptions::default()).ends_with("</svg>\n"));

    chart.steps.clear();
    chart.transitions.clear();
    let l = layout(&chart);
    assert!(l.steps.is_empty() && l.width > 0.0 && l.height > 0.0);
    assert!(svg(&chart, &l, &SvgOptions::default()).ends_with("</svg>\n"));

    // Absurd font sizes are tamed.
    let chart = chart_of(&source);
    for font_size in [f64::NAN, -3.0, 0.0, 1.0e9] {
        let opts = sfc_render::LayoutOptions { font_size, ..Default::default() };
        let l = sfc_render::layout_with(&chart, &opts);
        assert!(l.width.is_finite() && l.height.is_finite() && l.font_size > 0.0 && l.font_size <= 200.0);
    }
}
