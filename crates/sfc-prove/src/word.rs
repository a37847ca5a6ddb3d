//! Bit-vectors of AIG literals (least significant bit first) and the integer operations of
//! IEC 61131-3 on them: two's-complement wrap in the width, truncating division, signed and
//! unsigned comparisons. Constants fold through the graph, so arithmetic with literals costs
//! little.

use crate::aig::{Aig, Lit};

/// A bit-vector; its width is `bits.len()`. Whether it is signed is the caller's business.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Word {
    pub bits: Vec<Lit>,
}

impl Word {
    pub fn width(&self) -> usize {
        self.bits.len()
    }

    /// The constant `v` in `w` bits (two's complement, low bits kept).
    pub fn constant(v: i128, w: usize) -> Word {
        Word { bits: (0..w).map(|i| Lit::from_bool(i < 128 && (v >> i) & 1 == 1)).collect() }
    }

    pub fn from_bit(b: Lit, w: usize) -> Word {
        let mut bits = vec![Lit::FALSE; w.max(1)];
        bits[0] = b;
        Word { bits }
    }

    /// The value when every bit is constant (`signed`: the top bit is the sign).
    pub fn as_const(&self, signed: bool) -> Option<i128> {
        let mut v: i128 = 0;
        for (i, b) in self.bits.iter().enumerate() {
            if b.as_const()? && i < 127 {
                v |= 1 << i;
            }
        }
        let w = self.bits.len();
        if signed && w > 0 && w < 128 && (v >> (w - 1)) & 1 == 1 {
            v -= 1 << w;
        }
        Some(v)
    }

    /// Sign or zero extension, or truncation, to `w` bits.
    pub fn resize(&self, w: usize, signed: bool) -> Word {
        let mut bits = self.bits.clone();
        if bits.len() >= w {
            bits.truncate(w);
        } else {
            let fill = if signed { bits.last().copied().unwrap_or(Lit::FALSE) } else { Lit::FALSE };
            bits.resize(w, fill);
        }
        Word { bits }
    }

    /// The range of values the word can hold given its constant bits (a cheap bound).
    pub fn bounds(&self, signed: bool) -> (i128, i128) {
        let w = self.bits.len().min(126);
        if w == 0 {
            return (0, 0);
        }
        let mut lo: i128 = 0;
        let mut hi: i128 = 0;
        for i in 0..w {
            match self.bits[i].as_const() {
                Some(true) => {
                    if signed && i == w - 1 {
                        lo -= 1 << i;
                        hi -= 1 << i;
                    } else {
                        lo += 1 << i;
                        hi += 1 << i;
                    }
                }
                Some(false) => {}
                None => {
                    if signed && i == w - 1 {
                        lo -= 1 << i;
                    } else {
                        hi += 1 << i;
                    }
                }
            }
        }
        (lo, hi)
    }
}

/// Operations on words, all in the width of their operands (which must agree).
pub struct Ops<'a> {
    pub g: &'a mut Aig,
}

