//! Explicit breadth-first search over the situations of one network.
//!
//! Situations are bit sets of `words` `u64` words stored one after another in one arena; the arena
//! is also the queue (situations are expanded in the order they were found), and an open-addressing
//! table of arena indices finds duplicates. Each situation keeps its parent and the scan that
//! reached it, so witnesses are read backwards. Expanding in discovery order and trying the scans of
//! a situation in ascending order (a single transition `[t]`, then the group scans starting with
//! `t`, then `[t + 1]`…) makes the first path found to any situation the shortest one and, among
//! those, the lexicographically smallest: the order of the queue at each depth is the order of the
//! paths that reached its situations.

use super::{groups_among, Net, Outcome, SearchMethod, MAX_LOCKUPS};

const NONE: u32 = u32::MAX;
/// Label bit marking a group scan (the rest is an index into `groups`).
const GROUP: u32 = 1 << 31;

pub(crate) struct Search<'a> {
    net: &'a Net,
    w: usize,
    pre: Vec<u64>,
    post: Vec<u64>,
    /// Per step: the transitions whose smallest preset step it is (each enabled transition is
    /// found once, from that step).
    first_of: Vec<Vec<u32>>,
    has_out: Vec<u64>,
    states: Vec<u64>,
    parent: Vec<u32>,
    label: Vec<u32>,
    /// Open addressing: `hash >> 32 << 32 | index + 1`, 0 for empty.
    table: Vec<u64>,
    groups: Vec<Vec<u32>>,
    group_ids: std::collections::HashMap<Vec<u32>, u32>,
    head: usize,
    reach: Vec<u64>,
    enabled_seen: Vec<bool>,
    conc: Vec<u64>,
    unsafe_at: Vec<Option<(u32, u32)>>,
    lockups: Vec<u32>,
    /// A component of group candidates was too large to enumerate.
    broken: bool,
}

/// A bit set's hash (words mixed, then the 64-bit finaliser of MurmurHash3).
fn hash(words: &[u64]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for &w in words {
        h = (h ^ w).wrapping_mul(0xff51_afd7_ed55_8ccd).rotate_left(29);
    }
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}

