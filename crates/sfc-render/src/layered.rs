//! The fallback layout for nets that are not well nested: layers by longest path, barycentric
//! ordering, orthogonal links through channels between the layers.
//!
//! * Back edges of a depth-first search from the initial steps are not layered: a back link
//!   from a transition to its only successor step is drawn as a jump; any other back link is
//!   routed up along a lane right of the drawing, with an arrow (IEC marks upward links).
//! * Links spanning several layers pass through dummy slots, one per layer, so they never run
//!   through a box or a text.
//! * Between two layers every link gets its own horizontal track, except that links leaving
//!   one divergence share its line (single for a step, double for a transition) and links
//!   entering one convergence share its line. A link whose both ends would need a shared line
//!   is made two layers long, so each track serves at most one of them.
//! * No two slots of neighbouring layers are closer than a grid unit unless a link joins them
//!   straight, so vertical segments of different links never overlap; horizontal tracks all
//!   have their own y. Lines may cross, but never touch where they should not.

use crate::place::{link, transition_geom};
use crate::structure::Net;
use crate::text::{dim::*, jump_right, line_height, Sizes};
use crate::{
    ActionBlockGeom, BoxGeom, BranchBar, BranchKind, JumpGeom, Layout, LayoutKind, Point, Rect, TransitionGeom, Wire,
};
use sfc_model::Chart;

/// Vertical distance between tracks in a channel (double lines take `DOUBLE_GAP` more).
const TRACK_GAP: f64 = 8.0;
/// Horizontal distance between the lanes of upward links.
const LANE_GAP: f64 = 8.0;
/// Barycentric ordering passes (each one down and one up).
const ORDER_PASSES: usize = 6;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Real(usize),
    /// A slot of the link with this index in `down`.
    Dummy(usize),
}

#[derive(Debug, Clone)]
struct Slot {
    kind: Kind,
    layer: usize,
    left: f64,
    right: f64,
    height: f64,
    x: f64,
    /// Neighbour slots in the layer above and below.
    up: Vec<usize>,
    down: Vec<usize>,
}

/// A channel track: what it carries decides its position in the channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
enum Track {
    /// Start of an upward link from a node of the layer above (index into `ups`).
    UpExit(usize),
    /// The divergence line of a node of the layer above.
    Divergence(usize),
    /// A link between the two layers with its own track (segment index).
    Free(usize),
    /// The convergence line of a node of the layer below.
    Convergence(usize),
    /// End of an upward link into a node of the layer below.
    UpEnter(usize),
}

