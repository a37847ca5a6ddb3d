//! The property file (`<chart>.props.toml`): what the environment may do (`[assume]`) and the
//! requirements (`[[property]]`). Parsing keeps the position of every value, so errors name the
//! file, line and column, and errors inside an expression point into the string.
//!
//! ```toml
//! pou = "Door"                    # optional: the POU (as `--pou`)
//! period = "T#10ms"               # optional: the scan period (as `--period`)
//! profile = "codesys"             # optional: iec (default) or codesys (as `--profile`)
//!
//! [assume]
//! always = ["NOT (LimitLeft AND LimitRight)"]
//! ranges = { Level = "0..100" }
//! inputs = ["SFCQuitError"]       # more free inputs (variables the code also writes)
//!
//! [[property]]
//! name = "never both directions"
//! always = "NOT (MotorFwd AND MotorRev)"
//!
//! [[property]]
//! name = "door closes in time"
//! after = "DoorCmd"
//! expect = "DoorClosed"
//! within = "T#5s"                  # or scans = 50
//!
//! [[property]]
//! name = "back to idle"
//! reachable = "Idle.X"
//! from_initial = false
//!
//! [[property]]
//! name = "no spurious stroke"
//! never = "Press.X AND NOT GuardClosed"
//! ```

use sfc_sim::scenario::type_name;
use sfc_syntax::ast::Expr;
use std::fmt;
use std::ops::Range;
use toml_edit::{Item, TableLike};

/// A located problem in the property file (or in the chart it names).
#[derive(Debug, Clone, PartialEq)]
pub struct PropsError {
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub message: String,
}

impl fmt::Display for PropsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: {}", self.file, self.line, self.column, self.message)
    }
}

/// A string value of the file with where it starts (the first character after the quote).
#[derive(Debug, Clone, PartialEq)]
pub struct Located {
    pub text: String,
    /// Byte offset in the file of the value's first character (inside the quotes), and whether
    /// offsets inside the string map one to one (no escapes).
    pub offset: usize,
    pub exact: bool,
    pub line: u32,
    pub column: u32,
}

/// An ST expression of the file, parsed.
#[derive(Debug, Clone)]
pub struct PropExpr {
    pub src: Located,
    pub expr: Expr,
}

/// How long a response may take.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bound {
    Scans(u64),
    /// µs.
    Time(i64),
}

/// What a property requires.
#[derive(Debug, Clone)]
pub enum Kind {
    /// Holds after every scan.
    Always(PropExpr),
    /// Never holds after a scan.
    Never(PropExpr),
    /// Whenever `after` rises, `expect` holds within the bound (inclusive; the trigger scan
    /// itself counts).
    Response { after: PropExpr, expect: PropExpr, bound: Bound },
    /// From every reachable situation the goal can still be reached (AG EF), or only from the
    /// initial one (EF) with `from_initial`.
    Reachable { goal: PropExpr, from_initial: bool },
}

/// One `[[property]]`.
#[derive(Debug, Clone)]
pub struct Property {
    pub name: String,
    pub kind: Kind,
    pub line: u32,
    pub column: u32,
}

/// A value range of `[assume] ranges`.
#[derive(Debug, Clone)]
pub struct RangeSpec {
    pub name: Located,
    pub lo: i128,
    pub hi: i128,
    /// Written with TIME literals.
    pub time: bool,
}

/// The parsed file.
#[derive(Debug, Clone)]
pub struct PropertyFile {
    pub path: String,
    pub text: String,
    pub pou: Option<Located>,
    /// µs.
    pub period: Option<i64>,
    /// The profile (as `--profile`), with where it is written.
    pub profile: Option<(sfc_sim::Profile, Located)>,
    pub assume: Vec<PropExpr>,
    pub ranges: Vec<RangeSpec>,
    pub inputs: Vec<Located>,
    pub properties: Vec<Property>,
}

struct Src<'a> {
    file: &'a str,
    text: &'a str,
}

const TOP_KEYS: [&str; 5] = ["pou", "period", "profile", "assume", "property"];
const ASSUME_KEYS: [&str; 3] = ["always", "ranges", "inputs"];
const PROPERTY_KEYS: [&str; 10] =
    ["name", "always", "never", "after", "expect", "within", "scans", "reachable", "from_initial", "description"];

fn did_you_mean<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    match sfc_st::closest(name, candidates) {
        Some(c) => format!("; did you mean `{c}`?"),
        None => String::new(),
    }
}

