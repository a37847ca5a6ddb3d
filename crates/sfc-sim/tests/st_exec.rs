//! Runs the ST/IL execution fixtures in `tests/st/*.st` (syntax in `tests/st/README.md`): each
//! is a program a user could have written, with its expected values and faults written as
//! `(*! … *)` comments. Also unit tests of `Program::resolve` and `Program::instantiate`.

use sfc_diagnostics::{render_human, RenderOptions, SourceFile};
use sfc_model::{check_source, CheckOptions};
use sfc_sim::code::{Ctx, Fault, PouBody, Program};
use sfc_sim::engine::ScanSink;
use sfc_sim::{Profile, Value};
use sfc_st::Type;
use std::path::{Path, PathBuf};

#[derive(Debug)]
struct Expect {
    line: u32,
    /// After this scan (0-based); `None`: at the end.
    scan: Option<u64>,
    path: String,
    approx: bool,
    value: String,
}

#[derive(Debug, Default)]
struct Spec {
    scans: u64,
    period: i64,
    pou: Option<String>,
    expects: Vec<Expect>,
    /// (line of the comment, expected line, column, message part)
    fault: Option<(u32, u32, u32, String)>,
}

fn directives(text: &str) -> Result<Spec, String> {
    let mut spec = Spec { scans: 1, period: 10_000, ..Default::default() };
    for (i, line) in text.lines().enumerate() {
        let n = i as u32 + 1;
        let mut rest = line;
        while let Some(start) = rest.find("(*!") {
            let after = &rest[start + 3..];
            let end = after.find("*)").ok_or_else(|| format!("line {n}: unterminated (*! comment"))?;
            let d = after[..end].trim();
            rest = &after[end..];
            let (word, arg) = d.split_once(char::is_whitespace).unwrap_or((d, ""));
            let arg = arg.trim();
            match word {
                "scans" => spec.scans = arg.parse().map_err(|_| format!("line {n}: bad scan count"))?,
                "period" => spec.period = sfc_sim::parse_time(arg).ok_or_else(|| format!("line {n}: bad period"))?,
                "pou" => spec.pou = Some(arg.to_string()),
                "fault" => {
                    let (pos, msg) = arg.split_once(char::is_whitespace).unwrap_or((arg, ""));
                    let (l, c) = pos.split_once(':').ok_or_else(|| format!("line {n}: fault needs LINE:COL"))?;
                    let l = l.parse().map_err(|_| format!("line {n}: bad fault line"))?;
                    let c = c.parse().map_err(|_| format!("line {n}: bad fault column"))?;
                    spec.fault = Some((n, l, c, msg.trim().to_string()));
                }
                w if w == "expect" || w.starts_with("expect[") => {
                    let scan = match w.strip_prefix("expect[") {
                        Some(s) => {
                            Some(s.trim_end_matches(']').parse().map_err(|_| format!("line {n}: bad scan in {w}"))?)
                        }
                        None => None,
                    };
                    let (path, approx, value) = if let Some((p, v)) = arg.split_once("~=") {
                        (p, true, v)
                    } else if let Some((p, v)) = arg.split_once('=') {
                        (p, false, v)
                    } else {
                        return Err(format!("line {n}: expect needs `path = value`"));
                    };
                    spec.expects.push(Expect {
                        line: n,
                        scan,
                        path: path.trim().to_string(),
                        approx,
                        value: value.trim().to_string(),
                    });
                }
                other => return Err(format!("line {n}: unknown directive `{other}`")),
            }
        }
    }
    Ok(spec)
}

/// An expected integer as written: `-5`, `16#FF`, `2#1010`.
fn parse_int(text: &str) -> Option<i128> {
    let t = text.trim().replace('_', "");
    let (neg, body) = match t.strip_prefix('-') {
        Some(b) => (true, b.to_string()),
        None => (false, t.clone()),
    };
    let v = sfc_syntax::literal::decode_int(&body, Default::default()).ok()? as i128;
    Some(if neg { -v } else { v })
}

fn unsigned64(ty: &Type) -> bool {
    matches!(ty.base(), Type::ULInt | Type::LWord)
}

