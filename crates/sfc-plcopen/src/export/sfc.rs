//! An SFC chart as PLCopen graphical elements: steps, transitions, divergence and convergence
//! bars, jumps and action blocks, with `localId`s and connections.
//!
//! Geometry comes from the `sfc.x`, `sfc.y`, `sfc.w`, `sfc.h` attributes when every step and
//! transition has a position (a chart imported from XML or saved by the editor); jumps and
//! action blocks then come from `sfc.jump` and `sfc.actionblock`. Otherwise a simple structured
//! layout is made (the full layout is `sfc-render`'s): one column per branch, a row per step
//! level (longest path from the initial step), loops back drawn as jumps. Bars are placed
//! between the pins they join. Transitions leaving one step get increasing x in declaration
//! order, so an import, which orders alternatives left to right, keeps their order.

use super::{column_if_leading, dedent, description, slice, X};
use crate::attrs::{self, CODESYS_SFC_ELEMENT, STEP_ACTION_GUIDS};
use sfc_diagnostics::Span;
use sfc_model::{ActionTarget, Chart, Duration};
use sfc_syntax::ast;
use std::borrow::Cow;
use std::collections::{HashMap, HashSet};

const STEP_H: f64 = 30.0;
const TRANS_W: f64 = 20.0;
const TRANS_H: f64 = 2.0;
const ROW_H: f64 = 110.0;
const JUMP_W: f64 = 12.0;
const JUMP_H: f64 = 13.0;
const ACTION_ROW_H: f64 = 30.0;

#[derive(Debug, Clone, Copy, Default)]
struct Geo {
    x: f64,
    y: f64,
    w: f64,
    h: f64,
}

/// Pins sit at whole units inside the element, as Beremiz puts them (`width / 2` rounded down).
impl Geo {
    fn top(&self) -> (f64, f64) {
        (self.x + (self.w / 2.0).floor(), self.y)
    }
    fn bottom(&self) -> (f64, f64) {
        (self.x + (self.w / 2.0).floor(), self.y + self.h)
    }
    fn right(&self) -> (f64, f64) {
        (self.x + self.w, self.y + (self.h / 2.0).floor())
    }
}

type Pt = (f64, f64);

/// A producer pin: the element and the absolute point of its output.
#[derive(Debug, Clone, Copy)]
struct P {
    id: u64,
    at: Pt,
}

/// An input point with its connections.
struct In {
    at: Pt,
    conns: Vec<P>,
}

enum Kind {
    Step(usize),
    Trans(usize),
    SelDiv,
    SelConv,
    SimDiv,
    SimConv,
    Jump(String),
    /// Action block of a step: the step, the range of its associations.
    Actions(usize, std::ops::Range<usize>),
    Comment(String),
    /// A transition not connected on both sides (`sfc.loose`).
    Loose(attrs::Loose),
}

struct El {
    id: u64,
    kind: Kind,
    geo: Geo,
    ins: Vec<In>,
    outs: Vec<Pt>,
}

/// Where the successor `k` of a transition goes.
#[derive(Clone, Copy)]
enum Target {
    Wire,
    /// A jump at this top-left position.
    Jump(Pt),
}

fn step_width(name: &str) -> f64 {
    (name.chars().count() as f64 * 8.0 + 24.0).max(60.0).round()
}

fn assoc_text(a: &sfc_model::Association) -> String {
    let mut q = a.qualifier.name().to_string();
    if let Some(d) = &a.duration {
        q.push_str(", ");
        q.push_str(&duration_text(d));
    }
    format!("{q} {}", a.action)
}

fn duration_text(d: &Duration) -> String {
    match d {
        Duration::Literal(us) => super::fmt_duration(*us),
        Duration::Variable(v) => v.clone(),
    }
}

fn action_block_width(assocs: &[sfc_model::Association]) -> f64 {
    assocs.iter().map(|a| assoc_text(a).chars().count() as f64 * 7.0 + 40.0).fold(100.0, f64::max).round()
}

fn has_position(list: &[ast::Attribute]) -> bool {
    attrs::get_num(list, attrs::X).is_some() && attrs::get_num(list, attrs::Y).is_some()
}

/// Geometry of steps and transitions and the kind of every transition successor.
fn geometry(chart: &Chart) -> (Vec<Geo>, Vec<Geo>, Vec<Vec<Target>>, bool) {
    let stored = !chart.steps.is_empty()
        && chart.steps.iter().all(|s| has_position(&s.attributes))
        && chart.transitions.iter().all(|t| has_position(&t.attributes));
    if stored {
        let steps = chart
            .steps
            .iter()
            .map(|s| Geo {
                x: attrs::get_num(&s.attributes, attrs::X).unwrap_or(0.0),
                y: attrs::get_num(&s.attributes, attrs::Y).unwrap_or(0.0),
                w: attrs::get_num(&s.attributes, attrs::W).unwrap_or_else(|| step_width(&s.name)),
                h: attrs::get_num(&s.attributes, attrs::H).unwrap_or(STEP_H),
            })
            .collect();
        let trans: Vec<Geo> = chart
            .transitions
            .iter()
            .map(|t| Geo {
                x: attrs::get_num(&t.attributes, attrs::X).unwrap_or(0.0),
                y: attrs::get_num(&t.attributes, attrs::Y).unwrap_or(0.0),
                w: attrs::get_num(&t.attributes, attrs::W).unwrap_or(TRANS_W),
                h: attrs::get_num(&t.attributes, attrs::H).unwrap_or(TRANS_H),
            })
            .collect();
        let targets = chart
            .transitions
            .iter()
            .map(|t| {
                let jumps = parse_jumps(attrs::get(&t.attributes, attrs::JUMP).unwrap_or(""));
                t.to.iter()
                    .map(|&s| match jumps.iter().find(|j| j.0.eq_ignore_ascii_case(&chart.steps[s].name)) {
                        Some(j) => Target::Jump(j.1),
                        None => Target::Wire,
                    })
                    .collect()
            })
            .collect();
        return (steps, trans, targets, true);
    }
    let (s, t, j) = structured(chart);
    (s, t, j, false)
}

