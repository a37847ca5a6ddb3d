//! Decoding of literal tokens into values, with the IEC 61131-3 rules of seed 000 (underscores,
//! bases, `$` escapes, duration units, dates), reporting located errors.

use crate::ast::LiteralKind;
use sfc_diagnostics::{Diagnostic, Span};

/// Elementary type names that may prefix a literal (`INT#5`).
pub const ELEMENTARY_TYPES: &[&str] = &[
    "BOOL",
    "SINT",
    "INT",
    "DINT",
    "LINT",
    "USINT",
    "UINT",
    "UDINT",
    "ULINT",
    "BYTE",
    "WORD",
    "DWORD",
    "LWORD",
    "REAL",
    "LREAL",
    "TIME",
    "LTIME",
    "DATE",
    "LDATE",
    "TIME_OF_DAY",
    "TOD",
    "LTOD",
    "DATE_AND_TIME",
    "DT",
    "LDT",
    "STRING",
    "WSTRING",
    "CHAR",
    "WCHAR",
];

/// The result of decoding: the value, the upper-cased type prefix, or an error.
pub type Decoded = Result<(LiteralKind, Option<String>), Diagnostic>;

fn err(code: &'static str, span: Span, msg: impl Into<String>) -> Diagnostic {
    Diagnostic::error(code, span, msg)
}

/// Checks underscore placement: only single underscores between digits.
fn underscores_ok(s: &str) -> bool {
    !s.starts_with('_') && !s.ends_with('_') && !s.contains("__")
}

/// Decodes an unsigned integer (`123_456`, `2#1110_0000`, `16#e5`).
pub fn decode_int(text: &str, span: Span) -> Result<u128, Diagnostic> {
    let (radix, digits) = match text.split_once('#') {
        Some((base, digits)) => {
            let radix = match base {
                "2" => 2,
                "8" => 8,
                "16" => 16,
                _ => {
                    return Err(err(
                        "SFC0004",
                        span,
                        format!("invalid base `{base}`: IEC integers are based 2, 8 or 16"),
                    ))
                }
            };
            (radix, digits)
        }
        None => (10, text),
    };
    if digits.is_empty() || !underscores_ok(digits) {
        return Err(err("SFC0004", span, format!("invalid integer literal `{text}`: underscores only between digits")));
    }
    let mut value: u128 = 0;
    for c in digits.chars().filter(|&c| c != '_') {
        let d = c
            .to_digit(radix)
            .ok_or_else(|| err("SFC0004", span, format!("invalid digit `{c}` in base-{radix} literal `{text}`")))?;
        value = value * radix as u128 + d as u128;
        if value > u64::MAX as u128 {
            return Err(err("SFC0004", span, format!("integer literal `{text}` does not fit in 64 bits")));
        }
    }
    Ok(value)
}

/// Decodes a real literal (`3.14159_26`, `1.234e-6`).
pub fn decode_real(text: &str, span: Span) -> Result<f64, Diagnostic> {
    let mantissa_end = text.find(['e', 'E']).unwrap_or(text.len());
    let (int_part, frac_part) = text[..mantissa_end].split_once('.').unwrap_or((&text[..mantissa_end], "0"));
    if !underscores_ok(int_part) || !underscores_ok(frac_part) || int_part.is_empty() {
        return Err(err("SFC0004", span, format!("invalid real literal `{text}`: underscores only between digits")));
    }
    let clean: String = text.chars().filter(|&c| c != '_').collect();
    if text.chars().any(|c| c.is_ascii_alphabetic() && c != 'e' && c != 'E') {
        return Err(err("SFC0004", span, format!("invalid real literal `{text}`")));
    }
    clean.parse::<f64>().map_err(|_| err("SFC0004", span, format!("invalid real literal `{text}`")))
}

/// Decodes the body of a quoted string (quotes included in `text`).
pub fn decode_string(text: &str, span: Span) -> Result<String, Diagnostic> {
    let wide = text.starts_with('"');
    let quote = if wide { '"' } else { '\'' };
    let inner = text.strip_prefix(quote).and_then(|t| t.strip_suffix(quote)).unwrap_or(text);
    let mut out = String::new();
    let mut chars = inner.chars().peekable();
    let hex_len = if wide { 4 } else { 2 };
    while let Some(c) = chars.next() {
        if c != '$' {
            out.push(c);
            continue;
        }
        let Some(e) = chars.next() else {
            return Err(err("SFC0007", span, "`$` at the end of a string: write `$$` for a dollar sign"));
        };
        match e.to_ascii_uppercase() {
            '$' => out.push('$'),
            '\'' => out.push('\''),
            '"' => out.push('"'),
            'L' | 'N' => out.push('\n'),
            'P' => out.push('\x0c'),
            'R' => out.push('\r'),
            'T' => out.push('\t'),
            h if h.is_ascii_hexdigit() => {
                let mut code = String::from(h);
                for _ in 1..hex_len {
                    match chars.peek() {
                        Some(c) if c.is_ascii_hexdigit() => {
                            code.push(*c);
                            chars.next();
                        }
                        _ => {
                            return Err(err(
                                "SFC0007",
                                span,
                                format!("invalid escape `${code}`: a character code has {hex_len} hex digits"),
                            ))
                        }
                    }
                }
                let v = u32::from_str_radix(&code, 16).unwrap_or(0);
                out.push(char::from_u32(v).unwrap_or('\u{fffd}'));
            }
            _ => {
                return Err(err(
                    "SFC0007",
                    span,
                    format!("invalid escape `${e}` in string literal; valid are $$ $' $\" $L $N $P $R $T and $hh"),
                ))
            }
        }
    }
    Ok(out)
}

