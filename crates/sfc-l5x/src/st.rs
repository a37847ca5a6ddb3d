//! Logix Structured Text (transition conditions, action bodies, preset expressions) mapped
//! token by token into sfc's ST. Text that needs no change is copied with its exact location in
//! the XML; what changes (`[:=]`, the members of step tags) is written located on the characters
//! it replaces, so every diagnostic of the generated text lands on the CDATA it came from.

use sfc_xmlmap::{Frag, XText};
use std::collections::HashMap;
use std::ops::Range;

/// The kinds of token the mapping needs to tell apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Tok {
    Ident,
    Number,
    Str,
    Comment,
    Space,
    /// `[:=]`, Logix's non-retentive assignment.
    Nra,
    /// `:=`
    Assign,
    Punct,
}

#[derive(Debug, Clone)]
pub(crate) struct Token {
    pub kind: Tok,
    pub range: Range<usize>,
}

/// Splits Logix ST into tokens covering every byte. Never fails: an unterminated comment or
/// string runs to the end.
pub(crate) fn tokens(s: &str) -> Vec<Token> {
    let b = s.as_bytes();
    let at = |i: usize| b.get(i).copied().unwrap_or(0);
    let starts = |i: usize, p: &str| s.get(i..).is_some_and(|r| r.starts_with(p));
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start = i;
        let c = at(i);
        let kind = if c.is_ascii_whitespace() {
            while i < b.len() && at(i).is_ascii_whitespace() {
                i += 1;
            }
            Tok::Space
        } else if starts(i, "//") {
            while i < b.len() && at(i) != b'\n' {
                i += 1;
            }
            Tok::Comment
        } else if starts(i, "(*") || starts(i, "/*") {
            let close = if c == b'(' { "*)" } else { "*/" };
            i = s.get(i + 2..).and_then(|r| r.find(close)).map_or(b.len(), |e| i + 2 + e + 2);
            Tok::Comment
        } else if c == b'\'' || c == b'"' {
            i += 1;
            while i < b.len() && at(i) != c {
                i += if at(i) == b'$' { 2 } else { 1 };
            }
            i = (i + 1).min(b.len());
            Tok::Str
        } else if starts(i, "[:=]") {
            i += 4;
            Tok::Nra
        } else if starts(i, ":=") {
            i += 2;
            Tok::Assign
        } else if c.is_ascii_alphabetic() || c == b'_' {
            while at(i).is_ascii_alphanumeric() || at(i) == b'_' {
                i += 1;
            }
            if at(i) == b'#' {
                // A typed literal: `T#1s500ms`, `DINT#5`, `TIME_OF_DAY#12:00:00`.
                i += 1;
                while at(i).is_ascii_alphanumeric() || matches!(at(i), b'_' | b'.' | b'#' | b':' | b'-') {
                    i += 1;
                }
                Tok::Number
            } else {
                Tok::Ident
            }
        } else if c.is_ascii_digit() {
            while at(i).is_ascii_alphanumeric()
                || matches!(at(i), b'_' | b'#')
                || (at(i) == b'.' && at(i + 1).is_ascii_digit())
            {
                // An exponent's sign: `1.5e+002`.
                let e = matches!(at(i), b'e' | b'E') && matches!(at(i + 1), b'+' | b'-');
                i += if e { 2 } else { 1 };
            }
            Tok::Number
        } else {
            i += s.get(i..).and_then(|r| r.chars().next()).map_or(1, char::len_utf8);
            Tok::Punct
        };
        out.push(Token { kind, range: start..i });
    }
    out
}

/// IEC 61131-3 words that are not tags.
const KEYWORDS: &[&str] = &[
    "AND",
    "OR",
    "XOR",
    "NOT",
    "MOD",
    "TRUE",
    "FALSE",
    "IF",
    "THEN",
    "ELSE",
    "ELSIF",
    "END_IF",
    "CASE",
    "OF",
    "END_CASE",
    "FOR",
    "TO",
    "BY",
    "DO",
    "END_FOR",
    "WHILE",
    "END_WHILE",
    "REPEAT",
    "UNTIL",
    "END_REPEAT",
    "RETURN",
    "EXIT",
];

