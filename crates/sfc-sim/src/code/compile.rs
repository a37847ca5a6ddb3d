//! `Program::compile`: frame layouts of every POU, the globals, initial values, and the code of
//! POU bodies, transition conditions, action bodies and associations.

use super::place::{write, Loc, PlaceC};
use super::rt::*;
use super::stmt::to_block;
use super::unit::{Cx, Globals, MethodKind, MethodMeta, PouMeta, SubMeta, Sym, Unit, C};
use super::{
    AssocCode, Block, ChartCode, ControlSlots, DurationCode, FastGuard, Guard, Layout, MethodCode, Place, PouBody,
    PouCode, Program, VarSlot,
};
use crate::value::Value;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::{ActionTarget, Chart, Duration, Target};
use sfc_st::{Type, TypeEnv};
use sfc_syntax::ast::{
    ActionBody, Body, Condition, IlInstruction, Initializer, Item, PouKind, SourceUnit, TypeSpec, TypeSpecKind,
    VarDecl, VarKind,
};
use std::collections::HashMap;

/// Initial-value code of a frame, run in order when the frame is created.
pub(crate) enum InitOp {
    /// Initialise the nested instance of POU `pou` at frame offset `offset`.
    Nested {
        pou: usize,
        offset: u32,
    },
    Run(InitFn),
}

/// What compiled code needs at run time besides the public parts of [`Program`].
#[derive(Default)]
pub(crate) struct Support {
    /// Per POU: the slots of a fresh frame (type defaults, nested instances included).
    pub templates: Vec<Vec<Value>>,
    /// Per POU: the declared initial values.
    pub inits: Vec<Vec<InitOp>>,
    pub globals_template: Vec<Value>,
    pub global_inits: Vec<InitOp>,
    /// Standard function block layouts by upper-case type name.
    pub std_layouts: HashMap<String, Layout>,
}

/// Standard block type names, with the counter variants.
fn std_fb_names() -> Vec<String> {
    let mut out: Vec<String> = sfc_st::stdlib::STD_FUNCTION_BLOCK_NAMES.iter().map(|s| s.to_string()).collect();
    for c in ["CTU", "CTD", "CTUD"] {
        for t in ["DINT", "LINT", "UDINT", "ULINT"] {
            out.push(format!("{c}_{t}"));
        }
    }
    out
}

/// Function block type names used in a type.
fn fb_names(ty: &Type, out: &mut Vec<String>) {
    match ty {
        Type::FunctionBlock(n) => out.push(n.clone()),
        Type::Array { elem, .. } => fb_names(elem, out),
        Type::Struct { fields, .. } => fields.iter().for_each(|(_, t)| fb_names(t, out)),
        _ => {}
    }
}

fn il_depth(list: &[IlInstruction], d: u32) -> u32 {
    if d > 300 {
        return d;
    }
    let mut m = d + 1;
    for i in list {
        if let Some(n) = &i.nested {
            m = m.max(il_depth(n, d + 1));
        }
    }
    m
}

impl Program {
    /// Compiles every POU of a checked file. `unit` is the parsed file whose SFC bodies were
    /// moved into `charts` (see `sfc_model::check_source`: its `charts`, then its
    /// `action_charts`), `types` the checker's expression
    /// types by span (`CheckOptions::keep_types`).
    ///
    /// Err: SFC0320 diagnostics for what cannot be simulated.
    pub fn compile(
        unit: &SourceUnit,
        charts: Vec<Chart>,
        types: &HashMap<Span, Type>,
    ) -> Result<Program, Vec<Diagnostic>> {
        Program::compile_with(unit, charts, types, crate::Profile::Iec)
    }

    /// [`Program::compile`] for a profile: under `matiec`, TIME values are MatIEC's timespecs
    /// (literals truncated as its generated C computes them, `crate::timespec`).
    pub fn compile_with(
        unit: &SourceUnit,
        charts: Vec<Chart>,
        types: &HashMap<Span, Type>,
        profile: crate::Profile,
    ) -> Result<Program, Vec<Diagnostic>> {
        struct Reset(bool);
        impl Drop for Reset {
            fn drop(&mut self) {
                super::MATIEC_TIME.with(|f| f.set(self.0));
            }
        }
        let _reset = Reset(super::MATIEC_TIME.with(|f| f.replace(profile == crate::Profile::Matiec)));
        let mut prog = Program::compile_inner(unit, charts, types)?;
        prog.matiec_time = profile == crate::Profile::Matiec;
        Ok(prog)
    }

