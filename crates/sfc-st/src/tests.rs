//! Data-driven tests: source text → the diagnostic codes `check_unit` reports.

use crate::check_unit;

/// A chart whose action `A` (active in the initial step) holds `code`.
fn action(vars: &str, code: &str) -> String {
    format!(
        "PROGRAM P\nVAR\n{vars}\nEND_VAR\n\
         INITIAL_STEP S1: A(N); END_STEP\n\
         TRANSITION FROM S1 TO S2 := TRUE; END_TRANSITION\n\
         STEP S2: END_STEP\n\
         TRANSITION FROM S2 TO S1 := S2.T > T#1s; END_TRANSITION\n\
         ACTION A:\n{code}\nEND_ACTION\nEND_PROGRAM\n"
    )
}

/// A chart whose first transition has the ST condition `cond`.
fn guard(vars: &str, cond: &str) -> String {
    format!(
        "PROGRAM P\nVAR\n{vars}\nEND_VAR\n\
         INITIAL_STEP S1: A(N); END_STEP\n\
         TRANSITION FROM S1 TO S2 := {cond}; END_TRANSITION\n\
         STEP S2: END_STEP\n\
         TRANSITION FROM S2 TO S1 := TRUE; END_TRANSITION\n\
         ACTION A: ; END_ACTION\nEND_PROGRAM\n"
    )
}

/// A chart whose first transition has the IL condition `il`.
fn il_guard(vars: &str, il: &str) -> String {
    format!(
        "PROGRAM P\nVAR\n{vars}\nEND_VAR\n\
         INITIAL_STEP S1: END_STEP\n\
         TRANSITION FROM S1 TO S2:\n{il}\nEND_TRANSITION\n\
         STEP S2: END_STEP\n\
         TRANSITION FROM S2 TO S1 := TRUE; END_TRANSITION\nEND_PROGRAM\n"
    )
}

/// A chart whose action `A` has the IL body `il`.
fn il_action(vars: &str, il: &str) -> String {
    format!(
        "PROGRAM P\nVAR\n{vars}\nEND_VAR\n\
         INITIAL_STEP S1: A(N); END_STEP\n\
         TRANSITION FROM S1 TO S2 := TRUE; END_TRANSITION\n\
         STEP S2: END_STEP\n\
         TRANSITION FROM S2 TO S1 := TRUE; END_TRANSITION\n\
         ACTION A:\n{il}\nEND_ACTION\nEND_PROGRAM\n"
    )
}

/// A step association `assoc` (e.g. `A(L, T#1s)`) in the initial step.
fn association(vars: &str, assoc: &str) -> String {
    format!(
        "PROGRAM P\nVAR\n{vars}\nEND_VAR\n\
         INITIAL_STEP S1: {assoc}; END_STEP\n\
         TRANSITION FROM S1 TO S2 := TRUE; END_TRANSITION\n\
         STEP S2: END_STEP\n\
         TRANSITION FROM S2 TO S1 := TRUE; END_TRANSITION\n\
         ACTION A: ; END_ACTION\nEND_PROGRAM\n"
    )
}

const BLINKER: &str = "\
PROGRAM Blinker
VAR
  Start, Stop : BOOL;
  Visible : BOOL;
  TimeOn : TIME := T#1s;
  TimeOff : TIME := T#500ms;
END_VAR
INITIAL_STEP S1: END_STEP
TRANSITION T1 FROM S1 TO S2 := Start; END_TRANSITION
STEP S2: Show(N); END_STEP
TRANSITION T2 FROM S2 TO S3 := S2.T > TimeOn; END_TRANSITION
STEP S3: Hide(P); END_STEP
TRANSITION T4 FROM S3 TO S2 := S3.T > TimeOff AND NOT Stop; END_TRANSITION
TRANSITION T5 FROM S3 TO S1 := Stop; END_TRANSITION
ACTION Show: Visible := TRUE; END_ACTION
ACTION Hide: Visible := NOT Visible; END_ACTION
END_PROGRAM
";

const LIBRARY: &str = "\
TYPE
  Mode : (Idle, Running, Fault := 10);
  Point : STRUCT x, y : REAL; tag : STRING[8] := 'p'; END_STRUCT;
  Percent : INT (0..100) := 50;
  Row : ARRAY [1..Width] OF Percent;
  Temp : REAL := 20.0;
END_TYPE
VAR_GLOBAL CONSTANT
  Width : INT := 4;
END_VAR
VAR_GLOBAL
  Alarm : BOOL;
END_VAR
FUNCTION Scale : REAL
VAR_INPUT x : INT; k : REAL := 1.0; END_VAR
Scale := INT_TO_REAL(x) * k;
END_FUNCTION
FUNCTION_BLOCK Motor
VAR_INPUT Enable : BOOL; Speed : INT; END_VAR
VAR_OUTPUT Running : BOOL; Power : REAL; END_VAR
VAR_IN_OUT Count : DINT; END_VAR
VAR Internal : INT; END_VAR
Running := Enable AND Speed > 0;
Power := Scale(Speed, 0.5);
IF Running THEN Count := Count + 1; END_IF;
Internal := Speed;
END_FUNCTION_BLOCK
";

