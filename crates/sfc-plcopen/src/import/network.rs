//! FBD and LD networks translated to ST: statements for POU and action bodies, an expression for
//! a transition condition.
//!
//! A value flows from producers (variables, contacts, power rails, block outputs) to consumers
//! through `connectionPointIn/connection@refLocalId`. Elements with an effect (assignments to
//! output variables, coils, function block calls) become statements, written in execution order
//! (`executionOrderId` when given, else top to bottom and left to right, else document order),
//! each after the statements whose results it reads. A feedback loop through a variable or a
//! function block instance reads the value of the previous cycle, as in FBD.
//!
//! A condition is an expression: it can read variables, contacts and functions, but it cannot
//! call a function block. As Beremiz does when it compiles such a chart, the calls a condition
//! network needs are collected into the action `COMPUTE_FUNCTION_BLOCKS`, associated with the
//! initial step with qualifier S, so they run in every cycle; the condition reads their outputs
//! (`TON3.Q`). Edge modifiers become `R_TRIG`/`F_TRIG` instances declared in the POU, as Beremiz
//! declares them. A coil on a condition's path passes the power flow on without assigning its
//! variable (reported, SFC0710).

use super::Ctx;
use crate::emit::Frag;
use crate::xml::{self, anchor, attr, child, children, elements, XText};
use roxmltree::Node;
use sfc_syntax::lexer::TokenKind;
use std::collections::{HashMap, HashSet};
use std::ops::Range;

/// How deep values may nest before the network is given up.
const MAX_DEPTH: u32 = 200;

struct Pin {
    formal: Option<String>,
    negated: bool,
    /// `rising` or `falling`.
    edge: Option<String>,
    conns: Vec<(u64, Option<String>, Range<u32>)>,
}

struct OutPin {
    formal: String,
    negated: bool,
}

struct G<'a, 'i> {
    n: Node<'a, 'i>,
    kind: &'a str,
    ins: Vec<Pin>,
    in_outs: Vec<Pin>,
    outs: Vec<OutPin>,
    /// `expression` of variables, `variable` of contacts and coils.
    text: Option<XText>,
    order: u64,
    pos: (f64, f64),
}

pub(super) struct Net<'a, 'i> {
    els: Vec<G<'a, 'i>>,
    ids: HashMap<u64, usize>,
    consumed: Vec<bool>,
    /// How many input pins read each element's outputs (`fanout[i]`, all outputs together).
    fanout: Vec<usize>,
}

fn pin(n: Node, cp: Option<Node>, negated_attr: &str, edge_attr: &str) -> Pin {
    Pin {
        formal: attr(n, "formalParameter").map(|s| s.trim().to_string()),
        negated: xml::flag(n, negated_attr),
        edge: attr(n, edge_attr).filter(|e| *e == "rising" || *e == "falling").map(str::to_string),
        conns: cp
            .map(|cp| {
                children(cp, "connection")
                    .map(|c| {
                        (
                            attr(c, "refLocalId").and_then(|v| v.trim().parse().ok()).unwrap_or(u64::MAX),
                            attr(c, "formalParameter").map(|s| s.trim().to_string()).filter(|s| !s.is_empty()),
                            anchor(c),
                        )
                    })
                    .collect()
            })
            .unwrap_or_default(),
    }
}

