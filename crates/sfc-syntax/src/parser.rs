//! A hand-written recursive-descent parser (Pratt for expressions) that never fails: it returns a
//! [`SourceUnit`] and every error it met, recovering at keywords so one mistake gives one
//! diagnostic. Nesting is capped at [`MAX_DEPTH`] so no input can overflow the stack.

use crate::ast::*;
use crate::lexer::{lex, Token, TokenKind};
use crate::literal;
use sfc_diagnostics::{Diagnostic, Span};

/// The deepest nesting of expressions accepted (SFC0103 beyond).
pub const MAX_DEPTH: u32 = 256;
/// The deepest nesting of statements accepted (SFC0103 beyond); a statement level costs this
/// many expression levels of the shared budget, as its parse frames are larger.
pub const MAX_STMT_DEPTH: u32 = 64;
/// Leaves a quarter of the budget for the expressions inside the innermost statement.
const STMT_WEIGHT: u32 = (MAX_DEPTH * 3 / 4) / MAX_STMT_DEPTH;

/// Words that end or start a construct and therefore never name a variable.
const RESERVED: &[&str] = &[
    "END_IF",
    "END_CASE",
    "END_FOR",
    "END_WHILE",
    "END_REPEAT",
    "END_VAR",
    "END_STEP",
    "END_TRANSITION",
    "END_ACTION",
    "END_PROGRAM",
    "END_FUNCTION",
    "END_FUNCTION_BLOCK",
    "END_TYPE",
    "END_STRUCT",
    "END_CONFIGURATION",
    "END_RESOURCE",
    "IF",
    "THEN",
    "ELSIF",
    "ELSE",
    "CASE",
    "OF",
    "FOR",
    "DO",
    "BY",
    "WHILE",
    "REPEAT",
    "UNTIL",
    "EXIT",
    "RETURN",
    "VAR",
    "VAR_INPUT",
    "VAR_OUTPUT",
    "VAR_IN_OUT",
    "VAR_GLOBAL",
    "VAR_EXTERNAL",
    "VAR_ACCESS",
    "VAR_TEMP",
    "STEP",
    "INITIAL_STEP",
    "TRANSITION",
    "ACTION",
    "PROGRAM",
    "FUNCTION",
    "FUNCTION_BLOCK",
    "TYPE",
    "STRUCT",
    "ARRAY",
    "AND",
    "OR",
    "XOR",
    "NOT",
    "MOD",
    "AND_THEN",
    "OR_ELSE",
    "CONFIGURATION",
    "RESOURCE",
];

/// Keywords a statement list may meet at the start of a statement (a misspelling of one is
/// reported as such).
const STATEMENT_KEYWORDS: &[&str] = &[
    "END_IF",
    "END_CASE",
    "END_FOR",
    "END_WHILE",
    "END_REPEAT",
    "END_STEP",
    "END_TRANSITION",
    "END_ACTION",
    "END_PROGRAM",
    "END_FUNCTION",
    "END_FUNCTION_BLOCK",
    "ELSIF",
    "ELSE",
    "UNTIL",
    "CASE",
    "WHILE",
    "REPEAT",
    "RETURN",
    "INITIAL_STEP",
    "TRANSITION",
    "ACTION",
];

/// Edit distance between a written word and a keyword (both upper case), counting a swap of
/// two neighbours as one edit (`END_STPE`); at most 3 is ever needed, so longer is 3.
fn keyword_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    if a.len().abs_diff(b.len()) > 2 {
        return 3;
    }
    let w = b.len() + 1;
    let mut d = vec![0usize; (a.len() + 1) * w];
    let at = |i: usize, j: usize| i * w + j;
    for i in 0..=a.len() {
        if let Some(c) = d.get_mut(at(i, 0)) {
            *c = i;
        }
    }
    for j in 0..=b.len() {
        if let Some(c) = d.get_mut(at(0, j)) {
            *c = j;
        }
    }
    let get = |d: &Vec<usize>, i: usize, j: usize| d.get(at(i, j)).copied().unwrap_or(usize::MAX / 2);
    for (i, ca) in a.iter().enumerate() {
        for (j, cb) in b.iter().enumerate() {
            let (i1, j1) = (i + 1, j + 1);
            let cost = usize::from(ca != cb);
            let mut best = (get(&d, i, j1) + 1).min(get(&d, i1, j) + 1).min(get(&d, i, j) + cost);
            if i > 0 && j > 0 && a.get(i - 1) == Some(cb) && b.get(j - 1) == Some(ca) {
                best = best.min(get(&d, i - 1, j - 1) + 1);
            }
            if let Some(c) = d.get_mut(at(i1, j1)) {
                *c = best;
            }
        }
    }
    get(&d, a.len(), b.len()).min(3)
}

/// Keywords at which statement and element lists stop.
const STOPPERS: &[&str] = &[
    "END_IF",
    "END_CASE",
    "END_FOR",
    "END_WHILE",
    "END_REPEAT",
    "END_STEP",
    "END_TRANSITION",
    "END_ACTION",
    "END_PROGRAM",
    "END_FUNCTION",
    "END_FUNCTION_BLOCK",
    "ELSIF",
    "ELSE",
    "UNTIL",
    "STEP",
    "INITIAL_STEP",
    "TRANSITION",
    "ACTION",
    "PROGRAM",
    "FUNCTION",
    "FUNCTION_BLOCK",
    "TYPE",
    "CONFIGURATION",
    "END_VAR",
    "VAR",
    "VAR_INPUT",
    "VAR_OUTPUT",
    "VAR_IN_OUT",
    "VAR_GLOBAL",
    "VAR_EXTERNAL",
    "VAR_ACCESS",
    "VAR_TEMP",
    "END_TYPE",
    "END_STRUCT",
];

