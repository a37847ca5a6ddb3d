//! REX ATMT / EATMT transition tables (`sfc build --target atmt|eatmt`).
//!
//! The output is the one ASCII line of `interfaces.md` and of the REX SFC Editor (seed 001,
//! section 12.2 and fig. 21), without any line break:
//!
//! ```text
//! N[s c n;s c n;…][t0 t1 … tM-1]
//! ```
//!
//! * `N` rules `state condition next-state`, ordered by state, then by the priority of the
//!   transition within the state (explicit `PRIORITY` ascending, then declaration order), which
//!   is the order the block tests them in: the REX block tests the rules of its current state
//!   from the top and takes the first one whose condition input is TRUE, one transition per
//!   period (the seed's `IF R(i) THEN … ELSEIF R(j) …` reading of an OR divergence). Under the
//!   `iec` semantics a step with several true alternatives fires the first in exactly that
//!   order, so the table and the chart agree scan by scan.
//! * The condition is the input index, `1000 + index` when negated (EATMT only).
//! * `M` = the largest state number + 1: one timeout per state number `0…M-1` (the block's
//!   timeout vector is indexed by state, fig. 21 lists one per state). A state number no step
//!   uses (tags may leave gaps) gets `0`. Timeouts are the steps' `sfc.timeout` in seconds,
//!   written as the shortest exact decimal (`8.1`, `2`, `0.5`, `0.0015`); `0` = no timeout.
//!
//! The table is exactly one line with no trailing line break (the MMF of the seed holds no
//! end-of-line character either); a front end printing it to a terminal adds one.
//!
//! The chart must satisfy the target rules of `sfc_model::validate::target_rules` (they are
//! re-run here, so a chart checked for another target is still judged for this one).
//! With `flatten`, a chart with simultaneous branches is first compiled into one automaton
//! whose states are its reachable situations; see [`flatten`] for what that supports.

mod flatten;

pub use flatten::{flatten, Flattened};

use sfc_diagnostics::Diagnostic;
use sfc_model::{condition_input, Chart, Limits, Target};
use sfc_syntax::ast;

/// The largest timeout vector a table may have (EATMT has 256 states; `--nstep` may raise the
/// limit, this keeps a stray tag from asking for gigabytes).
pub const MAX_STATE_NUMBERS: usize = 1 << 16;

/// A built transition table.
#[derive(Debug, Clone, PartialEq)]
pub struct TableOutput {
    /// The table line, `N[…][…]`, without a line break.
    pub text: String,
    /// `M`: the number of entries of the timeout vector (largest state number + 1).
    pub states: usize,
    /// `N`: the number of rules.
    pub rules: usize,
    /// With flattening of a chart with simultaneous branches: the number of states (reachable
    /// situations) the flattening produced; `None` when the chart was compiled directly.
    pub flattened: Option<usize>,
    /// Notes for the user (with flattening: which situation each state number stands for).
    pub notes: Vec<Diagnostic>,
}

/// One rule of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rule {
    pub state: u32,
    /// The condition code: the input index, `1000 + index` when negated.
    pub condition: u32,
    pub next: u32,
}

/// Builds the ATMT/EATMT table of `chart` for `target` with `limits` (see the module doc).
/// Errors are the violated target rules (SFC04xx) or, with `flatten`, why the chart cannot be
/// flattened (SFC0411–SFC0414).
pub fn build_table(
    chart: &Chart,
    target: Target,
    limits: Limits,
    flatten: bool,
) -> Result<TableOutput, Vec<Diagnostic>> {
    let refused = crate::codesys_actions(None, chart, "a transition table");
    if !refused.is_empty() {
        return Err(refused);
    }
    if target == Target::Blank {
        return Err(vec![Diagnostic::error(
            "SFC0410",
            chart.name_span,
            format!("chart `{}`: a transition table needs the target atmt or eatmt, not blank", chart.pou),
        )
        .with_element(&chart.pou)]);
    }
    // Simultaneous branches, or several networks each with its initial step: more than one
    // step can be active.
    let flattening = flatten && chart.several_active_steps();
    let mut diags = target_diagnostics(chart, target, limits);
    if flattening {
        // The product automaton has its own states and rules: the step and transition counts,
        // the AND branches and the step tags are what flattening replaces (its own limits are
        // SFC0412 and SFC0413).
        diags.retain(|d| !sfc_model::FLATTENING_REPLACES.contains(&d.code));
    }
    diags.extend(unusable_conditions(chart));
    if chart.initial_steps().is_empty() {
        diags.push(
            Diagnostic::error(
                "SFC0410",
                chart.name_span,
                format!("chart `{}` has no initial step, so the automaton has no state 0", chart.pou),
            )
            .with_element(&chart.pou),
        );
    }
    if diags.iter().any(Diagnostic::is_error) {
        diags.retain(Diagnostic::is_error);
        return Err(diags);
    }
    if flattening {
        let f = flatten::flatten(chart, target, limits)?;
        return Ok(TableOutput {
            text: format_table(&f.rules, &f.timeouts),
            states: f.timeouts.len(),
            rules: f.rules.len(),
            flattened: Some(f.states.len()),
            notes: f.notes(chart),
        });
    }
    let numbers = chart.state_numbers();
    let mut rules: Vec<(u32, (u8, i64, usize), Rule)> = Vec::new();
    for (i, t) in chart.transitions.iter().enumerate() {
        let (Some(&from), Some(&to), Some(ci)) = (t.from.first(), t.to.first(), condition_input(&t.condition, target))
        else {
            continue; // reported above
        };
        let key = match t.priority {
            Some(p) => (0u8, p, i),
            None => (1u8, 0, i),
        };
        rules.push((numbers[from], key, Rule { state: numbers[from], condition: ci.code(), next: numbers[to] }));
    }
    rules.sort_by_key(|r| (r.0, r.1));
    let rules: Vec<Rule> = rules.into_iter().map(|r| r.2).collect();
    let m = numbers.iter().max().map_or(0, |&n| n as usize + 1);
    if m > MAX_STATE_NUMBERS {
        // Only reachable with a state limit raised far beyond any REX block (`--nstep`).
        return Err(vec![Diagnostic::error(
            "SFC0410",
            chart.name_span,
            format!("chart `{}` uses state number {}: the timeout vector would have {m} entries", chart.pou, m - 1),
        )
        .with_element(&chart.pou)]);
    }
    let mut timeouts = vec![0i64; m];
    for (s, step) in chart.steps.iter().enumerate() {
        if let Some(t) = step.timeout {
            timeouts[numbers[s] as usize] = t;
        }
    }
    Ok(TableOutput {
        text: format_table(&rules, &timeouts),
        states: m,
        rules: rules.len(),
        flattened: None,
        notes: Vec::new(),
    })
}

