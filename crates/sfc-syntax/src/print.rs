//! The canonical printer behind `sfc fmt`.
//!
//! The layout is fixed (upper-case keywords, four-space indentation, one declaration, statement,
//! association or instruction per line); what the user wrote that carries meaning or intent is
//! kept exactly: identifiers, literal text, grouping parentheses, comments and pragmas.
//!
//! Comments and pragmas are not in the tree but in [`SourceUnit::trivia`]. Every printed line
//! that starts a node has an *anchor*, the source offset of that node; before the line, every
//! not yet printed trivia that starts at or before the anchor is printed, on its own line, or at
//! the end of the previous line when it followed code on its line in the source. Lines that close
//! a block (`END_IF;`, `END_STEP`, …) first print the trivia that lies inside the block. Anchors
//! are visited in source order, so every trivia is printed exactly once, in source order, and
//! printing the output again puts each one at the same place (the printer is idempotent).

use crate::ast::*;
use crate::lexer::lex;

/// Prints a parsed file in canonical layout, putting every comment and pragma back.
///
/// The unit should come from an error-free parse: error placeholders print as nothing.
pub fn print(unit: &SourceUnit) -> String {
    let mut trivia: Vec<&Trivia> = unit.trivia.iter().collect();
    // Stable, so trivia at one offset (impossible from the lexer) would keep their order.
    trivia.sort_by_key(|t| t.span.start);
    let mut p = Printer::new(trivia, &unit.blank_lines);
    for (i, item) in unit.items.iter().enumerate() {
        if i > 0 {
            p.blank();
        }
        p.item(item);
    }
    // Comments after the last item are set apart from it like an item of their own.
    p.blank();
    p.flush_before(u32::MAX);
    p.finish()
}

const INDENT: &str = "    ";

/// One printed line; a comment or verbatim block spanning several lines counts as one.
struct Line {
    text: String,
    /// Code (not a comment or verbatim text): only code lines align their end-of-line comments.
    code: bool,
    /// Where the end-of-line comments of a code line start, to align them with the next lines'.
    comment_at: Option<usize>,
}

struct Printer<'a> {
    /// All trivia in source order; `next` is the first one not yet printed.
    trivia: Vec<&'a Trivia>,
    next: usize,
    /// Blank lines of the source; `next_blank` is the first one not yet passed.
    blank_lines: &'a [u32],
    next_blank: usize,
    lines: Vec<Line>,
    /// The line being built (indentation included); empty between lines.
    cur: String,
    indent: usize,
    /// A blank line is due before the next line that is printed.
    pending_blank: bool,
    /// The last line ends in a `//` comment: appending to it would comment the addition out.
    sealed: bool,
}

impl<'a> Printer<'a> {
    fn new(trivia: Vec<&'a Trivia>, blank_lines: &'a [u32]) -> Self {
        Printer {
            trivia,
            next: 0,
            blank_lines,
            next_blank: 0,
            lines: Vec::new(),
            cur: String::new(),
            indent: 0,
            pending_blank: false,
            sealed: false,
        }
    }

    fn finish(mut self) -> String {
        debug_assert!(self.cur.is_empty(), "a line was left open");
        debug_assert_eq!(self.next, self.trivia.len(), "trivia left unprinted");
        if self.lines.is_empty() {
            return String::new();
        }
        align_comments(&mut self.lines);
        let mut out = String::new();
        for line in &self.lines {
            out.push_str(&line.text);
            out.push('\n');
        }
        out
    }

    // -- Lines and trivia ---------------------------------------------------------------------

    /// Asks for one blank line before whatever is printed next (none at the start of the file).
    fn blank(&mut self) {
        self.pending_blank = true;
    }

    fn push_line(&mut self, text: String, code: bool) {
        if self.pending_blank && !self.lines.is_empty() {
            self.lines.push(Line { text: String::new(), code: false, comment_at: None });
        }
        self.pending_blank = false;
        self.lines.push(Line { text, code, comment_at: None });
        self.sealed = false;
    }

    /// Starts a line for a node beginning at `anchor`, after the trivia that precedes it.
    fn open(&mut self, anchor: u32) {
        // `<=`: a node whose span were to include its leading pragma still gets it before it.
        while let Some(t) = self.trivia.get(self.next).copied().filter(|t| t.span.start <= anchor) {
            if !self.can_trail(t) {
                self.keep_blank_before(t.span.start);
            }
            self.emit_next();
        }
        self.keep_blank_before(anchor);
        self.begin();
    }

    /// Keeps one blank line the user left before `pos`, between siblings only: not at the
    /// start of a block, where the line before is less indented.
    fn keep_blank_before(&mut self, pos: u32) {
        let mut seen = false;
        while self.blank_lines.get(self.next_blank).is_some_and(|b| *b < pos) {
            self.next_blank += 1;
            seen = true;
        }
        let indent = INDENT.len() * self.indent;
        let sibling = self.lines.last().is_some_and(|l| {
            let own = l.text.len() - l.text.trim_start().len();
            !l.text.is_empty() && own == indent
        });
        if seen && sibling {
            self.pending_blank = true;
        }
    }

    /// Starts a line that no node begins (a continuation or closing keyword).
    fn begin(&mut self) {
        debug_assert!(self.cur.is_empty());
        self.cur = INDENT.repeat(self.indent);
    }

    fn push(&mut self, text: &str) {
        self.cur.push_str(text);
    }

    fn end(&mut self) {
        let mut line = std::mem::take(&mut self.cur);
        line.truncate(line.trim_end().len());
        self.push_line(line, true);
    }

    /// A whole line for a node beginning at `anchor`.
    fn line(&mut self, anchor: u32, text: &str) {
        self.open(anchor);
        self.push(text);
        self.end();
    }

    /// A whole line that no node begins.
    fn plain(&mut self, text: &str) {
        self.begin();
        self.push(text);
        self.end();
    }

    /// Prints the trivia that starts before `pos` (the end of the enclosing block).
    fn flush_before(&mut self, pos: u32) {
        while self.trivia_before(pos) {
            self.emit_next();
        }
    }

    /// Prints the end-of-line comments that start before `pos`, for a keyword line without an
    /// anchor (`ELSE`): they belong to the line above it, own-line comments to what follows.
    fn flush_trailing(&mut self, pos: u32) {
        while let Some(t) = self.trivia.get(self.next).copied() {
            if t.span.start >= pos || !self.can_trail(t) {
                break;
            }
            self.emit_next();
        }
    }