pub(super) fn parse<'a, 'i>(body: Node<'a, 'i>) -> Net<'a, 'i> {
    let mut els = Vec::new();
    let mut ids = HashMap::new();
    for n in elements(body) {
        let kind = n.tag_name().name();
        let mut g = G {
            n,
            kind,
            ins: Vec::new(),
            in_outs: Vec::new(),
            outs: Vec::new(),
            text: None,
            order: xml::num(n, "executionOrderId").map(|v| v as u64).unwrap_or(0),
            pos: xml::position(n).unwrap_or((0.0, 0.0)),
        };
        match kind {
            "block" => {
                if let Some(iv) = child(n, "inputVariables") {
                    g.ins = children(iv, "variable")
                        .map(|v| pin(v, child(v, "connectionPointIn"), "negated", "edge"))
                        .collect();
                }
                if let Some(iov) = child(n, "inOutVariables") {
                    g.in_outs = children(iov, "variable")
                        .map(|v| pin(v, child(v, "connectionPointIn"), "negated", "edge"))
                        .collect();
                }
                if let Some(ov) = child(n, "outputVariables") {
                    g.outs = children(ov, "variable")
                        .map(|v| OutPin {
                            formal: attr(v, "formalParameter").unwrap_or("").trim().to_string(),
                            negated: xml::flag(v, "negated"),
                        })
                        .collect();
                }
            }
            "inVariable" | "continuation" => {
                g.outs = vec![OutPin { formal: String::new(), negated: xml::flag(n, "negated") }];
            }
            "outVariable" | "connector" => {
                g.ins = vec![pin(n, child(n, "connectionPointIn"), "negated", "edge")];
            }
            "inOutVariable" => {
                g.ins = vec![pin(n, child(n, "connectionPointIn"), "negatedIn", "edgeIn")];
                g.outs = vec![OutPin { formal: String::new(), negated: xml::flag(n, "negatedOut") }];
            }
            "contact" | "coil" => {
                // Their `negated` and `edge` apply to the variable, not to the power flow in.
                g.ins = vec![pin(n, child(n, "connectionPointIn"), "-", "-")];
                g.outs = vec![OutPin { formal: String::new(), negated: false }];
            }
            "rightPowerRail" => {
                g.ins = children(n, "connectionPointIn").map(|cp| pin(n, Some(cp), "-", "-")).collect();
            }
            _ => {}
        }
        g.text = match kind {
            // CODESYS accepts `a = b;` in an input's expression: the `;` ends nothing.
            "inVariable" => child(n, "expression").map(|e| {
                let t = xml::text_of(e).trim();
                match t.text.strip_suffix(';') {
                    Some(s) => t.slice(0..s.len()).trim(),
                    None => t,
                }
            }),
            "outVariable" | "inOutVariable" => child(n, "expression").map(|e| xml::text_of(e).trim()),
            "contact" | "coil" => child(n, "variable").map(|e| xml::text_of(e).trim()),
            _ => None,
        };
        if let Some(id) = attr(n, "localId").and_then(|v| v.trim().parse::<u64>().ok()) {
            ids.insert(id, els.len());
        }
        els.push(g);
    }
    let mut consumed = vec![false; els.len()];
    let mut fanout = vec![0usize; els.len()];
    for g in &els {
        for p in g.ins.iter().chain(g.in_outs.iter()) {
            for (r, _, _) in &p.conns {
                // `ids` holds positions in `els`, which both tables have.
                if let (Some(c), Some(f)) =
                    ids.get(r).and_then(|&i| Some((consumed.get_mut(i)?, fanout.get_mut(i)?))).unzip()
                {
                    *c = true;
                    *f += 1;
                }
            }
        }
    }
    Net { els, ids, consumed, fanout }
}

impl Net<'_, '_> {
    /// How many input pins read element `i`'s outputs.
    fn fanout(&self, i: usize) -> usize {
        self.fanout.get(i).copied().unwrap_or(0)
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    Statements,
    Condition,
}

struct Tr<'c, 'x, 'n, 'a, 'i> {
    cx: &'c mut Ctx<'x>,
    net: &'n Net<'a, 'i>,
    mode: Mode,
    done: Vec<bool>,
    active: Vec<bool>,
    stmts: Vec<Frag>,
    reported: HashSet<usize>,
    depth: u32,
    indent: String,
    /// Values of elements read more than once, computed once into a temporary (so the size of
    /// the translation stays linear in the size of the network): element → its temporary.
    shared: HashMap<usize, Frag>,
    /// Inside a condition's function (see [`condition`]): the arguments passed to it, each an
    /// expression of the POU, and the parameter standing for it.
    params: Option<Vec<(Frag, String)>>,
    /// The statements of that function (its temporaries).
    fn_stmts: Vec<Frag>,
    /// The EN inputs of the blocks the statement being written reads: it runs only when they
    /// are TRUE (`IF en THEN … END_IF;`, as Beremiz generates it).
    gates: Vec<Frag>,
}

/// A boolean operator block (a function without instance whose result is BOOL when its
/// operands are): the nodes whose sharing is written with BOOL temporaries.
fn is_boolean_op(g: &G) -> bool {
    g.kind == "block"
        && attr(g.n, "instanceName").is_none_or(|s| s.trim().is_empty())
        && ["AND", "OR", "XOR", "NOT"]
            .iter()
            .any(|k| attr(g.n, "typeName").is_some_and(|t| t.trim().eq_ignore_ascii_case(k)))
        && !g.ins.iter().any(|p| p.formal.as_deref().is_some_and(|f| f.eq_ignore_ascii_case("EN")))
}

/// Whether a text needs no parentheses as an operand: a name, a literal, a member or index
/// access, a call.
fn is_atomic(text: &str) -> bool {
    let (toks, _) = sfc_syntax::lexer::lex(0, text);
    let mut depth = 0i32;
    for t in toks.iter().filter(|t| !t.kind.is_trivia()) {
        match t.kind {
            TokenKind::LParen | TokenKind::LBracket => depth += 1,
            TokenKind::RParen | TokenKind::RBracket => depth -= 1,
            TokenKind::Ident => {
                let w = &text[t.start as usize..t.end as usize];
                if depth == 0
                    && ["AND", "OR", "XOR", "NOT", "MOD", "AND_THEN", "OR_ELSE"]
                        .iter()
                        .any(|k| k.eq_ignore_ascii_case(w))
                {
                    return false;
                }
            }
            TokenKind::Int
            | TokenKind::Real
            | TokenKind::String
            | TokenKind::WString
            | TokenKind::Typed
            | TokenKind::Address
            | TokenKind::Dot
            | TokenKind::Comma
            | TokenKind::Eof => {}
            TokenKind::Assign | TokenKind::Arrow if depth > 0 => {}
            _ if depth > 0 => {}
            _ => return false,
        }
    }
    true
}

