//! Compile-time state: the file's POUs with their frame layouts and name tables, the globals,
//! and the context in which one piece of code is compiled.

use super::{ControlSlots, Layout, Place, VarSlot};
use crate::value::Value;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::Chart;
use sfc_st::{PouInterface, Type, TypeEnv};
use sfc_syntax::ast::{Expr, Pou, PouKind, SourceUnit, TypeDecl};
use std::cell::RefCell;
use std::collections::HashMap;

/// Compile results (SFC0320 when something cannot be simulated).
pub(crate) type C<T> = Result<T, Box<Diagnostic>>;

/// What a name of a POU's code refers to.
#[derive(Debug, Clone)]
pub(crate) enum Sym {
    Var {
        place: Place,
        ty: Type,
        konst: Option<sfc_st::Value>,
    },
    Step(usize),
    Action(usize),
    /// The result variable of the FUNCTION being compiled.
    Return,
}

/// One POU of the file during compilation.
pub(crate) struct PouMeta<'a> {
    pub ast: &'a Pou,
    pub iface: PouInterface,
    /// Index into the charts.
    pub chart: Option<usize>,
    pub layout: Layout,
    /// Upper-case name → variable, step or action.
    pub names: HashMap<String, Sym>,
    pub step_x: Vec<u32>,
    pub step_t: Vec<u32>,
    /// Per step the first slot of its dialect's own members (`super::StepMembers`).
    pub step_vendor: Vec<u32>,
    pub step_members: super::StepMembers,
    pub action_q: Vec<u32>,
    pub action_a: Vec<u32>,
    pub control: ControlSlots,
    pub chart_slot: u32,
    /// The charts of the POU's actions written in SFC.
    pub subs: Vec<SubMeta>,
    /// First scratch slot of IL current results (one per nesting level).
    pub il_base: u32,
    pub il_slots: u32,
    /// FUNCTION result: offset and type.
    pub result: Option<(u32, Type)>,
    /// Its edge-triggered inputs (`Start : BOOL R_EDGE`): the input's slot, the slot of its
    /// value at the previous call, rising.
    pub edges: Vec<(u32, u32, bool)>,
    /// The methods and property accessors of its class: its own and its bases', overridden
    /// ones included (`SUPER^.M()`), each laid out in its frame.
    pub methods: Vec<MethodMeta<'a>>,
}

/// What a [`MethodMeta`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MethodKind {
    Method,
    Get,
    Set,
}

/// A method (or property accessor) of a block, compiled for the frame of one class: its
/// variables are slots of the instance's frame, fresh at every call.
pub(crate) struct MethodMeta<'a> {
    pub kind: MethodKind,
    /// The POU that declares it (a base block, for an inherited method).
    pub owner: usize,
    pub sig: sfc_st::MethodSig,
    pub body: &'a sfc_syntax::ast::Body,
    /// Upper-case name → its variables and its result (named after it).
    pub names: HashMap<String, Sym>,
    /// Its variables' slots.
    pub vars: Vec<VarSlot>,
}

/// The chart of an action written in SFC, laid out in its POU's frame.
#[derive(Default, Clone)]
pub(crate) struct SubMeta {
    /// Index into the charts.
    pub chart: usize,
    /// Its steps in the POU's `step_x`/`step_t` (after the body's and earlier actions').
    pub steps: std::ops::Range<usize>,
    pub action_q: Vec<u32>,
    pub action_a: Vec<u32>,
    pub chart_slot: u32,
    /// Its own SFC flags (CODESYS gives each chart its own: `Act(SFCReset := TRUE)`).
    pub control: ControlSlots,
}

impl PouMeta<'_> {
    pub(crate) fn name(&self) -> &str {
        &self.ast.name.text
    }
    pub(crate) fn kind(&self) -> PouKind {
        self.ast.kind
    }
    pub(crate) fn var(&self, name: &str) -> Option<&VarSlot> {
        self.layout.vars.iter().find(|v| v.name.eq_ignore_ascii_case(name))
    }
}

/// The globals as they grow (direct addresses are allocated on first sight).
#[derive(Default)]
pub(crate) struct Globals {
    pub layout: Layout,
    /// Upper-case name → index into `layout.vars`.
    pub index: HashMap<String, usize>,
    pub konst: HashMap<String, sfc_st::Value>,
    /// Upper-case address text (`%IX0.0`) → slot.
    pub addresses: HashMap<String, u32>,
    pub template: Vec<Value>,
}

/// The whole file being compiled.
pub(crate) struct Unit<'a> {
    pub env: TypeEnv,
    pub types: &'a HashMap<Span, Type>,
    pub ast: &'a SourceUnit,
    pub charts: &'a [Chart],
    pub pous: Vec<PouMeta<'a>>,
    /// Upper-case name → the first POU of that name.
    pub pou_index: HashMap<String, usize>,
    /// Standard function block layouts by upper-case type name, with their initial slots.
    pub std_layouts: HashMap<String, (Layout, Vec<Value>)>,
    pub globals: RefCell<Globals>,
    pub diags: RefCell<Vec<Diagnostic>>,
    pub type_decls: HashMap<String, &'a TypeDecl>,
}

