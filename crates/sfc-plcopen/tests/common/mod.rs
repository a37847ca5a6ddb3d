//! Helpers shared by the integration tests: paths, snapshots, the schema check with `xmllint`,
//! and the comparison of two checked files' models.
#![allow(dead_code)]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use sfc_diagnostics::{render_human, Diagnostic, RenderOptions, SourceFile};
use sfc_model::{check_source, ActionTarget, CheckOptions, Checked, Duration};
use sfc_syntax::ast;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The project root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub fn ci() -> bool {
    std::env::var_os("CI").is_some()
}

/// `../shared/corpus` relative to the project root, or `None` (with a message) when it is
/// missing and `CI` is not set; with `CI` set a missing corpus fails.
pub fn corpus_dir() -> Option<PathBuf> {
    let dir = root().join("../shared/corpus");
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(!ci(), "the corpus {} is missing (CI is set)", dir.display());
    eprintln!("skipped: the corpus {} is missing", dir.display());
    None
}

/// The schema file, in the corpus.
pub fn xsd() -> Option<PathBuf> {
    corpus_dir().map(|d| d.join("plcopen/tc6_xml_v201.xsd")).filter(|p| p.is_file())
}

/// Validates an XML text against the PLCopen v2.01 schema with `xmllint`. Returns `None` when
/// the check cannot run (no `xmllint` or no schema, and `CI` unset: a message is printed).
pub fn xmllint(xml: &str) -> Option<Result<(), String>> {
    let xsd = xsd()?;
    let child = Command::new("xmllint")
        .args(["--noout", "--schema"])
        .arg(&xsd)
        .arg("-")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => {
            assert!(!ci(), "xmllint cannot run ({e}); CI is set");
            eprintln!("skipped: xmllint is not installed (apt install libxml2-utils)");
            return None;
        }
    };
    if let Some(mut stdin) = child.stdin.take() {
        let _ = stdin.write_all(xml.as_bytes());
    }
    let out = child.wait_with_output().expect("xmllint runs");
    if out.status.success() {
        Some(Ok(()))
    } else {
        Some(Err(String::from_utf8_lossy(&out.stderr).into_owned()))
    }
}

/// Compares `actual` with the file `path`, or writes it with `UPDATE_EXPECT=1`.
pub fn snapshot(path: &Path, actual: &str) -> Result<(), String> {
    if std::env::var_os("UPDATE_EXPECT").is_some() {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        }
        std::fs::write(path, actual).map_err(|e| e.to_string())?;
        return Ok(());
    }
    let expected = std::fs::read_to_string(path).unwrap_or_default();
    if expected != actual {
        return Err(format!(
            "{} differs (run with UPDATE_EXPECT=1 to accept)\n--- expected\n{expected}\n--- actual\n{actual}",
            path.display()
        ));
    }
    Ok(())
}

pub fn render(diags: &[Diagnostic], file: &SourceFile) -> String {
    diags.iter().map(|d| render_human(d, std::slice::from_ref(file), RenderOptions::default()) + "\n").collect()
}

pub fn opts() -> CheckOptions {
    CheckOptions::default()
}

/// Exports, imports the XML again and checks the text: the second model.
pub fn reimport(checked: &Checked, name: &str) -> (String, Checked, Vec<Diagnostic>) {
    let xml = sfc_plcopen::export(checked).unwrap_or_else(|e| panic!("{name}: export failed: {e:?}"));
    let (_, again, diags) = sfc_plcopen::check_xml(0, name, &xml, &opts());
    (xml, again, diags)
}

/// Code tokens of a text, joined by one space: formatting and comments do not count.
pub fn norm(text: &str) -> String {
    let (toks, _) = sfc_syntax::lexer::lex(0, text);
    toks.iter()
        .filter(|t| !t.kind.is_trivia() && t.kind != sfc_syntax::lexer::TokenKind::Eof)
        .map(|t| &text[t.start as usize..t.end as usize])
        .collect::<Vec<_>>()
        .join(" ")
}

/// A type as PLCopen spells it: names are case-insensitive, `TIME_OF_DAY` is `TOD`,
/// `DATE_AND_TIME` is `DT`, `ARRAY [a..b][c..d]` is `ARRAY [a..b, c..d]`.
fn norm_type(text: &str) -> String {
    norm(text)
        .to_ascii_uppercase()
        .split(' ')
        .map(|w| match w {
            "TIME_OF_DAY" => "TOD",
            "DATE_AND_TIME" => "DT",
            _ => w,
        })
        .collect::<Vec<_>>()
        .join(" ")
        .replace("] [", ",")
}

fn slice(src: &str, start: u32, end: u32) -> &str {
    src.get(start as usize..end as usize).unwrap_or("")
}

fn cond_text(src: &str, c: &ast::Condition) -> String {
    match c {
        ast::Condition::St(e) => format!("ST {}", norm(slice(src, e.span.start, e.span.end))),
        ast::Condition::Il(b) => format!("IL {}", norm(slice(src, b.span.start, b.span.end))),
        ast::Condition::Missing => "missing".into(),
    }
}