fn text_frag(t: &XText) -> Frag {
    let mut f = Frag::from_xtext(t);
    f.atomic = is_atomic(&t.text);
    f
}

impl Tr<'_, '_, '_, '_, '_> {
    fn report(&mut self, i: usize, code: &'static str, msg: String) {
        let Some(g) = self.net.els.get(i) else { return };
        if self.reported.insert(i) {
            self.cx.diag(code, anchor(g.n), msg);
        }
    }

    fn is_active(&self, i: usize) -> bool {
        self.active.get(i).copied().unwrap_or(false)
    }

    fn set_active(&mut self, i: usize, on: bool) {
        if let Some(a) = self.active.get_mut(i) {
            *a = on;
        }
    }

    fn is_done(&self, i: usize) -> bool {
        self.done.get(i).copied().unwrap_or(false)
    }

    fn falsum(&self, i: usize) -> Frag {
        match self.net.els.get(i) {
            Some(g) => Frag::located("FALSE", anchor(g.n)),
            None => Frag::plain("FALSE"),
        }
    }

    /// The value arriving at an input pin: the OR of its connections (LD wiring), negated if the
    /// pin says so; `None` when nothing is connected.
    fn input(&mut self, owner: usize, p: &Pin) -> Option<Frag> {
        if p.conns.is_empty() {
            return None;
        }
        let mut vals = Vec::new();
        for (r, formal, range) in &p.conns {
            match self.net.ids.get(r) {
                Some(&src) => vals.push(self.value(src, formal.as_deref())),
                None => {
                    self.cx.diag(
                        "SFC0706",
                        range.clone(),
                        format!("the connection refers to localId {r}, which does not exist"),
                    );
                    vals.push(Frag::located("FALSE", range.clone()));
                }
            }
        }
        let v = if vals.len() == 1 { vals.pop().unwrap_or_default() } else { Frag::infix("OR", vals) };
        if p.negated {
            return Some(v.not());
        }
        match &p.edge {
            Some(e) => {
                let at = self.net.els.get(owner).map(|g| anchor(g.n)).unwrap_or_default();
                let e = e.clone();
                Some(self.trigger(&e, v, &at))
            }
            None => Some(v),
        }
    }

    /// The value produced by element `i` (at its output `formal`).
    fn value(&mut self, i: usize, formal: Option<&str>) -> Frag {
        let net = self.net;
        let Some(g) = net.els.get(i) else { return self.falsum(i) };
        let boolean = is_boolean_op(g) || g.kind == "contact";
        if let Some(t) = self.shared.get(&i) {
            return t.clone();
        }
        // Inside a condition's function, every operand that is not boolean logic is an
        // argument: the function sees only its parameters.
        if self.params.is_some() && !boolean && g.kind != "leftPowerRail" {
            let saved = self.params.take();
            let v = self.value(i, formal);
            self.params = saved;
            return self.as_param(v);
        }
        if boolean && net.fanout(i) > 1 && self.mode_shares() {
            let v = self.value_unshared(i, formal);
            let at = anchor(g.n);
            let name = match self.params {
                Some(_) => {
                    let name = format!("SHARED{}", self.fn_stmts.len() + 1);
                    let mut f = Frag::plain(format!("    {name} := "));
                    f.push(&v);
                    f.push_str(";\n");
                    self.fn_stmts.push(f);
                    name
                }
                None => {
                    let name = self.cx.fresh_var("SHARED", "BOOL");
                    let mut f = Frag::plain(format!("{}{name} := ", self.indent));
                    f.push(&v);
                    f.push_str(";\n");
                    self.stmts.push(f.locate(at.clone()));
                    name
                }
            };
            let t = Frag::located(name, at);
            self.shared.insert(i, t.clone());
            return t;
        }
        self.value_unshared(i, formal)
    }

    /// Inside a condition's function: the parameter that passes `v` in (one per distinct
    /// argument). Elsewhere `v` itself.
    fn as_param(&mut self, v: Frag) -> Frag {
        let Some(list) = self.params.as_mut() else { return v };
        if let Some((_, p)) = list.iter().find(|(f, _)| f.text == v.text) {
            return Frag::plain(p.clone());
        }
        let p = format!("IN{}", list.len() + 1);
        list.push((v, p.clone()));
        Frag::plain(p)
    }

    /// Whether shared values get temporaries here: in statements, and in a condition's function.
    fn mode_shares(&self) -> bool {
        self.mode == Mode::Statements || self.params.is_some()
    }

    fn value_unshared(&mut self, i: usize, formal: Option<&str>) -> Frag {
        if self.depth > MAX_DEPTH {
            self.report(i, "SFC0705", "the network is nested too deeply to be imported".into());
            return self.falsum(i);
        }
        self.depth += 1;
        let v = self.value_inner(i, formal);
        self.depth -= 1;
        v
    }

    fn value_inner(&mut self, i: usize, formal: Option<&str>) -> Frag {
        let net = self.net;
        let Some(g) = net.els.get(i) else { return self.falsum(i) };
        let at = anchor(g.n);
        let negated_out = g.outs.first().is_some_and(|o| o.negated);
        match g.kind {
            "inVariable" => {
                let Some(t) = g.text.as_ref().filter(|t| !t.text.is_empty()) else {
                    self.report(i, "SFC0705", "the variable has no expression".into());
                    return self.falsum(i);
                };
                let f = text_frag(&super::dialect::map(self.cx, t));
                if negated_out {
                    f.not()
                } else {
                    match xml::attr(g.n, "edge") {
                        Some(e @ ("rising" | "falling")) => self.trigger(e, f, &at),
                        _ => f,
                    }
                }
            }
            "inOutVariable" => {
                self.statement(i);
                let Some(t) = g.text.as_ref() else { return self.falsum(i) };
                let f = text_frag(&super::dialect::map(self.cx, t));
                if negated_out {
                    f.not()
                } else {
                    f
                }
            }
            "leftPowerRail" => Frag::located("TRUE", at),
            "contact" => {
                let Some(var) = g.text.as_ref() else {
                    self.report(i, "SFC0705", "the contact has no variable".into());
                    return self.falsum(i);
                };
                // A contact reads a variable as an expression does (`GVL.X`, `E.Value` mapped).
                let mut term = text_frag(&super::dialect::map(self.cx, var));
                if xml::flag(g.n, "negated") {
                    term = term.not();
                } else if let Some(e @ ("rising" | "falling")) = xml::attr(g.n, "edge") {
                    term = self.trigger(e, term, &at);
                }
                let term = self.as_param(term);
                let power = match g.ins.first() {
                    Some(p) => self.input(i, p),
                    None => None,
                };
                match power {
                    Some(p) if p.text != "TRUE" => Frag::infix("AND", vec![p, term]),
                    _ => term,
                }
                .locate(at)
            }
            "coil" => {
                if self.mode == Mode::Condition {
                    self.report(
                        i,
                        "SFC0710",
                        "a coil on the path of a transition condition passes the power flow on; its variable is not assigned".into(),
                    );
                } else {
                    self.statement(i);
                }
                match g.ins.first() {
                    Some(p) => self.input(i, p).unwrap_or_else(|| self.falsum(i)),
                    None => self.falsum(i),
                }
            }
            "continuation" => {
                let name = attr(g.n, "name").unwrap_or("").trim();
                let conn = net.els.iter().position(|e| {
                    e.kind == "connector" && attr(e.n, "name").is_some_and(|n| n.trim().eq_ignore_ascii_case(name))
                });
                match conn {
                    Some(c) => match net.els.get(c).and_then(|e| e.ins.first()) {
                        Some(p) => self.input(c, p).unwrap_or_else(|| self.falsum(c)),
                        None => self.falsum(c),
                    },
                    None => {
                        self.report(i, "SFC0706", format!("no connector named `{name}` for this continuation"));
                        self.falsum(i)
                    }
                }
            }
            "block" => self.block_value(i, formal),
            other => {
                self.report(i, "SFC0706", format!("a `{other}` does not produce a value here"));
                self.falsum(i)
            }
        }
    }

    fn block_value(&mut self, i: usize, formal: Option<&str>) -> Frag {
        let net = self.net;
        let Some(g) = net.els.get(i) else { return self.falsum(i) };
        let at = anchor(g.n);
        let type_name = attr(g.n, "typeName").unwrap_or("").trim().to_string();
        let instance = attr(g.n, "instanceName").map(str::trim).filter(|s| !s.is_empty()).map(str::to_string);
        let out = match formal {
            Some(f) => g.outs.iter().find(|o| o.formal.eq_ignore_ascii_case(f)),
            None => g.outs.iter().find(|o| !o.formal.eq_ignore_ascii_case("ENO")),
        };
        let out_name =
            out.map(|o| o.formal.clone()).or_else(|| formal.map(str::to_string)).unwrap_or_else(|| "OUT".into());
        // CODESYS's EXECUTE box has no output but ENO.
        let execute = instance.is_none() && type_name.eq_ignore_ascii_case("EXECUTE") && execute_code(g.n).is_some();
        // ENO is TRUE exactly when the block ran: its EN.
        if out_name.eq_ignore_ascii_case("ENO") || execute {
            if instance.is_some() || execute {
                self.statement(i);
            }
            let en = g.ins.iter().find(|p| p.formal.as_deref().is_some_and(|f| f.eq_ignore_ascii_case("EN")));
            return match en.and_then(|p| self.input(i, p)) {
                Some(v) => v,
                None => Frag::located("TRUE", at),
            };
        }
        let negated = out.is_some_and(|o| o.negated);
        let v = if let Some(inst) = instance {
            self.statement(i);
            Frag::located(format!("{inst}.{out_name}"), attr_range_or(g.n, "instanceName", &at))
        } else {
            if self.is_active(i) {
                self.report(
                    i,
                    "SFC0706",
                    format!("the network loops back through `{type_name}` without a variable to hold the value"),
                );
                return self.falsum(i);
            }
            self.set_active(i, true);
            let v = self.function(i, &type_name);
            self.set_active(i, false);
            v
        };
        if negated {
            v.not()
        } else {
            v
        }
    }

    /// Inputs of a block as `(formal, value)`, EN left out (reported if wired to anything but
    /// the power rail).
    fn args(&mut self, i: usize) -> Vec<(Option<String>, Frag)> {
        let net = self.net;
        let Some(g) = net.els.get(i) else { return Vec::new() };
        let mut out = Vec::new();
        for p in g.ins.iter().chain(g.in_outs.iter()) {
            let is_en = p.formal.as_deref().is_some_and(|f| f.eq_ignore_ascii_case("EN"));
            let Some(v) = self.input(i, p) else { continue };
            if is_en {
                if v.text != "TRUE" {
                    if self.mode == Mode::Statements {
                        // The block runs only when EN is TRUE.
                        if !self.gates.iter().any(|g| g.text == v.text) {
                            self.gates.push(v);
                        }
                    } else {
                        self.report(
                            i,
                            "SFC0705",
                            "a block enabled through EN cannot be part of a transition condition; it is evaluated unconditionally".into(),
                        );
                    }
                }
                continue;
            }
            out.push((p.formal.clone(), v));
        }
        out
    }

    /// A function (a block without instance) as an expression.
    fn function(&mut self, i: usize, type_name: &str) -> Frag {
        let at = self.net.els.get(i).map_or(0..0, |g| anchor(g.n));
        let args = self.args(i);
        let vals: Vec<Frag> = args.iter().map(|a| a.1.clone()).collect();
        let upper = type_name.to_ascii_uppercase();
        let infix = match upper.as_str() {
            "AND" => Some("AND"),
            "OR" => Some("OR"),
            "XOR" => Some("XOR"),
            "ADD" => Some("+"),
            "MUL" => Some("*"),
            "SUB" => Some("-"),
            "DIV" => Some("/"),
            "MOD" => Some("MOD"),
            "EXPT" => Some("**"),
            _ => None,
        };
        let cmp = match upper.as_str() {
            "GT" => Some(">"),
            "GE" => Some(">="),
            "EQ" => Some("="),
            "LE" => Some("<="),
            "LT" => Some("<"),
            "NE" => Some("<>"),
            _ => None,
        };
        let f = if let (Some(op), true) = (infix, vals.len() >= 2) {
            Frag::infix(op, vals)
        } else if let (Some(op), true) = (cmp, vals.len() >= 2) {
            // GT(a, b, c) is a > b AND b > c.
            let pairs: Vec<Frag> = vals.windows(2).map(|w| Frag::infix(op, w.to_vec())).collect();
            if pairs.len() == 1 {
                pairs.into_iter().next().unwrap_or_default()
            } else {
                Frag::infix("AND", pairs)
            }
        } else if upper == "NOT" && vals.len() == 1 {
            vals.into_iter().next().unwrap_or_default().not()
        } else if upper == "MOVE" && vals.len() == 1 {
            vals.into_iter().next().unwrap_or_default()
        } else {
            call(type_name, &args, sfc_st::stdlib::std_function(type_name).is_some())
        };
        f.locate(at)
    }

    /// An `R_TRIG`/`F_TRIG` instance fed with `v`, declared in the POU and called before the
    /// statement that reads its output (Beremiz's translation of edge modifiers).
    fn trigger(&mut self, edge: &str, v: Frag, at: &Range<u32>) -> Frag {
        let ty = if edge == "rising" { "R_TRIG" } else { "F_TRIG" };
        let name = self.cx.fresh_var(ty, ty);
        let mut f = Frag::plain(self.indent.clone());
        f.push_str(&format!("{name}(CLK := "));
        f.push(&v);
        f.push_str(");\n");
        self.stmts.push(f.locate(at.clone()));
        Frag::located(format!("{name}.Q"), at.clone())
    }

    /// Makes sure the statement of element `i` has been written (before its value is read).
    fn statement(&mut self, i: usize) {
        let net = self.net;
        let Some(g) = net.els.get(i) else { return };
        if self.is_done(i) || self.is_active(i) {
            return;
        }
        if self.mode == Mode::Condition && g.kind == "coil" {
            return;
        }
        self.set_active(i, true);
        let gates_before = std::mem::take(&mut self.gates);
        let at = anchor(g.n);
        let ind = self.indent.clone();
        let stmt: Option<Frag> = match g.kind {
            "outVariable" | "inOutVariable" => {
                let target = g.text.as_ref().map(|t| super::dialect::map(self.cx, t));
                let value = g.ins.first().and_then(|p| self.input(i, p));
                match (target, value) {
                    (Some(t), Some(v)) => {
                        let mut f = Frag::plain(ind.clone());
                        f.push(&Frag::from_xtext(&t));
                        f.push_str(" := ");
                        f.push(&v);
                        f.push_str(";\n");
                        Some(f)
                    }
                    (None, _) => {
                        self.report(i, "SFC0705", "the variable has no expression".into());
                        None
                    }
                    (Some(_), None) => {
                        if g.kind == "outVariable" {
                            self.report(i, "SFC0706", "nothing is connected to this output variable".into());
                        }
                        None
                    }
                }
            }
            "coil" => {
                let var = g.text.as_ref().map(|t| super::dialect::map(self.cx, t));
                let mut power =
                    g.ins.first().and_then(|p| self.input(i, p)).unwrap_or_else(|| Frag::located("FALSE", at.clone()));
                if let Some(e @ ("rising" | "falling")) = xml::attr(g.n, "edge") {
                    power = self.trigger(e, power, &at);
                }
                match var {
                    None => {
                        self.report(i, "SFC0705", "the coil has no variable".into());
                        None
                    }
                    Some(v) => {
                        let vf = Frag::from_xtext(&v);
                        let mut f = Frag::plain(ind.clone());
                        match attr(g.n, "storage").unwrap_or("none") {
                            s @ ("set" | "reset") => {
                                f.push_str("IF ");
                                f.push(&power);
                                f.push_str(" THEN\n");
                                f.push_str(&format!("{ind}    "));
                                f.push(&vf);
                                f.push_str(if s == "set" { " := TRUE;\n" } else { " := FALSE;\n" });
                                f.push_str(&format!("{ind}END_IF;\n"));
                            }
                            _ => {
                                f.push(&vf);
                                f.push_str(" := ");
                                f.push(&if xml::flag(g.n, "negated") { power.not() } else { power });
                                f.push_str(";\n");
                            }
                        }
                        Some(f)
                    }
                }
            }
            "block" => {
                let type_name = attr(g.n, "typeName").unwrap_or("").trim().to_string();
                let instance = attr(g.n, "instanceName").map(str::trim).filter(|s| !s.is_empty()).map(str::to_string);
                let st_code = (instance.is_none() && type_name.eq_ignore_ascii_case("EXECUTE"))
                    .then(|| execute_code(g.n))
                    .flatten();
                match instance {
                    // CODESYS's EXECUTE box: its ST code, run when EN is TRUE (the gate).
                    None if st_code.is_some() => {
                        let _ = self.args(i);
                        let code = super::dialect::map(self.cx, &st_code.unwrap_or_default());
                        let mut f = Frag::plain(String::new());
                        for line in code.text.lines().filter(|l| !l.trim().is_empty()) {
                            f.push_str(&format!("{ind}{line}\n"));
                        }
                        if !f.text.trim_end().ends_with(';') && !f.text.trim().is_empty() {
                            // The box's last statement may go without `;`.
                            f = Frag::plain(format!("{};\n", f.text.trim_end()));
                        }
                        Some(f)
                    }
                    Some(inst) => {
                        let args = self.args(i);
                        let mut f = Frag::plain(ind.clone());
                        f.push(&call(&inst, &args, false));
                        f.push_str(";\n");
                        Some(f)
                    }
                    None => {
                        // A function whose result nobody reads: called for its effect.
                        let v = self.function(i, &type_name);
                        let mut f = Frag::plain(ind.clone());
                        f.push(&v);
                        f.push_str(";\n");
                        Some(f)
                    }
                }
            }
            _ => None,
        };
        self.set_active(i, false);
        if let Some(d) = self.done.get_mut(i) {
            *d = true;
        }
        let gates = std::mem::replace(&mut self.gates, gates_before);
        if let Some(s) = stmt {
            let s = if gates.is_empty() {
                s
            } else {
                // `IF en THEN stmt END_IF;` with the statement indented one level more.
                let mut f = Frag::plain(format!("{ind}IF "));
                f.push(&Frag::infix("AND", gates));
                f.push_str(" THEN\n    ");
                let body = s;
                f.push(&body);
                f.push_str(&format!("{ind}END_IF;\n"));
                f
            };
            self.stmts.push(s.locate(at));
        }
    }
}

