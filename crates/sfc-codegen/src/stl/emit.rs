//! From bit logic to S7-200 instructions: NOT pushed down to the contacts, XOR expanded,
//! constants folded, and blocks combined with ALD/OLD within the 9 levels of the logic stack
//! (deeper parts are computed first into scratch bits). Also the two statement forms of action
//! bodies: a BOOL assignment under an enable chain, and IF.

use super::ir::{Addr, Ins, Op};
use super::logic::{BodyOp, Logic};

/// Levels of the S7-200 logic stack.
pub(crate) const STACK_LEVELS: usize = 9;

/// Normalised logic: no NOT above a contact, no XOR, no constant inside AND/OR.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Nl {
    Const(bool),
    Bit(Addr, bool, String),
    And(Vec<Nl>),
    Or(Vec<Nl>),
}

impl Nl {
    fn is_leaf(&self) -> bool {
        matches!(self, Nl::Const(_) | Nl::Bit(..))
    }
    /// Stack levels needed to compute it.
    fn depth(&self) -> usize {
        match self {
            Nl::Const(_) | Nl::Bit(..) => 1,
            Nl::And(v) | Nl::Or(v) => depth_seq(v),
        }
    }
    fn negate_leaf(self) -> Nl {
        match self {
            Nl::Const(b) => Nl::Const(!b),
            Nl::Bit(a, n, s) => Nl::Bit(a, !n, s),
            other => other,
        }
    }
}

/// Levels for `first; (A|O leaf | block ALD|OLD)…`.
fn depth_seq(items: &[Nl]) -> usize {
    let mut d = items.first().map_or(1, Nl::depth);
    for it in items.iter().skip(1) {
        if !it.is_leaf() {
            d = d.max(1 + it.depth());
        }
    }
    d
}

fn junction(and: bool, items: Vec<Nl>) -> Nl {
    let mut flat = Vec::with_capacity(items.len());
    for it in items {
        match it {
            Nl::Const(b) if b == and => {}
            Nl::Const(b) => return Nl::Const(b),
            Nl::And(v) if and => flat.extend(v),
            Nl::Or(v) if !and => flat.extend(v),
            other => flat.push(other),
        }
    }
    match flat.len() {
        0 => Nl::Const(and),
        1 => flat.pop().unwrap_or(Nl::Const(and)),
        _ if and => Nl::And(flat),
        _ => Nl::Or(flat),
    }
}

/// A contact of the enable chain of a statement.
pub(crate) type Contact = (Addr, bool, String);

/// Emits code and hands out scratch bits.
#[derive(Debug, Default)]
pub(crate) struct Emitter {
    next_temp: usize,
    /// Scratch bits needed at once, over the whole program.
    pub max_temps: usize,
}

impl Emitter {
    fn temp(&mut self) -> Addr {
        let t = Addr::Temp(self.next_temp);
        self.next_temp += 1;
        self.max_temps = self.max_temps.max(self.next_temp);
        t
    }
    /// Scratch bits are reused by every network: call at the start of each one.
    pub(crate) fn new_network(&mut self) {
        self.next_temp = 0;
    }

    /// Normalises `l` (its negation with `neg`). An XOR operand that is not a contact is
    /// computed first into a scratch bit (code in `pre`) so that the expansion
    /// `a·¬b + ¬a·b` repeats contacts only.
    pub(crate) fn norm(&mut self, l: &Logic, neg: bool, pre: &mut Vec<Ins>) -> Nl {
        match l {
            Logic::Const(b) => Nl::Const(*b != neg),
            Logic::Bit(a, n, s) => Nl::Bit(*a, *n != neg, s.clone()),
            Logic::Not(x) => self.norm(x, !neg, pre),
            Logic::And(v) | Logic::Or(v) => {
                let and = matches!(l, Logic::And(_)) != neg;
                let items = v.iter().map(|x| self.norm(x, neg, pre)).collect();
                junction(and, items)
            }
            Logic::Xor(a, b) => {
                let a = self.norm(a, false, pre);
                let a = self.leaf(a, pre);
                let b = self.norm(b, false, pre);
                let b = self.leaf(b, pre);
                let (na, nb) = (a.clone().negate_leaf(), b.clone().negate_leaf());
                if neg {
                    junction(false, vec![junction(true, vec![a, b]), junction(true, vec![na, nb])])
                } else {
                    junction(false, vec![junction(true, vec![a, nb]), junction(true, vec![na, b])])
                }
            }
        }
    }