impl Ops<'_> {
    pub fn not(&mut self, a: &Word) -> Word {
        Word { bits: a.bits.iter().map(|&b| b.not()).collect() }
    }

    pub fn bitwise(&mut self, a: &Word, b: &Word, f: impl Fn(&mut Aig, Lit, Lit) -> Lit) -> Word {
        Word { bits: a.bits.iter().zip(&b.bits).map(|(&x, &y)| f(self.g, x, y)).collect() }
    }

    pub fn ite(&mut self, c: Lit, t: &Word, e: &Word) -> Word {
        if let Some(k) = c.as_const() {
            return if k { t.clone() } else { e.clone() };
        }
        Word { bits: t.bits.iter().zip(&e.bits).map(|(&x, &y)| self.g.ite(c, x, y)).collect() }
    }

    /// `a + b + cin`, wrapping.
    pub fn add_carry(&mut self, a: &Word, b: &Word, cin: Lit) -> Word {
        let mut c = cin;
        let mut out = Vec::with_capacity(a.width());
        for (&x, &y) in a.bits.iter().zip(&b.bits) {
            let s = self.g.xor(x, y);
            let sum = self.g.xor(s, c);
            let c1 = self.g.and(x, y);
            let c2 = self.g.and(s, c);
            c = self.g.or(c1, c2);
            out.push(sum);
        }
        Word { bits: out }
    }

    pub fn add(&mut self, a: &Word, b: &Word) -> Word {
        self.add_carry(a, b, Lit::FALSE)
    }

    pub fn sub(&mut self, a: &Word, b: &Word) -> Word {
        let nb = self.not(b);
        self.add_carry(a, &nb, Lit::TRUE)
    }

    pub fn neg(&mut self, a: &Word) -> Word {
        let z = Word::constant(0, a.width());
        self.sub(&z, a)
    }

    /// `a · b`, wrapping (shift and add; cheap when `b` has constant bits).
    pub fn mul(&mut self, a: &Word, b: &Word) -> Word {
        let w = a.width();
        let (a, b) = if b.as_const(false).is_none() && a.as_const(false).is_some() { (b, a) } else { (a, b) };
        let mut acc = Word::constant(0, w);
        for i in 0..w {
            let bi = b.bits[i];
            if bi == Lit::FALSE {
                continue;
            }
            let mut shifted = vec![Lit::FALSE; i];
            shifted.extend(a.bits.iter().take(w - i).map(|&x| self.g.and(x, bi)));
            acc = self.add(&acc, &Word { bits: shifted });
        }
        acc
    }

    /// Unsigned `a < b`.
    pub fn ult(&mut self, a: &Word, b: &Word) -> Lit {
        // From the least significant bit: lt = (¬a ∧ b) ∨ (¬(a ⊕ b) ∧ lt_below).
        let mut lt = Lit::FALSE;
        for (&x, &y) in a.bits.iter().zip(&b.bits) {
            let here = self.g.and(x.not(), y);
            let same = self.g.xnor(x, y);
            let keep = self.g.and(same, lt);
            lt = self.g.or(here, keep);
        }
        lt
    }

    /// Signed `a < b`.
    pub fn slt(&mut self, a: &Word, b: &Word) -> Lit {
        let w = a.width();
        if w == 0 {
            return Lit::FALSE;
        }
        let mut a2 = a.clone();
        let mut b2 = b.clone();
        a2.bits[w - 1] = a.bits[w - 1].not();
        b2.bits[w - 1] = b.bits[w - 1].not();
        self.ult(&a2, &b2)
    }

    pub fn lt(&mut self, a: &Word, b: &Word, signed: bool) -> Lit {
        if signed {
            self.slt(a, b)
        } else {
            self.ult(a, b)
        }
    }

    pub fn eq(&mut self, a: &Word, b: &Word) -> Lit {
        let mut acc = Lit::TRUE;
        for (&x, &y) in a.bits.iter().zip(&b.bits) {
            let e = self.g.xnor(x, y);
            acc = self.g.and(acc, e);
        }
        acc
    }

    /// Unsigned division and remainder (restoring); division by zero gives all ones and `a`.
    pub fn udivrem(&mut self, a: &Word, b: &Word) -> (Word, Word) {
        let w = a.width();
        // Leading bits that are 0 in both operands do not take part.
        let used = |x: &Word| x.bits.iter().rposition(|l| *l != Lit::FALSE).map_or(0, |p| p + 1);
        let k = used(a).max(used(b)).max(1);
        if k < w {
            let (q, r) = self.udivrem(&a.resize(k, false), &b.resize(k, false));
            return (q.resize(w, false), r.resize(w, false));
        }
        let mut rem = Word::constant(0, w);
        let mut q = vec![Lit::FALSE; w];
        // Extended remainder has w+1 bits to hold the shifted value.
        let bx = b.resize(w + 1, false);
        for i in (0..w).rev() {
            let mut r = rem.resize(w + 1, false);
            r.bits.insert(0, a.bits[i]);
            r.bits.truncate(w + 1);
            let lt = self.ult(&r, &bx);
            let ge = lt.not();
            let diff = self.sub(&r, &bx);
            let nr = self.ite(ge, &diff, &r);
            rem = nr.resize(w, false);
            q[i] = ge;
        }
        (Word { bits: q }, rem)
    }

    /// Signed division truncating toward zero and the remainder with the dividend's sign.
    pub fn sdivrem(&mut self, a: &Word, b: &Word) -> (Word, Word) {
        let w = a.width();
        let sa = a.bits[w - 1];
        let sb = b.bits[w - 1];
        let na = self.neg(a);
        let nb = self.neg(b);
        let ua = self.ite(sa, &na, a);
        let ub = self.ite(sb, &nb, b);
        let (q, r) = self.udivrem(&ua, &ub);
        let sq = self.g.xor(sa, sb);
        let nq = self.neg(&q);
        let nr = self.neg(&r);
        let q = self.ite(sq, &nq, &q);
        let r = self.ite(sa, &nr, &r);
        (q, r)
    }

    pub fn is_zero(&mut self, a: &Word) -> Lit {
        let any = self.g.or_all(a.bits.iter().copied());
        any.not()
    }

    /// Shift left by a constant.
    pub fn shl(&mut self, a: &Word, n: usize) -> Word {
        let w = a.width();
        let mut bits = vec![Lit::FALSE; n.min(w)];
        bits.extend(a.bits.iter().take(w.saturating_sub(n)));
        Word { bits }
    }

    /// Logical shift right by a constant.
    pub fn shr(&mut self, a: &Word, n: usize) -> Word {
        let w = a.width();
        let mut bits: Vec<Lit> = a.bits.iter().skip(n).copied().collect();
        bits.resize(w, Lit::FALSE);
        Word { bits }
    }

    /// Shift by a symbolic amount (barrel shifter): left when `left`, else logical right.
    pub fn shift(&mut self, a: &Word, n: &Word, left: bool) -> Word {
        let w = a.width();
        let mut cur = a.clone();
        for (k, &bit) in n.bits.iter().enumerate() {
            let amount = if k < 20 { 1usize << k } else { usize::MAX };
            let shifted = if amount >= w {
                Word::constant(0, w)
            } else if left {
                self.shl(&cur, amount)
            } else {
                self.shr(&cur, amount)
            };
            cur = self.ite(bit, &shifted, &cur);
        }
        cur
    }

    /// Rotation by a constant (left when `left`).
    pub fn rotate(&mut self, a: &Word, n: usize, left: bool) -> Word {
        let w = a.width();
        if w == 0 {
            return a.clone();
        }
        let n = n % w;
        let k = if left { w - n } else { n };
        let bits = (0..w).map(|i| a.bits[(i + k) % w]).collect();
        Word { bits }
    }

    /// `lo ≤ a ≤ hi` for a word read as signed or unsigned.
    pub fn in_range(&mut self, a: &Word, signed: bool, lo: i128, hi: i128) -> Lit {
        let w = a.width();
        let (blo, bhi) = a.bounds(signed);
        let ge = if blo >= lo {
            Lit::TRUE
        } else {
            let c = Word::constant(lo, w);
            self.lt(a, &c, signed).not()
        };
        let le = if bhi <= hi {
            Lit::TRUE
        } else {
            let c = Word::constant(hi, w);
            self.lt(&c, a, signed).not()
        };
        self.g.and(ge, le)
    }
}