/// The ST code of CODESYS's EXECUTE box (`addData/data[@name=…/stcode]/STCode`).
fn execute_code(n: Node) -> Option<XText> {
    children(n, "addData")
        .flat_map(|a| children(a, "data"))
        .filter(|d| attr(*d, "name").is_some_and(|v| v.ends_with("/stcode")))
        .find_map(|d| child(d, "STCode"))
        .map(xml::text_of)
}

fn attr_range_or(n: Node, name: &str, or: &Range<u32>) -> Range<u32> {
    xml::attr_range(n, name).unwrap_or_else(|| or.clone())
}

/// `Name(a := x, b := y)` with formal arguments, or positional ones for a standard function.
fn call(name: &str, args: &[(Option<String>, Frag)], positional: bool) -> Frag {
    let mut f = Frag::plain(name);
    f.push_str("(");
    let named = !positional && args.iter().all(|a| a.0.as_deref().is_some_and(|s| !s.is_empty()));
    for (k, (formal, v)) in args.iter().enumerate() {
        if k > 0 {
            f.push_str(", ");
        }
        if named {
            f.push_str(formal.as_deref().unwrap_or(""));
            f.push_str(" := ");
        }
        f.push(v);
    }
    f.push_str(")");
    f.atomic = true;
    f
}

