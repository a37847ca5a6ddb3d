//! Three-way merge of chart files by element (`sfc merge BASE OURS THEIRS`, docs/diff.md).
//!
//! Each file is cut into POUs and the text between them; each POU into its elements
//! (`sfc_syntax::regions`: attributes, header, declarations, steps, transitions, actions, the
//! editor's layout). An element changed on one side only takes that side's text; changed on
//! both sides, its lines are merged (a step moved on one side and given another action on the
//! other merges), and where the same lines changed both ways the element is a conflict. Steps
//! renamed on one side are matched by structure (`crate::diff`), so a step renamed in one
//! version and moved in the other is one step. The editor's layout attribute (`sfc.graph`)
//! changed on both sides is dropped (the chart is laid out again from the steps' positions),
//! which is said in a note, not a conflict.
//!
//! A conflicting element is written as ours, and the POU gets an attribute
//! `{attribute 'sfc.conflict' := 'KEY$N…'}` holding the element's key and their text, so the
//! file still parses and the editor can show the conflict and take either side.

use crate::Kind;
use sfc_syntax::ast::{Item, Pou};
use sfc_syntax::attr_value::escape;
use sfc_syntax::regions::{regions, RegionKind};

/// One element changed both ways.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Conflict {
    /// The POU (empty for text outside any POU).
    pub pou: String,
    /// The element's region key (`step:fill`, `transition:t1`, `decl`, …).
    pub element: String,
    /// The element's kind and name as written (`step Fill`), or its key.
    pub name: String,
    /// What happened on each side.
    pub what: String,
    pub base: Option<String>,
    pub ours: Option<String>,
    pub theirs: Option<String>,
}

/// The result of a merge.
#[derive(Debug, Clone, Default)]
pub struct Merged {
    pub text: String,
    pub conflicts: Vec<Conflict>,
    /// What the merge decided that is no conflict (a layout dropped).
    pub notes: Vec<String>,
}

/// The attribute marking a conflict in a merged POU.
pub const CONFLICT: &str = "sfc.conflict";

/// A file's POUs, the text between them, by key.
struct Segments<'a> {
    /// (key, text, POU) in file order; keys `pou:NAME` or `text:K` (the K-th stretch between).
    parts: Vec<(String, &'a str, Option<Pou>)>,
}

fn segments(text: &str) -> Segments<'_> {
    let (unit, _) = sfc_syntax::parse(0, text);
    let mut parts = Vec::new();
    let mut at = 0usize;
    let mut gap = 0usize;
    for item in unit.items {
        let Item::Pou(p) = item else { continue };
        let r = regions(text, &p);
        let (Some(first), Some(last)) = (r.first(), r.last()) else { continue };
        let (start, end) = (first.range.start.max(at), last.range.end);
        if start > at {
            parts.push((format!("text:{gap}"), text.get(at..start).unwrap_or(""), None));
            gap += 1;
        }
        let key = format!("pou:{}", p.name.text.to_ascii_lowercase());
        parts.push((key, text.get(start..end).unwrap_or(""), Some(p)));
        at = end;
    }
    if at < text.len() {
        parts.push((format!("text:{gap}"), text.get(at..).unwrap_or(""), None));
    }
    Segments { parts }
}

fn text<'a>(s: &Segments<'a>, i: Option<usize>) -> Option<&'a str> {
    i.and_then(|i| s.parts.get(i)).map(|p| p.1)
}

fn pou<'s>(s: &'s Segments<'_>, i: Option<usize>) -> Option<&'s Pou> {
    i.and_then(|i| s.parts.get(i)).and_then(|p| p.2.as_ref())
}

/// Three optional texts merged: one side's change, both sides' same change, or their lines
/// merged; `Err` when the same lines changed both ways (or one side removed what the other
/// changed).
fn three(base: Option<&str>, ours: Option<&str>, theirs: Option<&str>) -> Result<Option<String>, String> {
    if ours == theirs {
        return Ok(ours.map(String::from));
    }
    if ours == base {
        return Ok(theirs.map(String::from));
    }
    if theirs == base {
        return Ok(ours.map(String::from));
    }
    match (base, ours, theirs) {
        (Some(b), Some(o), Some(t)) => diffy::merge(b, o, t).map(Some).map_err(|_| "changed both ways".to_string()),
        (None, Some(_), Some(_)) => Err("added both ways, differently".into()),
        (Some(_), None, Some(_)) => Err("removed in ours, changed in theirs".into()),
        (Some(_), Some(_), None) => Err("changed in ours, removed in theirs".into()),
        _ => Ok(None),
    }
}

