//! `--profile matiec` against real MatIEC.
//!
//! * `golden_traces_match_the_profile` (always, CI): every trace recorded from MatIEC-generated C
//!   (`tests/matiec/golden/*.jsonl`) is replayed through `sfc sim --profile matiec` with the same
//!   inputs, and the active steps, fired transitions and variables must agree scan by scan.
//! * `differential_against_matiec` (only with `MATIEC_SRC=dir`, a checkout of MatIEC's source):
//!   builds MatIEC (autoreconf, configure, make) under the target directory, and for the
//!   examples, the semantics fixtures and the random charts (`MATIEC_RANDOM=N`, default 500,
//!   regenerated into `tests/matiec/random/`) runs `iec2c`, compiles the generated C with a
//!   driver written here, runs it scan by scan, records the trace as the golden file and
//!   compares it with `sfc sim --profile matiec`. The charts MatIEC refuses are written to
//!   `tests/matiec/refused.md` with MatIEC's reason.

#[path = "matiec/gen.rs"]
mod gen;

mod common;

use serde_json::{json, Map, Value as Json};
use sfc_sim::{format_time, timespec::Timespec, Profile, SimOptions, Simulation, Value};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}
fn here() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/matiec")
}

/// One chart with its inputs.
struct Case {
    name: String,
    /// Relative to the project root.
    chart: String,
    pou: Option<String>,
    period: i64,
    scans: usize,
    /// Per scan: the values written before it.
    sets: Vec<Vec<(String, Value)>>,
}

/// One scan as both sides report it.
#[derive(Debug, Clone, PartialEq)]
struct Row {
    active: Vec<String>,
    fired: Vec<String>,
    vars: BTreeMap<String, Json>,
}

fn json_of(v: &Value) -> Json {
    match v {
        Value::Bool(b) => json!(b),
        Value::Int(i) => json!(i),
        Value::Real(r) => json!(r),
        Value::Time(t) => json!(format_time(*t)),
        Value::Str(s) => json!(s.as_ref()),
    }
}

fn value_of(j: &Json) -> Value {
    match j {
        Json::Bool(b) => Value::Bool(*b),
        Json::Number(n) if n.is_i64() => Value::Int(n.as_i64().unwrap()),
        Json::Number(n) => Value::Real(n.as_f64().unwrap()),
        Json::String(s) => match sfc_sim::parse_time(s) {
            Some(t) => Value::Time(t),
            None => Value::Str(s.as_str().into()),
        },
        _ => Value::Bool(false),
    }
}

/// Runs `sfc sim --profile matiec` on a case and returns its rows.
fn run_sfc(case: &Case, work: &Path) -> Result<Vec<Row>, String> {
    let mut sc = String::new();
    writeln!(sc, "# inputs of {}", case.name).unwrap();
    writeln!(sc, "chart = {:?}", root().join(&case.chart).display().to_string()).unwrap();
    if let Some(p) = &case.pou {
        writeln!(sc, "pou = {p:?}").unwrap();
    }
    writeln!(sc, "period = \"{}\"\nprofile = \"matiec\"\nscans = {}", format_time(case.period), case.scans).unwrap();
    sc.push_str(&common::scenario_entries(case.period, &case.sets));
    std::fs::create_dir_all(work).unwrap();
    let path = work.join(format!("{}.scenario.toml", case.name));
    std::fs::write(&path, sc).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .arg("sim")
        .arg(root().join(&case.chart))
        .arg("--scenario")
        .arg(&path)
        .args(["--profile", "matiec", "--trace", "-"])
        .output()
        .map_err(|e| e.to_string())?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<Row> = stdout
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| {
            let j: Json = serde_json::from_str(l).unwrap();
            let names = |k: &str| -> Vec<String> {
                j[k].as_array().unwrap().iter().map(|x| x.as_str().unwrap().to_string()).collect()
            };
            let vars = j["vars"].as_object().unwrap().iter().map(|(k, v)| (k.clone(), v.clone())).collect();
            Row { active: names("active"), fired: names("fired"), vars }
        })
        .collect();
    if rows.len() != case.scans {
        return Err(format!(
            "sfc sim wrote {} of {} scans: {}",
            rows.len(),
            case.scans,
            String::from_utf8_lossy(&out.stderr).lines().next().unwrap_or("")
        ));
    }
    Ok(rows)
}

