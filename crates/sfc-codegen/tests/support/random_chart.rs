//! Random block-structured charts, shared by the tests that run them (`tests/st.rs` in the
//! simulator against their ST translation; `sfc-cli/tests/st_compilers.rs` compiled by MatIEC
//! and STruC++): sequences, selections with priorities, simultaneous branches, loops, jumps; all
//! eleven qualifiers with literal and variable durations, BOOL variables as actions, bodies in ST
//! with RETURN and in IL with jumps, guards in ST and IL reading inputs, step times, step flags,
//! action flags and counters; supervision times, SFCInit/SFCPause/SFCQuitError; sometimes the
//! chart is a FUNCTION_BLOCK `Chart` called by a PROGRAM `Main` only in some scans.
//!
//! Case `k` is `random_chart(&mut Rng::for_case(k), 14)`, its inputs drawn after the chart from
//! the same generator by [`RandomInputs`]: the same seed gives the same chart and inputs in every
//! test that uses this file.
#![allow(dead_code)]

use std::fmt::Write as _;

pub struct Rng(pub u64);

impl Rng {
    /// The generator of random case `case` (the seeds of `random_charts_behave_identically`).
    pub fn for_case(case: usize) -> Rng {
        Rng((case as u64 + 1).wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x5DEE_CE66_D1CE_5EED)
    }
    pub fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    pub fn chance(&mut self, percent: usize) -> bool {
        self.below(100) < percent
    }
    pub fn pick<T: Clone>(&mut self, v: &[T]) -> T {
        v[self.below(v.len())].clone()
    }
}

pub const INPUTS: usize = 6;
const DURATIONS_MS: [i64; 7] = [0, 10, 20, 25, 30, 50, 80];
const GUARD_MS: [i64; 6] = [0, 10, 20, 30, 40, 60];
const QUALS: [&str; 11] = ["N", "R", "S", "L", "D", "P", "SD", "DS", "SL", "P1", "P0"];
const VAR_QUALS: [&str; 9] = ["N", "R", "S", "L", "D", "P", "SD", "DS", "SL"];

struct Tr {
    from: Vec<usize>,
    to: Vec<usize>,
    priority: Option<u32>,
    guard: String,
    il: Option<String>,
}

struct Gen<'r> {
    rng: &'r mut Rng,
    steps: Vec<(bool, usize)>,
    trs: Vec<Tr>,
    actions: usize,
    max_steps: usize,
}

