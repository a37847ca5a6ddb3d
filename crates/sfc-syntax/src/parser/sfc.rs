//! SFC elements: steps (with their step actions and action associations), transitions,
//! actions, and the charts written inside actions.

use super::*;

impl Parser<'_> {
    pub(super) fn sfc_elements(&mut self, end_kw: &str) -> Vec<SfcElement> {
        let mut elements = Vec::new();
        while !self.at(TokenKind::Eof) && !self.at_kw(end_kw) {
            if self.at_kw("STEP") || self.at_kw("INITIAL_STEP") {
                elements.push(SfcElement::Step(self.step()));
            } else if self.at_kw("TRANSITION") {
                elements.push(SfcElement::Transition(self.transition()));
            } else if self.at_kw("ACTION") {
                elements.push(SfcElement::Action(self.action()));
            } else if self.at_member_start()
                || self.at_any_kw(&[
                    "PROGRAM",
                    "FUNCTION",
                    "FUNCTION_BLOCK",
                    "TYPE",
                    "CONFIGURATION",
                    "END_PROGRAM",
                    "END_FUNCTION",
                    "END_FUNCTION_BLOCK",
                ])
            {
                break;
            } else if (self.nth(1).kind == TokenKind::Ident
                && self.fix_keyword_typo(&["STEP", "INITIAL_STEP", "TRANSITION", "ACTION"]))
                || self.fix_keyword_typo(&["END_PROGRAM", "END_FUNCTION", "END_FUNCTION_BLOCK"])
            {
                continue;
            } else {
                self.error_here("expected STEP, INITIAL_STEP, TRANSITION or ACTION");
                self.bump();
                self.recover_to(
                    &["STEP", "INITIAL_STEP", "TRANSITION", "ACTION", end_kw, "PROGRAM", "FUNCTION", "FUNCTION_BLOCK"],
                    false,
                );
            }
            let end = self.prev_end();
            self.drop_attrs_before(end);
        }
        elements
    }

    /// The elements of an action written in SFC. Its associations name the POU's actions, so an
    /// ACTION inside it is reported and skipped.
    pub(super) fn action_chart(&mut self) -> Vec<SfcElement> {
        let mut elements = Vec::new();
        while !self.at(TokenKind::Eof) && !self.at_kw("END_ACTION") {
            if self.at_kw("STEP") || self.at_kw("INITIAL_STEP") {
                elements.push(SfcElement::Step(self.step()));
            } else if self.at_kw("TRANSITION") {
                elements.push(SfcElement::Transition(self.transition()));
            } else if self.at_any_kw(&["ACTION", "END_PROGRAM", "END_FUNCTION_BLOCK", "PROGRAM", "FUNCTION_BLOCK"]) {
                // END_ACTION is missing: `expect_end` reports it.
                break;
            } else {
                self.error_here("expected STEP, INITIAL_STEP, TRANSITION or END_ACTION in an action written in SFC");
                self.bump();
                self.recover_to(&["STEP", "INITIAL_STEP", "TRANSITION", "END_ACTION", "ACTION"], false);
            }
            let end = self.prev_end();
            self.drop_attrs_before(end);
        }
        elements
    }

    pub(super) fn step(&mut self) -> Step {
        let kw = self.bump();
        let start = kw.start;
        let attributes = self.take_attrs(start);
        let initial = self.text_of(kw).eq_ignore_ascii_case("INITIAL_STEP");
        let name = self.expect_ident("a step name").unwrap_or_else(|| Ident::new("", self.cur_span()));
        self.expect(TokenKind::Colon, "`:` after the step name");
        let mut associations = Vec::new();
        let mut step_actions = Vec::new();
        while !self.at(TokenKind::Eof) && !self.at_kw("END_STEP") {
            if self.at_any_kw(STOPPERS) {
                break;
            }
            // `ENTRY_ACTION := A;` (the words are no keywords: only so before `:=`).
            if self.nth(1).kind == TokenKind::Assign {
                if let Some(kind) = StepActionKind::from_keyword(self.text_of(self.tok())) {
                    step_actions.push(self.step_action(kind));
                    continue;
                }
            }
            // An association is `Name(…)`: anything else here may be a misspelled `END_STEP`.
            if self.nth(1).kind != TokenKind::LParen && self.fix_keyword_typo(&["END_STEP"]) {
                continue;
            }
            let before = self.pos;
            if let Some(a) = self.association() {
                associations.push(a);
            }
            if self.pos == before {
                self.bump();
            }
        }
        self.expect_end("END_STEP", self.span_of(kw));
        let conditions = attributes
            .iter()
            .filter(|a| crate::ast::STEP_CONDITIONS.iter().any(|n| a.name.eq_ignore_ascii_case(n)))
            .map(|a| crate::ast::StepCondition { attribute: a.name.clone(), expr: self.attribute_expr(a) })
            .collect();
        Step { initial, name, associations, step_actions, attributes, conditions, span: self.span_from(start) }
    }

    /// `ENTRY_ACTION := Name;` or `… := instance.Action;` (the current token is the word).
    pub(super) fn step_action(&mut self, kind: StepActionKind) -> StepAction {
        let start = self.bump().start;
        self.bump(); // `:=`
        let first = self.expect_ident("an action name").unwrap_or_else(|| Ident::new("", self.cur_span()));
        let mut action = Expr { span: first.span, kind: ExprKind::Name(first) };
        while self.at(TokenKind::Dot) {
            self.bump();
            let Some(member) = self.expect_ident("an action name after `.`") else { break };
            let span = Span::new(action.span.file, action.span.start, member.span.end);
            action = Expr { kind: ExprKind::Member { base: Box::new(action), member }, span };
        }
        if !self.expect(TokenKind::Semi, &format!("`;` after the {} action", kind.word())) {
            self.recover_to(&["END_STEP"], true);
        }
        StepAction { kind, action, span: self.span_from(start) }
    }

    pub(super) fn association(&mut self) -> Option<ActionAssociation> {
        let start = self.tok().start;
        // `Motor.Stop(S);`: an action of an instance (CODESYS), as a qualified name.
        let action = match self.qualified_name("an action name") {
            Some(a) => a,
            None => {
                self.recover_to(&["END_STEP"], true);
                return None;
            }
        };
        let mut qualifier = None;
        let mut duration = None;
        let mut indicators = Vec::new();
        if self.eat(TokenKind::LParen) {
            if self.at(TokenKind::Ident) {
                let t = self.bump();
                qualifier = Some(Ident::new(self.text_of(t), self.span_of(t)));
            }
            let timed =
                qualifier.as_ref().map(|q| ["L", "D", "SD", "DS", "SL"].iter().any(|k| q.is(k))).unwrap_or(false);
            let mut first = true;
            while self.eat(TokenKind::Comma) {
                let t = self.tok();
                let is_duration_lit = t.kind == TokenKind::Typed && {
                    let p = self.text_of(t).split('#').next().unwrap_or("").to_ascii_uppercase();
                    matches!(p.as_str(), "T" | "TIME" | "LT" | "LTIME")
                };
                if first && (timed || is_duration_lit) {
                    duration = Some(self.expr());
                } else if let Some(id) = self.expect_ident("an indicator variable") {
                    indicators.push(id);
                } else {
                    break;
                }
                first = false;
            }
            if !self.expect(TokenKind::RParen, "`)` after the action qualifier") {
                self.recover_to(&["END_STEP"], true);
                return Some(ActionAssociation {
                    action,
                    qualifier,
                    duration,
                    indicators,
                    span: self.span_from(start),
                });
            }
        } else {
            self.error_here("expected `(` and an action qualifier, e.g. `(N)`");
        }
        if !self.expect(TokenKind::Semi, "`;` after the action association") {
            self.recover_to(&["END_STEP"], true);
        }
        Some(ActionAssociation { action, qualifier, duration, indicators, span: self.span_from(start) })
    }

    pub(super) fn step_list(&mut self) -> (Vec<Ident>, bool) {
        let mut steps = Vec::new();
        if self.eat(TokenKind::LParen) {
            loop {
                match self.expect_ident("a step name") {
                    Some(s) => steps.push(s),
                    None => break,
                }
                if !self.eat(TokenKind::Comma) {
                    break;
                }
            }
            self.expect(TokenKind::RParen, "`)` after the step list");
            (steps, true)
        } else {
            if let Some(s) = self.expect_ident("a step name") {
                steps.push(s);
            }
            (steps, false)
        }
    }

    pub(super) fn transition(&mut self) -> Transition {
        let kw = self.bump();
        let start = kw.start;
        let attributes = self.take_attrs(start);
        let mut name = None;
        if self.at(TokenKind::Ident) && !self.at_kw("FROM") && !self.is_reserved(self.tok()) {
            let t = self.bump();
            name = Some(self.ident_of(t));
        }
        let mut priority = None;
        if self.at(TokenKind::LParen) {
            self.bump();
            if !self.eat_kw("PRIORITY") {
                self.error_here("expected PRIORITY");
            }
            self.expect(TokenKind::Assign, "`:=`");
            priority = Some(Box::new(self.expr()));
            self.expect(TokenKind::RParen, "`)` after the priority");
        }
        let (mut from, mut from_parens, mut to, mut to_parens) = (Vec::new(), false, Vec::new(), false);
        if self.eat_kw("FROM") {
            (from, from_parens) = self.step_list();
        } else {
            self.error_here("expected FROM and the preceding step(s)");
        }
        if self.eat_kw("TO") {
            (to, to_parens) = self.step_list();
        } else {
            self.error_here("expected TO and the following step(s)");
        }
        let condition = if self.eat(TokenKind::Assign) {
            let e = self.expr();
            self.expect(TokenKind::Semi, "`;` after the transition condition");
            Condition::St(e)
        } else if self.eat(TokenKind::Colon) {
            Condition::Il(self.il_body(&["END_TRANSITION"]))
        } else {
            let t = self.tok();
            let span = self.span_of(t);
            if self.last_error_at != Some(self.pos) {
                self.last_error_at = Some(self.pos);
                self.diags.push(Diagnostic::error(
                    "SFC0217",
                    span,
                    format!(
                        "expected the transition condition (`:= expression;` or `:` and IL), found {}",
                        self.describe(t)
                    ),
                ));
            }
            self.recover_to(&["END_TRANSITION", "STEP", "INITIAL_STEP", "TRANSITION", "ACTION"], false);
            Condition::Missing
        };
        self.expect_end("END_TRANSITION", self.span_of(kw));
        Transition {
            name,
            priority,
            from,
            from_parens,
            to,
            to_parens,
            condition,
            attributes,
            span: self.span_from(start),
        }
    }

    pub(super) fn action(&mut self) -> Action {
        let kw = self.bump();
        let start = kw.start;
        let attributes = self.take_attrs(start);
        let name = self.expect_ident("an action name").unwrap_or_else(|| Ident::new("", self.cur_span()));
        if !self.eat(TokenKind::Colon) {
            self.error_here(&format!("expected `:` after the action name `{}`", name.text));
            if let Some(d) = self.diags.last_mut().filter(|d| d.code == "SFC0101") {
                d.notes.push(format!("IEC 61131-3 writes `ACTION {}: … END_ACTION`", name.text));
            }
        }
        let body = if self.at_any_kw(&["STEP", "INITIAL_STEP", "TRANSITION"]) {
            // An action written in SFC: steps and transitions up to END_ACTION.
            ActionBody::Sfc(self.action_chart())
        } else if self.looks_like_il() {
            ActionBody::Il(self.il_body(&["END_ACTION"]))
        } else {
            ActionBody::St(self.stmt_list(&["END_ACTION"]))
        };
        self.expect_end("END_ACTION", self.span_of(kw));
        Action { name, body, attributes, span: self.span_from(start) }
    }
}
