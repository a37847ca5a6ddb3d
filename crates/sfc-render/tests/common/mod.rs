//! Shared by the tests: loading charts, and the geometric checks every layout must pass.
#![allow(dead_code)]

use sfc_model::{check_source, Chart, CheckOptions};
use sfc_render::{Layout, LayoutKind, Point, Rect};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

pub fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn repo_dir() -> PathBuf {
    crate_dir().join("../..")
}

pub fn update() -> bool {
    std::env::var_os("UPDATE_EXPECT").is_some_and(|v| v == "1")
}

/// The `.st` files of a directory, sorted.
pub fn st_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else { return out };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(st_files(&p));
        } else if p.extension().is_some_and(|x| x == "st") {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// The charts of a source text; panics (a test failure) on errors.
pub fn charts(name: &str, text: &str) -> Vec<Chart> {
    let checked = check_source(0, name, text, &CheckOptions::default());
    let errors: Vec<String> =
        checked.diagnostics.iter().filter(|d| d.is_error()).map(|d| format!("{} {}", d.code, d.message)).collect();
    assert!(errors.is_empty(), "{name}: {errors:?}");
    checked.charts
}

/// Output file stem for chart `i` of a file: the file stem, plus the POU name when the file
/// has several charts.
pub fn stem(path: &Path, charts: &[Chart], i: usize) -> String {
    let base = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if charts.len() > 1 {
        format!("{base}.{}", charts[i].pou)
    } else {
        base
    }
}

// ---------------------------------------------------------------------------------------------
// Geometry checks

const EPS: f64 = 0.01;

#[derive(Debug, Clone, Copy)]
struct Seg {
    a: Point,
    b: Point,
}

impl Seg {
    fn horizontal(&self) -> bool {
        (self.a.y - self.b.y).abs() < EPS
    }
    fn vertical(&self) -> bool {
        (self.a.x - self.b.x).abs() < EPS
    }
    fn contains(&self, p: Point) -> bool {
        let (x1, x2) = (self.a.x.min(self.b.x), self.a.x.max(self.b.x));
        let (y1, y2) = (self.a.y.min(self.b.y), self.a.y.max(self.b.y));
        if self.horizontal() {
            (p.y - self.a.y).abs() < EPS && p.x >= x1 - EPS && p.x <= x2 + EPS
        } else if self.vertical() {
            (p.x - self.a.x).abs() < EPS && p.y >= y1 - EPS && p.y <= y2 + EPS
        } else {
            false
        }
    }
    /// Whether the segments touch: an end of one lies on the other.
    fn touches(&self, o: &Seg) -> bool {
        self.contains(o.a) || self.contains(o.b) || o.contains(self.a) || o.contains(self.b)
    }
    /// A horizontal and a vertical segment crossing strictly inside both.
    fn crosses(&self, o: &Seg) -> bool {
        let (h, v) = if self.horizontal() && o.vertical() {
            (self, o)
        } else if self.vertical() && o.horizontal() {
            (o, self)
        } else {
            return false;
        };
        let (hx1, hx2) = (h.a.x.min(h.b.x), h.a.x.max(h.b.x));
        let (vy1, vy2) = (v.a.y.min(v.b.y), v.a.y.max(v.b.y));
        v.a.x > hx1 + EPS && v.a.x < hx2 - EPS && h.a.y > vy1 + EPS && h.a.y < vy2 - EPS
    }
    /// Whether the segment runs through the interior of `r`.
    fn through(&self, r: &Rect) -> bool {
        let (x1, x2) = (self.a.x.min(self.b.x), self.a.x.max(self.b.x));
        let (y1, y2) = (self.a.y.min(self.b.y), self.a.y.max(self.b.y));
        x1 < r.right() - EPS && x2 > r.x + EPS && y1 < r.bottom() - EPS && y2 > r.y + EPS
    }
}

/// Directed reachability along the lines: a wire or jump line is followed from where it is
/// entered to its end; a bar, once entered anywhere, is all reachable. Lines join where an end
/// of one lies on the other or where they overlap; lines that merely cross do not join.
struct Flow<'a> {
    segs: &'a [Seg],
    grid: Grid,
    bar_of: &'a [Option<usize>],
    /// For every segment, the segments it joins and the junction (a point or an overlap).
    joins: Vec<Vec<(usize, Point, Point)>>,
}

