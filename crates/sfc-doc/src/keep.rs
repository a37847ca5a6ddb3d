//! Saves that change only what changed: the POU of a file rewritten from a document keeps, for
//! every element the document did not change, the element's bytes as they are in the file
//! (its comments, spacing, keyword case, and no layout pragmas where the file had none).
//!
//! Three versions of the POU take part: `file` (as on disk), `before` (the text the editor
//! writes for the document opened from it) and `after` (the text it writes for the document
//! being saved). All three are cut into regions by element (`sfc_syntax::regions`). A region
//! whose `before` and `after` texts are equal is taken from `file`; a changed one from `after`,
//! where its layout pragmas (`sfc.x`, `sfc.y`, …) and the rest are decided apart: a moved step
//! keeps its text as typed and gets its new position, a renamed one keeps its position. New
//! regions go after the region they follow in `after`, removed ones are dropped. The result is
//! checked: read back, it must say what `after` says (layout apart), or the POU is written whole.

use crate::{Element, ElementKind};
use sfc_syntax::ast::{Item, Pou};
use sfc_syntax::regions::{regions, Region, RegionKind};

/// The attributes that only place a block.
const LAYOUT: &[&str] = &["sfc.x", "sfc.y", "sfc.w", "sfc.h", "sfc.width", "sfc.height", "sfc.actionblock", "sfc.jump"];

/// The layout attributes that are written together.
const LAYOUT_GROUPS: &[&[&str]] =
    &[&["sfc.x", "sfc.y"], &["sfc.w", "sfc.h"], &["sfc.width", "sfc.height"], &["sfc.actionblock"], &["sfc.jump"]];

/// The attribute name of a layout line.
fn layout_name(line: &str) -> &str {
    let rest = line.trim().strip_prefix("{attribute '").unwrap_or("");
    rest.split('\'').next().unwrap_or("")
}

fn is_layout_line(line: &str) -> bool {
    let t = line.trim();
    let Some(rest) = t.strip_prefix("{attribute '") else { return false };
    t.ends_with('}') && t.matches('{').count() == 1 && LAYOUT.iter().any(|n| rest.strip_prefix(n).is_some_and(|r| r.starts_with('\'')))
}

/// A POU's text and its regions.
struct Cut<'a> {
    text: &'a str,
    regions: Vec<Region>,
}

impl<'a> Cut<'a> {
    fn of(text: &'a str, pou: &Pou) -> Cut<'a> {
        Cut { text, regions: regions(text, pou) }
    }
    fn get(&self, key: &str) -> Option<&Region> {
        self.regions.iter().find(|r| r.key == key)
    }
    fn text_of(&self, key: &str) -> Option<&'a str> {
        self.get(key).and_then(|r| self.text.get(r.range.clone()))
    }
}

fn only_pou(text: &str, name: Option<&str>) -> Option<Pou> {
    let (unit, diags) = sfc_syntax::parse(0, text);
    if diags.iter().any(|d| d.severity == sfc_diagnostics::Severity::Error) {
        return None;
    }
    unit.items.into_iter().find_map(|i| match i {
        Item::Pou(p) if name.is_none_or(|n| p.name.text.eq_ignore_ascii_case(n)) => Some(p),
        _ => None,
    })
}

/// Lines with their line breaks.
fn lines(s: &str) -> Vec<&str> {
    s.split_inclusive('\n').collect()
}

