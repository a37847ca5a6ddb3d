//! What every instance of one SFC POU shares: the net in flat tables, the per-step link table of
//! the one-in/one-out fast path, and the action control plan. Built once per POU
//! ([`ChartCode::plan`]).

use crate::code::{ChartCode, DurationCode, FastGuard, Place};
use crate::value::Value;
use sfc_model::{ActionTarget, Qualifier};
use std::sync::Arc;

/// What drives an action control block: an ACTION, or a BOOL variable used as an action.
#[derive(Debug, Clone)]
pub(crate) struct Entity {
    pub(crate) name: String,
    pub(crate) action: Option<usize>,
    pub(crate) variable: Option<Place>,
    /// Associations in text order (step declaration order, then order inside the step).
    pub(crate) assocs: Vec<Assoc>,
    /// No association is timed (L, D, SD, DS, SL): the block needs no timer and no contention
    /// test, and its inputs are one OR of qualifier bits.
    pub(crate) untimed: bool,
}

#[derive(Debug, Clone)]
pub(crate) struct Assoc {
    pub(crate) step: u32,
    pub(crate) qualifier: Qualifier,
    /// `1 << qualifier_bit(qualifier)`.
    pub(crate) bit: u16,
    pub(crate) duration: Option<DurationCode>,
    /// `graph`: the association depends on its step's interlock (GRAPH's "C": the step's
    /// `sfc.s7graph.interlocked` names it).
    pub(crate) interlocked: bool,
}

/// Bit of each qualifier in an input mask of ACTION_CONTROL.
pub(crate) const fn qualifier_bit(q: Qualifier) -> u16 {
    1 << match q {
        Qualifier::N => 0,
        Qualifier::R => 1,
        Qualifier::S => 2,
        Qualifier::L => 3,
        Qualifier::D => 4,
        Qualifier::P => 5,
        Qualifier::SD => 6,
        Qualifier::DS => 7,
        Qualifier::SL => 8,
        Qualifier::P1 => 9,
        Qualifier::P0 => 10,
    }
}

/// A list per index, stored flat (compressed rows): `rows[i]` is `items[start[i]..start[i+1]]`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Rows {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Rows {
    pub(crate) fn from_lists(lists: impl Iterator<Item = Vec<u32>>) -> Rows {
        let mut rows = Rows { start: vec![0], items: Vec::new() };
        for l in lists {
            rows.items.extend(l);
            rows.start.push(rows.items.len() as u32);
        }
        rows
    }
    #[inline]
    pub(crate) fn get(&self, i: u32) -> &[u32] {
        let i = i as usize;
        &self.items[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// One transition as the general evolution sees it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TrInfo {
    /// The guard, when it can be evaluated without calling its closure.
    pub(crate) guard: FastGuard,
    /// `from` and `to` of a transition between one step and one step; `from` is `u32::MAX` for
    /// the others.
    pub(crate) from: u32,
    pub(crate) to: u32,
    /// One preceding step: enabled whenever that step is active.
    pub(crate) single_pre: bool,
    /// Leaves a step that has other outgoing transitions: only such transitions can conflict.
    pub(crate) may_conflict: bool,
}

impl TrInfo {
    #[inline(always)]
    pub(crate) fn is_link(&self) -> bool {
        self.from != u32::MAX
    }
}

/// How a link's guard is read (see [`Link`]).
pub(crate) mod guard_kind {
    /// A BOOL slot of the instance's frame (`slot` is the frame offset).
    pub(crate) const LOCAL: u8 = 0;
    /// A BOOL global slot (`slot` is absolute).
    pub(crate) const GLOBAL: u8 = 1;
    /// A constant: `slot` is 1 for TRUE.
    pub(crate) const CONST: u8 = 2;
    /// The compiled closure.
    pub(crate) const CODE: u8 = 3;
    /// The step has no link: its transitions take the general path.
    pub(crate) const NONE: u8 = 4;
}

/// The one-in/one-out fast path of a step whose only outgoing transition leads from this step
/// alone to one step: the transition, its target and its guard, in 16 bytes, so testing and
/// firing it reads one record.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Link {
    pub(crate) t: u32,
    pub(crate) to: u32,
    pub(crate) slot: u32,
    pub(crate) kind: u8,
    pub(crate) neg: bool,
}