    /// Whether `t` goes at the end of the previous line rather than on its own.
    fn can_trail(&self, t: &Trivia) -> bool {
        // A pragma describes what follows it, so it always gets a line of its own.
        !t.own_line && t.kind != TriviaKind::Pragma && !self.sealed && !self.lines.is_empty()
    }

    fn emit_next(&mut self) {
        let Some(t) = self.trivia.get(self.next).copied() else { return };
        self.next += 1;
        let trail = self.can_trail(t);
        if let (true, Some(last)) = (trail, self.lines.last_mut()) {
            let multi_line = t.text.contains('\n');
            // A multi-line comment is not aligned with its neighbours: its continuation lines
            // move by exactly as much as its first line, so they stay under it.
            if last.code && last.comment_at.is_none() && !multi_line {
                last.comment_at = Some(last.text.len());
            }
            last.text.push(' ');
            let new_column = last.text.chars().count() as i64;
            last.text.push_str(&shift_continuation(&t.text, new_column - t.column as i64));
        } else {
            let line = format!("{}{}", INDENT.repeat(self.indent), t.text);
            self.push_line(line, false);
        }
        self.sealed = t.kind == TriviaKind::LineComment;
    }

    /// Whether unprinted trivia starts before `pos`, i.e. inside a block ending there.
    fn trivia_before(&self, pos: u32) -> bool {
        self.trivia.get(self.next).is_some_and(|t| t.span.start < pos)
    }

    /// Closes a block: its inner trivia at the inner indentation, then `keyword` one level out.
    fn close(&mut self, end: u32, keyword: &str) {
        self.flush_before(end);
        self.indent -= 1;
        self.plain(keyword);
    }

    // -- Top level ----------------------------------------------------------------------------

    fn item(&mut self, item: &Item) {
        match item {
            Item::Pou(pou) => self.pou(pou),
            Item::Types(block) => self.type_block(block),
            Item::Globals(block) => self.var_block(block),
            Item::Verbatim(v) => self.verbatim(v),
            Item::Interface(i) => self.interface(i),
        }
    }

    fn verbatim(&mut self, v: &Verbatim) {
        self.open(v.span.start);
        let text = std::mem::take(&mut self.cur) + &v.text;
        self.push_line(text, false);
        // Comments inside the block are part of its text already.
        while self.trivia_before(v.span.end) {
            self.next += 1;
        }
    }

    fn pou(&mut self, pou: &Pou) {
        self.open(lead(pou.span, &pou.attributes));
        self.push(pou.kind.keyword());
        self.modifiers(&pou.modifiers);
        self.push(" ");
        self.push(&pou.name.text);
        if let Some(base) = &pou.extends {
            self.push(" EXTENDS ");
            self.push(&base.text);
        }
        if !pou.implements.is_empty() {
            self.push(" IMPLEMENTS ");
            self.push(&names(&pou.implements));
        }
        if let Some(ty) = &pou.return_type {
            self.push(" : ");
            self.type_spec(ty);
        }
        self.end();
        self.indent += 1;
        for block in &pou.var_blocks {
            self.var_block(block);
        }
        // Methods and properties before the body, as IEC 61131-3 3rd edition orders them.
        self.members(!pou.var_blocks.is_empty(), &pou.methods, &pou.properties);
        let body_empty = match &pou.body {
            Body::St(stmts) => stmts.is_empty(),
            Body::Il(il) => il.instructions.is_empty(),
            Body::Sfc(elements) => elements.is_empty(),
        };
        let before = !pou.var_blocks.is_empty() || !pou.methods.is_empty() || !pou.properties.is_empty();
        if !body_empty {
            if before {
                self.blank();
            }
            match &pou.body {
                Body::St(stmts) => self.stmts(stmts),
                Body::Il(il) => self.il_body(il),
                Body::Sfc(elements) => self.sfc(elements),
            }
        }
        // The actions of a POU that is no chart, after its statements.
        for (i, action) in pou.actions.iter().enumerate() {
            if i > 0 || !body_empty || before {
                self.blank();
            }
            self.action(action);
        }
        self.close(pou.span.end, pou.kind.end_keyword());
    }

    fn modifiers(&mut self, modifiers: &[Ident]) {
        for m in modifiers {
            self.push(" ");
            self.push(&m.text);
        }
    }

    /// Methods, then properties, each after a blank line (also the first when `after` is set).
    fn members(&mut self, after: bool, methods: &[Method], properties: &[Property]) {
        for (i, m) in methods.iter().enumerate() {
            if after || i > 0 {
                self.blank();
            }
            self.method(m);
        }
        for (i, p) in properties.iter().enumerate() {
            if after || i > 0 || !methods.is_empty() {
                self.blank();
            }
            self.property(p);
        }
    }

    /// Var blocks, then the code, a blank line between them.
    fn code(&mut self, var_blocks: &[VarBlock], body: &Body) {
        for block in var_blocks {
            self.var_block(block);
        }
        let empty = match body {
            Body::St(stmts) => stmts.is_empty(),
            Body::Il(il) => il.instructions.is_empty(),
            Body::Sfc(elements) => elements.is_empty(),
        };
        if !empty && !var_blocks.is_empty() {
            self.blank();
        }
        match body {
            Body::St(stmts) => self.stmts(stmts),
            Body::Il(il) => self.il_body(il),
            Body::Sfc(elements) => self.sfc(elements),
        }
    }

    fn method(&mut self, m: &Method) {
        self.open(lead(m.span, &m.attributes));
        self.push("METHOD");
        self.modifiers(&m.modifiers);
        self.push(" ");
        self.push(&m.name.text);
        if let Some(ty) = &m.return_type {
            self.push(" : ");
            self.type_spec(ty);
        }
        self.end();
        self.indent += 1;
        self.code(&m.var_blocks, &m.body);
        self.close(m.span.end, "END_METHOD");
    }

    fn property(&mut self, p: &Property) {
        self.open(lead(p.span, &p.attributes));
        self.push("PROPERTY");
        self.modifiers(&p.modifiers);
        self.push(" ");
        self.push(&p.name.text);
        self.push(" : ");
        self.type_spec(&p.ty);
        self.end();
        self.indent += 1;
        for (kw, end, acc) in [("GET", "END_GET", &p.get), ("SET", "END_SET", &p.set)] {
            let Some(acc) = acc else { continue };
            self.open(lead(acc.span, &acc.attributes));
            self.push(kw);
            self.modifiers(&acc.modifiers);
            self.end();
            self.indent += 1;
            self.code(&acc.var_blocks, &acc.body);
            self.close(acc.span.end, end);
        }
        self.close(p.span.end, "END_PROPERTY");
    }

