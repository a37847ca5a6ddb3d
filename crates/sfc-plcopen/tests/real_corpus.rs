//! The corpus of PLCopen files in the shapes real tools write (`tests/corpus/real/`, one folder
//! per producing tool: Beremiz new and old, OpenPLC Editor, CODESYS V3, e!COCKPIT, TwinCAT,
//! PLCOpenEditor's TC6 v1.0). Every file:
//! - imports and checks without an error;
//! - has, per SFC POU, the step, transition and action counts that an independent script
//!   (`tests/corpus/real/count.py`, Python's own XML parser) counts in the XML;
//! - exports to XML that validates against the TC6 v2.01 schema and imports back to the same
//!   chart, and exporting that again gives the same XML.
//!
//! The test prints a conformance summary (`Passed: N/N`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;
use common::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn real_dir() -> PathBuf {
    root().join("tests/corpus/real")
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "xml") {
            out.push(p);
        }
    }
}

/// The counts of `count.py` for each file, or `None` when Python cannot run (and `CI` is unset).
fn script_counts(paths: &[PathBuf]) -> Option<Vec<BTreeMap<String, [usize; 4]>>> {
    let out = Command::new("python3").arg(real_dir().join("count.py")).args(paths).output();
    let out = match out {
        Ok(o) if o.status.success() => o,
        Ok(o) => panic!("count.py failed: {}", String::from_utf8_lossy(&o.stderr)),
        Err(e) => {
            assert!(!ci(), "python3 cannot run ({e}); CI is set");
            eprintln!("skipped the independent counts: python3 is not installed");
            return None;
        }
    };
    let text = String::from_utf8(out.stdout).expect("UTF-8");
    let lines: Vec<BTreeMap<String, [usize; 4]>> = text
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).expect("count.py prints JSON");
            v.as_object()
                .expect("an object")
                .iter()
                .map(|(k, v)| {
                    let a: Vec<usize> =
                        v.as_array().expect("a list").iter().map(|n| n.as_u64().unwrap_or(0) as usize).collect();
                    (k.clone(), [a[0], a[1], a[2], a[3]])
                })
                .collect()
        })
        .collect();
    assert_eq!(lines.len(), paths.len(), "count.py answers once per file");
    Some(lines)
}

fn check_file(path: &Path, expected: Option<&BTreeMap<String, [usize; 4]>>) -> Result<(), String> {
    let name = path.strip_prefix(root()).unwrap_or(path).display().to_string();
    let xml = std::fs::read_to_string(path).map_err(|e| format!("{name}: {e}"))?;
    let (file, checked, diags) = sfc_plcopen::check_xml(0, &name, &xml, &opts());
    if let Some(d) = diags.iter().find(|d| d.is_error()) {
        return Err(format!("{name}: imports with an error:\n{}", render(std::slice::from_ref(d), &file)));
    }
    if checked.charts.is_empty() && checked.action_charts.is_empty() {
        return Err(format!("{name}: no chart imported"));
    }
    if let Some(expected) = expected {
        // Transitions not connected on both sides are kept on the POU (`sfc.loose`), not in the chart.
        let loose = |pou: &str| -> usize {
            checked
                .unit
                .items
                .iter()
                .filter_map(|i| if let sfc_syntax::ast::Item::Pou(p) = i { Some(p) } else { None })
                .filter(|p| p.name.text.eq_ignore_ascii_case(pou))
                .flat_map(|p| p.attributes.iter())
                .filter(|a| a.name.eq_ignore_ascii_case(sfc_syntax::attr_value::LOOSE))
                .count()
        };
        let mut got: BTreeMap<String, [usize; 4]> = checked
            .charts
            .iter()
            .map(|c| {
                let step_actions = c.steps.iter().map(|s| s.step_actions.len()).sum();
                (
                    c.pou.to_ascii_uppercase(),
                    // An association naming an instance's action (`Line.ACT_Run`, CODESYS) is
                    // that block's action, counted under it, not one of this POU's.
                    [
                        c.steps.len(),
                        c.transitions.len() + loose(&c.pou),
                        c.actions.iter().filter(|a| !a.of_instance()).count(),
                        step_actions,
                    ],
                )
            })
            .collect();
        // The charts of actions written in SFC, as `POU.ACTION`.
        for c in &checked.action_charts {
            let key = format!("{}.{}", c.pou, c.action.as_deref().unwrap_or_default()).to_ascii_uppercase();
            let step_actions = c.steps.iter().map(|s| s.step_actions.len()).sum();
            got.insert(key, [c.steps.len(), c.transitions.len(), 0, step_actions]);
        }
        // The actions of POUs that are no chart.
        for p in
            checked.unit.items.iter().filter_map(|i| if let sfc_syntax::ast::Item::Pou(p) = i { Some(p) } else { None })
        {
            if !p.actions.is_empty() {
                got.insert(p.name.text.to_ascii_uppercase(), [0, 0, p.actions.len(), 0]);
            }
        }
        if &got != expected {
            return Err(format!(
                "{name}: [steps, transitions, actions, step actions] per POU differ from the XML's\n  count.py: {expected:?}\n  sfc:      {got:?}"
            ));
        }
    }
    let (xml1, again, diags) = reimport(&checked, &name);
    if let Some(r) = xmllint(&xml1) {
        r.map_err(|e| format!("{name}: the export does not validate:\n{e}"))?;
    }
    if let Some(d) = diags.iter().find(|d| d.is_error()) {
        return Err(format!("{name}: the export imports with an error: {d:?}"));
    }
    // A chart drawn without positions (CODESYS, TwinCAT) gets a layout on export.
    same_model(&checked, &again, true).map_err(|e| format!("{name}: import → export → import: {e}"))?;
    let (xml2, _, _) = reimport(&again, &name);
    if xml1 != xml2 {
        return Err(format!("{name}: exporting the re-imported file gives other XML"));
    }
    Ok(())
}