    fn compile_inner(
        unit: &SourceUnit,
        charts: Vec<Chart>,
        types: &HashMap<Span, Type>,
    ) -> Result<Program, Vec<Diagnostic>> {
        let (env, _) = TypeEnv::from_unit(unit);
        let mut std_layouts = HashMap::new();
        for n in std_fb_names() {
            if let Some(l) = super::stdfb::std_layout(&n) {
                std_layouts.insert(n, l);
            }
        }
        let mut type_decls = HashMap::new();
        for item in &unit.items {
            if let Item::Types(b) = item {
                for d in &b.decls {
                    type_decls.entry(d.name.key()).or_insert(d);
                }
            }
        }
        let mut pous = Vec::new();
        let mut pou_index = HashMap::new();
        for (item_idx, item) in unit.items.iter().enumerate() {
            let Item::Pou(p) = item else { continue };
            let Some(iface) = env.interface_of(p).cloned() else {
                continue;
            };
            pou_index.entry(p.name.key()).or_insert(pous.len());
            // The charts of its actions written in SFC come after those of the POUs'.
            let subs = (0..charts.len())
                .filter(|&c| charts[c].item == item_idx && charts[c].action.is_some())
                .map(|chart| SubMeta { chart, ..Default::default() })
                .collect();
            pous.push(PouMeta {
                ast: p,
                iface,
                chart: charts.iter().position(|c| c.item == item_idx && c.action.is_none()),
                subs,
                layout: Layout::default(),
                names: HashMap::new(),
                step_x: Vec::new(),
                step_t: Vec::new(),
                step_vendor: Vec::new(),
                step_members: Default::default(),
                action_q: Vec::new(),
                action_a: Vec::new(),
                control: ControlSlots::default(),
                chart_slot: 0,
                il_base: 0,
                il_slots: 0,
                result: None,
                methods: Vec::new(),
                edges: Vec::new(),
            });
        }
        let mut u = Unit {
            env,
            types,
            ast: unit,
            charts: &charts,
            pous,
            pou_index,
            std_layouts,
            globals: Default::default(),
            diags: Default::default(),
            type_decls,
        };
        let order = layout_order(&u);
        for &i in &order {
            lay_out(&mut u, i);
        }
        lay_out_globals(&u);
        for i in 0..u.pous.len() {
            fill_names(&mut u, i);
        }
        let templates = frame_templates(&u, &order);
        {
            let mut t = Vec::new();
            for v in u.env.globals() {
                t.extend(template_of(&u, &v.ty, &templates));
            }
            u.globals.borrow_mut().template = t;
        }
        let mut inits = Vec::new();
        for i in 0..u.pous.len() {
            inits.push(frame_inits(&u, i));
        }
        let global_inits = globals_inits(&u);
        let mut bodies: Vec<Compiled> = Vec::new();
        for i in 0..u.pous.len() {
            bodies.push(compile_pou(&u, i, &templates[i]));
        }
        let mut methods: Vec<Vec<MethodCode>> =
            (0..u.pous.len()).map(|i| compile_methods(&u, i, &templates[i])).collect();
        check_function_frames(&u);
        let diags = u.diags.into_inner();
        if !diags.is_empty() {
            return Err(diags);
        }
        let globals: Globals = u.globals.into_inner();
        let mut std_plain = HashMap::new();
        for (k, (l, _)) in u.std_layouts {
            std_plain.insert(k, l);
        }
        struct Parts {
            name: String,
            kind: PouKind,
            layout: Layout,
            chart: Option<usize>,
            step_x: Vec<u32>,
            step_t: Vec<u32>,
            step_vendor: Vec<u32>,
            step_members: super::StepMembers,
            action_q: Vec<u32>,
            action_a: Vec<u32>,
            control: ControlSlots,
            chart_slot: u32,
            subs: Vec<SubMeta>,
            wiring: super::wiring::Wiring,
            edges: Vec<(u32, u32, bool)>,
        }
        let parts: Vec<Parts> = u
            .pous
            .into_iter()
            .map(|m| Parts {
                name: m.ast.name.text.clone(),
                wiring: super::wiring::Wiring::of(m.ast),
                kind: m.ast.kind,
                layout: m.layout,
                chart: m.chart,
                step_x: m.step_x,
                step_t: m.step_t,
                step_vendor: m.step_vendor,
                step_members: m.step_members,
                action_q: m.action_q,
                action_a: m.action_a,
                control: m.control,
                chart_slot: m.chart_slot,
                subs: m.subs,
                edges: m.edges,
            })
            .collect();
        let mut charts: Vec<Option<Chart>> = charts.into_iter().map(Some).collect();
        let mut out = Vec::new();
        // The charts of actions written in SFC: each a POU of its own after the file's, named
        // `Pou.Action`, laid out in its POU's frame.
        let mut extra: Vec<PouCode> = Vec::new();
        let first_extra = parts.len();
        for ((meta, body), methods) in parts.into_iter().zip(bodies).zip(methods.drain(..)) {
            let mut actions = Vec::new();
            let (body, sub_parts) = match body {
                Compiled::Code(b, a, subs) => {
                    actions = a;
                    (PouBody::Code(b), subs)
                }
                Compiled::Chart(main, subs) => {
                    let chart = meta.chart.and_then(|c| charts[c].take()).expect("chart POUs have a chart");
                    let code = chart_code(chart, &meta.step_x, &meta.step_t, meta.action_q, meta.action_a, main);
                    (
                        PouBody::Chart(Box::new(ChartCode {
                            control: meta.control,
                            chart_slot: meta.chart_slot,
                            step_vendor: meta.step_vendor,
                            step_members: meta.step_members,
                            ..code
                        })),
                        subs,
                    )
                }
            };
            let mut subs = Vec::new();
            for (sub, p) in meta.subs.into_iter().zip(sub_parts) {
                let Some(chart) = charts[sub.chart].take() else { continue };
                let name = format!("{}.{}", meta.name, chart.action.as_deref().unwrap_or_default());
                let x = &meta.step_x[sub.steps.clone()];
                let t = &meta.step_t[sub.steps.clone()];
                let code = chart_code(chart, x, t, sub.action_q, sub.action_a, p);
                subs.push(first_extra + extra.len());
                extra.push(PouCode {
                    name,
                    kind: meta.kind,
                    layout: meta.layout.clone(),
                    body: PouBody::Chart(Box::new(ChartCode {
                        control: sub.control,
                        chart_slot: sub.chart_slot,
                        ..code
                    })),
                    actions: Vec::new(),
                    subs: Vec::new(),
                    wiring: meta.wiring.clone(),
                    methods: Vec::new(),
                    edges: Vec::new(),
                });
            }
            out.push(PouCode {
                name: meta.name,
                kind: meta.kind,
                layout: meta.layout,
                body,
                actions,
                subs,
                wiring: meta.wiring,
                methods,
                edges: meta.edges,
            });
        }
        // Frames are never made of an action's chart: its templates and initial values are its
        // POU's, and empty here.
        let mut templates = templates;
        let mut inits = inits;
        for _ in &extra {
            templates.push(Vec::new());
            inits.push(Vec::new());
        }
        out.extend(extra);
        Ok(Program {
            pous: out,
            globals: globals.layout,
            support: Support {
                templates,
                inits,
                globals_template: globals.template,
                global_inits,
                std_layouts: std_plain,
            },
            matiec_time: false,
        })
    }

    /// Index of the POU with this name (case-insensitive).
    pub fn pou(&self, name: &str) -> Option<usize> {
        self.pous.iter().position(|p| p.name.eq_ignore_ascii_case(name))
    }
}

enum Compiled {
    /// The body and the actions after it, and the charts of those written in SFC.
    Code(Block, Vec<Block>, Vec<ChartParts>),
    /// The chart, and the charts of its actions written in SFC.
    Chart(ChartParts, Vec<ChartParts>),
}

/// POUs in an order where every block type comes before the POUs that contain instances of it;
/// a block that contains itself is reported.
fn layout_order(u: &Unit<'_>) -> Vec<usize> {
    let n = u.pous.len();
    let mut state = vec![0u8; n];
    let mut order = Vec::with_capacity(n);
    fn visit(u: &Unit<'_>, i: usize, state: &mut [u8], order: &mut Vec<usize>, depth: u32) {
        if state[i] == 2 {
            return;
        }
        if state[i] == 1 || depth > 200 {
            let m = &u.pous[i];
            u.report(u.error(
                m.ast.name.span,
                format!(
                    "function block `{}` contains an instance of itself, so its memory would be infinite",
                    m.name()
                ),
            ));
            return;
        }
        state[i] = 1;
        let mut names = Vec::new();
        for v in &u.pous[i].iface.vars {
            fb_names(&v.ty, &mut names);
        }
        for (_, _, sig, _) in class_methods(u, i) {
            for v in sig.vars.iter() {
                fb_names(&v.ty, &mut names);
            }
            if let Some(t) = &sig.return_type {
                fb_names(t, &mut names);
            }
        }
        for name in names {
            if let Some(j) = u.fb_pou(&name) {
                visit(u, j, state, order, depth + 1);
            }
        }
        state[i] = 2;
        order.push(i);
    }
    for i in 0..n {
        visit(u, i, &mut state, &mut order, 0);
    }
    order
}

