//! The drawing of every example and fixture, as the editor opens it: no wire segment runs
//! through a block or a label, no two labels overlap and no label covers a block, every wire
//! of a chart the structured layout drew is straight, and laying out an opened chart again
//! changes nothing (so *Layout* leaves an unchanged chart unmodified). Also the charts imported
//! from real PLCopen files of other tools (Beremiz, matiec) once laid out (*Layout*): opened,
//! they keep their authors' positions, which are theirs to keep. And every chart the
//! repository holds (examples, every crate's fixtures, the real files of `tests/corpus/real`),
//! opened as the editor opens it: no label is cut, none overlaps another or a block; conditions
//! wrap by the rule the canvas follows too (`tests/shared/condition_lines.json`).

use sfc_doc::drawing::{labels, Rect};
use sfc_doc::route::crosses;
use sfc_doc::{auto_layout, open, EditorDoc, ElementKind, Point};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn files(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, ext, out);
        } else if p.extension().is_some_and(|x| x == ext) && !p.to_string_lossy().ends_with(".saved.st") {
            out.push(p);
        }
    }
}

/// The polyline of every wire: its bends, or straight from pin to pin.
fn wires(doc: &EditorDoc) -> Vec<(String, Vec<Point>)> {
    let pin = |id: &str, input: bool, k: u32| -> Option<Point> {
        let e = doc.elements.iter().find(|e| e.id == id)?;
        let (ins, outs) = match e.kind? {
            ElementKind::Step | ElementKind::Transition => (1, 1),
            ElementKind::SelectionDivergence | ElementKind::SimultaneousDivergence => (1, e.pins.unwrap_or(2)),
            ElementKind::SelectionConvergence | ElementKind::SimultaneousConvergence => (e.pins.unwrap_or(2), 1),
            ElementKind::Jump => (1, 0),
            _ => (0, 0),
        };
        let n = if input { ins } else { outs };
        let y = if input { e.y } else { e.y + e.h };
        if n <= 1 {
            return Some(Point { x: e.x + e.w / 2.0, y });
        }
        let off = 10.0 + (e.w - 20.0) * f64::from(k) / f64::from(n - 1);
        let snapped = ((off / 10.0).round() * 10.0).clamp(10.0, e.w - 10.0);
        Some(Point { x: e.x + snapped, y })
    };
    doc.connections
        .iter()
        .filter_map(|c| {
            let pts = if c.waypoints.len() >= 2 {
                c.waypoints.clone()
            } else {
                vec![pin(&c.source, false, c.source_pin)?, pin(&c.target, true, c.target_pin)?]
            };
            Some((c.id.clone(), pts))
        })
        .collect()
}

/// What is wrong with a drawing, one line per fault.
fn faults(name: &str, doc: &EditorDoc, straight: bool) -> Vec<String> {
    let mut out = Vec::new();
    let blocks: Vec<(String, Rect)> =
        doc.elements.iter().filter(|e| e.kind.is_some()).map(|e| (e.id.clone(), Rect::of(e))).collect();
    let labels = labels(doc);
    for (id, pts) in wires(doc) {
        for w in pts.windows(2) {
            for (b, r) in &blocks {
                if crosses(w[0], w[1], r) {
                    out.push(format!("{name}: wire {id} runs through block {b}"));
                }
            }
            for l in &labels {
                if crosses(w[0], w[1], &l.rect) {
                    out.push(format!(
                        "{name}: wire {id} runs through the label {:?} of {}",
                        l.lines, doc.elements[l.block].id
                    ));
                }
            }
        }
        if straight && pts.len() > 2 {
            out.push(format!("{name}: wire {id} bends: {pts:?}"));
        }
    }
    for (i, a) in labels.iter().enumerate() {
        if a.lines.iter().any(|l| l.ends_with('…')) {
            out.push(format!("{name}: the label {:?} of {} is cut", a.lines, doc.elements[a.block].id));
        }
        for b in &labels[i + 1..] {
            if a.rect.overlaps(&b.rect) {
                out.push(format!("{name}: labels {:?} and {:?} overlap", a.lines, b.lines));
            }
        }
        for (id, r) in &blocks {
            if a.rect.overlaps(r) {
                out.push(format!("{name}: label {:?} covers block {id}", a.lines));
            }
        }
    }
    for (i, (a, ra)) in blocks.iter().enumerate() {
        for (b, rb) in &blocks[i + 1..] {
            if ra.overlaps(rb) {
                out.push(format!("{name}: blocks {a} and {b} overlap"));
            }
        }
    }
    out
}