/// `Name x y;Name x y`.
fn parse_jumps(v: &str) -> Vec<(String, Pt)> {
    v.split(';')
        .filter_map(|e| {
            let mut it = e.split_whitespace();
            let name = it.next()?.to_string();
            let x = it.next()?.parse().ok()?;
            let y = it.next()?.parse().ok()?;
            Some((name, (x, y)))
        })
        .collect()
}

/// `x y w h n;…`.
fn parse_blocks(v: &str) -> Vec<(Geo, usize)> {
    v.split(';')
        .filter_map(|e| {
            let n: Vec<f64> = e.split_whitespace().filter_map(|p| p.parse().ok()).collect();
            (n.len() == 5).then(|| (Geo { x: n[0], y: n[1], w: n[2], h: n[3] }, n[4].max(0.0) as usize))
        })
        .collect()
}

/// The structured layout: columns by depth-first branch allocation, rows by longest path.
fn structured(chart: &Chart) -> (Vec<Geo>, Vec<Geo>, Vec<Vec<Target>>) {
    let n = chart.steps.len();
    let adj = chart.adjacency();
    let mut state = vec![0u8; n]; // 0 new, 1 on the stack, 2 done
    let mut col = vec![usize::MAX; n];
    let mut tcol = vec![usize::MAX; chart.transitions.len()];
    let mut back: HashSet<(usize, usize)> = HashSet::new();
    let mut next_col = 0usize;
    let mut roots: Vec<usize> = chart.initial_steps();
    roots.extend(0..n);
    for root in roots {
        if state[root] != 0 {
            continue;
        }
        col[root] = next_col;
        next_col += 1;
        state[root] = 1;
        // Frames: (step, index of the next outgoing transition).
        let mut stack: Vec<(usize, usize)> = vec![(root, 0)];
        while let Some(&mut (s, ref mut oi)) = stack.last_mut() {
            let Some(&t) = adj.outgoing[s].get(*oi) else {
                state[s] = 2;
                stack.pop();
                continue;
            };
            let k = *oi;
            *oi += 1;
            if tcol[t] == usize::MAX {
                tcol[t] = if k == 0 { col[s] } else { next_col_take(&mut next_col) };
            }
            let mut first = true;
            let mut pushed = Vec::new();
            for &to in &chart.transitions[t].to {
                match state[to] {
                    0 => {
                        col[to] = if first { tcol[t] } else { next_col_take(&mut next_col) };
                        first = false;
                        state[to] = 1;
                        pushed.push(to);
                    }
                    1 => {
                        back.insert((t, to));
                    }
                    _ => {}
                }
            }
            for to in pushed.into_iter().rev() {
                stack.push((to, 0));
            }
        }
    }
    // Rows: longest path over the forward connections.
    let mut indeg = vec![0usize; n];
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (t, tr) in chart.transitions.iter().enumerate() {
        for &to in &tr.to {
            if back.contains(&(t, to)) {
                continue;
            }
            for &from in &tr.from {
                succ[from].push(to);
                indeg[to] += 1;
            }
        }
    }
    let mut row = vec![0usize; n];
    let mut queue: std::collections::VecDeque<usize> = (0..n).filter(|&s| indeg[s] == 0).collect();
    while let Some(s) = queue.pop_front() {
        for &to in &succ[s] {
            row[to] = row[to].max(row[s] + 1);
            indeg[to] -= 1;
            if indeg[to] == 0 {
                queue.push_back(to);
            }
        }
    }
    // One step per cell.
    let mut taken: HashSet<(usize, usize)> = HashSet::new();
    for s in 0..n {
        if !taken.insert((col[s], row[s])) {
            col[s] = next_col_take(&mut next_col);
            taken.insert((col[s], row[s]));
        }
    }
    let trow: Vec<usize> =
        chart.transitions.iter().map(|t| t.from.iter().map(|&s| row[s]).max().unwrap_or(0)).collect();
    let mut ttaken: HashSet<(usize, usize)> = HashSet::new();
    for t in 0..chart.transitions.len() {
        if tcol[t] == usize::MAX {
            tcol[t] = chart.transitions[t].from.first().map(|&s| col[s]).unwrap_or(0);
        }
        if !ttaken.insert((tcol[t], trow[t])) {
            tcol[t] = next_col_take(&mut next_col);
            ttaken.insert((tcol[t], trow[t]));
        }
    }
    let max_w = chart.steps.iter().map(|s| step_width(&s.name)).fold(60.0, f64::max);
    let max_ab = chart
        .steps
        .iter()
        .filter(|s| !s.associations.is_empty())
        .map(|s| action_block_width(&s.associations) + 30.0)
        .fold(0.0, f64::max);
    let col_w = (max_w + max_ab + 40.0).round();
    let cx = |c: usize| 40.0 + c as f64 * col_w + max_w / 2.0;
    let steps: Vec<Geo> = chart
        .steps
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let w = step_width(&s.name);
            Geo { x: (cx(col[i]) - w / 2.0).round(), y: 40.0 + row[i] as f64 * ROW_H, w, h: STEP_H }
        })
        .collect();
    let trans: Vec<Geo> = (0..chart.transitions.len())
        .map(|t| Geo {
            x: (cx(tcol[t]) - TRANS_W / 2.0).round(),
            y: 40.0 + trow[t] as f64 * ROW_H + STEP_H + 35.0,
            w: TRANS_W,
            h: TRANS_H,
        })
        .collect();
    let targets = chart
        .transitions
        .iter()
        .enumerate()
        .map(|(t, tr)| {
            let mut j = 0.0;
            tr.to
                .iter()
                .map(|&to| {
                    if back.contains(&(t, to)) {
                        let g = trans[t];
                        let at = (g.x + g.w / 2.0 - JUMP_W / 2.0 + j * 40.0, g.y + g.h + 25.0);
                        j += 1.0;
                        Target::Jump(at)
                    } else {
                        Target::Wire
                    }
                })
                .collect()
        })
        .collect();
    (steps, trans, targets)
}