fn codes(src: &str) -> Vec<&'static str> {
    let (unit, parse_diags) = sfc_syntax::parse(0, src);
    let parse_errors: Vec<String> = parse_diags.iter().map(|d| format!("{}: {}", d.code, d.message)).collect();
    assert!(parse_errors.is_empty(), "test input does not parse: {parse_errors:?}\n{src}");
    let mut c: Vec<&'static str> = check_unit(&unit).iter().map(|d| d.code).collect();
    c.sort_unstable();
    c
}

/// Runs a table of (name, source, expected codes). SFC0317 (unused) is ignored unless a case
/// expects it, so cases need not use every variable.
fn run(cases: &[(&str, String, &[&str])]) {
    let mut failures = Vec::new();
    for (name, src, expected) in cases {
        let mut got = codes(src);
        if !expected.contains(&"SFC0317") {
            got.retain(|c| *c != "SFC0317");
        }
        let mut want: Vec<&str> = expected.to_vec();
        want.sort_unstable();
        if got != want {
            let (unit, _) = sfc_syntax::parse(0, src);
            let msgs: Vec<String> = check_unit(&unit).iter().map(|d| format!("{} {}", d.code, d.message)).collect();
            failures.push(format!("{name}: expected {want:?}, got {got:?}\n    {}", msgs.join("\n    ")));
        }
    }
    assert!(failures.is_empty(), "{} failing case(s):\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn valid_programs_have_no_diagnostics() {
    let lib = |body: &str| format!("{LIBRARY}{body}");
    let cases: Vec<(&str, String, &[&str])> = vec![
        ("blinker", BLINKER.to_string(), &[]),
        ("library", lib(""), &[]),
        (
            "TON call and outputs",
            action(
                "Start, Done : BOOL; T1 : TON; Elapsed : TIME;",
                "T1(IN := Start, PT := T#5s); Done := T1.Q; Elapsed := T1.ET; T1(IN := FALSE, Q => Done, ET => Elapsed);",
            ),
            &[],
        ),
        (
            "counters and triggers",
            action(
                "C : CTU; D : CTUD; E : R_TRIG; F : SR; G : RS; x : BOOL; n : INT;",
                "C(CU := x, R := FALSE, PV := 10); n := C.CV; D(CU := x, CD := NOT x, R := FALSE, LD := FALSE, PV := 3); \
                 E(CLK := x); F(S1 := E.Q, R := D.QU); G(S := x, R1 := F.Q1); x := G.Q1 OR C.Q;",
            ),
            &[],
        ),
        (
            "CASE on integers and enums",
            lib(&action(
                "i : INT; m : Mode; b : BOOL;",
                "CASE i OF 1, 2: b := TRUE; 3..5, 7: b := FALSE; ELSE i := 0; END_CASE; \
                 CASE m OF Idle: m := Running; Running, Mode#Fault: m := Idle; END_CASE;",
            )),
            &[],
        ),
        (
            "FOR, WHILE, REPEAT with arrays",
            action(
                "a : ARRAY [1..10] OF INT; i : INT; s : DINT; m : ARRAY [0..2, 0..3] OF BOOL;",
                "FOR i := 1 TO 10 BY 2 DO a[i] := a[i] + 1; IF a[i] > 5 THEN EXIT; END_IF; END_FOR; \
                 WHILE s < 100 DO s := s + a[1]; END_WHILE; REPEAT i := i - 1; UNTIL i <= 0 END_REPEAT; \
                 m[2, 3] := a[10] = 0;",
            ),
            &[],
        ),
        (
            "structs, enums, subranges, typed arrays",
            lib(&action(
                "p : Point; m : Mode; pc : Percent; r : Row; t : Temp; x : REAL;",
                "p.x := 1.5; p.y := p.x * 2.0; p.tag := 'abc'; m := Running; IF m = Mode#Fault THEN m := Idle; END_IF; \
                 pc := 100; r[Width] := pc; t := t + 1.0; x := t;",
            )),
            &[],
        ),
        (
            "string functions",
            action(
                "s, s3 : STRING[20]; n : INT; w : WSTRING;",
                "s := CONCAT(s, 'abc', s3); n := LEN(s); s3 := LEFT(s, 3); s3 := RIGHT(IN := s, L := 2); \
                 n := FIND(s, 'b'); s := MID(s, 2, 1); s := INSERT(s, 'x', 2); s := DELETE(s, 1, 1); \
                 s := REPLACE(s, 'y', 1, 1); w := \"wide\"; s := INT_TO_STRING(n);",
            ),
            &[],
        ),
        (
            "numeric functions and widening",
            action(
                "i, j, k : INT; d : DINT; r : REAL; lr : LREAL; w : WORD; b : BOOL; si : SINT; us : USINT;",
                "r := SQRT(r) + INT_TO_REAL(i); i := LIMIT(0, i, 100); i := MAX(i, 5, j); d := i * 1000; \
                 w := SHL(w, 2) AND 16#FF; b := SEL(b, i, j) > 3; i := MUX(k, 1, 2, 3); r := i; lr := d; \
                 d := si + us; r := ABS(-r) ** 2.0; r := EXPT(r, 2); i := i MOD 3; d := TRUNC(r); \
                 i := -32768; si := -128; b := GT(i, j, k); lr := i * 1.5; w := w OR WORD#16#F0F0; \
                 b := w.3 AND NOT w.15; i := REAL_TO_INT(r / 2.0); w := INT_TO_BCD(i); i := WORD_BCD_TO_INT(w);",
            ),
            &[],
        ),
        (
            "time and date arithmetic",
            action(
                "t, t2 : TIME; tod1 : TOD; dt1 : DT; d1 : DATE; i : INT;",
                "t := t + T#1s; t2 := t * 2; t2 := t / i; tod1 := tod1 + T#1h; t := tod1 - TOD#08:00:00; \
                 dt1 := dt1 + t; t := dt1 - DT#2020-01-01-00:00:00; t := d1 - D#2020-01-01; t := ADD(t, t2); \
                 t := SUB(t, T#5ms); t := MUL(t, 3);",
            ),
            &[],
        ),
        (
            "user functions and function blocks",
            lib(&action(
                "M1 : Motor; n : DINT; r : REAL; on : BOOL;",
                "M1(Enable := TRUE, Speed := 10, Count := n, Running => on); r := M1.Power + Scale(5, 2.0); \
                 r := Scale(x := 3); M1.Speed := 5; M1(Count := n);",
            )),
            &[],
        ),
        (
            "globals and externals",
            lib(
                "PROGRAM P\nVAR_EXTERNAL Alarm : BOOL; END_VAR\nVAR x : BOOL; END_VAR\n\
                 x := Alarm; Alarm := NOT x;\nEND_PROGRAM\n",
            ),
            &[],
        ),
        (
            "located variables and direct addresses",
            action(
                "Lim AT %IX27 : BOOL; Temp AT %IW28 : INT; Out AT %QW6 : ARRAY [0..9] OF INT; b : BOOL; w : WORD;",
                "b := Lim AND %IX2.4; w := %IW3; %QX5.1 := b; Out[0] := Temp; w := %MW6;",
            ),
            &[],
        ),
        (
            "step and action flags in guards",
            guard("b : BOOL;", "S1.X AND NOT S2.X AND A.Q AND NOT A.A AND S1.T >= T#2s AND b"),
            &[],
        ),
        ("constant guard", guard("", "1"), &[]),
        (
            "constants and initial values",
            action(
                "a : ARRAY [1..N] OF INT := [2(1), 3]; c : STRING[N * 2] := 'x'; r : REAL := 1; p : BOOL := 1;",
                "a[N] := LEN(c) + 1; IF r > 0.0 AND p THEN a[1] := 0; END_IF;",
            )
            .replacen("PROGRAM P\nVAR\n", "PROGRAM P\nVAR CONSTANT N : INT := 5; END_VAR\nVAR\n", 1),
            &[],
        ),
        (
            "function block instance initial value",
            action("T1 : TON := (PT := T#2s); b : BOOL;", "T1(IN := b); b := T1.Q;"),
            &[],
        ),
        ("IL condition", il_guard("", "LD %IX2.4\nAND %IX2.3"), &[]),
        ("IL condition with &", il_guard("a, b : BOOL;", "LD a\n& b"), &[]),
        ("IL comparison", il_guard("i : INT;", "LD i\nGT 5"), &[]),
        ("IL nested", il_guard("a, b, c : BOOL;", "LD a\nANDN( b\nOR c\n)"), &[]),
        ("IL function operator", il_guard("i, j : INT;", "LD i\nMAX j, 3\nLT 10"), &[]),
        (
            "IL action",
            il_action(
                "a, b : BOOL; x, y : INT; T1 : TON;",
                "LD a\nST b\nLD x\nADD 5\nST y\nCAL T1(IN := a, PT := T#1s)\nLD T1.Q\nJMPC done\nLD TRUE\nS b\ndone: LD b\nR a",
            ),
            &[],
        ),
        ("IL OR nested", il_guard("a, b, c : BOOL;", "LD a\nOR( b\nAND c\n)\nANDN S1.X"), &[]),
        ("IL arithmetic nested", il_guard("i, j : INT;", "LD i\nADD( j\nMUL 2\n)\nGT 10"), &[]),
        ("IL SEL with the current result as G", il_guard("g : BOOL; i, j : INT;", "LD g\nSEL i, j\nEQ 3"), &[]),
        ("IL bit string", il_guard("w : WORD;", "LD w\nAND 16#FF\nNE 0"), &[]),
        (
            "IL jumps, calls and function operators",
            il_action(
                "a, b : BOOL; i, x : INT; T1 : TON;",
                "LDN a\nST b\nJMP l2\nl1: LD x\nST i\nl2: LD i\nLIMIT 0, 10\nST x\nCAL T1\nLD T1.Q\nRETC\n\
                 LD 5\nST i\nLD T#1s\nST T1.PT\nCAL T1(IN := a, PT := T#2s)",
            ),
            &[],
        ),
        (
            "priorities",
            guard("", "TRUE").replace("TRANSITION FROM S1", "TRANSITION (PRIORITY := 2) FROM S1"),
            &[],
        ),
        (
            "function with formal and positional calls",
            "FUNCTION Add3 : INT\nVAR_INPUT a, b, c : INT; END_VAR\nAdd3 := a + b + c;\nEND_FUNCTION\n\
             PROGRAM P\nVAR x : INT; END_VAR\nx := Add3(1, 2, 3) + Add3(a := x, b := 1, c := 2);\nEND_PROGRAM\n"
                .to_string(),
            &[],
        ),
        (
            "action association with duration and indicator",
            association("d : TIME; ind : BOOL;", "A(L, T#5s, ind); A(D, d)"),
            &[],
        ),
        (
            "BOOL variable used as an action",
            association("Lamp : BOOL;", "Lamp(N)").replace("ACTION A: ; END_ACTION\n", ""),
            &[],
        ),
    ];
    run(&cases);
}

#[test]
fn each_error_code() {
    let lib = |body: &str| format!("{LIBRARY}{body}");
    let cases: Vec<(&str, String, &[&str])> = vec![
        ("SFC0301 undeclared", guard("Level : INT;", "Levle > 5"), &["SFC0301"]),
        ("SFC0301 step as value", action("b : BOOL;", "b := S1;"), &["SFC0301"]),
        ("SFC0302 assignment", action("Count : INT; r : REAL;", "Count := r;"), &["SFC0302"]),
        ("SFC0302 IF condition", action("i : INT;", "IF i THEN i := 0; END_IF;"), &["SFC0302"]),
        ("SFC0302 operator", action("b : BOOL; i : INT;", "i := b + 1;"), &["SFC0302"]),
        ("SFC0302 comparison", action("b : BOOL; s : STRING; i : INT;", "b := s = i;"), &["SFC0302"]),
        ("SFC0302 bit ops on INT", action("b : BOOL; i : INT;", "b := i AND b;"), &["SFC0302"]),
        ("SFC0302 time plus int", action("t : TIME;", "t := t + 5;"), &["SFC0302"]),
        ("SFC0302 FB input", action("T1 : TON;", "T1(IN := TRUE, PT := 5);"), &["SFC0302"]),
        ("SFC0302 FB output binding", action("T1 : TON; r : REAL;", "T1(IN := TRUE, Q => r);"), &["SFC0302"]),
        ("SFC0302 FOR variable", action("r : REAL;", "FOR r := 1 TO 10 DO ; END_FOR;"), &["SFC0302"]),
        ("SFC0302 CASE label", lib(&action("m : Mode; i : INT;", "CASE m OF 1: i := 0; END_CASE;")), &["SFC0302"]),
        ("SFC0302 CASE selector", action("r : REAL;", "CASE r OF 1: r := 0.0; END_CASE;"), &["SFC0302"]),
        ("SFC0302 narrowing", action("i : INT; d : DINT;", "i := d;"), &["SFC0302"]),
        ("SFC0302 array index", action("a : ARRAY [1..3] OF INT; r : REAL;", "a[r] := 1;"), &["SFC0302"]),
        (
            "SFC0302 VAR_EXTERNAL type",
            "FUNCTION_BLOCK F\nVAR_EXTERNAL Alarm : INT; END_VAR\nAlarm := 1;\nEND_FUNCTION_BLOCK\n\
             PROGRAM P\nVAR_GLOBAL Alarm : BOOL; END_VAR\nVAR f1 : F; END_VAR\nf1();\nEND_PROGRAM\n"
                .to_string(),
            &["SFC0302"],
        ),
        ("SFC0302 located size", action("x AT %IX1.0 : INT;", "x := 1;"), &["SFC0302"]),
        ("SFC0303 INT guard", guard("Level : INT;", "Level"), &["SFC0303"]),
        ("SFC0303 IL guard", il_guard("i : INT;", "LD i\nADD 1"), &["SFC0303"]),
        ("SFC0304 write step flag", action("", "S1.X := TRUE;"), &["SFC0304"]),
        ("SFC0304 write step time", action("", "S2.T := T#0s;"), &["SFC0304"]),
        ("SFC0304 write action flag", action("", "A.Q := FALSE;"), &["SFC0304"]),
        ("SFC0305 FB call in guard", guard("T1 : TON;", "T1(IN := TRUE)"), &["SFC0305"]),
        (
            "SFC0305 output binding in guard",
            format!(
                "FUNCTION Split : BOOL\nVAR_INPUT x : INT; END_VAR\nVAR_OUTPUT hi : BOOL; END_VAR\nSplit := x > 0; hi := x > 9;\nEND_FUNCTION\n{}",
                guard("b : BOOL;", "Split(x := 1, hi => b) AND b")
            ),
            &["SFC0305"],
        ),
        ("functions are allowed in guards", lib(&guard("i : INT;", "Scale(i, 1.0) > 0.0 AND LIMIT(0, i, 2) = 1")), &[]),
        ("SFC0305 IL store in guard", il_guard("a, b : BOOL;", "LD a\nST b"), &["SFC0305"]),
        ("SFC0305 IL call in guard", il_guard("T1 : TON;", "CAL T1(IN := TRUE)\nLD T1.Q"), &["SFC0305"]),
        ("SFC0306 unknown function", action("i : INT;", "i := FOO(1);"), &["SFC0306"]),
        ("SFC0306 FB type called", action("b : BOOL;", "TON(IN := b);"), &["SFC0306"]),
        ("SFC0307 argument count", action("i : INT;", "i := LIMIT(1, 2);"), &["SFC0307"]),
        ("SFC0307 unknown parameter", action("T1 : TON;", "T1(INN := TRUE);"), &["SFC0307"]),
        ("SFC0307 output with :=", action("T1 : TON;", "T1(Q := TRUE);"), &["SFC0307"]),
        ("SFC0307 mixed arguments", action("i : INT;", "i := LIMIT(0, IN := i, MX := 5);"), &["SFC0307"]),
        ("SFC0307 user function arity", lib(&action("r : REAL;", "r := Scale(1, 2.0, 3);")), &["SFC0307"]),
        ("SFC0307 missing in-out", lib(&action("M : Motor;", "M(Enable := TRUE);")), &["SFC0307"]),
        ("SFC0308 assign constant", action("i : INT;", "N := i;").replacen("PROGRAM P\nVAR\n", "PROGRAM P\nVAR CONSTANT N : INT := 5; END_VAR\nVAR\n", 1), &["SFC0308"]),
        ("SFC0308 assign FB output", action("T1 : TON;", "T1.Q := TRUE;"), &["SFC0308"]),
        ("SFC0309 struct field", lib(&action("p : Point;", "p.z := 1.0;")), &["SFC0309"]),
        ("SFC0309 step member", action("b : BOOL;", "b := S1.Y;"), &["SFC0309"]),
        ("SFC0309 FB internal written", lib(&action("M : Motor;", "M.Internal := 1;")), &["SFC0309"]),
        ("SFC0322 FB internal read", lib(&action("M : Motor; i : INT;", "i := M.Internal;")), &["SFC0322"]),
        ("SFC0309 member of INT", action("i : INT;", "i := i.x;"), &["SFC0309"]),
        ("SFC0310 not an array", action("i : INT;", "i[1] := 2;"), &["SFC0310"]),
        ("SFC0310 wrong dimensions", action("m : ARRAY [1..2, 1..2] OF INT;", "m[1] := 2;"), &["SFC0310"]),
        ("SFC0311 duration INT", association("", "A(L, 5)"), &["SFC0311"]),
        ("SFC0311 duration variable", association("i : INT;", "A(D, i)"), &["SFC0311"]),
        ("SFC0312 indicator", association("i : INT;", "A(L, T#1s, i)"), &["SFC0312"]),
        ("SFC0313 unknown type", action("x : Foo;", "x := 1;"), &["SFC0313"]),
        ("SFC0313 recursive type", "TYPE A1 : A2; A2 : A1; END_TYPE\n".to_string(), &["SFC0313"]),
        ("SFC0314 EXIT outside loop", action("", "EXIT;"), &["SFC0314"]),
        ("SFC0315 initial value", action("s : SINT := 300;", "s := 1;"), &["SFC0315"]),
        ("SFC0315 assignment", action("u : USINT;", "u := -1;"), &["SFC0315"]),
        ("SFC0315 index", action("a : ARRAY [1..10] OF INT;", "a[11] := 0;"), &["SFC0315"]),
        ("SFC0315 bit", action("w : WORD; b : BOOL;", "b := w.16;"), &["SFC0315"]),
        ("SFC0315 typed literal", action("i : INT;", "i := SINT#200;"), &["SFC0315"]),
        ("SFC0315 too many initial values", action("a : ARRAY [1..3] OF INT := [1, 2, 3, 4];", "a[1] := 0;"), &["SFC0315"]),
        ("SFC0316 ST without LD", il_action("b : BOOL;", "ST b"), &["SFC0316"]),
        ("SFC0316 undefined label", il_action("b : BOOL;", "LD b\nJMPC nowhere"), &["SFC0316"]),
        ("SFC0316 store mismatch", il_action("i : INT; b : BOOL;", "LD i\nST b"), &["SFC0316"]),
        ("SFC0316 operand mismatch", il_action("i : INT; b : BOOL;", "LD b\nADD i\nST i"), &["SFC0316"]),
        ("SFC0316 no result", il_guard("T1 : TON;", "CAL T1"), &["SFC0305", "SFC0316"]),
        ("SFC0315 FOR step zero", action("i : INT;", "FOR i := 1 TO 5 BY 0 DO ; END_FOR;"), &["SFC0315"]),
        ("SFC0315 negative priority", guard("", "TRUE").replace("TRANSITION FROM S1", "TRANSITION (PRIORITY := -1) FROM S1"), &["SFC0315"]),
        ("SFC0302 priority not constant", guard("p : INT;", "TRUE").replace("TRANSITION FROM S1", "TRANSITION (PRIORITY := p) FROM S1"), &["SFC0302"]),
        ("SFC0308 in-out needs a variable", lib(&action("M : Motor;", "M(Count := 5);")), &["SFC0308"]),
        ("SFC0316 unknown IL operator", il_action("x : INT;", "LD x\nFOO x"), &["SFC0316"]),
        ("SFC0316 conditional jump on INT", il_action("x : INT;", "LD x\nJMPC l\nl: LD x"), &["SFC0316"]),
        ("SFC0316 CALC after CAL", il_action("T1 : TON;", "CAL T1\nCALC T1"), &["SFC0316"]),
        ("SFC0319 overlapping CASE labels", action("i : INT;", "CASE i OF 1..5: i := 0; 3: i := 1; END_CASE;"), &["SFC0319"]),
        ("SFC0105 reversed array range", "TYPE Table : ARRAY [10..1] OF INT; END_TYPE\n".to_string(), &["SFC0105"]),
        ("SFC0105 string length", action("s : STRING[N - 5];", "s := 'a';").replacen("PROGRAM P\nVAR\n", "PROGRAM P\nVAR CONSTANT N : INT := 5; END_VAR\nVAR\n", 1), &["SFC0105"]),
        ("SFC0105 array bound not constant", action("n : INT; a : ARRAY [1..n] OF INT;", "n := 1;"), &["SFC0105"]),
        ("SFC0318 duplicate type", "TYPE A1 : INT; A1 : REAL; END_TYPE\n".to_string(), &["SFC0318"]),
        ("SFC0206 duplicate variable", action("x : INT; X : BOOL;", "x := 1;"), &["SFC0206"]),
        ("SFC0317 unused local", action("used, unused : INT;", "used := 1;"), &["SFC0317"]),
    ];
    run(&cases);
}

#[test]
fn messages_read_well() {
    let msgs = |src: &str| -> Vec<String> {
        let (unit, _) = sfc_syntax::parse(0, src);
        check_unit(&unit)
            .into_iter()
            .filter(|d| d.code != "SFC0317")
            .map(|d| format!("{}|{}|{}", d.message, d.notes.join(";"), d.element.unwrap_or_default()))
            .collect()
    };
    assert_eq!(
        msgs(&action("Count : INT; r : REAL;", "Count := r;")),
        ["type mismatch: cannot assign `REAL` to `INT` variable `Count`||A"]
    );
    assert_eq!(msgs(&guard("Level : INT;", "Level")), ["transition condition is `INT`, expected `BOOL`||T1"]);
    assert_eq!(msgs(&guard("Level : INT;", "Levle > 5")), ["undeclared variable `Levle`|did you mean `Level`?|T1"]);
    assert_eq!(msgs(&action("a : ARRAY [1..10] OF INT;", "a[0] := 1;")), ["index 0 is out of range 1..10||A"]);
}

#[test]
fn env_and_scope_api() {
    use crate::{Binding, Scope, Type, TypeEnv};
    let src = format!("{LIBRARY}{}", action("p : Point; m : Mode; i : INT;", "p.x := 1.0; i := 2;"));
    let (unit, _) = sfc_syntax::parse(0, &src);
    let (env, diags) = TypeEnv::from_unit(&unit);
    assert!(diags.is_empty(), "{diags:?}");
    let row = env.type_def("row").map(|d| d.ty.to_string());
    assert_eq!(row.as_deref(), Some("ARRAY [1..4] OF INT (0..100)"));
    let motor = env.function_block("MOTOR").expect("Motor");
    assert_eq!(motor.inputs().map(|v| v.name.as_str()).collect::<Vec<_>>(), ["Enable", "Speed"]);
    assert_eq!(env.function("scale").and_then(|f| f.return_type.clone()), Some(Type::Real));
    assert!(env.function_block("TON").is_some_and(|t| t.standard));
    assert_eq!(env.enum_types_with_value("running").len(), 1);

    let pou = unit
        .items
        .iter()
        .find_map(|i| match i {
            sfc_syntax::ast::Item::Pou(p) if p.name.is("P") => Some(p),
            _ => None,
        })
        .expect("P");
    let mut scope = Scope::for_pou(&env, pou);
    let s1 = sfc_syntax::ast::Ident::new("S1", Default::default());
    assert!(scope.add_step(&s1).is_ok());
    assert!(scope.add_step(&sfc_syntax::ast::Ident::new("i", Default::default())).is_err());
    assert!(matches!(scope.lookup("s1"), Some(Binding::Step(_))));
    assert!(matches!(scope.lookup("ALARM"), Some(Binding::Variable { global: true, .. })));
    let diags = crate::check_pou(&env, pou);
    assert!(diags.iter().all(|d| d.code == "SFC0317"), "{diags:?}");
    let mut ck = crate::Checker::new(&mut scope);
    let (e, _) = sfc_syntax::parse_expression(0, "i + 1");
    assert_eq!(ck.check_expr(&e, None), Type::Int);
    assert!(ck.finish().is_empty());
    assert!(scope.usage("I").read);
    assert!(!scope.usage("m").used());
}

#[test]
fn const_eval_folds_constants() {
    use crate::{const_eval, NoConstants, Value};
    let eval = |s: &str| const_eval(&sfc_syntax::parse_expression(0, s).0, &NoConstants);
    assert_eq!(eval("2 + 3 * 4"), Some(Value::Int(14)));
    assert_eq!(eval("-(7 / 2)"), Some(Value::Int(-3)));
    assert_eq!(eval("10 MOD 0"), None);
    assert_eq!(eval("T#1s + T#500ms"), Some(Value::Time(1_500_000)));
    assert_eq!(eval("3 > 2 AND TRUE"), Some(Value::Bool(true)));
    assert_eq!(eval("x + 1"), None);
}

#[test]
fn deep_and_hostile_input_does_not_panic() {
    // Deep nesting and garbage must give diagnostics, never a panic or a stack overflow; run in
    // a thread with the default test stack size.
    let handle = std::thread::Builder::new()
        .stack_size(2 * 1024 * 1024)
        .spawn(|| {
            let deep = format!("{}x{}", "(".repeat(300), ")".repeat(300));
            let long = vec!["x"; 5000].join(" + ");
            let nots = format!("{}x", "NOT ".repeat(300));
            let negs = format!("{}1", "-".repeat(300));
            // The parser does not cap postfix chains; the checker stops at its own depth limit.
            let members = format!("x{} > 0", ".a".repeat(3000));
            let indices = format!("x{} > 0", "[1]".repeat(3000));
            for cond in [deep, long, nots, negs, members, indices] {
                let _ = codes_lenient(&guard("x : INT;", &cond));
            }
            let nested_ifs = format!("{}x := 1;{}", "IF TRUE THEN ".repeat(100), " END_IF;".repeat(100));
            let _ = codes_lenient(&action("x : INT;", &nested_ifs));
            let _ = codes_lenient(&action("x : INT;", &format!("x{} := 1;", ".a".repeat(3000))));
            let aliases: String = (0..1000).map(|i| format!("A{i} : A{};", i + 1)).collect();
            let _ = codes_lenient(&format!("TYPE {aliases} A1000 : INT; END_TYPE"));
            for junk in [
                "PROGRAM",
                "PROGRAM P VAR x : ARRAY [",
                "FUNCTION F : INT F := F(F(F)); END_FUNCTION",
                "TYPE T : ARRAY [1..0] OF T; END_TYPE",
            ] {
                let _ = codes_lenient(junk);
            }
        })
        .expect("thread");
    assert!(handle.join().is_ok());
}

fn codes_lenient(src: &str) -> Vec<&'static str> {
    let (unit, _) = sfc_syntax::parse(0, src);
    check_unit(&unit).iter().map(|d| d.code).collect()
}

