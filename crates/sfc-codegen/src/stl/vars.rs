//! The variables the chart can see (the POU's declarations, then file-level globals), their
//! constant values, and the S7-200 bit each located BOOL variable names.

use super::ir::{Addr, Area};
use sfc_diagnostics::Span;
use sfc_st::{const_eval, ConstLookup, Value};
use sfc_syntax::ast::{self, DirectAddress, Initializer, Item, Pou, SourceUnit, TypeSpecKind, VarKind};
use std::collections::HashMap;

/// One declared variable.
#[derive(Debug, Clone)]
pub(crate) struct Var {
    /// Declared spelling.
    pub name: String,
    pub kind: VarKind,
    pub constant: bool,
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
}

impl Var {
    pub(crate) fn is_bool(&self) -> bool {
        self.ty.as_deref() == Some("BOOL")
    }
    /// A BOOL variable that lives in a bit (constants are folded instead).
    pub(crate) fn is_bit(&self) -> bool {
        self.is_bool() && !self.constant
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
        if let Some(l) = &self.location {
            s.push_str(" AT ");
            s.push_str(&l.text);
        }
        s
    }
}

/// The variables visible to the chart, by case-insensitive name.
pub(crate) struct Vars {
    pub list: Vec<Var>,
    index: HashMap<String, usize>,
}

impl Vars {
    /// The POU's declarations in order, then the file's `VAR_GLOBAL` blocks for names the POU
    /// does not declare; a `VAR_EXTERNAL` takes location and initial value from its global.
    pub(crate) fn collect(unit: &SourceUnit, pou: &Pou) -> Vars {
        let mut vars = Vars { list: Vec::new(), index: HashMap::new() };
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
            ty,
            location: d.location.clone(),
            init: None,
            init_expr: init_expr(d),
            span: n.span,
            addr: None,
        });
    }

    pub(crate) fn get(&self, name: &str) -> Option<usize> {
        self.index.get(&name.to_ascii_uppercase()).copied()
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
        let v = &self.list[self.get(name)?];
        if v.constant {
            v.init
        } else {
            None
        }
    }
}

/// Highest byte of each area the generator uses (CPU 22x): `I0.0`–`I15.7`, `Q0.0`–`Q15.7`,
/// `M0.0`–`M31.7`.
pub(crate) fn last_byte(area: Area) -> u32 {
    match area {
        Area::I | Area::Q => 15,
        Area::M | Area::S => 31,
        Area::V => 2047,
        Area::Sm => 0,
    }
}

/// The bit a direct address names: `%IX0.3` → `I0.3`, `%QX1.0` → `Q1.0`, `%MX2.7` → `M2.7`.
pub(crate) fn bit_address(a: &DirectAddress) -> Result<Addr, String> {
    let area = match a.area.to_ascii_uppercase() {
        'I' => Area::I,
        'Q' => Area::Q,
        'M' => Area::M,
        _ => return Err(format!("`{}` is not an input, output or memory address", a.text)),
    };
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
            "`{}` is outside {}0.0–{}{}.7 of the S7-200",
            a.text,
            area.prefix(),
            area.prefix(),
            last_byte(area)
        ));
    }
    Ok(Addr::Bit(area, byte, bit as u8))
}