/// Logix instructions callable from ST that sfc's ST does not have (or has with another
/// meaning: Logix's `TON(T)` runs a FBD_TIMER tag, IEC's TON is a function block type).
pub(crate) const INSTRUCTIONS: &[&str] = &[
    "JSR", "JXR", "SBR", "RET", "TND", "SFR", "SFP", "EVENT", "ONS", "OSRI", "OSFI", "TON", "TOF", "RTO", "TONR",
    "TOFR", "RTOR", "CTU", "CTD", "CTUD", "MSG", "GSV", "SSV", "IOT", "UID", "UIE", "AFI", "NOP", "COP", "CPS", "FLL",
    "SIZE", "BTD", "BTDT", "ALMD", "ALMA", "PID", "PIDE", "MAVE", "MAXC", "MINC", "SCL", "SCRV", "LDLG", "LDL2", "HPF",
    "LPF", "NTCH", "DEDT", "FGEN", "TOT", "RMPS", "SETD", "DFF", "JKFF", "SRT", "STD", "DDT", "DTR", "MSO", "MSF",
    "MAS", "MAJ", "MAM", "MAG", "MCD", "MCCD", "MCS", "MRP", "MCT", "MAH", "MAFR", "MASD", "MASR", "MDF", "MDO",
    "MDOC", "MGS", "MGSD", "MGSR", "MGSP", "STOD", "STOR", "DTOS", "RTOS", "UPPER", "LOWER", "DTOT", "TOD", "FRD",
    "CMP", "CPT", "DEG", "RAD", "TRN", "SWPB", "POVR", "PCMD", "PCLF", "PXRQ", "PATT", "PDET", "PPD", "PRNP", "PRDA",
    "PFL", "PSCAL", "SEL", "ESEL", "SSUM", "SNEG", "HLL", "RLIM", "SOC", "INTG", "PI", "UPDN", "MUX", "LDL", "ALM",
    "SEQ", "ATN", "XPY",
];

/// The members of an SFC_STEP tag that sfc's IEC text cannot say yet.
const STEP_MEMBERS: &[(&str, &str)] = &[
    ("ALARMEN", "FALSE"),
    ("ALARMLOW", "FALSE"),
    ("ALARMHIGH", "FALSE"),
    ("RESET", "FALSE"),
    ("PAUSETIMER", "FALSE"),
    ("STATUS", "0"),
    ("LIMITLOW", "0"),
    ("LIMITHIGH", "0"),
];

/// What the mapping knows of the chart's own elements.
#[derive(Default)]
pub(crate) struct Elements {
    /// Steps by upper-case operand: the name in text and the preset.
    pub steps: HashMap<String, StepInfo>,
    /// Actions by upper-case operand → name in text.
    pub actions: HashMap<String, String>,
    /// Tags imported under another name: upper-case Logix name → name in text.
    pub renamed: HashMap<String, String>,
    /// Upper-case names of the actions that are not Reset actions (those a Reset action may name).
    pub stored: std::collections::HashSet<String>,
    /// Stops by upper-case operand → name in text.
    pub stops: HashMap<String, String>,
}

#[derive(Clone, Default)]
pub(crate) struct StepInfo {
    pub name: String,
    /// The preset in ms from the step's tag (`PRE`), `None` when the tag is absent.
    pub pre: Option<i64>,
    /// The preset expression (`PresetUsesExpr="true"`), already mapped.
    pub pre_expr: Option<Frag>,
}

/// How an identifier the chart uses but the file does not declare is used (for the inferred
/// type of its declaration).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Use {
    Bool,
    Dint,
    /// A structure or array (`X.Y`, `X[1]`): no type can be inferred.
    Other,
}

