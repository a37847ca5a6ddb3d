//! A Boolean ST expression → a LAD network (`FlgNet`) of the forms the import reads
//! (`flgnet.rs`): an AND chain is contacts in series, an OR is an `O` box whose inputs start
//! where the chain stands, NOT of an operand is a negated contact, a comparison is a comparator
//! (`Eq` … `Le`) with its `SrcType`; XOR is an `X` box and the NOT of a compound value a negated
//! input of an `A` box (FBD's boxes, which the import reads alike). Anything else (arithmetic,
//! calls) is refused with the reason.

use super::xml::{esc, W};
use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, LiteralKind, UnaryOp};
use std::collections::HashMap;

/// What the names of a POU are, for its operands.
#[derive(Default)]
pub(crate) struct Operands {
    /// Variables of the POU (upper case) → their IEC type (upper case).
    pub vars: HashMap<String, String>,
    /// Globals (upper case) → (how TIA writes them, `"DB".a.b`, and their IEC type).
    pub globals: HashMap<String, (String, String)>,
    /// Steps (upper case IEC name) → their GRAPH names.
    pub steps: HashMap<String, String>,
    /// Transitions (upper case IEC name) → their GRAPH names.
    pub transitions: HashMap<String, String>,
    /// Each transition's condition as printed → its GRAPH name: the import writes a
    /// transition's `TT` read in an interlock or a supervision as `(condition)`.
    pub tt: Vec<(String, String)>,
}

/// Where a value comes from in the network.
#[derive(Clone, Copy)]
pub(crate) enum Src {
    Rail,
    Out(u32),
}

pub(crate) struct Net<'o> {
    ops: &'o Operands,
    /// An interlock or a supervision, where `(condition)` is a transition's `TT`.
    pub kept: bool,
    accesses: Vec<String>,
    parts: Vec<String>,
    wires: Vec<String>,
    next: u32,
}

/// An IEC elementary type as SIMATIC writes it.
pub(crate) fn simatic_type(iec: &str) -> Option<&'static str> {
    Some(match iec.trim().to_ascii_uppercase().as_str() {
        "BOOL" => "Bool",
        "BYTE" => "Byte",
        "WORD" => "Word",
        "DWORD" => "DWord",
        "LWORD" => "LWord",
        "SINT" => "SInt",
        "INT" => "Int",
        "DINT" => "DInt",
        "LINT" => "LInt",
        "USINT" => "USInt",
        "UINT" => "UInt",
        "UDINT" => "UDInt",
        "ULINT" => "ULInt",
        "REAL" => "Real",
        "LREAL" => "LReal",
        "TIME" => "Time",
        "LTIME" => "LTime",
        "DATE" => "Date",
        "TIME_OF_DAY" | "TOD" => "Time_Of_Day",
        "DATE_AND_TIME" | "DT" => "Date_And_Time",
        "CHAR" => "Char",
        "WCHAR" => "WChar",
        "STRING" => "String",
        "WSTRING" => "WString",
        _ => return None,
    })
}

/// One component of a symbol: its name and its indices (as `Access` elements).
struct Comp {
    name: String,
    idx: Vec<String>,
}

/// `"DB".a[3].b` → its components.
fn parse_origin(origin: &str) -> Option<Vec<Comp>> {
    let chars: Vec<char> = origin.chars().collect();
    let mut i = 0;
    let mut out = Vec::new();
    loop {
        let name: String = if chars.get(i) == Some(&'"') {
            let start = i + 1;
            i += 1;
            while chars.get(i).is_some_and(|c| *c != '"') {
                i += 1;
            }
            let n = chars.get(start..i)?.iter().collect();
            i += 1;
            n
        } else {
            let start = i;
            while chars.get(i).is_some_and(|c| *c != '.' && *c != '[') {
                i += 1;
            }
            chars.get(start..i)?.iter().collect()
        };
        let mut idx = Vec::new();
        if chars.get(i) == Some(&'[') {
            let start = i + 1;
            while chars.get(i).is_some_and(|c| *c != ']') {
                i += 1;
            }
            let inner: String = chars.get(start..i)?.iter().collect();
            i += 1;
            for x in inner.split(',') {
                idx.push(constant_access(x.trim(), Some("DInt")));
            }
        }
        out.push(Comp { name, idx });
        if chars.get(i) == Some(&'.') {
            i += 1;
            continue;
        }
        break;
    }
    (i >= chars.len()).then_some(out)
}