/// The first difference between MatIEC's rows and sfc's, if any.
fn compare(expected: &[Row], actual: &[Row]) -> Option<String> {
    for (k, (e, a)) in expected.iter().zip(actual).enumerate() {
        if e.active != a.active {
            return Some(format!("scan {k}: active MatIEC {:?}, sfc {:?}", e.active, a.active));
        }
        let (mut ef, mut af) = (e.fired.clone(), a.fired.clone());
        ef.sort();
        af.sort();
        if ef != af {
            return Some(format!("scan {k}: fired MatIEC {:?}, sfc {:?}", e.fired, a.fired));
        }
        for (name, ev) in &e.vars {
            match a.vars.get(name) {
                Some(av) if same(ev, av) => {}
                other => return Some(format!("scan {k}: {name} MatIEC {ev}, sfc {}", other.unwrap_or(&Json::Null))),
            }
        }
    }
    (expected.len() != actual.len()).then(|| format!("{} scans from MatIEC, {} from sfc", expected.len(), actual.len()))
}

fn same(a: &Json, b: &Json) -> bool {
    match (a, b) {
        (Json::Number(x), Json::Number(y)) if !(x.is_i64() && y.is_i64()) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            x == y || (x as f32 == y as f32) || (x - y).abs() <= 1e-12 * x.abs().max(y.abs())
        }
        _ => a == b,
    }
}

// ---------------------------------------------------------------------------------------------
// Golden files

fn read_golden(path: &Path) -> (Case, Vec<Row>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Json = serde_json::from_str(lines.next().unwrap()).unwrap();
    let period = sfc_sim::parse_time(head["period"].as_str().unwrap()).unwrap();
    let mut sets = Vec::new();
    let mut rows = Vec::new();
    for l in lines {
        let j: Json = serde_json::from_str(l).unwrap();
        let set =
            j["set"].as_object().map(|m| m.iter().map(|(k, v)| (k.clone(), value_of(v))).collect()).unwrap_or_default();
        sets.push(set);
        let names = |k: &str| -> Vec<String> {
            j[k].as_array().unwrap().iter().map(|x| x.as_str().unwrap().to_string()).collect()
        };
        let vars = j["vars"].as_object().unwrap().iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        rows.push(Row { active: names("active"), fired: names("fired"), vars });
    }
    let case = Case {
        name: path.file_stem().unwrap().to_string_lossy().trim_end_matches(".matiec").to_string(),
        chart: head["chart"].as_str().unwrap().to_string(),
        pou: head["pou"].as_str().map(str::to_string),
        period,
        scans: rows.len(),
        sets,
    };
    (case, rows)
}

fn write_golden(case: &Case, rows: &[Row]) {
    let mut out = String::new();
    let head = json!({"chart": case.chart, "pou": case.pou, "period": format_time(case.period),
        "recorded": "MatIEC iec2c + gcc (x86-64), driver of tests/matiec.rs"});
    out.push_str(&head.to_string());
    out.push('\n');
    for (k, r) in rows.iter().enumerate() {
        let set: Map<String, Json> = case.sets[k].iter().map(|(n, v)| (n.clone(), json_of(v))).collect();
        let vars: Map<String, Json> = r.vars.iter().map(|(n, v)| (n.clone(), v.clone())).collect();
        let line = json!({"scan": k, "set": set, "active": r.active, "fired": r.fired, "vars": vars});
        out.push_str(&line.to_string());
        out.push('\n');
    }
    let dir = here().join("golden");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{}.matiec.jsonl", case.name)), out).unwrap();
}

