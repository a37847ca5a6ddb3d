//! The prover on fixture charts with known verdicts (`tests/fixtures/NAME.st`,
//! `NAME.props.toml`, `NAME.expected`), each verdict cross-checked by the explicit-state
//! explorer (`explorer/`) where the chart is small enough, and on random charts against the
//! explorer alone.
//!
//! `NAME.expected` has one line per checked property: the verdict, then the property's name;
//! a violated one may end with `after scan N` (the last scan of the shortest witness).
//! `NAME.codesys.expected`, when present, holds the verdicts of the same chart and properties
//! proved under the `codesys` profile (the explorer then runs the simulator under it too).

mod explorer;

use explorer::{explore, Found};
use sfc_prove::{Options, Verdict};
use std::path::{Path, PathBuf};

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let mut out: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("fixtures")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    out.sort();
    out
}

struct Expected {
    verdict: String,
    name: String,
    scan: Option<usize>,
}

fn expected(path: &Path) -> Vec<Expected> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let (verdict, rest) = l.split_once(' ').expect("verdict name");
            let (name, scan) = match rest.rsplit_once(" after scan ") {
                Some((n, s)) => (n.to_string(), s.trim().parse().ok()),
                None => (rest.to_string(), None),
            };
            Expected { verdict: verdict.to_string(), name: name.trim().to_string(), scan }
        })
        .collect()
}

/// The prover's time budget per chart. The fixtures' verdicts must not depend on the speed of
/// the machine: `st_loops` takes about 25 s in the unoptimised test build on a quiet machine and
/// ran out of a 60 s budget on a loaded one. The budget only guards against a hang.
const BUDGET_SECONDS: f64 = 900.0;

/// How many verdicts the explorer confirmed (over the whole state space or to the depth asked
/// for; `shallow` of them only to a smaller depth, the smallest `min_depth` scans, when its
/// state budget ran out first), and how many it could not judge.
#[derive(Default)]
struct Tally {
    confirmed: usize,
    shallow: usize,
    min_depth: Option<usize>,
    not_judged: usize,
}

impl Tally {
    fn count(&mut self, f: &Found, unknown: bool, depth: usize) {
        match f {
            Found::Skipped | Found::TooBig => self.not_judged += 1,
            _ if unknown => self.not_judged += 1,
            Found::NotWithin(d) if *d < depth => {
                self.confirmed += 1;
                self.shallow += 1;
                self.min_depth = Some(self.min_depth.map_or(*d, |m| m.min(*d)));
            }
            _ => self.confirmed += 1,
        }
    }
    fn add(&mut self, o: &Tally) {
        self.confirmed += o.confirmed;
        self.shallow += o.shallow;
        self.not_judged += o.not_judged;
        self.min_depth = match (self.min_depth, o.min_depth) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
    }
    fn describe(&self) -> String {
        format!(
            "the explorer agreed with {} verdicts ({} of them only to a smaller depth, at least {} scans, where its state budget ran out); {} were beyond it (a kind it does not explore, too many input values, or an unknown)",
            self.confirmed,
            self.shallow,
            self.min_depth.unwrap_or(0),
            self.not_judged
        )
    }
}

/// Runs one fixture, and again under `codesys` when it has a `NAME.codesys.expected`;
/// returns the failures.
fn run_fixture(st: &Path, tally: &mut Tally) -> Vec<String> {
    let mut fails = run_fixture_as(st, None, &st.with_extension("expected"), tally);
    let codesys = st.with_extension("codesys.expected");
    if codesys.exists() {
        fails.extend(run_fixture_as(st, Some(sfc_sim::Profile::Codesys), &codesys, tally));
    }
    fails
}

