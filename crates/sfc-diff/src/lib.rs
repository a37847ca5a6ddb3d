//! Two versions of a chart file compared by meaning (`sfc diff`, docs/diff.md).
//!
//! Both sides are checked files ([`sfc_model::Checked`]: IEC text, or PLCopen XML, L5X or
//! SimaticML imported to it), so a chart saved by another tool compares with its text. Per POU
//! (matched by name): steps added, removed, renamed (an unmatched step of each side with the
//! same neighbours, actions and initial flag is the same step renamed) or changed (initial,
//! supervision and minimum time, associations: action, qualifier, duration), transitions rewired
//! (their steps, through the renames) or with another condition or priority, actions added,
//! removed or with another body, variables added, removed or changed (kind, type, initial
//! value, address). Conditions and bodies compare as printed by the formatter, so a change of
//! spacing, case of keywords or comments is no change. Layout (`sfc.x`, `sfc.y`, sizes, the
//! editor's `sfc.graph`) is apart: a layout-only change leaves the files equal in meaning.

pub mod merge;

use sfc_diagnostics::Span;
use sfc_model::{Chart, Checked, Duration};
use sfc_syntax::ast::{self, Attribute, Item};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt::Write as _;

/// What became of an element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Added,
    Removed,
    Renamed,
    Changed,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Added => "added",
            Kind::Removed => "removed",
            Kind::Renamed => "renamed",
            Kind::Changed => "changed",
        }
    }
}

/// One change of meaning.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Change {
    pub pou: String,
    /// `pou`, `step`, `transition`, `action`, `variable`, `body`.
    pub element: &'static str,
    /// The element's name (the old one when renamed or removed).
    pub name: String,
    pub kind: Kind,
    /// For a change, what changed (`condition`, `steps`, `qualifier`, `type` …); empty otherwise.
    pub what: String,
    pub old: Option<String>,
    pub new: Option<String>,
}

/// A change of an element's place or size only.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LayoutChange {
    pub pou: String,
    pub element: String,
    pub attribute: String,
    pub old: Option<String>,
    pub new: Option<String>,
}

/// The differences of two files.
#[derive(Debug, Clone, Default)]
pub struct Diff {
    pub changes: Vec<Change>,
    pub layout: Vec<LayoutChange>,
    /// What a tool records about the file rather than the chart (PLCopen's file and content
    /// headers with their modification times, project data), apart like the layout.
    pub info: Vec<LayoutChange>,
}

impl Diff {
    /// Equal in meaning (layout may differ).
    pub fn equal(&self) -> bool {
        self.changes.is_empty()
    }

    /// The changes as text, a POU at a time; `layout` lists the layout changes instead of
    /// summing them up in one line.
    pub fn text(&self, layout: bool) -> String {
        let mut out = String::new();
        let mut pous: Vec<&str> = Vec::new();
        let all = self.layout.iter().chain(&self.info);
        for p in self.changes.iter().map(|c| c.pou.as_str()).chain(all.map(|l| l.pou.as_str())) {
            if !pous.contains(&p) {
                pous.push(p);
            }
        }
        for p in pous {
            let _ = writeln!(out, "{p}:");
            for c in self.changes.iter().filter(|c| c.pou == p) {
                let _ = writeln!(out, "  {}", line(c));
            }
            for l in self.info.iter().filter(|l| l.pou == p && l.attribute == "comment") {
                let how = if l.old.is_none() { "added" } else { "removed" };
                let _ = writeln!(out, "  # {} {how}", l.element);
            }
            let info: Vec<&LayoutChange> = self.info.iter().filter(|l| l.pou == p && l.attribute != "comment").collect();
            if !info.is_empty() && !layout {
                let mut names: Vec<&str> = info.iter().map(|l| info_name(&l.attribute)).collect();
                names.dedup();
                let _ = writeln!(out, "  file information: {} changed (--layout lists it)", names.join(", "));
            }
            let moved: Vec<&LayoutChange> = self.layout.iter().filter(|l| l.pou == p).collect();
            if layout {
                for l in info.iter().chain(&moved) {
                    let _ = writeln!(
                        out,
                        "  layout {}: {} {} -> {}",
                        l.element,
                        l.attribute,
                        l.old.as_deref().unwrap_or("(none)"),
                        l.new.as_deref().unwrap_or("(none)")
                    );
                }
            } else if !moved.is_empty() {
                let mut elements: Vec<&str> = moved.iter().map(|l| l.element.as_str()).collect();
                elements.dedup();
                let n = elements.iter().collect::<HashSet<_>>().len();
                let _ = writeln!(
                    out,
                    "  layout: {n} element{} moved or resized (--layout lists them)",
                    if n == 1 { "" } else { "s" }
                );
            }
        }
        out
    }

