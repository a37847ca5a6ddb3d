//! What each compiler needs of the ST target's output (`sfc build --target st --st-dialect`),
//! applied to the whole translated file once every chart is plain ST:
//!
//! * every dialect: a `VAR` block that mixes located (`AT %IX0.0`) and unlocated variables is
//!   split into blocks of one kind (IEC 61131-3's grammar has separate productions for them),
//!   and the file is put in IEC order, each type, function and function block before the first
//!   declaration that uses it (a stable sort: a file already in order is not changed);
//! * every dialect but `codesys`: pragmas (`{attribute …}`) become comments: the standard leaves
//!   their meaning to the implementation, STruC++ refuses them and MatIEC copies `{…}` into its C;
//! * `matiec`: declarations of several function block instances in one line are written one per
//!   line (`iec2c` crashes on three or more), and TIME literals are written in the one form
//!   MatIEC reads exactly ([`matiec_time_literal`]).

use super::StDialect;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast;
use sfc_syntax::lexer::{lex, TokenKind};
use std::collections::HashSet;

/// The dialect's passes over a translated file, and whether a CONFIGURATION was added.
pub(crate) fn finish(text: &str, dialect: StDialect) -> (String, bool) {
    let mut t = if dialect == StDialect::Codesys { text.to_string() } else { pragmas_to_comments(text) };
    t = split_located(&t);
    if dialect == StDialect::Matiec {
        t = one_instance_per_declaration(&t);
    }
    t = iec_order(&t);
    let mut configured = false;
    if dialect == StDialect::Matiec {
        if let Some(c) = configuration(&t) {
            t.push_str(&c);
            configured = true;
        }
        let exact = matiec_time_literals(&t);
        if exact != t {
            t = format!("{MATIEC_LITERALS}{exact}");
        }
    }
    (t, configured)
}

const MATIEC_LITERALS: &str =
    "(* Written by sfc for MatIEC (--st-dialect matiec). A duration such as T#8.0000005ms is T#8ms:\n   \
MatIEC computes a TIME literal in floating point and truncates it to whole nanoseconds, so T#8ms\n   \
would be 7.999999 ms; the half nanosecond more is truncated away. *)\n";

/// OpenPLC v3 compiles an uploaded `.st` file with its CONFIGURATION (its editor writes one):
/// for a file without one, a configuration that runs every PROGRAM every 20 ms, OpenPLC v3's
/// default task. `None` when the file has a configuration or no program.
fn configuration(text: &str) -> Option<String> {
    let (unit, _) = sfc_syntax::parse(0, text);
    let mut programs = Vec::new();
    for item in &unit.items {
        match item {
            ast::Item::Verbatim(v) if v.keyword.eq_ignore_ascii_case("CONFIGURATION") => return None,
            ast::Item::Pou(p) if p.kind == ast::PouKind::Program => programs.push(p.name.text.clone()),
            _ => {}
        }
    }
    if programs.is_empty() {
        return None;
    }
    let mut c = String::from(
        "\n(* Added by sfc for MatIEC: OpenPLC v3 compiles a program with its configuration. This one\n   \
         runs every PROGRAM of the file every 20 ms (OpenPLC v3's default task): set INTERVAL to the\n   \
         scan period the chart was written for. *)\nCONFIGURATION Config0\n    RESOURCE Res0 ON PLC\n        \
         TASK task0(INTERVAL := T#20ms, PRIORITY := 0);\n",
    );
    for (k, p) in programs.iter().enumerate() {
        c.push_str(&format!("        PROGRAM instance{k} WITH task0 : {p};\n"));
    }
    c.push_str("    END_RESOURCE\nEND_CONFIGURATION\n");
    Some(c)
}

