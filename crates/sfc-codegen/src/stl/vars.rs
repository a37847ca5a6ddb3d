//! The variables the chart can see (the POU's declarations, then file-level globals), their
//! constant values, and the S7-200 operand each located variable names.

use super::ir::{Addr, Area, Val};
use sfc_diagnostics::Span;
use sfc_st::{const_eval, ConstLookup, Value};
use sfc_syntax::ast::{self, DirectAddress, Initializer, Item, Pou, Retain, SourceUnit, TypeSpecKind, VarKind};
use std::cell::RefCell;
use std::collections::HashMap;

/// The integer types the program computes with: 16 bits in a word, 32 in a double word.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum IntTy {
    Int,
    UInt,
    Word,
    DInt,
    UDInt,
    DWord,
}

impl IntTy {
    pub(crate) fn of(name: &str) -> Option<IntTy> {
        Some(match name {
            "INT" => IntTy::Int,
            "UINT" => IntTy::UInt,
            "WORD" => IntTy::Word,
            "DINT" => IntTy::DInt,
            "UDINT" => IntTy::UDInt,
            "DWORD" => IntTy::DWord,
            _ => return None,
        })
    }
    /// 32 bits.
    pub(crate) fn wide(self) -> bool {
        matches!(self, IntTy::DInt | IntTy::UDInt | IntTy::DWord)
    }
    /// Compared and divided as signed numbers (the S7-200 word instructions are signed).
    pub(crate) fn signed(self) -> bool {
        matches!(self, IntTy::Int | IntTy::DInt)
    }
    pub(crate) fn name(self) -> &'static str {
        match self {
            IntTy::Int => "INT",
            IntTy::UInt => "UINT",
            IntTy::Word => "WORD",
            IntTy::DInt => "DINT",
            IntTy::UDInt => "UDINT",
            IntTy::DWord => "DWORD",
        }
    }
    /// The value's bit pattern as the signed number the S7-200 stores.
    pub(crate) fn stored(self, v: i128) -> i64 {
        if self.wide() {
            i64::from(v as u32 as i32)
        } else {
            i64::from(v as u16 as i16)
        }
    }
}

/// The IEC counter blocks the program implements with S7-200 counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CounterKind {
    Ctu,
    Ctd,
    Ctud,
}

impl CounterKind {
    pub(crate) fn of(name: &str) -> Option<CounterKind> {
        Some(match name {
            "CTU" | "CTU_INT" => CounterKind::Ctu,
            "CTD" | "CTD_INT" => CounterKind::Ctd,
            "CTUD" | "CTUD_INT" => CounterKind::Ctud,
            _ => return None,
        })
    }
    pub(crate) fn name(self) -> &'static str {
        match self {
            CounterKind::Ctu => "CTU",
            CounterKind::Ctd => "CTD",
            CounterKind::Ctud => "CTUD",
        }
    }
}

/// One declared variable.
#[derive(Debug, Clone)]
pub(crate) struct Var {
    /// Declared spelling.
    pub name: String,
    pub kind: VarKind,
    pub constant: bool,
    pub retain: bool,
    /// The type name, upper-cased, when the type is written as a name (`BOOL`, `TIME`, …).
    pub ty: Option<String>,
    pub location: Option<DirectAddress>,
    /// The initial value when it is a constant expression.
    pub init: Option<Value>,
    init_expr: Option<ast::Expr>,
    /// Span of the name in its declaration.
    pub span: Span,
    /// The bit that holds it (BOOL variables that are not constants), once allocated.
    pub addr: Option<Addr>,
    /// The word or double word that holds it (integer variables), once allocated.
    pub val: Option<Val>,
    /// An implicit chart control variable the program adds (`SFCError`, `SFCQuitError`).
    pub implicit: bool,
}

