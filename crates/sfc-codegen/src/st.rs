//! IEC 61131-3 Structured Text from a chart (`sfc build --target st`).
//!
//! [`build_st`] returns the whole source file with the chart's POU replaced by a plain ST POU
//! of the **same kind and the same name**, so every other POU of the file that calls it keeps
//! working, and the file's types, functions and blocks stay as they were. The POU keeps its
//! interface: its declarations are copied verbatim (VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT,
//! VAR_EXTERNAL, VAR …); what the chart held implicitly is declared after them:
//!
//! * one variable per step, named like the step, of the structure `SfcStep` (`X` the step
//!   flag, `T` the step time), so `S.X` and `S.T` in the copied code need no rewriting;
//! * one instance per action, named like the action, of the block `SfcActionControl` (the
//!   ACTION_CONTROL block of IEC 61131-3 2nd ed. 2.6.4.5, with the `iec` details of
//!   `semantics.md`), so `A.Q` and `A.A` read its outputs; BOOL variables used as actions get
//!   an instance `SfcCtl_<name>` and are written with its `Q`;
//! * one BOOL per transition, named like the transition: TRUE in the scan it fires;
//! * the chart control variables of `docs/sim.md` (`SFCInit`, `SFCPause`, `SFCQuitError`
//!   inputs; `SFCError`, `SFCErrorStep`, `SFCCurrentStep` outputs) when the file mentions any
//!   of them or a step has an `sfc.timeout` (a declared one is used as it is);
//! * the implicit condition inputs `C0…`/`c0…` of an ATMT/EATMT chart, as VAR_INPUT;
//! * bookkeeping variables, all named `Sfc…` (made unique against every name of the file).
//!
//! `SfcStep` and `SfcActionControl` are declared at the end of the file; [`build_st_file`] then
//! puts the file in IEC order (they move before their first use) and applies the dialect's
//! passes (`dialect.rs`).
//!
//! **Behaviour.** One call of the POU is one scan of the chart under `iec`: the first call
//! (and the first after `SFCInit` falls) activates the initial steps and runs only the action
//! part (the activation edge); later calls advance the step times, evaluate every enabled
//! guard against one snapshot into the transition flags, resolve conflicts in priority order
//! (a transition is dropped when an earlier one in that order fired and shares a step with it),
//! fire all remaining ones together with set semantics (a step entered restarts its time; one
//! left and re-entered stays active), then update every action control block (each
//! qualifier input the OR of the flags of the steps associating it; timed associations in text
//! order, the first active one wins and equal ones join it, as the simulator's contention
//! rule), and run the bodies of the actions whose `A` is TRUE, in declaration order.
//!
//! **Time.** The POU measures the time between its calls with a free-running standard `TON`
//! (`SfcClock`, `PT` one day): `ET − ET of the previous call`, restarted every 12 hours so it
//! never saturates. On a PLC that is the controller's clock; in the simulator, whose standard
//! blocks read virtual time, it is exactly the virtual time, so a step's `T` and the timed
//! qualifiers (timers of `SfcActionControl` summing the same time, `DeltaT`: the library `TON`
//! switches on one call late, which `D T#0s` must not) match the chart scan for scan.
//! A POU not called for more than 12 hours loses the excess of that gap from its step times.
//!
//! Guards are copied as one line (comments dropped). ST action bodies are copied as written;
//! `RETURN`, which in an action ends the action and in the POU would end the scan, becomes an
//! `EXIT` from a `REPEAT … UNTIL TRUE` around the body (with a flag out of inner loops). IL
//! conditions and bodies are translated: the current result is followed as an ST expression,
//! jumps become blocks guarded by a pending-label variable (a backward jump adds a `REPEAT`);
//! what needs the current result kept in a variable of unknown type (using it right after a
//! label, or after a statement that may have changed what it was computed from) is refused
//! with a located diagnostic (SFC0802–SFC0804).

mod body;
mod dialect;
mod il;

pub use dialect::matiec_time_literal;

use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::{condition_input, ActionTarget, Chart, Checked, Duration, Qualifier, StepId, Target};
use sfc_st::Type;
use sfc_syntax::ast;
use std::collections::{HashMap, HashSet};

/// The compiler the ST is written for (`--st-dialect`, docs/targets.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StDialect {
    /// IEC 61131-3 as written, nothing outside the standard.
    #[default]
    Iec,
    /// MatIEC's `iec2c` (Beremiz, OpenPLC v3).
    Matiec,
    /// STruC++ (OpenPLC v4).
    Strucpp,
    /// CODESYS and TwinCAT (pragmas kept; TIME counts milliseconds).
    Codesys,
}

impl StDialect {
    pub const ALL: [StDialect; 4] = [StDialect::Iec, StDialect::Matiec, StDialect::Strucpp, StDialect::Codesys];

    pub fn name(self) -> &'static str {
        match self {
            StDialect::Iec => "iec",
            StDialect::Matiec => "matiec",
            StDialect::Strucpp => "strucpp",
            StDialect::Codesys => "codesys",
        }
    }

    pub fn parse(s: &str) -> Option<StDialect> {
        StDialect::ALL.into_iter().find(|d| d.name().eq_ignore_ascii_case(s))
    }
}

/// How to write the ST.
#[derive(Debug, Clone, Copy, Default)]
pub struct StOptions {
    pub dialect: StDialect,
}

