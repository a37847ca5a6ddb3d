//! The Structured Text of `sfc build --target st` compiled by two real IEC 61131-3 compilers,
//! run, and compared scan by scan with `sfc sim --profile iec` of the original chart.
//!
//! * `generated_st_runs_like_the_chart`: the compilers are MatIEC's `iec2c` (Beremiz, OpenPLC v3;
//!   ST to C, compiled by gcc) and STruC++ (OpenPLC v4; ST to C++17, compiled by g++), built from
//!   the snapshots in `../shared/tools` into `target/tools/` by their scripts (the first time takes
//!   a few minutes; a tool that cannot be built fails the test with the script's message). The
//!   cases: every scenario of `examples/`, of the simulator's semantics fixtures and of
//!   `tests/st_compilers/` (a chart for each problem this test found) whose profile is `iec`,
//!   the fixtures of `sfc-codegen/tests/st/` with random inputs, and random charts (the
//!   generator of `sfc-codegen/tests/st.rs`, shared through
//!   `sfc-codegen/tests/support/random_chart.rs`). Each case's POUs are renamed (`Chart` →
//!   `Chart_17`) so that all cases make one ST file per compiler (one copy of the helper
//!   declarations `SfcStep`/`SfcActionControl`), one C or C++ driver runs every case on its
//!   inputs with the scenario's period and prints, per scan, the step flags and the variables;
//!   the trace must equal `sfc sim --profile iec`'s: the active steps (a step is active when its
//!   `X` is TRUE, steps of chart instances as `inst.Step`), every elementary variable of the
//!   simulated POU (TIME in µs, REAL to single precision).
//!   MatIEC compiles the ST of `--st-dialect matiec`, STruC++ that of `--st-dialect strucpp`
//!   (the CONFIGURATION the former adds to each case becomes one with every case's program).
//!   MatIEC's output must be accepted with Beremiz's options
//!   (`-f -l -p`) and with OpenPLC v3's (`-f -l -p -r -R -a`); the C of the former runs.
//!   Charts `sfc build --target st` refuses as CODESYS-only (SFC0806) and files without an SFC
//!   POU to build are counted and listed, not compared.
//!   Located variables get addresses of their own per case (`%IX0.1` → `%IX17000.1`).
//!   `SFC_ST_COMPILERS_CASES=N` sets the number of random charts (default 40;
//!   `SFC_ST_COMPILERS_FULL=1`: 300), `SFC_ST_COMPILERS_ONLY=text` keeps the cases whose name
//!   contains it, `SFC_ST_COMPILERS_SCENARIOS=dir,…` adds the scenarios of other directories
//!   (`iec` profile) as cases. The work files (each case's chart, scenario, ST; the batch ST, C/C++, driver
//!   and a report) are under `target/tmp/st-compilers/`.
//! * `matiec_sfc_bug_is_gone_through_st`: `tests/st_compilers/alternatives.st`, where MatIEC's own
//!   SFC compilation fires every TRUE alternative (docs/sim.md, "The `matiec` profile", #2): its
//!   SFC compiled directly by `iec2c` runs like `--profile matiec` and unlike `--profile iec`,
//!   and the same chart through `sfc build --target st` and `iec2c` runs like `--profile iec`.

#[path = "../../sfc-codegen/tests/support/random_chart.rs"]
mod random_chart;

mod common;

use serde_json::Value as Json;
use sfc_sim::{format_time, parse_time, Profile, SimOptions, Simulation, Value};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::Instant;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

fn work_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

// ---------------------------------------------------------------------------------------------
// Processes

/// Runs `cmd`; `Ok(stdout)` when it succeeds, else `Err(stdout + stderr)`.
fn sh(cmd: &mut Command) -> Result<String, String> {
    let out = cmd.stdin(Stdio::null()).output().map_err(|e| format!("{cmd:?}: {e}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if out.status.success() {
        Ok(stdout)
    } else {
        Err(format!("{stdout}{}", String::from_utf8_lossy(&out.stderr)))
    }
}

/// Runs `cmd` with a time limit, its output kept to `limit` bytes (iec2c can print an error
/// forever). `Ok(stdout)` or `Err(output)`.
fn sh_bounded(cmd: &[&str], secs: u32, limit: usize, dir: &Path) -> Result<String, String> {
    let script = format!(
        "timeout {secs} \"$@\" 2>&1 | head -c {limit}; s=${{PIPESTATUS[0]}}; \
         if [ $s -eq 124 ]; then echo \"(stopped: no answer in {secs} s)\"; fi; exit $s"
    );
    sh(Command::new("bash").arg("-c").arg(script).arg("bash").args(cmd).current_dir(dir))
}

struct Tools {
    iec2c: PathBuf,
    matiec_lib: PathBuf,
    /// `node …/cli.js`
    strucpp: Vec<String>,
    strucpp_include: PathBuf,
}

/// Both compilers, built once per process (the tests of this file run on parallel threads).
fn tools() -> &'static Tools {
    static TOOLS: std::sync::OnceLock<Tools> = std::sync::OnceLock::new();
    TOOLS.get_or_init(build_tools)
}

/// Builds (or finds already built) both compilers with the scripts of `../shared/tools`, into
/// `target/tools/` of the workspace. Panics with the script's message when one cannot be built.
fn build_tools() -> Tools {
    let scripts = root().join("../shared/tools");
    let dest = root().join("target/tools");
    let build = |script: &str, dir: &str| -> String {
        let path = scripts.join(script);
        assert!(
            path.exists(),
            "{} is missing: the compilers to test against come from ../shared/tools",
            path.display()
        );
        let out = Command::new("bash").arg(&path).arg(dest.join(dir)).stdin(Stdio::null()).output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout).trim().to_string();
        assert!(
            out.status.success() && !stdout.is_empty(),
            "{script} could not build {dir}:\n{}{stdout}",
            String::from_utf8_lossy(&out.stderr)
        );
        stdout.lines().last().unwrap().to_string()
    };
    let iec2c = PathBuf::from(build("build-matiec.sh", "matiec"));
    let strucpp: Vec<String> = build("build-strucpp.sh", "strucpp").split_whitespace().map(String::from).collect();
    let matiec_lib = iec2c.parent().unwrap().join("lib");
    let strucpp_include = dest.join("strucpp/src/runtime/include");
    assert!(matiec_lib.join("C/iec_std_lib.h").exists(), "no MatIEC library in {}", matiec_lib.display());
    assert!(strucpp_include.join("iec_std_lib.hpp").exists(), "no STruC++ runtime in {}", strucpp_include.display());
    Tools { iec2c, matiec_lib, strucpp, strucpp_include }
}

fn sfc() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sfc"));
    c.env("NO_COLOR", "1");
    c
}

// ---------------------------------------------------------------------------------------------
// A light IEC lexer: identifiers outside comments, strings and pragmas

#[derive(Clone, Copy, PartialEq)]
enum Tok {
    Ident,
    Number,
    Punct(u8),
}

/// `(kind, start, end)` byte ranges of the tokens of `text`.
fn lex(text: &str) -> Vec<(Tok, usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c == b'(' && b.get(i + 1) == Some(&b'*') {
            i = text[i + 2..].find("*)").map(|e| i + 2 + e + 2).unwrap_or(b.len());
        } else if c == b'/' && b.get(i + 1) == Some(&b'/') {
            i = text[i..].find('\n').map(|e| i + e).unwrap_or(b.len());
        } else if c == b'{' {
            i = text[i..].find('}').map(|e| i + e + 1).unwrap_or(b.len());
        } else if c == b'\'' || c == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != c {
                j += if b[j] == b'$' { 2 } else { 1 };
            }
            i = j + 1;
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let s = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push((Tok::Ident, s, i));
        } else if c.is_ascii_digit() {
            let s = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_' || b[i] == b'#') {
                i += 1;
            }
            out.push((Tok::Number, s, i));
        } else {
            out.push((Tok::Punct(c), i, i + 1));
            i += 1;
        }
    }
    out
}

/// The POUs and data types `text` declares: `(kind, name)`, kind upper-case (`TYPE` for types).
fn declared(text: &str) -> Vec<(String, String)> {
    let toks = lex(text);
    let word = |k: usize| -> String {
        toks.get(k).filter(|t| t.0 == Tok::Ident).map(|t| text[t.1..t.2].to_ascii_uppercase()).unwrap_or_default()
    };
    let mut out = Vec::new();
    let mut k = 0;
    while k < toks.len() {
        let w = word(k);
        match w.as_str() {
            "PROGRAM" | "FUNCTION_BLOCK" | "FUNCTION" | "CLASS" | "INTERFACE" => {
                // FUNCTION_BLOCK ABSTRACT/FINAL/PUBLIC… Name
                let mut n = k + 1;
                while matches!(word(n).as_str(), "ABSTRACT" | "FINAL" | "PUBLIC" | "INTERNAL") {
                    n += 1;
                }
                if toks.get(n).is_some_and(|t| t.0 == Tok::Ident) {
                    out.push((w, text[toks[n].1..toks[n].2].to_string()));
                }
                k = n + 1;
            }
            "TYPE" => {
                let mut depth = 0;
                k += 1;
                while k < toks.len() && word(k) != "END_TYPE" {
                    match word(k).as_str() {
                        "STRUCT" => depth += 1,
                        "END_STRUCT" => depth -= 1,
                        _ => {}
                    }
                    let colon = toks.get(k + 1).is_some_and(|t| t.0 == Tok::Punct(b':'));
                    let prev_ok = k == 0 || matches!(toks[k - 1].0, Tok::Punct(b';')) || word(k - 1) == "TYPE";
                    if depth == 0 && toks[k].0 == Tok::Ident && colon && prev_ok {
                        out.push(("TYPE".to_string(), text[toks[k].1..toks[k].2].to_string()));
                    }
                    k += 1;
                }
            }
            _ => k += 1,
        }
    }
    out
}

