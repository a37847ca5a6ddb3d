//! The structured layout in the editor's own units: the block structure `sfc-render` recovers
//! from the net (sequences, selections, simultaneous branches, jumps) drawn the IEC way, as
//! CODESYS and Beremiz draw it:
//!
//! * every wire is straight: a step, its transition and the next step share one vertical axis;
//! * a divergence bar is centred under the step (or transition) above it, so the incoming wire
//!   comes straight down onto its single pin, and its branches hang from equidistant pins (the
//!   canvas spaces branch pins evenly), one branch axis per pin;
//! * a convergence bar spans the branches that reach it, its pins on their axes, and the flow
//!   goes on straight down from its middle;
//! * branches are spaced by their outlines (each block with its labels and action blocks, and
//!   the lines down to the convergence), so no wire runs through a block or a label and no two
//!   labels or action blocks overlap; a transition whose wrapped condition reaches further
//!   above and below its bar than the gaps there leave room for is drawn lower, with as much
//!   room below it; loops are jumps (arrows naming the target step), as in
//!   CODESYS, so nothing is routed back up;
//! * everything sits on the grid of 10.
//!
//! [`place`] returns `false` when the document's bars and wires do not match the recovered
//! structure in the expected way (a hand-drawn mixed structure, say); the caller then falls
//! back to placing blocks on `sfc-render`'s coordinates and routing around obstacles.

use crate::drawing::{self, action_block_size, labels_of, step_size, ROW_H};
use crate::graph::{pin_counts, Derived};
use crate::layout::{across, pin_pos, BAR_H, BAR_PAD, GRID, JUMP_SIZE, TRANSITION_H, TRANSITION_W};
use crate::{EditorDoc, Element, ElementKind};
use sfc_render::structure::{Branch, Elem, Tree};
use std::collections::HashMap;

/// Vertical gap between consecutive elements of a sequence.
const LINK: f64 = 30.0;
/// Vertical gap between a bar and the first or last block of a branch.
const STUB: f64 = 20.0;
/// Horizontal clearance between the outlines of neighbouring branches.
const COLUMN_GAP: f64 = 30.0;
/// Vertical clearance under which two bands count as level.
const CLEARANCE: f64 = 10.0;
/// Gap between a step and its action blocks, and between stacked action blocks.
const ACTION_GAP: f64 = 30.0;
/// Horizontal gap between separate networks (several initial steps).
const NETWORK_GAP: f64 = 60.0;
/// Top-left margin of the drawing.
const MARGIN: f64 = 40.0;
/// How far a condition label may reach above or below its transition into the gap before the
/// block there (the shortest gap is a branch's [`STUB`]) and stay clear of it.
const LABEL_REACH: f64 = STUB - 6.0;
/// Outlines with more bands are merged (conservatively) to keep spacing fast on big charts.
const MAX_BANDS: usize = 256;

/// Between `y0` and `y1` an element covers `lo..hi` (relative to its entry axis and top).
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
    fn line(x: f64, y0: f64, y1: f64) -> Band {
        Band { y0, y1, lo: x - 1.0, hi: x + 1.0 }
    }
    fn rect(r: drawing::Rect) -> Band {
        Band { y0: r.y, y1: r.bottom(), lo: r.x, hi: r.right() }
    }
}

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

/// The outline of an element or sequence, its height, and where the flow leaves it relative to
/// where it entered.
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

/// The columns of a divergence: branch axes relative to the incoming axis, one per pin.
struct Columns {
    /// Distance between neighbouring branch axes (a multiple of 20).
    spacing: f64,
    /// Per branch, in pin order: index into the construct's branches.
    order: Vec<usize>,
    exts: Vec<Ext>,
    body: f64,
}

struct Placer<'a> {
    doc: &'a mut EditorDoc,
    d: &'a Derived,
    step_block: &'a [usize],
    trans_block: &'a [usize],
    /// Action blocks of each step block, in document order.
    actions: HashMap<usize, Vec<usize>>,
    cache: HashMap<usize, Ext>,
}

/// Why the structured layout gives up (the caller falls back).
struct Mismatch;