/// Runs one fixture under `profile` (else the property file's) against the verdicts of
/// `exp_path`; returns the failures.
fn run_fixture_as(st: &Path, profile: Option<sfc_sim::Profile>, exp_path: &Path, tally: &mut Tally) -> Vec<String> {
    let mut fails = Vec::new();
    let chart_text = std::fs::read_to_string(st).expect("chart");
    let props_path = st.with_extension("props.toml");
    let props_text = std::fs::read_to_string(&props_path).expect("props");
    let file =
        sfc_prove::props::parse(&props_path.display().to_string(), &props_text).unwrap_or_else(|e| panic!("{e}"));
    let chart_name = st.display().to_string();
    let report = match sfc_prove::prove(
        &chart_name,
        &chart_text,
        &file,
        &Options { seconds: BUDGET_SECONDS, profile, ..Default::default() },
    ) {
        Ok(r) => r,
        Err(e) => return vec![format!("{}: {e:?}", st.display())],
    };
    if std::env::var_os("SFC_PROVE_BLESS").is_some() {
        // Writes the verdicts as they are (review them before committing).
        let mut text = String::new();
        for p in &report.properties {
            let scan = p.witness.as_ref().filter(|w| w.write).map(|w| format!(" after scan {}", w.scans - 1));
            text.push_str(&format!("{} {}{}\n", p.verdict.name(), p.name, scan.unwrap_or_default()));
        }
        let _ = std::fs::write(exp_path, text);
    }
    let want = expected(exp_path);
    let stem = format!("{} ({})", st.file_stem().unwrap_or_default().to_string_lossy(), report.profile.name());
    for p in &report.properties {
        let got = p.verdict.name();
        let scan = p.witness.as_ref().filter(|w| w.write).map(|w| w.scans - 1);
        match want.iter().find(|w| w.name == p.name) {
            None => fails.push(format!("{stem}: `{}` is {got} but not in the .expected file", p.name)),
            Some(w) => {
                if w.verdict != got {
                    fails.push(format!("{stem}: `{}`: expected {}, got {got} ({})", p.name, w.verdict, p.message));
                }
                if let (Some(ws), Some(gs)) = (w.scan, scan) {
                    if ws != gs {
                        fails.push(format!(
                            "{stem}: `{}`: expected the witness to end after scan {ws}, got {gs}",
                            p.name
                        ));
                    }
                }
                // A goal no reachable situation satisfies has no finite witness.
                let unreachable_goal = file.properties.iter().any(|q| {
                    q.name == p.name && matches!(q.kind, sfc_prove::props::Kind::Reachable { from_initial: true, .. })
                });
                if p.verdict == Verdict::Violated && !(unreachable_goal && p.witness.is_none()) {
                    let replayed = p.witness.as_ref().is_some_and(|w| w.replayed);
                    if !replayed {
                        fails.push(format!("{stem}: `{}`: violated without a replayed witness", p.name));
                    }
                }
                if p.verdict == Verdict::Holds {
                    if let Some((_, ok)) = p.invariant {
                        if !ok {
                            fails.push(format!("{stem}: `{}`: holds but its invariant check failed", p.name));
                        }
                    }
                }
            }
        }
    }
    for w in &want {
        if !report.properties.iter().any(|p| p.name == w.name) {
            fails.push(format!("{stem}: expected a verdict for `{}`", w.name));
        }
    }
    // The explorer's independent opinion, where the state space is small.
    let names: Vec<String> = report.properties.iter().map(|p| p.name.clone()).collect();
    let depth = 40;
    let found = explore(
        &chart_name,
        &chart_text,
        &report.pou,
        report.period,
        &file,
        &report.inputs,
        &names,
        depth,
        8_000,
        report.profile,
    );
    for (p, f) in report.properties.iter().zip(&found) {
        if std::env::var_os("SFC_PROVE_EXPLAIN").is_some() {
            println!("{stem}: `{}`: the prover says {}, the explorer {f:?}", p.name, p.verdict.name());
        }
        tally.count(f, p.verdict == Verdict::Unknown, depth);
        let agree = match (p.verdict, f) {
            (_, Found::Skipped | Found::TooBig) => true,
            (Verdict::Violated, Found::ViolatedAt(s)) => {
                Some(*s) == p.witness.as_ref().map(|w| w.scans - 1) || p.witness.is_none()
            }
            (Verdict::Violated, Found::NotWithin(d)) => p.witness.as_ref().is_none_or(|w| w.scans > *d),
            (Verdict::Holds, Found::NotWithin(_)) => true,
            (Verdict::Holds, Found::ReachedAt(s)) => p.witness.as_ref().is_none_or(|w| w.scans - 1 == *s),
            (Verdict::Violated, Found::ReachedAt(_)) => false,
            (Verdict::Holds, Found::ViolatedAt(_)) => false,
            (Verdict::Unknown, _) => true,
        };
        if !agree {
            fails.push(format!(
                "{stem}: `{}`: the prover says {} ({}), the explorer {:?}",
                p.name,
                p.verdict.name(),
                p.message,
                f
            ));
        }
    }
    fails
}

