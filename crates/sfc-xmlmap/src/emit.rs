//! Building the generated IEC text together with its [`SourceMap`] back into the XML.

use crate::xml::XText;
use sfc_diagnostics::Span;
use std::ops::Range;

/// One mapping from a byte range of the generated text to a byte range of the XML.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MapEntry {
    /// Byte range in the generated text.
    pub text: Range<u32>,
    /// Byte range in the XML.
    pub xml: Range<u32>,
    /// The text range is a byte-for-byte copy of the XML range (offsets map one to one);
    /// otherwise the whole text range stands for the XML range (an element's start tag).
    pub exact: bool,
}

/// Where each part of the generated IEC text came from in the XML. Every byte of the text is
/// covered: generated keywords map to the start tag of the element they were made from, copied
/// text (conditions, bodies, names, expressions) maps exactly to its characters in the XML.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SourceMap {
    entries: Vec<MapEntry>,
}

impl SourceMap {
    /// Every entry, ordered by the start of their text range.
    pub fn entries(&self) -> &[MapEntry] {
        &self.entries
    }

    /// The innermost entry covering text offset `at` (exact entries win over containers).
    fn lookup(&self, at: u32) -> Option<&MapEntry> {
        // Entries are sorted by start; only those starting at or before `at` can cover it.
        let upto = self.entries.partition_point(|e| e.text.start <= at);
        let mut best: Option<&MapEntry> = None;
        for e in self.entries.get(..upto).unwrap_or_default().iter().rev() {
            let covers = e.text.start <= at && (at < e.text.end || (e.text.is_empty() && at == e.text.start));
            if !covers {
                continue;
            }
            let better = match best {
                None => true,
                Some(b) => (e.exact && !b.exact) || (e.exact == b.exact && e.text.len() < b.text.len()),
            };
            if better {
                best = Some(e);
            }
        }
        best
    }

    /// The XML byte range a span of the generated text stands for.
    pub fn to_xml(&self, span: Span) -> Range<u32> {
        let at = span.start;
        let Some(e) = self.lookup(at).or_else(|| self.lookup(at.saturating_sub(1))) else {
            return 0..0;
        };
        if !e.exact {
            return e.xml.clone();
        }
        let start = e.xml.start + at.saturating_sub(e.text.start).min(e.xml.len() as u32);
        // The end: where the last byte of the span maps, when that is exact text too.
        let last = span.end.saturating_sub(1).max(at);
        let end = match self.lookup(last) {
            Some(l) if l.exact && span.end > at => {
                let off = l.xml.start + (last - l.text.start).min(l.xml.len() as u32) + 1;
                if off > start {
                    off
                } else {
                    start + 1
                }
            }
            _ => (start + span.len()).min(e.xml.end).max(start),
        };
        start..end
    }

    /// A span of the generated text as a span of the XML file `file`.
    pub fn span_to_xml(&self, span: Span, file: u32) -> Span {
        let r = self.to_xml(span);
        Span::new(file, r.start, r.end)
    }
}

/// A piece of generated text with the locations of its parts (offsets relative to the piece).
#[derive(Debug, Clone, Default)]
pub struct Frag {
    pub text: String,
    pub marks: Vec<MapEntry>,
    /// A name, literal, member access or call: needs no parentheses as an operand.
    pub atomic: bool,
}

impl Frag {
    pub fn plain(s: impl Into<String>) -> Frag {
        Frag { text: s.into(), marks: Vec::new(), atomic: true }
    }

    /// Text copied from the XML.
    pub fn from_xtext(t: &XText) -> Frag {
        let mut f = Frag { text: t.text.clone(), marks: Vec::new(), atomic: true };
        f.marks.push(MapEntry { text: 0..t.text.len() as u32, xml: t.anchor.clone(), exact: false });
        for r in &t.runs {
            f.marks.push(MapEntry { text: r.text..r.text + r.len, xml: r.raw..r.raw + r.len, exact: true });
        }
        f
    }

    /// Generated text standing for the element at `anchor`.
    pub fn located(s: impl Into<String>, anchor: Range<u32>) -> Frag {
        let text = s.into();
        let len = text.len() as u32;
        Frag { text, marks: vec![MapEntry { text: 0..len, xml: anchor, exact: false }], atomic: true }
    }

    pub fn push_str(&mut self, s: &str) {
        self.text.push_str(s);
    }

    pub fn push(&mut self, other: &Frag) {
        let base = self.text.len() as u32;
        self.text.push_str(&other.text);
        self.marks.extend(other.marks.iter().map(|m| MapEntry {
            text: m.text.start + base..m.text.end + base,
            xml: m.xml.clone(),
            exact: m.exact,
        }));
    }

    /// Marks the whole piece as standing for `anchor` (an element that produced it).
    pub fn locate(mut self, anchor: Range<u32>) -> Frag {
        self.marks.insert(0, MapEntry { text: 0..self.text.len() as u32, xml: anchor, exact: false });
        self
    }

    /// `( self )` unless atomic.
    pub fn operand(self) -> Frag {
        if self.atomic {
            return self;
        }
        let mut f = Frag::plain("(");
        f.push(&self);
        f.push_str(")");
        f.atomic = true;
        f
    }

