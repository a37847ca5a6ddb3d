//! Properties of the canonical printer (`sfc fmt`): printing is idempotent, printing then parsing
//! gives back the same tree (spans aside), and no comment or pragma is ever lost. Checked on
//! generated programs and charts (with comments at random token boundaries) and on every textual
//! file the project and the shared corpus hold.

// A panic in a test or a developer tool is a failure report, not a crash on user input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use proptest::prelude::*;
use sfc_syntax::{parse, print::print};
use std::path::{Path, PathBuf};

// -- The properties ---------------------------------------------------------------------------

/// The tree's Debug form without spans (offsets change when the layout does) and with the
/// keywords TRUE and FALSE in upper case, as the printer writes them.
fn shape(unit: &sfc_syntax::ast::SourceUnit) -> String {
    upper_case_bools(&strip_spans(&format!("{:?}", unit.items)))
}

/// Upper-cases the text of every untyped BOOL literal in a Debug form.
fn upper_case_bools(debug: &str) -> String {
    const BOOL: &str = "kind: Bool(";
    const TEXT: &str = "type_prefix: None, text: \"";
    let mut out = String::with_capacity(debug.len());
    let mut rest = debug;
    while let Some(at) = rest.find(BOOL) {
        let after = &rest[at..];
        // The text follows the kind directly: `kind: Bool(true), type_prefix: None, text: "…"`.
        let close = after.find(')').expect("Bool(…) is closed") + 1;
        let tail = &after[close..];
        match tail.strip_prefix(", ").filter(|t| t.starts_with(TEXT)) {
            Some(t) => {
                let value_len = t[TEXT.len()..].find('"').expect("a closed string");
                out.push_str(&rest[..at + close + 2 + TEXT.len()]);
                out.push_str(&t[TEXT.len()..TEXT.len() + value_len].to_ascii_uppercase());
                rest = &t[TEXT.len() + value_len..];
            }
            None => {
                out.push_str(&rest[..at + close]);
                rest = tail;
            }
        }
    }
    out.push_str(rest);
    out
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
/// Comment and pragma texts; the indentation of continuation lines is left out, since the
/// printer moves a multi-line trailing comment's lines together with its first line.
fn trivia_texts(unit: &sfc_syntax::ast::SourceUnit) -> Vec<String> {
    unit.trivia.iter().map(|t| t.text.split('\n').map(str::trim_start).collect::<Vec<_>>().join("\n")).collect()
}

fn parse_clean(text: &str, what: &str) -> sfc_syntax::ast::SourceUnit {
    let (unit, diags) = parse(0, text);
    let errors: Vec<_> = diags
        .iter()
        .filter(|d| d.severity == sfc_diagnostics::Severity::Error)
        .map(|d| (d.code, &d.message, d.span))
        .collect();
    assert!(errors.is_empty(), "{what} does not parse cleanly: {errors:?}\n--- text ---\n{text}");
    unit
}

fn has_errors(text: &str) -> bool {
    parse(0, text).1.iter().any(|d| d.severity == sfc_diagnostics::Severity::Error)
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
        // Whether a file parses is the parser tests' concern; the printer only promises
        // anything for a clean parse (`sfc fmt` refuses the others).
        if has_errors(&text) {
            eprintln!("skipped, does not parse cleanly: {}", file.display());
            continue;
        }
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

/// One of everything the printer lays out, without comments (the tests add them) and without
/// blanks inside literals (each run of blanks is a place for a comment).
const EVERY_CONSTRUCT: &str = "\
type
  Colour : (Red, Green := 2, Blue) := Red;
  Level : int (0..100) := 5;
  Point : struct x : INT;
     y : INT := 2; END_STRUCT;
  Grid : array [1..10, 0..2] of array[1..2] of Point;
  Name : string[20] := 'abc';
  Typed : INT (A := 1, B := 2);
END_TYPE
VAR_GLOBAL CONSTANT
  G : WSTRING(10) := \"x\";
  Arr : ARRAY [1..5] OF INT := [2(1), 3(), 7];
  P : Point := (x := 1, y := (z := 2));
END_VAR
function Add3 : INT
var_input a, b, c : INT; end_var
  Add3 := a + b + c;
end_function
FUNCTION_BLOCK Fb
VAR_INPUT IN : BOOL; END_VAR
VAR_OUTPUT Q : BOOL; END_VAR
VAR RETAIN cnt : DINT; s : STRUCT a : INT; END_STRUCT; END_VAR
VAR AT %IW6.2 : WORD; x AT %QX1.0 : BOOL; END_VAR
  LD IN
  ANDN Q
  ST Q
L1: AND( cnt
    OR IN
  )
  JMPC L1
  CAL T1(IN := TRUE, PT := T#1s)
lbl:
  ST Q
END_FUNCTION_BLOCK
PROGRAM Main
VAR_ACCESS
  acc : Conf.Res.x : INT READ_WRITE;
END_VAR
VAR x, i : INT; b : BOOL; END_VAR
  case x of
    1, 2..5: x := 1; b := TRUE;
    -3: ;
    6:
  else
    x := 0;
  end_case;
  if b then x := 1; elsif x > 2 then x := 2; else x := 3; end_if;
  for i := 1 to 10 by 2 do x := x * 2 ** i; exit; end_for;
  while x > 0 do x := x - 1; end_while;
  repeat x := x + 1; until x >= 10 end_repeat;
  Fb1(IN := b, NOT Q => b, Q =>);
  x := -(-x) + - -x - (x - 1) / arr[i, 2].y;
  b := NOT NOT b & (x MOD 3 = 0) OR %IX1.2 XOR Init.X;
  return;
END_PROGRAM
PROGRAM Chart
VAR a : BOOL; END_VAR
INITIAL_STEP Init:
  P1(L, T#5s); P2(N, Ind); P3(); P4(SD, t#1s);
END_STEP
TRANSITION Tr1 (PRIORITY := 1) FROM Init TO S2:
  LD a
  AND( a
    OR a
  )
END_TRANSITION
step S2: end_step
transition from S2 to Init := TRUE; end_transition
ACTION P1:
  LD a
  ST a
END_ACTION
ACTION P2: END_ACTION
END_PROGRAM
CONFIGURATION Conf
  RESOURCE Res ON PLC
    PROGRAM Inst : Main;
  END_RESOURCE
END_CONFIGURATION
";

#[test]
fn every_construct_roundtrips() {
    check_roundtrip(EVERY_CONSTRUCT, "the every-construct sample");
}

/// `EVERY_CONSTRUCT` with a gap at each run of blanks: in-line gaps within a line (IL is
/// line-oriented), line gaps at line breaks.
fn every_construct_template() -> String {
    let mut out = String::new();
    let mut chars = EVERY_CONSTRUCT.chars().peekable();
    while let Some(c) = chars.next() {
        if c.is_whitespace() {
            let mut newline = c == '\n';
            while let Some(&next) = chars.peek().filter(|n| n.is_whitespace()) {
                newline |= next == '\n';
                chars.next();
            }
            out.push(if newline { LINE } else { IN_LINE });
        } else {
            out.push(c);
        }
    }
    out
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

/// A token boundary inside one IL instruction, where no line may break.
const IN_LINE: char = '\u{2}';

const IN_LINE_SEPARATORS: &[&str] = &[" ", " ", "  ", " (* c *) ", "(*x*)"];

/// The end of an IL instruction: IL is line-oriented.
const LINE: char = '\u{3}';

const LINE_SEPARATORS: &[&str] = &["\n", "\n    ", " // end of line\n", "\n(* own line *)\n", "\n\n", " (* c *)\n"];

/// Replaces each gap with a separator chosen by `choices`.
fn fill_gaps(template: &str, choices: &[usize]) -> String {
    let mut out = String::with_capacity(template.len() * 2);
    let mut k = 0;
    for c in template.chars() {
        let separators = match c {
            GAP => SEPARATORS,
            IN_LINE => IN_LINE_SEPARATORS,
            LINE => LINE_SEPARATORS,
            _ => {
                out.push(c);
                continue;
            }
        };
        out.push_str(separators[choices[k % choices.len()] % separators.len()]);
        k += 1;
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
            (
                expression(),
                list.clone(),
                prop::option::of((expression(), list.clone())),
                prop::option::of(list.clone())
            )
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
            (expression(), list.clone()).prop_map(|(to, body)| toks(&[
                "FOR", "i", ":=", "1", "TO", &to, "BY", "2", "DO", &body, "END_FOR", ";"
            ])),
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
    let step =
        (1usize..4, prop::collection::vec(association(), 0..3), any::<bool>()).prop_map(|(n, assocs, tagged)| {
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
    let transition = (target.clone(), target, expression(), any::<bool>(), any::<bool>()).prop_map(
        |(from, to, cond, named, prio)| {
            let name = if named { "T1" } else { "" };
            let prio = if prio { toks(&["(", "PRIORITY", ":=", "2", ")"]) } else { String::new() };
            toks(&["TRANSITION", name, &prio, "FROM", &from, "TO", &to, ":=", &cond, ";", "END_TRANSITION"])
        },
    );
    let action =
        (0usize..3, statements()).prop_map(|(n, body)| toks(&["ACTION", &format!("A{n}"), ":", &body, "END_ACTION"]));
    let element = prop_oneof![2 => step, 2 => transition, 1 => action];
    prop::collection::vec(element, 0..6).prop_map(|elements| {
        let init = toks(&["INITIAL_STEP", "S0", ":", "A0", "(", "N", ")", ";", "END_STEP"]);
        toks(&["PROGRAM", "Chart", DECLARATIONS, &init, &elements.join(&GAP.to_string()), "END_PROGRAM"])
    })
}

/// One IL instruction (or a nested `OR(` … `)` group) on its line(s).
fn il_instruction() -> impl Strategy<Value = String> {
    let il = |parts: &[&str]| parts.join(&IN_LINE.to_string());
    prop_oneof![
        Just(il(&["LD", "a"])),
        Just(il(&["ldn", "Flag"])),
        Just(il(&["ST", "Done"])),
        Just(il(&["ANDN", "a"])),
        Just(il(&["ADD", "1"])),
        Just(il(&["GT", "count"])),
        Just(il(&["S", "Flag"])),
        Just(il(&["R", "Flag"])),
        Just(il(&["JMPC", "L1"])),
        Just(il(&["CAL", "Timer", "(", "IN", ":=", "a", ",", "PT", ":=", "T#1s", ")"])),
        Just(il(&["CAL", "Timer"])),
        Just(il(&["L1", ":"])),
        Just(il(&["L2", ":", "LD", "-5"])),
        Just(format!("{}{LINE}{}{LINE})", il(&["OR(", "a"]), il(&["AND", "Flag"]))),
        Just(format!("{}{LINE}{}{LINE}{}{LINE})", il(&["AND("]), il(&["LD", "a"]), il(&["OR", "count"]))),
    ]
}

/// An IL body: it starts with an operator, so that the parser sees IL.
fn il_body() -> impl Strategy<Value = String> {
    prop::collection::vec(il_instruction(), 0..6).prop_map(|v| {
        let mut lines = vec![format!("LD{IN_LINE}a")];
        lines.extend(v);
        lines.join(&LINE.to_string())
    })
}

fn il_program() -> impl Strategy<Value = String> {
    (il_body(), il_body(), il_body()).prop_map(|(body, cond, action)| {
        let fb = toks(&["FUNCTION_BLOCK", "Il", DECLARATIONS, &format!("{body}{LINE}END_FUNCTION_BLOCK")]);
        let chart = toks(&[
            "PROGRAM",
            "IlChart",
            DECLARATIONS,
            "INITIAL_STEP",
            "S0",
            ":",
            "END_STEP",
            "TRANSITION",
            "FROM",
            "S0",
            "TO",
            "S0",
            &format!(":{LINE}{cond}{LINE}END_TRANSITION"),
            "ACTION",
            "A0",
            &format!(":\n{action}{LINE}END_ACTION"),
            "END_PROGRAM",
        ]);
        toks(&[&fb, &chart])
    })
}

fn gaps() -> impl Strategy<Value = Vec<usize>> {
    prop::collection::vec(0..SEPARATORS.len(), 1..64)
}

proptest! {
    // 256 cases each unless PROPTEST_CASES says otherwise; failures are reported, not saved.
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn generated_st_programs_roundtrip(template in st_program(), choices in gaps()) {
        check_roundtrip(&fill_gaps(&template, &choices), "a generated ST program");
    }

    #[test]
    fn comments_anywhere_in_every_construct(choices in gaps()) {
        check_roundtrip(&fill_gaps(&every_construct_template(), &choices), "the commented every-construct sample");
    }

    #[test]
    fn generated_il_roundtrips(template in il_program(), choices in gaps()) {
        check_roundtrip(&fill_gaps(&template, &choices), "generated IL");
    }

    #[test]
    fn generated_charts_roundtrip(template in chart(), choices in gaps()) {
        check_roundtrip(&fill_gaps(&template, &choices), "a generated chart");
    }
}