#[test]
fn golden_traces_match_the_profile() {
    let dir = here().join("golden");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/matiec/golden exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".matiec.jsonl"))
        .collect();
    files.sort();
    assert!(files.len() >= 500, "only {} golden traces", files.len());
    let work = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("matiec-golden");
    let mut failures = Vec::new();
    let mut scans = 0;
    for f in &files {
        let (case, expected) = read_golden(f);
        scans += expected.len();
        match run_sfc(&case, &work) {
            Ok(actual) => {
                if let Some(d) = compare(&expected, &actual) {
                    failures.push(format!("{}: {d}", case.name));
                }
            }
            Err(e) => failures.push(format!("{}: {e}", case.name)),
        }
    }
    println!("{} charts, {scans} scans: {} agree with MatIEC", files.len(), files.len() - failures.len());
    assert!(failures.is_empty(), "{} of {} charts differ:\n{}", failures.len(), files.len(), failures.join("\n"));
}

/// The minimal charts of docs/sim.md ("The `matiec` profile") behave as the page says (their
/// scenarios), and their golden traces from MatIEC are among those checked above.
#[test]
fn documented_charts_behave_as_the_docs_say() {
    let out = Command::new(env!("CARGO_BIN_EXE_sfc")).arg("test").arg(here().join("charts")).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("5 passed, 0 failed"), "{stdout}");
    for stem in ["scan0", "priority", "associations", "time_literals", "whole_second"] {
        assert!(here().join(format!("golden/doc_{stem}.matiec.jsonl")).exists(), "no MatIEC trace of {stem}");
    }
}

// ---------------------------------------------------------------------------------------------
// The differential test against MatIEC built from source

fn sh(cmd: &mut Command) -> Result<String, String> {
    let out = cmd.output().map_err(|e| format!("{cmd:?}: {e}"))?;
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    if out.status.success() {
        Ok(text)
    } else {
        Err(text)
    }
}

/// Builds MatIEC from `src` (once) and returns the build directory (with `iec2c` and `lib/`).
fn build_matiec(src: &Path) -> PathBuf {
    let build = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("matiec-build");
    if build.join("iec2c").exists() {
        return build;
    }
    let _ = std::fs::remove_dir_all(&build);
    sh(Command::new("cp").arg("-r").arg(src).arg(&build)).expect("copy the MatIEC source");
    for step in [vec!["autoreconf", "-i"], vec!["./configure"], vec!["make", "-j2"]] {
        if let Err(e) = sh(Command::new(step[0]).args(&step[1..]).current_dir(&build)) {
            panic!("building MatIEC: `{}` failed:\n{e}", step.join(" "));
        }
    }
    build
}

/// What the driver needs to know of the compiled chart.
struct Shape {
    pou: String,
    /// Qualified step names in declaration order, with their C path (`data.__step_list[0]`).
    steps: Vec<(String, String)>,
    transitions: Vec<(String, String)>,
    /// (name, type, C lvalue)
    vars: Vec<(String, String, String)>,
}

fn shape(case: &Case) -> Result<Shape, String> {
    let path = root().join(&case.chart);
    let text = std::fs::read_to_string(&path).map_err(|e| e.to_string())?;
    let opts = SimOptions { period: case.period, profile: Profile::Matiec };
    let sim = Simulation::from_source(&case.chart, &text, case.pou.as_deref(), opts)
        .map_err(|(_, d)| format!("sfc refuses it: {}", d.first().map(|d| d.message.clone()).unwrap_or_default()))?;
    let c_path = |qualified: &str| -> Result<String, String> {
        let mut p = String::from("data");
        for seg in qualified.split('.') {
            if seg.contains('[') {
                return Err("an SFC instance inside an array".into());
            }
            write!(p, ".{}", seg.to_ascii_uppercase()).unwrap();
        }
        Ok(p)
    };
    let located: Vec<String> = sim.located_vars().into_iter().map(|(n, ..)| n.to_ascii_uppercase()).collect();
    let list = |names: Vec<String>, field: &str| -> Result<Vec<(String, String)>, String> {
        let mut out = Vec::new();
        let mut index: BTreeMap<String, usize> = BTreeMap::new();
        for n in names {
            let (prefix, _) = n.rsplit_once('.').unwrap_or(("", &n));
            let i = index.entry(prefix.to_string()).or_insert(0);
            let base = if prefix.is_empty() { "data".to_string() } else { c_path(prefix)? };
            let access = if field == "X" {
                format!("{base}.__step_list[{i}].X.value")
            } else {
                format!("{base}.__transition_list[{i}].value")
            };
            *i += 1;
            out.push((n, access));
        }
        Ok(out)
    };
    let steps = list(sim.step_names(), "X")?;
    let transitions = list(sim.transition_names(), "tr")?;
    let mut vars = Vec::new();
    for (n, ty) in sim.trace_vars() {
        let lv = if located.contains(&n.to_ascii_uppercase()) {
            format!("(*data.{}.value)", n.to_ascii_uppercase())
        } else {
            format!("data.{}.value", n.to_ascii_uppercase())
        };
        vars.push((n, ty.to_string().to_ascii_uppercase(), lv));
    }
    Ok(Shape { pou: sim.pou_name().to_ascii_uppercase(), steps, transitions, vars })
}