/// `codesys`: CODESYS's and TwinCAT's TIME counts milliseconds (finer durations are LTIME's),
/// so a duration with a part below the millisecond is refused where it is written (SFC0807),
/// not rounded.
pub(crate) fn codesys_limits(checked: &sfc_model::Checked, charts: &[&sfc_model::Chart]) -> Vec<Diagnostic> {
    let text = checked.file.text.as_str();
    let (tokens, _) = lex(0, text);
    let file = charts.first().map_or(0, |c| c.file);
    let mut out = Vec::new();
    for t in tokens.iter().filter(|t| t.kind == TokenKind::Typed) {
        let (s, e) = (t.start as usize, t.end as usize);
        let lit = &text[s..e];
        let Some((prefix, body)) = lit.split_once('#') else { continue };
        if !prefix.eq_ignore_ascii_case("T") && !prefix.eq_ignore_ascii_case("TIME") {
            continue;
        }
        let span = Span::new(file, t.start, t.end);
        if let Ok(us) = sfc_syntax::literal::decode_duration(body, span) {
            if us % 1000 != 0 {
                out.push(Diagnostic::error(
                    "SFC0807",
                    span,
                    format!(
                        "`{lit}` has a part below the millisecond, which CODESYS's and TwinCAT's TIME cannot hold (it counts milliseconds): write whole milliseconds for --st-dialect codesys"
                    ),
                ));
            }
        }
    }
    for c in charts {
        for s in &c.steps {
            if s.timeout.is_some_and(|us| us % 1000 != 0) {
                out.push(
                    Diagnostic::error(
                        "SFC0807",
                        s.name_span,
                        format!(
                            "the supervision time of step `{}` has a part below the millisecond, which CODESYS's and TwinCAT's TIME cannot hold",
                            s.name
                        ),
                    )
                    .with_element(&s.name),
                );
            }
        }
    }
    out
}

/// `(start, end, replacement)` edits applied from the last to the first.
fn apply(text: &str, mut edits: Vec<(usize, usize, String)>) -> String {
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = text.to_string();
    for (s, e, r) in edits {
        out.replace_range(s..e, &r);
    }
    out
}

fn pragmas_to_comments(text: &str) -> String {
    let (tokens, _) = lex(0, text);
    let edits = tokens
        .iter()
        .filter(|t| t.kind == TokenKind::Pragma)
        .map(|t| {
            let (s, e) = (t.start as usize, t.end as usize);
            (s, e, format!("(* pragma {} *)", text[s..e].replace("*)", "* )").replace("(*", "( *")))
        })
        .collect();
    apply(text, edits)
}

fn line_start(text: &str, at: usize) -> usize {
    text[..at].rfind('\n').map_or(0, |i| i + 1)
}

/// The position after the end of the line holding `at`.
fn line_end(text: &str, at: usize) -> usize {
    text[at..].find('\n').map_or(text.len(), |i| at + i + 1)
}

fn split_located(text: &str) -> String {
    let (unit, _) = sfc_syntax::parse(0, text);
    let mut edits = Vec::new();
    let mut block = |b: &ast::VarBlock| {
        if !matches!(b.kind, ast::VarKind::Var | ast::VarKind::Global) || b.decls.is_empty() {
            return;
        }
        let located: Vec<bool> = b.decls.iter().map(|d| d.location.is_some()).collect();
        if located.iter().all(|&l| l) || !located.iter().any(|&l| l) {
            return;
        }
        let (bs, be) = (b.span.start as usize, (b.span.end as usize).min(text.len()));
        if let Some(r) = split_by_lines(text, b, &located, bs, be) {
            edits.push((bs, be, r));
            return;
        }
        // Declarations on the keyword's line or END_VAR after one: written again, one per line.
        let header = text[bs..b.decls[0].span.start as usize].trim_end().to_string();
        let mut out = String::new();
        let mut k = 0;
        while k < b.decls.len() {
            if k > 0 {
                out.push_str("\n");
            }
            out.push_str(&header);
            out.push('\n');
            let kind = located[k];
            while k < b.decls.len() && located[k] == kind {
                let d = &b.decls[k];
                out.push_str(&format!("    {}\n", &text[d.span.start as usize..d.span.end as usize]));
                k += 1;
            }
            out.push_str("END_VAR");
        }
        edits.push((bs, be, out));
    };
    for item in &unit.items {
        match item {
            ast::Item::Pou(p) => p.var_blocks.iter().for_each(&mut block),
            ast::Item::Globals(b) => block(b),
            _ => {}
        }
    }
    apply(text, edits)
}

