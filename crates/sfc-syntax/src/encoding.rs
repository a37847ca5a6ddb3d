//! Text files as people have them: a UTF-8 byte order mark (Windows editors, vendor exports),
//! Latin-1 / Windows-1252 instead of UTF-8 (older tools, German and Czech comments), CRLF line
//! endings. [`decode`] reads any byte sequence into text and remembers how it was written;
//! [`encode`] writes text back the same way, so `sfc fmt` and the editor's save keep a file's
//! BOM, encoding and line endings.
//!
//! Windows-1252 is decoded by hand (the 32 code points of 0x80–0x9F that differ from Latin-1,
//! then Latin-1): one small table, instead of a dependency on a general encoding library.

use sfc_diagnostics::{Diagnostic, Span};

/// How a text file's bytes encode its characters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Encoding {
    #[default]
    Utf8,
    /// Windows-1252, a superset of the printable Latin-1 (ISO 8859-1).
    Windows1252,
}

/// A file's text and how it was written.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Decoded {
    /// The text, without the byte order mark.
    pub text: String,
    pub encoding: Encoding,
    /// The file started with a UTF-8 byte order mark.
    pub bom: bool,
    /// The file's line breaks are CRLF (its first line break is).
    pub crlf: bool,
    /// For [`Encoding::Windows1252`]: the 1-based line of the first byte that is not UTF-8, and
    /// that byte's offset in `text`.
    pub first_non_utf8: Option<(u32, u32)>,
}

const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Windows-1252 code points of 0x80..=0x9F (0 where the byte is undefined: kept as the C1
/// control of the same value, as Latin-1 has it).
const CP1252_HIGH: [u16; 32] = [
    0x20AC, 0, 0x201A, 0x0192, 0x201E, 0x2026, 0x2020, 0x2021, 0x02C6, 0x2030, 0x0160, 0x2039, 0x0152, 0, 0x017D, 0, 0,
    0x2018, 0x2019, 0x201C, 0x201D, 0x2022, 0x2013, 0x2014, 0x02DC, 0x2122, 0x0161, 0x203A, 0x0153, 0, 0x017E, 0x0178,
];

fn cp1252_char(b: u8) -> char {
    match b {
        0x80..=0x9F => match CP1252_HIGH.get((b - 0x80) as usize).copied().unwrap_or(0) {
            0 => char::from(b),
            c => char::from_u32(c as u32).unwrap_or(char::from(b)),
        },
        _ => char::from(b),
    }
}

fn cp1252_byte(c: char) -> Option<u8> {
    let u = c as u32;
    if u < 0x80 || (0xA0..=0xFF).contains(&u) {
        return Some(u as u8);
    }
    if let Some(i) = CP1252_HIGH.iter().position(|&x| x as u32 == u && x != 0) {
        return Some(0x80 + i as u8);
    }
    // The undefined bytes decode to the C1 control of the same value.
    if (0x80..=0x9F).contains(&u) && CP1252_HIGH.get((u - 0x80) as usize) == Some(&0) {
        return Some(u as u8);
    }
    None
}

/// Reads a text file's bytes: UTF-8 (with or without a BOM), else Windows-1252.
pub fn decode(bytes: &[u8]) -> Decoded {
    let (bom, body) = match bytes.strip_prefix(BOM) {
        Some(rest) => (true, rest),
        None => (false, bytes),
    };
    let crlf = body.iter().position(|&b| b == b'\n').is_some_and(|i| i > 0 && body.get(i - 1) == Some(&b'\r'));
    match std::str::from_utf8(body) {
        Ok(t) => Decoded { text: t.to_string(), encoding: Encoding::Utf8, bom, crlf, first_non_utf8: None },
        Err(e) => {
            let valid = body.get(..e.valid_up_to()).unwrap_or_default();
            let line = 1 + valid.iter().filter(|&&b| b == b'\n').count() as u32;
            let text: String = body.iter().map(|&b| cp1252_char(b)).collect();
            let offset = valid.iter().map(|&b| cp1252_char(b).len_utf8()).sum::<usize>() as u32;
            Decoded { text, encoding: Encoding::Windows1252, bom, crlf, first_non_utf8: Some((line, offset)) }
        }
    }
}

/// Writes `text` the way `like` was written: its encoding, its BOM, and CRLF line breaks if it
/// had them (lone `\n` become `\r\n`). A character Windows-1252 cannot hold is written as `?`;
/// the count of such characters is returned with the bytes.
pub fn encode(text: &str, like: &Decoded) -> (Vec<u8>, usize) {
    let text = if like.crlf { to_crlf(text) } else { text.to_string() };
    let mut out = Vec::with_capacity(text.len() + 3);
    if like.bom {
        out.extend_from_slice(BOM);
    }
    let mut lost = 0;
    match like.encoding {
        Encoding::Utf8 => out.extend_from_slice(text.as_bytes()),
        Encoding::Windows1252 => {
            for c in text.chars() {
                match cp1252_byte(c) {
                    Some(b) => out.push(b),
                    None => {
                        out.push(b'?');
                        lost += 1;
                    }
                }
            }
        }
    }
    (out, lost)
}

/// `\n` line breaks as `\r\n` (those already `\r\n` kept).
pub fn to_crlf(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + text.len() / 32);
    let mut prev = '\0';
    for c in text.chars() {
        if c == '\n' && prev != '\r' {
            out.push('\r');
        }
        out.push(c);
        prev = c;
    }
    out
}

