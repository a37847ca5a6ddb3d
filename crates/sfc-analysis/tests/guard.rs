//! Guard analysis: the fixtures under `tests/guard/` list their expected findings inline, and
//! every witness is checked by evaluating the guards on it with an evaluator written here,
//! independently of the analysis.
//!
//! Directives (in `(*! … *)` comments, attributed to the POU that contains them):
//! * `nonexclusive T1 T2` / `nonexclusive T1 T2 explicit` (explicit priority),
//! * `incomplete S1`, `always_true T5`, `always_false T6`,
//! * `none`: the POU has no finding,
//! * `apart A B C`: these steps can never be active together (the hand-written concurrency
//!   relation of the fixture; all other steps can be).

use sfc_analysis::guard::{analyze_guards, GuardContext, GuardFinding, GuardFindingKind};
use sfc_model::{check_source, Chart, CheckOptions, Checked};
use sfc_syntax::ast::{
    BinaryOp, Condition, Expr, ExprKind, IlInstruction, Item, LiteralKind, SourceUnit, UnaryOp, UNARY_PRECEDENCE,
};
use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn st_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else { return out };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(st_files(&p));
        } else if p.extension().is_some_and(|x| x == "st") {
            out.push(p);
        }
    }
    out.sort();
    out
}

fn check(name: &str, text: &str) -> Checked {
    check_source(0, name, text, &CheckOptions { keep_types: true, ..Default::default() })
}

// ---------------------------------------------------------------------------------------------
// An evaluator of guards on a witness, independent of the analysis.

#[derive(Debug, Clone, PartialEq)]
enum V {
    Bool(bool),
    Int(i128),
    Real(f64),
    Time(i64),
    Str(String),
}

/// Where leaf values come from: the witness, or random values for sampling.
trait Env {
    /// The value of a leaf printed as `key`; `like` is the constant it is compared with.
    fn get(&mut self, key: &str, like: Option<&V>) -> Option<V>;
}

struct Witness<'a>(&'a [(String, serde_json::Value)]);

impl Env for Witness<'_> {
    fn get(&mut self, key: &str, _like: Option<&V>) -> Option<V> {
        let (_, v) = self.0.iter().find(|(k, _)| k.eq_ignore_ascii_case(key))?;
        Some(match v {
            serde_json::Value::Bool(b) => V::Bool(*b),
            serde_json::Value::Number(n) => match n.as_i64() {
                Some(i) => V::Int(i128::from(i)),
                None => match n.as_u64() {
                    Some(u) => V::Int(i128::from(u)),
                    None => V::Real(n.as_f64()?),
                },
            },
            serde_json::Value::String(s) => match sfc_sim::parse_time(s) {
                Some(us) => V::Time(us),
                None => V::Str(s.clone()),
            },
            _ => return None,
        })
    }
}

/// Random values: BOOLs at random (step flags only where the concurrency relation allows),
/// numbers near the constant they are compared with, within their declared range.
struct Random {
    state: u64,
    values: Vec<(String, V)>,
    /// Integer ranges of the declared variables, by upper-case name.
    ranges: std::collections::HashMap<String, (i128, i128)>,
    steps: Vec<String>,
    apart: HashSet<(usize, usize)>,
}

impl Random {
    fn next(&mut self) -> u64 {
        self.state = self.state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.state >> 33
    }
    fn step_of(&self, key: &str) -> Option<usize> {
        let upper = key.to_ascii_uppercase();
        let name = upper.strip_suffix(".X")?;
        self.steps.iter().position(|s| s.eq_ignore_ascii_case(name))
    }
}

impl Env for Random {
    fn get(&mut self, key: &str, like: Option<&V>) -> Option<V> {
        // One value per atom or term within one sample.
        if let Some((_, v)) = self.values.iter().find(|(k, _)| k.eq_ignore_ascii_case(key)) {
            return Some(v.clone());
        }
        let r = self.next();
        let v = match like {
            None | Some(V::Bool(_)) => {
                let mut b = r & 1 == 0;
                if let Some(s) = self.step_of(key) {
                    let active: Vec<usize> = self
                        .values
                        .iter()
                        .filter(|(_, v)| *v == V::Bool(true))
                        .filter_map(|(k, _)| self.step_of(k))
                        .collect();
                    b &= active.iter().all(|&a| a == s || !self.apart.contains(&(a, s)));
                }
                V::Bool(b)
            }
            Some(V::Int(c)) => {
                let v = c + (r % 5) as i128 - 2;
                V::Int(match self.ranges.get(&key.to_ascii_uppercase()) {
                    Some((lo, hi)) => v.clamp(*lo, *hi),
                    None => v,
                })
            }
            Some(V::Real(c)) => V::Real(c + ((r % 9) as f64 - 4.0) / 2.0),
            Some(V::Time(c)) => V::Time((c + (r % 5) as i64 - 2).max(0)),
            Some(other) => other.clone(),
        };
        self.values.push((key.to_string(), v.clone()));
        Some(v)
    }
}

fn prec(e: &Expr) -> u8 {
    match &e.kind {
        ExprKind::Binary { op, .. } => op.precedence(),
        ExprKind::Unary { .. } => UNARY_PRECEDENCE,
        ExprKind::Paren(i) => prec(i),
        _ => 10,
    }
}

