//! Geometry: block sizes and pin positions as the canvas draws them, and placing a document's
//! blocks on a layout of its chart made by `sfc-render` (steps, transitions and branch bars
//! where the layout has them, jumps below their transitions, action blocks right of their
//! steps, orthogonal routes for connections whose ends are not aligned).

use crate::drawing::{self, Rect};
use crate::graph::{pin_counts, Derived};
use crate::{EditorDoc, Element, ElementKind, Point};
use sfc_render::{BranchKind, Layout, LayoutKind};

/// Canvas grid.
pub const GRID: f64 = 10.0;
pub const TRANSITION_W: f64 = 40.0;
pub const TRANSITION_H: f64 = 20.0;
/// Height of every divergence and convergence bar.
pub const BAR_H: f64 = 10.0;
/// Distance from a bar's end to its outermost pin.
pub const BAR_PAD: f64 = 10.0;
pub const JUMP_SIZE: f64 = 20.0;
pub const ROW_H: f64 = 24.0;
/// Least distance between a label and a block placed below it.
const LABEL_CLEARANCE: f64 = 4.0;
/// `sfc-render`'s layout is drawn with smaller boxes; its coordinates are scaled by these
/// factors so the editor's sizes fit (the fallback for charts the structured layout of
/// `structured.rs` does not take).
const SX: f64 = 1.75;
const SY: f64 = 1.5;

/// A step box for a step named `name` (see [`drawing::step_size`]).
pub fn step_size(name: &str) -> (f64, f64) {
    drawing::step_size(&Element { name: name.to_string(), ..Element::default() })
}

/// Where pin `k` of a block is, as the canvas draws it (`web/src/diagram/geometry.ts`): inputs
/// on the top edge, outputs on the bottom edge; a single pin in the middle, several pins
/// equidistant from [`BAR_PAD`] after the left end to `BAR_PAD` before the right end, each
/// offset rounded to the grid.
pub fn pin_pos(e: &Element, input: bool, k: u32) -> Point {
    let (i, o) = pin_counts(e);
    let n = if input { i } else { o };
    let y = if input { e.y } else { e.y + e.h };
    if n <= 1 {
        return Point { x: e.x + e.w / 2.0, y };
    }
    let off = BAR_PAD + (e.w - 2.0 * BAR_PAD) * f64::from(k) / f64::from(n - 1);
    let snapped = ((off / GRID).round() * GRID).max(BAR_PAD).min(e.w - BAR_PAD);
    Point { x: e.x + snapped, y }
}

/// How layout coordinates map to canvas coordinates.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    scaled: bool,
}

impl Frame {
    pub fn of(layout: &Layout) -> Frame {
        Frame { scaled: layout.kind != LayoutKind::Stored }
    }
    fn x(self, v: f64) -> f64 {
        if self.scaled {
            (v * SX / GRID).round() * GRID
        } else {
            v
        }
    }
    fn y(self, v: f64) -> f64 {
        if self.scaled {
            (v * SY / GRID).round() * GRID
        } else {
            v
        }
    }
}

/// Which step or transition of the laid-out chart each block is.
pub struct Model<'a> {
    pub step_of: &'a [Option<usize>],
    pub transition_of: &'a [Option<usize>],
}

fn branch_kind(k: Option<ElementKind>) -> Option<BranchKind> {
    match k? {
        ElementKind::SelectionDivergence => Some(BranchKind::SelectionDivergence),
        ElementKind::SelectionConvergence => Some(BranchKind::SelectionConvergence),
        ElementKind::SimultaneousDivergence => Some(BranchKind::SimultaneousDivergence),
        ElementKind::SimultaneousConvergence => Some(BranchKind::SimultaneousConvergence),
        _ => None,
    }
}

