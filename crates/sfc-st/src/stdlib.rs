//! Signatures of the IEC 61131-3 standard functions and standard function blocks.

use crate::types::{Generic, Type, ELEMENTARY_NAMES};
use sfc_syntax::ast::{BinaryOp, VarKind};

/// How one input of a standard function is typed.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamType {
    /// Exactly this type (or one that widens to it).
    Fixed(Type),
    /// The function's type variable: all `Same` inputs share one type, of this class.
    Same(Generic),
    /// An input of this class, independent of the others (`N` of `SHL`, `K` of `MUX`).
    Any(Generic),
}

/// The result type of a standard function.
#[derive(Debug, Clone, PartialEq)]
pub enum ReturnType {
    /// Always this type.
    Fixed(Type),
    /// The type of the `Same` inputs.
    Same,
    /// A type of the class chosen by the context (the assignment target), else the default:
    /// `TRUNC` returns ANY_INT.
    FromContext(Generic, Type),
}

/// The signature of a standard function.
#[derive(Debug, Clone, PartialEq)]
pub struct StdFunction {
    /// Upper-case name.
    pub name: String,
    /// Inputs in order, with their formal names.
    pub params: Vec<(String, ParamType)>,
    /// The last input may be repeated (`ADD(a, b, c)`), its formal name numbered on.
    pub extensible: bool,
    /// The result type.
    pub ret: ReturnType,
    /// Functions that are operators (`ADD`, `GT`, …) are typed exactly like the operator, so
    /// `ADD(t, T#1s)` follows the TIME rules of `+`.
    pub operator: Option<BinaryOp>,
}

impl StdFunction {
    /// The formal name of input `index` (0-based), numbering on past the declared inputs of
    /// an extensible function (`IN3`, `IN4`, …).
    pub fn param_name(&self, index: usize) -> Option<String> {
        if let Some((n, _)) = self.params.get(index) {
            return Some(n.clone());
        }
        if !self.extensible {
            return None;
        }
        let (last, _) = self.params.last()?;
        let digits = last.trim_start_matches(|c: char| !c.is_ascii_digit());
        let stem = &last[..last.len() - digits.len()];
        let n: usize = digits.parse().ok()?;
        Some(format!("{stem}{}", n + index + 1 - self.params.len()))
    }

    /// The type of input `index`, repeating the last one for an extensible function.
    pub fn param_type(&self, index: usize) -> Option<&ParamType> {
        match self.params.get(index) {
            Some((_, t)) => Some(t),
            None if self.extensible => self.params.last().map(|(_, t)| t),
            None => None,
        }
    }

    /// The position of the input with this formal name (case-insensitive).
    pub fn param_index(&self, name: &str) -> Option<usize> {
        let upper = name.to_ascii_uppercase();
        if let Some(i) = self.params.iter().position(|(n, _)| *n == upper) {
            return Some(i);
        }
        if self.extensible {
            // IN3, IN4, … of an extensible function; bounded so a silly name cannot loop.
            (self.params.len()..self.params.len() + 1024)
                .find(|&i| self.param_name(i).as_deref() == Some(upper.as_str()))
        } else {
            None
        }
    }
}

fn p(name: &str, t: ParamType) -> (String, ParamType) {
    (name.to_string(), t)
}

fn func(name: &str, params: Vec<(String, ParamType)>, extensible: bool, ret: ReturnType) -> StdFunction {
    StdFunction { name: name.to_string(), params, extensible, ret, operator: None }
}

fn operator(name: &str, op: BinaryOp, class: Generic, extensible: bool, ret: ReturnType) -> StdFunction {
    let params = vec![p("IN1", ParamType::Same(class)), p("IN2", ParamType::Same(class))];
    StdFunction { name: name.to_string(), params, extensible, ret, operator: Some(op) }
}