/// A problem found while mapping: code, XML range, message, note.
pub(crate) type Problem = (&'static str, Range<u32>, String, Option<String>);

/// The result of mapping one piece of Logix ST.
#[derive(Default)]
pub(crate) struct Mapped {
    pub frag: Frag,
    /// Line indexes (of the piece's lines, from 0) that hold a `[:=]`.
    pub nra_lines: Vec<usize>,
    pub problems: Vec<Problem>,
    /// Identifiers (as written), how they are used, where.
    pub idents: Vec<(String, Use, Range<u32>)>,
    /// A `:=` outside parentheses (an assignment where an expression was expected).
    pub assigns: Vec<Range<u32>>,
}

/// The XML range of the text range `r` of `x`.
pub(crate) fn xml_range(x: &XText, r: Range<usize>) -> Range<u32> {
    let (s, e) = (r.start as u32, r.end as u32);
    let find =
        |o: u32| x.runs.iter().find(|run| run.text <= o && o < run.text + run.len).map(|run| run.raw + (o - run.text));
    match (find(s), find(e.saturating_sub(1).max(s))) {
        (Some(a), Some(b)) if b >= a => a..b + 1,
        (Some(a), _) => a..a + (e - s),
        _ => x.anchor.clone(),
    }
}

/// The text being written: what is copied from `x` and what replaces parts of it.
struct Writer<'x> {
    x: &'x XText,
    frag: Frag,
    copied: usize,
}

impl Writer<'_> {
    /// Replaces the text range `r` of the source by `f` (the text before it is copied).
    fn replace(&mut self, r: Range<usize>, f: Frag) {
        if r.start > self.copied {
            self.frag.push(&Frag::from_xtext(&self.x.slice(self.copied..r.start)));
        }
        self.frag.push(&f);
        self.copied = r.end.max(self.copied);
    }

    /// Replaces `r` by generated text located on the characters it replaces.
    fn replace_text(&mut self, r: Range<usize>, s: String) {
        let at = xml_range(self.x, r.clone());
        self.replace(r, Frag::located(s, at));
    }
}

/// Maps `x` (Logix ST) into sfc ST.
pub(crate) fn map(x: &XText, el: &Elements) -> Mapped {
    let text = x.text.as_str();
    let toks = tokens(text);
    let mut m = Mapped::default();
    let mut w = Writer { x, frag: Frag::default(), copied: 0 };
    let sig: Vec<&Token> = toks.iter().filter(|t| !matches!(t.kind, Tok::Space | Tok::Comment)).collect();
    let word = |t: Option<&&Token>| t.and_then(|t| text.get(t.range.clone())).unwrap_or("");
    let mut depth = 0i32;
    let line_of = |at: usize| text.get(..at).map_or(0, |t| t.matches('\n').count());
    let mut skip_until = 0usize;
    for (si, t) in sig.iter().enumerate() {
        if t.range.start < skip_until {
            continue;
        }
        let prev = si.checked_sub(1).and_then(|p| sig.get(p));
        let next = sig.get(si + 1);
        let next2 = sig.get(si + 2);
        match t.kind {
            Tok::Nra => {
                m.nra_lines.push(line_of(t.range.start));
                w.replace_text(t.range.clone(), ":=".into());
            }
            Tok::Assign if depth <= 0 => m.assigns.push(xml_range(x, t.range.clone())),
            Tok::Punct if word(Some(t)) == "(" => depth += 1,
            Tok::Punct if word(Some(t)) == ")" => depth -= 1,
            Tok::Ident => {
                let name = word(Some(t));
                let up = name.to_ascii_uppercase();
                if word(prev) == "." {
                    continue;
                }
                if let Some(new) = el.renamed.get(&up) {
                    w.replace_text(t.range.clone(), new.clone());
                    continue;
                }
                if KEYWORDS.contains(&up.as_str()) {
                    continue;
                }
                let member = next2.filter(|m| word(next) == "." && m.kind == Tok::Ident);
                if let Some(mt) = member {
                    let mname = word(Some(mt));
                    let mup = mname.to_ascii_uppercase();
                    let whole = t.range.start..mt.range.end;
                    let at = xml_range(x, whole.clone());
                    if let Some(s) = el.steps.get(&up) {
                        skip_until = mt.range.end;
                        member_of_step(&mut m, &mut w, s, &mup, mname, whole, at);
                    } else if let Some(a) = el.actions.get(&up) {
                        skip_until = mt.range.end;
                        if mup != "Q" && mup != "A" {
                            let placeholder =
                                if matches!(mup.as_str(), "T" | "PRE" | "COUNT" | "STATUS") { "0" } else { "FALSE" };
                            m.problems.push(logix_member(at, a, mname, "SFC_ACTION"));
                            w.replace_text(whole, placeholder.into());
                        }
                    } else if let Some(s) = el.stops.get(&up) {
                        skip_until = mt.range.end;
                        if mup != "X" {
                            let placeholder = if mup == "COUNT" || mup == "STATUS" { "0" } else { "FALSE" };
                            m.problems.push(logix_member(at, s, mname, "SFC_STOP"));
                            w.replace_text(whole, placeholder.into());
                        }
                    } else {
                        m.idents.push((name.to_string(), Use::Other, xml_range(x, t.range.clone())));
                    }
                    continue;
                }
                if word(next) == "(" {
                    if INSTRUCTIONS.contains(&up.as_str()) {
                        // Its operands are the instruction's (a routine, a storage bit): not tags
                        // to declare from their use.
                        let mut depth = 0i32;
                        for u in sig.get(si + 1..).unwrap_or_default() {
                            match text.get(u.range.clone()) {
                                Some("(") => depth += 1,
                                Some(")") => depth -= 1,
                                _ => {}
                            }
                            skip_until = u.range.end;
                            if depth <= 0 {
                                break;
                            }
                        }
                        m.problems.push((
                            "SFC0724",
                            xml_range(x, t.range.clone()),
                            format!("the Logix instruction `{name}` has no equivalent in sfc's ST"),
                            Some(instruction_note(&up)),
                        ));
                    }
                    continue;
                }
                if el.steps.contains_key(&up) || el.actions.contains_key(&up) || el.stops.contains_key(&up) {
                    continue;
                }
                let u = if word(next) == "[" { Use::Other } else { guess(&sig, si, text) };
                m.idents.push((name.to_string(), u, xml_range(x, t.range.clone())));
            }
            _ => {}
        }
    }
    if w.copied < text.len() {
        let rest = Frag::from_xtext(&x.slice(w.copied..text.len()));
        w.frag.push(&rest);
    }
    m.frag = w.frag;
    m.frag.atomic = false;
    m
}