impl Src<'_> {
    fn pos(&self, offset: usize) -> (u32, u32) {
        let offset = offset.min(self.text.len());
        let before = &self.text.as_bytes()[..offset];
        let line = before.iter().filter(|b| **b == b'\n').count() as u32 + 1;
        let start = before.iter().rposition(|b| *b == b'\n').map_or(0, |p| p + 1);
        let column = String::from_utf8_lossy(&before[start..]).chars().count() as u32 + 1;
        (line, column)
    }
    fn err(&self, span: Option<Range<usize>>, message: impl Into<String>) -> PropsError {
        let (line, column) = span.map_or((1, 1), |s| self.pos(s.start));
        PropsError { file: self.file.to_string(), line, column, message: message.into() }
    }
    fn key_span(&self, table: &dyn TableLike, key: &str) -> Option<Range<usize>> {
        table.key(key).and_then(|k| k.span()).or_else(|| table.get(key).and_then(Item::span))
    }
    /// A string value with its location.
    fn located(&self, v: &toml_edit::Value) -> Option<Located> {
        let s = v.as_str()?;
        let span = v.span();
        let (offset, exact) = match &span {
            Some(r) => {
                let raw = &self.text[r.clone()];
                // A basic or literal string without escapes maps one to one after its quote(s).
                let quote = if raw.starts_with("\"\"\"") || raw.starts_with("'''") { 3 } else { 1 };
                let exact = !raw.starts_with('"') || !raw.contains('\\');
                (r.start + quote, exact && !raw.starts_with("\"\"\"") && !raw.starts_with("'''"))
            }
            None => (0, false),
        };
        let (line, column) = self.pos(span.map_or(0, |r| r.start));
        Some(Located { text: s.to_string(), offset, exact, line, column })
    }
    fn string(&self, table: &dyn TableLike, key: &str, item: &Item, what: &str) -> Result<Located, PropsError> {
        match item.as_value().and_then(|v| self.located(v)) {
            Some(l) => Ok(l),
            None => Err(self.err(
                item.span().or_else(|| self.key_span(table, key)),
                format!("`{key}` must be a string ({what}), found {}", type_name(item)),
            )),
        }
    }
    fn time(&self, table: &dyn TableLike, key: &str, item: &Item) -> Result<i64, PropsError> {
        let s = self.string(table, key, item, "a TIME literal such as \"T#5s\"")?;
        sfc_sim::parse_time(&s.text).ok_or_else(|| {
            self.err(
                item.span(),
                format!("`{key}`: `{}` is not a TIME literal (write e.g. \"T#5s\" or \"T#1s500ms\")", s.text),
            )
        })
    }
    /// Parses an ST expression from a located string; errors point into the string.
    fn expr(&self, l: &Located) -> Result<PropExpr, PropsError> {
        let (expr, diags) = sfc_syntax::parse_expression(1, &l.text);
        if let Some(d) = diags.iter().find(|d| d.is_error()) {
            return Err(self.at_expr(l, d.span.start as usize, d.message.clone()));
        }
        if l.text.trim().is_empty() {
            return Err(PropsError {
                file: self.file.to_string(),
                line: l.line,
                column: l.column,
                message: "the expression is empty".into(),
            });
        }
        Ok(PropExpr { src: l.clone(), expr })
    }
    fn at_expr(&self, l: &Located, inner: usize, message: String) -> PropsError {
        locate_in_string(self.file, self.text, l, inner, message)
    }
}

/// The position of byte `inner` of an expression string in the file.
pub fn locate_in_string(file: &str, text: &str, l: &Located, inner: usize, message: String) -> PropsError {
    if l.exact && l.offset > 0 {
        let src = Src { file, text };
        let (line, column) = src.pos(l.offset + inner.min(l.text.len()));
        return PropsError { file: file.to_string(), line, column, message };
    }
    PropsError { file: file.to_string(), line: l.line, column: l.column, message }
}

