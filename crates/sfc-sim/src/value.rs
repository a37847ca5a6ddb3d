//! Runtime values and the canonical text of TIME values used by traces and scenarios.

use std::fmt;
use std::sync::Arc;

/// The value held by one memory slot.
///
/// Every integer and bit-string type lives in `Int`; the declared type (known to the compiled
/// code and to the layout) says how to wrap it: ULINT and LWORD keep the bits of the `u64`.
/// REAL is stored as `f64` already rounded to `f32`. DATE, TIME_OF_DAY and DATE_AND_TIME are
/// `Int` microseconds (DATE: days since 1970-01-01 times 86 400 000 000).
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Bool(bool),
    Int(i64),
    Real(f64),
    /// TIME and LTIME, in microseconds.
    Time(i64),
    /// STRING and WSTRING.
    Str(Arc<str>),
}

impl Value {
    /// The boolean, if this is one.
    pub fn as_bool(&self) -> Option<bool> {
        match self {
            Value::Bool(b) => Some(*b),
            _ => None,
        }
    }
    /// The integer (or TIME microseconds), if this is one.
    pub fn as_int(&self) -> Option<i64> {
        match self {
            Value::Int(i) | Value::Time(i) => Some(*i),
            Value::Bool(b) => Some(i64::from(*b)),
            _ => None,
        }
    }
    pub fn as_real(&self) -> Option<f64> {
        match self {
            Value::Real(r) => Some(*r),
            Value::Int(i) => Some(*i as f64),
            _ => None,
        }
    }
}

impl Default for Value {
    fn default() -> Self {
        Value::Bool(false)
    }
}

/// Writes a TIME canonically: `T#` then the non-zero units `d h m s ms us`, largest first
/// (`T#1s500ms`, `T#2ms500us`), zero as `T#0s`, negative as `T#-200ms`.
pub fn format_time(us: i64) -> String {
    let mut out = String::new();
    write_time(&mut out, us);
    out
}

/// [`format_time`] appended to `out` (no allocation when `out` has room).
pub fn write_time(out: &mut String, us: i64) {
    use std::fmt::Write as _;
    if us == 0 {
        out.push_str("T#0s");
        return;
    }
    out.push_str("T#");
    if us < 0 {
        out.push('-');
    }
    let mut rest = us.unsigned_abs();
    const UNITS: [(u64, &str); 6] =
        [(86_400_000_000, "d"), (3_600_000_000, "h"), (60_000_000, "m"), (1_000_000, "s"), (1_000, "ms"), (1, "us")];
    for (size, unit) in UNITS {
        let n = rest / size;
        rest %= size;
        if n > 0 {
            let _ = write!(out, "{n}{unit}");
        }
    }
}

/// Parses a TIME literal as written in scenarios and on the command line (`T#1s500ms`,
/// `TIME#-2.5s`, `t#10ms`, `LTIME#1us`). `None` when it is not one or is finer than 1 µs.
pub fn parse_time(text: &str) -> Option<i64> {
    let t = text.trim();
    let (prefix, body) = t.split_once('#')?;
    if !["T", "TIME", "LT", "LTIME"].iter().any(|p| p.eq_ignore_ascii_case(prefix)) {
        return None;
    }
    sfc_syntax::literal::decode_duration(body, sfc_diagnostics::Span::default()).ok()
}

/// A TIME value displayed canonically.
pub struct TimeDisplay(pub i64);

impl fmt::Display for TimeDisplay {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&format_time(self.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonical_times() {
        assert_eq!(format_time(0), "T#0s");
        assert_eq!(format_time(1_500_000), "T#1s500ms");
        assert_eq!(format_time(2_500), "T#2ms500us");
        assert_eq!(format_time(-200_000), "T#-200ms");
        assert_eq!(format_time(90_061_001_001), "T#1d1h1m1s1ms1us");
        assert!(format_time(i64::MIN).len() > 3);
    }

    #[test]
    fn parses_literals() {
        assert_eq!(parse_time("T#1s500ms"), Some(1_500_000));
        assert_eq!(parse_time("t#-200ms"), Some(-200_000));
        assert_eq!(parse_time("TIME#2.5s"), Some(2_500_000));
        assert_eq!(parse_time("5s"), None);
        assert_eq!(parse_time("X#5s"), None);
    }
}