    /// The changes as JSON: `{"equal", "changes": [...], "layout": [...]}`.
    pub fn json(&self) -> serde_json::Value {
        let changes: Vec<serde_json::Value> = self
            .changes
            .iter()
            .map(|c| {
                serde_json::json!({
                    "pou": c.pou,
                    "element": c.element,
                    "name": c.name,
                    "kind": c.kind.name(),
                    "what": c.what,
                    "old": c.old,
                    "new": c.new,
                })
            })
            .collect();
        let layout: Vec<serde_json::Value> = self
            .layout
            .iter()
            .map(|l| {
                serde_json::json!({
                    "pou": l.pou, "element": l.element, "attribute": l.attribute, "old": l.old, "new": l.new,
                })
            })
            .collect();
        let info: Vec<serde_json::Value> = self
            .info
            .iter()
            .map(|l| {
                serde_json::json!({
                    "pou": l.pou, "element": l.element, "attribute": l.attribute, "old": l.old, "new": l.new,
                })
            })
            .collect();
        serde_json::json!({ "equal": self.equal(), "changes": changes, "layout": layout, "info": info })
    }
}

/// A change as one line: `+ step Rinse`, `- transition T3`, `~ step Fill renamed Filling`,
/// `~ transition T1 condition: a AND b -> a OR b`.
pub fn line(c: &Change) -> String {
    match c.kind {
        Kind::Added => match &c.new {
            Some(n) => format!("+ {} {} ({n})", c.element, c.name),
            None => format!("+ {} {}", c.element, c.name),
        },
        Kind::Removed => match &c.old {
            Some(o) => format!("- {} {} ({o})", c.element, c.name),
            None => format!("- {} {}", c.element, c.name),
        },
        Kind::Renamed => format!("~ {} {} renamed {}", c.element, c.name, c.new.as_deref().unwrap_or("")),
        // Statements: the ones removed and added, one per line.
        Kind::Changed
            if (c.what == "statements" || (c.element == "action" && c.what == "body"))
                && (c.old.as_deref().unwrap_or("").contains('\n') || c.new.as_deref().unwrap_or("").contains('\n')) =>
        {
            let (a, b) = (c.old.as_deref().unwrap_or(""), c.new.as_deref().unwrap_or(""));
            let mut s = format!("~ {} {} {}:", c.element, c.name, c.what);
            for l in diffy::create_patch(&lines_of(a), &lines_of(b)).hunks().iter().flat_map(|h| h.lines()) {
                match l {
                    diffy::Line::Delete(t) => s.push_str(&format!("\n      - {}", t.trim_end())),
                    diffy::Line::Insert(t) => s.push_str(&format!("\n      + {}", t.trim_end())),
                    diffy::Line::Context(_) => {}
                }
            }
            s
        }
        Kind::Changed => format!(
            "~ {} {} {}: {} -> {}",
            c.element,
            c.name,
            c.what,
            c.old.as_deref().unwrap_or("(none)"),
            c.new.as_deref().unwrap_or("(none)")
        ),
    }
}

/// A text as lines, each ending with a line break (for the line diff of statements).
fn lines_of(s: &str) -> String {
    s.lines().map(|l| format!("{l}\n")).collect()
}

