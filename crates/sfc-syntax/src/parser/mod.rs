//! A hand-written recursive-descent parser (Pratt for expressions) that never fails: it returns a
//! [`SourceUnit`] and every error it met, recovering at keywords so one mistake gives one
//! diagnostic. Nesting is capped at [`MAX_DEPTH`] so no input can overflow the stack.

use crate::ast::*;
use crate::keywords::RESERVED;
use crate::lexer::{lex, Token, TokenKind};
use crate::literal;
use sfc_diagnostics::{Diagnostic, Span};

mod decl;
mod expr;
mod il;
mod objects;
mod sfc;
mod stmt;

/// The deepest nesting of expressions accepted (SFC0103 beyond).
pub const MAX_DEPTH: u32 = 256;
/// The deepest nesting of statements accepted (SFC0103 beyond); a statement level costs this
/// many expression levels of the shared budget, as its parse frames are larger.
pub const MAX_STMT_DEPTH: u32 = 64;
/// Leaves a quarter of the budget for the expressions inside the innermost statement.
const STMT_WEIGHT: u32 = (MAX_DEPTH * 3 / 4) / MAX_STMT_DEPTH;

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
    "END_METHOD",
    "END_PROPERTY",
    "END_GET",
    "END_SET",
    "END_INTERFACE",
];

