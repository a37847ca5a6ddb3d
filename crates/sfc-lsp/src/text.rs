//! Positions: byte offsets (what spans hold) to LSP positions (line and UTF-16 code unit, what
//! the protocol speaks) and back, and incremental edits of a document's text.

use lsp_types::{Position, Range, TextDocumentContentChangeEvent};

/// The start of every line of a text, for offset ↔ position conversion.
#[derive(Debug, Clone)]
pub struct LineIndex {
    line_starts: Vec<u32>,
    len: u32,
}

impl LineIndex {
    pub fn new(text: &str) -> LineIndex {
        let mut line_starts = vec![0u32];
        for (i, b) in text.bytes().enumerate() {
            if b == b'\n' {
                line_starts.push(i as u32 + 1);
            }
        }
        LineIndex { line_starts, len: text.len() as u32 }
    }

    /// The LSP position of a byte offset (clamped into the text, moved back to a character
    /// boundary). Columns count UTF-16 code units, as the protocol requires by default.
    pub fn position(&self, text: &str, offset: u32) -> Position {
        let mut offset = offset.min(self.len) as usize;
        while offset > 0 && !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = match self.line_starts.binary_search(&(offset as u32)) {
            Ok(i) => i,
            Err(i) => i.saturating_sub(1),
        };
        let start = self.line_starts.get(line).map_or(0, |&s| s as usize);
        let column: usize = text.get(start..offset).map_or(0, |s| s.chars().map(char::len_utf16).sum());
        Position::new(line as u32, column as u32)
    }

    /// The byte offset of an LSP position; a column past the end of its line is the end of the
    /// line, a line past the end is the end of the text.
    pub fn offset(&self, text: &str, pos: Position) -> u32 {
        let Some(&start) = self.line_starts.get(pos.line as usize) else { return self.len };
        let end = self.line_starts.get(pos.line as usize + 1).map_or(self.len, |&e| e);
        let line = text.get(start as usize..end as usize).unwrap_or("");
        let mut units = 0u32;
        for (i, c) in line.char_indices() {
            if units >= pos.character || c == '\n' || (c == '\r' && line.get(i + 1..) == Some("\n")) {
                return start + i as u32;
            }
            units += c.len_utf16() as u32;
        }
        end
    }

    pub fn range(&self, text: &str, start: u32, end: u32) -> Range {
        Range::new(self.position(text, start), self.position(text, end))
    }

    /// The byte range of an LSP range (end never before start).
    pub fn offsets(&self, text: &str, range: Range) -> (u32, u32) {
        let s = self.offset(text, range.start);
        let e = self.offset(text, range.end);
        (s.min(e), e.max(s))
    }

    pub fn line_count(&self) -> u32 {
        self.line_starts.len() as u32
    }

    /// The byte offset where a 0-based line starts.
    pub fn line_start(&self, line: u32) -> u32 {
        self.line_starts.get(line as usize).copied().unwrap_or(self.len)
    }
}

/// Applies the changes of a `textDocument/didChange` in order (ranged or whole-text changes).
pub fn apply_changes(text: &mut String, changes: Vec<TextDocumentContentChangeEvent>) -> Option<Vec<Edit>> {
    let mut edits = Some(Vec::new());
    for change in changes {
        match change.range {
            None => {
                *text = change.text;
                edits = None;
            }
            Some(range) => {
                let index = LineIndex::new(text);
                let (s, e) = index.offsets(text, range);
                text.replace_range(s as usize..e as usize, &change.text);
                if let Some(list) = edits.as_mut() {
                    list.push(Edit { start: s, end: e, len: change.text.len() as u32 });
                }
            }
        }
    }
    edits
}

/// One replacement made in a text: bytes `start..end` of the text as it was became `len` bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edit {
    pub start: u32,
    pub end: u32,
    pub len: u32,
}

/// The edits made to a text since it was analysed, in order: maps offsets between the analysed
/// text and the current one.
#[derive(Debug, Clone, Copy)]
pub struct Shift<'a>(pub &'a [Edit]);

impl Shift<'_> {
    /// Analysed → current: an offset after an edit moves with it; one inside a replaced piece
    /// goes to its start.
    pub fn forward(&self, mut offset: u32) -> u32 {
        for e in self.0 {
            if offset >= e.end {
                offset = offset - (e.end - e.start) + e.len;
            } else if offset > e.start {
                offset = e.start;
            }
        }
        offset
    }

    /// Current → analysed: an offset inside an inserted piece goes to the end of what it
    /// replaced (where the typing happened).
    pub fn backward(&self, mut offset: u32) -> u32 {
        for e in self.0.iter().rev() {
            let new_end = e.start + e.len;
            if offset >= new_end {
                offset = offset - e.len + (e.end - e.start);
            } else if offset > e.start {
                offset = e.end;
            }
        }
        offset
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utf16_columns() {
        let text = "a\nžluť 😀 x\r\nend";
        let idx = LineIndex::new(text);
        let x = text.find('x').unwrap() as u32;
        // ž l u ť space (5) + 😀 (2 UTF-16 units) + space = 8
        assert_eq!(idx.position(text, x), Position::new(1, 8));
        assert_eq!(idx.offset(text, Position::new(1, 8)), x);
        // Past the end of a line: the line break.
        assert_eq!(idx.offset(text, Position::new(1, 99)), text.find("\r\n").unwrap() as u32);
        assert_eq!(idx.offset(text, Position::new(9, 0)), text.len() as u32);
        assert_eq!(idx.position(text, 999), Position::new(2, 3));
    }

    #[test]
    fn shifts_between_the_analysed_and_the_current_text() {
        // "abc def" → insert "XY" at 4 → "abc XYdef" → delete 0..1 → "bc XYdef"
        let edits = [Edit { start: 4, end: 4, len: 2 }, Edit { start: 0, end: 1, len: 0 }];
        let shift = Shift(&edits);
        assert_eq!(shift.forward(4), 5); // "d" of "def"
        assert_eq!(shift.forward(0), 0);
        assert_eq!(shift.forward(2), 1);
        assert_eq!(shift.backward(5), 4);
        assert_eq!(shift.backward(4), 4); // inside "XY": where it was typed
        assert_eq!(shift.backward(1), 2);
    }

    #[test]
    fn incremental_changes() {
        let mut text = String::from("STEP S1: END_STEP\nSTEP S2: END_STEP\n");
        apply_changes(
            &mut text,
            vec![
                TextDocumentContentChangeEvent {
                    range: Some(Range::new(Position::new(1, 5), Position::new(1, 7))),
                    range_length: None,
                    text: "Fill".into(),
                },
                TextDocumentContentChangeEvent {
                    range: Some(Range::new(Position::new(0, 0), Position::new(0, 0))),
                    range_length: None,
                    text: "INITIAL_".into(),
                },
            ],
        );
        assert_eq!(text, "INITIAL_STEP S1: END_STEP\nSTEP Fill: END_STEP\n");
    }
}
