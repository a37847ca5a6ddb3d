//! Tests of the net analysis (`sfc_analysis::net`).
//!
//! * `tests/net/*.st`: charts a user could write, with the expected findings inline:
//!   `(*! unsafe S3 via T1,T4 *)`, `(*! unreachable S9 *)`, `(*! dead T7 *)`,
//!   `(*! lockup {S2,S5} via T1,T2 *)` (`via -` for an empty witness), `(*! none *)`,
//!   `(*! method structure *)` (or `explicit`, `symbolic`), `(*! together A,B *)`,
//!   `(*! apart A,B *)`. Findings are compared exactly, witnesses by transition name, and the
//!   explicit and symbolic methods must agree with the automatic one.
//! * Every example and every valid fixture of the project reports nothing.
//! * A brute-force enumerator of the exact set semantics (every set of enabled transitions with
//!   disjoint presets fires) on random small nets, against all three methods.
//! * Random block-structured charts: the certificate against the explicit search, and mutated
//!   ones: whenever the certificate still claims a proof, the search must agree.

use sfc_analysis::net::{analyze_net, analyze_net_with, Method, NetOptions, NetReport, Strategy};
use sfc_diagnostics::Span;
use sfc_model::{Chart, StepNode, Target, TransitionNode};
use sfc_syntax::ast;
use std::collections::{BTreeSet, HashMap, HashSet, VecDeque};
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------------------------------------
// Helpers

fn mk_chart(n: usize, initial: &[usize], trans: &[(Vec<usize>, Vec<usize>)]) -> Chart {
    let span = Span::default();
    Chart {
        file: 0,
        item: 0,
        pou: "Random".into(),
        pou_kind: ast::PouKind::Program,
        action: None,
        target: Target::Blank,
        steps: (0..n)
            .map(|i| StepNode {
                step_actions: Vec::new(),
                name: format!("S{i}"),
                initial: initial.contains(&i),
                associations: Vec::new(),
                tag: None,
                timeout: None,
                min_time: None,
                is_final: false,
                interlock: None,
                supervision: None,
                attributes: Vec::new(),
                name_span: span,
                span,
            })
            .collect(),
        transitions: trans
            .iter()
            .enumerate()
            .map(|(i, (f, t))| TransitionNode {
                name: format!("T{i}"),
                named: true,
                priority: None,
                from: f.clone(),
                to: t.clone(),
                condition: ast::Condition::Missing,
                tag: None,
                attributes: Vec::new(),
                header_span: span,
                span,
            })
            .collect(),
        actions: Vec::new(),
        name_span: span,
        span,
        logix: Default::default(),
        s7graph: Default::default(),
    }
}

/// splitmix64
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn chance(&mut self, percent: usize) -> bool {
        self.below(100) < percent
    }
}

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn check_text(name: &str, text: &str) -> Vec<Chart> {
    let opts = sfc_model::CheckOptions::default();
    sfc_model::check_source(0, name, text, &opts).charts
}

fn no_findings(r: &NetReport) -> bool {
    r.complete && r.unsafe_steps.is_empty() && r.unreachable.is_empty() && r.dead.is_empty() && r.lockups.is_empty()
}

/// Every (a, b) pair, as the report's concurrency relation answers it.
fn relation(chart: &Chart, r: &NetReport) -> Vec<Vec<bool>> {
    let n = chart.steps.len();
    (0..n).map(|a| (0..n).map(|b| r.concurrency.together(a, b)).collect()).collect()
}

// ---------------------------------------------------------------------------------------------
// Brute force: the exact set semantics, no interleaving argument.

struct Brute {
    n: usize,
    pre: Vec<u32>,
    post: Vec<u32>,
    /// Reachable situations (all sets of enabled, preset-disjoint transitions fire).
    reach: BTreeSet<u32>,
    unsafe_steps: BTreeSet<usize>,
    /// Scans to each situation in the graph of single transitions and strongly connected groups.
    dist: HashMap<u32, usize>,
    nets: Vec<u32>,
    has_out: u32,
}