type Fit<T> = Result<T, Mismatch>;

/// Places every block of `doc` on `tree` (see the module doc); `step_block` and `trans_block`
/// give the block of each step and transition of the chart. Returns `false`, leaving `doc` as
/// it was, when the document's bars do not match the structure.
pub fn place(doc: &mut EditorDoc, d: &Derived, tree: &Tree, step_block: &[usize], trans_block: &[usize]) -> bool {
    let before = doc.clone();
    let mut actions: HashMap<usize, Vec<usize>> = HashMap::new();
    for (i, e) in doc.elements.iter().enumerate() {
        if e.kind == Some(ElementKind::ActionBlock) {
            if let Some(s) = e.step.as_ref().and_then(|s| d.by_id.get(s)) {
                actions.entry(*s).or_default().push(i);
            }
        }
    }
    // Sizes first: outlines depend on them.
    for e in doc.elements.iter_mut() {
        match e.kind {
            Some(ElementKind::Step) => (e.w, e.h) = step_size(e),
            Some(ElementKind::Transition) => (e.w, e.h) = (TRANSITION_W, TRANSITION_H),
            Some(ElementKind::Jump) => (e.w, e.h) = (JUMP_SIZE, JUMP_SIZE),
            Some(ElementKind::ActionBlock) => (e.w, e.h) = action_block_size(&e.associations),
            _ => {}
        }
    }
    let mut p = Placer { doc, d, step_block, trans_block, actions, cache: HashMap::new() };
    let ok = p.place_roots(tree).is_ok();
    if !ok {
        *p.doc = before;
        return false;
    }
    true
}