/// Whether `actual` of type `ty` matches the expectation text.
fn matches(ty: &Type, actual: &Value, e: &Expect) -> Result<bool, String> {
    let text = e.value.as_str();
    let bad = || format!("cannot read `{text}` as a `{ty}`");
    Ok(match ty.base() {
        Type::Bool => {
            let want = match text.to_ascii_uppercase().as_str() {
                "TRUE" | "1" => true,
                "FALSE" | "0" => false,
                _ => return Err(bad()),
            };
            actual == &Value::Bool(want)
        }
        Type::Real | Type::LReal => {
            let Value::Real(a) = actual else { return Ok(false) };
            let want: f64 = match text.to_ascii_lowercase().as_str() {
                "inf" => f64::INFINITY,
                "-inf" => f64::NEG_INFINITY,
                "nan" => return Ok(a.is_nan()),
                t => t.parse().map_err(|_| bad())?,
            };
            let want = if ty.base() == &Type::Real { want as f32 as f64 } else { want };
            if e.approx {
                (a - want).abs() <= 1e-6 * want.abs().max(1.0)
            } else {
                *a == want
            }
        }
        Type::Time | Type::LTime => {
            let want = sfc_sim::parse_time(text).ok_or_else(bad)?;
            actual == &Value::Time(want)
        }
        Type::String { .. } | Type::WString { .. } => {
            let want = sfc_syntax::literal::decode_string(text, Default::default()).map_err(|_| bad())?;
            matches!(actual, Value::Str(s) if **s == *want)
        }
        Type::Date | Type::TimeOfDay | Type::DateAndTime => {
            let want = match sfc_syntax::literal::decode_typed(text, Default::default()).map_err(|_| bad())?.0 {
                sfc_syntax::ast::LiteralKind::Date(d) => d * 86_400_000_000,
                sfc_syntax::ast::LiteralKind::TimeOfDay(us) | sfc_syntax::ast::LiteralKind::DateAndTime(us) => us,
                _ => return Err(bad()),
            };
            actual == &Value::Int(want)
        }
        Type::Enum { .. } => {
            let want = ty.enum_value(text).map(i128::from).or_else(|| parse_int(text)).ok_or_else(bad)?;
            matches!(actual, Value::Int(a) if i128::from(*a) == want)
        }
        _ => {
            let want = parse_int(text).ok_or_else(bad)?;
            let Value::Int(a) = actual else { return Ok(false) };
            let a = if unsigned64(ty) { i128::from(*a as u64) } else { i128::from(*a) };
            a == want
        }
    })
}

fn render(file: &SourceFile, diags: &[sfc_diagnostics::Diagnostic]) -> String {
    diags.iter().map(|d| render_human(d, std::slice::from_ref(file), RenderOptions::default())).collect()
}

/// Checks and compiles a source text.
fn build(name: &str, text: &str) -> Result<(Program, SourceFile), String> {
    let checked = check_source(0, name, text, &CheckOptions { keep_types: true, ..Default::default() });
    if checked.has_errors() {
        return Err(format!("{name}: does not check:\n{}", render(&checked.file, &checked.diagnostics)));
    }
    let file = checked.file.clone();
    match Program::compile(&checked.unit, checked.charts, &checked.expr_types) {
        Ok(p) => Ok((p, file)),
        Err(d) => Err(format!("{name}: does not compile:\n{}", render(&file, &d))),
    }
}