/// Bits needed to hold every value of `lo..=hi` (two's complement when `lo < 0`).
pub fn bits_for(lo: i128, hi: i128) -> usize {
    if lo >= 0 {
        let mut w = 1;
        while w < 127 && (1i128 << w) <= hi {
            w += 1;
        }
        w
    } else {
        let mut w = 1;
        while w < 127 && (-(1i128 << (w - 1)) > lo || (1i128 << (w - 1)) - 1 < hi) {
            w += 1;
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(g: &Aig, w: &Word, signed: bool) -> i128 {
        let t = g.eval_all(&[]);
        let bits: Vec<Lit> = w.bits.iter().map(|&l| Lit::from_bool(Aig::value(&t, l))).collect();
        Word { bits }.as_const(signed).unwrap()
    }

    #[test]
    fn arithmetic_on_constants_matches_i8() {
        let mut g = Aig::new();
        for &(x, y) in &[(5i128, 3i128), (-128, -1), (100, 100), (-7, 2), (7, -2), (0, 5), (-1, -1)] {
            let a = Word::constant(x, 8);
            let b = Word::constant(y, 8);
            let mut o = Ops { g: &mut g };
            let s = o.add(&a, &b);
            let d = o.sub(&a, &b);
            let m = o.mul(&a, &b);
            let (q, r) = o.sdivrem(&a, &b);
            let lt = o.slt(&a, &b);
            let (xs, ys) = (x as i8, y as i8);
            assert_eq!(eval(&g, &s, true), xs.wrapping_add(ys) as i128);
            assert_eq!(eval(&g, &d, true), xs.wrapping_sub(ys) as i128);
            assert_eq!(eval(&g, &m, true), xs.wrapping_mul(ys) as i128);
            assert_eq!(eval(&g, &q, true), xs.wrapping_div(ys) as i128);
            assert_eq!(eval(&g, &r, true), xs.wrapping_rem(ys) as i128);
            assert_eq!(lt.as_const(), Some(xs < ys));
        }
    }

    #[test]
    fn widths() {
        assert_eq!(bits_for(0, 1), 1);
        assert_eq!(bits_for(0, 100), 7);
        assert_eq!(bits_for(0, 1000), 10);
        assert_eq!(bits_for(-1, 0), 1);
        assert_eq!(bits_for(-5, 5), 4);
        assert_eq!(bits_for(-128, 127), 8);
    }
}