fn next_col_take(next: &mut usize) -> usize {
    *next += 1;
    *next - 1
}

fn round(v: f64) -> f64 {
    v.round()
}

/// Builds every graphical element of the chart.
/// The connections into the input pin at `top`: the wires `ps` themselves, or, when several
/// meet there, one selection convergence just above `top` that gathers them.
fn converge(els: &mut Vec<El>, new_id: &mut impl FnMut() -> u64, ps: Vec<P>, top: Pt) -> Vec<P> {
    if ps.len() <= 1 {
        return ps;
    }
    let max_y = ps.iter().map(|p| p.at.1).fold(f64::NEG_INFINITY, f64::max);
    let y = round(top.1 - ((top.1 - max_y) / 2.0).max(1.0));
    let xs: Vec<f64> = ps.iter().map(|p| p.at.0).chain([top.0]).collect();
    let x0 = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let x1 = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let id = new_id();
    els.push(El {
        id,
        kind: Kind::SelConv,
        geo: Geo { x: x0, y, w: x1 - x0, h: 1.0 },
        ins: ps.iter().map(|p| In { at: (p.at.0, y), conns: vec![*p] }).collect(),
        outs: vec![(top.0, y + 1.0)],
    });
    vec![P { id, at: (top.0, y + 1.0) }]
}