/// Merges `base`, `ours` and `theirs` (IEC 61131-3 text).
pub fn merge(base: &str, ours: &str, theirs: &str) -> Merged {
    let mut m = Merged::default();
    let (b, o, t) = (segments(base), segments(ours), segments(theirs));
    let keys = order(&o.parts.iter().map(|p| p.0.clone()).collect::<Vec<_>>(), &t.parts.iter().map(|p| p.0.clone()).collect::<Vec<_>>());
    let find = |s: &Segments<'_>, k: &str| s.parts.iter().position(|p| p.0 == k);
    let mut out = String::new();
    for key in keys {
        let (bi, oi, ti) = (find(&b, &key), find(&o, &key), find(&t, &key));
        let (bt, ot, tt) = (text(&b, bi), text(&o, oi), text(&t, ti));
        let name = key.strip_prefix("pou:").map(String::from);
        match (pou(&b, bi), pou(&o, oi), pou(&t, ti), &name) {
            (Some(_), Some(op), Some(_), Some(_)) if ot != tt && ot != bt && tt != bt => {
                let (Some(bt), Some(ot), Some(tt)) = (bt, ot, tt) else { continue };
                out.push_str(&merge_pou(&mut m, &op.name.text, bt, ot, tt));
            }
            _ => match three(bt, ot, tt) {
                Ok(Some(s)) => out.push_str(&s),
                Ok(None) => {}
                Err(what) => {
                    let pou = name.clone().unwrap_or_default();
                    m.conflicts.push(Conflict {
                        pou: pou.clone(),
                        element: if name.is_some() { "pou".into() } else { key.clone() },
                        name: if name.is_some() { format!("POU {pou}") } else { "text between POUs".into() },
                        what,
                        base: bt.map(String::from),
                        ours: ot.map(String::from),
                        theirs: tt.map(String::from),
                    });
                    // Ours is written (a removed POU stays removed: theirs is in the report).
                    out.push_str(ot.unwrap_or(""));
                }
            },
        }
    }
    m.text = out;
    m
}

/// Keys in ours' order, with theirs' new keys after the key they follow there.
fn order(ours: &[String], theirs: &[String]) -> Vec<String> {
    let mut out: Vec<String> = ours.to_vec();
    for (k, key) in theirs.iter().enumerate() {
        if out.contains(key) {
            continue;
        }
        let at = theirs.iter().take(k).rev().find_map(|p| out.iter().position(|o| o == p)).map_or(0, |i| i + 1);
        out.insert(at, key.clone());
    }
    out
}

/// A POU's regions: (key, kind, text, the element as said in messages).
fn cut<'a>(text: &'a str, pou: &Pou) -> Vec<(String, RegionKind, &'a str, String)> {
    regions(text, pou)
        .into_iter()
        .map(|r| {
            let said = match (r.key.split_once(':'), r.name.is_empty()) {
                (Some((kind, _)), false) => format!("{kind}:{}", r.name),
                _ => r.key.clone(),
            };
            (r.key, r.kind, text.get(r.range).unwrap_or(""), said)
        })
        .collect()
}

/// Step renames of one side against the base: (old name, new name).
fn renames(base: &str, side: &str, pou: &str) -> Vec<(String, String)> {
    let opts = sfc_model::CheckOptions { analysis: false, ..Default::default() };
    let (b, s) = (sfc_model::check_source(0, "base", base, &opts), sfc_model::check_source(0, "side", side, &opts));
    crate::diff(&b, &s)
        .changes
        .into_iter()
        .filter(|c| c.kind == Kind::Renamed && c.element == "step" && c.pou.eq_ignore_ascii_case(pou))
        .filter_map(|c| Some((c.name, c.new?)))
        .collect()
}

