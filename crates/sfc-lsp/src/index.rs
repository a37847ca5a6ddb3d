//! What an IDE needs to know about one IEC text: every declared name (POUs, types, globals,
//! variables, steps, actions, transitions) with its declaration, and every place a name is used,
//! found by walking the syntax tree (which recovers from errors, so a file being typed still
//! has an index).
//!
//! Names follow `semantics.md`: case-insensitive; inside a POU, variables, steps, actions,
//! transitions, methods and properties share one namespace; a method and each accessor (GET,
//! SET) of a property has a namespace of its own for its variables, looked at first in its code;
//! a name not found in its POU is a file-level name (a global, a type, a POU, an enumerated
//! value), then one of another file of the workspace. A member written after a name
//! (`inst.Start`, `THIS^.count`, `SUPER^.Add`) is a [`MemberUse`]: which block's member it is
//! depends on the type of the name, found across files by `navigate`.

use sfc_diagnostics::Span;
use sfc_syntax::ast::{
    self, ActionBody, Arg, Condition, Expr, ExprKind, IlBody, IlInstruction, Initializer, Item, Pou, PouKind,
    SfcElement, Stmt, StmtKind, TypeSpec, TypeSpecKind, VarBlock, VarKind,
};

/// What a declared name is.
#[derive(Debug, Clone, PartialEq)]
pub enum SymbolKind {
    Pou(PouKind),
    /// A data type of a TYPE block.
    Type,
    /// A value of an enumerated type (of a TYPE block).
    EnumValue,
    Variable(VarDetail),
    Step(StepDetail),
    Action,
    Transition(TransitionDetail),
    /// A method of a function block or program (IEC 61131-3 3rd edition).
    Method,
    /// A property of a function block or program (CODESYS).
    Property,
    /// An interface (IEC 61131-3 3rd edition), at file level.
    Interface,
}

impl SymbolKind {
    /// How the kind is called in messages ("step", "variable", …).
    pub fn noun(&self) -> &'static str {
        match self {
            SymbolKind::Pou(PouKind::Program) => "program",
            SymbolKind::Pou(PouKind::FunctionBlock) => "function block",
            SymbolKind::Pou(PouKind::Function) => "function",
            SymbolKind::Type => "type",
            SymbolKind::EnumValue => "enumerated value",
            SymbolKind::Variable(_) => "variable",
            SymbolKind::Step(_) => "step",
            SymbolKind::Action => "action",
            SymbolKind::Transition(_) => "transition",
            SymbolKind::Method => "method",
            SymbolKind::Property => "property",
            SymbolKind::Interface => "interface",
        }
    }
}

/// A variable's declaration as written.
#[derive(Debug, Clone, PartialEq)]
pub struct VarDetail {
    pub section: VarKind,
    pub constant: bool,
    pub retain: Option<ast::Retain>,
    /// The type as written (`INT`, `ARRAY [1..3] OF BOOL`).
    pub ty: String,
    /// The type's name when it is a name (`TON`, `Colour`), for members and navigation.
    pub type_name: Option<String>,
    pub init: Option<String>,
    /// `%IX2.4`
    pub at: Option<String>,
    /// Not declared by the user: a control variable of the chart (`SFCInit`, …).
    pub implicit: bool,
}

/// A step as written.
#[derive(Debug, Clone, PartialEq)]
pub struct StepDetail {
    pub initial: bool,
    pub is_final: bool,
    /// `sfc.timeout` as written.
    pub timeout: Option<String>,
    /// `sfc.min_time` as written.
    pub min_time: Option<String>,
    pub tag: Option<String>,
    pub associations: Vec<AssociationDetail>,
}

/// `Action(Q, T#1s, Indicator)` inside a step.
#[derive(Debug, Clone, PartialEq)]
pub struct AssociationDetail {
    pub action: String,
    /// As written; `None` is the null qualifier (N).
    pub qualifier: Option<String>,
    pub duration: Option<String>,
    pub indicators: Vec<String>,
}

/// A transition as written.
#[derive(Debug, Clone, PartialEq)]
pub struct TransitionDetail {
    pub named: bool,
    pub priority: Option<String>,
    pub from: Vec<String>,
    pub to: Vec<String>,
    /// The condition as written (`Go AND S1.T > T#1s`, or the IL lines).
    pub condition: String,
    /// Span of the `TRANSITION … FROM … TO …` header.
    pub header: Span,
    /// Where `(PRIORITY := n)` may be inserted: after the name, or after `TRANSITION`.
    pub priority_insert: u32,
}

/// One declared name.
#[derive(Debug, Clone, PartialEq)]
pub struct Symbol {
    pub name: String,
    pub kind: SymbolKind,
    /// The POU it belongs to (index into [`FileIndex::pous`]); `None` for file-level names.
    pub pou: Option<usize>,
    /// The name in its declaration (an unnamed transition: its header).
    pub name_span: Span,
    /// The whole declaration.
    pub span: Span,
    /// The method or accessor whose own variable it is (index into [`FileIndex::scopes`]);
    /// `None` for the names of the POU's namespace and file-level names.
    pub scope: Option<usize>,
}