/// The layout's geometry of a step or transition block: axis x, top and bottom.
fn layout_geom(layout: &Layout, m: &Model, i: usize) -> Option<(f64, f64, f64)> {
    if let Some(k) = m.step_of.get(i).copied().flatten() {
        let r = layout.steps.get(k)?.rect;
        return Some((r.x + r.w / 2.0, r.y, r.y + r.h));
    }
    let k = m.transition_of.get(i).copied().flatten()?;
    let g = layout.transitions.get(k)?;
    Some((g.x, g.y - g.thickness / 2.0, g.y + g.thickness / 2.0))
}

/// The block at the other end of the connection on a pin.
pub(crate) fn across(doc: &EditorDoc, d: &Derived, i: usize, input: bool, pin: usize) -> Option<(usize, u32)> {
    let c = if input { *d.ins.get(i)?.get(pin)? } else { *d.outs.get(i)?.get(pin)? }?;
    let c = &doc.connections[c];
    if input {
        Some((*d.by_id.get(&c.source)?, c.source_pin))
    } else {
        Some((*d.by_id.get(&c.target)?, c.target_pin))
    }
}

fn is_run_block(doc: &EditorDoc, i: usize) -> bool {
    matches!(doc.elements[i].kind, Some(ElementKind::Step | ElementKind::Transition))
}

/// Straightens the wires at the single pin of a branch bar. That pin sits in the middle of the
/// bar, while the layout puts the step above a divergence over its first branch (and the step
/// below a convergence over the first branch too), so the wire would bend twice on its way. A
/// vertical run of steps and transitions placed here is moved sideways onto the bar's single
/// pin when its ends are that pin, a jump or nothing (never a branch pin of a bar, which would
/// bend in turn), both ends agree, and it lands on no other block.
fn centre_runs(doc: &mut EditorDoc, d: &Derived, placed: &[bool], keep: &[bool]) {
    let n = doc.elements.len();
    let kind = |doc: &EditorDoc, i: usize| doc.elements[i].kind;
    let mut seen = vec![false; n];
    // Placed blocks by top edge, so a run is checked only against blocks level with it (tops
    // do not change here, only the runs' x).
    let mut by_top: Vec<usize> = (0..n).filter(|&j| placed[j]).collect();
    by_top.sort_by(|&a, &b| doc.elements[a].y.total_cmp(&doc.elements[b].y));
    let tallest = by_top.iter().map(|&j| doc.elements[j].h).fold(0.0, f64::max);
    for start in 0..n {
        if seen[start] || !placed[start] || !is_run_block(doc, start) {
            continue;
        }
        // Up to the top of the run (a loop of steps and transitions alone has none).
        let mut top = start;
        let mut path = vec![start];
        while let Some((p, _)) = across(doc, d, top, true, 0) {
            if !is_run_block(doc, p) || path.contains(&p) {
                break;
            }
            top = p;
            path.push(p);
        }
        let mut run = vec![top];
        let mut bottom = top;
        while let Some((next, _)) = across(doc, d, bottom, false, 0) {
            if !is_run_block(doc, next) || run.contains(&next) {
                break;
            }
            run.push(next);
            bottom = next;
        }
        for &i in &run {
            seen[i] = true;
        }
        if run.iter().any(|&i| keep.get(i).copied().unwrap_or(false) || !placed[i]) {
            continue;
        }
        // What each end asks for: Some(Some(x)) a bar's single pin at x, Some(None) nothing
        // (no wire, or a jump), None a wire that must stay where it is.
        let above = match across(doc, d, top, true, 0) {
            None => Some(None),
            Some((b, _)) if is_run_block(doc, b) => None, // a loop
            Some((b, _)) => match kind(doc, b) {
                Some(ElementKind::SelectionConvergence | ElementKind::SimultaneousConvergence) if placed[b] => {
                    Some(Some(pin_pos(&doc.elements[b], false, 0).x))
                }
                _ => None,
            },
        };
        let below = match across(doc, d, bottom, false, 0) {
            None => Some(None),
            Some((b, _)) => match kind(doc, b) {
                Some(ElementKind::Jump) => Some(None),
                Some(ElementKind::SelectionDivergence | ElementKind::SimultaneousDivergence) if placed[b] => {
                    Some(Some(pin_pos(&doc.elements[b], true, 0).x))
                }
                _ => None,
            },
        };
        let target = match (above, below) {
            (Some(Some(a)), Some(Some(b))) if (a - b).abs() < 0.5 => a,
            (Some(Some(a)), Some(None)) | (Some(None), Some(Some(a))) => a,
            _ => continue,
        };
        let axis = |e: &Element| e.x + e.w / 2.0;
        let x0 = axis(&doc.elements[top]);
        if run.iter().any(|&i| (axis(&doc.elements[i]) - x0).abs() > 0.5) || (target - x0).abs() < 0.5 {
            continue;
        }
        let dx = target - x0;
        let overlaps = run.iter().any(|&i| {
            let e = &doc.elements[i];
            let (l, r, t, b) = (e.x + dx - GRID / 2.0, e.x + e.w + dx + GRID / 2.0, e.y, e.y + e.h);
            // Only blocks whose top lies between `t - tallest` and `b` can reach into t..b.
            let first = by_top.partition_point(|&j| doc.elements[j].y <= t - tallest);
            by_top[first..].iter().take_while(|&&j| doc.elements[j].y < b).any(|&j| {
                let o = &doc.elements[j];
                !run.contains(&j) && o.x < r && o.x + o.w > l && o.y + o.h > t
            })
        });
        if overlaps {
            continue;
        }
        for &i in &run {
            doc.elements[i].x += dx;
        }
    }
}