fn run_fixture(path: &Path) -> Result<(), String> {
    let name = path.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let spec = directives(&text).map_err(|e| format!("{name}: {e}"))?;
    let (prog, file) = build(&name, &text)?;
    let top = match &spec.pou {
        Some(p) => prog.pou(p).ok_or_else(|| format!("{name}: no POU `{p}`"))?,
        None => prog
            .pous
            .iter()
            .position(|p| p.kind == sfc_syntax::ast::PouKind::Program)
            .ok_or_else(|| format!("{name}: no PROGRAM"))?,
    };
    let PouBody::Code(body) = &prog.pous[top].body else {
        return Err(format!("{name}: the top POU must have an ST or IL body"));
    };
    for e in &spec.expects {
        if prog.resolve(top, 0, &e.path).is_none() {
            return Err(format!("{name}:{}: cannot resolve `{}`", e.line, e.path));
        }
    }
    let mut mem = prog.instantiate(top);
    let mut failures: Vec<String> = Vec::new();
    let check = |mem: &[Value], top_frame: usize, scan: Option<u64>, failures: &mut Vec<String>| {
        for e in spec.expects.iter().filter(|e| e.scan == scan || (scan.is_none() && e.scan.is_none())) {
            let Some((slot, ty)) = prog.resolve(top, top_frame, &e.path) else { continue };
            match matches(&ty, &mem[slot], e) {
                Ok(true) => {}
                Ok(false) => failures.push(format!(
                    "{name}:{}: {}{} is {:?}, expected {}",
                    e.line,
                    e.path,
                    e.scan.map(|s| format!(" after scan {s}")).unwrap_or_default(),
                    mem[slot],
                    e.value
                )),
                Err(msg) => failures.push(format!("{name}:{}: {msg}", e.line)),
            }
        }
    };
    let mut fault: Option<Fault> = None;
    for k in 0..spec.scans {
        let mut charts = Vec::new();
        let mut sink = ScanSink::default();
        let mut ctx = Ctx {
            mem: &mut mem.mem,
            prog: &prog,
            charts: &mut charts,
            sink: &mut sink,
            now: k as i64 * spec.period,
            scan: k,
            profile: Profile::Iec,
            budget: Default::default(),
        };
        if let Err(f) = body(&mut ctx, mem.top_frame) {
            fault = Some(f);
            break;
        }
        check(&mem.mem, mem.top_frame, Some(k), &mut failures);
    }
    check(&mem.mem, mem.top_frame, None, &mut failures);
    match (&spec.fault, &fault) {
        (None, None) => {}
        (None, Some(f)) => {
            let lc = file.line_col(f.span.start);
            failures.push(format!("{name}: unexpected fault at {}:{}: {}", lc.line, lc.column, f.message));
        }
        (Some((n, ..)), None) => failures.push(format!("{name}:{n}: expected a fault, the program ran through")),
        (Some((n, l, c, msg)), Some(f)) => {
            let lc = file.line_col(f.span.start);
            if (lc.line, lc.column) != (*l, *c) || !f.message.contains(msg.as_str()) {
                failures.push(format!(
                    "{name}:{n}: expected fault at {l}:{c} `{msg}`, got {}:{} `{}`",
                    lc.line, lc.column, f.message
                ));
            }
        }
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(failures.join("\n"))
    }
}

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/st");
    let mut out: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/st exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "st"))
        .collect();
    out.sort();
    out
}