const US_PER: [(&str, i128); 7] = [
    ("D", 86_400_000_000),
    ("H", 3_600_000_000),
    ("M", 60_000_000),
    ("S", 1_000_000),
    ("MS", 1_000),
    ("US", 1),
    ("NS", 0),
];

/// Decodes the part of a duration after `T#` into microseconds.
pub fn decode_duration(body: &str, span: Span) -> Result<i64, Diagnostic> {
    let bad = |msg: String| err("SFC0005", span, msg);
    let (neg, rest) = match body.as_bytes().first() {
        Some(b'-') => (true, &body[1..]),
        Some(b'+') => (false, &body[1..]),
        _ => (false, body),
    };
    if rest.is_empty() {
        return Err(bad("empty duration: write e.g. `T#5s`".into()));
    }
    let upper = rest.to_ascii_uppercase();
    let bytes = upper.as_bytes();
    let mut i = 0;
    let mut total: i128 = 0;
    let mut last_rank: Option<usize> = None;
    let mut had_fraction = false;
    let at = |i: usize| bytes.get(i).copied().unwrap_or(0);
    while i < bytes.len() {
        if at(i) == b'_' {
            i += 1;
            continue;
        }
        let num_start = i;
        while at(i).is_ascii_digit() || at(i) == b'.' || at(i) == b'_' {
            i += 1;
        }
        let num = &upper[num_start..i];
        if num.is_empty() {
            return Err(bad(format!("invalid duration `T#{body}`: expected a number before a unit")));
        }
        let unit_start = i;
        while at(i).is_ascii_alphabetic() {
            i += 1;
        }
        let unit = &upper[unit_start..i];
        let Some((rank, &(_, scale))) = US_PER.iter().enumerate().find(|(_, (u, _))| *u == unit) else {
            let shown = &rest[unit_start..i];
            return Err(bad(format!("invalid duration `T#{body}`: unknown unit `{shown}` (use d, h, m, s, ms, us)")));
        };
        if had_fraction {
            return Err(bad(format!("invalid duration `T#{body}`: only the last unit may have a fraction")));
        }
        if let Some(prev) = last_rank {
            if rank <= prev {
                return Err(bad(format!(
                    "invalid duration `T#{body}`: units must go from largest to smallest, each once"
                )));
            }
        }
        last_rank = Some(rank);
        let (int_s, frac_s) = num.split_once('.').unwrap_or((num, ""));
        if int_s.is_empty() || int_s.contains("__") || (num.contains('.') && frac_s.is_empty()) {
            return Err(bad(format!("invalid number `{num}` in duration `T#{body}`")));
        }
        let int_v: i128 =
            int_s.replace('_', "").parse().map_err(|_| bad(format!("duration `T#{body}` is too large")))?;
        if unit == "NS" {
            // Nanoseconds: allowed only when they make whole microseconds.
            let frac_digits: String = frac_s.replace('_', "");
            if int_v % 1000 != 0 || frac_digits.chars().any(|c| c != '0') {
                return Err(bad(format!("duration `T#{body}` is finer than the 1 µs resolution of TIME")));
            }
            total += int_v / 1000;
        } else {
            total += int_v * scale;
            if !frac_s.is_empty() {
                had_fraction = true;
                let digits: String = frac_s.replace('_', "");
                if digits.len() > 18 {
                    return Err(bad(format!("too many fraction digits in duration `T#{body}`")));
                }
                let frac_v: i128 = digits.parse().unwrap_or(0);
                let denom = 10i128.pow(digits.len() as u32);
                let scaled = frac_v * scale;
                if scaled % denom != 0 {
                    return Err(bad(format!("duration `T#{body}` is finer than the 1 µs resolution of TIME")));
                }
                total += scaled / denom;
            }
        }
        if total > i64::MAX as i128 {
            return Err(bad(format!("duration `T#{body}` does not fit in TIME")));
        }
    }
    Ok(if neg { -(total as i64) } else { total as i64 })
}

