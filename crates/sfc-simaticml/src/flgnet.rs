//! A LAD or FBD network (`FlgNet`) as a Boolean ST expression (`docs/dev/s7graph.md` §3).
//!
//! Each `Wire` has one source (the power rail, an operand's `IdentCon`, a part's output pin) and
//! sinks (part input pins). The coil's `in` pin is evaluated backwards: a contact is
//! `in AND operand`, `O`/`A`/`X` boxes are `OR`/`AND`/`XOR` of their inputs, a comparator is
//! `pre AND (in1 op in2)`, several sources on one pin are a wired OR, a `Negated` pin is `NOT`.
//! The power rail is `TRUE` (dropped from conjunctions): a network that wires the rail straight
//! to its coil is the empty condition. Unknown parts, cycles, pins wired to nothing and UIds
//! that name nothing are located errors (SFC0743). The work is bounded: each part is evaluated
//! once (memoised), and an expression that grows beyond a bound is an error.

use crate::operand::{access, iec_elementary, Place};
use crate::Cx;
use roxmltree::Node;
use sfc_xmlmap::xml::{anchor, child, children, elements};
use sfc_xmlmap::Frag;
use std::collections::{HashMap, HashSet};
use std::ops::Range;

/// The longest expression a network may give (bytes); beyond it the network is refused.
const MAX_TEXT: usize = 64 * 1024;

/// A value in the network.
#[derive(Clone)]
struct Val {
    f: Frag,
    /// The power rail: `TRUE`.
    rail: bool,
    /// The terms of a conjunction (flattened: a contact chain is one `AND`), else empty.
    terms: Vec<Frag>,
}

impl Val {
    fn rail() -> Val {
        Val { f: Frag::plain("TRUE"), rail: true, terms: Vec::new() }
    }
    fn of(f: Frag) -> Val {
        Val { f, rail: false, terms: Vec::new() }
    }
    /// The terms of this value as a conjunction.
    fn conj(&self) -> Vec<Frag> {
        if self.terms.is_empty() {
            vec![self.f.clone()]
        } else {
            self.terms.clone()
        }
    }
}

#[derive(Clone, Debug)]
enum Src {
    Rail,
    Ident(String, Range<u32>),
    Out(String, Range<u32>),
}

struct Net<'a, 'i> {
    parts: HashMap<String, Node<'a, 'i>>,
    accesses: HashMap<String, Node<'a, 'i>>,
    /// (part UId, pin) → its sources.
    sinks: HashMap<(String, String), Vec<Src>>,
    memo: HashMap<String, Val>,
    visiting: HashSet<String>,
    place: Place,
    failed: bool,
}

fn is_output_pin(pin: &str) -> bool {
    pin == "out"
        || pin == "eno"
        || (pin.starts_with("out") && pin.get(3..).is_some_and(|d| d.bytes().all(|b| b.is_ascii_digit())))
}

impl<'a, 'i> Net<'a, 'i> {
    fn read(cx: &mut Cx, flg: Node<'a, 'i>, place: Place) -> Net<'a, 'i> {
        let mut net = Net {
            parts: HashMap::new(),
            accesses: HashMap::new(),
            sinks: HashMap::new(),
            memo: HashMap::new(),
            visiting: HashSet::new(),
            place,
            failed: false,
        };
        if let Some(parts) = child(flg, "Parts") {
            for p in elements(parts) {
                let uid = p.attribute("UId").unwrap_or("").to_string();
                let map = match p.tag_name().name() {
                    "Part" => &mut net.parts,
                    "Access" => &mut net.accesses,
                    _ => continue,
                };
                if map.insert(uid.clone(), p).is_some() {
                    cx.diag("SFC0743", anchor(p), format!("UId {uid} is used twice in the network"));
                    net.failed = true;
                }
            }
        }
        if let Some(wires) = child(flg, "Wires") {
            for w in children(wires, "Wire") {
                let mut src: Option<Src> = None;
                let mut sinks: Vec<(String, String, Node)> = Vec::new();
                for e in elements(w) {
                    let uid = e.attribute("UId").unwrap_or("").to_string();
                    let s = match e.tag_name().name() {
                        "Powerrail" => Some(Src::Rail),
                        "IdentCon" => Some(Src::Ident(uid, anchor(e))),
                        "NameCon" => {
                            let pin = e.attribute("Name").unwrap_or("").to_string();
                            if is_output_pin(&pin) {
                                Some(Src::Out(uid, anchor(e)))
                            } else {
                                sinks.push((uid, pin, e));
                                None
                            }
                        }
                        _ => None,
                    };
                    if let Some(s) = s {
                        if src.is_some() {
                            cx.diag("SFC0743", anchor(e), "the wire has two sources");
                            net.failed = true;
                        }
                        src = Some(s);
                    }
                }
                let Some(src) = src else { continue };
                for (uid, pin, e) in sinks {
                    if !net.parts.contains_key(&uid) {
                        cx.diag(
                            "SFC0743",
                            anchor(e),
                            format!("the wire goes to UId {uid}, which is no part of the network"),
                        );
                        net.failed = true;
                        continue;
                    }
                    net.sinks.entry((uid, pin)).or_default().push(src.clone());
                }
            }
        }
        net
    }