/// The documented canonical form of opaque atoms (minimal parentheses, one space around
/// binary operators).
fn show(e: &Expr) -> String {
    let wrap = |c: &Expr, min: u8| if prec(c) < min { format!("({})", show(c)) } else { show(c) };
    match &e.kind {
        ExprKind::Literal(l) => l.text.clone(),
        ExprKind::Name(n) => n.text.clone(),
        ExprKind::Address(a) => a.text.clone(),
        ExprKind::Member { base, member } => format!("{}.{}", wrap(base, 10), member.text),
        ExprKind::Index { base, indices } => {
            format!("{}[{}]", wrap(base, 10), indices.iter().map(show).collect::<Vec<_>>().join(", "))
        }
        ExprKind::Call { callee, args } => {
            let a: Vec<String> = args
                .iter()
                .map(|a| {
                    let mut s = String::new();
                    if a.negated {
                        s.push_str("NOT ");
                    }
                    if let Some(n) = &a.name {
                        s.push_str(&n.text);
                        s.push_str(if a.output { " => " } else { " := " });
                    }
                    if let Some(v) = &a.value {
                        s.push_str(&show(v));
                    }
                    s
                })
                .collect();
            format!("{}({})", callee.text, a.join(", "))
        }
        ExprKind::Unary { op, operand } => {
            let o = match op {
                UnaryOp::Not => "NOT ",
                UnaryOp::Neg => "-",
                UnaryOp::Plus => "+",
            };
            format!("{o}{}", wrap(operand, UNARY_PRECEDENCE))
        }
        ExprKind::Binary { op, lhs, rhs } => {
            let p = op.precedence();
            format!("{} {} {}", wrap(lhs, p), op.symbol(), wrap(rhs, p + 1))
        }
        ExprKind::Paren(i) => show(i),
        // Not a condition: an action call (a statement).
        ExprKind::MemberCall { .. } | ExprKind::Deref(_) | ExprKind::Error => "?".into(),
    }
}

struct Eval<'a, E: Env> {
    env: E,
    unit: &'a SourceUnit,
    pou: &'a str,
}