/// Whether variable `v` of POU `m` is a global seen through VAR_EXTERNAL or a PROGRAM's
/// VAR_GLOBAL (it has no slot in the frame).
fn is_global_ref(u: &Unit<'_>, m: &PouMeta<'_>, v: &sfc_st::VarInfo) -> bool {
    let g = match v.kind {
        VarKind::External => u.env.global(&v.name).is_some(),
        VarKind::Global => m.kind() == PouKind::Program && u.env.global(&v.name).is_some_and(|g| g.span == v.span),
        _ => false,
    };
    g
}

fn lay_out(u: &mut Unit<'_>, i: usize) {
    let m = &u.pous[i];
    let mut vars = Vec::new();
    let mut off: u32 = 0;
    for v in &m.iface.vars {
        if is_global_ref(u, m, v) {
            continue;
        }
        let size = u.type_size(&v.ty);
        vars.push(VarSlot {
            name: v.name.clone(),
            ty: v.ty.clone(),
            kind: v.kind,
            offset: off,
            size,
            location: v.location.as_ref().map(|l| l.text.clone()),
            implicit: v.implicit,
            retain: v.retain == Some(sfc_syntax::ast::Retain::Retain),
            persistent: v.persistent,
        });
        off += size;
    }
    let chart = m.chart.map(|c| &u.charts[c]);
    if let Some(ch) = chart {
        let (count, upper) = match ch.target {
            Target::Atmt => (16, true),
            Target::Eatmt => (256, false),
            Target::Blank => (0, true),
        };
        for n in 0..count {
            let name = if upper { format!("C{n}") } else { format!("c{n}") };
            if m.iface.vars.iter().any(|v| v.name.eq_ignore_ascii_case(&name)) {
                continue;
            }
            vars.push(hidden_slot(name, Type::Bool, VarKind::Input, off));
            off += 1;
        }
    }
    let mut step_x = Vec::new();
    let mut step_t = Vec::new();
    let mut step_vendor = Vec::new();
    let mut step_members = super::StepMembers::Iec;
    let mut action_q = Vec::new();
    let mut action_a = Vec::new();
    if let Some(ch) = chart {
        for _ in &ch.steps {
            step_x.push(off);
            step_t.push(off + 1);
            off += 2;
        }
        for _ in &ch.actions {
            action_q.push(off);
            action_a.push(off + 1);
            off += 2;
        }
        let (members, width) = super::StepMembers::of(m.ast);
        step_members = members;
        if width > 0 {
            for _ in &ch.steps {
                step_vendor.push(off);
                off += width;
            }
        }
    }
    let mut subs = m.subs.clone();
    for sub in &mut subs {
        let ch = &u.charts[sub.chart];
        let first = step_x.len();
        for _ in &ch.steps {
            step_x.push(off);
            step_t.push(off + 1);
            off += 2;
        }
        sub.steps = first..step_x.len();
        for _ in &ch.actions {
            sub.action_q.push(off);
            sub.action_a.push(off + 1);
            off += 2;
        }
    }
    let mut il = 0;
    if let Body::Il(b) = &m.ast.body {
        il = il.max(il_depth(&b.instructions, 0));
    }
    for a in &m.ast.actions {
        if let ActionBody::Il(b) = &a.body {
            il = il.max(il_depth(&b.instructions, 0));
        }
    }
    for ch in chart.into_iter().chain(subs.iter().map(|s| &u.charts[s.chart])) {
        for a in &ch.actions {
            if let ActionBody::Il(b) = &a.body {
                il = il.max(il_depth(&b.instructions, 0));
            }
        }
        for t in &ch.transitions {
            if let Condition::Il(b) = &t.condition {
                il = il.max(il_depth(&b.instructions, 0));
            }
        }
    }
    let il_base = off;
    off += il;
    let mut chart_slot = 0;
    if chart.is_some() {
        chart_slot = off;
        off += 1;
    }
    for sub in &mut subs {
        sub.chart_slot = off;
        off += 1;
    }
    // Each action chart's own SFC flags, as hidden variables `Act.SFCInit`, … of the frame.
    for sub in &mut subs {
        let action = u.charts[sub.chart].action.clone().unwrap_or_default();
        let mut flag = |name: &str, ty: Type, kind: VarKind| {
            let at = off;
            vars.push(hidden_slot(format!("{action}.{name}"), ty, kind, at));
            off += 1;
            at
        };
        let s = Type::String { len: None };
        sub.control = ControlSlots {
            init: flag("SFCInit", Type::Bool, VarKind::Input),
            pause: flag("SFCPause", Type::Bool, VarKind::Input),
            quit_error: flag("SFCQuitError", Type::Bool, VarKind::Input),
            error: flag("SFCError", Type::Bool, VarKind::Output),
            error_step: flag("SFCErrorStep", s.clone(), VarKind::Output),
            current_step: flag("SFCCurrentStep", s, VarKind::Output),
            reset: Some(flag("SFCReset", Type::Bool, VarKind::Input)),
            ..Default::default()
        };
    }
    let mut result = None;
    if m.kind() == PouKind::Function {
        let rt = m.iface.return_type.clone().unwrap_or(Type::Bool);
        result = Some((off, rt.clone()));
        off += u.type_size(&rt);
    }
    // Edge-triggered inputs: each with a slot for the value its previous call passed.
    let mut edges = Vec::new();
    // (An inherited input is declared by the base that declares it.)
    let chain: Vec<&sfc_syntax::ast::Pou> = class_chain(u, i).into_iter().map(|c| u.pous[c].ast).collect();
    for v in &m.iface.vars {
        let Some(edge) = chain.iter().find_map(|p| decl_of(p, &v.name)).and_then(|d| d.edge) else { continue };
        let Some(slot) = vars.iter().find(|s| s.name.eq_ignore_ascii_case(&v.name)).map(|s| s.offset) else { continue };
        vars.push(hidden_slot(format!("{}.prev", v.name), Type::Bool, VarKind::Var, off));
        edges.push((slot, off, edge == sfc_syntax::ast::Edge::Rising));
        off += 1;
    }
    // Methods and property accessors: their variables and result are slots of the frame.
    let mut methods = Vec::new();
    for (kind, owner, sig, body) in class_methods(u, i) {
        let suffix = match kind {
            MethodKind::Method => "",
            MethodKind::Get => ".GET",
            MethodKind::Set => ".SET",
        };
        let prefix = format!("{}.{}{suffix}", u.pous[owner].name(), sig.name);
        let mut names = HashMap::new();
        let mut mvars = Vec::new();
        let result = sig.return_type.clone().map(|t| (sig.name.clone(), t));
        let all = sig.vars.iter().map(|v| (v.name.clone(), v.ty.clone(), v.constant.then_some(v.value).flatten()));
        for (name, ty, konst) in all.chain(result.map(|(n, t)| (n, t, None))) {
            let size = u.type_size(&ty);
            let slot = VarSlot {
                name: format!("{prefix}.{name}"),
                ty: ty.clone(),
                kind: VarKind::Var,
                offset: off,
                size,
                location: None,
                implicit: true,
                retain: false,
                persistent: false,
            };
            names.insert(name.to_ascii_uppercase(), Sym::Var { place: Place::Local(off), ty, konst });
            mvars.push(slot.clone());
            vars.push(slot);
            off += size;
        }
        methods.push(MethodMeta { kind, owner, sig, body, names, vars: mvars });
    }
    let find = |name: &str| vars.iter().find(|v: &&VarSlot| v.name.eq_ignore_ascii_case(name)).map(|v| v.offset);
    // CODESYS's other SFC flags act only when declared (with their type; a STRING of any length).
    let declared = |name: &str, ty: &Type| {
        vars.iter()
            .find(|v: &&VarSlot| !v.implicit && v.size == 1 && v.name.eq_ignore_ascii_case(name))
            .filter(|v| if ty.is_string() { v.ty.is_string() } else { v.ty == *ty })
            .map(|v| v.offset)
    };
    let control = ControlSlots {
        init: find("SFCInit").unwrap_or(0),
        pause: find("SFCPause").unwrap_or(0),
        quit_error: find("SFCQuitError").unwrap_or(0),
        error: find("SFCError").unwrap_or(0),
        error_step: find("SFCErrorStep").unwrap_or(0),
        current_step: find("SFCCurrentStep").unwrap_or(0),
        reset: declared("SFCReset", &Type::Bool),
        enable_limit: declared("SFCEnableLimit", &Type::Bool),
        error_pou: declared("SFCErrorPOU", &Type::String { len: None }),
        trans: declared("SFCTrans", &Type::Bool),
        tip: declared("SFCTip", &Type::Bool),
        tip_mode: declared("SFCTipMode", &Type::Bool),
        ack_ef: declared("ACK_EF", &Type::Bool),
        init_sq: declared("INIT_SQ", &Type::Bool),
        off_sq: declared("OFF_SQ", &Type::Bool),
        err_flt: declared("ERR_FLT", &Type::Bool),
    };
    let m = &mut u.pous[i];
    m.layout = Layout { vars, size: off };
    m.step_x = step_x;
    m.step_t = step_t;
    m.step_vendor = step_vendor;
    m.step_members = step_members;
    m.action_q = action_q;
    m.action_a = action_a;
    m.control = control;
    m.chart_slot = chart_slot;
    m.subs = subs;
    m.il_base = il_base;
    m.il_slots = il;
    m.result = result;
    m.methods = methods;
    m.edges = edges;
}