fn build(chart: &Chart, pou_attrs: &[ast::Attribute]) -> Vec<El> {
    let (sg, tg, targets, stored) = geometry(chart);
    let ns = chart.steps.len();
    let nt = chart.transitions.len();
    let mut els: Vec<El> = Vec::new();
    let mut next_id = (ns + nt) as u64 + 1;
    let mut new_id = || {
        next_id += 1;
        next_id - 1
    };
    for (i, g) in sg.iter().enumerate() {
        els.push(El { id: i as u64 + 1, kind: Kind::Step(i), geo: *g, ins: Vec::new(), outs: Vec::new() });
    }
    for (i, g) in tg.iter().enumerate() {
        els.push(El { id: (ns + i) as u64 + 1, kind: Kind::Trans(i), geo: *g, ins: Vec::new(), outs: Vec::new() });
    }
    let step_id = |s: usize| s as u64 + 1;
    let trans_id = |t: usize| (ns + t) as u64 + 1;
    let adj = chart.adjacency();

    // Simultaneous convergences (before the divergences that feed them).
    let mut simconv: HashMap<usize, usize> = HashMap::new(); // transition -> element index
    for (t, tr) in chart.transitions.iter().enumerate() {
        if tr.from.len() > 1 {
            let y = tg[t].y - 13.0;
            let xs: Vec<f64> = tr.from.iter().map(|&s| sg[s].bottom().0).chain([tg[t].top().0]).collect();
            let x0 = xs.iter().copied().fold(f64::INFINITY, f64::min);
            let x1 = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let id = new_id();
            els.push(El {
                id,
                kind: Kind::SimConv,
                geo: Geo { x: x0, y, w: x1 - x0, h: 3.0 },
                ins: tr.from.iter().map(|&s| In { at: (sg[s].bottom().0, y), conns: Vec::new() }).collect(),
                outs: vec![(tg[t].top().0, y + 3.0)],
            });
            simconv.insert(t, els.len() - 1);
        }
    }
    // Where transition t takes its input from step s: its x and y.
    let consumer_of = |t: usize, s: usize, els: &[El]| -> Pt {
        match simconv.get(&t) {
            Some(&c) => (sg[s].bottom().0, els[c].geo.y),
            None => tg[t].top(),
        }
    };
    // Selection divergences.
    let mut seldiv: HashMap<usize, usize> = HashMap::new(); // step -> element index
    for (s, out) in adj.outgoing.iter().enumerate() {
        if out.len() > 1 {
            let p = sg[s].bottom();
            let cons: Vec<Pt> = out.iter().map(|&t| consumer_of(t, s, &els)).collect();
            let min_y = cons.iter().map(|c| c.1).fold(f64::INFINITY, f64::min);
            let y = round(p.1 + ((min_y - p.1) / 2.0).max(1.0));
            let xs: Vec<f64> = cons.iter().map(|c| c.0).chain([p.0]).collect();
            let x0 = xs.iter().copied().fold(f64::INFINITY, f64::min);
            let x1 = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            // The k-th alternative in declaration order hangs on the k-th output from the left,
            // whatever the positions of the transitions: an import orders alternatives by these
            // outputs, so the declaration order survives a layout that contradicts it.
            let mut sorted: Vec<f64> = cons.iter().map(|c| c.0).collect();
            sorted.sort_by(f64::total_cmp);
            let id = new_id();
            els.push(El {
                id,
                kind: Kind::SelDiv,
                geo: Geo { x: x0, y, w: x1 - x0, h: 1.0 },
                ins: vec![In { at: (p.0, y), conns: vec![P { id: step_id(s), at: p }] }],
                outs: sorted.iter().map(|&x| (x, y + 1.0)).collect(),
            });
            seldiv.insert(s, els.len() - 1);
        }
    }
    let producer_of_step = |s: usize, t: usize, els: &[El]| -> P {
        match seldiv.get(&s) {
            Some(&d) => {
                let k = adj.outgoing[s].iter().position(|&x| x == t).unwrap_or(0);
                P { id: els[d].id, at: els[d].outs.get(k).copied().unwrap_or(els[d].geo.top()) }
            }
            None => P { id: step_id(s), at: sg[s].bottom() },
        }
    };
    // Transition inputs.
    for (t, tr) in chart.transitions.iter().enumerate() {
        match simconv.get(&t) {
            Some(&c) => {
                for (k, &s) in tr.from.iter().enumerate() {
                    let p = producer_of_step(s, t, &els);
                    if let Some(i) = els[c].ins.get_mut(k) {
                        i.conns.push(p);
                    }
                }
                let out = els[c].outs[0];
                let cid = els[c].id;
                els[ns + t].ins.push(In { at: tg[t].top(), conns: vec![P { id: cid, at: out }] });
            }
            None => {
                let p = match tr.from.first() {
                    Some(&s) => vec![producer_of_step(s, t, &els)],
                    None => Vec::new(),
                };
                els[ns + t].ins.push(In { at: tg[t].top(), conns: p });
            }
        }
    }
    // Transition outputs: simultaneous divergences, jumps, wires into steps.
    let mut incoming: Vec<Vec<P>> = vec![Vec::new(); ns];
    let mut jump_groups: Vec<(String, Pt, Vec<P>)> = Vec::new();
    for (t, tr) in chart.transitions.iter().enumerate() {
        let tgt = &targets[t];
        let xs: Vec<f64> = tr
            .to
            .iter()
            .zip(tgt.iter())
            .map(|(&s, k)| match k {
                Target::Wire => sg[s].top().0,
                Target::Jump(at) => at.0 + JUMP_W / 2.0,
            })
            .collect();
        let producers: Vec<P> = if tr.to.len() > 1 {
            let y = tg[t].bottom().1 + 10.0;
            // As for selection divergences: the k-th step of the list on the k-th output from the
            // left, so an import keeps the order of the list; outputs are kept apart (steps drawn
            // one above the other would otherwise share an output).
            let mut sorted = xs.clone();
            sorted.sort_by(f64::total_cmp);
            for k in 1..sorted.len() {
                if sorted[k] < sorted[k - 1] + 10.0 {
                    sorted[k] = sorted[k - 1] + 10.0;
                }
            }
            let all: Vec<f64> = sorted.iter().copied().chain([tg[t].bottom().0]).collect();
            let x0 = all.iter().copied().fold(f64::INFINITY, f64::min);
            let x1 = all.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let id = new_id();
            els.push(El {
                id,
                kind: Kind::SimDiv,
                geo: Geo { x: x0, y, w: x1 - x0, h: 3.0 },
                ins: vec![In { at: (tg[t].bottom().0, y), conns: vec![P { id: trans_id(t), at: tg[t].bottom() }] }],
                outs: sorted.iter().map(|&x| (x, y + 3.0)).collect(),
            });
            sorted.iter().map(|&x| P { id, at: (x, y + 3.0) }).collect()
        } else {
            vec![P { id: trans_id(t), at: tg[t].bottom() }; tr.to.len()]
        };
        for ((&s, k), p) in tr.to.iter().zip(tgt.iter()).zip(producers) {
            match k {
                Target::Wire => incoming[s].push(p),
                Target::Jump(at) => {
                    let name = chart.steps[s].name.clone();
                    let same = |g: &(String, Pt, Vec<P>)| stored && g.0.eq_ignore_ascii_case(&name) && g.1 == *at;
                    match jump_groups.iter_mut().find(|g| same(g)) {
                        Some(g) => g.2.push(p),
                        None => jump_groups.push((name, *at, vec![p])),
                    }
                }
            }
        }
    }
    // Step inputs (selection convergences where several wires meet).
    for s in 0..ns {
        let ps = std::mem::take(&mut incoming[s]);
        let top = sg[s].top();
        if !ps.is_empty() {
            let conns = converge(&mut els, &mut new_id, ps, top);
            els[s].ins.push(In { at: top, conns });
        }
    }
    // Jumps (several transitions jumping from one place share a convergence).
    for (name, at, ps) in jump_groups {
        let geo = Geo { x: at.0, y: at.1, w: JUMP_W, h: JUMP_H };
        let top = geo.top();
        let input = converge(&mut els, &mut new_id, ps, top);
        let id = new_id();
        els.push(El { id, kind: Kind::Jump(name), geo, ins: vec![In { at: top, conns: input }], outs: Vec::new() });
    }
    // Action blocks.
    for (s, step) in chart.steps.iter().enumerate() {
        let n = step.associations.len();
        if n == 0 {
            continue;
        }
        let mut blocks: Vec<(Geo, usize)> = if stored {
            parse_blocks(attrs::get(&step.attributes, attrs::ACTIONBLOCK).unwrap_or(""))
        } else {
            Vec::new()
        };
        // Associations added since the blocks were recorded go into the last block.
        let before_last: usize = blocks.iter().rev().skip(1).map(|b| b.1).sum();
        if let Some(last) = blocks.last_mut() {
            if before_last < n {
                last.1 = n - before_last;
            }
        }
        let counted: usize = blocks.iter().map(|b| b.1).sum();
        if blocks.is_empty() || counted != n {
            let g = sg[s];
            blocks = vec![(
                Geo {
                    x: g.x + g.w + 30.0,
                    y: g.y,
                    w: action_block_width(&step.associations),
                    h: ACTION_ROW_H * n as f64,
                },
                n,
            )];
        }
        let mut from = 0;
        for (geo, count) in blocks {
            let id = new_id();
            let pin = (geo.x, geo.y + 15.0);
            els.push(El {
                id,
                kind: Kind::Actions(s, from..from + count),
                geo,
                ins: vec![In { at: pin, conns: vec![P { id: step_id(s), at: sg[s].right() }] }],
                outs: Vec::new(),
            });
            from += count;
        }
    }
    // Comment boxes kept on the POU.
    for c in attrs::all(pou_attrs, attrs::COMMENT) {
        let v = attrs::unescape(c);
        let (head, text) = v.split_once('\n').unwrap_or((v.as_str(), ""));
        let n: Vec<f64> = head.split_whitespace().filter_map(|p| p.parse().ok()).collect();
        if n.len() == 4 {
            let id = new_id();
            els.push(El {
                id,
                kind: Kind::Comment(text.to_string()),
                geo: Geo { x: n[0], y: n[1], w: n[2], h: n[3] },
                ins: Vec::new(),
                outs: Vec::new(),
            });
        }
    }
    // Transitions left unconnected while drawing, wired to the steps they were wired to.
    let right = els.iter().map(|e| e.geo.x + e.geo.w).fold(0.0, f64::max);
    for (k, v) in attrs::all(pou_attrs, attrs::LOOSE).enumerate() {
        let Some(l) = attrs::Loose::read(&attrs::unescape(v)) else { continue };
        let [x, y, w, h] = l.rect.unwrap_or([round(right + 60.0), 40.0 + 60.0 * k as f64, TRANS_W, TRANS_H]);
        let geo = Geo { x, y, w, h };
        let id = new_id();
        let from: Vec<P> =
            l.from.iter().filter_map(|n| chart.step(n)).map(|s| P { id: step_id(s), at: sg[s].bottom() }).collect();
        let ins = if from.is_empty() { Vec::new() } else { vec![In { at: geo.top(), conns: from }] };
        for s in l.to.iter().filter_map(|n| chart.step(n)) {
            let p = P { id, at: geo.bottom() };
            match els[s].ins.first_mut() {
                Some(i) => i.conns.push(p),
                None => els[s].ins.push(In { at: sg[s].top(), conns: vec![p] }),
            }
        }
        els.push(El { id, kind: Kind::Loose(l), geo, ins, outs: Vec::new() });
    }
    els
}