/// `text` with every identifier named in `map` (old → new, ignoring case) renamed; comments
/// and strings stay as they are.
fn rename_in(text: &str, map: &[(String, String)]) -> String {
    if map.is_empty() {
        return text.to_string();
    }
    let (tokens, _) = sfc_syntax::lexer::lex(0, text);
    let mut out = String::with_capacity(text.len());
    for t in tokens {
        let s = text.get(t.start as usize..t.end as usize).unwrap_or("");
        let new = (t.kind == sfc_syntax::lexer::TokenKind::Ident)
            .then(|| map.iter().find(|(old, _)| old.eq_ignore_ascii_case(s)))
            .flatten();
        out.push_str(new.map_or(s, |(_, n)| n.as_str()));
    }
    out
}

fn merge_pou(m: &mut Merged, name: &str, base: &str, ours: &str, theirs: &str) -> String {
    let name = name.to_string();
    // The POUs were parsed as parts of their files; their regions are found again in the
    // POU's own text.
    let own = |t: &str| -> Option<Pou> {
        let (unit, _) = sfc_syntax::parse(0, t);
        unit.items.into_iter().find_map(|i| match i {
            Item::Pou(p) => Some(p),
            _ => None,
        })
    };
    // A step renamed on one side is renamed in the base and on the other side too (with its
    // references), so the two sides' other changes to it and to its transitions line up. A
    // step renamed differently on both sides is left alone: it is a conflict.
    let (ro, rt) = (renames(base, ours, &name), renames(base, theirs, &name));
    let clash = |(old, new): &(String, String), other: &[(String, String)]| {
        other.iter().any(|(o, n)| o.eq_ignore_ascii_case(old) && !n.eq_ignore_ascii_case(new))
    };
    let (ro, ro_clash): (Vec<(String, String)>, Vec<(String, String)>) = ro.iter().cloned().partition(|r| !clash(r, &rt));
    let (rt, rt_clash): (Vec<(String, String)>, Vec<(String, String)>) = rt.iter().cloned().partition(|r| !clash(r, &ro_clash));
    let both: Vec<(String, String)> = ro.iter().chain(&rt).cloned().collect();
    let (bx, ox, tx) = (rename_in(base, &both), rename_in(ours, &rt), rename_in(theirs, &ro));
    let (Some(bp), Some(op), Some(tp)) = (own(&bx), own(&ox), own(&tx)) else {
        m.conflicts.push(Conflict {
            element: "pou".into(),
            name: format!("POU {name}"),
            pou: name,
            what: "changed both ways and does not parse".into(),
            base: Some(base.into()),
            ours: Some(ours.into()),
            theirs: Some(theirs.into()),
        });
        return ours.to_string();
    };
    type Cut = Vec<(String, RegionKind, String, String)>;
    // A step renamed both ways keeps its base key on both sides: its two names conflict.
    let owned = |v: Vec<(String, RegionKind, &str, String)>, clashing: &[(String, String)]| -> Cut {
        v.into_iter()
            .map(|(k, kind, t, said)| {
                let base_key = clashing
                    .iter()
                    .find(|(_, new)| format!("step:{}", new.to_ascii_lowercase()) == k)
                    .map_or(k, |(old, _)| format!("step:{}", old.to_ascii_lowercase()));
                (base_key, kind, t.to_string(), said)
            })
            .collect()
    };
    let b = owned(cut(&bx, &bp), &[]);
    let o = owned(cut(&ox, &op), &ro_clash);
    let t = owned(cut(&tx, &tp), &rt_clash);
    let keys = order(&o.iter().map(|r| r.0.clone()).collect::<Vec<_>>(), &t.iter().map(|r| r.0.clone()).collect::<Vec<_>>());
    let get = |v: &Cut, k: &str| v.iter().find(|r| r.0 == k).map(|r| r.2.clone());
    let said = |k: &str| b.iter().chain(&o).chain(&t).find(|r| r.0 == k).map_or(k.to_string(), |r| r.3.clone());
    let mut out = String::new();
    let mut marks = String::new();
    for key in keys {
        let (bt, ot, tt) = (get(&b, &key), get(&o, &key), get(&t, &key));
        let is_graph = [&b, &o, &t].iter().any(|v| v.iter().any(|r| r.0 == key && r.1 == RegionKind::Graph));
        // The layout's lines refer to blocks by their place in the list: changed on both sides,
        // their lines cannot be merged safely, and the layout is dropped (below).
        let both_changed = ot != bt && tt != bt && ot != tt;
        let merged = match three(bt.as_deref(), ot.as_deref(), tt.as_deref()) {
            Ok(_) if is_graph && both_changed => Err("changed both ways".to_string()),
            Err(why) if !is_graph => match (&bt, &ot, &tt) {
                (Some(b), Some(o), Some(t)) => apart(b, o, t, &mut |what| {
                    m.notes.push(format!("{} of `{name}`: {what}", said(&key).replacen(':', " ", 1)));
                })
                .map(Some)
                .ok_or(why),
                _ => Err(why),
            },
            r => r,
        };
        match merged {
            Ok(Some(s)) => out.push_str(&s),
            Ok(None) => {}
            Err(_) if is_graph => {
                m.notes.push(format!(
                    "the editor's layout of `{name}` changed on both sides: it is dropped, and the chart is laid out again from the steps' positions"
                ));
            }
            Err(what) => {
                if let Some(s) = &ot {
                    out.push_str(s);
                }
                let name_said = said(&key);
                marks.push_str(&format!(
                    "{{attribute '{CONFLICT}' := '{}'}}\n",
                    escape(&format!("{name_said}\n{}", tt.as_deref().unwrap_or("")))
                ));
                let shown = name_said.replacen(':', " ", 1);
                m.conflicts.push(Conflict { pou: name.clone(), element: key, name: shown, what, base: bt, ours: ot, theirs: tt });
            }
        }
    }
    format!("{marks}{out}")
}

