//! Conditions of scenario files: an ST BOOL expression over the simulated POU's variables, step
//! flags `S.X`, step times `S.T` and action flags `A.Q`, as in
//! `always = "NOT (MotorFwd AND MotorRev)"` or `after = "DoorCmd"`.
//!
//! The expression is parsed with the IEC parser and bound to the simulation once (every name
//! must exist, the result must be BOOL); evaluating it reads the values after a scan. It is a
//! small interpreter over [`Value`]s, not compiled code: scenarios evaluate a few conditions per
//! scan, and this keeps them independent of the engine's code generator.

use crate::{format_time, Simulation, Value};
use sfc_st::Type;
use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, LiteralKind, UnaryOp};
use std::sync::Arc;

/// A bound condition.
#[derive(Debug, Clone, PartialEq)]
pub struct Condition {
    /// The expression as written.
    pub text: String,
    expr: Node,
}

#[derive(Debug, Clone, PartialEq)]
enum Node {
    /// A variable, `Step.X`, `Step.T`, `Action.Q`, … (the key for [`Simulation::get`]).
    Read(String),
    Const(Value),
    Not(Box<Node>),
    Neg(Box<Node>),
    Binary(BinaryOp, Box<Node>, Box<Node>),
}

/// What a node is known to produce, for binding errors.
#[derive(Debug, Clone, PartialEq)]
enum Kind {
    Bool,
    Other(Option<Type>),
    /// A bare name that is no variable (an enumeration value, or a mistake).
    Name,
}

impl Condition {
    /// Parses `text` and binds it to the simulation; the error says what is wrong, in words.
    pub fn parse(text: &str, sim: &Simulation) -> Result<Condition, String> {
        let (expr, diags) = sfc_syntax::parse_expression(0, text);
        if let Some(d) = diags.iter().find(|d| d.is_error()) {
            return Err(format!("`{text}` is not an ST expression: {}", d.message));
        }
        let binder = Binder { sim, text };
        let (node, kind) = binder.bind(&expr)?;
        if kind != Kind::Bool {
            return Err(format!("`{text}` is not a BOOL expression"));
        }
        Ok(Condition { text: text.trim().to_string(), expr: node })
    }

    /// The value after the last scan; an error when it cannot be computed (division by zero).
    pub fn eval(&self, sim: &Simulation) -> Result<bool, String> {
        match eval(&self.expr, sim)? {
            Value::Bool(b) => Ok(b),
            other => Err(format!("`{}` gave {other:?}, not a BOOL", self.text)),
        }
    }