#[test]
fn fixture_verdicts_agree_with_the_explorer() {
    let all = fixtures();
    assert!(all.len() >= 30, "at least 30 fixture charts, found {}", all.len());
    let only = std::env::var("SFC_PROVE_FIXTURE").ok();
    let chosen: Vec<&PathBuf> =
        all.iter().filter(|st| only.as_ref().is_none_or(|o| st.display().to_string().contains(o.as_str()))).collect();
    // The explorer takes seconds per chart in the unoptimised test build: the charts are shared
    // out to one thread per core (the test binaries of the workspace run one after another, so
    // the cores would otherwise idle).
    let next = std::sync::atomic::AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(chosen.len().max(1));
    let results: Vec<(Vec<String>, Tally)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let worker = std::thread::Builder::new().stack_size(16 << 20);
                worker
                    .spawn_scoped(scope, || {
                        let (mut fails, mut tally) = (Vec::new(), Tally::default());
                        loop {
                            let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                            let Some(st) = chosen.get(i) else { break };
                            fails.extend(run_fixture(st, &mut tally));
                        }
                        (fails, tally)
                    })
                    .expect("a fixture thread")
            })
            .collect();
        workers.into_iter().map(|w| w.join().expect("a fixture thread panicked")).collect()
    });
    let mut fails = Vec::new();
    let mut tally = Tally::default();
    for (f, t) in results {
        fails.extend(f);
        tally.add(&t);
    }
    fails.sort();
    println!("{} fixture charts (up to 40 scans, or over the whole state space): {}", all.len(), tally.describe());
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// A small deterministic generator (xorshift).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
}