/// Two versions of a text that is no chart merged line by line with their ancestor, as git
/// does; `Err` holds the text with the conflicts marked (`<<<<<<<`, `=======`, `>>>>>>>`).
pub fn lines(base: &str, ours: &str, theirs: &str) -> Result<String, String> {
    diffy::merge(base, ours, theirs)
}

/// The attribute name of a line that is one layout attribute pragma (`sfc.x`, …).
fn layout_line(line: &str) -> Option<String> {
    let t = line.trim();
    let rest = t.strip_prefix("{attribute '")?;
    let name = rest.split('\'').next()?;
    (t.ends_with('}') && t.matches('{').count() == 1 && crate::is_layout(name)).then(|| name.to_ascii_lowercase())
}

/// An element changed both ways on the same lines, tried again with its layout apart: the
/// rest merged by lines, each layout attribute taken from the side that changed it (ours when
/// both did, which `note` says). `None` when the rest does not merge.
fn apart(base: &str, ours: &str, theirs: &str, note: &mut dyn FnMut(String)) -> Option<String> {
    type Split = (Vec<(String, String)>, String);
    let split = |s: &str| -> Split {
        let mut layout = Vec::new();
        let mut rest = String::new();
        for l in s.split_inclusive('\n') {
            match layout_line(l) {
                Some(n) => layout.push((n, l.to_string())),
                None => rest.push_str(l),
            }
        }
        (layout, rest)
    };
    let (bl, bm) = split(base);
    let (ol, om) = split(ours);
    let (tl, tm) = split(theirs);
    let meaning = match three(Some(&bm), Some(&om), Some(&tm)) {
        Ok(m) => m.unwrap_or_default(),
        Err(_) => return None,
    };
    let mut names: Vec<&String> = Vec::new();
    for (n, _) in ol.iter().chain(&tl) {
        if !names.contains(&n) {
            names.push(n);
        }
    }
    let get = |v: &[(String, String)], n: &str| v.iter().find(|(k, _)| k == n).map(|(_, l)| l.clone());
    let mut layout = String::new();
    for n in names {
        let (b, o, t) = (get(&bl, n), get(&ol, n), get(&tl, n));
        let line = match three(b.as_deref(), o.as_deref(), t.as_deref()) {
            Ok(l) => l,
            Err(_) => {
                note(format!("`{n}` changed both ways, ours kept"));
                o
            }
        };
        layout.push_str(&line.unwrap_or_default());
    }
    // The layout before the element: after the comments and blank lines that lead to it.
    let mut out = String::new();
    let mut placed = false;
    for l in meaning.split_inclusive('\n') {
        let t = l.trim();
        if !(placed || t.is_empty() || t.starts_with("(*") || t.starts_with("//")) {
            out.push_str(&layout);
            placed = true;
        }
        out.push_str(l);
    }
    if !placed {
        out.push_str(&layout);
    }
    Some(out)
}

