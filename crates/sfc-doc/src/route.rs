//! Orthogonal wire routing around blocks and labels. The same router runs in the canvas
//! (`web/src/diagram/layout/router.ts`, kept equal by the shared cases in
//! `crates/sfc-doc/tests/routes.json`), so a wire the layout routes and one the user's move
//! re-routes look alike.
//!
//! A wire leaves its output pin downwards and enters its input pin from above. The router
//! tries, in order, and takes the first route that crosses no obstacle (a block's or label's
//! interior):
//!
//! 1. straight down, when the pins are aligned;
//! 2. one horizontal run between the pins (down, across, down), at the middle height or the
//!    nearest free height;
//! 3. a vertical lane beside the obstacles: down a stub, across to the lane, along it, across
//!    above the input pin, down into it. Lanes are tried from the shortest route on.
//!
//! Routes never overshoot and come back: going down, every vertical run goes down. A wire to
//! a pin above its start (a loop drawn as a line) runs up a lane beside the obstacles. When no
//! candidate is free, the one crossing the fewest obstacles is taken.

use crate::drawing::Rect;
use crate::Point;

/// The vertical piece at each pin.
pub const STUB: f64 = 10.0;
const GRID: f64 = 10.0;

fn p(x: f64, y: f64) -> Point {
    Point { x, y }
}

/// Whether the segment `a`–`b` (horizontal or vertical) runs through the interior of `r`.
pub fn crosses(a: Point, b: Point, r: &Rect) -> bool {
    const E: f64 = 0.5;
    if (a.y - b.y).abs() < 1e-9 {
        let (x1, x2) = (a.x.min(b.x), a.x.max(b.x));
        a.y > r.y + E && a.y < r.bottom() - E && x1 < r.right() - E && x2 > r.x + E
    } else {
        let (y1, y2) = (a.y.min(b.y), a.y.max(b.y));
        a.x > r.x + E && a.x < r.right() - E && y1 < r.bottom() - E && y2 > r.y + E
    }
}

/// How many obstacles a polyline runs through.
pub fn hits(points: &[Point], obstacles: &[Rect]) -> usize {
    obstacles.iter().filter(|r| points.windows(2).any(|w| crosses(w[0], w[1], r))).count()
}

fn length(points: &[Point]) -> f64 {
    points.windows(2).map(|w| (w[0].x - w[1].x).abs() + (w[0].y - w[1].y).abs()).sum()
}

/// Drops repeated points and points in the middle of a straight run.
pub fn simplify(points: Vec<Point>) -> Vec<Point> {
    let mut out: Vec<Point> = Vec::with_capacity(points.len());
    for q in points {
        if out.last().is_some_and(|l: &Point| (l.x - q.x).abs() < 1e-9 && (l.y - q.y).abs() < 1e-9) {
            continue;
        }
        if out.len() >= 2 {
            let a = out[out.len() - 2];
            let b = out[out.len() - 1];
            let straight = ((a.x - b.x).abs() < 1e-9 && (b.x - q.x).abs() < 1e-9)
                || ((a.y - b.y).abs() < 1e-9 && (b.y - q.y).abs() < 1e-9);
            if straight {
                out.pop();
            }
        }
        out.push(q);
    }
    out
}

fn snap(v: f64) -> f64 {
    (v / GRID).round() * GRID
}

/// The Z-shaped candidates (down, across, down), from the middle height outwards.
fn z_routes(s: Point, e: Point) -> Vec<Vec<Point>> {
    let mut out = Vec::new();
    if e.y <= s.y {
        return out;
    }
    // Pins closer than two stubs: the run halfway.
    let stub = STUB.min((e.y - s.y) / 2.0);
    let (lo, hi) = (s.y + stub, e.y - stub);
    let mid = if hi - lo < GRID { (lo + hi) / 2.0 } else { snap((lo + hi) / 2.0).clamp(lo, hi) };
    let mut ys = vec![mid];
    let mut k = 1.0;
    while mid - k * GRID >= lo || mid + k * GRID <= hi {
        if mid - k * GRID >= lo {
            ys.push(mid - k * GRID);
        }
        if mid + k * GRID <= hi {
            ys.push(mid + k * GRID);
        }
        k += 1.0;
    }
    for y in [lo, hi] {
        if !ys.contains(&y) {
            ys.push(y);
        }
    }
    for y in ys.into_iter().take(64) {
        out.push(vec![s, p(s.x, y), p(e.x, y), e]);
    }
    out
}