    fn interface(&mut self, i: &Interface) {
        self.open(lead(i.span, &i.attributes));
        self.push("INTERFACE ");
        self.push(&i.name.text);
        if !i.extends.is_empty() {
            self.push(" EXTENDS ");
            self.push(&names(&i.extends));
        }
        self.end();
        self.indent += 1;
        self.members(false, &i.methods, &i.properties);
        self.close(i.span.end, "END_INTERFACE");
    }

    fn type_block(&mut self, block: &TypeBlock) {
        self.line(block.span.start, "TYPE");
        self.indent += 1;
        for decl in &block.decls {
            self.open(decl.span.start);
            self.push(&decl.name.text);
            self.push(" : ");
            self.type_spec(&decl.spec);
            if let Some(init) = &decl.init {
                self.push(" := ");
                self.push(&initializer(init));
            }
            self.push(";");
            self.end();
        }
        self.close(block.span.end, "END_TYPE");
    }

    fn var_block(&mut self, block: &VarBlock) {
        self.open(block.span.start);
        self.push(block.kind.keyword());
        if block.constant {
            self.push(" CONSTANT");
        }
        match block.retain {
            Some(Retain::Retain) => self.push(" RETAIN"),
            Some(Retain::NonRetain) => self.push(" NON_RETAIN"),
            None => {}
        }
        if block.persistent {
            self.push(" PERSISTENT");
        }
        self.end();
        self.indent += 1;
        for decl in &block.decls {
            self.var_decl(decl);
        }
        self.close(block.span.end, "END_VAR");
    }

    fn var_decl(&mut self, decl: &VarDecl) {
        self.open(lead(decl.span, &decl.attributes));
        let mut head = decl.names.iter().map(|n| n.text.as_str()).collect::<Vec<_>>().join(", ");
        if let Some(location) = &decl.location {
            if !head.is_empty() {
                head.push(' ');
            }
            head.push_str("AT ");
            head.push_str(&location.text);
        }
        self.push(&head);
        self.push(" : ");
        if let Some(path) = &decl.access_path {
            self.push(&access_path(path));
            self.push(" : ");
        }
        self.type_spec(&decl.ty);
        if let Some(edge) = decl.edge {
            self.push(" ");
            self.push(edge.keyword());
        }
        if let Some(mode) = &decl.access_mode {
            self.push(" ");
            self.push(mode);
        }
        if let Some(init) = &decl.init {
            self.push(" := ");
            self.push(&initializer(init));
        }
        self.push(";");
        self.end();
    }

    /// Appends a type to the current line; a STRUCT spreads over lines and leaves the line
    /// after `END_STRUCT` open.
    fn type_spec(&mut self, ty: &TypeSpec) {
        match &ty.kind {
            TypeSpecKind::Named(name) => self.push(&name.text),
            TypeSpecKind::Indirect { kind, target } => {
                self.push(kind.keyword());
                self.push(" ");
                self.type_spec(target);
            }
            TypeSpecKind::String { wide, length } => {
                self.push(if *wide { "WSTRING" } else { "STRING" });
                if let Some(length) = length {
                    self.push(&format!("[{}]", expr(length)));
                }
            }
            TypeSpecKind::Array { ranges, element } => {
                let ranges: Vec<String> = ranges.iter().map(|(lo, hi)| format!("{}..{}", expr(lo), expr(hi))).collect();
                self.push(&format!("ARRAY [{}] OF ", ranges.join(", ")));
                self.type_spec(element);
            }
            TypeSpecKind::Subrange { base, low, high } => {
                self.push(&format!("{} ({}..{})", base.text, expr(low), expr(high)));
            }
            TypeSpecKind::Enum { base, values } => {
                if let Some(base) = base {
                    self.push(&base.text);
                    self.push(" ");
                }
                let values: Vec<String> = values
                    .iter()
                    .map(|(name, value)| match value {
                        Some(v) => format!("{} := {}", name.text, expr(v)),
                        None => name.text.clone(),
                    })
                    .collect();
                self.push(&format!("({})", values.join(", ")));
            }
            TypeSpecKind::Struct(members) => {
                self.push("STRUCT");
                self.end();
                self.indent += 1;
                for member in members {
                    self.var_decl(member);
                }
                self.flush_before(ty.span.end);
                self.indent -= 1;
                self.begin();
                self.push("END_STRUCT");
            }
            TypeSpecKind::Error => {}
        }
    }

    // -- SFC ----------------------------------------------------------------------------------

    fn sfc(&mut self, elements: &[SfcElement]) {
        for (i, element) in elements.iter().enumerate() {
            if i > 0 {
                self.blank();
            }
            match element {
                SfcElement::Step(step) => self.step(step),
                SfcElement::Transition(transition) => self.transition(transition),
                SfcElement::Action(action) => self.action(action),
            }
        }
    }

    fn step(&mut self, step: &Step) {
        self.open(lead(step.span, &step.attributes));
        self.push(if step.initial { "INITIAL_STEP " } else { "STEP " });
        self.push(&step.name.text);
        self.push(":");
        // One line when empty, unless a comment inside would then move out of the step.
        if step.associations.is_empty() && step.step_actions.is_empty() && !self.trivia_before(step.span.end) {
            self.push(" END_STEP");
            self.end();
            return;
        }
        self.end();
        self.indent += 1;
        // The step actions first, then the IEC associations, each in the order written.
        for a in &step.step_actions {
            self.line(a.span.start, &format!("{} := {};", a.kind.keyword(), expr(&a.action)));
        }
        for assoc in &step.associations {
            self.line(assoc.span.start, &format!("{};", association(assoc)));
        }
        self.close(step.span.end, "END_STEP");
    }

    fn transition(&mut self, t: &Transition) {
        self.open(lead(t.span, &t.attributes));
        self.push("TRANSITION");
        if let Some(name) = &t.name {
            self.push(" ");
            self.push(&name.text);
        }
        if let Some(priority) = &t.priority {
            self.push(&format!(" (PRIORITY := {})", expr(priority)));
        }
        self.push(&format!(" FROM {} TO {}", step_list(&t.from, t.from_parens), step_list(&t.to, t.to_parens)));
        match &t.condition {
            Condition::St(cond) => {
                self.end();
                self.indent += 1;
                self.line(cond.span.start, &format!(":= {};", expr(cond)));
            }
            Condition::Il(il) => {
                self.push(":");
                self.end();
                self.indent += 1;
                self.il_body(il);
            }
            Condition::Missing => {
                self.end();
                self.indent += 1;
            }
        }
        self.close(t.span.end, "END_TRANSITION");
    }

