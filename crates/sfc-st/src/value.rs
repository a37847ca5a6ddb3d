//! Compile-time constant values and their evaluation (array bounds, string lengths, subrange
//! bounds, CONSTANT variables, CASE labels, FOR bounds).

use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, LiteralKind, UnaryOp};

/// A constant known at compile time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// Any integer (also bit strings); wide enough for every IEC integer type.
    Int(i128),
    /// A real number.
    Real(f64),
    /// A boolean.
    Bool(bool),
    /// Microseconds.
    Time(i64),
}

impl Value {
    /// The integer, if this is one (`BOOL` counts as 0/1 because IEC allows `0`/`1` for it).
    pub fn as_int(self) -> Option<i128> {
        match self {
            Value::Int(i) => Some(i),
            Value::Bool(b) => Some(i128::from(b)),
            _ => None,
        }
    }
}

/// Named constants visible to [`const_eval`]: CONSTANT variables, local or global.
pub trait ConstLookup {
    /// The value of the constant called `name` (case-insensitive), if it is one.
    fn constant(&self, name: &str) -> Option<Value>;
}

/// No named constants at all.
pub struct NoConstants;

impl ConstLookup for NoConstants {
    fn constant(&self, _name: &str) -> Option<Value> {
        None
    }
}

/// Deeper than this the evaluator gives up (the parser already caps nesting at 256).
const MAX_DEPTH: u32 = 512;

/// Evaluates a constant expression: literals, named constants and the operators on them.
/// `None` when the expression is not constant, overflows `i128`, or divides by zero.
pub fn const_eval(expr: &Expr, consts: &dyn ConstLookup) -> Option<Value> {
    eval(expr, consts, 0)
}

fn eval(expr: &Expr, consts: &dyn ConstLookup, depth: u32) -> Option<Value> {
    if depth > MAX_DEPTH {
        return None;
    }
    match &expr.kind {
        ExprKind::Literal(lit) => {
            let prefix = lit.type_prefix.as_deref().unwrap_or("");
            match &lit.kind {
                LiteralKind::Int(v) => {
                    let v = *v;
                    match prefix {
                        "BOOL" => match v {
                            0 => Some(Value::Bool(false)),
                            1 => Some(Value::Bool(true)),
                            _ => None,
                        },
                        "REAL" | "LREAL" => Some(Value::Real(v as f64)),
                        _ => Some(Value::Int(v)),
                    }
                }
                LiteralKind::Real(r) => Some(Value::Real(*r)),
                LiteralKind::Bool(b) => Some(Value::Bool(*b)),
                LiteralKind::Duration(us) => Some(Value::Time(*us)),
                _ => None,
            }
        }
        ExprKind::Name(id) => consts.constant(&id.text),
        ExprKind::Paren(inner) => eval(inner, consts, depth + 1),
        ExprKind::Unary { op, operand } => {
            let v = eval(operand, consts, depth + 1)?;
            match (op, v) {
                (UnaryOp::Plus, v) => Some(v),
                (UnaryOp::Neg, Value::Int(i)) => i.checked_neg().map(Value::Int),
                (UnaryOp::Neg, Value::Real(r)) => Some(Value::Real(-r)),
                (UnaryOp::Neg, Value::Time(t)) => t.checked_neg().map(Value::Time),
                (UnaryOp::Not, Value::Bool(b)) => Some(Value::Bool(!b)),
                _ => None,
            }
        }
        ExprKind::Binary { op, lhs, rhs } => {
            let a = eval(lhs, consts, depth + 1)?;
            let b = eval(rhs, consts, depth + 1)?;
            binary(*op, a, b)
        }
        _ => None,
    }
}

fn binary(op: BinaryOp, a: Value, b: Value) -> Option<Value> {
    use BinaryOp as B;
    use Value as V;
    match (a, b) {
        (V::Int(x), V::Int(y)) => match op {
            B::Add => x.checked_add(y).map(V::Int),
            B::Sub => x.checked_sub(y).map(V::Int),
            B::Mul => x.checked_mul(y).map(V::Int),
            // Integer division truncates toward zero, as in the simulator.
            B::Div => x.checked_div(y).map(V::Int),
            B::Mod => x.checked_rem(y).map(V::Int),
            B::Pow => Some(V::Real((x as f64).powf(y as f64))),
            B::And | B::AndThen => Some(V::Int(x & y)),
            B::Or | B::OrElse => Some(V::Int(x | y)),
            B::Xor => Some(V::Int(x ^ y)),
            _ => compare(op, x.cmp(&y)),
        },
        (V::Real(_), V::Int(_)) | (V::Int(_), V::Real(_)) | (V::Real(_), V::Real(_)) => {
            let x = as_f64(a)?;
            let y = as_f64(b)?;
            match op {
                B::Add => Some(V::Real(x + y)),
                B::Sub => Some(V::Real(x - y)),
                B::Mul => Some(V::Real(x * y)),
                B::Div if y != 0.0 => Some(V::Real(x / y)),
                B::Pow => Some(V::Real(x.powf(y))),
                _ => compare(op, x.partial_cmp(&y)?),
            }
        }
        (V::Bool(x), V::Bool(y)) => match op {
            B::And | B::AndThen => Some(V::Bool(x & y)),
            B::Or | B::OrElse => Some(V::Bool(x | y)),
            B::Xor => Some(V::Bool(x ^ y)),
            _ => compare(op, x.cmp(&y)),
        },
        (V::Time(x), V::Time(y)) => match op {
            B::Add => x.checked_add(y).map(V::Time),
            B::Sub => x.checked_sub(y).map(V::Time),
            _ => compare(op, x.cmp(&y)),
        },
        (V::Time(x), V::Int(y)) => {
            let y = i64::try_from(y).ok()?;
            match op {
                B::Mul => x.checked_mul(y).map(V::Time),
                B::Div => x.checked_div(y).map(V::Time),
                _ => None,
            }
        }
        _ => None,
    }
}

fn as_f64(v: Value) -> Option<f64> {
    match v {
        Value::Int(i) => Some(i as f64),
        Value::Real(r) => Some(r),
        _ => None,
    }
}

fn compare(op: BinaryOp, ord: std::cmp::Ordering) -> Option<Value> {
    use std::cmp::Ordering::*;
    let r = match op {
        BinaryOp::Eq => ord == Equal,
        BinaryOp::Ne => ord != Equal,
        BinaryOp::Lt => ord == Less,
        BinaryOp::Le => ord != Greater,
        BinaryOp::Gt => ord == Greater,
        BinaryOp::Ge => ord != Less,
        _ => return None,
    };
    Some(Value::Bool(r))
}