    /// The names it reads with their values now, for failure messages: `Fwd = TRUE, Rev = TRUE`.
    pub fn operands(&self, sim: &Simulation) -> String {
        let mut names = Vec::new();
        reads(&self.expr, &mut names);
        names
            .iter()
            .map(|n| {
                let v = sim.get(n).map_or_else(|| "?".to_string(), |v| show(&v));
                format!("{n} = {v}")
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

fn reads<'a>(n: &'a Node, out: &mut Vec<&'a str>) {
    match n {
        Node::Read(k) => {
            if !out.contains(&k.as_str()) {
                out.push(k);
            }
        }
        Node::Const(_) => {}
        Node::Not(a) | Node::Neg(a) => reads(a, out),
        Node::Binary(_, a, b) => {
            reads(a, out);
            reads(b, out);
        }
    }
}

/// A value as the failure messages show it (IEC spelling).
fn show(v: &Value) -> String {
    match v {
        Value::Bool(b) => if *b { "TRUE" } else { "FALSE" }.to_string(),
        Value::Int(i) => i.to_string(),
        Value::Real(r) => format!("{r}"),
        Value::Time(t) => format_time(*t),
        Value::Str(s) => format!("'{s}'"),
    }
}

struct Binder<'a> {
    sim: &'a Simulation,
    text: &'a str,
}

impl Binder<'_> {
    /// The key [`Simulation::get`] reads for a name, member or constant-index path.
    fn path(&self, e: &Expr) -> Option<String> {
        match &e.kind {
            ExprKind::Name(id) => Some(id.text.clone()),
            ExprKind::Member { base, member } => Some(format!("{}.{}", self.path(base)?, member.text)),
            ExprKind::Index { base, indices } => {
                let mut idx = Vec::new();
                for i in indices {
                    match &i.kind {
                        ExprKind::Literal(l) => match l.kind {
                            LiteralKind::Int(v) => idx.push(v.to_string()),
                            _ => return None,
                        },
                        ExprKind::Unary { op: UnaryOp::Neg, operand } => match &operand.kind {
                            ExprKind::Literal(l) => match l.kind {
                                LiteralKind::Int(v) => idx.push(format!("-{v}")),
                                _ => return None,
                            },
                            _ => return None,
                        },
                        _ => return None,
                    }
                }
                Some(format!("{}[{}]", self.path(base)?, idx.join(",")))
            }
            ExprKind::Paren(inner) => self.path(inner),
            _ => None,
        }
    }

    fn read(&self, e: &Expr) -> Result<(Node, Kind), String> {
        let Some(path) = self.path(e) else {
            return Err(format!(
                "`{}`: a scenario condition reads variables, `Step.X`, `Step.T` and `Action.Q` (array indices must be integer literals)",
                self.text
            ));
        };
        match self.sim.type_of(&path) {
            Some(ty) => {
                let kind = if ty.base().is_bool() { Kind::Bool } else { Kind::Other(Some(ty)) };
                Ok((Node::Read(path), kind))
            }
            None => {
                let mut names: Vec<String> = self.sim.trace_vars().into_iter().map(|(n, _)| n).collect();
                for s in self.sim.step_names() {
                    names.push(format!("{s}.X"));
                    names.push(format!("{s}.T"));
                }
                let hint = match sfc_st::closest(&path, names.iter().map(String::as_str)) {
                    Some(c) => format!("; did you mean `{c}`?"),
                    None => String::new(),
                };
                Err(format!("unknown variable `{path}` in `{}` (POU {}){hint}", self.text, self.sim.pou_name()))
            }
        }
    }

    fn bind(&self, e: &Expr) -> Result<(Node, Kind), String> {
        match &e.kind {
            ExprKind::Paren(inner) => self.bind(inner),
            ExprKind::Literal(l) => {
                let (v, kind) = match &l.kind {
                    LiteralKind::Bool(b) => (Value::Bool(*b), Kind::Bool),
                    LiteralKind::Int(i) => {
                        (Value::Int(i64::try_from(*i).map_err(|_| format!("{i} is too large"))?), Kind::Other(None))
                    }
                    LiteralKind::Real(r) => (Value::Real(*r), Kind::Other(None)),
                    LiteralKind::String { value, .. } => (Value::Str(Arc::from(value.as_str())), Kind::Other(None)),
                    LiteralKind::Duration(t) => (Value::Time(*t), Kind::Other(Some(Type::Time))),
                    LiteralKind::Date(d) => (Value::Int(d.saturating_mul(86_400_000_000)), Kind::Other(None)),
                    LiteralKind::TimeOfDay(t) | LiteralKind::DateAndTime(t) => (Value::Int(*t), Kind::Other(None)),
                    LiteralKind::Enum(id) => {
                        return Err(format!(
                            "`{}`: compare an enumerated variable with its value by name (`Mode = {}`)",
                            self.text, id.text
                        ))
                    }
                };
                Ok((Node::Const(v), kind))
            }
            ExprKind::Unary { op, operand } => {
                let (n, k) = self.bind(operand)?;
                match op {
                    UnaryOp::Not => Ok((Node::Not(Box::new(n)), k)),
                    UnaryOp::Neg => Ok((Node::Neg(Box::new(n)), k)),
                    UnaryOp::Plus => Ok((n, k)),
                }
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let comparison = matches!(
                    op,
                    BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge
                );
                let (mut a, ka) = if comparison { self.bind_operand(lhs)? } else { self.bind(lhs)? };
                let (mut b, kb) = if comparison { self.bind_operand(rhs)? } else { self.bind(rhs)? };
                // `Mode = Auto`: a bare name on one side is a value of the other side's enumeration.
                let enum_of = |k: &Kind| match k {
                    Kind::Other(Some(ty)) if ty.is_enum() => Some(ty.clone()),
                    _ => None,
                };
                if let Some(name) = enum_name(lhs, &ka) {
                    match enum_of(&kb) {
                        Some(ty) => a = Node::Const(Value::Int(self.enum_value(&ty, &name)?)),
                        None => return self.read(lhs),
                    }
                }
                if let Some(name) = enum_name(rhs, &kb) {
                    match enum_of(&ka) {
                        Some(ty) => b = Node::Const(Value::Int(self.enum_value(&ty, &name)?)),
                        None => return self.read(rhs),
                    }
                }
                let kind = match op {
                    BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge => {
                        Kind::Bool
                    }
                    BinaryOp::And | BinaryOp::AndThen | BinaryOp::Or | BinaryOp::OrElse | BinaryOp::Xor
                        if ka == Kind::Bool && kb == Kind::Bool =>
                    {
                        Kind::Bool
                    }
                    _ => Kind::Other(None),
                };
                Ok((Node::Binary(*op, Box::new(a), Box::new(b)), kind))
            }
            ExprKind::Name(_) | ExprKind::Member { .. } | ExprKind::Index { .. } => self.read(e),
            ExprKind::Call { callee: name, .. } | ExprKind::MemberCall { member: name, .. } => {
                Err(format!("`{}`: calls (`{}(…)`) are not allowed in a scenario condition", self.text, name.text))
            }
            ExprKind::Address(_) => {
                Err(format!("`{}`: name the variable declared at the address instead of the address", self.text))
            }
            ExprKind::Deref(_) => Err(format!("`{}` dereferences a pointer, which a condition cannot", self.text)),
            ExprKind::Error => Err(format!("`{}` is not an ST expression", self.text)),
        }
    }

    /// Like `bind`, but a bare name that is no variable is kept aside (marked by `Kind::Name`)
    /// for the enumeration of the other side of a comparison.
    fn bind_operand(&self, e: &Expr) -> Result<(Node, Kind), String> {
        if let ExprKind::Name(id) = &e.kind {
            if self.sim.type_of(&id.text).is_none() {
                return Ok((Node::Const(Value::Int(0)), Kind::Name));
            }
        }
        self.bind(e)
    }

    fn enum_value(&self, ty: &Type, name: &str) -> Result<i64, String> {
        ty.enum_value(name).ok_or_else(|| match ty {
            Type::Enum { values, .. } => {
                let names: Vec<&str> = values.iter().map(|(n, _)| n.as_str()).collect();
                format!("`{name}` is not a value of {ty} in `{}` (values: {})", self.text, names.join(", "))
            }
            _ => format!("unknown variable `{name}` in `{}` (POU {})", self.text, self.sim.pou_name()),
        })
    }
}

/// The bare name of an operand that `bind_operand` kept aside (no variable of that name).
fn enum_name(e: &Expr, kind: &Kind) -> Option<String> {
    match (&e.kind, kind) {
        (ExprKind::Name(id), Kind::Name) => Some(id.text.clone()),
        _ => None,
    }
}

fn num(v: &Value) -> Option<f64> {
    match v {
        Value::Int(i) | Value::Time(i) => Some(*i as f64),
        Value::Real(r) => Some(*r),
        Value::Bool(b) => Some(f64::from(u8::from(*b))),
        Value::Str(_) => None,
    }
}

fn eval(n: &Node, sim: &Simulation) -> Result<Value, String> {
    match n {
        Node::Read(k) => sim.get(k).ok_or_else(|| format!("`{k}` cannot be read")),
        Node::Const(v) => Ok(v.clone()),
        Node::Not(a) => match eval(a, sim)? {
            Value::Bool(b) => Ok(Value::Bool(!b)),
            Value::Int(i) => Ok(Value::Int(!i)),
            v => Err(format!("NOT of {}", show(&v))),
        },
        Node::Neg(a) => match eval(a, sim)? {
            Value::Int(i) => Ok(Value::Int(i.wrapping_neg())),
            Value::Time(t) => Ok(Value::Time(t.wrapping_neg())),
            Value::Real(r) => Ok(Value::Real(-r)),
            v => Err(format!("- of {}", show(&v))),
        },
        Node::Binary(op, a, b) => {
            let (x, y) = (eval(a, sim)?, eval(b, sim)?);
            binary(*op, &x, &y)
        }
    }
}

fn binary(op: BinaryOp, x: &Value, y: &Value) -> Result<Value, String> {
    use std::cmp::Ordering;
    let order = || -> Option<Ordering> {
        match (x, y) {
            (Value::Str(a), Value::Str(b)) => Some(a.cmp(b)),
            (Value::Int(a) | Value::Time(a), Value::Int(b) | Value::Time(b)) => Some(a.cmp(b)),
            (Value::Bool(a), Value::Bool(b)) => Some(a.cmp(b)),
            _ => num(x)?.partial_cmp(&num(y)?),
        }
    };
    let cmp = |f: fn(Ordering) -> bool| -> Result<Value, String> {
        order().map(|o| Value::Bool(f(o))).ok_or_else(|| format!("cannot compare {} with {}", show(x), show(y)))
    };
    let ints = |f: fn(i64, i64) -> Option<i64>| -> Result<Value, String> {
        match (x, y) {
            (Value::Int(a), Value::Int(b)) => f(*a, *b).map(Value::Int).ok_or_else(|| "division by zero".to_string()),
            (Value::Time(a) | Value::Int(a), Value::Time(b) | Value::Int(b)) => {
                f(*a, *b).map(Value::Time).ok_or_else(|| "division by zero".to_string())
            }
            _ => match (num(x), num(y)) {
                (Some(a), Some(b)) => {
                    let r = match op {
                        BinaryOp::Add => a + b,
                        BinaryOp::Sub => a - b,
                        BinaryOp::Mul => a * b,
                        BinaryOp::Div => a / b,
                        BinaryOp::Pow => a.powf(b),
                        _ => a % b,
                    };
                    Ok(Value::Real(r))
                }
                _ => Err(format!("cannot compute with {} and {}", show(x), show(y))),
            },
        }
    };
    let logic = |f: fn(bool, bool) -> bool, g: fn(i64, i64) -> i64| -> Result<Value, String> {
        match (x, y) {
            (Value::Bool(a), Value::Bool(b)) => Ok(Value::Bool(f(*a, *b))),
            (Value::Int(a), Value::Int(b)) => Ok(Value::Int(g(*a, *b))),
            _ => Err(format!("cannot combine {} and {}", show(x), show(y))),
        }
    };
    match op {
        BinaryOp::Eq => cmp(|o| o == Ordering::Equal),
        BinaryOp::Ne => cmp(|o| o != Ordering::Equal),
        BinaryOp::Lt => cmp(|o| o == Ordering::Less),
        BinaryOp::Gt => cmp(|o| o == Ordering::Greater),
        BinaryOp::Le => cmp(|o| o != Ordering::Greater),
        BinaryOp::Ge => cmp(|o| o != Ordering::Less),
        BinaryOp::And | BinaryOp::AndThen => logic(|a, b| a && b, |a, b| a & b),
        BinaryOp::Or | BinaryOp::OrElse => logic(|a, b| a || b, |a, b| a | b),
        BinaryOp::Xor => logic(|a, b| a ^ b, |a, b| a ^ b),
        BinaryOp::Add => ints(|a, b| Some(a.wrapping_add(b))),
        BinaryOp::Sub => ints(|a, b| Some(a.wrapping_sub(b))),
        BinaryOp::Mul => ints(|a, b| Some(a.wrapping_mul(b))),
        BinaryOp::Div => ints(|a, b| if b == 0 { None } else { Some(a.wrapping_div(b)) }),
        BinaryOp::Mod => ints(|a, b| if b == 0 { None } else { Some(a.wrapping_rem(b)) }),
        BinaryOp::Pow => ints(|a, b| u32::try_from(b).ok().map(|e| a.wrapping_pow(e))),
    }
}