impl<E: Env> Eval<'_, E> {
    /// A named CONSTANT of the POU or the file.
    fn constant(&self, e: &Expr) -> Option<V> {
        let (env, _) = sfc_st::TypeEnv::from_unit(self.unit);
        let pou = self.unit.items.iter().find_map(|i| match i {
            Item::Pou(p) if p.name.is(self.pou) => Some(p),
            _ => None,
        })?;
        let scope = sfc_st::Scope::for_pou(&env, pou);
        match sfc_st::const_eval(e, &scope)? {
            sfc_st::Value::Int(i) => Some(V::Int(i)),
            sfc_st::Value::Real(r) => Some(V::Real(r)),
            sfc_st::Value::Bool(b) => Some(V::Bool(b)),
            sfc_st::Value::Time(t) => Some(V::Time(t)),
        }
    }

    /// A bare enumeration value that is not also a variable of the POU.
    fn is_enum_value(&self, name: &str) -> bool {
        let (env, _) = sfc_st::TypeEnv::from_unit(self.unit);
        let Some(pou) = self.unit.items.iter().find_map(|i| match i {
            Item::Pou(p) if p.name.is(self.pou) => Some(p),
            _ => None,
        }) else {
            return false;
        };
        let scope = sfc_st::Scope::for_pou(&env, pou);
        scope.variable(name).is_none() && !env.enum_types_with_value(name).is_empty()
    }

    fn literal(e: &Expr) -> Option<V> {
        let ExprKind::Literal(l) = &e.kind else { return None };
        Some(match &l.kind {
            LiteralKind::Bool(b) => V::Bool(*b),
            LiteralKind::Int(i) if l.type_prefix.as_deref() == Some("REAL") => V::Real(*i as f64),
            LiteralKind::Int(i) => V::Int(*i),
            LiteralKind::Real(r) => V::Real(*r),
            LiteralKind::Duration(d) => V::Time(*d),
            LiteralKind::Enum(id) => V::Str(id.text.clone()),
            _ => return None,
        })
    }

    /// A constant, if `e` is one.
    fn konst(&self, e: &Expr) -> Option<V> {
        match &e.kind {
            ExprKind::Paren(i) => self.konst(i),
            ExprKind::Literal(_) => Self::literal(e),
            ExprKind::Name(n) if self.is_enum_value(&n.text) => Some(V::Str(n.text.clone())),
            ExprKind::Unary { op: UnaryOp::Neg, operand } => match self.konst(operand)? {
                V::Int(i) => Some(V::Int(-i)),
                V::Real(r) => Some(V::Real(-r)),
                V::Time(t) => Some(V::Time(-t)),
                _ => None,
            },
            _ => self.constant(e),
        }
    }

    fn boolean(&mut self, e: &Expr) -> Result<bool, String> {
        match &e.kind {
            ExprKind::Paren(i) => self.boolean(i),
            ExprKind::Unary { op: UnaryOp::Not, operand } => Ok(!self.boolean(operand)?),
            ExprKind::Binary { op, lhs, rhs } => match op {
                BinaryOp::And | BinaryOp::AndThen => Ok(self.boolean(lhs)? & self.boolean(rhs)?),
                BinaryOp::Or | BinaryOp::OrElse => Ok(self.boolean(lhs)? | self.boolean(rhs)?),
                BinaryOp::Xor => Ok(self.boolean(lhs)? ^ self.boolean(rhs)?),
                BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge => {
                    self.compare(*op, lhs, rhs)
                }
                _ => self.leaf_bool(e),
            },
            ExprKind::Call { callee, args } if args.iter().all(|a| a.name.is_none() && a.value.is_some()) => {
                let vals: Vec<&Expr> = args.iter().filter_map(|a| a.value.as_ref()).collect();
                let name = callee.text.to_ascii_uppercase();
                match name.as_str() {
                    "AND" | "OR" | "XOR" => {
                        let mut acc = self.boolean(vals[0])?;
                        for v in &vals[1..] {
                            let b = self.boolean(v)?;
                            acc = match name.as_str() {
                                "AND" => acc & b,
                                "OR" => acc | b,
                                _ => acc ^ b,
                            };
                        }
                        Ok(acc)
                    }
                    "NOT" => Ok(!self.boolean(vals[0])?),
                    "GT" | "GE" | "EQ" | "NE" | "LT" | "LE" => {
                        let op = match name.as_str() {
                            "GT" => BinaryOp::Gt,
                            "GE" => BinaryOp::Ge,
                            "EQ" => BinaryOp::Eq,
                            "NE" => BinaryOp::Ne,
                            "LT" => BinaryOp::Lt,
                            _ => BinaryOp::Le,
                        };
                        let mut acc = true;
                        for w in vals.windows(2) {
                            acc &= self.compare(op, w[0], w[1])?;
                        }
                        Ok(acc)
                    }
                    _ => self.leaf_bool(e),
                }
            }
            _ => self.leaf_bool(e),
        }
    }

    fn leaf_bool(&mut self, e: &Expr) -> Result<bool, String> {
        if let Some(v) = self.konst(e) {
            return match v {
                V::Bool(b) => Ok(b),
                V::Int(i) if i == 0 || i == 1 => Ok(i == 1),
                v => Err(format!("`{}` is {v:?}, not BOOL", show(e))),
            };
        }
        match self.env.get(&show(e), None) {
            Some(V::Bool(b)) => Ok(b),
            other => Err(format!("no BOOL value for `{}` (found {other:?})", show(e))),
        }
    }

    /// The value of a term compared with `like`.
    fn value(&mut self, e: &Expr, like: Option<&V>) -> Option<V> {
        if let Some(v) = self.konst(e) {
            return Some(v);
        }
        if let Some(v) = self.env.get(&show(e), like) {
            return Some(v);
        }
        // A bare enumeration value.
        match &e.kind {
            ExprKind::Name(n) if matches!(like, Some(V::Str(_)) | None) => Some(V::Str(n.text.clone())),
            ExprKind::Paren(i) => self.value(i, like),
            _ => None,
        }
    }

    fn compare(&mut self, op: BinaryOp, a: &Expr, b: &Expr) -> Result<bool, String> {
        let ka = self.konst(a);
        let kb = self.konst(b);
        let is_bool_side = |e: &Expr| {
            matches!(
                &e.kind,
                ExprKind::Unary { op: UnaryOp::Not, .. }
                    | ExprKind::Binary {
                        op: BinaryOp::And
                            | BinaryOp::Or
                            | BinaryOp::Xor
                            | BinaryOp::Eq
                            | BinaryOp::Ne
                            | BinaryOp::Lt
                            | BinaryOp::Gt
                            | BinaryOp::Le
                            | BinaryOp::Ge,
                        ..
                    }
            )
        };
        if matches!(op, BinaryOp::Eq | BinaryOp::Ne)
            && (is_bool_side(a) || is_bool_side(b) || matches!(ka, Some(V::Bool(_))) || matches!(kb, Some(V::Bool(_))))
        {
            let eq = self.boolean(a)? == self.boolean(b)?;
            return Ok(if op == BinaryOp::Eq { eq } else { !eq });
        }
        let va = self.value(a, kb.as_ref());
        let vb = self.value(b, va.as_ref().or(ka.as_ref()));
        if let (Some(x), Some(y)) = (&va, &vb) {
            if let Some(ord) = order(x, y) {
                return Ok(match op {
                    BinaryOp::Eq => ord.is_eq(),
                    BinaryOp::Ne => ord.is_ne(),
                    BinaryOp::Lt => ord.is_lt(),
                    BinaryOp::Gt => ord.is_gt(),
                    BinaryOp::Le => ord.is_le(),
                    _ => ord.is_ge(),
                });
            }
        }
        // Two terms without values: the relation atoms of the witness.
        let (sa, sb) = (show(a), show(b));
        let mut rel = |k: String| match self.env.get(&k, None) {
            Some(V::Bool(v)) => Some(v),
            _ => None,
        };
        let lt = |r: &mut dyn FnMut(String) -> Option<bool>, x: &str, y: &str| r(format!("{x} < {y}"));
        let eq =
            |r: &mut dyn FnMut(String) -> Option<bool>| r(format!("{sa} = {sb}")).or_else(|| r(format!("{sb} = {sa}")));
        let v = match op {
            BinaryOp::Lt => lt(&mut rel, &sa, &sb),
            BinaryOp::Gt => lt(&mut rel, &sb, &sa),
            BinaryOp::Ge => lt(&mut rel, &sa, &sb).map(|v| !v),
            BinaryOp::Le => lt(&mut rel, &sb, &sa).map(|v| !v),
            BinaryOp::Eq => eq(&mut rel),
            _ => eq(&mut rel).map(|v| !v),
        };
        v.ok_or_else(|| format!("cannot evaluate `{sa} {} {sb}` (values {va:?}, {vb:?})", op.symbol()))
    }

    /// An IL condition: LD/LDN, AND/OR/XOR with N and parentheses, NOT, comparisons.
    fn il(&mut self, instrs: &[IlInstruction], start: Option<V>) -> Result<Option<V>, String> {
        let mut cr = start;
        for ins in instrs {
            let Some(op) = &ins.op else { continue };
            let text = op.text.to_ascii_uppercase();
            let operand = |this: &mut Self, cr: &Option<V>| -> Result<V, String> {
                if let Some(n) = &ins.nested {
                    let start = match ins.operands.first() {
                        Some(e) => Some(this.value(e, None).ok_or("no value for a nested start")?),
                        None => None,
                    };
                    return this.il(n, start)?.ok_or_else(|| "empty parenthesis".to_string());
                }
                let e = ins.operands.first().ok_or("no operand")?;
                let like =
                    if let Some(v @ (V::Int(_) | V::Real(_) | V::Time(_))) = cr { Some(v.clone()) } else { None };
                match this.konst(e) {
                    Some(v) => Ok(v),
                    None => this.value(e, like.as_ref()).ok_or_else(|| format!("no value for `{}`", show(e))),
                }
            };
            let as_bool = |v: &V| match v {
                V::Bool(b) => Ok(*b),
                V::Int(0) => Ok(false),
                V::Int(1) => Ok(true),
                v => Err(format!("{v:?} is not BOOL")),
            };
            cr = Some(match text.as_str() {
                "LD" => operand(self, &cr)?,
                "LDN" => V::Bool(!as_bool(&operand(self, &cr)?)?),
                "NOT" => V::Bool(!as_bool(cr.as_ref().ok_or("NOT without a current result")?)?),
                "AND" | "ANDN" | "&" | "&N" | "OR" | "ORN" | "XOR" | "XORN" => {
                    let l = as_bool(cr.as_ref().ok_or("no current result")?)?;
                    let mut r = as_bool(&operand(self, &cr)?)?;
                    if text.ends_with('N') {
                        r = !r;
                    }
                    V::Bool(match text.trim_end_matches('N') {
                        "AND" | "&" => l & r,
                        "OR" => l | r,
                        _ => l ^ r,
                    })
                }
                "GT" | "GE" | "EQ" | "NE" | "LT" | "LE" => {
                    let l = cr.clone().ok_or("no current result")?;
                    let r = operand(self, &cr)?;
                    let ord = order(&l, &r).ok_or_else(|| format!("cannot compare {l:?} with {r:?}"))?;
                    V::Bool(match text.as_str() {
                        "GT" => ord.is_gt(),
                        "GE" => ord.is_ge(),
                        "EQ" => ord.is_eq(),
                        "NE" => ord.is_ne(),
                        "LT" => ord.is_lt(),
                        _ => ord.is_le(),
                    })
                }
                other => return Err(format!("IL operator `{other}` is not supported by the test evaluator")),
            });
        }
        Ok(cr)
    }

    fn condition(&mut self, c: &Condition) -> Result<bool, String> {
        match c {
            Condition::St(e) => self.boolean(e),
            Condition::Il(body) => match self.il(&body.instructions, None)? {
                Some(V::Bool(b)) => Ok(b),
                other => Err(format!("IL condition ends with {other:?}")),
            },
            Condition::Missing => Err("missing condition".into()),
        }
    }
}