impl Brute {
    fn enabled(&self, x: u32, t: usize) -> bool {
        self.pre[t] != 0 && self.pre[t] & !x == 0
    }
    /// Every non-empty set of enabled transitions with pairwise disjoint presets.
    fn firings(&self, x: u32) -> Vec<Vec<usize>> {
        let en: Vec<usize> = (0..self.pre.len()).filter(|&t| self.enabled(x, t)).collect();
        let mut out = Vec::new();
        for mask in 1u32..(1 << en.len()) {
            let f: Vec<usize> = (0..en.len()).filter(|&i| mask >> i & 1 == 1).map(|i| en[i]).collect();
            let mut used = 0u32;
            let mut ok = true;
            for &t in &f {
                if used & self.pre[t] != 0 {
                    ok = false;
                }
                used |= self.pre[t];
            }
            if ok {
                out.push(f);
            }
        }
        out
    }
    fn fire(&self, x: u32, f: &[usize]) -> (u32, u32) {
        let d = f.iter().fold(0, |a, &t| a | self.pre[t]);
        let a = f.iter().fold(0, |a, &t| a | self.post[t]);
        let mut twice = 0u32;
        for (i, &t) in f.iter().enumerate() {
            for &u in &f[i + 1..] {
                twice |= self.post[t] & self.post[u];
            }
        }
        ((x & !d) | a, (a & x & !d) | twice)
    }
    fn is_group(&self, f: &[usize]) -> bool {
        let k = f.len();
        if k < 2 {
            return false;
        }
        for i in 0..k {
            for j in i + 1..k {
                if self.pre[f[i]] & self.pre[f[j]] != 0 {
                    return false;
                }
            }
        }
        // transitive closure of "posts into the preset of"
        let mut r = vec![vec![false; k]; k];
        for i in 0..k {
            for j in 0..k {
                r[i][j] = i == j || self.post[f[i]] & self.pre[f[j]] != 0;
            }
        }
        for m in 0..k {
            for i in 0..k {
                for j in 0..k {
                    if r[i][m] && r[m][j] {
                        r[i][j] = true;
                    }
                }
            }
        }
        r.iter().all(|row| row.iter().all(|&b| b))
    }

    fn new(chart: &Chart) -> Brute {
        let n = chart.steps.len();
        let mask = |v: &[usize]| v.iter().filter(|&&s| s < n).fold(0u32, |m, &s| m | 1 << s);
        let pre: Vec<u32> = chart.transitions.iter().map(|t| mask(&t.from)).collect();
        let post: Vec<u32> = chart.transitions.iter().map(|t| mask(&t.to)).collect();
        let init = mask(&chart.initial_steps());
        let mut b = Brute {
            n,
            pre,
            post,
            reach: BTreeSet::new(),
            unsafe_steps: BTreeSet::new(),
            dist: HashMap::new(),
            nets: Vec::new(),
            has_out: 0,
        };
        // networks
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], x: usize) -> usize {
            if p[x] == x {
                x
            } else {
                let r = find(p, p[x]);
                p[x] = r;
                r
            }
        }
        for t in 0..b.pre.len() {
            if b.pre[t] == 0 {
                continue;
            }
            b.has_out |= b.pre[t];
            let all = b.pre[t] | b.post[t];
            let first = all.trailing_zeros() as usize;
            for s in 0..n {
                if all >> s & 1 == 1 {
                    let (x, y) = (find(&mut parent, first), find(&mut parent, s));
                    parent[x] = y;
                }
            }
        }
        let mut nets: HashMap<usize, u32> = HashMap::new();
        for s in 0..n {
            let r = find(&mut parent, s);
            *nets.entry(r).or_default() |= 1 << s;
        }
        b.nets = nets.into_values().collect();
        if init == 0 {
            return b;
        }
        // exact reachable set with all firings
        let mut queue = VecDeque::from([init]);
        b.reach.insert(init);
        while let Some(x) = queue.pop_front() {
            for f in b.firings(x) {
                let (y, bad) = b.fire(x, &f);
                for s in 0..n {
                    if bad >> s & 1 == 1 {
                        b.unsafe_steps.insert(s);
                    }
                }
                if b.reach.insert(y) {
                    queue.push_back(y);
                }
            }
        }
        // hybrid distances: singletons and strongly connected groups
        b.dist.insert(init, 0);
        let mut queue = VecDeque::from([init]);
        while let Some(x) = queue.pop_front() {
            let d = b.dist[&x];
            for f in b.firings(x) {
                if f.len() > 1 && !b.is_group(&f) {
                    continue;
                }
                let (y, _) = b.fire(x, &f);
                if let std::collections::hash_map::Entry::Vacant(e) = b.dist.entry(y) {
                    e.insert(d + 1);
                    queue.push_back(y);
                }
            }
        }
        b
    }

    fn net_of(&self, s: usize) -> u32 {
        self.nets.iter().copied().find(|m| m >> s & 1 == 1).unwrap_or(0)
    }

    /// Lock-up situations per network, with their shortest scan counts.
    fn lockups(&self) -> HashMap<u32, usize> {
        let mut out: HashMap<u32, usize> = HashMap::new();
        for &x in &self.reach {
            for &net in &self.nets {
                let y = x & net;
                if y & self.has_out == 0 {
                    continue;
                }
                let any = (0..self.pre.len()).any(|t| self.pre[t] & !net == 0 && self.enabled(x, t));
                if any {
                    continue;
                }
                let d = self.dist[&x];
                let e = out.entry(y).or_insert(d);
                *e = (*e).min(d);
            }
        }
        out
    }

    /// Shortest scans before an unsafe single firing at `s`.
    fn unsafe_dist(&self, s: usize) -> Option<usize> {
        let mut best: Option<usize> = None;
        for &x in &self.reach {
            for t in 0..self.pre.len() {
                if self.enabled(x, t) && ((self.post[t] & x & !self.pre[t]) >> s) & 1 == 1 {
                    let d = self.dist[&x] + 1;
                    best = Some(best.map_or(d, |b| b.min(d)));
                }
            }
        }
        best
    }

    /// All situations reachable by a segmentation of `w` into scans with `scans` scans in all.
    fn replay(&self, init: u32, w: &[usize]) -> Vec<(u32, usize)> {
        let mut out = Vec::new();
        let mut stack = vec![(0usize, init, 0usize)];
        while let Some((i, x, k)) = stack.pop() {
            if i == w.len() {
                out.push((x, k));
                continue;
            }
            for j in i + 1..=w.len() {
                let g = &w[i..j];
                if j > i + 1 && !(g.windows(2).all(|p| p[0] < p[1]) && self.is_group(g)) {
                    continue;
                }
                if g.iter().all(|&t| t < self.pre.len() && self.enabled(x, t)) {
                    let (y, _) = self.fire(x, g);
                    stack.push((j, y, k + 1));
                }
            }
        }
        out
    }
}

