//! The type environment of one source file: declared types, POU interfaces, global variables,
//! and the standard function blocks.

use crate::resolve::{resolve_spec, Named, TypeNames};
use crate::stdlib::{std_function, std_function_block, STD_FUNCTION_BLOCK_NAMES};
use crate::types::Type;
use crate::value::{const_eval, ConstLookup, Value};
use rustc_hash::FxHashMap;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{
    DirectAddress, Ident, Initializer, Item, Pou, PouKind, Retain, SourceUnit, TypeDecl, TypeSpecKind, VarBlock,
    VarKind,
};
use std::collections::HashMap;

/// A declared variable (of a POU, a global, or a parameter of a function block type).
#[derive(Debug, Clone, PartialEq)]
pub struct VarInfo {
    /// The name as declared.
    pub name: String,
    /// The span of the name in its declaration.
    pub span: Span,
    /// The var block it was declared in.
    pub kind: VarKind,
    /// Declared in a `VAR … CONSTANT` block.
    pub constant: bool,
    /// `RETAIN` / `NON_RETAIN` of its block.
    pub retain: Option<Retain>,
    /// Its block is `PERSISTENT`.
    pub persistent: bool,
    /// The declared type, resolved.
    pub ty: Type,
    /// `AT %IX1.2`.
    pub location: Option<DirectAddress>,
    /// The initial value as written.
    pub init: Option<Initializer>,
    /// The value of a CONSTANT whose initial value is a constant expression.
    pub value: Option<Value>,
    /// Not declared by the user: one of the control variables every SFC POU has
    /// ([`sfc_control_variables`]).
    pub implicit: bool,
}

impl VarInfo {
    /// The variable `name` of declaration `decl` in `block`, with its resolved type and, for a
    /// CONSTANT, its value from `consts`.
    pub(crate) fn declared(
        name: &Ident,
        block: &VarBlock,
        decl: &sfc_syntax::ast::VarDecl,
        ty: Type,
        consts: &HashMap<String, Value>,
    ) -> VarInfo {
        VarInfo {
            name: name.text.clone(),
            span: name.span,
            kind: block.kind,
            constant: block.constant,
            retain: block.retain,
            persistent: block.persistent,
            ty,
            location: decl.location.clone(),
            init: decl.init.clone(),
            value: consts.get(&name.key()).copied(),
            implicit: false,
        }
    }
}

/// The implicit control variables of every POU whose body is a Sequential Function Chart, as
/// `(name, kind, type)`: the inputs `SFCInit`, `SFCPause`, `SFCQuitError` (BOOL) and the outputs
/// `SFCError` (BOOL), `SFCErrorStep` and `SFCCurrentStep` (STRING). A variable the user declares
/// with one of these names is that control variable (and must have its type).
pub fn sfc_control_variables() -> [(&'static str, VarKind, Type); 6] {
    let s = Type::String { len: None };
    [
        ("SFCInit", VarKind::Input, Type::Bool),
        ("SFCPause", VarKind::Input, Type::Bool),
        ("SFCQuitError", VarKind::Input, Type::Bool),
        ("SFCError", VarKind::Output, Type::Bool),
        ("SFCErrorStep", VarKind::Output, s.clone()),
        ("SFCCurrentStep", VarKind::Output, s),
    ]
}

/// Whether `name` is one of [`sfc_control_variables`] (case-insensitive).
pub fn is_sfc_control_variable(name: &str) -> bool {
    sfc_control_variables().iter().any(|(n, _, _)| n.eq_ignore_ascii_case(name))
}

/// Adds the implicit control variables to the variables of an SFC POU (after the declared
/// ones), and reports a declared variable of such a name whose type differs (SFC0302).
pub(crate) fn add_sfc_control_variables(vars: &mut Vec<VarInfo>, pou_span: Span, diags: &mut Vec<Diagnostic>) {
    for (name, kind, ty) in sfc_control_variables() {
        if let Some(v) = vars.iter().find(|v| v.name.eq_ignore_ascii_case(name)) {
            let same = v.ty.is_error()
                || if ty.is_string() { v.ty.is_string() && !matches!(v.ty, Type::WString { .. }) } else { v.ty == ty };
            if !same {
                diags.push(Diagnostic::new(
                    "SFC0302",
                    v.span,
                    format!(
                        "type mismatch: `{name}` is a control variable of the chart and must be `{ty}`, not `{}`",
                        v.ty
                    ),
                ));
            }
            continue;
        }
        vars.push(VarInfo {
            name: name.to_string(),
            span: pou_span,
            kind,
            constant: false,
            retain: None,
            persistent: false,
            ty,
            location: None,
            init: None,
            value: None,
            implicit: true,
        });
    }
}

/// A declared data type (`TYPE Name : spec := init; END_TYPE`).
#[derive(Debug, Clone, PartialEq)]
pub struct TypeDef {
    /// The name as declared.
    pub name: String,
    /// The type, resolved.
    pub ty: Type,
    /// The declared default initial value of the type.
    pub init: Option<Initializer>,
    /// For a structure: the initial value of each field, in field order.
    pub field_inits: Vec<Option<Initializer>>,
    /// The span of the name in the declaration.
    pub span: Span,
}

/// The interface of a FUNCTION, FUNCTION_BLOCK or PROGRAM (user-declared or standard).
#[derive(Debug, Clone, PartialEq)]
pub struct PouInterface {
    /// The name as declared (upper-case for standard function blocks).
    pub name: String,
    /// FUNCTION, FUNCTION_BLOCK or PROGRAM.
    pub kind: PouKind,
    /// Every variable, in declaration order (inputs, outputs, in-outs, locals, …).
    pub vars: Vec<VarInfo>,
    /// The result type of a FUNCTION (`None` for a function without result, FBs and programs).
    pub return_type: Option<Type>,
    /// A standard function block (TON, CTU, …).
    pub standard: bool,
    /// The span of the POU's name (default for standard blocks).
    pub span: Span,
    /// The body is a Sequential Function Chart: the POU has the implicit control variables
    /// ([`sfc_control_variables`]).
    pub sfc: bool,
    /// The names of the POU's actions (a chart's, or those after a non-chart body), which
    /// `inst.Act()` calls from outside.
    pub actions: Vec<String>,
    /// The names of those actions written in SFC: a call may set their chart's flags
    /// (`Act(SFCReset := TRUE)`, CODESYS).
    pub sfc_actions: Vec<String>,
    /// The methods (CODESYS's `METHOD`): its own, then those of its base blocks that it does
    /// not override.
    pub methods: Vec<MethodSig>,
    /// The properties (CODESYS's `PROPERTY`), own then inherited, as [`PouInterface::methods`].
    pub properties: Vec<PropSig>,
    /// `EXTENDS Base`: the base block's name as written.
    pub base: Option<String>,
    /// `IMPLEMENTS I_A, I_B`: the interfaces' names as written (its own, not its base's).
    pub implements: Vec<String>,
}

/// An `INTERFACE` (IEC 61131-3 3rd edition): the methods and properties every block
/// implementing it has; a variable of its type calls them on the instance it designates.
#[derive(Debug, Clone, PartialEq)]
pub struct InterfaceInfo {
    /// The name as declared.
    pub name: String,
    /// `EXTENDS I_Base, …`: the interfaces' names as written.
    pub extends: Vec<String>,
    /// Its methods: its own, then those of the interfaces it extends.
    pub methods: Vec<MethodSig>,
    /// Its properties, as [`InterfaceInfo::methods`].
    pub properties: Vec<PropSig>,
    /// The properties declared without GET and SET (upper-case): read and written through the
    /// interface, and a block implementing it may have either accessor.
    pub open_properties: Vec<String>,
    /// The span of its name.
    pub span: Span,
}

impl InterfaceInfo {
    /// The method with this name (case-insensitive).
    pub fn method(&self, name: &str) -> Option<&MethodSig> {
        self.methods.iter().find(|m| m.name.eq_ignore_ascii_case(name))
    }

    /// The property with this name (case-insensitive).
    pub fn property(&self, name: &str) -> Option<&PropSig> {
        self.properties.iter().find(|p| p.name.eq_ignore_ascii_case(name))
    }
}

/// A method of a function block (or program), or one accessor of a property: its variables
/// (inputs, outputs, in-outs, locals, as declared in it) and its result. Inside its body the
/// method's own name is its result variable, as a function's.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodSig {
    /// The name as declared (a property accessor carries the property's name).
    pub name: String,
    /// The POU that declares it (the base block, for an inherited method).
    pub owner: String,
    /// Its variables, in declaration order; a property's SET has the property's name as input.
    pub vars: Vec<VarInfo>,
    /// The result type (a property's GET: the property's type).
    pub return_type: Option<Type>,
    /// The span of its name.
    pub span: Span,
}

