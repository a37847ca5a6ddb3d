//! From lowered logic and statements to S7-200 instructions: NOT pushed down to the contacts
//! (a negated comparison flips its operator), XOR expanded, constants folded, blocks combined
//! with ALD/OLD within the 9 levels of the logic stack (deeper parts are computed first into
//! scratch bits), integer expressions computed with the word instructions into scratch words,
//! and the statements of action bodies: assignments under an enable chain, IF, counter calls.

use super::ir::{Addr, Arg, ArithOp, CmpOp, Ins, Join, Network, Op, Val};
use super::logic::{BodyOp, IntExpr, Logic};
use super::vars::CounterKind;

/// Levels of the S7-200 logic stack.
pub(crate) const STACK_LEVELS: usize = 9;

/// Normalised logic: no NOT above a contact, no XOR, no constant inside AND/OR, comparison
/// operands computed.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Nl {
    Const(bool),
    Bit(Addr, bool, String),
    /// A compare contact: operator, 32-bit, operands, text.
    Cmp(CmpOp, bool, Val, Val, String),
    And(Vec<Nl>),
    Or(Vec<Nl>),
}

impl Nl {
    fn is_leaf(&self) -> bool {
        matches!(self, Nl::Const(_) | Nl::Bit(..) | Nl::Cmp(..))
    }
    /// Stack levels needed to compute it.
    fn depth(&self) -> usize {
        match self {
            Nl::Const(_) | Nl::Bit(..) | Nl::Cmp(..) => 1,
            Nl::And(v) | Nl::Or(v) => depth_seq(v),
        }
    }
    fn negate_leaf(self) -> Nl {
        match self {
            Nl::Const(b) => Nl::Const(!b),
            Nl::Bit(a, n, s) => Nl::Bit(a, !n, s),
            Nl::Cmp(op, w, a, b, s) => Nl::Cmp(op.negate(), w, a, b, s),
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

/// The networks a body produces: statements may need several (a counter call is skipped with
/// a jump, and its label starts a network).
#[derive(Debug, Default)]
pub(crate) struct Sink {
    pub networks: Vec<Network>,
    pub title: String,
    pub code: Vec<Ins>,
    part: usize,
}

impl Sink {
    pub(crate) fn start(&mut self, title: String) {
        self.flush();
        self.title = title;
        self.part = 0;
    }
    pub(crate) fn flush(&mut self) {
        if self.code.is_empty() {
            return;
        }
        let title = if self.part == 0 { self.title.clone() } else { format!("{} (continued)", self.title) };
        self.networks.push(Network { title, code: std::mem::take(&mut self.code) });
        self.part += 1;
    }
    fn push_network(&mut self, title: String, code: Vec<Ins>) {
        self.flush();
        self.networks.push(Network { title, code });
        self.part += 1;
    }
}

/// Emits code and hands out scratch bits, words and labels.
#[derive(Debug, Default)]
pub(crate) struct Emitter {
    next_temp: usize,
    next_word: usize,
    next_dword: usize,
    /// Scratch operands needed at once, over the whole program.
    pub max_temps: usize,
    pub max_words: usize,
    pub max_dwords: usize,
    /// Labels used (JMP/LBL), 0…255 on the S7-200.
    pub labels: u16,
}

impl Emitter {
    fn temp(&mut self) -> Addr {
        let t = Addr::Temp(self.next_temp);
        self.next_temp += 1;
        self.max_temps = self.max_temps.max(self.next_temp);
        t
    }
    fn temp_val(&mut self, wide: bool) -> Val {
        if wide {
            self.next_dword += 1;
            self.max_dwords = self.max_dwords.max(self.next_dword);
            Val::TempD(self.next_dword - 1)
        } else {
            self.next_word += 1;
            self.max_words = self.max_words.max(self.next_word);
            Val::TempW(self.next_word - 1)
        }
    }
    /// Scratch operands are reused by every network: call at the start of each one.
    pub(crate) fn new_network(&mut self) {
        self.next_temp = 0;
        self.next_word = 0;
        self.next_dword = 0;
    }
    fn label(&mut self) -> u16 {
        self.labels += 1;
        self.labels - 1
    }

    /// Code (box instructions, under an enable the caller provides) that leaves the value of
    /// `e` in an operand: the operand itself for a plain value, else a scratch word.
    pub(crate) fn int_value(&mut self, e: &IntExpr, wide: bool, code: &mut Vec<Ins>) -> Val {
        match e {
            IntExpr::Val(v) => *v,
            IntExpr::Widen(x) => {
                let xv = self.int_value(x, false, code);
                let t = self.temp_val(true);
                code.push(Ins::vals(Op::Itd, &[xv, t], "INT to DINT"));
                t
            }
            IntExpr::Neg(x) => {
                let xv = self.int_value(x, wide, code);
                let t = self.temp_val(wide);
                code.push(Ins::vals(Op::Mov(wide), &[Val::Const(0), t], ""));
                code.push(Ins::vals(Op::Arith(wide, ArithOp::Sub), &[xv, t], "negate"));
                t
            }
            IntExpr::Bin(op, a, b) => {
                let t = match **a {
                    IntExpr::Val(v) => {
                        let bv = self.int_value(b, wide, code);
                        let t = self.temp_val(wide);
                        code.push(Ins::vals(Op::Mov(wide), &[v, t], ""));
                        code.push(Ins::vals(Op::Arith(wide, *op), &[bv, t], ""));
                        return t;
                    }
                    _ => self.int_value(a, wide, code),
                };
                let bv = self.int_value(b, wide, code);
                code.push(Ins::vals(Op::Arith(wide, *op), &[bv, t], ""));
                t
            }
            IntExpr::Mod(a, b) => {
                let av = self.int_value(a, wide, code);
                let bv = self.int_value(b, wide, code);
                let q = self.temp_val(wide);
                let r = self.temp_val(wide);
                code.push(Ins::vals(Op::Mov(wide), &[av, q], "MOD: a - (a / b) * b"));
                code.push(Ins::vals(Op::Arith(wide, ArithOp::Div), &[bv, q], ""));
                code.push(Ins::vals(Op::Arith(wide, ArithOp::Mul), &[bv, q], ""));
                code.push(Ins::vals(Op::Mov(wide), &[av, r], ""));
                code.push(Ins::vals(Op::Arith(wide, ArithOp::Sub), &[q, r], ""));
                r
            }
        }
    }

    /// Normalises `l` (its negation with `neg`). An XOR operand that is not a contact is
    /// computed first into a scratch bit (code in `pre`) so that the expansion
    /// `a·¬b + ¬a·b` repeats contacts only; comparison operands that need computing are
    /// computed in `pre` into scratch words.
    pub(crate) fn norm(&mut self, l: &Logic, neg: bool, pre: &mut Vec<Ins>) -> Nl {
        match l {
            Logic::Const(b) => Nl::Const(*b != neg),
            Logic::Bit(a, n, s) => Nl::Bit(*a, *n != neg, s.clone()),
            Logic::Cmp(c) => {
                let mut code = Vec::new();
                let a = self.int_value(&c.a, c.wide, &mut code);
                let b = self.int_value(&c.b, c.wide, &mut code);
                if !code.is_empty() {
                    pre.push(Ins::on(Op::Ld, Addr::ALWAYS_ON, format!("compute {}", c.text)));
                    pre.extend(code);
                }
                let op = if neg { c.op.negate() } else { c.op };
                Nl::Cmp(op, c.wide, a, b, c.text.clone())
            }
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
            Nl::Cmp(op, wide, a, b, s) => out.push(Ins::vals(Op::Cmp(Join::Ld, wide, op), &[a, b], s)),
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
        let join = if and { Join::A } else { Join::O };
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
                Nl::Cmp(op, wide, a, b, s) => out.push(Ins::vals(Op::Cmp(join, wide, op), &[a, b], s)),
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
        self.logic_many(&[l], out);
    }

    /// Code that leaves the values of `ls` on the stack, the last one on top (the inputs of a
    /// counter box): every spill is computed before the first value is pushed.
    pub(crate) fn logic_many(&mut self, ls: &[&Logic], out: &mut Vec<Ins>) {
        let mut pre = Vec::new();
        let ns: Vec<Nl> = ls.iter().map(|l| self.norm(l, false, &mut pre)).collect();
        let mut codes = Vec::new();
        for (i, n) in ns.into_iter().enumerate() {
            let mut code = Vec::new();
            self.value(n, STACK_LEVELS - i, &mut pre, &mut code);
            codes.push(code);
        }
        out.extend(pre);
        for c in codes {
            out.extend(c);
        }
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
        let mark = (self.next_temp, self.next_word, self.next_dword);
        let mut pre = Vec::new();
        let v = self.norm(value, false, &mut pre);
        match v {
            Nl::Const(b) => {
                out.extend(pre);
                Self::chain(enable, out);
                out.push(Ins::count(if b { Op::Set } else { Op::Reset }, target, 1, name));
            }
            v => {
                let mut code = Vec::new();
                self.value(v, STACK_LEVELS - 2, &mut pre, &mut code);
                out.extend(pre);
                Self::chain(enable, out);
                out.push(Ins::bare(Op::Lps));
                out.extend(code);
                out.push(Ins::bare(Op::Ald));
                out.push(Ins::count(Op::Set, target, 1, name));
                out.push(Ins::bare(Op::Not));
                out.push(Ins::bare(Op::Ald));
                out.push(Ins::count(Op::Reset, target, 1, name));
            }
        }
        (self.next_temp, self.next_word, self.next_dword) = mark;
    }

    /// `target := value` for an integer, under the enable chain (box instructions run while
    /// the top of the stack is on). `x := x op e` is `op e, x`; `x := x + 1` is `INC`.
    fn move_value(
        &mut self,
        enable: &[Contact],
        target: Val,
        wide: bool,
        name: &str,
        value: &IntExpr,
        out: &mut Vec<Ins>,
    ) {
        let mark = (self.next_temp, self.next_word, self.next_dword);
        Self::chain(enable, out);
        match value {
            IntExpr::Bin(ArithOp::Add, a, b) if **a == IntExpr::Val(target) && **b == IntExpr::Val(Val::Const(1)) => {
                out.push(Ins::vals(Op::Inc(wide), &[target], name));
            }
            IntExpr::Bin(op, a, b) if **a == IntExpr::Val(target) && !b.reads(target) => {
                let bv = self.int_value(b, wide, out);
                out.push(Ins::vals(Op::Arith(wide, *op), &[bv, target], name));
            }
            v => {
                let r = self.int_value(v, wide, out);
                out.push(Ins::vals(Op::Mov(wide), &[r, target], name));
            }
        }
        (self.next_temp, self.next_word, self.next_dword) = mark;
    }

    /// The statements of an action body under an enable chain (the action's `A` bit, then the
    /// conditions of the enclosing IF branches, each captured in a scratch bit before its
    /// branch runs, so a branch that writes a variable of its own condition does not change
    /// which statements run).
    pub(crate) fn body(&mut self, ops: &[BodyOp], enable: &mut Vec<Contact>, sink: &mut Sink) {
        for op in ops {
            match op {
                BodyOp::Assign { target, name, value, .. } => self.assign(enable, *target, name, value, &mut sink.code),
                BodyOp::Move { target, wide, name, value, .. } => {
                    self.move_value(enable, *target, *wide, name, value, &mut sink.code)
                }
                BodyOp::Count { counter, kind, up, down, reset, preset, qd, text } => {
                    self.count(enable, *counter, *kind, (up, down, reset), (*preset, *qd), text, sink)
                }
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
                                self.body(body, enable, sink);
                                if let Some(last) = enable.last_mut() {
                                    last.1 = !neg;
                                }
                                continue;
                            }
                            n => {
                                let t = self.temp();
                                let mut code = Vec::new();
                                self.value(n, STACK_LEVELS, &mut pre, &mut code);
                                sink.code.extend(pre);
                                sink.code.extend(code);
                                sink.code.push(Ins::on(Op::Out, t, "IF condition"));
                                Some(t)
                            }
                        };
                        if let Some(t) = taken {
                            enable.push((t, false, "IF condition".to_string()));
                        }
                        self.body(body, enable, sink);
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
                        self.body(else_body, enable, sink);
                    }
                    enable.truncate(depth);
                    self.next_temp = mark;
                }
            }
        }
    }