fn init_mask(chart: &Chart) -> u32 {
    chart.initial_steps().iter().fold(0, |m, &s| m | 1 << s)
}

/// Compares one report with the brute force; returns a description of the first difference.
fn compare(chart: &Chart, b: &Brute, r: &NetReport, what: &str) -> Result<(), String> {
    if !r.complete {
        return Err(format!("{what}: incomplete"));
    }
    let n = b.n;
    let init = init_mask(chart);
    let reached = b.reach.iter().fold(0u32, |m, &x| m | x);
    let unreachable: Vec<usize> = if init == 0 { vec![] } else { (0..n).filter(|&s| reached >> s & 1 == 0).collect() };
    if r.unreachable != unreachable {
        return Err(format!("{what}: unreachable {:?}, expected {:?}", r.unreachable, unreachable));
    }
    let dead: Vec<usize> = if init == 0 {
        vec![]
    } else {
        (0..b.pre.len()).filter(|&t| !b.reach.iter().any(|&x| b.enabled(x, t))).collect()
    };
    if r.dead != dead {
        return Err(format!("{what}: dead {:?}, expected {:?}", r.dead, dead));
    }
    let got_unsafe: BTreeSet<usize> = r.unsafe_steps.iter().map(|u| u.step).collect();
    if got_unsafe != b.unsafe_steps {
        return Err(format!("{what}: unsafe {got_unsafe:?}, expected {:?}", b.unsafe_steps));
    }
    for u in &r.unsafe_steps {
        let want = b.unsafe_dist(u.step).ok_or(format!("{what}: no unsafe firing at {}", u.step))?;
        if u.witness.last() != Some(&u.transition) {
            return Err(format!("{what}: unsafe witness {:?} does not end with {}", u.witness, u.transition));
        }
        let t = u.transition;
        let prefix = &u.witness[..u.witness.len() - 1];
        let ok = b
            .replay(init, prefix)
            .into_iter()
            .any(|(x, k)| k + 1 == want && b.enabled(x, t) && ((b.post[t] & x & !b.pre[t]) >> u.step) & 1 == 1);
        if !ok {
            return Err(format!("{what}: unsafe witness {:?} for S{} is not a shortest ({want})", u.witness, u.step));
        }
    }
    // lock-ups
    let all = b.lockups();
    let got: Vec<u32> = r.lockups.iter().map(|l| l.situation.iter().fold(0u32, |m, &s| m | 1 << s)).collect();
    let got_set: HashSet<u32> = got.iter().copied().collect();
    if got_set.len() != got.len() {
        return Err(format!("{what}: duplicate lock-ups {got:?}"));
    }
    if all.len() <= 10 {
        let want: HashSet<u32> = all.keys().copied().collect();
        if got_set != want {
            return Err(format!("{what}: lock-ups {got:?}, expected {want:?}"));
        }
    } else {
        if got.len() != 10 || !got.iter().all(|y| all.contains_key(y)) {
            return Err(format!("{what}: lock-ups {got:?} are not 10 of {:?}", all.keys()));
        }
        let worst = got.iter().map(|y| all[y]).max().unwrap_or(0);
        if all.iter().any(|(y, &d)| !got_set.contains(y) && d < worst) {
            return Err(format!("{what}: a shorter lock-up was left out"));
        }
    }
    let mut last = 0;
    for l in &r.lockups {
        let y = l.situation.iter().fold(0u32, |m, &s| m | 1 << s);
        let want = all[&y];
        if want < last {
            return Err(format!("{what}: lock-ups not shortest first"));
        }
        last = want;
        let net = b.net_of(l.situation[0]);
        let ok = b.replay(init, &l.witness).into_iter().any(|(x, k)| k == want && x & net == y);
        if !ok {
            return Err(format!("{what}: lock-up witness {:?} for {:?} is not a shortest ({want})", l.witness, y));
        }
    }
    // concurrency
    for a in 0..n {
        for c in 0..n {
            let want = b.reach.iter().any(|&x| x >> a & 1 == 1 && x >> c & 1 == 1);
            if r.concurrency.together(a, c) != want {
                return Err(format!("{what}: together(S{a}, S{c}) should be {want}"));
            }
        }
    }
    Ok(())
}