fn num(v: f64) -> String {
    attrs::fmt_num(v)
}

/// A wire from a consumer pin to a producer pin, orthogonal.
fn wire(c: Pt, p: Pt, horizontal: bool) -> Vec<Pt> {
    if c.0 == p.0 || c.1 == p.1 {
        return vec![c, p];
    }
    if horizontal {
        let mx = ((c.0 + p.0) / 2.0).round();
        vec![c, (mx, c.1), (mx, p.1), p]
    } else {
        let my = ((c.1 + p.1) / 2.0).round();
        vec![c, (c.0, my), (p.0, my), p]
    }
}

fn write_in(x: &mut X, el: &El, i: &In, horizontal: bool) {
    x.open("connectionPointIn", &[]);
    x.position("relPosition", i.at.0 - el.geo.x, i.at.1 - el.geo.y);
    for c in &i.conns {
        x.open("connection", &[("refLocalId", c.id.to_string())]);
        for pt in wire(i.at, c.at, horizontal) {
            x.position("position", pt.0, pt.1);
        }
        x.close("connection");
    }
    x.close("connectionPointIn");
}

fn write_out(x: &mut X, name: &str, el: &El, at: Pt, formal: bool) {
    let a: Vec<(&str, String)> = if formal { vec![("formalParameter", String::new())] } else { Vec::new() };
    x.open(name, &a);
    x.position("relPosition", at.0 - el.geo.x, at.1 - el.geo.y);
    x.close(name);
}

