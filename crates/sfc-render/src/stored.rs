//! Charts with stored coordinates (from PLCopen XML or the editor): every step and transition
//! carries `{attribute 'sfc.x' := '120'}` and `sfc.y` (pixels, top-left corner of the element),
//! optionally `sfc.w`/`sfc.h` (or the long names `sfc.width`/`sfc.height`). The elements are
//! drawn where they are; only the links are routed, orthogonally:
//!
//! * a link leaves its element downwards and turns once to reach the element below it;
//! * the links of a divergence turn on one line just below the diverging element (single for a
//!   step, double for a transition), those of a convergence on one line just above the
//!   converging element, so the IEC branch lines appear wherever the elements are;
//! * a link to an element that is not below its start goes round on a lane right of both
//!   elements, with an arrow on its upward run.
//!
//! Drawings with negative coordinates are moved right/down just enough to be visible.

use crate::place::transition_geom;
use crate::text::{dim::*, line_height, Sizes};
use crate::{BoxGeom, BranchBar, BranchKind, Layout, LayoutKind, Point, Rect, TransitionGeom, Wire};
use sfc_model::Chart;
use sfc_syntax::ast::Attribute;

/// A stored element box: top-left corner and an optional size.
#[derive(Debug, Clone, Copy)]
pub struct Stored {
    x: f64,
    y: f64,
    w: Option<f64>,
    h: Option<f64>,
}

pub struct Positions {
    steps: Vec<Stored>,
    transitions: Vec<Stored>,
}

fn number(attrs: &[Attribute], names: &[&str]) -> Option<f64> {
    let a = attrs.iter().rev().find(|a| names.iter().any(|n| a.name.eq_ignore_ascii_case(n)))?;
    let v: f64 = a.value.as_deref()?.trim().parse().ok()?;
    // Beyond a million pixels a coordinate is not a drawing position.
    (v.is_finite() && v.abs() <= 1.0e6).then_some(v)
}

fn stored(attrs: &[Attribute]) -> Option<Stored> {
    let size = |names: &[&str]| number(attrs, names).filter(|v| *v >= 1.0);
    Some(Stored {
        x: number(attrs, &["sfc.x"])?,
        y: number(attrs, &["sfc.y"])?,
        w: size(&["sfc.w", "sfc.width"]),
        h: size(&["sfc.h", "sfc.height"]),
    })
}

/// The stored positions, when every step and transition has both coordinates.
pub fn positions(chart: &Chart) -> Option<Positions> {
    if chart.steps.is_empty() {
        return None;
    }
    let steps: Option<Vec<Stored>> = chart.steps.iter().map(|s| stored(&s.attributes)).collect();
    let transitions: Option<Vec<Stored>> = chart.transitions.iter().map(|t| stored(&t.attributes)).collect();
    Some(Positions { steps: steps?, transitions: transitions? })
}