impl<'a> Search<'a> {
    pub(crate) fn new(net: &'a Net) -> Search<'a> {
        let n = net.steps.len();
        let w = n.div_ceil(64).max(1);
        let nt = net.pre.len();
        let mut pre = vec![0u64; nt * w];
        let mut post = vec![0u64; nt * w];
        let mut first_of = vec![Vec::new(); n];
        let mut has_out = vec![0u64; w];
        for t in 0..nt {
            for &s in &net.pre[t] {
                pre[t * w + s as usize / 64] |= 1 << (s % 64);
                has_out[s as usize / 64] |= 1 << (s % 64);
            }
            for &s in &net.post[t] {
                post[t * w + s as usize / 64] |= 1 << (s % 64);
            }
            if let Some(&s) = net.pre[t].first() {
                first_of[s as usize].push(t as u32);
            }
        }
        let mut init = vec![0u64; w];
        for &s in &net.initial {
            init[s as usize / 64] |= 1 << (s % 64);
        }
        let mut s = Search {
            net,
            w,
            pre,
            post,
            first_of,
            has_out,
            states: Vec::new(),
            parent: Vec::new(),
            label: Vec::new(),
            table: vec![0; 1024],
            groups: Vec::new(),
            group_ids: Default::default(),
            head: 0,
            reach: vec![0; w],
            enabled_seen: vec![false; nt],
            conc: vec![0; n * w],
            unsafe_at: vec![None; n],
            lockups: Vec::new(),
            broken: false,
        };
        s.insert(&init, NONE, 0);
        s
    }

    fn state(&self, i: usize) -> &[u64] {
        &self.states[i * self.w..(i + 1) * self.w]
    }

    /// Adds `x` unless known; returns whether it was new.
    fn insert(&mut self, x: &[u64], parent: u32, label: u32) -> bool {
        let count = self.parent.len();
        if (count + 1) * 2 > self.table.len() {
            let size = self.table.len() * 2;
            let mut table = vec![0u64; size];
            for &e in &self.table {
                if e == 0 {
                    continue;
                }
                let i = (e & 0xffff_ffff) as usize - 1;
                let mut k = hash(self.state(i)) as usize & (size - 1);
                while table[k] != 0 {
                    k = (k + 1) & (size - 1);
                }
                table[k] = e;
            }
            self.table = table;
        }
        let mask = self.table.len() - 1;
        let h = hash(x);
        let tag = h & !0xffff_ffff;
        let mut k = h as usize & mask;
        loop {
            let e = self.table[k];
            if e == 0 {
                break;
            }
            if e & !0xffff_ffff == tag && self.state((e & 0xffff_ffff) as usize - 1) == x {
                return false;
            }
            k = (k + 1) & mask;
        }
        self.table[k] = tag | (count as u64 + 1);
        self.states.extend_from_slice(x);
        self.parent.push(parent);
        self.label.push(label);
        true
    }

    /// Whether every reachable situation has been expanded.
    pub(crate) fn finished(&self) -> bool {
        self.head == self.parent.len() && !self.broken
    }

    /// Expands situations until done or until storing the next one's successors could exceed
    /// `budget` situations in all. Can be called again with a larger budget.
    pub(crate) fn run(&mut self, budget: usize) {
        let w = self.w;
        let budget = budget.min(NONE as usize - 1);
        let mut x = vec![0u64; w];
        let mut y = vec![0u64; w];
        let mut enabled: Vec<u32> = Vec::new();
        let mut capable: Vec<u32> = Vec::new();
        while self.head < self.parent.len() && !self.broken {
            let i = self.head;
            x.copy_from_slice(self.state(i));
            enabled.clear();
            for (wi, &word) in x.iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let a = wi * 64 + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    for &t in &self.first_of[a] {
                        let p = &self.pre[t as usize * w..(t as usize + 1) * w];
                        if p.iter().zip(&x).all(|(p, x)| p & !x == 0) {
                            enabled.push(t);
                        }
                    }
                }
            }
            enabled.sort_unstable();
            // Group scans: only among transitions that post into an active step outside their
            // own preset (each member of a group does).
            capable.clear();
            for &t in &enabled {
                let (p, q) = (&self.pre[t as usize * w..][..w], &self.post[t as usize * w..][..w]);
                if (0..w).any(|k| q[k] & !p[k] & x[k] != 0) {
                    capable.push(t);
                }
            }
            let groups = if capable.len() >= 2 {
                match groups_among(self.net, &capable) {
                    Some(g) => g,
                    None => {
                        self.broken = true;
                        return;
                    }
                }
            } else {
                Vec::new()
            };
            if self.parent.len() + enabled.len() + groups.len() > budget {
                return;
            }
            self.head += 1;
            for (r, &xk) in self.reach.iter_mut().zip(&x) {
                *r |= xk;
            }
            for (wi, &word) in x.iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let a = wi * 64 + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    for (c, &xk) in self.conc[a * w..(a + 1) * w].iter_mut().zip(&x) {
                        *c |= xk;
                    }
                }
            }
            if enabled.is_empty() {
                if self.lockups.len() < MAX_LOCKUPS && (0..w).any(|k| x[k] & self.has_out[k] != 0) {
                    self.lockups.push(i as u32);
                }
                continue;
            }
            let mut gi = 0;
            for &t in &enabled {
                self.enabled_seen[t as usize] = true;
                let tu = t as usize;
                for k in 0..w {
                    let (p, q) = (self.pre[tu * w + k], self.post[tu * w + k]);
                    let hit = q & !p & x[k];
                    let mut bits = hit;
                    while bits != 0 {
                        let s = k * 64 + bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        if self.unsafe_at[s].is_none() {
                            self.unsafe_at[s] = Some((i as u32, t));
                        }
                    }
                    y[k] = (x[k] & !p) | q;
                }
                self.insert(&y, i as u32, t);
                while gi < groups.len() && groups[gi][0] == t {
                    let g = &groups[gi];
                    y.copy_from_slice(&x);
                    for &m in g {
                        for (yk, p) in y.iter_mut().zip(&self.pre[m as usize * w..(m as usize + 1) * w]) {
                            *yk &= !p;
                        }
                    }
                    for &m in g {
                        for (yk, q) in y.iter_mut().zip(&self.post[m as usize * w..(m as usize + 1) * w]) {
                            *yk |= q;
                        }
                    }
                    let id = match self.group_ids.get(g) {
                        Some(&id) => id,
                        None => {
                            let id = self.groups.len() as u32;
                            self.groups.push(g.clone());
                            self.group_ids.insert(g.clone(), id);
                            id
                        }
                    };
                    self.insert(&y, i as u32, GROUP | id);
                    gi += 1;
                }
            }
        }
    }

    fn path(&self, mut i: u32) -> Vec<Vec<u32>> {
        let mut p = Vec::new();
        while self.parent[i as usize] != NONE {
            let l = self.label[i as usize];
            p.push(if l & GROUP != 0 { self.groups[(l & !GROUP) as usize].clone() } else { vec![l] });
            i = self.parent[i as usize];
        }
        p.reverse();
        p
    }

    /// What was found; complete when [`Search::finished`].
    pub(crate) fn outcome(&self) -> Outcome {
        let n = self.net.steps.len();
        let w = self.w;
        let complete = self.finished();
        let unsafe_steps = (0..n).filter_map(|s| self.unsafe_at[s].map(|(i, t)| (s as u32, self.path(i), t))).collect();
        let lockups = self
            .lockups
            .iter()
            .map(|&i| {
                let x = self.state(i as usize);
                let sit = (0..n as u32).filter(|&s| super::bit(x, s as usize)).collect();
                (sit, self.path(i))
            })
            .collect();
        Outcome {
            complete,
            method: SearchMethod::Explicit(self.parent.len()),
            reachable: (0..n).map(|s| super::bit(&self.reach, s)).collect(),
            enabled: self.enabled_seen.clone(),
            unsafe_steps,
            lockups,
            conc: Some((w, self.reach.clone(), self.conc.clone())),
        }
    }
}