/// The names of the standard functions that are not type conversions (for "did you mean").
pub const STD_FUNCTION_NAMES: &[&str] = &[
    "ADD",
    "SUB",
    "MUL",
    "DIV",
    "MOD",
    "EXPT",
    "MOVE",
    "ABS",
    "SQRT",
    "LN",
    "LOG",
    "EXP",
    "SIN",
    "COS",
    "TAN",
    "ASIN",
    "ACOS",
    "ATAN",
    "TRUNC",
    "SHL",
    "SHR",
    "ROL",
    "ROR",
    "AND",
    "OR",
    "XOR",
    "NOT",
    "SEL",
    "MUX",
    "MIN",
    "MAX",
    "LIMIT",
    "GT",
    "GE",
    "EQ",
    "LE",
    "LT",
    "NE",
    "LEN",
    "LEFT",
    "RIGHT",
    "MID",
    "CONCAT",
    "INSERT",
    "DELETE",
    "REPLACE",
    "FIND",
    "ADD_TIME",
    "ADD_TOD_TIME",
    "ADD_DT_TIME",
    "SUB_TIME",
    "SUB_DATE_DATE",
    "SUB_TOD_TIME",
    "SUB_TOD_TOD",
    "SUB_DT_TIME",
    "SUB_DT_DT",
    "MUL_TIME",
    "DIV_TIME",
    "CONCAT_DATE_TOD",
];

