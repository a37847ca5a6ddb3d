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

/// The POU attribute that holds one transition drawn but not connected on both sides (a chart
/// being drawn, as Beremiz and CODESYS save it). IEC text has no place for such a transition, so
/// the PLCopen import writes it here, the editor draws it (and keeps it in `sfc.graph` when it
/// saves) and the PLCopen export writes it back; the chart itself does not hold it.
pub const LOOSE: &str = "sfc.loose";

/// One unconnected transition (`sfc.loose`): its box (when known), the steps wired to it on
/// each side (one side at most), its name (empty: unnamed) and its condition as ST.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Loose {
    pub rect: Option<[f64; 4]>,
    pub from: Vec<String>,
    pub to: Vec<String>,
    pub name: String,
    pub condition: String,
}

impl Loose {
    /// The value, before [`escape`]: `x y w h` (or nothing), then lines `FROM …`, `TO …`,
    /// `NAME …`, then the condition (which may span lines).
    pub fn write(&self) -> String {
        let rect = self.rect.map(|r| r.map(|v| v.to_string()).join(" ")).unwrap_or_default();
        let names = |l: &[String]| l.iter().map(|n| format!(" {n}")).collect::<String>();
        format!("{rect}\nFROM{}\nTO{}\nNAME {}\n{}", names(&self.from), names(&self.to), self.name, self.condition)
    }

    /// Reads a value written by [`Loose::write`] (after [`unescape`]); `None` when it is not one.
    pub fn read(v: &str) -> Option<Loose> {
        let mut lines = v.splitn(5, '\n');
        let head = lines.next()?.trim();
        let rect = if head.is_empty() {
            None
        } else {
            let n: Vec<f64> = head
                .split_whitespace()
                .map(|p| p.parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect::<Option<_>>()?;
            Some(<[f64; 4]>::try_from(n).ok()?)
        };
        let list = |l: &str, key: &str| -> Option<Vec<String>> {
            Some(l.strip_prefix(key)?.split_whitespace().map(str::to_string).collect())
        };
        let from = list(lines.next()?, "FROM")?;
        let to = list(lines.next()?, "TO")?;
        let name = lines.next()?.strip_prefix("NAME")?.trim().to_string();
        let condition = lines.next().unwrap_or("").to_string();
        Some(Loose { rect, from, to, name, condition })
    }
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

    #[test]
    fn loose_transitions_read_back() {
        let l = Loose {
            rect: Some([370.0, 100.5, 20.0, 2.0]),
            from: vec![],
            to: vec!["Draining".into()],
            name: "".into(),
            condition: "Level > 80 (* high\nwater *)".into(),
        };
        assert_eq!(Loose::read(&unescape(&escape(&l.write()))), Some(l));
        let bare = Loose { from: vec!["A".into(), "B".into()], ..Loose::default() };
        assert_eq!(Loose::read(&bare.write()), Some(bare));
        assert_eq!(Loose::read("1 2 3\nFROM\nTO\nNAME\n"), None);
        assert_eq!(Loose::read("garbage"), None);
    }
}