/// Parses the text of a property file.
pub fn parse(path: &str, text: &str) -> Result<PropertyFile, PropsError> {
    let src = Src { file: path, text };
    let doc = toml_edit::Document::parse(text.to_string())
        .map_err(|e| src.err(e.span(), format!("TOML syntax error: {}", e.message().trim())))?;
    let root: &dyn TableLike = doc.as_table();
    let mut out = PropertyFile {
        path: path.to_string(),
        text: text.to_string(),
        pou: None,
        period: None,
        profile: None,
        assume: Vec::new(),
        ranges: Vec::new(),
        inputs: Vec::new(),
        properties: Vec::new(),
    };
    for (key, item) in root.iter() {
        let span = src.key_span(root, key);
        match key {
            "pou" => out.pou = Some(src.string(root, key, item, "a POU name")?),
            "period" => {
                let t = src.time(root, key, item)?;
                if t <= 0 {
                    return Err(src.err(item.span(), "`period` must be positive"));
                }
                out.period = Some(t);
            }
            "profile" => {
                let l = src.string(root, key, item, "a profile name such as \"codesys\"")?;
                let Some(p) = sfc_sim::Profile::from_name(l.text.trim()) else {
                    return Err(src.err(item.span(), format!("unknown profile `{}` (expected iec or codesys)", l.text)));
                };
                out.profile = Some((p, l));
            }
            "assume" => {
                let Some(t) = item.as_table_like() else {
                    return Err(
                        src.err(span, format!("`assume` must be a table ([assume]), found {}", type_name(item)))
                    );
                };
                parse_assume(&src, t, &mut out)?;
            }
            "property" => parse_properties(&src, root, item, &mut out)?,
            other => {
                return Err(src.err(
                    span,
                    format!(
                        "unknown key `{other}` (expected pou, period, profile, [assume] or [[property]]){}",
                        did_you_mean(other, TOP_KEYS)
                    ),
                ))
            }
        }
    }
    Ok(out)
}

fn parse_assume(src: &Src<'_>, t: &dyn TableLike, out: &mut PropertyFile) -> Result<(), PropsError> {
    for (key, item) in t.iter() {
        let span = src.key_span(t, key);
        match key {
            "always" => {
                let list: Vec<&toml_edit::Value> = match item {
                    Item::Value(toml_edit::Value::Array(a)) => a.iter().collect(),
                    Item::Value(v @ toml_edit::Value::String(_)) => vec![v],
                    _ => {
                        return Err(src
                            .err(span, format!("`always` must be a list of ST conditions, found {}", type_name(item))))
                    }
                };
                for v in list {
                    let Some(l) = src.located(v) else {
                        return Err(src.err(v.span(), "each assumption must be a string with an ST condition"));
                    };
                    out.assume.push(src.expr(&l)?);
                }
            }
            "ranges" => {
                let Some(rt) = item.as_table_like() else {
                    return Err(src.err(
                        span,
                        format!("`ranges` must be a table such as {{ Level = \"0..100\" }}, found {}", type_name(item)),
                    ));
                };
                for (name, v) in rt.iter() {
                    let nspan = src.key_span(rt, name);
                    let (line, column) = nspan.clone().map_or((1, 1), |s| src.pos(s.start));
                    let nloc = Located {
                        text: name.to_string(),
                        offset: nspan.map_or(0, |s| s.start),
                        exact: false,
                        line,
                        column,
                    };
                    let (lo, hi, time) = parse_range(src, rt, name, v)?;
                    out.ranges.push(RangeSpec { name: nloc, lo, hi, time });
                }
            }
            "inputs" => {
                let Some(a) = item.as_array() else {
                    return Err(
                        src.err(span, format!("`inputs` must be a list of variable names, found {}", type_name(item)))
                    );
                };
                for v in a.iter() {
                    let Some(l) = src.located(v) else {
                        return Err(src.err(v.span(), "each input must be a variable name (a string)"));
                    };
                    out.inputs.push(l);
                }
            }
            other => {
                return Err(src.err(
                    span,
                    format!(
                        "unknown key `{other}` in [assume] (expected always, ranges or inputs){}",
                        did_you_mean(other, ASSUME_KEYS)
                    ),
                ))
            }
        }
    }
    Ok(())
}

