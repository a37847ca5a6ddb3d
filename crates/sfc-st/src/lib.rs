//! Structured Text typing, shared by the model checker, simulator and analyzer.
//!
//! * [`Type`] — IEC 61131-3 data types, generic classes and implicit widening.
//! * [`TypeEnv`] — what a file declares: types, POU interfaces, globals, plus the standard
//!   function blocks; standard functions are in [`stdlib`].
//! * [`Scope`] — the names visible in one POU's code (variables, globals, steps, actions) and
//!   how the code used them.
//! * [`Checker`] — type checking of ST statements and expressions, transition conditions (ST
//!   and IL), action associations and initial values, with located diagnostics (SFC03xx).
//! * [`const_eval`] — compile-time integer/real/BOOL/TIME constants.
//!
//! [`check_unit`] runs all of it over a parsed file. A caller that holds the chart elements
//! itself (the chart model) uses the parts:
//!
//! ```text
//! let (env, mut diags) = TypeEnv::from_unit(&unit);          // types, interfaces, globals
//! let mut scope = Scope::for_pou(&env, pou);                 // the POU's variables + globals
//! scope.add_step(&step.name)?; scope.add_action(&action.name)?;
//! let mut ck = Checker::new(&mut scope);
//! ck.check_declarations();                                   // initial values
//! ck.set_element(Some(name)); ck.check_condition(&t.condition); ck.check_action_body(&a.body);
//! diags.extend(ck.finish()); diags.extend(scope.unused_diagnostics());
//! ```

#![warn(missing_docs)]

mod calls;
mod check;
mod env;
mod il;
mod resolve;
mod scope;
pub mod stdlib;
mod suggest;
mod types;
mod value;

#[cfg(test)]
mod tests;

pub use check::Checker;
pub use env::{
    is_sfc_control_variable, sfc_control_variables, InterfaceInfo, MethodSig, PouInterface, PropSig, TypeDef, TypeEnv,
    VarInfo,
};
pub use il::{parse_il_op, IlOp};
pub use scope::{Binding, Scope, Usage};
pub use suggest::closest;
pub use types::{Generic, Type};
pub use value::{const_eval, ConstLookup, NoConstants, Value};

use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{ActionBody, Body, Ident, Item, Pou, PouKind, SfcElement, SourceUnit};
use std::collections::HashMap;

/// Type-checks a whole file: declarations, global and type initial values, and the code of
/// every POU (ST and IL bodies, and for charts the transition conditions, action bodies,
/// association durations and indicators), plus SFC0317 warnings for unused locals.
///
/// Chart structure (steps, links, names shared by steps, actions and variables, undeclared
/// actions) is the model's to check; clashing chart names are skipped here.
pub fn check_unit(unit: &SourceUnit) -> Vec<Diagnostic> {
    check_unit_with(unit, &mut |_, _| {})
}