/// `text` with every identifier of `names` (case-insensitive, not after `.` or `#`) followed by
/// `suffix`.
fn rename(text: &str, names: &BTreeSet<String>, suffix: &str) -> String {
    let toks = lex(text);
    let mut out = String::with_capacity(text.len() + 64);
    let mut last = 0;
    for (k, &(kind, s, e)) in toks.iter().enumerate() {
        if kind != Tok::Ident || !names.contains(&text[s..e].to_ascii_uppercase()) {
            continue;
        }
        if k > 0 && matches!(toks[k - 1].0, Tok::Punct(b'.') | Tok::Punct(b'#')) && toks[k - 1].2 == s {
            continue;
        }
        out.push_str(&text[last..e]);
        out.push_str(suffix);
        last = e;
    }
    out.push_str(&text[last..]);
    out
}

/// One top-level element of an ST file: its text (with the comments before it), kind and name.
struct Unit {
    kind: String,
    name: String,
    text: String,
    /// Its first line in the file (0-based).
    line: usize,
}

/// `text` cut into its top-level elements (TYPE blocks, POUs, configurations); text after the
/// last one is a unit of kind "".
fn units(text: &str) -> Vec<Unit> {
    let toks = lex(text);
    let word = |k: usize| -> String {
        toks.get(k).filter(|t| t.0 == Tok::Ident).map(|t| text[t.1..t.2].to_ascii_uppercase()).unwrap_or_default()
    };
    let mut out = Vec::new();
    let mut start = 0;
    let mut k = 0;
    let line_of = |pos: usize| text[..pos].matches('\n').count();
    while k < toks.len() {
        let w = word(k);
        if !matches!(
            w.as_str(),
            "TYPE" | "PROGRAM" | "FUNCTION_BLOCK" | "FUNCTION" | "CONFIGURATION" | "CLASS" | "INTERFACE"
        ) {
            k += 1;
            continue;
        }
        let end_word = format!("END_{w}");
        let mut n = k + 1;
        while n < toks.len() && word(n) != end_word {
            n += 1;
        }
        let mut end = toks.get(n).map(|t| t.2).unwrap_or(text.len());
        // the rest of the END_ line (`;`, a comment) belongs to the unit
        end = text[end..].find('\n').map(|e| end + e + 1).unwrap_or(text.len());
        let name = if w == "TYPE" {
            declared(&text[toks[k].1..end]).into_iter().map(|(_, n)| n).collect::<Vec<_>>().join(",")
        } else {
            let mut m = k + 1;
            while matches!(word(m).as_str(), "ABSTRACT" | "FINAL" | "PUBLIC" | "INTERNAL") {
                m += 1;
            }
            toks.get(m).map(|t| text[t.1..t.2].to_string()).unwrap_or_default()
        };
        out.push(Unit { kind: w, name, text: text[start..end].to_string(), line: line_of(start) });
        start = end;
        while k < toks.len() && toks[k].1 < end {
            k += 1;
        }
    }
    if !text[start..].trim().is_empty() {
        out.push(Unit {
            kind: String::new(),
            name: String::new(),
            text: text[start..].to_string(),
            line: line_of(start),
        });
    }
    out
}

/// The text of a unit without the comments and blank lines before it (how helpers are compared).
fn body(u: &Unit) -> &str {
    let toks = lex(&u.text);
    match toks.first() {
        Some(t) => &u.text[t.1..],
        None => "",
    }
}

// ---------------------------------------------------------------------------------------------
// Cases

/// A chart with its inputs.
#[derive(Clone)]
struct Case {
    name: String,
    /// The chart file `sfc sim` runs (the original, or a file written here).
    chart: PathBuf,
    /// Its IEC text.
    text: String,
    /// The simulated POU, as declared.
    pou: String,
    period: i64,
    scans: usize,
    /// Per scan: the values written before it.
    sets: Vec<Vec<(String, Value)>>,
}

/// The scenarios of `examples/` and of the semantics fixtures whose profile is `iec`.
fn scenario_cases(work: &Path) -> Vec<Case> {
    let mut out = Vec::new();
    let mut dirs = vec![
        root().join("examples"),
        root().join("crates/sfc-sim/tests/semantics"),
        // the reproductions of what this test found (one chart per problem)
        root().join("crates/sfc-cli/tests/st_compilers"),
    ];
    // more scenarios (a reproduction being minimised): SFC_ST_COMPILERS_SCENARIOS=dir,dir
    if let Ok(more) = std::env::var("SFC_ST_COMPILERS_SCENARIOS") {
        dirs.extend(more.split(',').map(PathBuf::from));
    }
    for dir in &dirs {
        for path in random_chart::scenario_files(dir) {
            let sc = sfc_sim::scenario::load(&path).unwrap_or_else(|e| panic!("{}: {}", path.display(), e.message));
            if sc.options.profile != Profile::Iec {
                continue;
            }
            let rel = path.strip_prefix(root()).unwrap_or(&path).to_string_lossy().into_owned();
            let name = rel
                .trim_end_matches(".scenario.toml")
                .replace("crates/sfc-sim/tests/", "")
                .replace("crates/sfc-cli/tests/", "")
                .trim_start_matches('/')
                .to_string();
            let scans = sc.total_scans() as usize;
            let mut sets: Vec<Vec<(String, Value)>> = vec![Vec::new(); scans];
            for e in &sc.entries {
                let k = sc.scan_of(e.time) as usize;
                if k < scans {
                    sets[k].extend(e.set.iter().cloned());
                }
            }
            let chart = if sc.chart.extension().is_some_and(|e| e == "st") {
                sc.chart.clone()
            } else {
                // a PLCopen XML chart: its IEC text
                let p = work.join(format!("{}.st", name.replace('/', "_")));
                std::fs::write(&p, sc.chart_text()).unwrap();
                p
            };
            out.push(Case {
                name,
                chart,
                text: sc.chart_text().to_string(),
                pou: sc.pou.clone(),
                period: sc.options.period,
                scans,
                sets,
            });
        }
    }
    out
}

/// The fixtures of `sfc-codegen/tests/st/`, their BOOL variables not written by the chart
/// flipped at random.
fn fixture_cases() -> Vec<Case> {
    let dir = root().join("crates/sfc-codegen/tests/st");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    files.sort();
    let mut rng = random_chart::Rng(0x57C0_DE0A_7A7E_0C0C);
    let mut out = Vec::new();
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let name = format!("fixture/{}", path.file_stem().unwrap().to_string_lossy());
        let sim = match Simulation::from_source(&name, &text, None, SimOptions::default()) {
            Ok(s) => s,
            // (a fixture the checker refuses: `sfc build` says why below)
            Err(_) => {
                out.push(Case {
                    name,
                    chart: path,
                    text,
                    pou: String::new(),
                    period: 10_000,
                    scans: 0,
                    sets: Vec::new(),
                });
                continue;
            }
        };
        let checked = sfc_model::check_source(0, &name, &text, &sfc_model::CheckOptions::default());
        let written: Vec<String> = checked
            .charts
            .iter()
            .flat_map(|c| c.steps.iter().flat_map(|s| s.associations.iter().map(|a| a.action.to_ascii_uppercase())))
            .collect();
        let inputs: Vec<String> = sim
            .trace_vars()
            .into_iter()
            .filter(|(n, t)| t.to_string() == "BOOL" && !written.contains(&n.to_ascii_uppercase()))
            .map(|(n, _)| n)
            .collect();
        let scans = 200;
        let mut values = vec![false; inputs.len()];
        let sets = (0..scans)
            .map(|_| {
                let mut w = Vec::new();
                for (k, v) in values.iter_mut().enumerate() {
                    let p = if inputs[k].to_ascii_uppercase().starts_with("SFC") { 3 } else { 15 };
                    if rng.chance(p) {
                        *v = !*v;
                        w.push((inputs[k].clone(), Value::Bool(*v)));
                    }
                }
                w
            })
            .collect();
        out.push(Case { name, chart: path, text, pou: sim.pou_name().to_string(), period: 10_000, scans, sets });
    }
    out
}

