//! Declarations: variable blocks, declarations, direct addresses, type declarations, type
//! specifications and initial values.

use super::*;

impl Parser<'_> {
    pub(super) fn var_block(&mut self) -> VarBlock {
        let kw = self.bump();
        let start = kw.start;
        let kwtext = self.text_of(kw).to_ascii_uppercase();
        let kind = VAR_KEYWORDS.iter().find(|v| v.0 == kwtext).map(|v| v.1).unwrap_or(VarKind::Var);
        let mut constant = false;
        let mut retain = None;
        let mut persistent = false;
        loop {
            if self.eat_kw("CONSTANT") {
                constant = true;
            } else if self.eat_kw("RETAIN") {
                retain = Some(Retain::Retain);
            } else if self.eat_kw("NON_RETAIN") {
                retain = Some(Retain::NonRetain);
            } else if self.at_kw("PERSISTENT")
                && !matches!(self.nth(1).kind, TokenKind::Colon | TokenKind::Comma)
                && !self.is_kw_tok(self.nth(1), "AT")
            {
                // Not an IEC keyword (CODESYS, TwinCAT): a variable of that name stays one.
                self.bump();
                persistent = true;
            } else {
                break;
            }
        }
        let mut decls = Vec::new();
        while !self.at(TokenKind::Eof) && !self.at_kw("END_VAR") {
            if self.at_any_kw(STOPPERS) {
                break;
            }
            // A declaration is `name ,` / `name :` / `name AT`: anything else after a name may be
            // a misspelled `END_VAR`.
            if !matches!(self.nth(1).kind, TokenKind::Comma | TokenKind::Colon)
                && !self.is_kw_tok(self.nth(1), "AT")
                && self.fix_keyword_typo(&["END_VAR"])
            {
                continue;
            }
            let before = self.pos;
            if let Some(d) = self.var_decl(kind == VarKind::Access) {
                decls.push(d);
            }
            if self.pos == before {
                self.bump();
            }
        }
        self.expect_end("END_VAR", self.span_of(kw));
        VarBlock { kind, constant, retain, persistent, decls, span: self.span_from(start) }
    }

    pub(super) fn var_decl(&mut self, access: bool) -> Option<VarDecl> {
        let start = self.tok().start;
        let attributes = self.take_attrs(start);
        let mut names = Vec::new();
        let mut location = None;
        if !self.at_kw("AT") {
            loop {
                match self.expect_ident("a variable name") {
                    Some(id) => names.push(id),
                    None => {
                        self.recover_to(&["END_VAR"], true);
                        return None;
                    }
                }
                if !self.eat(TokenKind::Comma) {
                    break;
                }
            }
        }
        if self.eat_kw("AT") {
            if self.at(TokenKind::Address) {
                let t = self.bump();
                location = Some(self.address(t));
            } else {
                self.error_here("expected a direct address such as `%IX0.0` after AT");
            }
        }
        if !self.expect(TokenKind::Colon, "`:` and a type") {
            self.recover_to(&["END_VAR"], true);
            return None;
        }
        let mut access_path = None;
        if access {
            // `name : path : type [READ_WRITE];`
            // Rebuilt from the tokens, so comments and spaces inside the path are not part of it.
            let mut path = String::new();
            while !self.at(TokenKind::Colon)
                && !self.at(TokenKind::Semi)
                && !self.at(TokenKind::Eof)
                && !self.at_kw("END_VAR")
            {
                let t = self.bump();
                path.push_str(self.text_of(t));
            }
            access_path = Some(path);
            self.expect(TokenKind::Colon, "`:` and the type of the access path");
        }
        let ty = self.type_spec();
        let mut access_mode = None;
        if access && (self.at_kw("READ_WRITE") || self.at_kw("READ_ONLY")) {
            let t = self.bump();
            access_mode = Some(self.text_of(t).to_ascii_uppercase());
        }
        // `Start : BOOL R_EDGE;` (IEC 61131-3: an edge-triggered input).
        let edge = if self.at_kw("R_EDGE") || self.at_kw("F_EDGE") {
            let t = self.bump();
            Some(if self.is_kw_tok(t, "R_EDGE") { Edge::Rising } else { Edge::Falling })
        } else {
            None
        };
        let init = if self.eat(TokenKind::Assign) { Some(self.initializer()) } else { None };
        if !self.expect(TokenKind::Semi, "`;` after the declaration") {
            self.recover_to(&["END_VAR"], true);
        }
        Some(VarDecl {
            names,
            location,
            access_path,
            access_mode,
            ty,
            init,
            edge,
            attributes,
            span: self.span_from(start),
        })
    }

    pub(super) fn address(&mut self, t: Tok) -> DirectAddress {
        let text = self.text_of(t);
        let span = self.span_of(t);
        let upper = text.to_ascii_uppercase();
        let bytes = upper.as_bytes();
        let bad = |p: &mut Self, why: &str| {
            p.diags.push(Diagnostic::error("SFC0009", span, format!("invalid direct address `{text}`: {why}")));
        };
        let area = bytes.get(1).copied().unwrap_or(b'?') as char;
        let mut i = 2;
        let mut size = 'X';
        let mut size_written = false;
        if !matches!(area, 'I' | 'Q' | 'M') {
            bad(self, "the location prefix is I, Q or M");
            return DirectAddress { area: 'I', size, size_written, path: vec![], text: text.into(), span };
        }
        if let Some(&c) = bytes.get(2) {
            if matches!(c, b'X' | b'B' | b'W' | b'D' | b'L') {
                size = c as char;
                size_written = true;
                i = 3;
            }
        }
        let rest = &upper[i.min(upper.len())..];
        let mut path = Vec::new();
        if rest == "*" {
            return DirectAddress { area, size, size_written, path, text: text.into(), span };
        }
        for part in rest.split('.') {
            match part.parse::<u32>() {
                Ok(n) if !part.is_empty() && part.chars().all(|c| c.is_ascii_digit()) => path.push(n),
                _ => {
                    bad(self, "the size prefix is X, B, W, D or L, followed by unsigned integers separated by dots");
                    return DirectAddress { area, size, size_written, path: vec![], text: text.into(), span };
                }
            }
        }
        DirectAddress { area, size, size_written, path, text: text.into(), span }
    }

    pub(super) fn type_block(&mut self) -> TypeBlock {
        let kw = self.bump();
        let start = kw.start;
        let mut decls = Vec::new();
        while !self.at(TokenKind::Eof) && !self.at_kw("END_TYPE") {
            if self.at_any_kw(&["PROGRAM", "FUNCTION", "FUNCTION_BLOCK", "TYPE", "CONFIGURATION"]) {
                break;
            }
            let dstart = self.tok().start;
            let Some(name) = self.expect_ident("a type name") else {
                self.bump();
                self.recover_to(&["END_TYPE"], true);
                continue;
            };
            if !self.expect(TokenKind::Colon, "`:` after the type name") {
                self.recover_to(&["END_TYPE"], true);
                continue;
            }
            let spec = self.type_spec();
            let init = if self.eat(TokenKind::Assign) { Some(self.initializer()) } else { None };
            if !self.expect(TokenKind::Semi, "`;` after the type declaration") {
                self.recover_to(&["END_TYPE"], true);
            }
            decls.push(TypeDecl { name, spec, init, span: self.span_from(dstart) });
        }
        self.expect_end("END_TYPE", self.span_of(kw));
        TypeBlock { decls, span: self.span_from(start) }
    }

    pub(super) fn type_spec(&mut self) -> TypeSpec {
        let start = self.tok().start;
        if !self.enter() {
            self.skip_nested();
            return TypeSpec { kind: TypeSpecKind::Error, span: self.span_from(start) };
        }
        let t = self.type_spec_inner(start);
        self.leave();
        t
    }

    pub(super) fn type_spec_inner(&mut self, start: u32) -> TypeSpec {
        let kind = if self.at_kw("ARRAY") {
            self.bump();
            let mut ranges = Vec::new();
            while self.at(TokenKind::LBracket) {
                self.bump();
                loop {
                    let lo = self.expr();
                    self.expect(TokenKind::DotDot, "`..` in the array range");
                    let hi = self.expr();
                    ranges.push((lo, hi));
                    if !self.eat(TokenKind::Comma) {
                        break;
                    }
                }
                self.expect(TokenKind::RBracket, "`]`");
            }
            if ranges.is_empty() {
                self.error_here("expected `[` and the array bounds");
            }
            if !self.eat_kw("OF") {
                self.error_here("expected OF and the element type");
            }
            let element = Box::new(self.type_spec());
            TypeSpecKind::Array { ranges, element }
        } else if self.at_kw("STRING") || self.at_kw("WSTRING") {
            let wide = self.at_kw("WSTRING");
            self.bump();
            let length = if self.at(TokenKind::LBracket) || self.at(TokenKind::LParen) {
                let close = if self.at(TokenKind::LBracket) { TokenKind::RBracket } else { TokenKind::RParen };
                self.bump();
                let e = self.expr();
                self.expect(close, "the closing bracket of the string length");
                Some(Box::new(e))
            } else {
                None
            };
            TypeSpecKind::String { wide, length }
        } else if self.at_kw("STRUCT") {
            let kw = self.bump();
            let mut fields = Vec::new();
            while !self.at(TokenKind::Eof) && !self.at_kw("END_STRUCT") {
                if self.at_any_kw(&["END_TYPE", "END_VAR"]) {
                    break;
                }
                let before = self.pos;
                if let Some(d) = self.var_decl(false) {
                    fields.push(d);
                }
                if self.pos == before {
                    self.bump();
                }
            }
            self.expect_end("END_STRUCT", self.span_of(kw));
            TypeSpecKind::Struct(fields)
        } else if let Some(kind) = self.indirection() {
            TypeSpecKind::Indirect { kind, target: Box::new(self.type_spec()) }
        } else if self.at(TokenKind::LParen) {
            TypeSpecKind::Enum { base: None, values: self.enum_values() }
        } else if self.at(TokenKind::Ident) && !self.is_reserved(self.tok()) {
            let t = self.bump();
            let id = self.ident_of(t);
            if self.at(TokenKind::LParen) {
                // `INT (0..100)` or `INT (A := 1, B := 2)`
                let a = self.nth(1);
                let b = self.nth(2);
                let is_enum = a.kind == TokenKind::Ident
                    && matches!(b.kind, TokenKind::Comma | TokenKind::RParen | TokenKind::Assign);
                if is_enum {
                    TypeSpecKind::Enum { base: Some(id), values: self.enum_values() }
                } else {
                    self.bump();
                    let low = Box::new(self.expr());
                    self.expect(TokenKind::DotDot, "`..` in the subrange");
                    let high = Box::new(self.expr());
                    self.expect(TokenKind::RParen, "`)` after the subrange");
                    TypeSpecKind::Subrange { base: id, low, high }
                }
            } else {
                TypeSpecKind::Named(id)
            }
        } else {
            self.error_here("expected a type");
            TypeSpecKind::Error
        };
        TypeSpec { kind, span: self.span_from(start) }
    }

    pub(super) fn enum_values(&mut self) -> Vec<(Ident, Option<Expr>)> {
        self.bump(); // (
        let mut values = Vec::new();
        loop {
            let Some(id) = self.expect_ident("an enumerated value") else { break };
            let v = if self.eat(TokenKind::Assign) { Some(self.expr()) } else { None };
            values.push((id, v));
            if !self.eat(TokenKind::Comma) {
                break;
            }
        }
        self.expect(TokenKind::RParen, "`)` after the enumerated values");
        values
    }

    pub(super) fn initializer(&mut self) -> Initializer {
        if !self.enter() {
            return Initializer::Expr(self.skip_nested());
        }
        let r = self.initializer_inner();
        self.leave();
        r
    }

    pub(super) fn initializer_inner(&mut self) -> Initializer {
        let start = self.tok().start;
        if self.at(TokenKind::LBracket) {
            self.bump();
            let mut elements = Vec::new();
            if !self.at(TokenKind::RBracket) {
                loop {
                    let estart = self.tok().start;
                    if self.at(TokenKind::Int) && self.nth(1).kind == TokenKind::LParen {
                        let repeat = Some(self.expr_primary_literal());
                        self.bump(); // (
                        let value = if self.at(TokenKind::RParen) { None } else { Some(self.initializer()) };
                        self.expect(TokenKind::RParen, "`)` after the repeated value");
                        elements.push(ArrayInitElement { repeat, value, span: self.span_from(estart) });
                    } else {
                        let value = Some(self.initializer());
                        elements.push(ArrayInitElement { repeat: None, value, span: self.span_from(estart) });
                    }
                    if !self.eat(TokenKind::Comma) {
                        break;
                    }
                }
            }
            self.expect(TokenKind::RBracket, "`]` after the array initialiser");
            return Initializer::Array { elements, span: self.span_from(start) };
        }
        if self.at(TokenKind::LParen) && self.nth(1).kind == TokenKind::Ident && self.nth(2).kind == TokenKind::Assign {
            self.bump();
            let mut fields = Vec::new();
            loop {
                let Some(name) = self.expect_ident("a field name") else { break };
                self.expect(TokenKind::Assign, "`:=`");
                let v = self.initializer();
                fields.push((name, v));
                if !self.eat(TokenKind::Comma) {
                    break;
                }
            }
            self.expect(TokenKind::RParen, "`)` after the structure initialiser");
            return Initializer::Struct { fields, span: self.span_from(start) };
        }
        Initializer::Expr(self.expr())
    }

    pub(super) fn expr_primary_literal(&mut self) -> Expr {
        let t = self.bump();
        self.literal_expr(t)
    }

    /// `POINTER TO`, `REFERENCE TO` or `REF_TO` at the current position, consumed.
    fn indirection(&mut self) -> Option<Indirection> {
        let kind = if self.at_kw("REF_TO") {
            self.bump();
            return Some(Indirection::RefTo);
        } else if self.at_kw("POINTER") {
            Indirection::Pointer
        } else if self.at_kw("REFERENCE") {
            Indirection::Reference
        } else {
            return None;
        };
        if !self.is_kw_tok(self.nth(1), "TO") {
            return None;
        }
        self.bump();
        self.bump();
        Some(kind)
    }
}