/// A random chart: a loop of steps with a selection branch or a parallel pair, guards over
/// three inputs and step times, BOOL outputs driven by actions with assorted qualifiers.
/// `rich`: also bodies whose order matters, CODESYS's step actions and an action written in
/// SFC run by a step.
fn random_chart(seed: u64, rich: bool) -> (String, String) {
    let mut r = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let n = 3 + r.below(4) as usize;
    let inputs = ["A", "B", "C"];
    let mut s = String::from("PROGRAM R\n    VAR_INPUT\n        A : BOOL;\n        B : BOOL;\n        C : BOOL;\n    END_VAR\n    VAR_OUTPUT\n        O1 : BOOL;\n        O2 : BOOL;\n        K : INT;\n    END_VAR\n");
    let guard = |r: &mut Rng, k: usize| -> String {
        let a = inputs[r.below(3) as usize];
        match r.below(5) {
            0 => a.to_string(),
            1 => format!("NOT {a}"),
            2 => format!("{a} AND {}", inputs[r.below(3) as usize]),
            3 => format!("S{k}.T >= T#{}ms", 20 * (1 + r.below(3))),
            _ => format!("{a} OR S{k}.T > T#30ms"),
        }
    };
    let quals = ["N", "S", "R", "P1", "P0", "L, T#20ms", "D, T#20ms", "P"];
    let mut actions = Vec::new();
    for k in 0..n {
        let kw = if k == 0 { "INITIAL_STEP" } else { "STEP" };
        let mut body = String::new();
        if r.below(3) > 0 {
            let q = quals[r.below(quals.len() as u64) as usize];
            let out = if r.below(2) == 0 { "O1" } else { "O2" };
            if r.below(2) == 0 {
                body.push_str(&format!("        {out}({q});\n"));
            } else {
                let act = format!("Act{k}");
                body.push_str(&format!("        {act}({q});\n"));
                let op = if rich && r.below(2) == 0 { "K * 2 + 1" } else { "K + 1" };
                actions.push(format!("    ACTION {act}:\n        K := {op};\n        IF K > 5 THEN\n            K := 0;\n        END_IF;\n    END_ACTION\n"));
            }
        }
        if rich {
            for (kind, what) in [("ENTRY_ACTION", "En"), ("STEP_ACTION", "Do"), ("EXIT_ACTION", "Ex")] {
                if r.below(4) == 0 {
                    let act = format!("{what}{k}");
                    body.push_str(&format!("        {kind} := {act};\n"));
                    let stmt = match r.below(3) {
                        0 => "O2 := NOT O2;".to_string(),
                        1 => "K := K + 2;\n        IF K > 5 THEN\n            K := 1;\n        END_IF;".to_string(),
                        _ => "O1 := K > 2;".to_string(),
                    };
                    actions.push(format!("    ACTION {act}:\n        {stmt}\n    END_ACTION\n"));
                }
            }
            if k == 1 {
                body.push_str("        Sub(N);\n");
            }
        }
        s.push_str(&format!("    {kw} S{k}:\n{body}    END_STEP\n"));
    }
    if rich {
        actions.push(
            "    ACTION Sub:\n        INITIAL_STEP SubA: END_STEP\n        TRANSITION FROM SubA TO SubB := B; END_TRANSITION\n        STEP SubB:\n            SubTick(P1);\n        END_STEP\n        TRANSITION FROM SubB TO SubA := NOT B OR SubB.T > T#20ms; END_TRANSITION\n    END_ACTION\n    ACTION SubTick:\n        K := K + 1;\n        IF K > 5 THEN\n            K := 0;\n        END_IF;\n    END_ACTION\n"
                .to_string(),
        );
    }
    for k in 0..n {
        let next = (k + 1) % n;
        s.push_str(&format!(
            "    TRANSITION FROM S{k} TO S{next}\n        := {};\n    END_TRANSITION\n",
            guard(&mut r, k)
        ));
        if r.below(3) == 0 && n > 2 {
            let other = (k + 2) % n;
            s.push_str(&format!(
                "    TRANSITION FROM S{k} TO S{other}\n        := {};\n    END_TRANSITION\n",
                guard(&mut r, k)
            ));
        }
    }
    for a in actions {
        s.push_str(&a);
    }
    s.push_str("END_PROGRAM\n");
    let a = r.below(n as u64);
    let b = (a + 1 + r.below(n as u64 - 1)) % n as u64;
    let props = format!(
        "period = \"T#10ms\"\n{}\n[[property]]\nname = \"exclusive\"\nnever = \"S{a}.X AND S{b}.X\"\n\n[[property]]\nname = \"outputs\"\nnever = \"O1 AND O2 AND S{a}.X\"\n\n[[property]]\nname = \"response\"\nafter = \"{}\"\nexpect = \"S{b}.X OR O1\"\nscans = {}\n\n[[property]]\nname = \"counter\"\nalways = \"K <= 5\"\n\n[[property]]\nname = \"reach\"\nreachable = \"S{b}.X AND O2\"\nfrom_initial = true\n",
        if rich {
            format!(
                "\n[[property]]\nname = \"sub\"\nnever = \"SubB.X AND S{a}.X AND O1\"\n\n[[property]]\nname = \"sub reach\"\nreachable = \"SubB.X AND NOT S1.X\"\nfrom_initial = true\n"
            )
        } else {
            String::new()
        },
        inputs[r.below(3) as usize],
        r.below(4)
    );
    (s, props)
}