impl Symbol {
    pub fn key(&self) -> String {
        self.name.to_ascii_uppercase()
    }
    /// Whether the name is written in the text (not an implicit variable, not `T<n>`).
    pub fn is_written(&self) -> bool {
        match &self.kind {
            SymbolKind::Variable(v) => !v.implicit,
            SymbolKind::Transition(t) => t.named,
            _ => true,
        }
    }
}

/// How a name is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// In code: a condition, an action body, an initial value, a duration, an indicator.
    Code,
    /// In a transition's FROM or TO list.
    StepLink,
    /// The action of an association.
    Association,
    /// A type name in a declaration.
    Type,
}

/// One use of a name.
#[derive(Debug, Clone, PartialEq)]
pub struct Occurrence {
    pub span: Span,
    /// Upper-case name.
    pub key: String,
    pub pou: Option<usize>,
    pub role: Role,
    /// Followed by `.member` (`S1.X`, `Timer.Q`): the member's name.
    pub member: Option<String>,
    /// Written in the code of a method or accessor (index into [`FileIndex::scopes`]).
    pub scope: Option<usize>,
}

/// What a member is written after.
#[derive(Debug, Clone, PartialEq)]
pub enum MemberBase {
    /// `name.Member`: a name (upper case) resolved where the member is written.
    Name(String),
    /// `THIS^.Member`: the block the code belongs to.
    This,
    /// `SUPER^.Member`: the block it extends.
    Super,
    /// A formal parameter of a call of the name (upper case): `Start(s := 1)`, `fb(IN := x)`,
    /// `F(a := 1)`.
    CallOf(String),
    /// A formal parameter of a call of a member (`m.Start(s := 5)`): what the member follows
    /// and its name (upper case).
    CallOfMember(Box<MemberBase>, String),
}

/// A name that belongs to another namespace than where it is written: a member written after
/// a name (`m.Start`, `m.Running`, `THIS^.count`), whose member it is depending on the name's
/// type, which may be a block of another file; a formal parameter of a call (`s` of
/// `m.Start(s := 5)`), a variable of what is called.
#[derive(Debug, Clone, PartialEq)]
pub struct MemberUse {
    /// The member's name.
    pub span: Span,
    /// Upper-case member name.
    pub key: String,
    pub base: MemberBase,
    pub pou: Option<usize>,
    pub scope: Option<usize>,
}

/// The code of a method, or of one accessor of a property: a namespace of its own for the
/// variables it declares, inside its POU's.
#[derive(Debug, Clone, PartialEq)]
pub struct Scope {
    /// Its POU (index into [`FileIndex::pous`]).
    pub pou: usize,
    /// The method or property (index into [`FileIndex::symbols`]).
    pub owner: usize,
    /// The whole method or accessor.
    pub span: Span,
    /// Its variables: indices into [`FileIndex::symbols`], in declaration order.
    pub symbols: Vec<usize>,
}

/// A qualifier written in an association, for hover and colouring.
#[derive(Debug, Clone, PartialEq)]
pub struct QualifierUse {
    pub span: Span,
    pub name: String,
}

/// A POU of the file.
#[derive(Debug, Clone, PartialEq)]
pub struct PouEntry {
    pub name: String,
    pub kind: PouKind,
    pub span: Span,
    pub name_span: Span,
    pub sfc: bool,
    /// Its symbols: indices into [`FileIndex::symbols`], in declaration order.
    pub symbols: Vec<usize>,
    /// Var blocks: (kind, span, insertion point before `END_VAR`).
    pub var_blocks: Vec<(VarKind, Span)>,
    /// The end of the header line (after the name and return type), where a new VAR block may go.
    pub header_end: u32,
    /// `EXTENDS Base`: the name of the block it extends.
    pub extends: Option<String>,
}

/// The index of one file.
#[derive(Debug, Clone, Default)]
pub struct FileIndex {
    pub symbols: Vec<Symbol>,
    pub occurrences: Vec<Occurrence>,
    pub qualifiers: Vec<QualifierUse>,
    pub pous: Vec<PouEntry>,
    /// The methods' and accessors' namespaces.
    pub scopes: Vec<Scope>,
    /// Members written after a name, in source order.
    pub members: Vec<MemberUse>,
    /// Upper-case name → symbol, for each POU (one namespace per POU).
    local: Vec<std::collections::HashMap<String, usize>>,
    /// Upper-case name → symbol, for each scope.
    scoped: Vec<std::collections::HashMap<String, usize>>,
    /// Upper-case name → file-level symbol.
    global: std::collections::HashMap<String, usize>,
}