/// The standard function called `name` (case-insensitive), including every
/// `<A>_TO_<B>` conversion, `TO_<B>`, `TRUNC`, `<A>_TRUNC_<B>` and the BCD conversions.
pub fn std_function(name: &str) -> Option<StdFunction> {
    use Generic as G;
    use ParamType::{Any, Fixed, Same};
    let upper = name.to_ascii_uppercase();
    let same = ReturnType::Same;
    let f = match upper.as_str() {
        "ADD" => operator("ADD", BinaryOp::Add, G::AnyMagnitude, true, same),
        "MUL" => operator("MUL", BinaryOp::Mul, G::AnyMagnitude, true, same),
        "SUB" => operator("SUB", BinaryOp::Sub, G::AnyMagnitude, false, same),
        "DIV" => operator("DIV", BinaryOp::Div, G::AnyMagnitude, false, same),
        "MOD" => operator("MOD", BinaryOp::Mod, G::AnyInt, false, same),
        "EXPT" => StdFunction {
            name: upper.clone(),
            params: vec![p("IN1", Same(G::AnyReal)), p("IN2", Any(G::AnyNum))],
            extensible: false,
            ret: same,
            operator: Some(BinaryOp::Pow),
        },
        "AND" => operator("AND", BinaryOp::And, G::AnyBit, true, same),
        "OR" => operator("OR", BinaryOp::Or, G::AnyBit, true, same),
        "XOR" => operator("XOR", BinaryOp::Xor, G::AnyBit, true, same),
        "GT" | "GE" | "EQ" | "LE" | "LT" | "NE" => {
            let op = match upper.as_str() {
                "GT" => BinaryOp::Gt,
                "GE" => BinaryOp::Ge,
                "EQ" => BinaryOp::Eq,
                "LE" => BinaryOp::Le,
                "LT" => BinaryOp::Lt,
                _ => BinaryOp::Ne,
            };
            // NE compares exactly two values; the others are extensible chains.
            operator(&upper, op, G::AnyElementary, upper != "NE", ReturnType::Fixed(Type::Bool))
        }
        "NOT" => func("NOT", vec![p("IN", Same(G::AnyBit))], false, same),
        "MOVE" => func("MOVE", vec![p("IN", Same(G::Any))], false, same),
        "ABS" => func("ABS", vec![p("IN", Same(G::AnyNum))], false, same),
        "SQRT" | "LN" | "LOG" | "EXP" | "SIN" | "COS" | "TAN" | "ASIN" | "ACOS" | "ATAN" => {
            func(&upper, vec![p("IN", Same(G::AnyReal))], false, same)
        }
        "TRUNC" => func("TRUNC", vec![p("IN", Any(G::AnyReal))], false, ReturnType::FromContext(G::AnyInt, Type::DInt)),
        "SHL" | "SHR" | "ROL" | "ROR" => {
            func(&upper, vec![p("IN", Same(G::AnyBit)), p("N", Any(G::AnyInt))], false, same)
        }
        "SEL" => {
            func("SEL", vec![p("G", Fixed(Type::Bool)), p("IN0", Same(G::Any)), p("IN1", Same(G::Any))], false, same)
        }
        "MUX" => func("MUX", vec![p("K", Any(G::AnyInt)), p("IN0", Same(G::Any)), p("IN1", Same(G::Any))], true, same),
        "MAX" | "MIN" => {
            func(&upper, vec![p("IN1", Same(G::AnyElementary)), p("IN2", Same(G::AnyElementary))], true, same)
        }
        "LIMIT" => func(
            "LIMIT",
            vec![p("MN", Same(G::AnyElementary)), p("IN", Same(G::AnyElementary)), p("MX", Same(G::AnyElementary))],
            false,
            same,
        ),
        "LEN" => func("LEN", vec![p("IN", Any(G::AnyString))], false, ReturnType::Fixed(Type::Int)),
        "LEFT" | "RIGHT" => func(&upper, vec![p("IN", Same(G::AnyString)), p("L", Any(G::AnyInt))], false, same),
        "MID" => {
            func("MID", vec![p("IN", Same(G::AnyString)), p("L", Any(G::AnyInt)), p("P", Any(G::AnyInt))], false, same)
        }
        "CONCAT" => func("CONCAT", vec![p("IN1", Same(G::AnyString)), p("IN2", Same(G::AnyString))], true, same),
        "INSERT" => func(
            "INSERT",
            vec![p("IN1", Same(G::AnyString)), p("IN2", Same(G::AnyString)), p("P", Any(G::AnyInt))],
            false,
            same,
        ),
        "DELETE" => func(
            "DELETE",
            vec![p("IN", Same(G::AnyString)), p("L", Any(G::AnyInt)), p("P", Any(G::AnyInt))],
            false,
            same,
        ),
        "REPLACE" => func(
            "REPLACE",
            vec![
                p("IN1", Same(G::AnyString)),
                p("IN2", Same(G::AnyString)),
                p("L", Any(G::AnyInt)),
                p("P", Any(G::AnyInt)),
            ],
            false,
            same,
        ),
        "FIND" => func(
            "FIND",
            vec![p("IN1", Same(G::AnyString)), p("IN2", Same(G::AnyString))],
            false,
            ReturnType::Fixed(Type::Int),
        ),
        "ADD_TIME" => fixed2(&upper, Type::Time, Type::Time, Type::Time),
        "ADD_TOD_TIME" => fixed2(&upper, Type::TimeOfDay, Type::Time, Type::TimeOfDay),
        "ADD_DT_TIME" => fixed2(&upper, Type::DateAndTime, Type::Time, Type::DateAndTime),
        "SUB_TIME" => fixed2(&upper, Type::Time, Type::Time, Type::Time),
        "SUB_DATE_DATE" => fixed2(&upper, Type::Date, Type::Date, Type::Time),
        "SUB_TOD_TIME" => fixed2(&upper, Type::TimeOfDay, Type::Time, Type::TimeOfDay),
        "SUB_TOD_TOD" => fixed2(&upper, Type::TimeOfDay, Type::TimeOfDay, Type::Time),
        "SUB_DT_TIME" => fixed2(&upper, Type::DateAndTime, Type::Time, Type::DateAndTime),
        "SUB_DT_DT" => fixed2(&upper, Type::DateAndTime, Type::DateAndTime, Type::Time),
        "CONCAT_DATE_TOD" => fixed2(&upper, Type::Date, Type::TimeOfDay, Type::DateAndTime),
        "MUL_TIME" | "DIV_TIME" => func(
            &upper,
            vec![p("IN1", Fixed(Type::Time)), p("IN2", Any(G::AnyNum))],
            false,
            ReturnType::Fixed(Type::Time),
        ),
        _ => return conversion(&upper),
    };
    Some(f)
}

fn fixed2(name: &str, a: Type, b: Type, r: Type) -> StdFunction {
    func(name, vec![p("IN1", ParamType::Fixed(a)), p("IN2", ParamType::Fixed(b))], false, ReturnType::Fixed(r))
}

