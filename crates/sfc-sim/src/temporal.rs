//! The interval expectations of scenario files, checked scan by scan: `always` and `never`
//! over `[time, to]`, `within` deadlines (from the entry's scan, or from each rising edge of
//! `after`), and forbidden runtime events (`forbid`, top-level or over an interval).
//!
//! Each reports its first violation with the scan, and how many more there were, so a broken
//! invariant over an hour gives one line, not 360,000.

use crate::scenario::{holding, mismatch, EventKind, Expectation, Scenario};
use crate::{format_time, Event, ScanRecord, Simulation};
use std::collections::HashSet;

/// The first violation of one check and how many there were.
#[derive(Debug, Default)]
struct Violations {
    first: Option<(u64, String)>,
    count: u64,
}

impl Violations {
    fn add(&mut self, scan: u64, text: impl FnOnce() -> String) {
        if self.first.is_none() {
            self.first = Some((scan, text()));
        }
        self.count += 1;
    }
    /// The first violation, with `(and N more …)`: `what` is the singular and plural noun.
    fn report(self, what: (&str, &str)) -> Option<(u64, String)> {
        let (scan, text) = self.first?;
        let more = match self.count {
            0 | 1 => String::new(),
            2 => format!(" (and 1 more {})", what.0),
            n => format!(" (and {} more {})", n - 1, what.1),
        };
        Some((scan, format!("{text}{more}")))
    }
}

/// A `within` obligation: from `trigger`, `expect` must hold by scan `deadline`.
#[derive(Debug, Clone, Copy)]
struct Pending {
    trigger: u64,
    deadline: u64,
}

#[derive(Debug)]
struct EntryWatch {
    index: usize,
    /// First and last scan of the interval (`u64::MAX`: the end of the run).
    start: u64,
    end: u64,
    always: Violations,
    never: Violations,
    /// Per kind of forbidden event, in the order of [`EventKind::ALL`].
    forbid: [Violations; 5],
    /// `within`: scans allowed after a trigger.
    slack: Option<u64>,
    after_before: bool,
    pending: Vec<Pending>,
    missed: Violations,
}

/// The interval checks of one run.
pub(crate) struct Watch<'s> {
    s: &'s Scenario,
    entries: Vec<EntryWatch>,
    /// Top-level `forbid`, per kind.
    forbid: [Violations; 5],
    /// Steps overdue after the previous scan (only followed when some `forbid` names it).
    overdue: Option<HashSet<String>>,
}