/// Keywords that start a top-level declaration (recovery stops at them).
const TOP_LEVEL: &[&str] =
    &["PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "TYPE", "CONFIGURATION", "VAR_GLOBAL", "INTERFACE"];

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
            | b"END_METHOD"
            | b"END_PROPERTY"
            | b"END_GET"
            | b"END_SET"
            | b"END_INTERFACE"
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
    /// Inside a POU marked `{attribute 'sfc.dialect' := 'codesys'}`: identifiers with doubled
    /// or trailing underscores (`Move__Pos3`, which CODESYS and TwinCAT accept) are read, and
    /// the first is named in one note (`codesys_name`).
    codesys: bool,
    codesys_name: Option<(String, Span)>,
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
            codesys: false,
            codesys_name: None,
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
        if self.codesys && (text.contains("__") || text.ends_with('_')) {
            self.codesys_name.get_or_insert_with(|| (text.to_string(), span));
        } else {
            check_identifier(text, span, &mut self.diags);
        }
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

    /// The value of attribute `a` parsed as an ST expression, located where it stands in the
    /// text (a value holding `$` escapes is parsed unescaped, located from where the value
    /// starts).
    fn attribute_expr(&mut self, a: &Attribute) -> Expr {
        let raw = a.value.as_deref().unwrap_or("");
        let whole = self.text.get(a.span.start as usize..a.span.end as usize).unwrap_or("");
        // The value is the quoted text after `:=`.
        let at = whole.find(":=").and_then(|i| whole.get(i..)?.find('\'').map(|j| i + j + 1)).unwrap_or(0);
        let off = a.span.start + at as u32;
        if raw.trim().is_empty() {
            self.diags.push(Diagnostic::error(
                "SFC0601",
                a.span,
                format!("`{}` holds no condition (an ST expression)", a.name),
            ));
            let lit = Literal { kind: LiteralKind::Bool(true), type_prefix: None, text: "TRUE".into() };
            return Expr { kind: ExprKind::Literal(lit), span: a.span };
        }
        let exact = !raw.contains('$') && whole.get(at..at + raw.len()) == Some(raw);
        // Tokens at their places in the file: lexed alone and moved (the parser reads their
        // text from the file); an escaped value is lexed unescaped behind padding instead.
        let padded;
        let (source, text) = if exact {
            (self.text, raw.to_string())
        } else {
            padded = format!("{}{}", " ".repeat(off as usize), crate::attr_value::unescape(raw));
            (padded.as_str(), String::new())
        };
        let (toks, diags) = if exact {
            let (mut toks, mut diags) = lex(self.file, &text);
            for t in &mut toks {
                t.start += off;
                t.end += off;
            }
            for d in &mut diags {
                d.span = Span::new(d.span.file, d.span.start + off, d.span.end + off);
            }
            (toks, diags)
        } else {
            lex(self.file, source)
        };
        self.diags.extend(diags);
        let mut p = Parser::new(self.file, source, &toks);
        let e = p.expr();
        if !p.at(TokenKind::Eof) {
            p.error_here("expected the end of the condition");
        }
        self.diags.append(&mut p.diags);
        e
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
            } else if self.at_kw("INTERFACE") && self.nth(1).kind == TokenKind::Ident {
                items.push(Item::Interface(self.interface()));
            } else if self.at_kw("VAR_GLOBAL") {
                items.push(Item::Globals(self.var_block()));
            } else if self.at_kw("CONFIGURATION") || self.at_kw("RESOURCE") {
                items.push(Item::Verbatim(self.verbatim()));
            } else if self.at_any_kw(&["STEP", "INITIAL_STEP", "TRANSITION", "ACTION"]) {
                self.error_here(
                    "expected PROGRAM, FUNCTION_BLOCK, FUNCTION or TYPE (SFC elements belong inside a POU)",
                );
                self.recover_to(TOP_LEVEL, false);
                // Skip the keyword we stopped on if it is not a top-level one.
            } else {
                self.error_here("expected PROGRAM, FUNCTION_BLOCK, FUNCTION, TYPE or CONFIGURATION");
                self.bump();
                self.recover_to(TOP_LEVEL, false);
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
        self.codesys = attributes.iter().any(|a| {
            a.name.eq_ignore_ascii_case("sfc.dialect")
                && a.value.as_deref().is_some_and(|v| v.eq_ignore_ascii_case("codesys"))
        });
        let kind = match self.text_of(kw).to_ascii_uppercase().as_str() {
            "PROGRAM" => PouKind::Program,
            "FUNCTION_BLOCK" => PouKind::FunctionBlock,
            _ => PouKind::Function,
        };
        let modifiers = self.modifiers();
        let name = self.expect_ident("a POU name").unwrap_or_else(|| Ident::new("", self.cur_span()));
        let (extends, implements) = self.inheritance();
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
        let (mut methods, mut properties) = (Vec::new(), Vec::new());
        self.members(&mut methods, &mut properties);
        let end_kw = kind.end_keyword();
        // A chart being drawn may hold only actions yet; the editor marks its POU as a chart.
        let chart = attributes
            .iter()
            .any(|a| ["sfc.target", "sfc.graph", "sfc.loose"].iter().any(|n| a.name.eq_ignore_ascii_case(n)));
        let (mut body, mut actions) = self.body(end_kw, chart);
        // After the body: further methods and properties, and actions among them.
        while self.at_member_start() || self.at_kw("ACTION") {
            if self.at_kw("ACTION") {
                let a = self.action();
                match body.sfc_mut() {
                    Some(elements) => elements.push(SfcElement::Action(a)),
                    None => actions.push(a),
                }
            } else {
                self.members(&mut methods, &mut properties);
            }
        }
        self.expect_end(end_kw, self.span_of(kw));
        if self.at_kw(end_kw) {
            self.bump();
        }
        self.codesys = false;
        if let Some((name, span)) = self.codesys_name.take() {
            self.diags.push(
                Diagnostic::note_diag(
                    "SFC0013",
                    span,
                    format!(
                        "`{name}` is a CODESYS identifier: IEC 61131-3 does not allow doubled or trailing underscores"
                    ),
                )
                .with_note("read as written, because the POU is marked `{attribute 'sfc.dialect' := 'codesys'}`"),
            );
        }
        Pou {
            kind,
            name,
            return_type,
            attributes,
            var_blocks,
            body,
            actions,
            modifiers,
            extends,
            implements,
            methods,
            properties,
            span: self.span_from(start),
        }
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
}

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

/// Reports identifiers with a leading double, doubled or trailing underscore (seed 000).
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