fn order(a: &V, b: &V) -> Option<std::cmp::Ordering> {
    match (a, b) {
        (V::Int(x), V::Int(y)) => Some(x.cmp(y)),
        (V::Int(x), V::Real(y)) => (*x as f64).partial_cmp(y),
        (V::Real(x), V::Int(y)) => x.partial_cmp(&(*y as f64)),
        (V::Real(x), V::Real(y)) => x.partial_cmp(y),
        (V::Time(x), V::Time(y)) => Some(x.cmp(y)),
        (V::Bool(x), V::Bool(y)) => Some(x.cmp(y)),
        (V::Str(x), V::Str(y)) => Some(if x.eq_ignore_ascii_case(y) { std::cmp::Ordering::Equal } else { x.cmp(y) }),
        _ => None,
    }
}

// ---------------------------------------------------------------------------------------------
// Fixtures

/// Directives of one POU: expected findings (as text), `none` given, and apart step groups.
#[derive(Default, Debug)]
struct Expected {
    findings: BTreeSet<String>,
    none: bool,
    apart: Vec<Vec<String>>,
    any: bool,
}

fn directives(text: &str, chart: &Chart) -> Result<Expected, String> {
    let mut exp = Expected::default();
    let (lo, hi) = (chart.span.start as usize, chart.span.end as usize);
    let mut pos = 0;
    while let Some(start) = text[pos..].find("(*!") {
        let at = pos + start;
        let after = at + 3;
        let end = text[after..].find("*)").map(|e| after + e).unwrap_or(text.len());
        pos = end;
        if at < lo || at >= hi {
            continue;
        }
        let words: Vec<&str> = text[after..end].split_whitespace().collect();
        exp.any = true;
        match words.as_slice() {
            ["none"] => exp.none = true,
            ["apart", steps @ ..] if steps.len() >= 2 => exp.apart.push(steps.iter().map(|s| s.to_string()).collect()),
            ["nonexclusive", a, b] => {
                exp.findings.insert(format!("nonexclusive {a} {b}"));
            }
            ["nonexclusive", a, b, "explicit"] => {
                exp.findings.insert(format!("nonexclusive {a} {b} explicit"));
            }
            ["incomplete", s] => {
                exp.findings.insert(format!("incomplete {s}"));
            }
            ["always_true", t] => {
                exp.findings.insert(format!("always_true {t}"));
            }
            ["always_false", t] => {
                exp.findings.insert(format!("always_false {t}"));
            }
            other => return Err(format!("unknown directive {other:?}")),
        }
    }
    if exp.none && !exp.findings.is_empty() {
        return Err("`none` together with expected findings".into());
    }
    Ok(exp)
}

