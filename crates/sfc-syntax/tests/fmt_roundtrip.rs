//! Properties of the canonical printer (`sfc fmt`): printing is idempotent, printing then parsing
//! gives back the same tree (spans aside), and no comment or pragma is ever lost. Checked on
//! generated programs and charts (with comments at random token boundaries) and on every textual
//! file the project and the shared corpus hold.

use proptest::prelude::*;
use sfc_syntax::{parse, print::print};
use std::path::{Path, PathBuf};

// -- The properties ---------------------------------------------------------------------------

/// The tree's Debug form without spans (offsets change when the layout does).
fn shape(unit: &sfc_syntax::ast::SourceUnit) -> String {
    strip_spans(&format!("{:?}", unit.items))
}

/// Replaces every `Span { file: …, start: …, end: … }` with `_`.
fn strip_spans(debug: &str) -> String {
    const OPEN: &str = "Span { ";
    let mut out = String::with_capacity(debug.len());
    let mut rest = debug;
    while let Some(at) = rest.find(OPEN) {
        out.push_str(&rest[..at]);
        out.push('_');
        let after = &rest[at + OPEN.len()..];
        // A span holds only numbers, so its first `}` closes it.
        let close = after.find('}').expect("a span's Debug form is closed");
        rest = &after[close + 1..];
    }
    out.push_str(rest);
    out
}

/// The text of every comment and pragma, in order.
fn trivia_texts(unit: &sfc_syntax::ast::SourceUnit) -> Vec<String> {
    unit.trivia.iter().map(|t| t.text.clone()).collect()
}

fn parse_clean(text: &str, what: &str) -> sfc_syntax::ast::SourceUnit {
    let (unit, diags) = parse(0, text);
    let errors: Vec<_> =
        diags.iter().filter(|d| d.severity == sfc_diagnostics::Severity::Error).map(|d| (d.code, &d.message, d.span)).collect();
    assert!(errors.is_empty(), "{what} does not parse cleanly: {errors:?}\n--- text ---\n{text}");
    unit
}

/// Checks every property on one source text that parses without errors.
fn check_roundtrip(source: &str, what: &str) {
    let original = parse_clean(source, what);
    let printed = print(&original);
    let reparsed = parse_clean(&printed, &format!("the printed form of {what}"));
    assert_eq!(shape(&reparsed), shape(&original), "{what}: printing changed the tree\n--- printed ---\n{printed}");
    assert_eq!(
        trivia_texts(&reparsed),
        trivia_texts(&original),
        "{what}: comments or pragmas changed\n--- printed ---\n{printed}"
    );
    let again = print(&reparsed);
    assert_eq!(again, printed, "{what}: printing is not idempotent\n--- first ---\n{printed}\n--- second ---\n{again}");
    assert!(printed.is_empty() || printed.ends_with('\n') && !printed.ends_with("\n\n"), "{what}: one final newline");
    for line in printed.lines() {
        // Comment text is kept exactly, so only lines of code must be free of trailing blanks.
        if !line.contains("(*") && !line.contains("//") && !line.contains('{') {
            assert_eq!(line, line.trim_end(), "{what}: trailing blanks in {line:?}");
        }
    }
}

// -- Files --------------------------------------------------------------------------------------

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every `.st` file under `dir` (none when it does not exist yet).
fn st_files(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else { return found };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            found.extend(st_files(&path));
        } else if path.extension().is_some_and(|e| e == "st") {
            found.push(path);
        }
    }
    found.sort();
    found
}

#[test]
fn project_files_roundtrip() {
    let root = root();
    let mut files = st_files(&root.join("examples"));
    files.extend(st_files(&root.join("tests/fixtures/valid")));
    let matiec = root.join("../shared/corpus/matiec/sfc.txt");
    if matiec.exists() {
        files.push(matiec);
    }
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        check_roundtrip(&text, &file.display().to_string());
    }
}