#[test]
fn expression_types_are_recorded() {
    use crate::{Checker, Scope, Type, TypeEnv};
    let src = action("s : SINT; r : REAL; i : INT;", "s := s + 1; r := i * 2; r := 2 * 1.5;");
    let (unit, _) = sfc_syntax::parse(0, &src);
    let (env, _) = TypeEnv::from_unit(&unit);
    let Some(sfc_syntax::ast::Item::Pou(pou)) = unit.items.first() else { panic!("no POU") };
    let mut scope = Scope::for_pou(&env, pou);
    let mut ck = Checker::new(&mut scope);
    ck.keep_types();
    let (stmts, _) = sfc_syntax::parse_statements(0, "s := s + 1; r := i * 2; r := 2 * 1.5;");
    ck.check_stmts(&stmts);
    let ty_of = |ck: &Checker<'_, '_>, text: &str, nth: usize| {
        let src = "s := s + 1; r := i * 2; r := 2 * 1.5;";
        let start = src.match_indices(text).nth(nth).map(|(i, _)| i as u32).expect("text");
        let span = sfc_syntax::ast::Span::new(0, start, start + text.len() as u32);
        ck.expr_type(span).cloned()
    };
    assert_eq!(ty_of(&ck, "1", 0), Some(Type::SInt), "the literal adapts to SINT");
    assert_eq!(ty_of(&ck, "s + 1", 0), Some(Type::SInt));
    assert_eq!(ty_of(&ck, "i * 2", 0), Some(Type::Int), "INT arithmetic, widened on assignment");
    assert_eq!(ty_of(&ck, "2 * 1.5", 0), Some(Type::Real), "a constant expression takes the target type");
    assert!(ck.finish().is_empty());
}