fn random_net(rng: &mut Rng) -> Chart {
    let n = 2 + rng.below(6);
    let m = 1 + rng.below(8);
    let pick = |rng: &mut Rng, empty: usize| {
        let k = match rng.below(100) {
            x if x < empty => 0,
            x if x < 62 => 1,
            x if x < 90 => 2,
            _ => 3,
        };
        let mut v: Vec<usize> = (0..k).map(|_| rng.below(n)).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let trans: Vec<(Vec<usize>, Vec<usize>)> = (0..m).map(|_| (pick(rng, 4), pick(rng, 6))).collect();
    let mut initial = vec![rng.below(n)];
    if rng.chance(30) {
        initial.push(rng.below(n));
    }
    mk_chart(n, &initial, &trans)
}

#[test]
fn brute_force_random_nets() {
    let seed = env_usize("NET_BRUTE_SEED", 4004) as u64;
    let cases = env_usize("NET_BRUTE_CASES", 2000);
    let mut rng = Rng(seed);
    let opts = NetOptions::default();
    let mut groups_seen = 0;
    let mut unsafe_seen = 0;
    let mut lockups_seen = 0;
    for case in 0..cases {
        let chart = random_net(&mut rng);
        let b = Brute::new(&chart);
        // The theory: single transitions plus strongly connected groups reach exactly the
        // situations of the set semantics.
        let hybrid: BTreeSet<u32> = b.dist.keys().copied().collect();
        assert_eq!(hybrid, b.reach, "case {case}: group scans must give the exact reachable set: {chart:?}");
        if b.reach.iter().any(|&x| b.firings(x).iter().any(|f| b.is_group(f))) {
            groups_seen += 1;
        }
        unsafe_seen += usize::from(!b.unsafe_steps.is_empty());
        lockups_seen += usize::from(!b.lockups().is_empty());
        let explicit = analyze_net_with(&chart, &opts, Strategy::Explicit);
        let symbolic = analyze_net_with(&chart, &opts, Strategy::Symbolic);
        let auto = analyze_net(&chart, &opts);
        let describe = |e: String| {
            let t: Vec<String> =
                chart.transitions.iter().map(|t| format!("{}:{:?}->{:?}", t.name, t.from, t.to)).collect();
            format!("case {case} (seed {seed}): {e}\n  init {:?}\n  {}", chart.initial_steps(), t.join("\n  "))
        };
        for (r, what) in [(&explicit, "explicit"), (&symbolic, "symbolic"), (&auto, "auto")] {
            if let Err(e) = compare(&chart, &b, r, what) {
                panic!("{}", describe(e));
            }
        }
        // Explicit and symbolic choose the same (lexicographically smallest) witnesses.
        assert_eq!(explicit.unsafe_steps, symbolic.unsafe_steps, "{}", describe("unsafe witnesses differ".into()));
        assert_eq!(explicit.lockups, symbolic.lockups, "{}", describe("lock-ups differ".into()));
        assert_eq!(explicit.unsafe_steps, auto.unsafe_steps, "{}", describe("auto unsafe differs".into()));
        assert_eq!(explicit.lockups, auto.lockups, "{}", describe("auto lock-ups differ".into()));
    }
    // The generator must exercise what it is meant to.
    if cases >= 1000 {
        assert!(groups_seen > 0, "no case with a group scan");
        assert!(unsafe_seen > cases / 20, "too few unsafe cases: {unsafe_seen}");
        assert!(lockups_seen > cases / 20, "too few lock-up cases: {lockups_seen}");
    }
}

// ---------------------------------------------------------------------------------------------
// Random block-structured charts

struct Gen {
    max_steps: usize,
    steps: usize,
    trans: Vec<(Vec<usize>, Vec<usize>)>,
}

impl Gen {
    fn step(&mut self) -> usize {
        self.steps += 1;
        self.steps - 1
    }
    fn link(&mut self, from: Vec<usize>, to: Vec<usize>) {
        self.trans.push((from, to));
    }
    /// A well-nested block; returns its entry and exit steps.
    fn block(&mut self, rng: &mut Rng, depth: usize) -> (usize, usize) {
        let choice = if depth == 0 || self.steps > self.max_steps { 0 } else { rng.below(6) };
        match choice {
            1 => {
                let (e1, x1) = self.block(rng, depth - 1);
                let (e2, x2) = self.block(rng, depth - 1);
                self.link(vec![x1], vec![e2]);
                (e1, x2)
            }
            2 => {
                let d = self.step();
                let k = 2 + rng.below(2);
                let mut ends = Vec::new();
                for _ in 0..k {
                    if rng.chance(25) {
                        ends.push(None);
                    } else {
                        let (e, x) = self.block(rng, depth - 1);
                        self.link(vec![d], vec![e]);
                        ends.push(Some(x));
                    }
                }
                let c = self.step();
                for x in ends {
                    match x {
                        Some(x) => self.link(vec![x], vec![c]),
                        None => self.link(vec![d], vec![c]),
                    }
                }
                (d, c)
            }
            3 | 4 => {
                let p = self.step();
                let k = 2 + rng.below(2);
                let branches: Vec<(usize, usize)> = (0..k).map(|_| self.block(rng, depth - 1)).collect();
                let q = self.step();
                self.link(vec![p], branches.iter().map(|b| b.0).collect());
                self.link(branches.iter().map(|b| b.1).collect(), vec![q]);
                (p, q)
            }
            5 => {
                let (e, x) = self.block(rng, depth - 1);
                self.link(vec![x], vec![e]);
                (e, x)
            }
            _ => {
                let s = self.step();
                (s, s)
            }
        }
    }
}

fn random_block_chart(rng: &mut Rng, max_steps: usize) -> Chart {
    let mut g = Gen { max_steps, steps: 0, trans: Vec::new() };
    let (e, x) = g.block(rng, 4);
    match rng.below(4) {
        0 => {} // the sequence ends: a normal end
        1 => {
            // open simultaneous block: branches that loop or end
            let k = 2 + rng.below(2);
            let mut entries = Vec::new();
            for _ in 0..k {
                let (be, bx) = g.block(rng, 2);
                if rng.chance(60) {
                    g.link(vec![bx], vec![be]);
                }
                entries.push(be);
            }
            g.link(vec![x], entries);
        }
        _ => g.link(vec![x], vec![e]),
    }
    // a second network sometimes
    let mut initial = vec![e];
    if rng.chance(25) {
        let (e2, x2) = g.block(rng, 2);
        g.link(vec![x2], vec![e2]);
        initial.push(e2);
    }
    // shuffle step ids so declaration order is not the structure's order
    let n = g.steps;
    let mut perm: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = rng.below(i + 1);
        perm.swap(i, j);
    }
    let trans: Vec<(Vec<usize>, Vec<usize>)> = g
        .trans
        .iter()
        .map(|(f, t)| (f.iter().map(|&s| perm[s]).collect(), t.iter().map(|&s| perm[s]).collect()))
        .collect();
    let initial: Vec<usize> = initial.iter().map(|&s| perm[s]).collect();
    mk_chart(n, &initial, &trans)
}