/// The text of an action body (between `ACTION name:` and `END_ACTION`), normalised.
fn action_text(src: &str, a: &sfc_model::ActionNode) -> String {
    // An action written in SFC is compared as a chart of its own (`Checked::action_charts`).
    if a.body.sfc().is_some() {
        return "SFC".into();
    }
    body_text(src, a.name_span.end, a.span.end)
}

/// The text of an action's body between the name's end and `END_ACTION`, normalised.
fn body_text(src: &str, name_end: u32, end: u32) -> String {
    let body = slice(src, name_end, end);
    let body = body.trim_start().trim_start_matches(':');
    let n = norm(body);
    let cut = n.len().saturating_sub("END_ACTION".len());
    match n.get(cut..) {
        Some(end) if end.eq_ignore_ascii_case("END_ACTION") => n[..cut].trim().to_string(),
        _ => n,
    }
}

/// Layout attributes an export adds to a chart that had none.
pub const LAYOUT: &[&str] = &["sfc.x", "sfc.y", "sfc.w", "sfc.h", "sfc.actionblock", "sfc.jump"];

fn attr_list(list: &[ast::Attribute]) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> =
        list.iter().map(|a| (a.name.to_ascii_lowercase(), a.value.clone().unwrap_or_default())).collect();
    v.sort();
    v
}

/// Attributes of `b` equal those of `a`; with `layout_added`, `b` may also hold layout
/// attributes `a` lacks.
fn same_attrs(what: &str, a: &[ast::Attribute], b: &[ast::Attribute], layout_added: bool) -> Result<(), String> {
    let la = attr_list(a);
    let mut lb = attr_list(b);
    if layout_added {
        // Layout the export filled in (positions, sizes, action blocks, jumps) may be added;
        // what `a` had must be kept.
        let extra: Vec<(String, String)> =
            lb.iter().filter(|e| LAYOUT.contains(&e.0.as_str()) && !la.contains(e)).cloned().collect();
        lb.retain(|e| !extra.contains(e));
    }
    if la != lb {
        return Err(format!("{what}: attributes differ\n  {la:?}\n  {lb:?}"));
    }
    Ok(())
}

fn duration(d: &Option<Duration>) -> String {
    match d {
        None => String::new(),
        Some(Duration::Literal(us)) => format!("{us}us"),
        Some(Duration::Variable(v)) => v.to_ascii_uppercase(),
    }
}