/// The ST translation of the file of `checked`: the chart `pou`, or every chart of the file one
/// after the other (so a chart function block and the chart program calling it both become
/// plain ST), then the dialect's passes over the whole file (IEC order, located variables in
/// their own blocks, what the compiler needs: `dialect.rs`). Errors are located in `checked`'s
/// text: every chart is tried against it first. Notes: what was added (SFC0808).
pub fn build_st_file(
    checked: &Checked,
    pou: Option<&str>,
    opts: &StOptions,
) -> Result<(String, Vec<Diagnostic>), Vec<Diagnostic>> {
    if checked.has_errors() {
        return Err(checked.diagnostics.iter().filter(|d| d.is_error()).cloned().collect());
    }
    let charts: Vec<&Chart> =
        checked.charts.iter().filter(|c| pou.is_none_or(|p| c.pou.eq_ignore_ascii_case(p))).collect();
    if let (true, Some(p)) = (charts.is_empty(), pou) {
        return Err(vec![Diagnostic::error(
            "SFC0801",
            Span::new(0, 0, 0),
            format!("`{p}` is not a chart of the file"),
        )]);
    }
    let mut errors = Vec::new();
    if opts.dialect == StDialect::Codesys {
        errors.extend(dialect::codesys_limits(checked, &charts));
    }
    errors.extend(dialect::short_circuits(checked, opts.dialect));
    for chart in &charts {
        if let Err(d) = build_st_with(checked, chart, opts) {
            errors.extend(d);
        }
    }
    if !errors.is_empty() {
        sfc_diagnostics::sort(&mut errors);
        errors.dedup_by(|a, b| a.code == b.code && a.span == b.span && a.message == b.message);
        return Err(errors);
    }
    let names: Vec<String> = charts.iter().map(|c| c.pou.clone()).collect();
    let mut text = checked.file.text.clone();
    for (k, name) in names.iter().enumerate() {
        if k > 0 {
            let again = sfc_model::check_source(charts[k].file, &checked.file.name, &text, &Default::default());
            let chart = again.charts.iter().find(|c| c.pou.eq_ignore_ascii_case(name));
            let built = match chart {
                Some(c) if !again.has_errors() => build_st_with(&again, c, opts).ok(),
                _ => None,
            };
            let Some(t) = built else {
                return Err(vec![Diagnostic::error(
                    "SFC0801",
                    charts[k].name_span,
                    format!(
                        "`{name}` could not be translated after the charts before it (an internal error of the ST target: please report it)"
                    ),
                )]);
            };
            text = t;
        } else {
            text = build_st_with(checked, charts[0], opts)?;
        }
    }
    // (a file without a chart goes through the dialect's passes as it is)
    let (text, configured, renamed) = dialect::finish(&text, opts.dialect);
    let at = charts.first().map_or(Span::new(0, 0, 0), |c| c.name_span);
    let mut notes: Vec<Diagnostic> = renamed.into_iter().map(|m| Diagnostic::note_diag("SFC0818", at, m)).collect();
    if configured {
        notes.push(Diagnostic::note_diag(
            "SFC0808",
            at,
            "added `CONFIGURATION Config0` at the end: OpenPLC v3 needs one; its task runs every PROGRAM every 20 ms (set INTERVAL to your scan period)",
        ));
    }
    Ok((text, notes))
}

/// [`build_st_with`] in the `iec` dialect, without the whole-file passes of [`build_st_file`].
pub fn build_st(checked: &Checked, chart: &Chart) -> Result<String, Vec<Diagnostic>> {
    build_st_with(checked, chart, &StOptions::default())
}

/// Builds the ST translation of `chart`, a chart of `checked` (see the module doc), without
/// the whole-file passes of [`build_st_file`]. Errors: the check's own errors, or why the chart
/// cannot be translated (SFC0801–SFC0804).
pub fn build_st_with(checked: &Checked, chart: &Chart, opts: &StOptions) -> Result<String, Vec<Diagnostic>> {
    if checked.has_errors() {
        return Err(checked.diagnostics.iter().filter(|d| d.is_error()).cloned().collect());
    }
    let refused = crate::codesys_actions(Some(checked), chart, "the ST target");
    if !refused.is_empty() {
        return Err(refused);
    }
    let pou = match checked.unit.items.get(chart.item) {
        Some(ast::Item::Pou(p)) if p.name.is(&chart.pou) => p,
        _ => {
            return Err(vec![Diagnostic::error(
                "SFC0801",
                chart.name_span,
                format!("chart `{}` is not a POU of the checked file", chart.pou),
            )])
        }
    };
    if pou.kind == ast::PouKind::Function {
        return Err(vec![Diagnostic::error(
            "SFC0801",
            chart.name_span,
            format!(
                "`{}` is a FUNCTION: a chart needs a PROGRAM or FUNCTION_BLOCK, whose state lasts between calls",
                chart.pou
            ),
        )
        .with_element(&chart.pou)]);
    }
    let src = checked.file.text.as_str();
    // IL needs the types of its operands; the check keeps them only on request.
    let has_il = chart.transitions.iter().any(|t| matches!(t.condition, ast::Condition::Il(_)))
        || chart.actions.iter().any(|a| matches!(a.body, ast::ActionBody::Il(_)));
    let retyped;
    let types = if has_il && checked.expr_types.is_empty() {
        let opts = sfc_model::CheckOptions { keep_types: true, ..Default::default() };
        retyped = sfc_model::check_source(chart.file, &checked.file.name, src, &opts).expr_types;
        &retyped
    } else {
        &checked.expr_types
    };
    let mut g = Gen::new(chart, pou, src, types, opts.dialect);
    let text = g.generate();
    if !g.diags.is_empty() {
        sfc_diagnostics::sort(&mut g.diags);
        return Err(g.diags);
    }
    Ok(text)
}

/// TIME literal, canonical (`T#1s500ms`, `T#0s`, `T#-200ms`).
pub fn time_literal(us: i64) -> String {
    if us == 0 {
        return "T#0s".to_string();
    }
    let mut rest = us.unsigned_abs();
    let mut out = String::from(if us < 0 { "T#-" } else { "T#" });
    for (unit, size) in
        [("d", 86_400_000_000u64), ("h", 3_600_000_000), ("m", 60_000_000), ("s", 1_000_000), ("ms", 1_000), ("us", 1)]
    {
        if rest >= size {
            out.push_str(&format!("{}{unit}", rest / size));
            rest %= size;
        }
    }
    out
}

/// At most this many operands in one AND/OR chain of the generated code.
const CHAIN: usize = 32;

/// The timed qualifiers in the order of the control block's timer table (`TQ` codes 1…5).
const TIMED: [Qualifier; 5] = [Qualifier::L, Qualifier::D, Qualifier::SD, Qualifier::DS, Qualifier::SL];

fn timed_code(q: Qualifier) -> usize {
    TIMED.iter().position(|&t| t == q).map_or(0, |i| i + 1)
}

/// What drives one action control block.
struct Entity {
    /// The instance name.
    instance: String,
    /// The action, if it is one.
    action: Option<usize>,
    /// The BOOL variable, if it is one.
    variable: Option<String>,
    /// `(step, qualifier, duration)` in text order.
    assocs: Vec<(StepId, Qualifier, Option<Duration>)>,
}

/// The six chart control variables as they are spelled in the generated POU.
struct Control {
    init: String,
    pause: String,
    quit: String,
    error: String,
    error_step: String,
    current: String,
}

/// Unique names against every identifier of the file.
struct Names {
    taken: HashSet<String>,
}