fn size_attrs(el: &El) -> Vec<(&'static str, String)> {
    vec![("localId", el.id.to_string()), ("height", num(el.geo.h)), ("width", num(el.geo.w))]
}

/// The body text of an action: between `ACTION name:` and `END_ACTION`.
fn action_text(src: &str, a: &sfc_model::ActionNode) -> String {
    action_body_text(src, a.name_span, a.span)
}

/// The body of `ACTION name: … END_ACTION` spanning `span`, the name at `name`, as written.
pub(super) fn action_body_text(src: &str, name: Span, span: Span) -> String {
    let after_name = name.end as usize;
    let start = src
        .get(after_name..span.end as usize)
        .and_then(|r| r.find(':'))
        .map(|i| after_name + i + 1)
        .unwrap_or(after_name);
    let kw = "END_ACTION";
    let end = (span.end as usize).saturating_sub(kw.len());
    let end = if src.get(end..span.end as usize).is_some_and(|t| t.eq_ignore_ascii_case(kw)) {
        end
    } else {
        span.end as usize
    };
    dedent(slice(src, Span::new(0, start as u32, end.max(start) as u32)), 0)
}

/// The step's attributes with its step actions written into its kept addData, as CODESYS
/// writes them: properties by GUID in the step's `sfc/element` data (made when there is none).
fn with_step_actions<'a>(list: &'a [ast::Attribute], step_actions: &[ast::StepAction]) -> Cow<'a, [ast::Attribute]> {
    if step_actions.is_empty() {
        return Cow::Borrowed(list);
    }
    let mut props = String::new();
    for a in step_actions {
        let guid = STEP_ACTION_GUIDS.iter().find(|(_, k)| *k == a.kind).map(|(g, _)| *g).unwrap_or_default();
        props.push_str(&format!("<attribute guid=\"{guid}\">{}</attribute>", crate::xml::escape_text(&a.name())));
    }
    let mut foreign: String = attrs::all(list, attrs::ADDDATA).map(attrs::unescape).collect();
    let open = format!("<data name=\"{CODESYS_SFC_ELEMENT}\"");
    let at = foreign.find(&open).and_then(|d| {
        let rel = foreign[d..].find("<attributes")?;
        let end = foreign[d + rel..].find('>')?;
        Some(d + rel + end + 1).filter(|&i| !foreign[..i].ends_with("/>"))
    });
    match at {
        Some(i) => foreign.insert_str(i, &props),
        None => foreign.push_str(&format!(
            "<data name=\"{CODESYS_SFC_ELEMENT}\" handleUnknown=\"implementation\"><attributes xmlns=\"\">{props}</attributes></data>"
        )),
    }
    let mut out: Vec<ast::Attribute> =
        list.iter().filter(|a| !a.name.eq_ignore_ascii_case(attrs::ADDDATA)).cloned().collect();
    out.push(ast::Attribute {
        name: attrs::ADDDATA.to_string(),
        value: Some(sfc_syntax::attr_value::escape(&foreign)),
        span: Default::default(),
    });
    Cow::Owned(out)
}

pub(super) fn body_lang(body: &ast::ActionBody) -> &'static str {
    match body {
        ast::ActionBody::Il(_) => "IL",
        ast::ActionBody::St(_) | ast::ActionBody::Sfc(_) => "ST",
    }
}

/// The text of a condition: the ST expression, or the IL lines.
fn condition_text(src: &str, c: &ast::Condition) -> Option<(&'static str, String)> {
    match c {
        ast::Condition::St(e) => Some(("ST", slice(src, e.span).trim().to_string())),
        ast::Condition::Il(b) => {
            let col = column_if_leading(src, b.span.start as usize);
            Some(("IL", dedent(slice(src, b.span), col)))
        }
        ast::Condition::Missing => None,
    }
}