/// The statement elements of a network in execution order.
fn sinks(net: &Net) -> Vec<usize> {
    let mut list: Vec<usize> = (0..net.els.len())
        .filter(|&i| {
            let Some(g) = net.els.get(i) else { return false };
            match g.kind {
                "outVariable" | "coil" => true,
                "inOutVariable" => g.ins.first().is_some_and(|p| !p.conns.is_empty()),
                "block" => {
                    attr(g.n, "instanceName").is_some_and(|s| !s.trim().is_empty())
                        || !net.consumed.get(i).copied().unwrap_or(false)
                        // CODESYS's EXECUTE box runs its code even when its ENO goes on.
                        || (attr(g.n, "typeName").is_some_and(|t| t.trim().eq_ignore_ascii_case("EXECUTE"))
                            && execute_code(g.n).is_some())
                }
                _ => false,
            }
        })
        .collect();
    let ordered = list.iter().any(|&i| net.els.get(i).is_some_and(|g| g.order > 0));
    list.sort_by(|&a, &b| {
        let (Some(ga), Some(gb)) = (net.els.get(a), net.els.get(b)) else { return a.cmp(&b) };
        let ka = if ordered && ga.order > 0 { ga.order } else { u64::MAX };
        let kb = if ordered && gb.order > 0 { gb.order } else { u64::MAX };
        ka.cmp(&kb).then(ga.pos.1.total_cmp(&gb.pos.1)).then(ga.pos.0.total_cmp(&gb.pos.0)).then(a.cmp(&b))
    });
    list
}