pub fn layout(chart: &Chart, sizes: &Sizes) -> Layout {
    let net = Net::new(chart);
    let (ns, nt) = (net.ns, net.nt);
    let n = ns + nt;
    let (disc, back) = net.dfs();
    let lh = line_height(sizes.font_size);

    // Classify the links.
    let mut down: Vec<(usize, usize)> = Vec::new();
    let mut ups: Vec<(usize, usize)> = Vec::new();
    let mut jumps: Vec<(usize, usize)> = Vec::new();
    for (v, succ) in net.succ.iter().enumerate() {
        for (&w, &is_back) in succ.iter().zip(&back[v]) {
            if !is_back {
                down.push((v, w));
            } else if v >= ns && succ.len() == 1 {
                jumps.push((v - ns, w));
            } else {
                ups.push((v, w));
            }
        }
    }
    let mut out_down = vec![0usize; n];
    let mut in_down = vec![0usize; n];
    for &(a, b) in &down {
        out_down[a] += 1;
        in_down[b] += 1;
    }
    // The jump target of each transition that jumps.
    let mut jump_of: Vec<Option<usize>> = vec![None; nt];
    for &(t, target) in &jumps {
        jump_of[t] = Some(target);
    }

    // Longest-path layers over the downward links, in topological order.
    let mut down_succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut indeg = vec![0usize; n];
    for (k, &(a, b)) in down.iter().enumerate() {
        down_succ[a].push(k);
        indeg[b] += 1;
    }
    let mut layer = vec![0usize; n];
    let mut ready: std::collections::BTreeSet<(usize, usize)> =
        (0..n).filter(|&v| indeg[v] == 0).map(|v| (disc[v], v)).collect();
    while let Some((_, v)) = ready.pop_first() {
        for &k in &down_succ[v] {
            let (a, b) = down[k];
            let len = if out_down[a] > 1 && in_down[b] > 1 { 2 } else { 1 };
            layer[b] = layer[b].max(layer[a] + len);
            indeg[b] -= 1;
            if indeg[b] == 0 {
                ready.insert((disc[b], b));
            }
        }
    }
    let layers_n = layer.iter().copied().max().map_or(0, |m| m + 1);

    // Slots: one per node, one per layer crossed by a longer link.
    let mut slots: Vec<Slot> = Vec::with_capacity(n);
    for v in 0..n {
        let (left, right, height) = if v < ns {
            let s = &sizes.steps[v];
            (s.left(), s.right(), s.height())
        } else {
            let t = &sizes.transitions[v - ns];
            let (right, extra) = match jump_of[v - ns] {
                Some(target) => (t.right().max(jump_right(sizes.jump_label(chart, target).1)), LINK + JUMP_H + 4.0),
                None => (t.right(), 0.0),
            };
            (t.left(), right, t.row_h + extra)
        };
        slots.push(Slot {
            kind: Kind::Real(v),
            layer: layer[v],
            left,
            right,
            height,
            x: 0.0,
            up: Vec::new(),
            down: Vec::new(),
        });
    }
    // Segments between neighbouring layers: (upper slot, lower slot, link index).
    let mut segs: Vec<(usize, usize, usize)> = Vec::new();
    for (k, &(a, b)) in down.iter().enumerate() {
        let mut prev = a;
        for l in layer[a] + 1..layer[b] {
            slots.push(Slot {
                kind: Kind::Dummy(k),
                layer: l,
                left: GRID / 2.0,
                right: GRID / 2.0,
                height: 0.0,
                x: 0.0,
                up: Vec::new(),
                down: Vec::new(),
            });
            let d = slots.len() - 1;
            segs.push((prev, d, k));
            prev = d;
        }
        segs.push((prev, b, k));
    }
    for &(u, l, _) in &segs {
        slots[u].down.push(l);
        slots[l].up.push(u);
    }

    // Order within layers: discovery order first, then barycentres.
    let key = |s: &Slot| match s.kind {
        Kind::Real(v) => (disc[v], 0usize),
        Kind::Dummy(k) => (disc[down[k].0], 1 + k),
    };
    let mut layers: Vec<Vec<usize>> = vec![Vec::new(); layers_n];
    for (i, s) in slots.iter().enumerate() {
        layers[s.layer].push(i);
    }
    for l in layers.iter_mut() {
        l.sort_by_key(|&i| key(&slots[i]));
    }
    let mut pos = vec![0usize; slots.len()];
    for layer in &layers {
        for (p, &i) in layer.iter().enumerate() {
            pos[i] = p;
        }
    }
    for _ in 0..ORDER_PASSES {
        for layer in layers.iter_mut().skip(1) {
            reorder(layer, &slots, &pos, true);
            for (p, &i) in layer.iter().enumerate() {
                pos[i] = p;
            }
        }
        for layer in layers.iter_mut().rev().skip(1) {
            reorder(layer, &slots, &pos, false);
            for (p, &i) in layer.iter().enumerate() {
                pos[i] = p;
            }
        }
    }

    // x: each slot under the mean of its upper neighbours, pushed right to keep its order and
    // the column gap, and off every x of the layer above that it is not linked to straight.
    for l in 0..layers_n {
        let above: Vec<(f64, usize)> =
            if l > 0 { layers[l - 1].iter().map(|&i| (slots[i].x, i)).collect() } else { Vec::new() };
        let mut edge = f64::NEG_INFINITY;
        for &i in &layers[l] {
            let s = &slots[i];
            let desired = if s.up.is_empty() {
                f64::NEG_INFINITY
            } else {
                (s.up.iter().map(|&u| slots[u].x).sum::<f64>() / s.up.len() as f64).round()
            };
            let min = if edge.is_finite() { edge + COLUMN_GAP + s.left } else { s.left };
            let mut x = desired.max(min).round();
            // At least a grid unit away from the slots above that it is not linked to, so that
            // their lines cannot run into (or next to) each other.
            for _ in 0..above.len() + 1 {
                match above.iter().find(|(ax, ai)| (ax - x).abs() < GRID && !s.up.contains(ai)) {
                    Some((ax, _)) => x = ax + GRID,
                    None => break,
                }
            }
            slots[i].x = x;
            edge = x + slots[i].right;
        }
    }
    let min_left = slots.iter().map(|s| s.x - s.left).fold(f64::INFINITY, f64::min);
    let shift = if min_left.is_finite() { MARGIN - min_left } else { 0.0 };
    for s in slots.iter_mut() {
        s.x += shift;
    }
    let max_right = slots.iter().map(|s| s.x + s.right).fold(MARGIN, f64::max);

    // Channels: channel c + 1 lies below layer c (channel 0 above the first layer).
    let mut channels: Vec<Vec<Track>> = vec![Vec::new(); layers_n + 1];
    let mut grouped_down = vec![false; n];
    let mut grouped_up = vec![false; n];
    for v in 0..n {
        grouped_down[v] = out_down[v] > 1;
        grouped_up[v] = in_down[v] > 1;
        if grouped_down[v] {
            channels[layer[v] + 1].push(Track::Divergence(v));
        }
        if grouped_up[v] {
            channels[layer[v]].push(Track::Convergence(v));
        }
    }
    for (i, &(u, l, _)) in segs.iter().enumerate() {
        let ru = real(&slots[u]);
        let rl = real(&slots[l]);
        let by_group = ru.is_some_and(|v| grouped_down[v]) || rl.is_some_and(|v| grouped_up[v]);
        if !by_group && (slots[u].x - slots[l].x).abs() >= 0.5 {
            channels[slots[u].layer + 1].push(Track::Free(i));
        }
    }
    for (k, &(u, v)) in ups.iter().enumerate() {
        channels[layer[u] + 1].push(Track::UpExit(k));
        channels[layer[v]].push(Track::UpEnter(k));
    }
    for c in channels.iter_mut() {
        c.sort();
        order_tracks(c, |t| match t {
            Track::Divergence(v) => {
                let i = v;
                let lower: Vec<f64> = slots[i].down.iter().map(|&l| slots[l].x).collect();
                Some((vec![slots[i].x], lower))
            }
            Track::Convergence(v) => {
                let upper: Vec<f64> = slots[v].up.iter().map(|&u| slots[u].x).collect();
                Some((upper, vec![slots[v].x]))
            }
            Track::Free(si) => {
                let (u, l, _) = segs[si];
                Some((vec![slots[u].x], vec![slots[l].x]))
            }
            Track::UpExit(_) | Track::UpEnter(_) => None,
        });
    }

    // y: rows and channels, top to bottom.
    let mut row_top = vec![0.0; layers_n];
    let mut row_h = vec![0.0f64; layers_n];
    for s in &slots {
        row_h[s.layer] = row_h[s.layer].max(s.height);
    }
    let mut track_y: std::collections::HashMap<Track, f64> = std::collections::HashMap::new();
    let mut y = MARGIN;
    for c in 0..=layers_n {
        let tracks = &channels[c];
        if !tracks.is_empty() {
            y += STUB;
            for (i, t) in tracks.iter().enumerate() {
                if i > 0 {
                    y += TRACK_GAP;
                }
                track_y.insert(*t, y);
                if is_double(*t, ns) {
                    y += DOUBLE_GAP;
                }
            }
            y += STUB;
        } else if c > 0 && c < layers_n {
            // Straight links only: keep the layers apart all the same.
            y += 2.0 * STUB;
        }
        if c < layers_n {
            row_top[c] = y;
            y += row_h[c];
        }
    }
    let height = (y + MARGIN).ceil();

    // Geometry of the nodes.
    let mut steps: Vec<Option<BoxGeom>> = vec![None; ns];
    let mut transitions: Vec<Option<TransitionGeom>> = vec![None; nt];
    let mut actions: Vec<ActionBlockGeom> = Vec::new();
    let mut wires: Vec<Wire> = Vec::new();
    let mut bars: Vec<BranchBar> = Vec::new();
    let mut jump_geoms: Vec<JumpGeom> = Vec::new();
    let mut slot_of = vec![0usize; n];
    for (i, s) in slots.iter().enumerate() {
        let top = row_top[s.layer];
        match s.kind {
            Kind::Real(v) if v < ns => {
                slot_of[v] = i;
                let size = &sizes.steps[v];
                let rect = Rect::new(s.x - size.w / 2.0, top, size.w, size.h);
                if let Some(a) = &size.actions {
                    let block = Rect::new(rect.right() + ACTION_GAP, top + size.action_dy(), a.w(), a.h());
                    let cy = top + (size.h / 2.0).round();
                    actions.push(a.geom(v, block, rect, cy));
                }
                let step = &chart.steps[v];
                steps[v] = Some(BoxGeom { step: v, name: step.name.clone(), initial: step.initial, rect });
            }
            Kind::Real(v) => {
                slot_of[v] = i;
                let t = v - ns;
                let size = &sizes.transitions[t];
                let bar_y = top + (size.row_h / 2.0).round();
                let geom = transition_geom(t, size, s.x, bar_y, lh);
                if let Some(target) = jump_of[t] {
                    let (label, w) = sizes.jump_label(chart, target);
                    let tip = Point::new(s.x, top + size.row_h + LINK + JUMP_H);
                    let label_rect = Rect::new(s.x + ARROW_HALF + 4.0, tip.y - ARROW_LEN / 2.0 - lh / 2.0, w, lh);
                    jump_geoms.push(JumpGeom { transition: t, target, from: geom.out_port(), tip, label, label_rect });
                }
                transitions[t] = Some(geom);
            }
            Kind::Dummy(_) => {
                wires.push(link(Point::new(s.x, top), Point::new(s.x, top + row_h[s.layer])));
            }
        }
    }
    // Ports of the slots.
    let out_port = |i: usize| -> Point {
        let s = &slots[i];
        match s.kind {
            Kind::Real(v) if v < ns => steps[v].as_ref().map_or(Point::new(s.x, 0.0), |g| g.bottom()),
            Kind::Real(v) => transitions[v - ns].as_ref().map_or(Point::new(s.x, 0.0), |g| g.out_port()),
            Kind::Dummy(_) => Point::new(s.x, row_top[s.layer] + row_h[s.layer]),
        }
    };
    let in_port = |i: usize| -> Point {
        let s = &slots[i];
        match s.kind {
            Kind::Real(v) if v < ns => steps[v].as_ref().map_or(Point::new(s.x, 0.0), |g| g.top()),
            Kind::Real(v) => transitions[v - ns].as_ref().map_or(Point::new(s.x, 0.0), |g| g.in_port()),
            Kind::Dummy(_) => Point::new(s.x, row_top[s.layer]),
        }
    };

    // Divergence and convergence lines with the links to and from their node.
    for v in 0..n {
        let i = slot_of[v];
        let x = slots[i].x;
        let double = v >= ns;
        let gap = if double { DOUBLE_GAP } else { 0.0 };
        if grouped_down[v] {
            let y = track_y.get(&Track::Divergence(v)).copied().unwrap_or(0.0);
            let xs = slots[i].down.iter().map(|&l| slots[l].x).chain([x]);
            let (x1, x2) = span(xs);
            let kind = if double { BranchKind::SimultaneousDivergence } else { BranchKind::SelectionDivergence };
            bars.push(BranchBar { kind, x1, x2, y, y2: y + gap });
            wires.push(link(out_port(i), Point::new(x, y)));
        }
        if grouped_up[v] {
            let y = track_y.get(&Track::Convergence(v)).copied().unwrap_or(0.0);
            let xs = slots[i].up.iter().map(|&u| slots[u].x).chain([x]);
            let (x1, x2) = span(xs);
            let kind = if double { BranchKind::SimultaneousConvergence } else { BranchKind::SelectionConvergence };
            bars.push(BranchBar { kind, x1, x2, y, y2: y + gap });
            wires.push(link(Point::new(x, y + gap), in_port(i)));
        }
    }
    // The segments.
    for (si, &(u, l, _)) in segs.iter().enumerate() {
        let (xu, xl) = (slots[u].x, slots[l].x);
        if let Some(v) = real(&slots[u]).filter(|&v| grouped_down[v]) {
            let y = track_y.get(&Track::Divergence(v)).copied().unwrap_or(0.0);
            let gap = if v >= ns { DOUBLE_GAP } else { 0.0 };
            wires.push(link(Point::new(xl, y + gap), in_port(l)));
        } else if let Some(v) = real(&slots[l]).filter(|&v| grouped_up[v]) {
            let y = track_y.get(&Track::Convergence(v)).copied().unwrap_or(0.0);
            wires.push(link(out_port(u), Point::new(xu, y)));
        } else if (xu - xl).abs() < 0.5 {
            wires.push(link(out_port(u), in_port(l)));
        } else {
            let y = track_y.get(&Track::Free(si)).copied().unwrap_or(0.0);
            let (a, b) = (out_port(u), in_port(l));
            wires.push(Wire { points: vec![a, Point::new(a.x, y), Point::new(b.x, y), b], upward_arrow: false });
        }
    }
    // Upward links along lanes right of everything.
    let mut width = max_right + MARGIN;
    for (k, &(u, v)) in ups.iter().enumerate() {
        let lane = (max_right + COLUMN_GAP + LANE_GAP * k as f64).round();
        let (a, b) = (out_port(slot_of[u]), in_port(slot_of[v]));
        let y1 = track_y.get(&Track::UpExit(k)).copied().unwrap_or(a.y);
        let y2 = track_y.get(&Track::UpEnter(k)).copied().unwrap_or(b.y);
        wires.push(Wire {
            points: vec![a, Point::new(a.x, y1), Point::new(lane, y1), Point::new(lane, y2), Point::new(b.x, y2), b],
            upward_arrow: true,
        });
        width = width.max(lane + MARGIN);
    }

    let mut actions_sorted = actions;
    actions_sorted.sort_by_key(|a| a.step);
    Layout {
        kind: LayoutKind::Layered,
        width: width.ceil(),
        height,
        font_size: sizes.font_size,
        steps: steps.into_iter().enumerate().map(|(s, g)| g.unwrap_or_else(|| empty_step(chart, s))).collect(),
        transitions: transitions
            .into_iter()
            .enumerate()
            .map(|(t, g)| g.unwrap_or_else(|| transition_geom(t, &sizes.transitions[t], 0.0, 0.0, lh)))
            .collect(),
        actions: actions_sorted,
        wires,
        branches: bars,
        jumps: jump_geoms,
    }
}