/// Random charts `0..n` of `random_chart.rs` (the seeds of `sfc-codegen/tests/st.rs`), with
/// their inputs over 120 scans.
fn random_cases(n: usize, work: &Path) -> Vec<Case> {
    (0..n)
        .map(|k| {
            let mut rng = random_chart::Rng::for_case(k);
            let (text, fb) = random_chart::random_chart(&mut rng, 14);
            let mut inputs = random_chart::RandomInputs::new(&text, fb);
            let scans = 120;
            let sets = (0..scans as u64)
                .map(|s| inputs.next(&mut rng, s).into_iter().map(|(n, b)| (n, Value::Bool(b))).collect())
                .collect();
            let name = format!("random/{k:03}");
            let chart = work.join(format!("random_{k:03}.st"));
            std::fs::write(&chart, &text).unwrap();
            Case { name, chart, text, pou: if fb { "Main" } else { "Chart" }.to_string(), period: 10_000, scans, sets }
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// The chart's side: sfc sim

/// One scan: the active steps (sorted) and the variables.
#[derive(Debug, Clone, PartialEq)]
struct Row {
    active: Vec<String>,
    vars: BTreeMap<String, Json>,
}

/// The case's inputs as a scenario file for `sfc sim` (written to `path`).
fn write_scenario(case: &Case, path: &Path, profile: &str) {
    let mut sc = String::new();
    writeln!(sc, "# the inputs of {} (tests/st_compilers.rs)", case.name).unwrap();
    writeln!(sc, "chart = {:?}", case.chart.display().to_string()).unwrap();
    writeln!(sc, "pou = {:?}", case.pou).unwrap();
    writeln!(sc, "period = \"{}\"\nprofile = \"{profile}\"\nscans = {}", format_time(case.period), case.scans).unwrap();
    sc.push_str(&common::scenario_entries(case.period, &case.sets));
    std::fs::write(path, sc).unwrap();
}

/// `sfc sim --profile PROFILE --trace -` of the case.
fn simulate(case: &Case, dir: &Path, profile: &str) -> Result<Vec<Row>, String> {
    let path = dir.join(format!("{profile}.scenario.toml"));
    write_scenario(case, &path, profile);
    let out = sfc()
        .arg("sim")
        .arg(&case.chart)
        .arg("--scenario")
        .arg(&path)
        .args(["--profile", profile, "--trace", "-"])
        .output()
        .map_err(|e| e.to_string())?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let mut rows = Vec::new();
    for l in stdout.lines().filter(|l| l.starts_with('{')) {
        let j: Json = serde_json::from_str(l).map_err(|e| format!("sfc sim wrote {l}: {e}"))?;
        let mut active: Vec<String> =
            j["active"].as_array().unwrap().iter().map(|x| x.as_str().unwrap().to_string()).collect();
        active.sort();
        let vars = j["vars"].as_object().unwrap().iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        rows.push(Row { active, vars });
    }
    if rows.len() != case.scans {
        return Err(format!(
            "sfc sim wrote {} of {} scans: {}",
            rows.len(),
            case.scans,
            String::from_utf8_lossy(&out.stderr).lines().find(|l| l.contains("error")).unwrap_or("")
        ));
    }
    Ok(rows)
}

// ---------------------------------------------------------------------------------------------
// What the drivers read and write

#[derive(Clone, Copy, PartialEq, Debug)]
enum Kind {
    Bool,
    /// signed or unsigned, up to 64 bits
    Int {
        unsigned: bool,
    },
    Real,
    LReal,
    Time,
    Str,
}

fn kind_of(ty: &str) -> Option<Kind> {
    Some(match ty {
        "BOOL" => Kind::Bool,
        "SINT" | "INT" | "DINT" | "LINT" => Kind::Int { unsigned: false },
        "USINT" | "UINT" | "UDINT" | "ULINT" | "BYTE" | "WORD" | "DWORD" | "LWORD" => Kind::Int { unsigned: true },
        "REAL" => Kind::Real,
        "LREAL" => Kind::LReal,
        "TIME" => Kind::Time,
        t if t.starts_with("STRING") => Kind::Str,
        _ => return None,
    })
}

/// A variable read or written by a driver.
#[derive(Clone, Debug)]
struct Var {
    /// As the trace names it (`busy`, `c.o0`).
    name: String,
    /// Upper-case path from the top POU (`["C", "O0"]`).
    path: Vec<String>,
    kind: Kind,
    located: bool,
}

/// What a driver needs to know of a case.
#[derive(Clone)]
struct Shape {
    /// The top POU as compiled (`MAIN_17`), and whether it is a function block.
    top: String,
    top_is_fb: bool,
    /// Qualified step names (as `sfc sim` prints them) and their path (`["C", "S0"]`).
    steps: Vec<(String, Vec<String>)>,
    /// The traced variables, in the trace's order.
    vars: Vec<Var>,
    /// The variables the inputs write, and per write: (scan, index in `inputs`, value).
    inputs: Vec<Var>,
    writes: Vec<(usize, usize, Value)>,
}

fn upper_path(name: &str) -> Vec<String> {
    name.split('.').map(|s| s.to_ascii_uppercase()).collect()
}

fn shape(case: &Case, suffix: &str) -> Result<Shape, String> {
    let opts = SimOptions { period: case.period, profile: Profile::Iec };
    let sim = Simulation::from_source(&case.name, &case.text, Some(&case.pou), opts).map_err(|(_, d)| {
        format!("the simulator refuses it: {}", d.first().map(|d| d.message.clone()).unwrap_or_default())
    })?;
    let located: Vec<String> = sim.located_vars().into_iter().map(|(n, ..)| n.to_ascii_uppercase()).collect();
    let decl = declared(&case.text);
    let top_is_fb = decl.iter().any(|(k, n)| k == "FUNCTION_BLOCK" && n.eq_ignore_ascii_case(&case.pou));
    let mut steps = Vec::new();
    for s in sim.step_names() {
        if s.contains('[') {
            return Err(format!("step {s}: a chart instance in an array (not supported by this test's drivers)"));
        }
        steps.push((s.clone(), upper_path(&s)));
    }
    let var = |name: &str, ty: String| -> Result<Var, String> {
        if name.contains('[') {
            return Err(format!("{name}: an array element (not supported by this test's drivers)"));
        }
        let kind = kind_of(&ty).ok_or_else(|| format!("{name}: type {ty} (not supported by this test's drivers)"))?;
        let path = upper_path(name);
        let located = path.len() == 1 && located.contains(&path[0]);
        Ok(Var { name: name.to_string(), path, kind, located })
    };
    let mut vars = Vec::new();
    for (n, ty) in sim.trace_vars() {
        vars.push(var(&n, ty.to_string())?);
    }
    let mut inputs: Vec<Var> = Vec::new();
    let mut writes = Vec::new();
    for (k, set) in case.sets.iter().enumerate() {
        for (n, v) in set {
            let i = match inputs.iter().position(|x| x.name.eq_ignore_ascii_case(n)) {
                Some(i) => i,
                None => {
                    let ty = sim.type_of(n).ok_or_else(|| format!("the input {n} has no type"))?;
                    inputs.push(var(n, ty.to_string())?);
                    inputs.len() - 1
                }
            };
            writes.push((k, i, v.clone()));
        }
    }
    Ok(Shape { top: format!("{}{suffix}", case.pou.to_ascii_uppercase()), top_is_fb, steps, vars, inputs, writes })
}

// ---------------------------------------------------------------------------------------------
// The compiled side

#[derive(Clone, Copy, PartialEq, Debug)]
enum Compiler {
    Matiec,
    Strucpp,
}

impl Compiler {
    fn label(self) -> &'static str {
        match self {
            Compiler::Matiec => "MatIEC",
            Compiler::Strucpp => "STruC++",
        }
    }
    fn dialect(self) -> &'static str {
        match self {
            Compiler::Matiec => "matiec",
            Compiler::Strucpp => "strucpp",
        }
    }
}

/// A case ready to compile: its ST per compiler, its shape, the trace it must produce.
struct Ready {
    case: Case,
    /// The suffix of its POU names (`_17`).
    suffix: String,
    shape: Shape,
    expected: Vec<Row>,
    /// [MatIEC, STruC++]
    st: [String; 2],
    /// The names each got renamed (SFC0818), upper-case old to new.
    renames: [Vec<(String, String)>; 2],
    dir: PathBuf,
    /// MatIEC compiles the chart itself (not its ST): the steps are read from its SFC step list.
    sfc_steps: bool,
}

enum Prepared {
    Ready(Box<Ready>),
    /// Not compared: why.
    Skipped(String),
    Failed(String),
}

/// `sfc build --target st --st-dialect DIALECT` of the chart file (every chart of it).
/// Its warning SFC0805 (CODESYS extensions copied as written, which neither compiler takes) is
/// an `Err` too.
fn translate(chart: &Path, dialect: &str, out: &Path) -> Result<(String, Vec<(String, String)>), String> {
    let o = sfc()
        .arg("build")
        .arg(chart)
        .args(["--target", "st", "--st-dialect", dialect, "-o"])
        .arg(out)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| e.to_string())?;
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    if !o.status.success() || stderr.contains("SFC0805") {
        return Err(format!("{}{stderr}", String::from_utf8_lossy(&o.stdout)));
    }
    Ok((std::fs::read_to_string(out).unwrap(), renames_of(&stderr)))
}