/// The largest step time a Logix step timer (`T`, a DINT of ms) holds before it rolls over
/// (`OV`).
pub(crate) const OV_MS: i64 = 2_147_483_647;

/// `S.X` stays, `S.T` is a DINT of ms, `S.DN` the preset reached, `S.PRE` the preset; the
/// other members are the `logix` profile's.
fn member_of_step(
    m: &mut Mapped,
    w: &mut Writer,
    s: &StepInfo,
    mup: &str,
    member: &str,
    whole: Range<usize>,
    at: Range<u32>,
) {
    let n = &s.name;
    match (mup, &s.pre_expr) {
        ("X", _) => w.replace_text(whole, format!("{n}.X")),
        // How many times the step became active: the `logix` dialect's step member.
        ("COUNT", _) => w.replace_text(whole, format!("{n}.Count")),
        // Its first scan, the scans between, its last scan: the dialect's step members too.
        ("FS" | "SA" | "LS", _) => w.replace_text(whole, format!("{n}.{mup}")),
        ("TMAX", _) => w.replace_text(whole, format!("{n}.TMax")),
        // The timer rolled over: `T`, a DINT of ms in Logix, passed 2^31 - 1.
        ("OV", _) => w.replace_text(whole, format!("({n}.T > T#{OV_MS}ms)")),
        ("T", _) => w.replace_text(whole, format!("TIME_TO_DINT({n}.T)")),
        ("DN", Some(e)) => {
            let mut f = Frag::plain(format!("(TIME_TO_DINT({n}.T) >= "));
            f.push(&e.clone().operand());
            f.push_str(")");
            w.replace(whole, f.locate(at));
        }
        ("DN" | "PRE", None) if s.pre.is_none() => {
            m.problems.push((
                "SFC0721",
                at,
                format!("the step `{n}` has no SFC_STEP tag in the file: its preset is taken as 0 ms"),
                Some("export the program with its tags so that the steps' presets come along".into()),
            ));
            let text = if mup == "DN" { format!("({n}.T >= T#0ms)") } else { "0".to_string() };
            w.replace_text(whole, text);
        }
        ("DN", None) => w.replace_text(whole, format!("({n}.T >= T#{}ms)", s.pre.unwrap_or(0))),
        ("PRE", Some(e)) => {
            let mut f = Frag::plain("(");
            f.push(e);
            f.push_str(")");
            w.replace(whole, f.locate(at));
        }
        ("PRE", None) => w.replace_text(whole, format!("{}", s.pre.unwrap_or(0))),
        _ => {
            let placeholder = STEP_MEMBERS.iter().find(|(k, _)| *k == mup).map_or("FALSE", |(_, v)| v);
            m.problems.push(logix_member(at, n, member, "SFC_STEP"));
            w.replace_text(whole, placeholder.into());
        }
    }
}