/// IL operators that may start an instruction list body.
const IL_OPERATORS: &[&str] = &[
    "LD", "LDN", "ST", "STN", "S", "R", "AND", "ANDN", "OR", "ORN", "XOR", "XORN", "NOT", "ADD", "SUB", "MUL", "DIV",
    "MOD", "GT", "GE", "EQ", "NE", "LE", "LT", "JMP", "JMPC", "JMPCN", "CAL", "CALC", "CALCN", "RET", "RETC", "RETCN",
];

const VAR_KEYWORDS: &[(&str, VarKind)] = &[
    ("VAR", VarKind::Var),
    ("VAR_INPUT", VarKind::Input),
    ("VAR_OUTPUT", VarKind::Output),
    ("VAR_IN_OUT", VarKind::InOut),
    ("VAR_GLOBAL", VarKind::Global),
    ("VAR_EXTERNAL", VarKind::External),
    ("VAR_ACCESS", VarKind::Access),
    ("VAR_TEMP", VarKind::Temp),
];

/// Parses a whole file. `file` is the id put into every span.
pub fn parse(file: u32, text: &str) -> (SourceUnit, Vec<Diagnostic>) {
    if let Some(d) = crate::encoding::binary_error(file, text) {
        // One error, not one per stray byte of a file that was never text.
        return (SourceUnit::default(), vec![d]);
    }
    let (all, mut diags) = lex(file, text);
    let mut p = Parser::new(file, text, &all);
    drop(all); // the parser keeps only significant tokens; free the rest before building the tree
    p.lexical_error_ends = diags.iter().map(|d| d.span.end).collect();
    let unit = p.source_unit();
    if !p.verbatim_spans.is_empty() {
        let spans = std::mem::take(&mut p.verbatim_spans);
        diags.retain(|d| !spans.iter().any(|&(s, e)| s <= d.span.start && d.span.end <= e));
    }
    diags.append(&mut p.diags);
    if unit.items.is_empty() && diags.is_empty() {
        // Nothing to check is worth saying: an empty file, or one holding only comments, is
        // usually the wrong file.
        let what = if text.trim().is_empty() { "the file is empty" } else { "the file holds only comments" };
        diags.push(
            Diagnostic::warning("SFC0106", Span::new(file, 0, 0), format!("nothing to check: {what}"))
                .with_note("a chart is a PROGRAM or FUNCTION_BLOCK whose body is steps and transitions"),
        );
    }
    (unit, diags)
}

/// Parses a single expression (for the editor's condition fields and tests).
pub fn parse_expression(file: u32, text: &str) -> (Expr, Vec<Diagnostic>) {
    let (all, mut diags) = lex(file, text);
    let mut p = Parser::new(file, text, &all);
    let e = p.expr();
    if !p.at(TokenKind::Eof) {
        p.error_here("expected the end of the expression");
    }
    diags.append(&mut p.diags);
    (e, diags)
}

/// Parses a list of ST statements (an action body as typed in the editor).
pub fn parse_statements(file: u32, text: &str) -> (Vec<Stmt>, Vec<Diagnostic>) {
    let (all, mut diags) = lex(file, text);
    let mut p = Parser::new(file, text, &all);
    let mut stmts = p.stmt_list(&[]);
    while !p.at(TokenKind::Eof) {
        p.error_here("unexpected input after the statements");
        p.bump();
        stmts.extend(p.stmt_list(&[]));
    }
    diags.append(&mut p.diags);
    (stmts, diags)
}

#[derive(Clone, Copy)]
struct Tok {
    kind: TokenKind,
    start: u32,
    end: u32,
    /// A line break lies between the previous significant token and this one.
    nl_before: bool,
    /// An identifier that is a reserved keyword (or a misspelling read as one): decided once
    /// per token, since the parser asks for most identifiers several times.
    reserved: bool,
}

/// Whether `s` is one of [`RESERVED`], case-insensitively: one `match` on the upper-case
/// bytes per identifier token (the parser then asks the token, not the keyword list). A test
/// keeps the arms equal to [`RESERVED`].
fn reserved_word(s: &str) -> bool {
    const LONGEST: usize = 18;
    if s.len() > LONGEST || s.len() < 2 {
        return false;
    }
    let mut buf = [0u8; LONGEST];
    let Some(upper) = buf.get_mut(..s.len()) else { return false };
    upper.copy_from_slice(s.as_bytes());
    upper.make_ascii_uppercase();
    matches!(
        &*upper,
        b"END_IF"
            | b"END_CASE"
            | b"END_FOR"
            | b"END_WHILE"
            | b"END_REPEAT"
            | b"END_VAR"
            | b"END_STEP"
            | b"END_TRANSITION"
            | b"END_ACTION"
            | b"END_PROGRAM"
            | b"END_FUNCTION"
            | b"END_FUNCTION_BLOCK"
            | b"END_TYPE"
            | b"END_STRUCT"
            | b"END_CONFIGURATION"
            | b"END_RESOURCE"
            | b"IF"
            | b"THEN"
            | b"ELSIF"
            | b"ELSE"
            | b"CASE"
            | b"OF"
            | b"FOR"
            | b"DO"
            | b"BY"
            | b"WHILE"
            | b"REPEAT"
            | b"UNTIL"
            | b"EXIT"
            | b"RETURN"
            | b"VAR"
            | b"VAR_INPUT"
            | b"VAR_OUTPUT"
            | b"VAR_IN_OUT"
            | b"VAR_GLOBAL"
            | b"VAR_EXTERNAL"
            | b"VAR_ACCESS"
            | b"VAR_TEMP"
            | b"STEP"
            | b"INITIAL_STEP"
            | b"TRANSITION"
            | b"ACTION"
            | b"PROGRAM"
            | b"FUNCTION"
            | b"FUNCTION_BLOCK"
            | b"TYPE"
            | b"STRUCT"
            | b"ARRAY"
            | b"AND"
            | b"OR"
            | b"XOR"
            | b"NOT"
            | b"MOD"
            | b"AND_THEN"
            | b"OR_ELSE"
            | b"CONFIGURATION"
            | b"RESOURCE"
    )
}