impl<'s> Watch<'s> {
    pub(crate) fn new(s: &'s Scenario) -> Watch<'s> {
        let period = s.options.period.max(1);
        let entries: Vec<EntryWatch> = s
            .entries
            .iter()
            .enumerate()
            .filter(|(_, e)| e.is_temporal())
            .map(|(index, e)| EntryWatch {
                index,
                start: s.scan_of(e.time),
                end: e.to.map_or(u64::MAX, |t| s.scan_at_or_before(t)),
                always: Violations::default(),
                never: Violations::default(),
                forbid: Default::default(),
                slack: e.within.map(|w| (w / period) as u64),
                after_before: false,
                pending: Vec::new(),
                missed: Violations::default(),
            })
            .collect();
        let wants_overdue =
            s.forbid.contains(&EventKind::Overdue) || s.entries.iter().any(|e| e.forbid.contains(&EventKind::Overdue));
        Watch { s, entries, forbid: Default::default(), overdue: wants_overdue.then(HashSet::new) }
    }

    /// Nothing to check: no interval entry and no top-level `forbid` (scans need no record).
    pub(crate) fn is_idle(&self) -> bool {
        self.entries.is_empty() && self.s.forbid.is_empty()
    }

    fn here(&self, index: usize) -> String {
        match self.s.entries.get(index) {
            Some(e) if e.line > 0 => format!("{}:{}", self.s.name, e.line),
            _ => self.s.name.clone(),
        }
    }

    fn interval(&self, w: &EntryWatch) -> String {
        let period = self.s.options.period;
        let from = format_time(w.start as i64 * period);
        match self.s.entries.get(w.index).and_then(|e| e.to) {
            Some(to) => format!("from {from} to {}", format_time(to)),
            None => format!("from {from} to the end"),
        }
    }

    /// Checks the scan just run.
    pub(crate) fn after_scan(&mut self, sim: &Simulation, rec: &ScanRecord) {
        if self.entries.is_empty() && self.s.forbid.is_empty() {
            return;
        }
        let k = rec.scan;
        let at = format!("at {} (scan {k})", format_time(rec.time));
        // Runtime events of this scan, with the overdue steps new since the previous scan.
        let mut events: Vec<(EventKind, String)> = rec
            .events
            .iter()
            .map(|e| {
                let kind = match e {
                    Event::Conflict { .. } => EventKind::Conflict,
                    Event::Unsafe { .. } => EventKind::Unsafe,
                    Event::Contention { .. } => EventKind::Contention,
                    Event::Error(_) => EventKind::Error,
                };
                (kind, e.describe())
            })
            .collect();
        if let Some(seen) = &mut self.overdue {
            let now: HashSet<String> = sim.overdue_steps().into_iter().collect();
            for step in now.difference(seen) {
                events.push((EventKind::Overdue, format!("step {step} is active longer than its timeout")));
            }
            *seen = now;
        }
        for (kind, text) in &events {
            if let (true, Some(v)) = (self.s.forbid.contains(kind), self.forbid.get_mut(kind_index(*kind))) {
                v.add(k, || {
                    let where_ = if self.s.forbid_line > 0 {
                        format!("{}:{}", self.s.name, self.s.forbid_line)
                    } else {
                        self.s.name.clone()
                    };
                    format!("{where_}: {at}: forbidden event `{}`: {text}", kind.name())
                });
            }
        }
        for i in 0..self.entries.len() {
            let Some(w) = self.entries.get(i) else { continue };
            let Some(e) = self.s.entries.get(w.index) else { continue };
            let (here, interval) = (self.here(w.index), self.interval(w));
            let inside = w.start <= k && k <= w.end;
            let Some(w) = self.entries.get_mut(i) else { continue };
            if inside {
                if let Some(m) = e.always.iter().find_map(|x| mismatch(sim, x)) {
                    w.always.add(k, || format!("{here}: always {interval}: {at}: {m}"));
                }
                if !e.never.is_empty() && e.never.iter().all(|x| mismatch(sim, x).is_none()) {
                    w.never.add(k, || format!("{here}: never {interval}: {at}: {}", holding(sim, &e.never)));
                }
                for (kind, text) in &events {
                    if let (true, Some(v)) = (e.forbid.contains(kind), w.forbid.get_mut(kind_index(*kind))) {
                        v.add(k, || format!("{here}: {at}: forbidden event `{}` {interval}: {text}", kind.name()));
                    }
                }
            }
            let Some(slack) = w.slack else { continue };
            // Triggers: the entry's scan, or each rising edge of `after` inside the interval.
            if e.after.is_empty() {
                if k == w.start {
                    w.pending.push(Pending { trigger: k, deadline: k.saturating_add(slack) });
                }
            } else {
                let now = e.after.iter().all(|x| mismatch(sim, x).is_none());
                if now && !w.after_before && inside {
                    w.pending.push(Pending { trigger: k, deadline: k.saturating_add(slack) });
                }
                w.after_before = now;
            }
            if w.pending.is_empty() {
                continue;
            }
            let failing = e.expect.iter().find_map(|x| mismatch(sim, x));
            match failing {
                // `expect` holds: every pending obligation is met (the trigger scan included).
                None => w.pending.clear(),
                Some(m) => {
                    let within = e.within.map_or_else(String::new, format_time);
                    let period = self.s.options.period;
                    let trigger_text = |p: &Pending| {
                        let t = format_time(p.trigger as i64 * period);
                        if e.after.is_empty() {
                            format!("{t} (scan {})", p.trigger)
                        } else {
                            format!("{t} (scan {}, when {} became TRUE)", p.trigger, describe(&e.after))
                        }
                    };
                    let mut still = Vec::with_capacity(w.pending.len());
                    for p in w.pending.drain(..) {
                        if k >= p.deadline {
                            let text =
                                format!("{here}: within {within} after {}: {at}, the deadline: {m}", trigger_text(&p));
                            w.missed.add(p.trigger, || text);
                        } else {
                            still.push(p);
                        }
                    }
                    w.pending = still;
                }
            }
        }
    }

    /// The failures, each with its scan; `end` says how the run ended, for checks it cut short.
    pub(crate) fn finish(self, scans: u64, end: &str) -> Vec<(u64, String)> {
        let mut out = Vec::new();
        for (v, kind) in self.forbid.into_iter().zip(EventKind::ALL) {
            out.extend(v.report((&format!("`{}` event", kind.name()), &format!("`{}` events", kind.name()))));
        }
        let period = self.s.options.period;
        let last = scans.checked_sub(1);
        for w in self.entries {
            let here = match self.s.entries.get(w.index) {
                Some(e) if e.line > 0 => format!("{}:{}", self.s.name, e.line),
                _ => self.s.name.clone(),
            };
            let interval = {
                let from = format_time(w.start as i64 * period);
                match self.s.entries.get(w.index).and_then(|e| e.to) {
                    Some(to) => format!("from {from} to {}", format_time(to)),
                    None => format!("from {from} to the end"),
                }
            };
            let has = |e: &crate::scenario::Entry| !e.always.is_empty() || !e.never.is_empty() || !e.forbid.is_empty();
            let Some(e) = self.s.entries.get(w.index) else { continue };
            // An interval the run did not cover completely was not checked completely.
            if has(e) && (last.is_none_or(|l| l < w.start) || (w.end != u64::MAX && last.is_none_or(|l| l < w.end))) {
                out.push((w.start, format!("{here}: interval {interval} never reached completely: {end}")));
            }
            out.extend(w.always.report(("scan", "scans")));
            out.extend(w.never.report(("scan", "scans")));
            for (v, kind) in w.forbid.into_iter().zip(EventKind::ALL) {
                out.extend(v.report((&format!("`{}` event", kind.name()), &format!("`{}` events", kind.name()))));
            }
            out.extend(w.missed.report(("missed deadline", "missed deadlines")));
            let within = e.within.map_or_else(String::new, format_time);
            if let Some(p) = w.pending.first() {
                let what = if e.after.is_empty() {
                    format!("{} (scan {})", format_time(p.trigger as i64 * period), p.trigger)
                } else {
                    format!(
                        "{} became TRUE at {} (scan {})",
                        describe(&e.after),
                        format_time(p.trigger as i64 * period),
                        p.trigger
                    )
                };
                out.push((
                    p.trigger,
                    format!(
                        "{here}: within {within} after {what}: not met before the run ended, deadline {} (scan {}): {end}",
                        format_time(p.deadline as i64 * period),
                        p.deadline
                    ),
                ));
            } else if e.within.is_some() && e.after.is_empty() && last.is_none_or(|l| l < w.start) {
                out.push((
                    w.start,
                    format!("{here}: within {within} after {}: expectation never reached: {end}", format_time(e.time)),
                ));
            }
        }
        out
    }
}

fn kind_index(kind: EventKind) -> usize {
    EventKind::ALL.iter().position(|k| *k == kind).unwrap_or(0)
}

/// A trigger condition as the user wrote it: `` `DoorCmd` `` or `` `Go` = true ``.
fn describe(xs: &[Expectation]) -> String {
    xs.iter()
        .map(|x| match x {
            Expectation::Active(steps) => format!("`active` = [{}]", steps.join(", ")),
            Expectation::Value { key, .. } => format!("`{key}`"),
            Expectation::Holds(c) => format!("`{}`", c.text),
            Expectation::ErrorRecord { instance, .. } => match instance {
                Some(i) => format!("`{i}.error_record`"),
                None => "`error_record`".to_string(),
            },
        })
        .collect::<Vec<_>>()
        .join(" and ")
}