/// `"0..100"`, `"-5..5"`, `"T#0s..T#10s"`, or `[0, 100]`.
fn parse_range(src: &Src<'_>, t: &dyn TableLike, name: &str, item: &Item) -> Result<(i128, i128, bool), PropsError> {
    let bad = |why: &str| {
        src.err(
            item.span().or_else(|| src.key_span(t, name)),
            format!("range of `{name}`: {why} (write \"LO..HI\", e.g. \"0..100\" or \"T#0s..T#10s\")"),
        )
    };
    if let Some(a) = item.as_array() {
        let v: Vec<i64> = a.iter().filter_map(|x| x.as_integer()).collect();
        if v.len() != 2 || a.len() != 2 {
            return Err(bad("expected two integers"));
        }
        if v[0] > v[1] {
            return Err(bad("the low end is above the high end"));
        }
        return Ok((v[0] as i128, v[1] as i128, false));
    }
    let Some(s) = item.as_str() else { return Err(bad("expected a string")) };
    let Some((a, b)) = s.split_once("..") else { return Err(bad("no `..`")) };
    let num = |x: &str| -> Option<(i128, bool)> {
        let x = x.trim().replace('_', "");
        if let Ok(v) = x.parse::<i128>() {
            return Some((v, false));
        }
        sfc_sim::parse_time(&x).map(|t| (t as i128, true))
    };
    let (Some((lo, t1)), Some((hi, t2))) = (num(a), num(b)) else {
        return Err(bad(&format!("`{s}` is not a range of integers or TIME literals")));
    };
    if t1 != t2 {
        return Err(bad("both ends must be integers or both TIME literals"));
    }
    if lo > hi {
        return Err(bad("the low end is above the high end"));
    }
    Ok((lo, hi, t1))
}