    fn action(&mut self, action: &Action) {
        self.open(lead(action.span, &action.attributes));
        self.push("ACTION ");
        self.push(&action.name.text);
        self.push(":");
        let empty = match &action.body {
            ActionBody::St(stmts) => stmts.is_empty(),
            ActionBody::Il(il) => il.instructions.is_empty(),
            ActionBody::Sfc(elements) => elements.is_empty(),
        };
        if empty && !self.trivia_before(action.span.end) {
            self.push(" END_ACTION");
            self.end();
            return;
        }
        self.end();
        self.indent += 1;
        match &action.body {
            ActionBody::St(stmts) => self.stmts(stmts),
            ActionBody::Il(il) => self.il_body(il),
            ActionBody::Sfc(elements) => self.sfc(elements),
        }
        self.close(action.span.end, "END_ACTION");
    }

    // -- Structured Text ----------------------------------------------------------------------

    fn stmts(&mut self, stmts: &[Stmt]) {
        for stmt in stmts {
            self.stmt(stmt);
        }
    }

    /// Statements one level in.
    fn block(&mut self, stmts: &[Stmt]) {
        self.indent += 1;
        self.stmts(stmts);
        self.indent -= 1;
    }

    fn stmt(&mut self, stmt: &Stmt) {
        let start = stmt.span.start;
        match &stmt.kind {
            StmtKind::Assign { target, value } => self.line(start, &format!("{} := {};", expr(target), expr(value))),
            StmtKind::Call(call) => self.line(start, &format!("{};", expr(call))),
            StmtKind::RefAssign { target, value } => {
                self.line(start, &format!("{} REF= {};", expr(target), expr(value)))
            }
            StmtKind::If { branches, else_body } => {
                for (i, (cond, body)) in branches.iter().enumerate() {
                    if i == 0 {
                        self.line(start, &format!("IF {} THEN", expr(cond)));
                    } else {
                        // Comments ending the previous branch stay inside it.
                        self.indent += 1;
                        self.flush_before(cond.span.start);
                        self.indent -= 1;
                        self.line(cond.span.start, &format!("ELSIF {} THEN", expr(cond)));
                    }
                    self.block(body);
                }
                if let Some(else_body) = else_body {
                    self.else_branch(else_body, stmt.span.end);
                }
                self.indent += 1;
                self.close(stmt.span.end, "END_IF;");
            }
            StmtKind::Case { selector, arms, else_body } => {
                self.line(start, &format!("CASE {} OF", expr(selector)));
                self.indent += 1;
                for arm in arms {
                    let labels: Vec<String> = arm
                        .labels
                        .iter()
                        .map(|label| match label {
                            CaseLabel::Value(v) => expr(v),
                            CaseLabel::Range(lo, hi) => format!("{}..{}", expr(lo), expr(hi)),
                        })
                        .collect();
                    self.line(arm.span.start, &format!("{}:", labels.join(", ")));
                    self.block(&arm.body);
                }
                if let Some(else_body) = else_body {
                    self.else_branch(else_body, stmt.span.end);
                }
                self.close(stmt.span.end, "END_CASE;");
            }
            StmtKind::For { var, from, to, by, body } => {
                let by = by.as_ref().map(|b| format!(" BY {}", expr(b))).unwrap_or_default();
                self.line(start, &format!("FOR {} := {} TO {}{} DO", var.text, expr(from), expr(to), by));
                self.indent += 1;
                self.stmts(body);
                self.close(stmt.span.end, "END_FOR;");
            }
            StmtKind::While { cond, body } => {
                self.line(start, &format!("WHILE {} DO", expr(cond)));
                self.indent += 1;
                self.stmts(body);
                self.close(stmt.span.end, "END_WHILE;");
            }
            StmtKind::Repeat { body, until } => {
                self.line(start, "REPEAT");
                self.indent += 1;
                self.stmts(body);
                self.flush_before(until.span.start);
                self.indent -= 1;
                self.line(until.span.start, &format!("UNTIL {}", expr(until)));
                self.indent += 1;
                self.close(stmt.span.end, "END_REPEAT;");
            }
            StmtKind::Exit => self.line(start, "EXIT;"),
            StmtKind::Return => self.line(start, "RETURN;"),
            StmtKind::Empty => self.line(start, ";"),
        }
    }

    /// `ELSE` and its statements; `end` is the end of the whole statement.
    fn else_branch(&mut self, body: &[Stmt], end: u32) {
        // The ELSE keyword's own offset is not in the tree: end-of-line comments before the first
        // statement stay on the line above, the others go under ELSE.
        self.flush_trailing(body.first().map_or(end, |s| s.span.start));
        self.plain("ELSE");
        self.block(body);
    }

    // -- Instruction List ---------------------------------------------------------------------

    fn il_body(&mut self, il: &IlBody) {
        for instruction in &il.instructions {
            self.il_instruction(instruction);
        }
    }

    fn il_instruction(&mut self, ins: &IlInstruction) {
        let mut text = String::new();
        if let Some(label) = &ins.label {
            text.push_str(&label.text);
            text.push(':');
        }
        if let Some(op) = &ins.op {
            if !text.is_empty() {
                text.push(' ');
            }
            text.push_str(&op.text);
            if ins.nested.is_some() {
                text.push('(');
            }
            if !ins.operands.is_empty() {
                text.push(' ');
                text.push_str(&ins.operands.iter().map(expr).collect::<Vec<_>>().join(", "));
            }
            if let Some(args) = &ins.call_args {
                text.push_str(&format!("({})", call_args(args)));
            }
        }
        self.line(ins.span.start, &text);
        if let Some(nested) = &ins.nested {
            self.indent += 1;
            self.il_body_slice(nested);
            self.close(ins.span.end, ")");
        }
    }

    fn il_body_slice(&mut self, instructions: &[IlInstruction]) {
        for instruction in instructions {
            self.il_instruction(instruction);
        }
    }
}