/// The target rules of the model for `target`, whatever target the chart was lowered with.
fn target_diagnostics(chart: &Chart, target: Target, limits: Limits) -> Vec<Diagnostic> {
    let mut diags = Vec::new();
    if chart.target == target {
        sfc_model::validate::target_rules(chart, limits, &mut diags);
    } else {
        let mut c = chart.clone();
        c.target = target;
        sfc_model::validate::target_rules(&c, limits, &mut diags);
    }
    diags
}

/// Transitions whose condition is missing (after a syntax error the parser reported): the
/// target rules skip them, but a table cannot leave a rule out.
fn unusable_conditions(chart: &Chart) -> Vec<Diagnostic> {
    chart
        .transitions
        .iter()
        .filter(|t| matches!(t.condition, ast::Condition::Missing))
        .map(|t| {
            Diagnostic::error("SFC0410", t.header_span, format!("transition `{}` has no condition input", t.name))
                .with_element(&t.name)
        })
        .collect()
}

/// `N[s c n;…][t0 …]`.
pub fn format_table(rules: &[Rule], timeouts_us: &[i64]) -> String {
    let mut out = String::new();
    out.push_str(&rules.len().to_string());
    out.push('[');
    for (i, r) in rules.iter().enumerate() {
        if i > 0 {
            out.push(';');
        }
        out.push_str(&format!("{} {} {}", r.state, r.condition, r.next));
    }
    out.push_str("][");
    for (i, &t) in timeouts_us.iter().enumerate() {
        if i > 0 {
            out.push(' ');
        }
        out.push_str(&seconds(t));
    }
    out.push(']');
    out
}

/// Microseconds as the shortest exact decimal number of seconds: `8100000` → `8.1`,
/// `2000000` → `2`, `500000` → `0.5`, `0` → `0`.
pub fn seconds(us: i64) -> String {
    let neg = us < 0;
    let a = us.unsigned_abs();
    let whole = a / 1_000_000;
    let frac = a % 1_000_000;
    let mut s = if neg { format!("-{whole}") } else { whole.to_string() };
    if frac != 0 {
        let digits = format!("{frac:06}");
        s.push('.');
        s.push_str(digits.trim_end_matches('0'));
    }
    s
}

/// Parses a table line back into its rules and timeouts (µs); `None` when it is not of the
/// form `N[s c n;…][t …]` with `N` matching the rules. Used by tests and by tools that read
/// tables produced elsewhere.
pub fn parse_table(text: &str) -> Option<(Vec<Rule>, Vec<i64>)> {
    let open = text.find('[')?;
    let n: usize = text[..open].parse().ok()?;
    let rest = &text[open + 1..];
    let close = rest.find(']')?;
    let body = &rest[..close];
    let rest = rest[close + 1..].strip_prefix('[')?.strip_suffix(']')?;
    let mut rules = Vec::new();
    if !body.is_empty() {
        for r in body.split(';') {
            let parts: Vec<&str> = r.split(' ').collect();
            let [s, c, x] = parts.as_slice() else { return None };
            rules.push(Rule { state: s.parse().ok()?, condition: c.parse().ok()?, next: x.parse().ok()? });
        }
    }
    if rules.len() != n {
        return None;
    }
    let mut timeouts = Vec::new();
    if !rest.is_empty() {
        for t in rest.split(' ') {
            timeouts.push(parse_seconds(t)?);
        }
    }
    Some((rules, timeouts))
}

/// `8.1` → 8100000 µs (at most 6 decimals).
fn parse_seconds(s: &str) -> Option<i64> {
    let (whole, frac) = match s.split_once('.') {
        Some((w, f)) => (w, f),
        None => (s, ""),
    };
    if whole.is_empty() || !whole.bytes().all(|b| b.is_ascii_digit()) || frac.len() > 6 {
        return None;
    }
    if !frac.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let w: i64 = whole.parse().ok()?;
    let f: i64 = if frac.is_empty() { 0 } else { format!("{frac:0<6}").parse().ok()? };
    w.checked_mul(1_000_000)?.checked_add(f)
}