fn parse_properties(
    src: &Src<'_>,
    root: &dyn TableLike,
    item: &Item,
    out: &mut PropertyFile,
) -> Result<(), PropsError> {
    let mut tables: Vec<(&dyn TableLike, Option<Range<usize>>)> = Vec::new();
    match item {
        Item::ArrayOfTables(a) => {
            for t in a.iter() {
                tables.push((t, t.span()));
            }
        }
        Item::Value(toml_edit::Value::Array(a)) => {
            for v in a.iter() {
                match v.as_inline_table() {
                    Some(t) => tables.push((t, t.span())),
                    None => return Err(src.err(v.span(), "each property must be a table")),
                }
            }
        }
        _ => {
            return Err(src.err(
                src.key_span(root, "property"),
                format!("`property` must be an array of tables (write `[[property]]`), found {}", type_name(item)),
            ))
        }
    }
    for (table, span) in tables {
        let (line, column) = span.clone().map_or((1, 1), |s| src.pos(s.start));
        let mut name = None;
        let mut always = None;
        let mut never = None;
        let mut after = None;
        let mut expect = None;
        let mut within = None;
        let mut scans = None;
        let mut reachable = None;
        let mut from_initial = None;
        for (key, v) in table.iter() {
            let kspan = src.key_span(table, key);
            match key {
                "name" => name = Some(src.string(table, key, v, "the property's name")?),
                "description" => {
                    src.string(table, key, v, "a description")?;
                }
                "always" => always = Some((src.string(table, key, v, "an ST condition")?, kspan)),
                "never" => never = Some((src.string(table, key, v, "an ST condition")?, kspan)),
                "after" => after = Some((src.string(table, key, v, "an ST condition")?, kspan)),
                "expect" => expect = Some((src.string(table, key, v, "an ST condition")?, kspan)),
                "reachable" => reachable = Some((src.string(table, key, v, "an ST condition")?, kspan)),
                "within" => {
                    let t = src.time(table, key, v)?;
                    if t < 0 {
                        return Err(src.err(v.span(), "`within` must not be negative"));
                    }
                    within = Some((t, kspan));
                }
                "scans" => {
                    let Some(n) = v.as_integer() else {
                        return Err(src.err(v.span(), format!("`scans` must be an integer, found {}", type_name(v))));
                    };
                    if n < 0 {
                        return Err(src.err(v.span(), "`scans` must not be negative"));
                    }
                    scans = Some((n as u64, kspan));
                }
                "from_initial" => {
                    let Some(b) = v.as_bool() else {
                        return Err(src.err(v.span(), format!("`from_initial` must be true or false, found {}", type_name(v))));
                    };
                    from_initial = Some((b, kspan));
                }
                other => {
                    return Err(src.err(
                        kspan,
                        format!(
                            "unknown key `{other}` in a [[property]] (expected name and one of always, never, after/expect/within, reachable){}",
                            did_you_mean(other, PROPERTY_KEYS)
                        ),
                    ))
                }
            }
        }
        let Some(name) = name else {
            return Err(src.err(span, "a [[property]] needs a `name`"));
        };
        if let Some(prev) = out.properties.iter().find(|p| p.name.eq_ignore_ascii_case(&name.text)) {
            return Err(PropsError {
                file: src.file.to_string(),
                line: name.line,
                column: name.column,
                message: format!("the name `{}` is already used by the property at line {}", name.text, prev.line),
            });
        }
        if name.text.trim().is_empty() {
            return Err(PropsError {
                file: src.file.to_string(),
                line: name.line,
                column: name.column,
                message: "the property's name is empty".into(),
            });
        }
        let kinds = [always.is_some(), never.is_some(), after.is_some() || expect.is_some(), reachable.is_some()];
        let count = kinds.iter().filter(|k| **k).count();
        if count == 0 {
            return Err(src.err(
                span,
                format!("property `{}` says nothing to check: give `always`, `never`, `after` with `expect`, or `reachable`", name.text),
            ));
        }
        if count > 1 {
            return Err(src.err(
                span,
                format!("property `{}` mixes kinds: give one of `always`, `never`, `after`/`expect`, `reachable` per [[property]]", name.text),
            ));
        }
        let misplaced = |what: &str, sp: &Option<Range<usize>>| {
            Err(src.err(sp.clone(), format!("`{what}` belongs to a response property (`after` … `expect`)")))
        };
        if after.is_none() && expect.is_none() {
            if let Some((_, sp)) = &within {
                return misplaced("within", sp);
            }
            if let Some((_, sp)) = &scans {
                return misplaced("scans", sp);
            }
        }
        if reachable.is_none() {
            if let Some((_, sp)) = &from_initial {
                return Err(src.err(sp.clone(), "`from_initial` belongs to a `reachable` property"));
            }
        }
        let kind = if let Some((l, _)) = always {
            Kind::Always(src.expr(&l)?)
        } else if let Some((l, _)) = never {
            Kind::Never(src.expr(&l)?)
        } else if let Some((l, _)) = reachable {
            Kind::Reachable { goal: src.expr(&l)?, from_initial: from_initial.map(|f| f.0).unwrap_or(false) }
        } else {
            let Some((a, _)) = after else {
                return Err(
                    src.err(span, format!("property `{}` has `expect` without `after` (the trigger)", name.text))
                );
            };
            let Some((e, _)) = expect else {
                return Err(
                    src.err(span, format!("property `{}` has `after` without `expect` (the response)", name.text))
                );
            };
            let bound = match (within, scans) {
                (Some(_), Some((_, sp))) => {
                    return Err(src.err(sp, "`within` and `scans` are both given: use one of them"))
                }
                (Some((t, _)), None) => Bound::Time(t),
                (None, Some((n, _))) => Bound::Scans(n),
                (None, None) => {
                    return Err(src.err(
                        span,
                        format!("property `{}` needs a bound: `within = \"T#5s\"` or `scans = 50`", name.text),
                    ))
                }
            };
            Kind::Response { after: src.expr(&a)?, expect: src.expr(&e)?, bound }
        };
        out.properties.push(Property { name: name.text.clone(), kind, line, column });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_issue_example() {
        let text = r#"
[assume]
always = ["NOT (LimitLeft AND LimitRight)"]
ranges = { Level = "0..100" }

[[property]]
name = "never both directions"
always = "NOT (MotorFwd AND MotorRev)"

[[property]]
name = "door closes in time"
after = "DoorCmd"
expect = "DoorClosed"
within = "T#5s"

[[property]]
name = "back to idle"
reachable = "Idle.X"

[[property]]
name = "no spurious stroke"
never = "Press.X AND NOT GuardClosed"
"#;
        let f = parse("door.props.toml", text).expect("parses");
        assert_eq!(f.properties.len(), 4);
        assert_eq!(f.ranges[0].lo, 0);
        assert_eq!(f.ranges[0].hi, 100);
        assert!(matches!(f.properties[1].kind, Kind::Response { bound: Bound::Time(5_000_000), .. }));
    }

    #[test]
    fn errors_are_located() {
        let e = parse("p.toml", "[[property]]\nname = \"x\"\nalways = \"A AND\"\n").unwrap_err();
        assert_eq!((e.line, e.column), (3, 16), "{e}");
        let e = parse("p.toml", "[[property]]\nname = \"x\"\nallways = \"A\"\n").unwrap_err();
        assert!(e.message.contains("did you mean `always`"), "{e}");
        assert_eq!(e.line, 3);
    }
}
