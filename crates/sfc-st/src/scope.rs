//! The names visible in the code of one POU: its variables, the globals, and the steps and
//! actions of its chart; with a record of which names the code reads and writes.

use crate::env::{add_sfc_control_variables, block_constants, is_sfc_control_variable, PouInterface, TypeEnv, VarInfo};
use crate::types::Type;
use crate::value::{ConstLookup, Value};
use rustc_hash::FxHashMap;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{Ident, Pou, PouKind, VarKind};
use std::collections::HashMap;

/// Whether the code read and wrote a name.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Usage {
    /// The code read the name.
    pub read: bool,
    /// The code wrote the name.
    pub written: bool,
}

impl Usage {
    /// Read or written.
    pub fn used(self) -> bool {
        self.read || self.written
    }
}

/// What a name in the code refers to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Binding<'a> {
    /// A variable of the POU (`global` false) or a file-level global (`global` true).
    Variable {
        /// The declaration.
        info: &'a VarInfo,
        /// Declared at file level.
        global: bool,
    },
    /// The result variable of a FUNCTION (its own name), of this type.
    ReturnValue(&'a Type),
    /// A step of the chart (members `X: BOOL`, `T: TIME`, read-only).
    Step(&'a str),
    /// An action of the chart (members `Q`, `A`: BOOL, read-only).
    Action(&'a str),
}

/// What [`Scope::leave_method`] restores.
#[derive(Debug)]
pub struct MethodFrame {
    vars_len: usize,
    shadowed: Vec<(String, Option<Sym>)>,
    return_type: Option<Type>,
    result_name: Option<String>,
}

/// A resolved name, cheap to copy while the checker mutates usage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Sym {
    Local(usize),
    Global(usize),
    Return,
    Step(usize),
    Action(usize),
}

#[derive(Debug, Clone)]
struct ChartName {
    name: String,
    span: Span,
    usage: Usage,
}

/// The names visible in the code of one POU. Lookups are case-insensitive.
#[derive(Debug, Clone)]
pub struct Scope<'e> {
    env: &'e TypeEnv,
    pou_name: Option<String>,
    pou_kind: Option<PouKind>,
    /// The POU's body is a chart (its control variables are used by the chart itself).
    sfc: bool,
    return_type: Option<Type>,
    /// Inside a method: its name, which is its result variable.
    result_name: Option<String>,
    vars: Vec<VarInfo>,
    var_usage: Vec<Usage>,
    global_usage: Vec<Usage>,
    return_usage: Usage,
    steps: Vec<ChartName>,
    actions: Vec<ChartName>,
    /// Upper-case name → local variable, step or action (they share one namespace).
    index: FxHashMap<String, Sym>,
    /// Type problems found while resolving a POU that is not part of the environment's file;
    /// the checker reports them.
    pub(crate) pending: Vec<Diagnostic>,
}