/// Reports the elements no translation reads or that have no ST equivalent.
fn unsupported(cx: &mut Ctx, net: &Net) {
    for g in &net.els {
        match g.kind {
            "label" | "jump" | "return" => {
                cx.diag("SFC0705", anchor(g.n), format!("`{}` (FBD control flow) is not imported", g.kind));
            }
            "vendorElement" => {
                cx.diag(
                    "SFC0711",
                    anchor(g.n),
                    "a vendor element (drawn by its own tool, no IEC meaning) is skipped; the rest of the network is imported",
                );
            }
            "error" => {
                cx.diag("SFC0705", anchor(g.n), format!("a `{}` element cannot be imported", g.kind));
            }
            _ => {}
        }
    }
}

/// The statements of an FBD or LD body, each line after `indent`; comment boxes first.
pub(super) fn statements(cx: &mut Ctx, body: Node, indent: &str) -> Frag {
    let net = parse(body);
    unsupported(cx, &net);
    let mut out = Frag::default();
    for g in net.els.iter().filter(|g| g.kind == "comment") {
        let text = child(g.n, "content").map(|c| xml::formatted_text(c).text).unwrap_or_default();
        let text = text.trim().replace("(*", "( *").replace("*)", "* )");
        if !text.is_empty() {
            let lines: Vec<&str> = text.lines().collect();
            out.push_str(&format!("{indent}(* {} *)\n", lines.join(&format!("\n{indent}   "))));
        }
    }
    let n = net.els.len();
    let mut tr = Tr {
        cx,
        net: &net,
        mode: Mode::Statements,
        done: vec![false; n],
        active: vec![false; n],
        stmts: Vec::new(),
        reported: HashSet::new(),
        depth: 0,
        indent: indent.to_string(),
        shared: HashMap::new(),
        params: None,
        fn_stmts: Vec::new(),
        gates: Vec::new(),
    };
    for i in sinks(&net) {
        tr.statement(i);
    }
    for s in tr.stmts {
        out.push(&s);
    }
    out
}