struct Reach<'a> {
    flow: &'a Flow<'a>,
    /// Entry distance along each directed segment (from its first point); `entered` for bars.
    entry: Vec<f64>,
    entered: Vec<bool>,
}

/// Segments by grid cell (of their bounding box grown by `GROW`), so that pairs of segments
/// that may touch are found without comparing all pairs.
struct Grid {
    cells: std::collections::HashMap<(i64, i64), Vec<usize>>,
}

const CELL: f64 = 64.0;
const GROW: f64 = 4.0;

impl Grid {
    fn new(segs: &[Seg]) -> Grid {
        let mut cells: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
        for (i, s) in segs.iter().enumerate() {
            for key in Grid::keys(s.a.x.min(s.b.x), s.a.y.min(s.b.y), s.a.x.max(s.b.x), s.a.y.max(s.b.y)) {
                cells.entry(key).or_default().push(i);
            }
        }
        Grid { cells }
    }
    fn keys(x1: f64, y1: f64, x2: f64, y2: f64) -> impl Iterator<Item = (i64, i64)> {
        let c = |v: f64| (v / CELL).floor() as i64;
        let (cx1, cy1, cx2, cy2) = (c(x1 - GROW), c(y1 - GROW), c(x2 + GROW), c(y2 + GROW));
        (cx1..=cx2).flat_map(move |x| (cy1..=cy2).map(move |y| (x, y)))
    }
    /// Segments whose cells meet those of the box, each once, in index order.
    fn near(&self, x1: f64, y1: f64, x2: f64, y2: f64) -> Vec<usize> {
        let mut out: Vec<usize> =
            Grid::keys(x1, y1, x2, y2).filter_map(|k| self.cells.get(&k)).flatten().copied().collect();
        out.sort_unstable();
        out.dedup();
        out
    }
    fn near_seg(&self, s: &Seg) -> Vec<usize> {
        self.near(s.a.x.min(s.b.x), s.a.y.min(s.b.y), s.a.x.max(s.b.x), s.a.y.max(s.b.y))
    }
}

fn param(s: &Seg, p: Point) -> f64 {
    (p.x - s.a.x).abs() + (p.y - s.a.y).abs()
}

impl<'a> Flow<'a> {
    fn new(segs: &'a [Seg], bar_of: &'a [Option<usize>]) -> Flow<'a> {
        let grid = Grid::new(segs);
        let mut joins = vec![Vec::new(); segs.len()];
        for i in 0..segs.len() {
            for j in grid.near_seg(&segs[i]) {
                if i == j {
                    continue;
                }
                let (a, b) = (&segs[i], &segs[j]);
                if let Some((p, q)) = overlap(a, b) {
                    joins[i].push((j, p, q));
                } else {
                    for p in [a.a, a.b, b.a, b.b] {
                        if a.contains(p) && b.contains(p) {
                            joins[i].push((j, p, p));
                            break;
                        }
                    }
                }
            }
        }
        Flow { segs, grid, bar_of, joins }
    }

    fn from(&'a self, port: Point) -> Reach<'a> {
        let n = self.segs.len();
        let mut r = Reach { flow: self, entry: vec![f64::INFINITY; n], entered: vec![false; n] };
        let mut queue = Vec::new();
        for i in self.grid.near(port.x, port.y, port.x, port.y) {
            let s = &self.segs[i];
            if self.bar_of[i].is_none() && s.contains(port) {
                r.entry[i] = param(s, port);
                r.entered[i] = true;
                queue.push(i);
            }
        }
        while let Some(i) = queue.pop() {
            let si = &self.segs[i];
            for &(j, p, q) in &self.joins[i] {
                // The part of the junction reachable on segment i.
                let (p, q) = match self.bar_of[i] {
                    Some(_) => (p, q),
                    None => {
                        let (tp, tq) = (param(si, p), param(si, q));
                        let e = r.entry[i];
                        if tp.max(tq) < e - EPS {
                            continue;
                        }
                        if tp < e - EPS {
                            (point_at(si, e), q)
                        } else if tq < e - EPS {
                            (p, point_at(si, e))
                        } else {
                            (p, q)
                        }
                    }
                };
                match self.bar_of[j] {
                    Some(bar) => {
                        // Entering a bar enters all its lines.
                        for k in 0..self.segs.len() {
                            if self.bar_of[k] == Some(bar) && !r.entered[k] {
                                r.entered[k] = true;
                                r.entry[k] = 0.0;
                                queue.push(k);
                            }
                        }
                    }
                    None => {
                        let sj = &self.segs[j];
                        let e = param(sj, p).min(param(sj, q));
                        if e < r.entry[j] - EPS {
                            r.entry[j] = e;
                            r.entered[j] = true;
                            queue.push(j);
                        }
                    }
                }
            }
        }
        r
    }
}