fn same_geometry(a: &EditorDoc, b: &EditorDoc) -> bool {
    a.elements.len() == b.elements.len()
        && a.elements.iter().zip(&b.elements).all(|(x, y)| (x.x, x.y, x.w, x.h) == (y.x, y.y, y.w, y.h))
        && a.connections.iter().zip(&b.connections).all(|(x, y)| x.waypoints == y.waypoints)
}

#[test]
fn examples_and_fixtures_draw_cleanly() {
    let mut paths = Vec::new();
    files(&root().join("examples"), "st", &mut paths);
    files(&root().join("tests/fixtures/valid"), "st", &mut paths);
    files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots"), "st", &mut paths);
    assert!(paths.len() >= 40, "{} files", paths.len());
    let mut all = Vec::new();
    let (mut charts, mut laid_out) = (0, 0);
    for p in &paths {
        let text = std::fs::read_to_string(p).unwrap();
        let name = p.strip_prefix(root()).unwrap_or(p).display().to_string();
        // Charts with the positions of their authors are drawn where they are.
        let stored = text.contains("sfc.x");
        for doc in open(0, &name, &text).charts {
            charts += 1;
            let structured = !stored && doc.elements.iter().any(|e| e.kind == Some(ElementKind::Step));
            all.extend(faults(&format!("{name}: {}", doc.pou), &doc, false));
            if structured {
                laid_out += 1;
                let again = auto_layout(&doc);
                if !same_geometry(&doc, &again) {
                    all.push(format!("{name}: {}: laying it out again moves blocks", doc.pou));
                }
            }
        }
    }
    println!("{charts} charts of {} files checked ({laid_out} laid out by the structured layout)", paths.len());
    assert!(all.is_empty(), "{} faults:\n{}", all.len(), all.join("\n"));
}

#[test]
fn imported_real_files_laid_out_draw_cleanly() {
    let corpus = root().join("../shared/corpus");
    let mut paths = Vec::new();
    files(&corpus.join("beremiz"), "xml", &mut paths);
    files(&corpus.join("matiec"), "xml", &mut paths);
    if paths.is_empty() {
        eprintln!("the shared corpus is not there; skipped");
        return;
    }
    let mut all = Vec::new();
    for p in &paths {
        let xml = std::fs::read_to_string(p).unwrap();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let imported = sfc_plcopen::import(0, &name, &xml);
        for doc in open(0, &name, &imported.text).charts {
            // Laid out afresh (Layout), it draws cleanly too.
            all.extend(faults(&format!("{name}: {} (laid out)", doc.pou), &auto_layout(&doc), false));
        }
    }
    assert!(all.is_empty(), "{} faults:\n{}", all.len(), all.join("\n"));
}

