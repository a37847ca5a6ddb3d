//! Geometry of the structured layout: the recovered block tree drawn as nested columns.
//!
//! Every element has an *extent* measured bottom-up: its outline as horizontal bands (how far
//! it reaches left and right of the axis it is entered on, at each height), how tall it is, and
//! where its axis leaves it (`out_dx`, non-zero only when the first branches of a selection end
//! with jumps and the flow goes on below a branch further right). A divergence puts its first
//! branch on the incoming axis and each further branch as far left as the outlines of the
//! branches before it allow, one column gap away at every height (a contour packing, as in tidy
//! tree drawing): a short branch that ends with a jump sits next to the top of a wide
//! neighbour instead of right of its widest part. Branches that reach the convergence keep
//! their line down to it in their outline, so no line crosses another and texts and action
//! blocks never overlap.

use crate::structure::{Branch, Elem, Tree};
use crate::text::{dim::*, jump_right, line_height, Sizes};
use crate::{
    ActionBlockGeom, BoxGeom, BranchBar, BranchKind, JumpGeom, Layout, LayoutKind, Point, Rect, TransitionGeom, Wire,
};
use sfc_model::Chart;

/// A horizontal band of an outline: between `y0` and `y1` the element covers `lo..hi`.
#[derive(Debug, Clone, Copy)]
struct Band {
    y0: f64,
    y1: f64,
    lo: f64,
    hi: f64,
}

impl Band {
    fn shifted(self, dx: f64, dy: f64) -> Band {
        Band { y0: self.y0 + dy, y1: self.y1 + dy, lo: self.lo + dx, hi: self.hi + dx }
    }
    /// A vertical line at `x` from `y0` to `y1`.
    fn line(x: f64, y0: f64, y1: f64) -> Band {
        Band { y0, y1, lo: x - 0.5, hi: x + 0.5 }
    }
}

/// Vertical clearance between bands of neighbouring branches.
const CLEARANCE: f64 = 6.0;
/// Outlines with more bands are coarsened (conservatively) to keep packing fast on big charts.
const MAX_BANDS: usize = 256;

/// Extent of an element or sequence relative to its entry axis and top.
#[derive(Debug, Clone)]
struct Ext {
    bands: Vec<Band>,
    h: f64,
    out_dx: f64,
}

impl Ext {
    fn min_x(&self) -> f64 {
        self.bands.iter().map(|b| b.lo).fold(0.0, f64::min)
    }
    fn max_x(&self) -> f64 {
        self.bands.iter().map(|b| b.hi).fold(0.0, f64::max)
    }
}

/// Merges neighbouring bands until at most [`MAX_BANDS`] are left; the merged band covers
/// both, so packing against it stays safe.
fn coarsen(mut bands: Vec<Band>) -> Vec<Band> {
    if bands.len() <= MAX_BANDS {
        return bands;
    }
    bands.sort_by(|a, b| a.y0.total_cmp(&b.y0));
    let per = bands.len().div_ceil(MAX_BANDS);
    bands
        .chunks(per)
        .map(|c| Band {
            y0: c.iter().map(|b| b.y0).fold(f64::INFINITY, f64::min),
            y1: c.iter().map(|b| b.y1).fold(f64::NEG_INFINITY, f64::max),
            lo: c.iter().map(|b| b.lo).fold(f64::INFINITY, f64::min),
            hi: c.iter().map(|b| b.hi).fold(f64::NEG_INFINITY, f64::max),
        })
        .collect()
}