impl Reach<'_> {
    fn reaches(&self, p: Point) -> bool {
        self.flow.grid.near(p.x, p.y, p.x, p.y).into_iter().any(|i| {
            let s = &self.flow.segs[i];
            self.entered[i] && s.contains(p) && (self.flow.bar_of[i].is_some() || param(s, p) >= self.entry[i] - EPS)
        })
    }
    fn bars(&self, l: &Layout) -> Vec<sfc_render::BranchKind> {
        let mut out: Vec<_> = (0..self.flow.segs.len())
            .filter(|&i| self.entered[i])
            .filter_map(|i| self.flow.bar_of[i])
            .map(|k| l.branches[k].kind)
            .collect();
        out.dedup();
        out
    }
}

fn point_at(s: &Seg, d: f64) -> Point {
    let len = param(s, s.b);
    if len < EPS {
        return s.a;
    }
    let f = d / len;
    Point::new(s.a.x + (s.b.x - s.a.x) * f, s.a.y + (s.b.y - s.a.y) * f)
}

/// The overlap of two collinear segments, if they share more than a point.
fn overlap(a: &Seg, b: &Seg) -> Option<(Point, Point)> {
    if a.horizontal() && b.horizontal() && (a.a.y - b.a.y).abs() < EPS {
        let lo = a.a.x.min(a.b.x).max(b.a.x.min(b.b.x));
        let hi = a.a.x.max(a.b.x).min(b.a.x.max(b.b.x));
        (hi > lo + EPS).then(|| (Point::new(lo, a.a.y), Point::new(hi, a.a.y)))
    } else if a.vertical() && b.vertical() && (a.a.x - b.a.x).abs() < EPS {
        let lo = a.a.y.min(a.b.y).max(b.a.y.min(b.b.y));
        let hi = a.a.y.max(a.b.y).min(b.a.y.max(b.b.y));
        (hi > lo + EPS).then(|| (Point::new(a.a.x, lo), Point::new(a.a.x, hi)))
    } else {
        None
    }
}