impl Var {
    pub(crate) fn is_bool(&self) -> bool {
        self.ty.as_deref() == Some("BOOL")
    }
    /// A BOOL variable that lives in a bit (constants are folded instead).
    pub(crate) fn is_bit(&self) -> bool {
        self.is_bool() && !self.constant
    }
    pub(crate) fn int_ty(&self) -> Option<IntTy> {
        IntTy::of(self.ty.as_deref()?)
    }
    /// An integer variable that lives in a word or double word.
    pub(crate) fn is_word(&self) -> bool {
        self.int_ty().is_some() && !self.constant
    }
    pub(crate) fn is_time(&self) -> bool {
        self.ty.as_deref() == Some("TIME")
    }
    pub(crate) fn counter(&self) -> Option<CounterKind> {
        CounterKind::of(self.ty.as_deref()?)
    }
    /// Written from outside the program: `VAR_INPUT`, `VAR_IN_OUT`, or located in the input
    /// image. Its bit is not initialised by the program.
    pub(crate) fn is_input(&self) -> bool {
        matches!(self.kind, VarKind::Input | VarKind::InOut) || self.location.as_ref().is_some_and(|l| l.area == 'I')
    }
    pub(crate) fn kind_text(&self) -> String {
        let mut s = self.kind.keyword().to_string();
        if self.constant {
            s.push_str(" CONSTANT");
        }
        if self.retain {
            s.push_str(" RETAIN");
        }
        if let Some(l) = &self.location {
            s.push_str(" AT ");
            s.push_str(&l.text);
        }
        if let Some(t) = &self.ty {
            s.push_str(" : ");
            s.push_str(t);
        }
        if self.implicit {
            s.push_str(" (implicit)");
        }
        s
    }
}

/// The variables visible to the chart, by case-insensitive name.
pub(crate) struct Vars {
    pub list: Vec<Var>,
    index: HashMap<String, usize>,
    /// TIME variables read as constants (their initial value), in the order first folded.
    pub folded: RefCell<Vec<usize>>,
    /// Fold TIME variables that are not CONSTANT to their initial value.
    fold_time: std::cell::Cell<bool>,
}

impl Vars {
    /// The POU's declarations in order, then the file's `VAR_GLOBAL` blocks for names the POU
    /// does not declare; a `VAR_EXTERNAL` takes location and initial value from its global.
    pub(crate) fn collect(unit: &SourceUnit, pou: &Pou) -> Vars {
        let mut vars = Vars {
            list: Vec::new(),
            index: HashMap::new(),
            folded: RefCell::new(Vec::new()),
            fold_time: std::cell::Cell::new(false),
        };
        for b in &pou.var_blocks {
            vars.add_block(b);
        }
        for item in &unit.items {
            let Item::Globals(b) = item else { continue };
            for d in &b.decls {
                for n in &d.names {
                    match vars.index.get(&n.key()).copied() {
                        Some(i) if vars.list[i].kind == VarKind::External => {
                            let v = &mut vars.list[i];
                            v.location = d.location.clone();
                            v.constant |= b.constant;
                            v.retain |= matches!(b.retain, Some(Retain::Retain));
                            v.kind = VarKind::Global;
                            v.init_expr = init_expr(d);
                        }
                        Some(_) => {}
                        None => vars.push(n, d, b),
                    }
                }
            }
        }
        // Initial values, in declaration order, so a constant may use the constants before it.
        for i in 0..vars.list.len() {
            let v = vars.list[i].init_expr.as_ref().and_then(|e| const_eval(e, &vars));
            vars.list[i].init = v;
        }
        vars
    }

    fn add_block(&mut self, b: &ast::VarBlock) {
        for d in &b.decls {
            for n in &d.names {
                if !self.index.contains_key(&n.key()) {
                    self.push(n, d, b);
                }
            }
        }
    }

    fn push(&mut self, n: &ast::Ident, d: &ast::VarDecl, b: &ast::VarBlock) {
        let ty = match &d.ty.kind {
            TypeSpecKind::Named(id) => Some(id.text.to_ascii_uppercase()),
            _ => None,
        };
        self.index.insert(n.key(), self.list.len());
        self.list.push(Var {
            name: n.text.clone(),
            kind: b.kind,
            constant: b.constant,
            retain: matches!(b.retain, Some(Retain::Retain)),
            ty,
            location: d.location.clone(),
            init: None,
            init_expr: init_expr(d),
            span: n.span,
            addr: None,
            val: None,
            implicit: false,
        });
    }

    /// Adds an implicit BOOL chart control variable (not declared by the chart).
    pub(crate) fn add_implicit(&mut self, name: &str, kind: VarKind, span: Span) -> usize {
        let i = self.list.len();
        self.index.insert(name.to_ascii_uppercase(), i);
        self.list.push(Var {
            name: name.to_string(),
            kind,
            constant: false,
            retain: false,
            ty: Some("BOOL".into()),
            location: None,
            init: Some(Value::Bool(false)),
            init_expr: None,
            span,
            addr: None,
            val: None,
            implicit: true,
        });
        i
    }