fn c_value(ty: &str, v: &Value) -> String {
    match v {
        Value::Bool(b) => (*b as i32).to_string(),
        Value::Int(i) => format!("{i}LL"),
        Value::Real(r) => format!("{r:?}"),
        Value::Time(us) => {
            let t = Timespec::from_us(*us);
            format!("(({ty}){{{}, {}}})", t.sec, t.nsec)
        }
        Value::Str(_) => "0".into(),
    }
}

fn driver(case: &Case, s: &Shape) -> String {
    let mut c = String::new();
    c.push_str("#include <stdio.h>\n#include \"iec_std_lib.h\"\n");
    c.push_str("#define __LOCATED_VAR(type, name, ...) type __loc_##name; type* name = &__loc_##name;\n");
    c.push_str("#include \"LOCATED_VARIABLES.h\"\n#undef __LOCATED_VAR\n");
    c.push_str("TIME __CURRENT_TIME;\nBOOL __DEBUG = 0;\n#include \"POUS.h\"\n#include \"POUS.c\"\n");
    writeln!(c, "static {} data;\nint main(void) {{", s.pou).unwrap();
    c.push_str("  __CURRENT_TIME = (TIME){0, 0};\n");
    writeln!(c, "  {}_init__(&data, 0);", s.pou).unwrap();
    for k in 0..case.scans {
        for (name, v) in &case.sets[k] {
            let Some((_, ty, lv)) = s.vars.iter().find(|(n, ..)| n.eq_ignore_ascii_case(name)) else {
                let path: Vec<String> = name.split('.').map(|x| x.to_ascii_uppercase()).collect();
                writeln!(c, "  data.{}.value = {};", path.join("."), c_value("TIME", v)).unwrap();
                continue;
            };
            writeln!(c, "  {lv} = {};", c_value(ty, v)).unwrap();
        }
        let t = Timespec::from_us(k as i64 * case.period);
        writeln!(c, "  __CURRENT_TIME = (TIME){{{}, {}}};\n  {}_body__(&data);", t.sec, t.nsec, s.pou).unwrap();
        c.push_str("  printf(\"");
        for _ in &s.steps {
            c.push_str("%d");
        }
        c.push('|');
        for _ in &s.transitions {
            c.push_str("%d");
        }
        for (_, ty, _) in &s.vars {
            c.push_str(match ty.as_str() {
                "BOOL" => "|%d",
                "REAL" => "|%.9g",
                "LREAL" => "|%.17g",
                "TIME" | "LTIME" => "|%ld %ld",
                "ULINT" | "LWORD" => "|%llu",
                t if is_int(t) => "|%lld",
                _ => "|?",
            });
        }
        c.push_str("\\n\"");
        for (_, a) in s.steps.iter().chain(&s.transitions) {
            write!(c, ", (int){a}").unwrap();
        }
        for (_, ty, lv) in &s.vars {
            match ty.as_str() {
                "BOOL" => write!(c, ", (int){lv}").unwrap(),
                "REAL" | "LREAL" => write!(c, ", (double){lv}").unwrap(),
                "TIME" | "LTIME" => write!(c, ", (long){lv}.tv_sec, (long){lv}.tv_nsec").unwrap(),
                "ULINT" | "LWORD" => write!(c, ", (unsigned long long){lv}").unwrap(),
                t if is_int(t) => write!(c, ", (long long){lv}").unwrap(),
                _ => {}
            }
        }
        c.push_str(");\n");
    }
    c.push_str("  return 0;\n}\n");
    c
}

