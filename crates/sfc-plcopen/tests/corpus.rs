//! Every file of the public corpus (`../shared/corpus`, never copied here) imports, with its
//! expected IEC text and diagnostics committed under `tests/corpus/` (rewritten with
//! `UPDATE_EXPECT=1`), exports to XML that passes the schema, and round-trips: import → export
//! → import gives the same model, and exporting again gives the same XML. Textual corpus files
//! are checked, exported and imported back.

mod common;
use common::*;
use std::path::{Path, PathBuf};

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else { return out };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files(&p));
        } else {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// `../shared/corpus/beremiz/x.xml` as written in expectations.
fn display(corpus: &Path, p: &Path) -> String {
    format!("../shared/corpus/{}", p.strip_prefix(corpus).unwrap_or(p).display())
}

fn expect_dir(corpus: &Path, p: &Path) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus").join(p.strip_prefix(corpus).unwrap_or(p))
}

fn with_ext(p: &Path, ext: &str) -> PathBuf {
    PathBuf::from(format!("{}.{ext}", p.display()))
}

fn xml_file(corpus: &Path, path: &Path) -> Result<(), String> {
    let name = display(corpus, path);
    let xml = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let imported = sfc_plcopen::import(0, &name, &xml);
    let (file, checked, diags) = sfc_plcopen::check_xml(0, &name, &xml, &opts());
    let expect = expect_dir(corpus, path);
    snapshot(&with_ext(&expect, "st"), &imported.text)?;
    snapshot(&with_ext(&expect, "diags"), &render(&diags, &file))?;
    // Every diagnostic is located inside the XML.
    for d in &diags {
        if d.span.end as usize > xml.len() || d.span.start > d.span.end {
            return Err(format!("{name}: diagnostic outside the file: {d:?}"));
        }
    }
    // Export passes the schema; export → import gives the same model; export is idempotent.
    let (xml1, again, _) = reimport(&checked, &name);
    if let Some(r) = xmllint(&xml1) {
        r.map_err(|e| format!("{name}: the export does not validate:\n{e}"))?;
    }
    same_model(&checked, &again, false).map_err(|e| format!("{name}: import → export → import: {e}"))?;
    let (xml2, third, _) = reimport(&again, &name);
    same_model(&again, &third, false).map_err(|e| format!("{name}: second round trip: {e}"))?;
    if xml1 != xml2 {
        return Err(format!("{name}: exporting the re-imported file gives other XML"));
    }
    Ok(())
}

fn text_file(corpus: &Path, path: &Path) -> Result<(), String> {
    let name = display(corpus, path);
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let checked = check_text(&name, &text);
    let expect = expect_dir(corpus, path);
    match sfc_plcopen::export_with(&checked, None) {
        Err(errors) => {
            // A file whose errors outside every POU keep it from being written: they say why.
            if errors.is_empty() {
                return Err(format!("{name}: export failed without a reason"));
            }
            snapshot(&with_ext(&expect, "export.diags"), &render(&errors, &checked.file))
        }
        Ok((xml, notes)) if !notes.is_empty() => {
            // POUs with errors are written with their text (SFC0716), which the import gives
            // back as it was.
            snapshot(&with_ext(&expect, "xml"), &xml)?;
            snapshot(&with_ext(&expect, "export.diags"), &render(&notes, &checked.file))?;
            if let Some(r) = xmllint(&xml) {
                r.map_err(|e| format!("{name}: the export does not validate:\n{e}"))?;
            }
            let back = sfc_plcopen::import(0, &name, &xml).text;
            for n in &notes {
                let pou = n.message.split('`').nth(1).unwrap_or("");
                let needle = format!(" {pou}\n");
                if !back.contains(&needle) || !text.contains(&needle) {
                    return Err(format!("{name}: `{pou}` does not come back from its addData"));
                }
            }
            Ok(())
        }
        Ok((xml, _)) => {
            snapshot(&with_ext(&expect, "xml"), &xml)?;
            if let Some(r) = xmllint(&xml) {
                r.map_err(|e| format!("{name}: the export does not validate:\n{e}"))?;
            }
            let (_, again, diags) = sfc_plcopen::check_xml(0, &name, &xml, &opts());
            if let Some(d) = diags.iter().find(|d| d.is_error()) {
                return Err(format!("{name}: the exported XML imports with an error: {d:?}"));
            }
            same_model(&checked, &again, true).map_err(|e| format!("{name}: text → XML → text: {e}"))?;
            let (xml2, _, _) = reimport(&again, &name);
            let (xml3, _, _) = reimport(&check_text(&name, &sfc_plcopen::import(0, &name, &xml2).text), &name);
            if xml2 != xml3 {
                return Err(format!("{name}: export is not idempotent"));
            }
            Ok(())
        }
    }
}