/// Checks that `l` draws `chart` completely and correctly:
/// * one box per step and one bar per transition, in id order;
/// * no two boxes, bars, texts or action blocks overlap, and no line runs through one;
/// * everything lies inside the drawing;
/// * following the lines downwards (and along upward wires in their direction), the output of
///   every step reaches exactly the transitions it leads to and nothing else, the output of
///   every transition exactly the steps it activates (a jump counts for its target);
/// * structured layouts: no two lines cross, and divergences/convergences are drawn with the
///   right kind of line.
pub fn check_layout(chart: &Chart, l: &Layout) -> Result<(), String> {
    if l.steps.len() != chart.steps.len() || l.steps.iter().enumerate().any(|(i, s)| s.step != i) {
        return Err("steps are not drawn once each, in order".into());
    }
    if l.transitions.len() != chart.transitions.len()
        || l.transitions.iter().enumerate().any(|(i, t)| t.transition != i)
    {
        return Err("transitions are not drawn once each, in order".into());
    }

    // Boxes.
    let mut rects: Vec<(String, Rect)> = Vec::new();
    for s in &l.steps {
        rects.push((format!("step {}", s.name), s.rect));
    }
    for a in &l.actions {
        rects.push((format!("actions of step {}", a.step), a.rect));
    }
    for t in &l.transitions {
        rects.push((format!("bar of transition {}", t.transition), t.bar_rect()));
        if let Some(r) = t.condition_rect {
            rects.push((format!("condition of transition {}", t.transition), r));
        }
        if let Some(r) = t.name_rect {
            rects.push((format!("name of transition {}", t.transition), r));
        }
    }
    for j in &l.jumps {
        rects.push((format!("jump label of transition {}", j.transition), j.label_rect));
    }
    for (i, (na, a)) in rects.iter().enumerate() {
        if a.x < -EPS || a.y < -EPS || a.right() > l.width + EPS || a.bottom() > l.height + EPS {
            return Err(format!("{na} {a:?} lies outside the drawing {}x{}", l.width, l.height));
        }
        for (nb, b) in &rects[i + 1..] {
            if a.overlaps(b) {
                return Err(format!("{na} {a:?} overlaps {nb} {b:?}"));
            }
        }
    }

    // Lines: wires and jump lines are directed (from their first point to their last), branch
    // bars are hubs (entering one line of a bar enters all of it, and both lines of a double
    // bar).
    let mut segs: Vec<Seg> = Vec::new();
    let mut bar_of: Vec<Option<usize>> = Vec::new();
    for w in &l.wires {
        for p in w.points.windows(2) {
            segs.push(Seg { a: p[0], b: p[1] });
            bar_of.push(None);
        }
    }
    for (k, b) in l.branches.iter().enumerate() {
        segs.push(Seg { a: Point::new(b.x1, b.y), b: Point::new(b.x2, b.y) });
        bar_of.push(Some(k));
        if b.y2 != b.y {
            segs.push(Seg { a: Point::new(b.x1, b.y2), b: Point::new(b.x2, b.y2) });
            bar_of.push(Some(k));
        }
    }
    let jump_base = segs.len();
    for j in &l.jumps {
        segs.push(Seg { a: j.from, b: j.tip });
        bar_of.push(None);
    }
    for s in &segs {
        if !(s.horizontal() || s.vertical()) {
            return Err(format!("slanted line {s:?}"));
        }
        for (name, r) in &rects {
            if s.through(r) {
                return Err(format!("line {s:?} runs through {name} {r:?}"));
            }
        }
    }
    // Distinct parallel lines closer than this look like one.
    let grid = Grid::new(&segs);
    for i in 0..segs.len() {
        for j in grid.near_seg(&segs[i]).into_iter().filter(|&j| j > i) {
            let (a, b) = (&segs[i], &segs[j]);
            let near = if a.vertical() && b.vertical() {
                let d = (a.a.x - b.a.x).abs();
                let lo = a.a.y.min(a.b.y).max(b.a.y.min(b.b.y));
                let hi = a.a.y.max(a.b.y).min(b.a.y.max(b.b.y));
                d > EPS && d < 3.0 && hi > lo + EPS
            } else if a.horizontal() && b.horizontal() && bar_of[i].is_none() && bar_of[j].is_none() {
                let d = (a.a.y - b.a.y).abs();
                let lo = a.a.x.min(a.b.x).max(b.a.x.min(b.b.x));
                let hi = a.a.x.max(a.b.x).min(b.a.x.max(b.b.x));
                d > EPS && d < 3.0 && hi > lo + EPS
            } else {
                false
            };
            if near {
                return Err(format!("lines {a:?} and {b:?} run side by side, too close to tell apart"));
            }
        }
    }
    if l.kind == LayoutKind::Structured {
        for i in 0..segs.len() {
            for j in grid.near_seg(&segs[i]).into_iter().filter(|&j| j > i) {
                if segs[i].crosses(&segs[j]) {
                    return Err(format!("lines cross: {:?} and {:?}", segs[i], segs[j]));
                }
            }
        }
    }
    let flow = Flow::new(&segs, &bar_of);

    // Follow the lines from every output port.
    let step_reach: Vec<Reach> = l.steps.iter().map(|s| flow.from(s.bottom())).collect();
    let trans_reach: Vec<Reach> = l.transitions.iter().map(|t| flow.from(t.out_port())).collect();
    let mut drawn_st: BTreeSet<(usize, usize)> = BTreeSet::new();
    let mut drawn_ts: BTreeSet<(usize, usize)> = BTreeSet::new();
    for (s, reach) in l.steps.iter().zip(&step_reach) {
        for t in &l.transitions {
            if reach.reaches(t.in_port()) {
                drawn_st.insert((s.step, t.transition));
            }
            if reach.reaches(t.out_port()) {
                return Err(format!(
                    "the output of step {} runs into the output of transition {}",
                    s.name, t.transition
                ));
            }
        }
        for o in &l.steps {
            if reach.reaches(o.top()) {
                return Err(format!("step {} is linked to step {} without a transition", s.name, o.name));
            }
        }
        if reach.entered.iter().enumerate().any(|(i, &e)| e && i >= jump_base) {
            return Err(format!("the output of step {} runs into a jump", s.name));
        }
    }
    for (t, reach) in l.transitions.iter().zip(&trans_reach) {
        for s in &l.steps {
            if reach.reaches(s.top()) {
                drawn_ts.insert((t.transition, s.step));
            }
        }
        for o in &l.transitions {
            if reach.reaches(o.in_port()) {
                return Err(format!(
                    "transition {} is linked to transition {} without a step",
                    t.transition, o.transition
                ));
            }
        }
        for (k, j) in l.jumps.iter().enumerate() {
            if reach.entered[jump_base + k] {
                drawn_ts.insert((t.transition, j.target));
            }
        }
    }
    if l.kind == LayoutKind::Structured {
        // Branch lines of the right kind: a step leading to several transitions has a selection
        // divergence line, and so on.
        use sfc_render::BranchKind::*;
        for (s, reach) in l.steps.iter().zip(&step_reach) {
            let outs = drawn_st.iter().filter(|(x, _)| *x == s.step).count();
            if outs > 1 && !reach.bars(l).contains(&SelectionDivergence) {
                return Err(format!("selection divergence of step {} without its line", s.name));
            }
        }
        for (t, reach) in l.transitions.iter().zip(&trans_reach) {
            let outs = drawn_ts.iter().filter(|(x, _)| *x == t.transition).count();
            let jumps = l.jumps.iter().filter(|j| j.transition == t.transition).count();
            if outs - jumps > 1 && !reach.bars(l).contains(&SimultaneousDivergence) {
                return Err(format!("simultaneous divergence of transition {} without its double line", t.transition));
            }
            let froms: Vec<usize> = drawn_st.iter().filter(|(_, x)| *x == t.transition).map(|(s, _)| *s).collect();
            if froms.len() > 1 && !froms.iter().all(|&s| step_reach[s].bars(l).contains(&SimultaneousConvergence)) {
                return Err(format!("simultaneous convergence of transition {} without its double line", t.transition));
            }
        }
        for s in &l.steps {
            let ins: Vec<usize> = drawn_ts
                .iter()
                .filter(|(t, x)| *x == s.step && !l.jumps.iter().any(|j| j.transition == *t))
                .map(|(t, _)| *t)
                .collect();
            if ins.len() > 1 && !ins.iter().all(|&t| trans_reach[t].bars(l).contains(&SelectionConvergence)) {
                return Err(format!("selection convergence at step {} without its line", s.name));
            }
        }
    }
    let mut want_st = BTreeSet::new();
    let mut want_ts = BTreeSet::new();
    for (t, tr) in chart.transitions.iter().enumerate() {
        for &s in &tr.from {
            want_st.insert((s, t));
        }
        for &s in &tr.to {
            want_ts.insert((t, s));
        }
    }
    if drawn_st != want_st {
        return Err(format!(
            "step→transition links: missing {:?}, extra {:?}",
            want_st.difference(&drawn_st).collect::<Vec<_>>(),
            drawn_st.difference(&want_st).collect::<Vec<_>>()
        ));
    }
    if drawn_ts != want_ts {
        return Err(format!(
            "transition→step links: missing {:?}, extra {:?}",
            want_ts.difference(&drawn_ts).collect::<Vec<_>>(),
            drawn_ts.difference(&want_ts).collect::<Vec<_>>()
        ));
    }
    Ok(())
}
