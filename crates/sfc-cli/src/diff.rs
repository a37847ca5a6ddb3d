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
    /// Output: text (default) or JSON.
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

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum DiffFormat {
    Text,
    Json,
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

/// Added lines green, removed red, changed yellow, on a terminal.
fn colour(text: &str) -> String {
    let on = term::color_stdout();
    text.lines()
        .map(|l| {
            let t = l.trim_start();
            let code = if t.starts_with("+ ") {
                "32"
            } else if t.starts_with("- ") {
                "31"
            } else if t.starts_with("~ ") {
                "33"
            } else {
                return format!("{l}\n");
            };
            format!("{}\n", term::paint(on, code, l))
        })
        .collect()
}
