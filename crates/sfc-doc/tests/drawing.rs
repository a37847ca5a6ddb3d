//! The drawing of every example and fixture, as the editor opens it: no wire segment runs
//! through a block or a label, no two labels overlap and no label covers a block, every wire
//! of a chart the structured layout drew is straight, and laying out an opened chart again
//! changes nothing (so *Layout* leaves an unchanged chart unmodified). Also the charts imported
//! from real PLCopen files of other tools (Beremiz, matiec) once laid out (*Layout*): opened,
//! they keep their authors' positions, which are theirs to keep.

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
    assert_eq!(
        marks,
        vec![("C", "Clamped AND NOT Down".to_string()), ("V", "Drilling.T > T#10s".to_string())]
    );
    assert!(sfc_doc::drawing::step_marks(&step("Idle")).is_empty());
    let svg = sfc_doc::svg(doc);
    assert!(svg.contains("<title>interlock: Clamped AND NOT Down</title>"), "{svg}");
    assert!(svg.contains("<title>supervision: Drilling.T &gt; T#10s</title>"), "{svg}");
    assert_eq!(svg.matches(">C</text>").count(), 1, "{svg}");
    assert_eq!(svg.matches(">V</text>").count(), 1, "{svg}");
}
