//! The lexer: splits text into tokens that cover every byte (trivia included), never fails, and
//! reports lexical errors as diagnostics. Keywords are not distinguished here: IEC keywords are
//! case-insensitive identifiers and many (`N`, `S`, `LD`, …) are ordinary names in some contexts,
//! so the parser decides.

use sfc_diagnostics::{Diagnostic, Span};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TokenKind {
    Whitespace,
    BlockComment,
    LineComment,
    Pragma,
    Ident,
    /// Decimal or based integer: `123_456`, `16#FF`.
    Int,
    /// `1.5`, `1.0e-6`
    Real,
    /// `'…'`
    String,
    /// `"…"`
    WString,
    /// `PREFIX#rest`: typed literals, durations, dates, times, `Type#Value` enum values.
    Typed,
    /// `%IX2.4`
    Address,
    LParen,
    RParen,
    LBracket,
    RBracket,
    Comma,
    Semi,
    Colon,
    /// `:=`
    Assign,
    /// `=>`
    Arrow,
    Dot,
    /// `..`
    DotDot,
    Plus,
    Minus,
    Star,
    Slash,
    /// `**`
    Power,
    Eq,
    /// `<>`
    Ne,
    Lt,
    Gt,
    Le,
    Ge,
    /// `&`
    Amp,
    /// `!`: not IEC, but the negation of an EATMT condition input (`!c5`); the parser reads it
    /// as NOT and the checker rejects it outside EATMT charts.
    Bang,
    /// `^`: dereference (`p^`, `THIS^`; IEC 61131-3 3rd edition, CODESYS).
    Caret,
    /// A character no token starts with (reported).
    Unknown,
    Eof,
}

impl TokenKind {
    /// Comments, pragmas and white space.
    pub fn is_trivia(self) -> bool {
        matches!(self, TokenKind::Whitespace | TokenKind::BlockComment | TokenKind::LineComment | TokenKind::Pragma)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Token {
    pub kind: TokenKind,
    pub start: u32,
    pub end: u32,
}

impl Token {
    pub fn span(&self, file: u32) -> Span {
        Span::new(file, self.start, self.end)
    }
}

/// Splits `text` into tokens (ending with one `Eof`); the concatenation of all tokens but `Eof`
/// is exactly `text`.
pub fn lex(file: u32, text: &str) -> (Vec<Token>, Vec<Diagnostic>) {
    let mut lx = Lexer { src: text.as_bytes(), text, pos: 0, file, tokens: Vec::new(), diags: Vec::new() };
    lx.run();
    (lx.tokens, lx.diags)
}

struct Lexer<'a> {
    src: &'a [u8],
    text: &'a str,
    pos: usize,
    file: u32,
    tokens: Vec<Token>,
    diags: Vec<Diagnostic>,
}

fn is_ident_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_'
}
fn is_ident_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

impl<'a> Lexer<'a> {
    fn peek(&self, n: usize) -> u8 {
        *self.src.get(self.pos + n).unwrap_or(&0)
    }

    fn span(&self, start: usize, end: usize) -> Span {
        Span::new(self.file, start as u32, end as u32)
    }

    fn push(&mut self, kind: TokenKind, start: usize) {
        self.tokens.push(Token { kind, start: start as u32, end: self.pos as u32 });
    }

    fn error(&mut self, code: &'static str, start: usize, end: usize, msg: impl Into<String>) {
        let span = self.span(start, end);
        self.diags.push(Diagnostic::error(code, span, msg));
    }