pub fn layout(chart: &Chart, sizes: &Sizes, pos: &Positions) -> Layout {
    let lh = line_height(sizes.font_size);
    let ns = chart.steps.len();
    let mut steps: Vec<BoxGeom> = Vec::with_capacity(ns);
    let mut actions = Vec::new();
    for (s, (step, p)) in chart.steps.iter().zip(&pos.steps).enumerate() {
        let size = &sizes.steps[s];
        let (w, h) = (p.w.unwrap_or(size.w).min(1.0e4), p.h.unwrap_or(size.h).min(1.0e4));
        let rect = Rect::new(p.x, p.y, w, h);
        if let Some(a) = &size.actions {
            let cy = (p.y + h / 2.0).round();
            let block = Rect::new(rect.right() + ACTION_GAP, cy - (a.row_h / 2.0).round(), a.w(), a.h());
            actions.push(a.geom(s, block, rect, cy));
        }
        steps.push(BoxGeom { step: s, name: step.name.clone(), initial: step.initial, rect });
    }
    let mut transitions: Vec<TransitionGeom> = Vec::with_capacity(chart.transitions.len());
    for (t, p) in pos.transitions.iter().enumerate() {
        let w = p.w.unwrap_or(2.0 * BAR_HALF).min(1.0e4);
        let h = p.h.unwrap_or(BAR_THICKNESS).min(1.0e4);
        let mut g = transition_geom(t, &sizes.transitions[t], p.x + w / 2.0, p.y + h / 2.0, lh);
        g.half_width = w / 2.0;
        if let Some(r) = g.condition_rect.as_mut() {
            r.x = p.x + w + LABEL_GAP;
        }
        if let Some(r) = g.name_rect.as_mut() {
            r.x = p.x - LABEL_GAP - r.w;
        }
        transitions.push(g);
    }

    let mut r = Router { wires: Vec::new(), bars: Vec::new(), lanes: 0, lane_base: 0.0 };
    r.lane_base = steps
        .iter()
        .map(|s| s.rect.right())
        .chain(transitions.iter().map(|t| t.x + t.half_width))
        .chain(actions.iter().map(|a| a.rect.right()))
        .fold(f64::NEG_INFINITY, f64::max);
    // Steps to transitions.
    for (s, step) in steps.iter().enumerate() {
        let outs: Vec<usize> =
            (0..chart.transitions.len()).filter(|&t| chart.transitions[t].from.contains(&s)).collect();
        let ends: Vec<(Point, f64)> = outs
            .iter()
            .map(|&t| (transitions[t].in_port(), conv_line(&transitions[t], chart.transitions[t].from.len())))
            .collect();
        let clear = actions.iter().filter(|a| a.step == s).map(|a| a.rect.bottom()).fold(step.rect.bottom(), f64::max);
        r.diverge(step.bottom(), clear, &ends, BranchKind::SelectionDivergence, step.rect.right());
    }
    // Transitions to steps.
    for (t, tr) in transitions.iter().enumerate() {
        let ends: Vec<(Point, f64)> = chart.transitions[t]
            .to
            .iter()
            .filter_map(|&d| steps.get(d))
            .map(|s| {
                let incoming = chart.transitions.iter().filter(|x| x.to.contains(&s.step)).count();
                (s.top(), if incoming > 1 { s.rect.y - STUB } else { f64::NAN })
            })
            .collect();
        let clear = tr.condition_rect.iter().chain(&tr.name_rect).map(|r| r.bottom()).fold(tr.out_port().y, f64::max);
        r.diverge(tr.out_port(), clear, &ends, BranchKind::SimultaneousDivergence, tr.x + tr.half_width);
    }
    // Convergence lines: one per step with several incoming and per transition with several
    // predecessors, spanning the links that come down to it.
    for s in &steps {
        let xs: Vec<f64> = r.arrivals(s.top(), s.rect.y - STUB);
        if xs.len() > 1 {
            let (x1, x2) = span(xs.iter().copied().chain([s.top().x]));
            r.bars.push(BranchBar {
                kind: BranchKind::SelectionConvergence,
                x1,
                x2,
                y: s.rect.y - STUB,
                y2: s.rect.y - STUB,
            });
        }
    }
    for (t, tr) in transitions.iter().enumerate() {
        if chart.transitions[t].from.len() > 1 {
            let y = conv_line(tr, 2);
            let xs = r.arrivals(tr.in_port(), y);
            if !xs.is_empty() {
                let (x1, x2) = span(xs.iter().copied().chain([tr.x]));
                r.bars.push(BranchBar { kind: BranchKind::SimultaneousConvergence, x1, x2, y, y2: y + DOUBLE_GAP });
            }
        }
    }

    let mut layout = Layout {
        kind: LayoutKind::Stored,
        width: 0.0,
        height: 0.0,
        font_size: sizes.font_size,
        steps,
        transitions,
        actions,
        wires: r.wires,
        branches: r.bars,
        jumps: Vec::new(),
    };
    fit(&mut layout);
    layout
}

/// The y of the convergence line above a transition with `from` predecessors (NaN: none).
fn conv_line(t: &TransitionGeom, from: usize) -> f64 {
    if from > 1 {
        (t.in_port().y - STUB - DOUBLE_GAP).round()
    } else {
        f64::NAN
    }
}

struct Router {
    wires: Vec<Wire>,
    bars: Vec<BranchBar>,
    lanes: usize,
    lane_base: f64,
}

