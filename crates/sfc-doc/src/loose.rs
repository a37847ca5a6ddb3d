//! Loose pieces and duplicates: what a layout places beside the chart rather than in it.
//!
//! A *loose piece* is a group of blocks wired to each other but not to the chart the text
//! describes (a transition dropped and not connected yet, a step with its own transition, a
//! jump of nothing): no step or transition of the text is among them. The layouts place the
//! chart without them and then put each piece, as drawn, in a column right of the chart, so a
//! piece never moves the chart's blocks or bends its wires. Blocks an import stacked at one
//! place (Beremiz's `first_steps` draws two identical jumps at the same position) are laid
//! side by side when the chart is opened.

use crate::drawing::{labels, Rect};
use crate::graph::{Derived, Role};
use crate::{layout, EditorDoc, ElementKind};

/// Gap between the chart and the column of loose pieces, and between two pieces.
const GAP: f64 = 40.0;
/// Gap between two blocks laid side by side.
const SIDE_GAP: f64 = 20.0;

fn snap_up(v: f64) -> f64 {
    (v / 10.0).ceil() * 10.0
}

/// Per block: whether it belongs to a loose piece. Text labels are never loose (they keep
/// their place, see `open::clear_text_labels`); an action block belongs to its step's piece.
pub fn loose_blocks(doc: &EditorDoc, d: &Derived) -> Vec<bool> {
    let n = doc.elements.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let union = |p: &mut Vec<usize>, a: usize, b: usize| {
        let (ra, rb) = (find(p, a), find(p, b));
        if ra != rb {
            p[ra] = rb;
        }
    };
    for c in &doc.connections {
        if let (Some(&a), Some(&b)) = (d.by_id.get(&c.source), d.by_id.get(&c.target)) {
            if a < n && b < n {
                union(&mut parent, a, b);
            }
        }
    }
    for (i, e) in doc.elements.iter().enumerate() {
        if let Some(&s) = e.step.as_ref().and_then(|s| d.by_id.get(s)) {
            if s < n {
                union(&mut parent, i, s);
            }
        }
    }
    let mut in_chart = vec![false; n];
    for (i, r) in d.roles.iter().enumerate().take(n) {
        if matches!(r, Role::Step(_) | Role::Transition(_)) {
            let root = find(&mut parent, i);
            in_chart[root] = true;
        }
    }
    (0..n)
        .map(|i| {
            let e = &doc.elements[i];
            e.kind.is_some() && e.kind != Some(ElementKind::Text) && !in_chart[find(&mut parent, i)]
        })
        .collect()
}

/// The rectangles of block `i` and its labels.
fn outline(doc: &EditorDoc, all_labels: &[crate::drawing::Label], i: usize) -> Vec<Rect> {
    let mut out = vec![Rect::of(&doc.elements[i])];
    out.extend(all_labels.iter().filter(|l| l.block == i).map(|l| l.rect));
    out
}

fn bbox(rects: &[Rect]) -> Option<Rect> {
    let first = rects.first()?;
    let (mut x0, mut y0, mut x1, mut y1) = (first.x, first.y, first.right(), first.bottom());
    for r in rects {
        x0 = x0.min(r.x);
        y0 = y0.min(r.y);
        x1 = x1.max(r.right());
        y1 = y1.max(r.bottom());
    }
    Some(Rect { x: x0, y: y0, w: x1 - x0, h: y1 - y0 })
}