/// The names `sfc build` renamed for the compiler (note SFC0818: "renamed `Left` to `Left_1`"),
/// upper-case, old to new.
fn renames_of(stderr: &str) -> Vec<(String, String)> {
    stderr
        .lines()
        .filter(|l| l.contains("SFC0818"))
        .filter_map(|l| {
            let mut q = l.split('`');
            let (_, old, _, new) = (q.next()?, q.next()?, q.next()?, q.next()?);
            Some((old.to_ascii_uppercase(), new.to_ascii_uppercase()))
        })
        .collect()
}

/// `shape` with the names the compiler got renamed.
fn renamed(shape: &Shape, renames: &[(String, String)]) -> Shape {
    let map = |p: &[String]| -> Vec<String> {
        p.iter().map(|x| renames.iter().find(|(o, _)| o == x).map_or_else(|| x.clone(), |(_, n)| n.clone())).collect()
    };
    let mut s = shape.clone();
    s.top = map(std::slice::from_ref(&s.top)).remove(0);
    for (_, p) in &mut s.steps {
        *p = map(p);
    }
    for v in s.vars.iter_mut().chain(s.inputs.iter_mut()) {
        v.path = map(&v.path);
    }
    s
}

/// Whether `chart` is a fixture of `sfc-codegen/tests/st/` whose expected translation is a
/// refusal.
fn refused_fixture(chart: &Path) -> bool {
    let expected = PathBuf::from(format!("{}.expected", chart.display()));
    std::fs::read_to_string(expected).is_ok_and(|t| t.starts_with("(* refused *)"))
}

/// `st` with the first number of every direct address (`AT %IX0.1`) plus `1000 * idx`.
fn relocate(st: &str, idx: usize) -> String {
    let toks = lex(st);
    let mut out = String::with_capacity(st.len());
    let mut last = 0;
    for (k, &(kind, s, e)) in toks.iter().enumerate() {
        // `%` then an identifier like `IX0` or `QW12` (the lexer reads `IX0` as one identifier)
        if kind != Tok::Ident || k == 0 || toks[k - 1].0 != Tok::Punct(b'%') || toks[k - 1].2 != s {
            continue;
        }
        let word = &st[s..e];
        let letters = word.trim_end_matches(|c: char| c.is_ascii_digit());
        let digits = &word[letters.len()..];
        let Ok(n) = digits.parse::<usize>() else { continue };
        out.push_str(&st[last..s]);
        write!(out, "{letters}{}", n + 1000 * idx).unwrap();
        last = e;
    }
    out.push_str(&st[last..]);
    out
}