/// [`check_unit`] with a hook that may add names to each POU's scope before its code is
/// checked (e.g. the implicit BOOL inputs `C0`…`C15` of an ATMT chart, via
/// [`Scope::declare`]).
pub fn check_unit_with(unit: &SourceUnit, prepare: &mut dyn FnMut(&mut Scope<'_>, &Pou)) -> Vec<Diagnostic> {
    check_unit_inner(unit, prepare, None)
}

/// [`check_unit`] that also returns the type of every checked expression by span (see
/// [`Checker::expr_type`]): every [`Checker`] it creates keeps its types. For the simulator.
pub fn check_unit_typed(unit: &SourceUnit) -> (Vec<Diagnostic>, HashMap<Span, Type>) {
    let mut types = HashMap::new();
    let diags = check_unit_inner(unit, &mut |_, _| {}, Some(&mut types));
    (diags, types)
}

fn check_unit_inner(
    unit: &SourceUnit,
    prepare: &mut dyn FnMut(&mut Scope<'_>, &Pou),
    mut types: Option<&mut HashMap<Span, Type>>,
) -> Vec<Diagnostic> {
    let (env, mut diags) = TypeEnv::from_unit(unit);
    {
        let mut scope = Scope::globals_only(&env);
        let mut ck = Checker::new(&mut scope);
        if types.is_some() {
            ck.keep_types();
        }
        ck.check_declarations();
        let mut defs: Vec<&TypeDef> = env.type_defs().collect();
        defs.sort_by_key(|d| d.span);
        for def in defs {
            if let Some(init) = &def.init {
                ck.check_initializer(init, &def.ty, &def.name);
            }
            if let Type::Struct { fields, .. } = &def.ty {
                for ((name, ty), init) in fields.iter().zip(&def.field_inits) {
                    if let Some(init) = init {
                        ck.check_initializer(init, ty, &format!("{}.{name}", def.name));
                    }
                }
            }
        }
        if let Some(t) = types.as_deref_mut() {
            t.extend(ck.take_expr_types());
        }
        diags.extend(ck.finish());
    }
    for item in &unit.items {
        if let Item::Pou(pou) = item {
            diags.extend(check_pou_inner(&env, pou, prepare, types.as_deref_mut()));
        }
    }
    diags
}

/// Whether `pou` is marked `{attribute 'sfc.dialect' := 'codesys'}`: CODESYS's typing rules
/// apply to its code.
pub fn is_codesys(pou: &Pou) -> bool {
    pou.attributes.iter().any(|a| {
        a.name.eq_ignore_ascii_case("sfc.dialect")
            && a.value.as_deref().is_some_and(|v| v.eq_ignore_ascii_case("codesys"))
    })
}

/// Whether `pou` is marked `{attribute 'sfc.dialect' := 'graph'}` (imported from an S7-GRAPH
/// block): its steps have S7-GRAPH's `U`.
pub fn is_graph(pou: &Pou) -> bool {
    is_dialect(pou, "graph")
}

/// The POU is marked `{attribute 'sfc.dialect' := '<dialect>'}`.
pub fn is_dialect(pou: &Pou, dialect: &str) -> bool {
    pou.attributes.iter().any(|a| {
        a.name.eq_ignore_ascii_case("sfc.dialect") && a.value.as_deref().is_some_and(|v| v.eq_ignore_ascii_case(dialect))
    })
}

/// Type-checks one POU of the file `env` was built from (see [`check_unit`]).
pub fn check_pou(env: &TypeEnv, pou: &Pou) -> Vec<Diagnostic> {
    check_pou_with(env, pou, &mut |_, _| {})
}

fn check_pou_with(env: &TypeEnv, pou: &Pou, prepare: &mut dyn FnMut(&mut Scope<'_>, &Pou)) -> Vec<Diagnostic> {
    check_pou_inner(env, pou, prepare, None)
}

fn check_pou_inner(
    env: &TypeEnv,
    pou: &Pou,
    prepare: &mut dyn FnMut(&mut Scope<'_>, &Pou),
    types: Option<&mut HashMap<Span, Type>>,
) -> Vec<Diagnostic> {
    let mut scope = Scope::for_pou(env, pou);
    if let Body::Sfc(elements) = &pou.body {
        for el in elements {
            // A clash is the model's SFC0206; the first declaration keeps the name.
            let _ = match el {
                SfcElement::Step(s) => scope.add_step(&s.name),
                SfcElement::Action(a) => scope.add_action(&a.name),
                SfcElement::Transition(_) => Ok(()),
            };
        }
    }
    // The actions of a POU that is no chart (a clash is the model's SFC0206 too).
    for a in &pou.actions {
        let _ = scope.add_action(&a.name);
    }
    // The steps of the actions written in SFC share the POU's namespace.
    for a in pou.actions() {
        for el in a.body.sfc().unwrap_or_default() {
            if let SfcElement::Step(s) = el {
                let _ = scope.add_step(&s.name);
            }
        }
    }
    prepare(&mut scope, pou);
    let mut ck = Checker::new(&mut scope);
    ck.set_codesys(is_codesys(pou));
    ck.set_graph(is_graph(pou));
    ck.set_logix(is_dialect(pou, "logix"));
    if types.is_some() {
        ck.keep_types();
    }
    ck.check_declarations();
    match &pou.body {
        Body::St(stmts) => ck.check_stmts(stmts),
        Body::Il(il) => ck.check_il(il),
        Body::Sfc(elements) => check_chart(&mut ck, elements),
    }
    for a in &pou.actions {
        ck.set_element(Some(a.name.text.clone()));
        match &a.body {
            ActionBody::Sfc(elements) => check_chart(&mut ck, elements),
            body => ck.check_action_body(body),
        }
    }
    ck.set_element(None);
    // Methods and property accessors: their variables over the POU's, their name their result.
    let iface = env.interface_of(pou);
    let own = |name: &Ident| -> Option<&MethodSig> {
        iface?.methods.iter().find(|m| m.span == name.span && m.owner == pou.name.text)
    };
    for m in &pou.methods {
        if let Some(sig) = own(&m.name) {
            check_method(&mut ck, &m.name, sig, &m.body);
        }
    }
    for p in &pou.properties {
        let Some(sig) = iface.and_then(|i| i.property(&p.name.text)).filter(|s| s.span == p.name.span) else {
            continue;
        };
        for (acc, s) in [(&p.get, &sig.get), (&p.set, &sig.set)] {
            if let (Some(a), Some(s)) = (acc, s) {
                check_method(&mut ck, &p.name, s, &a.body);
            }
        }
    }
    ck.set_element(None);
    if let Some(t) = types {
        t.extend(ck.take_expr_types());
    }
    let mut diags = ck.finish();
    // A variable of a program that other code reads as `Main.X` is used there.
    let reached = |d: &Diagnostic| {
        pou.kind == PouKind::Program
            && scope.unused_variables().iter().any(|v| v.span == d.span && env.is_reached(&pou.name.text, &v.name))
    };
    // A variable inherited from a base block (`EXTENDS`) is the base's to use.
    let own =
        |d: &Diagnostic| d.span.file != pou.span.file || (pou.span.start <= d.span.start && d.span.end <= pou.span.end);
    if !env.is_extended(&pou.name.text) {
        diags.extend(scope.unused_diagnostics().into_iter().filter(|d| !reached(d) && own(d)));
    }
    diags
}

/// Checks the body of a method or property accessor in its own scope.
fn check_method(ck: &mut Checker<'_, '_>, name: &Ident, sig: &MethodSig, body: &Body) {
    ck.set_element(Some(name.text.clone()));
    let frame = ck.scope.enter_method(sig);
    match body {
        Body::St(stmts) => ck.check_stmts(stmts),
        Body::Il(il) => ck.check_il(il),
        Body::Sfc(_) => {}
    }
    let unused = ck.scope.leave_method(frame);
    ck.diagnostics_mut().extend(unused);
}

/// Checks the elements of a chart (a POU's body, or an action written in SFC).
fn check_chart(ck: &mut Checker<'_, '_>, elements: &[SfcElement]) {
    let names = transition_names(ck, elements);
    let mut transitions = names.into_iter();
    for el in elements {
        match el {
            SfcElement::Step(s) => {
                ck.set_element(Some(s.name.text.clone()));
                for a in &s.associations {
                    ck.check_association(a);
                }
                for c in &s.conditions {
                    ck.check_step_condition(c);
                }
                // A step action is checked as the call that runs it.
                for call in s.step_actions.iter().filter_map(|a| a.call()) {
                    ck.call_stmt(&call);
                }
            }
            SfcElement::Transition(t) => {
                ck.set_element(transitions.next());
                if let Some(p) = &t.priority {
                    ck.check_priority(p);
                }
                ck.check_condition(&t.condition);
            }
            SfcElement::Action(a) => {
                ck.set_element(Some(a.name.text.clone()));
                match &a.body {
                    ActionBody::Sfc(inner) => check_chart(ck, inner),
                    body => ck.check_action_body(body),
                }
            }
        }
    }
    ck.set_element(None);
}

/// The names of the transitions in declaration order: as declared, or `T<n>` (`n` the
/// 1-based position among the TRANSITION declarations), or the first free `T<n>_k` when that
/// name is taken (semantics.md, "Names").
fn transition_names(ck: &Checker<'_, '_>, elements: &[SfcElement]) -> Vec<String> {
    use std::collections::HashSet;
    let declared: HashSet<String> = elements
        .iter()
        .filter_map(|e| match e {
            SfcElement::Transition(t) => t.name.as_ref().map(|n| n.key()),
            _ => None,
        })
        .collect();
    // Names given so far, upper-cased: a set, so a chart of many unnamed transitions stays linear.
    let mut given: HashSet<String> = HashSet::new();
    let free = |name: &str, given: &HashSet<String>| {
        let key = name.to_ascii_uppercase();
        ck.scope().lookup(name).is_none() && !declared.contains(&key) && !given.contains(&key)
    };
    let mut out: Vec<String> = Vec::new();
    let mut n = 0usize;
    for e in elements {
        let SfcElement::Transition(t) = e else { continue };
        n += 1;
        let name = match &t.name {
            Some(id) => id.text.clone(),
            None => {
                let base = format!("T{n}");
                if free(&base, &given) {
                    base
                } else {
                    (1..).map(|k| format!("{base}_{k}")).find(|c| free(c, &given)).unwrap_or(base)
                }
            }
        };
        given.insert(name.to_ascii_uppercase());
        out.push(name);
    }
    out
}
