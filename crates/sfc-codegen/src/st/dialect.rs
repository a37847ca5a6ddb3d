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
pub(crate) fn finish(text: &str, dialect: StDialect) -> (String, bool, Vec<String>) {
    let mut t = if dialect == StDialect::Codesys { text.to_string() } else { pragmas_to_comments(text) };
    let mut notes = Vec::new();
    if dialect != StDialect::Codesys {
        t = short_circuit_as_plain(&t);
    }
    if dialect == StDialect::Strucpp {
        for _ in 0..10_000 {
            match not_of_comparisons(&t) {
                Some(n) => t = n,
                None => break,
            }
        }
    }
    if dialect == StDialect::Matiec {
        for _ in 0..10_000 {
            match for_as_while(&t) {
                Some(n) => t = n,
                None => break,
            }
        }
    }
    if matches!(dialect, StDialect::Matiec | StDialect::Strucpp) {
        let (renamed, n) = rename_reserved(&t, dialect);
        t = renamed;
        notes = n;
    }
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
    }
    if matches!(dialect, StDialect::Matiec | StDialect::Strucpp) {
        // (`iec` keeps them where sfc reads them back: it does not analyse a configuration)
        t = globals_into_configuration(&t);
    }
    if dialect == StDialect::Strucpp {
        t = external_not_constant(&t);
    }
    if dialect == StDialect::Matiec {
        let exact = matiec_time_literals(&t);
        if exact != t {
            t = format!("{MATIEC_LITERALS}{exact}");
        }
    }
    (t, configured, notes)
}

const MATIEC_LITERALS: &str =
    "(* Written by sfc for MatIEC (--st-dialect matiec). A duration such as T#8.0000005ms is T#8ms:\n   \
MatIEC computes a TIME literal in floating point and truncates it to whole nanoseconds, so T#8ms\n   \
would be 7.999999 ms; the half nanosecond more is truncated away. *)\n";

/// IEC 61131-3 declares global variables in a CONFIGURATION or RESOURCE (a file-level
/// `VAR_GLOBAL`, as a PLCopen import of a configuration's globals or CODESYS's global variable
/// lists give, is CODESYS's): the file's `VAR_GLOBAL` blocks are moved to the start of its
/// first CONFIGURATION, where MatIEC and STruC++ find them. A file without one keeps them.
fn globals_into_configuration(text: &str) -> String {
    let (unit, _) = sfc_syntax::parse(0, text);
    let Some(config) = unit.items.iter().find_map(|i| match i {
        ast::Item::Verbatim(v) if v.keyword.eq_ignore_ascii_case("CONFIGURATION") => Some(v),
        _ => None,
    }) else {
        return text.to_string();
    };
    let globals: Vec<&ast::VarBlock> = unit
        .items
        .iter()
        .filter_map(|i| match i {
            ast::Item::Globals(b) => Some(b),
            _ => None,
        })
        .collect();
    if globals.is_empty() {
        return text.to_string();
    }
    let at = line_end(text, config.span.start as usize);
    let mut moved = String::new();
    let mut edits = Vec::new();
    for b in &globals {
        let (s, e) = (b.span.start as usize, (b.span.end as usize).min(text.len()));
        for l in text[s..e].lines() {
            moved.push_str(&format!("    {l}\n"));
        }
        edits.push((s, line_end(text, e.saturating_sub(1)).max(e), String::new()));
    }
    edits.push((at, at, moved));
    apply(text, edits)
}

