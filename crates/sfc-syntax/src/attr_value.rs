//! Values of attribute pragmas (`{attribute 'sfc.description' := '…'}`). A pragma has no escape
//! syntax of its own and ends at a quote (or the closing brace), so tools that write arbitrary
//! text into one (the editor's document, the PLCopen import) use IEC string escapes: `$$`, `$27`
//! for a quote, `$7D` for `}`, `$N`, `$R`, `$T`.

/// Writes a value so it survives inside `'…'` of an attribute pragma.
pub fn escape(v: &str) -> String {
    let mut out = String::with_capacity(v.len());
    for c in v.chars() {
        match c {
            '$' => out.push_str("$$"),
            '\'' => out.push_str("$27"),
            '\n' => out.push_str("$N"),
            '\r' => out.push_str("$R"),
            '\t' => out.push_str("$T"),
            '}' => out.push_str("$7D"),
            _ => out.push(c),
        }
    }
    out
}

/// Reads a value written by [`escape`]; a `$` not starting a known escape is kept as it is.
pub fn unescape(v: &str) -> String {
    let mut out = String::with_capacity(v.len());
    let mut it = v.char_indices().peekable();
    while let Some((i, c)) = it.next() {
        if c != '$' {
            out.push(c);
            continue;
        }
        let rest = &v[i + 1..];
        let (rep, skip) = match rest.chars().next() {
            Some('$') => ('$', 1),
            Some('N' | 'n' | 'L' | 'l') => ('\n', 1),
            Some('R' | 'r') => ('\r', 1),
            Some('T' | 't') => ('\t', 1),
            _ => match rest.get(..2).and_then(|h| u8::from_str_radix(h, 16).ok()) {
                Some(b) if b.is_ascii() => (b as char, 2),
                _ => ('$', 0),
            },
        };
        out.push(rep);
        for _ in 0..skip {
            it.next();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escaped_values_read_back_and_never_end_the_pragma() {
        for v in ["", "plain", "it's $5 {x}\n\ttab\r", "$$$", "'}'", "Ünïcode ✓ $N"] {
            let e = escape(v);
            assert!(!e.contains('\'') && !e.contains('}') && !e.contains('\n'), "{e:?}");
            assert_eq!(unescape(&e), v);
        }
        // A `$` that starts no escape is kept.
        assert_eq!(unescape("cost $x"), "cost $x");
        assert_eq!(unescape("$41$l"), "A\n");
    }
}
