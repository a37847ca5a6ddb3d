//! `sfc prove`: the engineer's requirements on an SFC chart — invariants, absence, bounded
//! response, reachability — proved or refuted under the exact scan semantics of the `iec` or
//! the `codesys` profile (`docs/sim.md`, "Profiles"), with CODESYS's step actions and actions
//! written in SFC.
//!
//! The chart and its ST/IL code are compiled into a bit-level relation of one scan
//! ([`model`]): the state is every variable, step flag, step time (in scans, bounded by the
//! largest constant it is compared with), action control block and timer; the inputs of a scan
//! are free within the `[assume]`d ones. The properties of a `<chart>.props.toml`
//! ([`props`]) become state predicates and monitors ([`compile`]). The engines ([`check`]):
//! bounded model checking with SAT ([`sat`], rustsat + BatSat), 1-induction strengthened with
//! the net analysis' invariants, BDD reachability ([`bdd`], biodivine-lib-bdd).
//!
//! Trust: every violation is turned into a scenario file ([`witness`]) and replayed in the
//! simulator before it is reported; every proof by induction or by a reachable set carries its
//! invariant, re-checked by a second, simpler procedure.

pub mod aig;
pub mod bdd;
pub mod check;
pub mod compile;
pub mod model;
pub mod props;
pub mod report;
pub mod sat;
pub mod system;
pub mod witness;
pub mod word;

pub use check::Verdict;
pub use props::{PropertyFile, PropsError};
pub use report::{PropertyReport, Report, WitnessInfo};

use aig::Lit;
use compile::{Origin, PropertyHooks};
use model::{Plan, Role, Setup};
use sfc_diagnostics::{Diagnostic, SourceFile};
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// The default scan period, `T#10ms`.
pub const DEFAULT_PERIOD: i64 = 10_000;

/// What `sfc prove` was asked for.
#[derive(Debug, Clone)]
pub struct Options {
    /// `--pou`, over the property file's `pou`.
    pub pou: Option<String>,
    /// `--period` (µs), over the property file's `period`.
    pub period: Option<i64>,
    /// `--budget`: seconds for all properties together.
    pub seconds: f64,
    /// `--budget Nstates`: reached states the symbolic search may hold per property.
    pub max_states: Option<f64>,
    /// Diagram nodes a BDD may have.
    pub node_limit: usize,
    /// Fill [`Report::debug`] with the model's registers and the engines' figures.
    pub debug: bool,
    /// Only check the property file against the chart (names, types); prove nothing.
    pub check_only: bool,
    /// `--profile`, over the property file's `profile`; `iec` when neither says. `iec` and
    /// `codesys` are modelled; the others are refused ([`ProveError::Unsupported`]).
    pub profile: Option<sfc_sim::Profile>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            pou: None,
            period: None,
            seconds: 60.0,
            max_states: None,
            node_limit: 1_000_000,
            debug: false,
            check_only: false,
            profile: None,
        }
    }
}

/// Why no verdicts could be given.
#[derive(Debug, Clone)]
pub enum ProveError {
    /// The chart has syntax or type errors (or names a POU that cannot be simulated).
    Chart(Box<(SourceFile, Vec<Diagnostic>)>),
    /// The property file is wrong.
    Props(PropsError),
    /// What was asked is not modelled (a profile other than `iec` and `codesys`).
    Unsupported(String),
}

/// The profiles `prove` models.
pub const PROFILES: [sfc_sim::Profile; 2] = [sfc_sim::Profile::Iec, sfc_sim::Profile::Codesys];

/// Why `profile` is refused, if it is.
pub fn unsupported_profile(profile: sfc_sim::Profile) -> Option<String> {
    (!PROFILES.contains(&profile)).then(|| {
        format!("`sfc prove` models the iec and codesys profiles; the {} profile is not modelled yet", profile.name())
    })
}