/// The actions of POU `i` that is no chart, in the order of `PouCode::actions`: its own, then
/// those its bases declare (written in ST or IL) that it does not declare again, compiled for
/// its frame.
pub(crate) fn pou_actions<'a>(u: &Unit<'a>, i: usize) -> Vec<&'a sfc_syntax::ast::Action> {
    let own: &'a sfc_syntax::ast::Pou = u.pous[i].ast;
    let mut out: Vec<&'a sfc_syntax::ast::Action> = own.actions.iter().collect();
    for b in class_chain(u, i).into_iter().skip(1) {
        let base: &'a sfc_syntax::ast::Pou = u.pous[b].ast;
        for a in &base.actions {
            if a.body.sfc().is_none() && !out.iter().any(|x| x.name.key() == a.name.key()) {
                out.push(a);
            }
        }
    }
    out
}

/// POU `i` and its bases (`EXTENDS`), nearest first.
pub(crate) fn class_chain(u: &Unit<'_>, i: usize) -> Vec<usize> {
    let mut out = vec![i];
    let mut at = i;
    while let Some(b) = u.pous[at].iface.base.as_deref().and_then(|b| u.fb_pou(b)) {
        if out.contains(&b) {
            break;
        }
        out.push(b);
        at = b;
    }
    out
}

/// The methods and property accessors a frame of POU `i` holds: those its class and each of
/// its bases declare (overridden ones too, for `SUPER^.M()`), with the POU declaring each.
fn class_methods<'a>(u: &Unit<'a>, i: usize) -> Vec<(MethodKind, usize, sfc_st::MethodSig, &'a Body)> {
    let mut out = Vec::new();
    for c in class_chain(u, i) {
        let m = &u.pous[c];
        let ast: &'a sfc_syntax::ast::Pou = m.ast;
        for d in &ast.methods {
            if let Some(sig) = m.iface.methods.iter().find(|s| s.span == d.name.span) {
                out.push((MethodKind::Method, c, sig.clone(), &d.body));
            }
        }
        for p in &ast.properties {
            let Some(ps) = m.iface.properties.iter().find(|s| s.span == p.name.span) else { continue };
            if let (Some(a), Some(sig)) = (&p.get, &ps.get) {
                out.push((MethodKind::Get, c, sig.clone(), &a.body));
            }
            if let (Some(a), Some(sig)) = (&p.set, &ps.set) {
                out.push((MethodKind::Set, c, sig.clone(), &a.body));
            }
        }
    }
    out
}

/// The compiled methods of POU `i` (in [`PouMeta::methods`] order): the initial values of
/// their variables, run at every call, and their statements.
fn compile_methods(u: &Unit<'_>, i: usize, template: &[Value]) -> Vec<MethodCode> {
    let mut out = Vec::new();
    for (k, mm) in u.pous[i].methods.iter().enumerate() {
        let cx = Cx { u, pou: Some(i), method: Some(k), owner: None };
        let mut init = Vec::new();
        let mut r: C<()> = Ok(());
        for (slot, v) in mm.vars.iter().zip(mm.sig.vars.iter().map(Some).chain(std::iter::repeat(None))) {
            let (off, size) = (slot.offset as usize, slot.size as usize);
            let fresh: Vec<Value> = template.get(off..off + size).map(<[Value]>::to_vec).unwrap_or_default();
            init.push(InitOp::Run(Box::new(move |c, b| {
                c.mem[b + off..b + off + fresh.len()].clone_from_slice(&fresh);
                Ok(())
            })));
            let loc = Loc::Static(Place::Local(slot.offset));
            r = r.and_then(|_| cx.type_inits(&slot.ty, None, &loc, &mut init, 0));
            if let Some(initial) = v.and_then(|v| v.init.as_ref()) {
                r = r.and_then(|_| cx.initializer(initial, &slot.ty, &loc, &mut init));
            }
        }
        let body = r.and_then(|_| match mm.body {
            Body::St(stmts) => cx.stmt_list(stmts).map(to_block),
            Body::Il(il) => cx.il_block(il),
            Body::Sfc(_) => Err(u.error(mm.sig.span, "a method written in SFC")),
        });
        let body = body.unwrap_or_else(|d| {
            u.report(d);
            placeholder_block()
        });
        out.push(MethodCode { init, body });
    }
    out
}

/// A one-slot variable of a frame that the user did not declare.
fn hidden_slot(name: String, ty: Type, kind: VarKind, offset: u32) -> VarSlot {
    VarSlot { name, ty, kind, offset, size: 1, location: None, implicit: true, retain: false, persistent: false }
}