/// Indentation of the statements of `COMPUTE_FUNCTION_BLOCKS`.
const COMPUTE_INDENT: &str = "        ";

fn condition_tr<'c, 'x, 'n, 'a, 'i>(cx: &'c mut Ctx<'x>, net: &'n Net<'a, 'i>) -> Tr<'c, 'x, 'n, 'a, 'i> {
    let n = net.els.len();
    Tr {
        cx,
        net,
        mode: Mode::Condition,
        done: vec![false; n],
        active: vec![false; n],
        stmts: Vec::new(),
        reported: HashSet::new(),
        depth: 0,
        indent: COMPUTE_INDENT.to_string(),
        shared: HashMap::new(),
        params: None,
        fn_stmts: Vec::new(),
        gates: Vec::new(),
    }
}

/// Hands the calls a condition needs to `COMPUTE_FUNCTION_BLOCKS`.
fn keep_calls(cx: &mut Ctx, stmts: Vec<Frag>, owner: &Range<u32>) {
    if stmts.is_empty() {
        return;
    }
    cx.diag(
        "SFC0707",
        owner.clone(),
        "the condition's network calls function blocks: the calls are imported into the action \
         COMPUTE_FUNCTION_BLOCKS, stored (S) in the initial step so they run in every cycle, as Beremiz does",
    );
    cx.compute.extend(stmts);
}

