//! The registry of diagnostic codes. Codes are a contract: never renumber, only add.
//!
//! Ranges: `SFC00xx` lexical, `SFC01xx` syntax, `SFC02xx` chart structure, `SFC03xx` names and
//! types, `SFC04xx` ATMT/EATMT target rules, `SFC05xx` analysis, `SFC06xx` pragmas and attributes,
//! `SFC07xx` import (PLCopen XML), `SFC08xx` code generation, `SFC09xx` behaviour that differs
//! under a vendor profile (`sfc check --profile`), `SFC10xx`
//! requirements (`sfc prove`).

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
    "SFC0013" Note "CODESYS identifier"
        "In a POU marked `{attribute 'sfc.dialect' := 'codesys'}` (the PLCopen import marks those \
of CODESYS and TwinCAT projects that need it), identifiers with doubled or trailing underscores \
(`Move_Forwards__Pos3`), which CODESYS and TwinCAT accept, are read as written. IEC 61131-3 does \
not allow them; the note names the first.";
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

    "SFC0011" Warning "text file not in UTF-8"
        "The file is not valid UTF-8, so it was read as Latin-1 / Windows-1252 (what older Windows \
editors and many PLC tools write). The warning names the first line that is not UTF-8. `sfc fmt` \
and the editor write the file back in the same encoding, with its byte order mark and line \
endings; converting it to UTF-8 silences the warning. A UTF-16 file with a broken character (an \
unpaired surrogate, an odd last byte) gets this warning too: the character reads as U+FFFD.";
    "SFC0012" Error "binary file"
        "The file holds a NUL byte near its start: it is not text, and no other diagnostic is given \
for it. sfc reads IEC 61131-3 text (UTF-8, UTF-16 or Latin-1) and PLCopen XML. A vendor's project \
file is binary (a CODESYS `.project`, a TwinCAT archive); export the POU as PLCopen XML from that \
tool and give sfc that file.";
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

    "SFC0106" Warning "nothing to check"
        "The file declares no POU, type or global variable: it is empty or holds only comments. \
Perhaps it is the wrong file, or it was saved empty.";

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
    "SFC0215" Warning "duplicate transition"
        "Two transitions connect exactly the same steps with the same condition. IEC 61131-3 allows \
it, but the later one never fires (the earlier one always takes the step first, in declaration or \
priority order), so it is probably a copy: delete it or change its condition.";
    "SFC0216" Error "step links to itself in one transition"
        "A transition lists the same step twice in FROM or in TO.";
    "SFC0217" Error "transition condition missing"
        "A transition needs a condition: `:= expression;` or an IL body after `:`.";
    "SFC0218" Error "no SFC body"
        "The file has no POU with steps; sfc needs at least one chart for this command.";

    "SFC0219" Warning "output latched by a non-stored action"
        "An action associated with N (or L, D) sets a BOOL output TRUE in its body, and nothing in \
the POU ever writes anything else to it. The assignment is stored in the variable, so the output \
stays TRUE after the step is left, although the action looks as if it lasted only while the step \
is active.\n\n    STEP S2: Show(N); END_STEP\n    ACTION Show: Visible := TRUE; END_ACTION   (* latches *)\n\n\
Associate the output itself so it follows the step (`STEP S2: Visible(N); END_STEP`), or reset \
it (`Visible := FALSE` in another step, or `IF NOT Show.Q THEN Visible := FALSE; END_IF` for the \
action's last run).";
    "SFC0220" Warning "step name repeated in another chart of the POU"
        "A step of an action written in SFC has the name of a step of another chart of the same POU \
(its body or another action's). CODESYS's documentation asks for step names unique within the POU; \
TwinCAT projects exist that repeat them, and each chart keeps its own step. In code, `Step.X` means \
the step declared first.";

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
    "SFC0322" Warning "internal variable of an instance read from outside"
        "A local variable (`VAR`) of a function block instance is read from outside the block \
(`Valve.DI_Open`). IEC 61131-3 lets only inputs and outputs be reached through an instance; \
CODESYS and TwinCAT also allow reading its local variables (their static analysis reports it as \
SA0102), so projects written there do it. sfc reads the value as they do. Writing it stays an \
error (SFC0309).";
    "SFC0323" Error "interface not implemented"
        "A block that `IMPLEMENTS` an interface lacks one of the interface's methods or properties, \
or declares it with another result type, other parameters, or without an accessor the interface \
declares (`GET`, `SET`). Every call through the interface must find the method in the block.";
    "SFC0324" Warning "interface not declared in the file"
        "A block `IMPLEMENTS` an interface the file does not declare (a library's): what the \
block promises is not checked. Declare the interface (`INTERFACE … END_INTERFACE`) in the file to \
have it checked and to call the block through it.";
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
    "SFC0410" Error "chart cannot be compiled to a transition table"
        "A transition table needs the target `atmt` or `eatmt`, an initial step (it becomes \
state 0) and a condition input on every transition (a transition whose condition was lost to a \
syntax error has none). Fix the chart, or build for another target.";
    "SFC0411" Error "simultaneous firings cannot be flattened"
        "`--flatten` turns every reachable situation of a chart with simultaneous branches into \
one state of the automaton. An ATMT/EATMT rule tests ONE condition and the block takes the first \
true rule of its state, so the flattened table can follow the chart only when, in every \
situation, what happens next is decided condition by condition. Two parallel branches waiting \
for different inputs are not: when both inputs are TRUE in the same scan both transitions fire \
together, which needs `C1 AND C2`. The witness is the firing sequence that reaches the \
situation. Make the branches wait on the same input, use exclusive conditions (EATMT: `c1` and \
`NOT c1`), or sequence them:\n\n    TRANSITION FROM S0 TO (A1, B1) := C0; END_TRANSITION\n    \
TRANSITION FROM A1 TO A2 := C1; END_TRANSITION   (* may fire together with ... *)\n    \
TRANSITION FROM B1 TO B2 := C2; END_TRANSITION   (* ... this one: refused *)";
    "SFC0412" Error "flattened automaton has too many states"
        "The chart has more reachable situations than the block has states (ATMT 16, EATMT 256, \
`--nstep` overrides). Each combination of active steps of parallel branches is one state, so \
their number multiplies; split the chart or shorten the parallel branches.";
    "SFC0413" Error "flattened automaton has too many rules"
        "The rules of all states of the flattened automaton exceed the block's limit (ATMT 64, \
EATMT 1024, `--ntr` overrides).";
    "SFC0414" Error "too many inputs in one situation to flatten"
        "Flattening examines every valuation of the inputs that the transitions enabled in one \
situation test; it handles at most 16 different inputs per situation.";
    "SFC0415" Note "states of the flattened automaton"
        "Lists which set of active steps each state number of a flattened table stands for. State \
0 is the initial situation; the others are numbered in the order they are first reached. A \
state's timeout is the smallest `sfc.timeout` of its steps, and the block restarts it at every \
state change, including a move of another parallel branch.";

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
    "SFC0510" Warning "runaway scan"
        "While the analysis replayed a witness in the simulator, one scan spent its whole budget \
of loop iterations, IL jumps and calls (a loop that does not end for the inputs the replay \
tried, or unbounded recursion through calls). The replay stops there, so the finding it was \
confirming stays *possible*. The same code would stop `sfc sim` and trip the watchdog of \
`sfc run`: give the loop a bound that holds for every input.";

    "SFC0601" Error "invalid attribute value"
        "An `sfc.*` attribute has a value of the wrong form: `sfc.tag` an integer, `sfc.timeout` \
a duration, `sfc.target` one of blank, atmt, eatmt.";
    "SFC0602" Warning "unknown sfc attribute"
        "The attribute is in the `sfc.` namespace but sfc does not know it; check its spelling.";
    "SFC0603" Warning "misplaced attribute"
        "The attribute pragma is not directly before an element it can describe.";
    "SFC0604" Warning "setting not simulated"
        "The chart sets a vendor's execution option that the simulator does not follow yet (for \
example Studio 5000's \"Automatic reset\" last scan, `sfc.logix.lastscan 'AutomaticReset'`, whose \
postscan mode is not simulated). The message says what runs instead; docs/sim.md gives the \
details.";
    "SFC0605" Error "unresolved merge conflict"
        "`sfc merge` (or git's merge through `sfc git setup`) found an element changed both ways \
and wrote our version of it, marked with `{attribute 'sfc.conflict' := …}` before the POU, which \
holds the element and their version. Open the file in the editor and take ours or theirs for \
each conflict, or edit the element by hand and delete the attribute.";

    "SFC0701" Error "malformed XML"
        "The file is not well-formed XML (an unclosed element, a stray `<` or `&`, a mismatched end \
tag), so nothing can be imported. The location is where the XML parser stopped; the mistake is \
often just before it:\n\n    <step localId=\"1\" name=\"Init\">    <!-- neither `/>` nor `</step>` -->";
    "SFC0702" Error "not a PLCopen project"
        "The document element of a PLCopen TC6 file is `project` (with `fileHeader`, \
`contentHeader`, `types` and `instances`); this file has another one and is not imported.";
    "SFC0703" Warning "unknown PLCopen namespace"
        "The `project` element is not in one of the PLCopen TC6 namespaces sfc reads \
(`http://www.plcopen.org/xml/tc6_0201`, `…/tc6_0200`, `http://www.plcopen.org/xml/tc6.xsd` for \
v1.0). The file is read by element names anyway; check the result.";
    "SFC0704" Error "invalid IEC name"
        "A name in the XML (of a step, variable, action, POU, type) is not an IEC 61131-3 \
identifier: letters, digits and single underscores, starting with a letter or `_`, not ending \
with `_`, not a keyword. It is imported under a repaired name (`Step 1` becomes `Step_1`); rename \
it in the source tool.";
    "SFC0705" Error "unsupported PLCopen element"
        "The element has no counterpart in textual IEC 61131-3 and is not imported (or imported \
as the message says): FBD jumps, labels and returns, vendor elements, pointer types, an action or \
condition written in SFC, a macro step without a body, a block enabled through `EN`. The rest of \
the file is imported; rewrite this part in ST or as plain SFC.";
    "SFC0706" Error "broken connection"
        "A connection of a graphical body refers to a `localId` that does not exist, joins \
elements that cannot follow each other (a transition after a transition, a step after a step), \
or a transition lacks a preceding or following step. A transition without a step on one side (a \
chart still being drawn) cannot be written in IEC text: it is kept on the POU in an `sfc.loose` \
attribute, which the editor draws and the PLCopen export writes back wired as it was, but the chart \
does not hold it. Any other such element is not imported. PLCopen stores each link on its \
consumer: `connectionPointIn/connection@refLocalId` names the producer.";
    "SFC0707" Note "condition network calls function blocks"
        "A transition condition drawn in FBD or LD uses function block instances (a timer, a \
flip-flop). A condition is an expression and cannot call them, so, as Beremiz does when it \
compiles the chart, the calls are put into the action `COMPUTE_FUNCTION_BLOCKS`, associated with \
the initial step with qualifier S: they run in every cycle, and the condition reads their \
outputs:\n\n    INITIAL_STEP Init:\n        COMPUTE_FUNCTION_BLOCKS(S);\n    END_STEP\n    \
TRANSITION FROM Green TO Orange := TON3.Q OR WarnCars; END_TRANSITION";
    "SFC0708" Error "missing transition condition"
        "The transition has no usable condition: no `condition` element, a reference to a name \
missing from the POU's `transitions`, a condition body that never assigns the transition's name, \
or nothing wired to the condition input. It is imported as `FALSE`, so the transition never \
fires; supply the condition in the source tool.";
    "SFC0709" Note "macro step flattened"
        "Textual IEC 61131-3 has no macro steps: the macro step's body is imported in its place. \
Transitions into the macro step go to the first step of its body, transitions out of it leave \
from the body's last step. Exporting the chart again writes the flattened steps.";
    "SFC0710" Warning "XML content not imported"
        "Part of the file has no effect in the imported program and is left out: a named \
transition condition nothing refers to, a second body of a POU, an element that does not belong \
in an SFC body, a coil on the path of a transition condition (a condition cannot assign it).";
    "SFC0711" Note "vendor element skipped"
        "A network holds a vendor's own element (a CODESYS FBD `vendorElement`: a box, a comment or \
a connector only its tool can draw). It has no IEC 61131-3 meaning and is skipped; the rest of the \
network is imported.";
    "SFC0712" Warning "no SFC POU in the file"
        "The file imports, but none of its POUs is a Sequential Function Chart, so there is no chart \
to check, simulate, build or edit. The note lists the POUs found. A CODESYS project export keeps an \
application's POUs in its resource's `addData`; those are read too.";
    "SFC0713" Warning "unknown type imported as an opaque block"
        "The file uses a data type or function block that it does not declare: a library's (a \
CODESYS library, `Util.BLINK`), or an extension's (Beremiz's svghmi `HMI_*`, py_ext `python_eval`, \
svgui `Button`, `Led`). It is imported as an opaque function block: its instances are kept and \
written back on export, everything done with them is accepted, and nothing about them is analysed \
or simulated.";

    "SFC0714" Note "library data type declared"
        "The file uses a data type of Beremiz's svghmi library without declaring it, as Beremiz \
projects with an SVG HMI do. The library declares each as an elementary type (`HMI_BOOL`, \
`HMI_CLASS` and `HMI_LABEL` as BOOL, `HMI_INT` as INT, `HMI_REAL` as REAL, `HMI_STRING` as \
STRING), and the import adds that declaration, so the HMI variables are checked and simulated as \
the values they are.";

    "SFC0715" Warning "variable renamed with its uses"
        "A variable of the imported POU is named by a word that begins a chart element in sfc's \
text (`Step`, `Action`, `Transition`, `From`: IEC 61131-3 reserves them, CODESYS's ST does \
not). It is imported as `X_Step`, and every use of it in the code of the file is renamed alike, \
so the program does what it did. An export writes the new name.";
    "SFC0716" Warning "POU written as it was read"
        "`sfc build --target plcopen` never refuses a POU for its own errors: a POU whose errors \
keep its chart from being written whole (a syntax error, an association naming no action, a \
timed qualifier without duration, …) is written as it was read from the PLCopen file, or, for \
textual input, with its text kept in its `addData`, which `sfc` reads back as it was. The import \
says so when it reads such a POU.";

    "SFC0720" Note "L5X import note"
        "Something the L5X import decided that changes nothing of the chart's behaviour but is worth knowing: a program or routine export carries no controller SFC settings, so Studio's defaults (`CurrentActive`, `MostRecent`, `DontScan`) are written in `sfc.logix.exec`, `sfc.logix.restart` and `sfc.logix.lastscan`; an SFC routine is imported under another name (`Program_Routine` when two programs have routines of the same name); a selection divergence with user-defined priorities is read in the order of its legs.";

    "SFC0721" Warning "tag declared from its use"
        "The chart uses a tag that the L5X file does not declare (a program export leaves the controller's tags out). The import declares it in the POU from how the chart uses it: BOOL when it is read as a condition or written 0 or 1, DINT when it takes part in arithmetic or is compared with other numbers. A tag used as a structure or an array cannot be declared this way. Export the controller, or the program with its context, to get the real types.\n\n    Tank_Level > 80   (* Tank_Level : DINT *)";

    "SFC0722" Warning "L5X content not imported"
        "Part of the L5X file has no place in sfc's text and is left out or reduced, never silently: an alias tag (declared as a variable of its own), a produced or consumed tag (a plain variable), a tag of an Add-On Instruction or a module type, an initial value that is not a simple literal, a forced transition or leg (imported without the force), SFC subroutine parameters (`SbrRet`, kept in an attribute).";

    "SFC0723" Error "Logix tag member without IEC equivalent"
        "A condition or an action reads a member of an SFC_STEP, SFC_ACTION or SFC_STOP tag that sfc's IEC text cannot express: the alarm bits and limits of a step, `T`, `PRE` and `Count` of an action, `Count` of a stop. The `logix` simulation profile does not simulate them yet. The import reads `.X`, `.T` (as `TIME_TO_DINT(S.T)`, milliseconds), `.DN` (as `S.T >= T#<PRE>ms`), `.PRE`, `.OV` (as `S.T > T#2147483647ms`, the DINT timer rolled over), `.Count` (the `logix` dialect's step member: how many times the step became active) `.FS`, `.SA`, `.LS` (its first scan, the scans between, its last scan) and `.TMax` (its longest activation, ms; members of the dialect too) of a step, `.Q` and `.A` of an action and `.X` of a stop.";

    "SFC0724" Error "Logix instruction not in sfc's ST"
        "The Structured Text of a condition or an action calls a Logix instruction that sfc's ST does not have, or has with another meaning: `JSR`, `SFR`, `SFP`, `ONS`, `TONR`, Logix's `TON(Timer)` on a FBD_TIMER tag, `MSG`, `GSV`, `COP`… Write the IEC equivalent (a function block instance such as `T1(IN := Run, PT := T#5s)`, or the step's own timer `Step.T`).";

    "SFC0725" Error "SFC routine links do not make a chart"
        "The steps, transitions, branches and directed links of the SFC routine do not make a chart sfc can hold: a transition with no step above or below it (kept in `sfc.loose`, drawn but not part of the chart), a step no transition leads to, a link naming an ID no element has, an ID used twice, two transitions linked without a step between them, a selection branch where Studio places a simultaneous one. Studio exports charts that do not verify; fix the chart in Studio or in sfc.";

    "SFC0726" Warning "preset from an expression"
        "A step's or an action's preset is an expression (`PresetUsesExpr=\"true\"`) instead of the tag's `PRE`. A step's `.DN` is imported as the comparison of its time with the expression in every scan; a timed action's duration is written `T#0ms` (an IEC association takes a literal or a TIME variable). The expression is kept in `sfc.logix.preset_expr`.";

    "SFC0727" Warning "unknown L5X value"
        "An attribute of the L5X file has a value the import does not know (a qualifier, a branch type, a controller SFC setting) or an element lacks its tag name (`Operand`). The import says how it read it; the value is kept as written for the way back.";

    "SFC0728" Warning "tag named like a chart element"
        "A program tag has the name of one of the chart's steps, transitions or actions (Studio gives every transition a BOOL tag of its name). In sfc's text an element and a variable of the same POU cannot share a name: the element keeps it and the tag is not declared.";

    "SFC0729" Error "transition condition is not an expression"
        "A transition's condition is empty, or is an assignment instead of a BOOL expression (`Done := Level > 80;`). Studio's verification refuses it too; the import writes `FALSE` in its place.\n\n    Level > 80;";

    "SFC0730" Warning "no SFC routine in the L5X file"
        "The L5X file imports, but none of its programs has a routine of type SFC, so there is no chart to check, simulate, build or edit. The note lists the routines found.";

    "SFC0731" Error "not an L5X export sfc can read"
        "The file's document element is not `RSLogix5000Content`, it has no `Controller`, or an SFC routine has no `SFCContent`. Export the controller, program or routine again from Studio 5000 (File > Save As > L5X, or Export Routine).";
    "SFC0740" Error "no S7-GRAPH block in the TIA Portal export"
        "The TIA Portal (Openness, SimaticML) export holds no function block whose `ProgrammingLanguage` is GRAPH (a LAD or SCL block, a data block, a tag table), so there is no chart to import; the message names what it holds. A GRAPH block without a `Graph` network source is reported the same way. Export the GRAPH FB itself from TIA Portal.";
    "SFC0741" Note "GRAPH block properties assumed"
        "The export does not give the GRAPH block properties that decide how the sequence runs (`AcknowledgeErrorsRequired`, `SkipSteps`, `LockOperatingMode`, `PermanentILProcessingInMANMode`, `WithAlarmHandling`): minimal exports leave them out. TIA Portal's defaults are assumed and written into the `sfc.s7graph.*` attributes of the FUNCTION_BLOCK. An export made with defaults (`ExportOptions.WithDefaults`) writes them.";
    "SFC0742" Warning "GRAPH behaviour kept but not simulated"
        "Interlocks, supervisions, actions bound to the events V1, V0, L1, L0, A1 and R1, interlock-dependent (C) actions and the permanent pre/post instructions of a GRAPH block are imported into `sfc.s7graph.*` attributes and unassociated actions, so an export writes them back, but the IEC simulation does not run them: it runs the steps, the transitions and the plain actions. The `graph` simulation profile will run them. The message counts what the file holds; an interlock-dependent action runs as if its interlock were satisfied.";
    "SFC0743" Error "GRAPH network cannot be read"
        "A LAD or FBD network of a transition, an interlock, a supervision or a permanent instruction could not be turned into ST: a part sfc does not read (edge contacts, timers, boxes with EN/ENO), a pin wired to nothing, a wire from or to a UId that is no part or operand of the network, wires that form a cycle, two coils, a part off the path to the coil, an operand of an absolute address. The location is the offending `Part`, `Access` or wire end; the transition's condition is imported as `FALSE`.";
    "SFC0744" Warning "global operand declared from its use"
        "A network or an action uses a global operand (`\"DB\".a.b`, a PLC tag, a global constant) whose data block or tag table is not in the export. It is declared in a file-level `VAR_GLOBAL` under a flat name (the path's parts joined by `_`: `DB_a_b`), with the type its first use implies (BOOL from a contact or an N action, the comparator's `SrcType`, INT from an assignment of an integer, TIME from the time of a D or L action). The message says which; a global constant starts at its type's default value, since its value is not exported.";
    "SFC0745" Warning "GRAPH action imported approximately"
        "The GRAPH action has no exact IEC counterpart and is imported as the message says: a counter (CS, CU, CD, CR) counts an INT; a block call (CALL), a step activation (ON, OFF) or a GRAPH timer (TD, TF, TL, TR) is kept as a comment in a named action, which does nothing in the IEC simulation; an S or R action with an assignment runs the assignment while the step is active. The original tokens are kept in `sfc.s7graph.tokens`.";
    "SFC0746" Error "GRAPH action cannot be imported"
        "The GRAPH action cannot be read: an unknown qualifier, a D or L action without `operand , time` or bound to an event, tokens that do not form operands (an unclosed quote or index), an array index that is not a constant on a DB operand. It is not imported.";
    "SFC0747" Note "sequence end imported as a final step"
        "A GRAPH transition may end its sequence path (`EndConnection`, a branch stop); an IEC transition must lead to a step. The transition leads to a step of its own, named after it (`T4_End`), marked `{attribute 'sfc.s7graph.end' := '<transition>'}` (an export writes it back as the sequence end) and `sfc.final` (no way out, intended).";
    "SFC0748" Error "broken GRAPH sequence"
        "The sequence's `Connections` do not link steps and transitions as GRAPH does: a connection names a step, transition or branch the sequence lacks, a transition has no step before or after it, a transition follows a transition, a branch is entered the wrong way (a transition into an AltBegin, a step into an AltEnd), two steps or transitions share a number. The element is not imported.";
    "SFC0749" Warning "GRAPH system data disagrees with the chart"
        "The interface's system members (`G7_StepPlus_Vn` per step, `G7_TransitionPlus_Vn` per transition) are the chart's runtime data and are not imported as variables: TIA Portal writes them from the steps and transitions (`SNO` and `TNO` their numbers, `T_MAX` and `T_WARN` the step's `MaximumStepTime` and `WarningTime`). Here they disagree with the chart, or belong to no step or transition; the chart's values are imported.";
    "SFC0750" Error "GRAPH condition or action is not valid ST"
        "An interlock, a supervision or an action body, as imported into ST, does not parse (checked with sfc's own ST parser). The text is kept as it came; correct it in TIA Portal.";
    "SFC0751" Warning "GRAPH runtime data in a transition condition"
        "A transition condition reads GRAPH runtime data of a step or transition (`U`, `S1`, `LA`, `TT`, …) that an IEC step does not have; IEC steps have `.X` and `.T`. `Step.U`, the step time without disturbance, is read as `Step.T` (an IEC step is never disturbed); any other member is kept as written and the check reports it.";
    "SFC0752" Warning "SIMATIC declaration imported approximately"
        "A member of the block interface is declared in a way IEC text cannot say exactly: a data type that is not in the export (a PLC data type, a system type) is written under its name and must be declared for sfc to check the block; `IEC_TIMER` becomes `TON`; the start values of elements (`Subelement`) are imported only for a one-dimensional array of an elementary type; an unknown interface section is left out.";
    "SFC0753" Note "GRAPH name imported as an IEC name"
        "GRAPH names steps, transitions, variables and blocks freely (`Z-Achse MA05 Pos1`, `compr. air release 1`); IEC names are letters, digits and single underscores. The name is repaired (`Z_Achse_MA05_Pos1`, numbered if two names give the same one), its uses follow, and the original is kept in `sfc.s7graph.name` for the export.";

    "SFC0754" Note "GRAPH transition without a network"
        "The transition has no LAD or FBD network (`FlgNet`): GRAPH treats an empty transition as \
fulfilled, so it is imported as `TRUE`, and the step before it is left in the next cycle.";

    "SFC0801" Error "chart cannot be translated to ST"
        "The Structured Text target (`--target st`) replaces the chart's POU by a plain ST POU of \
the same kind and name. It needs an error-free file, a PROGRAM or FUNCTION_BLOCK (a FUNCTION \
keeps no state between calls, so it cannot hold a chart), and a condition on every transition.";
    "SFC0802" Error "IL current result after a label"
        "The ST translation follows IL's current result as an expression. After a label the \
current result depends on how control got there (the line before or a jump), so an instruction \
that uses it right after the label cannot be translated; jumps inside transition conditions or \
inside parentheses cannot either. Load a value after the label:\n\n    \
JMPC Skip\n    LDN  X\nSkip:   LD   Y      (* not: Skip: ST X *)\n    ST   X";
    "SFC0803" Error "IL current result may have changed"
        "The ST translation writes IL's current result as the expression that computed it. An \
instruction before this one may have changed a variable that expression reads (`LD X  R X  ST \
Y`: Y gets the old X in IL), so reusing the expression would give another value. Load the value \
again, or store it in a variable and load that.";
    "SFC0804" Error "IL instruction not translatable"
        "The instruction has no ST translation here: a statement (ST, S, R, CAL, JMP, RET) inside \
a transition condition or a parenthesised operand, an operator without the operand it needs, or \
a jump to a label that does not exist.";

    "SFC0805" Warning "CODESYS extension kept as CODESYS writes it"
        "The file has what CODESYS, TwinCAT and e!COCKPIT add to IEC 61131-3: actions of a function \
block or program that is no chart (`ACTION … END_ACTION` after the POU's statements, called \
`inst.Act();`), methods, properties, `EXTENDS`, `IMPLEMENTS` or interfaces. The Structured Text \
target copies them as they are: CODESYS and its family compile the result, the IEC 61131-3 \
compilers of Beremiz and OpenPLC v3 (MatIEC) and of OpenPLC v4 (STruC++) do not. \
`--st-dialect codesys` says nothing about them.";
    "SFC0806" Error "CODESYS action not generated for this target"
        "The chart's POU has an action written in SFC (a chart inside an action) or a step with \
step actions (`ENTRY_ACTION`, `STEP_ACTION`, `EXIT_ACTION`), as CODESYS, TwinCAT and e!COCKPIT \
write them. The ST, STL, ATMT and EATMT targets do not generate them yet, and leaving them out \
would give a program that does something else. `sfc sim`, `sfc check`, `--target text` and \
`--target plcopen` handle them.";
    "SFC0807" Error "duration finer than the dialect's TIME"
        "`--st-dialect codesys` writes ST for CODESYS and TwinCAT, whose TIME counts milliseconds \
(durations below the millisecond are LTIME's). A duration of the chart with a part below the \
millisecond (`T#2ms500us`, or a supervision time like it) would be rounded there, and the \
program would not behave as the chart: it is refused where it is written. Write whole \
milliseconds, or build with `--st-dialect iec` for a compiler whose TIME holds microseconds.";
    "SFC0808" Note "configuration added for MatIEC"
        "`--st-dialect matiec` writes ST for MatIEC, the compiler of Beremiz and OpenPLC v3. OpenPLC \
v3 compiles an uploaded `.st` file together with its `CONFIGURATION` (its editor writes one), so \
a file without one gets `CONFIGURATION Config0` at the end: one resource, one task `task0` every \
20 ms (OpenPLC v3's default), and one instance of every PROGRAM of the file. Set `INTERVAL` to \
the scan period the chart was written for. A file with a configuration is left as it is.";
    "SFC0809" Error "short-circuit operator without an IEC form"
        "`AND_THEN` and `OR_ELSE` (CODESYS) skip their right operand when the left one decides. \
IEC 61131-3 Structured Text as MatIEC and STruC++ read it has no such operator, so the ST target \
writes them as `AND` and `OR`, which give the same value when the right operand cannot fault. \
When it may (a division or `MOD`, an array index, a call), the plain operator would evaluate it \
where the chart does not, and could stop the program: the translation is refused there. Write \
the condition as an `IF`, or build with `--st-dialect codesys`, which keeps them.";
    "SFC0810" Error "not expressible in the S7-200 program"
        "The S7-200 statement-list target (`--target stl`) turns conditions into bit logic over \
inputs, outputs, memory, step, timer and counter bits, and into compare contacts (`LDW>=`, \
`LDD<>`) over INT, UINT, WORD, DINT, UDINT and DWORD values. This expression has no faithful \
form there: a REAL or STRING, a function call, an array element, a division by a variable (the \
S7-200 goes on with the old value where the IEC chart stops with a runtime error), an unsigned \
comparison by size (the compare contacts are signed), the count of a CTD (the S7-200 CTD stops \
at 0), or an IL instruction other than LD, AND, OR, XOR (also with N) and NOT. Compute the value \
in INT or DINT, or give the chart a BOOL:\n\n    \
TRANSITION FROM Fill TO Full := Level >= 80; END_TRANSITION   (* Level : INT *)";
    "SFC0811" Error "statement not supported by the STL target"
        "S7-200 action bodies are BOOL and integer assignments (`Lamp := Start AND NOT Fault;`, \
`Count := Count + 1;`), IF / ELSIF / ELSE around them, calls of counter blocks (CTU, CTD, CTUD, \
one call per instance: an S7-200 counter instruction runs at most once per scan), and in IL the \
instructions LD, AND, OR, XOR, NOT, ST, STN, S and R on BOOL variables. Other blocks (a TON is an \
action qualifier here: `Lamp(L, T#2s)`), CASE, FOR, WHILE, REPEAT, EXIT, RETURN, assignments to \
TIME variables (they are timer presets) and inputs have no translation; build for `st` instead.";
    "SFC0812" Error "step time not representable by an S7-200 timer"
        "A step time is read through 100 ms S7-200 timers whose presets are fixed in the program, \
so `S.T` must be compared with a duration known when the program is generated (a literal, a \
CONSTANT, or a TIME variable the chart does not write: warning SFC0817), of at most 3276.7 s; \
= and <> need a multiple of 100 ms (a step time counts whole timer ticks):\n\n    \
TRANSITION FROM Heat TO Hold := Heat.T >= T#1m30s; END_TRANSITION";
    "SFC0813" Error "action association not supported by the STL target"
        "Timed qualifiers (L, D, SD, DS, SL) use one S7-200 100 ms TON per action, so the \
duration must be known when the program is generated (at most T#54m36s700ms), and the timed \
associations of one action must all have the same qualifier and duration: different ones contend \
at run time, and the simulator's choice between them has no fixed program form.\n\n    \
Horn(L, T#2s);   (* in every step that sounds the horn *)";
    "SFC0814" Error "address not available on the S7-200"
        "A variable located `AT` a direct address is that S7-200 operand: `%IXb.i` is `Ib.i`, \
`%QXb.i` is `Qb.i`, `%MXb.i` is `Mb.i` (bytes I0-I15, Q0-Q15, M0-M31, bits 0-7); an INT, UINT or \
WORD is `%MWn`, `%IWn` or `%QWn`, a DINT, UDINT or DWORD `%MDn`. Other addresses name no such \
operand. The input image is read-only for the program: no action or assignment may write a \
variable located in `%I`.";
    "SFC0815" Error "S7-200 resources exceeded"
        "The program needs more than the S7-200 has: 100 ms timers (182 TON: T37-T63 and \
T101-T255; 54 TONR: T5-T31 and T69-T95; one per distinct step-time comparison, supervision time \
and action with a timed qualifier), 256 counters, 256 jump labels, bit memory (M0.0-M31.7, then \
V memory), or, with `--stl-method scr`, one S bit per step (S0.0-S31.7: 256 steps; the set/reset \
method continues in M and V bits). Split the chart, or use fewer distinct step-time constants.";
    "SFC0816" Error "chart control variable not supported by the STL target"
        "The S7-200 program implements `SFCError` (set when a step stays longer than its \
`sfc.timeout`, readable by the chart) and `SFCQuitError` (acknowledges it). `SFCInit` and \
`SFCPause` (hold or freeze the chart) and the STRING outputs `SFCErrorStep` and `SFCCurrentStep` \
have no form there, so a chart that declares or reads one is refused rather than run \
differently. Drive the chart with ordinary transitions instead (an abort transition on a BOOL \
input).";
    "SFC0817" Warning "value fixed when the S7-200 program is generated"
        "A TIME variable used as a step-time comparison or a qualifier duration becomes the preset \
of an S7-200 timer, which the program fixes at the variable's initial value: changing the \
variable at run time has no effect on the PLC. Declare it CONSTANT to state that, or change the \
initial value and build again. The same warning marks a RETAIN variable with a non-zero initial \
value, which the program does not set in the first scan (the retentive memory keeps its value).";

    "SFC0818" Note "name renamed for the compiler"
        "MatIEC reserves the names of its standard functions and keywords (`LEFT`, `LOG`, `ADD_INT`, \
`DT`…): `iec2c` refuses a variable, step or POU so named. STruC++ reads a call `Inc(…)` of a \
function block instance named like a function of its libraries (`INC`, `CMP`…) as a call of the \
function. For `--st-dialect matiec` and `strucpp` such a name is renamed in the whole output \
(`Left` becomes `Left_1`), and this note says so: the program's variable has the new name in \
the PLC.";
    "SFC0820" Error "not expressible in an L5X SFC routine"
        "The chart uses something a Studio 5000 SFC routine cannot hold (the message says what and \
where): `sfc build --target l5x` writes nothing rather than a routine that behaves otherwise.";
    "SFC0821" Warning "behaves differently in Studio 5000"
        "The chart is written as an L5X SFC routine, but a Logix controller runs this element \
differently from the chart's own rules (the message says how; docs/sim.md, \"The `logix` \
profile\"). The routine is written; check the behaviour, or change the chart.";
    "SFC0830" Error "not expressible in an S7-GRAPH block"
        "The chart uses something an S7-GRAPH function block cannot hold (the message says what and \
where): `sfc build --target simaticml` writes nothing rather than a block that behaves \
otherwise.";
    "SFC0831" Warning "behaves differently in S7-GRAPH"
        "The chart is written as an S7-GRAPH block, but S7-GRAPH runs this element differently from \
the chart's own rules (the message says how; docs/sim.md, \"The `graph` profile\"). The block \
is written; check the behaviour, or change the chart.";

    "SFC0840" Warning "behaves differently in IEC 61131-3 tools"
        "The chart was written for Studio 5000 or S7-GRAPH (`sfc.dialect`) and the output (PLCopen \
XML, ST) goes to tools that run IEC 61131-3's rules (CODESYS, TwinCAT, Beremiz, OpenPLC): the \
message says what runs differently there (the order of a call, the first call, an action's \
final run, S7-GRAPH's interlocks and supervisions, which act in no IEC tool). The output is \
written; check the behaviour (`sfc sim --profile iec`).";

    "SFC0901" Warning "transition tested in scan 0 under MatIEC"
        "MatIEC's generated code has no first-scan guard: a transition leaving an initial step is \
tested in the very first scan, so when its condition already holds the initial step is left \
before its actions run. IEC (and `--profile iec`) runs only the initial step's actions in scan 0. \
Reported by `sfc check --profile matiec`:\n\n    INITIAL_STEP S0: Y(N); END_STEP\n    TRANSITION \
T1 FROM S0 TO S1 := TRUE; END_TRANSITION   (* MatIEC: S1 at scan 0, Y never on *)\n\nWait for an \
input or a step time (`S0.T >= T#10ms`) if the initial actions must run.";
    "SFC0902" Warning "every TRUE alternative fires under MatIEC"
        "MatIEC fires every transition whose preceding steps are active when it is tested: two TRUE \
alternatives without PRIORITY both fire (the step gets two successors), and an unprioritised \
transition tested before a prioritised one fires with it. IEC fires one: explicit PRIORITY first, \
then declaration order. Make the conditions exclusive, or give each alternative a PRIORITY \
(MatIEC then clears the step as soon as the first one fires):\n\n    TRANSITION T1 (PRIORITY := 1) \
FROM S1 TO S2 := Full; END_TRANSITION\n    TRANSITION T2 (PRIORITY := 2) FROM S1 TO S3 := Full OR \
Timeout; END_TRANSITION";
    "SFC0903" Warning "step flag read after a PRIORITY transition cleared it under MatIEC"
        "When a transition with an explicit PRIORITY fires, MatIEC clears its preceding steps at \
once, in the middle of testing the transitions, so a condition tested after it reads `S.X` as \
FALSE in the same scan. IEC evaluates every condition on the situation at the start of the \
scan. Read an input or a variable instead of the step flag, or drop the PRIORITY.";
    "SFC0904" Warning "association switched off by another under MatIEC"
        "MatIEC writes the associations of an action (or BOOL variable) one by one, steps in \
declaration order, each on its own: N writes TRUE while its step is active and FALSE in the scan \
it is left; L writes FALSE once its time is up; P, P1 and P0 write FALSE in every scan they do \
not pulse. A later association therefore switches off what an earlier one switched on, e.g. an \
N action on S1 and S2 (S2 declared first) is off in the scan S2 hands over to S1. IEC ORs the \
associations of one qualifier. Use one association per action, or S and R.";
    "SFC0905" Warning "R does not stop an action under MatIEC"
        "MatIEC's R only clears the stored flag of S, SD, DS and SL; an N, L, D or P association of \
the same action on an active step keeps running it. IEC's ACTION_CONTROL lets R override every \
qualifier (`Q := NOT R AND (…)`). Switch the continuous association off by leaving its step.";
    "SFC0906" Warning "timed association behaves differently under MatIEC"
        "MatIEC starts SD, DS and SL on the activation edge of their step, which an initial step \
does not have, and counts them down from the duration: SD or DS with T#0s never acts, SL with \
T#0s stays stored until R. L and D compare the step's own elapsed time, so a step that loops to \
itself restarts them. IEC times these qualifiers in the action's ACTION_CONTROL block.";
    "SFC0907" Warning "time comparison changes in another scan under MatIEC"
        "MatIEC converts TIME literals with x86-64 `long double` arithmetic and truncates to whole \
nanoseconds, so `T#4ms` is 3.999999 ms and `S.T > T#4ms` already holds at 4 ms; and a step time \
that reaches a whole second exactly is kept as {0 s, 1 000 000 000 ns}, which compares below \
`T#1s`, so `S.T >= T#1s` holds one scan later. Compare with `>=` / `<` against a literal a \
nanosecond-exact value (`T#4ms` → `>= T#5ms`), or avoid whole seconds.";
    "SFC0908" Warning "P1/P0 on a BOOL variable under MatIEC"
        "MatIEC treats P1 and P0 as pulses that write the variable used as the action: TRUE for one \
scan on the activation (P1) or deactivation (P0) of the step. IEC runs P1/P0 with Q FALSE, so a \
BOOL variable used as the action stays FALSE. Use an ACTION that sets the variable.";

    "SFC0911" Warning "PRIORITY ignored under CODESYS"
        "CODESYS, TwinCAT and e!COCKPIT have no transition priorities: of the alternatives leaving \
a step, the first TRUE one from the left (declared first) fires (CODESYS's help, \"Processing \
order in SFC\"). IEC fires the one with the smallest PRIORITY. Order the alternatives as they \
should be tested, or make their conditions exclude each other.";
    "SFC0912" Warning "transition tested in the first call under CODESYS"
        "IEC tests no transition in scan 0: the initial steps' actions run once first. CODESYS \
processes the first call like any other (\"In the first cycle after calling a POU in SFC, the \
initial step is automatically activated and the step action is executed\", then the transitions \
are tested), so an initial step whose transition is already TRUE is active for one call only. \
Guard the transition with a step time (`Init.T >= T#…`) or a condition that starts FALSE.";
    "SFC0913" Warning "IEC action used at two levels of a chart (CODESYS refuses it)"
        "The action is associated in a POU's chart and in the chart of one of its actions written \
in SFC. CODESYS reports an error for the same IEC action used at different levels of a chart \
(\"Processing order in SFC\": unpredictable results); sfc runs it in each chart, with a control \
block per chart. Use a separate action at each level.";
    "SFC0921" Warning "transition tested in the first call on Logix"
        "A Logix 5000 controller executes the initial step in the first call of the routine and \
then tests its transitions in the same call; IEC 61131-3 tests no transition in scan 0. The \
initial step may be active for one call only (docs/sim.md, \"The `logix` profile\").";
    "SFC0922" Warning "P executes on activation and on deactivation on Logix"
        "Logix's P qualifier executes the action once when its step is activated and once when it \
is deactivated (Logix Designer help, \"Assign a qualifier to an action\"); IEC's P executes it in \
the scan its step is entered and once more, with Q FALSE, in the next scan. Use P1 for once on \
activation, P0 for once on deactivation.";
    "SFC0923" Warning "no final run of a stopping action on Logix"
        "IEC 61131-3 runs an action once more, with Q FALSE, after it stops (its final run), which \
charts use to switch off what the action switched on. A Logix controller set to \"Don't scan\" \
(Studio 5000's default \"Last Scan of Active Steps\") executes only P and P0 actions in a step's \
last scan, and an action stopped by its time does not execute again either. Clear in a P0 action, \
or set the controller (and `sfc.logix.lastscan`) to \"Programmatic reset\".";

    "SFC1001" Error "error in the property file"
        "The property file (`<chart>.props.toml`) of `sfc prove` is not valid: TOML syntax, an \
unknown key, a name the POU does not declare, or an ST condition that is not BOOL. The message \
points at the line and column.\n\n    [[property]]\n    name = \"never both directions\"\n    \
always = \"NOT (MotorFwd AND MotorRev)\"";
    "SFC1002" Error "requirement violated"
        "`sfc prove` found a run of the chart, allowed by the `[assume]`d inputs, in which the \
property fails. The shortest such run is written as a scenario file \
(`<chart>.<property>.witness.toml`) and was replayed in the simulator; `sfc test` on it shows \
the failing expectation, which is the property itself.";
    "SFC1003" Warning "requirement not decided"
        "`sfc prove` ran out of its budget (`--budget`) before proving or refuting the property; \
the message says how far it got (e.g. no violation within 2,000 scans). Give it more time, \
narrow the inputs with `[assume] ranges`, or split the property.";
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