    /// A contact for `n`: itself when it is one, else a scratch bit computed in `pre`.
    fn leaf(&mut self, n: Nl, pre: &mut Vec<Ins>) -> Nl {
        if n.is_leaf() {
            return n;
        }
        let t = self.temp();
        let mut code = Vec::new();
        self.value(n, STACK_LEVELS, pre, &mut code);
        pre.extend(code);
        pre.push(Ins::on(Op::Out, t, "scratch"));
        Nl::Bit(t, false, "scratch".to_string())
    }

    /// Code in `out` that pushes the value of `n` using at most `budget` stack levels; parts
    /// that do not fit are computed before (in `pre`) into scratch bits.
    pub(crate) fn value(&mut self, n: Nl, budget: usize, pre: &mut Vec<Ins>, out: &mut Vec<Ins>) {
        match n {
            Nl::Const(b) => out.push(Ins::on(if b { Op::Ld } else { Op::Ldn }, Addr::ALWAYS_ON, "always on")),
            Nl::Bit(a, neg, s) => out.push(Ins::on(if neg { Op::Ldn } else { Op::Ld }, a, s)),
            Nl::And(items) => self.junction_value(true, items, budget, pre, out),
            Nl::Or(items) => self.junction_value(false, items, budget, pre, out),
        }
    }

    fn junction_value(&mut self, and: bool, mut items: Vec<Nl>, budget: usize, pre: &mut Vec<Ins>, out: &mut Vec<Ins>) {
        if items.is_empty() {
            // Not produced by `junction`; kept total: an empty AND is TRUE, an empty OR FALSE.
            out.push(Ins::on(if and { Op::Ld } else { Op::Ldn }, Addr::ALWAYS_ON, "always on"));
            return;
        }
        let budget = budget.max(1);
        if depth_seq(&items) > budget {
            // The deepest block first: it then needs no extra level.
            if let Some(i) = (0..items.len()).max_by_key(|&i| (items[i].depth(), usize::MAX - i)) {
                let it = items.remove(i);
                items.insert(0, it);
            }
        }
        while depth_seq(&items) > budget {
            let cost = |i: usize, it: &Nl| if i == 0 { it.depth() } else { it.depth() + 1 };
            let Some(i) =
                (0..items.len()).filter(|&i| !items[i].is_leaf()).max_by_key(|&i| (cost(i, &items[i]), usize::MAX - i))
            else {
                break;
            };
            let it = std::mem::replace(&mut items[i], Nl::Const(true));
            items[i] = self.leaf(it, pre);
        }
        let mut it = items.into_iter();
        if let Some(first) = it.next() {
            self.value(first, budget, pre, out);
        }
        for x in it {
            match x {
                Nl::Bit(a, neg, s) => {
                    let op = match (and, neg) {
                        (true, false) => Op::A,
                        (true, true) => Op::An,
                        (false, false) => Op::O,
                        (false, true) => Op::On,
                    };
                    out.push(Ins::on(op, a, s));
                }
                Nl::Const(b) => {
                    let op = match (and, b) {
                        (true, true) => Op::A,
                        (true, false) => Op::An,
                        (false, true) => Op::O,
                        (false, false) => Op::On,
                    };
                    out.push(Ins::on(op, Addr::ALWAYS_ON, "always on"));
                }
                block => {
                    self.value(block, budget - 1, pre, out);
                    out.push(Ins::bare(if and { Op::Ald } else { Op::Old }));
                }
            }
        }
    }

    /// Code that leaves `l` on top of the stack (spills first).
    pub(crate) fn logic(&mut self, l: &Logic, out: &mut Vec<Ins>) {
        let mut pre = Vec::new();
        let n = self.norm(l, false, &mut pre);
        let mut code = Vec::new();
        self.value(n, STACK_LEVELS, &mut pre, &mut code);
        out.extend(pre);
        out.extend(code);
    }

    /// `LD c0`, `A c1`, `AN c2`, … (`LD SM0.0` for an empty chain).
    fn chain(enable: &[Contact], out: &mut Vec<Ins>) {
        let Some(((a, n, s), rest)) = enable.split_first() else {
            out.push(Ins::on(Op::Ld, Addr::ALWAYS_ON, "always on"));
            return;
        };
        out.push(Ins::on(if *n { Op::Ldn } else { Op::Ld }, *a, s.clone()));
        for (a, n, s) in rest {
            out.push(Ins::on(if *n { Op::An } else { Op::A }, *a, s.clone()));
        }
    }