impl Names {
    /// The name of a helper declaration: `base` (or `base_1`, …) whose declaration `text(name)`
    /// the file already holds from an earlier translation (`false`: nothing to add), else the
    /// first free one (`true`: to be added).
    fn helper(&mut self, src: &str, base: &str, text: &dyn Fn(&str) -> String) -> (String, bool) {
        let mut k = 0;
        loop {
            let name = if k == 0 { base.to_string() } else { format!("{base}_{k}") };
            if src.contains(&text(&name)) {
                self.taken.insert(name.to_ascii_uppercase());
                return (name, false);
            }
            if !self.taken.contains(&name.to_ascii_uppercase()) {
                self.taken.insert(name.to_ascii_uppercase());
                return (name, true);
            }
            k += 1;
        }
    }

    fn fresh(&mut self, base: &str) -> String {
        let mut name = base.to_string();
        let mut k = 1;
        while self.taken.contains(&name.to_ascii_uppercase()) {
            name = format!("{base}_{k}");
            k += 1;
        }
        self.taken.insert(name.to_ascii_uppercase());
        name
    }
}

/// Lines with indentation.
#[derive(Default)]
struct Out {
    lines: Vec<String>,
    depth: usize,
}

impl Out {
    fn line(&mut self, s: impl AsRef<str>) {
        let s = s.as_ref();
        if s.is_empty() {
            self.lines.push(String::new());
        } else {
            self.lines.push(format!("{}{s}", "    ".repeat(self.depth)));
        }
    }
    fn open(&mut self, s: impl AsRef<str>) {
        self.line(s);
        self.depth += 1;
    }
    fn close(&mut self, s: impl AsRef<str>) {
        self.depth = self.depth.saturating_sub(1);
        self.line(s);
    }
    /// `close` then `open` (ELSE, ELSIF).
    fn reopen(&mut self, s: impl AsRef<str>) {
        self.depth = self.depth.saturating_sub(1);
        self.line(s);
        self.depth += 1;
    }
}

struct Gen<'a> {
    dialect: StDialect,
    chart: &'a Chart,
    pou: &'a ast::Pou,
    src: &'a str,
    il: il::Ctx<'a>,
    names: Names,
    diags: Vec<Diagnostic>,
    entities: Vec<Entity>,
    /// The flag of each transition.
    fired: Vec<String>,
    /// The supervision flag of each step with a timeout (when supervised).
    overdue: Vec<Option<String>>,
    control: Option<Control>,
    step_type: String,
    control_type: String,
    /// The helper types are not in the file yet (a file translated before has them).
    new_step_type: bool,
    new_control_type: bool,
    started: String,
    held: String,
    clock: String,
    last: String,
    delta: String,
    win_q: String,
    win_d: String,
    timed_in: [String; 5],
    goto: String,
    ret: String,
    expired: String,
    /// Scratch BOOLs for long AND/OR chains, by slot.
    scratch: Vec<String>,
    /// Extra declarations: `(section, name, type, comment)`.
    decls: Vec<(ast::VarKind, String, String, &'static str)>,
}

/// Upper-cased identifiers of `text` (keywords included: they only make names unavailable).
fn identifiers(text: &str, out: &mut HashSet<String>) {
    let (tokens, _) = sfc_syntax::lexer::lex(0, text);
    for t in tokens {
        if t.kind == sfc_syntax::lexer::TokenKind::Ident {
            out.insert(text[t.start as usize..t.end as usize].to_ascii_uppercase());
        }
    }
}