/// Aligns the end-of-line comments of consecutive code lines at one indentation, as engineers
/// do in declaration lists: one space after the longest code of the run.
/// Moves the second and later lines of `text` right (or left, over blanks only) by `shift`.
fn shift_continuation(text: &str, shift: i64) -> String {
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
            if shift >= 0 {
                out.push_str(&" ".repeat(shift as usize));
                out.push_str(line);
            } else {
                let blanks = line.len() - line.trim_start_matches(' ').len();
                out.push_str(&line[blanks.min((-shift) as usize)..]);
            }
        } else {
            out.push_str(line);
        }
    }
    out
}

fn align_comments(lines: &mut [Line]) {
    let indent = |line: &Line| line.text.len() - line.text.trim_start().len();
    let width = |line: &Line| line.comment_at.map_or(0, |at| line.text[..at].chars().count());
    let mut i = 0;
    while let Some(first) = lines.get(i) {
        if first.comment_at.is_none() {
            i += 1;
            continue;
        }
        // A run of lines with trailing comments at one indentation (at least `first`).
        let level = indent(first);
        let run = lines.iter().skip(i).take_while(|l| l.comment_at.is_some() && indent(l) == level).count().max(1);
        let widest = lines.iter().skip(i).take(run).map(width).max().unwrap_or(0);
        for line in lines.iter_mut().skip(i).take(run) {
            let pad = widest - width(line);
            if let Some(at) = line.comment_at {
                line.text.insert_str(at, &" ".repeat(pad));
            }
        }
        i += run;
    }
}

/// Where the line of an element with attributes starts: after its last attribute pragma, so
/// that the pragmas are printed before it even if its span were to include them.
fn lead(span: Span, attributes: &[Attribute]) -> u32 {
    attributes.iter().map(|a| a.span.end).fold(span.start, u32::max)
}

/// A VAR_ACCESS path without the white space and comments the parser keeps in it (the comments
/// are printed from the trivia, so printing them here too would double them).
fn access_path(path: &str) -> String {
    let (tokens, _) = lex(0, path);
    tokens.iter().filter(|t| !t.kind.is_trivia()).map(|t| &path[t.start as usize..t.end as usize]).collect()
}

/// `S1` or `(S1, S2)`.
fn step_list(steps: &[Ident], parens: bool) -> String {
    let names = steps.iter().map(|s| s.text.as_str()).collect::<Vec<_>>().join(", ");
    if parens || steps.len() != 1 {
        format!("({names})")
    } else {
        names
    }
}

/// `Name(Q)`, `Name(L, T#5s)`, `Name(N, Indicator)`, `Name()`.
fn association(assoc: &ActionAssociation) -> String {
    let mut parts = vec![assoc.qualifier.as_ref().map(|q| q.text.clone()).unwrap_or_default()];
    parts.extend(assoc.duration.iter().map(expr));
    parts.extend(assoc.indicators.iter().map(|i| i.text.clone()));
    format!("{}({})", assoc.action.text, parts.join(", "))
}

/// `[10(1), 2, 3()]`, `(a := 1, b := (c := 2))` or an expression.
fn initializer(init: &Initializer) -> String {
    match init {
        Initializer::Expr(e) => expr(e),
        Initializer::Array { elements, .. } => {
            let elements: Vec<String> = elements
                .iter()
                .map(|el| {
                    let value = el.value.as_ref().map(initializer).unwrap_or_default();
                    match &el.repeat {
                        Some(count) => format!("{}({})", expr(count), value),
                        None => value,
                    }
                })
                .collect();
            format!("[{}]", elements.join(", "))
        }
        Initializer::Struct { fields, .. } => {
            let fields: Vec<String> =
                fields.iter().map(|(name, value)| format!("{} := {}", name.text, initializer(value))).collect();
            format!("({})", fields.join(", "))
        }
    }
}

fn call_args(args: &[Arg]) -> String {
    let args: Vec<String> = args
        .iter()
        .map(|arg| {
            let value = arg.value.as_ref().map(expr).unwrap_or_default();
            match &arg.name {
                None => value,
                Some(name) if arg.output => {
                    let not = if arg.negated { "NOT " } else { "" };
                    format!("{not}{} => {value}", name.text).trim_end().to_string()
                }
                Some(name) => format!("{} := {value}", name.text),
            }
        })
        .collect();
    args.join(", ")
}

// -- Expressions ------------------------------------------------------------------------------

/// An expression on one line, with the user's parentheses and only those the tree needs.
pub fn expr(e: &Expr) -> String {
    let mut out = String::new();
    write_expr(&mut out, e);
    out
}

fn write_expr(out: &mut String, e: &Expr) {
    match &e.kind {
        ExprKind::Literal(lit) => match lit.kind {
            // TRUE and FALSE are keywords, upper case like the others; every other literal keeps
            // its text (`16#ff`, `t#5s` and `1_000` say something about the value).
            LiteralKind::Bool(_) if lit.type_prefix.is_none() => out.push_str(&lit.text.to_ascii_uppercase()),
            _ => out.push_str(&lit.text),
        },
        ExprKind::Name(name) => out.push_str(&name.text),
        ExprKind::Address(address) => out.push_str(&address.text),
        ExprKind::Member { base, member } => {
            write_operand(out, base, !is_postfix_base(base));
            out.push('.');
            out.push_str(&member.text);
        }
        ExprKind::Index { base, indices } => {
            write_operand(out, base, !is_postfix_base(base));
            out.push('[');
            for (i, index) in indices.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_expr(out, index);
            }
            out.push(']');
        }
        ExprKind::Call { callee, args } => {
            out.push_str(&callee.text);
            out.push('(');
            out.push_str(&call_args(args));
            out.push(')');
        }
        ExprKind::MemberCall { base, member, args } => {
            write_operand(out, base, !is_postfix_base(base));
            out.push('.');
            out.push_str(&member.text);
            out.push('(');
            out.push_str(&call_args(args));
            out.push(')');
        }
        ExprKind::Unary { op, operand } => {
            out.push_str(match op {
                UnaryOp::Neg => "-",
                UnaryOp::Plus => "+",
                UnaryOp::Not => "NOT ",
            });
            let mut inner = String::new();
            write_operand(&mut inner, operand, unary_operand_needs_parens(operand));
            // `- -x`, not `--x`; `-+x` alike: keep signs apart for the reader.
            if *op != UnaryOp::Not && inner.starts_with(['-', '+']) {
                out.push(' ');
            }
            out.push_str(&inner);
        }
        ExprKind::Binary { op, lhs, rhs } => {
            write_operand(out, lhs, binary_operand_needs_parens(*op, lhs, Side::Left));
            out.push(' ');
            out.push_str(op.symbol());
            out.push(' ');
            write_operand(out, rhs, binary_operand_needs_parens(*op, rhs, Side::Right));
        }
        ExprKind::Paren(inner) => {
            out.push('(');
            write_expr(out, inner);
            out.push(')');
        }
        ExprKind::Deref(base) => {
            write_operand(out, base, !is_postfix_base(base));
            out.push('^');
        }
        ExprKind::Error => {}
    }
}

