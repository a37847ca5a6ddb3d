//! Hostile and huge input through the whole `check_source` pipeline (parser, type checker,
//! lowering, validation): diagnostics or success, never a panic or a stack overflow. Test threads
//! have 2 MiB of stack, far less than the CLI's 64 MiB.

use sfc_model::{check_source, CheckOptions};

fn check(text: &str) -> Vec<&'static str> {
    check_source(0, "hostile.st", text, &CheckOptions::default()).diagnostics.iter().map(|d| d.code).collect()
}

fn in_chart(guard: &str, body: &str) -> String {
    format!(
        "PROGRAM P\nVAR x : BOOL; i : INT; END_VAR\nINITIAL_STEP S1: A(N); END_STEP\nSTEP S2: END_STEP\n\
         TRANSITION FROM S1 TO S2 := {guard}; END_TRANSITION\nTRANSITION FROM S2 TO S1 := TRUE; END_TRANSITION\n\
         ACTION A: {body} END_ACTION\nEND_PROGRAM\n"
    )
}

#[test]
fn ten_thousand_levels_of_nesting() {
    let n = 10_000;
    let deep_guard = format!("{}x{}", "(".repeat(n), ")".repeat(n));
    assert!(check(&in_chart(&deep_guard, "x := TRUE;")).contains(&"SFC0103"));
    let deep_not = format!("{}x", "NOT ".repeat(n));
    assert!(check(&in_chart(&deep_not, "x := TRUE;")).contains(&"SFC0103"));
    let deep_if = format!("{}x := TRUE;{}", "IF x THEN ".repeat(n), " END_IF;".repeat(n));
    assert!(check(&in_chart("x", &deep_if)).contains(&"SFC0103"));
    let deep_sum = format!("i := {}1{};", "(1 + ".repeat(n), ")".repeat(n));
    assert!(check(&in_chart("x", &deep_sum)).contains(&"SFC0103"));
}

#[test]
fn nesting_just_under_the_limit_checks_cleanly() {
    // The deepest expression the parser accepts inside a guard type-checks without trouble.
    let n = 200;
    let guard = format!("{}x{}", "(".repeat(n), ")".repeat(n));
    assert_eq!(check(&in_chart(&guard, "x := TRUE; i := 0;")), Vec::<&str>::new());
    let body = format!("{}x := TRUE; i := 0;{}", "IF x THEN ".repeat(40), " END_IF;".repeat(40));
    assert_eq!(check(&in_chart("x", &body)), Vec::<&str>::new());
}

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
    let raw = bytes(0xD1B5_4A32_D192_ED03, 2 * 1024 * 1024);
    assert!(!check(&String::from_utf8_lossy(&raw)).is_empty());
}

#[test]
fn random_chart_fragments() {
    // Real tokens in random order reach the checker and the model, not just the parser.
    const WORDS: &[&str] = &[
        "PROGRAM P",
        "END_PROGRAM",
        "VAR x : BOOL; i : INT; t : TON; END_VAR",
        "INITIAL_STEP",
        "STEP",
        "S1",
        "S2",
        ":",
        "END_STEP",
        "A(N);",
        "B(L, T#1s);",
        "TRANSITION",
        "FROM",
        "TO",
        "(S1, S2)",
        ":=",
        "x",
        "i > 3",
        ";",
        "END_TRANSITION",
        "ACTION",
        "A",
        "B",
        "END_ACTION",
        "i := i + 1;",
        "t(IN := x, PT := T#1s);",
        "IF",
        "THEN",
        "END_IF;",
        "S1.X",
        "S2.T > T#1s",
        "NOT",
        "AND",
        "(",
        ")",
        "{attribute 'sfc.tag' := '1'}",
        "LD x",
        "ST x",
        "\n",
        "CASE i OF 1: x := TRUE; END_CASE;",
        "FUNCTION_BLOCK F",
        "END_FUNCTION_BLOCK",
        "[",
        "]",
        ".",
    ];
    for seed in 1..300u64 {
        let raw = bytes(seed, 300);
        let text: Vec<&str> = raw.iter().map(|b| WORDS[*b as usize % WORDS.len()]).collect();
        let _ = check(&text.join(" "));
    }
}

#[test]
fn a_hundred_thousand_line_valid_file() {
    let mut s = String::from("PROGRAM Long\nVAR\n    Go : BOOL;\n    Count : DINT;\nEND_VAR\n");
    let n = 12_500; // 8 lines per step: 100,000 lines
    for i in 0..n {
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        s.push_str(&format!(
            "{kw} S{i}:\n    A{i}(N);\nEND_STEP\nACTION A{i}:\n    Count := Count + {i};\nEND_ACTION\n"
        ));
        s.push_str(&format!("TRANSITION FROM S{i} TO S{} := Go; END_TRANSITION\n\n", (i + 1) % n));
    }
    s.push_str("END_PROGRAM\n");
    assert!(s.lines().count() >= 100_000);
    let checked = check_source(0, "long.st", &s, &CheckOptions::default());
    assert!(checked.diagnostics.is_empty(), "{:?}", checked.diagnostics.first());
    assert_eq!(checked.charts[0].steps.len(), n);
}