fn describe(chart: &Chart, f: &GuardFinding) -> String {
    let t = |i: usize| chart.transitions[i].name.clone();
    let s = |i: usize| chart.steps[i].name.clone();
    match &f.kind {
        GuardFindingKind::NonExclusive { first, second, explicit_priority } => {
            format!("nonexclusive {} {}{}", t(*first), t(*second), if *explicit_priority { " explicit" } else { "" })
        }
        GuardFindingKind::Incomplete { step } => format!("incomplete {}", s(*step)),
        GuardFindingKind::AlwaysTrue { transition } => format!("always_true {}", t(*transition)),
        GuardFindingKind::AlwaysFalse { transition } => format!("always_false {}", t(*transition)),
    }
}

fn apart_relation(chart: &Chart, apart: &[Vec<String>]) -> Result<HashSet<(usize, usize)>, String> {
    let mut out = HashSet::new();
    for group in apart {
        let ids: Vec<usize> = group
            .iter()
            .map(|n| chart.step(n).ok_or_else(|| format!("`apart`: no step `{n}`")))
            .collect::<Result<_, _>>()?;
        for &a in &ids {
            for &b in &ids {
                if a != b {
                    out.insert((a, b));
                }
            }
        }
    }
    Ok(out)
}

/// Checks one finding's witness against the guards; `Err` explains the failure.
fn check_witness(
    unit: &SourceUnit,
    chart: &Chart,
    f: &GuardFinding,
    together: &dyn Fn(usize, usize) -> bool,
) -> Result<(), String> {
    let eval = |t: usize| -> Result<bool, String> {
        let mut ev = Eval { env: Witness(&f.witness), unit, pou: &chart.pou };
        ev.condition(&chart.transitions[t].condition).map_err(|e| format!("{}: {e}", chart.transitions[t].name))
    };
    // Step flags TRUE in the witness must be able to be active together.
    let active: Vec<usize> = f
        .witness
        .iter()
        .filter(|(k, v)| k.to_ascii_uppercase().ends_with(".X") && *v == serde_json::Value::Bool(true))
        .filter_map(|(k, _)| chart.step(&k[..k.len() - 2]))
        .collect();
    for &a in &active {
        for &b in &active {
            if a != b && !together(a, b) {
                return Err(format!(
                    "witness activates {} and {}, which are apart",
                    chart.steps[a].name, chart.steps[b].name
                ));
            }
        }
    }
    let flag = |s: usize| -> Option<bool> {
        let key = format!("{}.X", chart.steps[s].name);
        f.witness.iter().find(|(k, _)| k.eq_ignore_ascii_case(&key)).and_then(|(_, v)| v.as_bool())
    };
    match &f.kind {
        GuardFindingKind::NonExclusive { first, second, .. } => {
            for t in [*first, *second] {
                if !eval(t)? {
                    return Err(format!("{} is FALSE on the witness", chart.transitions[t].name));
                }
                for &s in &chart.transitions[t].from {
                    if flag(s) == Some(false) {
                        return Err(format!("witness has source step {} inactive", chart.steps[s].name));
                    }
                }
            }
        }
        GuardFindingKind::Incomplete { step } => {
            if flag(*step) == Some(false) {
                return Err("witness has the step inactive".into());
            }
            for (t, tr) in chart.transitions.iter().enumerate() {
                let live = tr.from.iter().all(|&a| tr.from.iter().all(|&b| a == b || together(a, b)));
                if tr.from.contains(step) && live && eval(t)? {
                    return Err(format!("{} is TRUE on the witness", tr.name));
                }
            }
        }
        GuardFindingKind::AlwaysTrue { transition } | GuardFindingKind::AlwaysFalse { transition } => {
            if !f.witness.is_empty() {
                return Err("a constant guard has a witness".into());
            }
            // Sample valuations of ST guards: the guard must keep its constant value.
            let want = matches!(f.kind, GuardFindingKind::AlwaysTrue { .. });
            if let Condition::St(e) = &chart.transitions[*transition].condition {
                let (env, _) = sfc_st::TypeEnv::from_unit(unit);
                let mut ranges = std::collections::HashMap::new();
                if let Some(pou) = unit.items.iter().find_map(|i| match i {
                    Item::Pou(p) if p.name.is(&chart.pou) => Some(p),
                    _ => None,
                }) {
                    for v in sfc_st::Scope::for_pou(&env, pou).vars() {
                        if let Some(r) = v.ty.int_range() {
                            ranges.insert(v.name.to_ascii_uppercase(), r);
                        }
                    }
                }
                let steps: Vec<String> = chart.steps.iter().map(|s| s.name.clone()).collect();
                let n = steps.len();
                let apart: HashSet<(usize, usize)> = (0..n)
                    .flat_map(|a| (0..n).map(move |b| (a, b)))
                    .filter(|&(a, b)| a != b && !together(a, b))
                    .collect();
                for seed in 0..200u64 {
                    let random = Random {
                        state: seed * 7919 + 17,
                        values: Vec::new(),
                        ranges: ranges.clone(),
                        steps: steps.clone(),
                        apart: apart.clone(),
                    };
                    let mut ev = Eval { env: random, unit, pou: &chart.pou };
                    let mut flags = Vec::new();
                    for &s in &chart.transitions[*transition].from {
                        flags.push((format!("{}.X", chart.steps[s].name), true));
                    }
                    ev.env.values.extend(flags.into_iter().map(|(k, b)| (k, V::Bool(b))));
                    let v = ev.boolean(e)?;
                    if v != want {
                        return Err(format!("{} is {v} on a random sample", chart.transitions[*transition].name));
                    }
                }
            }
        }
    }
    Ok(())
}

