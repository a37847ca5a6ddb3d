//! Objects as IEC 61131-3's 3rd edition and CODESYS write them: the modifiers, `EXTENDS` and
//! `IMPLEMENTS` of a POU's header, `METHOD … END_METHOD`, CODESYS's
//! `PROPERTY … GET … END_GET SET … END_SET END_PROPERTY`, and `INTERFACE … END_INTERFACE`.
//!
//! `METHOD`, `PROPERTY`, `GET` and `SET` are words only where a member starts (the word followed
//! by a name), so variables called `Method` or `Set` in older files keep their meaning.

use super::*;

/// Access specifiers and modifiers of POUs, methods and properties.
const MODIFIERS: &[&str] = &["PUBLIC", "PRIVATE", "PROTECTED", "INTERNAL", "ABSTRACT", "FINAL"];

impl Parser<'_> {
    /// Whether a method or a property starts here (`METHOD Name`, `PROPERTY PUBLIC Name`).
    pub(super) fn at_member_start(&self) -> bool {
        (self.at_kw("METHOD") || self.at_kw("PROPERTY")) && self.nth(1).kind == TokenKind::Ident
    }

    /// The modifiers before a name: `ABSTRACT`, `PUBLIC`, … each followed by a further word.
    pub(super) fn modifiers(&mut self) -> Vec<Ident> {
        let mut out = Vec::new();
        while self.at_any_kw(MODIFIERS) && self.nth(1).kind == TokenKind::Ident {
            let t = self.bump();
            out.push(Ident::new(self.text_of(t).to_ascii_uppercase(), self.span_of(t)));
        }
        out
    }

    /// A possibly qualified name (`FB_Base`, `Lib.FB_Base`), as one identifier.
    pub(super) fn qualified_name(&mut self, what: &str) -> Option<Ident> {
        let first = self.expect_ident(what)?;
        let (mut text, start, mut end) = (first.text.clone(), first.span.start, first.span.end);
        while self.at(TokenKind::Dot) && self.nth(1).kind == TokenKind::Ident {
            self.bump();
            let t = self.bump();
            text.push('.');
            text.push_str(self.text_of(t));
            end = t.end;
        }
        Some(Ident::new(text, Span::new(self.file, start, end)))
    }

    /// `EXTENDS A` and `IMPLEMENTS B, C` after a POU's name (either order, as CODESYS allows).
    pub(super) fn inheritance(&mut self) -> (Option<Ident>, Vec<Ident>) {
        let mut extends = None;
        let mut implements = Vec::new();
        loop {
            if self.at_kw("EXTENDS") && self.nth(1).kind == TokenKind::Ident {
                self.bump();
                extends = self.qualified_name("the name of the function block it extends");
            } else if self.at_kw("IMPLEMENTS") && self.nth(1).kind == TokenKind::Ident {
                self.bump();
                implements.extend(self.name_list("an interface name"));
            } else {
                return (extends, implements);
            }
        }
    }

    fn name_list(&mut self, what: &str) -> Vec<Ident> {
        let mut out = Vec::new();
        loop {
            match self.qualified_name(what) {
                Some(n) => out.push(n),
                None => break,
            }
            if !self.eat(TokenKind::Comma) {
                break;
            }
        }
        out
    }

    /// Methods and properties at the current position, into `methods` and `properties`.
    pub(super) fn members(&mut self, methods: &mut Vec<Method>, properties: &mut Vec<Property>) {
        while self.at_member_start() {
            if self.at_kw("METHOD") {
                methods.push(self.method());
            } else {
                properties.push(self.property());
            }
            let end = self.prev_end();
            self.drop_attrs_before(end);
        }
    }

    fn var_blocks(&mut self) -> Vec<VarBlock> {
        let mut out = Vec::new();
        while self.at_any_kw(&VAR_KEYWORDS.iter().map(|v| v.0).collect::<Vec<_>>()) {
            out.push(self.var_block());
        }
        out
    }

    /// Statements (or IL) up to `end_kw`.
    fn code_until(&mut self, end_kw: &str) -> Body {
        if self.looks_like_il() {
            Body::Il(self.il_body(&[end_kw]))
        } else {
            Body::St(self.stmt_list(&[end_kw]))
        }
    }

    /// `METHOD [modifiers] Name [: Type] var blocks statements END_METHOD`
    pub(super) fn method(&mut self) -> Method {
        let kw = self.bump();
        let start = kw.start;
        let attributes = self.take_attrs(start);
        let modifiers = self.modifiers();
        let name = self.expect_ident("a method name").unwrap_or_else(|| Ident::new("", self.cur_span()));
        let return_type = if self.eat(TokenKind::Colon) { Some(self.type_spec()) } else { None };
        self.eat(TokenKind::Semi);
        let var_blocks = self.var_blocks();
        let body = self.code_until("END_METHOD");
        self.expect_end("END_METHOD", self.span_of(kw));
        self.eat(TokenKind::Semi);
        Method { name, modifiers, return_type, attributes, var_blocks, body, span: self.span_from(start) }
    }

    /// `PROPERTY [modifiers] Name : Type GET … END_GET SET … END_SET END_PROPERTY`
    pub(super) fn property(&mut self) -> Property {
        let kw = self.bump();
        let start = kw.start;
        let attributes = self.take_attrs(start);
        let modifiers = self.modifiers();
        let name = self.expect_ident("a property name").unwrap_or_else(|| Ident::new("", self.cur_span()));
        if !self.expect(TokenKind::Colon, "`:` and the type of the property") {
            self.recover_to(&["GET", "SET", "END_PROPERTY"], false);
        }
        let ty = if self.at_any_kw(&["GET", "SET", "END_PROPERTY"]) {
            TypeSpec { kind: TypeSpecKind::Error, span: self.cur_span() }
        } else {
            self.type_spec()
        };
        self.eat(TokenKind::Semi);
        let (mut get, mut set) = (None, None);
        loop {
            let is_get = self.at_kw("GET");
            if !is_get && !self.at_kw("SET") {
                break;
            }
            let acc = self.bump();
            let attributes = self.take_attrs(acc.start);
            let modifiers = self.modifiers();
            let end_kw = if is_get { "END_GET" } else { "END_SET" };
            let var_blocks = self.var_blocks();
            let body = self.code_until(end_kw);
            self.expect_end(end_kw, self.span_of(acc));
            self.eat(TokenKind::Semi);
            let a = Accessor { modifiers, attributes, var_blocks, body, span: self.span_from(acc.start) };
            let slot = if is_get { &mut get } else { &mut set };
            if slot.is_some() {
                let what = if is_get { "GET" } else { "SET" };
                self.push_error("SFC0101", a.span, format!("the property `{}` has a second {what}", name.text));
            }
            *slot = Some(a);
        }
        self.expect_end("END_PROPERTY", self.span_of(kw));
        self.eat(TokenKind::Semi);
        Property { name, modifiers, ty, attributes, get, set, span: self.span_from(start) }
    }

    /// `INTERFACE Name [EXTENDS A, B] methods and properties END_INTERFACE`
    pub(super) fn interface(&mut self) -> Interface {
        let kw = self.bump();
        let start = kw.start;
        let attributes = self.take_attrs(start);
        let name = self.expect_ident("an interface name").unwrap_or_else(|| Ident::new("", self.cur_span()));
        let extends = if self.at_kw("EXTENDS") && self.nth(1).kind == TokenKind::Ident {
            self.bump();
            self.name_list("the name of an interface it extends")
        } else {
            Vec::new()
        };
        let (mut methods, mut properties) = (Vec::new(), Vec::new());
        loop {
            self.members(&mut methods, &mut properties);
            if self.at(TokenKind::Eof) || self.at_kw("END_INTERFACE") || self.at_any_kw(TOP_LEVEL) {
                break;
            }
            self.error_here("expected METHOD, PROPERTY or END_INTERFACE (an interface holds prototypes only)");
            self.bump();
            self.recover_to(&["METHOD", "PROPERTY", "END_INTERFACE"], false);
        }
        self.expect_end("END_INTERFACE", self.span_of(kw));
        Interface { name, attributes, extends, methods, properties, span: self.span_from(start) }
    }
}
