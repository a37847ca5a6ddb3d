//! How a POU is wired to the machine, as the diagnostics of a running machine need it: the
//! terminal labels of its variables (`{attribute 'sfc.terminal' := 'X12.3'}`), the variable
//! that holds its error code (`{attribute 'sfc.error_code'}`), and what its function block
//! calls pass to their inputs (`Rev(KM2Fb := KM2Contact)`), so an input of a mechanism can be
//! followed to the located variable of its caller.

use sfc_st::Type;
use sfc_syntax::ast::{ActionBody, Body, Expr, ExprKind, Pou, SfcElement, Stmt, StmtKind, VarKind};
use std::collections::HashMap;

/// The wiring of one POU (names are keys: lowercase).
#[derive(Debug, Clone, Default)]
pub struct Wiring {
    /// Variable → its `sfc.terminal` label.
    pub terminals: HashMap<String, String>,
    /// The variable named with `sfc.error_code`, as declared.
    pub error_code: Option<String>,
    /// The activation bit of a mechanism, named with `sfc.activation`, as declared.
    pub activation: Option<String>,
    /// `(instance, input)` → the variable path or direct address passed to it, as written,
    /// from the calls in the POU's body (the last call wins when calls differ).
    pub bindings: HashMap<(String, String), String>,
}

impl Wiring {
    pub(crate) fn of(p: &Pou) -> Wiring {
        let mut w = Wiring::default();
        for block in &p.var_blocks {
            for d in &block.decls {
                for a in &d.attributes {
                    for n in &d.names {
                        if a.name.eq_ignore_ascii_case("sfc.terminal") {
                            if let Some(v) = a.value.as_ref().filter(|v| !v.trim().is_empty()) {
                                w.terminals.insert(n.text.to_ascii_lowercase(), v.trim().to_string());
                            }
                        } else if a.name.eq_ignore_ascii_case("sfc.error_code") && w.error_code.is_none() {
                            w.error_code = Some(n.text.clone());
                        } else if a.name.eq_ignore_ascii_case("sfc.activation") && w.activation.is_none() {
                            w.activation = Some(n.text.clone());
                        }
                    }
                }
            }
        }
        match &p.body {
            Body::St(stmts) => w.statements(stmts, 0),
            Body::Sfc(elements) => {
                for e in elements {
                    if let SfcElement::Action(a) = e {
                        if let ActionBody::St(stmts) = &a.body {
                            w.statements(stmts, 0);
                        }
                    }
                }
            }
            Body::Il(_) => {}
        }
        w
    }

    fn statements(&mut self, stmts: &[Stmt], depth: u32) {
        if depth > 64 {
            return;
        }
        for s in stmts {
            match &s.kind {
                StmtKind::Call(e) => self.call(e),
                StmtKind::If { branches, else_body } => {
                    for (_, b) in branches {
                        self.statements(b, depth + 1);
                    }
                    if let Some(b) = else_body {
                        self.statements(b, depth + 1);
                    }
                }
                StmtKind::Case { arms, else_body, .. } => {
                    for a in arms {
                        self.statements(&a.body, depth + 1);
                    }
                    if let Some(b) = else_body {
                        self.statements(b, depth + 1);
                    }
                }
                StmtKind::For { body, .. } | StmtKind::While { body, .. } | StmtKind::Repeat { body, .. } => {
                    self.statements(body, depth + 1)
                }
                _ => {}
            }
        }
    }

    fn call(&mut self, e: &Expr) {
        let ExprKind::Call { callee, args } = &e.kind else { return };
        for a in args {
            let (Some(name), Some(value), false) = (&a.name, &a.value, a.output) else { continue };
            if let Some(path) = path_of(value, 0) {
                self.bindings.insert((callee.text.to_ascii_lowercase(), name.text.to_ascii_lowercase()), path);
            }
        }
    }
}

