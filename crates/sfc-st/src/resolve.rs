//! Resolution of declared types (`TypeSpec`) into [`Type`]s, shared by the environment builder
//! (which resolves TYPE declarations lazily) and later declarations.

use crate::suggest::closest;
use crate::types::{Generic, Type, ELEMENTARY_NAMES};
use crate::value::{const_eval, ConstLookup, Value};
use sfc_diagnostics::Diagnostic;
use sfc_syntax::ast::{Expr, ExprKind, Ident, TypeSpec, TypeSpecKind};
use std::collections::HashMap;

/// What a type name refers to.
pub(crate) enum Named {
    Type(Type),
    /// A name that exists but is no type ("a function").
    NotAType(&'static str),
    Unknown,
}

/// Where names in a type specification are looked up.
pub(crate) trait TypeNames {
    /// A declared type or function block type (never an elementary type).
    fn named_type(&mut self, ident: &Ident, diags: &mut Vec<Diagnostic>) -> Named;
    /// A named constant (array bounds, string lengths).
    fn constant(&self, name: &str) -> Option<Value>;
    /// Declared type names, for suggestions.
    fn candidates(&self) -> Vec<String>;
}

struct Consts<'a, N: ?Sized>(&'a N);

impl<N: TypeNames + ?Sized> ConstLookup for Consts<'_, N> {
    fn constant(&self, name: &str) -> Option<Value> {
        self.0.constant(name)
    }
}

/// Longest string length accepted (characters).
const MAX_STRING_LEN: i128 = 65_535;

/// Resolves `spec`; `decl_name` names the type being declared (structures and enumerations
/// keep it). Every problem is reported and yields [`Type::Error`].
pub(crate) fn resolve_spec<N: TypeNames + ?Sized>(
    names: &mut N,
    spec: &TypeSpec,
    decl_name: Option<&str>,
    diags: &mut Vec<Diagnostic>,
) -> Type {
    match &spec.kind {
        TypeSpecKind::Named(id) => named(names, id, diags),
        // `POINTER TO T`, `REFERENCE TO T`, `REF_TO T` (CODESYS, IEC 61131-3 3rd edition).
        TypeSpecKind::Indirect { kind, target } => {
            let t = resolve_spec(names, target, None, diags);
            if t.is_error() {
                return Type::Error;
            }
            // IEC's `REF_TO` is dereferenced with `^`, as CODESYS's pointer; CODESYS's
            // `REFERENCE TO` is an alias.
            match kind {
                sfc_syntax::ast::Indirection::Reference => Type::Reference(Box::new(t)),
                _ => Type::Pointer(Box::new(t)),
            }
        }
        TypeSpecKind::String { wide, length } => {
            let len = match length {
                None => None,
                Some(e) => {
                    let Some(n) = const_int(names, e, "a string length", diags) else { return Type::Error };
                    if !(1..=MAX_STRING_LEN).contains(&n) {
                        diags.push(Diagnostic::new(
                            "SFC0105",
                            e.span,
                            format!("string length {n} is not between 1 and {MAX_STRING_LEN}"),
                        ));
                        return Type::Error;
                    }
                    u32::try_from(n).ok()
                }
            };
            if *wide {
                Type::WString { len }
            } else {
                Type::String { len }
            }
        }
        TypeSpecKind::Array { ranges, element } => {
            let mut dims = Vec::with_capacity(ranges.len());
            let mut ok = true;
            for (lo_e, hi_e) in ranges {
                let lo = const_int(names, lo_e, "an array bound", diags);
                let hi = const_int(names, hi_e, "an array bound", diags);
                match (lo.and_then(|v| fit_i64(v, lo_e, diags)), hi.and_then(|v| fit_i64(v, hi_e, diags))) {
                    (Some(lo), Some(hi)) if lo <= hi => dims.push((lo, hi)),
                    (Some(lo), Some(hi)) => {
                        diags.push(Diagnostic::new(
                            "SFC0105",
                            lo_e.span.to(hi_e.span),
                            format!("array range {lo}..{hi} is reversed: the lower bound exceeds the upper"),
                        ));
                        ok = false;
                    }
                    _ => ok = false,
                }
            }
            let elem = resolve_spec(names, element, None, diags);
            if !ok || elem.is_error() {
                return Type::Error;
            }
            Type::Array { dims, elem: Box::new(elem) }
        }
        TypeSpecKind::Subrange { base, low, high } => {
            let Some(base_ty) = Type::elementary(&base.text) else {
                diags.push(Diagnostic::new(
                    "SFC0105",
                    base.span,
                    format!("a subrange needs an elementary integer base type, not `{}`", base.text),
                ));
                return Type::Error;
            };
            if base_ty.is_real() {
                // IEC defines subranges of integers only; a REAL range (seen in teaching
                // material) is accepted as its base type without a range check.
                return base_ty;
            }
            if !base_ty.is_integer() {
                diags.push(Diagnostic::new(
                    "SFC0105",
                    base.span,
                    format!("a subrange needs an integer base type, not `{base_ty}`"),
                ));
                return Type::Error;
            }
            let lo = const_int(names, low, "a subrange bound", diags);
            let hi = const_int(names, high, "a subrange bound", diags);
            let (Some(lo), Some(hi)) = (lo, hi) else { return Type::Error };
            if let Some((min, max)) = base_ty.int_range() {
                for (v, e) in [(lo, low), (hi, high)] {
                    if v < min || v > max {
                        diags.push(Diagnostic::new(
                            "SFC0315",
                            e.span,
                            format!("subrange bound {v} is out of range for `{base_ty}` ({min}..{max})"),
                        ));
                        return Type::Error;
                    }
                }
            }
            if lo > hi {
                diags.push(Diagnostic::new(
                    "SFC0105",
                    low.span.to(high.span),
                    format!("subrange {lo}..{hi} is empty: the lower bound exceeds the upper"),
                ));
                return Type::Error;
            }
            let (Some(lo), Some(hi)) = (fit_i64(lo, low, diags), fit_i64(hi, high, diags)) else {
                return Type::Error;
            };
            Type::Subrange { base: Box::new(base_ty), lo, hi }
        }
        TypeSpecKind::Enum { base, values } => {
            let base_ty = match base {
                None => None,
                Some(b) => match Type::elementary(&b.text).filter(Type::is_integer) {
                    Some(t) => Some(Box::new(t)),
                    None => {
                        diags.push(Diagnostic::new(
                            "SFC0105",
                            b.span,
                            format!("a typed enumeration needs an integer base type, not `{}`", b.text),
                        ));
                        return Type::Error;
                    }
                },
            };
            let mut out: Vec<(String, i64)> = Vec::with_capacity(values.len());
            let mut seen: HashMap<String, sfc_diagnostics::Span> = HashMap::new();
            let mut next: i64 = 0;
            for (id, value) in values {
                let ordinal = match value {
                    Some(e) => {
                        match const_int(names, e, "an enumerated value", diags).and_then(|v| fit_i64(v, e, diags)) {
                            Some(v) => v,
                            None => next,
                        }
                    }
                    None => next,
                };
                next = ordinal.saturating_add(1);
                if let Some(prev) = seen.get(&id.key()) {
                    diags.push(
                        Diagnostic::new(
                            "SFC0318",
                            id.span,
                            format!("enumerated value `{}` is declared twice", id.text),
                        )
                        .with_label(*prev, "first declared here"),
                    );
                    continue;
                }
                seen.insert(id.key(), id.span);
                out.push((id.text.clone(), ordinal));
            }
            Type::Enum { name: decl_name.map(str::to_string), base: base_ty, values: out }
        }
        TypeSpecKind::Struct(decls) => {
            let mut fields: Vec<(String, Type)> = Vec::new();
            let mut seen: HashMap<String, sfc_diagnostics::Span> = HashMap::new();
            for decl in decls {
                let ty = resolve_spec(names, &decl.ty, None, diags);
                for n in &decl.names {
                    if let Some(prev) = seen.get(&n.key()) {
                        diags.push(
                            Diagnostic::new("SFC0318", n.span, format!("field `{}` is declared twice", n.text))
                                .with_label(*prev, "first declared here"),
                        );
                        continue;
                    }
                    seen.insert(n.key(), n.span);
                    fields.push((n.text.clone(), ty.clone()));
                }
            }
            Type::Struct { name: decl_name.map(str::to_string), fields }
        }
        TypeSpecKind::Error => Type::Error,
    }
}