/// Attributes in which an import keeps what a tool records about the file: PLCopen's file
/// and content headers (with their modification times) and foreign project data.
pub fn is_file_info(attribute: &str) -> bool {
    matches!(attribute.to_ascii_lowercase().as_str(), "sfc.fileheader" | "sfc.contentheader" | "sfc.projectdata")
}

fn info_name(attribute: &str) -> &'static str {
    match attribute {
        "sfc.fileheader" => "file header",
        "sfc.contentheader" => "content header",
        _ => "project data",
    }
}

/// Attributes that place, size or colour an element, or hold a drawing (the editor's
/// `sfc.graph`, a PLCopen action block's and jump's places, the XML attributes of an L5X
/// element, which carry its place).
pub fn is_layout(attribute: &str) -> bool {
    let a = attribute.to_ascii_lowercase();
    matches!(
        a.as_str(),
        "sfc.x"
            | "sfc.y"
            | "sfc.w"
            | "sfc.h"
            | "sfc.width"
            | "sfc.height"
            | "sfc.graph"
            | "sfc.graph.e"
            | "sfc.graph.c"
            | "sfc.layout"
            | "sfc.actionblock"
            | "sfc.jump"
            | "sfc.linewidth"
            | "sfc.foreground"
            | "sfc.background"
            | "sfc.hidelabel"
            | "sfc.logix.attrs"
    )
}

/// Compares two checked files.
pub fn diff(old: &Checked, new: &Checked) -> Diff {
    let mut d = Diff::default();
    let olds = pous(old);
    let news = pous(new);
    for (key, o) in &olds {
        let Some(n) = news.get(key) else {
            d.changes.push(change(&o.pou.name.text, "pou", &o.pou.name.text, Kind::Removed));
            continue;
        };
        compare_pou(&mut d, old, new, o, n);
    }
    for (key, n) in &news {
        if !olds.contains_key(key) {
            d.changes.push(change(&n.pou.name.text, "pou", &n.pou.name.text, Kind::Added));
        }
    }
    d
}

/// A POU of a file and its chart.
struct Pou<'a> {
    pou: &'a ast::Pou,
    chart: Option<&'a Chart>,
}

/// The POUs of a file by upper-case name, in file order.
fn pous(c: &Checked) -> BTreeMap<String, Pou<'_>> {
    let mut out = BTreeMap::new();
    for (i, item) in c.unit.items.iter().enumerate() {
        if let Item::Pou(p) = item {
            let chart = c.charts.iter().find(|ch| ch.item == i && ch.action.is_none());
            out.entry(p.name.key()).or_insert(Pou { pou: p, chart });
        }
    }
    out
}

fn change(pou: &str, element: &'static str, name: &str, kind: Kind) -> Change {
    Change { pou: pou.to_string(), element, name: name.to_string(), kind, what: String::new(), old: None, new: None }
}

fn changed(pou: &str, element: &'static str, name: &str, what: &str, old: String, new: String) -> Change {
    Change {
        pou: pou.to_string(),
        element,
        name: name.to_string(),
        kind: Kind::Changed,
        what: what.to_string(),
        old: Some(old),
        new: Some(new),
    }
}