/// Every node has a slot, so this is never used; it keeps the function total.
fn empty_step(chart: &Chart, s: usize) -> BoxGeom {
    BoxGeom {
        step: s,
        name: chart.steps.get(s).map(|x| x.name.clone()).unwrap_or_default(),
        initial: false,
        rect: Rect::new(0.0, 0.0, STEP_MIN_W, STEP_MIN_H),
    }
}

fn real(s: &Slot) -> Option<usize> {
    match s.kind {
        Kind::Real(v) => Some(v),
        Kind::Dummy(_) => None,
    }
}

fn is_double(t: Track, ns: usize) -> bool {
    matches!(t, Track::Divergence(v) | Track::Convergence(v) if v >= ns)
}

fn span(xs: impl Iterator<Item = f64>) -> (f64, f64) {
    xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)))
}

/// Sorts a layer by the mean position of each slot's neighbours above (`from_above`) or below;
/// slots without such neighbours keep their place.
fn reorder(layer: &mut [usize], slots: &[Slot], pos: &[usize], from_above: bool) {
    let mut keyed: Vec<(f64, usize, usize)> = layer
        .iter()
        .enumerate()
        .map(|(p, &i)| {
            let nb = if from_above { &slots[i].up } else { &slots[i].down };
            let k =
                if nb.is_empty() { p as f64 } else { nb.iter().map(|&j| pos[j] as f64).sum::<f64>() / nb.len() as f64 };
            (k, p, i)
        })
        .collect();
    keyed.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for (slot, (_, _, i)) in layer.iter_mut().zip(keyed) {
        *slot = i;
    }
}