/// Places every block not marked `keep` on `layout` and routes every connection read.
// Blocks are written by index while their neighbours are read.
#[allow(clippy::needless_range_loop)]
pub fn place(doc: &mut EditorDoc, d: &Derived, m: &Model, layout: &Layout, keep: &[bool]) {
    let f = Frame::of(layout);
    let n = doc.elements.len();
    let mut placed: Vec<bool> = keep.to_vec();
    placed.resize(n, false);
    // Steps and transitions.
    for i in 0..n {
        if placed[i] {
            continue;
        }
        let e = &mut doc.elements[i];
        if let Some(r) = m.step_of[i].and_then(|k| layout.steps.get(k)).map(|g| g.rect) {
            let (w, h) = drawing::step_size(e);
            e.x = f.x(r.x + r.w / 2.0) - w / 2.0;
            e.y = f.y(r.y + r.h / 2.0) - h / 2.0;
            (e.w, e.h) = (w, h);
            placed[i] = true;
        } else if let Some(g) = m.transition_of[i].and_then(|k| layout.transitions.get(k)) {
            e.x = f.x(g.x) - TRANSITION_W / 2.0;
            e.y = f.y(g.y) - TRANSITION_H / 2.0;
            (e.w, e.h) = (TRANSITION_W, TRANSITION_H);
            placed[i] = true;
        }
    }
    // Branch bars.
    let mut used = vec![false; layout.branches.len()];
    for i in 0..n {
        let Some(kind) = branch_kind(doc.elements[i].kind) else { continue };
        if placed[i] {
            continue;
        }
        let diverging = matches!(kind, BranchKind::SelectionDivergence | BranchKind::SimultaneousDivergence);
        let (ins, outs) = pin_counts(&doc.elements[i]);
        let single = across(doc, d, i, diverging, 0);
        let branch_pins = if diverging { outs } else { ins };
        let branches: Vec<Option<(usize, u32)>> =
            (0..branch_pins as usize).map(|k| across(doc, d, i, !diverging, k)).collect();
        // The layout's bar of this kind at the single side, spanning the branches.
        let single_geom = single.and_then(|(s, _)| layout_geom(layout, m, s));
        let mut best: Option<(f64, usize)> = None;
        for (b, bar) in layout.branches.iter().enumerate() {
            if used[b] || bar.kind != kind {
                continue;
            }
            let mut score = 0.0;
            if let Some((_, top, bottom)) = single_geom {
                if diverging {
                    if bar.y < bottom - 1.0 {
                        continue;
                    }
                    score += bar.y - bottom;
                } else {
                    if bar.y2 > top + 1.0 {
                        continue;
                    }
                    score += top - bar.y2;
                }
            }
            for (x, _, _) in branches.iter().flatten().filter_map(|(e, _)| layout_geom(layout, m, *e)) {
                score += 10.0 * ((bar.x1 - 1.0 - x).max(0.0) + (x - bar.x2 - 1.0).max(0.0));
            }
            if best.is_none_or(|(s, _)| score < s) {
                best = Some((score, b));
            }
        }
        let h = BAR_H;
        let single_pin = single.filter(|(s, _)| placed[*s]).map(|(s, p)| pin_pos(&doc.elements[s], !diverging, p));
        let cy = match best {
            Some((_, b)) => {
                used[b] = true;
                f.y((layout.branches[b].y + layout.branches[b].y2) / 2.0)
            }
            None => match single_pin {
                Some(p) if diverging => p.y + 2.0 * GRID,
                Some(p) => p.y - 2.0 * GRID,
                None => 0.0,
            },
        };
        let xs: Vec<f64> = branches
            .iter()
            .map(|b| b.filter(|(e, _)| placed[*e]).map(|(e, p)| pin_pos(&doc.elements[e], diverging, p).x))
            .collect::<Option<Vec<f64>>>()
            .unwrap_or_default();
        // The outer pins on the outer branches (the canvas spreads the others evenly between).
        let np = f64::from(branch_pins.max(2));
        let (x, w) = match (xs.first(), xs.last()) {
            (Some(&a), Some(&z)) if z - a >= 2.0 * GRID * (np - 1.0) => (a - BAR_PAD, z - a + 2.0 * BAR_PAD),
            _ => {
                let centre = match single_pin {
                    Some(p) => p.x,
                    None if !xs.is_empty() => xs.iter().sum::<f64>() / xs.len() as f64,
                    None => 0.0,
                };
                let w = 6.0 * GRID * (np - 1.0) + 2.0 * BAR_PAD;
                (centre - w / 2.0, w)
            }
        };
        let e = &mut doc.elements[i];
        (e.x, e.y, e.w, e.h) = (x.round(), cy - h / 2.0, w.round(), h);
        placed[i] = true;
    }
    centre_runs(doc, d, &placed, keep);
    // Jumps, below the pin they leave and the labels of the block there (a wrapped condition
    // reaches below its bar).
    for i in 0..n {
        if placed[i] || doc.elements[i].kind != Some(ElementKind::Jump) {
            continue;
        }
        let from = across(doc, d, i, true, 0).map(|(s, p)| {
            let src = &doc.elements[s];
            let clear = drawing::labels_of(src, s).iter().map(|l| l.rect.bottom()).fold(f64::NEG_INFINITY, f64::max);
            (pin_pos(src, false, p), clear)
        });
        let e = &mut doc.elements[i];
        if let Some((p, clear)) = from {
            let below_labels = ((clear + LABEL_CLEARANCE) / GRID).ceil() * GRID;
            (e.x, e.y) = (p.x - JUMP_SIZE / 2.0, (p.y + 2.0 * GRID).max(below_labels));
        }
        (e.w, e.h) = (JUMP_SIZE, JUMP_SIZE);
        placed[i] = true;
    }
    // Action blocks, right of their step, one under the other.
    let mut next_y: std::collections::HashMap<usize, f64> = std::collections::HashMap::new();
    for i in 0..n {
        if placed[i] || doc.elements[i].kind != Some(ElementKind::ActionBlock) {
            continue;
        }
        let step = doc.elements[i].step.as_ref().and_then(|s| d.by_id.get(s)).copied();
        let (w, h) = drawing::action_block_size(&doc.elements[i].associations);
        let (x, y) = match step {
            Some(s) => {
                let st = &doc.elements[s];
                let y = *next_y.entry(s).or_insert(st.y + st.h / 2.0 - ROW_H / 2.0);
                (st.x + st.w + 3.0 * GRID, y)
            }
            None => (doc.elements[i].x, doc.elements[i].y),
        };
        if let Some(s) = step {
            next_y.insert(s, y + h + GRID);
        }
        let e = &mut doc.elements[i];
        (e.x, e.y, e.w, e.h) = (x, y, w, h);
    }
    route_all(doc, d);
}