/// Days from 1970-01-01 to a civil date (proleptic Gregorian).
pub fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = if y >= 0 { y } else { y - 399 } / 400;
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

fn days_in_month(y: i64, m: i64) -> i64 {
    match m {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if (y % 4 == 0 && y % 100 != 0) || y % 400 == 0 => 29,
        2 => 28,
        _ => 0,
    }
}

fn parse_date(s: &str, span: Span, whole: &str) -> Result<i64, Diagnostic> {
    let bad = || err("SFC0008", span, format!("invalid date in `{whole}`: expected year-month-day such as 2006-03-20"));
    let parts: Vec<&str> = s.split('-').collect();
    let [y, m, d] = parts.as_slice() else { return Err(bad()) };
    if parts.iter().any(|p| p.is_empty() || !p.chars().all(|c| c.is_ascii_digit())) {
        return Err(bad());
    }
    let y: i64 = y.parse().map_err(|_| bad())?;
    let m: i64 = m.parse().map_err(|_| bad())?;
    let d: i64 = d.parse().map_err(|_| bad())?;
    if !(1..=12).contains(&m) || d < 1 || d > days_in_month(y, m) {
        return Err(err("SFC0008", span, format!("`{whole}` is not a calendar date")));
    }
    Ok(days_from_civil(y, m, d))
}

fn parse_tod(s: &str, span: Span, whole: &str) -> Result<i64, Diagnostic> {
    let bad = || {
        err(
            "SFC0008",
            span,
            format!("invalid time of day in `{whole}`: expected hours:minutes:seconds such as 10:42:23.78"),
        )
    };
    let parts: Vec<&str> = s.split(':').collect();
    let [h, m, sec] = parts.as_slice() else { return Err(bad()) };
    let h: i64 = h.parse().map_err(|_| bad())?;
    let m: i64 = m.parse().map_err(|_| bad())?;
    let (sec_s, frac_s) = sec.split_once('.').unwrap_or((sec, ""));
    let sec: i64 = sec_s.parse().map_err(|_| bad())?;
    if !frac_s.chars().all(|c| c.is_ascii_digit()) || frac_s.len() > 6 {
        return Err(bad());
    }
    let frac_us: i64 = if frac_s.is_empty() { 0 } else { format!("{frac_s:0<6}").parse().map_err(|_| bad())? };
    if h > 23 || m > 59 || sec > 59 {
        return Err(err("SFC0008", span, format!("`{whole}` is not a valid time of day")));
    }
    Ok(((h * 60 + m) * 60 + sec) * 1_000_000 + frac_us)
}