    fn run(&mut self) {
        while self.pos < self.src.len() {
            let start = self.pos;
            let b = self.peek(0);
            match b {
                // A UTF-8 byte order mark at the start of a file is white space.
                0xEF if start == 0 && self.src.starts_with(b"\xEF\xBB\xBF") => {
                    self.pos += 3;
                    self.push(TokenKind::Whitespace, start);
                }
                b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c => {
                    while matches!(self.peek(0), b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c) {
                        self.pos += 1;
                    }
                    self.push(TokenKind::Whitespace, start);
                }
                b'(' if self.peek(1) == b'*' => self.block_comment(),
                b'/' if self.peek(1) == b'*' => self.slash_comment(),
                b'/' if self.peek(1) == b'/' => {
                    while self.pos < self.src.len() && self.peek(0) != b'\n' {
                        self.pos += 1;
                    }
                    self.push(TokenKind::LineComment, start);
                }
                b'{' => self.pragma(),
                b'\'' | b'"' => {
                    self.string(b);
                    let kind = if b == b'\'' { TokenKind::String } else { TokenKind::WString };
                    self.push(kind, start);
                }
                b'%' => self.address(),
                b'0'..=b'9' => self.number(),
                _ if is_ident_start(b) => self.ident_or_typed(),
                _ => self.punct(),
            }
        }
        self.tokens.push(Token { kind: TokenKind::Eof, start: self.pos as u32, end: self.pos as u32 });
    }

    fn block_comment(&mut self) {
        let start = self.pos;
        self.pos += 2;
        // Depth > 1 only after a reported nested `(*`: we then close at the matching `*)` to avoid
        // a cascade of errors from the rest of the outer comment.
        let mut depth = 1;
        while self.pos < self.src.len() {
            if self.peek(0) == b'*' && self.peek(1) == b')' {
                self.pos += 2;
                depth -= 1;
                if depth == 0 {
                    self.push(TokenKind::BlockComment, start);
                    return;
                }
            } else if self.peek(0) == b'(' && self.peek(1) == b'*' {
                self.error("SFC0010", self.pos, self.pos + 2, "comments do not nest in IEC 61131-3");
                self.pos += 2;
                depth += 1;
            } else {
                self.pos += 1;
            }
        }
        self.error("SFC0001", start, start + 2, "unterminated comment: `(*` has no closing `*)`");
        self.push(TokenKind::BlockComment, start);
    }

    /// `/* … */`, IEC 61131-3 3rd edition's other block comment (CODESYS writes it). It does
    /// not nest either; a `/*` inside is text.
    fn slash_comment(&mut self) {
        let start = self.pos;
        self.pos += 2;
        while self.pos < self.src.len() {
            if self.peek(0) == b'*' && self.peek(1) == b'/' {
                self.pos += 2;
                self.push(TokenKind::BlockComment, start);
                return;
            }
            self.pos += 1;
        }
        self.error("SFC0001", start, start + 2, "unterminated comment: `/*` has no closing `*/`");
        self.push(TokenKind::BlockComment, start);
    }

    fn pragma(&mut self) {
        let start = self.pos;
        self.pos += 1;
        let mut in_str = false;
        while self.pos < self.src.len() {
            let c = self.peek(0);
            self.pos += 1;
            if c == b'\'' {
                in_str = !in_str;
            } else if c == b'}' && !in_str {
                self.push(TokenKind::Pragma, start);
                return;
            }
        }
        self.error("SFC0001", start, start + 1, "unterminated pragma: `{` has no closing `}`");
        self.push(TokenKind::Pragma, start);
    }

    /// Consumes a string literal body starting at its opening quote. Escapes are validated when
    /// the literal is decoded; here only the extent matters (a `$` escapes the next character).
    fn string(&mut self, quote: u8) {
        let start = self.pos;
        self.pos += 1;
        while self.pos < self.src.len() {
            let c = self.peek(0);
            if c == b'$' {
                self.pos += 1;
                if self.pos < self.src.len() && self.peek(0) != b'\n' {
                    self.pos += 1;
                }
                continue;
            }
            if c == b'\n' {
                break;
            }
            self.pos += 1;
            if c == quote {
                return;
            }
        }
        self.error("SFC0002", start, self.pos, "unterminated string literal");
    }

    fn address(&mut self) {
        let start = self.pos;
        self.pos += 1;
        while is_ident_char(self.peek(0))
            || self.peek(0) == b'*'
            || (self.peek(0) == b'.' && self.peek(1).is_ascii_digit())
        {
            self.pos += 1;
        }
        self.push(TokenKind::Address, start);
    }