#[test]
fn random_charts_agree_with_the_explorer() {
    random_charts(sfc_sim::Profile::Iec, 1, false);
}

/// Random charts with step actions and an action written in SFC, under `iec`.
#[test]
fn rich_random_charts_agree_with_the_explorer() {
    random_charts(sfc_sim::Profile::Iec, 2001, true);
}

/// The random charts under `codesys`, with their seeds shifted (other charts than the `iec`
/// test's).
#[test]
fn random_charts_agree_with_the_explorer_under_codesys() {
    random_charts(sfc_sim::Profile::Codesys, 1001, true);
}

fn random_charts(profile: sfc_sim::Profile, first: u64, rich: bool) {
    // The rich charts have more states: fewer of them, explored less far (the explorer takes
    // most of the time).
    let (default, max_states) = if rich { (4, 20_000) } else { (8, 20_000) };
    let count: u64 = std::env::var("SFC_PROVE_RANDOM").ok().and_then(|v| v.parse().ok()).unwrap_or(default);
    let mut fails = Vec::new();
    let mut tally = Tally::default();
    for seed in first..first + count {
        let (chart, props) = random_chart(seed, rich);
        let file = sfc_prove::props::parse("random.props.toml", &props).expect("props");
        let name = format!("random{seed}.st");
        let opts = Options { seconds: BUDGET_SECONDS, profile: Some(profile), ..Default::default() };
        let report = match sfc_prove::prove(&name, &chart, &file, &opts) {
            Ok(r) => r,
            Err(e) => {
                fails.push(format!("seed {seed}: {e:?}\n{chart}"));
                continue;
            }
        };
        let names: Vec<String> = report.properties.iter().map(|p| p.name.clone()).collect();
        let found =
            explore(&name, &chart, &report.pou, report.period, &file, &report.inputs, &names, 30, max_states, profile);
        for (p, f) in report.properties.iter().zip(&found) {
            tally.count(f, p.verdict == Verdict::Unknown, 30);
            let scans = p.witness.as_ref().map(|w| w.scans - 1);
            let ok = match (p.verdict, f) {
                (_, Found::Skipped | Found::TooBig) => true,
                (Verdict::Violated, Found::ViolatedAt(s)) => {
                    scans == Some(*s) && p.witness.as_ref().is_some_and(|w| w.replayed)
                }
                (Verdict::Holds, Found::NotWithin(_)) => true,
                (Verdict::Holds, Found::ReachedAt(s)) => scans == Some(*s),
                // A goal no reachable situation satisfies: violated without a finite witness.
                (Verdict::Violated, Found::NotWithin(d)) => scans.is_none_or(|s| s >= *d),
                _ => false,
            };
            if !ok {
                fails.push(format!(
                    "seed {seed} ({}): `{}`: the prover says {} {:?} ({}), the explorer {:?}\n{chart}\n{props}",
                    profile.name(),
                    p.name,
                    p.verdict.name(),
                    scans,
                    p.message,
                    f
                ));
            }
        }
    }
    println!(
        "{count} random charts ({}{}): {}",
        profile.name(),
        if rich { ", with step actions and an action written in SFC" } else { "" },
        tally.describe()
    );
    assert!(fails.is_empty(), "{}", fails.join("\n\n"));
}

/// Development aid: prints the rich random chart of `SFC_PROVE_SEED` with its properties.
#[test]
fn print_random_chart() {
    let Some(seed) = std::env::var("SFC_PROVE_SEED").ok().and_then(|v| v.parse().ok()) else { return };
    let (chart, props) = random_chart(seed, true);
    println!("{chart}\n----\n{props}");
}