impl Gen<'_> {
    fn step(&mut self, initial: bool, network: usize) -> usize {
        self.steps.push((initial, network));
        self.steps.len() - 1
    }

    fn atom(&mut self, from: &[usize]) -> String {
        match self.rng.below(14) {
            0 => "TRUE".into(),
            1..=3 => format!("S{}.T >= T#{}ms", self.rng.pick(from), self.rng.pick(&GUARD_MS)),
            4 => format!("S{}.X", self.rng.below(self.steps.len())),
            5 if self.actions > 0 => {
                format!("a{}.{}", self.rng.below(self.actions), if self.rng.chance(50) { "Q" } else { "A" })
            }
            6 => format!("o{}", self.rng.below(3)),
            7 => format!("n{} > {}", self.rng.below(2), self.rng.below(6)),
            8 => format!("n{} / 2 >= {}", self.rng.below(2), self.rng.below(3)),
            _ => format!("i{}", self.rng.below(INPUTS)),
        }
    }

    fn guard(&mut self, from: &[usize], depth: u32) -> String {
        if depth < 2 && self.rng.chance(35) {
            let a = self.guard(from, depth + 1);
            return match self.rng.below(4) {
                0 => format!("NOT ({a})"),
                1 => format!("({a}) AND ({})", self.guard(from, depth + 1)),
                2 => format!("({a}) XOR ({})", self.guard(from, depth + 1)),
                _ => format!("({a}) OR ({})", self.guard(from, depth + 1)),
            };
        }
        self.atom(from)
    }

    fn il_guard(&mut self) -> String {
        let mut s = format!("        LD{} i{}\n", if self.rng.chance(30) { "N" } else { "" }, self.rng.below(INPUTS));
        for _ in 0..self.rng.below(3) {
            let op = self.rng.pick(&["AND", "ANDN", "OR", "ORN", "XOR"]);
            if self.rng.chance(25) {
                s.push_str(&format!(
                    "        {op}( i{}\n        OR o{}\n        )\n",
                    self.rng.below(INPUTS),
                    self.rng.below(3)
                ));
            } else {
                s.push_str(&format!("        {op} i{}\n", self.rng.below(INPUTS)));
            }
        }
        s
    }

    fn transition(&mut self, from: Vec<usize>, to: Vec<usize>) {
        let (guard, il) =
            if self.rng.chance(15) { (String::new(), Some(self.il_guard())) } else { (self.guard(&from, 0), None) };
        let key = |t: &Tr| (t.from.clone(), t.to.clone(), t.guard.clone(), t.il.clone());
        let tr = Tr { from, to, priority: None, guard, il };
        if self.trs.iter().any(|t| key(t) == key(&tr)) {
            return;
        }
        self.trs.push(tr);
    }

    fn sequence(&mut self, entry: usize, depth: u32, net: usize) -> usize {
        let mut cur = entry;
        let mut chain = vec![entry];
        for _ in 0..1 + self.rng.below(3) {
            if self.steps.len() >= self.max_steps {
                break;
            }
            match self.rng.below(10) {
                4 | 5 if depth < 2 => {
                    let join = self.step(false, net);
                    let mut ends = Vec::new();
                    for b in 0..2 + self.rng.below(2) {
                        if b > 0 && self.rng.chance(15) {
                            self.transition(vec![cur], vec![join]);
                            continue;
                        }
                        let first = self.step(false, net);
                        self.transition(vec![cur], vec![first]);
                        ends.push(self.sequence(first, depth + 1, net));
                    }
                    for e in ends {
                        self.transition(vec![e], vec![join]);
                    }
                    cur = join;
                    chain.push(join);
                }
                6 | 7 if depth < 2 => {
                    let firsts: Vec<usize> = (0..2 + self.rng.below(2)).map(|_| self.step(false, net)).collect();
                    self.transition(vec![cur], firsts.clone());
                    let ends: Vec<usize> = firsts.iter().map(|&f| self.sequence(f, depth + 1, net)).collect();
                    let join = self.step(false, net);
                    self.transition(ends, vec![join]);
                    cur = join;
                    chain.push(join);
                }
                8 | 9 if chain.len() >= 2 => {
                    let target = self.rng.pick(&chain);
                    self.transition(vec![cur], vec![target]);
                }
                _ => {
                    let next = self.step(false, net);
                    self.transition(vec![cur], vec![next]);
                    cur = next;
                    chain.push(next);
                }
            }
        }
        cur
    }
}

/// Action bodies: counters, copies of flags, RETURN inside and outside loops, IL with jumps.
pub fn action_body(rng: &mut Rng, a: usize) -> String {
    match rng.below(6) {
        0 => format!(
            "        n{a2} := n{a2} + 1;\n        q{a} := a{a}.Q;\n        IF i{i} THEN\n            RETURN;\n        END_IF;\n        n2 := n2 + 1;\n",
            a2 = a % 2,
            i = rng.below(INPUTS)
        ),
        1 => format!(
            "        FOR k := 1 TO 3 DO\n            IF i{i} AND k = 2 THEN\n                RETURN; (* leaves the action *)\n            END_IF;\n            n2 := n2 + 1;\n        END_FOR;\n        q{a} := a{a}.Q;\n",
            i = rng.below(INPUTS)
        ),
        2 => format!(
            "        LD n{a2}\n        ADD 1\n        ST n{a2}\n        GT 4\n        JMPC Big\n        LD a{a}.Q\n        ST q{a}\n        RET\nBig:    LD 0\n        ST n{a2}\n        LD i{i}\n        ANDN q{a}\n        ST q{a}\n",
            a2 = a % 2,
            i = rng.below(INPUTS)
        ),
        3 => format!("        LD i{i}\n        OR( a{a}.Q\n        AND S{s}.X\n        )\n        ST q{a}\n        S o{o}\n        LD n2\n        ADD 2\n        ST n2\n", i = rng.below(INPUTS), s = 0, o = rng.below(3)),
        _ => format!(
            "        n{a2} := n{a2} + 1;\n        q{a} := a{a}.Q AND NOT a{a}.A OR S0.X;\n        IF S0.T > T#20ms THEN\n            n2 := n2 + 10;\n        END_IF;\n        IF i3 THEN\n            d0 := d0 + T#10ms; (* a duration that changes while its timer runs *)\n        ELSE\n            d0 := T#20ms;\n        END_IF;\n",
            a2 = a % 2
        ),
    }
}