/// Proves the properties of `file` about the chart `chart_name` (its text `chart_text`).
pub fn prove(chart_name: &str, chart_text: &str, file: &PropertyFile, opts: &Options) -> Result<Report, ProveError> {
    let started = Instant::now();
    let check_opts = sfc_model::CheckOptions { keep_types: true, ..Default::default() };
    let checked = sfc_model::check_source(0, chart_name, chart_text, &check_opts);
    if checked.has_errors() {
        let errors = checked.diagnostics.iter().filter(|d| d.is_error()).cloned().collect();
        return Err(ProveError::Chart(Box::new((checked.file.clone(), errors))));
    }
    let period = opts.period.or(file.period).unwrap_or(DEFAULT_PERIOD);
    let profile = match (opts.profile, &file.profile) {
        (Some(p), _) => {
            if let Some(why) = unsupported_profile(p) {
                return Err(ProveError::Unsupported(why));
            }
            p
        }
        (None, Some((p, l))) => {
            if let Some(why) = unsupported_profile(*p) {
                return Err(ProveError::Props(PropsError {
                    file: file.path.clone(),
                    line: l.line,
                    column: l.column,
                    message: why,
                }));
            }
            *p
        }
        (None, None) => sfc_sim::Profile::Iec,
    };
    let pou_req = opts.pou.clone().or_else(|| file.pou.as_ref().map(|p| p.text.clone()));
    let sim_opts = sfc_sim::SimOptions { period, profile };
    let sim = match sfc_sim::Simulation::from_source(chart_name, chart_text, pou_req.as_deref(), sim_opts) {
        Ok(s) => s,
        Err((src, diags)) => {
            // A `pou` of the property file that names nothing is the file's error.
            if let (None, Some(p)) = (&opts.pou, &file.pou) {
                if let Some(d) = diags.iter().find(|d| d.code == "SFC0321") {
                    return Err(ProveError::Props(PropsError {
                        file: file.path.clone(),
                        line: p.line,
                        column: p.column,
                        message: d.message.clone(),
                    }));
                }
            }
            return Err(ProveError::Chart(Box::new((src, diags))));
        }
    };
    let pou = sim.pou_name().to_string();
    // Names of `ranges` and `inputs` must be variables of the POU.
    let var_names: Vec<String> = sim.trace_vars().into_iter().map(|(n, _)| n).collect();
    let check_name = |l: &props::Located| -> Result<sfc_st::Type, PropsError> {
        match sim.type_of(&l.text) {
            Some(t) if !t.is_error() => Ok(t),
            _ => Err(PropsError {
                file: file.path.clone(),
                line: l.line,
                column: l.column,
                message: format!(
                    "unknown variable `{}` in POU {pou}{}",
                    l.text,
                    match sfc_st::closest(&l.text, var_names.iter().map(String::as_str)) {
                        Some(c) => format!("; did you mean `{c}`?"),
                        None => String::new(),
                    }
                ),
            }),
        }
    };
    let mut ranges = HashMap::new();
    for r in &file.ranges {
        let ty = check_name(&r.name).map_err(ProveError::Props)?;
        let ok =
            if r.time { ty.is_duration() } else { ty.is_integer() || ty.is_bit() && !ty.is_bool() || ty.is_enum() };
        if !ok {
            return Err(ProveError::Props(PropsError {
                file: file.path.clone(),
                line: r.name.line,
                column: r.name.column,
                message: format!(
                    "`{}` is {ty}: a range needs an integer variable (or TIME with TIME literals)",
                    r.name.text
                ),
            }));
        }
        ranges.insert(r.name.text.to_ascii_uppercase(), (r.lo, r.hi));
    }
    let mut extra_inputs = Vec::new();
    for l in &file.inputs {
        check_name(l).map_err(ProveError::Props)?;
        extra_inputs.push(l.text.to_ascii_uppercase());
    }
    let setup = Setup { period, pou: pou.clone(), extra_inputs, ranges, profile };
    let initial = |path: &str| sim.get(path);
    // Pass 1: which variables does the code write? Pass 2: with the others constant, how far
    // must each counter count? Pass 3: the model.
    let mut plan = Plan::default();
    let mut hooks = PropertyHooks::new(file, period);
    let (m1, l1) = model::encode(&checked, &setup, &plan, &initial, &mut hooks)
        .map_err(|m| ProveError::Props(PropsError { file: file.path.clone(), line: 1, column: 1, message: m }))?;
    if let Some(e) = hooks.errors.first() {
        return Err(ProveError::Props(e.clone()));
    }
    if opts.check_only {
        return Ok(Report {
            chart: chart_name.to_string(),
            pou,
            period,
            profile,
            properties_file: file.path.clone(),
            state_bits: 0,
            inputs: Vec::new(),
            notes: m1.notes.clone(),
            properties: Vec::new(),
            time: started.elapsed(),
            debug: Vec::new(),
        });
    }
    // A range must hold the variable's initial value (the state before scan 0).
    for reg in &m1.regs {
        if let (true, Some((lo, hi))) = (reg.obligation, reg.range) {
            if reg.init < lo || reg.init > hi {
                let r = file.ranges.iter().find(|r| r.name.text.eq_ignore_ascii_case(&reg.name));
                let (line, column) = r.map_or((1, 1), |r| (r.name.line, r.name.column));
                return Err(ProveError::Props(PropsError {
                    file: file.path.clone(),
                    line,
                    column,
                    message: format!(
                        "the initial value {} of `{}` is outside its range {lo}..{hi}",
                        reg.init, reg.name
                    ),
                }));
            }
        }
    }
    for (r, reg) in m1.regs.iter().enumerate() {
        if reg.role == (Role::Var { input: false }) && !l1.written.contains(&r) && !reg.obligation {
            plan.constants.insert(reg.name.to_ascii_uppercase());
        }
    }
    let mut hooks = PropertyHooks::new(file, period);
    let (m2, l2) = model::encode(&checked, &setup, &plan, &initial, &mut hooks)
        .map_err(|m| ProveError::Props(PropsError { file: file.path.clone(), line: 1, column: 1, message: m }))?;
    plan.final_pass = true;
    plan.inexact = l2.inexact.clone();
    for k in l2.need.keys() {
        if k.ends_with("#T") && !l2.time_read_elsewhere.contains(k) {
            plan.dead_inactive.insert(k.clone());
        }
    }
    for (k, v) in &l2.need {
        plan.bounds.insert(k.clone(), (*v).clamp(1, model::MAX_COUNT));
    }
    // A nested chart's call gap counts as far as its longest step time.
    for c in &m2.charts {
        if c.path.is_empty() {
            continue;
        }
        let prefix = format!("{}.", c.path.to_ascii_uppercase());
        let max =
            plan.bounds.iter().filter(|(k, _)| k.starts_with(&prefix) && k.ends_with("#T")).map(|(_, v)| *v).max();
        plan.bounds.insert(format!("{}#GAP", c.path.to_ascii_uppercase()), max.unwrap_or(1));
    }
    let mut hooks = PropertyHooks::new(file, period);
    let (m, _) = model::encode(&checked, &setup, &plan, &initial, &mut hooks)
        .map_err(|m| ProveError::Props(PropsError { file: file.path.clone(), line: 1, column: 1, message: m }))?;
    if let Some(e) = hooks.errors.first() {
        return Err(ProveError::Props(e.clone()));
    }
    let compiled = hooks.out;
    if std::env::var_os("SFC_PROVE_TRACE").is_some() {
        eprintln!("[prove] encoded in {:?}: {} AIG nodes", started.elapsed(), m.g.num_nodes());
    }
    let full = system::System::from_model(&m, m.constraint);
    let mut strengthen = sat::Invariant { clauses: pre_start_invariants(&m), at_most_one: Vec::new() };
    strengthen.extend(&net_invariants(&checked, &m));
    if std::env::var_os("SFC_PROVE_TRACE").is_some() {
        eprintln!(
            "[prove] net invariants in {:?}: {} clauses, at most one of {:?}",
            started.elapsed(),
            strengthen.clauses.len(),
            strengthen.at_most_one.iter().map(Vec::len).collect::<Vec<_>>()
        );
    }
    let total = Duration::from_secs_f64(opts.seconds.max(0.01));
    let mut reports = Vec::new();
    let mut cache = check::Cache::default();
    let n = compiled.len().max(1);
    for (k, c) in compiled.iter().enumerate() {
        let now = Instant::now();
        let left = total.saturating_sub(started.elapsed());
        let share = left / (n - k) as u32;
        let budget = check::Budget { deadline: now + share, max_states: opts.max_states, node_limit: opts.node_limit };
        let finding = check::check(&full, &c.signal, &strengthen, &budget, &mut cache);
        sat::set_deadline(None);
        let mut rep = report::PropertyReport::new(c, &finding, now.elapsed());
        rep.line = report::line_of(c, file);
        if let Some(trace) = &finding.trace {
            let expect = witness::Expect::of(c);
            match witness::Witness::build(&m, &full, trace, c, file, period) {
                Ok(w) => {
                    let own = witness::file_name_for(chart_name, &c.name);
                    let chart_file = std::path::Path::new(chart_name)
                        .file_name()
                        .map_or_else(|| chart_name.to_string(), |f| f.to_string_lossy().into_owned());
                    let (scenario, own_line) = w.scenario(&chart_file, &pou, period, profile, c, file, &own);
                    let replay = witness::replay(chart_name, chart_text, &own, &scenario, own_line, expect);
                    let write = finding.verdict == Verdict::Violated;
                    rep.attach(w, own, scenario, replay, write);
                }
                Err(why) => {
                    rep.verdict = Verdict::Unknown;
                    rep.message = format!("the engine's path could not be completed into a run: {why}");
                }
            }
        }
        rep.time = now.elapsed();
        reports.push(rep);
    }
    let inputs = m.inputs.iter().filter(|i| i.reg.is_some()).map(|i| i.name.clone()).collect();
    let mut debug = Vec::new();
    if opts.debug {
        for r in &m.regs {
            if !r.constant && r.role != Role::Temp {
                debug.push(format!("reg {} : {} stored {} bits {:?} {:?}", r.name, r.ty, r.stored, r.range, r.role));
            }
        }
        debug.push(format!("plan: {:?}", plan.bounds));
        debug.push(format!("AIG: {} nodes, {} variables", m.g.num_nodes(), m.g.num_vars()));
    }
    Ok(Report {
        chart: chart_name.to_string(),
        pou,
        period,
        profile,
        properties_file: file.path.clone(),
        state_bits: full.state.len(),
        inputs,
        notes: m.notes.clone(),
        properties: reports,
        time: started.elapsed(),
        debug,
    })
}

