//! `Program::resolve`: a variable path as a user writes it (`Rev.Busy`, `Arr[3]`, `S2.T`) to
//! its absolute slot.

use super::rt::{kind_of, Kind};
use super::{PouBody, Program};
use sfc_st::Type;

#[derive(Debug, Clone, PartialEq)]
enum Seg {
    Name(String),
    Index(Vec<i64>),
}

fn parse_path(path: &str) -> Option<Vec<Seg>> {
    let mut out = Vec::new();
    let b = path.trim().as_bytes();
    let mut i = 0;
    let mut expect_name = true;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        if expect_name {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            if i == start {
                return None;
            }
            out.push(Seg::Name(path.trim()[start..i].to_string()));
            expect_name = false;
            continue;
        }
        match c {
            b'.' => {
                expect_name = true;
                i += 1;
            }
            b'[' => {
                let end = i + path.trim()[i..].find(']')?;
                let inner = &path.trim()[i + 1..end];
                let idx: Option<Vec<i64>> = inner.split(',').map(|s| s.trim().parse().ok()).collect();
                out.push(Seg::Index(idx?));
                i = end + 1;
            }
            _ => return None,
        }
    }
    if expect_name {
        return None;
    }
    Some(out)
}

/// Where resolution stands.
enum Cur {
    Val {
        slot: usize,
        ty: Type,
    },
    Step {
        pou: usize,
        base: usize,
        k: usize,
    },
    Action {
        pou: usize,
        base: usize,
        k: usize,
    },
    /// CODESYS's `_<action>`: `.x` (executed, `A`) and `._x` (active, `Q`).
    Implicit {
        pou: usize,
        base: usize,
        k: usize,
    },
}

impl Program {
    /// Resolves a path as a user writes it, relative to the top POU (frame at `top_frame`),
    /// case-insensitive: `Start`, global names, `Rev.Busy`, `Arr[3]`, `Pt.X` (structure field),
    /// `S2.X`/`S2.T` (step flag/time), `Act.Q`/`Act.A`, nested `Rev.OpenKM1.X`, `Rev.SFCError`,
    /// direct addresses used in code (`%IX0.0`). Returns the absolute slot and the type
    /// (elementary types only).
    pub fn resolve(&self, top: usize, top_frame: usize, path: &str) -> Option<(usize, Type)> {
        let path = path.trim();
        if path.starts_with('%') {
            let v = self
                .globals
                .vars
                .iter()
                .find(|v| v.location.as_deref().is_some_and(|l| l.eq_ignore_ascii_case(path)) && v.size == 1)?;
            return Some((v.offset as usize, v.ty.clone()));
        }
        let segs = parse_path(path)?;
        let mut it = segs.into_iter();
        let Some(Seg::Name(first)) = it.next() else { return None };
        let mut cur = self.member_of(top, top_frame, &first).or_else(|| {
            let g = self.globals.vars.iter().find(|v| v.name.eq_ignore_ascii_case(&first))?;
            Some(Cur::Val { slot: g.offset as usize, ty: g.ty.clone() })
        })?;
        for seg in it {
            cur = match (cur, seg) {
                (Cur::Val { slot, ty: Type::FunctionBlock(fb) }, Seg::Name(n)) => match self.fb_index(&fb) {
                    Some(j) => self.member_of(j, slot, &n)?,
                    None => {
                        let l = self.support.std_layouts.get(&fb.to_ascii_uppercase())?;
                        let v = l.vars.iter().find(|v| v.name.eq_ignore_ascii_case(&n))?;
                        Cur::Val { slot: slot + v.offset as usize, ty: v.ty.clone() }
                    }
                },
                (Cur::Val { slot, ty: Type::Struct { fields, .. } }, Seg::Name(n)) => {
                    let mut off = 0;
                    let mut found = None;
                    for (f, t) in &fields {
                        if f.eq_ignore_ascii_case(&n) {
                            found = Some(Cur::Val { slot: slot + off, ty: t.clone() });
                            break;
                        }
                        off += self.type_size(t);
                    }
                    found?
                }
                (Cur::Val { slot, ty: Type::Array { dims, elem } }, Seg::Index(ix)) => {
                    if ix.len() != dims.len() {
                        return None;
                    }
                    let esize = self.type_size(&elem);
                    let mut flat: i64 = 0;
                    for (i, (lo, hi)) in ix.iter().zip(&dims) {
                        if i < lo || i > hi {
                            return None;
                        }
                        flat = flat * (hi - lo + 1) + (i - lo);
                    }
                    Cur::Val { slot: slot + flat as usize * esize, ty: *elem }
                }
                (Cur::Step { pou, base, k }, Seg::Name(n)) => {
                    let PouBody::Chart(cc) = &self.pous[pou].body else { return None };
                    match n.to_ascii_uppercase().as_str() {
                        "X" | "_X" => Cur::Val { slot: base + cc.step_x[k] as usize, ty: Type::Bool },
                        "U" if cc.step_members == crate::code::StepMembers::Graph => {
                            Cur::Val { slot: base + *cc.step_vendor.get(k)? as usize, ty: Type::Time }
                        }
                        "T" | "_T" | "U" => Cur::Val { slot: base + cc.step_t[k] as usize, ty: Type::Time },
                        m @ ("COUNT" | "FS" | "SA" | "LS" | "TMAX") if cc.step_members == crate::code::StepMembers::Logix => {
                            let (off, ty) = super::expr::logix_member(m);
                            Cur::Val { slot: base + (*cc.step_vendor.get(k)? + off) as usize, ty }
                        }
                        _ => return None,
                    }
                }
                (Cur::Implicit { pou, base, k }, Seg::Name(n)) => {
                    let PouBody::Chart(cc) = &self.pous[pou].body else { return None };
                    match n.to_ascii_uppercase().as_str() {
                        "X" => Cur::Val { slot: base + cc.action_a[k] as usize, ty: Type::Bool },
                        "_X" => Cur::Val { slot: base + cc.action_q[k] as usize, ty: Type::Bool },
                        _ => return None,
                    }
                }
                (Cur::Action { pou, base, k }, Seg::Name(n)) => {
                    let PouBody::Chart(cc) = &self.pous[pou].body else { return None };
                    match n.to_ascii_uppercase().as_str() {
                        "Q" => Cur::Val { slot: base + cc.action_q[k] as usize, ty: Type::Bool },
                        "A" => Cur::Val { slot: base + cc.action_a[k] as usize, ty: Type::Bool },
                        _ => return None,
                    }
                }
                _ => return None,
            };
        }
        match cur {
            Cur::Val { slot, ty } if kind_of(&ty) != Kind::Agg => Some((slot, ty)),
            _ => None,
        }
    }

