//! `Program::instantiate`: the memory of one top-level POU with every declared initial value,
//! and the list of SFC instances in it.

use super::call::run_inits;
use super::compile::InitOp;
use super::{class_of, ChartInstance, Ctx, Memory, PouBody, Program, Retained};
use crate::engine::ScanSink;
use crate::value::Value;
use sfc_st::Type;
use sfc_syntax::ast::PouKind;

impl Program {
    /// Memory with every declared initial value for running POU `top` (PROGRAM or
    /// FUNCTION_BLOCK) as the top-level instance: globals first, then the top frame, nested
    /// instances inside; lists every SFC instance (see [`Memory`]).
    pub fn instantiate(&self, top: usize) -> Memory {
        let mut mem = self.support.globals_template.clone();
        mem.resize(self.globals.size as usize, Value::Bool(false));
        // A PROGRAM is its one instance, the global named after it (code reaches into it as
        // `Main.X`): run as the top, that global is its frame.
        let own = self
            .pous
            .get(top)
            .filter(|p| p.kind == PouKind::Program)
            .and_then(|p| self.globals.vars.iter().find(|v| v.implicit && v.name.eq_ignore_ascii_case(&p.name)));
        let top_frame = match own {
            Some(v) => v.offset as usize,
            None => {
                let at = mem.len();
                if let Some(t) = self.support.templates.get(top) {
                    mem.extend_from_slice(t);
                }
                at
            }
        };
        {
            let mut charts = Vec::new();
            let mut sink = ScanSink::default();
            let mut ctx = Ctx {
                mem: &mut mem,
                prog: self,
                charts: &mut charts,
                sink: &mut sink,
                now: 0,
                scan: 0,
                profile: Default::default(),
                budget: Default::default(),
            };
            // A fault in an initial value leaves the type's default in place.
            for op in &self.support.global_inits {
                let _ = match op {
                    InitOp::Nested { pou, offset } => run_inits(&mut ctx, *pou, *offset as usize),
                    InitOp::Run(f) => f(&mut ctx, 0),
                };
            }
            if top < self.pous.len() {
                let _ = run_inits(&mut ctx, top, top_frame);
            }
        }
        let mut charts = Vec::new();
        if let Some(p) = self.pous.get(top) {
            if let PouBody::Chart(cc) = &p.body {
                mem[top_frame + cc.chart_slot as usize] = Value::Int(0);
                charts.push(ChartInstance { pou: top, frame: top_frame, path: String::new() });
            }
            self.action_charts(top, top_frame, "", &mut mem, &mut charts);
            for v in &p.layout.vars {
                self.walk(&v.ty, top_frame + v.offset as usize, v.name.clone(), &mut mem, &mut charts, 0);
            }
        }
        // The instances of the other programs are listed too: they run only when code calls
        // them (`Unit(bRun := x);`), and a chart's first call is its scan 0.
        let top_global = own.map(|v| v.offset);
        for v in self.globals.vars.iter().filter(|v| Some(v.offset) != top_global) {
            self.walk(&v.ty, v.offset as usize, v.name.clone(), &mut mem, &mut charts, 0);
        }
        Memory { mem, top_frame, charts }
    }

    /// The retentive values of POU `top` (frame at `top_frame`) and of the globals, as
    /// elementary leaves (`Counts[2]`, `Pump.Hours`, `Recipe.Speed`) in declaration order:
    /// variables declared `RETAIN` or `PERSISTENT` (all of an array, a structure or a function
    /// block instance declared so), and those declared so inside function block instances.
    /// At most `limit` leaves.
    pub fn retained(&self, top: usize, top_frame: usize, limit: usize) -> Vec<Retained> {
        let mut out = Vec::new();
        if let Some(p) = self.pous.get(top) {
            for v in p.layout.vars.iter().filter(|v| !v.implicit) {
                let class = class_of(v.retain, v.persistent);
                self.retained_in(&v.ty, top_frame + v.offset as usize, v.name.clone(), class, &mut out, limit, 0);
            }
        }
        for v in self.globals.vars.iter().filter(|v| !v.implicit) {
            let class = class_of(v.retain, v.persistent);
            self.retained_in(&v.ty, v.offset as usize, v.name.clone(), class, &mut out, limit, 0);
        }
        out
    }