/// A changed region: its layout lines and the rest decided apart (see the module's doc).
fn merge_region(file: &str, file_lead: usize, before: &str, after: &str, force_layout: bool) -> String {
    let split = |s: &str| -> (Vec<String>, Vec<String>) {
        let (l, m): (Vec<&str>, Vec<&str>) = lines(s).into_iter().partition(|l| is_layout_line(l));
        (l.into_iter().map(String::from).collect(), m.into_iter().map(String::from).collect())
    };
    let (fl, _) = split(file);
    let (bl, bm) = split(before);
    let (al, am) = split(after);
    // Per group of attributes that go together (a position is both coordinates): as in the
    // file unless the document changed it. A layout written anew needs every position.
    let layout: Vec<String> = if force_layout && fl.is_empty() {
        al
    } else {
        LAYOUT_GROUPS
            .iter()
            .flat_map(|g| {
                let of = |v: &[String]| -> Vec<String> { v.iter().filter(|l| g.contains(&layout_name(l))).cloned().collect() };
                let (f, b, a) = (of(&fl), of(&bl), of(&al));
                if b == a { f } else { a }
            })
            .collect()
    };
    let (base, lead) = if bm == am { (file, Some(file_lead)) } else { (after, None) };
    // The base's lines without its layout, the layout put where the base had its own, else
    // before the element (its attributes or keyword).
    let mut out = String::new();
    let mut placed = false;
    let mut offset = 0;
    for l in lines(base) {
        let at_lead = lead.is_some_and(|p| p >= offset && p < offset + l.len());
        offset += l.len();
        if is_layout_line(l) {
            if !placed {
                layout.iter().for_each(|x| out.push_str(x));
                placed = true;
            }
            continue;
        }
        if at_lead && !placed {
            layout.iter().for_each(|x| out.push_str(x));
            placed = true;
        }
        out.push_str(l);
    }
    if !placed {
        // After the comments, before the element: the first line that is neither blank nor a
        // comment line of the base.
        let mut rebuilt = String::new();
        let mut done = false;
        for l in lines(&out) {
            let t = l.trim();
            if !(done || t.is_empty() || t.starts_with("(*") || t.starts_with("//")) {
                layout.iter().for_each(|x| rebuilt.push_str(x));
                done = true;
            }
            rebuilt.push_str(l);
        }
        if !done {
            layout.iter().for_each(|x| rebuilt.push_str(x));
        }
        out = rebuilt;
    }
    out
}

/// What a POU's text says once the layout is set aside: its regions without layout lines,
/// by key, sorted.
fn meaning(text: &str, pou: &Pou) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = regions(text, pou)
        .into_iter()
        .filter(|r| r.kind != RegionKind::Graph)
        .map(|r| {
            let t: String = lines(text.get(r.range.clone()).unwrap_or("")).into_iter().filter(|l| !is_layout_line(l)).collect();
            (r.key, t)
        })
        .collect();
    v.sort();
    v
}

/// The POU `name` of `file_text` written as `after_text` (the editor's text of the document
/// saved), keeping the bytes of what did not change; `None` when this cannot be done safely
/// (the caller then replaces the POU whole).
pub fn keep(file_text: &str, name: &str, after_text: &str) -> Option<String> {
    let opened = crate::open(0, "file", file_text);
    let old = opened.charts.iter().find(|c| c.pou.eq_ignore_ascii_case(name))?;
    let before_text = crate::to_text(old).text;
    let file_pou = only_pou(file_text, Some(name))?;
    if before_text == after_text {
        return Some(file_text.to_string());
    }
    let before_pou = only_pou(&before_text, None)?;
    let after_pou = only_pou(after_text, None)?;
    let file = Cut::of(file_text, &file_pou);
    let before = Cut::of(&before_text, &before_pou);
    let after = Cut::of(after_text, &after_pou);

    let name = after_pou.name.text.as_str();
    let saved = crate::open(0, "file", after_text).charts.into_iter().find(|c| c.pou.eq_ignore_ascii_case(name))?;
    // Blocks left without a position are laid out around the positioned ones when the file
    // is opened again; those that would land elsewhere than where the document has them get
    // their position written too.
    // The layout lines are written when they changed; when the file has none and the drawing
    // opened again without them would differ (a bar, a bend, a label placed by hand), they
    // are written too.
    let mut graph = before.text_of("graph") != after.text_of("graph");
    let mut forced: Vec<String> = Vec::new();
    for _ in 0..6 {
        let result = build(file_text, &file, &before, &after, &forced, graph)?;
        let check = crate::open(0, "file", &result);
        let doc = check.charts.iter().find(|c| c.pou.eq_ignore_ascii_case(name))?;
        let written = crate::to_text(doc).text;
        let written_pou = only_pou(&written, None)?;
        // Read back, it must say what the document says.
        if meaning(&written, &written_pou) != meaning(after_text, &after_pou) {
            return None;
        }
        let moved: Vec<String> = saved
            .elements
            .iter()
            .filter(|e| matches!(e.kind, Some(ElementKind::Step | ElementKind::Transition)))
            .filter(|e| doc.elements.iter().find(|o| o.id == e.id).is_none_or(|o| (o.x, o.y, o.w, o.h) != (e.x, e.y, e.w, e.h)))
            .filter_map(key_of)
            .filter(|k| !forced.contains(k))
            .collect();
        if !moved.is_empty() {
            forced.extend(moved);
            continue;
        }
        if !graph && !same_drawing(doc, &saved) {
            graph = true;
            continue;
        }
        return Some(result);
    }
    None
}