/// Routes every connection read around the blocks and labels (`route.rs`): straight where the
/// pins are aligned and nothing is in the way.
pub fn route_all(doc: &mut EditorDoc, d: &Derived) {
    route_where(doc, d, |_| true);
}

/// Routes the connections that have no waypoints (a layout stored without the automatic routes).
pub fn route_empty(doc: &mut EditorDoc, d: &Derived) {
    route_where(doc, d, |c| c.waypoints.is_empty());
}

/// Routes the connections `which` selects.
pub fn route_matching(doc: &mut EditorDoc, d: &Derived, which: impl Fn(&crate::Connection) -> bool) {
    route_where(doc, d, which);
}

fn obstacles(doc: &EditorDoc) -> Vec<Rect> {
    let mut obstacles: Vec<Rect> = doc.elements.iter().filter(|e| e.kind.is_some()).map(Rect::of).collect();
    obstacles.extend(drawing::labels(doc).into_iter().map(|l| l.rect));
    obstacles
}

/// The automatic route of connection `c` (empty for a straight wire), with its two pins.
fn automatic(doc: &EditorDoc, d: &Derived, obstacles: &[Rect], c: usize) -> Option<(Vec<Point>, Point, Point)> {
    if !d.used.get(c).copied().unwrap_or(false) {
        return None;
    }
    let con = doc.connections.get(c)?;
    let (Some(&s), Some(&t)) = (d.by_id.get(&con.source), d.by_id.get(&con.target)) else { return None };
    let from = pin_pos(doc.elements.get(s)?, false, con.source_pin);
    let to = pin_pos(doc.elements.get(t)?, true, con.target_pin);
    let straight =
        (from.x - to.x).abs() < 0.5 && to.y > from.y && !obstacles.iter().any(|r| crate::route::crosses(from, to, r));
    let route = if straight { Vec::new() } else { crate::route::route(from, to, obstacles, None) };
    Some((route, from, to))
}