/// A track's horizontal extent and the x of its lines up and down.
type TrackSpan = (f64, f64, Vec<f64>, Vec<f64>);

/// Orders the tracks of one channel that join its two layers (divergence lines, convergence
/// lines and single links) so that few lines cross: a track above another crosses the other's
/// lines coming down from the upper layer where its own line spans them, and the other's line
/// crosses this one's lines going down to the lower layer. Adjacent tracks are swapped while
/// that lowers the count (a local optimum, deterministic). Upward links stay at the edges.
/// `ends` gives a track's upper and lower vertical lines (their x), `None` for fixed tracks.
fn order_tracks(tracks: &mut [Track], ends: impl Fn(Track) -> Option<(Vec<f64>, Vec<f64>)>) {
    let info: Vec<Option<TrackSpan>> = tracks
        .iter()
        .map(|&t| {
            ends(t).map(|(upper, lower)| {
                let (lo, hi) = span(upper.iter().chain(&lower).copied());
                (lo, hi, upper, lower)
            })
        })
        .collect();
    let mut idx: Vec<usize> = (0..tracks.len()).collect();
    // Crossings when track a lies above track b.
    let cost = |a: usize, b: usize| -> usize {
        match (&info[a], &info[b]) {
            (Some((alo, ahi, _, alower)), Some((blo, bhi, bupper, _))) => {
                let inside = |x: f64, lo: f64, hi: f64| x > lo + 0.5 && x < hi - 0.5;
                bupper.iter().filter(|&&x| inside(x, *alo, *ahi)).count()
                    + alower.iter().filter(|&&x| inside(x, *blo, *bhi)).count()
            }
            _ => 0,
        }
    };
    for _ in 0..tracks.len() {
        let mut swapped = false;
        for i in 0..idx.len().saturating_sub(1) {
            let (a, b) = (idx[i], idx[i + 1]);
            if info[a].is_some() && info[b].is_some() && cost(b, a) < cost(a, b) {
                idx.swap(i, i + 1);
                swapped = true;
            }
        }
        if !swapped {
            break;
        }
    }
    let sorted: Vec<Track> = idx.iter().map(|&i| tracks[i]).collect();
    tracks.copy_from_slice(&sorted);
}