impl MethodSig {
    /// The method as a function, for binding the arguments of a call.
    pub fn as_function(&self) -> PouInterface {
        PouInterface {
            name: self.name.clone(),
            kind: PouKind::Function,
            vars: self.vars.clone(),
            return_type: self.return_type.clone(),
            standard: false,
            span: self.span,
            sfc: false,
            actions: Vec::new(),
            sfc_actions: Vec::new(),
            methods: Vec::new(),
            properties: Vec::new(),
            base: None,
            implements: Vec::new(),
        }
    }
}

/// A property of a function block: read through its GET, written through its SET.
#[derive(Debug, Clone, PartialEq)]
pub struct PropSig {
    /// The name as declared.
    pub name: String,
    /// The POU that declares it.
    pub owner: String,
    /// Its type.
    pub ty: Type,
    /// `GET`: the accessor whose result is the value read.
    pub get: Option<MethodSig>,
    /// `SET`: the accessor whose input (the property's name) is the value written.
    pub set: Option<MethodSig>,
    /// The span of its name.
    pub span: Span,
}

/// The names of the actions of `pou` written in SFC.
pub(crate) fn sfc_actions(pou: &Pou) -> Vec<String> {
    pou.actions().filter(|a| a.body.sfc().is_some()).map(|a| a.name.text.clone()).collect()
}

/// The flags of an action's chart a call may set (`Act(SFCReset := TRUE)`), all BOOL inputs.
pub const SFC_ACTION_FLAGS: [&str; 4] = ["SFCInit", "SFCReset", "SFCPause", "SFCQuitError"];

impl PouInterface {
    /// The variable with this name (case-insensitive); for a standard block also under
    /// CODESYS's name of it ([`crate::stdlib::param_alias`]).
    pub fn var(&self, name: &str) -> Option<&VarInfo> {
        let name = if self.standard { crate::stdlib::param_alias(&self.name, name).unwrap_or(name) } else { name };
        self.vars.iter().find(|v| v.name.eq_ignore_ascii_case(name))
    }

    /// The method with this name (case-insensitive), own or inherited.
    pub fn method(&self, name: &str) -> Option<&MethodSig> {
        self.methods.iter().find(|m| m.name.eq_ignore_ascii_case(name))
    }

    /// The property with this name (case-insensitive), own or inherited.
    pub fn property(&self, name: &str) -> Option<&PropSig> {
        self.properties.iter().find(|p| p.name.eq_ignore_ascii_case(name))
    }

    /// The parameters that positional (non-formal) arguments bind to: VAR_INPUT and
    /// VAR_IN_OUT, in declaration order.
    pub fn positional_params(&self) -> impl Iterator<Item = &VarInfo> {
        self.vars.iter().filter(|v| matches!(v.kind, VarKind::Input | VarKind::InOut))
    }

    /// The VAR_INPUT parameters.
    pub fn inputs(&self) -> impl Iterator<Item = &VarInfo> {
        self.vars.iter().filter(|v| v.kind == VarKind::Input)
    }

    /// The VAR_OUTPUT parameters.
    pub fn outputs(&self) -> impl Iterator<Item = &VarInfo> {
        self.vars.iter().filter(|v| v.kind == VarKind::Output)
    }

    /// The VAR_IN_OUT parameters.
    pub fn in_outs(&self) -> impl Iterator<Item = &VarInfo> {
        self.vars.iter().filter(|v| v.kind == VarKind::InOut)
    }
}

/// Everything declared at file level, resolved, plus the standard function blocks.
#[derive(Debug, Clone, Default)]
pub struct TypeEnv {
    types: FxHashMap<String, TypeDef>,
    /// User POUs in source order (duplicates included, so each has its interface).
    pous: Vec<PouInterface>,
    /// Upper-case name → index into `pous`; the first declaration wins.
    pou_index: FxHashMap<String, usize>,
    std_fbs: FxHashMap<String, PouInterface>,
    globals: Vec<VarInfo>,
    global_index: FxHashMap<String, usize>,
    /// Upper-case enumerated value → the enumerated types (named or inline in a global) that
    /// declare it.
    enum_values: FxHashMap<String, Vec<Type>>,
    /// Upper-case names of the POUs kept as written (`sfc.verbatim`): opaque, so a variable of
    /// such a type, a call of such a function, and everything done with them is accepted
    /// without analysis (their type is [`Type::Error`]).
    opaque: std::collections::HashSet<String>,
    /// Variables of programs that code reaches into (`Main.X`, CODESYS), as upper-case
    /// `(program, variable)`: the program's one instance is a global named after it.
    reached: std::collections::HashSet<(String, String)>,
    /// Upper-case names of the blocks that POUs kept as written extend.
    opaque_bases: std::collections::HashSet<String>,
    /// The interfaces, by upper-case name.
    interfaces: FxHashMap<String, InterfaceInfo>,
}

impl TypeEnv {
    /// Whether code of the file reaches variable `var` of program `program` (`Main.X`).
    pub fn is_reached(&self, program: &str, var: &str) -> bool {
        self.reached.contains(&(program.to_ascii_uppercase(), var.to_ascii_uppercase()))
    }