/// Writes the `actions`, `transitions` and `body` of an SFC POU; `subs` are the charts of its
/// actions written in SFC.
pub(super) fn write_chart(x: &mut X, src: &str, pou: &ast::Pou, chart: &Chart, subs: &[&Chart]) {
    // Actions written inline in their action block: marked so, and used exactly once.
    let mut uses: HashMap<usize, usize> = HashMap::new();
    for s in &chart.steps {
        for a in &s.associations {
            if let ActionTarget::Action(id) = a.target {
                *uses.entry(id).or_insert(0) += 1;
            }
        }
    }
    let inline: HashSet<usize> = chart
        .actions
        .iter()
        .enumerate()
        .filter(|(i, a)| {
            attrs::get(&a.attributes, attrs::INLINE).is_some_and(|v| v.trim().eq_ignore_ascii_case("true"))
                && uses.get(i) == Some(&1)
                && a.body.sfc().is_none()
        })
        .map(|(i, _)| i)
        .collect();
    // An instance's action (`Motor.Stop`) is referenced by its blocks, declared in its POU.
    let listed: Vec<usize> =
        (0..chart.actions.len()).filter(|i| !inline.contains(i) && !chart.actions[*i].of_instance()).collect();
    if !listed.is_empty() {
        x.open("actions", &[]);
        for &i in &listed {
            let a = &chart.actions[i];
            x.open("action", &[("name", a.name.clone())]);
            match subs.iter().find(|c| a.body.sfc().is_some() && c.action.as_deref() == Some(&a.name)) {
                Some(sub) => write_sfc(x, src, sub, &a.attributes, &HashSet::new(), &HashMap::new()),
                None => {
                    x.open("body", &[]);
                    x.formatted(body_lang(&a.body), &action_text(src, a));
                    x.close("body");
                }
            }
            x.add_data(&a.attributes, &[], &[attrs::DESCRIPTION, attrs::COMMENT, attrs::LOOSE]);
            x.documentation(&a.attributes);
            x.close("action");
        }
        x.close("actions");
    }
    // Conditions by reference: the first transition naming a reference defines it; another
    // with a different condition is written inline.
    let mut refs: Vec<(String, &'static str, String)> = Vec::new();
    let mut by_ref: HashMap<usize, String> = HashMap::new();
    for (t, tr) in chart.transitions.iter().enumerate() {
        let Some(r) =
            attrs::get(&tr.attributes, attrs::REFERENCE).map(attrs::unescape).filter(|r| !r.trim().is_empty())
        else {
            continue;
        };
        let Some((lang, text)) = condition_text(src, &tr.condition) else { continue };
        match refs.iter().find(|e| e.0.eq_ignore_ascii_case(&r)) {
            Some(e) if e.1 == lang && e.2 == text => {
                by_ref.insert(t, e.0.clone());
            }
            Some(_) => {}
            None => {
                refs.push((r.clone(), lang, text));
                by_ref.insert(t, r);
            }
        }
    }
    if !refs.is_empty() {
        x.open("transitions", &[]);
        for (name, lang, text) in &refs {
            x.open("transition", &[("name", name.clone())]);
            x.open("body", &[]);
            // Beremiz compiles an ST condition body as the rest of `TRANSITION … TO …`.
            let body = if *lang == "ST" { format!(":= {text};") } else { text.clone() };
            x.formatted(lang, &body);
            x.close("body");
            x.close("transition");
        }
        x.close("transitions");
    }

    write_sfc(x, src, chart, &pou.attributes, &inline, &by_ref);
}

/// Writes the `body` of a chart (a POU's, or an action's written in SFC): `inline` are the
/// actions written in their action block, `by_ref` the conditions written by reference.
pub(super) fn write_sfc(
    x: &mut X,
    src: &str,
    chart: &Chart,
    attributes: &[ast::Attribute],
    inline: &HashSet<usize>,
    by_ref: &HashMap<usize, String>,
) {
    let els = build(chart, attributes);
    x.open("body", &[]);
    x.open("SFC", &[]);
    // Steps and transitions in declaration order of the source, the rest after them.
    let mut order: Vec<usize> = (0..els.len()).collect();
    let key = |e: &El| -> (u8, u32, u64) {
        match e.kind {
            Kind::Step(s) => (0, chart.steps[s].span.start, e.id),
            Kind::Trans(t) => (0, chart.transitions[t].span.start, e.id),
            _ => (1, 0, e.id),
        }
    };
    order.sort_by_key(|&i| key(&els[i]));
    for i in order {
        let el = &els[i];
        match &el.kind {
            Kind::Step(s) => {
                let step = &chart.steps[*s];
                let mut a = vec![("localId", el.id.to_string()), ("name", step.name.clone())];
                a.push(("initialStep", step.initial.to_string()));
                a.push(("height", num(el.geo.h)));
                a.push(("width", num(el.geo.w)));
                x.open("step", &a);
                x.position("position", el.geo.x, el.geo.y);
                for i in &el.ins {
                    write_in(x, el, i, false);
                }
                write_out(x, "connectionPointOut", el, el.geo.bottom(), true);
                if !step.associations.is_empty() {
                    write_out(x, "connectionPointOutAction", el, el.geo.right(), true);
                }
                // Positions, sizes and action blocks are written in the elements (or, for a chart
                // laid out afresh, replaced).
                let native = [attrs::X, attrs::Y, attrs::W, attrs::H, attrs::ACTIONBLOCK, attrs::DESCRIPTION];
                x.take_comments(src, step.span);
                x.add_data(&with_step_actions(&step.attributes, &step.step_actions), &[], &native);
                x.documentation(&step.attributes);
                x.close("step");
            }
            Kind::Trans(t) => {
                let tr = &chart.transitions[*t];
                let mut a = size_attrs(el);
                if let Some(p) = tr.priority {
                    a.push(("priority", p.to_string()));
                }
                x.open("transition", &a);
                x.position("position", el.geo.x, el.geo.y);
                for i in &el.ins {
                    write_in(x, el, i, false);
                }
                write_out(x, "connectionPointOut", el, el.geo.bottom(), false);
                x.open("condition", &[]);
                let mut extra: Vec<(&str, Vec<(&str, String)>)> = Vec::new();
                match by_ref.get(t) {
                    Some(r) => {
                        x.empty("reference", &[("name", r.clone())]);
                        if tr.named {
                            extra.push(("name", vec![("value", tr.name.clone())]));
                        }
                    }
                    None => {
                        let name = if tr.named { tr.name.clone() } else { String::new() };
                        x.open("inline", &[("name", name)]);
                        match condition_text(src, &tr.condition) {
                            Some((lang, text)) => x.formatted(lang, &text),
                            None => x.formatted("ST", "FALSE"),
                        }
                        x.close("inline");
                    }
                }
                x.close("condition");
                let mut native = vec![attrs::X, attrs::Y, attrs::W, attrs::H, attrs::JUMP, attrs::DESCRIPTION];
                if by_ref.contains_key(t) {
                    native.push(attrs::REFERENCE);
                }
                x.take_comments(src, tr.span);
                x.add_data(&tr.attributes, &extra, &native);
                x.documentation(&tr.attributes);
                x.close("transition");
            }
            Kind::Loose(l) => {
                x.open("transition", &size_attrs(el));
                x.position("position", el.geo.x, el.geo.y);
                for i in &el.ins {
                    write_in(x, el, i, false);
                }
                write_out(x, "connectionPointOut", el, el.geo.bottom(), false);
                x.open("condition", &[]);
                x.open("inline", &[("name", l.name.clone())]);
                x.formatted("ST", &l.condition);
                x.close("inline");
                x.close("condition");
                x.close("transition");
            }
            Kind::SelDiv | Kind::SimDiv => {
                let name =
                    if matches!(el.kind, Kind::SelDiv) { "selectionDivergence" } else { "simultaneousDivergence" };
                x.open(name, &size_attrs(el));
                x.position("position", el.geo.x, el.geo.y);
                for i in &el.ins {
                    write_in(x, el, i, false);
                }
                for o in &el.outs {
                    write_out(x, "connectionPointOut", el, *o, true);
                }
                x.close(name);
            }
            Kind::SelConv | Kind::SimConv => {
                let name =
                    if matches!(el.kind, Kind::SelConv) { "selectionConvergence" } else { "simultaneousConvergence" };
                x.open(name, &size_attrs(el));
                x.position("position", el.geo.x, el.geo.y);
                for i in &el.ins {
                    write_in(x, el, i, false);
                }
                for o in &el.outs {
                    write_out(x, "connectionPointOut", el, *o, false);
                }
                x.close(name);
            }
            Kind::Jump(target) => {
                let mut a = size_attrs(el);
                a.insert(1, ("targetName", target.clone()));
                x.open("jumpStep", &a);
                x.position("position", el.geo.x, el.geo.y);
                for i in &el.ins {
                    write_in(x, el, i, false);
                }
                x.close("jumpStep");
            }
            Kind::Actions(s, range) => {
                let step = &chart.steps[*s];
                x.open(
                    "actionBlock",
                    &[("localId", el.id.to_string()), ("width", num(el.geo.w)), ("height", num(el.geo.h))],
                );
                x.position("position", el.geo.x, el.geo.y);
                for i in &el.ins {
                    write_in(x, el, i, true);
                }
                let n = range.len().max(1) as f64;
                for (k, a) in step.associations[range.clone()].iter().enumerate() {
                    let mut at: Vec<(&str, String)> = vec![("localId", "0".into())];
                    at.push(("qualifier", a.qualifier.name().to_string()));
                    if let Some(d) = &a.duration {
                        at.push(("duration", duration_text(d)));
                    }
                    if let Some(ind) = a.indicators.first() {
                        at.push(("indicator", ind.clone()));
                    }
                    x.open("action", &at);
                    x.position("relPosition", 0.0, (el.geo.h / n * k as f64).round());
                    match a.target {
                        ActionTarget::Action(id) if inline.contains(&id) => {
                            let act = &chart.actions[id];
                            x.open("inline", &[]);
                            x.formatted(body_lang(&act.body), &action_text(src, act));
                            x.close("inline");
                            x.add_data(&act.attributes, &[], &[attrs::INLINE, attrs::DESCRIPTION]);
                            if let Some(d) = description(&act.attributes) {
                                x.formatted("documentation", &d);
                            }
                        }
                        _ => x.empty("reference", &[("name", a.action.clone())]),
                    }
                    x.close("action");
                }
                x.close("actionBlock");
            }
            Kind::Comment(text) => {
                x.open("comment", &size_attrs(el));
                x.position("position", el.geo.x, el.geo.y);
                x.formatted("content", text);
                x.close("comment");
            }
        }
    }
    x.close("SFC");
    x.close("body");
}