/// A block whose keyword line and `END_VAR` line hold nothing else, split between the lines of
/// two declarations of different kinds (the comments and blank lines before a declaration stay
/// with it).
fn split_by_lines(text: &str, b: &ast::VarBlock, located: &[bool], bs: usize, be: usize) -> Option<String> {
    let header_end = line_end(text, bs);
    if (b.decls[0].span.start as usize) < header_end {
        return None;
    }
    let header = text[bs..header_end].trim_end();
    let end_kw = be.checked_sub("END_VAR".len())?;
    let end_line = line_start(text, end_kw);
    let indent = &text[end_line..end_kw];
    if !indent.chars().all(|c| c == ' ' || c == '\t') {
        return None;
    }
    let mut out = text[bs..header_end].to_string();
    let mut cut = header_end;
    for k in 1..b.decls.len() {
        if located[k] == located[k - 1] {
            continue;
        }
        let eol = line_end(text, b.decls[k - 1].span.end as usize);
        if eol > b.decls[k].span.start as usize {
            return None;
        }
        out.push_str(&text[cut..eol]);
        out.push_str(&format!("{indent}END_VAR\n{indent}{header}\n"));
        cut = eol;
    }
    out.push_str(&text[cut..be]);
    Some(out)
}

/// `a, b, c : TON;` as `a : TON;` `b : TON;` `c : TON;` for every type that is not elementary.
fn one_instance_per_declaration(text: &str) -> String {
    let (unit, _) = sfc_syntax::parse(0, text);
    let mut edits = Vec::new();
    let mut block = |b: &ast::VarBlock| {
        for d in &b.decls {
            let named = match &d.ty.kind {
                ast::TypeSpecKind::Named(id) => sfc_st::Type::elementary(&id.text).is_none(),
                _ => false,
            };
            if d.names.len() < 2 || !named || d.location.is_some() {
                continue;
            }
            let (ds, de) = (d.span.start as usize, (d.span.end as usize).min(text.len()));
            let Some(last) = d.names.last() else { continue };
            let first = d.names[0].span.start as usize;
            let rest = &text[last.span.end as usize..de];
            let lead = &text[ds..first];
            let ls = line_start(text, ds);
            let indent: String = text[ls..ds].chars().take_while(|c| *c == ' ' || *c == '\t').collect();
            let parts: Vec<String> = d.names.iter().map(|n| format!("{}{rest}", n.text)).collect();
            edits.push((ds, de, format!("{lead}{}", parts.join(&format!("\n{indent}")))));
        }
    };
    for item in &unit.items {
        match item {
            ast::Item::Pou(p) => p.var_blocks.iter().for_each(&mut block),
            ast::Item::Globals(b) => block(b),
            _ => {}
        }
    }
    apply(text, edits)
}

/// The names an item declares for the others (POU, type, interface, global variable names).
fn declared(item: &ast::Item) -> Vec<String> {
    match item {
        ast::Item::Pou(p) => vec![p.name.text.to_ascii_uppercase()],
        ast::Item::Types(t) => t.decls.iter().map(|d| d.name.text.to_ascii_uppercase()).collect(),
        ast::Item::Globals(b) => {
            b.decls.iter().flat_map(|d| d.names.iter().map(|n| n.text.to_ascii_uppercase())).collect()
        }
        ast::Item::Interface(i) => vec![i.name.text.to_ascii_uppercase()],
        ast::Item::Verbatim(v) => v.name.iter().map(|n| n.text.to_ascii_uppercase()).collect(),
    }
}