/// A variable path (`KM2Contact`, `Io.In3`) or direct address (`%IX0.5`) as text.
fn path_of(e: &Expr, depth: u32) -> Option<String> {
    if depth > 16 {
        return None;
    }
    match &e.kind {
        ExprKind::Name(n) => Some(n.text.clone()),
        ExprKind::Address(a) => Some(a.text.clone()),
        ExprKind::Paren(inner) => path_of(inner, depth + 1),
        ExprKind::Member { base, member } => Some(format!("{}.{}", path_of(base, depth + 1)?, member.text)),
        _ => None,
    }
}

/// Where a variable meets the machine: the label of the machine's own numbering
/// (`sfc.terminal`) and the IEC address (`AT %IX0.5`), either of which may be missing.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Terminal {
    pub label: Option<String>,
    pub address: Option<String>,
}

impl Terminal {
    /// `X12.3, %IX0.5`, `%IX0.5` or `X12.3`; `None` when neither is known.
    pub fn text(&self) -> Option<String> {
        match (&self.label, &self.address) {
            (Some(l), Some(a)) if !l.eq_ignore_ascii_case(a) => Some(format!("{l}, {a}")),
            (Some(l), _) => Some(l.clone()),
            (None, Some(a)) => Some(a.clone()),
            (None, None) => None,
        }
    }
}

impl super::Program {
    /// The terminal of the variable at `path` (as [`super::Program::resolve`] takes it,
    /// relative to the top POU `top`): its own `sfc.terminal` label and AT address; an input of
    /// a function block instance without an address is followed to what its caller passes
    /// (`Rev.KM2Fb` → `KM2Contact AT %IX0.5`), keeping the nearest label.
    pub fn terminal(&self, top: usize, path: &str) -> Option<Terminal> {
        self.terminal_at(top, path.trim(), 0)
    }

    fn terminal_at(&self, top: usize, path: &str, depth: u32) -> Option<Terminal> {
        if depth > 8 || path.contains('[') {
            return None;
        }
        if path.starts_with('%') {
            return Some(Terminal { label: None, address: Some(path.to_string()) });
        }
        let segs: Vec<&str> = path.split('.').map(str::trim).collect();
        let (last, inner) = segs.split_last()?;
        let mut pou = top;
        for seg in inner {
            let v = self.pous[pou].layout.vars.iter().find(|v| v.name.eq_ignore_ascii_case(seg))?;
            let Type::FunctionBlock(fb) = &v.ty else { return None };
            pou = self.fb_index(fb)?;
        }
        let key = last.to_ascii_lowercase();
        let Some(v) = self.pous[pou].layout.vars.iter().find(|v| v.name.eq_ignore_ascii_case(last)) else {
            // A global read from the top POU.
            if !inner.is_empty() {
                return None;
            }
            let g = self.globals.vars.iter().find(|v| v.name.eq_ignore_ascii_case(last))?;
            let t = Terminal { label: None, address: g.location.clone() };
            return t.text().map(|_| t);
        };
        let mut t = Terminal { label: self.pous[pou].wiring.terminals.get(&key).cloned(), address: v.location.clone() };
        if t.address.is_none() && matches!(v.kind, VarKind::Input | VarKind::InOut) && !inner.is_empty() {
            let (instance, outer) = inner.split_last()?;
            let mut caller = top;
            for seg in outer {
                let v = self.pous[caller].layout.vars.iter().find(|v| v.name.eq_ignore_ascii_case(seg))?;
                let Type::FunctionBlock(fb) = &v.ty else { return None };
                caller = self.fb_index(fb)?;
            }
            let bound = self.pous[caller].wiring.bindings.get(&(instance.to_ascii_lowercase(), key));
            if let Some(arg) = bound {
                let full = if outer.is_empty() || arg.starts_with('%') {
                    arg.clone()
                } else {
                    format!("{}.{arg}", outer.join("."))
                };
                if let Some(from) = self.terminal_at(top, &full, depth + 1) {
                    t.address = from.address;
                    t.label = t.label.or(from.label);
                }
            }
        }
        t.text().map(|_| t)
    }
}