#[test]
fn comments_everywhere_survive() {
    let source = "\
(* file header *)
{attribute 'sfc.target' := 'blank'}
PROGRAM Mixer (* after the name *)
VAR // the variables
    (* before a declaration *)
    a, b : BOOL := TRUE; (* after a declaration *)
    t AT %QX1 : INT (0..100) := 5;
    {attribute 'sfc.description' := 'between declarations'}
    arr : ARRAY [1..3] OF INT := [3(0)];
    (* before END_VAR *)
END_VAR
(* before the first element *)
{attribute 'sfc.tag' := '0'}
INITIAL_STEP Init: (* inside an empty step *) END_STEP
// between elements
STEP Fill:
    Pump(N); (* end of association *)
    (* between associations *)
    Valve(L, T#5s);
END_STEP
TRANSITION FROM Init TO Fill (* before the condition *)
    := a AND (* inside the condition *) b; // after it
END_TRANSITION
TRANSITION FROM Fill TO Init := NOT a; END_TRANSITION
ACTION Pump:
    IF a THEN (* after THEN *)
        t := t + 1; (* end of statement *)
    (* before ELSIF *)
    ELSIF b THEN
        t := (* inside an expression *) 0;
    ELSE (* after ELSE *)
        t := 1;
        // before END_IF
    END_IF; (* after END_IF *)
END_ACTION
ACTION Valve: END_ACTION
END_PROGRAM (* after END_PROGRAM *)
// at the end of the file
(* really the end *)";
    check_roundtrip(source, "the comment test");
}

// -- Generated programs -------------------------------------------------------------------------

/// Stands for a token boundary in generated text; each becomes a random separator.
const GAP: char = '\u{1}';

/// What may stand between two tokens: white space and comments of every kind.
const SEPARATORS: &[&str] = &[
    " ",
    " ",
    " ",
    " ",
    "\n",
    "\n    ",
    "  ",
    " (* c *) ",
    "(*x*)",
    "\n(* own line *)\n",
    " // end of line\n",
    "\n// own line\n",
    "\n\n",
];

/// Replaces each gap with a separator chosen by `choices`.
fn fill_gaps(template: &str, choices: &[usize]) -> String {
    let mut out = String::with_capacity(template.len() * 2);
    let mut k = 0;
    for c in template.chars() {
        if c == GAP {
            out.push_str(SEPARATORS[choices[k % choices.len()] % SEPARATORS.len()]);
            k += 1;
        } else {
            out.push(c);
        }
    }
    out
}

/// Joins tokens with gaps.
fn toks(parts: &[&str]) -> String {
    parts.join(&GAP.to_string())
}

fn keyword(word: &'static str) -> impl Strategy<Value = String> {
    // Keywords are case-insensitive; the printer upper-cases them.
    prop_oneof![Just(word.to_string()), Just(word.to_ascii_lowercase())]
}

fn name() -> impl Strategy<Value = String> {
    prop_oneof![Just("a"), Just("Flag"), Just("count"), Just("x_1"), Just("Speed")].prop_map(String::from)
}

fn literal() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("0"),
        Just("42"),
        Just("1_000"),
        Just("16#FF"),
        Just("2.5"),
        Just("1.0E-3"),
        Just("TRUE"),
        Just("false"),
        Just("T#5s"),
        Just("t#1h2m"),
        Just("INT#-5"),
        Just("'text'"),
    ]
    .prop_map(String::from)
}

fn expression() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        3 => name(),
        3 => literal(),
        1 => name().prop_map(|n| toks(&[&n, ".", "X"])),
        1 => (name(), literal()).prop_map(|(n, i)| toks(&[&n, "[", &i, "]"])),
    ];
    leaf.prop_recursive(4, 24, 3, |inner| {
        let op = prop_oneof![
            Just("+"),
            Just("-"),
            Just("*"),
            Just("/"),
            Just("MOD"),
            Just("mod"),
            Just("**"),
            Just("AND"),
            Just("and"),
            Just("&"),
            Just("OR"),
            Just("XOR"),
            Just("="),
            Just("<>"),
            Just("<"),
            Just(">"),
            Just("<="),
            Just(">="),
        ];
        prop_oneof![
            4 => (inner.clone(), op, inner.clone()).prop_map(|(a, op, b)| toks(&[&a, op, &b])),
            2 => inner.clone().prop_map(|a| toks(&["(", &a, ")"])),
            1 => inner.clone().prop_map(|a| toks(&["-", &a])),
            1 => (keyword("NOT"), inner.clone()).prop_map(|(not, a)| toks(&[&not, &a])),
            1 => (inner.clone(), inner.clone()).prop_map(|(a, b)| toks(&["LIMIT", "(", "0", ",", &a, ",", &b, ")"])),
            1 => inner.prop_map(|a| toks(&["Timer", "(", "IN", ":=", &a, ",", "Q", "=>", "Done", ")"])),
        ]
    })
}