struct Parser<'a> {
    file: u32,
    text: &'a str,
    toks: Vec<Tok>,
    pos: usize,
    trivia: Vec<Trivia>,
    blank_lines: Vec<u32>,
    attrs: Vec<Attribute>,
    attr_cursor: usize,
    diags: Vec<Diagnostic>,
    /// Token index of the last error, so one bad token yields one diagnostic.
    last_error_at: Option<usize>,
    depth: u32,
    depth_reported: bool,
    /// Ends of lexical errors: a syntax error right after a malformed token (an unterminated
    /// string swallowed its `;`) is a follow-on error and not reported.
    lexical_error_ends: std::collections::HashSet<u32>,
    /// Misspelled keywords, by token start: reported once, then read as the keyword they stand
    /// for, so one typo gives one error and no cascade.
    keyword_typos: std::collections::HashMap<u32, &'static str>,
    /// Byte ranges of the POUs kept as written (their lexical errors are dropped).
    verbatim_spans: Vec<(u32, u32)>,
}

impl<'a> Parser<'a> {
    fn new(file: u32, text: &'a str, all: &[Token]) -> Self {
        let mut toks = Vec::with_capacity(all.len() / 2 + 1);
        let mut trivia = Vec::new();
        let mut attrs = Vec::new();
        let mut blank_lines = Vec::new();
        let mut nl = false;
        let mut line_blank = true; // only white space since the last line break
        for t in all {
            let s = &text[t.start as usize..t.end as usize];
            match t.kind {
                TokenKind::Whitespace => {
                    let breaks = s.bytes().filter(|&b| b == b'\n').take(2).count();
                    if breaks > 1 {
                        blank_lines.push(t.start);
                    }
                    if breaks > 0 {
                        nl = true;
                        line_blank = true;
                    }
                }
                TokenKind::BlockComment | TokenKind::LineComment | TokenKind::Pragma => {
                    let kind = match t.kind {
                        TokenKind::BlockComment => TriviaKind::BlockComment,
                        TokenKind::LineComment => TriviaKind::LineComment,
                        _ => TriviaKind::Pragma,
                    };
                    let span = Span::new(file, t.start, t.end);
                    if kind == TriviaKind::Pragma {
                        if let Some(a) = parse_attribute(s, span) {
                            attrs.push(a);
                        }
                    }
                    let line_start = text[..t.start as usize].rfind('\n').map_or(0, |i| i + 1);
                    let column = text[line_start..t.start as usize].chars().count() as u32;
                    trivia.push(Trivia { kind, text: s.to_string(), span, own_line: line_blank, column });
                    if kind == TriviaKind::LineComment || s.contains('\n') {
                        nl = true;
                    }
                    line_blank = kind == TriviaKind::LineComment;
                }
                _ => {
                    let reserved = t.kind == TokenKind::Ident && reserved_word(s);
                    toks.push(Tok { kind: t.kind, start: t.start, end: t.end, nl_before: nl, reserved });
                    nl = false;
                    line_blank = false;
                }
            }
        }
        Parser {
            file,
            text,
            toks,
            pos: 0,
            trivia,
            blank_lines,
            attrs,
            attr_cursor: 0,
            diags: Vec::new(),
            last_error_at: None,
            depth: 0,
            depth_reported: false,
            lexical_error_ends: Default::default(),
            keyword_typos: Default::default(),
            verbatim_spans: Vec::new(),
        }
    }

    // ----------------------------------------------------------------------------------------
    // Token access

