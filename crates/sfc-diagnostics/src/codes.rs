//! The registry of diagnostic codes. Codes are a contract: never renumber, only add.
//!
//! Ranges: `SFC00xx` lexical, `SFC01xx` syntax, `SFC02xx` chart structure, `SFC03xx` names and
//! types, `SFC04xx` ATMT/EATMT target rules, `SFC05xx` analysis, `SFC06xx` pragmas and attributes,
//! `SFC07xx` import (PLCopen XML).

use crate::Severity;

/// What a code means: its default severity, a title, and an explanation with an example.
#[derive(Debug, Clone, Copy)]
pub struct CodeInfo {
    pub code: &'static str,
    pub severity: Severity,
    pub title: &'static str,
    pub explanation: &'static str,
}

macro_rules! codes {
    ($( $code:literal $sev:ident $title:literal $expl:literal ;)*) => {
        /// Every code sfc can emit.
        pub const CODES: &[CodeInfo] = &[
            $( CodeInfo { code: $code, severity: Severity::$sev, title: $title, explanation: $expl }, )*
        ];
    };
}

codes! {
    "SFC0001" Error "unterminated comment"
        "A `(*` comment has no closing `*)`. IEC 61131-3 comments do not nest.\n\n    (* a comment *)";
    "SFC0002" Error "unterminated string literal"
        "A string literal has no closing quote before the end of the line or file.\n\n    Msg : STRING := 'ready';";
    "SFC0003" Error "invalid character"
        "The character cannot start any token of IEC 61131-3 text.";
    "SFC0004" Error "invalid numeric literal"
        "Numbers are decimal (`123_456`), based (`2#1110_0000`, `8#377`, `16#E5`) or real (`1.234e-6`); \
underscores only between digits; a type prefix is `INT#5`.";
    "SFC0005" Error "invalid duration literal"
        "A duration is `T#` or `TIME#` followed by units d h m s ms us (ns), largest first, only the \
last may have a fraction: `T#5d14h12m18s3.5ms`, `TIME#14.7h`. Resolution is 1 µs.";
    "SFC0006" Error "invalid identifier"
        "Identifiers start with a letter or `_`, contain letters, digits and single underscores, and \
do not end with `_`: `MAX_U_24` is valid, `__MAX_U`, `MAX__U` and `MAX_U_` are not.";
    "SFC0007" Error "invalid escape in string literal"
        "Strings use `$` escapes: `$$ $' $\" $L $N $P $R $T`, `$hh` (two hex digits) in `'…'` and \
`$hhhh` in `\"…\"`.";
    "SFC0008" Error "invalid date or time-of-day literal"
        "Dates are `D#2006-03-20`, times of day `TOD#10:42:23.78`, date and time \
`DT#2006-03-20-10:42:23.78`.";
    "SFC0009" Error "invalid direct address"
        "A direct address is `%` then I, Q or M, an optional size X B W D L, and unsigned integers \
separated by dots: `%IX2.4`, `%QW29`, `%MW6`.";
    "SFC0010" Error "nested comment"
        "IEC 61131-3 comments do not nest: `(* (* inner *) *)` ends at the first `*)`.";

    "SFC0101" Error "syntax error"
        "The parser expected something else here. It recovers at the next keyword, so later \
errors are usually real.";
    "SFC0102" Error "missing end keyword"
        "A block (`END_STEP`, `END_TRANSITION`, `END_ACTION`, `END_IF`, `END_PROGRAM`, …) is not \
closed.";
    "SFC0103" Error "nesting too deep"
        "Expressions or statements are nested deeper than sfc supports (256 levels). Split the \
expression with intermediate variables.";
    "SFC0104" Note "declaration not analysed"
        "`CONFIGURATION`, `RESOURCE` and similar declarations are parsed and skipped: sfc \
checks and runs program organisation units.";
    "SFC0105" Error "invalid type"
        "The type specification is not valid, for example an array with a reversed range \
`ARRAY [10..1] OF INT` or a string length that is not a positive integer.";

    "SFC0201" Error "no initial step"
        "Every network of steps needs exactly one `INITIAL_STEP`.\n\n    INITIAL_STEP Init: END_STEP";
    "SFC0202" Error "more than one initial step in a network"
        "A connected network of steps and transitions has exactly one initial step; several \
initial steps are allowed only in separate networks.";
    "SFC0203" Error "step without connection"
        "A step that no transition enters or leaves (and that is not initial) can never be \
activated. Connect it with a TRANSITION … FROM … TO … or delete it.";
    "SFC0204" Error "transition without connection"
        "A transition must have at least one preceding and one following step.";
    "SFC0205" Error "invalid link"
        "Steps and transitions alternate: a step links to a transition and a transition to a \
step. Step-to-step and transition-to-transition links are not allowed.";
    "SFC0206" Error "duplicate name"
        "Variables, steps, actions and transitions of one POU share one case-insensitive \
namespace; each name may be declared once.";
    "SFC0207" Error "undeclared action"
        "A step associates an action that is neither an ACTION of the POU nor a BOOL variable.";
    "SFC0208" Error "undeclared step"
        "A transition names a step in FROM or TO that is not declared with STEP or INITIAL_STEP.";
    "SFC0209" Error "unknown action qualifier"
        "The qualifiers are N R S L D P SD DS SL P1 P0.\n\n    Pump(SD, T#2s);";
    "SFC0210" Error "timed qualifier without duration"
        "L, D, SD, DS and SL need a duration: `Fill(L, T#5s);` or a TIME variable.";
    "SFC0211" Error "duration on an untimed qualifier"
        "Only L, D, SD, DS and SL take a duration; N R S P P1 P0 do not: `Fill(N);`.";
    "SFC0212" Error "jump to nowhere"
        "A jump names a step that does not exist.";
    "SFC0213" Warning "step without a way out"
        "A non-initial step has no outgoing transition, so the sequence ends there. Add a \
transition, or mark it as a final step with `{attribute 'sfc.final' := 'true'}`.";
    "SFC0214" Warning "unused action"
        "An ACTION is declared but no step associates it and no code calls it.";
    "SFC0215" Error "duplicate transition"
        "Two transitions connect exactly the same steps with the same condition; one of them can \
never fire first and is probably a copy.";
    "SFC0216" Error "step links to itself in one transition"
        "A transition lists the same step twice in FROM or in TO.";
    "SFC0217" Error "transition condition missing"
        "A transition needs a condition: `:= expression;` or an IL body after `:`.";
    "SFC0218" Error "no SFC body"
        "The file has no POU with steps; sfc needs at least one chart for this command.";

    "SFC0301" Error "undeclared variable"
        "A name in an expression or statement is not a variable, step, action or constant of \
the POU, nor a global.";
    "SFC0302" Error "type mismatch"
        "The operands or the assigned value do not have compatible types. Convert explicitly, for \
example with `INT_TO_REAL(i)`.";
    "SFC0303" Error "transition condition is not BOOL"
        "A transition condition must be a BOOL expression: `:= Level > 10;`, not `:= Level;` \
for an INT.";
    "SFC0304" Error "step flags are read-only"
        "`Step.X` and `Step.T` are maintained by the chart; they can be read anywhere in the POU \
but never written.";
    "SFC0305" Error "side effect in a transition condition"
        "Transition conditions are evaluated on a snapshot and must not change state: no \
assignments and no function block calls. Move the call into an action.";
    "SFC0306" Error "unknown function or function block"
        "The called name is not a standard function, a standard function block, nor a FUNCTION \
or FUNCTION_BLOCK declared in the file.";
    "SFC0307" Error "wrong arguments"
        "The call has the wrong number of arguments, an unknown formal parameter name, or mixes \
formal and positional arguments.";
    "SFC0308" Error "cannot assign"
        "The target is a constant, an input of the POU being read, a literal or an expression.";
    "SFC0309" Error "unknown member"
        "The structure, function block instance or step has no member with this name. Steps \
have `.X` and `.T`, actions `.Q` and `.A`.";
    "SFC0310" Error "not an array"
        "Only ARRAY variables can be indexed with `[…]`.";
    "SFC0311" Error "duration is not TIME"
        "The duration of a timed qualifier is a TIME literal or a TIME variable.";
    "SFC0312" Error "indicator variable is not BOOL"
        "An action association's indicator variable must be a declared BOOL variable.";
    "SFC0313" Error "unknown type"
        "The type name is neither elementary, nor declared in a TYPE block of the file, nor a \
function block.";
    "SFC0314" Error "EXIT outside a loop"
        "`EXIT` leaves the innermost FOR, WHILE or REPEAT loop and is only valid inside one.";
    "SFC0315" Error "constant out of range"
        "The literal does not fit the type it is used with, for example `SINT#300`.";
    "SFC0316" Error "IL error"
        "The instruction list is not valid: an operator needs a loaded current result, or the \
operand type does not fit.";
    "SFC0317" Warning "variable never used"
        "A local variable is declared but never read or written.";
    "SFC0318" Error "duplicate declaration"
        "A type, POU, enumerated value or structure field is declared twice, or a declaration \
redefines a standard type, function or function block. Rename one of them.";
    "SFC0319" Error "duplicate CASE label"
        "Two labels of one CASE statement cover the same value, so the later arm can never run \
for it.\n\n    CASE n OF 1..5: a(); 3: b(); END_CASE  (* 3 is already in 1..5 *)";
    "SFC0320" Error "cannot be simulated"
        "The file checks, but the simulator cannot run this part of it: for example a function \
block type that contains an instance of itself (its memory would be infinite), or an SFC function \
block instance declared inside a FUNCTION (a function has no state that lasts between calls). \
Restructure the code, or simulate another POU.";
    "SFC0321" Error "no such POU to simulate"
        "`sfc sim --pou NAME` (or `pou =` in a scenario) names no PROGRAM or FUNCTION_BLOCK of \
the file, or the file has several candidates and none was named. Name one of those the note \
lists:\n\n    sfc sim plant.st --pou Main";

    "SFC0401" Error "too many states for the target"
        "ATMT has at most 16 states, EATMT 256 (`--nstep` overrides).";
    "SFC0402" Error "too many conditions for the target"
        "ATMT has at most 16 condition inputs (C0…C15), EATMT 256 (c0…c255).";
    "SFC0403" Error "too many rules for the target"
        "ATMT has at most 64 transition rules, EATMT 1024 (`--ntr` overrides).";
    "SFC0404" Error "simultaneous branch not supported by the target"
        "ATMT/EATMT are finite automata with one active state: no AND divergence or convergence.";
    "SFC0405" Error "actions not supported by the target"
        "ATMT/EATMT tables carry states and conditions only; the block's outputs are the state \
index. Remove action associations, or build for `st` instead.";
    "SFC0406" Error "condition must be a single input"
        "An ATMT condition is one input `C0`…`C15`; an EATMT condition `c0`…`c255`, `cX.Y` or its \
negation `NOT c5` / `!c5`.";
    "SFC0407" Error "negated condition not supported by ATMT"
        "Only EATMT accepts negated conditions (encoded as 1000+index).";
    "SFC0408" Error "tag does not match the condition input"
        "A transition's `sfc.tag` must equal the index of its condition input.";
    "SFC0409" Error "invalid state tag"
        "Step tags are distinct non-negative integers below the state limit, and the initial \
step must be state 0.";

    "SFC0501" Error "unsafe chart"
        "With the guards taken as free inputs, some firing sequence activates a step that is \
already active (IEC 61131-3: an \"unsafe SFC\"). The step then holds two tokens; the simulator \
keeps it active (set semantics) and emits an `unsafe` event. The witness is the shortest firing \
sequence from the initial situation; a note says whether the simulator could follow it with the \
real guards (confirmed, with the input schedule) or not (possible). A typical cause is a \
selection branch that leaves a simultaneous branch, so one token goes round while the other \
branch still runs:\n\n    TRANSITION FROM S1 TO (S2, S3) := Start; END_TRANSITION\n    \
TRANSITION FROM S2 TO S1 := Abort; END_TRANSITION   (* leaves S3 active *)\n\nLeave a \
simultaneous sequence only through its convergence: `TRANSITION FROM (S2, S3) TO S1`.";
    "SFC0502" Error "unreachable step"
        "No firing sequence from the initial situation ever activates the step, even with every \
guard free: it hangs from a dead transition or from nothing at all. (IEC 61131-3 calls such \
charts erroneous.) A typical cause is a simultaneous convergence that waits for a step of a \
selection branch that was not taken:\n\n    TRANSITION FROM S1 TO S2 := A; END_TRANSITION\n    \
TRANSITION FROM S1 TO S3 := B; END_TRANSITION\n    TRANSITION FROM (S2, S3) TO S4 := TRUE; \
END_TRANSITION   (* S2 and S3 are never active together: S4 is unreachable *)\n\nConverge a \
selection with a selection convergence (`FROM S2 TO S4` and `FROM S3 TO S4`).";
    "SFC0503" Error "dead transition"
        "The transition is never enabled: in no reachable situation are all its preceding steps \
active together. Usually a simultaneous convergence whose input steps lie in different branches \
of a selection, or a step that is itself unreachable. Connect the transition to steps that can be \
active together.";
    "SFC0504" Error "lock-up"
        "A reachable situation in which some active step has outgoing transitions but none of them \
can ever be enabled: the chart stops for good (a situation where no active step has any outgoing \
transition is a normal end, not a lock-up). Typical: a simultaneous branch ends, or jumps away, \
while its convergence still waits for it. The witness is the shortest firing sequence that \
reaches the situation; a note gives the input schedule that makes the simulator reach it.";
    "SFC0505" Warning "non-exclusive alternatives"
        "Two transitions leaving the same step can be true in the same scan: then only one fires, \
chosen by explicit PRIORITY or, without it, silently by declaration order. The witness is an \
input valuation under which both guards hold. Make the guards exclusive, or state the order:\n\n    \
TRANSITION T1 (PRIORITY := 1) FROM S1 TO S2 := Full; END_TRANSITION\n    TRANSITION T2 \
(PRIORITY := 2) FROM S1 TO S3 := Full OR Timeout; END_TRANSITION\n\nWith explicit priorities \
the finding is a note.";
    "SFC0506" Note "incomplete alternatives"
        "There is an input valuation (the witness) under which no transition leaving the step is \
true, so the step waits. That is normal SFC behaviour; the note helps to check that waiting is \
intended in that case, e.g. that `Level < 10` and `Level > 90` really should leave the chart \
waiting for `Level` between 10 and 90.";
    "SFC0507" Warning "condition always true"
        "The transition condition holds for every input valuation whenever its preceding steps \
are active (for example `Ready OR NOT Ready`), so the transition fires in the first scan after \
its step is activated. Write `TRUE` if that is intended. (A literal `TRUE` is not reported.)";
    "SFC0508" Warning "condition always false"
        "The transition condition can never hold when its preceding steps are active (for \
example `Level > 90 AND Level < 10`, or `S2.X` of a step that is never active together with the \
preceding step), so the transition never fires. (A literal `FALSE` is not reported.)";
    "SFC0509" Note "analysis incomplete"
        "The chart has more reachable situations than the analysis explores explicitly and is not \
structured enough for the cheap proofs; the findings listed are real, but the absence of others \
is not proven. Split the chart into function blocks, or structure its branches as matched \
divergences and convergences.";

    "SFC0601" Error "invalid attribute value"
        "An `sfc.*` attribute has a value of the wrong form: `sfc.tag` an integer, `sfc.timeout` \
a duration, `sfc.target` one of blank, atmt, eatmt.";
    "SFC0602" Warning "unknown sfc attribute"
        "The attribute is in the `sfc.` namespace but sfc does not know it; check its spelling.";
    "SFC0603" Warning "misplaced attribute"
        "The attribute pragma is not directly before an element it can describe.";
}

/// Looks a code up.
pub fn explain(code: &str) -> Option<&'static CodeInfo> {
    CODES.iter().find(|c| c.code.eq_ignore_ascii_case(code))
}

/// The registered severity of a code (error for an unregistered one).
pub(crate) fn default_severity(code: &str) -> Severity {
    explain(code).map(|c| c.severity).unwrap_or(Severity::Error)
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn codes_are_unique_and_well_formed() {
        let mut seen = std::collections::HashSet::new();
        for c in CODES {
            assert!(c.code.len() == 7 && c.code.starts_with("SFC"), "{}", c.code);
            assert!(c.code[3..].chars().all(|d| d.is_ascii_digit()), "{}", c.code);
            assert!(seen.insert(c.code), "duplicate {}", c.code);
        }
    }
}