#[test]
fn real_tool_files_import_count_export_and_round_trip() {
    let mut paths = Vec::new();
    files(&real_dir(), &mut paths);
    paths.sort();
    let tools: std::collections::BTreeSet<String> = paths
        .iter()
        .filter_map(|p| p.parent().and_then(|d| d.file_name()).map(|d| d.to_string_lossy().into_owned()))
        .collect();
    assert!(paths.len() >= 25, "expected at least 25 files, found {}", paths.len());
    assert!(tools.len() >= 5, "expected files of at least 5 tools, found {tools:?}");
    let counts = script_counts(&paths);
    let mut failures = Vec::new();
    for (k, p) in paths.iter().enumerate() {
        if let Err(e) = check_file(p, counts.as_ref().map(|c| &c[k])) {
            failures.push(e);
        }
    }
    println!(
        "Passed: {}/{} ({} tools: {})",
        paths.len() - failures.len(),
        paths.len(),
        tools.len(),
        tools.iter().cloned().collect::<Vec<_>>().join(", ")
    );
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// Two CODESYS applications that each declare `GVL.limit`: each resource keeps its own scope,
/// so there is no clash, and each program reaches its own `limit` (through VAR_EXTERNAL).
#[test]
fn resources_keep_their_own_global_lists() {
    let path = real_dir().join("codesys/two_applications_own_gvl.xml");
    let xml = std::fs::read_to_string(&path).expect("fixture");
    let imported = sfc_plcopen::import(0, "two.xml", &xml);
    let t = &imported.text;
    assert_eq!(t.matches("limit : INT := 100;").count(), 1, "{t}");
    assert_eq!(t.matches("limit : INT := 250;").count(), 1, "{t}");
    assert_eq!(t.matches("VAR_EXTERNAL").count(), 2, "{t}");
    let (_, checked, diags) = sfc_plcopen::check_xml(0, "two.xml", &xml, &opts());
    assert!(!diags.iter().any(|d| d.is_error()), "{diags:?}");
    assert_eq!(checked.charts.len(), 2);
}

/// CODESYS ST dialect: `Enum.Value` and `GVL.X` are mapped, an FB with methods, pointers and
/// `__ISVALIDREF` is analysed (one note, on the CODESYS identifier), and the chart that uses
/// it is analysed.
#[test]
fn codesys_dialect_is_mapped_or_kept_as_written() {
    let xml = std::fs::read_to_string(real_dir().join("codesys/st_dialect_enum_oop.xml")).expect("fixture");
    let (_, checked, diags) = sfc_plcopen::check_xml(0, "d.xml", &xml, &opts());
    assert!(!diags.iter().any(|d| d.is_error()), "{diags:?}");
    assert!(!diags.iter().any(|d| d.message.contains("kept as written, not analysed")), "{diags:?}");
    let notes: Vec<_> = diags.iter().filter(|d| d.code == "SFC0013").collect();
    assert_eq!(notes.len(), 1, "{diags:?}");
    assert!(notes[0].message.contains("__ISVALIDREF"), "{:?}", notes[0]);
    assert!(checked.file.text.contains("Mode = E_Mode#Auto"), "{}", checked.file.text);
    assert!(checked.file.text.contains("Mode : E_Mode := E_Mode#Manual;"), "{}", checked.file.text);
    assert_eq!(checked.charts.len(), 1);
    // The FB goes back with its body and its methods in CODESYS's shapes.
    let out = sfc_plcopen::export(&checked).expect("export");
    assert!(out.contains("pTarget^ := pTarget^ + 1;"), "{out}");
    assert!(out.contains("plcopenxml/method"), "{out}");
}

/// A network whose 30 chained AND blocks each feed both inputs of the next would be 2^30 terms
/// expanded; sharing each output once keeps the translation linear (the text size is checked,
/// the time printed, never asserted).
#[test]
fn shared_outputs_translate_linearly() {
    for as_condition in [false, true] {
        let xml = chained_and_network(30, as_condition);
        let t0 = std::time::Instant::now();
        let (_, checked, diags) = sfc_plcopen::check_xml(0, "chain.xml", &xml, &opts());
        let took = t0.elapsed();
        assert!(!diags.iter().any(|d| d.is_error()), "{diags:?}");
        assert!(checked.file.text.len() < 20_000, "{} bytes:\n{}", checked.file.text.len(), checked.file.text);
        println!(
            "30 chained AND blocks ({}): imported and checked in {took:?}",
            if as_condition { "a condition" } else { "a body" }
        );
    }
}

/// `n` AND blocks, each fed twice by the one before: in an FBD body, or as a transition's
/// condition in an SFC body.
pub fn chained_and_network(n: usize, as_condition: bool) -> String {
    let mut els = String::new();
    els.push_str(r#"<inVariable localId="1"><position x="0" y="0"/><connectionPointOut/><expression>A</expression></inVariable>"#);
    els.push_str(r#"<inVariable localId="2"><position x="0" y="0"/><connectionPointOut/><expression>B</expression></inVariable>"#);
    let (mut a, mut b) = (1, 2);
    for k in 0..n {
        let id = 10 + k;
        els.push_str(&format!(
            r#"<block localId="{id}" typeName="AND"><position x="0" y="0"/><inputVariables><variable formalParameter="IN1"><connectionPointIn><connection refLocalId="{a}"/></connectionPointIn></variable><variable formalParameter="IN2"><connectionPointIn><connection refLocalId="{b}"/></connectionPointIn></variable></inputVariables><inOutVariables/><outputVariables><variable formalParameter="OUT"><connectionPointOut/></variable></outputVariables></block>"#
        ));
        a = id;
        b = id;
    }
    let vars = r#"<interface><localVars><variable name="A"><type><BOOL/></type></variable><variable name="B"><type><BOOL/></type></variable><variable name="Q"><type><BOOL/></type></variable></localVars></interface>"#;
    let body = if as_condition {
        format!(
            r#"<SFC><step localId="500" name="S0" initialStep="true"><position x="0" y="0"/><connectionPointOut/></step>{els}<transition localId="501"><position x="0" y="0"/><connectionPointIn><connection refLocalId="500"/></connectionPointIn><condition><connectionPointIn><connection refLocalId="{a}"/></connectionPointIn></condition></transition><step localId="502" name="S1"><position x="0" y="0"/><connectionPointIn><connection refLocalId="501"/></connectionPointIn></step></SFC>"#
        )
    } else {
        format!(
            r#"<FBD>{els}<outVariable localId="900"><position x="0" y="0"/><connectionPointIn><connection refLocalId="{a}"/></connectionPointIn><expression>Q</expression></outVariable></FBD>"#
        )
    };
    format!(
        r#"<?xml version="1.0" encoding="utf-8"?><project xmlns="http://www.plcopen.org/xml/tc6_0201"><fileHeader companyName="t" productName="t" productVersion="1" creationDateTime="2024-01-01T00:00:00"/><contentHeader name="chain"><coordinateInfo><fbd><scaling x="0" y="0"/></fbd><ld><scaling x="0" y="0"/></ld><sfc><scaling x="0" y="0"/></sfc></coordinateInfo></contentHeader><types><dataTypes/><pous><pou name="Chain" pouType="program">{vars}<body>{body}</body></pou></pous></types></project>"#
    )
}

/// Putting one POU back into a file: only its element changes; in a CODESYS file (no `xhtml`
/// prefix declared) the POU declares it; code inside CDATA is not re-indented.
#[test]
fn splicing_one_pou_keeps_every_other_byte() {
    for (rel, pou) in [("beremiz/sfc_fbd_ld_project.plc.xml", "Conveyor"), ("codesys/types_pous_selection.xml", "Lift")]
    {
        let xml = std::fs::read_to_string(real_dir().join(rel)).expect("fixture");
        let imported = sfc_plcopen::import(0, rel, &xml);
        // The POU's text as the editor would save it: here, its imported text with a step renamed.
        let (unit, _) = sfc_syntax::parse(0, &imported.text);
        let p = unit
            .items
            .iter()
            .find_map(|i| match i {
                sfc_syntax::ast::Item::Pou(p) if p.name.text == pou => Some(p.span),
                _ => None,
            })
            .expect("the POU");
        let text = imported.text[p.start as usize..p.end as usize].to_string();
        let (old_step, new_step) = if pou == "Lift" { ("Arrived", "AtFloor") } else { ("Running", "Moving") };
        let text = text.replace(old_step, new_step);
        let checked = check_text("pou.st", &text);
        let out = sfc_plcopen::splice_pou(&xml, pou, &checked).expect("spliced");
        let start = xml.find(&format!("<pou name=\"{pou}\"")).expect("start");
        let end = xml[start..].find("</pou>").map(|e| start + e + 6).expect("end");
        assert_eq!(&out[..start], &xml[..start], "{rel}: bytes before the POU");
        let tail = &xml[end..];
        assert!(out.ends_with(tail), "{rel}: bytes after the POU");
        roxmltree::Document::parse(&out).unwrap_or_else(|e| panic!("{rel}: not well-formed: {e}"));
        let (_, again, diags) = sfc_plcopen::check_xml(0, rel, &out, &opts());
        assert!(!diags.iter().any(|d| d.is_error()), "{rel}: {diags:?}");
        let chart = again.charts.iter().find(|c| c.pou == pou).expect("chart");
        assert!(chart.step(new_step).is_some(), "{rel}: renamed step");
        if pou == "Conveyor" {
            assert!(out.contains("<![CDATA[Logic(Run := TRUE, Fault := Jam);\nBelt := Logic.Motor;"), "{out}");
        }
    }
}

/// Two initial steps in one network (Beremiz, MatIEC and OpenPLC run such charts; IEC does not
/// allow it): imported as drawn and reported, and exported as drawn.
#[test]
fn two_initial_steps_in_one_network_are_kept_and_reported() {
    let xml = std::fs::read_to_string(real_dir().join("openplc/two_initial_networks.xml")).expect("fixture");
    // Join the two loops into one network: B1 also leads back to A0.
    let joined = xml.replacen("targetName=\"B0\"", "targetName=\"A0\"", 1);
    let (_, checked, diags) = sfc_plcopen::check_xml(0, "joined.xml", &joined, &opts());
    assert!(diags.iter().any(|d| d.code == "SFC0202"), "{diags:?}");
    let chart = &checked.charts[0];
    assert_eq!(chart.steps.iter().filter(|s| s.initial).count(), 2);
    let out = sfc_plcopen::export(&checked).expect("exported as drawn");
    if let Some(r) = xmllint(&out) {
        r.expect("valid");
    }
    let (_, again, _) = sfc_plcopen::check_xml(0, "again.xml", &out, &opts());
    assert_eq!(again.charts[0].steps.iter().filter(|s| s.initial).count(), 2);
}

/// A chart being drawn in Beremiz: a transition with no step after it, one with no step before
/// it and one wired to nothing, and a step wired only to those. IEC text cannot hold such
/// transitions; they are reported (SFC0706), kept on the POU (`sfc.loose`, counted with the
/// chart's transitions against the XML's own count), and exported back wired as they were.
#[test]
fn unconnected_transitions_of_a_chart_being_drawn_are_kept_and_exported_back() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/drawing_in_progress.xml");
    let xml = std::fs::read_to_string(&path).expect("fixture");
    let (_, checked, diags) = sfc_plcopen::check_xml(0, "drawing.xml", &xml, &opts());
    let unconnected: Vec<_> = diags.iter().filter(|d| d.code == "SFC0706").collect();
    assert_eq!(unconnected.len(), 3, "{diags:?}");
    let loose = |c: &sfc_model::Checked| -> Vec<sfc_syntax::attr_value::Loose> {
        c.unit
            .items
            .iter()
            .filter_map(|i| if let sfc_syntax::ast::Item::Pou(p) = i { Some(p) } else { None })
            .flat_map(|p| p.attributes.iter())
            .filter(|a| a.name.eq_ignore_ascii_case(sfc_syntax::attr_value::LOOSE))
            .filter_map(|a| sfc_syntax::attr_value::Loose::read(&sfc_syntax::attr_value::unescape(a.value.as_deref()?)))
            .collect()
    };
    let kept = loose(&checked);
    assert_eq!(kept.len(), 3);
    assert_eq!((kept[0].from.len(), kept[0].to.as_slice()), (0, &["Draining".to_string()][..]));
    assert_eq!(kept[0].condition, "Level > 80");
    assert_eq!((kept[1].from.as_slice(), kept[1].to.len()), (&["Draining".to_string()][..], 0));
    assert!(kept[2].from.is_empty() && kept[2].to.is_empty());
    let chart = &checked.charts[0];
    if let Some(counts) = script_counts(&[path.clone()]) {
        assert_eq!(
            counts[0]["TANKFILL"],
            [chart.steps.len(), chart.transitions.len() + kept.len(), chart.actions.len(), 0]
        );
    }
    // The export writes the chart as drawn: the step and the three transitions, wired as before.
    let out = sfc_plcopen::export(&checked).expect("a chart being drawn is exported as drawn");
    if let Some(r) = xmllint(&out) {
        r.expect("valid");
    }
    assert_eq!(out.matches("<transition ").count(), 5, "{out}");
    let (_, again, diags) = sfc_plcopen::check_xml(0, "again.xml", &out, &opts());
    assert_eq!(diags.iter().filter(|d| d.code == "SFC0706").count(), 3, "{diags:?}");
    assert_eq!(loose(&again), kept);
    assert_eq!(again.charts[0].transitions.len(), chart.transitions.len());
}

/// CODESYS spellings outside ST bodies and lists outside resources: bits read by partial access
/// (`wStatus.%X3` is `wStatus.3`), a contact and a coil naming a qualified global
/// (`GVL_Cip.bEStop` is `bEStop`), and the global variable lists of the project's pool (its
/// `addData`), one of them holding a VAR_GLOBAL and a VAR_GLOBAL CONSTANT block, which CODESYS
/// writes as an empty list with its `mixedattrsvarlist`.
#[test]
fn partial_access_qualified_contacts_and_pool_lists_are_imported() {
    let read = |rel: &str| {
        let xml = std::fs::read_to_string(real_dir().join(rel)).expect("fixture");
        let (_, checked, diags) = sfc_plcopen::check_xml(0, rel, &xml, &opts());
        assert!(!diags.iter().any(|d| d.is_error()), "{rel}: {diags:?}");
        checked.file.text.clone()
    };
    let t = read("twincat/car_park_barrier.xml");
    assert!(t.contains("bJam := wStatus.3 OR wStatus.7;"), "{t}");
    assert!(!t.contains("%X"), "{t}");
    let t = read("twincat/cip_skid_ld_selection.xml");
    assert!(t.contains("NOT bEStop") && !t.contains("GVL_Cip.bEStop"), "{t}");
    let t = read("codesys/batch_mixer_pool_gvls.xml");
    assert!(t.contains("xValveA : BOOL;"), "{t}");
    assert!(t.contains("VAR_GLOBAL CONSTANT"), "{t}");
    assert!(t.contains("tMix : TIME := T#20S;") && t.contains("rSetA : REAL := 12.5;"), "{t}");
    assert!(!t.contains("plcopenxml/globalvars"), "the pool's lists are imported, not carried: {t}");
}
