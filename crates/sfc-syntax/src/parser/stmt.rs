//! Structured Text statements, with the nesting budget shared with expressions.

use super::*;

impl Parser<'_> {
    /// Statements until a stopper keyword, `extra` stoppers, or end of file.
    pub(super) fn stmt_list(&mut self, extra: &[&str]) -> Vec<Stmt> {
        self.stmts_until(|p| p.at_any_kw(extra))
    }

    /// Statements until a stopper keyword, end of file, or where `stop` says.
    pub(super) fn stmts_until(&mut self, stop: impl Fn(&Self) -> bool) -> Vec<Stmt> {
        let mut out = Vec::new();
        loop {
            if self.at(TokenKind::Eof) || self.at_any_kw(STOPPERS) || self.at_member_start() || stop(self) {
                break;
            }
            // A statement starts with a name followed by `:=`, `(`, `.` or `[`: a name
            // followed by anything else may be a misspelled keyword (`END_ACTON`, `ELSEIF`).
            if !matches!(self.nth(1).kind, TokenKind::Assign | TokenKind::LParen | TokenKind::Dot | TokenKind::LBracket)
                && self.fix_keyword_typo(STATEMENT_KEYWORDS)
            {
                continue;
            }
            let before = self.pos;
            if let Some(s) = self.stmt() {
                out.push(s);
            }
            if self.pos == before {
                self.bump();
            }
        }
        out
    }

    pub(super) fn enter(&mut self) -> bool {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            if !self.depth_reported {
                self.depth_reported = true;
                let span = self.cur_span();
                self.diags.push(Diagnostic::error(
                    "SFC0103",
                    span,
                    format!(
                        "nesting too deep (at most {MAX_DEPTH} levels of expressions, {MAX_STMT_DEPTH} of statements): \
split it with intermediate variables"
                    ),
                ));
            }
            self.depth -= 1;
            return false;
        }
        true
    }
    pub(super) fn leave(&mut self) {
        self.depth -= 1;
    }

    /// Whether a chain of `chain` links at the current depth exceeds the budget (reported once).
    pub(super) fn chain_too_deep(&mut self, chain: u32) -> bool {
        if self.depth + chain <= MAX_DEPTH {
            return false;
        }
        self.depth += chain;
        self.enter();
        self.depth -= chain;
        true
    }

    /// Skips a too-deeply nested construct without recursion, returning an error expression.
    pub(super) fn skip_nested(&mut self) -> Expr {
        let start = self.tok().start;
        let mut level = 0i64;
        while !self.at(TokenKind::Eof) {
            match self.kind() {
                TokenKind::LParen | TokenKind::LBracket => level += 1,
                TokenKind::RParen | TokenKind::RBracket => {
                    if level == 0 {
                        break;
                    }
                    level -= 1;
                }
                TokenKind::Semi if level == 0 => break,
                _ => {
                    if self.at_any_kw(STOPPERS) && level == 0 {
                        break;
                    }
                    if self.at_any_kw(&["IF", "CASE", "FOR", "WHILE", "REPEAT"]) {
                        level += 1;
                    } else if self.at_any_kw(&["END_IF", "END_CASE", "END_FOR", "END_WHILE", "END_REPEAT"]) {
                        level -= 1;
                        if level < 0 {
                            break;
                        }
                    }
                }
            }
            self.bump();
        }
        Expr { kind: ExprKind::Error, span: self.span_from(start) }
    }

    pub(super) fn stmt(&mut self) -> Option<Stmt> {
        // Statement levels use STMT_WEIGHT units of the depth budget.
        self.depth += STMT_WEIGHT - 1;
        let ok = self.enter();
        self.depth -= STMT_WEIGHT - 1;
        if !ok {
            self.skip_nested();
            self.eat(TokenKind::Semi);
            return None;
        }
        self.depth += STMT_WEIGHT - 1;
        let r = self.stmt_inner();
        self.depth -= STMT_WEIGHT - 1;
        self.leave();
        r
    }

    pub(super) fn block_end(&mut self, kw: &str, opened: Tok) {
        self.expect_end(kw, self.span_of(opened));
        self.eat(TokenKind::Semi);
    }

    pub(super) fn stmt_inner(&mut self) -> Option<Stmt> {
        let start = self.tok().start;
        let kind = if self.at(TokenKind::Semi) {
            self.bump();
            return Some(Stmt { kind: StmtKind::Empty, span: self.span_from(start) });
        } else if self.at_kw("IF") {
            let kw = self.bump();
            let mut branches = Vec::new();
            let cond = self.expr();
            self.then_kw("THEN");
            let body = self.stmt_list(&[]);
            branches.push((cond, body));
            let mut else_body = None;
            loop {
                if self.eat_kw("ELSIF") {
                    let c = self.expr();
                    self.then_kw("THEN");
                    let b = self.stmt_list(&[]);
                    branches.push((c, b));
                } else if self.eat_kw("ELSE") {
                    else_body = Some(self.stmt_list(&[]));
                    // ELSE is the last branch: a further ELSE or ELSIF is an error, not a
                    // replacement of the branch before it.
                    if self.at_kw("ELSE") || self.at_kw("ELSIF") {
                        self.error_here("expected END_IF (ELSE is the last branch of an IF)");
                    }
                    break;
                } else {
                    break;
                }
            }
            self.block_end("END_IF", kw);
            StmtKind::If { branches, else_body }
        } else if self.at_kw("CASE") {
            let kw = self.bump();
            let selector = self.expr();
            self.then_kw("OF");
            let mut arms = Vec::new();
            let mut else_body = None;
            loop {
                if self.at(TokenKind::Eof) || self.at_kw("END_CASE") || self.at_any_kw(STOPPERS) && !self.at_kw("ELSE")
                {
                    break;
                }
                if self.eat_kw("ELSE") {
                    else_body = Some(self.stmt_list(&[]));
                    break;
                }
                let astart = self.tok().start;
                let mut labels = Vec::new();
                loop {
                    let a = self.expr();
                    if self.eat(TokenKind::DotDot) {
                        let b = self.expr();
                        labels.push(CaseLabel::Range(a, b));
                    } else {
                        labels.push(CaseLabel::Value(a));
                    }
                    if !self.eat(TokenKind::Comma) {
                        break;
                    }
                }
                if !self.expect(TokenKind::Colon, "`:` after the CASE labels") {
                    self.recover_to(&["END_CASE"], true);
                    continue;
                }
                let body = self.case_body();
                arms.push(CaseArm { labels, body, span: self.span_from(astart) });
            }
            self.block_end("END_CASE", kw);
            StmtKind::Case { selector: Box::new(selector), arms, else_body }
        } else if self.at_kw("FOR") {
            let kw = self.bump();
            let var = self.expect_ident("the loop variable").unwrap_or_else(|| Ident::new("", self.cur_span()));
            self.expect(TokenKind::Assign, "`:=`");
            let from = self.expr();
            self.then_kw("TO");
            let to = self.expr();
            let by = if self.eat_kw("BY") { Some(Box::new(self.expr())) } else { None };
            self.then_kw("DO");
            let body = self.stmt_list(&[]);
            self.block_end("END_FOR", kw);
            StmtKind::For { var, from: Box::new(from), to: Box::new(to), by, body }
        } else if self.at_kw("WHILE") {
            let kw = self.bump();
            let cond = self.expr();
            self.then_kw("DO");
            let body = self.stmt_list(&[]);
            self.block_end("END_WHILE", kw);
            StmtKind::While { cond: Box::new(cond), body }
        } else if self.at_kw("REPEAT") {
            let kw = self.bump();
            let body = self.stmt_list(&[]);
            self.then_kw("UNTIL");
            let until = self.expr();
            self.block_end("END_REPEAT", kw);
            StmtKind::Repeat { body, until: Box::new(until) }
        } else if self.at_kw("EXIT") {
            self.bump();
            self.expect(TokenKind::Semi, "`;` after EXIT");
            StmtKind::Exit
        } else if self.at_kw("RETURN") {
            self.bump();
            self.expect(TokenKind::Semi, "`;` after RETURN");
            StmtKind::Return
        } else if (self.at(TokenKind::Ident) && !self.is_reserved(self.tok())) || self.at(TokenKind::Address) {
            let target = self.postfix_expr();
            if self.eat(TokenKind::Assign) {
                let value = self.expr();
                if !self.expect(TokenKind::Semi, "`;` after the assignment") {
                    self.recover_stmt();
                }
                StmtKind::Assign { target: Box::new(target), value: Box::new(value) }
            } else if self.at_kw("REF") && self.nth(1).kind == TokenKind::Eq {
                // `r REF= x;` (CODESYS): `r` made to designate `x`.
                self.bump();
                self.bump();
                let value = self.expr();
                if !self.expect(TokenKind::Semi, "`;` after the assignment") {
                    self.recover_stmt();
                }
                StmtKind::RefAssign { target: Box::new(target), value: Box::new(value) }
            } else if matches!(target.kind, ExprKind::Call { .. } | ExprKind::MemberCall { .. }) {
                if !self.expect(TokenKind::Semi, "`;` after the call") {
                    self.recover_stmt();
                }
                StmtKind::Call(Box::new(target))
            } else {
                self.error_here("expected `:=` or a call");
                self.recover_stmt();
                return None;
            }
        } else {
            self.error_here("expected a statement");
            self.bump();
            self.recover_stmt();
            return None;
        };
        Some(Stmt { kind, span: self.span_from(start) })
    }

    pub(super) fn recover_stmt(&mut self) {
        self.recover_to(STOPPERS, true);
    }

    pub(super) fn then_kw(&mut self, kw: &str) {
        if !self.eat_kw(kw) {
            self.error_here(&format!("expected {kw}"));
        }
    }

    /// Statements of a CASE arm: stop where the next arm's labels begin.
    pub(super) fn case_body(&mut self) -> Vec<Stmt> {
        self.stmts_until(|p| p.at_kw("END_CASE") || p.at_case_label())
    }

    pub(super) fn at_case_label(&self) -> bool {
        let (a, b) = if self.at(TokenKind::Minus) { (self.nth(1), self.nth(2)) } else { (self.tok(), self.nth(1)) };
        matches!(a.kind, TokenKind::Int | TokenKind::Typed | TokenKind::Ident)
            && !self.is_reserved(a)
            && matches!(b.kind, TokenKind::Colon | TokenKind::Comma | TokenKind::DotDot)
    }
}
