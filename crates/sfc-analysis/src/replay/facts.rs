//! What the replay needs to know about the chart's code, read from the AST: which variables
//! the code writes, which paths each guard and each action body reads, which constants the
//! code compares a path with, and which actions can influence a guard.
//!
//! Paths are variable references the simulator can resolve by name: `Start`, `Cmd.Start`,
//! `Tmr.Q`, `Cells[2]` (indices must be constant). Keys are upper-case (IEC names are
//! case-insensitive); the text kept is the first spelling met.

use sfc_model::{ActionTarget, Chart, Duration};
use sfc_st::Value as Const;
use sfc_syntax::ast::{
    ActionBody, Arg, BinaryOp, CaseLabel, Condition, Expr, ExprKind, IlBody, IlInstruction, Item, Pou, PouKind,
    SourceUnit, Stmt, StmtKind, UnaryOp, VarKind,
};
use std::collections::{BTreeMap, BTreeSet};

/// Operators of IL that load an input of a function block instance (`IN Tmr`, `CU Ctr`): their
/// operand is an instance, written by the instruction.
const FB_INPUT_OPS: [&str; 8] = ["S1", "R1", "CLK", "CU", "CD", "PV", "IN", "PT"];

/// Nesting beyond this is not walked (the parser caps expressions at 256 levels already).
const MAX_WALK_DEPTH: u32 = 300;

/// A variable reference as text, with its root name.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct PathRef {
    /// Upper-case key of the whole path.
    pub key: String,
    /// As written.
    pub text: String,
    /// Upper-case key of the first name.
    pub root: String,
}

/// What one piece of code (a guard or an action body) does with variables.
#[derive(Debug, Clone, Default)]
pub(crate) struct Usage {
    /// Paths read, in order of first appearance (no repetition).
    pub reads: Vec<PathRef>,
    /// Roots read, also through non-constant indices and partial paths.
    pub read_roots: BTreeSet<String>,
    /// Roots written (assignment targets, IL stores, output bindings, FB instances called).
    pub writes: BTreeSet<String>,
    /// `(path key, constant)` for every comparison of a path with a constant.
    pub comparisons: Vec<(String, Const)>,
    /// `(target key, source key)` for every plain copy `target := source`.
    pub copies: Vec<(String, String)>,
    /// Steps whose time `S.T` the code reads (upper-case names).
    pub time_steps: BTreeSet<String>,
}

impl Usage {
    fn read(&mut self, p: PathRef) {
        self.read_roots.insert(p.root.clone());
        if !self.reads.iter().any(|r| r.key == p.key) {
            self.reads.push(p);
        }
    }
}

/// The facts of one chart's code.
#[derive(Debug, Clone, Default)]
pub(crate) struct Facts {
    /// Per transition, what its guard reads.
    pub guards: Vec<Usage>,
    /// Per action, what its body does.
    pub actions: Vec<Usage>,
    /// Roots written by any code of the simulated POU, its associations (BOOL variables used
    /// as actions, indicators) and globals written by other POUs through `VAR_EXTERNAL`.
    pub written: BTreeSet<String>,
    /// Declared variables of the simulated POU and the file's globals: upper-case key →
    /// (declared spelling, constant, kind).
    pub declared: BTreeMap<String, (String, bool, VarKind)>,
    /// Declared roots in declaration order (POU first, then globals), upper-case.
    pub order: Vec<String>,
    /// Function block instances (upper-case root → type name as declared).
    pub fb_types: BTreeMap<String, String>,
    /// Per action, the roots its associations' duration variables name.
    pub durations: Vec<BTreeSet<String>>,
    /// Roots that can influence some guard: read by a guard, or read by an action that writes
    /// such a root (closure), or a duration variable of such an action.
    pub relevant: BTreeSet<String>,
    /// Indices of actions whose body writes a relevant root.
    pub relevant_actions: Vec<usize>,
    /// Constants compared with each path (upper-case key), propagated through plain copies.
    pub constants: BTreeMap<String, Vec<Const>>,
    /// Steps whose elapsed time matters: their `S.T` is read by a guard or an action body,
    /// or they have an `sfc.timeout` (supervision sets `SFCError` as time passes).
    pub time_steps: BTreeSet<usize>,
    /// Some association has a timed qualifier (L, D, SD, DS, SL).
    pub timed_associations: bool,
}