/// A step with S7-GRAPH's interlock and supervision (imported from SimaticML) shows them as
/// S7-GRAPH does, a `C` and a `V` box on its left side, with the condition as the tooltip; a
/// step without them has none.
#[test]
fn graph_interlock_and_supervision_are_drawn_on_the_step() {
    let text = "FUNCTION_BLOCK Drill\nVAR_INPUT Clamped, Down : BOOL; END_VAR\nVAR_OUTPUT Motor : BOOL; END_VAR\n\
        INITIAL_STEP Idle : END_STEP\n\
        {attribute 'sfc.s7graph.interlock' := 'Clamped AND NOT Down'}\n\
        {attribute 'sfc.s7graph.supervision' := 'Drilling.T > T#10s'}\n\
        STEP Drilling : Motor(N); END_STEP\n\
        TRANSITION FROM Idle TO Drilling := Clamped; END_TRANSITION\n\
        TRANSITION FROM Drilling TO Idle := Down; END_TRANSITION\n\
        END_FUNCTION_BLOCK\n";
    let opened = open(0, "drill.st", text);
    let doc = opened.charts.first().expect("one chart");
    let step = |name: &str| doc.elements.iter().find(|e| e.name == name).expect(name).clone();
    let marks = sfc_doc::drawing::step_marks(&step("Drilling"));
    assert_eq!(marks, vec![("C", "Clamped AND NOT Down".to_string()), ("V", "Drilling.T > T#10s".to_string())]);
    assert!(sfc_doc::drawing::step_marks(&step("Idle")).is_empty());
    let svg = sfc_doc::svg(doc);
    assert!(svg.contains("<title>interlock: Clamped AND NOT Down</title>"), "{svg}");
    assert!(svg.contains("<title>supervision: Drilling.T &gt; T#10s</title>"), "{svg}");
    assert_eq!(svg.matches(">C</text>").count(), 1, "{svg}");
    assert_eq!(svg.matches(">V</text>").count(), 1, "{svg}");
}

/// The condition labels follow the rule of `tests/shared/condition_lines.json`, which the
/// canvas's tests (`web/test/diagram/view.test.ts`) read too: the same lines on both sides.
#[test]
fn conditions_wrap_by_the_shared_rule() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/shared/condition_lines.json");
    let shared: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    assert_eq!(shared["chars"].as_u64(), Some(sfc_doc::drawing::CONDITION_CHARS as u64));
    let cases = shared["cases"].as_array().unwrap();
    assert!(cases.len() > 10);
    for c in cases {
        let e = sfc_doc::Element {
            kind: Some(ElementKind::Transition),
            condition: Some(c["condition"].as_str().unwrap().to_string()),
            w: 40.0,
            h: 20.0,
            ..sfc_doc::Element::default()
        };
        let want: Vec<&str> = c["lines"].as_array().unwrap().iter().map(|l| l.as_str().unwrap()).collect();
        assert_eq!(sfc_doc::drawing::condition_lines(&e), want, "{}", c["what"]);
        // The label is as tall as its lines, centred on the bar.
        let label =
            sfc_doc::drawing::labels_of(&e, 0).into_iter().find(|l| l.kind == sfc_doc::drawing::LabelKind::Condition);
        match label {
            Some(l) => {
                assert_eq!(l.rect.h, sfc_doc::drawing::LINE_H * want.len() as f64);
                assert_eq!(l.rect.y + l.rect.h / 2.0, 10.0);
            }
            None => assert!(want.is_empty()),
        }
    }
}