    /// `target := value` when the enable chain holds. The value is computed once, before the
    /// target changes: `LD en; LPS; <value>; ALD; S t; NOT; ALD; R t` (the second ALD gives
    /// `en AND NOT (en AND value)` = `en AND NOT value` from the saved copy of `en`).
    fn assign(&mut self, enable: &[Contact], target: Addr, name: &str, value: &Logic, out: &mut Vec<Ins>) {
        let mark = self.next_temp;
        let mut pre = Vec::new();
        let v = self.norm(value, false, &mut pre);
        match v {
            Nl::Const(b) => {
                out.extend(pre);
                Self::chain(enable, out);
                out.push(Ins::on(if b { Op::Set(1) } else { Op::Reset(1) }, target, name));
            }
            v => {
                let mut code = Vec::new();
                self.value(v, STACK_LEVELS - 2, &mut pre, &mut code);
                out.extend(pre);
                Self::chain(enable, out);
                out.push(Ins::bare(Op::Lps));
                out.extend(code);
                out.push(Ins::bare(Op::Ald));
                out.push(Ins::on(Op::Set(1), target, name));
                out.push(Ins::bare(Op::Not));
                out.push(Ins::bare(Op::Ald));
                out.push(Ins::on(Op::Reset(1), target, name));
            }
        }
        self.next_temp = mark;
    }

    /// The statements of an action body under an enable chain (the action's `A` bit, then the
    /// conditions of the enclosing IF branches, each captured in a scratch bit before its
    /// branch runs, so a branch that writes a variable of its own condition does not change
    /// which statements run).
    pub(crate) fn body(&mut self, ops: &[BodyOp], enable: &mut Vec<Contact>, out: &mut Vec<Ins>) {
        for op in ops {
            match op {
                BodyOp::Assign { target, name, value, .. } => self.assign(enable, *target, name, value, out),
                BodyOp::If { branches, else_body, .. } => {
                    let mark = self.next_temp;
                    let depth = enable.len();
                    let mut reachable = true;
                    for (cond, body) in branches {
                        let mut pre = Vec::new();
                        let n = self.norm(cond, false, &mut pre);
                        let taken = match n {
                            Nl::Const(false) => continue,
                            Nl::Const(true) => None,
                            // A contact that no statement of the IF writes keeps its value
                            // through the IF: no need to capture it.
                            Nl::Bit(a, neg, s) if !writes_any(branches, else_body, a) => {
                                enable.push((a, neg, s));
                                self.body(body, enable, out);
                                if let Some(last) = enable.last_mut() {
                                    last.1 = !neg;
                                }
                                continue;
                            }
                            n => {
                                let t = self.temp();
                                let mut code = Vec::new();
                                self.value(n, STACK_LEVELS, &mut pre, &mut code);
                                out.extend(pre);
                                out.extend(code);
                                out.push(Ins::on(Op::Out, t, "IF condition"));
                                Some(t)
                            }
                        };
                        if let Some(t) = taken {
                            enable.push((t, false, "IF condition".to_string()));
                        }
                        self.body(body, enable, out);
                        match taken {
                            Some(_) => {
                                // Later branches run only when this condition was FALSE.
                                if let Some(last) = enable.last_mut() {
                                    last.1 = true;
                                }
                            }
                            None => {
                                reachable = false;
                                break;
                            }
                        }
                    }
                    if reachable {
                        self.body(else_body, enable, out);
                    }
                    enable.truncate(depth);
                    self.next_temp = mark;
                }
            }
        }
    }
}

/// Whether any statement of an IF writes bit `a`.
fn writes_any(branches: &[(Logic, Vec<BodyOp>)], else_body: &[BodyOp], a: Addr) -> bool {
    branches.iter().any(|(_, b)| writes(b, a)) || writes(else_body, a)
}

fn writes(ops: &[BodyOp], a: Addr) -> bool {
    ops.iter().any(|op| match op {
        BodyOp::Assign { target, .. } => *target == a,
        BodyOp::If { branches, else_body, .. } => writes_any(branches, else_body, a),
    })
}