fn logix_member(at: Range<u32>, element: &str, member: &str, ty: &str) -> Problem {
    (
        "SFC0723",
        at,
        format!("`{element}.{member}` is a member of Logix's {ty} tag that sfc's IEC text has no equivalent for"),
        Some(
            "the `logix` simulation profile does not simulate these SFC_STEP, SFC_ACTION and SFC_STOP members \
             yet; sfc reads `.X`, `.T` (as DINT ms), `.DN`, `.PRE`, `.OV`, `.Count`, `.FS`, `.SA`, `.LS` and `.TMax` of a step, \
             `.Q` and `.A` of an action and `.X` of a stop; the member is replaced by a constant in the text"
                .into(),
        ),
    )
}

fn instruction_note(up: &str) -> String {
    match up {
        "JSR" | "JXR" | "SBR" | "RET" => {
            "sfc imports SFC routines only; a routine called with JSR is not part of the chart".into()
        }
        "SFR" | "SFP" => {
            "resetting (SFR) and pausing (SFP) a chart are not simulated yet, by the `logix` profile either".into()
        }
        "TON" | "TOF" | "RTO" | "TONR" | "TOFR" | "RTOR" | "CTU" | "CTD" | "CTUD" => {
            "Logix's timers and counters run a tag with the instruction's own members; write the IEC function \
             block (`T1(IN := …, PT := T#…)`) or use the step's own timer (`Step.T`)"
                .into()
        }
        _ => "only IEC 61131-3 ST operators, functions and function blocks are checked and simulated".into(),
    }
}

/// The type an undeclared identifier is used as: DINT next to arithmetic, an ordering or a
/// number other than 0 and 1, BOOL otherwise.
fn guess(sig: &[&Token], si: usize, text: &str) -> Use {
    const ARITH: &[&str] = &["+", "-", "*", "/", "<", ">"];
    let word = |k: usize| sig.get(k).and_then(|t| text.get(t.range.clone())).unwrap_or("");
    let number = |k: usize| sig.get(k).is_some_and(|t| t.kind == Tok::Number) && !matches!(word(k), "0" | "1");
    for p in [si.checked_sub(1), Some(si + 1)].into_iter().flatten() {
        let w = word(p);
        if ARITH.contains(&w) || w.eq_ignore_ascii_case("MOD") || number(p) {
            return Use::Dint;
        }
        // `X := Y + 1;`: the right-hand side.
        if w == ":=" && p > si {
            let rhs =
                sig.get(p + 1..).unwrap_or_default().iter().take_while(|t| text.get(t.range.clone()) != Some(";"));
            let dint = rhs.enumerate().any(|(k, t)| {
                let tw = text.get(t.range.clone()).unwrap_or("");
                ARITH.contains(&tw) || tw.eq_ignore_ascii_case("MOD") || number(p + 1 + k)
            });
            if dint {
                return Use::Dint;
            }
        }
        // `X := 5`, `5 = X`: one further.
        if matches!(w, ":=" | "=" | "<>") {
            let q = if p > si { Some(p + 1) } else { p.checked_sub(1) };
            if q.is_some_and(number) {
                return Use::Dint;
            }
        }
    }
    Use::Bool
}