pub fn layout(chart: &Chart, sizes: &Sizes, tree: &Tree) -> Option<Layout> {
    let mut p = Placer {
        chart,
        sizes,
        steps: vec![None; chart.steps.len()],
        transitions: vec![None; chart.transitions.len()],
        actions: Vec::new(),
        wires: Vec::new(),
        branches: Vec::new(),
        jumps: Vec::new(),
    };
    let mut cursor = MARGIN;
    let mut height: f64 = 0.0;
    for root in &tree.roots {
        let ext = p.ext_seq(root);
        let x = cursor - ext.min_x();
        p.place_seq(root, x, MARGIN, None);
        cursor += ext.max_x() - ext.min_x() + NETWORK_GAP;
        height = height.max(ext.h);
    }
    let width = if tree.roots.is_empty() { 2.0 * MARGIN } else { cursor - NETWORK_GAP + MARGIN };
    let steps: Option<Vec<BoxGeom>> = p.steps.into_iter().collect();
    let transitions: Option<Vec<TransitionGeom>> = p.transitions.into_iter().collect();
    let mut actions = p.actions;
    actions.sort_by_key(|a| a.step);
    Some(Layout {
        kind: LayoutKind::Structured,
        width: width.ceil(),
        height: (height + 2.0 * MARGIN).ceil(),
        font_size: sizes.font_size,
        steps: steps?,
        transitions: transitions?,
        actions,
        wires: p.wires,
        branches: p.branches,
        jumps: p.jumps,
    })
}

struct Placer<'a> {
    chart: &'a Chart,
    sizes: &'a Sizes,
    steps: Vec<Option<BoxGeom>>,
    transitions: Vec<Option<TransitionGeom>>,
    actions: Vec<ActionBlockGeom>,
    wires: Vec<Wire>,
    branches: Vec<BranchBar>,
    jumps: Vec<JumpGeom>,
}

/// A vertical link (or, should the two ends ever be apart, an orthogonal one).
pub fn link(from: Point, to: Point) -> Wire {
    if (from.x - to.x).abs() < 0.01 {
        Wire { points: vec![from, to], upward_arrow: false }
    } else {
        let mid = ((from.y + to.y) / 2.0).round();
        Wire { points: vec![from, Point::new(from.x, mid), Point::new(to.x, mid), to], upward_arrow: to.y < from.y }
    }
}

