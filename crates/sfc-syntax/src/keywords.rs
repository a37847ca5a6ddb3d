//! The words of the language, in one place: the parser's reserved words and the words that
//! cannot name anything an importer writes (a step, a transition, an action, a variable, a POU).

/// Words that end or start a construct and therefore never name a variable.
pub const RESERVED: &[&str] = &[
    "END_IF",
    "END_CASE",
    "END_FOR",
    "END_WHILE",
    "END_REPEAT",
    "END_VAR",
    "END_STEP",
    "END_TRANSITION",
    "END_ACTION",
    "END_PROGRAM",
    "END_FUNCTION",
    "END_FUNCTION_BLOCK",
    "END_TYPE",
    "END_STRUCT",
    "END_CONFIGURATION",
    "END_RESOURCE",
    "END_METHOD",
    "END_PROPERTY",
    "END_GET",
    "END_SET",
    "END_INTERFACE",
    "IF",
    "THEN",
    "ELSIF",
    "ELSE",
    "CASE",
    "OF",
    "FOR",
    "DO",
    "BY",
    "WHILE",
    "REPEAT",
    "UNTIL",
    "EXIT",
    "RETURN",
    "VAR",
    "VAR_INPUT",
    "VAR_OUTPUT",
    "VAR_IN_OUT",
    "VAR_GLOBAL",
    "VAR_EXTERNAL",
    "VAR_ACCESS",
    "VAR_TEMP",
    "STEP",
    "INITIAL_STEP",
    "TRANSITION",
    "ACTION",
    "PROGRAM",
    "FUNCTION",
    "FUNCTION_BLOCK",
    "TYPE",
    "STRUCT",
    "ARRAY",
    "AND",
    "OR",
    "XOR",
    "NOT",
    "MOD",
    "AND_THEN",
    "OR_ELSE",
    "CONFIGURATION",
    "RESOURCE",
];

/// Words that are no construct of their own but still cannot name a variable or a step in
/// text (literals, parts of declarations, of configurations and of transitions).
pub const NOT_NAMES: &[&str] =
    &["FROM", "TO", "TRUE", "FALSE", "AT", "CONSTANT", "RETAIN", "NON_RETAIN", "TASK", "WITH", "ON", "PRIORITY"];

/// Words of sfc's text for charts that CODESYS's Structured Text lets a variable be named by
/// (an importer renames such variables).
pub const CHART_WORDS: &[&str] =
    &["STEP", "INITIAL_STEP", "END_STEP", "TRANSITION", "END_TRANSITION", "ACTION", "END_ACTION", "FROM"];

/// Whether `s` cannot name a variable, step, transition, action or POU in text, in any case.
pub fn cannot_name(s: &str) -> bool {
    RESERVED.iter().chain(NOT_NAMES).any(|k| k.eq_ignore_ascii_case(s))
}

/// Whether `s` is an IEC identifier (letters, digits, single underscores, not a keyword): what
/// an importer may copy into text as a name.
pub fn is_identifier(s: &str) -> bool {
    let b = s.as_bytes();
    !b.is_empty()
        && b.first().is_some_and(|c| c.is_ascii_alphabetic() || *c == b'_')
        && b.iter().all(|c| c.is_ascii_alphanumeric() || *c == b'_')
        && !s.contains("__")
        && !s.ends_with('_')
        && !cannot_name(s)
}

/// A usable identifier made from `s` (invalid characters become `_`; a name that cannot be one
/// gets the prefix `X_`).
pub fn sanitize_identifier(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        let c = if c.is_ascii_alphanumeric() { c } else { '_' };
        if c == '_' && (out.is_empty() || out.ends_with('_')) {
            continue;
        }
        out.push(c);
    }
    while out.ends_with('_') {
        out.pop();
    }
    if out.is_empty() {
        // Nothing usable (`""`, `"_"`, `"()"`): `X`, not `X_`, which is no identifier.
        return "X".to_string();
    }
    if out.as_bytes().first().is_some_and(u8::is_ascii_digit) || cannot_name(&out) {
        out.insert_str(0, "X_");
    }
    out
}