    fn tok(&self) -> Tok {
        self.nth(0)
    }
    /// The token `n` ahead; past the end, the end of file (the lexer always ends with one).
    fn nth(&self, n: usize) -> Tok {
        self.toks.get(self.pos.saturating_add(n)).or(self.toks.last()).copied().unwrap_or(Tok {
            kind: TokenKind::Eof,
            start: self.text.len() as u32,
            end: self.text.len() as u32,
            nl_before: false,
            reserved: false,
        })
    }
    fn kind(&self) -> TokenKind {
        self.tok().kind
    }
    fn at(&self, k: TokenKind) -> bool {
        self.kind() == k
    }
    fn text_of(&self, t: Tok) -> &'a str {
        // Hot (every token's text): the map of misspelt keywords is nearly always empty.
        if !self.keyword_typos.is_empty() {
            if let Some(kw) = self.keyword_typos.get(&t.start) {
                return kw;
            }
        }
        &self.text[t.start as usize..t.end as usize]
    }
    fn cur_text(&self) -> &'a str {
        self.text_of(self.tok())
    }
    fn span_of(&self, t: Tok) -> Span {
        Span::new(self.file, t.start, t.end)
    }
    fn cur_span(&self) -> Span {
        self.span_of(self.tok())
    }
    /// End of the previous significant token (for spans of finished nodes).
    fn prev_end(&self) -> u32 {
        self.pos.checked_sub(1).and_then(|p| self.toks.get(p)).map_or(0, |t| t.end)
    }
    fn span_from(&self, start: u32) -> Span {
        Span::new(self.file, start, self.prev_end().max(start))
    }
    fn bump(&mut self) -> Tok {
        let t = self.tok();
        if t.kind != TokenKind::Eof {
            self.pos += 1;
        }
        t
    }
    fn is_kw_tok(&self, t: Tok, kw: &str) -> bool {
        t.kind == TokenKind::Ident && self.text_of(t).eq_ignore_ascii_case(kw)
    }
    fn at_kw(&self, kw: &str) -> bool {
        self.is_kw_tok(self.tok(), kw)
    }
    fn at_any_kw(&self, kws: &[&str]) -> bool {
        self.tok().kind == TokenKind::Ident && kws.iter().any(|k| self.cur_text().eq_ignore_ascii_case(k))
    }
    fn eat_kw(&mut self, kw: &str) -> bool {
        if self.at_kw(kw) {
            self.bump();
            true
        } else {
            false
        }
    }
    fn eat(&mut self, k: TokenKind) -> bool {
        if self.at(k) {
            self.bump();
            true
        } else {
            false
        }
    }
    fn is_reserved(&self, t: Tok) -> bool {
        t.kind == TokenKind::Ident && t.reserved
    }

    fn describe(&self, t: Tok) -> String {
        match t.kind {
            TokenKind::Eof => "end of file".into(),
            TokenKind::Ident if self.is_reserved(t) => format!("keyword `{}`", self.text_of(t).to_ascii_uppercase()),
            TokenKind::Ident => format!("identifier `{}`", self.text_of(t)),
            _ => {
                let s: String = self.text_of(t).chars().take(30).collect();
                format!("`{s}`")
            }
        }
    }

    // ----------------------------------------------------------------------------------------
    // Errors and recovery

    fn push_error(&mut self, code: &'static str, span: Span, msg: String) {
        if self.last_error_at == Some(self.pos) || self.after_lexical_error() {
            return;
        }
        self.last_error_at = Some(self.pos);
        self.diags.push(Diagnostic::error(code, span, msg));
    }

    fn after_lexical_error(&self) -> bool {
        self.pos > 0 && self.lexical_error_ends.contains(&self.prev_end())
    }

    /// `expected X, found Y` at the current token.
    fn error_here(&mut self, expected: &str) {
        let t = self.tok();
        let msg = format!("{expected}, found {}", self.describe(t));
        let span = if t.kind == TokenKind::Eof { Span::new(self.file, t.start, t.start) } else { self.span_of(t) };
        self.push_error("SFC0101", span, msg);
    }

    fn expect(&mut self, k: TokenKind, what: &str) -> bool {
        if self.eat(k) {
            true
        } else {
            self.error_here(&format!("expected {what}"));
            false
        }
    }

    /// When the current token is an identifier that misspells one of `candidates` (`INITAL_STEP`,
    /// `END_TRANSITON`), reports it and reads it as that keyword from now on. Callers ask only
    /// where an identifier cannot stand, so a variable that looks like a keyword is left alone.
    fn fix_keyword_typo(&mut self, candidates: &[&str]) -> bool {
        let t = self.tok();
        if t.kind != TokenKind::Ident
            || self.is_reserved(t)
            || (!self.keyword_typos.is_empty() && self.keyword_typos.contains_key(&t.start))
        {
            return false;
        }
        let written = self.text_of(t).to_ascii_uppercase();
        let best = candidates
            .iter()
            .filter(|k| k.len() >= 4)
            .map(|k| (keyword_distance(&written, k), *k))
            .filter(|(d, k)| *d <= if k.len() <= 6 { 1 } else { 2 })
            .min_by_key(|(d, _)| *d);
        let Some(kw) = best.and_then(|(_, k)| RESERVED.iter().find(|r| r.eq_ignore_ascii_case(k))) else {
            return false;
        };
        let span = self.span_of(t);
        let shown = self.text_of(t).to_string();
        if !self.after_lexical_error() {
            self.last_error_at = Some(self.pos);
            self.diags.push(
                Diagnostic::error("SFC0101", span, format!("misspelled keyword `{shown}`"))
                    .with_note(format!("did you mean `{kw}`?")),
            );
        }
        self.keyword_typos.insert(t.start, kw);
        if let Some(tok) = self.toks.get_mut(self.pos) {
            tok.reserved = true;
        }
        true
    }

    /// Expects a closing keyword (SFC0102 when it is missing).
    fn expect_end(&mut self, kw: &str, opened: Span) {
        if self.eat_kw(kw) {
            return;
        }
        if self.fix_keyword_typo(&[kw]) && self.eat_kw(kw) {
            return;
        }
        let t = self.tok();
        let msg = format!("missing `{kw}`: found {}", self.describe(t));
        let span = if t.kind == TokenKind::Eof { Span::new(self.file, t.start, t.start) } else { self.span_of(t) };
        if self.last_error_at != Some(self.pos) {
            self.last_error_at = Some(self.pos);
            let line = self.line_of(opened.start);
            self.diags
                .push(Diagnostic::error("SFC0102", span, msg).with_label(opened, format!("opened here (line {line})")));
        }
    }

    fn line_of(&self, offset: u32) -> usize {
        self.text[..(offset as usize).min(self.text.len())].matches('\n').count() + 1
    }

    fn expect_ident(&mut self, what: &str) -> Option<Ident> {
        let t = self.tok();
        if t.kind == TokenKind::Ident && !self.is_reserved(t) {
            self.bump();
            Some(self.ident_of(t))
        } else {
            self.error_here(&format!("expected {what}"));
            None
        }
    }

    fn ident_of(&mut self, t: Tok) -> Ident {
        let text = self.text_of(t);
        let span = self.span_of(t);
        check_identifier(text, span, &mut self.diags);
        Ident::new(text, span)
    }

    /// Skips tokens until one of `kws` (or a statement end `;` when `semi`) at nesting level 0.
    fn recover_to(&mut self, kws: &[&str], semi: bool) {
        let mut parens = 0i32;
        while !self.at(TokenKind::Eof) {
            match self.kind() {
                TokenKind::LParen | TokenKind::LBracket => parens += 1,
                TokenKind::RParen | TokenKind::RBracket => parens -= 1,
                TokenKind::Semi if semi && parens <= 0 => {
                    self.bump();
                    return;
                }
                _ => {}
            }
            if self.at_any_kw(kws) {
                return;
            }
            self.bump();
        }
    }

    // ----------------------------------------------------------------------------------------
    // Attributes

    /// The unattached attribute pragmas that start before byte `start`.
    fn take_attrs(&mut self, start: u32) -> Vec<Attribute> {
        let mut out = Vec::new();
        while let Some(a) = self.attrs.get(self.attr_cursor).filter(|a| a.span.start < start) {
            out.push(a.clone());
            self.attr_cursor += 1;
        }
        out
    }

    /// Attribute pragmas left inside an element that just ended are misplaced.
    fn drop_attrs_before(&mut self, end: u32) {
        while let Some(a) = self.attrs.get(self.attr_cursor).filter(|a| a.span.start < end) {
            if a.name.to_ascii_lowercase().starts_with("sfc.") {
                self.diags.push(Diagnostic::warning(
                    "SFC0603",
                    a.span,
                    format!(
                        "attribute `{}` is not directly before a POU, variable, step, transition or action",
                        a.name
                    ),
                ));
            }
            self.attr_cursor += 1;
        }
    }

    // ----------------------------------------------------------------------------------------
    // Top level

    fn source_unit(&mut self) -> SourceUnit {
        let mut items = Vec::new();
        while !self.at(TokenKind::Eof) {
            if (self.at_kw("PROGRAM") || self.at_kw("FUNCTION_BLOCK") || self.at_kw("FUNCTION"))
                && self.verbatim_pou_ahead()
            {
                items.push(Item::Verbatim(self.verbatim()));
            } else if self.at_kw("PROGRAM") || self.at_kw("FUNCTION_BLOCK") || self.at_kw("FUNCTION") {
                items.push(Item::Pou(self.pou()));
            } else if self.at_kw("TYPE") {
                items.push(Item::Types(self.type_block()));
            } else if self.at_kw("VAR_GLOBAL") {
                items.push(Item::Globals(self.var_block()));
            } else if self.at_kw("CONFIGURATION") || self.at_kw("RESOURCE") {
                items.push(Item::Verbatim(self.verbatim()));
            } else if self.at_any_kw(&["STEP", "INITIAL_STEP", "TRANSITION", "ACTION"]) {
                self.error_here(
                    "expected PROGRAM, FUNCTION_BLOCK, FUNCTION or TYPE (SFC elements belong inside a POU)",
                );
                self.recover_to(
                    &["PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "TYPE", "CONFIGURATION", "VAR_GLOBAL"],
                    false,
                );
                // Skip the keyword we stopped on if it is not a top-level one.
            } else {
                self.error_here("expected PROGRAM, FUNCTION_BLOCK, FUNCTION, TYPE or CONFIGURATION");
                self.bump();
                self.recover_to(
                    &["PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "TYPE", "CONFIGURATION", "VAR_GLOBAL"],
                    false,
                );
            }
            let end = self.prev_end();
            self.drop_attrs_before(end);
        }
        SourceUnit {
            items,
            trivia: std::mem::take(&mut self.trivia),
            blank_lines: std::mem::take(&mut self.blank_lines),
            span: Span::new(self.file, 0, self.text.len() as u32),
        }
    }

    /// Whether the POU that starts here carries an `sfc.verbatim` attribute: it is kept as
    /// written (an import found code in it that is not IEC 61131-3, say CODESYS pointers).
    fn verbatim_pou_ahead(&self) -> bool {
        let start = self.tok().start;
        self.attrs
            .get(self.attr_cursor..)
            .unwrap_or_default()
            .iter()
            .take_while(|a| a.span.start < start)
            .any(|a| a.name.eq_ignore_ascii_case("sfc.verbatim"))
    }

    fn verbatim(&mut self) -> Verbatim {
        let kw_tok = self.bump();
        let keyword = self.text_of(kw_tok).to_ascii_uppercase();
        let start = kw_tok.start;
        let attributes = self.take_attrs(start);
        let pou = matches!(keyword.as_str(), "PROGRAM" | "FUNCTION_BLOCK" | "FUNCTION");
        let name = if self.at(TokenKind::Ident) && !self.is_reserved(self.tok()) {
            let t = self.bump();
            Some(self.ident_of(t))
        } else {
            None
        };
        let end_kw = format!("END_{keyword}");
        let mut nested = 0;
        loop {
            if self.at(TokenKind::Eof) {
                self.expect_end(&end_kw, self.span_of(kw_tok));
                break;
            }
            if self.at_kw(&keyword) {
                nested += 1;
            }
            if self.at_kw(&end_kw) {
                if nested == 0 {
                    self.bump();
                    break;
                }
                nested -= 1;
            }
            self.bump();
        }
        let span = self.span_from(start);
        // Inside a POU kept as written, the text may be another tool's dialect: its lexical
        // errors are not errors of the file.
        let end = self.prev_end();
        self.attr_cursor = self.attrs.partition_point(|a| a.span.start < end).max(self.attr_cursor);
        if pou {
            self.verbatim_spans.push((start, end));
        }
        let why = attributes
            .iter()
            .rev()
            .find(|a| a.name.eq_ignore_ascii_case("sfc.verbatim"))
            .and_then(|a| a.value.as_deref())
            .map(crate::attr_value::unescape)
            .filter(|w| !w.trim().is_empty() && pou);
        // A stand-in for a type declared elsewhere (an import's opaque block) is reported there.
        let stub = why.as_deref() == Some("opaque");
        let mut note = Diagnostic::note_diag(
            "SFC0104",
            self.span_of(kw_tok),
            match &name {
                Some(n) if pou => format!("`{keyword} {}` is kept as written, not analysed", n.text),
                _ => format!("`{keyword}` is kept as written and not analysed"),
            },
        );
        if let Some(w) = why.filter(|_| !stub) {
            note.notes.push(w);
        }
        if !stub {
            self.diags.push(note);
        }
        Verbatim { keyword, attributes, name, text: self.text[span.range()].to_string(), span }
    }

    fn pou(&mut self) -> Pou {
        let kw = self.bump();
        let start = kw.start;
        let attributes = self.take_attrs(start);
        let kind = match self.text_of(kw).to_ascii_uppercase().as_str() {
            "PROGRAM" => PouKind::Program,
            "FUNCTION_BLOCK" => PouKind::FunctionBlock,
            _ => PouKind::Function,
        };
        let name = self.expect_ident("a POU name").unwrap_or_else(|| Ident::new("", self.cur_span()));
        let mut return_type = None;
        if kind == PouKind::Function {
            if self.eat(TokenKind::Colon) {
                return_type = Some(self.type_spec());
            } else {
                self.error_here("expected `:` and the return type of the FUNCTION");
            }
        }
        let mut var_blocks = Vec::new();
        let var_keywords: Vec<&str> = VAR_KEYWORDS.iter().map(|v| v.0).collect();
        loop {
            // `VAR_INPT a : BOOL;`: an identifier followed by an identifier or a newline.
            if !self.at_any_kw(&var_keywords) && (self.nth(1).kind == TokenKind::Ident || self.nth(1).nl_before) {
                self.fix_keyword_typo(&var_keywords);
            }
            if self.at_any_kw(&var_keywords) {
                var_blocks.push(self.var_block());
            } else {
                break;
            }
        }
        let end_kw = kind.end_keyword();
        // A chart being drawn may hold only actions yet; the editor marks its POU as a chart.
        let chart = attributes
            .iter()
            .any(|a| ["sfc.target", "sfc.graph", "sfc.loose"].iter().any(|n| a.name.eq_ignore_ascii_case(n)));
        let (body, actions) = self.body(end_kw, chart);
        self.expect_end(end_kw, self.span_of(kw));
        if self.at_kw(end_kw) {
            self.bump();
        }
        Pou { kind, name, return_type, attributes, var_blocks, body, actions, span: self.span_from(start) }
    }

    /// The body, and the actions after it when it is not a chart. A body is a chart when it
    /// has a step or a transition, or when `chart` (the POU carries a chart's attribute:
    /// `sfc.target`, `sfc.graph`, `sfc.loose`); otherwise actions alone (a function block whose
    /// code is all in its actions) follow an empty ST body.
    fn body(&mut self, end_kw: &str, chart: bool) -> (Body, Vec<Action>) {
        // An identifier followed by an identifier starts no statement: a misspelled element?
        if self.nth(1).kind == TokenKind::Ident {
            self.fix_keyword_typo(&["STEP", "INITIAL_STEP", "TRANSITION", "ACTION"]);
        }
        if self.at_any_kw(&["STEP", "INITIAL_STEP", "TRANSITION", "ACTION"]) {
            let elements = self.sfc_elements(end_kw);
            return match only_actions(&elements).filter(|_| !chart) {
                Some(actions) => (Body::St(Vec::new()), actions),
                None => (Body::Sfc(elements), Vec::new()),
            };
        }
        let body = if self.looks_like_il() {
            Body::Il(self.il_body(&[end_kw, "ACTION"]))
        } else {
            Body::St(self.stmt_list(&[end_kw, "ACTION"]))
        };
        if !self.at_any_kw(&["STEP", "INITIAL_STEP", "TRANSITION", "ACTION"]) {
            return (body, Vec::new());
        }
        let elements = self.sfc_elements(end_kw);
        match only_actions(&elements) {
            Some(actions) => (body, actions),
            None => {
                // A chart after statements by mistake: parsed, and reported.
                let empty = match &body {
                    Body::St(s) => s.is_empty(),
                    Body::Il(il) => il.instructions.is_empty(),
                    Body::Sfc(_) => true,
                };
                if !empty {
                    let at = elements
                        .iter()
                        .find(|e| !matches!(e, SfcElement::Action(_)))
                        .map_or(self.cur_span(), SfcElement::span);
                    self.push_error(
                        "SFC0101",
                        at,
                        "expected the end of the POU (a POU body is either statements or a chart)".into(),
                    );
                }
                (Body::Sfc(elements), Vec::new())
            }
        }
    }

    /// IL bodies start with `label:` or an IL operator not followed by ST punctuation.
    fn looks_like_il(&self) -> bool {
        let t = self.tok();
        let next = self.nth(1);
        if t.kind != TokenKind::Ident || self.is_kw_tok(t, "END_ACTION") {
            return false;
        }
        if next.kind == TokenKind::Colon {
            return true;
        }
        let is_op = IL_OPERATORS.iter().any(|k| self.text_of(t).eq_ignore_ascii_case(k));
        is_op
            && !matches!(
                next.kind,
                TokenKind::Assign | TokenKind::LParen | TokenKind::Dot | TokenKind::LBracket | TokenKind::Semi
            )
            && !(next.nl_before && self.is_reserved(t))
    }

    // ----------------------------------------------------------------------------------------
    // Declarations

    fn var_block(&mut self) -> VarBlock {
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

    fn var_decl(&mut self, access: bool) -> Option<VarDecl> {
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
        let init = if self.eat(TokenKind::Assign) { Some(self.initializer()) } else { None };
        if !self.expect(TokenKind::Semi, "`;` after the declaration") {
            self.recover_to(&["END_VAR"], true);
        }
        Some(VarDecl { names, location, access_path, access_mode, ty, init, attributes, span: self.span_from(start) })
    }

    fn address(&mut self, t: Tok) -> DirectAddress {
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

    fn type_block(&mut self) -> TypeBlock {
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

    fn type_spec(&mut self) -> TypeSpec {
        let start = self.tok().start;
        if !self.enter() {
            self.skip_nested();
            return TypeSpec { kind: TypeSpecKind::Error, span: self.span_from(start) };
        }
        let t = self.type_spec_inner(start);
        self.leave();
        t
    }

    fn type_spec_inner(&mut self, start: u32) -> TypeSpec {
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

    fn enum_values(&mut self) -> Vec<(Ident, Option<Expr>)> {
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

    fn initializer(&mut self) -> Initializer {
        if !self.enter() {
            return Initializer::Expr(self.skip_nested());
        }
        let r = self.initializer_inner();
        self.leave();
        r
    }

    fn initializer_inner(&mut self) -> Initializer {
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

    fn expr_primary_literal(&mut self) -> Expr {
        let t = self.bump();
        self.literal_expr(t)
    }

    // ----------------------------------------------------------------------------------------
    // SFC

    fn sfc_elements(&mut self, end_kw: &str) -> Vec<SfcElement> {
        let mut elements = Vec::new();
        while !self.at(TokenKind::Eof) && !self.at_kw(end_kw) {
            if self.at_kw("STEP") || self.at_kw("INITIAL_STEP") {
                elements.push(SfcElement::Step(self.step()));
            } else if self.at_kw("TRANSITION") {
                elements.push(SfcElement::Transition(self.transition()));
            } else if self.at_kw("ACTION") {
                elements.push(SfcElement::Action(self.action()));
            } else if self.at_any_kw(&[
                "PROGRAM",
                "FUNCTION",
                "FUNCTION_BLOCK",
                "TYPE",
                "CONFIGURATION",
                "END_PROGRAM",
                "END_FUNCTION",
                "END_FUNCTION_BLOCK",
            ]) {
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
    fn action_chart(&mut self) -> Vec<SfcElement> {
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

    fn step(&mut self) -> Step {
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
        Step { initial, name, associations, step_actions, attributes, span: self.span_from(start) }
    }

    /// `ENTRY_ACTION := Name;` or `… := instance.Action;` (the current token is the word).
    fn step_action(&mut self, kind: StepActionKind) -> StepAction {
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

    fn association(&mut self) -> Option<ActionAssociation> {
        let start = self.tok().start;
        let action = match self.expect_ident("an action name") {
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

    fn step_list(&mut self) -> (Vec<Ident>, bool) {
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

    fn transition(&mut self) -> Transition {
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

    fn action(&mut self) -> Action {
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

    // ----------------------------------------------------------------------------------------
    // Instruction List

    fn il_body(&mut self, ends: &[&str]) -> IlBody {
        let start = self.tok().start;
        let instructions = self.il_list(ends, false);
        IlBody { instructions, span: self.span_from(start) }
    }

    fn il_list(&mut self, ends: &[&str], nested: bool) -> Vec<IlInstruction> {
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

    fn il_instruction(&mut self, ends: &[&str]) -> Option<IlInstruction> {
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

    fn skip_line(&mut self) {
        while !self.at(TokenKind::Eof) && !self.tok().nl_before {
            self.bump();
        }
    }

    // ----------------------------------------------------------------------------------------
    // Statements

    /// Statements until a stopper keyword, `extra` stoppers, or end of file.
    fn stmt_list(&mut self, extra: &[&str]) -> Vec<Stmt> {
        self.stmts_until(|p| p.at_any_kw(extra))
    }

    /// Statements until a stopper keyword, end of file, or where `stop` says.
    fn stmts_until(&mut self, stop: impl Fn(&Self) -> bool) -> Vec<Stmt> {
        let mut out = Vec::new();
        loop {
            if self.at(TokenKind::Eof) || self.at_any_kw(STOPPERS) || stop(self) {
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

    fn enter(&mut self) -> bool {
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
    fn leave(&mut self) {
        self.depth -= 1;
    }

    /// Whether a chain of `chain` links at the current depth exceeds the budget (reported once).
    fn chain_too_deep(&mut self, chain: u32) -> bool {
        if self.depth + chain <= MAX_DEPTH {
            return false;
        }
        self.depth += chain;
        self.enter();
        self.depth -= chain;
        true
    }

    /// Skips a too-deeply nested construct without recursion, returning an error expression.
    fn skip_nested(&mut self) -> Expr {
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

    fn stmt(&mut self) -> Option<Stmt> {
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

    fn block_end(&mut self, kw: &str, opened: Tok) {
        self.expect_end(kw, self.span_of(opened));
        self.eat(TokenKind::Semi);
    }

    fn stmt_inner(&mut self) -> Option<Stmt> {
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

    fn recover_stmt(&mut self) {
        self.recover_to(STOPPERS, true);
    }

    fn then_kw(&mut self, kw: &str) {
        if !self.eat_kw(kw) {
            self.error_here(&format!("expected {kw}"));
        }
    }

    /// Statements of a CASE arm: stop where the next arm's labels begin.
    fn case_body(&mut self) -> Vec<Stmt> {
        self.stmts_until(|p| p.at_kw("END_CASE") || p.at_case_label())
    }

    fn at_case_label(&self) -> bool {
        let (a, b) = if self.at(TokenKind::Minus) { (self.nth(1), self.nth(2)) } else { (self.tok(), self.nth(1)) };
        matches!(a.kind, TokenKind::Int | TokenKind::Typed | TokenKind::Ident)
            && !self.is_reserved(a)
            && matches!(b.kind, TokenKind::Colon | TokenKind::Comma | TokenKind::DotDot)
    }

    // ----------------------------------------------------------------------------------------
    // Expressions

    fn expr(&mut self) -> Expr {
        if !self.enter() {
            return self.skip_nested();
        }
        let e = self.expr_bp(1);
        self.leave();
        e
    }

    fn binop(&self) -> Option<BinaryOp> {
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
    fn expr_bp(&mut self, min: u8) -> Expr {
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

    fn unary(&mut self) -> Expr {
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

    fn literal_expr(&mut self, t: Tok) -> Expr {
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

    fn postfix_expr(&mut self) -> Expr {
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
            } else {
                break;
            }
        }
        e
    }

    fn call_args(&mut self) -> Vec<Arg> {
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
            if !self.eat(TokenKind::Comma) {
                break;
            }
        }
        self.expect(TokenKind::RParen, "`)` after the arguments");
        args
    }
}

/// Reports identifiers with a leading double, doubled or trailing underscore (seed 000).
/// The actions of `elements` when it holds nothing else (no step, no transition).
fn only_actions(elements: &[SfcElement]) -> Option<Vec<Action>> {
    elements
        .iter()
        .map(|e| match e {
            SfcElement::Action(a) => Some(a.clone()),
            _ => None,
        })
        .collect()
}

fn check_identifier(text: &str, span: Span, diags: &mut Vec<Diagnostic>) {
    if text.contains("__") || (text.ends_with('_') && !text.is_empty()) {
        diags.push(Diagnostic::error(
            "SFC0006",
            span,
            format!("invalid identifier `{text}`: underscores may not be doubled or end a name"),
        ));
    }
}

/// Parses `{attribute 'name' := 'value'}` (also `{attribute 'name'}`).
fn parse_attribute(text: &str, span: Span) -> Option<Attribute> {
    let inner = text.strip_prefix('{')?.strip_suffix('}').unwrap_or(&text[1..]).trim();
    let rest = inner.get(..9).filter(|k| k.eq_ignore_ascii_case("attribute")).map(|_| inner[9..].trim_start())?;
    let (name, rest) = quoted(rest)?;
    let rest = rest.trim_start();
    let value = if let Some(r) = rest.strip_prefix(":=") { Some(quoted(r.trim_start())?.0) } else { None };
    Some(Attribute { name, value, span })
}

fn quoted(s: &str) -> Option<(String, &str)> {
    let s = s.strip_prefix('\'')?;
    let end = s.find('\'')?;
    Some((s[..end].to_string(), &s[end + 1..]))
}

#[cfg(test)]
mod reserved_tests {
    use super::{reserved_word, RESERVED};

    #[test]
    fn the_keyword_match_is_the_keyword_list() {
        for k in RESERVED {
            assert!(reserved_word(k), "{k}");
            assert!(reserved_word(&k.to_ascii_lowercase()), "{k}");
            assert!(!reserved_word(&format!("{k}X")), "{k}X");
        }
        for name in ["S1", "Go", "Count", "END_", "Step1", "I", "", "END_FUNCTION_BLOCKS", "ÉTAPE"] {
            assert!(!reserved_word(name), "{name}");
        }
    }
}