fn run_file(path: &Path) -> Result<Vec<(String, Vec<String>)>, String> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: {e}"))?;
    let checked = check(&name, &text);
    if checked.has_errors() {
        return Err(format!("{name}: has errors: {:#?}", checked.diagnostics));
    }
    let mut out = Vec::new();
    for chart in &checked.charts {
        let exp = directives(&text, chart).map_err(|e| format!("{name}: {e}"))?;
        let apart = apart_relation(chart, &exp.apart).map_err(|e| format!("{name}: {e}"))?;
        let together = |a: usize, b: usize| !apart.contains(&(a, b));
        let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
        let findings = analyze_guards(chart, &cx);
        let got: Vec<String> = findings.iter().map(|f| describe(chart, f)).collect();
        for f in &findings {
            check_witness(&checked.unit, chart, f, &together)
                .map_err(|e| format!("{name}: {}: witness {:?}: {e}", describe(chart, f), f.witness))?;
        }
        if exp.any {
            let got_set: BTreeSet<String> = got.iter().cloned().collect();
            if got_set != exp.findings || got_set.len() != got.len() {
                return Err(format!(
                    "{name}: POU {}: expected {:?}, got {:?}\nwitnesses: {:#?}",
                    chart.pou,
                    exp.findings,
                    got,
                    findings.iter().map(|f| (describe(chart, f), &f.witness)).collect::<Vec<_>>()
                ));
            }
        }
        if std::env::var_os("GUARD_SHOW").is_some() {
            for f in &findings {
                eprintln!("{name}: {}: {:?}", describe(chart, f), f.witness);
            }
        }
        out.push((chart.pou.clone(), got));
    }
    Ok(out)
}

#[test]
fn fixtures() {
    let files = st_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/guard"));
    assert!(files.len() >= 8, "guard fixtures are missing");
    let mut failures = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("fixture is UTF-8 text");
        let checked = check("x", &text);
        // Every chart of a fixture states what it expects.
        for chart in &checked.charts {
            match directives(&text, chart) {
                Ok(e) if e.any => {}
                Ok(_) => failures.push(format!("{}: POU {} has no directive", f.display(), chart.pou)),
                Err(e) => failures.push(format!("{}: {e}", f.display())),
            }
        }
        if let Err(e) = run_file(f) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn findings_are_ordered() {
    for f in st_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/guard")) {
        let text = std::fs::read_to_string(&f).expect("fixture is UTF-8 text");
        let checked = check("x", &text);
        for chart in &checked.charts {
            let together = |_: usize, _: usize| true;
            let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
            let findings = analyze_guards(chart, &cx);
            let rank = |k: &GuardFindingKind| match k {
                GuardFindingKind::NonExclusive { first, second, .. } => (0, *first, *second),
                GuardFindingKind::Incomplete { step } => (1, *step, 0),
                GuardFindingKind::AlwaysTrue { transition } | GuardFindingKind::AlwaysFalse { transition } => {
                    (2, *transition, 0)
                }
            };
            let ranks: Vec<_> = findings.iter().map(|f| rank(&f.kind)).collect();
            let mut sorted = ranks.clone();
            sorted.sort();
            assert_eq!(ranks, sorted, "{}: findings out of order", f.display());
            for f in &findings {
                if let GuardFindingKind::NonExclusive { first, second, .. } = f.kind {
                    assert!(first < second);
                }
            }
            // The same input gives the same findings.
            assert_eq!(findings, analyze_guards(chart, &cx));
        }
    }
}