/// The conflicts a merged POU is marked with: (element as `kind:Name`, their text).
pub fn conflicts_of(attributes: &[sfc_syntax::ast::Attribute]) -> Vec<(String, String)> {
    attributes
        .iter()
        .filter(|a| a.name.eq_ignore_ascii_case(CONFLICT))
        .map(|a| {
            let v = sfc_syntax::attr_value::unescape(a.value.as_deref().unwrap_or(""));
            let (element, theirs) = v.split_once('\n').unwrap_or((v.as_str(), ""));
            (element.to_string(), theirs.to_string())
        })
        .collect()
}

/// `text` with the conflict of `element` (`kind:Name`, as marked) in POU `pou` resolved: its
/// `sfc.conflict` attribute removed, and with `theirs` the element's text replaced by theirs
/// (removed when their side removed it). `Err` says why it cannot be done.
pub fn resolve(text: &str, pou: &str, element: &str, theirs: bool) -> Result<String, String> {
    let (unit, _) = sfc_syntax::parse(0, text);
    let p = unit
        .items
        .iter()
        .find_map(|i| match i {
            Item::Pou(p) if p.name.text.eq_ignore_ascii_case(pou) => Some(p),
            _ => None,
        })
        .ok_or_else(|| format!("no POU `{pou}`"))?;
    let mark = p
        .attributes
        .iter()
        .find(|a| {
            a.name.eq_ignore_ascii_case(CONFLICT)
                && conflicts_of(std::slice::from_ref(a)).first().is_some_and(|(e, _)| e.eq_ignore_ascii_case(element))
        })
        .ok_or_else(|| format!("`{pou}` has no conflict on {element}"))?;
    let their_text = conflicts_of(std::slice::from_ref(mark)).into_iter().next().map(|(_, t)| t).unwrap_or_default();
    // The attribute's line (with its line break).
    let (s, e) = (mark.span.start as usize, mark.span.end as usize);
    let line_start = text.get(..s).and_then(|b| b.rfind('\n')).map_or(0, |i| i + 1);
    let line_end = text.get(e..).and_then(|r| r.find('\n')).map_or(text.len(), |i| e + i + 1);
    let own_line = text.get(line_start..s).is_some_and(|b| b.trim().is_empty())
        && text.get(e..line_end).is_some_and(|a| a.trim().is_empty());
    let cut = if own_line { line_start..line_end } else { s..e };
    let mut edits: Vec<(std::ops::Range<usize>, String)> = vec![(cut, String::new())];
    if theirs {
        let key = match element.split_once(':') {
            Some((kind, name)) => format!("{}:{}", kind.to_ascii_lowercase(), name.to_ascii_lowercase()),
            None => element.to_ascii_lowercase(),
        };
        let r = regions(text, p).into_iter().find(|r| r.key == key).map(|r| r.range);
        match r {
            Some(range) => edits.push((range, their_text)),
            None if !their_text.is_empty() => {
                // Removed on our side: theirs goes before the end of the POU.
                let tail = regions(text, p).into_iter().find(|r| r.kind == RegionKind::Tail).map(|r| r.range.start);
                let at = tail.ok_or_else(|| format!("cannot place {element} in `{pou}`"))?;
                edits.push((at..at, their_text));
            }
            None => {}
        }
    }
    edits.sort_by_key(|(r, _)| std::cmp::Reverse(r.start));
    let mut out = text.to_string();
    for (r, t) in edits {
        if out.get(r.clone()).is_none() {
            return Err("the marks do not fit the text".into());
        }
        out.replace_range(r, &t);
    }
    Ok(out)
}