#[test]
fn hook_declares_implicit_inputs() {
    use crate::{check_unit_with, Type, VarInfo};
    let src = "PROGRAM P\nINITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1 := C0; END_TRANSITION\n\
               STEP S1: END_STEP\nTRANSITION FROM S1 TO S0 := NOT C1; END_TRANSITION\nEND_PROGRAM\n";
    let (unit, _) = sfc_syntax::parse(0, src);
    assert_eq!(check_unit(&unit).iter().map(|d| d.code).collect::<Vec<_>>(), ["SFC0301", "SFC0301"]);
    let diags = check_unit_with(&unit, &mut |scope, _| {
        for i in 0..16 {
            let var = VarInfo {
                name: format!("C{i}"),
                span: Default::default(),
                kind: sfc_syntax::ast::VarKind::Input,
                constant: false,
                retain: None,
                persistent: false,
                ty: Type::Bool,
                location: None,
                init: None,
                value: None,
                implicit: true,
            };
            let _ = scope.declare(var);
        }
    });
    assert!(diags.is_empty(), "{diags:?}");
}

/// A function block `Seq` with an SFC body (so it has the implicit control variables) and a
/// program that uses it.
fn chart_fb(decls: &str, guard: &str, program: &str) -> String {
    format!(
        "FUNCTION_BLOCK Seq\nVAR_INPUT Go : BOOL; END_VAR\n{decls}\n\
         INITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1 := {guard}; END_TRANSITION\n\
         STEP S1: END_STEP\nTRANSITION FROM S1 TO S0 := TRUE; END_TRANSITION\nEND_FUNCTION_BLOCK\n\
         PROGRAM P\nVAR Rev : Seq; x, y : BOOL; s : STRING; END_VAR\n{program}\nEND_PROGRAM\n"
    )
}