    /// Whether `name` is a POU kept as written, so not analysed (an opaque type or function).
    pub fn is_opaque(&self, name: &str) -> bool {
        self.opaque.contains(&name.to_ascii_uppercase())
    }

    /// An environment with only the standard library (no file declarations).
    pub fn standard() -> TypeEnv {
        let mut env = TypeEnv::default();
        for name in STD_FUNCTION_BLOCK_NAMES {
            if let Some(fb) = standard_fb(name) {
                env.std_fbs.insert(name.to_string(), fb);
            }
        }
        // The counters in other integer types (CTU_DINT, CTD_UDINT, …, IEC 61131-3 3rd ed.).
        for stem in ["CTU", "CTD", "CTUD"] {
            for ty in ["DINT", "LINT", "UDINT", "ULINT"] {
                let name = format!("{stem}_{ty}");
                if let Some(fb) = standard_fb(&name) {
                    env.std_fbs.insert(name, fb);
                }
            }
        }
        env
    }

    /// Builds the environment of a parsed file, reporting unknown, duplicate and malformed
    /// types (SFC0313, SFC0318, SFC0105, SFC0315), duplicate variables (SFC0206), located
    /// variables whose type does not fit the address, and VAR_EXTERNAL declarations that
    /// disagree with the global (SFC0302).
    pub fn from_unit(unit: &SourceUnit) -> (TypeEnv, Vec<Diagnostic>) {
        let mut diags = Vec::new();
        let mut env = TypeEnv::standard();
        let mut b = Builder::default();

        // Names first, so that declarations may refer to types and blocks declared later.
        for item in &unit.items {
            match item {
                Item::Types(block) => {
                    for decl in &block.decls {
                        let key = decl.name.key();
                        if let Some(prev) = b.name_span(&key) {
                            diags.push(duplicate(&decl.name, prev, "type"));
                        } else if reserved(&key) {
                            diags.push(reserved_name(&decl.name, "type"));
                        } else {
                            b.decls.insert(key, decl);
                        }
                    }
                }
                Item::Pou(pou) => {
                    let key = pou.name.key();
                    if let Some(prev) = b.name_span(&key) {
                        diags.push(duplicate(&pou.name, prev, pou.kind.keyword()));
                    } else if reserved(&key) {
                        diags.push(reserved_name(&pou.name, pou.kind.keyword()));
                    } else {
                        b.pou_kinds.insert(key, (pou.kind, pou.name.span));
                    }
                }
                Item::Verbatim(v) => {
                    // `FUNCTION_BLOCK B EXTENDS A …`: the header line names the base.
                    let header: Vec<&str> = v.text.lines().next().unwrap_or("").split_whitespace().collect();
                    if let Some(k) = header.iter().position(|w| w.eq_ignore_ascii_case("EXTENDS")) {
                        if let Some(b) = header.get(k + 1) {
                            env.opaque_bases.insert(b.trim_end_matches(',').to_ascii_uppercase());
                        }
                    }
                    if let (true, Some(name)) =
                        (matches!(v.keyword.as_str(), "PROGRAM" | "FUNCTION_BLOCK" | "FUNCTION" | "INTERFACE"), &v.name)
                    {
                        b.opaque.insert(name.key());
                    }
                }
                Item::Interface(i) => {
                    let key = i.name.key();
                    if let Some(prev) = b.name_span(&key) {
                        diags.push(duplicate(&i.name, prev, "INTERFACE"));
                    } else if reserved(&key) {
                        diags.push(reserved_name(&i.name, "INTERFACE"));
                    } else {
                        b.interfaces.insert(key, i.name.span);
                    }
                }
                Item::Globals(_) => {}
            }
        }
        env.opaque = b.opaque.clone();

        // Global constants, needed by array bounds and string lengths everywhere.
        let global_blocks: Vec<&VarBlock> =
            unit.items.iter().filter_map(|i| if let Item::Globals(g) = i { Some(g) } else { None }).collect();
        for block in &global_blocks {
            b.consts.extend(block_constants(block, &b.consts));
        }

        // Every TYPE declaration (resolving is lazy and memoised, so order does not matter).
        let mut keys: Vec<(String, Span)> = b.decls.iter().map(|(k, d)| (k.clone(), d.name.span)).collect();
        keys.sort_by_key(|(_, span)| *span);
        for (key, _) in &keys {
            b.resolve_decl(key, &mut diags);
        }

        // Global variables.
        let mut seen: HashMap<String, Span> = HashMap::new();
        for block in &global_blocks {
            for var in b.block_vars(block, &mut diags) {
                env.add_global(var, &mut seen, &mut diags);
            }
        }

        // POU interfaces.
        for item in &unit.items {
            if let Item::Pou(pou) = item {
                let iface = b.interface(pou, &mut diags);
                let key = pou.name.key();
                let first = b.pou_kinds.get(&key).is_some_and(|(_, span)| *span == pou.name.span);
                if first {
                    env.pou_index.insert(key, env.pous.len());
                }
                env.pous.push(iface);
            }
        }

        // Interfaces, then what each inherits from those it extends.
        for item in &unit.items {
            if let Item::Interface(i) = item {
                if b.interfaces.get(&i.name.key()) == Some(&i.name.span) {
                    let info = b.interface_info(i, &mut diags);
                    env.interfaces.insert(i.name.key(), info);
                }
            }
        }
        inherit_interfaces(&mut env.interfaces, &mut diags);

        inherit(&mut env.pous, &env.pou_index, &mut diags);
        check_implements(&env, &mut diags);

        // VAR_GLOBAL inside a PROGRAM (IEC 61131-3 2nd ed.) is reachable from the blocks it
        // calls through VAR_EXTERNAL, like a file-level global.
        let program_globals: Vec<VarInfo> = env
            .pous
            .iter()
            .filter(|p| p.kind == PouKind::Program)
            .flat_map(|p| p.vars.iter().filter(|v| v.kind == VarKind::Global).cloned())
            .collect();
        for var in program_globals {
            env.add_global(var, &mut seen, &mut diags);
        }

        // Every PROGRAM is one instance, which CODESYS lets any code reach into (`Main.X`):
        // a global named after it, unless a global already has the name.
        env.reached = reached_programs(unit, &env);
        let mut instances: Vec<String> =
            env.pous.iter().filter(|p| p.kind == PouKind::Program).map(|p| p.name.to_ascii_uppercase()).collect();
        instances.sort_unstable();
        instances.dedup();
        let implicit: Vec<VarInfo> = instances
            .iter()
            .filter(|p| !seen.contains_key(*p))
            .filter_map(|p| env.pou(p))
            .map(|p| VarInfo {
                name: p.name.clone(),
                span: p.span,
                kind: VarKind::Global,
                constant: false,
                retain: None,
                persistent: false,
                ty: Type::FunctionBlock(p.name.to_ascii_uppercase()),
                location: None,
                init: None,
                value: None,
                implicit: true,
            })
            .collect();
        for var in implicit {
            env.add_global(var, &mut seen, &mut diags);
        }

        // A VAR_EXTERNAL must repeat the type of its global.
        for pou in &env.pous {
            for var in pou.vars.iter().filter(|v| v.kind == VarKind::External) {
                let Some(g) = env.global(&var.name) else { continue };
                if !g.ty.is_error() && !var.ty.is_error() && g.ty != var.ty {
                    diags.push(
                        Diagnostic::new(
                            "SFC0302",
                            var.span,
                            format!(
                                "type mismatch: VAR_EXTERNAL `{}` is declared `{}`, but the global is `{}`",
                                var.name, var.ty, g.ty
                            ),
                        )
                        .with_label(g.span, "global declared here"),
                    );
                }
            }
        }

        env.types = b.resolved.into_iter().collect();
        let mut index: FxHashMap<String, Vec<Type>> = FxHashMap::default();
        let mut named: Vec<&TypeDef> = env.types.values().collect();
        named.sort_by_key(|d| d.span);
        let enum_types = named.iter().map(|d| &d.ty).chain(env.globals.iter().map(|v| &v.ty));
        for ty in enum_types {
            if let Type::Enum { values, .. } = ty {
                for (v, _) in values {
                    let list = index.entry(v.to_ascii_uppercase()).or_default();
                    if !list.contains(ty) {
                        list.push(ty.clone());
                    }
                }
            }
        }
        env.enum_values = index;
        (env, diags)
    }