/// Before scan 0 the state is the initial one: for every state bit, `(scan 0 done) ∨ bit = its
/// initial value`. Inductive on its own (every scan sets the flag), it keeps 1-induction from
/// starting in a state that no run has: variables off their initial values while scan 0 has
/// not run, from which scan 0 would go on with those values (a counter at −9 that no run
/// reaches made `Rejects <= Parts` fail induction).
fn pre_start_invariants(m: &model::Model) -> Vec<Vec<Lit>> {
    let Some(&done) = m.latch.get(m.scanned).and_then(|l| l.first()) else {
        return Vec::new();
    };
    if done.as_const().is_some() {
        return Vec::new();
    }
    let mut out = Vec::new();
    for (r, lits) in m.latch.iter().enumerate() {
        if r == m.scanned {
            continue;
        }
        let Some(reg) = m.regs.get(r) else { continue };
        for (b, &l) in lits.iter().enumerate() {
            if l.as_const().is_some() {
                continue;
            }
            // The same initial value as `System::from_model` gives the bit.
            let init = b < 127 && (reg.init >> b) & 1 == 1;
            out.push(vec![done, if init { l } else { l.not() }]);
        }
    }
    out
}

/// The net analysis' invariants over the step flags of every chart instance: steps never
/// active, and steps never active together — said as at-most-one constraints over groups of
/// steps that are pairwise never together (the states of a state machine: a greedy cover of
/// the "never together" pairs by such groups), and as pairwise clauses for the pairs no group
/// covers. Together they say exactly what the pairwise clauses would say (a group is the same
/// as the clauses of its pairs), so their inductiveness is that of the whole set; a subset
/// could lose it.
fn net_invariants(checked: &sfc_model::Checked, m: &model::Model) -> sat::Invariant {
    let mut out = sat::Invariant::default();
    for c in &m.charts {
        let chart = model::chart::chart_at(checked, c.chart);
        if chart.steps.len() > 400 {
            continue;
        }
        let report = sfc_analysis::net::analyze_net(chart, &sfc_analysis::net::NetOptions { max_states: 200_000 });
        if !report.complete {
            continue;
        }
        let x: Vec<Lit> = c.x.iter().map(|&r| m.latch[r][0]).collect();
        let started = m.latch[c.started][0];
        // Before its first call (or after SFCInit) a chart has at most its initial steps active.
        for (s, step) in chart.steps.iter().enumerate() {
            if !step.initial {
                out.clauses.push(vec![started, x[s].not()]);
            }
        }
        let mut live = Vec::new();
        for (a, &xa) in x.iter().enumerate() {
            if report.concurrency.together(a, a) {
                live.push(a);
            } else {
                out.clauses.push(vec![xa.not()]);
            }
        }
        let exclusive = |a: usize, b: usize| !report.concurrency.together(a, b);
        for group in exclusive_groups(&live, exclusive, &mut out.clauses, &x) {
            out.at_most_one.push(group.iter().map(|&s| x[s]).collect());
        }
    }
    out
}