#[test]
fn chart_control_variables() {
    run(&[
        ("read outside", chart_fb("", "Go", "Rev(Go := x); y := Rev.SFCError; s := Rev.SFCCurrentStep;"), &[]),
        ("set as inputs", chart_fb("", "Go", "Rev(SFCInit := x, SFCPause := y, SFCQuitError := x);"), &[]),
        ("error step", chart_fb("", "Go", "Rev(); s := Rev.SFCErrorStep;"), &[]),
        ("read inside", chart_fb("", "Go AND NOT SFCError AND NOT SFCInit", "Rev();"), &[]),
        ("outputs are read-only outside", chart_fb("", "Go", "Rev.SFCError := x;"), &["SFC0308"]),
        ("declared with its type", chart_fb("VAR_OUTPUT SFCError : BOOL; END_VAR", "Go", "y := Rev.SFCError;"), &[]),
        ("declared with another type", chart_fb("VAR_INPUT SFCInit : INT; END_VAR", "Go", "Rev();"), &["SFC0302"]),
        (
            "not on other POUs",
            "FUNCTION_BLOCK F\nVAR_INPUT a : BOOL; END_VAR\n;\nEND_FUNCTION_BLOCK\n\
             PROGRAM P\nVAR i : F; x : BOOL; END_VAR\nx := i.SFCError;\nEND_PROGRAM\n"
                .to_string(),
            &["SFC0309"],
        ),
    ]);
    // A declared but unused control variable is the chart's, not an unused local.
    let src = chart_fb("VAR SFCPause : BOOL; END_VAR", "Go", "Rev(Go := x); y := Rev.SFCError; s := '';");
    assert_eq!(codes(&src), Vec::<&str>::new());
}