impl<'a> Gen<'a> {
    fn new(
        chart: &'a Chart,
        pou: &'a ast::Pou,
        src: &'a str,
        types: &'a HashMap<Span, Type>,
        dialect: StDialect,
    ) -> Gen<'a> {
        let mut taken = HashSet::new();
        identifiers(src, &mut taken);
        let mut outside = HashSet::new();
        let (ps, pe) = (pou.span.start as usize, (pou.span.end as usize).min(src.len()));
        identifiers(src.get(..ps).unwrap_or(""), &mut outside);
        identifiers(src.get(pe..).unwrap_or(""), &mut outside);
        let mut names = Names { taken };
        let (step_type, new_step_type) = names.helper(src, "SfcStep", &step_type_text);
        let add = |a: &str, b: &str| add_time(dialect, a, b);
        let (control_type, new_control_type) =
            names.helper(src, "SfcActionControl", &|n: &str| control_type_text(n, &add));
        let fired = chart
            .transitions
            .iter()
            .map(|t| {
                if outside.contains(&t.name.to_ascii_uppercase()) {
                    names.fresh(&format!("{}_Fired", t.name))
                } else {
                    t.name.clone()
                }
            })
            .collect();
        let mut g = Gen {
            dialect,
            chart,
            pou,
            src,
            il: il::Ctx { src, types },
            diags: Vec::new(),
            entities: Vec::new(),
            fired,
            overdue: vec![None; chart.steps.len()],
            control: None,
            step_type,
            control_type,
            new_step_type,
            new_control_type,
            started: names.fresh("SfcStarted"),
            held: String::new(),
            clock: names.fresh("SfcClock"),
            last: names.fresh("SfcLast"),
            delta: names.fresh("SfcDelta"),
            win_q: String::new(),
            win_d: String::new(),
            timed_in: Default::default(),
            goto: String::new(),
            ret: String::new(),
            expired: String::new(),
            scratch: Vec::new(),
            decls: Vec::new(),
            names,
        };
        g.entities = g.entities();
        g.control = g.control_variables();
        g
    }

    /// Actions first (declaration order), then the BOOL variables used as actions (order of
    /// first association), as the simulator's action control plan.
    fn entities(&mut self) -> Vec<Entity> {
        let chart = self.chart;
        let mut out: Vec<Entity> = chart
            .actions
            .iter()
            .enumerate()
            .map(|(i, a)| Entity { instance: a.name.clone(), action: Some(i), variable: None, assocs: Vec::new() })
            .collect();
        for (s, step) in chart.steps.iter().enumerate() {
            for a in &step.associations {
                let e = match a.target {
                    ActionTarget::Action(id) => id,
                    ActionTarget::Variable => {
                        let found = out
                            .iter()
                            .position(|e| e.variable.as_deref().is_some_and(|v| v.eq_ignore_ascii_case(&a.action)));
                        match found {
                            Some(e) => e,
                            None => {
                                let instance = self.names.fresh(&format!("SfcCtl_{}", a.action));
                                out.push(Entity {
                                    instance,
                                    action: None,
                                    variable: Some(a.action.clone()),
                                    assocs: Vec::new(),
                                });
                                out.len() - 1
                            }
                        }
                    }
                };
                if let Some(ent) = out.get_mut(e) {
                    ent.assocs.push((s, a.qualifier, a.duration.clone()));
                }
            }
        }
        out
    }

    /// The chart control variables, when the file mentions one of them or a step is supervised.
    fn control_variables(&mut self) -> Option<Control> {
        let lower = self.src.to_ascii_lowercase();
        let all = sfc_st::sfc_control_variables();
        let mentioned = all.iter().any(|(n, _, _)| lower.contains(&n.to_ascii_lowercase()));
        let supervised = self.chart.steps.iter().any(|s| s.timeout.is_some());
        if !mentioned && !supervised {
            return None;
        }
        let declared: Vec<&ast::Ident> =
            self.pou.var_blocks.iter().flat_map(|b| b.decls.iter().flat_map(|d| d.names.iter())).collect();
        let mut spelled = Vec::new();
        for (name, kind, ty) in all {
            match declared.iter().find(|d| d.is(name)) {
                Some(d) => spelled.push(d.text.clone()),
                None => {
                    self.names.taken.insert(name.to_ascii_uppercase());
                    let ty = if ty.is_string() { "STRING".to_string() } else { "BOOL".to_string() };
                    let comment = match kind {
                        ast::VarKind::Input => "chart control input (see docs/sim.md)",
                        _ => "chart control output (see docs/sim.md)",
                    };
                    self.decls.push((kind, name.to_string(), ty, comment));
                    spelled.push(name.to_string());
                }
            }
        }
        let [init, pause, quit, error, error_step, current] = <[String; 6]>::try_from(spelled).ok()?;
        if supervised {
            for (s, step) in self.chart.steps.iter().enumerate() {
                if step.timeout.is_some() {
                    self.overdue[s] = Some(self.names.fresh(&format!("SfcOverdue_{}", step.name)));
                }
            }
            self.expired = self.names.fresh("SfcExpired");
        }
        self.held = self.names.fresh("SfcHeld");
        Some(Control { init, pause, quit, error, error_step, current })
    }

    fn generate(&mut self) -> String {
        let body = self.body();
        let decls = self.declarations();
        let src = self.src;
        let pou = self.pou;
        let start = pou.span.start as usize;
        let end = (pou.span.end as usize).min(src.len());
        let mut out = String::new();
        out.push_str(&src[..start]);
        // Header and declarations as written.
        let head_end = pou.return_type.as_ref().map_or(pou.name.span.end, |t| t.span.end) as usize;
        out.push_str(&src[start..head_end]);
        if let Some(last) = pou.var_blocks.last() {
            out.push_str(&src[head_end..last.span.end as usize]);
        }
        out.push('\n');
        for l in decls {
            out.push_str(&l);
            out.push('\n');
        }
        out.push('\n');
        for l in body {
            out.push_str(&l);
            out.push('\n');
        }
        out.push_str(pou.kind.end_keyword());
        out.push_str(&src[end..]);
        if !out.ends_with('\n') {
            out.push('\n');
        }
        out.push('\n');
        out.push_str(&self.runtime());
        out
    }

    // -----------------------------------------------------------------------------------------
    // Declarations

    fn declarations(&mut self) -> Vec<String> {
        let chart = self.chart;
        // Implicit condition inputs of ATMT/EATMT charts.
        if matches!(chart.target, Target::Atmt | Target::Eatmt) {
            let declared: Vec<String> = self
                .pou
                .var_blocks
                .iter()
                .flat_map(|b| b.decls.iter().flat_map(|d| d.names.iter().map(|n| n.key())))
                .collect();
            let mut seen = HashSet::new();
            for t in &chart.transitions {
                if let Some(ci) = condition_input(&t.condition, chart.target) {
                    let name = input_name(chart.target, ci.index);
                    if !declared.contains(&name.to_ascii_uppercase()) && seen.insert(ci.index) {
                        self.decls.push((ast::VarKind::Input, name, "BOOL".into(), "condition input of the automaton"));
                    }
                }
            }
        }
        let mut out = Vec::new();
        for kind in [ast::VarKind::Input, ast::VarKind::Output] {
            let list: Vec<&(ast::VarKind, String, String, &str)> = self.decls.iter().filter(|d| d.0 == kind).collect();
            if list.is_empty() {
                continue;
            }
            out.push(format!("    {}", kind.keyword()));
            for (_, n, t, c) in list {
                out.push(format!("        {n} : {t}; (* {c} *)"));
            }
            out.push("    END_VAR".to_string());
        }
        out.push("    VAR".to_string());
        out.push("        (* The chart, translated by sfc (sfc build --target st). *)".to_string());
        for s in &chart.steps {
            out.push(format!(
                "        {} : {}; (* step{} *)",
                s.name,
                self.step_type,
                if s.initial { ", initial" } else { "" }
            ));
        }
        for e in &self.entities {
            let what = match (&e.action, &e.variable) {
                (Some(_), _) => "action".to_string(),
                (None, Some(v)) => format!("action control of the BOOL variable {v}"),
                _ => String::new(),
            };
            out.push(format!("        {} : {}; (* {what} *)", e.instance, self.control_type));
        }
        for (t, f) in chart.transitions.iter().zip(&self.fired) {
            let what = if *f == t.name {
                "transition, TRUE in the scan it fires".to_string()
            } else {
                format!("transition {} fired", t.name)
            };
            out.push(format!("        {f} : BOOL; (* {what} *)"));
        }
        let mut misc: Vec<(String, &str, &str)> = vec![
            (self.started.clone(), "BOOL", "the initial situation has been activated"),
            (self.clock.clone(), "TON", "stopwatch: the time between calls"),
            (self.last.clone(), "TIME", ""),
            (self.delta.clone(), "TIME", ""),
        ];
        if self.control.is_some() {
            misc.push((self.held.clone(), "BOOL", "SFCInit holds the initial situation"));
        }
        for n in self.overdue.iter().flatten() {
            misc.push((n.clone(), "BOOL", "supervision time reported"));
        }
        if !self.expired.is_empty() {
            misc.push((self.expired.clone(), "BOOL", ""));
        }
        if !self.win_q.is_empty() {
            misc.push((self.win_q.clone(), "INT", "timed association that wins: 1 L, 2 D, 3 SD, 4 DS, 5 SL"));
            misc.push((self.win_d.clone(), "TIME", "its duration"));
            for n in self.timed_in.iter().filter(|n| !n.is_empty()) {
                misc.push((n.clone(), "BOOL", ""));
            }
        }
        for n in &self.scratch {
            misc.push((n.clone(), "BOOL", "part of a long AND/OR"));
        }
        if !self.goto.is_empty() {
            misc.push((self.goto.clone(), "INT", "IL: pending jump (label number, -1 return)"));
        }
        if !self.ret.is_empty() {
            misc.push((self.ret.clone(), "BOOL", "RETURN inside a loop of an action"));
        }
        for (n, t, c) in misc {
            if c.is_empty() {
                out.push(format!("        {n} : {t};"));
            } else {
                out.push(format!("        {n} : {t}; (* {c} *)"));
            }
        }
        out.push("    END_VAR".to_string());
        out
    }

    // -----------------------------------------------------------------------------------------
    // The scan

    fn body(&mut self) -> Vec<String> {
        let mut o = Out { depth: 1, ..Default::default() };
        let control = self.control.take();
        if let Some(c) = &control {
            o.open(format!("IF {} THEN", c.init));
            o.line("(* SFCInit: back to the initial situation, held while it is TRUE *)");
            o.open(format!("IF NOT {} THEN", self.held));
            self.reset(&mut o, c);
            o.close("END_IF;");
            o.reopen("ELSE");
            o.line(format!("IF {} THEN {} := FALSE; END_IF;", c.quit, c.error));
        }
        o.open(format!("IF NOT {} THEN", self.started));
        o.line("(* scan 0: the initial situation; its actions run once before its transitions are tested *)");
        o.line(format!("{} := TRUE;", self.started));
        if control.is_some() {
            o.line(format!("{} := FALSE;", self.held));
        }
        o.line(format!("{}(IN := FALSE);", self.clock));
        o.line(format!("{}(IN := TRUE, PT := T#1d);", self.clock));
        o.line(format!("{} := T#0s;", self.last));
        o.line(format!("{} := T#0s;", self.delta));
        for s in self.chart.initial_steps() {
            self.enter(&mut o, s);
        }
        o.reopen("ELSE");
        o.line(format!("{}(IN := TRUE, PT := T#1d);", self.clock));
        o.line(format!("{} := {}.ET - {};", self.delta, self.clock, self.last));
        o.line(format!("{} := {}.ET;", self.last, self.clock));
        o.open(format!("IF {} >= T#12h THEN", self.last));
        o.line("(* restart the stopwatch long before it saturates *)");
        o.line(format!("{}(IN := FALSE);", self.clock));
        o.line(format!("{}(IN := TRUE, PT := T#1d);", self.clock));
        o.line(format!("{} := T#0s;", self.last));
        o.close("END_IF;");
        if let Some(c) = &control {
            o.open(format!("IF NOT {} THEN", c.pause));
        }
        self.evolution(&mut o);
        if control.is_some() {
            o.close("END_IF;");
        }
        o.close("END_IF;");
        self.action_control(&mut o);
        if control.is_some() {
            o.close("END_IF;");
        }
        self.bodies(&mut o);
        if let Some(c) = &control {
            o.line("");
            o.open(format!("IF NOT {} THEN", self.held));
            self.supervision(&mut o, c);
            o.line("(* SFCCurrentStep: the first active step in declaration order *)");
            self.current_step(&mut o, c);
            o.close("END_IF;");
        }
        self.control = control;
        o.lines
    }

    /// `terms` joined by `op` (` AND ` / ` OR `). The parser bounds the length of operator
    /// chains, so a long one is accumulated in scratch variable `slot` by lines of
    /// [`CHAIN`] terms before its use, and that variable is returned.
    fn chain(&mut self, o: &mut Out, terms: &[String], op: &str, slot: usize) -> String {
        if terms.len() <= CHAIN {
            return terms.join(op);
        }
        while self.scratch.len() <= slot {
            let n = self.names.fresh(&format!("SfcPart{}", self.scratch.len() + 1));
            self.scratch.push(n);
        }
        let v = self.scratch[slot].clone();
        for (k, part) in terms.chunks(CHAIN).enumerate() {
            if k == 0 {
                o.line(format!("{v} := {};", part.join(op)));
            } else {
                o.line(format!("{v} := {v}{op}{};", part.join(op)));
            }
        }
        v
    }

    /// `a + b` for TIME values, in the dialect's form.
    fn add_time(&self, a: &str, b: &str) -> String {
        add_time(self.dialect, a, b)
    }

    /// Activation of step `s`: flag, time, supervision.
    fn enter(&self, o: &mut Out, s: StepId) {
        let name = &self.chart.steps[s].name;
        o.line(format!("{name}.X := TRUE;"));
        o.line(format!("{name}.T := T#0s;"));
        if let Some(f) = &self.overdue[s] {
            o.line(format!("{f} := FALSE;"));
        }
    }

    fn reset(&self, o: &mut Out, c: &Control) {
        for (s, step) in self.chart.steps.iter().enumerate() {
            o.line(format!("{}.X := {};", step.name, if step.initial { "TRUE" } else { "FALSE" }));
            o.line(format!("{}.T := T#0s;", step.name));
            if let Some(f) = &self.overdue[s] {
                o.line(format!("{f} := FALSE;"));
            }
        }
        for e in &self.entities {
            o.line(format!("{}(Reset := TRUE);", e.instance));
            if let Some(v) = &e.variable {
                o.line(format!("{v} := FALSE;"));
            }
        }
        o.line(format!("{} := FALSE;", c.error));
        o.line(format!("{} := '';", c.error_step));
        // The first active step is the first initial one (docs/sim.md). The simulator shows
        // that value to scenarios and traces, but leaves the variable its code reads as it was
        // until the next scan after SFCInit falls.
        let first = self.chart.steps.iter().find(|s| s.initial).map_or("", |s| s.name.as_str());
        o.line(format!("{} := '{first}';", c.current));
        o.line(format!("{} := FALSE;", self.started));
        if !self.chart.initial_steps().is_empty() {
            o.line(format!("{} := TRUE;", self.held));
        }
    }

    /// Steps 2–5 of `semantics.md`.
    fn evolution(&mut self, o: &mut Out) {
        let chart = self.chart;
        o.line("(* step times *)");
        for s in &chart.steps {
            let sum = self.add_time(&format!("{}.T", s.name), &self.delta);
            o.line(format!("IF {0}.X THEN {0}.T := {sum}; END_IF;", s.name));
        }
        o.line("(* enabled transitions with a true guard, all against the same snapshot *)");
        for (t, tr) in chart.transitions.iter().enumerate() {
            let flag = self.fired[t].clone();
            let mut pre: Vec<StepId> = Vec::new();
            for &s in &tr.from {
                if !pre.contains(&s) {
                    pre.push(s);
                }
            }
            let flags: Vec<String> = pre.iter().map(|&s| format!("{}.X", chart.steps[s].name)).collect();
            let enabled = if flags.is_empty() { "FALSE".to_string() } else { self.chain(o, &flags, " AND ", 0) };
            match self.guard(t) {
                Some((g, prec, safe)) if safe => {
                    if g.eq_ignore_ascii_case("TRUE") {
                        o.line(format!("{flag} := {enabled};"));
                    } else {
                        o.line(format!("{flag} := {enabled} AND {};", il::wrap(&g, prec, 3)));
                    }
                }
                Some((g, _, _)) => {
                    // The guard may fault (division, index, call): evaluate it only when enabled.
                    o.line(format!("{flag} := FALSE;"));
                    o.open(format!("IF {enabled} THEN"));
                    o.line(format!("{flag} := {g};"));
                    o.close("END_IF;");
                }
                None => o.line(format!("{flag} := FALSE;")),
            }
        }
        // Conflicts: in priority order, a transition is dropped when an earlier one (in that
        // order) that shares a preceding step fires.
        let mut order: Vec<usize> = (0..chart.transitions.len()).collect();
        order.sort_by_key(|&i| match chart.transitions[i].priority {
            Some(p) => (0u8, p, i),
            None => (1u8, 0, i),
        });
        let mut rank = vec![0usize; order.len()];
        for (k, &t) in order.iter().enumerate() {
            rank[t] = k;
        }
        let adj = chart.adjacency();
        let mut header = false;
        for &t in &order {
            // Earlier transitions (in priority order) leaving one of t's preceding steps.
            let mut earlier: Vec<usize> = Vec::new();
            for &s in &chart.transitions[t].from {
                for &u in &adj.outgoing[s] {
                    if rank[u] < rank[t] && !earlier.contains(&u) {
                        earlier.push(u);
                    }
                }
            }
            if earlier.is_empty() {
                continue;
            }
            if !header {
                o.line("(* conflicts: each step is taken by the first transition in priority order *)");
                header = true;
            }
            earlier.sort_by_key(|&u| rank[u]);
            let names: Vec<String> = earlier.iter().map(|&u| self.fired[u].clone()).collect();
            let taken = self.chain(o, &names, " OR ", 0);
            let taken = if names.len() == 1 || names.len() > CHAIN { taken } else { format!("({taken})") };
            let f = &self.fired[t];
            o.line(format!("{f} := {f} AND NOT {taken};"));
        }
        o.line("(* firing: the steps left are deactivated, the steps entered activated *)");
        for (s, step) in chart.steps.iter().enumerate() {
            let mut enter: Vec<String> = Vec::new();
            for &t in &adj.incoming[s] {
                if !enter.contains(&self.fired[t]) {
                    enter.push(self.fired[t].clone());
                }
            }
            let mut leave: Vec<String> = Vec::new();
            for &t in &adj.outgoing[s] {
                if !leave.contains(&self.fired[t]) {
                    leave.push(self.fired[t].clone());
                }
            }
            let enter = self.chain(o, &enter, " OR ", 0);
            let leave = self.chain(o, &leave, " OR ", 1);
            if !enter.is_empty() {
                o.open(format!("IF {enter} THEN"));
                self.enter(o, s);
                if leave.is_empty() {
                    o.close("END_IF;");
                } else {
                    o.reopen(format!("ELSIF {leave} THEN"));
                    o.line(format!("{}.X := FALSE;", step.name));
                    o.close("END_IF;");
                }
            } else if !leave.is_empty() {
                o.line(format!("IF {leave} THEN {}.X := FALSE; END_IF;", step.name));
            }
        }
    }

    /// The guard of transition `t` as `(text, precedence, cannot fault)`.
    fn guard(&mut self, t: usize) -> Option<(String, u8, bool)> {
        let chart = self.chart;
        let tr = &chart.transitions[t];
        if matches!(chart.target, Target::Atmt | Target::Eatmt) {
            if let Some(ci) = condition_input(&tr.condition, chart.target) {
                let name = input_name(chart.target, ci.index);
                return Some(if ci.negated { (format!("NOT {name}"), 8, true) } else { (name, il::ATOM, true) });
            }
        }
        match &tr.condition {
            ast::Condition::St(e) => Some((il::clean(self.src, e.span), il::prec_of(e), il::cannot_fault(e))),
            ast::Condition::Il(b) => match self.il.condition(b) {
                Ok(g) => Some(g),
                Err(d) => {
                    self.diags.push(d.with_element(&tr.name));
                    None
                }
            },
            ast::Condition::Missing => {
                self.diags.push(
                    Diagnostic::error("SFC0801", tr.header_span, format!("transition `{}` has no condition", tr.name))
                        .with_element(&tr.name),
                );
                None
            }
        }
    }

    /// Step 6: every action control block, then the BOOL variables used as actions.
    fn action_control(&mut self, o: &mut Out) {
        let chart = self.chart;
        o.line("(* action control: each qualifier input is the OR of the flags of the steps associating it *)");
        for k in 0..self.entities.len() {
            if self.entities[k].assocs.is_empty() {
                continue;
            }
            let assocs = self.entities[k].assocs.clone();
            let instance = self.entities[k].instance.clone();
            let mut args: Vec<String> = Vec::new();
            for q in Qualifier::ALL.iter().filter(|q| !q.is_timed()) {
                let mut steps: Vec<StepId> = Vec::new();
                for &(s, aq, _) in &assocs {
                    if aq == *q && !steps.contains(&s) {
                        steps.push(s);
                    }
                }
                if !steps.is_empty() {
                    let flags: Vec<String> = steps.iter().map(|&s| format!("{}.X", chart.steps[s].name)).collect();
                    let slot = args.len();
                    args.push(format!("{} := {}", q.name(), self.chain(o, &flags, " OR ", slot)));
                }
            }
            let timed: Vec<(StepId, Qualifier, String)> =
                assocs.iter().filter(|a| a.1.is_timed()).map(|(s, q, d)| (*s, *q, duration_text(d.as_ref()))).collect();
            match timed.as_slice() {
                [] => {}
                [(s, q, d)] => {
                    // One timed association: it wins whenever its step is active.
                    let x = format!("{}.X", chart.steps[*s].name);
                    args.push(format!("{} := {x}", q.name()));
                    args.push(format!("TQ := SEL({x}, 0, {})", timed_code(*q)));
                    args.push(format!("TD := {d}"));
                }
                _ => {
                    self.timed_selection(o, &instance, &timed);
                    let mut used: Vec<Qualifier> = Vec::new();
                    for (_, q, _) in &timed {
                        if !used.contains(q) {
                            used.push(*q);
                        }
                    }
                    for q in TIMED.iter().filter(|q| used.contains(q)) {
                        args.push(format!("{} := {}", q.name(), self.timed_in[timed_code(*q) - 1]));
                    }
                    args.push(format!("TQ := {}", self.win_q));
                    args.push(format!("TD := {}", self.win_d));
                }
            }
            args.push(format!("DeltaT := {}", self.delta));
            if !self.held.is_empty() {
                // (the chart has control variables: SFCInit resets the block)
                args.push("Reset := FALSE".to_string());
            }
            o.line(format!("{instance}({});", args.join(", ")));
            if let Some(v) = &self.entities[k].variable {
                o.line(format!("{v} := {instance}.Q;"));
            }
        }
    }

    /// Several timed associations: in text order the first active one wins, later active ones
    /// with the same qualifier and duration join it, the others are ignored this scan.
    fn timed_selection(&mut self, o: &mut Out, instance: &str, timed: &[(StepId, Qualifier, String)]) {
        if self.win_q.is_empty() {
            self.win_q = self.names.fresh("SfcWinQ");
            self.win_d = self.names.fresh("SfcWinD");
        }
        for (_, q, _) in timed {
            let i = timed_code(*q) - 1;
            if self.timed_in[i].is_empty() {
                self.timed_in[i] = self.names.fresh(&format!("SfcIn{}", q.name()));
            }
        }
        o.line(format!("(* {instance}: the first active timed association in text order wins *)"));
        o.line(format!("{} := 0;", self.win_q));
        o.line(format!("{} := T#0s;", self.win_d));
        let mut cleared = Vec::new();
        for (_, q, _) in timed {
            if !cleared.contains(q) {
                cleared.push(*q);
                o.line(format!("{} := FALSE;", self.timed_in[timed_code(*q) - 1]));
            }
        }
        for (s, q, d) in timed {
            let code = timed_code(*q);
            let input = &self.timed_in[code - 1];
            o.open(format!("IF {}.X THEN", self.chart.steps[*s].name));
            o.open(format!("IF {} = 0 THEN", self.win_q));
            o.line(format!("{} := {code};", self.win_q));
            o.line(format!("{} := {d};", self.win_d));
            o.line(format!("{input} := TRUE;"));
            o.reopen(format!("ELSIF {} = {code} AND {} = {d} THEN", self.win_q, self.win_d));
            o.line(format!("{input} := TRUE;"));
            o.close("END_IF;");
            o.close("END_IF;");
        }
    }

    /// Step 7: the bodies of the actions whose `A` is TRUE, in declaration order.
    fn bodies(&mut self, o: &mut Out) {
        let chart = self.chart;
        for (i, a) in chart.actions.iter().enumerate() {
            let lines = match &a.body {
                ast::ActionBody::St(stmts) => match body::action_body_range(self.src, a.name_span.end, a.span.end) {
                    Some(range) => {
                        let names = &mut self.names;
                        let ret = &mut self.ret;
                        let mut flag = || {
                            if ret.is_empty() {
                                *ret = names.fresh("SfcReturn");
                            }
                            ret.clone()
                        };
                        body::body_lines(self.src, range, stmts, &mut flag)
                    }
                    None => Vec::new(),
                },
                // Refused before generation (SFC0806, `sfc-driver`).
                ast::ActionBody::Sfc(_) => Vec::new(),
                ast::ActionBody::Il(b) => {
                    if il::Ctx::needs_goto(b) && self.goto.is_empty() {
                        self.goto = self.names.fresh("SfcGoto");
                    }
                    match self.il.body(b, &self.goto) {
                        Ok(l) => l,
                        Err(d) => {
                            self.diags.push(d.with_element(&a.name));
                            Vec::new()
                        }
                    }
                }
            };
            let instance = &self.entities[i].instance;
            o.line("");
            o.line(format!("(* ACTION {} *)", a.name));
            o.open(format!("IF {instance}.A THEN"));
            for l in lines {
                o.line(l);
            }
            o.close("END_IF;");
        }
    }

    /// `sfc.timeout`: a step active longer than its timeout sets SFCError (once per activation);
    /// SFCErrorStep names the first such step in declaration order.
    fn supervision(&self, o: &mut Out, c: &Control) {
        if self.expired.is_empty() {
            return;
        }
        o.line("(* supervision times (sfc.timeout) *)");
        o.line(format!("{} := FALSE;", self.expired));
        for (s, step) in self.chart.steps.iter().enumerate() {
            let (Some(f), Some(limit)) = (&self.overdue[s], step.timeout) else { continue };
            o.open(format!("IF {0}.X AND {0}.T > {1} AND NOT {f} THEN", step.name, time_literal(limit)));
            o.line(format!("{f} := TRUE;"));
            o.line(format!(
                "IF NOT {0} THEN {0} := TRUE; {1} := '{2}'; END_IF;",
                self.expired, c.error_step, step.name
            ));
            o.close("END_IF;");
        }
        o.line(format!("IF {} THEN {} := TRUE; END_IF;", self.expired, c.error));
    }

    fn current_step(&self, o: &mut Out, c: &Control) {
        for (i, s) in self.chart.steps.iter().enumerate() {
            let kw = if i == 0 { "IF" } else { "ELSIF" };
            if i == 0 {
                o.open(format!("{kw} {}.X THEN", s.name));
            } else {
                o.reopen(format!("{kw} {}.X THEN", s.name));
            }
            o.line(format!("{} := '{}';", c.current, s.name));
        }
        if self.chart.steps.is_empty() {
            o.line(format!("{} := '';", c.current));
        } else {
            o.reopen("ELSE");
            o.line(format!("{} := '';", c.current));
            o.close("END_IF;");
        }
    }

    // -----------------------------------------------------------------------------------------
    // The helper types

    /// The helper declarations this translation adds at the end of the file.
    fn runtime(&self) -> String {
        let mut s = String::new();
        if self.new_step_type {
            s.push_str(
                "(* The state of a step of a chart translated to ST by sfc: X is the step flag, T the time\n   \
                 since the step was last activated (frozen while it is inactive). *)\n",
            );
            s.push_str(&step_type_text(&self.step_type));
            s.push('\n');
        }
        if self.new_control_type && !self.entities.is_empty() {
            if !s.is_empty() {
                s.push('\n');
            }
            s.push_str(CONTROL_COMMENT);
            let dialect = self.dialect;
            s.push_str(&control_type_text(&self.control_type, &|a: &str, b: &str| add_time(dialect, a, b)));
            s.push('\n');
        }
        s
    }
}