    fn digits(&mut self, radix_ok: impl Fn(u8) -> bool) {
        while radix_ok(self.peek(0)) || self.peek(0) == b'_' {
            self.pos += 1;
        }
    }

    fn number(&mut self) {
        let start = self.pos;
        self.digits(|c| c.is_ascii_digit());
        if self.peek(0) == b'#' {
            // Based integer `16#FF`; the digits are validated on decoding.
            self.pos += 1;
            self.digits(|c| c.is_ascii_alphanumeric());
            self.push(TokenKind::Int, start);
            return;
        }
        let mut kind = TokenKind::Int;
        if self.peek(0) == b'.' && self.peek(1).is_ascii_digit() {
            self.pos += 1;
            self.digits(|c| c.is_ascii_digit());
            kind = TokenKind::Real;
        }
        if matches!(self.peek(0), b'e' | b'E')
            && (self.peek(1).is_ascii_digit() || (matches!(self.peek(1), b'+' | b'-') && self.peek(2).is_ascii_digit()))
        {
            self.pos += 2;
            self.digits(|c| c.is_ascii_digit());
            kind = TokenKind::Real;
        }
        // `12abc`: swallow the glued letters so the whole thing is one bad literal.
        if is_ident_start(self.peek(0)) {
            while is_ident_char(self.peek(0)) {
                self.pos += 1;
            }
        }
        self.push(kind, start);
    }

    fn ident_or_typed(&mut self) {
        let start = self.pos;
        while is_ident_char(self.peek(0)) {
            self.pos += 1;
        }
        if self.peek(0) == b'#' {
            let prefix = self.text[start..self.pos].to_ascii_uppercase();
            self.pos += 1;
            self.typed_rest(&prefix);
            self.push(TokenKind::Typed, start);
            return;
        }
        self.push(TokenKind::Ident, start);
    }

    /// The part after `PREFIX#`.
    fn typed_rest(&mut self, prefix: &str) {
        match prefix {
            "T" | "TIME" | "LT" | "LTIME" => {
                if matches!(self.peek(0), b'+' | b'-') {
                    self.pos += 1;
                }
                while is_ident_char(self.peek(0)) || self.peek(0) == b'.' {
                    self.pos += 1;
                }
            }
            "D" | "DATE" | "LDATE" | "TOD" | "TIME_OF_DAY" | "LTOD" | "DT" | "DATE_AND_TIME" | "LDT" => {
                while self.peek(0).is_ascii_digit() || matches!(self.peek(0), b'-' | b':' | b'.' | b'_') {
                    self.pos += 1;
                }
            }
            _ => match self.peek(0) {
                b'\'' | b'"' => {
                    let q = self.peek(0);
                    self.string(q);
                }
                b'+' | b'-' => {
                    self.pos += 1;
                    self.number_body();
                }
                b'0'..=b'9' => self.number_body(),
                c if is_ident_start(c) => {
                    while is_ident_char(self.peek(0)) {
                        self.pos += 1;
                    }
                }
                _ => {}
            },
        }
    }

    /// A number after a type prefix (`INT#16#FE`, `REAL#1.5`).
    fn number_body(&mut self) {
        let before = self.tokens.len();
        self.number();
        // `number` pushed a token of its own; the typed token covers it instead.
        self.tokens.truncate(before);
    }