/// Whether boolean logic reachable from `p` (AND, OR, XOR, NOT blocks, contacts) reads one
/// element's value more than once: inlined, such a network grows exponentially with its depth.
fn shares_logic(net: &Net, p: &Pin) -> bool {
    let mut seen = HashSet::new();
    let mut todo: Vec<usize> = p.conns.iter().filter_map(|(r, _, _)| net.ids.get(r).copied()).collect();
    while let Some(i) = todo.pop() {
        if !seen.insert(i) {
            continue;
        }
        let Some(g) = net.els.get(i) else { continue };
        if !(is_boolean_op(g) || g.kind == "contact") {
            continue;
        }
        if net.fanout(i) > 1 {
            return true;
        }
        for q in &g.ins {
            todo.extend(q.conns.iter().filter_map(|(r, _, _)| net.ids.get(r).copied()));
        }
    }
    false
}

/// The value at `p` as a condition: an expression, or, when its boolean logic shares values, a
/// call of a function generated for it (a condition cannot hold statements, and a function is
/// free of side effects), whose temporaries compute each shared value once.
fn condition_value(tr: &mut Tr, p: &Pin) -> Option<Frag> {
    if !shares_logic(tr.net, p) {
        return tr.input(usize::MAX, p);
    }
    tr.params = Some(Vec::new());
    let v = tr.input(usize::MAX, p);
    let params = tr.params.take().unwrap_or_default();
    let stmts = std::mem::take(&mut tr.fn_stmts);
    let v = v?;
    let cx = &mut *tr.cx;
    cx.condition_functions += 1;
    let name = format!("{}_CONDITION{}", cx.pou_name, cx.condition_functions);
    let mut text = format!("FUNCTION {name} : BOOL\n");
    if !params.is_empty() {
        text.push_str("    VAR_INPUT\n");
        for (_, p) in &params {
            text.push_str(&format!("        {p} : BOOL;\n"));
        }
        text.push_str("    END_VAR\n");
    }
    if !stmts.is_empty() {
        text.push_str("    VAR\n");
        for k in 1..=stmts.len() {
            text.push_str(&format!("        SHARED{k} : BOOL;\n"));
        }
        text.push_str("    END_VAR\n");
    }
    for st in &stmts {
        text.push_str(&st.text);
    }
    text.push_str(&format!("    {name} := {};\nEND_FUNCTION\n\n", v.text));
    cx.functions.push(text);
    let mut call = Frag::plain(format!("{name}("));
    for (k, (arg, p)) in params.iter().enumerate() {
        if k > 0 {
            call.push_str(", ");
        }
        call.push_str(&format!("{p} := "));
        call.push(arg);
    }
    call.push_str(")");
    call.atomic = true;
    Some(call)
}

/// A transition condition wired to an FBD/LD network in an SFC body (`net`, the body parsed
/// once for all its conditions).
pub(super) fn condition(cx: &mut Ctx, net: &Net, cp: Node, owner: &Range<u32>) -> Frag {
    let p = pin(cp, Some(cp), "-", "-");
    let mut tr = condition_tr(cx, net);
    let v = condition_value(&mut tr, &p);
    let stmts = std::mem::take(&mut tr.stmts);
    drop(tr);
    keep_calls(cx, stmts, owner);
    match v {
        Some(v) => v,
        None => {
            cx.diag("SFC0708", owner.clone(), "nothing is connected to the condition; imported as FALSE");
            Frag::located("FALSE", owner.clone())
        }
    }
}

/// A named transition condition written in FBD or LD: the value assigned to the variable or coil
/// named like the transition (Beremiz's rule).
pub(super) fn transition_body(cx: &mut Ctx, body: Node, name: &str, owner: &Range<u32>) -> Frag {
    let net = parse(body);
    unsupported(cx, &net);
    let target = net.els.iter().enumerate().find(|(_, g)| {
        matches!(g.kind, "outVariable" | "inOutVariable" | "coil")
            && g.text.as_ref().is_some_and(|t| !name.is_empty() && t.text.eq_ignore_ascii_case(name))
    });
    let Some((t, target)) = target else {
        cx.diag("SFC0708", anchor(body), format!("the condition body never assigns `{name}`; imported as FALSE"));
        return Frag::located("FALSE", anchor(body));
    };
    let mut tr = condition_tr(cx, &net);
    tr.reported.insert(t);
    let value = match target.ins.first() {
        Some(p) => condition_value(&mut tr, p),
        None => None,
    };
    // Elements that neither feed the condition nor are called for it have no place in it.
    for i in sinks(&net) {
        if i != t && !tr.is_done(i) && !tr.reported.contains(&i) {
            tr.report(i, "SFC0710", format!("only the value assigned to `{name}` is imported from a condition body"));
        }
    }
    let stmts = std::mem::take(&mut tr.stmts);
    drop(tr);
    keep_calls(cx, stmts, owner);
    match value {
        Some(v) => v,
        None => {
            cx.diag("SFC0708", anchor(target.n), format!("nothing is connected to `{name}`; imported as FALSE"));
            Frag::located("FALSE", anchor(target.n))
        }
    }
}