#[test]
fn block_structured_charts_are_certified_and_agree_with_the_search() {
    let seed = env_usize("NET_BLOCK_SEED", 61131) as u64;
    let cases = env_usize("NET_BLOCK_CASES", 400);
    let mut rng = Rng(seed);
    let opts = NetOptions::default();
    for case in 0..cases {
        let chart = random_block_chart(&mut rng, 40);
        let auto = analyze_net(&chart, &opts);
        let explicit = analyze_net_with(&chart, &opts, Strategy::Explicit);
        assert_eq!(auto.method, Method::Structure, "case {case}: not certified: {chart:#?}");
        assert!(no_findings(&auto), "case {case}");
        assert!(no_findings(&explicit), "case {case}: the search finds something: {explicit:?}");
        assert_eq!(relation(&chart, &auto), relation(&chart, &explicit), "case {case}: concurrency differs");
    }
}

#[test]
fn mutated_block_charts_never_get_a_false_certificate() {
    let seed = env_usize("NET_BLOCK_SEED", 61131) as u64 ^ 0x5555;
    let cases = env_usize("NET_BLOCK_CASES", 400) * 5;
    let mut rng = Rng(seed);
    let opts = NetOptions::default();
    let mut certified = 0;
    let mut rejected = 0;
    for case in 0..cases {
        let base = random_block_chart(&mut rng, 24);
        let n = base.steps.len();
        let mut trans: Vec<(Vec<usize>, Vec<usize>)> =
            base.transitions.iter().map(|t| (t.from.clone(), t.to.clone())).collect();
        match rng.below(4) {
            0 if trans.len() > 1 => {
                let i = rng.below(trans.len());
                trans.remove(i);
            }
            1 if !trans.is_empty() => {
                // redirect one end of a transition
                let i = rng.below(trans.len());
                if rng.chance(50) {
                    let k = rng.below(trans[i].1.len().max(1));
                    if let Some(s) = trans[i].1.get_mut(k) {
                        *s = rng.below(n);
                    }
                } else {
                    let k = rng.below(trans[i].0.len().max(1));
                    if let Some(s) = trans[i].0.get_mut(k) {
                        *s = rng.below(n);
                    }
                }
            }
            _ => {
                let from: Vec<usize> = (0..1 + rng.below(2)).map(|_| rng.below(n)).collect();
                let to: Vec<usize> = (0..1 + rng.below(2)).map(|_| rng.below(n)).collect();
                trans.push((from, to));
            }
        }
        let initial = base.initial_steps();
        let chart = mk_chart(n, &initial, &trans);
        let cert = analyze_net_with(&chart, &opts, Strategy::Structure);
        if !cert.complete {
            rejected += 1;
            continue;
        }
        // The certificate proved every network (a safe chart: the search finishes quickly).
        certified += 1;
        let explicit = analyze_net_with(&chart, &opts, Strategy::Explicit);
        assert!(explicit.complete, "case {case}: certified, but the search does not finish");
        assert_eq!(cert.unsafe_steps, explicit.unsafe_steps, "case {case}");
        assert_eq!(cert.unreachable, explicit.unreachable, "case {case}");
        assert_eq!(cert.dead, explicit.dead, "case {case}");
        assert_eq!(cert.lockups, explicit.lockups, "case {case}");
        assert_eq!(relation(&chart, &cert), relation(&chart, &explicit), "case {case}: concurrency differs");
    }
    assert!(certified > cases / 10 && rejected > cases / 10, "certified {certified}, rejected {rejected}");
}