/// Splits `name` into an elementary type name at its start and the rest.
fn strip_type_prefix(name: &str) -> Option<(Type, &str)> {
    ELEMENTARY_NAMES.iter().find_map(|t| {
        let rest = name.strip_prefix(t)?;
        if rest.is_empty() || rest.starts_with('_') {
            Some((Type::elementary(t)?, rest))
        } else {
            None
        }
    })
}

fn conversion_fn(name: &str, input: ParamType, ret: Type) -> Option<StdFunction> {
    Some(func(name, vec![p("IN", input)], false, ReturnType::Fixed(ret)))
}

/// Type conversion functions, recognised by their name.
fn conversion(name: &str) -> Option<StdFunction> {
    use ParamType::{Any, Fixed};
    // TO_<B>: the overloaded conversion of IEC 61131-3 3rd ed.
    if let Some(target) = name.strip_prefix("TO_") {
        let to = Type::elementary(target)?;
        return conversion_fn(name, Any(Generic::AnyElementary), to);
    }
    // BCD_TO_<INT>: from a BCD-coded bit string.
    if let Some(target) = name.strip_prefix("BCD_TO_") {
        let to = Type::elementary(target).filter(Type::is_integer)?;
        return conversion_fn(name, Any(Generic::AnyBit), to);
    }
    // TRUNC_<INT>: overloaded truncation.
    if let Some(target) = name.strip_prefix("TRUNC_") {
        let to = Type::elementary(target).filter(Type::is_integer)?;
        return conversion_fn(name, Any(Generic::AnyReal), to);
    }
    let (from, rest) = strip_type_prefix(name)?;
    if let Some(target) = rest.strip_prefix("_TRUNC_") {
        let to = Type::elementary(target).filter(Type::is_integer)?;
        return if from.is_real() { conversion_fn(name, Fixed(from), to) } else { None };
    }
    if let Some(target) = rest.strip_prefix("_BCD_TO_") {
        let to = Type::elementary(target).filter(Type::is_integer)?;
        return if from.is_bit() && !from.is_bool() { conversion_fn(name, Fixed(from), to) } else { None };
    }
    let target = rest.strip_prefix("_TO_")?;
    if target == "BCD" {
        let to = Type::bits_of_width(from.bit_width()?)?;
        return if from.is_integer() { conversion_fn(name, Fixed(from), to) } else { None };
    }
    if let Some(bits) = target.strip_prefix("BCD_") {
        let to = Type::elementary(bits).filter(|t| t.is_bit() && !t.is_bool())?;
        return if from.is_integer() { conversion_fn(name, Fixed(from), to) } else { None };
    }
    let to = Type::elementary(target)?;
    if convertible(&from, &to) {
        conversion_fn(name, Fixed(from), to)
    } else {
        None
    }
}

/// Whether the standard defines (or common practice offers) `<from>_TO_<to>`.
fn convertible(from: &Type, to: &Type) -> bool {
    let plain = |t: &Type| t.is_num() || t.is_bit() || t.is_duration() || t.is_string();
    if plain(from) && plain(to) {
        return true;
    }
    // Dates convert to and from strings and integer/bit types, DT splits into DATE and TOD.
    let date_partner = |t: &Type| t.is_string() || t.is_integer() || (t.is_bit() && !t.is_bool());
    match (from, to) {
        (Type::DateAndTime, Type::Date | Type::TimeOfDay) => true,
        (a, b) if a.is_date() && b.is_date() => a == b,
        (a, b) if a.is_date() => date_partner(b),
        (a, b) if b.is_date() => date_partner(a),
        _ => false,
    }
}

