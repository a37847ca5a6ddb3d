//! Structured Text expressions: a Pratt parser over the binary operators, then unary,
//! postfix (members, indexes, calls) and primaries.

use super::*;

impl Parser<'_> {
    pub(super) fn expr(&mut self) -> Expr {
        if !self.enter() {
            return self.skip_nested();
        }
        let e = self.expr_bp(1);
        self.leave();
        e
    }

    pub(super) fn binop(&self) -> Option<BinaryOp> {
        let t = self.tok();
        Some(match t.kind {
            TokenKind::Plus => BinaryOp::Add,
            TokenKind::Minus => BinaryOp::Sub,
            TokenKind::Star => BinaryOp::Mul,
            TokenKind::Slash => BinaryOp::Div,
            TokenKind::Power => BinaryOp::Pow,
            TokenKind::Eq => BinaryOp::Eq,
            TokenKind::Ne => BinaryOp::Ne,
            TokenKind::Lt => BinaryOp::Lt,
            TokenKind::Gt => BinaryOp::Gt,
            TokenKind::Le => BinaryOp::Le,
            TokenKind::Ge => BinaryOp::Ge,
            TokenKind::Amp => BinaryOp::And,
            TokenKind::Ident => match self.text_of(t).to_ascii_uppercase().as_str() {
                "AND" => BinaryOp::And,
                "AND_THEN" => BinaryOp::AndThen,
                "OR" => BinaryOp::Or,
                "OR_ELSE" => BinaryOp::OrElse,
                "XOR" => BinaryOp::Xor,
                "MOD" => BinaryOp::Mod,
                _ => return None,
            },
            _ => return None,
        })
    }

    /// Pratt loop; left-associative binary operators of precedence ≥ `min`. The depth counter
    /// also bounds long operator chains' recursion through `unary`.
    pub(super) fn expr_bp(&mut self, min: u8) -> Expr {
        let mut lhs = self.unary();
        // A chain `a + b + c …` builds a left spine as deep as it is long, and every later pass
        // (printer, checker, drop) recurses along it: it counts against the depth budget too.
        let mut chain = 0;
        while let Some(op) = self.binop() {
            let prec = op.precedence();
            if prec < min {
                break;
            }
            chain += 1;
            if self.chain_too_deep(chain) {
                let rest = self.skip_nested();
                let span = lhs.span.to(rest.span);
                return Expr { kind: ExprKind::Error, span };
            }
            self.bump();
            let rhs = if self.enter() {
                let r = self.expr_bp(prec + 1);
                self.leave();
                r
            } else {
                self.skip_nested()
            };
            let span = lhs.span.to(rhs.span);
            lhs = Expr { kind: ExprKind::Binary { op, lhs: Box::new(lhs), rhs: Box::new(rhs) }, span };
        }
        lhs
    }

    pub(super) fn unary(&mut self) -> Expr {
        let start = self.tok().start;
        let op = match self.kind() {
            TokenKind::Minus => Some(UnaryOp::Neg),
            TokenKind::Plus => Some(UnaryOp::Plus),
            TokenKind::Ident if self.at_kw("NOT") => Some(UnaryOp::Not),
            TokenKind::Bang => Some(UnaryOp::Not),
            _ => None,
        };
        if let Some(op) = op {
            self.bump();
            if !self.enter() {
                return self.skip_nested();
            }
            let operand = self.expr_bp(UNARY_PRECEDENCE);
            self.leave();
            return Expr { kind: ExprKind::Unary { op, operand: Box::new(operand) }, span: self.span_from(start) };
        }
        self.postfix_expr()
    }

    pub(super) fn literal_expr(&mut self, t: Tok) -> Expr {
        let span = self.span_of(t);
        let text = self.text_of(t);
        let decoded: literal::Decoded = match t.kind {
            TokenKind::Int => literal::decode_int(text, span).map(|v| (LiteralKind::Int(v as i128), None)),
            TokenKind::Real => literal::decode_real(text, span).map(|v| (LiteralKind::Real(v), None)),
            TokenKind::String | TokenKind::WString => literal::decode_string(text, span)
                .map(|v| (LiteralKind::String { value: v, wide: t.kind == TokenKind::WString }, None)),
            _ => literal::decode_typed(text, span),
        };
        match decoded {
            Ok((kind, type_prefix)) => {
                Expr { kind: ExprKind::Literal(Literal { kind, type_prefix, text: text.into() }), span }
            }
            Err(d) => {
                self.diags.push(d);
                Expr { kind: ExprKind::Error, span }
            }
        }
    }

    pub(super) fn postfix_expr(&mut self) -> Expr {
        let t = self.tok();
        let start = t.start;
        let mut e = match t.kind {
            TokenKind::Int | TokenKind::Real | TokenKind::String | TokenKind::WString | TokenKind::Typed => {
                self.bump();
                return self.literal_expr(t);
            }
            TokenKind::Address => {
                self.bump();
                let a = self.address(t);
                Expr { kind: ExprKind::Address(a), span: self.span_of(t) }
            }
            TokenKind::LParen => {
                self.bump();
                let inner = self.expr();
                self.expect(TokenKind::RParen, "`)`");
                Expr { kind: ExprKind::Paren(Box::new(inner)), span: self.span_from(start) }
            }
            TokenKind::Ident if self.is_kw_tok(t, "TRUE") || self.is_kw_tok(t, "FALSE") => {
                self.bump();
                let v = self.is_kw_tok(t, "TRUE");
                let lit = Literal { kind: LiteralKind::Bool(v), type_prefix: None, text: self.text_of(t).into() };
                return Expr { kind: ExprKind::Literal(lit), span: self.span_of(t) };
            }
            // The function-call form of the extensible operators whose names are reserved words
            // (`AND(a, b, c)`, `OR`, `XOR`, `MOD(a, b)`: IEC 61131-3's standard functions, as
            // Beremiz and OpenPLC write them): a call of the standard function.
            TokenKind::Ident
                if self.at_any_kw(&["AND", "OR", "XOR", "MOD"]) && self.nth(1).kind == TokenKind::LParen =>
            {
                self.bump();
                let id = self.ident_of(t);
                let args = self.call_args();
                Expr { kind: ExprKind::Call { callee: id, args }, span: self.span_from(start) }
            }
            TokenKind::Ident if !self.is_reserved(t) => {
                self.bump();
                let id = self.ident_of(t);
                if self.at(TokenKind::LParen) {
                    let args = self.call_args();
                    Expr { kind: ExprKind::Call { callee: id, args }, span: self.span_from(start) }
                } else {
                    Expr { kind: ExprKind::Name(id), span: self.span_of(t) }
                }
            }
            _ => {
                self.error_here("expected an expression");
                let span =
                    if t.kind == TokenKind::Eof { Span::new(self.file, t.start, t.start) } else { self.span_of(t) };
                // Consume a stray operator token so recovery makes progress, but never a keyword.
                if !matches!(
                    t.kind,
                    TokenKind::Ident | TokenKind::Semi | TokenKind::Eof | TokenKind::RParen | TokenKind::RBracket
                ) {
                    self.bump();
                }
                return Expr { kind: ExprKind::Error, span };
            }
        };
        // Like operator chains, `a.b.c…` and `a[1][2]…` nest the tree one level per link.
        let mut chain = 0;
        loop {
            if self.at(TokenKind::Dot) || self.at(TokenKind::LBracket) {
                chain += 1;
                if self.chain_too_deep(chain) {
                    while self.at(TokenKind::Dot)
                        || self.at(TokenKind::LBracket)
                        || self.at(TokenKind::Ident)
                        || self.at(TokenKind::Int)
                    {
                        if self.at(TokenKind::LBracket) {
                            self.bump();
                            self.skip_nested();
                            self.eat(TokenKind::RBracket);
                        } else {
                            self.bump();
                        }
                    }
                    return Expr { kind: ExprKind::Error, span: self.span_from(start) };
                }
            }
            if self.at(TokenKind::Dot) {
                self.bump();
                let m = self.tok();
                if m.kind == TokenKind::Ident || m.kind == TokenKind::Int {
                    self.bump();
                    let member = Ident::new(self.text_of(m), self.span_of(m));
                    e = if m.kind == TokenKind::Ident && self.at(TokenKind::LParen) {
                        // `inst.Act()`: a member called (an action of an instance).
                        let args = self.call_args();
                        Expr {
                            kind: ExprKind::MemberCall { base: Box::new(e), member, args },
                            span: self.span_from(start),
                        }
                    } else {
                        Expr { kind: ExprKind::Member { base: Box::new(e), member }, span: self.span_from(start) }
                    };
                } else if m.kind == TokenKind::Address {
                    // `w.%X0`, `d.%W1`: partial access (IEC 61131-3 3rd edition), a member
                    // named by its size prefix and index.
                    self.bump();
                    let member = Ident::new(self.text_of(m), self.span_of(m));
                    e = Expr { kind: ExprKind::Member { base: Box::new(e), member }, span: self.span_from(start) };
                } else {
                    self.error_here("expected a member name after `.`");
                    break;
                }
            } else if self.at(TokenKind::LBracket) {
                self.bump();
                let mut indices = vec![self.expr()];
                while self.eat(TokenKind::Comma) {
                    indices.push(self.expr());
                }
                self.expect(TokenKind::RBracket, "`]`");
                e = Expr { kind: ExprKind::Index { base: Box::new(e), indices }, span: self.span_from(start) };
            } else if self.at(TokenKind::Caret) {
                // `p^`: what the pointer `p` points to (`THIS^`, `SUPER^`).
                self.bump();
                if matches!(&e.kind, ExprKind::Name(id) if id.is("SUPER")) && self.at(TokenKind::LParen) {
                    // `SUPER^()`: the body of the base block, called (CODESYS); the callee is
                    // named `SUPER^`.
                    let callee = Ident::new("SUPER^".to_string(), self.span_from(start));
                    let args = self.call_args();
                    e = Expr { kind: ExprKind::Call { callee, args }, span: self.span_from(start) };
                    continue;
                }
                e = Expr { kind: ExprKind::Deref(Box::new(e)), span: self.span_from(start) };
            } else {
                break;
            }
        }
        e
    }

    pub(super) fn call_args(&mut self) -> Vec<Arg> {
        self.bump(); // (
        let mut args = Vec::new();
        if self.eat(TokenKind::RParen) {
            return args;
        }
        loop {
            let astart = self.tok().start;
            let negated_out =
                self.at_kw("NOT") && self.nth(1).kind == TokenKind::Ident && self.nth(2).kind == TokenKind::Arrow;
            if negated_out {
                self.bump();
            }
            let t = self.tok();
            let n = self.nth(1);
            if t.kind == TokenKind::Ident && matches!(n.kind, TokenKind::Assign | TokenKind::Arrow) {
                self.bump();
                let name = Some(self.ident_of(t));
                let output = self.bump().kind == TokenKind::Arrow;
                let value = if output && matches!(self.kind(), TokenKind::Comma | TokenKind::RParen) {
                    None
                } else {
                    Some(self.expr())
                };
                args.push(Arg { name, output, negated: negated_out, value, span: self.span_from(astart) });
            } else {
                let v = self.expr();
                args.push(Arg {
                    name: None,
                    output: false,
                    negated: false,
                    value: Some(v),
                    span: self.span_from(astart),
                });
            }
            // A comma before `)` (CODESYS accepts it, often left by an argument commented out).
            if !self.eat(TokenKind::Comma) || self.at(TokenKind::RParen) {
                break;
            }
        }
        self.expect(TokenKind::RParen, "`)` after the arguments");
        args
    }
}