fn constant_access(v: &str, ty: Option<&str>) -> String {
    let scope = if v.contains('#') { "TypedConstant" } else { "LiteralConstant" };
    let t = ty.map(|t| format!("<ConstantType>{t}</ConstantType>")).unwrap_or_default();
    format!("<Access Scope=\"{scope}\"><Constant>{t}<ConstantValue>{}</ConstantValue></Constant></Access>", esc(v))
}

fn symbol(comps: &[Comp]) -> String {
    let mut s = String::from("<Symbol>");
    for c in comps {
        if c.idx.is_empty() {
            s.push_str(&format!("<Component Name=\"{}\" />", esc(&c.name)));
        } else {
            s.push_str(&format!(
                "<Component Name=\"{}\" AccessModifier=\"Array\">{}</Component>",
                esc(&c.name),
                c.idx.concat()
            ));
        }
    }
    s.push_str("</Symbol>");
    s
}

fn strip(e: &Expr) -> &Expr {
    match &e.kind {
        ExprKind::Paren(inner) => strip(inner),
        _ => e,
    }
}

/// The operands of a chain of `op` (not through parentheses).
fn flatten<'e>(e: &'e Expr, op: BinaryOp, out: &mut Vec<&'e Expr>) {
    match &e.kind {
        ExprKind::Binary { op: o, lhs, rhs } if *o == op => {
            flatten(lhs, op, out);
            flatten(rhs, op, out);
        }
        _ => out.push(e),
    }
}