impl Router {
    /// Links from `start` to each end (its port and the y of a convergence line above it, NaN
    /// if none). Two or more links going down share a divergence line just below `start`;
    /// horizontal runs stay below `clear` (the texts and action block of the element).
    fn diverge(&mut self, start: Point, clear: f64, ends: &[(Point, f64)], kind: BranchKind, right: f64) {
        let line = (start.y + STUB).max((clear + STUB / 2.0).round());
        let below: Vec<&(Point, f64)> = ends.iter().filter(|(p, _)| p.y >= line + STUB).collect();
        let double = kind.is_double();
        let gap = if double { DOUBLE_GAP } else { 0.0 };
        if below.len() > 1 {
            let (x1, x2) = span(below.iter().map(|(p, _)| p.x).chain([start.x]));
            self.bars.push(BranchBar { kind, x1, x2, y: line, y2: line + gap });
            self.wires.push(Wire { points: vec![start, Point::new(start.x, line)], upward_arrow: false });
        }
        for &(end, conv) in ends {
            if end.y >= line + STUB {
                let from = if below.len() > 1 { Point::new(end.x, line + gap) } else { start };
                // Turn on the convergence line above the end when there is one, else halfway.
                let turn = if conv.is_finite() && conv > from.y {
                    conv
                } else if below.len() > 1 {
                    from.y
                } else {
                    ((from.y + end.y) / 2.0).round()
                };
                let mut points = vec![from];
                if (from.x - end.x).abs() >= 0.01 {
                    points.push(Point::new(from.x, turn));
                    points.push(Point::new(end.x, turn));
                }
                points.push(end);
                dedup(&mut points);
                self.wires.push(Wire { points, upward_arrow: false });
            } else {
                let lane = (self.lane_base.max(right) + COLUMN_GAP + 8.0 * self.lanes as f64).round();
                self.lanes += 1;
                let y1 = line;
                let y2 = end.y - STUB / 2.0;
                let points = vec![
                    start,
                    Point::new(start.x, y1),
                    Point::new(lane, y1),
                    Point::new(lane, y2),
                    Point::new(end.x, y2),
                    end,
                ];
                self.wires.push(Wire { points, upward_arrow: true });
            }
        }
    }

    /// x of the links that arrive at `port` through the line at `y`.
    fn arrivals(&self, port: Point, y: f64) -> Vec<f64> {
        if !y.is_finite() {
            return Vec::new();
        }
        self.wires
            .iter()
            .filter(|w| w.points.last().is_some_and(|p| p == &port) && w.points.len() >= 3)
            .filter_map(|w| {
                let n = w.points.len();
                let turn = w.points[n - 2];
                ((turn.y - y).abs() < 0.01).then(|| w.points[n - 3].x)
            })
            .collect()
    }
}

fn dedup(points: &mut Vec<Point>) {
    points.dedup_by(|a, b| (a.x - b.x).abs() < 0.01 && (a.y - b.y).abs() < 0.01);
}

fn span(xs: impl Iterator<Item = f64>) -> (f64, f64) {
    xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)))
}

/// Sets the size of the drawing, moving everything right/down if something lies left of or
/// above the margin.
fn fit(l: &mut Layout) {
    let mut rects: Vec<Rect> = l.steps.iter().map(|s| s.rect).collect();
    rects.extend(l.actions.iter().map(|a| a.rect));
    for t in &l.transitions {
        rects.push(t.bar_rect());
        rects.extend(t.condition_rect);
        rects.extend(t.name_rect);
    }
    for w in &l.wires {
        rects.extend(w.points.iter().map(|p| Rect::new(p.x, p.y, 0.0, 0.0)));
    }
    for b in &l.branches {
        rects.push(Rect::new(b.x1, b.y, b.x2 - b.x1, b.y2 - b.y));
    }
    let min_x = rects.iter().map(|r| r.x).fold(f64::INFINITY, f64::min);
    let min_y = rects.iter().map(|r| r.y).fold(f64::INFINITY, f64::min);
    let dx = if min_x < MARGIN { (MARGIN - min_x).ceil() } else { 0.0 };
    let dy = if min_y < MARGIN { (MARGIN - min_y).ceil() } else { 0.0 };
    if dx != 0.0 || dy != 0.0 {
        let mv = |p: &mut Point| {
            p.x += dx;
            p.y += dy;
        };
        let mvr = |r: &mut Rect| {
            r.x += dx;
            r.y += dy;
        };
        for s in l.steps.iter_mut() {
            mvr(&mut s.rect);
        }
        for a in l.actions.iter_mut() {
            mvr(&mut a.rect);
            mv(&mut a.link.0);
            mv(&mut a.link.1);
        }
        for t in l.transitions.iter_mut() {
            t.x += dx;
            t.y += dy;
            if let Some(r) = t.condition_rect.as_mut() {
                mvr(r);
            }
            if let Some(r) = t.name_rect.as_mut() {
                mvr(r);
            }
        }
        for w in l.wires.iter_mut() {
            w.points.iter_mut().for_each(mv);
        }
        for b in l.branches.iter_mut() {
            b.x1 += dx;
            b.x2 += dx;
            b.y += dy;
            b.y2 += dy;
        }
    }
    let max_x = rects.iter().map(|r| r.right()).fold(0.0, f64::max) + dx;
    let max_y = rects.iter().map(|r| r.bottom()).fold(0.0, f64::max) + dy;
    l.width = (max_x + MARGIN).ceil();
    l.height = (max_y + MARGIN).ceil();
}