fn lay_out_globals(u: &Unit<'_>) {
    let mut g = u.globals.borrow_mut();
    let mut off = 0;
    for v in u.env.globals() {
        let size = u.type_size(&v.ty);
        let key = v.name.to_ascii_uppercase();
        let n = g.layout.vars.len();
        g.index.insert(key.clone(), n);
        if v.constant {
            if let Some(k) = v.value {
                g.konst.insert(key, k);
            }
        }
        g.layout.vars.push(VarSlot {
            name: v.name.clone(),
            ty: v.ty.clone(),
            kind: VarKind::Global,
            offset: off,
            size,
            location: v.location.as_ref().map(|l| l.text.clone()),
            // A program's instance (`Main`), not declared by the user.
            implicit: v.implicit,
            retain: v.retain == Some(sfc_syntax::ast::Retain::Retain),
            persistent: v.persistent,
        });
        off += size;
    }
    g.layout.size = off;
}

fn fill_names(u: &mut Unit<'_>, i: usize) {
    let mut names: HashMap<String, Sym> = HashMap::new();
    {
        let m = &u.pous[i];
        for v in &m.iface.vars {
            let key = v.name.to_ascii_uppercase();
            if names.contains_key(&key) {
                continue;
            }
            let konst = if v.constant { v.value } else { None };
            if is_global_ref(u, m, v) {
                if let Some((slot, ty, k)) = u.global(&v.name) {
                    names.insert(key, Sym::Var { place: Place::Global(slot), ty, konst: k.or(konst) });
                }
                continue;
            }
            if let Some(s) = m.var(&v.name) {
                names.insert(key, Sym::Var { place: Place::Local(s.offset), ty: s.ty.clone(), konst });
            }
        }
        for s in m.layout.vars.iter().filter(|s| s.implicit) {
            names.entry(s.name.to_ascii_uppercase()).or_insert(Sym::Var {
                place: Place::Local(s.offset),
                ty: s.ty.clone(),
                konst: None,
            });
        }
        if let Some(c) = m.chart {
            let ch = &u.charts[c];
            for (k, s) in ch.steps.iter().enumerate() {
                names.entry(s.name.to_ascii_uppercase()).or_insert(Sym::Step(k));
            }
            for (k, a) in ch.actions.iter().enumerate() {
                names.entry(a.name.to_ascii_uppercase()).or_insert(Sym::Action(k));
            }
        } else {
            // The actions of a POU that is no chart, by their index in `PouCode::actions`.
            for (k, a) in pou_actions(u, i).into_iter().enumerate() {
                names.entry(a.name.text.to_ascii_uppercase()).or_insert(Sym::Action(k));
            }
        }
        // The steps of its actions written in SFC, by their index in the POU's `step_x`.
        for sub in &m.subs {
            for (k, s) in u.charts[sub.chart].steps.iter().enumerate() {
                names.entry(s.name.to_ascii_uppercase()).or_insert(Sym::Step(sub.steps.start + k));
            }
        }
    }
    u.pous[i].names = names;
}

/// The slots of a fresh value of `ty` (nested instances with their own defaults).
fn template_of(u: &Unit<'_>, ty: &Type, frames: &[Vec<Value>]) -> Vec<Value> {
    match ty {
        Type::Array { dims, elem } => {
            let one = template_of(u, elem, frames);
            let n: i64 = dims.iter().map(|(lo, hi)| hi - lo + 1).product();
            let mut out = Vec::with_capacity(one.len() * n.max(0) as usize);
            for _ in 0..n.max(0) {
                out.extend_from_slice(&one);
            }
            out
        }
        Type::Struct { fields, .. } => fields.iter().flat_map(|(_, t)| template_of(u, t, frames)).collect(),
        Type::FunctionBlock(name) => match u.fb_pou(name) {
            Some(j) => frames
                .get(j)
                .cloned()
                .filter(|f| !f.is_empty())
                .unwrap_or_else(|| vec![Value::Bool(false); u.pous[j].layout.size as usize]),
            None => u
                .std_layouts
                .get(&name.to_ascii_uppercase())
                .map(|(_, t)| t.clone())
                .unwrap_or_else(|| vec![Value::Bool(false)]),
        },
        t => vec![default_value(t)],
    }
}

fn frame_templates(u: &Unit<'_>, order: &[usize]) -> Vec<Vec<Value>> {
    let mut frames: Vec<Vec<Value>> = vec![Vec::new(); u.pous.len()];
    for &i in order {
        let m = &u.pous[i];
        let mut t = vec![Value::Bool(false); m.layout.size as usize];
        for v in &m.layout.vars {
            let vals = template_of(u, &v.ty, &frames);
            for (k, x) in vals.into_iter().enumerate() {
                if let Some(slot) = t.get_mut(v.offset as usize + k) {
                    *slot = x;
                }
            }
        }
        for &o in &m.step_t {
            t[o as usize] = Value::Time(0);
        }
        if m.chart.is_some() {
            t[m.chart_slot as usize] = Value::Int(0);
        }
        if let Some((o, rt)) = &m.result {
            for (k, x) in template_of(u, rt, &frames).into_iter().enumerate() {
                t[*o as usize + k] = x;
            }
        }
        frames[i] = t;
    }
    frames
}

/// The declaration of variable `name` in a POU's var blocks.
fn decl_of<'a>(pou: &'a sfc_syntax::ast::Pou, name: &str) -> Option<&'a VarDecl> {
    pou.var_blocks.iter().flat_map(|b| b.decls.iter()).find(|d| d.names.iter().any(|n| n.is(name)))
}