/// Text with its white space collapsed to single spaces.
fn squeeze(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Code without the white space that does not separate two words (`a+b` and `a + b` are the
/// same code), keywords and names in upper case: what two bodies are compared on.
fn code_key(s: &str) -> String {
    let word = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '#' || c == '.';
    let mut out = String::new();
    let mut pending = false;
    let mut quote: Option<char> = None;
    for c in s.chars() {
        // Inside a string literal every character counts as written.
        if let Some(q) = quote {
            out.push(c);
            if c == q {
                quote = None;
            }
            continue;
        }
        if c == '\'' || c == '"' {
            quote = Some(c);
        }
        if c.is_whitespace() {
            pending = true;
            continue;
        }
        if pending && out.chars().next_back().is_some_and(word) && word(c) {
            out.push(' ');
        }
        pending = false;
        out.push(if quote.is_some() { c } else { c.to_ascii_uppercase() });
    }
    out
}

fn slice(c: &Checked, span: Span) -> &str {
    c.file.text.get(span.start as usize..span.end as usize).unwrap_or("")
}

fn compare_pou(d: &mut Diff, oc: &Checked, nc: &Checked, o: &Pou<'_>, n: &Pou<'_>) {
    let name = n.pou.name.text.as_str();
    if o.pou.kind != n.pou.kind {
        d.changes.push(changed(name, "pou", name, "kind", o.pou.kind.keyword().into(), n.pou.kind.keyword().into()));
    }
    attributes(d, name, "pou", name, &o.pou.attributes, &n.pou.attributes);
    variables(d, oc, nc, name, o.pou, n.pou);
    match (o.chart, n.chart) {
        (Some(a), Some(b)) => chart(d, oc, nc, name, a, b),
        (None, None) => {
            // A POU in ST or IL: its body, as printed.
            let a = body_text(oc, o.pou);
            let b = body_text(nc, n.pou);
            if code_key(&a) != code_key(&b) {
                d.changes.push(changed(name, "body", name, "statements", a, b));
            }
        }
        (a, _) => d.changes.push(changed(
            name,
            "body",
            name,
            "language",
            if a.is_some() { "SFC".into() } else { "code".into() },
            if a.is_some() { "code".into() } else { "SFC".into() },
        )),
    }
}

/// The statements of a POU without a chart, white space squeezed.
fn body_text(c: &Checked, p: &ast::Pou) -> String {
    let stmts: Vec<&str> = match &p.body {
        ast::Body::St(s) => s.iter().map(|s| slice(c, s.span)).collect(),
        _ => Vec::new(),
    };
    stmts.iter().map(|s| squeeze(s)).collect::<Vec<_>>().join("\n")
}

/// A declaration's meaning: kind, address, type and initial value.
fn variables(d: &mut Diff, oc: &Checked, nc: &Checked, pou: &str, o: &ast::Pou, n: &ast::Pou) {
    let decls = |c: &Checked, p: &ast::Pou| -> Vec<(String, String, String, String)> {
        let mut v = Vec::new();
        for b in &p.var_blocks {
            let mut kind = b.kind.keyword().to_string();
            if b.constant {
                kind.push_str(" CONSTANT");
            }
            if b.retain.is_some() {
                kind.push_str(" RETAIN");
            }
            for dcl in &b.decls {
                let ty = squeeze(slice(c, dcl.ty.span));
                let init = dcl.init.as_ref().map(|i| squeeze(slice(c, init_span(i)))).unwrap_or_default();
                let at = dcl.location.as_ref().map(|l| l.text.clone()).unwrap_or_default();
                for name in &dcl.names {
                    v.push((name.text.clone(), kind.clone(), format!("{ty}{}", if at.is_empty() { String::new() } else { format!(" AT {at}") }), init.clone()));
                }
            }
        }
        v
    };
    let a = decls(oc, o);
    let b = decls(nc, n);
    let find = |list: &[(String, String, String, String)], k: &str| list.iter().find(|x| x.0.eq_ignore_ascii_case(k)).cloned();
    for x in &a {
        match find(&b, &x.0) {
            None => d.changes.push(change(pou, "variable", &x.0, Kind::Removed)),
            Some(y) => {
                if x.1 != y.1 {
                    d.changes.push(changed(pou, "variable", &y.0, "kind", x.1.clone(), y.1.clone()));
                }
                if !x.2.eq_ignore_ascii_case(&y.2) {
                    d.changes.push(changed(pou, "variable", &y.0, "type", x.2.clone(), y.2.clone()));
                }
                if x.3 != y.3 {
                    d.changes.push(changed(pou, "variable", &y.0, "initial value", x.3.clone(), y.3.clone()));
                }
            }
        }
    }
    for y in &b {
        if find(&a, &y.0).is_none() {
            let mut c = change(pou, "variable", &y.0, Kind::Added);
            c.new = Some(y.2.clone());
            d.changes.push(c);
        }
    }
}

fn init_span(i: &ast::Initializer) -> Span {
    match i {
        ast::Initializer::Expr(e) => e.span,
        ast::Initializer::Array { span, .. } | ast::Initializer::Struct { span, .. } => *span,
    }
}

/// Non-layout attributes compared; layout ones noted apart.
fn attributes(d: &mut Diff, pou: &str, element: &'static str, name: &str, a: &[Attribute], b: &[Attribute]) {
    let map = |l: &[Attribute]| -> BTreeMap<String, String> {
        l.iter().map(|x| (x.name.to_ascii_lowercase(), x.value.clone().unwrap_or_default())).collect()
    };
    let (ma, mb) = (map(a), map(b));
    comments(d, pou, a, b);
    let keys: HashSet<&String> = ma.keys().chain(mb.keys()).filter(|k| k.as_str() != "sfc.comment").collect();
    let mut keys: Vec<&String> = keys.into_iter().collect();
    keys.sort();
    for k in keys {
        let (x, y) = (ma.get(k), mb.get(k));
        if x == y {
            continue;
        }
        if is_file_info(k) {
            d.info.push(LayoutChange {
                pou: pou.to_string(),
                element: format!("{element} {name}"),
                attribute: k.clone(),
                old: x.cloned(),
                new: y.cloned(),
            });
        } else if is_layout(k) {
            d.layout.push(LayoutChange {
                pou: pou.to_string(),
                element: format!("{element} {name}"),
                attribute: k.clone(),
                old: x.cloned(),
                new: y.cloned(),
            });
        } else {
            d.changes.push(Change {
                pou: pou.to_string(),
                element,
                name: name.to_string(),
                kind: Kind::Changed,
                what: format!("attribute {k}"),
                old: x.cloned(),
                new: y.cloned(),
            });
        }
    }
}

/// The text labels of a POU (`sfc.comment`: a box, a line break, the text): a label whose text
/// is on both sides is the same label (moved or resized: layout), others added or removed
/// (documentation, listed with the file information: no change of meaning).
fn comments(d: &mut Diff, pou: &str, a: &[Attribute], b: &[Attribute]) {
    let labels = |l: &[Attribute]| -> Vec<(String, String)> {
        l.iter()
            .filter(|x| x.name.eq_ignore_ascii_case("sfc.comment"))
            .map(|x| {
                let v = sfc_syntax::attr_value::unescape(x.value.as_deref().unwrap_or(""));
                let (bx, text) = v.split_once('\n').unwrap_or(("", v.as_str()));
                (bx.trim().to_string(), text.trim().to_string())
            })
            .collect()
    };
    let short = |t: &str| {
        let one = squeeze(t);
        if one.chars().count() > 60 {
            format!("{}…", one.chars().take(60).collect::<String>())
        } else {
            one
        }
    };
    let (la, mut lb) = (labels(a), labels(b));
    for (bx, text) in la {
        match lb.iter().position(|(_, t)| squeeze(t) == squeeze(&text)) {
            Some(i) => {
                let (nbx, _) = lb.remove(i);
                if nbx != bx {
                    d.layout.push(LayoutChange {
                        pou: pou.to_string(),
                        element: format!("comment \"{}\"", short(&text)),
                        attribute: "sfc.comment".into(),
                        old: Some(bx),
                        new: Some(nbx),
                    });
                }
            }
            None => d.info.push(LayoutChange {
                pou: pou.to_string(),
                element: format!("comment \"{}\"", short(&text)),
                attribute: "comment".into(),
                old: Some(text),
                new: None,
            }),
        }
    }
    for (_, text) in lb {
        d.info.push(LayoutChange {
            pou: pou.to_string(),
            element: format!("comment \"{}\"", short(&text)),
            attribute: "comment".into(),
            old: None,
            new: Some(text),
        });
    }
}

/// A condition as the formatter prints it.
fn condition(c: &Checked, cond: &ast::Condition) -> String {
    match cond {
        ast::Condition::St(e) => sfc_syntax::print::expr(e),
        ast::Condition::Il(il) => squeeze(slice(c, il.span)),
        ast::Condition::Missing => String::new(),
    }
}

/// An action's body: its text between the name's `:` and `END_ACTION`, white space squeezed.
fn action_body(c: &Checked, a: &sfc_model::chart::ActionNode) -> String {
    let whole = slice(c, a.span);
    let from = (a.name_span.end.saturating_sub(a.span.start)) as usize;
    let body = whole.get(from..).unwrap_or("").trim_start();
    let body = body.strip_prefix(':').unwrap_or(body);
    let end = body.to_ascii_uppercase().rfind("END_ACTION").unwrap_or(body.len());
    squeeze(body.get(..end).unwrap_or(body))
}

fn duration(d: &Option<Duration>) -> String {
    match d {
        Some(Duration::Literal(us)) if us % 1000 == 0 => format!("T#{}ms", us / 1000),
        Some(Duration::Literal(us)) => format!("T#{us}us"),
        Some(Duration::Variable(v)) => v.clone(),
        None => String::new(),
    }
}

/// A step's associations as `Action(Q, t)`.
fn assocs(s: &sfc_model::StepNode) -> Vec<String> {
    s.associations
        .iter()
        .map(|a| {
            let t = duration(&a.duration);
            if t.is_empty() {
                format!("{}({})", a.action, a.qualifier.name())
            } else {
                format!("{}({}, {t})", a.action, a.qualifier.name())
            }
        })
        .collect()
}

fn chart(d: &mut Diff, oc: &Checked, nc: &Checked, pou: &str, a: &Chart, b: &Chart) {
    // Steps: by name, then the unmatched ones by their neighbours and actions.
    let mut map: HashMap<usize, usize> = HashMap::new();
    for (i, s) in a.steps.iter().enumerate() {
        if let Some(j) = b.steps.iter().position(|t| t.name.eq_ignore_ascii_case(&s.name)) {
            map.insert(i, j);
        }
    }
    // A step that is its own neighbour (a transition from it back to it) is named as itself,
    // whatever its name, so that it matches when renamed.
    const ITSELF: &str = "\u{0}itself";
    let neighbours = |c: &Chart, i: usize| -> (Vec<String>, Vec<String>) {
        let name = |k: usize| if k == i { Some(ITSELF.to_string()) } else { c.steps.get(k).map(|s| s.name.to_ascii_uppercase()) };
        let mut before = Vec::new();
        let mut after = Vec::new();
        for t in &c.transitions {
            if t.to.contains(&i) {
                before.extend(t.from.iter().filter_map(|&k| name(k)));
            }
            if t.from.contains(&i) {
                after.extend(t.to.iter().filter_map(|&k| name(k)));
            }
        }
        before.sort();
        after.sort();
        (before, after)
    };
    // The neighbours of an old step, named as in the new file where already matched.
    let renamed_neighbours = |i: usize, map: &HashMap<usize, usize>| -> (Vec<String>, Vec<String>) {
        let name = |k: usize| match map.get(&k).and_then(|&j| b.steps.get(j)) {
            _ if k == i => ITSELF.to_string(),
            Some(s) => s.name.to_ascii_uppercase(),
            None => a.steps.get(k).map(|s| s.name.to_ascii_uppercase()).unwrap_or_default(),
        };
        let mut before = Vec::new();
        let mut after = Vec::new();
        for t in &a.transitions {
            if t.to.contains(&i) {
                before.extend(t.from.iter().map(|&k| name(k)));
            }
            if t.from.contains(&i) {
                after.extend(t.to.iter().map(|&k| name(k)));
            }
        }
        before.sort();
        after.sort();
        (before, after)
    };
    let unmatched_new: Vec<usize> = (0..b.steps.len()).filter(|j| !map.values().any(|v| v == j)).collect();
    let mut taken: HashSet<usize> = HashSet::new();
    for i in 0..a.steps.len() {
        if map.contains_key(&i) {
            continue;
        }
        let Some(s) = a.steps.get(i) else { continue };
        let (before, after) = renamed_neighbours(i, &map);
        // The same actions and initial flag, and the same steps before or after it (both
        // preferred): the step renamed, though a neighbour may have changed too.
        let score = |j: usize| -> u32 {
            let Some(t) = b.steps.get(j) else { return 0 };
            if t.initial != s.initial || assocs(t) != assocs(s) {
                return 0;
            }
            let (nb, na) = neighbours(b, j);
            u32::from(!before.is_empty() && nb == before) + u32::from(!after.is_empty() && na == after)
        };
        let best = unmatched_new
            .iter()
            .copied()
            .filter(|j| !taken.contains(j))
            .map(|j| (score(j), j))
            .filter(|&(sc, _)| sc > 0)
            .max_by_key(|&(sc, j)| (sc, std::cmp::Reverse(j)))
            .map(|(_, j)| j);
        if let Some(j) = best {
            taken.insert(j);
            map.insert(i, j);
            let mut c = change(pou, "step", &s.name, Kind::Renamed);
            c.old = Some(s.name.clone());
            c.new = b.steps.get(j).map(|t| t.name.clone());
            d.changes.push(c);
        }
    }
    // The renames, so that a condition or body that only follows a rename is unchanged.
    let renames: HashMap<String, String> = map
        .iter()
        .filter_map(|(&i, &j)| Some((a.steps.get(i)?, b.steps.get(j)?)))
        .filter(|(s, t)| !s.name.eq_ignore_ascii_case(&t.name))
        .map(|(s, t)| (s.name.to_ascii_uppercase(), t.name.clone()))
        .collect();
    for (i, s) in a.steps.iter().enumerate() {
        match map.get(&i).and_then(|&j| b.steps.get(j)) {
            None => d.changes.push(change(pou, "step", &s.name, Kind::Removed)),
            Some(t) => step(d, pou, s, t),
        }
    }
    for (j, t) in b.steps.iter().enumerate() {
        if !map.values().any(|&v| v == j) {
            d.changes.push(change(pou, "step", &t.name, Kind::Added));
        }
    }
    // Transitions: by name when both are named, else by their steps (through the renames).
    let new_name = |i: usize| map.get(&i).and_then(|&j| b.steps.get(j)).map(|s| s.name.to_ascii_uppercase());
    let ends_old = |t: &sfc_model::TransitionNode| -> (Vec<String>, Vec<String>) {
        let mut f: Vec<String> = t.from.iter().map(|&k| new_name(k).unwrap_or_else(|| format!("-{k}"))).collect();
        let mut o: Vec<String> = t.to.iter().map(|&k| new_name(k).unwrap_or_else(|| format!("-{k}"))).collect();
        f.sort();
        o.sort();
        (f, o)
    };
    let ends_new = |t: &sfc_model::TransitionNode| -> (Vec<String>, Vec<String>) {
        let mut f: Vec<String> = t.from.iter().filter_map(|&k| b.steps.get(k)).map(|s| s.name.to_ascii_uppercase()).collect();
        let mut o: Vec<String> = t.to.iter().filter_map(|&k| b.steps.get(k)).map(|s| s.name.to_ascii_uppercase()).collect();
        f.sort();
        o.sort();
        (f, o)
    };
    let show = |c: &Chart, t: &sfc_model::TransitionNode| -> String {
        let names = |l: &[usize]| l.iter().filter_map(|&k| c.steps.get(k)).map(|s| s.name.clone()).collect::<Vec<_>>().join(", ");
        format!("FROM {} TO {}", names(&t.from), names(&t.to))
    };
    let mut tmap: HashMap<usize, usize> = HashMap::new();
    for (i, t) in a.transitions.iter().enumerate() {
        if t.named {
            if let Some(j) = b.transitions.iter().position(|u| u.named && u.name.eq_ignore_ascii_case(&t.name)) {
                tmap.insert(i, j);
            }
        }
    }
    for (i, t) in a.transitions.iter().enumerate() {
        if tmap.contains_key(&i) {
            continue;
        }
        let e = ends_old(t);
        if let Some(j) = (0..b.transitions.len())
            .find(|j| !tmap.values().any(|v| v == j) && b.transitions.get(*j).is_some_and(|u| !(u.named && t.named) && ends_new(u) == e))
        {
            tmap.insert(i, j);
        }
    }
    for (i, t) in a.transitions.iter().enumerate() {
        let Some(u) = tmap.get(&i).and_then(|&j| b.transitions.get(j)) else {
            let mut c = change(pou, "transition", &t.name, Kind::Removed);
            c.old = Some(show(a, t));
            d.changes.push(c);
            continue;
        };
        if ends_old(t) != ends_new(u) {
            d.changes.push(changed(pou, "transition", &u.name, "steps", show(a, t), show(b, u)));
        }
        let (x, y) = (condition(oc, &t.condition), condition(nc, &u.condition));
        if rename_words(&x, &renames) != y {
            d.changes.push(changed(pou, "transition", &u.name, "condition", x, y));
        }
        if t.priority != u.priority {
            d.changes.push(changed(
                pou,
                "transition",
                &u.name,
                "priority",
                t.priority.map(|p| p.to_string()).unwrap_or_default(),
                u.priority.map(|p| p.to_string()).unwrap_or_default(),
            ));
        }
        attributes(d, pou, "transition", &u.name, &t.attributes, &u.attributes);
    }
    for (j, u) in b.transitions.iter().enumerate() {
        if !tmap.values().any(|&v| v == j) {
            let mut c = change(pou, "transition", &u.name, Kind::Added);
            c.new = Some(show(b, u));
            d.changes.push(c);
        }
    }
    // Actions, by name.
    for x in &a.actions {
        match b.actions.iter().find(|y| y.name.eq_ignore_ascii_case(&x.name)) {
            None => d.changes.push(change(pou, "action", &x.name, Kind::Removed)),
            Some(y) => {
                let (p, q) = (action_body(oc, x), action_body(nc, y));
                if code_key(&rename_words(&p, &renames)) != code_key(&q) {
                    d.changes.push(changed(pou, "action", &y.name, "body", p, q));
                }
                attributes(d, pou, "action", &y.name, &x.attributes, &y.attributes);
            }
        }
    }
    for y in &b.actions {
        if !a.actions.iter().any(|x| x.name.eq_ignore_ascii_case(&y.name)) {
            d.changes.push(change(pou, "action", &y.name, Kind::Added));
        }
    }
}

fn step(d: &mut Diff, pou: &str, s: &sfc_model::StepNode, t: &sfc_model::StepNode) {
    if s.initial != t.initial {
        d.changes.push(changed(pou, "step", &t.name, "initial", s.initial.to_string(), t.initial.to_string()));
    }
    let (x, y) = (assocs(s), assocs(t));
    if x != y {
        d.changes.push(changed(pou, "step", &t.name, "actions", x.join(" "), y.join(" ")));
    }
    attributes(d, pou, "step", &t.name, &s.attributes, &t.attributes);
}

/// `text` with every identifier that `renames` names (upper case) replaced by its new name.
fn rename_words(text: &str, renames: &HashMap<String, String>) -> String {
    if renames.is_empty() {
        return text.to_string();
    }
    let mut out = String::with_capacity(text.len());
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        match renames.get(&word.to_ascii_uppercase()) {
            Some(n) => out.push_str(n),
            None => out.push_str(word),
        }
        word.clear();
    };
    for c in text.chars() {
        if c.is_ascii_alphanumeric() || c == '_' {
            word.push(c);
        } else {
            flush(&mut word, &mut out);
            out.push(c);
        }
    }
    flush(&mut word, &mut out);
    out
}
