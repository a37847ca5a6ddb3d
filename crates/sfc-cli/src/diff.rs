//! `sfc diff OLD NEW`, `sfc diff REV -- FILE`, `sfc diff REV1 REV2 -- FILE`: two versions of a
//! chart file compared by meaning (`sfc_diff`), per POU. Exit status as `diff`'s: 0 equal in
//! meaning (the layout may differ), 1 different, 2 usage or I/O error.

use crate::term;
use crate::Status;
use std::path::{Path, PathBuf};
use std::process::Command;

#[derive(clap::Args)]
pub struct DiffArgs {
    /// Two files (`OLD NEW`), or with `-- FILE` one or two git revisions (`REV`: the revision
    /// against the working tree; `REV1 REV2`: two revisions).
    #[arg(value_name = "OLD|REV", num_args = 1..=7, required = true)]
    sides: Vec<String>,
    /// The file whose revisions are compared (after `--`).
    #[arg(last = true, value_name = "FILE")]
    file: Option<PathBuf>,
    /// Output: text (default), JSON, or the charts drawn side by side (SVG, an HTML page).
    #[arg(long, value_enum, default_value = "text")]
    format: DiffFormat,
    /// List every layout change (moved or resized elements) instead of counting them.
    #[arg(long)]
    layout: bool,
    /// Called by git as its external diff (`sfc git setup` configures it): PATH OLD-FILE
    /// OLD-HEX OLD-MODE NEW-FILE NEW-HEX NEW-MODE. Always exits 0, as git expects; a file that
    /// is no chart is shown as git would show it.
    #[arg(long, hide = true)]
    git_external: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DiffFormat {
    Text,
    Json,
    /// The old and new charts drawn side by side, added elements green, removed red, changed
    /// and renamed orange (one SVG).
    Svg,
    /// A review page: the changes listed, and the charts drawn as `svg` does.
    Html,
}

/// One side: its name for messages, its file name (for the format), its text.
struct Side {
    label: String,
    path: PathBuf,
    text: String,
}

fn read(path: &Path) -> Result<Side, String> {
    let decoded = sfc_driver::read_source(path).map_err(|e| e.message)?;
    Ok(Side { label: path.display().to_string(), path: path.to_path_buf(), text: decoded.text })
}

/// `git show REV:./FILE`, run in the file's directory.
fn at_revision(rev: &str, file: &Path) -> Result<Side, String> {
    let dir = file.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = file.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    let out = Command::new("git")
        .current_dir(dir)
        .args(["show", &format!("{rev}:./{name}")])
        .output()
        .map_err(|e| format!("cannot run git: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "git cannot give `{}` at `{rev}`: {}",
            file.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let text = String::from_utf8(out.stdout).map_err(|_| format!("`{}` at `{rev}` is not UTF-8 text", file.display()))?;
    Ok(Side { label: format!("{}@{rev}", file.display()), path: file.to_path_buf(), text })
}

fn sides(a: &DiffArgs) -> Result<(Side, Side), String> {
    if a.sides.len() > 2 {
        return Err("two files, or one or two revisions and `-- FILE`".into());
    }
    match (&a.file, a.sides.as_slice()) {
        (None, [old, new]) => Ok((read(Path::new(old))?, read(Path::new(new))?)),
        (None, [_]) => Err("two files to compare, or `REV -- FILE` for a git revision".into()),
        (Some(f), [rev]) => Ok((at_revision(rev, f)?, read(f)?)),
        (Some(f), [r1, r2]) => Ok((at_revision(r1, f)?, at_revision(r2, f)?)),
        _ => Err("two files, or one or two revisions and `-- FILE`".into()),
    }
}

/// git's external diff: `PATH OLD-FILE OLD-HEX OLD-MODE NEW-FILE NEW-HEX NEW-MODE`.
fn git_external(a: &DiffArgs) -> u8 {
    let [path, old, _, _, new, _, _] = a.sides.as_slice() else {
        term::error("--git-external takes the seven arguments git passes to an external diff");
        return Status::Usage.code();
    };
    let side = |file: &str, label: String| -> Option<Side> {
        if file == "/dev/null" {
            return None;
        }
        let text = std::fs::read_to_string(file).ok()?;
        Some(Side { label, path: PathBuf::from(path), text })
    };
    let (o, n) = (side(old, format!("a/{path}")), side(new, format!("b/{path}")));
    let charts = |s: &Side| {
        let (_, c, d) = sfc_driver::check_any(0, &s.path, &s.text, &sfc_model::CheckOptions::default());
        (!c.unit.items.is_empty() && !d.iter().any(|x| x.is_error())).then_some(c)
    };
    match (&o, &n) {
        (Some(os), Some(ns)) => match (charts(os), charts(ns)) {
            (Some(oc), Some(nc)) => {
                let d = sfc_diff::diff(&oc, &nc);
                println!("sfc diff {path}\n--- {}\n+++ {}", os.label, ns.label);
                print!("{}", colour(&d.text(a.layout)));
                if d.equal() {
                    println!("equal in meaning");
                }
            }
            // Not a chart sfc reads without errors: the lines, as git shows them.
            _ => plain(old, new),
        },
        (None, Some(_)) => println!("sfc diff {path}: new file"),
        (Some(_), None) => println!("sfc diff {path}: deleted"),
        (None, None) => {}
    }
    Status::Ok.code()
}

/// The line diff git itself would show.
fn plain(old: &str, new: &str) {
    let out = Command::new("git").args(["diff", "--no-index", "--no-ext-diff", "--no-textconv", "--", old, new]).output();
    if let Ok(o) = out {
        print!("{}", String::from_utf8_lossy(&o.stdout));
    }
}

pub fn diff(a: DiffArgs) -> u8 {
    if a.git_external {
        return git_external(&a);
    }
    let (old, new) = match sides(&a) {
        Ok(s) => s,
        Err(m) => {
            term::error(&m);
            return Status::Usage.code();
        }
    };
    let opts = sfc_model::CheckOptions::default();
    let (_, oc, od) = sfc_driver::check_any(0, &old.path, &old.text, &opts);
    let (_, nc, nd) = sfc_driver::check_any(0, &new.path, &new.text, &opts);
    for (side, diags) in [(&old, &od), (&new, &nd)] {
        let errors = diags.iter().filter(|d| d.is_error()).count();
        if errors > 0 {
            eprintln!(
                "note: `{}` has {errors} error{} (`sfc check` lists them); it is compared as far as it could be read",
                side.label,
                if errors == 1 { "" } else { "s" }
            );
        }
    }
    let d = sfc_diff::diff(&oc, &nc);
    match a.format {
        DiffFormat::Json => {
            let mut v = d.json();
            v["old"] = old.label.clone().into();
            v["new"] = new.label.clone().into();
            println!("{v}");
        }
        DiffFormat::Svg | DiffFormat::Html => {
            let drawn = drawings(&d, &oc, &nc);
            if a.format == DiffFormat::Svg {
                println!("{}", side_by_side(&drawn, &old.label, &new.label));
            } else {
                println!("{}", html(&d, &drawn, &old.label, &new.label, a.layout));
            }
        }
        DiffFormat::Text => {
            println!("--- {}\n+++ {}", old.label, new.label);
            print!("{}", colour(&d.text(a.layout)));
            if d.equal() {
                println!("equal in meaning");
            }
        }
    }
    if d.equal() {
        Status::Ok.code()
    } else {
        Status::Findings.code()
    }
}

/// What a line of the text output is: `added`, `removed`, `changed`, or none (a POU's name, the
/// layout line).
fn class(line: &str) -> Option<&'static str> {
    let t = line.trim_start();
    if t.starts_with("+ ") {
        Some("added")
    } else if t.starts_with("- ") {
        Some("removed")
    } else if t.starts_with("~ ") {
        Some("changed")
    } else {
        None
    }
}

/// Added lines green, removed red, changed yellow, on a terminal.
fn colour(text: &str) -> String {
    let on = term::color_stdout();
    text.lines()
        .map(|l| match class(l) {
            Some(c) => {
                let code = match c {
                    "added" => "32",
                    "removed" => "31",
                    _ => "33",
                };
                format!("{}\n", term::paint(on, code, l))
            }
            None => format!("{l}\n"),
        })
        .collect()
}

/// Per chart POU in either file: its old and new drawings (SVG), empty where it has none.
fn drawings(d: &sfc_diff::Diff, oc: &sfc_model::Checked, nc: &sfc_model::Checked) -> Vec<(String, String, String)> {
    let mut pous: Vec<String> = Vec::new();
    for c in oc.charts.iter().chain(nc.charts.iter()).filter(|c| c.action.is_none()) {
        if !pous.iter().any(|p| p.eq_ignore_ascii_case(&c.pou)) {
            pous.push(c.pou.clone());
        }
    }
    let draw = |c: &sfc_model::Checked, pou: &str| -> String {
        if !c.charts.iter().any(|ch| ch.action.is_none() && ch.pou.eq_ignore_ascii_case(pou)) {
            return String::new();
        }
        let opts = sfc_driver::compile::CompileOptions { pou: Some(pou), ..Default::default() };
        match sfc_driver::compile::compile(c, sfc_driver::compile::BuildTarget::Svg, &opts) {
            Ok(out) => out.text.trim_start_matches("<?xml version=\"1.0\" encoding=\"UTF-8\"?>").trim().to_string(),
            Err(_) => {
                // Not silently blank: the side is missing from the drawing, and this says why.
                eprintln!("note: `{pou}` of `{}` could not be drawn; its side of the drawing is empty", c.file.name);
                String::new()
            }
        }
    };
    pous.into_iter()
        .map(|p| {
            let (a, b) = (draw(oc, &p), draw(nc, &p));
            (colour_svg(&a, d, &p, true), colour_svg(&b, d, &p, false), p)
        })
        .map(|(a, b, p)| (p, a, b))
        .collect()
}

/// A drawing with its changed elements coloured, by a style on their `data-id`s.
fn colour_svg(svg: &str, d: &sfc_diff::Diff, pou: &str, old: bool) -> String {
    if svg.is_empty() {
        return String::new();
    }
    let side = if old { "sfc-old" } else { "sfc-new" };
    let mut rules = Vec::new();
    for c in d.changes.iter().filter(|c| c.pou.eq_ignore_ascii_case(pou)) {
        if !matches!(c.element, "step" | "transition") {
            continue;
        }
        let (name, colour) = match (c.kind, old) {
            (sfc_diff::Kind::Added, false) => (c.name.clone(), "#2e7d32"),
            (sfc_diff::Kind::Removed, true) => (c.name.clone(), "#c62828"),
            (sfc_diff::Kind::Renamed, true) => (c.old.clone().unwrap_or_default(), "#ef6c00"),
            (sfc_diff::Kind::Renamed, false) => (c.new.clone().unwrap_or_default(), "#ef6c00"),
            (sfc_diff::Kind::Changed, _) => (c.name.clone(), "#ef6c00"),
            _ => continue,
        };
        let id = format!("{}:{}", c.element, name).replace(['"', '\\'], "");
        let g = format!(".{side} g[data-id=\"{id}\"]");
        rules.push(format!(
            "{g} rect, {g} line, {g} polyline {{ stroke: {colour}; stroke-width: 3; }} {g} text {{ fill: {colour}; font-weight: bold; }}"
        ));
    }
    // The side's class scopes its rules (the drawings share one document in `svg` and `html`).
    let svg = svg.replacen("<svg ", &format!("<svg class=\"{side}\" "), 1);
    if rules.is_empty() {
        return svg;
    }
    let style = format!("<style>{}</style>", rules.join(" "));
    match svg.find('>') {
        Some(k) => format!("{}{style}{}", svg.get(..=k).unwrap_or(""), svg.get(k + 1..).unwrap_or("")),
        None => svg,
    }
}

/// `width`/`height` of a drawing's root element.
fn size(svg: &str) -> (f64, f64) {
    let root = svg.split('>').next().unwrap_or("");
    let attr = |n: &str| {
        root.split(&format!(" {n}=\"")).nth(1).and_then(|r| r.split('"').next()).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0)
    };
    (attr("width"), attr("height"))
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// The drawings of every POU in one SVG: old on the left, new on the right.
fn side_by_side(drawn: &[(String, String, String)], old: &str, new: &str) -> String {
    let mut body = String::new();
    let mut y = 0.0;
    let mut width: f64 = 0.0;
    for (pou, a, b) in drawn {
        let (wa, ha) = size(a);
        let (wb, hb) = size(b);
        let left = wa.max(200.0);
        body.push_str(&format!("<text x=\"0\" y=\"{}\" font-size=\"14\" font-weight=\"bold\">{}</text>\n", y + 16.0, esc(pou)));
        body.push_str(&format!("<text x=\"0\" y=\"{}\" font-size=\"12\">{}</text>\n", y + 34.0, esc(old)));
        body.push_str(&format!("<text x=\"{}\" y=\"{}\" font-size=\"12\">{}</text>\n", left + 40.0, y + 34.0, esc(new)));
        let place = |svg: &str, x: f64| -> String {
            if svg.is_empty() {
                return String::new();
            }
            svg.replacen("<svg ", &format!("<svg x=\"{x}\" y=\"{}\" ", y + 44.0), 1)
        };
        body.push_str(&place(a, 0.0));
        body.push_str(&place(b, left + 40.0));
        width = width.max(left + 40.0 + wb);
        y += 44.0 + ha.max(hb) + 30.0;
    }
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{width}\" height=\"{y}\" font-family=\"sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n{body}</svg>"
    )
}

/// A review page: the changes, then the drawings.
fn html(d: &sfc_diff::Diff, drawn: &[(String, String, String)], old: &str, new: &str, layout: bool) -> String {
    let list: String = d
        .text(layout)
        .lines()
        .map(|l| format!("<li class=\"{}\">{}</li>\n", class(l).unwrap_or("pou"), esc(l.trim())))
        .collect();
    let verdict = if d.equal() { "<p>Equal in meaning.</p>" } else { "" };
    let mut charts = String::new();
    for (pou, a, b) in drawn {
        charts.push_str(&format!(
            "<h2>{}</h2>\n<div class=\"pair\"><figure><figcaption>{}</figcaption>{a}</figure><figure><figcaption>{}</figcaption>{b}</figure></div>\n",
            esc(pou),
            esc(old),
            esc(new)
        ));
    }
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>sfc diff {} {}</title>\n<style>body {{ font-family: sans-serif; }} li.added {{ color: #2e7d32; }} li.removed {{ color: #c62828; }} li.changed {{ color: #ef6c00; }} li.pou {{ font-weight: bold; list-style: none; }} .pair {{ display: flex; gap: 2em; align-items: flex-start; }} figure {{ margin: 0; }}</style></head>\n<body><h1>{} → {}</h1>\n{verdict}<ul>\n{list}</ul>\n{charts}</body></html>",
        esc(old),
        esc(new),
        esc(old),
        esc(new)
    )
}
