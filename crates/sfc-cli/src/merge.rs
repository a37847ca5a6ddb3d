//! `sfc merge BASE OURS THEIRS [-o OUT]`: a three-way merge of chart files by element
//! (`sfc_diff::merge`). Also git's merge driver (`sfc git setup`): `sfc merge %O %A %B -o %A
//! --path %P`. Exit 0 merged cleanly, 1 conflicts (the output is written, conflicting elements
//! as ours and marked), 2 usage or I/O error.

use crate::term;
use crate::Status;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The common ancestor.
    base: PathBuf,
    /// Our version.
    ours: PathBuf,
    /// Their version.
    theirs: PathBuf,
    /// Where the merged file goes (default: standard output); may be OURS (git's merge driver).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// The file's name in messages (git passes `%P`).
    #[arg(long, value_name = "NAME")]
    path: Option<String>,
}

/// Whether a text is XML (git hands the driver temporary files without their extension).
fn is_xml(text: &str) -> bool {
    text.trim_start_matches('\u{feff}').trim_start().starts_with('<')
}

fn read(p: &Path) -> Result<String, String> {
    sfc_driver::read_source(p).map(|d| d.text).map_err(|e| e.message)
}

pub fn merge(a: MergeArgs) -> u8 {
    let name = a.path.clone().unwrap_or_else(|| a.ours.display().to_string());
    let texts = [&a.base, &a.ours, &a.theirs].map(|p| read(p));
    let [Ok(base), Ok(ours), Ok(theirs)] = texts else {
        for e in texts.into_iter().filter_map(Result::err) {
            term::error(&e);
        }
        return Status::Usage.code();
    };
    let xml = [&base, &ours, &theirs].iter().filter(|t| is_xml(t)).count();
    let result = match xml {
        0 => merge_text(&name, &base, &ours, &theirs),
        3 => merge_xml(&name, &base, &ours, &theirs),
        _ => Err("the three versions are not all IEC text or all PLCopen XML".to_string()),
    };
    let (out, conflicts) = match result {
        Ok(r) => r,
        Err(why) => {
            // Not charts sfc reads: merged line by line, as git would.
            term::note(&format!("`{name}`: {why}; merged line by line"));
            match sfc_diff::merge::lines(&base, &ours, &theirs) {
                Ok(t) => (t, 0),
                Err(t) => {
                    term::error(&format!("`{name}`: lines changed both ways (marked with <<<<<<< and >>>>>>>)"));
                    (t, 1)
                }
            }
        }
    };
    let written = match &a.output {
        Some(p) => sfc_driver::write_atomically(p, out.as_bytes()).map_err(|e| format!("cannot write `{}`: {e}", p.display())),
        None => {
            print!("{out}");
            Ok(())
        }
    };
    if let Err(e) = written {
        term::error(&e);
        return Status::Usage.code();
    }
    if conflicts > 0 {
        term::error(&format!("`{name}`: {conflicts} conflict{} to resolve", if conflicts == 1 { "" } else { "s" }));
        return Status::Findings.code();
    }
    Status::Ok.code()
}

/// Prints the merge's conflicts and notes; the number of conflicts, the check's errors counted.
fn report(name: &str, m: &sfc_diff::merge::Merged) -> usize {
    for n in &m.notes {
        term::note(&format!("`{name}`: {n}"));
    }
    for c in &m.conflicts {
        let what = match c.name.split_once(' ') {
            Some((kind, element)) => format!("{kind} `{element}`"),
            None => c.name.clone(),
        };
        let pou = if c.pou.is_empty() || c.element == "pou" { String::new() } else { format!(" of `{}`", c.pou) };
        term::error(&format!("`{name}`: conflict: {what}{pou} {}", c.what));
    }
    m.conflicts.len()
}

/// The merged text is checked before it is written: errors count as conflicts.
fn check(name: &str, text: &str) -> usize {
    let opts = sfc_model::CheckOptions { analysis: false, ..Default::default() };
    let c = sfc_model::check_source(0, name, text, &opts);
    let errors: Vec<_> = c.diagnostics.iter().filter(|d| d.is_error()).cloned().collect();
    if !errors.is_empty() {
        term::print_diagnostics(&errors, std::slice::from_ref(&c.file));
        term::error(&format!("`{name}`: the merged chart has {} error(s)", errors.len()));
    }
    errors.len()
}

fn parses(text: &str) -> bool {
    let (unit, d) = sfc_syntax::parse(0, text);
    !unit.items.is_empty() && !d.iter().any(|x| x.is_error())
}

fn merge_text(name: &str, base: &str, ours: &str, theirs: &str) -> Result<(String, usize), String> {
    if ![base, ours, theirs].iter().all(|t| parses(t)) {
        return Err("not IEC 61131-3 text that parses on all three sides".into());
    }
    let m = sfc_diff::merge::merge(base, ours, theirs);
    let conflicts = report(name, &m);
    let errors = if conflicts == 0 { check(name, &m.text) } else { 0 };
    Ok((m.text, conflicts + errors))
}

/// PLCopen XML: the three imported to text and merged; ours' file then gets each POU whose
/// merged text differs from ours' (`patch_pou`: what can be changed in place is, and every
/// other byte of ours stays).
fn merge_xml(name: &str, base: &str, ours: &str, theirs: &str) -> Result<(String, usize), String> {
    let import = |x: &str| sfc_plcopen::import(0, name, x);
    let (b, o, t) = (import(base), import(ours), import(theirs));
    if [&b, &o, &t].iter().any(|i| i.diagnostics.iter().any(|d| d.is_error()) || !parses(&i.text)) {
        return Err("not PLCopen XML that imports on all three sides".into());
    }
    let m = sfc_diff::merge::merge(&b.text, &o.text, &t.text);
    let conflicts = report(name, &m);
    if conflicts > 0 {
        // The conflicts are written as ours, marked: the merged text's POUs go into ours.
    } else if check(name, &m.text) > 0 {
        return Ok((ours.to_string(), 1));
    }
    let plain = sfc_model::CheckOptions { analysis: false, ..Default::default() };
    let pou_texts = |text: &str| -> Vec<(String, String)> {
        let (unit, _) = sfc_syntax::parse(0, text);
        unit.items
            .iter()
            .filter_map(|i| match i {
                sfc_syntax::ast::Item::Pou(p) => {
                    let r = sfc_syntax::regions::regions(text, p);
                    let range = r.first()?.range.start..r.last()?.range.end;
                    Some((p.name.text.clone(), text.get(range)?.to_string()))
                }
                _ => None,
            })
            .collect()
    };
    let ours_pous = pou_texts(&o.text);
    let mut xml = ours.to_string();
    for (pou, text) in pou_texts(&m.text) {
        if ours_pous.iter().any(|(n, t)| n.eq_ignore_ascii_case(&pou) && *t == text) {
            continue;
        }
        let checked = sfc_model::check_source(0, name, &text, &plain);
        xml = sfc_plcopen::patch_pou(&xml, &pou, &checked)
            .map(|(x, _)| x)
            .map_err(|_| format!("POU `{pou}` cannot be written as PLCopen XML"))?;
    }
    for (pou, _) in &ours_pous {
        if !pou_texts(&m.text).iter().any(|(n, _)| n.eq_ignore_ascii_case(pou)) {
            term::note(&format!("`{name}`: POU `{pou}` was removed by their side; the merged XML still holds it (remove it in the editor)"));
        }
    }
    Ok((xml, conflicts))
}
