//! The fixture harness: every `.st` under `tests/fixtures/valid` must check without any
//! diagnostic; every `.st` under `tests/fixtures/invalid` lists its expected diagnostics inline as
//! `(*! SFC0208 *)` on the line where each one starts, and its full human rendering is kept beside
//! it as `<file>.stderr` (rewritten with `UPDATE_EXPECT=1`). The corpus and the examples are
//! checked the same way.

use sfc_diagnostics::{render_human, Diagnostic, RenderOptions};
use sfc_model::{check_source, CheckOptions};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn st_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else { return out };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(st_files(&p));
        } else if p.extension().is_some_and(|x| x == "st") {
            out.push(p);
        }
    }
    out.sort();
    out
}

fn display_name(path: &Path) -> String {
    path.strip_prefix(root()).unwrap_or(path).display().to_string().replace('\\', "/")
}

fn check(path: &Path) -> (String, Vec<Diagnostic>, sfc_diagnostics::SourceFile) {
    let text = std::fs::read_to_string(path).expect("fixture is UTF-8 text");
    let checked = check_source(0, &display_name(path), &text, &CheckOptions { analysis: true, ..Default::default() });
    (text, checked.diagnostics, checked.file)
}

fn render_all(diags: &[Diagnostic], file: &sfc_diagnostics::SourceFile) -> String {
    diags.iter().map(|d| render_human(d, std::slice::from_ref(file), RenderOptions::default()) + "\n").collect()
}

/// Expected `(line, code)` pairs from `(*! CODE CODE *)` comments.
fn expectations(text: &str) -> BTreeMap<(u32, String), usize> {
    let mut out = BTreeMap::new();
    for (i, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(start) = rest.find("(*!") {
            let after = &rest[start + 3..];
            let end = after.find("*)").unwrap_or(after.len());
            for code in after[..end].split_whitespace().filter(|w| w.starts_with("SFC")) {
                *out.entry((i as u32 + 1, code.to_string())).or_insert(0) += 1;
            }
            rest = &after[end..];
        }
    }
    out
}

/// Compares a rendering with the file beside the fixture, or rewrites it with UPDATE_EXPECT=1.
fn snapshot(path: &Path, actual: &str) -> Result<(), String> {
    let snap = path.with_extension("st.stderr");
    if std::env::var_os("UPDATE_EXPECT").is_some() {
        std::fs::write(&snap, actual).map_err(|e| e.to_string())?;
        return Ok(());
    }
    let expected = std::fs::read_to_string(&snap).unwrap_or_default();
    if expected != actual {
        return Err(format!(
            "{}: rendered diagnostics differ from {} (run with UPDATE_EXPECT=1 to accept)\n--- expected\n{expected}\n--- actual\n{actual}",
            display_name(path),
            display_name(&snap)
        ));
    }
    Ok(())
}

#[test]
fn valid_fixtures_have_no_diagnostics() {
    let files = st_files(&root().join("tests/fixtures/valid"));
    assert!(files.len() >= 20, "expected the valid fixture folder, found {} files", files.len());
    let mut failures = Vec::new();
    for path in &files {
        let (_, diags, file) = check(path);
        if !diags.is_empty() {
            failures.push(render_all(&diags, &file));
        }
    }
    assert!(failures.is_empty(), "valid fixtures produced diagnostics:\n{}", failures.join("\n"));
}

#[test]
fn invalid_fixtures_report_what_they_announce() {
    let files = st_files(&root().join("tests/fixtures/invalid"));
    assert!(files.len() >= 30, "expected the invalid fixture folder, found {} files", files.len());
    let mut failures = Vec::new();
    for path in &files {
        let (text, diags, file) = check(path);
        let expected = expectations(&text);
        assert!(!expected.is_empty(), "{}: an invalid fixture must announce a diagnostic", display_name(path));
        let mut actual: BTreeMap<(u32, String), usize> = BTreeMap::new();
        for d in &diags {
            let line = file.line_col(d.span.start).line;
            *actual.entry((line, d.code.to_string())).or_insert(0) += 1;
        }
        if expected != actual {
            let fmt = |m: &BTreeMap<(u32, String), usize>| {
                m.iter()
                    .map(|((l, c), n)| format!("{c}@{l}{}", if *n > 1 { format!("x{n}") } else { String::new() }))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            failures.push(format!(
                "{}\n  expected: {}\n  actual:   {}\n{}",
                display_name(path),
                fmt(&expected),
                fmt(&actual),
                render_all(&diags, &file)
            ));
            continue;
        }
        if let Err(e) = snapshot(path, &render_all(&diags, &file)) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{} invalid fixture(s) failed:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn examples_check_cleanly() {
    let files = st_files(&root().join("examples"));
    assert!(files.len() >= 4, "expected the examples");
    for path in &files {
        let (_, diags, file) = check(path);
        assert!(diags.is_empty(), "{}", render_all(&diags, &file));
    }
}

/// The public corpus: the MatIEC text imports cleanly, the VerifAPS dialect file reports its real
/// defects (rendering kept in `tests/corpus/`).
#[test]
fn corpus_text_files() {
    let corpus = root().join("../shared/corpus");
    if !corpus.exists() {
        // CI always has shared/ beside the clone: there a missing corpus is a failure.
        assert!(std::env::var_os("CI").is_none(), "../shared/corpus is missing");
        eprintln!("shared corpus not found beside the project; skipped");
        return;
    }
    let (_, diags, file) = check(&corpus.join("matiec/sfc.txt"));
    assert!(diags.iter().all(|d| !d.is_error()), "{}", render_all(&diags, &file));
    // MatIEC's test chart latches one output for real: INLINE10 (N in E3) sets QX3 TRUE and no
    // statement ever sets it back (SFC0219).
    assert_eq!(
        diags.iter().map(|d| d.code).collect::<Vec<_>>(),
        vec!["SFC0219", "SFC0104"],
        "{}",
        render_all(&diags, &file)
    );
    assert!(diags[0].message.starts_with("`QX3` is set TRUE by action `INLINE10`"), "{}", diags[0].message);

    let path = corpus.join("verifaps/single_sfc2st_tests.st");
    let (_, diags, file) = check(&path);
    let rendered = render_all(&diags, &file);
    let snap = root().join("tests/corpus/verifaps_single_sfc2st_tests.st");
    std::fs::create_dir_all(snap.parent().unwrap()).unwrap();
    snapshot(&snap, &rendered).unwrap();
}