/// Named constants of the POU and the file (`VAR CONSTANT`), for `sfc_st::const_eval`.
struct Constants<'a> {
    decls: Vec<(&'a str, &'a Expr)>,
}

impl sfc_st::ConstLookup for Constants<'_> {
    fn constant(&self, name: &str) -> Option<Const> {
        let (_, e) = self.decls.iter().find(|(n, _)| n.eq_ignore_ascii_case(name))?;
        // A constant defined through itself would recurse: evaluate without named constants
        // below the first level.
        sfc_st::const_eval(e, &sfc_st::NoConstants).or_else(|| {
            let inner = Constants {
                decls: self.decls.iter().filter(|(n, _)| !n.eq_ignore_ascii_case(name)).copied().collect(),
            };
            sfc_st::const_eval(e, &inner)
        })
    }
}

/// The walker over ST and IL code.
struct Walker<'a> {
    chart: &'a Chart,
    consts: &'a Constants<'a>,
    unit: &'a SourceUnit,
    /// Declared variables of the simulated POU with their type names (for in-out parameters
    /// of user function blocks).
    instance_types: &'a BTreeMap<String, String>,
    /// Per user POU (upper-case name), the globals its code writes through `VAR_EXTERNAL`:
    /// calling it writes them.
    externals: &'a BTreeMap<String, BTreeSet<String>>,
}