impl<'a> Unit<'a> {
    /// The user POU (not a FUNCTION) that is the function block type `name`.
    pub(crate) fn fb_pou(&self, name: &str) -> Option<usize> {
        let i = *self.pou_index.get(&name.to_ascii_uppercase())?;
        (self.pous[i].kind() != PouKind::Function).then_some(i)
    }

    pub(crate) fn function(&self, name: &str) -> Option<usize> {
        let i = *self.pou_index.get(&name.to_ascii_uppercase())?;
        (self.pous[i].kind() == PouKind::Function).then_some(i)
    }

    /// Slots taken by a value of `ty`.
    pub(crate) fn type_size(&self, ty: &Type) -> u32 {
        match ty {
            Type::Array { dims, elem } => {
                let n: i64 = dims.iter().map(|(lo, hi)| hi - lo + 1).product();
                (n.max(0) as u32).saturating_mul(self.type_size(elem))
            }
            Type::Struct { fields, .. } => fields.iter().map(|(_, t)| self.type_size(t)).sum(),
            Type::FunctionBlock(name) => match self.fb_pou(name) {
                Some(i) => self.pous[i].layout.size,
                None => self.std_layouts.get(&name.to_ascii_uppercase()).map(|(l, _)| l.size).unwrap_or(1),
            },
            _ => 1,
        }
    }

    /// A global variable by name: its slot, type and constant value.
    pub(crate) fn global(&self, name: &str) -> Option<(u32, Type, Option<sfc_st::Value>)> {
        let g = self.globals.borrow();
        let key = name.to_ascii_uppercase();
        let i = *g.index.get(&key)?;
        let v = &g.layout.vars[i];
        Some((v.offset, v.ty.clone(), g.konst.get(&key).copied()))
    }

    /// The declared spelling of a global variable.
    pub(crate) fn global_name(&self, name: &str) -> Option<String> {
        let g = self.globals.borrow();
        let i = *g.index.get(&name.to_ascii_uppercase())?;
        g.layout.vars.get(i).map(|v| v.name.clone())
    }

    pub(crate) fn error(&self, span: Span, msg: impl Into<String>) -> Box<Diagnostic> {
        Box::new(Diagnostic::error("SFC0320", span, format!("cannot be simulated: {}", msg.into())))
    }

    #[allow(clippy::boxed_local)]
    pub(crate) fn report(&self, d: Box<Diagnostic>) {
        self.diags.borrow_mut().push(*d);
    }

    /// Parameter `name` of the function block type `fb`: frame offset, type.
    pub(crate) fn fb_param(&self, fb: &str, name: &str) -> Option<(u32, Type, sfc_syntax::ast::VarKind)> {
        match self.fb_pou(fb) {
            Some(i) => self.pous[i].var(name).map(|v| (v.offset, v.ty.clone(), v.kind)),
            None => super::stdfb::std_param(fb, name),
        }
    }
}

/// The context of one piece of code: the POU it belongs to (`None` for global and type
/// initial values).
pub(crate) struct Cx<'u, 'a> {
    pub u: &'u Unit<'a>,
    pub pou: Option<usize>,
    /// The method (index into the POU's [`PouMeta::methods`]) whose code this is.
    pub method: Option<usize>,
    /// The POU whose code this is, when not [`Cx::pou`] nor the method's (a base block's body
    /// run by `SUPER^()`).
    pub owner: Option<usize>,
}

impl<'u, 'a> Cx<'u, 'a> {
    pub(crate) fn meta(&self) -> Option<&'u PouMeta<'a>> {
        self.pou.map(|i| &self.u.pous[i])
    }

    /// Resolves a name as the checker's scope does: POU variables, steps and actions, the
    /// function's result, then globals.
    pub(crate) fn lookup(&self, name: &str) -> Option<Sym> {
        if let (Some(m), Some(k)) = (self.meta(), self.method) {
            if let Some(s) = m.methods.get(k).and_then(|mm| mm.names.get(&name.to_ascii_uppercase())) {
                return Some(s.clone());
            }
        }
        if let Some(m) = self.meta() {
            if let Some(s) = m.names.get(&name.to_ascii_uppercase()) {
                return Some(s.clone());
            }
            if m.result.is_some() && m.name().eq_ignore_ascii_case(name) {
                return Some(Sym::Return);
            }
        }
        let (slot, ty, konst) = self.u.global(name)?;
        Some(Sym::Var { place: Place::Global(slot), ty, konst })
    }

    /// The type the checker recorded for an expression.
    pub(crate) fn recorded(&self, e: &Expr) -> Option<Type> {
        self.recorded_at(e.span)
    }

    /// The type the checker recorded for the expression spanning `span`.
    pub(crate) fn recorded_at(&self, span: Span) -> Option<Type> {
        self.u.types.get(&span).filter(|t| !t.is_error()).cloned()
    }

    pub(crate) fn error(&self, span: Span, msg: impl Into<String>) -> Box<Diagnostic> {
        self.u.error(span, msg)
    }
}