    /// A declared data type by name (case-insensitive).
    pub fn type_def(&self, name: &str) -> Option<&TypeDef> {
        self.types.get(&name.to_ascii_uppercase())
    }

    /// All declared data types.
    pub fn type_defs(&self) -> impl Iterator<Item = &TypeDef> {
        self.types.values()
    }

    /// The type a name stands for where a type is expected (`SIZEOF(T)`): elementary, declared,
    /// an interface or a function block.
    pub fn named_type(&self, name: &str) -> Option<Type> {
        if let Some(t) = Type::elementary(name) {
            return Some(t);
        }
        if let Some(d) = self.type_def(name) {
            return Some(d.ty.clone());
        }
        if self.interface(name).is_some() {
            return Some(Type::Interface(name.to_ascii_uppercase()));
        }
        self.function_block(name).map(|_| Type::FunctionBlock(name.to_ascii_uppercase()))
    }

    /// An interface by name (case-insensitive).
    pub fn interface(&self, name: &str) -> Option<&InterfaceInfo> {
        self.interfaces.get(&name.to_ascii_uppercase())
    }

    /// Whether a value of type `from` may be assigned to (or passed as) an interface `to`: an
    /// instance of a block that implements it (itself, through an interface extending it, or
    /// through its base blocks), or an interface that is it or extends it.
    pub fn converts_to_interface(&self, from: &Type, to: &str) -> bool {
        let extends =
            |i: &str| interface_chain(&self.interfaces, i).is_ok_and(|c| c.iter().any(|k| k.eq_ignore_ascii_case(to)));
        match from {
            Type::Interface(i) => extends(i),
            Type::FunctionBlock(fb) => {
                let mut at = self.function_block(fb);
                let mut hops = 0;
                while let Some(p) = at {
                    if p.implements.iter().any(|i| extends(i)) {
                        return true;
                    }
                    hops += 1;
                    if hops > 64 {
                        return false;
                    }
                    at = p.base.as_deref().and_then(|b| self.function_block(b));
                }
                false
            }
            _ => false,
        }
    }

    /// The method `name` of a value of type `ty`: of the block of an instance, or of an
    /// interface.
    pub fn method_of(&self, ty: &Type, name: &str) -> Option<&MethodSig> {
        match ty {
            Type::Interface(i) => self.interface(i)?.method(name),
            _ => self.fb_of(ty)?.method(name),
        }
    }

    /// The property `name` of a value of type `ty`, as [`TypeEnv::method_of`].
    pub fn property_of(&self, ty: &Type, name: &str) -> Option<&PropSig> {
        match ty {
            Type::Interface(i) => self.interface(i)?.property(name),
            _ => self.fb_of(ty)?.property(name),
        }
    }

    /// A user POU by name (the first one declared with that name).
    pub fn pou(&self, name: &str) -> Option<&PouInterface> {
        self.pou_index.get(&name.to_ascii_uppercase()).and_then(|&i| self.pous.get(i))
    }

    /// The interface of this very POU of the file (found by the span of its name, so each of
    /// two POUs with the same name has its own).
    pub fn interface_of(&self, pou: &Pou) -> Option<&PouInterface> {
        self.pous.iter().find(|p| p.span == pou.name.span && p.name == pou.name.text)
    }

    /// Whether a POU of the file extends the block `name` (`EXTENDS`): its variables are used
    /// by the code of the blocks extending it too.
    pub fn is_extended(&self, name: &str) -> bool {
        self.pous.iter().any(|p| p.base.as_deref().is_some_and(|b| b.eq_ignore_ascii_case(name)))
            || self.opaque_bases.contains(&name.to_ascii_uppercase())
    }

    /// A user FUNCTION by name.
    pub fn function(&self, name: &str) -> Option<&PouInterface> {
        self.pou(name).filter(|p| p.kind == PouKind::Function)
    }

    /// A function block type (user or standard) by name; programs count too, since a program
    /// type can be instantiated like a block.
    pub fn function_block(&self, name: &str) -> Option<&PouInterface> {
        let key = name.to_ascii_uppercase();
        if let Some(p) = self.pou(&key).filter(|p| p.kind != PouKind::Function) {
            return Some(p);
        }
        self.std_fbs.get(&key)
    }

    /// The interface of the function block type of an instance type.
    pub fn fb_of(&self, ty: &Type) -> Option<&PouInterface> {
        match ty {
            Type::FunctionBlock(name) => self.function_block(name),
            _ => None,
        }
    }

    /// File-level global variables, in declaration order.
    pub fn globals(&self) -> &[VarInfo] {
        &self.globals
    }

    /// The position of a global variable in [`TypeEnv::globals`].
    pub(crate) fn global_position(&self, name: &str) -> Option<usize> {
        self.global_index.get(&name.to_ascii_uppercase()).copied()
    }

    /// A global variable by name (case-insensitive).
    pub fn global(&self, name: &str) -> Option<&VarInfo> {
        self.global_index.get(&name.to_ascii_uppercase()).and_then(|&i| self.globals.get(i))
    }

    /// The enumerated types (named, or inline in a global declaration) that have a value of
    /// this name.
    pub fn enum_types_with_value(&self, name: &str) -> &[Type] {
        self.enum_values.get(&name.to_ascii_uppercase()).map(Vec::as_slice).unwrap_or(&[])
    }

    /// The names of user functions, function blocks, programs and types (for suggestions).
    pub(crate) fn declared_names(&self) -> impl Iterator<Item = &str> {
        self.pous.iter().map(|p| p.name.as_str()).chain(self.types.values().map(|t| t.name.as_str()))
    }