#[test]
fn st_fixtures() {
    let files = fixtures();
    assert!(!files.is_empty(), "fixtures are missing");
    let only = std::env::var("ST_FIXTURE").ok();
    let mut failures = Vec::new();
    for f in &files {
        if only.as_deref().is_some_and(|o| !f.to_string_lossy().contains(o)) {
            continue;
        }
        if let Err(e) = run_fixture(f) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{} fixture(s) failed:\n{}", failures.len(), failures.join("\n\n"));
}

const NESTED: &str = "\
TYPE Point : STRUCT X, Y : INT; END_STRUCT; END_TYPE
VAR_GLOBAL Alarm : BOOL; Limits : ARRAY [1..3] OF INT := [10, 20, 30]; END_VAR
FUNCTION_BLOCK Seq
VAR_INPUT Go : BOOL; END_VAR
VAR_OUTPUT Busy : BOOL; END_VAR
INITIAL_STEP Idle: END_STEP
TRANSITION FROM Idle TO OpenKM1 := Go; END_TRANSITION
STEP OpenKM1: Work(N); END_STEP
TRANSITION FROM OpenKM1 TO Idle := NOT Go; END_TRANSITION
ACTION Work: Busy := TRUE; END_ACTION
END_FUNCTION_BLOCK
FUNCTION_BLOCK Cell
VAR_INPUT On : BOOL; END_VAR
VAR Seq1 : Seq; END_VAR
Seq1(Go := On);
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  Start : BOOL := TRUE;
  Rev : Seq;
  Cells : ARRAY [1..2] OF Cell;
  Arr : ARRAY [0..4] OF DINT := [1, 2, 3(7)];
  Grid : ARRAY [1..2, 1..3] OF SINT;
  Pt : Point := (X := 3, Y := 4);
  T1 : TON := (PT := T#2s);
END_VAR
INITIAL_STEP S1: Act(N); END_STEP
TRANSITION FROM S1 TO S2 := Start; END_TRANSITION
STEP S2: END_STEP
TRANSITION FROM S2 TO S1 := S2.T > T#1s AND Rev.Busy; END_TRANSITION
ACTION Act:
  Rev(Go := Start);
  T1(IN := Start);
  Alarm := Rev.SFCError;
END_ACTION
END_PROGRAM
";

#[test]
fn resolve_paths() {
    let (prog, _) = build("nested.st", NESTED).unwrap_or_else(|e| panic!("{e}"));
    let top = prog.pou("main").expect("Main");
    let mem = prog.instantiate(top);
    let f = mem.top_frame;
    let get = |p: &str| prog.resolve(top, f, p).map(|(s, t)| (mem.mem[s].clone(), t));
    assert_eq!(get("Start"), Some((Value::Bool(true), Type::Bool)));
    assert_eq!(get("start").map(|x| x.1), Some(Type::Bool), "case-insensitive");
    assert_eq!(get("Alarm").map(|x| x.1), Some(Type::Bool));
    assert_eq!(get("Limits[2]"), Some((Value::Int(20), Type::Int)));
    assert_eq!(get("Arr[0]"), Some((Value::Int(1), Type::DInt)));
    assert_eq!(get("Arr[4]"), Some((Value::Int(7), Type::DInt)));
    assert_eq!(get("Arr[5]"), None, "out of range");
    assert_eq!(get("Grid[2, 3]").map(|x| x.1), Some(Type::SInt));
    assert_eq!(get("Pt.Y"), Some((Value::Int(4), Type::Int)));
    assert_eq!(get("Pt"), None, "not elementary");
    assert_eq!(get("S2.X"), Some((Value::Bool(false), Type::Bool)));
    assert_eq!(get("S2.T"), Some((Value::Time(0), Type::Time)));
    assert_eq!(get("Act.Q").map(|x| x.1), Some(Type::Bool));
    assert_eq!(get("Act.A").map(|x| x.1), Some(Type::Bool));
    assert_eq!(get("Rev.Busy").map(|x| x.1), Some(Type::Bool));
    assert_eq!(get("Rev.OpenKM1.X").map(|x| x.1), Some(Type::Bool));
    assert_eq!(get("Rev.Work.Q").map(|x| x.1), Some(Type::Bool));
    assert_eq!(get("Rev.SFCError").map(|x| x.1), Some(Type::Bool));
    assert_eq!(get("Rev.SFCCurrentStep").map(|x| x.1), Some(Type::String { len: None }));
    assert_eq!(get("SFCInit").map(|x| x.1), Some(Type::Bool), "the top chart's own control input");
    assert_eq!(get("Cells[2].Seq1.Idle.X").map(|x| x.1), Some(Type::Bool));
    assert_eq!(get("T1.PT"), Some((Value::Time(2_000_000), Type::Time)));
    assert_eq!(get("T1.Q"), Some((Value::Bool(false), Type::Bool)));
    assert_eq!(get("Nope"), None);
    assert_eq!(get("Rev.Nope"), None);
    assert_eq!(get("S2.Y"), None);
    // Distinct variables have distinct slots.
    let a = prog.resolve(top, f, "Rev.Busy").expect("slot").0;
    let b = prog.resolve(top, f, "Cells[1].Seq1.Busy").expect("slot").0;
    let c = prog.resolve(top, f, "Cells[2].Seq1.Busy").expect("slot").0;
    assert!(a != b && b != c && a != c);
}

#[test]
fn instantiate_lists_sfc_instances() {
    let (prog, _) = build("nested.st", NESTED).unwrap_or_else(|e| panic!("{e}"));
    let top = prog.pou("Main").expect("Main");
    let mem = prog.instantiate(top);
    let paths: Vec<&str> = mem.charts.iter().map(|c| c.path.as_str()).collect();
    assert_eq!(paths, ["", "Rev", "Cells[1].Seq1", "Cells[2].Seq1"]);
    // A PROGRAM is one instance, the global named after it: run as the top, that is its frame.
    let main = prog.globals.vars.iter().find(|v| v.name == "Main" && v.implicit).expect("Main's instance");
    assert_eq!(mem.top_frame, main.offset as usize);
    for (i, c) in mem.charts.iter().enumerate() {
        let PouBody::Chart(cc) = &prog.pous[c.pou].body else { panic!("an SFC POU") };
        assert_eq!(mem.mem[c.frame + cc.chart_slot as usize], Value::Int(i as i64), "chart slot of {}", c.path);
    }
    let layout = &prog.pous[prog.pou("Seq").expect("Seq")].layout;
    let implicit: Vec<&str> = layout.vars.iter().filter(|v| v.implicit).map(|v| v.name.as_str()).collect();
    assert_eq!(implicit, ["SFCInit", "SFCPause", "SFCQuitError", "SFCError", "SFCErrorStep", "SFCCurrentStep"]);
}

#[test]
fn atmt_inputs_are_implicit_variables() {
    let text = "{attribute 'sfc.target' := 'atmt'}\nPROGRAM A\nINITIAL_STEP S0: END_STEP\n\
                TRANSITION FROM S0 TO S1 := C3; END_TRANSITION\nSTEP S1: END_STEP\n\
                TRANSITION FROM S1 TO S0 := C15; END_TRANSITION\nEND_PROGRAM\n";
    let (prog, _) = build("atmt.st", text).unwrap_or_else(|e| panic!("{e}"));
    let top = prog.pou("A").expect("A");
    let names: Vec<&str> = prog.pous[top].layout.vars.iter().filter(|v| v.implicit).map(|v| v.name.as_str()).collect();
    assert!(names.contains(&"C0") && names.contains(&"C15") && !names.contains(&"C16"), "{names:?}");
    let mut mem = prog.instantiate(top);
    let (slot, _) = prog.resolve(top, mem.top_frame, "c3").expect("C3");
    let PouBody::Chart(cc) = &prog.pous[top].body else { panic!("chart") };
    let mut charts = Vec::new();
    let mut sink = ScanSink::default();
    let mut ctx = Ctx {
        mem: &mut mem.mem,
        prog: &prog,
        charts: &mut charts,
        sink: &mut sink,
        now: 0,
        scan: 0,
        profile: Profile::Iec,
        budget: Default::default(),
    };
    assert_eq!((cc.guards[0])(&mut ctx, mem.top_frame), Ok(false));
    ctx.mem[slot] = Value::Bool(true);
    assert_eq!((cc.guards[0])(&mut ctx, mem.top_frame), Ok(true));
}

#[test]
fn guards_read_step_times() {
    let (prog, _) = build("nested.st", NESTED).unwrap_or_else(|e| panic!("{e}"));
    let top = prog.pou("Main").expect("Main");
    let mut mem = prog.instantiate(top);
    let PouBody::Chart(cc) = &prog.pous[top].body else { panic!("chart") };
    let (t, _) = prog.resolve(top, mem.top_frame, "S2.T").expect("S2.T");
    let (busy, _) = prog.resolve(top, mem.top_frame, "Rev.Busy").expect("Rev.Busy");
    let mut charts = Vec::new();
    let mut sink = ScanSink::default();
    let mut ctx = Ctx {
        mem: &mut mem.mem,
        prog: &prog,
        charts: &mut charts,
        sink: &mut sink,
        now: 0,
        scan: 0,
        profile: Profile::Iec,
        budget: Default::default(),
    };
    assert_eq!((cc.guards[0])(&mut ctx, mem.top_frame), Ok(true), "Start is TRUE initially");
    assert_eq!((cc.guards[1])(&mut ctx, mem.top_frame), Ok(false));
    ctx.mem[t] = Value::Time(1_500_000);
    ctx.mem[busy] = Value::Bool(true);
    assert_eq!((cc.guards[1])(&mut ctx, mem.top_frame), Ok(true));
}

#[test]
fn self_containing_block_cannot_be_simulated() {
    let text = "FUNCTION_BLOCK A\nVAR inner : B; END_VAR\n;\nEND_FUNCTION_BLOCK\n\
                FUNCTION_BLOCK B\nVAR inner : A; END_VAR\n;\nEND_FUNCTION_BLOCK\n\
                PROGRAM P\nVAR x : A; END_VAR\nx();\nEND_PROGRAM\n";
    let checked = check_source(0, "rec.st", text, &CheckOptions { keep_types: true, ..Default::default() });
    let errors: Vec<_> = checked.diagnostics.iter().filter(|d| d.is_error()).collect();
    assert!(errors.is_empty(), "{errors:?}");
    let r = Program::compile(&checked.unit, checked.charts, &checked.expr_types);
    let Err(d) = r else { panic!("compiled a block that contains itself") };
    assert!(d.iter().all(|d| d.code == "SFC0320"), "{d:?}");

    // A FUNCTION's frame lasts one call: it cannot hold a chart instance.
    let text = "FUNCTION_BLOCK Seq\nINITIAL_STEP S0: END_STEP\nEND_FUNCTION_BLOCK\n\
                FUNCTION F : BOOL\nVAR s : Seq; END_VAR\ns();\nF := TRUE;\nEND_FUNCTION\n";
    let checked = check_source(0, "f.st", text, &CheckOptions { keep_types: true, ..Default::default() });
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    let r = Program::compile(&checked.unit, checked.charts, &checked.expr_types);
    let Err(d) = r else { panic!("compiled a chart inside a function") };
    assert_eq!(d.len(), 1, "{d:?}");
    assert!(d[0].message.contains("FUNCTION `F`"), "{}", d[0].message);
}

/// A context over `mem` for calling compiled code directly.
fn with_ctx<T>(prog: &Program, mem: &mut Vec<Value>, now: i64, f: impl FnOnce(&mut Ctx<'_>) -> T) -> T {
    let mut charts = Vec::new();
    let mut sink = ScanSink::default();
    let mut ctx = Ctx {
        mem,
        prog,
        charts: &mut charts,
        sink: &mut sink,
        now,
        scan: 0,
        profile: Profile::Iec,
        budget: Default::default(),
    };
    f(&mut ctx)
}

#[test]
fn chart_code_il_guards_action_bodies_and_associations() {
    let text = "PROGRAM P
VAR
  a, b, lamp : BOOL;
  n : INT;
  hold : TIME := T#2s;
END_VAR
INITIAL_STEP S1: Count(N); lamp(N); END_STEP
TRANSITION FROM S1 TO S2:
    LD a
    AND( b
    OR S1.X
    )
    ANDN Count.Q
END_TRANSITION
STEP S2: Count(L, hold); Count(D, T#1s); END_STEP
TRANSITION FROM S2 TO S1 := S2.T >= hold; END_TRANSITION
ACTION Count:
    n := n + 1;
    Helper();
END_ACTION
ACTION Helper:
    n := n + 100;
END_ACTION
END_PROGRAM
";
    let (prog, _) = build("chart.st", text).unwrap_or_else(|e| panic!("{e}"));
    let top = prog.pou("P").expect("P");
    let mut mem = prog.instantiate(top);
    let f = mem.top_frame;
    let PouBody::Chart(cc) = &prog.pous[top].body else { panic!("chart") };
    let slot = |p: &str| prog.resolve(top, f, p).expect(p).0;
    let (a, s1x, q, n) = (slot("a"), slot("S1.X"), slot("Count.Q"), slot("n"));
    with_ctx(&prog, &mut mem.mem, 0, |ctx| {
        assert_eq!((cc.guards[0])(ctx, f), Ok(false), "a is FALSE");
        ctx.mem[a] = Value::Bool(true);
        assert_eq!((cc.guards[0])(ctx, f), Ok(false), "S1 is not active");
        ctx.mem[s1x] = Value::Bool(true);
        assert_eq!((cc.guards[0])(ctx, f), Ok(true));
        ctx.mem[q] = Value::Bool(true);
        assert_eq!((cc.guards[0])(ctx, f), Ok(false), "ANDN Count.Q");
        (cc.bodies[0])(ctx, f).expect("runs");
        assert_eq!(ctx.mem[n], Value::Int(101), "the body calls action Helper");
    });
    let lamp = prog.resolve(top, f, "lamp").expect("lamp").0;
    let hold = prog.resolve(top, f, "hold").expect("hold").0;
    assert_eq!(cc.associations[0][1].variable.map(|p| p.slot(f)), Some(lamp), "BOOL variable as an action");
    assert_eq!(
        cc.associations[1][0]
            .duration
            .map(|d| matches!(d, sfc_sim::code::DurationCode::Variable(p) if p.slot(f) == hold)),
        Some(true)
    );
    assert_eq!(cc.associations[1][1].duration, Some(sfc_sim::code::DurationCode::Literal(1_000_000)));
}

#[test]
fn calling_an_sfc_instance_copies_inputs_and_runs_its_chart() {
    let text = "FUNCTION_BLOCK Seq
VAR_INPUT Go : BOOL; END_VAR
VAR_OUTPUT Busy : BOOL; END_VAR
INITIAL_STEP Idle: END_STEP
TRANSITION FROM Idle TO Run := Go; END_TRANSITION
STEP Run: Busy(N); END_STEP
TRANSITION FROM Run TO Idle := NOT Go; END_TRANSITION
END_FUNCTION_BLOCK
PROGRAM Main
VAR rev : Seq; x : BOOL := TRUE; hold, err, busy : BOOL; END_VAR
rev(Go := x, SFCInit := hold, SFCError => err, Busy => busy);
END_PROGRAM
";
    let mut sim = sfc_sim::Simulation::from_source("sfcfb.st", text, Some("Main"), Default::default())
        .unwrap_or_else(|(f, d)| panic!("{}", render(&f, &d)));
    sim.scan();
    assert_eq!(sim.error().map(|e| e.message.clone()), None);
    assert_eq!(sim.get("rev.Go"), Some(Value::Bool(true)), "inputs are copied before the chart runs");
    assert_eq!(sim.get("rev.Idle.X"), Some(Value::Bool(true)), "the instance's scan 0");
    sim.scan();
    assert_eq!(sim.get("rev.Run.X"), Some(Value::Bool(true)), "one scan of the chart per call");
    assert_eq!(sim.get("busy"), Some(Value::Bool(true)), "outputs are copied after it");
    assert_eq!(sim.get("err"), Some(Value::Bool(false)));
}

fn st_files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            st_files_under(&p, out);
        } else if p.extension().is_some_and(|x| x == "st") {
            out.push(p);
        }
    }
}

/// Everything the front end accepts compiles for simulation: every example, valid fixture and
/// corpus file without errors compiles, and every PROGRAM and FUNCTION_BLOCK instantiates.
#[test]
fn every_checked_file_compiles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    for d in ["examples", "tests/fixtures/valid", "tests/corpus", "../shared/corpus"] {
        st_files_under(&root.join(d), &mut files);
    }
    files.sort();
    let mut failures = Vec::new();
    let mut compiled = 0;
    for f in &files {
        let Ok(text) = std::fs::read_to_string(f) else { continue };
        let name = f.display().to_string();
        let checked = check_source(0, &name, &text, &CheckOptions { keep_types: true, ..Default::default() });
        if checked.has_errors() {
            continue;
        }
        let file = checked.file.clone();
        match Program::compile(&checked.unit, checked.charts, &checked.expr_types) {
            Ok(prog) => {
                compiled += 1;
                for (i, p) in prog.pous.iter().enumerate() {
                    if p.kind != sfc_syntax::ast::PouKind::Function {
                        let mem = prog.instantiate(i);
                        assert!(mem.mem.len() >= mem.top_frame + p.layout.size as usize);
                    }
                }
            }
            Err(d) => failures.push(render(&file, &d)),
        }
    }
    eprintln!("compiled {compiled} of {} files", files.len());
    assert!(compiled > 0);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn eatmt_conditions_read_their_inputs() {
    let text = "{attribute 'sfc.target' := 'eatmt'}\nPROGRAM E\nINITIAL_STEP S0: END_STEP\n\
                TRANSITION FROM S0 TO S1 := c1.2; END_TRANSITION\nSTEP S1: END_STEP\n\
                TRANSITION FROM S1 TO S0 := !c5; END_TRANSITION\nEND_PROGRAM\n";
    let (prog, _) = build("eatmt.st", text).unwrap_or_else(|e| panic!("{e}"));
    let top = prog.pou("E").expect("E");
    assert_eq!(prog.pous[top].layout.vars.iter().filter(|v| v.implicit && v.name.starts_with('c')).count(), 256);
    let mut mem = prog.instantiate(top);
    let f = mem.top_frame;
    let (c18, c5) = (prog.resolve(top, f, "c18").expect("c18").0, prog.resolve(top, f, "C5").expect("c5").0);
    let PouBody::Chart(cc) = &prog.pous[top].body else { panic!("chart") };
    with_ctx(&prog, &mut mem.mem, 0, |ctx| {
        assert_eq!((cc.guards[0])(ctx, f), Ok(false));
        assert_eq!((cc.guards[1])(ctx, f), Ok(true), "NOT c5");
        ctx.mem[c18] = Value::Bool(true);
        ctx.mem[c5] = Value::Bool(true);
        assert_eq!((cc.guards[0])(ctx, f), Ok(true), "c1.2 is c18");
        assert_eq!((cc.guards[1])(ctx, f), Ok(false));
    });
}