impl Cx<'_, '_> {
    /// Initial-value code for a value of `ty` declared with `spec` at `loc`: nested instances,
    /// then the default initial values of named types and structure fields.
    fn type_inits(&self, ty: &Type, spec: Option<&TypeSpec>, loc: &Loc, out: &mut Vec<InitOp>, depth: u32) -> C<()> {
        if depth > 64 {
            return Ok(());
        }
        if let Some(TypeSpec { kind: TypeSpecKind::Named(id), .. }) = spec {
            if let Some(decl) = self.u.type_decls.get(&id.key()) {
                let g = Cx { u: self.u, pou: None, method: None, owner: None };
                g.type_inits(ty, Some(&decl.spec), loc, out, depth + 1)?;
                if let Some(init) = &decl.init {
                    g.initializer(init, ty, loc, out)?;
                }
                return Ok(());
            }
        }
        match ty {
            Type::FunctionBlock(name) => {
                if let Some(j) = self.u.fb_pou(name) {
                    match loc {
                        Loc::Static(Place::Local(o)) => out.push(InitOp::Nested { pou: j, offset: *o }),
                        Loc::Static(Place::Global(g)) => out.push(InitOp::Nested { pou: j, offset: *g }),
                        Loc::Dyn(_) => {}
                    }
                }
            }
            Type::Array { dims, elem } => {
                let elem_spec = match spec {
                    Some(TypeSpec { kind: TypeSpecKind::Array { element, .. }, .. }) => Some(element.as_ref()),
                    _ => None,
                };
                if !self.needs_init(elem, elem_spec, depth) {
                    return Ok(());
                }
                let n: i64 = dims.iter().map(|(lo, hi)| hi - lo + 1).product();
                let esize = self.u.type_size(elem);
                for k in 0..n.max(0) as u32 {
                    self.type_inits(elem, elem_spec, &loc.clone().offset(k * esize), out, depth + 1)?;
                }
            }
            Type::Struct { fields, .. } => {
                let decls: Vec<(&VarDecl, usize)> = match spec {
                    Some(TypeSpec { kind: TypeSpecKind::Struct(decls), .. }) => {
                        decls.iter().flat_map(|d| (0..d.names.len()).map(move |k| (d, k))).collect()
                    }
                    _ => Vec::new(),
                };
                let mut off = 0;
                for (fi, (fname, fty)) in fields.iter().enumerate() {
                    let floc = loc.clone().offset(off);
                    let d = decls.iter().find(|(d, k)| d.names[*k].text.eq_ignore_ascii_case(fname)).map(|(d, _)| *d);
                    self.type_inits(fty, d.map(|d| &d.ty), &floc, out, depth + 1)?;
                    let init = d.and_then(|d| d.init.as_ref()).or_else(|| {
                        let name = match ty {
                            Type::Struct { name: Some(n), .. } => n,
                            _ => return None,
                        };
                        let def = self.u.env.type_def(name)?;
                        def.field_inits.get(fi)?.as_ref()
                    });
                    if let Some(init) = init {
                        self.initializer(init, fty, &floc, out)?;
                    }
                    off += self.u.type_size(fty);
                }
            }
            Type::Enum { name: Some(n), .. } => {
                if let Some(def) = self.u.env.type_def(n) {
                    if let Some(init) = &def.init {
                        Cx { u: self.u, pou: None, method: None, owner: None }.initializer(init, ty, loc, out)?;
                    }
                }
            }
            _ => {}
        }
        Ok(())
    }

    fn needs_init(&self, ty: &Type, spec: Option<&TypeSpec>, depth: u32) -> bool {
        if depth > 64 {
            return false;
        }
        if let Some(TypeSpec { kind: TypeSpecKind::Named(id), .. }) = spec {
            if self.u.type_decls.contains_key(&id.key()) {
                return true;
            }
        }
        match ty {
            Type::FunctionBlock(n) => self.u.fb_pou(n).is_some(),
            Type::Array { elem, .. } => self.needs_init(elem, None, depth + 1),
            Type::Struct { .. } => true,
            Type::Enum { name: Some(_), .. } => true,
            _ => false,
        }
    }

    /// Code for a declared initial value of a value of `ty` at `loc`.
    fn initializer(&self, init: &Initializer, ty: &Type, loc: &Loc, out: &mut Vec<InitOp>) -> C<()> {
        match init {
            Initializer::Expr(e) => {
                let v = self.expr_as(e, ty)?;
                let size = self.u.type_size(ty);
                let w = write(PlaceC::new(loc.clone(), ty.clone()), v, size);
                out.push(InitOp::Run(Box::new(move |c, b| {
                    w(c, b)?;
                    Ok(())
                })));
            }
            Initializer::Array { elements, span } => {
                let Type::Array { dims, elem } = ty else {
                    return Err(self.error(*span, "an array initial value for a non-array"));
                };
                let total: i64 = dims.iter().map(|(lo, hi)| hi - lo + 1).product();
                let esize = self.u.type_size(elem);
                let mut k: i64 = 0;
                for el in elements {
                    let count = match &el.repeat {
                        None => 1,
                        Some(r) => {
                            let v = self.expr(r, Some(&Type::DInt))?;
                            int_of(
                                &v.const_value()
                                    .ok_or_else(|| self.error(r.span, "a repetition count must be constant"))?,
                            )
                        }
                    };
                    for _ in 0..count.max(0) {
                        if k >= total {
                            break;
                        }
                        if let Some(v) = &el.value {
                            self.initializer(v, elem, &loc.clone().offset(k as u32 * esize), out)?;
                        }
                        k += 1;
                    }
                }
            }
            Initializer::Struct { fields, span } => {
                for (name, value) in fields {
                    let (off, fty) = match ty {
                        Type::Struct { fields: fs, .. } => {
                            let mut off = 0;
                            let mut found = None;
                            for (n, t) in fs {
                                if n.eq_ignore_ascii_case(&name.text) {
                                    found = Some((off, t.clone()));
                                    break;
                                }
                                off += self.u.type_size(t);
                            }
                            found.ok_or_else(|| self.error(name.span, format!("no field `{}`", name.text)))?
                        }
                        Type::FunctionBlock(fb) => {
                            let (o, t, _) = self
                                .u
                                .fb_param(fb, &name.text)
                                .ok_or_else(|| self.error(name.span, format!("no parameter `{}`", name.text)))?;
                            (o, t)
                        }
                        _ => return Err(self.error(*span, "a structure initial value for a non-structure")),
                    };
                    self.initializer(value, &fty, &loc.clone().offset(off), out)?;
                }
            }
        }
        Ok(())
    }
}

fn frame_inits(u: &Unit<'_>, i: usize) -> Vec<InitOp> {
    let cx = Cx { u, pou: Some(i), method: None, owner: None };
    let m = &u.pous[i];
    let mut out = Vec::new();
    for v in &m.layout.vars {
        if v.implicit {
            continue;
        }
        let info = m.iface.var(&v.name);
        let decl = decl_of(m.ast, &v.name);
        let loc = Loc::Static(Place::Local(v.offset));
        let r = cx.type_inits(&v.ty, decl.map(|d| &d.ty), &loc, &mut out, 0).and_then(|_| {
            match info.and_then(|i| i.init.as_ref()) {
                Some(init) => cx.initializer(init, &v.ty, &loc, &mut out),
                None => Ok(()),
            }
        });
        if let Err(d) = r {
            u.report(d);
        }
    }
    out
}

fn globals_inits(u: &Unit<'_>) -> Vec<InitOp> {
    let cx = Cx { u, pou: None, method: None, owner: None };
    let mut out = Vec::new();
    let decls: Vec<&VarDecl> = u
        .ast
        .items
        .iter()
        .flat_map(|it| match it {
            Item::Globals(b) => b.decls.iter().collect::<Vec<_>>(),
            Item::Pou(p) if p.kind == PouKind::Program => {
                p.var_blocks.iter().filter(|b| b.kind == VarKind::Global).flat_map(|b| b.decls.iter()).collect()
            }
            _ => Vec::new(),
        })
        .collect();
    for v in u.env.globals() {
        let Some((slot, ty, _)) = u.global(&v.name) else {
            continue;
        };
        let loc = Loc::Static(Place::Global(slot));
        let decl = decls.iter().find(|d| d.names.iter().any(|n| n.span == v.span));
        let r = cx.type_inits(&ty, decl.map(|d| &d.ty), &loc, &mut out, 0).and_then(|_| match &v.init {
            Some(init) => cx.initializer(init, &ty, &loc, &mut out),
            None => Ok(()),
        });
        if let Err(d) = r {
            u.report(d);
        }
    }
    out
}