    pub(crate) fn get(&self, name: &str) -> Option<usize> {
        self.index.get(&name.to_ascii_uppercase()).copied()
    }

    /// Evaluates a constant expression; TIME variables that are not CONSTANT count as their
    /// initial value (recorded in [`Vars::folded`]).
    pub(crate) fn eval_folding(&self, e: &ast::Expr) -> Option<Value> {
        self.fold_time.set(true);
        let v = const_eval(e, self);
        self.fold_time.set(false);
        v
    }
}

fn init_expr(d: &ast::VarDecl) -> Option<ast::Expr> {
    match &d.init {
        Some(Initializer::Expr(e)) => Some(e.clone()),
        _ => None,
    }
}

impl ConstLookup for Vars {
    fn constant(&self, name: &str) -> Option<Value> {
        let i = self.get(name)?;
        let v = &self.list[i];
        if v.constant {
            return v.init;
        }
        if self.fold_time.get() && v.is_time() {
            let mut f = self.folded.borrow_mut();
            if !f.contains(&i) {
                f.push(i);
            }
            return Some(v.init.unwrap_or(Value::Time(0)));
        }
        None
    }
}

/// Highest byte of each bit area the generator uses (CPU 22x): `I0.0`–`I15.7`, `Q0.0`–`Q15.7`,
/// `M0.0`–`M31.7`, `S0.0`–`S31.7`, `V` up to `VB10239`.
pub(crate) fn last_byte(area: Area) -> u32 {
    match area {
        Area::I | Area::Q => 15,
        Area::M | Area::S => 31,
        Area::V => 10239,
        Area::Sm => 0,
    }
}

fn area_of(a: &DirectAddress) -> Result<Area, String> {
    match a.area.to_ascii_uppercase() {
        'I' => Ok(Area::I),
        'Q' => Ok(Area::Q),
        'M' => Ok(Area::M),
        _ => Err(format!("`{}` is not an input, output or memory address", a.text)),
    }
}

/// The bit a direct address names: `%IX0.3` → `I0.3`, `%QX1.0` → `Q1.0`, `%MX2.7` → `M2.7`.
pub(crate) fn bit_address(a: &DirectAddress) -> Result<Addr, String> {
    let area = area_of(a)?;
    if !a.size.eq_ignore_ascii_case(&'X') {
        return Err(format!("`{}` is not a bit address: write `%{}X<byte>.<bit>`", a.text, a.area));
    }
    let [byte, bit] = a.path[..] else {
        return Err(format!("`{}` needs a byte and a bit number: `%{}X<byte>.<bit>`", a.text, a.area));
    };
    if bit > 7 {
        return Err(format!("`{}`: the bit number must be 0 to 7", a.text));
    }
    if byte > last_byte(area) {
        return Err(format!(
            "`{}` is outside {}0.0-{}{}.7 of the S7-200",
            a.text,
            area.prefix(),
            area.prefix(),
            last_byte(area)
        ));
    }
    Ok(Addr::Bit(area, byte, bit as u8))
}

/// The word or double word a direct address names: `%MW10` → `MW10`, `%QW0` → `QW0`,
/// `%MD4` → `MD4`, `%IW2` → `IW2`.
pub(crate) fn value_address(a: &DirectAddress, wide: bool) -> Result<Val, String> {
    let area = area_of(a)?;
    let (letter, len) = if wide { ('D', 4) } else { ('W', 2) };
    if !a.size.eq_ignore_ascii_case(&letter) {
        return Err(format!("`{}` does not fit a {}-bit variable: write `%{}{letter}<byte>`", a.text, len * 8, a.area));
    }
    let [byte] = a.path[..] else {
        return Err(format!("`{}` needs one byte number: `%{}{letter}<byte>`", a.text, a.area));
    };
    if byte + len - 1 > last_byte(area) {
        return Err(format!("`{}` is outside the {} area of the S7-200", a.text, area.prefix()));
    }
    Ok(if wide { Val::DWord(area, byte) } else { Val::Word(area, byte) })
}