/// Types from the declarations alone (no `expr_types`) give the same findings.
#[test]
fn without_recorded_types() {
    for f in st_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/guard")) {
        let text = std::fs::read_to_string(&f).expect("fixture is UTF-8 text");
        let checked = check("x", &text);
        let empty = std::collections::HashMap::new();
        for chart in &checked.charts {
            let exp = directives(&text, chart).expect("directives");
            let apart = apart_relation(chart, &exp.apart).expect("apart");
            let together = |a: usize, b: usize| !apart.contains(&(a, b));
            let with = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
            let without = GuardContext { unit: &checked.unit, expr_types: &empty, together: &together };
            assert_eq!(
                analyze_guards(chart, &with),
                analyze_guards(chart, &without),
                "{}: POU {}",
                f.display(),
                chart.pou
            );
        }
    }
}

/// The examples give no warning (no non-exclusive pair without explicit priority), and every
/// note they give has a valid witness.
#[test]
fn examples_have_no_warning() {
    let files = st_files(&root().join("examples"));
    assert!(!files.is_empty());
    let mut report = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("example is UTF-8 text");
        let checked = check(&f.display().to_string(), &text);
        assert!(!checked.has_errors(), "{}", f.display());
        for chart in &checked.charts {
            let together = |_: usize, _: usize| true;
            let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
            for finding in analyze_guards(chart, &cx) {
                let d = describe(chart, &finding);
                assert!(
                    !matches!(finding.kind, GuardFindingKind::NonExclusive { explicit_priority: false, .. }),
                    "{}: warning {d}: {:?}",
                    f.display(),
                    finding.witness
                );
                check_witness(&checked.unit, chart, &finding, &together)
                    .unwrap_or_else(|e| panic!("{}: {d}: {e}", f.display()));
                report.push(format!("{}: {}: {d} {:?}", f.display(), chart.pou, finding.witness));
            }
        }
    }
    eprintln!("{}", report.join("\n"));
}

/// Generated charts: hundreds of divergences are analysed quickly, and over-large guards are
/// left alone without a finding.
#[test]
fn large_charts() {
    let n = 300;
    let mut src = String::from("PROGRAM Big\nVAR_INPUT\n");
    for i in 0..n {
        src.push_str(&format!("  a{i}, b{i} : BOOL; x{i} : INT; r{i} : REAL;\n"));
    }
    src.push_str("END_VAR\nINITIAL_STEP S0: END_STEP\n");
    for i in 0..n {
        let next = (i + 1) % n;
        // Four alternatives: two exclusive comparisons, a REAL range, and a BOOL overlap.
        src.push_str(&format!(
            "TRANSITION TA{i} FROM S{i} TO S{next} := x{i} > 5 AND a{i}; END_TRANSITION\n\
             TRANSITION TB{i} FROM S{i} TO S{next} := x{i} < 3 AND a{i}; END_TRANSITION\n\
             TRANSITION TC{i} FROM S{i} TO S{next} := r{i} >= 1.5 AND r{i} < 2.5 AND NOT a{i}; END_TRANSITION\n\
             TRANSITION TD{i} FROM S{i} TO S{next} := b{i} AND NOT a{i} AND r{i} > 2.0; END_TRANSITION\n"
        ));
        if i + 1 < n {
            src.push_str(&format!("STEP S{next}: END_STEP\n"));
        }
    }
    src.push_str("END_PROGRAM\n");
    let checked = check("big.st", &src);
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics.iter().take(3).collect::<Vec<_>>());
    let chart = &checked.charts[0];
    let together = |_: usize, _: usize| true;
    let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
    let t0 = Instant::now();
    let findings = analyze_guards(chart, &cx);
    let elapsed = t0.elapsed();
    eprintln!("{} transitions, {} findings in {elapsed:?}", chart.transitions.len(), findings.len());
    // Per divergence: C and D overlap (r in (2.0, 2.5), b, NOT a); the step is incomplete.
    let nonex = findings.iter().filter(|f| matches!(f.kind, GuardFindingKind::NonExclusive { .. })).count();
    let incomplete = findings.iter().filter(|f| matches!(f.kind, GuardFindingKind::Incomplete { .. })).count();
    assert_eq!((nonex, incomplete, findings.len()), (n, n, 2 * n));
    for f in findings.iter().take(20) {
        check_witness(&checked.unit, chart, f, &together).unwrap();
    }
    assert!(elapsed.as_secs() < 20, "too slow: {elapsed:?}");

    // One step with 150 alternatives on one INT (11,175 pairs) plus one overlapping range.
    let mut src = String::from(
        "PROGRAM Many\nVAR_INPUT m : INT; Go : BOOL; END_VAR\nINITIAL_STEP S0: END_STEP\nSTEP S1: END_STEP\n",
    );
    for i in 1..=150 {
        src.push_str(&format!("TRANSITION K{i} FROM S0 TO S1 := m = {i}; END_TRANSITION\n"));
    }
    src.push_str("TRANSITION KX FROM S0 TO S1 := m > 100 AND Go; END_TRANSITION\n");
    src.push_str("TRANSITION KB FROM S1 TO S0 := TRUE; END_TRANSITION\nEND_PROGRAM\n");
    let checked = check("many.st", &src);
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics.iter().take(3).collect::<Vec<_>>());
    let chart = &checked.charts[0];
    let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
    let t0 = Instant::now();
    let findings = analyze_guards(chart, &cx);
    let elapsed = t0.elapsed();
    eprintln!("150 alternatives: {} findings in {elapsed:?}", findings.len());
    let got: Vec<String> = findings.iter().map(|f| describe(chart, f)).collect();
    let mut want: Vec<String> = (101..=150).map(|i| format!("nonexclusive K{i} KX")).collect();
    want.push("incomplete S0".into());
    assert_eq!(got, want);
    for f in &findings {
        check_witness(&checked.unit, chart, f, &together).unwrap();
    }
    assert!(elapsed.as_secs() < 20, "too slow: {elapsed:?}");

    // One guard with 200 BOOL atoms (beyond the per-guard limit), one XOR chain, and one
    // alternative each: the big one is unknown and gives no finding.
    let mut src = String::from("PROGRAM Wide\nVAR_INPUT\n");
    for i in 0..200 {
        src.push_str(&format!("  v{i} : BOOL;\n"));
    }
    src.push_str("END_VAR\nINITIAL_STEP S0: END_STEP\nSTEP S1: END_STEP\n");
    let wide: Vec<String> = (0..200).map(|i| format!("v{i}")).collect();
    src.push_str(&format!("TRANSITION TW FROM S0 TO S1 := {}; END_TRANSITION\n", wide.join(" OR ")));
    let xor: Vec<String> = (0..100).map(|i| format!("v{i}")).collect();
    src.push_str(&format!("TRANSITION TX FROM S0 TO S1 := {}; END_TRANSITION\n", xor.join(" XOR ")));
    src.push_str("TRANSITION TB FROM S1 TO S0 := TRUE; END_TRANSITION\nEND_PROGRAM\n");
    let checked = check("wide.st", &src);
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics.iter().take(3).collect::<Vec<_>>());
    let chart = &checked.charts[0];
    let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
    let t0 = Instant::now();
    let findings = analyze_guards(chart, &cx);
    eprintln!("wide chart: {} findings in {:?}", findings.len(), t0.elapsed());
    assert!(findings.is_empty(), "{findings:?}");
}