/// Whether two documents draw the same: every block at the same place and size, every wire
/// between the same pins along the same route.
fn same_drawing(a: &crate::EditorDoc, b: &crate::EditorDoc) -> bool {
    let blocks = |d: &crate::EditorDoc| -> Vec<(String, f64, f64, f64, f64)> {
        let mut v: Vec<_> = d.elements.iter().map(|e| (e.id.clone(), e.x, e.y, e.w, e.h)).collect();
        v.sort_by(|x, y| x.0.cmp(&y.0));
        v
    };
    let wires = |d: &crate::EditorDoc| -> Vec<(String, u32, String, u32, Vec<crate::Point>)> {
        let mut v: Vec<_> = d
            .connections
            .iter()
            .map(|c| (c.source.clone(), c.source_pin, c.target.clone(), c.target_pin, c.waypoints.clone()))
            .collect();
        v.sort_by(|x, y| (&x.0, x.1, &x.2, x.3).cmp(&(&y.0, y.1, &y.2, y.3)));
        v
    };
    blocks(a) == blocks(b) && wires(a) == wires(b)
}

/// The region key of a step or transition block (`step:NAME`, `transition:NAME`; `None` for
/// an unnamed transition, whose key depends on its place among the unnamed ones).
fn key_of(e: &Element) -> Option<String> {
    let (kind, name) = e.id.split_once(':')?;
    Some(format!("{kind}:{}", name.to_ascii_lowercase()))
}

/// The POU's new text: the regions of `file` in its order, changed, kept or dropped, and the new
/// ones of `after`; the regions named in `forced` get the position `after` gives them.
fn build(file_text: &str, file: &Cut, before: &Cut, after: &Cut, forced: &[String], graph_new: bool) -> Option<String> {
    // The layout attribute: kept as in the file unless it changed; written anew, every block
    // needs its position (the layout is read only when all steps and transitions have one).
    let mut out: Vec<(String, String)> = Vec::new();
    for r in &file.regions {
        let f = file.text.get(r.range.clone()).unwrap_or("");
        let (b, a) = (before.text_of(&r.key), after.text_of(&r.key));
        let text = match (b, a) {
            // Removed by the document.
            (Some(_), None) => continue,
            // Not read into the document: kept.
            (None, None) => f.to_string(),
            (None, Some(a)) => a.to_string(),
            (Some(b), Some(a)) if r.kind == RegionKind::Graph => {
                if b == a {
                    f.to_string()
                } else {
                    a.to_string()
                }
            }
            // An action (its chart's steps inside) or anything else that changed: written anew.
            (Some(b), Some(a)) if !matches!(r.kind, RegionKind::Step | RegionKind::Transition) => {
                if b == a {
                    f.to_string()
                } else {
                    a.to_string()
                }
            }
            (Some(b), Some(a)) => {
                let positioned = lines(f).iter().any(|l| is_layout_line(l));
                if b == a && !((graph_new || forced.contains(&r.key)) && !positioned) {
                    f.to_string()
                } else {
                    merge_region(f, r.lead.saturating_sub(r.range.start), b, a, graph_new || forced.contains(&r.key))
                }
            }
        };
        out.push((r.key.clone(), text));
    }
    // What the document added, after what it follows there.
    for (k, r) in after.regions.iter().enumerate() {
        if out.iter().any(|(key, _)| *key == r.key) {
            continue;
        }
        let is_new_graph = r.kind == RegionKind::Graph && !graph_new;
        if is_new_graph || (before.get(&r.key).is_some() && before.text_of(&r.key) == after.text_of(&r.key)) {
            // In the document as opened and unchanged: the file did without it.
            continue;
        }
        let text = after.text.get(r.range.clone()).unwrap_or("").to_string();
        let at = after.regions[..k]
            .iter()
            .rev()
            .find_map(|p| out.iter().position(|(key, _)| *key == p.key))
            .map_or(0, |i| i + 1);
        out.insert(at, (r.key.clone(), text));
    }
    let pou_text: String = out.into_iter().map(|(_, t)| t).collect();
    let start = file.regions.first()?.range.start;
    let end = file.regions.last()?.range.end;
    Some(format!("{}{}{}", file_text.get(..start)?, pou_text, file_text.get(end..)?))
}
