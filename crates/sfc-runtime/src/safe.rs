//! The safe state: the value each output takes when the runtime stops scanning (watchdog,
//! runtime error, STOP, SIGTERM, SIGINT), before the process ends or waits in FAULT.
//!
//! Every located output (`%Q…`) has one, FALSE/0 unless the chart says otherwise with
//! `{attribute 'sfc.safe' := 'TRUE'}` before the variable's declaration, or the run
//! configuration does (`[safe]`, `--safe NAME=VALUE`, which win over the chart). Any other
//! variable may be given one the same ways.

use crate::io::IoPoint;
use crate::Slot;
use sfc_sim::{Simulation, Value};
use sfc_syntax::ast;

/// The safe values of a run.
#[derive(Debug, Clone, Default)]
pub struct SafeState {
    /// `(variable name, slot, value)` for every variable with a safe value.
    pub vars: Vec<(String, Slot, Value)>,
    /// `(point index, value)`: the process image's part.
    pub points: Vec<(usize, Value)>,
}

impl SafeState {
    /// `Motor=FALSE, Setpoint=0` (the first `max`, then how many more).
    pub fn summary(&self, max: usize) -> String {
        let mut parts: Vec<String> =
            self.vars.iter().take(max).map(|(n, _, v)| format!("{n}={}", literal(v))).collect();
        if self.vars.len() > max {
            parts.push(format!("… {} more", self.vars.len() - max));
        }
        parts.join(", ")
    }

    /// The safe value of the variable in `slot`, if it has one.
    pub fn of_slot(&self, slot: usize) -> Option<&Value> {
        self.vars.iter().find(|(_, s, _)| s.index == slot).map(|(_, _, v)| v)
    }
}

/// A value as IEC text: `TRUE`, `0`, `2.5`, `T#1s`, `'text'`.
pub fn literal(v: &Value) -> String {
    match v {
        Value::Bool(b) => if *b { "TRUE" } else { "FALSE" }.to_string(),
        Value::Int(i) => i.to_string(),
        Value::Real(r) => format!("{r:?}"),
        Value::Time(t) => sfc_sim::format_time(*t),
        Value::Str(s) => format!("'{s}'"),
    }
}

/// `sfc.safe` attributes of the variables of POU `pou` and of the file's globals:
/// `(name, value text, 1-based line)`.
fn declared(text: &str, pou: &str) -> Vec<(String, String, u32)> {
    let (unit, _) = sfc_syntax::parse(0, text);
    let file = sfc_diagnostics::SourceFile::new("", text);
    let mut out = Vec::new();
    let mut take = |block: &ast::VarBlock| {
        for d in &block.decls {
            let Some(a) = d.attributes.iter().rev().find(|a| a.name.eq_ignore_ascii_case("sfc.safe")) else {
                continue;
            };
            let value = a.value.clone().unwrap_or_default();
            let line = file.line_col(a.span.start).line;
            for n in &d.names {
                out.push((n.text.clone(), value.clone(), line));
            }
            if d.names.is_empty() {
                if let Some(l) = &d.location {
                    out.push((l.text.clone(), value.clone(), line));
                }
            }
        }
    };
    for item in &unit.items {
        match item {
            ast::Item::Globals(b) => take(b),
            ast::Item::Pou(p) if p.name.text.eq_ignore_ascii_case(pou) => p.var_blocks.iter().for_each(&mut take),
            _ => {}
        }
    }
    out
}

/// The safe values of the simulated POU: its located outputs (FALSE/0), the chart's
/// `sfc.safe` attributes, then `configured` (`NAME`, value text), which win. Errors name the
/// variable and where its value was given.
pub fn safe_state(sim: &Simulation, points: &[IoPoint], configured: &[(String, String)]) -> Result<SafeState, String> {
    let mut s = SafeState::default();
    let mut set = |name: &str, text: Option<&str>, from: &str| -> Result<(), String> {
        let (index, ty) = sim
            .handle(name)
            .ok_or_else(|| format!("{from}: no variable `{name}` in `{}` to give a safe value", sim.pou_name()))?;
        let v = match text {
            Some(t) => sfc_sim::scenario::value_from_text(t, &ty)
                .map_err(|e| format!("{from}: the safe value of `{name}` ({ty}): {e}"))?,
            None => zero(&ty),
        };
        match s.vars.iter_mut().find(|(_, slot, _)| slot.index == index) {
            Some(entry) => entry.2 = v,
            None => s.vars.push((name.to_string(), Slot { index, ty }, v)),
        }
        Ok(())
    };
    for (name, location, _, _) in sim.located_vars() {
        if location.to_ascii_uppercase().starts_with("%Q") {
            set(&name, None, "the outputs")?;
        }
    }
    let file = sim.source().name.clone();
    for (name, text, line) in declared(&sim.source().text, sim.pou_name()) {
        set(&name, Some(&text), &format!("{file}:{line}: `sfc.safe`"))?;
    }
    for (name, text) in configured {
        set(name, Some(text), "the run configuration's [safe]")?;
    }
    for (i, p) in points.iter().enumerate() {
        if let Some(v) = s.of_slot(p.slot.index) {
            s.points.push((i, v.clone()));
        }
    }
    Ok(s)
}

/// FALSE, 0, 0.0, T#0s or '' for `ty`.
fn zero(ty: &sfc_st::Type) -> Value {
    for t in ["FALSE", "0", "0.0", "T#0s", "''"] {
        if let Ok(v) = sfc_sim::scenario::value_from_text(t, ty) {
            return v;
        }
    }
    Value::Int(0)
}
