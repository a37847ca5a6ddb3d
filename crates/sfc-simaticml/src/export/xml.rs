//! A small XML writer: indented elements, escaped text and attribute values.

pub(crate) struct W {
    pub s: String,
    depth: usize,
}

pub(crate) fn esc(v: &str) -> String {
    sfc_xmlmap::xml::escape_attr(v)
}

fn attrs(a: &[(&str, String)]) -> String {
    a.iter().map(|(k, v)| format!(" {k}=\"{}\"", esc(v))).collect()
}

impl W {
    pub fn new() -> W {
        W { s: String::new(), depth: 0 }
    }
    fn indent(&mut self) {
        for _ in 0..self.depth {
            self.s.push_str("  ");
        }
    }
    pub fn open(&mut self, name: &str, a: &[(&str, String)]) {
        self.indent();
        self.s.push_str(&format!("<{name}{}>\n", attrs(a)));
        self.depth += 1;
    }
    pub fn close(&mut self, name: &str) {
        self.depth = self.depth.saturating_sub(1);
        self.indent();
        self.s.push_str(&format!("</{name}>\n"));
    }
    pub fn empty(&mut self, name: &str, a: &[(&str, String)]) {
        self.indent();
        self.s.push_str(&format!("<{name}{} />\n", attrs(a)));
    }
    /// `<name a="…">text</name>` on one line.
    pub fn leaf(&mut self, name: &str, a: &[(&str, String)], text: &str) {
        self.indent();
        self.s.push_str(&format!("<{name}{}>{}</{name}>\n", attrs(a), esc(text)));
    }
    /// A line of raw XML at the current depth.
    pub fn raw(&mut self, line: &str) {
        self.indent();
        self.s.push_str(line);
        self.s.push('\n');
    }
    /// A multilingual text (`lang: text` lines, or one text in en-US) as `MultiLanguageText`s.
    pub fn texts(&mut self, name: &str, v: &str) {
        self.open(name, &[]);
        for (lang, t) in split_langs(v) {
            self.leaf("MultiLanguageText", &[("Lang", lang)], &t);
        }
        self.close(name);
    }
}

/// `de-DE: a\nen-US: b` → its languages; any other text is one en-US text.
fn split_langs(v: &str) -> Vec<(String, String)> {
    let lines: Vec<&str> = v.lines().collect();
    let parsed: Vec<(String, String)> = lines
        .iter()
        .filter_map(|l| {
            let (lang, t) = l.split_once(": ")?;
            let ok = lang.len() >= 2 && lang.len() <= 12 && lang.chars().all(|c| c.is_ascii_alphabetic() || c == '-');
            ok.then(|| (lang.to_string(), t.to_string()))
        })
        .collect();
    if lines.len() > 1 && parsed.len() == lines.len() {
        parsed
    } else {
        vec![("en-US".to_string(), v.to_string())]
    }
}