fn is_int(t: &str) -> bool {
    ["SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "BYTE", "WORD", "DWORD"].contains(&t)
}

/// Runs the chart through MatIEC: `Err` says why MatIEC (or the C compiler) refuses it.
fn run_matiec(case: &Case, build: &Path, work: &Path) -> Result<Vec<Row>, String> {
    let s = shape(case)?;
    let dir = work.join(&case.name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let lib = build.join("lib");
    // iec2c can loop on an error forever, printing: bound its time and what is kept of its output.
    let out = sh(Command::new("bash")
        .arg("-c")
        .arg("set -o pipefail; timeout 30 \"$0\" -I \"$1\" -T \"$2\" \"$3\" 2>&1 | head -c 20000")
        .arg(build.join("iec2c"))
        .arg(&lib)
        .arg(&dir)
        .arg(root().join(&case.chart)));
    if let Err(e) = out {
        let first = e.lines().find(|l| l.contains("error")).or_else(|| e.lines().next()).unwrap_or("").trim();
        // MatIEC's message without the path: `file.st:15: error: …` → `line 15: …`.
        let short = match first.split_once(".st:") {
            Some((_, rest)) => format!("line {}", rest.replacen(": error:", ":", 1)),
            None => first.to_string(),
        };
        let text = std::fs::read_to_string(root().join(&case.chart)).unwrap_or_default();
        return Err(format!("{} (iec2c, {short})", cause(&text, first)));
    }
    std::fs::write(dir.join("driver.c"), driver(case, &s)).unwrap();
    if let Err(e) = sh(Command::new("gcc")
        .args(["-w", "-O0", "-I"])
        .arg(&dir)
        .arg("-I")
        .arg(lib.join("C"))
        .arg(dir.join("driver.c"))
        .arg("-o")
        .arg(dir.join("driver"))
        .arg("-lm"))
    {
        let why = e.lines().find(|l| l.contains("error")).unwrap_or("").trim().to_string();
        return Err(format!("the generated C does not compile: {why}"));
    }
    let text =
        sh(Command::new("timeout").arg("60").arg(dir.join("driver"))).map_err(|e| format!("the driver failed: {e}"))?;
    let mut rows = Vec::new();
    for line in text.lines() {
        let mut parts = line.split('|');
        let xs = parts.next().unwrap_or("").as_bytes();
        let trs = parts.next().unwrap_or("").as_bytes();
        let mut active: Vec<String> = s
            .steps
            .iter()
            .enumerate()
            .filter(|(i, _)| xs.get(*i) == Some(&b'1'))
            .map(|(_, (n, _))| n.clone())
            .collect();
        active.sort();
        let fired = s
            .transitions
            .iter()
            .enumerate()
            .filter(|(i, _)| trs.get(*i) == Some(&b'1'))
            .map(|(_, (n, _))| n.clone())
            .collect();
        let mut vars = BTreeMap::new();
        for ((name, ty, _), raw) in s.vars.iter().zip(parts) {
            let v = match ty.as_str() {
                "BOOL" => json!(raw == "1"),
                "REAL" | "LREAL" => json!(raw.parse::<f64>().unwrap_or(f64::NAN)),
                "TIME" | "LTIME" => {
                    let mut it = raw.split(' ').map(|x| x.parse::<i64>().unwrap_or(0));
                    let t = Timespec { sec: it.next().unwrap_or(0), nsec: it.next().unwrap_or(0) };
                    json!(format_time(t.to_us()))
                }
                "ULINT" | "LWORD" => json!(raw.parse::<u64>().unwrap_or(0) as i64),
                t if is_int(t) => json!(raw.parse::<i64>().unwrap_or(0)),
                _ => continue,
            };
            vars.insert(name.clone(), v);
        }
        rows.push(Row { active, fired, vars });
    }
    if rows.len() != case.scans {
        return Err(format!("the driver printed {} of {} scans", rows.len(), case.scans));
    }
    Ok(rows)
}

/// What in the chart makes MatIEC refuse it, judged from the text and MatIEC's first error.
fn cause(text: &str, error: &str) -> String {
    let lower = text.to_ascii_lowercase();
    let mut causes = Vec::new();
    let in_chart = |needle: &str| {
        lower.match_indices(needle).any(|(i, _)| {
            let before = &lower[..i];
            before.rfind("step ").is_some()
                && before.rfind("end_var").is_some_and(|v| before.rfind("step ").unwrap() > v)
        })
    };
    if in_chart("{attribute") || in_chart("{") {
        causes.push("a pragma inside the chart");
    }
    if lower.contains(".q ")
        || lower.contains(".q;")
        || lower.contains(".q)")
        || lower.contains(".a ")
        || lower.contains(".a;")
    {
        causes.push("`Action.Q` / `Action.A`");
    }
    if (lower.contains("us)") || lower.contains("us;") || lower.contains("us ") && lower.contains("t#"))
        && lower.split("t#").skip(1).any(|t| {
            t.trim_start_matches(|c: char| c.is_ascii_digit() || c == '.' || c.is_ascii_alphabetic() && c != 'u')
                .starts_with("us")
        })
    {
        causes.push("a duration in `us`");
    }
    if lower.contains(" at %") && lower.matches("var").count() > 2 {
        causes.push("located variables in a VAR block MatIEC does not take them in");
    }
    if lower.contains("and_then") || lower.contains("or_else") {
        causes.push("`AND_THEN` / `OR_ELSE`");
    }
    if error.contains("unexpected token after SFC network") && causes.is_empty() {
        causes.push("a network that does not start with its initial step, or a step named before it is declared");
    }
    if error.contains("invalid variable") && causes.is_empty() {
        causes.push("a name MatIEC reserves (a standard function such as `EQ`, or a keyword)");
    }
    if causes.is_empty() {
        causes.push("not supported by MatIEC");
    }
    causes.join("; ")
}

/// The examples and the semantics fixtures with the inputs of their scenarios.
fn scenario_cases() -> Vec<Case> {
    let mut out = Vec::new();
    let mut add = |scenario: PathBuf, name: String| {
        let Ok(sc) = sfc_sim::scenario::load(&scenario) else { return };
        let period = sc.options.period;
        let last = sc.entries.iter().map(|e| e.time).max().unwrap_or(0);
        let scans = match sc.length {
            sfc_sim::scenario::RunLength::Scans(n) => n as usize,
            sfc_sim::scenario::RunLength::Until(t) => (t / period) as usize + 1,
            sfc_sim::scenario::RunLength::LastEntry => (last + period - 1) as usize / period as usize + 1,
        };
        let mut sets: Vec<Vec<(String, Value)>> = vec![Vec::new(); scans];
        for e in &sc.entries {
            let k = ((e.time + period - 1) / period) as usize;
            if k < scans {
                sets[k].extend(e.set.iter().cloned());
            }
        }
        let chart = sc.chart.canonicalize().unwrap();
        let chart = chart.strip_prefix(root()).unwrap().to_string_lossy().into_owned();
        out.push(Case { name, chart, pou: Some(sc.pou.clone()), period, scans, sets });
    };
    let mut examples: Vec<PathBuf> = std::fs::read_dir(root().join("examples"))
        .unwrap()
        .flat_map(|d| std::fs::read_dir(d.unwrap().path()).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".scenario.toml"))
        .collect();
    examples.sort();
    for p in examples {
        let stem = p.file_name().unwrap().to_string_lossy().trim_end_matches(".scenario.toml").to_string();
        add(p, format!("example_{stem}"));
    }
    let mut docs: Vec<PathBuf> = std::fs::read_dir(here().join("charts"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".scenario.toml"))
        .collect();
    docs.sort();
    for p in docs {
        let stem = p.file_name().unwrap().to_string_lossy().trim_end_matches(".scenario.toml").to_string();
        add(p, format!("doc_{stem}"));
    }
    let fixtures = root().join("crates/sfc-sim/tests/semantics");
    let mut charts: Vec<PathBuf> = std::fs::read_dir(&fixtures)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    charts.sort();
    for chart in charts {
        let stem = chart.file_stem().unwrap().to_string_lossy().into_owned();
        add(fixtures.join(format!("{stem}.scenario.toml")), format!("fixture_{stem}"));
    }
    out
}

/// Charts from other tools' own material (`../shared/corpus`), with inputs toggled at random.
fn corpus_cases() -> Vec<Case> {
    let chart = "../shared/corpus/matiec/sfc.txt";
    if !root().join(chart).exists() {
        return Vec::new();
    }
    let mut r = gen::Rng::new(7);
    let mut sets = Vec::new();
    for _ in 0..60 {
        let mut row = Vec::new();
        for n in ["IX1", "IX2", "IX3"] {
            if r.chance(20) {
                row.push((n.to_string(), Value::Bool(r.chance(50))));
            }
        }
        sets.push(row);
    }
    vec![Case {
        name: "corpus_matiec_sfc".into(),
        chart: chart.into(),
        pou: Some("MAIN_TEST".into()),
        period: 10_000,
        scans: 60,
        sets,
    }]
}

fn random_cases(n: u64) -> Vec<Case> {
    let dir = here().join("random");
    std::fs::create_dir_all(&dir).unwrap();
    (1..=n)
        .map(|seed| {
            let g = gen::chart(seed);
            let name = format!("random_{seed:03}");
            std::fs::write(dir.join(format!("{name}.st")), &g.text).unwrap();
            let sets =
                g.sets.into_iter().map(|row| row.into_iter().map(|(n, b)| (n, Value::Bool(b))).collect()).collect();
            Case {
                name: name.clone(),
                chart: format!("crates/sfc-cli/tests/matiec/random/{name}.st"),
                pou: Some(format!("R{seed}")),
                period: sfc_sim::parse_time(&g.period).unwrap(),
                scans: g.scans,
                sets,
            }
        })
        .collect()
}

#[test]
fn differential_against_matiec() {
    let Some(src) = std::env::var_os("MATIEC_SRC") else {
        println!("MATIEC_SRC not set: the differential test against MatIEC is skipped (the golden traces are checked)");
        return;
    };
    let build = build_matiec(Path::new(&src));
    let n: u64 = std::env::var("MATIEC_RANDOM").ok().and_then(|v| v.parse().ok()).unwrap_or(500);
    let work = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("matiec-runs");
    let mut cases = scenario_cases();
    cases.extend(corpus_cases());
    cases.extend(random_cases(n));
    // MATIEC_ONLY=prefix,… runs only the cases whose name starts with one of them (`doc_`).
    if let Ok(only) = std::env::var("MATIEC_ONLY") {
        cases.retain(|c| only.split(',').any(|p| c.name.starts_with(p)));
    }
    let mut refused = Vec::new();
    let mut failures = Vec::new();
    let mut agreed = 0;
    for case in &cases {
        match run_matiec(case, &build, &work) {
            Err(why) => refused.push((case.chart.clone(), why)),
            Ok(rows) => {
                write_golden(case, &rows);
                match run_sfc(case, &work) {
                    Ok(actual) => match compare(&rows, &actual) {
                        None => agreed += 1,
                        Some(d) => failures.push(format!("{} ({}): {d}", case.name, case.chart)),
                    },
                    Err(e) => failures.push(format!("{}: {e}", case.name)),
                }
            }
        }
    }
    let mut md = String::from(
        "# Charts MatIEC refuses\n\nWritten by `MATIEC_SRC=… cargo test -p sfc-cli --test matiec` \
         (`differential_against_matiec`): the examples and semantics fixtures that MatIEC's `iec2c` \
         (or the C compiler, on the C it generates) does not accept, with the first error it gives. \
         They are not compared.\n\n| chart | why |\n|---|---|\n",
    );
    refused.dedup();
    for (chart, why) in &refused {
        writeln!(md, "| `{chart}` | {} |", why.replace('|', "\\|")).unwrap();
    }
    for (chart, why) in &refused {
        println!("refused: {chart}: {why}");
    }
    if std::env::var("MATIEC_ONLY").is_err() {
        std::fs::write(here().join("refused.md"), md).unwrap();
    }
    println!(
        "{} charts: {agreed} agree with MatIEC, {} differ, {} refused by MatIEC",
        cases.len(),
        failures.len(),
        refused.len()
    );
    assert!(failures.is_empty(), "{} charts differ:\n{}", failures.len(), failures.join("\n"));
}