/// Covers the pairs of `steps` that `exclusive` says are never active together with groups
/// of pairwise exclusive steps (greedily: from the step with the most uncovered pairs, adding
/// the step exclusive with the whole group that covers the most new pairs), while a group
/// has at least three steps; the pairs left become clauses `¬x_a ∨ ¬x_b` in `clauses`.
fn exclusive_groups(
    steps: &[usize],
    exclusive: impl Fn(usize, usize) -> bool,
    clauses: &mut Vec<Vec<Lit>>,
    x: &[Lit],
) -> Vec<Vec<usize>> {
    let k = steps.len();
    // `uncovered[i][j]`: steps i and j (indices into `steps`) are exclusive and no group says so.
    let mut uncovered = vec![vec![false; k]; k];
    let mut degree = vec![0usize; k];
    for i in 0..k {
        for j in 0..k {
            if i != j && exclusive(steps[i], steps[j]) {
                uncovered[i][j] = true;
                degree[i] += 1;
            }
        }
    }
    let mut groups = Vec::new();
    while let Some((v, d)) = degree.iter().copied().enumerate().max_by_key(|&(i, d)| (d, std::cmp::Reverse(i))) {
        if d == 0 {
            break;
        }
        let mut group = vec![v];
        let mut cand: Vec<usize> = (0..k).filter(|&j| j != v && exclusive(steps[v], steps[j])).collect();
        // `gain[j]`: the uncovered pairs between step j and the group.
        let mut gain: Vec<usize> = (0..k).map(|j| usize::from(uncovered[v][j])).collect();
        while let Some(best) = cand.iter().copied().max_by_key(|&j| (gain[j], std::cmp::Reverse(j))) {
            group.push(best);
            cand.retain(|&j| j != best && exclusive(steps[best], steps[j]));
            for &j in &cand {
                gain[j] += usize::from(uncovered[best][j]);
            }
        }
        if group.len() < 3 {
            break;
        }
        for (a, &i) in group.iter().enumerate() {
            for &j in &group[a + 1..] {
                for (p, q) in [(i, j), (j, i)] {
                    if uncovered[p][q] {
                        uncovered[p][q] = false;
                        degree[p] -= 1;
                    }
                }
            }
        }
        groups.push(group.iter().map(|&i| steps[i]).collect());
    }
    for i in 0..k {
        for j in i + 1..k {
            if uncovered[i][j] {
                clauses.push(vec![x[steps[i]].not(), x[steps[j]].not()]);
            }
        }
    }
    groups
}