fn placeholder_block() -> Block {
    Box::new(|_, _| Ok(()))
}

/// The VAR_TEMP variables of a FUNCTION_BLOCK or PROGRAM take their initial values again at
/// every call (a FUNCTION's whole frame is fresh anyway).
fn temp_inits(u: &Unit<'_>, i: usize, template: &[Value]) -> C<Vec<InitOp>> {
    let cx = Cx { u, pou: Some(i), method: None, owner: None };
    let m = &u.pous[i];
    let mut out = Vec::new();
    if m.kind() == PouKind::Function {
        return Ok(out);
    }
    for v in m.layout.vars.iter().filter(|v| v.kind == VarKind::Temp) {
        let (off, size) = (v.offset as usize, v.size as usize);
        let fresh: Vec<Value> = template.get(off..off + size).map(<[Value]>::to_vec).unwrap_or_default();
        out.push(InitOp::Run(Box::new(move |c, b| {
            c.mem[b + off..b + off + fresh.len()].clone_from_slice(&fresh);
            Ok(())
        })));
        let loc = Loc::Static(Place::Local(v.offset));
        cx.type_inits(&v.ty, decl_of(m.ast, &v.name).map(|d| &d.ty), &loc, &mut out, 0)?;
        if let Some(init) = m.iface.var(&v.name).and_then(|i| i.init.as_ref()) {
            cx.initializer(init, &v.ty, &loc, &mut out)?;
        }
    }
    Ok(out)
}

fn compile_pou(u: &Unit<'_>, i: usize, template: &[Value]) -> Compiled {
    let cx = Cx { u, pou: Some(i), method: None, owner: None };
    let m = &u.pous[i];
    let Some(c) = m.chart else {
        let r = match &m.ast.body {
            Body::St(stmts) => cx.stmt_list(stmts).map(to_block),
            Body::Il(il) => cx.il_block(il),
            Body::Sfc(_) => Err(u.error(m.ast.name.span, "a chart without its model")),
        };
        let r = r.and_then(|body| {
            let temps = temp_inits(u, i, template)?;
            if temps.is_empty() {
                return Ok(body);
            }
            let b: Block = Box::new(move |c, base| {
                for op in &temps {
                    let r = match op {
                        InitOp::Nested { pou, offset } => super::call::run_inits(c, *pou, base + *offset as usize),
                        InitOp::Run(f) => f(c, base),
                    };
                    r.map_err(|e| *e)?;
                }
                body(c, base)
            });
            Ok(b)
        });
        let actions = pou_actions(u, i).into_iter().map(|a| action_block(&cx, m, &a.name.text, &a.body)).collect();
        let subs = m.subs.iter().map(|sub| compile_chart(&cx, &u.charts[sub.chart])).collect();
        return Compiled::Code(
            r.unwrap_or_else(|d| {
                u.report(d);
                placeholder_block()
            }),
            actions,
            subs,
        );
    };
    let main = compile_chart(&cx, &u.charts[c]);
    let subs = m.subs.iter().map(|sub| compile_chart(&cx, &u.charts[sub.chart])).collect();
    Compiled::Chart(main, subs)
}

/// A chart's code from its compiled parts and its slots (the control and chart slots are set
/// by the caller).
fn chart_code(chart: Chart, x: &[u32], t: &[u32], q: Vec<u32>, a: Vec<u32>, p: ChartParts) -> ChartCode {
    ChartCode {
        chart,
        step_x: x.to_vec(),
        step_t: t.to_vec(),
        step_vendor: Vec::new(),
        step_members: Default::default(),
        action_q: q,
        action_a: a,
        guards: p.guards,
        fast: p.fast,
        bodies: p.bodies,
        interlocks: p.interlocks,
        supervisions: p.supervisions,
        associations: p.associations,
        step_actions: p.step_actions,
        control: ControlSlots::default(),
        chart_slot: 0,
        plan: Default::default(),
    }
}

/// The code of an action body: its statements, or for an action written in SFC one scan of
/// its chart (the chart instance is in the frame's slot for it).
fn action_block(cx: &Cx<'_, '_>, m: &PouMeta<'_>, name: &str, body: &ActionBody) -> Block {
    let b = match body {
        ActionBody::St(stmts) => cx.stmt_list(stmts).map(to_block),
        ActionBody::Il(il) => cx.il_block(il),
        ActionBody::Sfc(_) => {
            let sub = m
                .subs
                .iter()
                .find(|s| cx.u.charts[s.chart].action.as_deref().is_some_and(|a| a.eq_ignore_ascii_case(name)));
            match sub {
                Some(sub) => {
                    let slot = sub.chart_slot as usize;
                    let span = cx.u.charts[sub.chart].name_span;
                    let name = name.to_string();
                    Ok(Box::new(move |c: &mut super::Ctx<'_>, base: usize| {
                        let depth = CALL_DEPTH.with(|d| d.get());
                        if depth >= MAX_CALL_DEPTH {
                            return Err(*fault(format!("the chart of action `{name}` runs itself (recursion)"), span));
                        }
                        CALL_DEPTH.with(|d| d.set(depth + 1));
                        let idx = int_of(&c.mem[base + slot]);
                        let r = crate::engine::run_chart(c, idx.max(0) as usize);
                        CALL_DEPTH.with(|d| d.set(depth));
                        r
                    }) as Block)
                }
                None => Err(cx.u.error(
                    cx.u.charts.first().map(|c| c.name_span).unwrap_or_default(),
                    format!("the chart of action `{name}` is missing"),
                )),
            }
        }
    };
    b.unwrap_or_else(|d| {
        cx.u.report(d);
        placeholder_block()
    })
}

/// The compiled parts of one chart of a POU.
struct ChartParts {
    guards: Vec<Guard>,
    fast: Vec<FastGuard>,
    bodies: Vec<Block>,
    interlocks: Vec<Option<Guard>>,
    supervisions: Vec<Option<Guard>>,
    associations: Vec<Vec<AssocCode>>,
    step_actions: Vec<Vec<(sfc_syntax::ast::StepActionKind, Block)>>,
}