// ---------------------------------------------------------------------------------------------
// Budget, erroneous charts, networks

/// `k` independent-looking loops of `len` steps started by one simultaneous divergence, with a
/// synchronising shortcut between neighbours (not block-structured).
fn irregular_loops(k: usize, len: usize) -> Chart {
    let n = 1 + k * len;
    let step = |i: usize, j: usize| 1 + i * len + j;
    let mut trans = vec![(vec![0], (0..k).map(|i| step(i, 0)).collect::<Vec<_>>())];
    for i in 0..k {
        for j in 0..len {
            trans.push((vec![step(i, j)], vec![step(i, (j + 1) % len)]));
        }
        if i + 1 < k {
            trans.push((vec![step(i, len / 2), step(i + 1, 1)], vec![step(i, len / 2 + 1), step(i + 1, 2)]));
        }
    }
    mk_chart(n, &[0], &trans)
}

#[test]
fn budget_exhausted_is_reported_as_incomplete() {
    let chart = irregular_loops(6, 6);
    let small = NetOptions { max_states: 500 };
    let r = analyze_net_with(&chart, &small, Strategy::Explicit);
    assert!(!r.complete);
    assert!(r.unreachable.is_empty() && r.dead.is_empty());
    assert!(r.concurrency.together(1, 2), "unknown must answer true");
    assert!(matches!(r.method, Method::Explicit { states } if states <= 500));
    // The automatic strategy goes symbolic and decides it.
    let r = analyze_net(&chart, &small);
    assert!(r.complete, "{r:?}");
    assert!(matches!(r.method, Method::Symbolic { states } if states == 6f64.powi(6) + 1.0), "{:?}", r.method);
    assert!(no_findings(&r));
    assert!(r.concurrency.together(1, 7) && !r.concurrency.together(1, 2) && !r.concurrency.together(0, 1));
}