fn named<N: TypeNames + ?Sized>(names: &mut N, id: &Ident, diags: &mut Vec<Diagnostic>) -> Type {
    if let Some(t) = Type::elementary(&id.text) {
        return t;
    }
    if let Some(g) = Generic::from_name(&id.text) {
        diags.push(Diagnostic::new(
            "SFC0313",
            id.span,
            format!("the generic type `{}` can only be used by standard functions", g.name()),
        ));
        return Type::Error;
    }
    match names.named_type(id, diags) {
        Named::Type(t) => t,
        Named::NotAType(what) => {
            diags.push(Diagnostic::new("SFC0313", id.span, format!("`{}` is {what}, not a type", id.text)));
            Type::Error
        }
        Named::Unknown => {
            let mut d = Diagnostic::new("SFC0313", id.span, format!("unknown type `{}`", id.text));
            let declared = names.candidates();
            let all = declared
                .iter()
                .map(String::as_str)
                .chain(ELEMENTARY_NAMES.iter().copied())
                .chain(crate::stdlib::STD_FUNCTION_BLOCK_NAMES.iter().copied());
            if let Some(s) = closest(&id.text, all) {
                d = d.with_note(format!("did you mean `{s}`?"));
            }
            diags.push(d);
            Type::Error
        }
    }
}

/// Evaluates an integer constant, reporting SFC0105 when the expression is not one.
fn const_int<N: TypeNames + ?Sized>(names: &N, e: &Expr, what: &str, diags: &mut Vec<Diagnostic>) -> Option<i128> {
    if matches!(e.kind, ExprKind::Error) {
        return None;
    }
    match const_eval(e, &Consts(names)) {
        Some(Value::Int(v)) => Some(v),
        _ => {
            diags.push(Diagnostic::new("SFC0105", e.span, format!("{what} must be a constant integer expression")));
            None
        }
    }
}

fn fit_i64(v: i128, e: &Expr, diags: &mut Vec<Diagnostic>) -> Option<i64> {
    match i64::try_from(v) {
        Ok(v) => Some(v),
        Err(_) => {
            diags.push(Diagnostic::new("SFC0315", e.span, format!("{v} does not fit a 64-bit bound")));
            None
        }
    }
}