/// The origin of a compiled property, for reports.
pub fn origin_kind(o: &Origin) -> &'static str {
    match o {
        Origin::User(_) => "property",
        Origin::Range { .. } => "range",
        Origin::Fault => "runtime error",
    }
}

/// Diagnostics on a property file, for the editor and the language server: the file's error
/// (SFC1001) when there is one, else, given a report, one per violated (SFC1002) or undecided
/// (SFC1003) property at its `[[property]]` line. Spans are byte offsets in `props_text`,
/// file number `file_id`.
pub fn property_diagnostics(
    file_id: u32,
    props_text: &str,
    error: Option<&PropsError>,
    report: Option<&Report>,
) -> Vec<Diagnostic> {
    let src = SourceFile::new("", props_text);
    let span_at = |line: u32, column: u32| -> sfc_diagnostics::Span {
        let start = offset_of(props_text, line, column);
        let end = props_text[start..].find('\n').map_or(props_text.len(), |n| start + n);
        sfc_diagnostics::Span::new(file_id, start as u32, end.max(start + 1).min(props_text.len()) as u32)
    };
    let _ = src;
    let mut out = Vec::new();
    if let Some(e) = error {
        out.push(Diagnostic::error("SFC1001", span_at(e.line, e.column), e.message.clone()));
        return out;
    }
    if let Some(r) = report {
        for p in &r.properties {
            let line = p.line.max(1);
            let span = span_at(line, 1);
            match p.verdict {
                Verdict::Holds => {}
                Verdict::Violated => {
                    let mut d =
                        Diagnostic::error("SFC1002", span, format!("property `{}` is violated: {}", p.name, p.message));
                    if let Some(w) = &p.witness {
                        d = d.with_note(format!(
                            "witness: {} ({} scans), replay it with `sfc test {}`",
                            w.file, w.scans, w.file
                        ));
                    }
                    out.push(d);
                }
                Verdict::Unknown => {
                    out.push(Diagnostic::warning(
                        "SFC1003",
                        span,
                        format!("property `{}` is not decided: {}", p.name, p.message),
                    ));
                }
            }
        }
    }
    out
}

/// The byte offset of a 1-based line and column (in characters).
fn offset_of(text: &str, line: u32, column: u32) -> usize {
    let mut off = 0;
    for (i, l) in text.split_inclusive('\n').enumerate() {
        if i + 1 == line as usize {
            let col: usize = l.chars().take(column.saturating_sub(1) as usize).map(char::len_utf8).sum();
            return off + col.min(l.len());
        }
        off += l.len();
    }
    text.len()
}