fn write_operand(out: &mut String, e: &Expr, parens: bool) {
    if parens {
        out.push('(');
        write_expr(out, e);
        out.push(')');
    } else {
        write_expr(out, e);
    }
}

/// Whether `e` can be followed by `.member` or `[index]` as it is: a literal cannot (`1.5`).
fn is_postfix_base(e: &Expr) -> bool {
    matches!(
        e.kind,
        ExprKind::Name(_)
            | ExprKind::Address(_)
            | ExprKind::Member { .. }
            | ExprKind::Index { .. }
            | ExprKind::Call { .. }
            | ExprKind::Paren(_)
            | ExprKind::Deref(_)
    )
}

#[derive(Clone, Copy, PartialEq)]
enum Side {
    Left,
    Right,
}

/// Parentheses a parsed tree never needs but a built one may: an operand binding looser than
/// its operator, an equal-precedence right operand (all IEC binary operators group to the left,
/// `**` included), and a unary operand that would swallow the operator after it.
fn binary_operand_needs_parens(op: BinaryOp, operand: &Expr, side: Side) -> bool {
    match &operand.kind {
        ExprKind::Binary { op: inner, .. } => match side {
            Side::Left => {
                inner.precedence() < op.precedence() || op.precedence() >= UNARY_PRECEDENCE && ends_in_unary(operand)
            }
            Side::Right => inner.precedence() <= op.precedence(),
        },
        // `-a ** b` reads as `-(a ** b)`: a unary left operand of an operator binding at least as
        // tightly as the unary operators needs parentheses.
        ExprKind::Unary { .. } => side == Side::Left && op.precedence() >= UNARY_PRECEDENCE,
        _ => false,
    }
}

/// Whether `e` prints ending in a unary operator's operand, which would also take a following
/// operator binding at least as tightly as the unary operators (`a ** -b ** c`).
fn ends_in_unary(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Unary { .. } => true,
        ExprKind::Binary { rhs, .. } => ends_in_unary(rhs),
        _ => false,
    }
}

/// `-(a + b)`: a binary operand binding looser than the unary operator.
fn unary_operand_needs_parens(operand: &Expr) -> bool {
    match &operand.kind {
        ExprKind::Binary { op, .. } => op.precedence() < UNARY_PRECEDENCE,
        _ => false,
    }
}

