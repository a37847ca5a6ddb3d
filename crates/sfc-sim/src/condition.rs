//! ST conditions in scenario files (`expect = "Door.X AND NOT Alarm"`, `always = "…"`): a BOOL
//! expression over the simulated POU's variables, step flags and times (`S.X`, `S.T`) and
//! action flags (`A.Q`), bound to the simulation once and evaluated after a scan.
//!
//! Integer arithmetic follows IEC: the result has the common type of its operands and wraps in
//! that width (untyped constants take the other operand's type); TIME values are microseconds.

use crate::{Simulation, Value};
use sfc_st::Type;
use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, LiteralKind, UnaryOp};

/// A condition bound to a simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct Condition {
    /// The text as written.
    pub text: String,
    root: Node,
}

/// A problem in a condition: the byte offset in its text and a message.
#[derive(Debug, Clone, PartialEq)]
pub struct ConditionError {
    pub offset: usize,
    pub message: String,
}

#[derive(Debug, Clone, PartialEq)]
enum Node {
    Bool(bool),
    Int(i128, Type),
    /// An integer constant without a type.
    Untyped(i128),
    Real(f64),
    Str(String),
    Read(String, Type),
    Not(Box<Node>),
    Neg(Box<Node>, Type),
    Bin(BinaryOp, Box<Node>, Box<Node>, Type),
}

#[derive(Debug, Clone, PartialEq)]
enum V {
    B(bool),
    I(i128),
    R(f64),
    S(String),
}

fn err<T>(offset: usize, message: impl Into<String>) -> Result<T, ConditionError> {
    Err(ConditionError { offset, message: message.into() })
}

/// Wraps an integer into the width of an integer-like type.
fn wrap(v: i128, ty: &Type) -> i128 {
    let ty = ty.base();
    let (bits, signed) = match ty {
        Type::SInt => (8, true),
        Type::Int => (16, true),
        Type::DInt => (32, true),
        Type::USInt | Type::Byte => (8, false),
        Type::UInt | Type::Word => (16, false),
        Type::UDInt | Type::DWord => (32, false),
        Type::ULInt | Type::LWord => (64, false),
        _ => (64, true),
    };
    let m = v & ((1i128 << bits) - 1);
    if signed && m >= 1i128 << (bits - 1) {
        m - (1i128 << bits)
    } else {
        m
    }
}

fn is_int_like(t: &Type) -> bool {
    t.is_integer() || (t.is_bit() && !t.is_bool()) || t.is_duration() || t.is_date() || t.is_enum()
}

impl Condition {
    /// Parses and binds `text` to the variables of `sim`.
    pub fn new(text: &str, sim: &Simulation) -> Result<Condition, ConditionError> {
        let (expr, diags) = sfc_syntax::parse_expression(0, text);
        if let Some(d) = diags.iter().find(|d| d.is_error()) {
            return err(d.span.start as usize, d.message.clone());
        }
        if text.trim().is_empty() {
            return err(0, "the condition is empty");
        }
        let root = bind(&expr, sim, None)?;
        match node_type(&root) {
            Some(Type::Bool) => Ok(Condition { text: text.to_string(), root }),
            other => err(
                0,
                format!(
                    "a condition must be BOOL, found {}",
                    other.map_or_else(|| "an untyped number".to_string(), |t| format!("`{t}`"))
                ),
            ),
        }
    }

    /// The value after the last scan of `sim`.
    pub fn eval(&self, sim: &Simulation) -> Result<bool, String> {
        match eval(&self.root, sim)? {
            V::B(b) => Ok(b),
            _ => Err("the condition is not BOOL".into()),
        }
    }
}

fn node_type(n: &Node) -> Option<Type> {
    match n {
        Node::Bool(_) | Node::Not(_) => Some(Type::Bool),
        Node::Int(_, t) | Node::Read(_, t) | Node::Neg(_, t) => Some(t.clone()),
        Node::Untyped(_) => None,
        Node::Real(_) => Some(Type::LReal),
        Node::Str(_) => Some(Type::String { len: None }),
        Node::Bin(op, a, _, t) => match op {
            BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge => Some(Type::Bool),
            BinaryOp::AndThen | BinaryOp::OrElse => Some(Type::Bool),
            _ => {
                let _ = a;
                Some(t.clone())
            }
        },
    }
}

/// The dotted path of a place expression (`Rev.Busy`, `S2.X`, `Cells[2]`).
fn path_of(e: &Expr) -> Option<String> {
    match &e.kind {
        ExprKind::Name(id) => Some(id.text.clone()),
        ExprKind::Member { base, member } => Some(format!("{}.{}", path_of(base)?, member.text)),
        ExprKind::Index { base, indices } => {
            let mut ix = Vec::new();
            for i in indices {
                match sfc_st::const_eval(i, &sfc_st::NoConstants)? {
                    sfc_st::Value::Int(v) => ix.push(v.to_string()),
                    _ => return None,
                }
            }
            Some(format!("{}[{}]", path_of(base)?, ix.join(",")))
        }
        ExprKind::Paren(inner) => path_of(inner),
        _ => None,
    }
}