/// Charts with errors (missing conditions, unknown names) do not panic.
#[test]
fn broken_input_does_not_panic() {
    let srcs = [
        "PROGRAM P\nINITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1 := ; END_TRANSITION\nTRANSITION FROM S0 TO S1 := x > ; END_TRANSITION\nSTEP S1: END_STEP\nEND_PROGRAM\n",
        "PROGRAM P\nINITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1 := Nope.T > T#1s AND a[i] AND F(1) > 2; END_TRANSITION\nTRANSITION FROM S0 TO S1 := 5; END_TRANSITION\nSTEP S1: END_STEP\nEND_PROGRAM\n",
        "PROGRAM P\nINITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1:\n LD a\n JMPC l1\n l1: LD b\nEND_TRANSITION\nTRANSITION FROM S0 TO S1:\n AND b\n ST c\nEND_TRANSITION\nSTEP S1: END_STEP\nEND_PROGRAM\n",
        "PROGRAM P\nVAR x : INT; END_VAR\nINITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1 := x > 170141183460469231731687303715884105727; END_TRANSITION\nTRANSITION FROM S0 TO S1 := x < -170141183460469231731687303715884105727 OR x > 1.0E300 OR x = 0.5; END_TRANSITION\nSTEP S1: END_STEP\nEND_PROGRAM\n",
    ];
    for s in srcs {
        let checked = check("bad.st", s);
        for chart in &checked.charts {
            let together = |_: usize, _: usize| true;
            let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
            let _ = analyze_guards(chart, &cx);
            // Without the declarations at all.
            let empty_unit = SourceUnit::default();
            let cx = GuardContext { unit: &empty_unit, expr_types: &checked.expr_types, together: &together };
            let _ = analyze_guards(chart, &cx);
        }
    }
}

/// Every chart of the project (valid fixtures, simulator semantics fixtures, examples): the
/// analysis runs, and every witness holds on the guards.
#[test]
fn project_charts_have_valid_witnesses() {
    let mut files = st_files(&root().join("tests/fixtures/valid"));
    files.extend(st_files(&root().join("crates/sfc-sim/tests/semantics")));
    files.extend(st_files(&root().join("examples")));
    let mut report = Vec::new();
    let mut failures = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("UTF-8 text");
        let checked = check(&f.display().to_string(), &text);
        if checked.has_errors() {
            continue;
        }
        for chart in &checked.charts {
            let together = |_: usize, _: usize| true;
            let cx = GuardContext { unit: &checked.unit, expr_types: &checked.expr_types, together: &together };
            for finding in analyze_guards(chart, &cx) {
                let d = describe(chart, &finding);
                let name = f.strip_prefix(root()).unwrap_or(f).display().to_string();
                if let Err(e) = check_witness(&checked.unit, chart, &finding, &together) {
                    failures.push(format!("{name}: {}: {d}: {e}", chart.pou));
                }
                report.push(format!("{name}: {}: {d} {:?}", chart.pou, finding.witness));
            }
        }
    }
    if std::env::var_os("GUARD_SHOW").is_some() {
        eprintln!("{}", report.join("\n"));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