    /// Member `name` of the frame of POU `pou` at `base`: a variable, step or action.
    fn member_of(&self, pou: usize, base: usize, name: &str) -> Option<Cur> {
        let p = self.pous.get(pou)?;
        if let Some(v) = p.layout.vars.iter().find(|v| v.name.eq_ignore_ascii_case(name)) {
            return Some(Cur::Val { slot: base + v.offset as usize, ty: v.ty.clone() });
        }
        if let PouBody::Chart(cc) = &p.body {
            if let Some(k) = cc.chart.step(name) {
                return Some(Cur::Step { pou, base, k });
            }
            if let Some(k) = cc.chart.action(name) {
                return Some(Cur::Action { pou, base, k });
            }
            if let Some(k) = name.strip_prefix('_').and_then(|a| cc.chart.action(a)) {
                return Some(Cur::Implicit { pou, base, k });
            }
        }
        // The steps of its actions written in SFC (one namespace with the body's).
        for &sub in &p.subs {
            if let PouBody::Chart(cc) = &self.pous[sub].body {
                if let Some(k) = cc.chart.step(name) {
                    return Some(Cur::Step { pou: sub, base, k });
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse() {
        assert_eq!(parse_path("Rev.Busy"), Some(vec![Seg::Name("Rev".into()), Seg::Name("Busy".into())]));
        assert_eq!(
            parse_path("Cells[1, 2].Seq"),
            Some(vec![Seg::Name("Cells".into()), Seg::Index(vec![1, 2]), Seg::Name("Seq".into())])
        );
        assert_eq!(parse_path("a."), None);
        assert_eq!(parse_path("[1]"), None);
        assert_eq!(parse_path("a b"), None);
    }
}