fn bind(e: &Expr, sim: &Simulation, expected: Option<&Type>) -> Result<Node, ConditionError> {
    let at = e.span.start as usize;
    match &e.kind {
        ExprKind::Paren(inner) => bind(inner, sim, expected),
        ExprKind::Literal(lit) => Ok(match &lit.kind {
            LiteralKind::Bool(b) => Node::Bool(*b),
            LiteralKind::Int(v) => match lit.type_prefix.as_deref().and_then(Type::elementary) {
                Some(t) if t.is_bool() => Node::Bool(*v != 0),
                Some(t) => Node::Int(*v, t),
                None => Node::Untyped(*v),
            },
            LiteralKind::Real(r) => Node::Real(*r),
            LiteralKind::Duration(us) => Node::Int(*us as i128, Type::Time),
            LiteralKind::String { value, .. } => Node::Str(value.clone()),
            LiteralKind::Date(d) => Node::Int(*d as i128 * 86_400_000_000, Type::Date),
            LiteralKind::TimeOfDay(us) => Node::Int(*us as i128, Type::TimeOfDay),
            LiteralKind::DateAndTime(us) => Node::Int(*us as i128, Type::DateAndTime),
            LiteralKind::Enum(v) => match expected.and_then(|t| t.enum_value(&v.text).map(|n| (t.clone(), n))) {
                Some((t, n)) => Node::Int(n as i128, t),
                None => return err(at, format!("unknown enumerated value `{}`", lit.text)),
            },
        }),
        ExprKind::Name(id) => {
            if let Some(t) = sim.type_of(&id.text) {
                return Ok(Node::Read(id.text.clone(), t));
            }
            if let Some(n) = expected.and_then(|t| t.enum_value(&id.text)) {
                return Ok(Node::Int(n as i128, expected.cloned().unwrap_or(Type::DInt)));
            }
            if sim.step_names().iter().any(|s| s.eq_ignore_ascii_case(&id.text)) {
                return err(at, format!("`{}` is a step; read `{0}.X` or `{0}.T`", id.text));
            }
            let mut names: Vec<String> = sim.trace_vars().into_iter().map(|(n, _)| n).collect();
            for s in sim.step_names() {
                names.push(format!("{s}.X"));
            }
            let hint = match sfc_st::closest(&id.text, names.iter().map(String::as_str)) {
                Some(c) => format!("; did you mean `{c}`?"),
                None => String::new(),
            };
            err(at, format!("unknown name `{}` in POU {}{hint}", id.text, sim.pou_name()))
        }
        ExprKind::Member { .. } | ExprKind::Index { .. } => {
            let Some(p) = path_of(e) else { return err(at, "not a variable") };
            match sim.type_of(&p) {
                Some(t) => Ok(Node::Read(p, t)),
                None => err(at, format!("unknown name `{p}` in POU {}", sim.pou_name())),
            }
        }
        ExprKind::Unary { op, operand } => {
            let v = bind(operand, sim, expected)?;
            match op {
                UnaryOp::Plus => Ok(v),
                UnaryOp::Not => match node_type(&v) {
                    Some(t) if t.is_bool() || t.is_bit() => Ok(Node::Not(Box::new(v))),
                    _ => err(at, "NOT needs a BOOL or a bit string"),
                },
                UnaryOp::Neg => match (&v, node_type(&v)) {
                    (Node::Untyped(c), _) => Ok(Node::Untyped(-c)),
                    (Node::Real(r), _) => Ok(Node::Real(-r)),
                    (_, Some(t)) if is_int_like(&t) || t.is_real() => Ok(Node::Neg(Box::new(v), t)),
                    _ => err(at, "minus needs a number"),
                },
            }
        }
        ExprKind::Binary { op, lhs, rhs } => {
            let l = bind(lhs, sim, None)?;
            let lt = node_type(&l);
            let r = bind(rhs, sim, lt.as_ref().or(expected))?;
            let rt = node_type(&r);
            let l = if lt.is_none() { bind(lhs, sim, rt.as_ref())? } else { l };
            let lt = node_type(&l);
            let t = match (&lt, &rt) {
                (Some(a), Some(b)) => match Type::common(a, b) {
                    Some(t) => t,
                    None if is_int_like(a) && is_int_like(b) => a.clone(),
                    None if a.is_real() || b.is_real() => Type::LReal,
                    None => return err(at, format!("`{}` cannot combine `{a}` and `{b}`", op.symbol())),
                },
                (Some(a), None) | (None, Some(a)) => a.base().clone(),
                (None, None) => Type::LInt,
            };
            match op {
                BinaryOp::And | BinaryOp::Or | BinaryOp::Xor | BinaryOp::AndThen | BinaryOp::OrElse => {
                    if !(t.is_bool() || t.is_bit()) {
                        return err(at, format!("`{}` needs BOOL operands, found `{t}`", op.symbol()));
                    }
                }
                BinaryOp::Pow => return err(at, "`**` is not supported in conditions"),
                _ => {}
            }
            Ok(Node::Bin(*op, Box::new(l), Box::new(r), t))
        }
        ExprKind::Call { callee, .. } => err(at, format!("calls (`{}`) are not supported in conditions", callee.text)),
        ExprKind::Address(a) => match sim.type_of(&a.text) {
            Some(t) => Ok(Node::Read(a.text.clone(), t)),
            None => err(at, format!("unknown address `{}`", a.text)),
        },
        ExprKind::Error => err(at, "syntax error"),
    }
}