    /// Resolves a type as written in a declaration; named constants come from `consts`.
    pub fn resolve_type_spec(
        &self,
        spec: &sfc_syntax::ast::TypeSpec,
        consts: &dyn ConstLookup,
        diags: &mut Vec<Diagnostic>,
    ) -> Type {
        let mut names = EnvNames { env: self, consts };
        resolve_spec(&mut names, spec, None, diags)
    }
}

impl ConstLookup for TypeEnv {
    fn constant(&self, name: &str) -> Option<Value> {
        self.global(name).filter(|v| v.constant).and_then(|v| v.value)
    }
}

/// Names reserved by the language and the standard library.
fn reserved(key: &str) -> bool {
    Type::elementary(key).is_some()
        || crate::types::Generic::from_name(key).is_some()
        || std_function(key).is_some()
        || std_function_block(key).is_some()
}

fn duplicate(name: &Ident, prev: Span, what: &str) -> Diagnostic {
    Diagnostic::new("SFC0318", name.span, format!("`{}` is declared more than once ({what})", name.text))
        .with_label(prev, "first declared here")
}

fn reserved_name(name: &Ident, what: &str) -> Diagnostic {
    Diagnostic::new(
        "SFC0318",
        name.span,
        format!("{what} `{}` redefines a standard type, function or function block", name.text),
    )
}

impl TypeEnv {
    /// Registers a global, or reports it as a duplicate of the one `seen` first.
    fn add_global(&mut self, var: VarInfo, seen: &mut HashMap<String, Span>, diags: &mut Vec<Diagnostic>) {
        let key = var.name.to_ascii_uppercase();
        if let Some(prev) = seen.get(&key) {
            diags.push(duplicate_var(&var, *prev));
            return;
        }
        seen.insert(key.clone(), var.span);
        self.global_index.insert(key, self.globals.len());
        self.globals.push(var);
    }
}

/// `(program, variable)` for every `Program.Variable` (or `Program.Action()`) in the code of
/// the file, upper case.
fn reached_programs(unit: &SourceUnit, env: &TypeEnv) -> std::collections::HashSet<(String, String)> {
    let mut out = std::collections::HashSet::new();
    for item in &unit.items {
        let Item::Pou(pou) = item else { continue };
        sfc_syntax::visit::pou_exprs(pou, &mut |e| {
            let (sfc_syntax::ast::ExprKind::Member { base, member }
            | sfc_syntax::ast::ExprKind::MemberCall { base, member, .. }) = &e.kind
            else {
                return;
            };
            if let sfc_syntax::ast::ExprKind::Name(n) = &base.kind {
                if env.pou(&n.text).is_some_and(|p| p.kind == PouKind::Program) {
                    out.insert((n.key(), member.key()));
                }
            }
        });
    }
    out
}

fn duplicate_var(var: &VarInfo, prev: Span) -> Diagnostic {
    Diagnostic::new("SFC0206", var.span, format!("variable `{}` is declared more than once", var.name))
        .with_label(prev, "first declared here")
}

/// The interface of a standard function block.
fn standard_fb(name: &str) -> Option<PouInterface> {
    let params = std_function_block(name)?;
    let vars = params
        .into_iter()
        .map(|(n, kind, ty)| VarInfo {
            name: n.to_string(),
            span: Span::default(),
            kind,
            constant: false,
            retain: None,
            persistent: false,
            ty,
            location: None,
            init: None,
            value: None,
            implicit: false,
        })
        .collect();
    Some(PouInterface {
        name: name.to_ascii_uppercase(),
        kind: PouKind::FunctionBlock,
        vars,
        return_type: None,
        standard: true,
        span: Span::default(),
        sfc: false,
        actions: Vec::new(),
        sfc_actions: Vec::new(),
        methods: Vec::new(),
        properties: Vec::new(),
        base: None,
        implements: Vec::new(),
    })
}

/// Evaluates the CONSTANT declarations of a block in order (later ones may use earlier ones).
pub(crate) fn block_constants(block: &VarBlock, outer: &dyn ConstLookup) -> HashMap<String, Value> {
    struct Chain<'a> {
        local: &'a HashMap<String, Value>,
        outer: &'a dyn ConstLookup,
    }
    impl ConstLookup for Chain<'_> {
        fn constant(&self, name: &str) -> Option<Value> {
            self.local.get(&name.to_ascii_uppercase()).copied().or_else(|| self.outer.constant(name))
        }
    }
    let mut local = HashMap::new();
    if !block.constant {
        return local;
    }
    for decl in &block.decls {
        let Some(Initializer::Expr(e)) = &decl.init else { continue };
        let value = const_eval(e, &Chain { local: &local, outer });
        if let Some(v) = value {
            for n in &decl.names {
                local.insert(n.key(), v);
            }
        }
    }
    local
}

impl ConstLookup for HashMap<String, Value> {
    fn constant(&self, name: &str) -> Option<Value> {
        self.get(&name.to_ascii_uppercase()).copied()
    }
}

/// Type names as seen after the environment is built.
struct EnvNames<'a> {
    env: &'a TypeEnv,
    consts: &'a dyn ConstLookup,
}

impl TypeNames for EnvNames<'_> {
    fn named_type(&mut self, ident: &Ident, _diags: &mut Vec<Diagnostic>) -> Named {
        let key = ident.key();
        if let Some(def) = self.env.types.get(&key) {
            return Named::Type(def.ty.clone());
        }
        if self.env.opaque.contains(&key) {
            return Named::Type(Type::Error);
        }
        match self.env.pou(&key) {
            Some(p) if p.kind == PouKind::Function => Named::NotAType("a function"),
            Some(_) => Named::Type(Type::FunctionBlock(key)),
            None if std_function_block(&key).is_some() => Named::Type(Type::FunctionBlock(key)),
            None if std_function(&key).is_some() => Named::NotAType("a standard function"),
            None => Named::Unknown,
        }
    }
    fn constant(&self, name: &str) -> Option<Value> {
        self.consts.constant(name)
    }
    fn candidates(&self) -> Vec<String> {
        self.env.declared_names().map(str::to_string).collect()
    }
}

/// Deeper chains of type definitions (`A : B; B : C; …`) are refused rather than risking the
/// stack.
const MAX_TYPE_NESTING: usize = 128;

/// State while building a [`TypeEnv`]: TYPE declarations are resolved on demand so that they
/// may refer to each other in any order, and cycles are reported instead of looping.
#[derive(Default)]
struct Builder<'a> {
    decls: HashMap<String, &'a TypeDecl>,
    resolved: HashMap<String, TypeDef>,
    in_progress: Vec<String>,
    pou_kinds: HashMap<String, (PouKind, Span)>,
    /// Global constants.
    consts: HashMap<String, Value>,
    /// Constants of the POU whose interface is being resolved.
    local_consts: HashMap<String, Value>,
    /// POUs kept as written: opaque types.
    opaque: std::collections::HashSet<String>,
    /// Interfaces: where each name was declared.
    interfaces: HashMap<String, Span>,
}

