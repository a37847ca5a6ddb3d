//! Reading a numeric term's value back from the truth values of its thresholds.
//!
//! The thresholds of a term, sorted, are linked by the chain `t[i+1] → t[i]` (a term at least
//! 6 is at least 3), so a satisfying valuation makes a prefix of them true: the term lies in
//! the region between the highest true threshold and the lowest false one. Thresholds at or
//! below the type's lowest value are TRUE and those above its highest are FALSE when the guard
//! is translated, so every region of an integer-valued term holds at least one value of its
//! type. The witness takes the value of the region closest to zero (`x > 5` gives 6,
//! `S.T < T#5s` gives `T#0s`).

use super::translate::{NumKind, NumVar, Thr};
use serde_json::Value;

/// The witness value of `nv` given its thresholds (sorted ascending) with their truth values.
pub(super) fn value_of(nv: &NumVar, ts: &[(Thr, bool)]) -> Value {
    let lower_idx = ts.iter().rposition(|(_, v)| *v);
    let lower = lower_idx.and_then(|i| ts.get(i)).map(|(t, _)| *t);
    let upper = match lower_idx {
        Some(i) => ts.iter().skip(i + 1).find(|(_, v)| !*v).map(|(t, _)| *t),
        None => ts.first().map(|(t, _)| *t),
    };
    match &nv.kind {
        NumKind::Real => real_json(real_value(lower, upper)),
        kind => {
            let mut a = nv.lo;
            let mut b = nv.hi;
            if let Some(Thr::Int(k)) = lower {
                a = a.max(k);
            }
            if let Some(Thr::Int(k)) = upper {
                b = b.min(k.saturating_sub(1));
            }
            let v = if a <= b { 0i128.clamp(a, b) } else { a };
            match kind {
                NumKind::Time => match i64::try_from(v) {
                    Ok(us) => Value::String(sfc_sim::format_time(us)),
                    Err(_) => Value::String(v.to_string()),
                },
                NumKind::Enum(names) => match usize::try_from(v).ok().and_then(|i| names.get(i)) {
                    Some(n) => Value::String(n.clone()),
                    None => Value::String(v.to_string()),
                },
                _ => int_json(v),
            }
        }
    }
}

fn int_json(v: i128) -> Value {
    if let Ok(x) = i64::try_from(v) {
        Value::from(x)
    } else if let Ok(x) = u64::try_from(v) {
        Value::from(x)
    } else {
        Value::String(v.to_string())
    }
}

fn real_json(v: f64) -> Value {
    match serde_json::Number::from_f64(v) {
        Some(n) => Value::Number(n),
        None => Value::String(v.to_string()),
    }
}

/// A value of a REAL term in the region above `lower` and below `upper`, closest to zero.
/// `Real(c, false)` true means `v >= c` (closed), `Real(c, true)` true means `v > c` (open);
/// as an upper bound (false) they mean `v < c` (open) and `v <= c` (closed).
fn real_value(lower: Option<Thr>, upper: Option<Thr>) -> f64 {
    let lo = match lower {
        Some(Thr::Real(c, strict)) => Some((c, strict)),
        _ => None,
    };
    let hi = match upper {
        // `v > d` false: `v <= d`, a closed bound; `v >= d` false: `v < d`, open.
        Some(Thr::Real(d, strict)) => Some((d, !strict)),
        _ => None,
    };
    let zero_above_lo = match lo {
        None => true,
        Some((c, open)) => {
            if open {
                c < 0.0
            } else {
                c <= 0.0
            }
        }
    };
    let zero_below_hi = match hi {
        None => true,
        Some((d, closed)) => {
            if closed {
                0.0 <= d
            } else {
                0.0 < d
            }
        }
    };
    if zero_above_lo && zero_below_hi {
        return 0.0;
    }
    if !zero_above_lo {
        // The region lies above zero: its lower end.
        let (c, open) = lo.unwrap_or((0.0, false));
        if !open {
            return c;
        }
        return match hi {
            Some((d, _)) => c + (d - c) / 2.0,
            None => step_up(c),
        };
    }
    // The region lies below zero: its upper end.
    let (d, closed) = hi.unwrap_or((0.0, true));
    if closed {
        return d;
    }
    match lo {
        Some((c, _)) => c + (d - c) / 2.0,
        None => -step_up(-d),
    }
}

/// A number above `c` (`c + 1` unless that rounds back to `c`).
fn step_up(c: f64) -> f64 {
    let n = c + 1.0;
    if n > c {
        n
    } else {
        c * 2.0
    }
}