fn value_of(v: Value) -> V {
    match v {
        Value::Bool(b) => V::B(b),
        Value::Int(i) | Value::Time(i) => V::I(i as i128),
        Value::Real(r) => V::R(r),
        Value::Str(s) => V::S(s.to_string()),
    }
}

fn eval(n: &Node, sim: &Simulation) -> Result<V, String> {
    Ok(match n {
        Node::Bool(b) => V::B(*b),
        Node::Int(v, _) | Node::Untyped(v) => V::I(*v),
        Node::Real(r) => V::R(*r),
        Node::Str(s) => V::S(s.clone()),
        Node::Read(p, t) => {
            let v = sim.get(p).ok_or_else(|| format!("`{p}` cannot be read"))?;
            match (value_of(v), t.base()) {
                (V::I(i), Type::ULInt | Type::LWord) => V::I(i & ((1i128 << 64) - 1)),
                (v, _) => v,
            }
        }
        Node::Not(a) => match eval(a, sim)? {
            V::B(b) => V::B(!b),
            V::I(i) => V::I(!i),
            _ => return Err("NOT of a non-BOOL value".into()),
        },
        Node::Neg(a, t) => match eval(a, sim)? {
            V::I(i) => V::I(wrap(-i, t)),
            V::R(r) => V::R(-r),
            _ => return Err("minus of a non-number".into()),
        },
        Node::Bin(op, a, b, t) => {
            let x = eval(a, sim)?;
            let y = eval(b, sim)?;
            binary(*op, x, y, t)?
        }
    })
}

fn num(v: &V) -> Option<f64> {
    match v {
        V::I(i) => Some(*i as f64),
        V::R(r) => Some(*r),
        _ => None,
    }
}

fn binary(op: BinaryOp, x: V, y: V, t: &Type) -> Result<V, String> {
    use BinaryOp as B;
    let cmp = |o: std::cmp::Ordering| -> V {
        V::B(match op {
            B::Eq => o.is_eq(),
            B::Ne => o.is_ne(),
            B::Lt => o.is_lt(),
            B::Gt => o.is_gt(),
            B::Le => o.is_le(),
            _ => o.is_ge(),
        })
    };
    Ok(match (op, x, y) {
        (B::And | B::AndThen, V::B(a), V::B(b)) => V::B(a && b),
        (B::Or | B::OrElse, V::B(a), V::B(b)) => V::B(a || b),
        (B::Xor, V::B(a), V::B(b)) => V::B(a ^ b),
        (B::And, V::I(a), V::I(b)) => V::I(wrap(a & b, t)),
        (B::Or, V::I(a), V::I(b)) => V::I(wrap(a | b, t)),
        (B::Xor, V::I(a), V::I(b)) => V::I(wrap(a ^ b, t)),
        (B::Eq | B::Ne | B::Lt | B::Gt | B::Le | B::Ge, V::B(a), V::B(b)) => cmp(a.cmp(&b)),
        (B::Eq | B::Ne | B::Lt | B::Gt | B::Le | B::Ge, V::I(a), V::I(b)) => cmp(wrap(a, t).cmp(&wrap(b, t))),
        (B::Eq | B::Ne | B::Lt | B::Gt | B::Le | B::Ge, V::S(a), V::S(b)) => cmp(a.cmp(&b)),
        (B::Eq | B::Ne | B::Lt | B::Gt | B::Le | B::Ge, a, b) => match (num(&a), num(&b)) {
            (Some(p), Some(q)) => cmp(p.partial_cmp(&q).unwrap_or(std::cmp::Ordering::Equal)),
            _ => return Err("comparing values of different kinds".into()),
        },
        (B::Add, V::I(a), V::I(b)) => V::I(wrap(a + b, t)),
        (B::Sub, V::I(a), V::I(b)) => V::I(wrap(a - b, t)),
        (B::Mul, V::I(a), V::I(b)) => V::I(wrap(a.wrapping_mul(b), t)),
        (B::Div, V::I(_), V::I(0)) | (B::Mod, V::I(_), V::I(0)) => return Err("division by zero".into()),
        (B::Div, V::I(a), V::I(b)) => V::I(wrap(a / b, t)),
        (B::Mod, V::I(a), V::I(b)) => V::I(wrap(a % b, t)),
        (op, a, b) => match (num(&a), num(&b)) {
            (Some(p), Some(q)) => V::R(match op {
                B::Add => p + q,
                B::Sub => p - q,
                B::Mul => p * q,
                B::Div => p / q,
                _ => return Err(format!("`{}` on numbers", op.symbol())),
            }),
            _ => return Err(format!("`{}` on these values", op.symbol())),
        },
    })
}