impl FileIndex {
    /// Indexes a parsed file; `text` is its source.
    pub fn new(unit: &ast::SourceUnit, text: &str) -> FileIndex {
        let mut b = Builder { ix: FileIndex::default(), text, pou: None, scope: None };
        for item in &unit.items {
            match item {
                Item::Pou(p) => b.pou_decl(p),
                Item::Types(t) => b.types(t),
                Item::Globals(g) => b.var_block(g, None),
                Item::Interface(i) => {
                    b.pou = None;
                    b.add(&i.name.text, SymbolKind::Interface, i.name.span, i.span);
                }
                Item::Verbatim(_) => {}
            }
        }
        for item in &unit.items {
            if let Item::Pou(p) = item {
                b.pou_body(p);
            }
        }
        b.ix.occurrences.sort_by_key(|o| o.span.start);
        b.ix.members.sort_by_key(|m| m.span.start);
        b.ix
    }

    /// The POU whose text contains `offset`.
    pub fn pou_at(&self, offset: u32) -> Option<usize> {
        self.pous.iter().position(|p| p.span.start <= offset && offset <= p.span.end)
    }

    /// The symbol declared in POU `pou` (or at file level) under `key`.
    pub fn lookup(&self, pou: Option<usize>, key: &str) -> Option<usize> {
        if let Some(p) = pou {
            if let Some(&s) = self.local.get(p).and_then(|m| m.get(key)) {
                return Some(s);
            }
        }
        self.global.get(key).copied()
    }

    /// The symbol `key` as code of scope `scope` (a method, an accessor) of POU `pou` sees it:
    /// the scope's own variables first, then as [`FileIndex::lookup`].
    pub fn lookup_in(&self, pou: Option<usize>, scope: Option<usize>, key: &str) -> Option<usize> {
        if let Some(&s) = scope.and_then(|sc| self.scoped.get(sc)).and_then(|m| m.get(key)) {
            return Some(s);
        }
        self.lookup(pou, key)
    }

    /// The symbol a use of a name stands for, in this file.
    pub fn resolve(&self, o: &Occurrence) -> Option<usize> {
        self.lookup_in(o.pou, o.scope, &o.key)
    }

    /// The variable of scope `scope` named `key`.
    pub fn lookup_scoped(&self, scope: usize, key: &str) -> Option<usize> {
        self.scoped.get(scope).and_then(|m| m.get(key)).copied()
    }

    /// The member written at `offset` (touching counts, as for [`FileIndex::occurrence_at`]).
    pub fn member_at(&self, offset: u32) -> Option<&MemberUse> {
        let i = self.members.partition_point(|m| m.span.start <= offset);
        self.members.get(..i)?.iter().rev().take(4).find(|m| m.span.start <= offset && offset <= m.span.end)
    }

    /// The file-level symbol `key`.
    pub fn lookup_global(&self, key: &str) -> Option<usize> {
        self.global.get(key).copied()
    }

    /// The symbol of POU `pou` named `key`, not looking at file level.
    pub fn lookup_local(&self, pou: usize, key: &str) -> Option<usize> {
        self.local.get(pou).and_then(|m| m.get(key)).copied()
    }

    pub fn symbol(&self, id: usize) -> Option<&Symbol> {
        self.symbols.get(id)
    }

    /// The occurrence whose span contains `offset` (touching counts: a cursor right after a
    /// name is on it).
    pub fn occurrence_at(&self, offset: u32) -> Option<&Occurrence> {
        let i = self.occurrences.partition_point(|o| o.span.start <= offset);
        self.occurrences.get(..i)?.iter().rev().take(4).find(|o| o.span.start <= offset && offset <= o.span.end)
    }

    /// The symbol whose declared name contains `offset`.
    pub fn declaration_at(&self, offset: u32) -> Option<usize> {
        self.symbols.iter().position(|s| s.is_written() && s.name_span.start <= offset && offset <= s.name_span.end)
    }

    /// The qualifier written at `offset`.
    pub fn qualifier_at(&self, offset: u32) -> Option<&QualifierUse> {
        self.qualifiers.iter().find(|q| q.span.start <= offset && offset <= q.span.end)
    }

    /// The symbols of a POU.
    pub fn pou_symbols(&self, pou: usize) -> impl Iterator<Item = (usize, &Symbol)> {
        self.pous
            .get(pou)
            .into_iter()
            .flat_map(move |p| p.symbols.iter().filter_map(|&i| Some((i, self.symbols.get(i)?))))
    }

    /// The file-level symbols.
    pub fn globals(&self) -> impl Iterator<Item = (usize, &Symbol)> {
        self.symbols.iter().enumerate().filter(|(_, s)| s.pou.is_none())
    }
}

struct Builder<'t> {
    ix: FileIndex,
    text: &'t str,
    pou: Option<usize>,
    /// The method or accessor whose declarations or code are being read.
    scope: Option<usize>,
}