fn statement() -> impl Strategy<Value = String> {
    let simple = prop_oneof![
        4 => (name(), expression()).prop_map(|(n, e)| toks(&[&n, ":=", &e, ";"])),
        1 => expression().prop_map(|e| toks(&["Timer", "(", "IN", ":=", &e, ",", "PT", ":=", "T#1s", ")", ";"])),
        1 => Just(toks(&["EXIT", ";"])),
        1 => Just(toks(&["RETURN", ";"])),
    ];
    simple.prop_recursive(3, 16, 3, |inner| {
        let list = prop::collection::vec(inner, 0..3).prop_map(|v| v.join(&GAP.to_string()));
        prop_oneof![
            (expression(), list.clone(), prop::option::of((expression(), list.clone())), prop::option::of(list.clone()))
                .prop_map(|(c, then, elsif, els)| {
                    let mut s = toks(&["IF", &c, "THEN", &then]);
                    if let Some((c2, body)) = elsif {
                        s = toks(&[&s, "ELSIF", &c2, "THEN", &body]);
                    }
                    if let Some(body) = els {
                        s = toks(&[&s, "ELSE", &body]);
                    }
                    toks(&[&s, "END_IF", ";"])
                }),
            (name(), list.clone(), list.clone(), prop::option::of(list.clone())).prop_map(|(sel, one, two, els)| {
                let mut s = toks(&["CASE", &sel, "OF", "1", ",", "2", ":", &one, "3", "..", "5", ":", &two]);
                if let Some(body) = els {
                    s = toks(&[&s, "ELSE", &body]);
                }
                toks(&[&s, "END_CASE", ";"])
            }),
            (expression(), list.clone()).prop_map(|(to, body)| toks(&["FOR", "i", ":=", "1", "TO", &to, "BY", "2", "DO", &body, "END_FOR", ";"])),
            (expression(), list.clone()).prop_map(|(c, body)| toks(&["WHILE", &c, "DO", &body, "END_WHILE", ";"])),
            (list, expression()).prop_map(|(body, c)| toks(&["REPEAT", &body, "UNTIL", &c, "END_REPEAT", ";"])),
        ]
    })
}

fn statements() -> impl Strategy<Value = String> {
    prop::collection::vec(statement(), 1..5).prop_map(|v| v.join(&GAP.to_string()))
}

const DECLARATIONS: &str = "VAR\u{1}a\u{1},\u{1}Flag\u{1}:\u{1}BOOL\u{1};\u{1}count\u{1},\u{1}x_1\u{1},\u{1}i\u{1}:\u{1}INT\u{1}:=\u{1}3\u{1};\
\u{1}Speed\u{1}:\u{1}REAL\u{1};\u{1}Done\u{1}:\u{1}BOOL\u{1};\u{1}Timer\u{1}:\u{1}TON\u{1};\u{1}END_VAR";

fn st_program() -> impl Strategy<Value = String> {
    statements().prop_map(|body| toks(&["PROGRAM", "Main", DECLARATIONS, &body, "END_PROGRAM"]))
}

fn association() -> impl Strategy<Value = String> {
    let action = prop_oneof![Just("A0"), Just("A1"), Just("A2")];
    let qualifier = prop_oneof![
        Just(toks(&["N"])),
        Just(toks(&["S"])),
        Just(toks(&["R"])),
        Just(toks(&["P"])),
        Just(toks(&["L", ",", "T#5s"])),
        Just(toks(&["SD", ",", "t#1s500ms"])),
        Just(toks(&["N", ",", "Flag"])),
        Just(String::new()),
    ];
    (action, qualifier).prop_map(|(a, q)| toks(&[a, "(", &q, ")", ";"]))
}

fn chart() -> impl Strategy<Value = String> {
    let step = (1usize..4, prop::collection::vec(association(), 0..3), any::<bool>()).prop_map(|(n, assocs, tagged)| {
        let mut s = String::new();
        if tagged {
            s = toks(&[&format!("{{attribute 'sfc.tag' := '{n}'}}"), ""]);
        }
        toks(&[&s, &format!("STEP{GAP}S{n}{GAP}:"), &assocs.join(&GAP.to_string()), "END_STEP"])
    });
    let target = prop_oneof![
        Just("S1".to_string()),
        Just("S2".to_string()),
        Just(toks(&["(", "S2", ")"])),
        Just(toks(&["(", "S1", ",", "S3", ")"])),
    ];
    let transition = (target.clone(), target, expression(), any::<bool>(), any::<bool>()).prop_map(|(from, to, cond, named, prio)| {
        let name = if named { "T1" } else { "" };
        let prio = if prio { toks(&["(", "PRIORITY", ":=", "2", ")"]) } else { String::new() };
        toks(&["TRANSITION", name, &prio, "FROM", &from, "TO", &to, ":=", &cond, ";", "END_TRANSITION"])
    });
    let action =
        (0usize..3, statements()).prop_map(|(n, body)| toks(&["ACTION", &format!("A{n}"), ":", &body, "END_ACTION"]));
    let element = prop_oneof![2 => step, 2 => transition, 1 => action];
    prop::collection::vec(element, 0..6).prop_map(|elements| {
        let init = toks(&["INITIAL_STEP", "S0", ":", "A0", "(", "N", ")", ";", "END_STEP"]);
        toks(&["PROGRAM", "Chart", DECLARATIONS, &init, &elements.join(&GAP.to_string()), "END_PROGRAM"])
    })
}

fn gaps() -> impl Strategy<Value = Vec<usize>> {
    prop::collection::vec(0..SEPARATORS.len(), 1..64)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn generated_st_programs_roundtrip(template in st_program(), choices in gaps()) {
        check_roundtrip(&fill_gaps(&template, &choices), "a generated ST program");
    }

    #[test]
    fn generated_charts_roundtrip(template in chart(), choices in gaps()) {
        check_roundtrip(&fill_gaps(&template, &choices), "a generated chart");
    }
}