    /// Reports the first part (in the file's order) that no coil's value used: a second output
    /// or a dangling branch would be lost. `coil` tells the coils.
    fn off_path(&self, cx: &mut Cx, coil: &dyn Fn(&str) -> bool) -> bool {
        let unused = self
            .parts
            .iter()
            .filter(|(u, p)| !self.memo.contains_key(*u) && !coil(p.attribute("Name").unwrap_or("")))
            .map(|(_, p)| *p)
            .min_by_key(|p| p.range().start);
        if let Some(p) = unused {
            cx.diag(
                "SFC0743",
                anchor(p),
                format!("the `{}` part is not on the path to the coil", p.attribute("Name").unwrap_or("")),
            );
        }
        unused.is_some()
    }

    fn negated(p: Node, pin: &str) -> bool {
        children(p, "Negated").any(|n| n.attribute("Name") == Some(pin))
    }

    /// The value on input `pin` of part `uid` (`None`: not wired).
    fn input(&mut self, cx: &mut Cx, uid: &str, pin: &str, ty: &str, why: &str) -> Option<Option<Val>> {
        let Some(srcs) = self.sinks.get(&(uid.to_string(), pin.to_string())).cloned() else {
            return Some(None);
        };
        let mut vals = Vec::new();
        for s in srcs {
            vals.push(self.source(cx, &s, ty, why)?);
        }
        let v = or(vals);
        let negate = self.parts.get(uid).is_some_and(|p| Net::negated(*p, pin));
        Some(Some(if negate { Val::of(v.f.not()) } else { v }))
    }

    fn required(&mut self, cx: &mut Cx, uid: &str, pin: &str, ty: &str, why: &str) -> Option<Val> {
        match self.input(cx, uid, pin, ty, why)? {
            Some(v) => Some(v),
            None => {
                let at = self.parts.get(uid).map(|p| anchor(*p)).unwrap_or(0..0);
                cx.diag("SFC0743", at, format!("pin `{pin}` of the part is not connected"));
                None
            }
        }
    }

    fn source(&mut self, cx: &mut Cx, s: &Src, ty: &str, why: &str) -> Option<Val> {
        match s {
            Src::Rail => Some(Val::rail()),
            Src::Ident(uid, at) => {
                let Some(a) = self.accesses.get(uid).copied() else {
                    cx.diag(
                        "SFC0743",
                        at.clone(),
                        format!("the wire comes from UId {uid}, which is no operand of the network"),
                    );
                    return None;
                };
                access(cx, a, ty, why, self.place).map(Val::of)
            }
            Src::Out(uid, at) => {
                if !self.parts.contains_key(uid) {
                    cx.diag(
                        "SFC0743",
                        at.clone(),
                        format!("the wire comes from UId {uid}, which is no part of the network"),
                    );
                    return None;
                }
                self.part(cx, uid)
            }
        }
    }

    fn part(&mut self, cx: &mut Cx, uid: &str) -> Option<Val> {
        if let Some(v) = self.memo.get(uid) {
            return Some(v.clone());
        }
        let p = *self.parts.get(uid)?;
        if !self.visiting.insert(uid.to_string()) {
            cx.diag("SFC0743", anchor(p), "the network's wires form a cycle through this part").notes.push(
                "a LAD or FBD condition is evaluated from the power rail to the coil; a loop has no value".into(),
            );
            return None;
        }
        let v = self.part_value(cx, uid, p);
        self.visiting.remove(uid);
        let v = v?;
        if v.f.text.len() > MAX_TEXT {
            cx.diag("SFC0743", anchor(p), "the network's expression is too large to import");
            return None;
        }
        self.memo.insert(uid.to_string(), v.clone());
        Some(v)
    }