impl Walker<'_> {
    fn is_step(&self, name: &str) -> bool {
        self.chart.step(name).is_some()
    }
    fn is_action(&self, name: &str) -> bool {
        self.chart.action(name).is_some()
    }

    /// The path an expression names, if it is a plain variable reference.
    fn path(&self, e: &Expr, depth: u32) -> Option<PathRef> {
        if depth > MAX_WALK_DEPTH {
            return None;
        }
        match &e.kind {
            ExprKind::Name(id) => Some(PathRef {
                key: id.text.to_ascii_uppercase(),
                text: id.text.clone(),
                root: id.text.to_ascii_uppercase(),
            }),
            ExprKind::Address(a) => Some(PathRef {
                key: a.text.to_ascii_uppercase(),
                text: a.text.clone(),
                root: a.text.to_ascii_uppercase(),
            }),
            ExprKind::Paren(inner) => self.path(inner, depth + 1),
            ExprKind::Member { base, member } => {
                let b = self.path(base, depth + 1)?;
                let text = format!("{}.{}", b.text, member.text);
                Some(PathRef { key: text.to_ascii_uppercase(), text, root: b.root })
            }
            ExprKind::Index { base, indices } => {
                let b = self.path(base, depth + 1)?;
                let mut ix = Vec::new();
                for i in indices {
                    let v = sfc_st::const_eval(i, self.consts)?.as_int()?;
                    ix.push(v.to_string());
                }
                let text = format!("{}[{}]", b.text, ix.join(","));
                Some(PathRef { key: text.to_ascii_uppercase(), text, root: b.root })
            }
            _ => None,
        }
    }

    /// The root name of an assignment target or an operand, even with variable indices.
    fn root(&self, e: &Expr, depth: u32) -> Option<String> {
        if depth > MAX_WALK_DEPTH {
            return None;
        }
        match &e.kind {
            ExprKind::Name(id) => Some(id.text.to_ascii_uppercase()),
            ExprKind::Address(a) => Some(a.text.to_ascii_uppercase()),
            ExprKind::Paren(inner) => self.root(inner, depth + 1),
            ExprKind::Member { base, .. } | ExprKind::Index { base, .. } => self.root(base, depth + 1),
            _ => None,
        }
    }

    fn constant(&self, e: &Expr) -> Option<Const> {
        sfc_st::const_eval(e, self.consts)
    }

    /// Records what an expression reads.
    fn expr(&self, e: &Expr, u: &mut Usage, depth: u32) {
        if depth > MAX_WALK_DEPTH {
            return;
        }
        match &e.kind {
            ExprKind::Literal(_) | ExprKind::Error => {}
            ExprKind::Deref(base) => self.expr(base, u, depth + 1),
            ExprKind::Address(_) => {
                if let Some(p) = self.path(e, depth) {
                    u.read(p);
                }
            }
            ExprKind::Name(id) => {
                if self.is_step(&id.text) {
                    // A step name alone reads its flag, which time changes only through firing.
                    return;
                }
                if let Some(p) = self.path(e, depth) {
                    u.read(p);
                }
            }
            ExprKind::Member { base, member } => {
                if let ExprKind::Name(b) = &base.kind {
                    if self.is_step(&b.text) {
                        if member.is("T") {
                            u.time_steps.insert(b.text.to_ascii_uppercase());
                        }
                        return;
                    }
                    if self.is_action(&b.text) {
                        return;
                    }
                }
                match self.path(e, depth) {
                    Some(p) => u.read(p),
                    None => self.expr(base, u, depth + 1),
                }
            }
            ExprKind::Index { base, indices } => {
                match self.path(e, depth) {
                    Some(p) => u.read(p),
                    None => {
                        if let Some(r) = self.root(base, depth + 1) {
                            u.read_roots.insert(r);
                        }
                        self.expr(base, u, depth + 1);
                    }
                }
                for i in indices {
                    self.expr(i, u, depth + 1);
                }
            }
            ExprKind::Call { callee, args } => self.call(&callee.text, args, u, depth + 1),
            ExprKind::MemberCall { base, args, .. } => {
                // An action of an instance runs on the instance: it may write any of it, and
                // the globals its type uses.
                if let Some(r) = self.root(base, depth + 1) {
                    if let Some(globals) =
                        self.instance_types.get(&r).and_then(|t| self.externals.get(&t.to_ascii_uppercase()))
                    {
                        u.writes.extend(globals.iter().cloned());
                    }
                    u.writes.insert(r);
                }
                for v in args.iter().filter_map(|a| a.value.as_ref()) {
                    self.expr(v, u, depth + 1);
                }
            }
            ExprKind::Unary { operand, .. } => self.expr(operand, u, depth + 1),
            ExprKind::Paren(inner) => self.expr(inner, u, depth + 1),
            ExprKind::Binary { op, lhs, rhs } => {
                if matches!(op, BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge)
                {
                    self.comparison(lhs, rhs, u, depth);
                    self.comparison(rhs, lhs, u, depth);
                }
                self.expr(lhs, u, depth + 1);
                self.expr(rhs, u, depth + 1);
            }
        }
    }

    /// `path <op> constant`: the constant is a candidate for the path.
    /// `side <op> other` with `other` constant: the constant is a candidate for `side` when
    /// it is a path, else for every path inside `side` (`Level + 5 > 50`, `F(Raw) > 0`: a
    /// guess that often lands near the threshold).
    fn comparison(&self, side: &Expr, other: &Expr, u: &mut Usage, depth: u32) {
        let c = match self.constant(other) {
            Some(c) => c,
            None => match &other.kind {
                ExprKind::Unary { op: UnaryOp::Neg, operand } => match self.constant(operand) {
                    Some(Const::Int(i)) => Const::Int(-i),
                    Some(Const::Real(r)) => Const::Real(-r),
                    Some(Const::Time(t)) => Const::Time(t.saturating_neg()),
                    _ => return,
                },
                _ => return,
            },
        };
        if self.constant(side).is_some() {
            return;
        }
        match self.path(side, depth + 1) {
            Some(p) => u.comparisons.push((p.key, c)),
            None => {
                let mut inner = Usage::default();
                self.expr(side, &mut inner, depth + 1);
                for p in inner.reads {
                    u.comparisons.push((p.key, c));
                }
            }
        }
    }

    /// A call (function or function block instance): inputs are read; output bindings and
    /// in-out parameters of user POUs are written; an instance called is written.
    fn call(&self, callee: &str, args: &[Arg], u: &mut Usage, depth: u32) {
        let key = callee.to_ascii_uppercase();
        let inouts = self.in_out_params(&key);
        if self.instance_types.contains_key(&key) {
            u.writes.insert(key.clone());
        }
        let pou = self.instance_types.get(&key).map_or(key.clone(), |t| t.to_ascii_uppercase());
        if let Some(globals) = self.externals.get(&pou) {
            u.writes.extend(globals.iter().cloned());
        }
        let mut positional = 0usize;
        for a in args {
            let Some(v) = &a.value else { continue };
            if a.output {
                if let Some(r) = self.root(v, depth) {
                    u.writes.insert(r);
                }
                continue;
            }
            let is_inout = match &a.name {
                Some(n) => inouts.0.iter().any(|p| p.eq_ignore_ascii_case(&n.text)),
                None => inouts.1.get(positional).copied().unwrap_or(false),
            };
            positional += 1;
            if is_inout {
                if let Some(r) = self.root(v, depth) {
                    u.writes.insert(r);
                }
            }
            self.expr(v, u, depth + 1);
        }
    }

    /// The in-out parameter names of the user POU a call reaches (directly for a function,
    /// through the instance's type for a function block), and per positional parameter
    /// (inputs and in-outs in declaration order) whether it is in-out.
    fn in_out_params(&self, callee_key: &str) -> (Vec<String>, Vec<bool>) {
        let type_name = self.instance_types.get(callee_key).map(String::as_str).unwrap_or(callee_key);
        let Some(pou) = find_pou(self.unit, type_name) else { return (Vec::new(), Vec::new()) };
        let mut names = Vec::new();
        let mut positional = Vec::new();
        for b in &pou.var_blocks {
            for d in &b.decls {
                for n in &d.names {
                    match b.kind {
                        VarKind::InOut => {
                            names.push(n.text.clone());
                            positional.push(true);
                        }
                        VarKind::Input => positional.push(false),
                        _ => {}
                    }
                }
            }
        }
        (names, positional)
    }

    fn stmts(&self, body: &[Stmt], u: &mut Usage, depth: u32) {
        for s in body {
            self.stmt(s, u, depth);
        }
    }

    fn stmt(&self, s: &Stmt, u: &mut Usage, depth: u32) {
        if depth > MAX_WALK_DEPTH {
            return;
        }
        match &s.kind {
            StmtKind::Assign { target, value } | StmtKind::RefAssign { target, value } => {
                if let Some(r) = self.root(target, depth) {
                    u.writes.insert(r);
                }
                // Indices of the target are read.
                if let ExprKind::Index { indices, .. } = &target.kind {
                    for i in indices {
                        self.expr(i, u, depth + 1);
                    }
                }
                if let (Some(t), Some(v)) = (self.path(target, depth), self.path(value, depth)) {
                    u.copies.push((t.key, v.key));
                }
                self.expr(value, u, depth + 1);
            }
            StmtKind::Call(e) => match &e.kind {
                ExprKind::Call { callee, args } => self.call(&callee.text, args, u, depth + 1),
                _ => self.expr(e, u, depth + 1),
            },
            StmtKind::If { branches, else_body } => {
                for (c, b) in branches {
                    self.expr(c, u, depth + 1);
                    self.stmts(b, u, depth + 1);
                }
                if let Some(b) = else_body {
                    self.stmts(b, u, depth + 1);
                }
            }
            StmtKind::Case { selector, arms, else_body } => {
                self.expr(selector, u, depth + 1);
                let sel = self.path(selector, depth);
                for arm in arms {
                    if let Some(p) = &sel {
                        for l in &arm.labels {
                            match l {
                                CaseLabel::Value(v) => {
                                    if let Some(c) = self.constant(v) {
                                        u.comparisons.push((p.key.clone(), c));
                                    }
                                }
                                CaseLabel::Range(lo, hi) => {
                                    for v in [lo, hi] {
                                        if let Some(c) = self.constant(v) {
                                            u.comparisons.push((p.key.clone(), c));
                                        }
                                    }
                                }
                            }
                        }
                    }
                    self.stmts(&arm.body, u, depth + 1);
                }
                if let Some(b) = else_body {
                    self.stmts(b, u, depth + 1);
                }
            }
            StmtKind::For { var, from, to, by, body } => {
                u.writes.insert(var.text.to_ascii_uppercase());
                self.expr(from, u, depth + 1);
                self.expr(to, u, depth + 1);
                if let Some(b) = by {
                    self.expr(b, u, depth + 1);
                }
                self.stmts(body, u, depth + 1);
            }
            StmtKind::While { cond, body } => {
                self.expr(cond, u, depth + 1);
                self.stmts(body, u, depth + 1);
            }
            StmtKind::Repeat { body, until } => {
                self.stmts(body, u, depth + 1);
                self.expr(until, u, depth + 1);
            }
            StmtKind::Exit | StmtKind::Return | StmtKind::Empty => {}
        }
    }

    /// IL: the current result is tracked as "the path last loaded" so `LD Level GT 50`
    /// compares `Level` with 50 and `LD a ST b` copies `a` into `b`.
    fn il(&self, instrs: &[IlInstruction], u: &mut Usage, depth: u32, initial: Option<PathRef>) {
        if depth > MAX_WALK_DEPTH {
            return;
        }
        let mut loaded: Option<PathRef> = initial;
        for ins in instrs {
            if let Some(nested) = &ins.nested {
                // `AND( Level GT 1000 )`: the operand is the nested expression's first load.
                let first = ins.operands.first().and_then(|o| self.path(o, depth));
                self.il(nested, u, depth + 1, first);
            }
            let Some(op) = &ins.op else { continue };
            let parsed = sfc_st::parse_il_op(&op.text);
            if let Some(args) = &ins.call_args {
                let callee = ins.operands.first().and_then(|o| self.root(o, depth));
                match callee {
                    Some(c) => self.call(&c, args, u, depth + 1),
                    None => {
                        for a in args {
                            if let Some(v) = &a.value {
                                self.expr(v, u, depth + 1);
                            }
                        }
                    }
                }
            }
            match parsed {
                Some((sfc_st::IlOp::Ld, _, _)) => {
                    loaded = ins.operands.first().and_then(|o| self.path(o, depth));
                    for o in &ins.operands {
                        self.expr(o, u, depth + 1);
                    }
                }
                Some((sfc_st::IlOp::St | sfc_st::IlOp::Set | sfc_st::IlOp::Reset, negated, _)) => {
                    for o in &ins.operands {
                        if let Some(r) = self.root(o, depth) {
                            u.writes.insert(r);
                        }
                        if let (Some(src), Some(t), false) = (&loaded, self.path(o, depth), negated) {
                            if matches!(parsed, Some((sfc_st::IlOp::St, _, _))) {
                                u.copies.push((t.key, src.key.clone()));
                            }
                        }
                    }
                }
                Some((sfc_st::IlOp::Cal, _, _)) => {
                    for o in &ins.operands {
                        if let Some(r) = self.root(o, depth) {
                            u.writes.insert(r);
                        }
                    }
                    loaded = None;
                }
                Some((sfc_st::IlOp::Binary(b), _, _)) => {
                    if matches!(
                        b,
                        BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge
                    ) {
                        if let (Some(p), Some(o)) = (&loaded, ins.operands.first()) {
                            if let Some(c) = self.constant(o) {
                                u.comparisons.push((p.key.clone(), c));
                            }
                        }
                    }
                    for o in &ins.operands {
                        self.expr(o, u, depth + 1);
                    }
                    loaded = None;
                }
                Some(_) => {
                    for o in &ins.operands {
                        self.expr(o, u, depth + 1);
                    }
                    loaded = None;
                }
                None => {
                    let upper = op.text.to_ascii_uppercase();
                    if FB_INPUT_OPS.contains(&upper.as_str()) {
                        for o in &ins.operands {
                            if let Some(r) = self.root(o, depth) {
                                u.writes.insert(r);
                            }
                        }
                    } else {
                        // A function called as an operator: its operands are read.
                        for o in &ins.operands {
                            self.expr(o, u, depth + 1);
                        }
                    }
                    loaded = None;
                }
            }
        }
    }

    fn condition(&self, c: &Condition) -> Usage {
        let mut u = Usage::default();
        match c {
            Condition::St(e) => self.expr(e, &mut u, 0),
            Condition::Il(body) => self.il_body(body, &mut u),
            Condition::Missing => {}
        }
        u
    }

    fn il_body(&self, body: &IlBody, u: &mut Usage) {
        self.il(&body.instructions, u, 0, None);
    }

    fn action(&self, body: &ActionBody) -> Usage {
        let mut u = Usage::default();
        match body {
            ActionBody::St(stmts) => self.stmts(stmts, &mut u, 0),
            ActionBody::Il(il) => self.il_body(il, &mut u),
            // An action written in SFC writes through the actions its steps name, which are
            // read where the charts of the POU's actions are (not yet: see docs/targets.md).
            ActionBody::Sfc(_) => {}
        }
        u
    }
}