/// A random chart as IEC text, and whether it is a FUNCTION_BLOCK called by `Main`.
pub fn random_chart(rng: &mut Rng, max_steps: usize) -> (String, bool) {
    let actions = rng.below(4);
    let mut g = Gen { rng, steps: Vec::new(), trs: Vec::new(), actions, max_steps };
    let networks = if g.rng.chance(20) { 2 } else { 1 };
    for net in 0..networks {
        let init = g.step(true, net);
        let last = g.sequence(init, 0, net);
        g.transition(vec![last], vec![init]);
    }
    if g.rng.chance(20) {
        let from = g.rng.below(g.steps.len());
        let same: Vec<usize> = (0..g.steps.len()).filter(|&s| g.steps[s].1 == g.steps[from].1).collect();
        let to = g.rng.pick(&same);
        g.transition(vec![from], vec![to]);
    }
    if g.rng.chance(40) {
        for t in 0..g.trs.len() {
            if g.rng.chance(50) {
                g.trs[t].priority = Some(g.rng.below(4) as u32);
            }
        }
    }
    let supervised = g.rng.chance(30);
    let control = supervised || g.rng.chance(20);
    let fb = g.rng.chance(30);
    let rng = g.rng;
    let mut t = String::new();
    let kind = if fb { "FUNCTION_BLOCK" } else { "PROGRAM" };
    writeln!(t, "{kind} Chart").unwrap();
    writeln!(t, "    VAR_INPUT").unwrap();
    for i in 0..INPUTS {
        writeln!(t, "        i{i} : BOOL;").unwrap();
    }
    writeln!(t, "    END_VAR").unwrap();
    writeln!(t, "    VAR_OUTPUT\n        o0, o1, o2 : BOOL;\n        n0, n1 : INT;\n    END_VAR").unwrap();
    writeln!(t, "    VAR\n        n2 : INT;\n        k : INT;\n        d0 : TIME := T#30ms;").unwrap();
    for a in 0..actions {
        writeln!(t, "        q{a} : BOOL;").unwrap();
    }
    writeln!(t, "    END_VAR").unwrap();
    if control {
        writeln!(t, "    (* driven through SFCInit, SFCPause and SFCQuitError; SFCError reports timeouts *)").unwrap();
    }
    for (s, (initial, _)) in g.steps.iter().enumerate() {
        if supervised && rng.chance(40) {
            writeln!(t, "    {{attribute 'sfc.timeout' := 'T#{}ms'}}", rng.pick(&[20, 40, 70])).unwrap();
        }
        writeln!(t, "    {} S{s}:", if *initial { "INITIAL_STEP" } else { "STEP" }).unwrap();
        let mut used = Vec::new();
        for _ in 0..rng.pick(&[0, 0, 1, 1, 2, 3]) {
            let target = rng.below(actions + 3);
            if used.contains(&target) {
                continue;
            }
            used.push(target);
            let (name, q) = if target < actions {
                (format!("a{target}"), rng.pick(&QUALS))
            } else {
                (format!("o{}", target - actions), rng.pick(&VAR_QUALS))
            };
            let timed = matches!(q, "L" | "D" | "SD" | "DS" | "SL");
            if timed {
                let d = if rng.chance(20) { "d0".to_string() } else { format!("T#{}ms", rng.pick(&DURATIONS_MS)) };
                writeln!(t, "        {name}({q}, {d});").unwrap();
            } else {
                writeln!(t, "        {name}({q});").unwrap();
            }
        }
        writeln!(t, "    END_STEP").unwrap();
    }
    for (k, tr) in g.trs.iter().enumerate() {
        let list = |v: &[usize]| {
            let n: Vec<String> = v.iter().map(|s| format!("S{s}")).collect();
            if n.len() > 1 {
                format!("({})", n.join(", "))
            } else {
                n[0].clone()
            }
        };
        let prio = tr.priority.map(|p| format!(" (PRIORITY := {p})")).unwrap_or_default();
        let guard = if supervised && rng.chance(15) { format!("({}) OR SFCError", tr.guard) } else { tr.guard.clone() };
        match &tr.il {
            Some(il) => writeln!(
                t,
                "    TRANSITION Tr{k}{prio} FROM {} TO {}:\n{il}    END_TRANSITION",
                list(&tr.from),
                list(&tr.to)
            )
            .unwrap(),
            None => writeln!(
                t,
                "    TRANSITION Tr{k}{prio} FROM {} TO {} := {guard}; END_TRANSITION",
                list(&tr.from),
                list(&tr.to)
            )
            .unwrap(),
        }
    }
    for a in 0..actions {
        writeln!(t, "    ACTION a{a}:\n{}    END_ACTION", action_body(rng, a)).unwrap();
    }
    writeln!(t, "END_{kind}").unwrap();
    if fb {
        let ins: Vec<String> = (0..INPUTS).map(|i| format!("i{i} := i{i}")).collect();
        let ctl = if control { ", SFCInit := init, SFCPause := pause, SFCQuitError := quit" } else { "" };
        writeln!(
            t,
            "\nPROGRAM Main\n    VAR_INPUT\n        i0, i1, i2, i3, i4, i5, run, init, pause, quit : BOOL;\n    END_VAR\n    VAR\n        c : Chart;\n        busy : BOOL;\n        m0 : INT;\n    END_VAR\n    IF run THEN\n        c({}{ctl});\n    END_IF;\n    busy := c.o0;\n    m0 := c.n0;\nEND_PROGRAM",
            ins.join(", ")
        )
        .unwrap();
    }
    (t, fb)
}