/// The warning for a file read as Windows-1252 (SFC0011), naming its first non-UTF-8 line.
pub fn warning(file: u32, d: &Decoded) -> Option<Diagnostic> {
    let (line, offset) = d.first_non_utf8?;
    let end =
        d.text.get(offset as usize..).and_then(|t| t.chars().next()).map_or(offset, |c| offset + c.len_utf8() as u32);
    Some(
        Diagnostic::warning(
            "SFC0011",
            Span::new(file, offset, end),
            format!(
                "the file is not UTF-8: read as Latin-1 / Windows-1252 (line {line} is the first that is not UTF-8)"
            ),
        )
        .with_note("`sfc fmt` and the editor write it back in the same encoding; save it as UTF-8 to silence this"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utf8_with_bom_and_crlf_round_trips() {
        let bytes = b"\xEF\xBB\xBFPROGRAM P\r\nEND_PROGRAM\r\n";
        let d = decode(bytes);
        assert!(d.bom && d.crlf && d.encoding == Encoding::Utf8);
        assert_eq!(d.text, "PROGRAM P\r\nEND_PROGRAM\r\n");
        assert_eq!(encode("PROGRAM P\nEND_PROGRAM\n", &d).0, bytes.to_vec());
    }

    #[test]
    fn latin1_is_read_with_its_line_and_written_back() {
        let bytes = b"(* ok *)\n(* Ventil \xF6ffnen \x80 *)\n";
        let d = decode(bytes);
        assert_eq!(d.encoding, Encoding::Windows1252);
        assert_eq!(d.text, "(* ok *)\n(* Ventil öffnen € *)\n");
        assert_eq!(d.first_non_utf8.map(|f| f.0), Some(2));
        let w = warning(0, &d).expect("a warning");
        assert!(w.message.contains("line 2"), "{}", w.message);
        assert_eq!(&d.text[w.span.start as usize..w.span.end as usize], "ö");
        assert_eq!(encode(&d.text, &d), (bytes.to_vec(), 0));
        assert_eq!(encode("ř", &d), (b"?".to_vec(), 1));
    }

    #[test]
    fn every_byte_decodes_and_encodes_back() {
        let bytes: Vec<u8> = (0..=255u8).collect();
        let d = decode(&bytes);
        assert_eq!(encode(&d.text, &d).0, bytes);
    }
}