/// The POU called `name` (case-insensitive).
pub(crate) fn find_pou<'a>(unit: &'a SourceUnit, name: &str) -> Option<&'a Pou> {
    unit.items.iter().find_map(|i| match i {
        Item::Pou(p) if p.name.is(name) => Some(p),
        _ => None,
    })
}

/// The type name a declaration gives, when it is a plain name (an FB type, an elementary
/// type or a derived type).
fn type_name(spec: &sfc_syntax::ast::TypeSpec) -> Option<String> {
    match &spec.kind {
        sfc_syntax::ast::TypeSpecKind::Named(id) => Some(id.text.clone()),
        _ => None,
    }
}

impl Facts {
    /// Reads the facts of `chart` from `unit` (the parsed file the chart comes from).
    pub(crate) fn of(unit: &SourceUnit, chart: &Chart) -> Facts {
        let mut facts = Facts::default();
        let pou = find_pou(unit, &chart.pou);
        // Declarations: the POU's, then the file's globals.
        let mut const_decls: Vec<(&str, &Expr)> = Vec::new();
        let mut instance_types: BTreeMap<String, String> = BTreeMap::new();
        let mut blocks: Vec<&sfc_syntax::ast::VarBlock> = Vec::new();
        if let Some(p) = pou {
            blocks.extend(p.var_blocks.iter());
        }
        for item in &unit.items {
            if let Item::Globals(b) = item {
                blocks.push(b);
            }
        }
        for b in &blocks {
            for d in &b.decls {
                for n in &d.names {
                    let key = n.text.to_ascii_uppercase();
                    if !facts.declared.contains_key(&key) {
                        facts.declared.insert(key.clone(), (n.text.clone(), b.constant, b.kind));
                        facts.order.push(key.clone());
                    }
                    if let Some(t) = type_name(&d.ty) {
                        instance_types.entry(key).or_insert(t);
                    }
                    if b.constant {
                        if let Some(sfc_syntax::ast::Initializer::Expr(e)) = &d.init {
                            const_decls.push((n.text.as_str(), e));
                        }
                    }
                }
            }
        }
        // Only names that are declared types of user or standard FBs count as instances.
        instance_types.retain(|_, t| {
            sfc_st::stdlib::std_function_block(t).is_some()
                || find_pou(unit, t).is_some_and(|p| p.kind == PouKind::FunctionBlock)
        });
        let consts = Constants { decls: const_decls };
        // Globals written by user POUs, twice so a block calling a block is seen through.
        let none = BTreeMap::new();
        let w0 = Walker { chart, consts: &consts, unit, instance_types: &instance_types, externals: &none };
        let ext1 = pou_external_writes(unit, &chart.pou, &w0);
        let w1 = Walker { chart, consts: &consts, unit, instance_types: &instance_types, externals: &ext1 };
        let externals = pou_external_writes(unit, &chart.pou, &w1);
        let w = Walker { chart, consts: &consts, unit, instance_types: &instance_types, externals: &externals };
        facts.guards = chart.transitions.iter().map(|t| w.condition(&t.condition)).collect();
        facts.actions = chart.actions.iter().map(|a| w.action(&a.body)).collect();
        facts.durations = vec![BTreeSet::new(); chart.actions.len()];
        let mut var_action_durations: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for step in &chart.steps {
            for a in &step.associations {
                if a.qualifier.is_timed() {
                    facts.timed_associations = true;
                }
                let dur = match &a.duration {
                    Some(Duration::Variable(v)) => Some(v.to_ascii_uppercase()),
                    _ => None,
                };
                match a.target {
                    ActionTarget::Action(id) => {
                        if let (Some(d), Some(set)) = (dur, facts.durations.get_mut(id)) {
                            set.insert(d);
                        }
                    }
                    ActionTarget::Variable => {
                        let key = a.action.to_ascii_uppercase();
                        facts.written.insert(key.clone());
                        if let Some(d) = dur {
                            var_action_durations.entry(key).or_default().insert(d);
                        }
                    }
                }
                for i in &a.indicators {
                    facts.written.insert(i.to_ascii_uppercase());
                }
            }
        }
        for (i, step) in chart.steps.iter().enumerate() {
            if step.timeout.is_some() {
                facts.time_steps.insert(i);
            }
        }
        for u in facts.guards.iter().chain(facts.actions.iter()) {
            facts.written.extend(u.writes.iter().cloned());
            facts.time_steps.extend(u.time_steps.iter().filter_map(|n| chart.step(n)));
        }
        facts.written.extend(instance_types.keys().cloned());
        facts.fb_types = instance_types.clone();
        // Relevance: the closure of the guards' reads through the actions that write them.
        let mut relevant: BTreeSet<String> = BTreeSet::new();
        for g in &facts.guards {
            relevant.extend(g.read_roots.iter().cloned());
        }
        for (v, ds) in &var_action_durations {
            if relevant.contains(v) {
                relevant.extend(ds.iter().cloned());
            }
        }
        let mut in_closure = vec![false; facts.actions.len()];
        loop {
            let mut grew = false;
            for (i, a) in facts.actions.iter().enumerate() {
                if in_closure[i] || !a.writes.iter().any(|w| relevant.contains(w)) {
                    continue;
                }
                in_closure[i] = true;
                grew = true;
                relevant.extend(a.read_roots.iter().cloned());
                relevant.extend(facts.durations[i].iter().cloned());
            }
            if !grew {
                break;
            }
        }
        facts.relevant = relevant;
        facts.relevant_actions = (0..facts.actions.len()).filter(|&i| in_closure[i]).collect();
        // Candidate constants, propagated backwards through plain copies.
        let mut constants: BTreeMap<String, Vec<Const>> = BTreeMap::new();
        let mut copies: Vec<(String, String)> = Vec::new();
        for u in facts.guards.iter().chain(facts.relevant_actions.iter().filter_map(|&i| facts.actions.get(i))) {
            for (k, c) in &u.comparisons {
                push_const(constants.entry(k.clone()).or_default(), *c);
            }
            copies.extend(u.copies.iter().cloned());
        }
        for _ in 0..8 {
            let mut grew = false;
            for (t, s) in &copies {
                let Some(from) = constants.get(t).cloned() else { continue };
                let to = constants.entry(s.clone()).or_default();
                for c in from {
                    grew |= push_const(to, c);
                }
            }
            if !grew {
                break;
            }
        }
        facts.constants = constants;
        facts
    }