impl<'a> Builder<'a> {
    /// Where a type or POU name was first declared.
    fn name_span(&self, key: &str) -> Option<Span> {
        self.decls
            .get(key)
            .map(|d| d.name.span)
            .or_else(|| self.pou_kinds.get(key).map(|(_, s)| *s))
            .or_else(|| self.interfaces.get(key).copied())
    }

    fn resolve_decl(&mut self, key: &str, diags: &mut Vec<Diagnostic>) -> Type {
        if let Some(def) = self.resolved.get(key) {
            return def.ty.clone();
        }
        let Some(decl) = self.decls.get(key).copied() else { return Type::Error };
        if self.in_progress.len() > MAX_TYPE_NESTING {
            diags.push(Diagnostic::new(
                "SFC0313",
                decl.name.span,
                format!("type `{}` is defined through too many other types", decl.name.text),
            ));
            return Type::Error;
        }
        if self.in_progress.iter().any(|k| k == key) {
            diags.push(Diagnostic::new(
                "SFC0313",
                decl.name.span,
                format!("type `{}` is defined in terms of itself", decl.name.text),
            ));
            return Type::Error;
        }
        self.in_progress.push(key.to_string());
        let ty = resolve_spec(self, &decl.spec, Some(&decl.name.text), diags);
        self.in_progress.pop();
        let field_inits = match &decl.spec.kind {
            TypeSpecKind::Struct(fields) => {
                fields.iter().flat_map(|f| f.names.iter().map(|_| f.init.clone())).collect()
            }
            _ => Vec::new(),
        };
        // A cycle found deeper down may already have stored an entry; keep the first.
        self.resolved.entry(key.to_string()).or_insert(TypeDef {
            name: decl.name.text.clone(),
            ty: ty.clone(),
            init: decl.init.clone(),
            field_inits,
            span: decl.name.span,
        });
        ty
    }

    /// The variables of one var block, with types resolved and locations checked.
    fn block_vars(&mut self, block: &VarBlock, diags: &mut Vec<Diagnostic>) -> Vec<VarInfo> {
        let consts: HashMap<String, Value> = if block.constant {
            let chain = ChainConsts { a: &self.local_consts, b: &self.consts };
            block_constants(block, &chain)
        } else {
            HashMap::new()
        };
        let mut out = Vec::new();
        for decl in &block.decls {
            let ty = resolve_spec(self, &decl.ty, None, diags);
            if let (Some(edge), Some(n)) = (decl.edge, decl.names.first()) {
                if block.kind != VarKind::Input || !(ty.is_bool() || ty.is_error()) {
                    diags.push(Diagnostic::new(
                        "SFC0302",
                        n.span,
                        format!(
                            "`{}` is declared {}, which only a BOOL VAR_INPUT can be (IEC 61131-3 table 14)",
                            n.text,
                            edge.keyword()
                        ),
                    ));
                }
            }
            if let Some(addr) = &decl.location {
                check_location(addr, &ty, decl.names.first(), diags);
            }
            for name in &decl.names {
                out.push(VarInfo::declared(name, block, decl, ty.clone(), &consts));
            }
        }
        out
    }

    fn interface(&mut self, pou: &Pou, diags: &mut Vec<Diagnostic>) -> PouInterface {
        self.local_consts.clear();
        for block in &pou.var_blocks {
            let chain = ChainConsts { a: &self.local_consts, b: &self.consts };
            let c = block_constants(block, &chain);
            self.local_consts.extend(c);
        }
        let mut vars: Vec<VarInfo> = Vec::new();
        let mut seen: HashMap<String, Span> = HashMap::new();
        for block in &pou.var_blocks {
            for var in self.block_vars(block, diags) {
                let key = var.name.to_ascii_uppercase();
                if let Some(prev) = seen.get(&key) {
                    diags.push(duplicate_var(&var, *prev));
                    continue;
                }
                seen.insert(key, var.span);
                vars.push(var);
            }
        }
        let return_type = pou.return_type.as_ref().map(|spec| resolve_spec(self, spec, None, diags));
        self.local_consts.clear();
        let sfc = pou.has_chart();
        if sfc {
            add_sfc_control_variables(&mut vars, pou.name.span, diags);
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
            sfc_actions: sfc_actions(pou),
            methods: pou.methods.iter().map(|m| self.method_sig(&pou.name.text, m, diags)).collect(),
            properties: pou.properties.iter().map(|p| self.property_sig(&pou.name.text, p, diags)).collect(),
            base: pou.extends.as_ref().map(|b| b.text.clone()),
            implements: pou.implements.iter().map(|i| i.text.clone()).collect(),
        };
        // A method or property shares the block's namespace with its variables.
        let names =
            iface.methods.iter().map(|m| (&m.name, m.span)).chain(iface.properties.iter().map(|p| (&p.name, p.span)));
        let mut seen: HashMap<String, Span> =
            iface.vars.iter().filter(|v| !v.implicit).map(|v| (v.name.to_ascii_uppercase(), v.span)).collect();
        for (name, span) in names {
            match seen.get(&name.to_ascii_uppercase()) {
                Some(prev) => diags.push(
                    Diagnostic::new(
                        "SFC0206",
                        span,
                        format!("`{name}` is declared more than once in `{}`", iface.name),
                    )
                    .with_label(*prev, "first declared here"),
                ),
                None => {
                    seen.insert(name.to_ascii_uppercase(), span);
                }
            }
        }
        iface
    }

    /// The variables of a method or accessor, each name declared once.
    fn own_vars(&mut self, blocks: &[VarBlock], diags: &mut Vec<Diagnostic>) -> Vec<VarInfo> {
        self.local_consts.clear();
        let mut vars: Vec<VarInfo> = Vec::new();
        let mut seen: HashMap<String, Span> = HashMap::new();
        for block in blocks {
            for var in self.block_vars(block, diags) {
                let key = var.name.to_ascii_uppercase();
                if let Some(prev) = seen.get(&key) {
                    diags.push(duplicate_var(&var, *prev));
                    continue;
                }
                seen.insert(key, var.span);
                vars.push(var);
            }
        }
        vars
    }

    fn method_sig(&mut self, owner: &str, m: &sfc_syntax::ast::Method, diags: &mut Vec<Diagnostic>) -> MethodSig {
        let vars = self.own_vars(&m.var_blocks, diags);
        MethodSig {
            name: m.name.text.clone(),
            owner: owner.to_string(),
            vars,
            return_type: m.return_type.as_ref().map(|spec| resolve_spec(self, spec, None, diags)),
            span: m.name.span,
        }
    }

