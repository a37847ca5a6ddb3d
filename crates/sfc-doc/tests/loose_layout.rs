//! Layout that never breaks (issue 36, part 5): loose pieces go beside the chart without
//! moving it, and blocks an import stacked at one place are laid side by side.

use sfc_doc::drawing::{labels, Rect};
use sfc_doc::{auto_layout, open, EditorDoc, Element, ElementKind};
use std::path::Path;

fn traffic() -> EditorDoc {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join("examples/carwash/carwash.st")).unwrap();
    open(0, "carwash.st", &text).charts.remove(0)
}

fn rects(doc: &EditorDoc, ids: &[&str]) -> Vec<(String, f64, f64)> {
    doc.elements.iter().filter(|e| !ids.contains(&e.id.as_str())).map(|e| (e.id.clone(), e.x, e.y)).collect()
}

/// Every wire of the chart is where it is without the loose piece, and the bars hang centred
/// under the block above them, as the laid-out chart alone has them.
#[test]
fn an_unconnected_transition_does_not_disturb_the_layout() {
    let chart = auto_layout(&traffic());
    let mut with = chart.clone();
    // A transition dropped in the middle of the chart and not connected.
    let mid = chart.elements.iter().find(|e| e.kind == Some(ElementKind::Step) && !e.initial).unwrap();
    with.elements.push(Element {
        id: "loose".into(),
        kind: Some(ElementKind::Transition),
        x: mid.x + 5.0,
        y: mid.y + 3.0,
        w: 40.0,
        h: 10.0,
        condition: Some(String::new()),
        ..Element::default()
    });
    let laid = auto_layout(&with);
    assert_eq!(rects(&laid, &["loose"]), rects(&chart, &[]), "the chart's blocks moved");
    for (a, b) in laid.connections.iter().zip(&chart.connections) {
        assert_eq!(a.waypoints, b.waypoints, "wire {} took a detour", a.id);
    }
    // Bars centred: each divergence's incoming pin is straight under its block.
    for c in &laid.connections {
        let t = laid.elements.iter().find(|e| e.id == c.target).unwrap();
        if matches!(t.kind, Some(ElementKind::SelectionDivergence | ElementKind::SimultaneousDivergence)) {
            let s = laid.elements.iter().find(|e| e.id == c.source).unwrap();
            assert!(((s.x + s.w / 2.0) - (t.x + t.w / 2.0)).abs() < 0.5, "bar {} is off-centre", t.id);
        }
    }
    // The loose transition sits right of the chart, touching nothing.
    let lone = laid.elements.iter().find(|e| e.id == "loose").unwrap();
    let r = Rect::of(lone);
    let right = chart.elements.iter().map(|e| e.x + e.w).fold(0.0, f64::max);
    assert!(r.x > right, "the loose transition is not beside the chart: {r:?}");
    for e in laid.elements.iter().filter(|e| e.id != "loose") {
        assert!(!Rect::of(e).overlaps(&r), "the loose transition overlaps {}", e.id);
    }
    for l in labels(&laid).into_iter().filter(|l| laid.elements[l.block].id != "loose") {
        assert!(!l.rect.overlaps(&r), "the loose transition overlaps a label");
    }
    // Laid out again, nothing moves.
    let again = auto_layout(&laid);
    assert_eq!(rects(&again, &[]), rects(&laid, &[]));
}

/// A transition and a jump wired to each other but not to the chart are one piece: moved
/// together, wired as before.
#[test]
fn a_loose_piece_moves_as_one() {
    let chart = auto_layout(&traffic());
    let mut with = chart.clone();
    let at = |id: &str, kind, x, y, w, h| Element {
        id: String::from(id),
        kind: Some(kind),
        x,
        y,
        w,
        h,
        name: id.into(),
        ..Element::default()
    };
    with.elements.push(at("LooseT", ElementKind::Transition, 80.0, 170.0, 40.0, 10.0));
    with.elements
        .push(Element { target: Some("Idle".into()), ..at("LooseA", ElementKind::Jump, 90.0, 240.0, 20.0, 20.0) });
    with.connections.push(sfc_doc::Connection {
        id: "lc".into(),
        source: "LooseT".into(),
        target: "LooseA".into(),
        ..Default::default()
    });
    let laid = auto_layout(&with);
    assert_eq!(rects(&laid, &["LooseA", "LooseT"]), rects(&chart, &[]));
    let a = laid.elements.iter().find(|e| e.id == "LooseA").unwrap();
    let t = laid.elements.iter().find(|e| e.id == "LooseT").unwrap();
    assert_eq!((a.x - t.x, a.y - t.y), (10.0, 70.0), "the piece was pulled apart");
}

/// Imported blocks at identical places (Beremiz's `first_steps` draws two "Start" jumps at
/// one position) are laid side by side when opened.
#[test]
fn stacked_blocks_are_laid_side_by_side() {
    let text = "PROGRAM P\nVAR a, b : BOOL; END_VAR\n\
        INITIAL_STEP Start : END_STEP\n\
        STEP S1 : END_STEP\n\
        TRANSITION FROM Start TO S1 := a; END_TRANSITION\n\
        {attribute 'sfc.jump' := 'Start 300 300'}\n\
        TRANSITION T2 FROM S1 TO Start := b; END_TRANSITION\n\
        END_PROGRAM\n";
    let doc = open(0, "p.st", text).charts.remove(0);
    no_stacked(&doc, "p.st");
}

fn no_stacked(doc: &EditorDoc, name: &str) {
    let blocks: Vec<&Element> =
        doc.elements.iter().filter(|e| e.kind.is_some() && e.kind != Some(ElementKind::Text)).collect();
    for (i, a) in blocks.iter().enumerate() {
        for b in &blocks[i + 1..] {
            assert!(!Rect::of(a).overlaps(&Rect::of(b)), "{name}: {} and {} overlap", a.id, b.id);
        }
    }
}

#[test]
fn first_steps_jumps_are_side_by_side() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/corpus/beremiz/first_steps.plc.xml");
    let Ok(xml) = std::fs::read_to_string(&path) else {
        eprintln!("{} is not there; skipped", path.display());
        return;
    };
    let imported = sfc_plcopen::import(0, "first_steps.plc.xml", &xml);
    let charts = open(0, "first_steps.plc.xml", &imported.text).charts;
    assert!(!charts.is_empty());
    for doc in &charts {
        // Each jump with its label (the target's name right of it) touches no other jump.
        let ls = labels(doc);
        let jumps: Vec<usize> =
            (0..doc.elements.len()).filter(|&i| doc.elements[i].kind == Some(ElementKind::Jump)).collect();
        assert!(jumps.len() >= 2, "{}: {} jumps", doc.pou, jumps.len());
        let outline = |i: usize| -> Vec<Rect> {
            std::iter::once(Rect::of(&doc.elements[i]))
                .chain(ls.iter().filter(|l| l.block == i).map(|l| l.rect))
                .collect()
        };
        for (k, &a) in jumps.iter().enumerate() {
            for &b in &jumps[k + 1..] {
                let clash = outline(a).iter().any(|x| outline(b).iter().any(|y| x.overlaps(y)));
                assert!(!clash, "{}: jumps {} and {} overlap", doc.pou, doc.elements[a].id, doc.elements[b].id);
            }
        }
    }
}