/// Every item after the items it names (stable: an item moves only to follow what it uses; a
/// cycle keeps the written order). Each item moves with the text before it (its comments).
fn iec_order(text: &str) -> String {
    let (unit, _) = sfc_syntax::parse(0, text);
    let n = unit.items.len();
    if n < 2 {
        return text.to_string();
    }
    let names: Vec<Vec<String>> = unit.items.iter().map(declared).collect();
    let mut uses: Vec<Vec<usize>> = Vec::with_capacity(n);
    let mut prev_end = 0usize;
    let mut segments = Vec::with_capacity(n);
    for (i, item) in unit.items.iter().enumerate() {
        let span = item.span();
        let (s, e) = (span.start as usize, (span.end as usize).min(text.len()));
        let (tokens, _) = lex(0, &text[s..e]);
        let ids: HashSet<String> = tokens
            .iter()
            .filter(|t| t.kind == TokenKind::Ident)
            .map(|t| text[s + t.start as usize..s + t.end as usize].to_ascii_uppercase())
            .collect();
        uses.push((0..n).filter(|&j| j != i && names[j].iter().any(|x| ids.contains(x))).collect());
        segments.push((prev_end, e));
        prev_end = e;
    }
    let mut placed = vec![false; n];
    let mut order = Vec::with_capacity(n);
    while order.len() < n {
        let next = (0..n)
            .find(|&i| !placed[i] && uses[i].iter().all(|&j| placed[j]))
            .or_else(|| (0..n).find(|&i| !placed[i]))
            .unwrap_or(0);
        placed[next] = true;
        order.push(next);
    }
    if order.iter().enumerate().all(|(k, &i)| k == i) {
        return text.to_string();
    }
    let mut out = String::new();
    for &i in &order {
        let seg = &text[segments[i].0..segments[i].1];
        if out.is_empty() {
            out.push_str(seg.trim_start_matches(['\n', '\r']));
        } else {
            if !seg.starts_with('\n') && !seg.starts_with("\r\n") {
                out.push_str("\n\n");
            }
            out.push_str(seg);
        }
    }
    out.push_str(&text[prev_end..]);
    out
}

fn matiec_time_literals(text: &str) -> String {
    let (tokens, _) = lex(0, text);
    let mut edits = Vec::new();
    for t in tokens.iter().filter(|t| t.kind == TokenKind::Typed) {
        let (s, e) = (t.start as usize, t.end as usize);
        let lit = &text[s..e];
        let Some((prefix, body)) = lit.split_once('#') else { continue };
        if !prefix.eq_ignore_ascii_case("T") && !prefix.eq_ignore_ascii_case("TIME") {
            continue;
        }
        if let Ok(us) = sfc_syntax::literal::decode_duration(body, Span::new(0, 0, 0)) {
            let written = matiec_time_literal(us);
            if written != lit {
                edits.push((s, e, written));
            }
        }
    }
    apply(text, edits)
}

/// A TIME literal MatIEC reads exactly. `iec2c` writes a literal as
/// `((days·24 + hours)·60 + minutes)·60 + seconds + milliseconds/1000` seconds computed in
/// floating point (`long double` on x86-64, `double` on 32-bit ARM) and truncates the
/// nanoseconds, so `T#8ms` becomes 7.999999 ms; it refuses `us`. Whole days, hours, minutes and
/// seconds are exact, and so is a fraction of a second in 1/64 s steps; any other fraction is
/// written in milliseconds with half a nanosecond more (`T#8.0000005ms`), which the truncation
/// removes whatever the floating-point error (below 0.02 ns up to a day, even in `double`).
/// (No form is exact in both MatIEC and STruC++, which sums `parseFloat(part)·unit` in
/// nanoseconds and must get an integer: see docs/targets.md.)
pub fn matiec_time_literal(us: i64) -> String {
    if us == 0 {
        return "T#0s".to_string();
    }
    let abs = us.unsigned_abs();
    let (whole, sub) = (abs / 1_000_000, abs % 1_000_000);
    let mut out = String::from(if us < 0 { "T#-" } else { "T#" });
    let mut rest = whole;
    for (unit, size) in [("d", 86_400u64), ("h", 3_600), ("m", 60), ("s", 1)] {
        if rest >= size {
            out.push_str(&format!("{}{unit}", rest / size));
            rest %= size;
        }
    }
    if sub != 0 {
        let (ms, frac) = (sub / 1000, sub % 1000);
        if sub % 15_625 == 0 {
            // A dyadic fraction of a second: exact in binary.
            if frac == 0 {
                out.push_str(&format!("{ms}ms"));
            } else {
                let digits = format!("{frac:03}");
                out.push_str(&format!("{ms}.{}ms", digits.trim_end_matches('0')));
            }
        } else {
            out.push_str(&format!("{ms}.{frac:03}0005ms"));
        }
    }
    out
}