/// What a translation declares about the action control block.
const CONTROL_COMMENT: &str =
    "(* ACTION_CONTROL (IEC 61131-3 2nd ed. 2.6.4.5) as sfc's iec semantics settle it: one instance per
   action. Each qualifier input is the OR of the flags of the steps that associate the action
   with that qualifier; TQ/TD give the timed qualifier (1 L, 2 D, 3 SD, 4 DS, 5 SL) that won this
   call and its duration, which that qualifier's timer keeps; DeltaT the time since the previous
   call, which the timers add up. R overrides everything and
   cancels pending SD/SL timers and DS flags. A is Q, plus one call after Q falls (the final
   scan) and the P1/P0 pulses. Reset clears the block (SFCInit). *)
";

/// The step structure, as declared.
fn step_type_text(name: &str) -> String {
    format!("TYPE\n    {name} : STRUCT\n        X : BOOL;\n        T : TIME;\n    END_STRUCT;\nEND_TYPE")
}

/// ACTION_CONTROL as a function block, as declared. Its timers are its own (the time since
/// each timer input rose, summed from `DeltaT`), not the library's `TON`, whose first call on a
/// rising input never switches on: `D T#0s` acts at once (`semantics.md`). `add` writes a TIME
/// sum (the dialect's form).
fn control_type_text(name: &str, add: &dyn Fn(&str, &str) -> String) -> String {
    let timer = |input: &str, t: &str| {
        format!(
            "    IF {input} THEN\n        IF {t}_IN THEN\n            {t}_ET := {};\n        ELSE\n            {t}_ET := T#0s;\n        END_IF;\n    END_IF;\n    {t}_IN := {input};\n",
            add(&format!("{t}_ET"), "DeltaT")
        )
    };
    let timers: String = [("L", "L"), ("D", "D"), ("SD_FF", "SD"), ("DS", "DS"), ("SL_FF", "SL")]
        .iter()
        .map(|(i, t)| timer(i, t))
        .collect();
    format!(
        r#"FUNCTION_BLOCK {name}
    VAR_INPUT
        N, R, S, L, D, P, SD, DS, SL, P1, P0 : BOOL;
        TQ : INT;
        TD : TIME;
        DeltaT : TIME; (* the time since the previous call *)
        Reset : BOOL;
    END_VAR
    VAR_OUTPUT
        Q : BOOL;
        A : BOOL;
    END_VAR
    VAR
        S_FF, SD_FF, DS_FF, SL_FF : BOOL;
        P_MEM, P1_MEM, P0_MEM : BOOL;
        L_IN, D_IN, SD_IN, DS_IN, SL_IN : BOOL;
        L_ET, D_ET, SD_ET, DS_ET, SL_ET : TIME;
        T_L, T_D, T_SD, T_DS, T_SL : TIME;
        P_Q, NEW_Q : BOOL;
    END_VAR

    IF Reset THEN
        S_FF := FALSE;
        SD_FF := FALSE;
        DS_FF := FALSE;
        SL_FF := FALSE;
        P_MEM := FALSE;
        P1_MEM := FALSE;
        P0_MEM := FALSE;
        L_IN := FALSE;
        D_IN := FALSE;
        SD_IN := FALSE;
        DS_IN := FALSE;
        SL_IN := FALSE;
        T_L := T#0s;
        T_D := T#0s;
        T_SD := T#0s;
        T_DS := T#0s;
        T_SL := T#0s;
        Q := FALSE;
        A := FALSE;
        RETURN;
    END_IF;
    CASE TQ OF
        1: T_L := TD;
        2: T_D := TD;
        3: T_SD := TD;
        4: T_DS := TD;
        5: T_SL := TD;
    END_CASE;
    S_FF := NOT R AND (S_FF OR S);
    SD_FF := NOT R AND (SD_FF OR SD);
    SL_FF := NOT R AND (SL_FF OR SL);
    (* the timers: the time since the input rose, from the call it was first seen TRUE *)
{timers}    P_Q := P AND NOT P_MEM;
    P_MEM := P;
    DS_FF := NOT R AND (DS_FF OR (DS AND DS_ET >= T_DS));
    NEW_Q := NOT R AND (N OR (L AND NOT (L_ET >= T_L)) OR (D AND D_ET >= T_D) OR P_Q OR S_FF
        OR (SD_FF AND SD_ET >= T_SD) OR DS_FF OR (SL_FF AND NOT (SL_ET >= T_SL)));
    A := NEW_Q OR (Q AND NOT NEW_Q) OR (P1 AND NOT P1_MEM) OR (P0_MEM AND NOT P0);
    Q := NEW_Q;
    P1_MEM := P1;
    P0_MEM := P0;
END_FUNCTION_BLOCK"#
    )
}

/// The sum of two TIME values. MatIEC does not carry a whole second when an addition makes
/// exactly 10⁹ ns (`T#990ms + T#10ms` compares below `T#1s`); its multiplication does, so the
/// `matiec` dialect writes `(a + b) * 1`.
fn add_time(dialect: StDialect, a: &str, b: &str) -> String {
    if dialect == StDialect::Matiec {
        format!("({a} + {b}) * 1")
    } else {
        format!("{a} + {b}")
    }
}

/// `C3` for ATMT, `c3` for EATMT.
fn input_name(target: Target, index: u32) -> String {
    if target == Target::Atmt {
        format!("C{index}")
    } else {
        format!("c{index}")
    }
}

fn duration_text(d: Option<&Duration>) -> String {
    match d {
        Some(Duration::Literal(us)) => time_literal(*us),
        Some(Duration::Variable(v)) => v.clone(),
        None => "T#0s".to_string(),
    }
}