impl<'o> Net<'o> {
    pub fn new(ops: &'o Operands) -> Net<'o> {
        Net { ops, kept: false, accesses: Vec::new(), parts: Vec::new(), wires: Vec::new(), next: 21 }
    }

    fn uid(&mut self) -> u32 {
        let u = self.next;
        self.next += 1;
        u
    }

    fn wire(&mut self, from: Src, to: u32, pin: &str) {
        let w = self.uid();
        let src = match from {
            Src::Rail => "<Powerrail />".to_string(),
            Src::Out(u) => format!("<NameCon UId=\"{u}\" Name=\"out\" />"),
        };
        self.wires.push(format!("<Wire UId=\"{w}\">{src}<NameCon UId=\"{to}\" Name=\"{pin}\" /></Wire>"));
    }

    fn wire_ident(&mut self, acc: u32, to: u32, pin: &str) {
        let w = self.uid();
        self.wires.push(format!(
            "<Wire UId=\"{w}\"><IdentCon UId=\"{acc}\" /><NameCon UId=\"{to}\" Name=\"{pin}\" /></Wire>"
        ));
    }

    fn part(&mut self, name: &str, inner: &str) -> u32 {
        let u = self.uid();
        if inner.is_empty() {
            self.parts.push(format!("<Part Name=\"{name}\" UId=\"{u}\" />"));
        } else {
            self.parts.push(format!("<Part Name=\"{name}\" UId=\"{u}\">{inner}</Part>"));
        }
        u
    }

    /// The components of a variable, a member or an element, and whether it is global.
    fn comps(&self, e: &Expr) -> Result<(Vec<Comp>, bool), String> {
        match &strip(e).kind {
            ExprKind::Name(id) => {
                let up = id.text.to_ascii_uppercase();
                if let Some((origin, _)) = self.ops.globals.get(&up) {
                    if let Some(c) = parse_origin(origin) {
                        return Ok((c, true));
                    }
                }
                if let Some(raw) = self.ops.steps.get(&up).or_else(|| self.ops.transitions.get(&up)) {
                    return Ok((vec![Comp { name: raw.clone(), idx: Vec::new() }], false));
                }
                if self.ops.vars.contains_key(&up) {
                    return Ok((vec![Comp { name: id.text.clone(), idx: Vec::new() }], false));
                }
                Err(format!("`{}` is no variable of the block, which a GRAPH network can read", id.text))
            }
            ExprKind::Member { base, member } => {
                let (mut c, g) = self.comps(base)?;
                c.push(Comp { name: member.text.clone(), idx: Vec::new() });
                Ok((c, g))
            }
            ExprKind::Index { base, indices } => {
                let (mut c, g) = self.comps(base)?;
                let mut idx = Vec::new();
                for i in indices {
                    idx.push(self.access_xml(i, None)?);
                }
                match c.last_mut() {
                    Some(last) if last.idx.is_empty() => last.idx = idx,
                    _ => return Err("an element of an element cannot be written".into()),
                }
                Ok((c, g))
            }
            _ => Err(format!("`{}` is no operand a LAD network can read", sfc_syntax::print::expr(e))),
        }
    }

    /// An operand as an `Access` element (without a UId).
    fn access_xml(&self, e: &Expr, ty: Option<&str>) -> Result<String, String> {
        let e = strip(e);
        match &e.kind {
            ExprKind::Literal(l) => {
                let v = match l.kind {
                    LiteralKind::Bool(b) if l.type_prefix.is_none() => b.to_string(),
                    _ => l.text.clone(),
                };
                Ok(constant_access(&v, ty.filter(|_| !v.contains('#'))))
            }
            ExprKind::Unary { op: UnaryOp::Neg, operand } => match &strip(operand).kind {
                ExprKind::Literal(l) if !l.text.contains('#') => Ok(constant_access(&format!("-{}", l.text), ty)),
                _ => Err(format!("`{}` is no operand a LAD network can read", sfc_syntax::print::expr(e))),
            },
            // A step's time compared as an integer: the import converts it back.
            ExprKind::Call { callee, args }
                if callee.text.to_ascii_uppercase().starts_with("TIME_TO_") && args.len() == 1 =>
            {
                match args.first().and_then(|a| a.value.as_ref()) {
                    Some(v) if self.is_step_time(v) => self.access_xml(v, None),
                    _ => Err(format!("the call `{}` cannot be written in a LAD network", sfc_syntax::print::expr(e))),
                }
            }
            _ => {
                let (c, global) = self.comps(e)?;
                let scope = if global { "GlobalVariable" } else { "LocalVariable" };
                Ok(format!("<Access Scope=\"{scope}\">{}</Access>", symbol(&c)))
            }
        }
    }

    fn is_step_time(&self, e: &Expr) -> bool {
        match &strip(e).kind {
            ExprKind::Member { base, member } => {
                matches!(&strip(base).kind, ExprKind::Name(b) if self.ops.steps.contains_key(&b.text.to_ascii_uppercase()))
                    && matches!(member.text.to_ascii_uppercase().as_str(), "T" | "U")
            }
            _ => false,
        }
    }

    /// An `Access` part for `e`; its UId.
    fn operand(&mut self, e: &Expr, ty: Option<&str>) -> Result<u32, String> {
        let x = self.access_xml(e, ty)?;
        let u = self.uid();
        let x = x.replacen("<Access ", &format!("<Access UId=\"{u}\" "), 1);
        // Keep the attribute order TIA writes: Scope first.
        let x = x.replacen(
            &format!("<Access UId=\"{u}\" Scope=\"{}\"", scope_of(&x)),
            &format!("<Access Scope=\"{}\" UId=\"{u}\"", scope_of(&x)),
            1,
        );
        self.accesses.push(x);
        Ok(u)
    }

    /// The IEC type of an operand, if known.
    fn type_of(&self, e: &Expr) -> Option<String> {
        match &strip(e).kind {
            ExprKind::Name(id) => {
                let up = id.text.to_ascii_uppercase();
                self.ops.vars.get(&up).cloned().or_else(|| self.ops.globals.get(&up).map(|g| g.1.clone()))
            }
            ExprKind::Member { .. } if self.is_step_time(e) => Some("TIME".into()),
            ExprKind::Literal(l) => match l.kind {
                LiteralKind::Real(_) => Some("REAL".into()),
                LiteralKind::Duration(_) => Some("TIME".into()),
                LiteralKind::Bool(_) => Some("BOOL".into()),
                _ => l.type_prefix.clone(),
            },
            ExprKind::Call { callee, .. } => {
                callee.text.to_ascii_uppercase().strip_prefix("TIME_TO_").map(str::to_string)
            }
            _ => None,
        }
    }

    /// The GRAPH name of the transition whose `TT` `e` is (`(condition)` in a kept network).
    fn tt_of(&self, e: &Expr) -> Option<String> {
        if !self.kept {
            return None;
        }
        let ExprKind::Paren(inner) = &e.kind else { return None };
        let text = sfc_syntax::print::expr(inner);
        self.ops.tt.iter().find(|(c, _)| *c == text).map(|(_, t)| t.clone())
    }

    fn contact_tt(&mut self, trans: &str, input: Src, negated: bool) -> Src {
        let u = self.uid();
        self.accesses.push(format!(
            "<Access Scope=\"LocalVariable\" UId=\"{u}\"><Symbol><Component Name=\"{}\" /><Component Name=\"TT\" /></Symbol></Access>",
            esc(trans)
        ));
        let c = self.part("Contact", if negated { "<Negated Name=\"operand\" />" } else { "" });
        self.wire(input, c, "in");
        self.wire_ident(u, c, "operand");
        Src::Out(c)
    }

    /// Writes `input AND e`; returns where that value comes out.
    pub fn chain(&mut self, e: &Expr, input: Src) -> Result<Src, String> {
        if let Some(t) = self.tt_of(e) {
            return Ok(self.contact_tt(&t, input, false));
        }
        if let ExprKind::Unary { op: UnaryOp::Not, operand } = &e.kind {
            if let Some(t) = self.tt_of(operand) {
                return Ok(self.contact_tt(&t, input, true));
            }
        }
        match &e.kind {
            ExprKind::Paren(inner) => self.chain(inner, input),
            ExprKind::Binary { op: BinaryOp::And | BinaryOp::AndThen, .. } => {
                let mut terms = Vec::new();
                flatten(e, BinaryOp::And, &mut terms);
                let mut src = input;
                for t in terms {
                    src = self.chain(t, src)?;
                }
                Ok(src)
            }
            ExprKind::Binary { op: BinaryOp::Or | BinaryOp::OrElse, .. } => {
                let mut terms = Vec::new();
                flatten(e, BinaryOp::Or, &mut terms);
                let mut outs = Vec::new();
                for t in terms {
                    outs.push(self.chain(t, input)?);
                }
                let o = self.part(
                    "O",
                    &format!("<TemplateValue Name=\"Card\" Type=\"Cardinality\">{}</TemplateValue>", outs.len()),
                );
                for (i, s) in outs.into_iter().enumerate() {
                    self.wire(s, o, &format!("in{}", i + 1));
                }
                Ok(Src::Out(o))
            }
            ExprKind::Binary { op: BinaryOp::Xor, lhs, rhs } => {
                let a = self.chain(lhs, Src::Rail)?;
                let b = self.chain(rhs, Src::Rail)?;
                let x = self.part("X", "<TemplateValue Name=\"Card\" Type=\"Cardinality\">2</TemplateValue>");
                self.wire(a, x, "in1");
                self.wire(b, x, "in2");
                Ok(self.and_box(input, Src::Out(x), false))
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let name = match op {
                    BinaryOp::Eq => "Eq",
                    BinaryOp::Ne => "Ne",
                    BinaryOp::Gt => "Gt",
                    BinaryOp::Ge => "Ge",
                    BinaryOp::Lt => "Lt",
                    BinaryOp::Le => "Le",
                    _ => {
                        return Err(format!(
                            "`{}` is arithmetic, which a LAD condition cannot hold",
                            sfc_syntax::print::expr(e)
                        ))
                    }
                };
                let ty = self.type_of(lhs).or_else(|| self.type_of(rhs)).unwrap_or_else(|| "INT".into());
                let st = simatic_type(&ty).unwrap_or("Int");
                let a = self.operand(lhs, Some(st))?;
                let b = self.operand(rhs, Some(st))?;
                let c = self.part(name, &format!("<TemplateValue Name=\"SrcType\" Type=\"Type\">{st}</TemplateValue>"));
                self.wire(input, c, "pre");
                self.wire_ident(a, c, "in1");
                self.wire_ident(b, c, "in2");
                Ok(Src::Out(c))
            }
            ExprKind::Unary { op: UnaryOp::Not, operand } => {
                if self.comps(operand).is_ok() && !matches!(strip(operand).kind, ExprKind::Literal(_)) {
                    return self.contact(operand, input, true);
                }
                let inner = self.chain(operand, Src::Rail)?;
                Ok(self.and_box(input, inner, true))
            }
            ExprKind::Literal(l) if matches!(l.kind, LiteralKind::Bool(true)) => Ok(input),
            ExprKind::Literal(l) if matches!(l.kind, LiteralKind::Bool(false)) => self.contact(e, input, false),
            ExprKind::Name(_) | ExprKind::Member { .. } | ExprKind::Index { .. } => self.contact(e, input, false),
            _ => Err(format!("`{}` cannot be written as a LAD condition", sfc_syntax::print::expr(e))),
        }
    }

    fn contact(&mut self, e: &Expr, input: Src, negated: bool) -> Result<Src, String> {
        let a = self.operand(e, Some("Bool"))?;
        let c = self.part("Contact", if negated { "<Negated Name=\"operand\" />" } else { "" });
        self.wire(input, c, "in");
        self.wire_ident(a, c, "operand");
        Ok(Src::Out(c))
    }

    /// `input AND value` through an `A` box (`value` negated when `negate`); just `value` when
    /// the input is the rail and nothing is negated.
    fn and_box(&mut self, input: Src, value: Src, negate: bool) -> Src {
        if matches!(input, Src::Rail) && !negate {
            return value;
        }
        let n = if matches!(input, Src::Rail) { 1 } else { 2 };
        let pin = format!("in{n}");
        let inner = format!(
            "<TemplateValue Name=\"Card\" Type=\"Cardinality\">{n}</TemplateValue>{}",
            if negate { format!("<Negated Name=\"{pin}\" />") } else { String::new() }
        );
        let a = self.part("A", &inner);
        if n == 2 {
            self.wire(input, a, "in1");
        }
        self.wire(value, a, &pin);
        Src::Out(a)
    }

    /// A coil part (`TrCoil`, `IlCoil`, `SvCoil`) fed by `src`.
    pub fn coil(&mut self, name: &str, src: Src) {
        let c = self.part(name, "");
        self.wire(src, c, "in");
    }

    /// A permanent instruction's coil (`Coil`, `SCoil`, `RCoil`) on `target`, fed by `src`.
    pub fn assign(&mut self, name: &str, target: &Expr, src: Src) -> Result<(), String> {
        let a = self.operand(target, Some("Bool"))?;
        let c = self.part(name, "");
        self.wire(src, c, "in");
        self.wire_ident(a, c, "operand");
        Ok(())
    }

    pub fn write(self, w: &mut W) {
        w.open("FlgNet", &[]);
        w.open("Parts", &[]);
        for a in self.accesses.iter().chain(self.parts.iter()) {
            w.raw(a);
        }
        w.close("Parts");
        w.open("Wires", &[]);
        for x in &self.wires {
            w.raw(x);
        }
        w.close("Wires");
        w.close("FlgNet");
    }
}

fn scope_of(x: &str) -> &str {
    x.split("Scope=\"").nth(1).and_then(|r| r.split('"').next()).unwrap_or("")
}