#[test]
fn corpus_imports_and_round_trips() {
    let Some(corpus) = corpus_dir() else { return };
    let mut failures = Vec::new();
    let mut seen = 0;
    for path in files(&corpus) {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        let result = match ext {
            "xml" => {
                seen += 1;
                xml_file(&corpus, &path)
            }
            "st" | "txt" => {
                seen += 1;
                text_file(&corpus, &path)
            }
            _ => continue,
        };
        if let Err(e) = result {
            failures.push(e);
        }
    }
    assert!(seen >= 5, "expected the corpus files, found {seen}");
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// The structure of the Beremiz example: branches told apart by wire position (the branch
/// drawn on the left comes first), jumps, inline actions.
#[test]
fn beremiz_branch_order_follows_wire_positions() {
    let Some(corpus) = corpus_dir() else { return };
    let path = corpus.join("beremiz/first_steps.plc.xml");
    let xml = std::fs::read_to_string(&path).expect("corpus file");
    let (_, checked, diags) = sfc_plcopen::check_xml(0, "first_steps.plc.xml", &xml, &opts());
    assert!(!diags.iter().any(|d| d.is_error()), "{diags:?}");
    let chart = checked.charts.iter().find(|c| c.pou == "CounterSFC").expect("CounterSFC chart");
    let start = chart.step("Start").expect("Start");
    let out = chart.outgoing(start);
    let targets: Vec<&str> = out.iter().map(|&t| chart.steps[chart.transitions[t].to[0]].name.as_str()).collect();
    // Document order has the `Reset` branch (x = 501) first; the wire positions put `Count`
    // (x = 70) on the left.
    assert_eq!(targets, ["Count", "ResetCounter"]);
    let count = chart.step("Count").expect("Count");
    assert_eq!(chart.steps[count].associations.len(), 2);
    // Both branches jump back to Start.
    for s in ["Count", "ResetCounter"] {
        let id = chart.step(s).expect("step");
        let t = chart.outgoing(id)[0];
        assert_eq!(chart.transitions[t].to, vec![start]);
    }
}

/// The traffic light's condition drawn in FBD with a timer: the timer runs in
/// COMPUTE_FUNCTION_BLOCKS (stored in the initial step), the condition reads its output; the
/// LD action became ST with R_TRIG calls and set/reset coils.
#[test]
fn traffic_light_networks_become_st() {
    let Some(corpus) = corpus_dir() else { return };
    let xml = std::fs::read_to_string(corpus.join("beremiz/svghmi_traffic_light.plc.xml")).expect("corpus file");
    let imported = sfc_plcopen::import(0, "traffic.xml", &xml);
    let t = &imported.text;
    assert!(t.contains(":= TON3.Q OR WARN_CARS;"), "{t}");
    assert!(t.contains("COMPUTE_FUNCTION_BLOCKS(S);"), "{t}");
    assert!(t.contains("TON3(IN := SR0.Q1, PT := T#2s);"), "{t}");
    assert!(t.contains(":= NOT SWITCH_BUTTON;"), "{t}");
    assert!(t.contains("IF R_TRIG1.Q THEN"), "{t}");
    assert!(t.contains("{attribute 'sfc.reference' := 'STOP'}"), "{t}");
    assert!(imported.diagnostics.iter().any(|d| d.code == "SFC0707"));
}