fn route_where(doc: &mut EditorDoc, d: &Derived, which: impl Fn(&crate::Connection) -> bool) {
    let obstacles = obstacles(doc);
    for c in 0..doc.connections.len() {
        if !which(&doc.connections[c]) {
            continue;
        }
        if let Some((route, _, _)) = automatic(doc, d, &obstacles, c) {
            doc.connections[c].waypoints = route;
        }
    }
}

/// For each connection, its waypoints as `open` gives them when they differ: none for a
/// straight wire kept as its two pins, the automatic route for a wire without waypoints.
pub fn canonical_routes(doc: &EditorDoc, d: &Derived) -> Vec<Option<Vec<Point>>> {
    let obstacles = obstacles(doc);
    (0..doc.connections.len())
        .map(|c| {
            let w = &doc.connections[c].waypoints;
            let (route, from, to) = automatic(doc, d, &obstacles, c)?;
            if route.is_empty() && w.len() == 2 && w[0] == from && w[1] == to {
                Some(Vec::new())
            } else if w.is_empty() && !route.is_empty() {
                Some(route)
            } else {
                None
            }
        })
        .collect()
}

/// For each connection, whether it runs on its automatic route (the one [`route_all`] gives,
/// or for a straight wire its two pins, as the canvas keeps it): saved without waypoints, it
/// is routed the same way when opened.
pub fn on_automatic_route(doc: &EditorDoc, d: &Derived) -> Vec<bool> {
    let obstacles = obstacles(doc);
    (0..doc.connections.len())
        .map(|c| {
            let w = &doc.connections[c].waypoints;
            match automatic(doc, d, &obstacles, c) {
                Some((route, from, to)) => {
                    *w == route || (route.is_empty() && w.len() == 2 && w[0] == from && w[1] == to)
                }
                None => false,
            }
        })
        .collect()
}