fn slice(text: &str, span: Span) -> String {
    text.get(span.range()).unwrap_or("").to_string()
}

/// A condition or a body as one line of text for hovers (white space runs collapsed).
fn one_line(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

impl Builder<'_> {
    fn add(&mut self, name: &str, kind: SymbolKind, name_span: Span, span: Span) -> usize {
        let id = self.ix.symbols.len();
        let key = name.to_ascii_uppercase();
        let scope = self.scope;
        self.ix.symbols.push(Symbol { name: name.to_string(), kind, pou: self.pou, name_span, span, scope });
        match (self.pou, scope) {
            (Some(_), Some(sc)) => {
                if let Some(m) = self.ix.scoped.get_mut(sc) {
                    m.entry(key).or_insert(id);
                }
                if let Some(e) = self.ix.scopes.get_mut(sc) {
                    e.symbols.push(id);
                }
            }
            (Some(p), None) => {
                if let Some(m) = self.ix.local.get_mut(p) {
                    m.entry(key).or_insert(id);
                }
                if let Some(e) = self.ix.pous.get_mut(p) {
                    e.symbols.push(id);
                }
            }
            (None, _) => {
                self.ix.global.entry(key).or_insert(id);
            }
        }
        id
    }

    /// A new scope of POU `pou` for the method or property `owner`, spanning `span`.
    fn new_scope(&mut self, pou: usize, owner: usize, span: Span) -> usize {
        self.ix.scopes.push(Scope { pou, owner, span, symbols: Vec::new() });
        self.ix.scoped.push(Default::default());
        self.ix.scopes.len() - 1
    }

    /// The scope of a method or accessor spanning `span`, made in [`Builder::pou_decl`].
    fn scope_of(&self, span: Span) -> Option<usize> {
        self.ix.scopes.iter().position(|s| s.span == span)
    }

    /// `base.member`: the member, when the base is a name, `THIS^` or `SUPER^`.
    fn member_use(&mut self, base: &Expr, member: &ast::Ident) {
        if let Some(base) = member_base(base) {
            self.push_member(member, base);
        }
    }

    fn push_member(&mut self, name: &ast::Ident, base: MemberBase) {
        self.ix.members.push(MemberUse { span: name.span, key: name.key(), base, pou: self.pou, scope: self.scope });
    }

    fn occ(&mut self, ident: &ast::Ident, role: Role, member: Option<&ast::Ident>) {
        self.ix.occurrences.push(Occurrence {
            span: ident.span,
            key: ident.key(),
            pou: self.pou,
            role,
            member: member.map(|m| m.text.clone()),
            scope: self.scope,
        });
    }

    fn types(&mut self, block: &ast::TypeBlock) {
        for d in &block.decls {
            self.add(&d.name.text, SymbolKind::Type, d.name.span, d.span);
            if let TypeSpecKind::Enum { values, .. } = &d.spec.kind {
                for (v, _) in values {
                    self.add(&v.text, SymbolKind::EnumValue, v.span, v.span);
                }
            }
        }
        for d in &block.decls {
            self.type_spec(&d.spec);
            if let Some(i) = &d.init {
                self.init(i);
            }
        }
    }

    fn pou_decl(&mut self, p: &Pou) {
        self.pou = None;
        self.add(&p.name.text, SymbolKind::Pou(p.kind), p.name.span, p.span);
        let header_end = p
            .return_type
            .as_ref()
            .map(|t| t.span.end)
            .unwrap_or(p.name.span.end)
            .max(p.attributes.iter().map(|a| a.span.end).max().unwrap_or(0));
        let header_end = match self.text.get(header_end as usize..).and_then(|r| r.find('\n')) {
            Some(nl) => header_end + nl as u32,
            None => header_end,
        };
        self.ix.pous.push(PouEntry {
            name: p.name.text.clone(),
            kind: p.kind,
            span: p.span,
            name_span: p.name.span,
            sfc: matches!(p.body, ast::Body::Sfc(_)),
            symbols: Vec::new(),
            var_blocks: p.var_blocks.iter().map(|b| (b.kind, b.span)).collect(),
            header_end,
            extends: p.extends.as_ref().map(|e| e.text.clone()),
        });
        self.ix.local.push(Default::default());
        let idx = self.ix.pous.len() - 1;
        self.pou = Some(idx);
        for b in &p.var_blocks {
            self.var_block(b, Some(idx));
        }
        if let ast::Body::Sfc(elements) = &p.body {
            let declared: Vec<String> = self.ix.pou_symbols(idx).map(|(_, s)| s.key()).collect();
            for (name, kind, ty) in sfc_st_control_variables() {
                if !declared.iter().any(|d| d.eq_ignore_ascii_case(name)) {
                    let detail = VarDetail {
                        section: kind,
                        constant: false,
                        retain: None,
                        ty: ty.to_string(),
                        type_name: None,
                        init: None,
                        at: None,
                        implicit: true,
                    };
                    self.add(name, SymbolKind::Variable(detail), p.name.span, p.name.span);
                }
            }
            self.sfc_decls(elements);
        }
        // The actions of a POU that is no chart; the steps of those written in SFC.
        for a in &p.actions {
            self.add(&a.name.text, SymbolKind::Action, a.name.span, a.span);
            if let ActionBody::Sfc(inner) = &a.body {
                self.sfc_decls(inner);
            }
        }
        // Its methods and properties; the variables of a method or an accessor are its own.
        let methods: Vec<usize> =
            p.methods.iter().map(|m| self.add(&m.name.text, SymbolKind::Method, m.name.span, m.span)).collect();
        let properties: Vec<usize> =
            p.properties.iter().map(|q| self.add(&q.name.text, SymbolKind::Property, q.name.span, q.span)).collect();
        for (m, owner) in p.methods.iter().zip(methods) {
            self.scope = Some(self.new_scope(idx, owner, m.span));
            for b in &m.var_blocks {
                self.var_block(b, Some(idx));
            }
            if let Some(t) = &m.return_type {
                self.type_spec(t);
            }
        }
        for (q, owner) in p.properties.iter().zip(properties) {
            self.scope = None;
            self.type_spec(&q.ty);
            for acc in [&q.get, &q.set].into_iter().flatten() {
                self.scope = Some(self.new_scope(idx, owner, acc.span));
                for b in &acc.var_blocks {
                    self.var_block(b, Some(idx));
                }
            }
        }
        self.scope = None;
        self.pou = None;
    }

    fn var_block(&mut self, b: &VarBlock, _pou: Option<usize>) {
        for d in &b.decls {
            let type_name = match &d.ty.kind {
                TypeSpecKind::Named(n) => Some(n.text.clone()),
                _ => None,
            };
            for n in &d.names {
                let detail = VarDetail {
                    section: b.kind,
                    constant: b.constant,
                    retain: b.retain,
                    ty: one_line(&slice(self.text, d.ty.span)),
                    type_name: type_name.clone(),
                    init: d.init.as_ref().map(|i| one_line(&slice(self.text, i.span()))),
                    at: d.location.as_ref().map(|l| l.text.clone()),
                    implicit: false,
                };
                self.add(&n.text, SymbolKind::Variable(detail), n.span, d.span);
            }
        }
        for d in &b.decls {
            self.type_spec(&d.ty);
            if let Some(i) = &d.init {
                self.init(i);
            }
        }
    }

    fn sfc_decls(&mut self, elements: &[SfcElement]) {
        let mut unnamed = 0usize;
        let mut taken: std::collections::HashSet<String> = std::collections::HashSet::new();
        for e in elements {
            match e {
                SfcElement::Step(s) => {
                    taken.insert(s.name.key());
                }
                SfcElement::Action(a) => {
                    taken.insert(a.name.key());
                }
                SfcElement::Transition(t) => {
                    if let Some(n) = &t.name {
                        taken.insert(n.key());
                    }
                }
            }
        }
        if let Some(p) = self.pou {
            for (_, s) in self.ix.pou_symbols(p) {
                taken.insert(s.key());
            }
        }
        for e in elements {
            match e {
                SfcElement::Step(s) => {
                    let attr = |n: &str| s.attributes.iter().find(|a| a.name == n).and_then(|a| a.value.clone());
                    let detail = StepDetail {
                        initial: s.initial,
                        is_final: attr("sfc.final").is_some_and(|v| v.eq_ignore_ascii_case("true")),
                        timeout: attr("sfc.timeout"),
                        min_time: attr("sfc.min_time"),
                        tag: attr("sfc.tag"),
                        associations: s
                            .associations
                            .iter()
                            .map(|a| AssociationDetail {
                                action: a.action.text.clone(),
                                qualifier: a.qualifier.as_ref().map(|q| q.text.to_ascii_uppercase()),
                                duration: a.duration.as_ref().map(|d| one_line(&slice(self.text, d.span))),
                                indicators: a.indicators.iter().map(|i| i.text.clone()).collect(),
                            })
                            .collect(),
                    };
                    self.add(&s.name.text, SymbolKind::Step(detail), s.name.span, s.span);
                }
                SfcElement::Action(a) => {
                    self.add(&a.name.text, SymbolKind::Action, a.name.span, a.span);
                    if let ActionBody::Sfc(inner) = &a.body {
                        self.sfc_decls(inner);
                    }
                }
                SfcElement::Transition(t) => {
                    unnamed += 1;
                    let condition = match &t.condition {
                        Condition::St(e) => one_line(&slice(self.text, e.span)),
                        Condition::Il(il) => slice(self.text, il.span).trim().to_string(),
                        Condition::Missing => String::new(),
                    };
                    let header_end = t.to.last().map(|i| i.span.end).unwrap_or(t.span.start);
                    let header = Span::new(t.span.file, t.span.start, header_end.max(t.span.start));
                    let priority_insert = match &t.name {
                        Some(n) => n.span.end,
                        None => t.span.start + "TRANSITION".len() as u32,
                    };
                    let detail = TransitionDetail {
                        named: t.name.is_some(),
                        priority: t.priority.as_ref().map(|p| slice(self.text, p.span)),
                        from: t.from.iter().map(|i| i.text.clone()).collect(),
                        to: t.to.iter().map(|i| i.text.clone()).collect(),
                        condition,
                        header,
                        priority_insert,
                    };
                    let (name, name_span) = match &t.name {
                        Some(n) => (n.text.clone(), n.span),
                        None => {
                            // `T<n>`, or the first free `T<n>_k` (semantics.md).
                            let mut name = format!("T{unnamed}");
                            let mut k = 1;
                            while taken.contains(&name.to_ascii_uppercase()) {
                                name = format!("T{unnamed}_{k}");
                                k += 1;
                            }
                            taken.insert(name.to_ascii_uppercase());
                            (name, header)
                        }
                    };
                    self.add(&name, SymbolKind::Transition(detail), name_span, t.span);
                }
            }
        }
    }

    fn pou_body(&mut self, p: &Pou) {
        self.pou = self.ix.pous.iter().position(|e| e.span == p.span);
        match &p.body {
            ast::Body::St(stmts) => self.stmts(stmts),
            ast::Body::Il(il) => self.il(il),
            ast::Body::Sfc(elements) => self.chart_body(elements),
        }
        for a in &p.actions {
            self.action_body(&a.body);
        }
        // The code of its methods and properties, each in its scope (its variables, then the
        // POU's names).
        let bodies = p
            .methods
            .iter()
            .map(|m| (m.span, &m.body))
            .chain(p.properties.iter().flat_map(|q| [&q.get, &q.set]).flatten().map(|a| (a.span, &a.body)));
        for (span, b) in bodies {
            self.scope = self.scope_of(span);
            match b {
                ast::Body::St(stmts) => self.stmts(stmts),
                ast::Body::Il(il) => self.il(il),
                ast::Body::Sfc(elements) => self.chart_body(elements),
            }
        }
        self.scope = None;
        self.pou = None;
    }

    fn action_body(&mut self, body: &ActionBody) {
        match body {
            ActionBody::St(stmts) => self.stmts(stmts),
            ActionBody::Il(il) => self.il(il),
            ActionBody::Sfc(elements) => self.chart_body(elements),
        }
    }

    fn chart_body(&mut self, elements: &[SfcElement]) {
        for e in elements {
            match e {
                SfcElement::Step(s) => {
                    for a in &s.step_actions {
                        self.expr(&a.action);
                    }
                    for a in &s.associations {
                        self.occ(&a.action, Role::Association, None);
                        if let Some(q) = &a.qualifier {
                            self.ix.qualifiers.push(QualifierUse { span: q.span, name: q.text.to_ascii_uppercase() });
                        }
                        if let Some(d) = &a.duration {
                            self.expr(d);
                        }
                        for i in &a.indicators {
                            self.occ(i, Role::Code, None);
                        }
                    }
                }
                SfcElement::Transition(t) => {
                    if let Some(p) = &t.priority {
                        self.expr(p);
                    }
                    for s in t.from.iter().chain(&t.to) {
                        self.occ(s, Role::StepLink, None);
                    }
                    match &t.condition {
                        Condition::St(e) => self.expr(e),
                        Condition::Il(il) => self.il(il),
                        Condition::Missing => {}
                    }
                }
                SfcElement::Action(a) => self.action_body(&a.body),
            }
        }
    }

    fn type_spec(&mut self, t: &TypeSpec) {
        match &t.kind {
            TypeSpecKind::Named(n) => {
                if sfc_st::Type::elementary(&n.text).is_none() {
                    self.occ(n, Role::Type, None);
                }
            }
            TypeSpecKind::String { length: Some(e), .. } => self.expr(e),
            TypeSpecKind::Indirect { target, .. } => self.type_spec(target),
            TypeSpecKind::Array { ranges, element } => {
                for (a, b) in ranges {
                    self.expr(a);
                    self.expr(b);
                }
                self.type_spec(element);
            }
            TypeSpecKind::Subrange { low, high, .. } => {
                self.expr(low);
                self.expr(high);
            }
            TypeSpecKind::Enum { values, .. } => {
                for (_, v) in values {
                    if let Some(v) = v {
                        self.expr(v);
                    }
                }
            }
            TypeSpecKind::Struct(fields) => {
                for f in fields {
                    self.type_spec(&f.ty);
                    if let Some(i) = &f.init {
                        self.init(i);
                    }
                }
            }
            TypeSpecKind::String { length: None, .. } | TypeSpecKind::Error => {}
        }
    }

    fn init(&mut self, i: &Initializer) {
        match i {
            Initializer::Expr(e) => self.expr(e),
            Initializer::Array { elements, .. } => {
                for el in elements {
                    if let Some(r) = &el.repeat {
                        self.expr(r);
                    }
                    if let Some(v) = &el.value {
                        self.init(v);
                    }
                }
            }
            Initializer::Struct { fields, .. } => {
                for (_, v) in fields {
                    self.init(v);
                }
            }
        }
    }

    fn stmts(&mut self, stmts: &[Stmt]) {
        for s in stmts {
            self.stmt(s);
        }
    }

    fn stmt(&mut self, s: &Stmt) {
        match &s.kind {
            StmtKind::Assign { target, value } | StmtKind::RefAssign { target, value } => {
                self.expr(target);
                self.expr(value);
            }
            StmtKind::Call(e) => self.expr(e),
            StmtKind::If { branches, else_body } => {
                for (c, b) in branches {
                    self.expr(c);
                    self.stmts(b);
                }
                if let Some(b) = else_body {
                    self.stmts(b);
                }
            }
            StmtKind::Case { selector, arms, else_body } => {
                self.expr(selector);
                for arm in arms {
                    for l in &arm.labels {
                        match l {
                            ast::CaseLabel::Value(v) => self.expr(v),
                            ast::CaseLabel::Range(a, b) => {
                                self.expr(a);
                                self.expr(b);
                            }
                        }
                    }
                    self.stmts(&arm.body);
                }
                if let Some(b) = else_body {
                    self.stmts(b);
                }
            }
            StmtKind::For { var, from, to, by, body } => {
                self.occ(var, Role::Code, None);
                self.expr(from);
                self.expr(to);
                if let Some(b) = by {
                    self.expr(b);
                }
                self.stmts(body);
            }
            StmtKind::While { cond, body } => {
                self.expr(cond);
                self.stmts(body);
            }
            StmtKind::Repeat { body, until } => {
                self.stmts(body);
                self.expr(until);
            }
            StmtKind::Exit | StmtKind::Return | StmtKind::Empty => {}
        }
    }

    fn expr(&mut self, e: &Expr) {
        match &e.kind {
            ExprKind::Name(n) => self.occ(n, Role::Code, None),
            ExprKind::Member { base, member } => {
                match &base.kind {
                    ExprKind::Name(n) => self.occ(n, Role::Code, Some(member)),
                    _ => self.expr(base),
                }
                self.member_use(base, member);
            }
            ExprKind::Index { base, indices } => {
                self.expr(base);
                for i in indices {
                    self.expr(i);
                }
            }
            ExprKind::Call { callee, args } => {
                self.occ(callee, Role::Code, None);
                let of = (!callee.text.ends_with('^')).then(|| MemberBase::CallOf(callee.key()));
                self.args(of, args);
            }
            ExprKind::MemberCall { base, member, args } => {
                match &base.kind {
                    ExprKind::Name(n) => self.occ(n, Role::Code, Some(member)),
                    _ => self.expr(base),
                }
                self.member_use(base, member);
                let of = member_base(base).map(|b| MemberBase::CallOfMember(Box::new(b), member.key()));
                self.args(of, args);
            }
            ExprKind::Unary { operand, .. } => self.expr(operand),
            ExprKind::Binary { lhs, rhs, .. } => {
                self.expr(lhs);
                self.expr(rhs);
            }
            ExprKind::Paren(inner) | ExprKind::Deref(inner) => self.expr(inner),
            ExprKind::Literal(l) => {
                if let (ast::LiteralKind::Enum(v), Some(_)) = (&l.kind, &l.type_prefix) {
                    self.occ(v, Role::Code, None);
                }
            }
            ExprKind::Address(_) | ExprKind::Error => {}
        }
    }

    /// The arguments of a call; their formal parameter names are those of `of`'s parameters.
    fn args(&mut self, of: Option<MemberBase>, args: &[Arg]) {
        for a in args {
            if let (Some(of), Some(n)) = (&of, &a.name) {
                self.push_member(n, of.clone());
            }
            if let Some(v) = &a.value {
                self.expr(v);
            }
        }
    }

    fn il(&mut self, il: &IlBody) {
        self.il_instructions(&il.instructions);
    }

    fn il_instructions(&mut self, instructions: &[IlInstruction]) {
        for i in instructions {
            if let Some(op) = &i.op {
                if sfc_st::parse_il_op(&op.text).is_none() {
                    self.occ(op, Role::Code, None);
                }
            }
            let jump = i.op.as_ref().is_some_and(|o| o.text.to_ascii_uppercase().starts_with("JMP"));
            if !jump {
                for o in &i.operands {
                    self.expr(o);
                }
            }
            if let Some(n) = &i.nested {
                self.il_instructions(n);
            }
            if let Some(a) = &i.call_args {
                self.args(None, a);
            }
        }
    }
}

