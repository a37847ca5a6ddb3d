//! Instruction List bodies.

use super::*;

impl Parser<'_> {
    pub(super) fn il_body(&mut self, ends: &[&str]) -> IlBody {
        let start = self.tok().start;
        let instructions = self.il_list(ends, false);
        IlBody { instructions, span: self.span_from(start) }
    }

    pub(super) fn il_list(&mut self, ends: &[&str], nested: bool) -> Vec<IlInstruction> {
        let mut out = Vec::new();
        loop {
            if self.at(TokenKind::Eof) || self.at_any_kw(ends) || self.at_any_kw(STOPPERS) {
                break;
            }
            if nested && self.at(TokenKind::RParen) {
                break;
            }
            if self.eat(TokenKind::Semi) {
                continue;
            }
            let before = self.pos;
            if let Some(i) = self.il_instruction(ends) {
                out.push(i);
            }
            if self.pos == before {
                self.bump();
            }
        }
        out
    }

    pub(super) fn il_instruction(&mut self, ends: &[&str]) -> Option<IlInstruction> {
        let start = self.tok().start;
        let mut label = None;
        if self.at(TokenKind::Ident) && self.nth(1).kind == TokenKind::Colon {
            let t = self.bump();
            label = Some(self.ident_of(t));
            self.bump();
            if self.tok().nl_before || self.at_any_kw(ends) || self.at(TokenKind::Eof) {
                return Some(IlInstruction {
                    label,
                    op: None,
                    operands: vec![],
                    nested: None,
                    call_args: None,
                    span: self.span_from(start),
                });
            }
        }
        let op_tok = match self.kind() {
            TokenKind::Ident => self.bump(),
            TokenKind::Amp => self.bump(),
            _ => {
                self.error_here("expected an IL operator");
                self.skip_line();
                return None;
            }
        };
        let op = Ident::new(self.text_of(op_tok), self.span_of(op_tok));
        let upper = op.text.to_ascii_uppercase();
        let mut operands = Vec::new();
        let mut nested = None;
        let mut call_args = None;
        if self.at(TokenKind::LParen) && !self.tok().nl_before {
            self.bump();
            if !self.enter() {
                self.skip_nested();
                return None;
            }
            // `AND( operand` on the same line loads the operand first.
            if !self.tok().nl_before && !self.at(TokenKind::RParen) {
                operands.push(self.unary());
            }
            let inner = self.il_list(ends, true);
            self.leave();
            self.expect(TokenKind::RParen, "`)` closing the nested IL expression");
            nested = Some(inner);
        } else if upper.starts_with("CAL") {
            if let Some(id) = self.expect_ident("a function block instance after CAL") {
                let span = id.span;
                operands.push(Expr { kind: ExprKind::Name(id), span });
            }
            if self.at(TokenKind::LParen) {
                call_args = Some(self.call_args());
            }
        } else {
            while !self.tok().nl_before
                && !self.at(TokenKind::Eof)
                && !self.at(TokenKind::Semi)
                && !self.at(TokenKind::RParen)
                && !self.at_any_kw(ends)
            {
                operands.push(self.unary());
                if !self.eat(TokenKind::Comma) {
                    break;
                }
            }
        }
        if !self.tok().nl_before
            && !self.at(TokenKind::Eof)
            && !self.at(TokenKind::Semi)
            && !self.at(TokenKind::RParen)
            && !self.at_any_kw(ends)
        {
            self.error_here("expected the end of the IL instruction (one instruction per line)");
            self.skip_line();
        }
        self.eat(TokenKind::Semi);
        Some(IlInstruction { label, op: Some(op), operands, nested, call_args, span: self.span_from(start) })
    }

    pub(super) fn skip_line(&mut self) {
        while !self.at(TokenKind::Eof) && !self.tok().nl_before {
            self.bump();
        }
    }
}