    fn punct(&mut self) {
        let start = self.pos;
        let b = self.peek(0);
        let two = (b, self.peek(1));
        let (kind, len) = match two {
            (b':', b'=') => (TokenKind::Assign, 2),
            (b'=', b'>') => (TokenKind::Arrow, 2),
            (b'.', b'.') => (TokenKind::DotDot, 2),
            (b'*', b'*') => (TokenKind::Power, 2),
            (b'<', b'>') => (TokenKind::Ne, 2),
            (b'<', b'=') => (TokenKind::Le, 2),
            (b'>', b'=') => (TokenKind::Ge, 2),
            (b'(', _) => (TokenKind::LParen, 1),
            (b')', _) => (TokenKind::RParen, 1),
            (b'[', _) => (TokenKind::LBracket, 1),
            (b']', _) => (TokenKind::RBracket, 1),
            (b',', _) => (TokenKind::Comma, 1),
            (b';', _) => (TokenKind::Semi, 1),
            (b':', _) => (TokenKind::Colon, 1),
            (b'.', _) => (TokenKind::Dot, 1),
            (b'+', _) => (TokenKind::Plus, 1),
            (b'-', _) => (TokenKind::Minus, 1),
            (b'*', _) => (TokenKind::Star, 1),
            (b'/', _) => (TokenKind::Slash, 1),
            (b'=', _) => (TokenKind::Eq, 1),
            (b'<', _) => (TokenKind::Lt, 1),
            (b'>', _) => (TokenKind::Gt, 1),
            (b'&', _) => (TokenKind::Amp, 1),
            (b'!', _) => (TokenKind::Bang, 1),
            (b'^', _) => (TokenKind::Caret, 1),
            _ => {
                // One whole UTF-8 character (or a run of bytes) no token starts with.
                let mut end = self.pos + 1;
                while end < self.src.len() && !self.text.is_char_boundary(end) {
                    end += 1;
                }
                // Glue a run of unknown characters into one token: one error, not hundreds.
                loop {
                    let Some(&c) = self.src.get(end) else { break };
                    let starts_token = c.is_ascii_whitespace()
                        || c.is_ascii_alphanumeric()
                        || b"_()[],;:.+-*/=<>&!^'\"%{".contains(&c);
                    if starts_token {
                        break;
                    }
                    end += 1;
                    while end < self.src.len() && !self.text.is_char_boundary(end) {
                        end += 1;
                    }
                }
                let shown: String = self.text[start..end].chars().take(20).collect();
                self.error(
                    "SFC0003",
                    start,
                    end,
                    format!(
                        "invalid character{} `{}`",
                        if end - start > 1 && self.text[start..end].chars().count() > 1 { "s" } else { "" },
                        shown.escape_debug()
                    ),
                );
                self.pos = end;
                self.push(TokenKind::Unknown, start);
                return;
            }
        };
        self.pos += len;
        self.push(kind, start);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(text: &str) -> Vec<TokenKind> {
        lex(0, text).0.into_iter().filter(|t| !t.kind.is_trivia()).map(|t| t.kind).collect()
    }

    #[test]
    fn tokens_cover_the_input() {
        let text = "PROGRAM P (* c *) x := 16#FF + T#1s; {attribute 'a' := 'b'} y[1..2] %IX2.4 'it$'s' ü";
        let (toks, _) = lex(0, text);
        let joined: String = toks.iter().map(|t| &text[t.start as usize..t.end as usize]).collect();
        assert_eq!(joined, text);
    }

    #[test]
    fn ranges_are_not_reals() {
        use TokenKind::*;
        assert_eq!(kinds("1..10"), vec![Int, DotDot, Int, Eof]);
        assert_eq!(kinds("1.5e-3"), vec![Real, Eof]);
        assert_eq!(kinds("UINT#16#FE INT#-5 T#-2s"), vec![Typed, Typed, Typed, Eof]);
    }

    #[test]
    fn slash_star_comments_as_iec_3rd_edition_and_codesys_write_them() {
        use TokenKind::*;
        let (toks, d) = lex(0, "/* a\n (* b *) */ x");
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(toks.iter().map(|t| t.kind).collect::<Vec<_>>(), vec![BlockComment, Whitespace, Ident, Eof]);
        assert_eq!(kinds("a / b"), vec![Ident, Slash, Ident, Eof]);
        let (toks, d) = lex(0, "x /* open");
        assert_eq!(d.len(), 1, "unterminated: {d:?}");
        assert_eq!(toks.iter().filter(|t| t.kind == BlockComment).count(), 1);
    }

    #[test]
    fn nested_comment_is_reported_once() {
        let (_, d) = lex(0, "(* a (* b *) c *) x");
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].code, "SFC0010");
    }
}