/// The lane candidates: down a stub, across to a vertical lane beside an obstacle (or the
/// hint), along it, across above the end, down into it; the hint first, then shortest first.
fn lane_routes(s: Point, e: Point, obstacles: &[Rect], lane_hint: Option<f64>) -> Vec<Vec<Point>> {
    let below = e.y > s.y;
    let (top, bottom) = (s.y.min(e.y) - STUB, s.y.max(e.y) + STUB);
    let mut lanes: Vec<f64> = Vec::new();
    if let Some(h) = lane_hint {
        lanes.push(snap(h));
    }
    for r in obstacles.iter().filter(|r| r.y < bottom + 40.0 && r.bottom() > top - 40.0) {
        lanes.push(snap(r.x) - GRID);
        lanes.push(snap(r.right()) + GRID);
    }
    lanes.push(s.x.max(e.x) + 2.0 * GRID);
    lanes.push(s.x.min(e.x) - 2.0 * GRID);
    lanes.sort_by(|a, b| a.total_cmp(b));
    lanes.dedup();
    let hint = lane_hint.map(snap);
    let starts = [s.y + STUB, s.y + 2.0 * STUB, s.y + 3.0 * STUB];
    let ends = [e.y - STUB, e.y - 2.0 * STUB, e.y - 3.0 * STUB];
    let mut routes: Vec<(bool, f64, Vec<Point>)> = Vec::new();
    for &x in &lanes {
        for &y1 in &starts {
            for &y2 in &ends {
                if below && y2 < y1 {
                    continue;
                }
                let r = vec![s, p(s.x, y1), p(x, y1), p(x, y2), p(e.x, y2), e];
                routes.push((hint != Some(x), length(&r), r));
            }
        }
    }
    routes.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    routes.into_iter().map(|(_, _, r)| r).collect()
}

/// The route from output pin `s` to input pin `e` around `obstacles` (see the module doc): the
/// whole polyline, both pins included, or empty for a straight wire. `lane_hint` is a vertical
/// run the user asked for (a dragged segment), tried right after the straight wire.
pub fn route(s: Point, e: Point, obstacles: &[Rect], lane_hint: Option<f64>) -> Vec<Point> {
    let mut best: Option<(usize, Vec<Point>)> = None;
    let straight = || if (s.x - e.x).abs() < 0.5 && e.y > s.y { vec![vec![s, e]] } else { Vec::new() };
    // Cheapest first: straight, (the hinted lanes,) one horizontal run, then every lane.
    let mut stages: Vec<Box<dyn Fn() -> Vec<Vec<Point>> + '_>> =
        vec![Box::new(straight), Box::new(|| z_routes(s, e)), Box::new(|| lane_routes(s, e, obstacles, lane_hint))];
    if lane_hint.is_some() {
        stages.insert(1, Box::new(|| lane_routes(s, e, obstacles, lane_hint).into_iter().take(9).collect()));
    }
    for stage in &stages {
        for c in stage() {
            let n = hits(&c, obstacles);
            if n == 0 {
                return finish(simplify(c));
            }
            if best.as_ref().is_none_or(|(m, _)| n < *m) {
                best = Some((n, c));
            }
        }
    }
    finish(simplify(best.map(|(_, c)| c).unwrap_or_else(|| vec![s, e])))
}

/// A straight wire is written without bends (empty: the canvas draws it pin to pin).
fn finish(points: Vec<Point>) -> Vec<Point> {
    if points.len() == 2 && (points[0].x - points[1].x).abs() < 0.5 {
        return Vec::new();
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x: f64, y: f64, w: f64, h: f64) -> Rect {
        Rect { x, y, w, h }
    }

    #[test]
    fn straight_when_aligned_and_free() {
        assert!(route(p(100.0, 50.0), p(100.0, 200.0), &[], None).is_empty());
    }

    #[test]
    fn around_a_block_in_the_way() {
        let block = rect(60.0, 100.0, 80.0, 40.0);
        let r = route(p(100.0, 50.0), p(100.0, 200.0), &[block], None);
        assert_eq!(hits(&r, &[block]), 0, "{r:?}");
        // Going down, every vertical run goes down: no loop.
        for w in r.windows(2) {
            assert!(w[1].y >= w[0].y, "{r:?}");
        }
    }

    #[test]
    fn a_z_between_offset_pins() {
        let r = route(p(100.0, 50.0), p(200.0, 150.0), &[], None);
        assert_eq!(r, vec![p(100.0, 50.0), p(100.0, 100.0), p(200.0, 100.0), p(200.0, 150.0)]);
    }
}
