//! MatIEC's TIME (`IEC_TIMESPEC`, `lib/C/iec_std_lib.h`) for the `matiec` profile: seconds and
//! nanoseconds, compared field by field (`__time_cmp`), added and subtracted with a
//! normalisation that carries only when the nanoseconds pass ±10⁹ strictly (so a sum of exactly
//! one second stays `{0 s, 10⁹ ns}`, which compares below `{1 s, 0 ns}`), and literals converted
//! by the `__time_to_timespec` macro in x86-64 `long double` arithmetic (64-bit mantissa), which
//! truncates `T#4ms` to 3 999 999 ns.
//!
//! Under the `matiec` profile a TIME value in simulator memory is a [`Timespec`] packed into the
//! `i64` of `Value::Time` ([`Timespec::pack`]): the packing preserves the order of `__time_cmp`,
//! so compiled comparisons stay integer comparisons, and the boundaries (traces, scenarios)
//! unpack it to microseconds.

use std::cmp::Ordering;

/// `IEC_TIMESPEC`: `tv_sec`, `tv_nsec` as MatIEC keeps them (not always normalised).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Timespec {
    pub sec: i64,
    pub nsec: i64,
}

const NS: i64 = 1_000_000_000;
/// Packing: `sec · 2³² + nsec`, `nsec` within ±2³¹ (it stays within ±2·10⁹ for every value
/// MatIEC's normalisation produces from normalised operands), so `T#0s` packs to 0.
const HALF: i64 = 1 << 31;

impl Ord for Timespec {
    /// `__time_cmp`: seconds first, then nanoseconds.
    fn cmp(&self, other: &Self) -> Ordering {
        self.sec.cmp(&other.sec).then(self.nsec.cmp(&other.nsec))
    }
}
impl PartialOrd for Timespec {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Timespec {
    pub const ZERO: Timespec = Timespec { sec: 0, nsec: 0 };

    /// A whole number of microseconds, normalised (how a driver hands over `__CURRENT_TIME`).
    pub fn from_us(us: i64) -> Timespec {
        Timespec { sec: us / 1_000_000, nsec: (us % 1_000_000) * 1000 }
    }
    /// Microseconds, truncated toward zero (the trace shows µs).
    pub fn to_us(self) -> i64 {
        let ns = i128::from(self.sec) * i128::from(NS) + i128::from(self.nsec);
        (ns / 1000).clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64
    }

    /// `__normalize_timespec`: one carry step, only past ±10⁹ ns (strictly), or when the signs
    /// of the two fields differ.
    fn normalize(mut self) -> Timespec {
        if self.nsec < -NS || (self.sec > 0 && self.nsec < 0) {
            self.sec -= 1;
            self.nsec += NS;
        }
        if self.nsec > NS || (self.sec < 0 && self.nsec > 0) {
            self.sec += 1;
            self.nsec -= NS;
        }
        self
    }
    /// `__time_add`.
    pub fn add(self, o: Timespec) -> Timespec {
        Timespec { sec: self.sec.wrapping_add(o.sec), nsec: self.nsec + o.nsec }.normalize()
    }
    /// `__time_sub`.
    pub fn sub(self, o: Timespec) -> Timespec {
        Timespec { sec: self.sec.wrapping_sub(o.sec), nsec: self.nsec - o.nsec }.normalize()
    }
    /// `__time_mul(t, k)` with an LREAL factor.
    pub fn mul(self, k: f64) -> Timespec {
        let s_f = self.sec as f64 * k;
        let s = s_f as i64;
        let ns = ((self.nsec as f64 * k) as i32) as i64;
        let (quot, rem) = (ns / NS, ns % NS);
        Timespec { sec: s + quot, nsec: (rem as f64 + (s_f - s as f64) * NS as f64) as i64 }.normalize()
    }
    /// `__time_div(t, k)` with an LREAL divisor.
    pub fn div(self, k: f64) -> Timespec {
        let s_f = self.sec as f64 / k;
        let s = s_f as i64;
        Timespec { sec: s, nsec: (self.nsec as f64 / k + (s_f - s as f64) * NS as f64) as i64 }.normalize()
    }