    /// A counter call: `JMP` over the counter instruction in the scans in which the call does
    /// not run (an IEC block that is not called does not see its inputs), the instruction with
    /// its inputs on the stack, and the label.
    #[allow(clippy::too_many_arguments)]
    fn count(
        &mut self,
        enable: &[Contact],
        counter: usize,
        kind: CounterKind,
        (up, down, reset): (&Logic, &Logic, &Logic),
        (preset, qd): (Val, Option<Addr>),
        text: &str,
        sink: &mut Sink,
    ) {
        sink.flush();
        let label = self.label();
        let mut skip = Vec::new();
        Self::chain(enable, &mut skip);
        skip.push(Ins::bare(Op::Not));
        skip.push(Ins::label(Op::Jmp, label, "the call does not run in this scan"));
        sink.push_network(format!("jump over the counter call below in the scans it does not run (LBL {label})"), skip);
        let mut code = Vec::new();
        let c = Addr::Counter(counter);
        let (op, inputs, what): (Op, Vec<&Logic>, &str) = match kind {
            CounterKind::Ctu => (Op::Ctu, vec![up, reset], "CU, R (top)"),
            CounterKind::Ctd => (Op::Ctd, vec![down, reset], "CD, LD (top)"),
            CounterKind::Ctud => (Op::Ctud, vec![up, down, reset], "CU, CD, R (top)"),
        };
        self.logic_many(&inputs, &mut code);
        code.push(Ins { op, args: vec![Arg::Bit(c), Arg::Val(preset)], note: format!("inputs {what}") });
        if let Some(qd) = qd {
            code.push(Ins::vals(
                Op::Cmp(Join::Ld, false, CmpOp::Le),
                &[Val::Counter(counter), Val::Const(0)],
                "CV <= 0",
            ));
            code.push(Ins::on(Op::Out, qd, "QD"));
        }
        sink.push_network(format!("counter call: {text}"), code);
        sink.code.push(Ins::label(Op::Lbl, label, ""));
    }
}

/// Whether any statement of an IF writes bit `a`.
fn writes_any(branches: &[(Logic, Vec<BodyOp>)], else_body: &[BodyOp], a: Addr) -> bool {
    branches.iter().any(|(_, b)| writes(b, a)) || writes(else_body, a)
}

fn writes(ops: &[BodyOp], a: Addr) -> bool {
    ops.iter().any(|op| match op {
        BodyOp::Assign { target, .. } => *target == a,
        BodyOp::Count { counter, qd, .. } => a == Addr::Counter(*counter) || Some(a) == *qd,
        BodyOp::Move { .. } => false,
        BodyOp::If { branches, else_body, .. } => writes_any(branches, else_body, a),
    })
}