    pub fn not(self) -> Frag {
        let mut f = Frag::plain("NOT ");
        f.push(&self.operand());
        f.atomic = false;
        f
    }

    /// `a op b op c` with every operand parenthesised as needed.
    pub fn infix(op: &str, operands: Vec<Frag>) -> Frag {
        let mut f = Frag::default();
        for (i, o) in operands.into_iter().enumerate() {
            if i > 0 {
                f.push_str(&format!(" {op} "));
            }
            f.push(&o.operand());
        }
        f.atomic = false;
        f
    }
}

/// The generated text being written, with its source map and a stack of enclosing elements.
pub struct Emitter {
    pub out: String,
    entries: Vec<MapEntry>,
    /// Open elements: the XML anchor and the text offset where each began.
    stack: Vec<(Range<u32>, u32)>,
}

impl Emitter {
    pub fn new(root: Range<u32>) -> Emitter {
        Emitter { out: String::new(), entries: Vec::new(), stack: vec![(root, 0)] }
    }

    /// Everything written until the matching [`Emitter::close`] stands for `anchor`.
    pub fn open(&mut self, anchor: Range<u32>) {
        self.stack.push((anchor, self.out.len() as u32));
    }

    pub fn close(&mut self) {
        if self.stack.len() > 1 {
            if let Some((xml, start)) = self.stack.pop() {
                self.entries.push(MapEntry { text: start..self.out.len() as u32, xml, exact: false });
            }
        }
    }

    pub fn str(&mut self, s: &str) {
        self.out.push_str(s);
    }

    pub fn frag(&mut self, f: &Frag) {
        let base = self.out.len() as u32;
        self.out.push_str(&f.text);
        for m in &f.marks {
            self.entries.push(MapEntry {
                text: m.text.start + base..m.text.end + base,
                xml: m.xml.clone(),
                exact: m.exact,
            });
        }
    }

    pub fn xtext(&mut self, t: &XText) {
        self.frag(&Frag::from_xtext(t));
    }

    /// Writes multi-line text copied from the XML, each line after `indent`, dropping the
    /// indentation common to its lines and blank lines at either end.
    pub fn lines(&mut self, t: &XText, indent: &str) {
        for line in block_lines(t) {
            if line.text.trim().is_empty() {
                self.out.push('\n');
            } else {
                self.out.push_str(indent);
                self.xtext(&line);
                self.out.push('\n');
            }
        }
    }

    /// Inserts `s` at byte `at` of the text written so far, moving what follows (and its map).
    pub fn insert(&mut self, at: usize, s: &str) {
        if s.is_empty() || at > self.out.len() {
            return;
        }
        self.out.insert_str(at, s);
        let (at, n) = (at as u32, s.len() as u32);
        for e in &mut self.entries {
            if e.text.start >= at {
                e.text.start += n;
            }
            if e.text.end > at || (e.text.end == at && e.text.start > at) {
                e.text.end += n;
            }
        }
        for (_, start) in &mut self.stack {
            if *start > at {
                *start += n;
            }
        }
    }

    /// Appends text written by another emitter (with its map) at the current end.
    pub fn append(&mut self, other: Emitter) {
        let base = self.out.len() as u32;
        let (text, map) = other.finish();
        self.out.push_str(&text);
        self.entries.extend(map.entries.into_iter().map(|e| MapEntry {
            text: e.text.start + base..e.text.end + base,
            xml: e.xml,
            exact: e.exact,
        }));
    }

    pub fn finish(mut self) -> (String, SourceMap) {
        while self.stack.len() > 1 {
            self.close();
        }
        if let Some((xml, _)) = self.stack.pop() {
            self.entries.push(MapEntry { text: 0..self.out.len() as u32, xml, exact: false });
        }
        let mut entries = self.entries;
        entries.sort_by(|a, b| {
            (a.text.start, std::cmp::Reverse(a.text.end)).cmp(&(b.text.start, std::cmp::Reverse(b.text.end)))
        });
        (self.out, SourceMap { entries })
    }
}

/// The lines of a block of text without common indentation and blank lines at either end, each
/// line without its line break (and without trailing white space).
pub fn block_lines(t: &XText) -> Vec<XText> {
    let text = &t.text;
    let mut lines: Vec<(usize, usize)> = Vec::new();
    let mut start = 0;
    for (i, b) in text.bytes().enumerate() {
        if b == b'\n' {
            lines.push((start, i));
            start = i + 1;
        }
    }
    lines.push((start, text.len()));
    while lines.first().is_some_and(|&(s, e)| text[s..e].trim().is_empty()) {
        lines.remove(0);
    }
    while lines.last().is_some_and(|&(s, e)| text[s..e].trim().is_empty()) {
        lines.pop();
    }
    let common = lines
        .iter()
        .filter(|&&(s, e)| !text[s..e].trim().is_empty())
        .map(|&(s, e)| text[s..e].len() - text[s..e].trim_start_matches([' ', '\t']).len())
        .min()
        .unwrap_or(0);
    lines
        .into_iter()
        .map(|(s, e)| {
            let line = &text[s..e];
            let trimmed_end = line.trim_end().len();
            let from = (s + common).min(s + trimmed_end);
            t.slice(from..s + trimmed_end)
        })
        .collect()
}