#[test]
fn erroneous_charts_do_not_panic_and_follow_the_conventions() {
    // T0 has no valid source step: never enabled, reported dead. T2 activates nothing.
    let chart = mk_chart(3, &[0], &[(vec![7], vec![1]), (vec![0], vec![1, 1, 9]), (vec![1], vec![])]);
    for s in [Strategy::Auto, Strategy::Explicit, Strategy::Symbolic] {
        let r = analyze_net_with(&chart, &NetOptions::default(), s);
        assert!(r.complete);
        assert_eq!(r.dead, vec![0], "{s:?}");
        assert_eq!(r.unreachable, vec![2], "{s:?}");
        assert!(r.lockups.is_empty() && r.unsafe_steps.is_empty(), "{s:?}: the empty situation is a normal end");
    }
    // No steps, no initial step: nothing to analyse.
    let r = analyze_net(&mk_chart(0, &[], &[]), &NetOptions::default());
    assert_eq!(r.method, Method::Empty);
    let r = analyze_net(&mk_chart(2, &[], &[(vec![0], vec![1])]), &NetOptions::default());
    assert_eq!(r.method, Method::Empty);
    assert!(no_findings(&r) && !r.concurrency.together(0, 0));
    // Out-of-range queries.
    assert!(!r.concurrency.together(5, 0));
    // A network without an initial step next to one with.
    let chart = mk_chart(4, &[0], &[(vec![0], vec![1]), (vec![1], vec![0]), (vec![2], vec![3]), (vec![3], vec![2])]);
    let r = analyze_net(&chart, &NetOptions::default());
    assert_eq!(r.unreachable, vec![2, 3]);
    assert_eq!(r.dead, vec![2, 3]);
    assert!(!r.concurrency.together(0, 2) && r.concurrency.together(0, 0) && !r.concurrency.together(2, 2));
}