impl Placer<'_> {
    fn place_roots(&mut self, tree: &Tree) -> Fit<()> {
        let mut cursor = MARGIN;
        for root in &tree.roots {
            let ext = self.ext_seq(root)?;
            let axis = snap(cursor - ext.min_x());
            self.place_seq(root, axis, MARGIN)?;
            cursor = axis + ext.max_x() + NETWORK_GAP;
        }
        Ok(())
    }

    fn block(&self, e: &Elem) -> Option<usize> {
        match e {
            Elem::Step(s) => self.step_block.get(*s).copied(),
            Elem::Transition(t) => self.trans_block.get(*t).copied(),
            _ => None,
        }
    }

    fn kind(&self, i: usize) -> Option<ElementKind> {
        self.doc.elements[i].kind
    }

    /// The block on the other side of output (`input` false) or input pin `pin` of block `i`.
    fn across(&self, i: usize, input: bool, pin: usize) -> Option<(usize, u32)> {
        across(self.doc, self.d, i, input, pin)
    }

    // ---- outlines ------------------------------------------------------------------------

    fn ext_seq(&mut self, seq: &[Elem]) -> Fit<Ext> {
        let (mut dx, mut y) = (0.0f64, 0.0f64);
        let mut bands = Vec::new();
        for (i, e) in seq.iter().enumerate() {
            if i > 0 {
                bands.push(Band::line(dx, y, y + LINK));
                y += LINK;
            }
            let x = self.ext_elem(seq, i)?;
            bands.extend(x.bands.iter().map(|b| b.shifted(dx, y)));
            y += x.h;
            dx += x.out_dx;
            let _ = e;
        }
        Ok(Ext { bands: coarsen(bands), h: y, out_dx: dx })
    }

    /// The outline of a step with its action blocks, relative to its axis and top; its height
    /// covers the action blocks, so the next element comes below them.
    fn step_ext(&self, b: usize) -> Ext {
        let e = &self.doc.elements[b];
        let (w, h) = (e.w, e.h);
        let mut bands = vec![Band { y0: 0.0, y1: h, lo: -w / 2.0, hi: w / 2.0 }];
        let mut bottom = h;
        if let Some(list) = self.actions.get(&b) {
            let mut y = h / 2.0 - ROW_H / 2.0;
            for &a in list {
                let ab = &self.doc.elements[a];
                bands.push(Band { y0: y, y1: y + ab.h, lo: w / 2.0, hi: w / 2.0 + ACTION_GAP + ab.w });
                y += ab.h + GRID;
                bottom = bottom.max(y - GRID);
            }
        }
        Ext { bands, h: snap(bottom), out_dx: 0.0 }
    }

    /// The outline of a block drawn at axis 0, top 0, with its labels. A transition whose
    /// condition label reaches further than [`LABEL_REACH`] above and below its bar has room
    /// made for it: the block is drawn [`Self::label_pad`] lower and the outline is as much
    /// taller at each end.
    fn block_ext(&self, b: usize) -> Ext {
        let e = &self.doc.elements[b];
        let pad = self.label_pad(b);
        let probe = Element { x: -e.w / 2.0, y: pad, ..e.clone() };
        let mut bands = vec![Band { y0: pad, y1: pad + e.h, lo: -e.w / 2.0, hi: e.w / 2.0 }];
        bands.extend(labels_of(&probe, b).into_iter().map(|l| Band::rect(l.rect)));
        Ext { bands, h: e.h + 2.0 * pad, out_dx: 0.0 }
    }

    /// The room added above and below block `b` for its labels (a wrapped condition taller than
    /// the gaps around the bar leave room for), on the grid; 0 for most blocks.
    fn label_pad(&self, b: usize) -> f64 {
        let e = &self.doc.elements[b];
        if e.kind != Some(ElementKind::Transition) {
            return 0.0;
        }
        let probe = Element { y: 0.0, ..e.clone() };
        let reach = labels_of(&probe, b).iter().map(|l| (-l.rect.y).max(l.rect.bottom() - e.h)).fold(0.0, f64::max);
        if reach <= LABEL_REACH {
            0.0
        } else {
            snap_up(reach - LABEL_REACH)
        }
    }

    fn ext_elem(&mut self, seq: &[Elem], i: usize) -> Fit<Ext> {
        let key = &seq[i] as *const Elem as usize;
        if let Some(x) = self.cache.get(&key) {
            return Ok(x.clone());
        }
        let x = match &seq[i] {
            Elem::Step(_) => self.step_ext(self.block(&seq[i]).ok_or(Mismatch)?),
            Elem::Transition(_) => self.block_ext(self.block(&seq[i]).ok_or(Mismatch)?),
            Elem::Jump { transition, .. } => {
                let j = self.jump_block(*transition)?;
                self.block_ext(j)
            }
            Elem::Selection { branches, merges } | Elem::Simultaneous { branches, merges } => {
                let div = self.divergence(seq, i)?;
                let cols = self.columns(div, branches, *merges)?;
                let n = cols.order.len();
                let first = -(n as f64 - 1.0) * cols.spacing / 2.0;
                let top = BAR_H + STUB;
                let conv_y = top + cols.body + STUB;
                let mut bands = vec![Band { y0: 0.0, y1: BAR_H, lo: first - BAR_PAD, hi: -first + BAR_PAD }];
                let mut reached = Vec::new();
                for (k, &bi) in cols.order.iter().enumerate() {
                    let o = first + k as f64 * cols.spacing;
                    let x = &cols.exts[k];
                    bands.push(Band::line(o, BAR_H, top));
                    bands.extend(x.bands.iter().map(|b| b.shifted(o, top)));
                    if *merges && branches[bi].reaches {
                        let out = o + x.out_dx;
                        bands.push(Band::line(out, top + x.h, conv_y));
                        reached.push(out);
                    }
                }
                let (h, out_dx) = if *merges && reached.len() > 1 {
                    let (lo, hi) = span(&reached);
                    let mid = convergence_axis(lo, hi);
                    bands.push(Band {
                        y0: conv_y,
                        y1: conv_y + BAR_H,
                        lo: lo - BAR_PAD,
                        hi: hi.max(2.0 * mid - lo) + BAR_PAD,
                    });
                    (conv_y + BAR_H, mid)
                } else if *merges && reached.len() == 1 {
                    (top + cols.body, reached[0])
                } else {
                    (top + cols.body, 0.0)
                };
                Ext { bands: coarsen(bands), h, out_dx }
            }
        };
        self.cache.insert(key, x.clone());
        Ok(x)
    }

    /// The divergence bar of the construct `seq[i]`: the block after the element before it.
    fn divergence(&self, seq: &[Elem], i: usize) -> Fit<usize> {
        let prev = i.checked_sub(1).and_then(|k| self.block(&seq[k])).ok_or(Mismatch)?;
        let (bar, pin) = self.across(prev, false, 0).ok_or(Mismatch)?;
        let want = match &seq[i] {
            Elem::Selection { .. } => ElementKind::SelectionDivergence,
            _ => ElementKind::SimultaneousDivergence,
        };
        if pin != 0 || self.kind(bar) != Some(want) {
            return Err(Mismatch);
        }
        Ok(bar)
    }

    /// The jump block a transition leads to.
    fn jump_block(&self, t: usize) -> Fit<usize> {
        let b = *self.trans_block.get(t).ok_or(Mismatch)?;
        match self.across(b, false, 0) {
            Some((j, 0)) if self.kind(j) == Some(ElementKind::Jump) => Ok(j),
            _ => Err(Mismatch),
        }
    }

    /// Branch order by the divergence's pins and their common spacing: the smallest multiple
    /// of 20 at which no two branch outlines come closer than [`COLUMN_GAP`].
    fn columns(&mut self, div: usize, branches: &[Branch], merges: bool) -> Fit<Columns> {
        let (_, outs) = pin_counts(&self.doc.elements[div]);
        if outs as usize != branches.len() {
            return Err(Mismatch);
        }
        let mut order = vec![usize::MAX; branches.len()];
        for (bi, b) in branches.iter().enumerate() {
            let head = b.seq.first().and_then(|e| self.block(e)).ok_or(Mismatch)?;
            match self.across(head, true, 0) {
                Some((bar, pin)) if bar == div && (pin as usize) < order.len() && order[pin as usize] == usize::MAX => {
                    order[pin as usize] = bi;
                }
                _ => return Err(Mismatch),
            }
        }
        let mut exts = Vec::with_capacity(order.len());
        for &bi in &order {
            exts.push(self.ext_seq(&branches[bi].seq)?);
        }
        let body = exts.iter().map(|e| e.h).fold(0.0, f64::max);
        let outlines: Vec<Vec<Band>> = order
            .iter()
            .zip(&exts)
            .map(|(&bi, e)| {
                let mut o = e.bands.clone();
                if merges && branches[bi].reaches {
                    o.push(Band::line(e.out_dx, e.h, body + STUB));
                }
                o
            })
            .collect();
        let mut spacing: f64 = 2.0 * GRID * 2.0;
        for i in 0..outlines.len() {
            for j in i + 1..outlines.len() {
                let mut need: f64 = 0.0;
                for a in &outlines[i] {
                    for b in &outlines[j] {
                        if b.y0 < a.y1 + CLEARANCE && a.y0 < b.y1 + CLEARANCE {
                            need = need.max(a.hi + COLUMN_GAP - b.lo);
                        }
                    }
                }
                spacing = spacing.max(need / (j - i) as f64);
            }
        }
        let spacing = (spacing / (2.0 * GRID)).ceil() * 2.0 * GRID;
        Ok(Columns { spacing, order, exts, body })
    }

    // ---- placing -------------------------------------------------------------------------

    fn set(&mut self, b: usize, x: f64, y: f64) {
        let e = &mut self.doc.elements[b];
        e.x = x;
        e.y = y;
    }

    fn place_seq(&mut self, seq: &[Elem], axis: f64, top: f64) -> Fit<()> {
        let (mut x, mut y) = (axis, top);
        for i in 0..seq.len() {
            if i > 0 {
                y += LINK;
            }
            let ext = self.ext_elem(seq, i)?;
            self.place_elem(seq, i, x, y)?;
            y += ext.h;
            x += ext.out_dx;
        }
        Ok(())
    }

    fn place_elem(&mut self, seq: &[Elem], i: usize, axis: f64, y: f64) -> Fit<()> {
        match &seq[i] {
            Elem::Step(_) => {
                let b = self.block(&seq[i]).ok_or(Mismatch)?;
                let (w, h) = (self.doc.elements[b].w, self.doc.elements[b].h);
                self.set(b, axis - w / 2.0, y);
                if let Some(list) = self.actions.get(&b).cloned() {
                    let mut ay = y + h / 2.0 - ROW_H / 2.0;
                    for a in list {
                        let ah = self.doc.elements[a].h;
                        self.set(a, axis + w / 2.0 + ACTION_GAP, ay);
                        ay += ah + GRID;
                    }
                }
            }
            Elem::Transition(_) => {
                let b = self.block(&seq[i]).ok_or(Mismatch)?;
                let pad = self.label_pad(b);
                self.set(b, axis - TRANSITION_W / 2.0, y + pad);
            }
            Elem::Jump { transition, .. } => {
                let j = self.jump_block(*transition)?;
                self.set(j, axis - JUMP_SIZE / 2.0, y);
            }
            Elem::Selection { branches, merges } | Elem::Simultaneous { branches, merges } => {
                let div = self.divergence(seq, i)?;
                let cols = self.columns(div, branches, *merges)?;
                let n = cols.order.len();
                let first = axis - (n as f64 - 1.0) * cols.spacing / 2.0;
                {
                    let e = &mut self.doc.elements[div];
                    e.x = first - BAR_PAD;
                    e.w = (n as f64 - 1.0) * cols.spacing + 2.0 * BAR_PAD;
                    e.y = y;
                    e.h = BAR_H;
                }
                let top = y + BAR_H + STUB;
                let conv_y = top + cols.body + STUB;
                // The blocks that reach the convergence, by the pin they reach.
                let mut conv: Option<usize> = None;
                let mut reached = 0;
                for (k, &bi) in cols.order.clone().iter().enumerate() {
                    let bx = first + k as f64 * cols.spacing;
                    self.place_seq(&branches[bi].seq, bx, top)?;
                    if *merges && branches[bi].reaches {
                        reached += 1;
                        let last = branches[bi].seq.last().and_then(|e| self.block(e)).ok_or(Mismatch)?;
                        if let Some((c, _)) = self.across(last, false, 0) {
                            let is_conv = matches!(
                                self.kind(c),
                                Some(ElementKind::SelectionConvergence | ElementKind::SimultaneousConvergence)
                            );
                            if is_conv {
                                if conv.is_some_and(|x| x != c) {
                                    return Err(Mismatch);
                                }
                                conv = Some(c);
                            }
                        }
                    }
                }
                if *merges && reached > 1 {
                    let c = conv.ok_or(Mismatch)?;
                    let (ins, _) = pin_counts(&self.doc.elements[c]);
                    if ins as usize != reached {
                        return Err(Mismatch);
                    }
                    // Its pins on the axes of the blocks that reach it.
                    let xs: Vec<f64> = (0..ins as usize)
                        .map(|k| {
                            let (s, p) = self.across(c, true, k).ok_or(Mismatch)?;
                            Ok(pin_pos(&self.doc.elements[s], false, p).x)
                        })
                        .collect::<Fit<_>>()?;
                    let (lo, hi) = span(&xs);
                    let mid = convergence_axis(lo, hi);
                    let e = &mut self.doc.elements[c];
                    e.x = lo - BAR_PAD;
                    e.w = 2.0 * (mid - lo) + 2.0 * BAR_PAD;
                    e.y = conv_y;
                    e.h = BAR_H;
                }
            }
        }
        Ok(())
    }
}

fn span(xs: &[f64]) -> (f64, f64) {
    (xs.iter().copied().fold(f64::INFINITY, f64::min), xs.iter().copied().fold(f64::NEG_INFINITY, f64::max))
}

/// The axis below a convergence spanning `lo..hi`: its middle, on the grid.
fn convergence_axis(lo: f64, hi: f64) -> f64 {
    snap_up((lo + hi) / 2.0)
}

fn snap(v: f64) -> f64 {
    (v / GRID).round() * GRID
}

fn snap_up(v: f64) -> f64 {
    (v / GRID - 1e-9).ceil() * GRID
}