/// `A, B, C`
fn names(list: &[Ident]) -> String {
    list.iter().map(|n| n.text.as_str()).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{parse, parse_expression};
    use sfc_diagnostics::Severity;

    /// Formats `source`, checking that input and output parse cleanly, that the output is stable
    /// and that every comment and pragma appears in it as often as in the input.
    fn fmt(source: &str) -> String {
        let (unit, diags) = parse(0, source);
        assert!(diags.iter().all(|d| d.severity != Severity::Error), "{diags:?}");
        let out = print(&unit);
        let (again, diags) = parse(0, &out);
        assert!(diags.iter().all(|d| d.severity != Severity::Error), "{diags:?}\n{out}");
        assert_eq!(print(&again), out, "not idempotent");
        // Continuation lines of a moved multi-line comment are re-indented: compare without it.
        let flat = |s: &str| s.split('\n').map(str::trim_start).collect::<Vec<_>>().join("\n");
        let (flat_out, flat_src) = (flat(&out), flat(source));
        for t in &unit.trivia {
            let text = flat(&t.text);
            assert_eq!(flat_out.matches(&text).count(), flat_src.matches(&text).count(), "{:?} in\n{out}", t.text);
        }
        out
    }

    #[test]
    fn chart_layout() {
        let source = "(* Filling a tank. *)
{attribute 'sfc.target' := 'blank'}
program Tank
var level : int; full, pump : bool; end_var
{attribute 'sfc.tag' := '0'}
initial_step Idle: end_step
transition Start (priority := 1) from Idle to (Fill, Log) := level < 10 and not full; end_transition
step Fill: Pump(N); Alarm(L, T#5s, pump); Valve(); end_step
step Log: end_step
transition from (Fill, Log) to Idle := full; end_transition
action Pump: pump := true; end_action
end_program";
        let expected = "\
(* Filling a tank. *)
{attribute 'sfc.target' := 'blank'}
PROGRAM Tank
    VAR
        level : int;
        full, pump : bool;
    END_VAR

    {attribute 'sfc.tag' := '0'}
    INITIAL_STEP Idle: END_STEP

    TRANSITION Start (PRIORITY := 1) FROM Idle TO (Fill, Log)
        := level < 10 AND NOT full;
    END_TRANSITION

    STEP Fill:
        Pump(N);
        Alarm(L, T#5s, pump);
        Valve();
    END_STEP

    STEP Log: END_STEP

    TRANSITION FROM (Fill, Log) TO Idle
        := full;
    END_TRANSITION

    ACTION Pump:
        pump := TRUE;
    END_ACTION
END_PROGRAM
";
        assert_eq!(fmt(source), expected);
    }

    #[test]
    fn statement_layout() {
        let source = "FUNCTION_BLOCK Count
VAR_INPUT go : BOOL; END_VAR
VAR n, i : INT; END_VAR
if go then n := n + 1; elsif n > 10 then n := 0; else ; end_if;
case n of 0: n := 0; 1, 2..4: n := n * 2; else n := -n; end_case;
for i := 0 to 9 by 3 do exit; end_for;
while n > 0 do n := n - 1; end_while;
repeat n := n + 1; until n = 5 end_repeat;
Timer(IN := go, PT := T#1s, NOT Q => go, ET =>);
return;
END_FUNCTION_BLOCK";
        let expected = "\
FUNCTION_BLOCK Count
    VAR_INPUT
        go : BOOL;
    END_VAR
    VAR
        n, i : INT;
    END_VAR

    IF go THEN
        n := n + 1;
    ELSIF n > 10 THEN
        n := 0;
    ELSE
        ;
    END_IF;
    CASE n OF
        0:
            n := 0;
        1, 2..4:
            n := n * 2;
        ELSE
            n := -n;
    END_CASE;
    FOR i := 0 TO 9 BY 3 DO
        EXIT;
    END_FOR;
    WHILE n > 0 DO
        n := n - 1;
    END_WHILE;
    REPEAT
        n := n + 1;
    UNTIL n = 5
    END_REPEAT;
    Timer(IN := go, PT := T#1s, NOT Q => go, ET =>);
    RETURN;
END_FUNCTION_BLOCK
";
        assert_eq!(fmt(source), expected);
    }

    #[test]
    fn declaration_layout() {
        let source = "type Point : struct x : INT; y : INT := 2; end_struct;
Grid : array [1..10, 0..2] of Point; Name : string(20) := 'abc'; Level : INT (0..100);
Colour : (Red, Green := 2) := Red; end_type
function F : INT var_input a : INT; end_var
var constant AT %IW6.2 : WORD; p AT %QX1.0 : BOOL := TRUE; end_var
var_access acc : Conf . Res.x : INT read_write; end_var
var arr : ARRAY [1..5] OF INT := [2(1), 3(), 7]; pt : Point := (x := 1, y := 2); end_var
F := a; end_function";
        let expected = "\
TYPE
    Point : STRUCT
        x : INT;
        y : INT := 2;
    END_STRUCT;
    Grid : ARRAY [1..10, 0..2] OF Point;
    Name : STRING[20] := 'abc';
    Level : INT (0..100);
    Colour : (Red, Green := 2) := Red;
END_TYPE

FUNCTION F : INT
    VAR_INPUT
        a : INT;
    END_VAR
    VAR CONSTANT
        AT %IW6.2 : WORD;
        p AT %QX1.0 : BOOL := TRUE;
    END_VAR
    VAR_ACCESS
        acc : Conf.Res.x : INT READ_WRITE;
    END_VAR
    VAR
        arr : ARRAY [1..5] OF INT := [2(1), 3(), 7];
        pt : Point := (x := 1, y := 2);
    END_VAR

    F := a;
END_FUNCTION
";
        assert_eq!(fmt(source), expected);
    }

    #[test]
    fn instruction_list_layout() {
        let source = "PROGRAM P
VAR a, b : BOOL; END_VAR
INITIAL_STEP S0: END_STEP
TRANSITION FROM S0 TO S0 :
 LD a
 AND( b
 OR a
 )
END_TRANSITION
ACTION A:
start: LD a
 ANDN b
 JMPC start
 CAL T1(IN := a)
done:
 ST b
END_ACTION
END_PROGRAM";
        let expected = "\
PROGRAM P
    VAR
        a, b : BOOL;
    END_VAR

    INITIAL_STEP S0: END_STEP

    TRANSITION FROM S0 TO S0:
        LD a
        AND( b
            OR a
        )
    END_TRANSITION

    ACTION A:
        start: LD a
        ANDN b
        JMPC start
        CAL T1(IN := a)
        done:
        ST b
    END_ACTION
END_PROGRAM
";
        assert_eq!(fmt(source), expected);
    }

    #[test]
    fn end_of_line_comments_stay_and_align() {
        let source = "PROGRAM P
VAR
  a : BOOL; (* first *)
  longer_name : INT := 5; (* second *)
  (* on its own *)
  b : BOOL; // third
END_VAR
a := TRUE; (* set *)
END_PROGRAM (* done *)";
        let expected = "\
PROGRAM P
    VAR
        a : BOOL;               (* first *)
        longer_name : INT := 5; (* second *)
        (* on its own *)
        b : BOOL; // third
    END_VAR

    a := TRUE; (* set *)
END_PROGRAM (* done *)
";
        assert_eq!(fmt(source), expected);
    }

    #[test]
    fn multi_line_trailing_comments_move_as_one() {
        let src = "PROGRAM P\n    VAR\n        Start : BOOL;       (* one\n                               two *)\n    END_VAR\nEND_PROGRAM\n";
        let out = fmt(src);
        assert!(out.contains("        Start : BOOL; (* one\n                         two *)\n"), "{out}");
        assert_eq!(fmt(&out), out);
    }

    #[test]
    fn blank_lines_between_statements_are_kept_once() {
        let src = "PROGRAM P\nVAR x : INT; END_VAR\nx := 1;\n\n\n\nx := 2;\nx := 3;\nIF x > 1 THEN\n\n    x := 4;\nEND_IF;\nEND_PROGRAM\n";
        let out = fmt(src);
        assert!(out.contains("    x := 1;\n\n    x := 2;\n    x := 3;\n    IF x > 1 THEN\n        x := 4;"), "{out}");
        assert_eq!(fmt(&out), out);
    }

    #[test]
    fn nothing_is_appended_after_a_line_comment() {
        let source = "PROGRAM P\nx := a + // why\n b; (* what *)\nEND_PROGRAM";
        assert_eq!(fmt(source), "PROGRAM P\n    x := a + b; // why\n    (* what *)\nEND_PROGRAM\n");
    }

    #[test]
    fn comments_inside_constructs_stay_inside() {
        let source = "PROGRAM P\nIF a THEN x := 1;\n(* last of the branch *)\nEND_IF;\nEND_PROGRAM";
        assert_eq!(
            fmt(source),
            "PROGRAM P\n    IF a THEN\n        x := 1;\n        (* last of the branch *)\n    END_IF;\nEND_PROGRAM\n"
        );
        let chart =
            "PROGRAM P\nINITIAL_STEP S1: (* nothing yet *) END_STEP\nACTION A:\n(* later *)\nEND_ACTION\nEND_PROGRAM";
        assert_eq!(
            fmt(chart),
            "PROGRAM P\n    INITIAL_STEP S1: (* nothing yet *)\n    END_STEP\n\n    ACTION A:\n        (* later *)\n    END_ACTION\nEND_PROGRAM\n"
        );
    }

    #[test]
    fn pragmas_always_get_their_own_line() {
        let source = "PROGRAM P VAR a : INT; {attribute 'sfc.description' := 'b'} b : INT; END_VAR END_PROGRAM";
        let out = fmt(source);
        assert!(
            out.contains("        a : INT;\n        {attribute 'sfc.description' := 'b'}\n        b : INT;\n"),
            "{out}"
        );
    }

    #[test]
    fn comments_inside_verbatim_blocks_are_printed_once() {
        let source =
            "CONFIGURATION C (* kept in the text *)\n  RESOURCE R ON PLC\n  END_RESOURCE\nEND_CONFIGURATION // after";
        assert_eq!(fmt(source), format!("{}\n", source));
    }

    #[test]
    fn comments_in_an_access_path_are_printed_once() {
        let out = fmt("PROGRAM P VAR_ACCESS acc : Conf.(* c *)Res.x : INT READ_ONLY; END_VAR END_PROGRAM");
        assert!(out.contains("acc : Conf.Res.x : INT READ_ONLY; (* c *)"), "{out}");
    }

    #[test]
    fn empty_and_comment_only_files() {
        assert_eq!(fmt(""), "");
        assert_eq!(fmt("  \n\n"), "");
        assert_eq!(fmt("(* a *) (* b *)\n\n// c"), "(* a *) (* b *)\n// c\n");
    }

    #[test]
    fn trailing_comments_of_the_file_come_last() {
        let out = fmt("PROGRAM P\nEND_PROGRAM (* same line *)\n\n\n(* the end *)\n");
        assert_eq!(out, "PROGRAM P\nEND_PROGRAM (* same line *)\n\n(* the end *)\n");
    }

    #[test]
    fn parsed_expressions_keep_their_parentheses_and_get_none() {
        for text in [
            "a + b * c",
            "(a + b) * c",
            "a - (b - c)",
            "a - b - c",
            "a ** b ** c",
            "a ** (b ** c)",
            "-a ** b",
            "(-a) ** b",
            "a ** -b ** c",
            "- -a",
            "NOT a AND b",
            "NOT (a AND b)",
            "NOT NOT a = b",
            "x MOD 3 = 0 OR y XOR z",
            "((a))",
            "s.x[i, j + 1].y",
            "Fb(IN := -x, Q => y, NOT Q2 =>, 3)",
            "%IX1.2 AND Step1.X",
            "16#FF + 1_000 + INT#-5 + T#1h2m + 'it$'s'",
        ] {
            let (e, diags) = parse_expression(0, text);
            assert!(diags.is_empty(), "{text}: {diags:?}");
            assert_eq!(expr(&e), text);
        }
        let (e, _) = parse_expression(0, "a&b  AND_THEN  c OR_ELSE -(d)");
        assert_eq!(expr(&e), "a AND b AND_THEN c OR_ELSE -(d)");
    }

    #[test]
    fn the_deepest_accepted_nesting_prints() {
        let depth = crate::MAX_DEPTH as usize - 8;
        let parens = format!("x := {}a{};", "(".repeat(depth), ")".repeat(depth));
        let unary = format!("x := {}a;", "-".repeat(depth).replace('-', "- "));
        let chain = format!("x := a{};", " + a".repeat(depth));
        let ifs = crate::MAX_STMT_DEPTH as usize - 4;
        let nested = format!("{}x := 1;{}", "IF a THEN ".repeat(ifs), " END_IF;".repeat(ifs));
        for body in [parens, unary, chain, nested] {
            fmt(&format!("PROGRAM P\n{body}\nEND_PROGRAM"));
        }
    }

    // -- Built trees, which the parser cannot produce: parentheses are added -----------------

    fn node(kind: ExprKind) -> Expr {
        Expr { kind, span: Span::default() }
    }
    fn name(n: &str) -> Expr {
        node(ExprKind::Name(Ident::new(n, Span::default())))
    }
    fn bin(op: BinaryOp, lhs: Expr, rhs: Expr) -> Expr {
        node(ExprKind::Binary { op, lhs: Box::new(lhs), rhs: Box::new(rhs) })
    }
    fn un(op: UnaryOp, operand: Expr) -> Expr {
        node(ExprKind::Unary { op, operand: Box::new(operand) })
    }

    /// The tree with every operation parenthesised and the Paren nodes dropped: what the
    /// expression means, whatever parentheses spell it.
    fn meaning(e: &Expr) -> String {
        match &e.kind {
            ExprKind::Binary { op, lhs, rhs } => format!("({} {} {})", meaning(lhs), op.symbol(), meaning(rhs)),
            ExprKind::Unary { op, operand } => format!("({op:?} {})", meaning(operand)),
            ExprKind::Paren(inner) => meaning(inner),
            _ => expr(e),
        }
    }

    #[test]
    fn built_trees_get_the_parentheses_they_need() {
        use BinaryOp::*;
        let (a, b, c) = (name("a"), name("b"), name("c"));
        let five = node(ExprKind::Literal(Literal { kind: LiteralKind::Int(5), type_prefix: None, text: "5".into() }));
        let cases = [
            (bin(Sub, a.clone(), bin(Sub, b.clone(), c.clone())), "a - (b - c)"),
            (bin(Sub, bin(Sub, a.clone(), b.clone()), c.clone()), "a - b - c"),
            (bin(Mul, bin(Add, a.clone(), b.clone()), c.clone()), "(a + b) * c"),
            (bin(Add, a.clone(), bin(Mul, b.clone(), c.clone())), "a + b * c"),
            (bin(Pow, a.clone(), bin(Pow, b.clone(), c.clone())), "a ** (b ** c)"),
            (un(UnaryOp::Neg, bin(Add, a.clone(), b.clone())), "-(a + b)"),
            (un(UnaryOp::Neg, bin(Pow, a.clone(), b.clone())), "-a ** b"),
            (bin(Pow, un(UnaryOp::Neg, a.clone()), b.clone()), "(-a) ** b"),
            (bin(Pow, bin(Pow, a.clone(), un(UnaryOp::Neg, b.clone())), c.clone()), "(a ** -b) ** c"),
            (un(UnaryOp::Neg, un(UnaryOp::Neg, a.clone())), "- -a"),
            (un(UnaryOp::Not, bin(And, a.clone(), b.clone())), "NOT (a AND b)"),
            (bin(And, un(UnaryOp::Not, a.clone()), b.clone()), "NOT a AND b"),
            (node(ExprKind::Member { base: Box::new(five), member: Ident::new("x", Span::default()) }), "(5).x"),
        ];
        for (tree, text) in cases {
            assert_eq!(expr(&tree), text);
            let (parsed, diags) = parse_expression(0, text);
            assert!(diags.is_empty(), "{text}: {diags:?}");
            assert_eq!(meaning(&parsed), meaning(&tree), "{text}");
        }
    }
}