impl Placer<'_> {
    fn ext_seq(&self, seq: &[Elem]) -> Ext {
        let (mut dx, mut y) = (0.0f64, 0.0f64);
        let mut bands = Vec::new();
        for (i, e) in seq.iter().enumerate() {
            if i > 0 {
                bands.push(Band::line(dx, y, y + LINK));
                y += LINK;
            }
            let x = self.ext_elem(e);
            bands.extend(x.bands.iter().map(|b| b.shifted(dx, y)));
            y += x.h;
            dx += x.out_dx;
        }
        Ext { bands: coarsen(bands), h: y, out_dx: dx }
    }

    /// Column offsets of the branches (entry axes relative to the first), their extents, and
    /// the height of the tallest: each branch as far left as the outlines of those before it
    /// allow. The outline of a branch that reaches the convergence includes its line down to it.
    fn columns(&self, branches: &[Branch], merges: bool) -> (Vec<f64>, Vec<Ext>, f64) {
        let exts: Vec<Ext> = branches.iter().map(|b| self.ext_seq(&b.seq)).collect();
        let body = exts.iter().map(|e| e.h).fold(0.0, f64::max);
        let mut offsets: Vec<f64> = Vec::with_capacity(exts.len());
        let mut placed: Vec<Band> = Vec::new();
        for (b, e) in branches.iter().zip(&exts) {
            let mut outline = e.bands.clone();
            if merges && b.reaches {
                outline.push(Band::line(e.out_dx, e.h, body + STUB));
            }
            let mut o = match offsets.last() {
                Some(prev) => prev + 1.0,
                None => 0.0,
            };
            if !offsets.is_empty() {
                for nb in &outline {
                    for pb in &placed {
                        if nb.y0 < pb.y1 + CLEARANCE && pb.y0 < nb.y1 + CLEARANCE {
                            o = o.max(pb.hi + COLUMN_GAP - nb.lo);
                        }
                    }
                }
            }
            let o = o.ceil();
            offsets.push(o);
            placed.extend(outline.iter().map(|b| b.shifted(o, 0.0)));
            placed = coarsen(placed);
        }
        (offsets, exts, body)
    }

    fn ext_elem(&self, e: &Elem) -> Ext {
        match e {
            Elem::Step(s) => {
                let size = &self.sizes.steps[*s];
                let h = size.height();
                Ext { bands: vec![Band { y0: 0.0, y1: h, lo: -size.left(), hi: size.right() }], h, out_dx: 0.0 }
            }
            Elem::Transition(t) => {
                let size = &self.sizes.transitions[*t];
                let h = size.row_h;
                Ext { bands: vec![Band { y0: 0.0, y1: h, lo: -size.left(), hi: size.right() }], h, out_dx: 0.0 }
            }
            Elem::Jump { target, .. } => {
                let (_, w) = self.sizes.jump_label(self.chart, *target);
                let h = JUMP_H + 4.0;
                Ext { bands: vec![Band { y0: 0.0, y1: h, lo: -ARROW_HALF, hi: jump_right(w) }], h, out_dx: 0.0 }
            }
            Elem::Selection { branches, merges } | Elem::Simultaneous { branches, merges } => {
                let double = matches!(e, Elem::Simultaneous { .. });
                let gap = if double { DOUBLE_GAP } else { 0.0 };
                let overhang = if double { DOUBLE_OVERHANG } else { 0.0 };
                let (offsets, exts, body) = self.columns(branches, *merges);
                let top = gap + STUB;
                let conv_y = top + body + STUB;
                let last = offsets.last().copied().unwrap_or(0.0);
                let mut bands = vec![Band { y0: 0.0, y1: gap, lo: -overhang, hi: last + overhang }];
                let mut reached = Vec::new();
                for ((b, o), x) in branches.iter().zip(&offsets).zip(&exts) {
                    bands.push(Band::line(*o, gap, top));
                    bands.extend(x.bands.iter().map(|band| band.shifted(*o, top)));
                    if *merges && b.reaches {
                        let out = o + x.out_dx;
                        bands.push(Band::line(out, top + x.h, conv_y));
                        reached.push(out);
                    }
                }
                let out_dx = reached.iter().copied().fold(f64::INFINITY, f64::min);
                if *merges && !reached.is_empty() {
                    let hi = reached.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    bands.push(Band { y0: conv_y, y1: conv_y + gap, lo: out_dx - overhang, hi: hi + overhang });
                }
                let h = if *merges { conv_y + gap } else { top + body };
                Ext { bands: coarsen(bands), h, out_dx: if *merges && out_dx.is_finite() { out_dx } else { 0.0 } }
            }
        }
    }

    /// Places a sequence with its entry axis at `x` and its top at `y`; `incoming` is where the
    /// link from above starts. Returns where the link below the sequence starts, if it goes on.
    fn place_seq(&mut self, seq: &[Elem], x0: f64, y0: f64, mut incoming: Option<Point>) -> Option<Point> {
        let (mut x, mut y) = (x0, y0);
        for (i, e) in seq.iter().enumerate() {
            if i > 0 {
                y += LINK;
            }
            let ext = self.ext_elem(e);
            incoming = self.place_elem(e, x, y, incoming);
            y += ext.h;
            x += ext.out_dx;
        }
        incoming
    }

    fn place_elem(&mut self, e: &Elem, x: f64, y: f64, incoming: Option<Point>) -> Option<Point> {
        let fs = self.sizes.font_size;
        let lh = line_height(fs);
        match e {
            Elem::Step(s) => {
                let size = &self.sizes.steps[*s];
                let rect = Rect::new(x - size.w / 2.0, y, size.w, size.h);
                let step = &self.chart.steps[*s];
                let geom = BoxGeom { step: *s, name: step.name.clone(), initial: step.initial, rect };
                if let Some(from) = incoming {
                    self.wires.push(link(from, geom.top()));
                }
                if let Some(a) = &size.actions {
                    let block = Rect::new(rect.right() + ACTION_GAP, y + size.action_dy(), a.w(), a.h());
                    let cy = y + (size.h / 2.0).round();
                    self.actions.push(a.geom(*s, block, rect, cy));
                }
                let out = geom.bottom();
                self.steps[*s] = Some(geom);
                Some(out)
            }
            Elem::Transition(t) => {
                let size = &self.sizes.transitions[*t];
                let bar_y = y + (size.row_h / 2.0).round();
                let geom = transition_geom(*t, size, x, bar_y, lh);
                if let Some(from) = incoming {
                    self.wires.push(link(from, geom.in_port()));
                }
                let out = geom.out_port();
                self.transitions[*t] = Some(geom);
                Some(out)
            }
            Elem::Jump { transition, target } => {
                let (label, w) = self.sizes.jump_label(self.chart, *target);
                let from = incoming.unwrap_or(Point::new(x, y));
                let tip = Point::new(x, y + JUMP_H);
                let label_rect = Rect::new(x + ARROW_HALF + 4.0, tip.y - ARROW_LEN / 2.0 - lh / 2.0, w, lh);
                self.jumps.push(JumpGeom { transition: *transition, target: *target, from, tip, label, label_rect });
                None
            }
            Elem::Selection { branches, merges } | Elem::Simultaneous { branches, merges } => {
                let double = matches!(e, Elem::Simultaneous { .. });
                let gap = if double { DOUBLE_GAP } else { 0.0 };
                let overhang = if double { DOUBLE_OVERHANG } else { 0.0 };
                let (offsets, _, body) = self.columns(branches, *merges);
                if let Some(from) = incoming {
                    self.wires.push(link(from, Point::new(x, y)));
                }
                let last = offsets.last().copied().unwrap_or(0.0);
                self.branches.push(BranchBar {
                    kind: if double { BranchKind::SimultaneousDivergence } else { BranchKind::SelectionDivergence },
                    x1: x - overhang,
                    x2: x + last + overhang,
                    y,
                    y2: y + gap,
                });
                let top = y + gap + STUB;
                let conv_y = top + body + STUB;
                let mut reached = Vec::new();
                for (b, o) in branches.iter().zip(&offsets) {
                    let bx = x + o;
                    let out = self.place_seq(&b.seq, bx, top, Some(Point::new(bx, y + gap)));
                    if let (true, Some(p)) = (b.reaches && *merges, out) {
                        self.wires.push(link(p, Point::new(p.x, conv_y)));
                        reached.push(p.x);
                    }
                }
                if !*merges || reached.is_empty() {
                    return None;
                }
                let lo = reached.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = reached.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                if reached.len() > 1 {
                    self.branches.push(BranchBar {
                        kind: if double {
                            BranchKind::SimultaneousConvergence
                        } else {
                            BranchKind::SelectionConvergence
                        },
                        x1: lo - overhang,
                        x2: hi + overhang,
                        y: conv_y,
                        y2: conv_y + gap,
                    });
                }
                Some(Point::new(lo, conv_y + gap))
            }
        }
    }
}

/// The geometry of transition `t` with its axis at `x` and its bar at `bar_y`.
pub fn transition_geom(t: usize, size: &crate::text::TransitionSize, x: f64, bar_y: f64, lh: f64) -> TransitionGeom {
    let text_h = lh * size.condition.len() as f64;
    let condition_rect = (!size.condition.is_empty())
        .then(|| Rect::new(x + BAR_HALF + LABEL_GAP, (bar_y - text_h / 2.0).round(), size.condition_w, text_h));
    let name_rect = size
        .name
        .as_ref()
        .map(|_| Rect::new(x - BAR_HALF - LABEL_GAP - size.name_w, (bar_y - lh / 2.0).round(), size.name_w, lh));
    TransitionGeom {
        transition: t,
        x,
        y: bar_y,
        half_width: BAR_HALF,
        thickness: BAR_THICKNESS,
        condition: size.condition.clone(),
        condition_rect,
        name: size.name.clone(),
        name_rect,
    }
}