/// The interface of a standard function block: `(name, kind, type)` in declaration order.
pub fn std_function_block(name: &str) -> Option<Vec<(&'static str, VarKind, Type)>> {
    use Type::{Bool, Time};
    use VarKind::{Input as I, Output as O};
    let upper = name.to_ascii_uppercase();
    // CTU_DINT, CTD_UDINT, … (3rd edition) count in another integer type.
    let (stem, count) = match upper.split_once('_') {
        Some((stem @ ("CTU" | "CTD" | "CTUD"), suffix)) => {
            let t = Type::elementary(suffix)
                .filter(|t| matches!(t, Type::DInt | Type::LInt | Type::UDInt | Type::ULInt))?;
            (stem, t)
        }
        _ => (upper.as_str(), Type::Int),
    };
    let v = match stem {
        "TON" | "TOF" | "TP" => vec![("IN", I, Bool), ("PT", I, Time), ("Q", O, Bool), ("ET", O, Time)],
        "CTU" => vec![("CU", I, Bool), ("R", I, Bool), ("PV", I, count.clone()), ("Q", O, Bool), ("CV", O, count)],
        "CTD" => vec![("CD", I, Bool), ("LD", I, Bool), ("PV", I, count.clone()), ("Q", O, Bool), ("CV", O, count)],
        "CTUD" => vec![
            ("CU", I, Bool),
            ("CD", I, Bool),
            ("R", I, Bool),
            ("LD", I, Bool),
            ("PV", I, count.clone()),
            ("QU", O, Bool),
            ("QD", O, Bool),
            ("CV", O, count),
        ],
        "R_TRIG" | "F_TRIG" => vec![("CLK", I, Bool), ("Q", O, Bool)],
        "SR" => vec![("S1", I, Bool), ("R", I, Bool), ("Q1", O, Bool)],
        "RS" => vec![("S", I, Bool), ("R1", I, Bool), ("Q1", O, Bool)],
        _ => return None,
    };
    Some(v)
}

/// The names of the standard function blocks (without the CTU_DINT-style variants).
pub const STD_FUNCTION_BLOCK_NAMES: &[&str] =
    &["TON", "TOF", "TP", "CTU", "CTD", "CTUD", "R_TRIG", "F_TRIG", "SR", "RS"];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_by_name() {
        let f = std_function("int_to_real").expect("INT_TO_REAL");
        assert_eq!(f.params[0].1, ParamType::Fixed(Type::Int));
        assert_eq!(f.ret, ReturnType::Fixed(Type::Real));
        assert!(std_function("TIME_OF_DAY_TO_STRING").is_some());
        assert!(std_function("DT_TO_TOD").is_some());
        assert!(std_function("TIME_TO_DATE").is_none());
        assert!(std_function("INT_TO_BCD").is_some_and(|f| f.ret == ReturnType::Fixed(Type::Word)));
        assert!(std_function("WORD_BCD_TO_INT").is_some());
        assert!(std_function("LREAL_TRUNC_DINT").is_some());
        assert!(std_function("FOO_TO_INT").is_none());
    }

    #[test]
    fn extensible_names() {
        let f = std_function("ADD").expect("ADD");
        assert_eq!(f.param_name(3).as_deref(), Some("IN4"));
        assert_eq!(f.param_index("in3"), Some(2));
        let m = std_function("MUX").expect("MUX");
        assert_eq!(m.param_name(3).as_deref(), Some("IN2"));
        assert_eq!(std_function("SEL").expect("SEL").param_name(3), None);
    }

    #[test]
    fn counters() {
        let ctu = std_function_block("CTU_DINT").expect("CTU_DINT");
        assert!(ctu.iter().any(|(n, _, t)| *n == "PV" && *t == Type::DInt));
        assert!(std_function_block("CTU_REAL").is_none());
    }
}

/// The IEC 61131-3 name of a parameter of a standard function block that CODESYS names
/// otherwise: RS's `SET` and `RESET1` are `S` and `R1`, SR's `SET1` and `RESET` are `S1` and `R`.
pub fn param_alias(fb: &str, name: &str) -> Option<&'static str> {
    let fb = fb.to_ascii_uppercase();
    let name = name.to_ascii_uppercase();
    match (fb.as_str(), name.as_str()) {
        ("RS", "SET") => Some("S"),
        ("RS", "RESET1") => Some("R1"),
        ("SR", "SET1") => Some("S1"),
        ("SR", "RESET") => Some("R"),
        _ => None,
    }
}