/// What a member written after `base` belongs to: a name, `THIS^` or `SUPER^`.
fn member_base(base: &Expr) -> Option<MemberBase> {
    match &base.kind {
        ExprKind::Name(n) => Some(MemberBase::Name(n.key())),
        ExprKind::Deref(inner) => match &inner.kind {
            ExprKind::Name(n) if n.is("THIS") => Some(MemberBase::This),
            ExprKind::Name(n) if n.is("SUPER") => Some(MemberBase::Super),
            _ => None,
        },
        _ => None,
    }
}

/// The implicit control variables of an SFC POU as (name, section, type).
fn sfc_st_control_variables() -> Vec<(&'static str, VarKind, String)> {
    sfc_st::sfc_control_variables().into_iter().map(|(n, k, t)| (n, k, t.to_string())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn index(text: &str) -> FileIndex {
        let (unit, _) = sfc_syntax::parse(0, text);
        FileIndex::new(&unit, text)
    }

    #[test]
    fn steps_and_their_uses() {
        let text = "PROGRAM P\nVAR Go : BOOL; END_VAR\nINITIAL_STEP S1: A(N); END_STEP\n\
                    TRANSITION FROM S1 TO S1 := Go AND S1.T > T#1s; END_TRANSITION\n\
                    ACTION A: Go := NOT A.Q; END_ACTION\nEND_PROGRAM\n";
        let ix = index(text);
        let s1 = ix.lookup(Some(0), "S1").unwrap();
        assert!(matches!(ix.symbols[s1].kind, SymbolKind::Step(_)));
        let uses: Vec<_> =
            ix.occurrences.iter().filter(|o| o.key == "S1").map(|o| (o.role, o.member.clone())).collect();
        assert_eq!(uses, [(Role::StepLink, None), (Role::StepLink, None), (Role::Code, Some("T".into()))]);
        let t = ix.lookup(Some(0), "T1").unwrap();
        assert!(
            matches!(&ix.symbols[t].kind, SymbolKind::Transition(d) if !d.named && d.condition == "Go AND S1.T > T#1s")
        );
        assert!(ix.lookup(Some(0), "SFCINIT").is_some());
        assert_eq!(ix.lookup(None, "P"), Some(0));
    }

    /// A method and each accessor have their own variables; the block's names used there are
    /// the block's; members and formal parameters are recorded with what they belong to.
    #[test]
    fn scopes_of_methods_and_accessors_and_members() {
        let text = "FUNCTION_BLOCK B\nVAR x : INT; END_VAR\nMETHOD M : INT\nVAR_INPUT x : INT; END_VAR\nVAR y : INT; END_VAR\n\
                    y := x; M := THIS^.x;\nEND_METHOD\nPROPERTY P : INT\nGET VAR g : INT; END_VAR P := g + x; END_GET\n\
                    END_PROPERTY\nEND_FUNCTION_BLOCK\nPROGRAM Q\nVAR b : B; END_VAR\nb.M(x := 1); b.P := 2;\nEND_PROGRAM\n";
        let ix = index(text);
        assert_eq!(ix.scopes.len(), 2);
        let m = ix.lookup_local(0, "M").unwrap();
        assert_eq!(ix.scopes[0].owner, m);
        let uses: Vec<(usize, usize)> = ix
            .occurrences
            .iter()
            .filter(|o| o.key == "X" || o.key == "Y" || o.key == "G")
            .map(|o| (ix.resolve(o).unwrap(), o.scope.unwrap()))
            .collect();
        let (bx, mx) = (ix.lookup_local(0, "X").unwrap(), ix.lookup_scoped(0, "X").unwrap());
        let (my, g) = (ix.lookup_scoped(0, "Y").unwrap(), ix.lookup_scoped(1, "G").unwrap());
        assert_ne!(bx, mx);
        assert_eq!(uses, [(my, 0), (mx, 0), (g, 1), (bx, 1)]);
        assert!(ix.pou_symbols(0).all(|(id, _)| id != mx && id != my), "the method's variables are not the block's");
        let members: Vec<(&str, &MemberBase, Option<usize>)> =
            ix.members.iter().map(|u| (u.key.as_str(), &u.base, u.pou)).collect();
        assert_eq!(
            members,
            [
                ("X", &MemberBase::This, Some(0)),
                ("M", &MemberBase::Name("B".into()), Some(1)),
                ("X", &MemberBase::CallOfMember(Box::new(MemberBase::Name("B".into())), "M".into()), Some(1)),
                ("P", &MemberBase::Name("B".into()), Some(1))
            ]
        );
    }
}