    fn property_sig(&mut self, owner: &str, p: &sfc_syntax::ast::Property, diags: &mut Vec<Diagnostic>) -> PropSig {
        let ty = resolve_spec(self, &p.ty, None, diags);
        let get = p.get.as_ref().map(|a| MethodSig {
            name: p.name.text.clone(),
            owner: owner.to_string(),
            vars: self.own_vars(&a.var_blocks, diags),
            return_type: Some(ty.clone()),
            span: p.name.span,
        });
        let set = p.set.as_ref().map(|a| {
            let mut vars = self.own_vars(&a.var_blocks, diags);
            vars.insert(
                0,
                VarInfo {
                    name: p.name.text.clone(),
                    span: p.name.span,
                    kind: VarKind::Input,
                    constant: false,
                    retain: None,
                    persistent: false,
                    ty: ty.clone(),
                    location: None,
                    init: None,
                    value: None,
                    implicit: true,
                },
            );
            MethodSig {
                name: p.name.text.clone(),
                owner: owner.to_string(),
                vars,
                return_type: None,
                span: p.name.span,
            }
        });
        PropSig { name: p.name.text.clone(), owner: owner.to_string(), ty, get, set, span: p.name.span }
    }

    /// An interface's own methods and properties. A property of an interface written without
    /// GET and SET (CODESYS's text declares neither) has both.
    fn interface_info(&mut self, i: &sfc_syntax::ast::Interface, diags: &mut Vec<Diagnostic>) -> InterfaceInfo {
        let owner = i.name.text.as_str();
        let methods = i.methods.iter().map(|m| self.method_sig(owner, m, diags)).collect();
        let open_properties =
            i.properties.iter().filter(|p| p.get.is_none() && p.set.is_none()).map(|p| p.name.key()).collect();
        let properties = i
            .properties
            .iter()
            .map(|p| {
                let mut sig = self.property_sig(owner, p, diags);
                if p.get.is_none() && p.set.is_none() {
                    let both = sfc_syntax::ast::Property {
                        get: Some(empty_accessor(p.span)),
                        set: Some(empty_accessor(p.span)),
                        ..p.clone()
                    };
                    sig = self.property_sig(owner, &both, diags);
                }
                sig
            })
            .collect();
        InterfaceInfo {
            name: i.name.text.clone(),
            extends: i.extends.iter().map(|e| e.text.clone()).collect(),
            methods,
            properties,
            open_properties,
            span: i.name.span,
        }
    }
}

/// `EXTENDS`: each block that extends another gets the base's variables before its own, and
/// the base's methods and properties that it does not override (after its own). Unknown bases
/// and cycles are reported.
fn inherit(pous: &mut [PouInterface], index: &FxHashMap<String, usize>, diags: &mut Vec<Diagnostic>) {
    fn chain(pous: &[PouInterface], index: &FxHashMap<String, usize>, i: usize) -> Result<Vec<usize>, ()> {
        let mut out = Vec::new();
        let mut at = i;
        while let Some(b) = &pous[at].base {
            let Some(&j) = index.get(&b.to_ascii_uppercase()) else { break };
            if j == i || out.contains(&j) {
                return Err(());
            }
            out.push(j);
            at = j;
        }
        Ok(out)
    }
    let originals: Vec<PouInterface> = pous.to_vec();
    for i in 0..pous.len() {
        let Some(base) = pous[i].base.clone() else { continue };
        let bi = index.get(&base.to_ascii_uppercase()).copied();
        match bi.map(|b| &originals[b]) {
            None => {
                diags.push(Diagnostic::new(
                    "SFC0313",
                    pous[i].span,
                    format!("`{}` extends `{base}`, which is not declared", pous[i].name),
                ));
                continue;
            }
            Some(b) if b.kind == PouKind::Function || b.kind != pous[i].kind => {
                diags.push(Diagnostic::new(
                    "SFC0313",
                    pous[i].span,
                    format!("`{}` extends `{base}`, which is a {}", pous[i].name, b.kind.keyword()),
                ));
                continue;
            }
            Some(_) => {}
        }
        let Ok(bases) = chain(&originals, index, i) else {
            diags.push(Diagnostic::new(
                "SFC0313",
                pous[i].span,
                format!("`{}` extends itself through `{base}`", pous[i].name),
            ));
            pous[i].base = None;
            continue;
        };
        // The farthest base first: its variables lie first in every frame of the family.
        let mut vars: Vec<VarInfo> = Vec::new();
        for &b in bases.iter().rev() {
            vars.extend(originals[b].vars.iter().filter(|v| !v.implicit).cloned());
        }
        let own = std::mem::take(&mut pous[i].vars);
        for v in own {
            if let Some(prev) = vars.iter().find(|p| p.name.eq_ignore_ascii_case(&v.name)) {
                if !v.implicit {
                    diags.push(duplicate_var(&v, prev.span));
                }
                continue;
            }
            vars.push(v);
        }
        pous[i].vars = vars;
        for &b in &bases {
            for m in &originals[b].methods {
                if pous[i].method(&m.name).is_none() {
                    pous[i].methods.push(m.clone());
                }
            }
            for p in &originals[b].properties {
                if pous[i].property(&p.name).is_none() {
                    pous[i].properties.push(p.clone());
                }
            }
            for a in &originals[b].actions {
                if !pous[i].actions.iter().any(|x| x.eq_ignore_ascii_case(a)) {
                    pous[i].actions.push(a.clone());
                }
            }
        }
    }
}

/// An accessor without variables or code: what an interface's property declares.
fn empty_accessor(span: Span) -> sfc_syntax::ast::Accessor {
    sfc_syntax::ast::Accessor {
        modifiers: Vec::new(),
        attributes: Vec::new(),
        var_blocks: Vec::new(),
        body: sfc_syntax::ast::Body::St(Vec::new()),
        span,
    }
}

/// The interfaces `name` extends, itself first, each once (upper-case); `Err` with the
/// unknown one, or on a cycle back to `name`.
fn interface_chain(interfaces: &FxHashMap<String, InterfaceInfo>, name: &str) -> Result<Vec<String>, String> {
    let first = name.to_ascii_uppercase();
    let mut out = vec![first.clone()];
    let mut k = 0;
    while let Some(n) = out.get(k).cloned() {
        k += 1;
        let Some(i) = interfaces.get(&n) else { return Err(n) };
        for e in &i.extends {
            let key = e.to_ascii_uppercase();
            if key == first {
                return Err(format!("itself through `{}`", i.name));
            }
            if !out.contains(&key) {
                out.push(key);
            }
        }
    }
    Ok(out)
}

