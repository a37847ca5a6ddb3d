//! Hostile input never panics nor overflows the stack: it yields diagnostics or success.
//! (Test threads have a 2 MiB stack, smaller than a program's main thread, so these also show
//! the nesting cap leaves a wide margin.)

// A panic in a test or a developer tool is a failure report, not a crash on user input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use sfc_syntax::parse;

fn codes(text: &str) -> Vec<&'static str> {
    parse(0, text).1.iter().map(|d| d.code).collect()
}

fn program_with(body: &str) -> String {
    format!("PROGRAM P\nVAR x : BOOL; END_VAR\n{body}\nEND_PROGRAM\n")
}

#[test]
fn deeply_nested_parentheses() {
    let n = 10_000;
    let e = format!("{}x{}", "(".repeat(n), ")".repeat(n));
    let c = codes(&program_with(&format!("x := {e};")));
    assert_eq!(c, vec!["SFC0103"]);
}

#[test]
fn deeply_nested_unary_operators() {
    let e = format!("{}x", "NOT ".repeat(10_000));
    assert_eq!(codes(&program_with(&format!("x := {e};"))), vec!["SFC0103"]);
    let e = format!("{}1", "- ".repeat(10_000));
    assert_eq!(codes(&program_with(&format!("x := {e};"))), vec!["SFC0103"]);
}

#[test]
fn deeply_nested_statements() {
    let n = 10_000;
    let body = format!("{}x := TRUE;{}", "IF x THEN ".repeat(n), " END_IF;".repeat(n));
    assert_eq!(codes(&program_with(&body)), vec!["SFC0103"]);
}

#[test]
fn deeply_nested_types_and_initialisers() {
    let n = 10_000;
    let ty = format!("{}INT", "ARRAY [1..2] OF ".repeat(n));
    assert!(codes(&format!("TYPE T : {ty}; END_TYPE")).contains(&"SFC0103"));
    let init = format!("{}1{}", "[".repeat(n), "]".repeat(n));
    assert!(
        codes(&format!("PROGRAM P VAR a : ARRAY [1..2] OF INT := {init}; END_VAR END_PROGRAM")).contains(&"SFC0103")
    );
}

#[test]
fn long_operator_chains() {
    let e = vec!["x"; 200].join(" AND ");
    assert!(codes(&program_with(&format!("x := {e};"))).is_empty());
    let e = vec!["x"; 50_000].join(" AND ");
    assert_eq!(codes(&program_with(&format!("x := {e};"))), vec!["SFC0103"]);
}

/// A deterministic xorshift generator, so failures reproduce.
fn bytes(seed: u64, n: usize) -> Vec<u8> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s as u8
        })
        .collect()
}

#[test]
fn two_megabytes_of_random_bytes() {
    let raw = bytes(0x9E37_79B9_7F4A_7C15, 2 * 1024 * 1024);
    let text = String::from_utf8_lossy(&raw);
    let (_, diags) = parse(0, &text);
    assert!(!diags.is_empty());
}

#[test]
fn random_token_soup() {
    // Random sequences of real tokens reach deeper into the parser than random bytes.
    const WORDS: &[&str] = &[
        "PROGRAM",
        "END_PROGRAM",
        "STEP",
        "END_STEP",
        "INITIAL_STEP",
        "TRANSITION",
        "FROM",
        "TO",
        "END_TRANSITION",
        "ACTION",
        "END_ACTION",
        "VAR",
        "END_VAR",
        "IF",
        "THEN",
        "ELSE",
        "END_IF",
        "CASE",
        "OF",
        "END_CASE",
        "FOR",
        "WHILE",
        "DO",
        "(",
        ")",
        "[",
        "]",
        ":",
        ":=",
        ";",
        ",",
        "..",
        "x",
        "S1",
        "T#1s",
        "16#FF",
        "'a'",
        "+",
        "*",
        "AND",
        "NOT",
        "(*c*)",
        "{attribute 'sfc.tag' := '1'}",
        "%IX1.0",
        "LD",
        "ST",
        "\n",
        "FUNCTION_BLOCK",
        "TYPE",
        "STRUCT",
        "END_STRUCT",
        "ARRAY",
        "=>",
        "N",
        "L",
        "PRIORITY",
        ".",
        "1.5",
        "D#2020-01-01",
    ];
    for seed in 1..200u64 {
        let raw = bytes(seed, 400);
        let text: Vec<&str> = raw.iter().map(|b| WORDS[*b as usize % WORDS.len()]).collect();
        let _ = parse(0, &text.join(" "));
    }
}

#[test]
fn else_is_the_last_branch() {
    let p = program_with("IF x THEN x := TRUE; ELSE x := FALSE; ELSE x := TRUE; END_IF;");
    assert_eq!(codes(&p), vec!["SFC0101"]);
    let p = program_with("IF x THEN x := TRUE; ELSE x := FALSE; ELSIF x THEN x := TRUE; END_IF;");
    assert!(codes(&p).contains(&"SFC0101"));
}

#[test]
fn long_member_and_index_chains() {
    let e = format!("x{}", ".a".repeat(100_000));
    assert_eq!(codes(&program_with(&format!("x := {e};"))), vec!["SFC0103"]);
    let e = format!("x{}", "[1]".repeat(100_000));
    assert_eq!(codes(&program_with(&format!("x := {e};"))), vec!["SFC0103"]);
}