    /// The leaves of a value of `ty` at `slot`: all of them when `class` says it is retentive,
    /// else only those of retentive variables of function block instances inside it.
    #[allow(clippy::too_many_arguments)]
    fn retained_in(
        &self,
        ty: &Type,
        slot: usize,
        path: String,
        class: Option<bool>,
        out: &mut Vec<Retained>,
        limit: usize,
        depth: u32,
    ) {
        if depth > 64 || out.len() >= limit {
            return;
        }
        match ty {
            Type::FunctionBlock(name) => {
                let vars = match self.fb_index(name) {
                    Some(j) => &self.pous[j].layout.vars,
                    None => match self.support.std_layouts.get(&name.to_ascii_uppercase()) {
                        Some(l) if class.is_some() => &l.vars,
                        _ => return,
                    },
                };
                for v in vars.iter().filter(|v| !v.implicit) {
                    let inner = match (class, class_of(v.retain, v.persistent)) {
                        (Some(a), Some(b)) => Some(a || b),
                        (a, b) => a.or(b),
                    };
                    let p = format!("{path}.{}", v.name);
                    self.retained_in(&v.ty, slot + v.offset as usize, p, inner, out, limit, depth + 1);
                }
            }
            Type::Array { dims, elem } => {
                if class.is_none() && !self.holds_fb(elem, 0) {
                    return;
                }
                let esize = self.type_size(elem);
                let counts: Vec<i64> = dims.iter().map(|(lo, hi)| hi - lo + 1).collect();
                let total: i64 = counts.iter().product();
                for k in 0..total.max(0) {
                    if out.len() >= limit {
                        return;
                    }
                    let mut rest = k;
                    let mut idx = vec![0i64; dims.len()];
                    for d in (0..dims.len()).rev() {
                        idx[d] = dims[d].0 + rest % counts[d];
                        rest /= counts[d];
                    }
                    let list: Vec<String> = idx.iter().map(|i| i.to_string()).collect();
                    let p = format!("{path}[{}]", list.join(","));
                    self.retained_in(elem, slot + k as usize * esize, p, class, out, limit, depth + 1);
                }
            }
            Type::Struct { fields, .. } => {
                let mut off = 0;
                for (n, t) in fields {
                    self.retained_in(t, slot + off, format!("{path}.{n}"), class, out, limit, depth + 1);
                    off += self.type_size(t);
                }
            }
            t => {
                if let Some(persistent) = class {
                    out.push(Retained { name: path, ty: t.clone(), slot, persistent });
                }
            }
        }
    }

    /// The user POU that is function block type `name`.
    pub(crate) fn fb_index(&self, name: &str) -> Option<usize> {
        self.pous.iter().position(|p| p.kind != PouKind::Function && p.name.eq_ignore_ascii_case(name))
    }

    /// Slots taken by a value of `ty`.
    pub(crate) fn type_size(&self, ty: &Type) -> usize {
        match ty {
            Type::Array { dims, elem } => {
                let n: i64 = dims.iter().map(|(lo, hi)| hi - lo + 1).product();
                n.max(0) as usize * self.type_size(elem)
            }
            Type::Struct { fields, .. } => fields.iter().map(|(_, t)| self.type_size(t)).sum(),
            Type::FunctionBlock(name) => match self.fb_index(name) {
                Some(j) => self.pous[j].layout.size as usize,
                None => self.support.std_layouts.get(&name.to_ascii_uppercase()).map(|l| l.size as usize).unwrap_or(1),
            },
            _ => 1,
        }
    }

    /// The instances of the charts of the actions written in SFC of POU `p`'s frame at `frame`
    /// (instance path `path`): named `path.Action`.
    fn action_charts(&self, p: usize, frame: usize, path: &str, mem: &mut [Value], out: &mut Vec<ChartInstance>) {
        for &sub in &self.pous[p].subs {
            let PouBody::Chart(cc) = &self.pous[sub].body else { continue };
            if let Some(s) = mem.get_mut(frame + cc.chart_slot as usize) {
                *s = Value::Int(out.len() as i64);
            }
            let action = cc.chart.action.as_deref().unwrap_or_default();
            let path = if path.is_empty() { action.to_string() } else { format!("{path}.{action}") };
            out.push(ChartInstance { pou: sub, frame, path });
        }
    }

    /// Finds SFC instances inside a value of `ty` at `slot`, depth first.
    fn walk(&self, ty: &Type, slot: usize, path: String, mem: &mut [Value], out: &mut Vec<ChartInstance>, depth: u32) {
        if depth > 64 {
            return;
        }
        match ty {
            Type::FunctionBlock(name) => {
                let Some(j) = self.fb_index(name) else { return };
                if let PouBody::Chart(cc) = &self.pous[j].body {
                    if let Some(s) = mem.get_mut(slot + cc.chart_slot as usize) {
                        *s = Value::Int(out.len() as i64);
                    }
                    out.push(ChartInstance { pou: j, frame: slot, path: path.clone() });
                }
                self.action_charts(j, slot, &path, mem, out);
                for v in &self.pous[j].layout.vars {
                    self.walk(&v.ty, slot + v.offset as usize, format!("{path}.{}", v.name), mem, out, depth + 1);
                }
            }
            Type::Array { dims, elem } => {
                if !self.holds_fb(elem, 0) {
                    return;
                }
                let esize = self.type_size(elem);
                let counts: Vec<i64> = dims.iter().map(|(lo, hi)| hi - lo + 1).collect();
                let total: i64 = counts.iter().product();
                for k in 0..total.max(0) {
                    let mut rest = k;
                    let mut idx = vec![0i64; dims.len()];
                    for d in (0..dims.len()).rev() {
                        idx[d] = dims[d].0 + rest % counts[d];
                        rest /= counts[d];
                    }
                    let list: Vec<String> = idx.iter().map(|i| i.to_string()).collect();
                    let p = format!("{path}[{}]", list.join(","));
                    self.walk(elem, slot + k as usize * esize, p, mem, out, depth + 1);
                }
            }
            Type::Struct { fields, .. } => {
                let mut off = 0;
                for (n, t) in fields {
                    self.walk(t, slot + off, format!("{path}.{n}"), mem, out, depth + 1);
                    off += self.type_size(t);
                }
            }
            _ => {}
        }
    }

    fn holds_fb(&self, ty: &Type, depth: u32) -> bool {
        if depth > 64 {
            return false;
        }
        match ty {
            Type::FunctionBlock(n) => self.fb_index(n).is_some(),
            Type::Array { elem, .. } => self.holds_fb(elem, depth + 1),
            Type::Struct { fields, .. } => fields.iter().any(|(_, t)| self.holds_fb(t, depth + 1)),
            _ => false,
        }
    }
}