    /// The `i64` held in a `Value::Time` slot under the `matiec` profile.
    pub fn pack(self) -> i64 {
        let nsec = self.nsec.clamp(-HALF, HALF - 1);
        self.sec.wrapping_shl(32).wrapping_add(nsec)
    }
    /// The inverse of [`Timespec::pack`].
    pub fn unpack(v: i64) -> Timespec {
        let sec = v.wrapping_add(HALF) >> 32;
        Timespec { sec, nsec: v.wrapping_sub(sec.wrapping_shl(32)) }
    }

    /// What `__time_to_timespec(sign, ms, s, m, h, d)` gives for a TIME literal as written
    /// (`T#4ms`, `TIME#1.5s`, `t#1h_30m`): `None` when the text is not a duration MatIEC reads
    /// (for example one with `us`).
    pub fn from_literal(text: &str) -> Option<Timespec> {
        let body = match text.split_once('#') {
            Some((prefix, body)) if ["T", "TIME", "LT", "LTIME"].iter().any(|p| p.eq_ignore_ascii_case(prefix)) => body,
            _ => return None,
        };
        let (neg, body) = match body.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, body),
        };
        // days, hours, minutes, seconds, milliseconds as the C source gets them.
        let mut fields: [Option<f64>; 5] = [None; 5];
        let lower: String = body.chars().filter(|&c| c != '_').collect::<String>().to_ascii_lowercase();
        let b = lower.as_bytes();
        let mut i = 0;
        let mut last = None;
        while i < b.len() {
            let start = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            if start == i {
                return None;
            }
            let number: f64 = lower[start..i].parse().ok()?;
            let ustart = i;
            while i < b.len() && b[i].is_ascii_alphabetic() {
                i += 1;
            }
            let k = match &lower[ustart..i] {
                "d" => 0,
                "h" => 1,
                "m" => 2,
                "s" => 3,
                "ms" => 4,
                _ => return None,
            };
            if last.is_some_and(|l| l >= k) || fields[k].is_some() {
                return None;
            }
            last = Some(k);
            fields[k] = Some(number);
        }
        last?;
        let [d, h, m, s, ms] = fields.map(|f| Ext::from_f64(f.unwrap_or(0.0)));
        // ((((d*24 + h)*60 + m)*60 + s) + ms/1e3), each operation rounded to 64 bits.
        let total = d.mul_int(24).add(h).mul_int(60).add(m).mul_int(60).add(s).add(ms.div_int(1000));
        let (int, frac) = total.split();
        let nsec = frac.mul_int(1_000_000_000).trunc();
        let (sec, nsec) = (int as i64, nsec as i64);
        Some(if neg { Timespec { sec: -sec, nsec: -nsec } } else { Timespec { sec, nsec } })
    }
}

/// A non-negative x87 extended value: `m · 2^e` with a 64-bit mantissa (top bit set unless
/// zero); every operation rounds to nearest, ties to even, like the FPU and GCC's folding.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Ext {
    m: u64,
    e: i32,
}