#[test]
fn typed_check_records_every_expression() {
    use crate::Type;
    let src = "PROGRAM P\nVAR a : SINT; b : REAL; END_VAR\na := a + 1;\nb := b * 2;\nEND_PROGRAM\n";
    let (unit, _) = sfc_syntax::parse(0, src);
    let (diags, types) = crate::check_unit_typed(&unit);
    assert!(diags.is_empty(), "{diags:?}");
    let at = |text: &str, nth: usize| {
        let start = src.match_indices(text).nth(nth).map(|(i, _)| i as u32).expect("in source");
        types.iter().find(|(s, _)| s.start == start && s.end == start + text.len() as u32).map(|(_, t)| t.clone())
    };
    assert_eq!(at("a + 1", 0), Some(Type::SInt));
    assert_eq!(at("1", 0), Some(Type::SInt));
    assert_eq!(at("b * 2", 0), Some(Type::Real));
    assert_eq!(at("2", 0), Some(Type::Real));
}

#[test]
fn counter_variants_are_function_blocks() {
    run(&[
        (
            "CTD_UDINT",
            "PROGRAM P\nVAR c : CTD_UDINT; q : BOOL; n : UDINT; END_VAR\n\
             c(CD := q, LD := q, PV := 2);\nq := c.Q;\nn := c.CV;\nEND_PROGRAM\n"
                .to_string(),
            &[],
        ),
        (
            "CTUD_LINT",
            "PROGRAM P\nVAR c : CTUD_LINT; n : LINT; END_VAR\nc(CU := TRUE, PV := 5, CV => n);\nEND_PROGRAM\n"
                .to_string(),
            &[],
        ),
    ]);
}