/// Compiles the conditions, action bodies and associations of a chart of the POU being
/// compiled (its body's, or an action's written in SFC).
fn compile_chart(cx: &Cx<'_, '_>, ch: &Chart) -> ChartParts {
    let u = cx.u;
    let m = cx.meta().expect("a chart belongs to a POU");
    let mut guards: Vec<Guard> = Vec::new();
    let mut fast: Vec<FastGuard> = Vec::new();
    for t in &ch.transitions {
        let g = if matches!(ch.target, Target::Atmt | Target::Eatmt) {
            match sfc_model::condition_input(&t.condition, ch.target) {
                Some(ci) => atmt_guard(cx, ch.target, ci, t.span),
                None => guard(cx, &t.condition),
            }
        } else {
            guard(cx, &t.condition)
        };
        let (g, f) = g.unwrap_or_else(|d| {
            u.report(d);
            (Box::new(|_, _| Ok(false)), FastGuard::Const(false))
        });
        guards.push(g);
        fast.push(f);
    }
    let bodies = ch.actions.iter().map(|a| action_block(cx, m, &a.name, &a.body)).collect();
    let mut associations = Vec::new();
    for s in &ch.steps {
        let mut list = Vec::new();
        for a in &s.associations {
            let duration = match &a.duration {
                None => None,
                Some(Duration::Literal(us)) => Some(DurationCode::Literal(*us)),
                Some(Duration::Variable(name)) => match cx.lookup(name) {
                    Some(Sym::Var { place, konst: None, .. }) => Some(DurationCode::Variable(place)),
                    Some(Sym::Var { konst: Some(sfc_st::Value::Time(t)), .. }) => Some(DurationCode::Literal(t)),
                    Some(Sym::Var { place, .. }) => Some(DurationCode::Variable(place)),
                    _ => {
                        u.report(u.error(a.span, format!("the duration `{name}` is not a variable")));
                        None
                    }
                },
            };
            let variable = match a.target {
                ActionTarget::Variable => match cx.lookup(&a.action) {
                    Some(Sym::Var { place, .. }) => Some(place),
                    _ => None,
                },
                ActionTarget::Action(_) => None,
            };
            // Events name the variable as declared, not as spelled at this association.
            let variable_name = variable.map(|_| {
                cx.meta()
                    .and_then(|m| m.layout.vars.iter().find(|v| v.name.eq_ignore_ascii_case(&a.action)))
                    .map(|v| v.name.clone())
                    .or_else(|| cx.u.global_name(&a.action))
                    .unwrap_or_else(|| a.action.clone())
            });
            list.push(AssocCode { duration, variable, variable_name });
        }
        associations.push(list);
    }
    // A step action runs as the call `A();` or `inst.A();` does.
    let step_actions = ch
        .steps
        .iter()
        .map(|s| {
            s.step_actions
                .iter()
                .filter_map(|a| {
                    let call = a.call()?;
                    let b = cx.call_stmt(&call).map(|f| to_block(vec![f])).unwrap_or_else(|d| {
                        u.report(d);
                        placeholder_block()
                    });
                    Some((a.kind, b))
                })
                .collect()
        })
        .collect();
    // S7-GRAPH's step conditions, as guards (only the `graph` profile evaluates them).
    let condition = |e: &Option<sfc_syntax::ast::Expr>| -> Option<Guard> {
        let e = e.as_ref()?;
        match guard(cx, &Condition::St(e.clone())) {
            Ok((g, _)) => Some(g),
            Err(d) => {
                u.report(d);
                None
            }
        }
    };
    let interlocks = ch.steps.iter().map(|s| condition(&s.interlock)).collect();
    let supervisions = ch.steps.iter().map(|s| condition(&s.supervision)).collect();
    ChartParts { guards, fast, bodies, interlocks, supervisions, associations, step_actions }
}

fn guard(cx: &Cx<'_, '_>, cond: &Condition) -> C<(Guard, FastGuard)> {
    let g = match cond {
        Condition::St(e) => {
            let v = cx.expr_as(e, &Type::Bool)?;
            // A plain BOOL variable: read it directly.
            match v.leaf {
                Some(super::texpr::Leaf::Local(o)) => {
                    return Ok((Box::new(move |c, b| Ok(bool_of(&c.mem[b + o]))), FastGuard::Local(o as u32, false)))
                }
                Some(super::texpr::Leaf::Global(g)) => {
                    return Ok((Box::new(move |c, _| Ok(bool_of(&c.mem[g]))), FastGuard::Global(g as u32, false)))
                }
                Some(super::texpr::Leaf::Bool(x)) => return Ok((Box::new(move |_, _| Ok(x)), FastGuard::Const(x))),
                _ => v.bool(),
            }
        }
        Condition::Il(il) => cx.il_guard(il)?,
        Condition::Missing => return Ok((Box::new(|_, _| Ok(false)), FastGuard::Const(false))),
    };
    Ok((
        Box::new(move |c, b| match g(c, b) {
            Ok(x) => Ok(x),
            Err(e) => Err(*e),
        }),
        FastGuard::Code,
    ))
}

/// An ATMT/EATMT condition: one implicit input `C3` / `c18`, maybe negated.
fn atmt_guard(cx: &Cx<'_, '_>, target: Target, ci: sfc_model::ConditionInput, span: Span) -> C<(Guard, FastGuard)> {
    let name = if target == Target::Atmt { format!("C{}", ci.index) } else { format!("c{}", ci.index) };
    let Some(Sym::Var { place, .. }) = cx.lookup(&name) else {
        return Err(cx.error(span, format!("the condition input `{name}` does not exist")));
    };
    let neg = ci.negated;
    Ok(match place {
        Place::Local(o) => {
            let f = FastGuard::Local(o, neg);
            let o = o as usize;
            let g: Guard = Box::new(move |c, b| Ok(bool_of(&c.mem[b + o]) != neg));
            (g, f)
        }
        Place::Global(g) => {
            let f = FastGuard::Global(g, neg);
            let g = g as usize;
            let g: Guard = Box::new(move |c, _| Ok(bool_of(&c.mem[g]) != neg));
            (g, f)
        }
    })
}

/// A FUNCTION's frame lives only during one call: it may not hold SFC instances.
fn check_function_frames(u: &Unit<'_>) {
    fn has_chart(u: &Unit<'_>, ty: &Type, depth: u32) -> bool {
        if depth > 64 {
            return false;
        }
        match ty {
            Type::FunctionBlock(n) => u.fb_pou(n).is_some_and(|j| {
                u.pous[j].chart.is_some() || u.pous[j].layout.vars.iter().any(|v| has_chart(u, &v.ty, depth + 1))
            }),
            Type::Array { elem, .. } => has_chart(u, elem, depth + 1),
            Type::Struct { fields, .. } => fields.iter().any(|(_, t)| has_chart(u, t, depth + 1)),
            _ => false,
        }
    }
    for m in &u.pous {
        if m.kind() != PouKind::Function {
            continue;
        }
        for v in &m.layout.vars {
            if has_chart(u, &v.ty, 0) {
                let span = m.iface.var(&v.name).map(|i| i.span).unwrap_or(m.ast.name.span);
                u.report(u.error(
                    span,
                    format!(
                        "`{}` holds an SFC instance inside FUNCTION `{}`, whose frame lasts one call",
                        v.name,
                        m.name()
                    ),
                ));
            }
        }
    }
}