/// The charts of a file as the editor opens it (text as it is, XML — PLCopen, L5X, SimaticML —
/// through the import), and whether its text stores positions.
fn open_any(path: &Path, name: &str) -> (Vec<EditorDoc>, bool) {
    let Ok(bytes) = std::fs::read(path) else { return (Vec::new(), false) };
    let text = String::from_utf8_lossy(&bytes);
    let ext = path.extension().map(|x| x.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let text = if ext == "xml" || ext == "l5x" { sfc_plcopen::import(0, name, &text).text } else { text.into_owned() };
    (open(0, name, &text).charts, text.contains("sfc.x"))
}

/// Every chart file the repository holds: the examples, the fixtures of the repository and of
/// every crate (text, PLCopen XML, L5X, SimaticML), the real files of `tests/corpus/real`.
fn every_chart_file() -> Vec<PathBuf> {
    let root = root();
    let mut paths = Vec::new();
    for ext in ["st", "xml", "L5X"] {
        files(&root.join("examples"), ext, &mut paths);
        files(&root.join("tests/fixtures"), ext, &mut paths);
        files(&root.join("tests/corpus/real"), ext, &mut paths);
        for c in std::fs::read_dir(root.join("crates")).unwrap().flatten() {
            files(&c.path().join("tests/fixtures"), ext, &mut paths);
        }
    }
    paths.sort();
    paths.dedup();
    paths
}

/// What is wrong with the labels of a drawing: a label cut (`…`), two labels overlapping, a
/// label over a block. With `wrapped_only`, only the faults of labels of several lines.
fn label_faults(name: &str, doc: &EditorDoc, wrapped_only: bool) -> Vec<String> {
    let mut out = Vec::new();
    let labels = labels(doc);
    let blocks: Vec<(usize, Rect)> =
        doc.elements.iter().enumerate().filter(|(_, e)| e.kind.is_some()).map(|(i, e)| (i, Rect::of(e))).collect();
    let id = |i: usize| doc.elements[i].id.as_str();
    for (k, a) in labels.iter().enumerate() {
        if a.lines.iter().any(|l| l.ends_with('…')) {
            out.push(format!("{name}: the label {:?} of {} is cut", a.lines, id(a.block)));
        }
        for b in &labels[k + 1..] {
            if a.rect.overlaps(&b.rect) && (!wrapped_only || a.lines.len() > 1 || b.lines.len() > 1) {
                out.push(format!(
                    "{name}: labels {:?} of {} and {:?} of {} overlap",
                    a.lines,
                    id(a.block),
                    b.lines,
                    id(b.block)
                ));
            }
        }
        if wrapped_only && a.lines.len() < 2 {
            continue;
        }
        for (i, r) in &blocks {
            if a.rect.overlaps(r) {
                out.push(format!("{name}: the label {:?} of {} covers block {}", a.lines, id(a.block), id(*i)));
            }
        }
    }
    out
}

/// Every label of every chart the repository holds, as the editor opens it: whole (no `…`),
/// clear of every other label and of every block. A chart drawn where its authors placed it
/// (stored positions, most of them another tool's: PLCopen, L5X) keeps those positions, which
/// are theirs to keep, and another tool's label sizes are not the editor's: there the labels of
/// several lines (what wrapping adds) must be clear as it opens, and every label once laid out
/// (*Layout*). Files over 2 MB and charts of over 5,000 blocks are left out, so this runs in
/// seconds.
#[test]
fn every_chart_in_the_repository_draws_whole_labels_clear_of_blocks() {
    let paths = every_chart_file();
    assert!(paths.len() >= 150, "{} files", paths.len());
    let (mut charts, mut stored, mut wrapped) = (0, 0, 0);
    let mut all = Vec::new();
    for p in &paths {
        if std::fs::metadata(p).map_or(true, |m| m.len() > 2_000_000) {
            continue;
        }
        let name = p.strip_prefix(root()).unwrap_or(p).display().to_string();
        let (docs, positioned) = open_any(p, &name);
        for doc in docs {
            if doc.elements.len() > 5_000 {
                continue;
            }
            charts += 1;
            wrapped += labels(&doc).iter().filter(|l| l.lines.len() > 1).count();
            let name = format!("{name}: {}", doc.pou);
            if positioned {
                stored += 1;
                all.extend(label_faults(&name, &doc, true));
                all.extend(label_faults(&format!("{name} (laid out)"), &auto_layout(&doc), false));
            } else {
                all.extend(label_faults(&name, &doc, false));
            }
        }
    }
    println!(
        "{charts} charts of {} files checked ({stored} at stored positions), {wrapped} labels of several lines",
        paths.len()
    );
    assert!(charts >= 150, "{charts} charts");
    assert!(all.is_empty(), "{} faults:\n{}", all.len(), all.join("\n"));
}

/// A condition of `words` words, `k` telling them apart.
fn long_condition(k: usize, words: usize) -> String {
    (0..words).map(|w| format!("Sensor{k}_{w}")).collect::<Vec<_>>().join(" AND ")
}

/// Conditions of one to twelve lines, at the head and the tail of selection branches, in
/// simultaneous branches, before a jump and in a long sequence, in the structured layout and
/// in the fallback one (a chart the block structure does not take): every label whole, none
/// overlapping another or a block, no wire through a label, and the layout still stable.
#[test]
fn long_conditions_wrap_and_get_the_room_they_need() {
    let mut vars = String::new();
    let c = |k: usize, words: usize| long_condition(k, words);
    for k in 0..40 {
        for w in 0..24 {
            vars.push_str(&format!("Sensor{k}_{w}, "));
        }
    }
    let structured = format!(
        "PROGRAM P\nVAR {vars}Out : BOOL; END_VAR\n\
         INITIAL_STEP S0 : END_STEP\n\
         TRANSITION FROM S0 TO A1 := {}; END_TRANSITION\n\
         TRANSITION FROM S0 TO B1 := {}; END_TRANSITION\n\
         TRANSITION FROM S0 TO C1 := {}; END_TRANSITION\n\
         STEP A1 : Out(N); END_STEP\n STEP B1 : Out(N); END_STEP\n STEP C1 : END_STEP\n\
         TRANSITION FROM A1 TO J := {}; END_TRANSITION\n\
         TRANSITION FROM B1 TO J := {}; END_TRANSITION\n\
         TRANSITION FROM C1 TO S0 := {}; END_TRANSITION\n\
         STEP J : END_STEP\n\
         TRANSITION FROM J TO (P1, P2) := {}; END_TRANSITION\n\
         STEP P1 : END_STEP\n STEP P2 : END_STEP\n\
         TRANSITION FROM P1 TO P1b := {}; END_TRANSITION\n\
         TRANSITION FROM P2 TO P2b := {}; END_TRANSITION\n\
         STEP P1b : END_STEP\n STEP P2b : END_STEP\n\
         TRANSITION FROM (P1b, P2b) TO Q := {}; END_TRANSITION\n\
         STEP Q : END_STEP\n\
         TRANSITION FROM Q TO S0 := {}; END_TRANSITION\n\
         END_PROGRAM\n",
        c(1, 20),
        c(2, 2),
        c(3, 12),
        c(4, 30),
        c(5, 1),
        c(6, 9),
        c(7, 16),
        c(8, 24),
        c(9, 3),
        c(10, 40),
        c(11, 7),
    );
    // Branches that meet out of order (B leads into A's branch and past it): no block
    // structure, so the fallback layout places the blocks and routes the wires.
    let tangled = format!(
        "PROGRAM T\nVAR {vars} END_VAR\n\
         INITIAL_STEP S : END_STEP\n STEP A : END_STEP\n STEP B : END_STEP\n STEP C : END_STEP\n STEP D : END_STEP\n\
         TRANSITION FROM S TO A := {}; END_TRANSITION\n\
         TRANSITION FROM S TO B := {}; END_TRANSITION\n\
         TRANSITION FROM A TO C := {}; END_TRANSITION\n\
         TRANSITION FROM B TO C := {}; END_TRANSITION\n\
         TRANSITION FROM C TO D := {}; END_TRANSITION\n\
         TRANSITION FROM B TO D := {}; END_TRANSITION\n\
         TRANSITION FROM D TO S := {}; END_TRANSITION\n\
         END_PROGRAM\n",
        c(20, 14),
        c(21, 22),
        c(22, 30),
        c(23, 8),
        c(24, 18),
        c(25, 5),
        c(26, 11),
    );
    let mut all = Vec::new();
    for (name, text) in [("structured", &structured), ("tangled", &tangled)] {
        let opened = open(0, name, text);
        assert!(!opened.charts.is_empty(), "{name}: no chart");
        for doc in opened.charts {
            let tallest = labels(&doc).iter().map(|l| l.lines.len()).max().unwrap_or(0);
            assert!(tallest >= 8, "{name}: the tallest label has {tallest} lines");
            let bends = doc.connections.iter().any(|c| c.waypoints.len() > 2);
            assert_eq!(bends, name == "tangled", "{name}: the fallback layout bends wires, the structured one none");
            all.extend(faults(name, &doc, false));
            all.extend(label_faults(name, &doc, false));
            if !same_geometry(&doc, &auto_layout(&doc)) {
                all.push(format!("{name}: laying it out again moves blocks"));
            }
        }
    }
    assert!(all.is_empty(), "{} faults:\n{}", all.len(), all.join("\n"));
}