/// STruC++ asks an initial value of a `VAR_EXTERNAL CONSTANT` declaration, which IEC 61131-3
/// forbids there (the value is the global's): `CONSTANT` is dropped from those blocks (a chart
/// that wrote the constant would not have checked).
fn external_not_constant(text: &str) -> String {
    let (unit, _) = sfc_syntax::parse(0, text);
    let (tokens, _) = lex(0, text);
    let mut edits = Vec::new();
    var_blocks(&unit, &mut |b| {
        if b.kind != ast::VarKind::External || !b.constant {
            return;
        }
        let (s, e) = (b.span.start as usize, b.span.end as usize);
        if let Some(t) = tokens.iter().find(|t| {
            t.start as usize >= s
                && (t.end as usize) <= e
                && text[t.start as usize..t.end as usize].eq_ignore_ascii_case("CONSTANT")
        }) {
            // the keyword and the space before it
            let from = text[..t.start as usize].trim_end_matches([' ', '\t']).len();
            edits.push((from, t.end as usize, String::new()));
        }
    });
    apply(text, edits)
}

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
    let file = charts.first().map_or(0, |c| c.file);
    let mut out = Vec::new();
    for (s, e, _) in time_literals(text).into_iter().filter(|l| l.2 % 1000 != 0) {
        let lit = &text[s..e];
        out.push(Diagnostic::error(
            "SFC0807",
            Span::new(file, s as u32, e as u32),
            format!(
                "`{lit}` has a part below the millisecond, which CODESYS's and TwinCAT's TIME cannot hold (it counts milliseconds): write whole milliseconds for --st-dialect codesys"
            ),
        ));
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

/// Every `VAR…END_VAR` block of the POUs and the file's globals.
fn var_blocks(unit: &ast::SourceUnit, f: &mut dyn FnMut(&ast::VarBlock)) {
    for item in &unit.items {
        match item {
            ast::Item::Pou(p) => p.var_blocks.iter().for_each(&mut *f),
            ast::Item::Globals(b) => f(b),
            _ => {}
        }
    }
}

/// Every identifier of `text`, upper-case (names a new one must not take).
fn identifiers(text: &str) -> HashSet<String> {
    let (tokens, _) = lex(0, text);
    tokens
        .iter()
        .filter(|t| t.kind == TokenKind::Ident)
        .map(|t| text[t.start as usize..t.end as usize].to_ascii_uppercase())
        .collect()
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
    var_blocks(&unit, &mut block);
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
    var_blocks(&unit, &mut block);
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

/// The TIME literals of `text` (`T#…`, `TIME#…`): where, and their value in µs.
fn time_literals(text: &str) -> Vec<(usize, usize, i64)> {
    let (tokens, _) = lex(0, text);
    tokens
        .iter()
        .filter(|t| t.kind == TokenKind::Typed)
        .filter_map(|t| {
            let (s, e) = (t.start as usize, t.end as usize);
            let (prefix, body) = text[s..e].split_once('#')?;
            if !prefix.eq_ignore_ascii_case("T") && !prefix.eq_ignore_ascii_case("TIME") {
                return None;
            }
            let us = sfc_syntax::literal::decode_duration(body, Span::new(0, 0, 0)).ok()?;
            Some((s, e, us))
        })
        .collect()
}

fn matiec_time_literals(text: &str) -> String {
    let edits = time_literals(text)
        .into_iter()
        .map(|(s, e, us)| (s, e, matiec_time_literal(us)))
        .filter(|(s, e, written)| *written != text[*s..*e])
        .collect();
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

// ---------------------------------------------------------------------------------------------
// Names the compilers reserve

/// MatIEC's standard functions (its `lib/`), which `iec2c` reserves: a variable, step or POU of
/// that name is "an invalid declaration". Their typed forms (`ADD_INT`, `LEFT_STRING`…) and the
/// conversions (`INT_TO_REAL`) are reserved too; see [`matiec_reserved`].
const MATIEC_FUNCTIONS: &str = "ABS ACOS ADD AND ASIN ATAN CONCAT COS DELETE DIV DIVTIME EQ EXP EXPT FIND GE GT \
INSERT LE LEFT LEN LIMIT LN LOG LT MAX MID MIN MOD MOVE MUL MULTIME MUX NE NOT OR REPLACE RIGHT ROL ROR SEL \
SHL SHR SIN SQRT SUB TAN TRUNC XOR";

/// What `iec2c` reads as keywords that sfc reads as names.
const MATIEC_KEYWORDS: &str = "DT TOD DATE_AND_TIME TIME_OF_DAY EN ENO ON WITH TASK SINGLE INTERVAL PRIORITY RESOURCE \
CONFIGURATION READ_ONLY READ_WRITE";

const IEC_TYPES: &str =
    "BOOL BYTE WORD DWORD LWORD SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL TIME DATE TOD DT STRING";

/// The functions of STruC++'s bundled libraries (0.6.1: `iec-std-functions` and OSCAT Basic
/// 3.35, which it loads by default): an instance of a function block called `Name(…)` whose name
/// is one of them is read as a call of the function ("'INC' is missing required inputs").
const STRUCPP_FUNCTIONS: &str =
    "ABS ACOS ACOSH ACOTH ADD ADR AGDF AIN AND AOUT AOUT1 ARRAY_AVG ARRAY_GAV ARRAY_HAV ARRAY_MAX \
ARRAY_MIN ARRAY_SDV ARRAY_SPR ARRAY_SUM ARRAY_TREND ARRAY_VAR ASIN ASINH ATAN ATAN2 ATANH \
BAND_B BCDC_TO_INT BETA BFT_TO_MS BINOM BIN_TO_BYTE BIN_TO_DWORD BIT_COUNT BIT_LOAD_B \
BIT_LOAD_B2 BIT_LOAD_DW BIT_LOAD_DW2 BIT_LOAD_W BIT_LOAD_W2 BIT_OF_DWORD BIT_TOGGLE_B \
BIT_TOGGLE_DW BIT_TOGGLE_W BUFFER_COMP BUFFER_SEARCH BUFFER_TO_STRING BYTE_OF_BIT \
BYTE_OF_DWORD BYTE_TO_GRAY BYTE_TO_RANGE BYTE_TO_STRB BYTE_TO_STRH CABS CACOS CACOSH CADD \
CAPITALIZE CARG CASIN CASINH CATAN CATANH CAUCHY CAUCHYCD CCON CCOS CCOSH CDIV CEIL CEIL2 \
CEXP CHARCODE CHARNAME CHECK_PARITY CHK_REAL CHR_TO_STRING CINV CIRCLE_A CIRCLE_C CIRCLE_SEG \
CLEAN CLOG CMP CMUL CODE CONCAT CONE_V COS COSH COTH COUNT_CHAR COUNT_SUBSTRING CPOL CPOW \
CRC_GEN CSET CSIN CSINH CSQRT CSUB CTAN CTANH CTRL_IN CURRENT_DT C_TO_F C_TO_K DATE_ADD \
DAYS_DELTA DAYS_IN_MONTH DAYS_IN_YEAR DAY_OF_DATE DAY_OF_MONTH DAY_OF_WEEK DAY_OF_YEAR \
DAY_TO_TIME DEAD_BAND DEAD_ZONE DEC1 DEC_TO_BYTE DEC_TO_DWORD DEC_TO_INT DEG DEG_TO_DIR \
DELETE DEL_CHARS DIFFER DIR_TO_DEG DIV DST DT2_TO_SDT DT_TO_SDT DT_TO_STRF DWORD_OF_BYTE \
DWORD_OF_WORD DWORD_TO_STRB DWORD_TO_STRF DWORD_TO_STRH DW_TO_REAL D_TRUNC EASTER ELLIPSE_A \
ELLIPSE_C EQ ERF ERFC EVEN EXEC EXP EXP10 EXPN EXPT FACT FIB FILL FIND FINDB FINDB_NONUM \
FINDB_NUM FINDP FIND_CHAR FIND_CTRL FIND_NONUM FIND_NUM FIX FLOAT_TO_REAL FLOOR FLOOR2 FRACT \
FRMP_B FSTRING_TO_BYTE FSTRING_TO_DT FSTRING_TO_DWORD FSTRING_TO_MONTH FSTRING_TO_WEEK \
FSTRING_TO_WEEKDAY F_LIN F_LIN2 F_POLY F_POWER F_QUAD F_TO_C F_TO_OM F_TO_PT GAMMA GAUSS \
GAUSSCD GCD GDF GE GEO_TO_DEG GOLD GRAY_TO_BYTE GT HEX_TO_BYTE HEX_TO_DWORD HOUR HOUR_OF_DT \
HOUR_TO_TIME HOUR_TO_TOD HYPOT INC INC1 INC2 INSERT INT_TO_BCDC INV ISC_ALPHA ISC_CTRL \
ISC_HEX ISC_LOWER ISC_NUM ISC_UPPER IS_ALNUM IS_ALPHA IS_CC IS_CTRL IS_HEX IS_LOWER IS_NCC \
IS_NUM IS_SORTED IS_UPPER JD2000 KMH_TO_MS K_TO_C LAMBERT_W LANGEVIN LE LEAP_DAY \
LEAP_OF_DATE LEAP_YEAR LEFT LEN LIMIT LINEAR_INT LIST_ADD LIST_CLEAN LIST_GET LIST_INSERT \
LIST_LEN LIST_RETRIEVE LIST_RETRIEVE_LAST LN LOG LOWERCASE LOWER_BOUND LT LTIME_TO_UTC \
MANUAL MAX MAX3 MEMCPY MID MID3 MIN MIN3 MINUTE MINUTE_OF_DT MINUTE_TO_TIME MIRROR MIX MOD \
MODR MONTH_BEGIN MONTH_END MONTH_OF_DATE MONTH_TO_STRING MOVE MS_TO_BFT MS_TO_KMH MUL \
MULTIME MULTI_IN MUL_ADD MUX MUX_2 MUX_4 MUX_R2 MUX_R4 NE NEG NEGX NOT OCT_TO_BYTE \
OCT_TO_DWORD OFFSET OFFSET2 OM_TO_F OR OSCAT_VERSION OVERRIDE PARITY PERIOD PERIOD2 \
POLYNOM_INT PT_TO_F R2_ABS R2_ADD R2_ADD2 R2_MUL R2_SET RAD RANGE_TO_BYTE RANGE_TO_WORD RDM \
RDM2 RDMDW REAL_TO_DW REAL_TO_FRAC REAL_TO_STRF REFLECT REFRACTION REF_LINK REPLACE \
REPLACE_ALL REPLACE_CHARS REPLACE_UML RES_NI RES_NTC RES_PT RES_SI REVERSE RIGHT RND ROL ROR \
ROUND SCALE SCALE_B SCALE_B2 SCALE_B4 SCALE_B8 SCALE_D SCALE_R SCALE_X2 SCALE_X4 SCALE_X8 \
SDT_TO_DATE SDT_TO_DT SDT_TO_TOD SECOND SECOND_OF_DT SECOND_TO_TIME SEL SENSOR_INT SET_DATE \
SET_DT SET_TOD SGN SHL SHL1 SHR SHR1 SIGMOID SIGN_I SIGN_R SIN SINC SINH SIZEOF SPHERE_V \
SQRT SQRTN STAIR STATUS_TO_ESR SUB SUN_MIDDAY SWAP_BYTE SWAP_BYTE2 TAN TANC TANH TEMP_NI \
TEMP_NTC TEMP_PT TEMP_SI TIME TIMECHECK TIME_FROM_MS TIME_FROM_S TIME_TO_MS TIME_TO_S \
TO_BOOL TO_BYTE TO_DATE TO_DINT TO_DT TO_DWORD TO_INT TO_LINT TO_LOWER TO_LREAL TO_LWORD \
TO_REAL TO_SINT TO_STRING TO_TIME TO_TOD TO_UDINT TO_UINT TO_ULINT TO_UML TO_UPPER TO_USINT \
TO_WORD TRIANGLE_A TRIM TRIM1 TRIME TRUNC T_PLC_MS T_PLC_US UPPERCASE UPPER_BOUND \
UTC_TO_LTIME V3_ABS V3_ADD V3_ANG V3_DPRO V3_NORM V3_NUL V3_PAR V3_REV V3_SMUL V3_SUB \
V3_XANG V3_XPRO V3_YANG V3_ZANG WEEKDAY_TO_STRING WINDOW WINDOW2 WORD_OF_BYTE WORD_OF_DWORD \
WORD_TO_RANGE WORK_WEEK XOR YEAR_BEGIN YEAR_END YEAR_OF_DATE _ARRAY_ABS _ARRAY_ADD \
_ARRAY_INIT _ARRAY_MEDIAN _ARRAY_MUL _ARRAY_SHUFFLE _ARRAY_SORT _BUFFER_CLEAR _BUFFER_INIT \
_BUFFER_INSERT _BUFFER_UPPERCASE _STRING_TO_BUFFER";

fn matiec_reserved(upper: &str) -> bool {
    let types: Vec<&str> = IEC_TYPES.split(' ').collect();
    if MATIEC_FUNCTIONS.split(' ').any(|f| f == upper) || MATIEC_KEYWORDS.split(' ').any(|k| k == upper) {
        return true;
    }
    // ADD_INT, MUX_DINT_BOOL, INT_TO_REAL
    if let Some((a, b)) = upper.split_once("_TO_") {
        return types.contains(&a) && types.contains(&b);
    }
    let mut parts = upper.split('_');
    let base = parts.next().unwrap_or("");
    let rest: Vec<&str> = parts.collect();
    !rest.is_empty()
        && (MATIEC_FUNCTIONS.split(' ').any(|f| f == base) || base == "DIVTIME" || base == "MULTIME")
        && rest.iter().all(|r| types.contains(r))
}

/// Declared names (upper-case) with whether a call `Name(…)` of them is possible (a function
/// block instance, a POU), each once.
fn declared_names(unit: &ast::SourceUnit) -> Vec<(String, bool)> {
    let mut out: Vec<(String, bool)> = Vec::new();
    let mut add = |n: &str, callable: bool| {
        let u = n.to_ascii_uppercase();
        match out.iter_mut().find(|(x, _)| *x == u) {
            Some(e) => e.1 |= callable,
            None => out.push((u, callable)),
        }
    };
    // (a variable of a structure or enumeration of the file is not called)
    let types: HashSet<String> = unit
        .items
        .iter()
        .filter_map(|i| match i {
            ast::Item::Types(t) => Some(t.decls.iter().map(|d| d.name.text.to_ascii_uppercase())),
            _ => None,
        })
        .flatten()
        .collect();
    let decls = |blocks: &[ast::VarBlock], add: &mut dyn FnMut(&str, bool)| {
        for d in blocks.iter().flat_map(|b| &b.decls) {
            let callable = matches!(&d.ty.kind, ast::TypeSpecKind::Named(id)
                if sfc_st::Type::elementary(&id.text).is_none() && !types.contains(&id.text.to_ascii_uppercase()));
            for n in &d.names {
                add(&n.text, callable);
            }
        }
    };
    for item in &unit.items {
        match item {
            ast::Item::Pou(p) => {
                add(&p.name.text, true);
                decls(&p.var_blocks, &mut add);
            }
            ast::Item::Globals(b) => decls(std::slice::from_ref(b), &mut add),
            ast::Item::Types(t) => {
                for d in &t.decls {
                    add(&d.name.text, false);
                    if let ast::TypeSpecKind::Struct(fields) = &d.spec.kind {
                        for f in fields.iter().flat_map(|f| &f.names) {
                            add(&f.text, false);
                        }
                    }
                }
            }
            _ => {}
        }
    }
    out
}

/// Renames, everywhere in the file, every declared name the compiler reserves (`Left` →
/// `Left_1`): each identifier of that spelling, but for a call `NAME(` of a name that cannot be
/// called (the standard function itself). The messages say what was renamed and why.
fn rename_reserved(text: &str, dialect: StDialect) -> (String, Vec<String>) {
    let (unit, _) = sfc_syntax::parse(0, text);
    let (tokens, _) = lex(0, text);
    let mut taken = identifiers(text);
    let mut renames: Vec<(String, bool, String)> = Vec::new();
    let mut notes = Vec::new();
    for (name, callable) in declared_names(&unit) {
        let (reserved, why) = match dialect {
            StDialect::Matiec => {
                (matiec_reserved(&name), "MatIEC reserves it (a standard function or keyword of iec2c)")
            }
            StDialect::Strucpp => (
                callable && STRUCPP_FUNCTIONS.split_whitespace().any(|f| f == name),
                "STruC++ reads a call of it as a call of the function of its library",
            ),
            _ => (false, ""),
        };
        if !reserved {
            continue;
        }
        let spelled = tokens
            .iter()
            .map(|t| &text[t.start as usize..t.end as usize])
            .find(|s| s.eq_ignore_ascii_case(&name))
            .unwrap_or(&name)
            .to_string();
        let mut k = 1;
        while taken.contains(&format!("{name}_{k}")) {
            k += 1;
        }
        let new = format!("{spelled}_{k}");
        taken.insert(new.to_ascii_uppercase());
        notes.push(format!("renamed `{spelled}` to `{new}` in the whole file: {why}"));
        renames.push((name, callable, new));
    }
    if renames.is_empty() {
        return (text.to_string(), notes);
    }
    let mut edits = Vec::new();
    for (i, t) in tokens.iter().enumerate() {
        if t.kind != TokenKind::Ident {
            continue;
        }
        let word = &text[t.start as usize..t.end as usize];
        let Some((_, callable, new)) = renames.iter().find(|(n, _, _)| word.eq_ignore_ascii_case(n)) else { continue };
        let next = tokens[i + 1..]
            .iter()
            .find(|n| !matches!(n.kind, TokenKind::Whitespace | TokenKind::BlockComment | TokenKind::LineComment));
        // After a `.` the name is a member (a field, an output): renamed with the declaration.
        let called = next.is_some_and(|n| n.kind == TokenKind::LParen);
        if called && !callable {
            continue;
        }
        edits.push((t.start as usize, t.end as usize, new.clone()));
    }
    (apply(text, edits), notes)
}

// ---------------------------------------------------------------------------------------------
// Statements and expressions the compilers read otherwise

/// Every statement list of the file's POUs (bodies, actions), outermost first.
fn stmt_lists<'u>(unit: &'u ast::SourceUnit, f: &mut dyn FnMut(&'u [ast::Stmt])) {
    fn walk<'u>(list: &'u [ast::Stmt], f: &mut dyn FnMut(&'u [ast::Stmt])) {
        f(list);
        for s in list {
            match &s.kind {
                ast::StmtKind::If { branches, else_body } => {
                    branches.iter().for_each(|(_, b)| walk(b, f));
                    if let Some(b) = else_body {
                        walk(b, f);
                    }
                }
                ast::StmtKind::Case { arms, else_body, .. } => {
                    arms.iter().for_each(|a| walk(&a.body, f));
                    if let Some(b) = else_body {
                        walk(b, f);
                    }
                }
                ast::StmtKind::For { body, .. }
                | ast::StmtKind::While { body, .. }
                | ast::StmtKind::Repeat { body, .. } => walk(body, f),
                _ => {}
            }
        }
    }
    for item in &unit.items {
        if let ast::Item::Pou(p) = item {
            if let ast::Body::St(list) = &p.body {
                walk(list, f);
            }
            for a in &p.actions {
                if let ast::ActionBody::St(list) = &a.body {
                    walk(list, f);
                }
            }
        }
    }
}

/// An integer literal (with its sign), as written.
fn int_literal(e: &ast::Expr, text: &str) -> Option<i64> {
    let t = text[e.span.start as usize..e.span.end as usize].replace(['_', ' ', '(', ')'], "");
    t.parse().ok()
}

/// `matiec`: `iec2c` compiles `FOR i := a TO b` into a loop that stops with `i = b` (sfc: one
/// step past it) and runs no iteration when `a = b`. Each FOR becomes the loop sfc runs:
/// `i := a; WHILE i <= b DO … i := i + step; END_WHILE;` (end and step computed once, into
/// variables declared for it when they are not literals). One loop per pass, outermost first.
fn for_as_while(text: &str) -> Option<String> {
    let (unit, _) = sfc_syntax::parse(0, text);
    let mut found: Option<&ast::Stmt> = None;
    stmt_lists(&unit, &mut |list| {
        if found.is_none() {
            found = list.iter().find(|s| matches!(s.kind, ast::StmtKind::For { .. }));
        }
    });
    let s = found?;
    let ast::StmtKind::For { var, from, to, by, body } = &s.kind else { return None };
    let src = |e: &ast::Expr| text[e.span.start as usize..e.span.end as usize].to_string();
    let pou = unit.items.iter().find_map(|i| match i {
        ast::Item::Pou(p) if p.span.start <= s.span.start && s.span.end <= p.span.end => Some(p),
        _ => None,
    })?;
    let var_type = pou
        .var_blocks
        .iter()
        .flat_map(|b| &b.decls)
        .find(|d| d.names.iter().any(|n| n.text.eq_ignore_ascii_case(&var.text)))
        .map(|d| text[d.ty.span.start as usize..d.ty.span.end as usize].to_string())
        .unwrap_or_else(|| "DINT".to_string());
    let taken = identifiers(text);
    let fresh = |base: &str| {
        let mut k = 1;
        while taken.contains(&format!("{base}{k}").to_ascii_uppercase()) {
            k += 1;
        }
        format!("{base}{k}")
    };
    let ls = line_start(text, s.span.start as usize);
    let indent: String = text[ls..s.span.start as usize].chars().take_while(|c| *c == ' ' || *c == '\t').collect();
    let i = &var.text;
    let mut head = Vec::new();
    let mut temps = Vec::new();
    let end = match int_literal(to, text) {
        Some(v) => v.to_string(),
        None => {
            let n = fresh("SfcForEnd");
            head.push(format!("{n} := {};", src(to)));
            temps.push(n.clone());
            n
        }
    };
    let step_lit = match by {
        None => Some(1),
        Some(b) => int_literal(b, text),
    };
    let step = match (step_lit, by) {
        (Some(v), _) => v.to_string(),
        (None, Some(b)) => {
            let n = fresh("SfcForBy");
            head.push(format!("{n} := {};", src(b)));
            temps.push(n.clone());
            n
        }
        (None, None) => "1".to_string(),
    };
    let cond = match step_lit {
        Some(v) if v >= 0 => format!("{i} <= {end}"),
        Some(_) => format!("{i} >= {end}"),
        None => format!("({step} >= 0 AND {i} <= {end}) OR ({step} < 0 AND {i} >= {end})"),
    };
    let plus = if step.starts_with('-') { format!("({step})") } else { step.clone() };
    // `END_FOR` alone on its line: the body is every line before it (its comments too)
    let stmt_text = &text[s.span.start as usize..s.span.end as usize];
    let end_for = stmt_text.to_ascii_uppercase().rfind("END_FOR").map(|i| s.span.start as usize + i);
    let body_text = match (body.first(), body.last()) {
        // the body's own lines, or (a loop written on one line) its statements, indented
        (Some(a), Some(b)) if line_start(text, a.span.start as usize) > s.span.start as usize => {
            let from = line_start(text, a.span.start as usize);
            let to = match end_for {
                Some(e)
                    if text[line_start(text, e)..e].trim().is_empty() && line_start(text, e) > b.span.end as usize =>
                {
                    line_start(text, e) - 1
                }
                _ => b.span.end as usize,
            };
            text[from..to].trim_end().to_string()
        }
        (Some(a), Some(b)) => format!("{indent}    {}", &text[a.span.start as usize..b.span.end as usize]),
        _ => String::new(),
    };
    let mut out = String::new();
    out.push_str(&format!(
        "(* FOR {i} := {} TO {}{} DO, as sfc runs it: MatIEC's FOR stops at the end value *)\n",
        src(from),
        src(to),
        by.as_ref().map(|b| format!(" BY {}", src(b))).unwrap_or_default()
    ));
    for h in &head {
        out.push_str(&format!("{indent}{h}\n"));
    }
    out.push_str(&format!("{indent}{i} := {};\n{indent}WHILE {cond} DO\n", src(from)));
    if !body_text.is_empty() {
        out.push_str(&body_text);
        out.push('\n');
    }
    out.push_str(&format!("{indent}    {i} := {i} + {plus};\n{indent}END_WHILE"));
    // IEC ends every statement with `;` (sfc does not insist on the last one): one after
    // END_WHILE, whether the FOR had it inside its text, right after it, or not at all.
    let after_has_semi = text[s.span.end as usize..].trim_start().starts_with(';');
    if stmt_text.trim_end().ends_with(';') || !after_has_semi {
        out.push(';');
    }
    let mut edits = vec![(s.span.start as usize, s.span.end as usize, out)];
    if !temps.is_empty() {
        let last = pou.var_blocks.last()?;
        let decl: String = temps.iter().map(|t| format!("        {t} : {var_type};\n")).collect();
        edits.push((last.span.end as usize, last.span.end as usize, format!("\n    VAR\n{decl}    END_VAR")));
    }
    Some(apply(text, edits))
}

/// The outermost `NOT x` whose operand is an AND/OR/XOR of comparisons (so BOOL), as
/// `(x = FALSE)`: STruC++ writes `NOT((a >= b) & (c > d))`, whose operand C++ makes an `int`,
/// for which its runtime has no NOT. One per pass.
fn not_of_comparisons(text: &str) -> Option<String> {
    fn logic_of_comparisons(e: &ast::Expr) -> bool {
        match &e.kind {
            ast::ExprKind::Paren(i) => logic_of_comparisons(i),
            ast::ExprKind::Binary { op, lhs, rhs } => match op {
                ast::BinaryOp::And | ast::BinaryOp::Or | ast::BinaryOp::Xor => {
                    let cmp = |x: &ast::Expr| {
                        let mut x = x;
                        while let ast::ExprKind::Paren(i) = &x.kind {
                            x = i;
                        }
                        matches!(&x.kind, ast::ExprKind::Binary { op, .. } if matches!(op, ast::BinaryOp::Eq | ast::BinaryOp::Ne | ast::BinaryOp::Lt | ast::BinaryOp::Gt | ast::BinaryOp::Le | ast::BinaryOp::Ge))
                    };
                    cmp(lhs) || cmp(rhs) || logic_of_comparisons(lhs) || logic_of_comparisons(rhs)
                }
                _ => false,
            },
            _ => false,
        }
    }
    let (unit, _) = sfc_syntax::parse(0, text);
    let mut found: Option<(usize, usize, String)> = None;
    for item in &unit.items {
        if let ast::Item::Pou(p) = item {
            sfc_syntax::visit::pou_exprs(p, &mut |e| {
                if found.is_some() {
                    return;
                }
                if let ast::ExprKind::Unary { op: ast::UnaryOp::Not, operand } = &e.kind {
                    if logic_of_comparisons(operand) {
                        let inner = &text[operand.span.start as usize..operand.span.end as usize];
                        found = Some((e.span.start as usize, e.span.end as usize, format!("({inner} = FALSE)")));
                    }
                }
            });
        }
    }
    found.map(|(s, e, r)| apply(text, vec![(s, e, r)]))
}

/// `AND_THEN` and `OR_ELSE` (CODESYS's short-circuit operators) as `AND` and `OR`, which give
/// the same value when the right operand cannot fault ([`short_circuits`] refuses the others).
fn short_circuit_as_plain(text: &str) -> String {
    let (tokens, _) = lex(0, text);
    let edits = tokens
        .iter()
        .filter(|t| t.kind == TokenKind::Ident)
        .filter_map(|t| {
            let w = &text[t.start as usize..t.end as usize];
            if w.eq_ignore_ascii_case("AND_THEN") {
                Some((t.start as usize, t.end as usize, "AND".to_string()))
            } else if w.eq_ignore_ascii_case("OR_ELSE") {
                Some((t.start as usize, t.end as usize, "OR".to_string()))
            } else {
                None
            }
        })
        .collect();
    apply(text, edits)
}

/// SFC0809 for `a AND_THEN b` / `a OR_ELSE b` whose `b` may fault (a division, an index, a
/// call): written as `AND`/`OR` for a compiler without them, `b` would be evaluated where the
/// chart skips it.
pub(crate) fn short_circuits(checked: &sfc_model::Checked, dialect: StDialect) -> Vec<Diagnostic> {
    if dialect == StDialect::Codesys {
        return Vec::new();
    }
    let mut out = Vec::new();
    // (a fresh parse: the checked unit lent its action bodies and conditions to the charts)
    let file = checked.charts.first().map_or(0, |c| c.file);
    let (unit, _) = sfc_syntax::parse(file, &checked.file.text);
    for item in &unit.items {
        if let ast::Item::Pou(p) = item {
            sfc_syntax::visit::pou_exprs(p, &mut |e| {
                if let ast::ExprKind::Binary {
                    op: op @ (ast::BinaryOp::AndThen | ast::BinaryOp::OrElse), rhs, ..
                } = &e.kind
                {
                    if !super::il::cannot_fault(rhs) {
                        let name = if *op == ast::BinaryOp::AndThen { "AND_THEN" } else { "OR_ELSE" };
                        out.push(Diagnostic::error(
                            "SFC0809",
                            e.span,
                            format!(
                                "`{name}` whose right operand is a call, a division or an index (it may act or fault) has no form in IEC 61131-3 ST that skips it: write it as an IF, or build with --st-dialect codesys"
                            ),
                        ));
                    }
                }
            });
        }
    }
    out
}