#[test]
fn lockups_of_several_networks_are_merged_shortest_first_and_capped() {
    // 12 networks, each locking up after i + 1 scans: A_i0 → … → A_i(i+1), then a convergence
    // that needs a step never reached.
    let mut trans = Vec::new();
    let mut initial = Vec::new();
    let mut n = 0;
    let mut expect = Vec::new();
    for i in 0..12 {
        let base = n;
        let len = i + 2;
        n += len + 1; // + the missing partner
        initial.push(base);
        let mut w = Vec::new();
        for j in 0..len - 1 {
            w.push(trans.len());
            trans.push((vec![base + j], vec![base + j + 1]));
        }
        trans.push((vec![base + len - 1, base + len], vec![base]));
        expect.push((vec![base + len - 1], w));
    }
    let chart = mk_chart(n, &initial, &trans);
    for s in [Strategy::Auto, Strategy::Explicit, Strategy::Symbolic] {
        let r = analyze_net_with(&chart, &NetOptions::default(), s);
        let got: Vec<(Vec<usize>, Vec<usize>)> =
            r.lockups.iter().map(|l| (l.situation.clone(), l.witness.clone())).collect();
        assert_eq!(got, expect[..10].to_vec(), "{s:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// Fixtures

#[derive(Debug, Default, PartialEq)]
struct Expected {
    unsafe_steps: Vec<(String, Vec<String>)>,
    unreachable: Vec<String>,
    dead: Vec<String>,
    lockups: Vec<(Vec<String>, Vec<String>)>,
}

fn names(list: &str) -> Vec<String> {
    if list.trim() == "-" {
        return Vec::new();
    }
    list.split(',').map(|s| s.trim().to_ascii_uppercase()).filter(|s| !s.is_empty()).collect()
}

fn actual(chart: &Chart, r: &NetReport) -> Expected {
    let step = |s: usize| chart.steps[s].name.to_ascii_uppercase();
    let tr = |t: usize| chart.transitions[t].name.to_ascii_uppercase();
    Expected {
        unsafe_steps: r
            .unsafe_steps
            .iter()
            .map(|u| (step(u.step), u.witness.iter().map(|&t| tr(t)).collect()))
            .collect(),
        unreachable: r.unreachable.iter().map(|&s| step(s)).collect(),
        dead: r.dead.iter().map(|&t| tr(t)).collect(),
        lockups: r
            .lockups
            .iter()
            .map(|l| {
                let mut sit: Vec<String> = l.situation.iter().map(|&s| step(s)).collect();
                sit.sort();
                (sit, l.witness.iter().map(|&t| tr(t)).collect())
            })
            .collect(),
    }
}

fn run_fixture(path: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let charts = check_text(&path.display().to_string(), &text);
    let [chart] = charts.as_slice() else {
        return Err(format!("expected one chart, found {}", charts.len()));
    };
    let mut want = Expected::default();
    let mut none = false;
    let mut method = None;
    let mut relations = Vec::new();
    let mut annotations = 0;
    for piece in text.split("(*!").skip(1) {
        let body = piece.split("*)").next().unwrap_or("").trim();
        annotations += 1;
        let (kw, rest) = body.split_once(char::is_whitespace).unwrap_or((body, ""));
        let rest = rest.trim();
        match kw {
            "none" => none = true,
            "unsafe" => {
                let (s, via) = rest.split_once(" via ").ok_or(format!("bad annotation `{body}`"))?;
                want.unsafe_steps.push((s.trim().to_ascii_uppercase(), names(via)));
            }
            "unreachable" => want.unreachable.extend(names(rest)),
            "dead" => want.dead.extend(names(rest)),
            "lockup" => {
                let (sit, via) = rest.split_once(" via ").ok_or(format!("bad annotation `{body}`"))?;
                let mut sit = names(sit.trim().trim_start_matches('{').trim_end_matches('}'));
                sit.sort();
                want.lockups.push((sit, names(via)));
            }
            "method" => method = Some(rest.to_ascii_lowercase()),
            "together" | "apart" => relations.push((kw == "together", names(rest))),
            _ => return Err(format!("unknown annotation `{body}`")),
        }
    }
    if annotations == 0 {
        return Err("no expectation written in the fixture".into());
    }
    let order = |name: &String, by_step: bool| {
        if by_step {
            chart.step(name).unwrap_or(usize::MAX)
        } else {
            chart.transition(name).unwrap_or(usize::MAX)
        }
    };
    want.unsafe_steps.sort_by_key(|u| order(&u.0, true));
    want.unreachable.sort_by_key(|s| order(s, true));
    want.dead.sort_by_key(|t| order(t, false));
    if none && want != Expected::default() {
        return Err("`none` together with findings".into());
    }
    let opts = NetOptions::default();
    let auto = analyze_net(chart, &opts);
    if !auto.complete {
        return Err("incomplete".into());
    }
    let got = actual(chart, &auto);
    if got != want {
        return Err(format!("findings differ\n  expected {want:?}\n  actual   {got:?}"));
    }
    if let Some(m) = method {
        let ok = match m.as_str() {
            "structure" => auto.method == Method::Structure,
            "explicit" => matches!(auto.method, Method::Explicit { .. }),
            "symbolic" => matches!(auto.method, Method::Symbolic { .. }),
            _ => false,
        };
        if !ok {
            return Err(format!("method {:?}, expected {m}", auto.method));
        }
    }
    for (together, pair) in relations {
        let [a, b] = pair.as_slice() else { return Err("together/apart needs two steps".into()) };
        let (Some(a), Some(b)) = (chart.step(a), chart.step(b)) else {
            return Err(format!("unknown step in {pair:?}"));
        };
        if auto.concurrency.together(a, b) != together {
            return Err(format!("together({pair:?}) should be {together}"));
        }
    }
    for s in [Strategy::Explicit, Strategy::Symbolic] {
        let r = analyze_net_with(chart, &opts, s);
        let other = actual(chart, &r);
        if other != got {
            return Err(format!("{s:?} differs: {other:?}"));
        }
        if relation(chart, &r) != relation(chart, &auto) {
            return Err(format!("{s:?}: concurrency differs"));
        }
    }
    Ok(())
}

fn st_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            st_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "st") {
            out.push(p);
        }
    }
}

#[test]
fn fixtures() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/net");
    let mut files = Vec::new();
    st_files(&dir, &mut files);
    files.sort();
    assert!(files.len() >= 10, "fixtures missing in {}", dir.display());
    let mut failures = Vec::new();
    for f in &files {
        if let Err(e) = run_fixture(f) {
            failures.push(format!("{}: {e}", f.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn examples_and_valid_fixtures_report_nothing() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    st_files(&root.join("examples"), &mut files);
    st_files(&root.join("tests/fixtures/valid"), &mut files);
    files.sort();
    assert!(files.len() >= 20, "examples and fixtures not found under {}", root.display());
    let mut charts_seen = 0;
    let mut failures = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap_or_default();
        for chart in check_text(&f.display().to_string(), &text) {
            charts_seen += 1;
            let r = analyze_net(&chart, &NetOptions::default());
            if !no_findings(&r) {
                failures.push(format!("{} ({}): {:?}", f.display(), chart.pou, actual(&chart, &r)));
            }
        }
    }
    assert!(charts_seen >= 20, "only {charts_seen} charts");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