impl<'e> Scope<'e> {
    /// Only the globals of the environment (for checking global initial values).
    pub fn globals_only(env: &'e TypeEnv) -> Scope<'e> {
        Scope {
            env,
            pou_name: None,
            pou_kind: None,
            sfc: false,
            return_type: None,
            result_name: None,
            vars: Vec::new(),
            var_usage: Vec::new(),
            global_usage: vec![Usage::default(); env.globals().len()],
            return_usage: Usage::default(),
            steps: Vec::new(),
            actions: Vec::new(),
            index: FxHashMap::default(),
            pending: Vec::new(),
        }
    }

    /// The scope of a POU's code: its variables (as resolved in `env`) and the globals.
    /// Steps and actions are added with [`Scope::add_step`] and [`Scope::add_action`].
    pub fn for_pou(env: &'e TypeEnv, pou: &Pou) -> Scope<'e> {
        if let Some(iface) = env.interface_of(pou) {
            return Scope::for_interface(env, iface);
        }
        // A POU from another file: resolve its declarations against this environment.
        let mut pending = Vec::new();
        let mut consts: HashMap<String, Value> = HashMap::new();
        for block in &pou.var_blocks {
            let c = block_constants(block, &Chain { local: &consts, env });
            consts.extend(c);
        }
        let lookup = Chain { local: &consts, env };
        let mut vars = Vec::new();
        for block in &pou.var_blocks {
            for decl in &block.decls {
                let ty = env.resolve_type_spec(&decl.ty, &lookup, &mut pending);
                for n in &decl.names {
                    vars.push(VarInfo::declared(n, block, decl, ty.clone(), &consts));
                }
            }
        }
        let return_type = pou.return_type.as_ref().map(|s| env.resolve_type_spec(s, &lookup, &mut pending));
        let sfc = pou.has_chart();
        if sfc {
            add_sfc_control_variables(&mut vars, pou.name.span, &mut pending);
        }
        let iface = PouInterface {
            name: pou.name.text.clone(),
            kind: pou.kind,
            vars,
            return_type,
            standard: false,
            span: pou.name.span,
            sfc,
            actions: pou.actions().map(|a| a.name.text.clone()).collect(),
            sfc_actions: crate::env::sfc_actions(pou),
            methods: Vec::new(),
            properties: Vec::new(),
            base: None,
            implements: Vec::new(),
        };
        let mut scope = Scope::for_interface(env, &iface);
        scope.pending = pending;
        scope
    }

    /// The scope of the code of a POU with this interface.
    pub fn for_interface(env: &'e TypeEnv, iface: &PouInterface) -> Scope<'e> {
        let mut scope = Scope::globals_only(env);
        scope.pou_name = Some(iface.name.clone());
        scope.pou_kind = Some(iface.kind);
        scope.sfc = iface.sfc;
        if iface.kind == PouKind::Function {
            scope.return_type = Some(iface.return_type.clone().unwrap_or(Type::Error));
        }
        for v in &iface.vars {
            // Duplicates were reported when the environment was built; the first one wins.
            let key = v.name.to_ascii_uppercase();
            if scope.index.contains_key(&key) {
                continue;
            }
            scope.index.insert(key, Sym::Local(scope.vars.len()));
            scope.vars.push(v.clone());
            scope.var_usage.push(Usage::default());
        }
        scope
    }

    /// The environment the scope resolves types and globals in.
    pub fn env(&self) -> &'e TypeEnv {
        self.env
    }

    /// The name of the POU, if the scope belongs to one.
    pub fn pou_name(&self) -> Option<&str> {
        self.pou_name.as_deref()
    }

    /// The kind of the POU, if the scope belongs to one.
    pub fn pou_kind(&self) -> Option<PouKind> {
        self.pou_kind
    }

    /// The POU's own variables, in declaration order.
    pub fn vars(&self) -> &[VarInfo] {
        &self.vars
    }

    /// Declares a step. `Err` holds the span of the variable, step or action that already has
    /// the name (the caller reports the clash, SFC0206); the earlier declaration stays.
    pub fn add_step(&mut self, name: &Ident) -> Result<(), Span> {
        let key = name.key();
        if let Some(prev) = self.local_span(&key) {
            return Err(prev);
        }
        self.index.insert(key, Sym::Step(self.steps.len()));
        self.steps.push(ChartName { name: name.text.clone(), span: name.span, usage: Usage::default() });
        Ok(())
    }

    /// Declares an action (members `Q` and `A`); `Err` as for [`Scope::add_step`].
    pub fn add_action(&mut self, name: &Ident) -> Result<(), Span> {
        let key = name.key();
        if let Some(prev) = self.local_span(&key) {
            return Err(prev);
        }
        self.index.insert(key, Sym::Action(self.actions.len()));
        self.actions.push(ChartName { name: name.text.clone(), span: name.span, usage: Usage::default() });
        Ok(())
    }

    /// Enters the code of method (or property accessor) `m` of this POU: its variables hide
    /// the POU's of the same name, and its name is its result. [`Scope::leave_method`] undoes it.
    pub fn enter_method(&mut self, m: &crate::env::MethodSig) -> MethodFrame {
        let frame = MethodFrame {
            vars_len: self.vars.len(),
            shadowed: Vec::new(),
            return_type: self.return_type.take(),
            result_name: self.result_name.take(),
        };
        let mut frame = frame;
        for v in &m.vars {
            let key = v.name.to_ascii_uppercase();
            let prev = self.index.insert(key.clone(), Sym::Local(self.vars.len()));
            frame.shadowed.push((key, prev));
            self.vars.push(v.clone());
            self.var_usage.push(Usage::default());
        }
        self.return_type = m.return_type.clone();
        self.result_name = Some(m.name.clone());
        frame
    }

    /// Leaves a method entered with [`Scope::enter_method`]; SFC0317 for its unused locals.
    pub fn leave_method(&mut self, frame: MethodFrame) -> Vec<Diagnostic> {
        let unused = self.vars[frame.vars_len..]
            .iter()
            .zip(&self.var_usage[frame.vars_len..])
            .filter(|(v, u)| matches!(v.kind, VarKind::Var | VarKind::Temp) && v.location.is_none() && !u.used())
            .map(|(v, _)| Diagnostic::new("SFC0317", v.span, format!("variable `{}` is never used", v.name)))
            .collect();
        for (key, prev) in frame.shadowed.into_iter().rev() {
            match prev {
                Some(s) => self.index.insert(key, s),
                None => self.index.remove(&key),
            };
        }
        self.vars.truncate(frame.vars_len);
        self.var_usage.truncate(frame.vars_len);
        self.return_type = frame.return_type;
        self.result_name = frame.result_name;
        unused
    }

    /// Declares a variable the caller knows of without a declaration (e.g. the implicit BOOL
    /// condition inputs `C0`…`C15` of an ATMT chart); `Err` as for [`Scope::add_step`].
    pub fn declare(&mut self, var: VarInfo) -> Result<(), Span> {
        let key = var.name.to_ascii_uppercase();
        if let Some(prev) = self.local_span(&key) {
            return Err(prev);
        }
        self.index.insert(key, Sym::Local(self.vars.len()));
        self.vars.push(var);
        self.var_usage.push(Usage::default());
        Ok(())
    }

    fn local_span(&self, key: &str) -> Option<Span> {
        match self.index.get(key)? {
            Sym::Local(i) => self.vars.get(*i).map(|v| v.span),
            Sym::Step(i) => self.steps.get(*i).map(|s| s.span),
            Sym::Action(i) => self.actions.get(*i).map(|a| a.span),
            Sym::Global(_) | Sym::Return => None,
        }
    }

    /// Resolves a name: POU variables, steps and actions first, then the function's result
    /// variable, then globals.
    pub(crate) fn resolve(&self, name: &str) -> Option<Sym> {
        // Every name of every expression comes here: short names are folded on the stack.
        let mut buf = [0u8; 64];
        let found = match buf.get_mut(..name.len()) {
            Some(upper) => {
                upper.copy_from_slice(name.as_bytes());
                upper.make_ascii_uppercase();
                // ASCII upper-casing keeps UTF-8 valid.
                std::str::from_utf8(upper).ok().and_then(|key| self.index.get(key))
            }
            None => self.index.get(&name.to_ascii_uppercase()),
        };
        if let Some(s) = found {
            return Some(*s);
        }
        let result = self.result_name.as_deref().or(self.pou_name.as_deref());
        if self.return_type.is_some() && result.is_some_and(|p| p.eq_ignore_ascii_case(name)) {
            return Some(Sym::Return);
        }
        let g = self.env.global_position(name)?;
        Some(Sym::Global(g))
    }

    /// What a name refers to, if anything.
    pub fn lookup(&self, name: &str) -> Option<Binding<'_>> {
        let b = match self.resolve(name)? {
            Sym::Local(i) => Binding::Variable { info: self.vars.get(i)?, global: false },
            Sym::Global(i) => Binding::Variable { info: self.env.globals().get(i)?, global: true },
            Sym::Return => Binding::ReturnValue(self.return_type.as_ref()?),
            Sym::Step(i) => Binding::Step(&self.steps.get(i)?.name),
            Sym::Action(i) => Binding::Action(&self.actions.get(i)?.name),
        };
        Some(b)
    }

    /// The variable (local or global) with this name.
    pub fn variable(&self, name: &str) -> Option<&VarInfo> {
        match self.lookup(name)? {
            Binding::Variable { info, .. } => Some(info),
            _ => None,
        }
    }

    pub(crate) fn var_info(&self, sym: Sym) -> Option<&VarInfo> {
        match sym {
            Sym::Local(i) => self.vars.get(i),
            Sym::Global(i) => self.env.globals().get(i),
            _ => None,
        }
    }

    pub(crate) fn return_type(&self) -> Option<&Type> {
        self.return_type.as_ref()
    }

    pub(crate) fn chart_name(&self, sym: Sym) -> &str {
        match sym {
            Sym::Step(i) => self.steps.get(i).map(|s| s.name.as_str()).unwrap_or(""),
            Sym::Action(i) => self.actions.get(i).map(|s| s.name.as_str()).unwrap_or(""),
            _ => "",
        }
    }

    /// Records a read of (`write` false) or a write to a name.
    pub(crate) fn mark(&mut self, sym: Sym, write: bool) {
        let u = match sym {
            Sym::Local(i) => self.var_usage.get_mut(i),
            Sym::Global(i) => self.global_usage.get_mut(i),
            Sym::Return => Some(&mut self.return_usage),
            Sym::Step(i) => self.steps.get_mut(i).map(|s| &mut s.usage),
            Sym::Action(i) => self.actions.get_mut(i).map(|s| &mut s.usage),
        };
        if let Some(u) = u {
            if write {
                u.written = true;
            } else {
                u.read = true;
            }
        }
    }

    /// Records that the chart reads a name outside checked code (an indicator variable, an
    /// action association); false when the name is unknown.
    pub fn mark_read(&mut self, name: &str) -> bool {
        let Some(sym) = self.resolve(name) else { return false };
        self.mark(sym, false);
        true
    }

    /// Records that the chart writes a name outside checked code (a BOOL variable used as an
    /// action); false when the name is unknown.
    pub fn mark_written(&mut self, name: &str) -> bool {
        let Some(sym) = self.resolve(name) else { return false };
        self.mark(sym, true);
        true
    }

    /// How the checked code used a name (variables, globals, steps, actions).
    pub fn usage(&self, name: &str) -> Usage {
        let Some(sym) = self.resolve(name) else { return Usage::default() };
        match sym {
            Sym::Local(i) => self.var_usage.get(i).copied(),
            Sym::Global(i) => self.global_usage.get(i).copied(),
            Sym::Return => Some(self.return_usage),
            Sym::Step(i) => self.steps.get(i).map(|s| s.usage),
            Sym::Action(i) => self.actions.get(i).map(|s| s.usage),
        }
        .unwrap_or_default()
    }

    /// Local variables (VAR, VAR_TEMP, not located) that the checked code never read nor
    /// wrote. Interface variables are excluded: the caller of the POU uses them; so are the
    /// control variables of a chart (`SFCInit`, …), which the chart itself uses.
    pub fn unused_variables(&self) -> Vec<&VarInfo> {
        self.vars
            .iter()
            .zip(&self.var_usage)
            .filter(|(v, u)| matches!(v.kind, VarKind::Var | VarKind::Temp) && v.location.is_none() && !u.used())
            .filter(|(v, _)| !(self.sfc && is_sfc_control_variable(&v.name)))
            .map(|(v, _)| v)
            .collect()
    }

    /// SFC0317 warnings for [`Scope::unused_variables`]; call after all code of the POU has
    /// been checked.
    pub fn unused_diagnostics(&self) -> Vec<Diagnostic> {
        self.unused_variables()
            .into_iter()
            .map(|v| Diagnostic::new("SFC0317", v.span, format!("variable `{}` is never used", v.name)))
            .collect()
    }

    /// The names that can stand where a variable is read or written: variables, globals and a
    /// function's result (not steps or actions, which are read only through `.X`, `.T`, `.Q`).
    pub(crate) fn variable_names(&self) -> impl Iterator<Item = &str> {
        self.vars
            .iter()
            .map(|v| v.name.as_str())
            .chain(self.env.globals().iter().map(|v| v.name.as_str()))
            .chain(self.result_name.as_deref().or(self.pou_name.as_deref()).filter(|_| self.return_type.is_some()))
    }

    /// The enumerated types that have a value of this name: inline enumerations of this POU's
    /// variables, then those of the environment.
    pub(crate) fn enum_types_with_value(&self, name: &str) -> Vec<Type> {
        let mut out: Vec<Type> = Vec::new();
        for v in &self.vars {
            let ty = match &v.ty {
                Type::Array { elem, .. } => elem.as_ref(),
                t => t,
            };
            if ty.enum_value(name).is_some() && !out.contains(ty) {
                out.push(ty.clone());
            }
        }
        for t in self.env.enum_types_with_value(name) {
            if !out.contains(t) {
                out.push(t.clone());
            }
        }
        out
    }
}

impl ConstLookup for Scope<'_> {
    fn constant(&self, name: &str) -> Option<Value> {
        match self.resolve(name)? {
            Sym::Local(i) => self.vars.get(i).filter(|v| v.constant).and_then(|v| v.value),
            Sym::Global(i) => self.env.globals().get(i).filter(|v| v.constant).and_then(|v| v.value),
            _ => None,
        }
    }
}

struct Chain<'a> {
    local: &'a HashMap<String, Value>,
    env: &'a TypeEnv,
}

impl ConstLookup for Chain<'_> {
    fn constant(&self, name: &str) -> Option<Value> {
        self.local.get(&name.to_ascii_uppercase()).copied().or_else(|| self.env.constant(name))
    }
}