/// `INTERFACE I EXTENDS A, B`: `I` gets the methods and properties of `A` and `B` it does not
/// declare itself. Unknown interfaces and cycles are reported (SFC0313).
fn inherit_interfaces(interfaces: &mut FxHashMap<String, InterfaceInfo>, diags: &mut Vec<Diagnostic>) {
    let originals = interfaces.clone();
    let mut keys: Vec<&String> = originals.keys().collect();
    keys.sort_by_key(|k| originals[*k].span);
    for key in keys {
        let info = &originals[key];
        let chain = match interface_chain(&originals, key) {
            Ok(c) => c,
            Err(why) => {
                let what = if why.starts_with("itself") {
                    why
                } else {
                    // The name as written where it is extended.
                    let written = originals
                        .values()
                        .flat_map(|i| i.extends.iter())
                        .find(|e| e.eq_ignore_ascii_case(&why))
                        .cloned()
                        .unwrap_or(why);
                    format!("`{written}`, which is not a declared interface")
                };
                diags.push(Diagnostic::new("SFC0313", info.span, format!("interface `{}` extends {what}", info.name)));
                continue;
            }
        };
        let Some(me) = interfaces.get_mut(key) else { continue };
        for other in chain.iter().skip(1).filter_map(|k| originals.get(k)) {
            for m in &other.methods {
                if me.method(&m.name).is_none() {
                    me.methods.push(m.clone());
                }
            }
            for p in &other.properties {
                if me.property(&p.name).is_none() {
                    me.properties.push(p.clone());
                    if other.open_properties.contains(&p.name.to_ascii_uppercase()) {
                        me.open_properties.push(p.name.to_ascii_uppercase());
                    }
                }
            }
        }
    }
}

/// `FUNCTION_BLOCK B IMPLEMENTS I`: `B` (with what it inherits) has each method and property
/// of `I`, with the same result type and parameters (SFC0323 otherwise); an interface the file
/// does not declare is a warning (SFC0324: a library's, not checked).
fn check_implements(env: &TypeEnv, diags: &mut Vec<Diagnostic>) {
    for pou in &env.pous {
        for name in &pou.implements {
            if env.is_opaque(name) {
                continue;
            }
            let Some(itf) = env.interface(name) else {
                diags.push(if env.pou(name).is_some() || env.type_def(name).is_some() {
                    Diagnostic::new(
                        "SFC0323",
                        pou.span,
                        format!("`{}` implements `{name}`, which is no interface", pou.name),
                    )
                } else {
                    Diagnostic::warning(
                        "SFC0324",
                        pou.span,
                        format!(
                            "`{}` implements `{name}`, which the file does not declare (a library's interface?)",
                            pou.name
                        ),
                    )
                    .with_note("what the block promises is not checked")
                });
                continue;
            };
            for m in &itf.methods {
                let params = |s: &MethodSig| -> Vec<(VarKind, String, Type)> {
                    s.vars
                        .iter()
                        .filter(|v| matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::InOut))
                        .map(|v| (v.kind, v.name.to_ascii_uppercase(), v.ty.clone()))
                        .collect()
                };
                match pou.method(&m.name) {
                    None => diags.push(Diagnostic::new(
                        "SFC0323",
                        pou.span,
                        format!("`{}` implements `{}` but has no method `{}`", pou.name, itf.name, m.name),
                    )),
                    Some(own) if own.return_type != m.return_type || params(own) != params(m) => diags.push(
                        Diagnostic::new(
                            "SFC0323",
                            own.span,
                            format!(
                                "method `{}` of `{}` differs from its prototype in interface `{}` (result or parameters)",
                                own.name, pou.name, itf.name
                            ),
                        )
                        .with_label(m.span, "the prototype"),
                    ),
                    Some(_) => {}
                }
            }
            for p in &itf.properties {
                let own = pou.property(&p.name);
                let open = itf.open_properties.contains(&p.name.to_ascii_uppercase());
                let ok = own.is_some_and(|o| {
                    o.ty == p.ty
                        && (open || ((p.get.is_none() || o.get.is_some()) && (p.set.is_none() || o.set.is_some())))
                });
                if !ok {
                    diags.push(Diagnostic::new(
                        "SFC0323",
                        own.map_or(pou.span, |o| o.span),
                        format!(
                            "`{}` implements `{}` but has no property `{}` of type `{}` with {}",
                            pou.name,
                            itf.name,
                            p.name,
                            p.ty,
                            match (p.get.is_some(), p.set.is_some()) {
                                _ if open => "GET or SET",
                                (true, true) => "GET and SET",
                                (true, false) => "GET",
                                _ => "SET",
                            }
                        ),
                    ));
                }
            }
        }
    }
}

struct ChainConsts<'a> {
    a: &'a HashMap<String, Value>,
    b: &'a HashMap<String, Value>,
}

impl ConstLookup for ChainConsts<'_> {
    fn constant(&self, name: &str) -> Option<Value> {
        let key = name.to_ascii_uppercase();
        self.a.get(&key).or_else(|| self.b.get(&key)).copied()
    }
}

impl TypeNames for Builder<'_> {
    fn named_type(&mut self, ident: &Ident, diags: &mut Vec<Diagnostic>) -> Named {
        let key = ident.key();
        if self.decls.contains_key(&key) {
            return Named::Type(self.resolve_decl(&key, diags));
        }
        if self.opaque.contains(&key) {
            return Named::Type(Type::Error);
        }
        if self.interfaces.contains_key(&key) {
            return Named::Type(Type::Interface(key));
        }
        match self.pou_kinds.get(&key) {
            Some((PouKind::Function, _)) => Named::NotAType("a function"),
            Some(_) => Named::Type(Type::FunctionBlock(key)),
            None if std_function_block(&key).is_some() => Named::Type(Type::FunctionBlock(key)),
            None if std_function(&key).is_some() => Named::NotAType("a standard function"),
            None => Named::Unknown,
        }
    }
    fn constant(&self, name: &str) -> Option<Value> {
        ChainConsts { a: &self.local_consts, b: &self.consts }.constant(name)
    }
    fn candidates(&self) -> Vec<String> {
        self.decls.values().map(|d| d.name.text.clone()).collect()
    }
}

/// Checks that a located variable's type has the size of its address (`%IX` a BOOL, `%IW` a
/// 16-bit type, …); arrays are checked by their element type.
fn check_location(addr: &DirectAddress, ty: &Type, name: Option<&Ident>, diags: &mut Vec<Diagnostic>) {
    if addr.path.is_empty() {
        return; // `%I*`: the size is decided at configuration time.
    }
    let elem = match ty {
        Type::Array { elem, .. } => elem.as_ref(),
        t => t,
    };
    let Some(width) = elem.bit_width() else { return };
    let (ok, wanted) = match addr.size.to_ascii_uppercase() {
        'X' => (width == 1, "a single bit (BOOL)"),
        'B' => (width == 8 && !elem.is_bool(), "8 bits"),
        'W' => (width == 16, "16 bits"),
        'D' => (width == 32, "32 bits"),
        'L' => (width == 64, "64 bits"),
        _ => return,
    };
    if !ok {
        let who = name.map(|n| format!("`{}`", n.text)).unwrap_or_else(|| "the variable".to_string());
        diags.push(Diagnostic::new(
            "SFC0302",
            addr.span,
            format!("type mismatch: `{}` holds {wanted}, but {who} is `{ty}`", addr.text),
        ));
    }
}