    fn part_value(&mut self, cx: &mut Cx, uid: &str, p: Node) -> Option<Val> {
        let name = p.attribute("Name").unwrap_or("");
        let at = anchor(p);
        match name {
            "Contact" => {
                let inp = self.input(cx, uid, "in", "BOOL", "BOOL from a contact")?.unwrap_or_else(Val::rail);
                let op = self.required(cx, uid, "operand", "BOOL", "BOOL from a contact")?;
                Some(and(vec![inp, op]).locate(at))
            }
            "O" | "A" | "X" => {
                let mut pins: Vec<(u32, String)> = self
                    .sinks
                    .keys()
                    .filter(|(u, pin)| u == uid && pin.starts_with("in"))
                    .filter_map(|(_, pin)| pin.get(2..).and_then(|d| d.parse::<u32>().ok()).map(|n| (n, pin.clone())))
                    .collect();
                pins.sort();
                if pins.is_empty() {
                    cx.diag("SFC0743", at, format!("the `{name}` box has no input connected"));
                    return None;
                }
                let mut vals = Vec::new();
                for (_, pin) in pins {
                    vals.push(self.required(cx, uid, &pin, "BOOL", "BOOL from a logic box")?);
                }
                let v = match name {
                    "O" => or(vals),
                    "A" => and(vals),
                    _ => Val::of(Frag::infix("XOR", vals.into_iter().map(|v| v.f).collect())),
                };
                Some(v.locate(at))
            }
            "Eq" | "Ne" | "Gt" | "Ge" | "Lt" | "Le" => {
                let src = children(p, "TemplateValue")
                    .find(|t| t.attribute("Name") == Some("SrcType"))
                    .and_then(|t| t.text())
                    .unwrap_or("")
                    .trim()
                    .to_string();
                let ty = iec_elementary(&src).unwrap_or("INT");
                let why = if iec_elementary(&src).is_some() {
                    format!("{ty} from the comparator's SrcType")
                } else {
                    format!("INT: the comparator's SrcType `{src}` is not an elementary type")
                };
                let op = match name {
                    "Eq" => "=",
                    "Ne" => "<>",
                    "Gt" => ">",
                    "Ge" => ">=",
                    "Lt" => "<",
                    _ => "<=",
                };
                let pre =
                    self.input(cx, uid, "pre", "BOOL", "BOOL from a comparator's enable")?.unwrap_or_else(Val::rail);
                let a = self.required(cx, uid, "in1", ty, &why)?;
                let b = self.required(cx, uid, "in2", ty, &why)?;
                // A step's time (`T`, `U`: TIME) compared as an integer (TIA compares it as the
                // DInt of its milliseconds): converted, so the condition types.
                let as_int = |v: Val| -> Frag {
                    let text = v.f.text.as_str();
                    let step_time = ty != "TIME"
                        && text.rsplit_once('.').is_some_and(|(base, m)| {
                            ["T", "U"].iter().any(|x| m.eq_ignore_ascii_case(x))
                                && cx.steps.values().any(|s| s.eq_ignore_ascii_case(base))
                        });
                    if step_time {
                        let mut f = Frag::plain(format!("TIME_TO_{ty}("));
                        f.push(&v.f);
                        f.push_str(")");
                        f
                    } else {
                        v.f
                    }
                };
                let cmp = Val::of(Frag::infix(op, vec![as_int(a), as_int(b)]));
                Some(and(vec![pre, cmp]).locate(at))
            }
            _ => {
                cx.diag("SFC0743", at, format!("the LAD/FBD part `{name}` cannot be imported into a condition"))
                    .notes
                    .push(
                    "sfc reads contacts (negated too), O/A/X boxes, the comparators Eq Ne Gt Ge Lt Le and wired ORs; \
                         edge contacts, timers and boxes with EN/ENO are not read yet"
                        .into(),
                );
                None
            }
        }
    }
}

impl Val {
    fn locate(self, at: Range<u32>) -> Val {
        if self.rail {
            return self;
        }
        Val { f: self.f.locate(at), rail: false, terms: self.terms }
    }
}

fn and(vals: Vec<Val>) -> Val {
    let terms: Vec<Frag> = vals.iter().filter(|v| !v.rail).flat_map(Val::conj).collect();
    match terms.len() {
        0 => Val::rail(),
        1 => Val::of(terms.into_iter().next().unwrap_or_default()),
        _ => Val { f: Frag::infix("AND", terms.clone()), rail: false, terms },
    }
}