impl Link {
    const NONE: Link = Link { t: u32::MAX, to: u32::MAX, slot: 0, kind: guard_kind::NONE, neg: false };
}

/// The net and the action control plan of one SFC POU.
#[derive(Debug)]
pub struct ChartPlan {
    pub(crate) outgoing: Rows,
    pub(crate) pre: Rows,
    pub(crate) post: Rows,
    /// What the general evolution reads of each transition, packed so one transition is one load.
    pub(crate) tr: Vec<TrInfo>,
    /// Per step: its link (one-in/one-out fast path), or a record of kind `NONE`.
    pub(crate) link: Vec<Link>,
    /// Some step has step actions (CODESYS's entry, step, exit actions).
    pub(crate) step_actions: bool,
    /// Frame offsets of the `X` and `T` slots of each step.
    pub(crate) x_slots: Vec<u32>,
    pub(crate) t_slots: Vec<u32>,
    /// The first slot of each step's dialect members (`Count`… of Logix, `U` of S7-GRAPH; empty
    /// for other charts) and which they are.
    pub(crate) vendor_slots: Vec<u32>,
    pub(crate) step_members: crate::code::StepMembers,
    /// Sort key of each transition for conflict resolution: explicit priorities first.
    pub(crate) order_key: Vec<(u8, i64, u32)>,
    pub(crate) explicit: Vec<bool>,
    pub(crate) initial: Vec<u32>,
    pub(crate) is_initial: Vec<bool>,
    pub(crate) timeouts: Vec<Option<i64>>,
    pub(crate) supervised: bool,
    /// Per step: its minimum time (`sfc.min_time`), which its outgoing transitions wait for.
    pub(crate) min_times: Vec<Option<i64>>,
    pub(crate) entities: Vec<Entity>,
    /// Entities each step associates, without repetition.
    pub(crate) step_entities: Rows,
    /// Per step: it associates an entity (its activation makes entities live).
    pub(crate) has_entities: Vec<bool>,
    /// Some step associates an entity.
    pub(crate) any_entities: bool,
    /// Entities that are BOOL variables: written with Q every scan.
    pub(crate) variable_entities: Vec<u32>,
    /// Position of each entity in the alphabetical order of the names (CODESYS body order).
    pub(crate) alpha_rank: Vec<u32>,
    pub(crate) step_names: Vec<String>,
    /// The step names as STRING values (for SFCCurrentStep and SFCErrorStep, shared, so
    /// writing them allocates nothing).
    pub(crate) step_values: Vec<Value>,
    pub(crate) transition_names: Vec<String>,
    pub(crate) action_names: Vec<String>,
    /// S7-GRAPH (`graph` profile): the permanent instructions run before and after the
    /// sequencer in every call (actions marked `sfc.s7graph.permanent` 'pre' or 'post'), in
    /// declaration order.
    pub(crate) permanent_pre: Vec<usize>,
    pub(crate) permanent_post: Vec<usize>,
    /// `graph`: S7-GRAPH's event actions (`sfc.s7graph.step` names the step,
    /// `sfc.s7graph.event` the event): `(step, event, action, interlocked)`.
    pub(crate) event_actions: Vec<(u32, GraphEvent, usize, bool)>,
}

/// An S7-GRAPH step event that runs an action once (manual 13.3, 13.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum GraphEvent {
    /// V1: a supervision error comes.
    V1,
    /// V0: it goes.
    V0,
    /// L1: the interlock stops being satisfied (or is not when the step is activated).
    L1,
    /// L0: it is satisfied again.
    L0,
    /// A1: the step's error is acknowledged.
    A1,
}