/// Compares the models of two checked files: every chart (steps, transitions with their steps,
/// conditions, priorities, actions, associations, attributes incl. layout), POU attributes and
/// declarations. `layout_added`: `b` was exported from a chart without layout, so it may hold
/// layout attributes `a` lacks.
pub fn same_model(a: &Checked, b: &Checked, layout_added: bool) -> Result<(), String> {
    let (sa, sb) = (a.file.text.as_str(), b.file.text.as_str());
    let pous = |c: &Checked| -> Vec<ast::Pou> {
        c.unit.items.iter().filter_map(|i| if let ast::Item::Pou(p) = i { Some(p.clone()) } else { None }).collect()
    };
    let (pa, pb) = (pous(a), pous(b));
    if pa.len() != pb.len() {
        return Err(format!("{} POUs, then {}", pa.len(), pb.len()));
    }
    for (x, y) in pa.iter().zip(pb.iter()) {
        if !x.name.text.eq_ignore_ascii_case(&y.name.text) || x.kind != y.kind {
            return Err(format!("POU {} {:?} became {} {:?}", x.name.text, x.kind, y.name.text, y.kind));
        }
        same_attrs(&format!("POU {}", x.name.text), &x.attributes, &y.attributes, layout_added)?;
        let decls = |p: &ast::Pou, src: &str| -> Vec<String> {
            p.var_blocks
                .iter()
                .flat_map(|b| {
                    b.decls.iter().flat_map(move |d| {
                        let names: Vec<String> = if d.names.is_empty() {
                            vec![String::new()]
                        } else {
                            d.names.iter().map(|n| n.text.clone()).collect()
                        };
                        names.into_iter().map(move |n| {
                            format!(
                                "{:?} {} {:?} {} AT {} : {} := {}",
                                b.kind,
                                b.constant,
                                b.retain,
                                n,
                                d.location.as_ref().map(|l| l.text.clone()).unwrap_or_default(),
                                norm_type(slice(src, d.ty.span.start, d.ty.span.end)),
                                d.init
                                    .as_ref()
                                    .map(|i| norm(slice(src, i.span().start, i.span().end)))
                                    .unwrap_or_default()
                            )
                        })
                    })
                })
                .collect()
        };
        let (da, db) = (decls(x, sa), decls(y, sb));
        if da != db {
            return Err(format!("POU {}: declarations differ\n  {da:?}\n  {db:?}", x.name.text));
        }
    }
    // The actions of POUs that are no chart.
    for (x, y) in pa.iter().zip(pb.iter()) {
        let list = |p: &ast::Pou, src: &str| -> Vec<String> {
            p.actions
                .iter()
                .map(|a| match a.body {
                    ast::ActionBody::Sfc(_) => format!("{}: SFC", a.name.text),
                    _ => format!("{}: {}", a.name.text, body_text(src, a.name.span.end, a.span.end)),
                })
                .collect()
        };
        if list(x, sa) != list(y, sb) {
            return Err(format!("POU {}: actions differ\n  {:?}\n  {:?}", x.name.text, list(x, sa), list(y, sb)));
        }
    }
    let all = |c: &Checked| c.charts.len() + c.action_charts.len();
    if all(a) != all(b) {
        return Err(format!("{} charts, then {}", all(a), all(b)));
    }
    for (x, y) in a.charts.iter().chain(&a.action_charts).zip(b.charts.iter().chain(&b.action_charts)) {
        let pou = &match &x.action {
            Some(act) => format!("{}.{act}", x.pou),
            None => x.pou.clone(),
        };
        if !x.pou.eq_ignore_ascii_case(&y.pou) || x.action != y.action {
            return Err(format!("chart {pou} became {} {:?}", y.pou, y.action));
        }
        let steps = |c: &sfc_model::Chart| -> Vec<String> {
            c.steps.iter().map(|s| format!("{} {}", s.name, s.initial)).collect()
        };
        if steps(x) != steps(y) {
            return Err(format!("{pou}: steps differ\n  {:?}\n  {:?}", steps(x), steps(y)));
        }
        for (s, t) in x.steps.iter().zip(y.steps.iter()) {
            let assoc = |c: &sfc_model::Chart, st: &sfc_model::StepNode| -> Vec<String> {
                st.associations
                    .iter()
                    .map(|a| {
                        let target = match a.target {
                            ActionTarget::Action(id) => {
                                format!("action {}", c.actions.get(id).map(|a| a.name.as_str()).unwrap_or("?"))
                            }
                            ActionTarget::Variable => "variable".into(),
                        };
                        format!(
                            "{}({} {} {:?}) {target}",
                            a.action,
                            a.qualifier.name(),
                            duration(&a.duration),
                            a.indicators
                        )
                    })
                    .collect()
            };
            if assoc(x, s) != assoc(y, t) {
                return Err(format!(
                    "{pou}: associations of {} differ\n  {:?}\n  {:?}",
                    s.name,
                    assoc(x, s),
                    assoc(y, t)
                ));
            }
            let step_actions = |st: &sfc_model::StepNode| -> Vec<String> {
                st.step_actions.iter().map(|a| format!("{} := {}", a.kind.keyword(), a.name())).collect()
            };
            if step_actions(s) != step_actions(t) {
                return Err(format!(
                    "{pou}: step actions of {} differ\n  {:?}\n  {:?}",
                    s.name,
                    step_actions(s),
                    step_actions(t)
                ));
            }
            same_attrs(&format!("{pou}: step {}", s.name), &s.attributes, &t.attributes, layout_added)?;
        }
        let trans = |c: &sfc_model::Chart, src: &str| -> Vec<String> {
            c.transitions
                .iter()
                .map(|t| {
                    let names = |l: &[usize]| l.iter().map(|&s| c.steps[s].name.clone()).collect::<Vec<_>>().join(",");
                    format!(
                        "{} named={} prio={:?} {} -> {} : {}",
                        t.name,
                        t.named,
                        t.priority,
                        names(&t.from),
                        names(&t.to),
                        cond_text(src, &t.condition)
                    )
                })
                .collect()
        };
        if trans(x, sa) != trans(y, sb) {
            return Err(format!("{pou}: transitions differ\n  {:#?}\n  {:#?}", trans(x, sa), trans(y, sb)));
        }
        for (s, t) in x.transitions.iter().zip(y.transitions.iter()) {
            same_attrs(&format!("{pou}: transition {}", s.name), &s.attributes, &t.attributes, layout_added)?;
        }
        let actions = |c: &sfc_model::Chart, src: &str| -> Vec<String> {
            c.actions.iter().map(|a| format!("{}: {}", a.name, action_text(src, a))).collect()
        };
        if actions(x, sa) != actions(y, sb) {
            return Err(format!("{pou}: actions differ\n  {:#?}\n  {:#?}", actions(x, sa), actions(y, sb)));
        }
        for (s, t) in x.actions.iter().zip(y.actions.iter()) {
            same_attrs(&format!("{pou}: action {}", s.name), &s.attributes, &t.attributes, layout_added)?;
        }
    }
    Ok(())
}

/// Checks a text file the way `sfc check` does (without analysis).
pub fn check_text(name: &str, text: &str) -> Checked {
    check_source(0, name, text, &opts())
}