    /// Whether `root` (upper-case) names a value the replay may set: a declared,
    /// non-constant variable the code never writes, or an undeclared name the simulator
    /// resolves (`resolves`: the implicit inputs of ATMT/EATMT charts, direct addresses)
    /// that the code never writes. Of the implicit chart control variables only the
    /// acknowledgement `SFCQuitError` is an input an operator sets; `SFCInit` and `SFCPause`
    /// would stop the chart.
    pub(crate) fn settable_root(&self, root: &str, resolves: bool) -> bool {
        if self.written.contains(root) {
            return false;
        }
        if root.eq_ignore_ascii_case("SFCQuitError") {
            return resolves || self.declared.contains_key(root);
        }
        if sfc_st::is_sfc_control_variable(root) {
            return false;
        }
        match self.declared.get(root) {
            Some((_, constant, _)) => !constant,
            None => resolves,
        }
    }
}

fn push_const(v: &mut Vec<Const>, c: Const) -> bool {
    if v.contains(&c) {
        false
    } else {
        v.push(c);
        true
    }
}

/// Per POU of the file other than the chart's (upper-case name), the globals its code writes
/// through `VAR_EXTERNAL` (a user function block called by an action may write them).
fn pou_external_writes(unit: &SourceUnit, chart_pou: &str, w: &Walker<'_>) -> BTreeMap<String, BTreeSet<String>> {
    let mut out = BTreeMap::new();
    for item in &unit.items {
        let Item::Pou(p) = item else { continue };
        if p.name.is(chart_pou) {
            continue;
        }
        let externals: BTreeSet<String> = p
            .var_blocks
            .iter()
            .filter(|b| b.kind == VarKind::External)
            .flat_map(|b| b.decls.iter().flat_map(|d| d.names.iter().map(|n| n.text.to_ascii_uppercase())))
            .collect();
        if externals.is_empty() {
            continue;
        }
        let mut u = Usage::default();
        match &p.body {
            sfc_syntax::ast::Body::St(stmts) => w.stmts(stmts, &mut u, 0),
            sfc_syntax::ast::Body::Il(il) => w.il_body(il, &mut u),
            sfc_syntax::ast::Body::Sfc(elements) => {
                for e in elements {
                    if let sfc_syntax::ast::SfcElement::Action(a) = e {
                        match &a.body {
                            ActionBody::St(stmts) => w.stmts(stmts, &mut u, 0),
                            ActionBody::Il(il) => w.il_body(il, &mut u),
                            ActionBody::Sfc(_) => {}
                        }
                    }
                }
            }
        }
        let writes: BTreeSet<String> = u.writes.into_iter().filter(|r| externals.contains(r)).collect();
        if !writes.is_empty() {
            out.insert(p.name.key(), writes);
        }
    }
    out
}