/// The inputs of a random chart, flipped at random scan after scan: `i0`…`i5`, and `run` (the
/// call of the chart FB), `init`/`pause`/`quit` of `Main` or `SFCInit`/`SFCPause`/
/// `SFCQuitError` of the chart when it has control variables.
pub struct RandomInputs {
    pub names: Vec<String>,
    values: Vec<bool>,
}

impl RandomInputs {
    /// For the chart `text` returned by [`random_chart`] with `fb`.
    pub fn new(text: &str, fb: bool) -> RandomInputs {
        let control = text.contains("SFCInit");
        let mut names: Vec<String> = (0..INPUTS).map(|i| format!("i{i}")).collect();
        if fb {
            names.push("run".into());
            if control {
                names.extend(["init", "pause", "quit"].map(String::from));
            }
        } else if control {
            names.extend(["SFCInit", "SFCPause", "SFCQuitError"].map(String::from));
        }
        let values = vec![false; names.len()];
        RandomInputs { names, values }
    }

    /// The writes before scan `scan` (call it for scan 0, 1, 2… in order).
    pub fn next(&mut self, rng: &mut Rng, scan: u64) -> Vec<(String, bool)> {
        let mut w = Vec::new();
        for (k, v) in self.values.iter_mut().enumerate() {
            let n = &self.names[k];
            let p = match n.as_str() {
                "run" => 25,
                "init" | "pause" | "quit" | "SFCInit" | "SFCPause" | "SFCQuitError" => {
                    if *v {
                        50
                    } else {
                        4
                    }
                }
                _ => 20,
            };
            if scan == 0 && n == "run" || rng.chance(p) {
                *v = !*v;
                w.push((n.clone(), *v));
            }
        }
        w
    }
}

/// Every `*.scenario.toml` under `dir`, sorted (the scenarios both tests run the ST on).
pub fn scenario_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.to_string_lossy().ends_with(".scenario.toml") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}