impl ChartPlan {
    pub(crate) fn new(code: &ChartCode) -> ChartPlan {
        let chart = &code.chart;
        let n = chart.steps.len();
        let dedup = |v: &[usize]| {
            let mut out: Vec<u32> = Vec::new();
            for &s in v {
                if !out.contains(&(s as u32)) {
                    out.push(s as u32);
                }
            }
            out
        };
        let mut outgoing = vec![Vec::new(); n];
        for (t, tr) in chart.transitions.iter().enumerate() {
            for s in dedup(&tr.from) {
                outgoing[s as usize].push(t as u32);
            }
        }
        let pre = Rows::from_lists(chart.transitions.iter().map(|t| dedup(&t.from)));
        let post = Rows::from_lists(chart.transitions.iter().map(|t| dedup(&t.to)));
        let order_key = chart
            .transitions
            .iter()
            .enumerate()
            .map(|(i, t)| match t.priority {
                Some(p) => (0u8, p, i as u32),
                None => (1u8, 0, i as u32),
            })
            .collect();
        let explicit = chart.transitions.iter().map(|t| t.priority.is_some()).collect();
        let mut entities: Vec<Entity> = chart
            .actions
            .iter()
            .enumerate()
            .map(|(i, a)| Entity {
                name: a.name.clone(),
                action: Some(i),
                variable: None,
                assocs: Vec::new(),
                untimed: true,
            })
            .collect();
        let mut step_entities = vec![Vec::new(); n];
        let mut variable_entities = Vec::new();
        for (s, step) in chart.steps.iter().enumerate() {
            for (k, a) in step.associations.iter().enumerate() {
                let assoc_code = code.associations.get(s).and_then(|v| v.get(k));
                let e = match a.target {
                    ActionTarget::Action(id) => id,
                    ActionTarget::Variable => {
                        let Some(place) = assoc_code.and_then(|c| c.variable) else {
                            continue;
                        };
                        match entities.iter().position(|e| e.variable == Some(place)) {
                            Some(e) => e,
                            None => {
                                entities.push(Entity {
                                    name: assoc_code
                                        .and_then(|c| c.variable_name.clone())
                                        .unwrap_or_else(|| a.action.clone()),
                                    action: None,
                                    variable: Some(place),
                                    assocs: Vec::new(),
                                    untimed: true,
                                });
                                variable_entities.push((entities.len() - 1) as u32);
                                entities.len() - 1
                            }
                        }
                    }
                };
                entities[e].untimed &= !a.qualifier.is_timed();
                let interlocked = step
                    .attributes
                    .iter()
                    .filter(|x| x.name.eq_ignore_ascii_case("sfc.s7graph.interlocked"))
                    .filter_map(|x| x.value.as_deref())
                    .any(|v| v.split(',').any(|n| n.trim().eq_ignore_ascii_case(&a.action)));
                entities[e].assocs.push(Assoc {
                    step: s as u32,
                    qualifier: a.qualifier,
                    bit: qualifier_bit(a.qualifier),
                    duration: assoc_code.and_then(|c| c.duration),
                    interlocked,
                });
                if !step_entities[s].contains(&(e as u32)) {
                    step_entities[s].push(e as u32);
                }
            }
        }
        let timeouts: Vec<Option<i64>> = chart.steps.iter().map(|s| s.timeout).collect();
        let tr: Vec<TrInfo> = (0..chart.transitions.len() as u32)
            .map(|t| {
                let (from, to) = match (pre.get(t), post.get(t)) {
                    ([from], [to]) => (*from, *to),
                    _ => (u32::MAX, 0),
                };
                TrInfo {
                    guard: code.fast[t as usize],
                    from,
                    to,
                    single_pre: pre.get(t).len() == 1,
                    may_conflict: pre.get(t).iter().any(|&s| outgoing[s as usize].len() > 1),
                }
            })
            .collect();
        let min_times: Vec<Option<i64>> = chart.steps.iter().map(|s| s.min_time.filter(|&m| m > 0)).collect();
        let link: Vec<Link> = outgoing
            .iter()
            .enumerate()
            .map(|(s, o)| match o.as_slice() {
                // A step with a minimum time takes the general path, which waits for it; so
                // does a step with an S7-GRAPH supervision, whose error holds it.
                [t] if tr[*t as usize].is_link() && min_times[s].is_none() && code.supervisions[s].is_none() => {
                    let info = tr[*t as usize];
                    let (kind, slot, neg) = match info.guard {
                        FastGuard::Local(o, neg) => (guard_kind::LOCAL, o, neg),
                        FastGuard::Global(g, neg) => (guard_kind::GLOBAL, g, neg),
                        FastGuard::Const(b) => (guard_kind::CONST, u32::from(b), false),
                        FastGuard::Code => (guard_kind::CODE, 0, false),
                    };
                    Link { t: *t, to: info.to, slot, kind, neg }
                }
                _ => Link::NONE,
            })
            .collect();
        let has_entities: Vec<bool> = step_entities.iter().map(|e| !e.is_empty()).collect();
        // The evolution's fast path indexes with these without bounds checks.
        let link: Vec<Link> = link;
        assert!(
            link.iter().all(
                |l| l.kind == guard_kind::NONE || ((l.to as usize) < n && (l.t as usize) < chart.transitions.len())
            ),
            "a link names a step or transition outside its chart"
        );
        let mut by_name: Vec<usize> = (0..entities.len()).collect();
        by_name.sort_by_cached_key(|&e| (entities[e].name.to_ascii_uppercase(), e));
        let mut alpha_rank = vec![0u32; entities.len()];
        for (rank, &e) in by_name.iter().enumerate() {
            alpha_rank[e] = rank as u32;
        }
        ChartPlan {
            step_actions: code.step_actions.iter().any(|v| !v.is_empty()),
            outgoing: Rows::from_lists(outgoing.into_iter()),
            tr,
            link,
            x_slots: code.step_x.clone(),
            t_slots: code.step_t.clone(),
            vendor_slots: code.step_vendor.clone(),
            step_members: code.step_members,
            pre,
            post,
            order_key,
            explicit,
            initial: chart.steps.iter().enumerate().filter(|(_, s)| s.initial).map(|(i, _)| i as u32).collect(),
            is_initial: chart.steps.iter().map(|s| s.initial).collect(),
            supervised: timeouts.iter().any(Option::is_some),
            min_times,
            timeouts,
            entities,
            step_entities: Rows::from_lists(step_entities.into_iter()),
            any_entities: has_entities.iter().any(|&h| h),
            has_entities,
            variable_entities,
            alpha_rank,
            step_names: chart.steps.iter().map(|s| s.name.clone()).collect(),
            step_values: chart.steps.iter().map(|s| Value::Str(Arc::from(s.name.as_str()))).collect(),
            transition_names: chart.transitions.iter().map(|t| t.name.clone()).collect(),
            action_names: chart.actions.iter().map(|a| a.name.clone()).collect(),
            permanent_pre: (0..chart.actions.len())
                .filter(|&i| attribute_is(&chart.actions[i].attributes, "sfc.s7graph.permanent", "pre"))
                .collect(),
            permanent_post: (0..chart.actions.len())
                .filter(|&i| attribute_is(&chart.actions[i].attributes, "sfc.s7graph.permanent", "post"))
                .collect(),
            event_actions: chart
                .actions
                .iter()
                .enumerate()
                .filter_map(|(i, a)| {
                    let value = |n: &str| {
                        a.attributes.iter().rev().find(|x| x.name.eq_ignore_ascii_case(n)).and_then(|x| x.value.clone())
                    };
                    let step = chart.step(value("sfc.s7graph.step")?.trim())? as u32;
                    let event = match value("sfc.s7graph.event")?.trim().to_ascii_uppercase().as_str() {
                        "V1" => GraphEvent::V1,
                        "V0" => GraphEvent::V0,
                        "L1" => GraphEvent::L1,
                        "L0" => GraphEvent::L0,
                        "A1" => GraphEvent::A1,
                        _ => return None,
                    };
                    Some((step, event, i, attribute_is(&a.attributes, "sfc.s7graph.interlock", "true")))
                })
                .collect(),
        }
    }
}

/// Whether the last attribute `name` of a list has the value `value` (any case).
fn attribute_is(attrs: &[sfc_syntax::ast::Attribute], name: &str, value: &str) -> bool {
    attrs
        .iter()
        .rev()
        .find(|a| a.name.eq_ignore_ascii_case(name))
        .is_some_and(|a| a.value.as_deref().is_some_and(|v| v.trim().eq_ignore_ascii_case(value)))
}