impl Ext {
    fn from_f64(x: f64) -> Ext {
        if x == 0.0 || !x.is_finite() || x < 0.0 {
            return Ext { m: 0, e: 0 };
        }
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7FF) as i32;
        let frac = bits & ((1 << 52) - 1);
        let (m, e) = if exp == 0 { (frac, -1074) } else { (frac | (1 << 52), exp - 1075) };
        Ext::round(u128::from(m), e, false)
    }

    /// Rounds `q · 2^e` (plus a sticky bit below `q`) to 64 bits.
    fn round(q: u128, e: i32, sticky: bool) -> Ext {
        if q == 0 {
            return Ext { m: 0, e: 0 };
        }
        let bits = 128 - q.leading_zeros() as i32;
        if bits <= 64 {
            let shift = 64 - bits;
            return Ext { m: (q << shift) as u64, e: e - shift };
        }
        let s = bits - 64;
        let mut m = q >> s;
        let rem = q & ((1u128 << s) - 1);
        let half = 1u128 << (s - 1);
        let up = rem > half || (rem == half && (sticky || m & 1 == 1));
        if up {
            m += 1;
        }
        let mut e = e + s;
        if m >> 64 != 0 {
            m >>= 1;
            e += 1;
        }
        Ext { m: m as u64, e }
    }

    fn mul_int(self, k: u64) -> Ext {
        Ext::round(u128::from(self.m) * u128::from(k), self.e, false)
    }

    fn div_int(self, k: u64) -> Ext {
        if self.m == 0 {
            return self;
        }
        let n = u128::from(self.m) << 64;
        let (q, r) = (n / u128::from(k), n % u128::from(k));
        Ext::round(q, self.e - 64, r != 0)
    }

    fn add(self, o: Ext) -> Ext {
        if self.m == 0 {
            return o;
        }
        if o.m == 0 {
            return self;
        }
        let (hi, lo) = if self.e >= o.e { (self, o) } else { (o, self) };
        let d = hi.e - lo.e;
        if d <= 63 {
            let sum = (u128::from(hi.m) << d) + u128::from(lo.m);
            Ext::round(sum, lo.e, false)
        } else {
            let cut = d - 63;
            let (kept, sticky) = if cut >= 64 { (0, true) } else { (lo.m >> cut, lo.m & ((1u64 << cut) - 1) != 0) };
            let sum = (u128::from(hi.m) << 63) + u128::from(kept);
            Ext::round(sum, hi.e - 63, sticky)
        }
    }

    /// Integer part (as C's cast to `long`) and the exact fractional part.
    fn split(self) -> (u64, Ext) {
        if self.e >= 0 {
            return (self.m.checked_shl(self.e as u32).unwrap_or(u64::MAX), Ext { m: 0, e: 0 });
        }
        let s = -self.e;
        if s >= 64 {
            return (0, self);
        }
        let int = self.m >> s;
        let frac = self.m & ((1u64 << s) - 1);
        (int, Ext::round(u128::from(frac), self.e, false))
    }

    /// Truncation toward zero.
    fn trunc(self) -> u64 {
        self.split().0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_as_matiec_computes_them() {
        // Checked against gcc on x86-64 (`__time_to_timespec` with the same arguments).
        assert_eq!(Timespec::from_literal("T#4ms"), Some(Timespec { sec: 0, nsec: 3_999_999 }));
        assert_eq!(Timespec::from_literal("T#1s"), Some(Timespec { sec: 1, nsec: 0 }));
        assert_eq!(Timespec::from_literal("T#1.5s"), Some(Timespec { sec: 1, nsec: 500_000_000 }));
        assert_eq!(Timespec::from_literal("T#0s"), Some(Timespec::ZERO));
        assert_eq!(Timespec::from_literal("T#2us"), None);
        assert_eq!(Timespec::from_literal("T#-4ms"), Some(Timespec { sec: 0, nsec: -3_999_999 }));
    }

    #[test]
    fn whole_seconds_are_not_carried() {
        let t = Timespec { sec: 0, nsec: 990_000_000 }.add(Timespec::from_us(10_000));
        assert_eq!(t, Timespec { sec: 0, nsec: 1_000_000_000 });
        assert!(t < Timespec { sec: 1, nsec: 0 });
        assert_eq!(t.add(Timespec::from_us(10_000)), Timespec { sec: 1, nsec: 10_000_000 });
    }

    #[test]
    fn packing_keeps_the_order() {
        let vals = [
            Timespec { sec: 0, nsec: 999_999_999 },
            Timespec { sec: 0, nsec: 1_000_000_000 },
            Timespec { sec: 1, nsec: 0 },
            Timespec { sec: -1, nsec: -5 },
            Timespec { sec: 3, nsec: 7 },
        ];
        for a in vals {
            assert_eq!(Timespec::unpack(a.pack()), a);
            for b in vals {
                assert_eq!(a.cmp(&b), a.pack().cmp(&b.pack()), "{a:?} {b:?}");
            }
        }
    }
}

#[cfg(test)]
mod gcc_check {
    /// Prints `literal sec nsec` for a list of literals (compare with the C program beside the
    /// MatIEC harness when MATIEC_LITERALS=1).
    #[test]
    fn print_literals() {
        if std::env::var("MATIEC_LITERALS").is_err() {
            return;
        }
        for lit in super::tests_literals() {
            let t = super::Timespec::from_literal(&lit).unwrap();
            println!("{lit} {} {}", t.sec, t.nsec);
        }
    }
}

#[cfg(test)]
fn tests_literals() -> Vec<String> {
    let mut out = Vec::new();
    for ms in 0..2000 {
        out.push(format!("T#{ms}ms"));
    }
    for cs in 0..300 {
        out.push(format!("T#{}.{:02}s", cs / 100, cs % 100));
    }
    for x in ["T#1h30m", "T#2m15.5s", "T#1d2h3m4s5ms", "T#0.1s", "T#0.3s", "T#2.7ms", "T#59.999s", "T#1.001s"] {
        out.push(x.to_string());
    }
    out
}
