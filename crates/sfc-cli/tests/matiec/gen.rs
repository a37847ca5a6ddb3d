//! Random charts for the differential test against MatIEC: every qualifier (with durations
//! written in several spellings), explicit priorities (0 included), selection and simultaneous
//! divergences and convergences, loops, step-time guards (`S.T` against literals, whole seconds
//! included), step flags in guards, ACTIONs whose bodies count their runs, BOOL variables used as
//! actions. Shaped to what MatIEC accepts: the chart starts with its initial step, every step is
//! declared before the transitions that name it, TIME literals have no `us`.

/// A small deterministic generator (xorshift64*), so a seed always gives the same chart.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    pub fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

pub const INPUTS: [&str; 4] = ["I1", "I2", "I3", "I4"];
const PERIODS: [(&str, i64); 4] = [("T#10ms", 10), ("T#20ms", 20), ("T#50ms", 50), ("T#100ms", 100)];
const DURATIONS: [&str; 18] = [
    "T#0s", "T#10ms", "T#20ms", "T#25ms", "T#30ms", "T#40ms", "T#50ms", "T#70ms", "T#100ms", "T#0.1s", "T#0.03s",
    "T#150ms", "T#0.2s", "T#250ms", "T#1s", "T#1.5s", "T#2s", "T#0.5s",
];
const QUALIFIERS: [&str; 11] = ["N", "R", "S", "L", "D", "P", "SD", "DS", "SL", "P1", "P0"];

/// One generated chart: its text, period and the input values per scan.
pub struct Generated {
    pub text: String,
    pub period: String,
    pub scans: usize,
    /// Per scan: the inputs written before it (only changes).
    pub sets: Vec<Vec<(String, bool)>>,
}

pub fn chart(seed: u64) -> Generated {
    let mut r = Rng::new(seed);
    let n_steps = 3 + r.below(6);
    let n_actions = 1 + r.below(3);
    let n_vars = 1 + r.below(3);
    let (period, _) = *r.pick(&PERIODS);
    let mut text = format!("PROGRAM R{seed}\n    VAR_INPUT\n");
    for i in INPUTS {
        text.push_str(&format!("        {i} : BOOL;\n"));
    }
    text.push_str("    END_VAR\n    VAR\n");
    for v in 1..=n_vars {
        text.push_str(&format!("        Y{v} : BOOL;\n"));
    }
    for a in 1..=n_actions {
        text.push_str(&format!("        C{a} : INT;\n"));
    }
    text.push_str("    END_VAR\n\n");
    let step = |i: usize| format!("S{i}");
    // Steps with their associations.
    for s in 0..n_steps {
        let kw = if s == 0 { "INITIAL_STEP" } else { "STEP" };
        let mut assocs = Vec::new();
        for _ in 0..r.below(4) {
            let target =
                if r.chance(60) { format!("A{}", 1 + r.below(n_actions)) } else { format!("Y{}", 1 + r.below(n_vars)) };
            let q = *r.pick(&QUALIFIERS);
            let timed = matches!(q, "L" | "D" | "SD" | "DS" | "SL");
            if timed {
                assocs.push(format!("{target}({q}, {})", r.pick(&DURATIONS)));
            } else {
                assocs.push(format!("{target}({q})"));
            }
        }
        if assocs.is_empty() {
            text.push_str(&format!("    {kw} {}: END_STEP\n", step(s)));
        } else {
            text.push_str(&format!("    {kw} {}:\n", step(s)));
            for a in assocs {
                text.push_str(&format!("        {a};\n"));
            }
            text.push_str("    END_STEP\n");
        }
    }
    text.push('\n');
    // Transitions: a spine S0 → S1 → … keeps every step in the initial step's network; every
    // step gets up to three ways out, some of them divergences or convergences.
    let mut k = 0;
    let mut trans = Vec::new();
    let mut links: Vec<(String, String)> = Vec::new();
    for s in 0..n_steps {
        let outs = 1 + r.below(3);
        for o in 0..outs {
            k += 1;
            let prio = if r.chance(30) { format!(" (PRIORITY := {})", r.below(4)) } else { String::new() };
            let from;
            let to;
            if o == 0 && s + 1 < n_steps {
                from = step(s);
                to = step(s + 1);
            } else if r.chance(15) && n_steps >= 4 {
                let a = r.below(n_steps);
                let b = (a + 1 + r.below(n_steps - 1)) % n_steps;
                if r.chance(50) {
                    // Simultaneous divergence.
                    from = step(s);
                    to = format!("({}, {})", step(a), step(b));
                } else {
                    // Convergence of s and another step.
                    let b = if a == s { (s + 1) % n_steps } else { a };
                    from = format!("({}, {})", step(s), step(b));
                    to = step(r.below(n_steps));
                }
            } else {
                from = step(s);
                to = if r.chance(25) { step(0) } else { step(r.below(n_steps)) };
            }
            let guard = guard(&mut r, s, n_steps);
            // Two transitions with the same steps before and after are one too many.
            if links.contains(&(from.clone(), to.clone())) {
                continue;
            }
            links.push((from.clone(), to.clone()));
            trans.push(format!(
                "    TRANSITION T{k}{prio} FROM {from} TO {to}\n        := {guard};\n    END_TRANSITION\n"
            ));
        }
    }
    for t in trans {
        text.push_str(&t);
    }
    text.push('\n');
    for a in 1..=n_actions {
        text.push_str(&format!("    ACTION A{a}:\n        C{a} := C{a} + 1;\n    END_ACTION\n"));
    }
    text.push_str("END_PROGRAM\n");
    let scans = 50;
    let mut sets = Vec::new();
    let mut values = [false; 4];
    for k in 0..scans {
        let mut row = Vec::new();
        for (i, name) in INPUTS.iter().enumerate() {
            if (k == 0 && r.chance(30)) || (k > 0 && r.chance(15)) {
                values[i] = !values[i];
                row.push((name.to_string(), values[i]));
            }
        }
        sets.push(row);
    }
    Generated { text, period: period.to_string(), scans, sets }
}

fn guard(r: &mut Rng, s: usize, n: usize) -> String {
    let other = format!("S{}", r.below(n));
    let own = format!("S{s}");
    let input = |r: &mut Rng| {
        let i = *r.pick(&INPUTS);
        if r.chance(30) {
            format!("NOT {i}")
        } else {
            i.to_string()
        }
    };
    let time = |r: &mut Rng, st: &str| {
        let op = *r.pick(&[">", ">=", "<", "<="]);
        format!("{st}.T {op} {}", r.pick(&DURATIONS))
    };
    match r.below(9) {
        0 => "TRUE".to_string(),
        1 | 2 => input(r),
        3 => format!("{} AND {}", input(r), input(r)),
        4 => format!("{} OR {}", input(r), input(r)),
        5 | 6 => time(r, &own),
        7 => format!("{} AND {}", input(r), time(r, &own)),
        _ => format!("{other}.X OR {}", input(r)),
    }
}