/// `a OR b`; branches that start with the same contacts (a fan-out in LAD) are factored:
/// `(A AND B) OR (A AND C)` is written `A AND (B OR C)`.
fn or(vals: Vec<Val>) -> Val {
    if vals.iter().any(|v| v.rail) || vals.is_empty() {
        return Val::rail();
    }
    if vals.len() == 1 {
        return vals.into_iter().next().unwrap_or_else(Val::rail);
    }
    let lists: Vec<Vec<Frag>> = vals.iter().map(Val::conj).collect();
    let shortest = lists.iter().map(Vec::len).min().unwrap_or(0);
    let mut common = 0;
    while common + 1 < shortest.max(1)
        && lists
            .iter()
            .all(|l| l.get(common).map(|f| &f.text) == lists.first().and_then(|f| f.get(common)).map(|f| &f.text))
    {
        common += 1;
    }
    if common > 0 {
        let prefix: Vec<Val> =
            lists.first().map(|l| l.iter().take(common).cloned().map(Val::of).collect()).unwrap_or_default();
        let rests: Vec<Val> =
            lists.iter().map(|l| and(l.iter().skip(common).cloned().map(Val::of).collect())).collect();
        let mut all = prefix;
        all.push(or(rests));
        return and(all);
    }
    Val::of(Frag::infix("OR", vals.into_iter().map(|v| v.f).collect()))
}

/// A network's value as the condition of its coil (`TrCoil`, `IlCoil`, `SvCoil`): `Some(None)`
/// for the empty network (the rail straight to the coil), `None` after a located error.
pub(crate) fn condition(cx: &mut Cx, flg: Node, coil: &str, place: Place) -> Option<Option<Frag>> {
    let mut net = Net::read(cx, flg, place);
    if net.failed {
        return None;
    }
    let coils: Vec<String> =
        net.parts.iter().filter(|(_, p)| p.attribute("Name") == Some(coil)).map(|(u, _)| u.clone()).collect();
    let [uid] = coils.as_slice() else {
        cx.diag("SFC0743", anchor(flg), format!("the network has {} `{coil}` parts; it needs one", coils.len()));
        return None;
    };
    // Every other part must lie on the coil's path (a second output would be lost).
    let v = net.required(cx, uid, "in", "BOOL", "BOOL from a contact")?;
    if net.off_path(cx, &|name| name == coil) {
        return None;
    }
    Some(if v.rail { None } else { Some(v.f) })
}

/// A permanent instruction's network: one statement per coil (`x := expr;`, `S`/`R` coils as
/// `IF expr THEN x := TRUE; END_IF;`). `None` after a located error.
pub(crate) fn statements(cx: &mut Cx, flg: Node, place: Place) -> Option<Vec<Frag>> {
    let mut net = Net::read(cx, flg, place);
    if net.failed {
        return None;
    }
    let mut coils: Vec<(String, Node)> = net
        .parts
        .iter()
        .filter(|(_, p)| matches!(p.attribute("Name"), Some("Coil" | "SCoil" | "RCoil")))
        .map(|(u, p)| (u.clone(), *p))
        .collect();
    coils.sort_by_key(|(_, p)| p.range().start);
    if coils.is_empty() && !net.parts.is_empty() {
        cx.diag("SFC0743", anchor(flg), "the permanent instruction's network has no coil (Coil, SCoil, RCoil)");
        return None;
    }
    let mut out = Vec::new();
    for (uid, p) in coils {
        let kind = p.attribute("Name").unwrap_or("Coil");
        let v = net.required(cx, &uid, "in", "BOOL", "BOOL from a contact")?;
        let target = net.required(cx, &uid, "operand", "BOOL", "BOOL from a coil")?;
        let negate = Net::negated(p, "operand");
        let mut s = Frag::default();
        match kind {
            "Coil" => {
                s.push(&target.f);
                s.push_str(" := ");
                s.push(&if negate { v.f.not() } else { v.f });
                s.push_str(";");
            }
            _ => {
                let value = if kind == "SCoil" { "TRUE" } else { "FALSE" };
                if v.rail {
                    s.push(&target.f);
                    s.push_str(&format!(" := {value};"));
                } else {
                    s.push_str("IF ");
                    s.push(&v.f);
                    s.push_str(" THEN ");
                    s.push(&target.f);
                    s.push_str(&format!(" := {value}; END_IF;"));
                }
            }
        }
        out.push(s.locate(anchor(p)));
    }
    if net.off_path(cx, &|name| matches!(name, "Coil" | "SCoil" | "RCoil")) {
        return None;
    }
    Some(out)
}
