//! Text files as people have them: a UTF-8 byte order mark (Windows editors, vendor exports),
//! Latin-1 / Windows-1252 instead of UTF-8 (older tools, German and Czech comments), UTF-16
//! (Notepad's "Unicode", Windows PowerShell's `>`, XML declared `encoding="utf-16"`), CRLF line
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
    /// UTF-16 little-endian: a file that starts with the BOM `FF FE`, or without a BOM whose
    /// first two characters are ASCII (`P\0R\0`). An unpaired surrogate reads as U+FFFD.
    Utf16Le,
    /// UTF-16 big-endian (`FE FF`, or `\0P\0R`).
    Utf16Be,
}

/// A file's text and how it was written.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Decoded {
    /// The text, without the byte order mark.
    pub text: String,
    pub encoding: Encoding,
    /// The file started with a byte order mark (UTF-8's, or UTF-16's for the UTF-16 encodings).
    pub bom: bool,
    /// The file's line breaks are CRLF (its first line break is).
    pub crlf: bool,
    /// For [`Encoding::Windows1252`]: the 1-based line of the first byte that is not UTF-8, and
    /// that byte's offset in `text`. For UTF-16: the same of the first broken character (an
    /// unpaired surrogate, an odd last byte), read as U+FFFD.
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

/// Reads a text file's bytes: UTF-16 when it says so (a BOM) or looks so (ASCII with every
/// other byte 0), else UTF-8 (with or without a BOM), else Windows-1252.
pub fn decode(bytes: &[u8]) -> Decoded {
    if let Some(d) = decode_utf16(bytes) {
        return d;
    }
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
    if like.bom && matches!(like.encoding, Encoding::Utf8 | Encoding::Windows1252) {
        out.extend_from_slice(BOM);
    }
    let mut lost = 0;
    match like.encoding {
        Encoding::Utf16Le | Encoding::Utf16Be => {
            let le = like.encoding == Encoding::Utf16Le;
            if like.bom {
                out.extend_from_slice(if le { b"\xFF\xFE" } else { b"\xFE\xFF" });
            }
            for u in text.encode_utf16() {
                out.extend_from_slice(&if le { u.to_le_bytes() } else { u.to_be_bytes() });
            }
        }
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

/// UTF-16, by its BOM or by ASCII characters with every other byte 0 at the start.
fn decode_utf16(bytes: &[u8]) -> Option<Decoded> {
    let (encoding, bom, body) = match bytes {
        [0xFF, 0xFE, rest @ ..] => (Encoding::Utf16Le, true, rest),
        [0xFE, 0xFF, rest @ ..] => (Encoding::Utf16Be, true, rest),
        [a, 0, b, 0, ..] if a.is_ascii() && *a != 0 && b.is_ascii() && *b != 0 => (Encoding::Utf16Le, false, bytes),
        [0, a, 0, b, ..] if a.is_ascii() && *a != 0 && b.is_ascii() && *b != 0 => (Encoding::Utf16Be, false, bytes),
        _ => return None,
    };
    let units = body.chunks_exact(2).map(|p| match (encoding, p) {
        (Encoding::Utf16Le, [lo, hi]) => u16::from_le_bytes([*lo, *hi]),
        (_, [hi, lo]) => u16::from_be_bytes([*hi, *lo]),
        _ => 0xFFFD,
    });
    let mut text = String::with_capacity(body.len() / 2);
    let mut broken = None;
    let mut line = 1;
    let mut replace = |text: &mut String, line: u32| {
        broken.get_or_insert((line, text.len() as u32));
        text.push(char::REPLACEMENT_CHARACTER);
    };
    for c in char::decode_utf16(units) {
        match c {
            Ok(c) => {
                line += u32::from(c == '\n');
                text.push(c);
            }
            Err(_) => replace(&mut text, line),
        }
    }
    if !body.len().is_multiple_of(2) {
        replace(&mut text, line);
    }
    let crlf = text.find('\n').is_some_and(|i| i > 0 && text.as_bytes().get(i - 1) == Some(&b'\r'));
    Some(Decoded { text, encoding, bom, crlf, first_non_utf8: broken })
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

/// How far into a text [`binary_error`] looks for a NUL (as git does to tell binary files).
const BINARY_PROBE: usize = 8000;

/// The offset of a NUL within the first [`BINARY_PROBE`] bytes: the text is a binary file's.
fn first_nul(text: &str) -> Option<usize> {
    text.bytes().take(BINARY_PROBE).position(|b| b == 0)
}

/// The error for a file that is not text at all (SFC0012): a NUL character near its start, as
/// a vendor's binary project file has. `None` for text.
pub fn binary_error(file: u32, text: &str) -> Option<Diagnostic> {
    let at = first_nul(text)? as u32;
    Some(
        Diagnostic::error("SFC0012", Span::new(file, at, at + 1), "the file is binary, not text: it holds a NUL byte")
            .with_note("sfc reads IEC 61131-3 text and PLCopen XML")
            .with_note(
                "a vendor's project file (a CODESYS `.project`, for one) is binary: export the POU as PLCopen \
                 XML from that tool (in CODESYS: Project > Export PLCopenXML...) and give sfc that file",
            ),
    )
}

/// The warning for a file read as Windows-1252 (SFC0011), naming its first non-UTF-8 line.
/// None for a binary file: [`binary_error`] says what is wrong with it.
pub fn warning(file: u32, d: &Decoded) -> Option<Diagnostic> {
    if first_nul(&d.text).is_some() {
        return None;
    }
    let (line, offset) = d.first_non_utf8?;
    if matches!(d.encoding, Encoding::Utf16Le | Encoding::Utf16Be) {
        return Some(
            Diagnostic::warning(
                "SFC0011",
                Span::new(file, offset, offset + char::REPLACEMENT_CHARACTER.len_utf8() as u32),
                format!("the file is UTF-16 with a broken character on line {line}: read as U+FFFD"),
            )
            .with_note("`sfc fmt` and the editor would write U+FFFD back in its place"),
        );
    }
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
    fn utf16_with_and_without_bom_round_trips() {
        let text = "PROGRAM P (* Ventil öffnen, žluťoučký 🚰 *)\r\nEND_PROGRAM\r\n";
        for (encoding, bom) in [
            (Encoding::Utf16Le, true),
            (Encoding::Utf16Be, true),
            (Encoding::Utf16Le, false),
            (Encoding::Utf16Be, false),
        ] {
            let like = Decoded { encoding, bom, crlf: true, ..Decoded::default() };
            let (bytes, lost) = encode(text, &like);
            assert_eq!(lost, 0);
            let d = decode(&bytes);
            assert_eq!((d.encoding, d.bom, d.crlf), (encoding, bom, true), "{encoding:?} {bom}");
            assert_eq!(d.text, text);
            assert_eq!(d.first_non_utf8, None);
            assert_eq!(encode(&d.text, &d).0, bytes);
        }
        // Notepad's "Unicode": the BOM FF FE.
        assert_eq!(decode(b"\xFF\xFEP\0\n\0").text, "P\n");
        // A broken surrogate and an odd last byte read as U+FFFD, never a panic, and are said.
        let d = decode(b"\xFF\xFEA\0\n\0\x00\xD8P\0\x01");
        assert_eq!(d.text, "A\n\u{FFFD}P\u{FFFD}");
        assert_eq!(d.first_non_utf8, Some((2, 2)));
        let w = warning(0, &d).expect("a warning");
        assert!(w.message.contains("UTF-16 with a broken character on line 2"), "{}", w.message);
        assert_eq!(&d.text[w.span.start as usize..w.span.end as usize], "\u{FFFD}");
    }

    #[test]
    fn every_byte_decodes_and_encodes_back() {
        let bytes: Vec<u8> = (0..=255u8).collect();
        let d = decode(&bytes);
        assert_eq!(encode(&d.text, &d).0, bytes);
    }
}