/// Puts the loose pieces (`loose`) in a column right of the rest of the drawing, each piece as
/// drawn (its blocks keep their places relative to each other), one below the other from the
/// chart's top; then routes their wires. The chart's blocks do not move. Returns whether a
/// block moved.
pub fn place_beside(doc: &mut EditorDoc, d: &Derived, loose: &[bool]) -> bool {
    if !loose.iter().any(|&l| l) {
        return false;
    }
    let all_labels = labels(doc);
    let chart: Vec<Rect> = (0..doc.elements.len())
        .filter(|&i| !loose[i] && doc.elements[i].kind.is_some())
        .flat_map(|i| outline(doc, &all_labels, i))
        .collect();
    let (column_x, mut y) = match bbox(&chart) {
        Some(b) => (snap_up(b.right() + GAP), snap_up(b.y.max(0.0))),
        None => (40.0, 40.0),
    };
    // Pieces in document order of their first block; a piece is the blocks wired together.
    let mut piece_of = vec![usize::MAX; doc.elements.len()];
    let mut pieces: Vec<Vec<usize>> = Vec::new();
    for i in 0..doc.elements.len() {
        if !loose[i] || piece_of[i] != usize::MAX {
            continue;
        }
        let k = pieces.len();
        let mut stack = vec![i];
        let mut members = Vec::new();
        piece_of[i] = k;
        while let Some(j) = stack.pop() {
            members.push(j);
            let id = doc.elements[j].id.clone();
            let mut next: Vec<usize> = Vec::new();
            for c in &doc.connections {
                let other = if c.source == id {
                    &c.target
                } else if c.target == id {
                    &c.source
                } else {
                    continue;
                };
                next.extend(d.by_id.get(other).copied());
            }
            for (m, e) in doc.elements.iter().enumerate() {
                if e.step.as_deref() == Some(id.as_str()) || doc.elements[j].step.as_deref() == Some(e.id.as_str()) {
                    next.push(m);
                }
            }
            for m in next {
                if m < loose.len() && loose[m] && piece_of[m] == usize::MAX {
                    piece_of[m] = k;
                    stack.push(m);
                }
            }
        }
        members.sort_unstable();
        pieces.push(members);
    }
    let mut moved = false;
    for members in &pieces {
        let rects: Vec<Rect> = members.iter().flat_map(|&i| outline(doc, &all_labels, i)).collect();
        let Some(b) = bbox(&rects) else { continue };
        let (dx, dy) = (column_x - b.x, y - b.y);
        let (dx, dy) = ((dx / 10.0).ceil() * 10.0 + 0.0, (dy / 10.0).ceil() * 10.0 + 0.0);
        if dx != 0.0 || dy != 0.0 {
            moved = true;
        }
        for &i in members {
            let e = &mut doc.elements[i];
            e.x += dx;
            e.y += dy;
        }
        for c in &mut doc.connections {
            if members.iter().any(|&i| doc.elements[i].id == c.source || doc.elements[i].id == c.target) {
                for p in &mut c.waypoints {
                    p.x += dx;
                    p.y += dy;
                }
            }
        }
        y = snap_up(y + b.h + GAP);
    }
    moved
}

/// Lays blocks an import put at one place side by side: a block whose rectangle is the same as
/// an earlier block's moves right, past its neighbours, to the first place where it overlaps no
/// block. Returns the blocks moved (their wires are to be routed again).
pub fn spread_duplicates(doc: &mut EditorDoc) -> Vec<usize> {
    let mut moved = Vec::new();
    for i in 1..doc.elements.len() {
        let e = &doc.elements[i];
        if e.kind.is_none() || e.kind == Some(ElementKind::Text) || e.w <= 0.0 || e.h <= 0.0 {
            continue;
        }
        let here = Rect::of(e);
        let stacked = doc.elements[..i].iter().any(|o| {
            o.kind.is_some() && o.kind != Some(ElementKind::Text) && (o.x - e.x).abs() < 0.5 && (o.y - e.y).abs() < 0.5
        });
        if !stacked {
            continue;
        }
        // The block with its labels (a jump's target name right of it) and everything else's.
        let all_labels = labels(doc);
        let others: Vec<Rect> = (0..doc.elements.len())
            .filter(|&j| j != i && doc.elements[j].kind.is_some() && doc.elements[j].kind != Some(ElementKind::Text))
            .flat_map(|j| outline(doc, &all_labels, j))
            .collect();
        let own = outline(doc, &all_labels, i);
        let Some(whole) = bbox(&own) else { continue };
        let mut x = here.x;
        for _ in 0..200 {
            x = snap_up(x + whole.w + SIDE_GAP);
            let dx = x - here.x;
            let moved: Vec<Rect> = own.iter().map(|r| Rect { x: r.x + dx, ..*r }).collect();
            if !moved.iter().any(|m| others.iter().any(|o| o.overlaps(m))) {
                break;
            }
        }
        doc.elements[i].x = x;
        moved.push(i);
    }
    moved
}

/// Routes again the wires of the blocks `blocks`.
pub fn route_of(doc: &mut EditorDoc, d: &Derived, blocks: &[usize]) {
    let ids: Vec<String> = blocks.iter().filter_map(|&i| doc.elements.get(i)).map(|e| e.id.clone()).collect();
    layout::route_matching(doc, d, |c| ids.iter().any(|id| *id == c.source || *id == c.target));
}