/// Decodes a `PREFIX#rest` token.
pub fn decode_typed(text: &str, span: Span) -> Decoded {
    let Some((prefix_raw, rest)) = text.split_once('#') else {
        return Err(err("SFC0004", span, format!("invalid literal `{text}`")));
    };
    let prefix = prefix_raw.to_ascii_uppercase();
    match prefix.as_str() {
        "T" | "TIME" | "LT" | "LTIME" => {
            let p = if prefix.starts_with('L') { "LTIME" } else { "TIME" };
            Ok((LiteralKind::Duration(decode_duration(rest, span)?), Some(p.into())))
        }
        "D" | "DATE" | "LDATE" => Ok((LiteralKind::Date(parse_date(rest, span, text)?), Some("DATE".into()))),
        "TOD" | "TIME_OF_DAY" | "LTOD" => {
            Ok((LiteralKind::TimeOfDay(parse_tod(rest, span, text)?), Some("TIME_OF_DAY".into())))
        }
        "DT" | "DATE_AND_TIME" | "LDT" => {
            // `2006-03-20-10:42:23.78`: the date is the first three dash-separated fields.
            let mut idx = None;
            let mut dashes = 0;
            for (i, c) in rest.char_indices() {
                if c == '-' {
                    dashes += 1;
                    if dashes == 3 {
                        idx = Some(i);
                        break;
                    }
                }
            }
            let Some(i) = idx else {
                return Err(err(
                    "SFC0008",
                    span,
                    format!("invalid date and time `{text}`: expected 2006-03-20-10:42:23.78"),
                ));
            };
            let days = parse_date(&rest[..i], span, text)?;
            let tod = parse_tod(&rest[i + 1..], span, text)?;
            Ok((LiteralKind::DateAndTime(days * 86_400_000_000 + tod), Some("DATE_AND_TIME".into())))
        }
        p if ELEMENTARY_TYPES.contains(&p) => {
            let (neg, body) = match rest.as_bytes().first() {
                Some(b'-') => (true, &rest[1..]),
                Some(b'+') => (false, &rest[1..]),
                _ => (false, rest),
            };
            let kind = if body.starts_with('\'') || body.starts_with('"') {
                if !matches!(p, "STRING" | "WSTRING" | "CHAR" | "WCHAR") {
                    return Err(err("SFC0004", span, format!("`{p}#` cannot prefix a string")));
                }
                LiteralKind::String { value: decode_string(body, span)?, wide: body.starts_with('"') }
            } else if p == "BOOL" {
                match body.to_ascii_uppercase().as_str() {
                    "TRUE" | "1" => LiteralKind::Bool(true),
                    "FALSE" | "0" => LiteralKind::Bool(false),
                    _ => {
                        return Err(err(
                            "SFC0004",
                            span,
                            format!("invalid BOOL literal `{text}`: use TRUE, FALSE, 1 or 0"),
                        ))
                    }
                }
            } else if body.contains('.') || (!body.contains('#') && body.contains(['e', 'E'])) {
                let v = decode_real(body, span)?;
                LiteralKind::Real(if neg { -v } else { v })
            } else {
                let v = decode_int(body, span)? as i128;
                LiteralKind::Int(if neg { -v } else { v })
            };
            Ok((kind, Some(p.to_string())))
        }
        _ => {
            if rest.is_empty() || !rest.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(err("SFC0004", span, format!("invalid typed literal `{text}`")));
            }
            let start = span.start + prefix_raw.len() as u32 + 1;
            let ident = crate::ast::Ident::new(rest, Span::new(span.file, start, span.end));
            Ok((LiteralKind::Enum(ident), Some(prefix_raw.to_string())))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    const S: Span = Span { file: 0, start: 0, end: 0 };

    #[test]
    fn seed_000_numbers() {
        assert_eq!(decode_int("123_456", S).unwrap(), 123456);
        // Seed 000 says 240; 2#1110_0000 is 224 (128 + 64 + 32).
        assert_eq!(decode_int("2#1110_0000", S).unwrap(), 224);
        assert_eq!(decode_int("8#377", S).unwrap(), 255);
        assert_eq!(decode_int("16#e5", S).unwrap(), 229);
        assert!(decode_int("2#102", S).is_err());
        assert!(decode_int("1__0", S).is_err());
        assert_eq!(decode_real("3.14159_26", S).unwrap(), "3.1415926".parse::<f64>().unwrap());
        assert_eq!(decode_real("1.234e-6", S).unwrap(), 1.234e-6);
    }

    #[test]
    fn seed_000_strings() {
        assert_eq!(decode_string("'$''", S).unwrap(), "'");
        assert_eq!(decode_string("'$R$L'", S).unwrap(), "\r\n");
        assert_eq!(decode_string("'$$1.00'", S).unwrap(), "$1.00");
        assert_eq!(decode_string("'$0A'", S).unwrap(), "\n");
        assert_eq!(decode_string("\"$0041\"", S).unwrap(), "A");
        assert!(decode_string("'$Q'", S).is_err());
    }

    #[test]
    fn seed_000_durations() {
        let us = |s: &str| decode_typed(s, S).map(|(k, _)| k);
        assert_eq!(
            us("T#5d14h12m18s3.5ms").unwrap(),
            LiteralKind::Duration(((((5 * 24 + 14) * 60 + 12) * 60 + 18) * 1000 + 3) * 1000 + 500)
        );
        assert_eq!(us("TIME#14.7h").unwrap(), LiteralKind::Duration(52_920_000_000));
        assert_eq!(us("time#25h15m").unwrap(), LiteralKind::Duration((25 * 60 + 15) * 60_000_000));
        assert_eq!(us("T#-200ms").unwrap(), LiteralKind::Duration(-200_000));
        assert!(us("T#1.5h3m").is_err());
        assert!(us("T#5x").is_err());
        assert!(us("T#1s1h").is_err());
        assert!(us("T#0.5us").is_err());
    }

    #[test]
    fn seed_000_dates() {
        let v = |s: &str| decode_typed(s, S).map(|(k, _)| k);
        assert_eq!(v("D#1970-01-02").unwrap(), LiteralKind::Date(1));
        assert!(v("DATE#2006-03-20").is_ok());
        assert_eq!(v("TOD#10:42:23.78").unwrap(), LiteralKind::TimeOfDay(38_543_780_000));
        assert!(v("DT#2006-03-20-10:42:23.78").is_ok());
        assert!(v("D#2006-13-40").is_err());
        assert_eq!(v("UINT#16#FE").unwrap(), LiteralKind::Int(254));
        assert_eq!(v("BOOL#1").unwrap(), LiteralKind::Bool(true));
        assert!(matches!(v("Colour#Red").unwrap(), LiteralKind::Enum(_)));
    }
}