fn prepare(idx: usize, case: &Case, work: &Path) -> Prepared {
    let dir = work.join(case.name.replace('/', "_"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let checked = sfc_model::check_source(0, &case.name, &case.text, &sfc_model::CheckOptions::default());
    let mut pous: Vec<String> = Vec::new();
    for c in &checked.charts {
        if !pous.iter().any(|p| p.eq_ignore_ascii_case(&c.pou)) {
            pous.push(c.pou.clone());
        }
    }
    if pous.is_empty() {
        return Prepared::Skipped("no chart in a POU body: nothing for sfc build --target st to translate".into());
    }
    // Every POU and type of the file gets the case's suffix.
    let suffix = format!("_{idx}");
    let names: BTreeSet<String> = declared(&case.text).into_iter().map(|(_, n)| n.to_ascii_uppercase()).collect();
    let renamed = rename(&case.text, &names, &suffix);
    let chart = dir.join("chart.st");
    std::fs::write(&chart, &renamed).unwrap();
    let built = |dialect: &str| -> Result<(String, Vec<(String, String)>), Prepared> {
        translate(&chart, dialect, &dir.join(format!("{dialect}.built.st"))).map_err(|e| {
            let first = |code: &str| e.lines().find(|l| l.contains(code)).unwrap_or("").trim().to_string();
            if e.contains("SFC0806") {
                Prepared::Skipped(format!("refused by sfc build --target st (CODESYS features): {}", first("SFC0806")))
            } else if e.contains("SFC0809") {
                Prepared::Skipped(format!(
                    "refused by sfc build --target st (AND_THEN/OR_ELSE over a call has no IEC form): {}",
                    first("SFC0809")
                ))
            } else if e.contains("SFC0805") && !e.contains("error") {
                Prepared::Skipped(format!(
                    "CODESYS extensions kept as written, which neither compiler takes (sfc build says so): {}",
                    first("SFC0805")
                ))
            } else if e.contains("no SFC POU to build") {
                Prepared::Skipped(format!("no SFC POU for sfc build: {}", first("error")))
            } else if refused_fixture(&case.chart) {
                Prepared::Skipped(format!(
                    "a fixture the ST target refuses (its .expected says so): {}",
                    first("error")
                ))
            } else {
                Prepared::Failed(format!("sfc build --target st --st-dialect {dialect} fails:\n{e}"))
            }
        })
    };
    let (st, renames) = match (built("matiec"), built("strucpp")) {
        (Ok(m), Ok(s)) => ([m.0, s.0], [m.1, s.1]),
        (Err(p), _) | (_, Err(p)) => return p,
    };
    // Located variables of different cases at different addresses (%IX0.1 → %IX17000.1): STruC++
    // refuses two variables at one address, MatIEC would share their storage.
    let st = st.map(|t| relocate(&t, idx));
    let shape = match shape(case, &suffix) {
        Ok(s) => s,
        Err(e) => return Prepared::Failed(format!("harness: {e}")),
    };
    let expected = match simulate(case, &dir, "iec") {
        Ok(r) => r,
        Err(e) => return Prepared::Failed(e),
    };
    std::fs::write(dir.join("matiec.st"), &st[0]).unwrap();
    std::fs::write(dir.join("strucpp.st"), &st[1]).unwrap();
    Prepared::Ready(Box::new(Ready { case: case.clone(), suffix, shape, expected, st, renames, dir, sfc_steps: false }))
}

/// The ST of several cases as one file: the first copy of each helper (a unit whose name does
/// not carry a case suffix) kept. Returns the text, per line the cases it belongs to with the
/// line in each case's own ST (a helper's lines belong to every case that has it), and the cases
/// whose helper differs from the first copy.
#[allow(clippy::type_complexity)]
fn concat(parts: &[(usize, &str)]) -> (String, Vec<Vec<(usize, usize)>>, Vec<(usize, String)>) {
    let mut text = String::new();
    let mut owners: Vec<Vec<(usize, usize)>> = Vec::new();
    let mut helpers: Vec<(String, String, usize, usize)> = Vec::new(); // (name, body, first line, lines)
    let mut conflicts = Vec::new();
    // (case, its CONFIGURATION unit)
    let mut configs: Vec<(usize, Unit)> = Vec::new();
    for &(idx, st) in parts {
        let suffix = format!("_{idx}");
        for u in units(st) {
            if u.kind == "CONFIGURATION" {
                configs.push((idx, u));
                continue;
            }
            let own = u.kind.is_empty()
                || u.name.split(',').all(|n| n.to_ascii_uppercase().ends_with(&suffix.to_ascii_uppercase()));
            if !own {
                if let Some(h) = helpers.iter().find(|h| h.0.eq_ignore_ascii_case(&u.name)) {
                    if h.1 != body(&u) {
                        conflicts
                            .push((idx, format!("its {} {} differs from the one of an earlier case", u.kind, u.name)));
                    }
                    for (i, l) in (h.2..h.2 + h.3).enumerate() {
                        owners[l].push((idx, u.line + i));
                    }
                    continue;
                }
            }
            let first = owners.len();
            let mut t = u.text.clone();
            if !t.ends_with('\n') {
                t.push('\n');
            }
            let n = t.matches('\n').count();
            text.push_str(&t);
            owners.extend((0..n).map(|i| vec![(idx, u.line + i)]));
            if !own {
                helpers.push((u.name.clone(), body(&u).to_string(), first, n));
            }
        }
    }
    // One configuration: the first case's, with the program instances of every case
    // (`PROGRAM instance0 WITH task0 : Main_17;` → `PROGRAM instance0_17 WITH …`).
    if let Some((first_idx, first)) = configs.first() {
        let is_program = |l: &str| {
            let w: Vec<&str> = l.split_whitespace().collect();
            w.len() >= 4 && w[0].eq_ignore_ascii_case("PROGRAM") && w[2].eq_ignore_ascii_case("WITH")
        };
        let mut programs: Vec<(usize, usize, String)> = Vec::new(); // (case, line in its ST, text)
        for (idx, u) in &configs {
            for (i, l) in u.text.lines().enumerate() {
                if is_program(l) {
                    let w: Vec<&str> = l.split_whitespace().collect();
                    let renamed = l.replacen(&format!(" {} ", w[1]), &format!(" {}_{idx} ", w[1]), 1);
                    programs.push((*idx, u.line + i, renamed));
                }
            }
        }
        let all: Vec<(usize, usize)> = configs.iter().map(|(k, u)| (*k, u.line)).collect();
        let mut emitted = false;
        for (i, l) in first.text.lines().enumerate() {
            if is_program(l) {
                if !emitted {
                    for (k, line, p) in &programs {
                        text.push_str(p);
                        text.push('\n');
                        owners.push(vec![(*k, *line)]);
                    }
                    emitted = true;
                }
                continue;
            }
            text.push_str(l);
            text.push('\n');
            // (the configurations differ only in their programs: a line is every case's)
            let mut o: Vec<(usize, usize)> = all.iter().map(|(k, start)| (*k, start + i)).collect();
            o.sort_by_key(|(k, _)| (*k != *first_idx) as u8);
            owners.push(o);
        }
    }
    (text, owners, conflicts)
}

/// The error lines of a compiler's output about `file`: (line, message). Lines are read from
/// `file:LINE:`, `file:LINE-COL..` and, for errors at line 1 with an `offset: N`, from the offset
/// into `text`.
fn error_lines(output: &str, file: &str, text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for l in output.lines() {
        let Some(rest) = l.split_once(&format!("{file}:")).map(|x| x.1) else { continue };
        if !l.contains("error") {
            continue;
        }
        let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        let Ok(mut n) = digits.parse::<usize>() else { continue };
        if let Some(off) = l
            .split_once("offset: ")
            .and_then(|(_, o)| o.chars().take_while(|c| c.is_ascii_digit()).collect::<String>().parse::<usize>().ok())
        {
            if off <= text.len() {
                n = text[..off].matches('\n').count() + 1;
            }
        }
        // the message without the file and position
        let msg = rest.trim_start_matches(|c: char| c.is_ascii_digit() || ".:-".contains(c)).trim();
        out.push((n, msg.to_string()));
    }
    out
}

/// Translates `all.st` in `dir`; `Err` is the compiler's output.
fn translate_batch(c: Compiler, tools: &Tools, dir: &Path) -> Result<(), String> {
    match c {
        Compiler::Matiec => {
            let lib = tools.matiec_lib.to_string_lossy().into_owned();
            let iec2c = tools.iec2c.to_string_lossy().into_owned();
            for (sub, extra) in [("beremiz", &[][..]), ("openplc", &["-r", "-R", "-a"][..])] {
                let out = dir.join(sub);
                let _ = std::fs::remove_dir_all(&out);
                std::fs::create_dir_all(&out).unwrap();
                let o = out.to_string_lossy().into_owned();
                let mut args = vec![iec2c.as_str(), "-f", "-l", "-p"];
                args.extend(extra);
                args.extend(["-I", lib.as_str(), "-T", o.as_str(), "all.st"]);
                sh_bounded(&args, 30, 40_000, dir).map_err(|e| {
                    if sub == "openplc" {
                        format!("(with OpenPLC v3's options -r -R -a)\n{e}")
                    } else {
                        e
                    }
                })?;
            }
            Ok(())
        }
        Compiler::Strucpp => {
            let mut args: Vec<&str> = tools.strucpp.iter().map(String::as_str).collect();
            args.extend(["all.st", "-o", "all.cpp"]);
            sh_bounded(&args, 300, 40_000, dir).map(|_| ())
        }
    }
}

fn c_path(c: Compiler, inst: &str, v: &Var) -> String {
    match c {
        Compiler::Matiec => {
            let (last, prefix) = v.path.split_last().unwrap();
            let mut p = inst.to_string();
            for s in prefix {
                write!(p, ".{s}").unwrap();
            }
            if v.located {
                format!("(*{p}.{last}.value)")
            } else {
                format!("{p}.{last}.value")
            }
        }
        Compiler::Strucpp => format!("{inst}.{}", v.path.join(".")),
    }
}

fn step_path(c: Compiler, inst: &str, path: &[String]) -> String {
    let (last, prefix) = path.split_last().unwrap();
    let mut p = inst.to_string();
    for s in prefix {
        write!(p, ".{s}").unwrap();
    }
    match c {
        Compiler::Matiec => format!("{p}.{last}.value.X"),
        Compiler::Strucpp => format!("{p}.{last}.X.get()"),
    }
}

/// The C (MatIEC) or C++ (STruC++) source that runs `cases` one after the other (from the
/// position given as its argument) and prints `@begin K`, per scan `K SCAN BITS\tVALUE…`, and
/// `@end K`.
fn driver(c: Compiler, cases: &[&Ready], located: &str) -> String {
    let mut d = String::new();
    match c {
        Compiler::Matiec => {
            d.push_str("#include <stdio.h>\n#include <stdlib.h>\n#include \"iec_std_lib.h\"\n");
            d.push_str("#define __LOCATED_VAR(type, name, ...) type __loc_##name; type* name = &__loc_##name;\n");
            d.push_str(located);
            d.push_str("#undef __LOCATED_VAR\nTIME __CURRENT_TIME;\nBOOL __DEBUG = 0;\n");
            d.push_str("#include \"POUS.h\"\n#include \"POUS.c\"\n");
            d.push_str(
                "static TIME us_time(long long us) { TIME t; long long s = us / 1000000, r = us % 1000000;\n  \
                 if (r < 0) { r += 1000000; s -= 1; } t.tv_sec = s; t.tv_nsec = r * 1000; return t; }\n\
                 static long long time_us(TIME t) { long long ns = (long long)t.tv_sec * 1000000000LL + t.tv_nsec;\n  \
                 return ns >= 0 ? ns / 1000 : -((-ns + 999) / 1000); }\n\
                 static STRING str_of(const char *s) { STRING x; x.len = 0; while (s[x.len]) { x.body[x.len] = s[x.len]; x.len++; } return x; }\n",
            );
        }
        Compiler::Strucpp => {
            d.push_str("#include <cstdio>\n#include <cstdlib>\n#include <string>\n#include \"all.hpp\"\nusing namespace strucpp;\n");
            d.push_str(
                "static long long ns_us(long long ns) { return ns >= 0 ? ns / 1000 : -((-ns + 999) / 1000); }\n",
            );
        }
    }
    d.push_str("typedef struct { int scan, var; long long i; double r; const char *s; } Write;\n");
    for r in cases {
        let k = r.suffix.trim_start_matches('_');
        let shape = renamed(&r.shape, &r.renames[c as usize]);
        let s = &shape;
        let inst = "(*p)";
        // the writes
        writeln!(d, "\n/* {} */\nstatic const Write writes{k}[] = {{", r.case.name).unwrap();
        for (scan, var, v) in &s.writes {
            let (i, f, st) = match v {
                Value::Bool(b) => (*b as i64, 0.0, String::from("0")),
                Value::Int(i) => (*i, 0.0, "0".into()),
                Value::Real(x) => (0, *x, "0".into()),
                Value::Time(us) => (*us, 0.0, "0".into()),
                Value::Str(t) => (0, 0.0, format!("{:?}", t.as_ref())),
            };
            writeln!(d, "  {{{scan}, {var}, {i}LL, {f:?}, {st}}},").unwrap();
        }
        writeln!(d, "  {{-1, -1, 0, 0.0, 0}}\n}};").unwrap();
        let ty = match (c, s.top_is_fb) {
            (Compiler::Matiec, _) | (Compiler::Strucpp, true) => s.top.clone(),
            (Compiler::Strucpp, false) => format!("Program_{}", s.top),
        };
        writeln!(d, "static void put{k}({ty} *p, const Write *w) {{\n  switch (w->var) {{").unwrap();
        for (i, v) in s.inputs.iter().enumerate() {
            let lv = c_path(c, inst, v);
            let value = match (c, v.kind) {
                (_, Kind::Bool) => "(w->i != 0)".to_string(),
                (_, Kind::Int { .. }) => "w->i".to_string(),
                (_, Kind::Real | Kind::LReal) => "w->r".to_string(),
                (Compiler::Matiec, Kind::Time) => "us_time(w->i)".to_string(),
                (Compiler::Strucpp, Kind::Time) => "(w->i * 1000LL)".to_string(),
                (Compiler::Matiec, Kind::Str) => "str_of(w->s)".to_string(),
                (Compiler::Strucpp, Kind::Str) => "w->s".to_string(),
            };
            match c {
                Compiler::Matiec => writeln!(d, "  case {i}: {lv} = {value}; break;").unwrap(),
                Compiler::Strucpp => writeln!(d, "  case {i}: {lv} = {value}; break;").unwrap(),
            }
        }
        d.push_str("  }\n}\n");
        writeln!(d, "static void run{k}(void) {{").unwrap();
        match c {
            Compiler::Matiec => {
                writeln!(
                    d,
                    "  static {ty} data; {ty} *p = &data;\n  __CURRENT_TIME = us_time(0);\n  {}_init__(p, 0);",
                    s.top
                )
                .unwrap();
            }
            Compiler::Strucpp => writeln!(d, "  {ty} *p = new {ty}();\n  __CURRENT_TIME_NS = 0;").unwrap(),
        }
        writeln!(d, "  printf(\"@begin {k}\\n\");\n  const Write *w = writes{k};").unwrap();
        writeln!(d, "  for (int k = 0; k < {}; k++) {{", r.case.scans).unwrap();
        writeln!(d, "    while (w->scan == k) put{k}(p, w++);").unwrap();
        match c {
            Compiler::Matiec => {
                writeln!(
                    d,
                    "    __CURRENT_TIME = us_time((long long)k * {}LL);\n    {}_body__(p);",
                    r.case.period, s.top
                )
                .unwrap();
            }
            Compiler::Strucpp => {
                let call = if s.top_is_fb { "(*p)()" } else { "p->run()" };
                writeln!(d, "    __CURRENT_TIME_NS = (long long)k * {}LL * 1000LL;\n    {call};", r.case.period)
                    .unwrap();
            }
        }
        writeln!(d, "    printf(\"{k} %d \", k);").unwrap();
        for (i, (_, path)) in s.steps.iter().enumerate() {
            let x = if r.sfc_steps { format!("{inst}.__step_list[{i}].X.value") } else { step_path(c, inst, path) };
            writeln!(d, "    putchar({x} ? '1' : '0');").unwrap();
        }
        for v in &s.vars {
            let lv = c_path(c, inst, v);
            let get = match c {
                Compiler::Matiec => lv.clone(),
                Compiler::Strucpp => format!("{lv}.get()"),
            };
            let line = match (c, v.kind) {
                (_, Kind::Bool) => format!("printf(\"\\t%d\", (int)({get}));"),
                (_, Kind::Int { unsigned: false }) => format!("printf(\"\\t%lld\", (long long)({get}));"),
                (_, Kind::Int { unsigned: true }) => format!("printf(\"\\t%llu\", (unsigned long long)({get}));"),
                (_, Kind::Real) => format!("printf(\"\\t%.9g\", (double)({get}));"),
                (_, Kind::LReal) => format!("printf(\"\\t%.17g\", (double)({get}));"),
                (Compiler::Matiec, Kind::Time) => format!("printf(\"\\t%lld\", time_us({get}));"),
                (Compiler::Strucpp, Kind::Time) => format!("printf(\"\\t%lld\", ns_us((long long)({get})));"),
                (Compiler::Matiec, Kind::Str) => {
                    format!("printf(\"\\t%.*s\", (int)({lv}).len, (const char *)({lv}).body);")
                }
                (Compiler::Strucpp, Kind::Str) => format!("printf(\"\\t%s\", {lv}.get().c_str());"),
            };
            writeln!(d, "    {line}").unwrap();
        }
        d.push_str("    putchar('\\n');\n  }\n");
        writeln!(d, "  printf(\"@end {k}\\n\");\n  fflush(stdout);\n}}").unwrap();
    }
    d.push_str("\nstatic void (*const runs[])(void) = {");
    for r in cases {
        write!(d, "run{}, ", r.suffix.trim_start_matches('_')).unwrap();
    }
    d.push_str("0};\nint main(int argc, char **argv) {\n  int from = argc > 1 ? atoi(argv[1]) : 0;\n");
    d.push_str("  for (int i = from; runs[i]; i++) runs[i]();\n  return 0;\n}\n");
    d
}

/// Compiles the driver in `dir`; `Err` is the compiler's output.
fn compile_driver(c: Compiler, tools: &Tools, dir: &Path) -> Result<(), String> {
    match c {
        Compiler::Matiec => {
            let inc = tools.matiec_lib.join("C");
            sh(Command::new("gcc")
                .args(["-w", "-O0", "-I", "beremiz", "-I"])
                .arg(&inc)
                .args(["driver.c", "-o", "driver", "-lm"])
                .current_dir(dir))
            .map(|_| ())
        }
        Compiler::Strucpp => sh(Command::new("g++")
            .args(["-std=c++17", "-w", "-O0", "-I", "."])
            .arg(format!("-I{}", tools.strucpp_include.display()))
            .args(["driver.cpp", "all.cpp", "-o", "driver"])
            .current_dir(dir))
        .map(|_| ()),
    }
}

/// The case (`_17` suffix → 17) a line of generated C/C++ or driver code belongs to: the last
/// case suffix of an identifier on the lines up to it that name a case's POU.
fn case_of_c_line(lines: &[&str], line: usize, pous: &[(String, usize)]) -> Option<usize> {
    for l in lines[..line.min(lines.len())].iter().rev() {
        let up = l.to_ascii_uppercase();
        for (p, k) in pous {
            if up.contains(p.as_str()) {
                return Some(*k);
            }
        }
        if let Some(rest) = l.strip_prefix("static void run").or_else(|| l.strip_prefix("static void put")) {
            let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
            if let Ok(k) = digits.parse() {
                return Some(k);
            }
        }
    }
    None
}

type Results = BTreeMap<usize, Result<Vec<Row>, String>>;

fn idx_of(r: &Ready) -> usize {
    r.suffix[1..].parse().unwrap()
}

/// The compiler's errors about `all.st` (`text`) as `line N: message` lines (at most `n`), or
/// the start of its output when it names no line.
fn errors_of(output: &str, text: &str, n: usize) -> String {
    let lines: Vec<String> =
        error_lines(output, "all.st", text).into_iter().take(n).map(|(l, m)| format!("line {l}: {m}")).collect();
    if lines.is_empty() {
        head(output, n)
    } else {
        lines.join("\n  ")
    }
}

/// Translates one case's ST alone (in `dir`): `Err` with the compiler's errors.
fn translate_alone(c: Compiler, tools: &Tools, st: &str, dir: &Path) -> Result<(), String> {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("all.st"), st).unwrap();
    translate_batch(c, tools, dir).map_err(|e| {
        let what = if e.starts_with("(with OpenPLC") { " with OpenPLC v3's options (-r -R -a)" } else { "" };
        format!("{} refuses the ST{what}:\n  {}", c.label(), errors_of(&e, st, 6))
    })
}

/// One compiler's run of a batch of cases: per case, its rows or why it has none. The cases are
/// compiled together; the cases the compiler refuses are found from the error lines and
/// confirmed alone (MatIEC's parser gives up after errors and then blames the cases after the
/// faulty one: a blamed case it accepts alone stays in the batch, and is compiled on its own
/// when blamed again).
fn run_batch(c: Compiler, tools: &Tools, cases: &[&Ready], dir: &Path) -> Results {
    let mut results = Results::new();
    let mut pending: Vec<&Ready> = cases.to_vec();
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    let ci = c as usize;
    let mut solo: Vec<&Ready> = Vec::new();
    // cases blamed once but accepted alone (MatIEC's parser blames the cases after a faulty one)
    let mut cleared: BTreeSet<usize> = BTreeSet::new();
    let mut round = 0;
    while !pending.is_empty() {
        round += 1;
        let parts: Vec<(usize, &str)> = pending.iter().map(|r| (idx_of(r), r.st[ci].as_str())).collect();
        let (all, owners, conflicts) = concat(&parts);
        if !conflicts.is_empty() {
            for (k, why) in conflicts {
                results.insert(k, Err(format!("harness: {why}")));
            }
            pending.retain(|r| !results.contains_key(&idx_of(r)));
            continue;
        }
        std::fs::write(dir.join("all.st"), &all).unwrap();
        // ST → C / C++
        if let Err(e) = translate_batch(c, tools, dir) {
            // kept for reading: each refused batch and what the compiler said
            std::fs::copy(dir.join("all.st"), dir.join(format!("refused{round}.st"))).unwrap();
            std::fs::write(dir.join(format!("refused{round}.txt")), &e).unwrap();
            let mut blamed = BTreeSet::new();
            for (line, _) in error_lines(&e, "all.st", &all) {
                for &(k, _) in owners.get(line.saturating_sub(1)).map(|v| v.as_slice()).unwrap_or(&[]) {
                    blamed.insert(k);
                }
            }
            if blamed.is_empty() && pending.len() > 1 {
                // not located: halves
                let (a, b) = pending.split_at(pending.len() / 2);
                for half in [a, b] {
                    results.extend(run_batch(c, tools, half, &dir.join(format!("part{}", idx_of(half[0])))));
                }
                pending.clear();
                break;
            }
            if blamed.is_empty() {
                blamed.insert(idx_of(pending[0]));
            }
            for k in blamed {
                let r = pending.iter().find(|r| idx_of(r) == k).unwrap();
                match translate_alone(c, tools, &r.st[ci], &dir.join(format!("alone{k}"))) {
                    Err(e) => {
                        results.insert(k, Err(e));
                    }
                    // accepted alone: refused next to other cases (a cascade of another
                    // case's error, or the cases together): compiled on its own if blamed again
                    Ok(()) if cleared.contains(&k) => solo.push(r),
                    Ok(()) => {
                        cleared.insert(k);
                    }
                }
            }
            pending.retain(|r| !results.contains_key(&idx_of(r)) && !solo.iter().any(|s| idx_of(s) == idx_of(r)));
            continue;
        }
        // the driver
        let located = if c == Compiler::Matiec {
            let text = std::fs::read_to_string(dir.join("beremiz/LOCATED_VARIABLES.h")).unwrap_or_default();
            let mut seen = BTreeSet::new();
            text.lines()
                .filter(|l| l.starts_with("__LOCATED_VAR") && seen.insert(l.to_string()))
                .map(|l| format!("{l}\n"))
                .collect()
        } else {
            String::new()
        };
        let src = driver(c, &pending, &located);
        let name = if c == Compiler::Matiec { "driver.c" } else { "driver.cpp" };
        std::fs::write(dir.join(name), &src).unwrap();
        if let Err(e) = compile_driver(c, tools, dir) {
            std::fs::write(dir.join(format!("cc{round}.txt")), &e).unwrap();
            if pending.len() == 1 {
                let k = idx_of(pending[0]);
                results.insert(k, Err(format!("the {} code does not compile:\n{}", c.label(), head(&e, 12))));
                break;
            }
            // Which case: the POU names before the error line.
            let pous: Vec<(String, usize)> = pending
                .iter()
                .flat_map(|r| {
                    let k = idx_of(r);
                    declared(&r.st[ci])
                        .into_iter()
                        .map(move |(_, n)| (n.to_ascii_uppercase(), k))
                        .filter(move |(n, _)| n.ends_with(&format!("_{k}")))
                })
                .collect();
            let mut blamed = BTreeSet::new();
            for file in ["POUS.c", "all.cpp", "all.hpp", name] {
                let path = if file == "POUS.c" { dir.join("beremiz").join(file) } else { dir.join(file) };
                let text = std::fs::read_to_string(path).unwrap_or_default();
                let lines: Vec<&str> = text.lines().collect();
                for (line, _) in error_lines(&e, file, &text) {
                    if let Some(k) = case_of_c_line(&lines, line, &pous) {
                        blamed.insert(k);
                    }
                }
            }
            if blamed.is_empty() {
                let (a, b) = pending.split_at(pending.len() / 2);
                for half in [a, b] {
                    results.extend(run_batch(c, tools, half, &dir.join(format!("part{}", idx_of(half[0])))));
                }
                pending.clear();
                break;
            }
            for k in blamed {
                solo.push(pending.iter().find(|r| idx_of(r) == k).unwrap());
            }
            pending.retain(|r| !solo.iter().any(|s| idx_of(s) == idx_of(r)));
            continue;
        }
        // run, from the first case not done (a case that crashes or hangs is reported and skipped)
        let mut from = 0;
        while from < pending.len() {
            let out = Command::new("timeout")
                .args(["120", "./driver", &from.to_string()])
                .current_dir(dir)
                .stdin(Stdio::null())
                .output()
                .unwrap();
            let text = String::from_utf8_lossy(&out.stdout);
            let mut current: Option<usize> = None;
            let mut lines: Vec<&str> = Vec::new();
            for l in text.lines() {
                if let Some(k) = l.strip_prefix("@begin ") {
                    current = Some(k.parse().unwrap());
                    lines.clear();
                } else if let Some(k) = l.strip_prefix("@end ") {
                    let k: usize = k.parse().unwrap();
                    let r = pending.iter().find(|r| idx_of(r) == k).unwrap();
                    results.insert(k, parse_rows(r, &lines));
                    current = None;
                    from += 1;
                } else {
                    lines.push(l);
                }
            }
            if !out.status.success() || current.is_some() {
                let k = current.unwrap_or_else(|| idx_of(pending[from.min(pending.len() - 1)]));
                let why = if out.status.code() == Some(124) {
                    "does not finish in 120 s".to_string()
                } else {
                    format!("stops ({})", out.status)
                };
                results.insert(k, Err(format!("the compiled program {why} after {} scans", lines.len())));
                from += 1;
            }
        }
        break;
    }
    for r in solo {
        results.extend(run_batch(c, tools, &[r], &dir.join(format!("solo{}", idx_of(r)))));
    }
    results
}

fn head(text: &str, n: usize) -> String {
    text.lines().filter(|l| !l.trim().is_empty()).take(n).collect::<Vec<_>>().join("\n")
}

fn parse_rows(r: &Ready, lines: &[&str]) -> Result<Vec<Row>, String> {
    let s = &r.shape;
    let mut rows = Vec::new();
    for l in lines {
        let mut cols = l.split('\t');
        let head = cols.next().unwrap_or("");
        let bits = head.split(' ').nth(2).unwrap_or("").as_bytes();
        let mut active: Vec<String> = s
            .steps
            .iter()
            .enumerate()
            .filter(|(i, _)| bits.get(*i) == Some(&b'1'))
            .map(|(_, (n, _))| n.clone())
            .collect();
        active.sort();
        let mut vars = BTreeMap::new();
        for v in &s.vars {
            let raw = cols.next().unwrap_or("");
            let j = match v.kind {
                Kind::Bool => Json::Bool(raw == "1"),
                Kind::Int { unsigned: false } | Kind::Time => Json::from(raw.parse::<i64>().unwrap_or(i64::MIN)),
                Kind::Int { unsigned: true } => Json::from(raw.parse::<u64>().unwrap_or(u64::MAX)),
                Kind::Real | Kind::LReal => Json::from(raw.parse::<f64>().unwrap_or(f64::NAN)),
                Kind::Str => Json::String(raw.to_string()),
            };
            let j = if v.kind == Kind::Time { Json::String(format_time(j.as_i64().unwrap())) } else { j };
            vars.insert(v.name.clone(), j);
        }
        rows.push(Row { active, vars });
    }
    if rows.len() != r.case.scans {
        return Err(format!("the driver printed {} of {} scans", rows.len(), r.case.scans));
    }
    Ok(rows)
}

/// Whether two values of a variable agree (TIME in µs, REAL to single precision).
fn same(kind: Kind, a: &Json, b: &Json) -> bool {
    match kind {
        Kind::Time => a.as_str().and_then(parse_time) == b.as_str().and_then(parse_time),
        Kind::Real => {
            let (x, y) = (a.as_f64().unwrap_or(f64::NAN), b.as_f64().unwrap_or(f64::NAN));
            x as f32 == y as f32 || (x - y).abs() <= 1e-6 * x.abs().max(y.abs())
        }
        Kind::LReal => {
            let (x, y) = (a.as_f64().unwrap_or(f64::NAN), b.as_f64().unwrap_or(f64::NAN));
            x == y || (x - y).abs() <= 1e-12 * x.abs().max(y.abs())
        }
        Kind::Int { .. } => {
            a.as_i64().map(|x| x as i128).or(a.as_u64().map(|x| x as i128))
                == b.as_i64().map(|x| x as i128).or(b.as_u64().map(|x| x as i128))
        }
        _ => a == b,
    }
}

/// The first scan where the compiled rows differ from the chart's: (scan, what).
fn first_divergence(r: &Ready, compiled: &[Row]) -> Option<(usize, String)> {
    divergence(&r.shape, &r.expected, compiled)
}

/// The first scan where `compiled` differs from `expected`, the chart's trace: (scan, what).
fn divergence(shape: &Shape, expected: &[Row], compiled: &[Row]) -> Option<(usize, String)> {
    for (k, (e, a)) in expected.iter().zip(compiled).enumerate() {
        if e.active != a.active {
            return Some((k, format!("active: chart {:?}, compiled {:?}", e.active, a.active)));
        }
        for v in &shape.vars {
            let (Some(x), Some(y)) = (e.vars.get(&v.name), a.vars.get(&v.name)) else {
                return Some((k, format!("{}: not in the trace of sfc sim", v.name)));
            };
            if !same(v.kind, x, y) {
                return Some((k, format!("{}: chart {x}, compiled {y}", v.name)));
            }
        }
    }
    (expected.len() != compiled.len()).then(|| (0, format!("{} scans, {} compiled", expected.len(), compiled.len())))
}

// ---------------------------------------------------------------------------------------------
// The test

/// Cases whose chart itself uses what a compiler does not have, not something the translation
/// adds: (case, compiler, what the refusal says, why). Listed, not failures, as long as the
/// compiler refuses them saying that.
const CHART_FEATURES: &[(&str, Compiler, &str, &str)] = &[
    (
        "semantics/50_programs_are_instances",
        Compiler::Matiec,
        "invalid expression after",
        "another POU reads a PROGRAM's variables as those of a global instance (`Main.Count`)",
    ),
    (
        "semantics/50_programs_are_instances",
        Compiler::Strucpp,
        "Cannot access members of program",
        "another POU reads a PROGRAM's variables as those of a global instance (`Main.Count`)",
    ),
];

#[test]
fn generated_st_runs_like_the_chart() {
    let started = Instant::now();
    let tools = tools();
    let work = work_dir("st-compilers");
    let cases_dir = work.join("cases");
    std::fs::create_dir_all(&cases_dir).unwrap();
    let full = std::env::var("SFC_ST_COMPILERS_FULL").is_ok_and(|v| v == "1");
    let n: usize = std::env::var("SFC_ST_COMPILERS_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(if full {
        300
    } else {
        40
    });
    let mut cases = scenario_cases(&cases_dir);
    cases.extend(fixture_cases());
    cases.extend(random_cases(n, &cases_dir));
    if let Ok(only) = std::env::var("SFC_ST_COMPILERS_ONLY") {
        cases.retain(|c| only.split(',').any(|o| c.name.contains(o)));
    }
    println!("{} cases ({n} random)", cases.len());

    // sfc build and sfc sim of every case, on two threads
    let prepared: Mutex<Vec<(usize, Prepared)>> = Mutex::new(Vec::new());
    let next = Mutex::new(0usize);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let k = {
                    let mut n = next.lock().unwrap();
                    *n += 1;
                    *n - 1
                };
                let Some(case) = cases.get(k) else { break };
                let p = prepare(k, case, &cases_dir);
                prepared.lock().unwrap().push((k, p));
            });
        }
    });
    let mut prepared = prepared.into_inner().unwrap();
    prepared.sort_by_key(|p| p.0);
    let mut skipped = Vec::new();
    let mut failures: Vec<String> = Vec::new();
    let mut ready: Vec<&Ready> = Vec::new();
    for (k, p) in &prepared {
        match p {
            Prepared::Ready(r) => ready.push(r),
            Prepared::Skipped(why) => skipped.push(format!("{}: {why}", cases[*k].name)),
            Prepared::Failed(why) => failures.push(format!("{} (both compilers): {why}", cases[*k].name)),
        }
    }
    println!(
        "prepared in {:.1?}: {} to compile, {} skipped, {} failed",
        started.elapsed(),
        ready.len(),
        skipped.len(),
        failures.len()
    );
    for s in &skipped {
        println!("  skipped {s}");
    }

    // both compilers at once
    let results: Vec<(Compiler, Results)> = std::thread::scope(|s| {
        let handles: Vec<_> = [Compiler::Matiec, Compiler::Strucpp]
            .into_iter()
            .map(|c| {
                let ready = &ready;
                let dir = work.join(c.dialect());
                s.spawn(move || {
                    let t = Instant::now();
                    let r = run_batch(c, tools, ready, &dir);
                    println!("{}: batch done in {:.1?}", c.label(), t.elapsed());
                    (c, r)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });

    let mut report = String::new();
    let mut summary = Vec::new();
    let mut features = Vec::new();
    let mut shown = 0;
    for (c, res) in &results {
        let (mut compiled, mut equal, mut scans) = (0, 0, 0);
        for r in &ready {
            let k: usize = r.suffix[1..].parse().unwrap();
            let st_file = r.dir.join(format!("{}.st", c.dialect()));
            let failure = match res.get(&k) {
                None => Some("no result (harness)".to_string()),
                Some(Err(e)) => {
                    let known = CHART_FEATURES
                        .iter()
                        .find(|(name, cc, says, _)| *name == r.case.name && cc == c && e.contains(says));
                    match known {
                        Some((_, _, _, why)) => {
                            features.push(format!("{} [{}]: {why}", r.case.name, c.label()));
                            None
                        }
                        None => Some(e.clone()),
                    }
                }
                Some(Ok(rows)) => {
                    compiled += 1;
                    match first_divergence(r, rows) {
                        None => {
                            equal += 1;
                            scans += rows.len();
                            None
                        }
                        Some((scan, what)) => {
                            Some(format!("scan {scan} ({}): {what}", format_time(scan as i64 * r.case.period)))
                        }
                    }
                }
            };
            if let Some(f) = failure {
                let line = format!(
                    "{} [{}]: {f}\n  chart {} (POU {}), inputs {}, ST {}",
                    r.case.name,
                    c.label(),
                    r.case.chart.display(),
                    r.case.pou,
                    r.dir.join("iec.scenario.toml").display(),
                    st_file.display()
                );
                writeln!(report, "## {line}\n\n```\n{}```\n", r.st[*c as usize]).unwrap();
                if shown < 3 {
                    failures.push(format!("{line}\n----- ST -----\n{}--------------", r.st[*c as usize]));
                    shown += 1;
                } else {
                    failures.push(line);
                }
            }
        }
        summary.push(format!("{}: {} cases compiled, {} traces equal ({} scans)", c.label(), compiled, equal, scans));
    }
    std::fs::write(work.join("report.md"), &report).unwrap();
    for f in &features {
        println!("  refused for the chart's own features: {f}");
    }
    for s in &summary {
        println!("{s}");
    }
    println!(
        "{} cases: {} compared, {} skipped and {} refused for the chart's features (listed above), {} failures; {:.1?} in all; report in {}",
        cases.len(),
        ready.len(),
        skipped.len(),
        features.len(),
        failures.len(),
        started.elapsed(),
        work.join("report.md").display()
    );
    assert!(failures.is_empty(), "{} failures:\n\n{}\n\n{}", failures.len(), failures.join("\n\n"), summary.join("\n"));
}

// ---------------------------------------------------------------------------------------------
// A MatIEC SFC bug, and the same chart through the ST

/// The inputs of `tests/st_compilers/alternatives.st`: Go for one scan, then Back for one.
fn alternatives_case() -> Case {
    let chart = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/st_compilers/alternatives.st");
    let text = std::fs::read_to_string(&chart).unwrap();
    let mut sets: Vec<Vec<(String, Value)>> = vec![Vec::new(); 8];
    sets[2].push(("Go".into(), Value::Bool(true)));
    sets[3].push(("Go".into(), Value::Bool(false)));
    sets[5].push(("Back".into(), Value::Bool(true)));
    sets[6].push(("Back".into(), Value::Bool(false)));
    Case { name: "alternatives".into(), chart, text, pou: "Alternatives".into(), period: 10_000, scans: 8, sets }
}

fn show(rows: &[Row]) -> String {
    rows.iter().enumerate().map(|(k, r)| format!("  scan {k}: {:?} {:?}\n", r.active, r.vars)).collect()
}

#[test]
fn matiec_sfc_bug_is_gone_through_st() {
    let tools = tools();
    let work = work_dir("st-compilers-alternatives");
    let case = alternatives_case();
    let iec = simulate(&case, &work, "iec").unwrap();
    let matiec = simulate(&case, &work, "matiec").unwrap();
    let shape_of = |suffix: &str| shape(&case, suffix).unwrap();
    assert!(divergence(&shape_of(""), &iec, &matiec).is_some(), "the profiles agree on the chart:\n{}", show(&iec));

    // MatIEC's own SFC: the chart as it is, compiled by iec2c
    let names: BTreeSet<String> = declared(&case.text).into_iter().map(|(_, n)| n.to_ascii_uppercase()).collect();
    let direct = Ready {
        case: case.clone(),
        suffix: "_0".into(),
        shape: shape_of("_0"),
        expected: matiec.clone(),
        st: [rename(&case.text, &names, "_0"), String::new()],
        renames: Default::default(),
        dir: work.clone(),
        sfc_steps: true,
    };
    let rows = run_batch(Compiler::Matiec, tools, &[&direct], &work.join("sfc")).remove(&0).unwrap().unwrap();
    if let Some((k, what)) = divergence(&direct.shape, &matiec, &rows) {
        panic!("MatIEC's SFC differs from --profile matiec at scan {k}: {what}\nMatIEC:\n{}", show(&rows));
    }
    let (k, what) = divergence(&direct.shape, &iec, &rows).expect("MatIEC's SFC runs the chart like --profile iec");
    println!("MatIEC compiling the SFC itself: like --profile matiec, unlike --profile iec from scan {k} ({what})");

    // The same chart through `sfc build --target st --st-dialect matiec` and iec2c
    let ready = match prepare(1, &case, &work.join("cases")) {
        Prepared::Ready(r) => r,
        Prepared::Skipped(why) | Prepared::Failed(why) => panic!("{why}"),
    };
    let rows = match run_batch(Compiler::Matiec, tools, &[&ready], &work.join("st")).remove(&1).unwrap() {
        Ok(rows) => rows,
        Err(e) => panic!("{e}\n{}", ready.st[0]),
    };
    if let Some((k, what)) = first_divergence(&ready, &rows) {
        panic!(
            "through the ST, MatIEC differs from --profile iec at scan {k}: {what}\n{}\n{}",
            show(&rows),
            ready.st[0]
        );
    }
    println!("MatIEC compiling sfc's ST: like --profile iec ({} scans)", rows.len());
}
