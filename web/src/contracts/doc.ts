// GENERATED from crates/sfc-doc/src/lib.rs by ts-rs: do not edit.
// `UPDATE_CONTRACTS=1 cargo test -p sfc-doc contracts` writes it anew; the test fails when it is stale.

export type EditorDoc = { 
/**
 * The POU's name.
 */
pou: string, pouKind: PouKind, 
/**
 * The target device (`sfc.target` before the POU).
 */
target: ChartTarget, description?: string, 
/**
 * The POU's declarations (its `VAR … END_VAR` blocks) verbatim, as written between the POU
 * header line and its first SFC element.
 */
declarations: string, 
/**
 * The POU's body when it is not a chart (ST statements or IL instructions, dedented): a
 * FUNCTION_BLOCK or PROGRAM written in ST or IL that holds actions written in SFC (added to
 * the contract by sfc-doc). Such a document has no blocks; its actions' charts are edited.
 */
body?: string, bodyLanguage?: Language, 
/**
 * Named actions with their bodies, in declaration order.
 */
actions: Array<ActionDef>, elements: Array<Element>, connections: Array<Connection>, 
/**
 * Attribute pragmas before the POU that the editor does not edit (added to the contract by
 * sfc-doc: kept so that saving does not drop them).
 */
attributes?: Array<OtherAttribute>, 
/**
 * The comments after the chart's last element, before `END_PROGRAM` / `END_FUNCTION_BLOCK`
 * (each whole, delimiters included, in order).
 */
trailingComments?: Array<string>, };

export type OtherAttribute = { name: string, value?: string, };

export type PouKind = "program" | "functionBlock";

export type ChartTarget = "blank" | "atmt" | "eatmt";

export type Language = "ST" | "IL";

export type ActionDef = { name: string, language?: Language, 
/**
 * The statements (ST) or instructions (IL), without the `ACTION`/`END_ACTION` lines.
 */
body: string, description?: string, 
/**
 * Attribute pragmas the editor does not edit (see [`OtherAttribute`]).
 */
attributes?: Array<OtherAttribute>, 
/**
 * The comments written before the action in the text (each whole, delimiters included).
 */
comments?: Array<string>, 
/**
 * An action written in SFC (CODESYS's SFC action): its chart as a document of its own
 * (`pou` the POU's name, no declarations or actions of its own; its steps name the POU's
 * actions). When present, saving writes the action's body from it (`body` is the text it
 * wrote when opened); the attributes of the chart (its layout) travel in the chart.
 */
chart?: EditorDoc, };

export type ElementKind = "step" | "transition" | "selectionDivergence" | "selectionConvergence" | "simultaneousDivergence" | "simultaneousConvergence" | "jump" | "text" | "actionBlock";

export type Element = { id: string, kind: ElementKind, 
/**
 * Top-left corner and size, in canvas units (1 unit = 1 CSS pixel at zoom 1).
 */
x: number, y: number, w: number, h: number, 
/**
 * Step or transition name (empty for an unnamed transition and for other blocks).
 */
name?: string, 
/**
 * Steps: the initial step.
 */
initial?: boolean, 
/**
 * `sfc.tag`: state number of a step, condition index of a transition.
 */
tag?: number, 
/**
 * `sfc.timeout` of a step, an IEC duration literal (`T#8.1s`).
 */
timeout?: string, 
/**
 * Shown as the tooltip.
 */
description?: string, 
/**
 * CSS colours (`#rrggbb`).
 */
background?: string, foreground?: string, lineWidth?: number, hideLabel?: boolean, 
/**
 * Steps: `sfc.final`, a step intentionally without a way out (added to the contract by
 * sfc-doc so files using it keep it when saved from the editor).
 */
final?: boolean, 
/**
 * Divergences and convergences: the number of branch pins (≥ 2).
 */
pins?: number, 
/**
 * Jumps: the name of the target step.
 */
target?: string, 
/**
 * Transitions: the condition, an ST expression (language ST) or IL instructions (IL).
 */
condition?: string, conditionLanguage?: Language, 
/**
 * Transitions: explicit `PRIORITY`.
 */
priority?: number, 
/**
 * Text labels: the text, its alignment (`left`, `center`, `right`) and CSS font.
 */
text?: string, align?: "left" | "center" | "right", font?: string, 
/**
 * Action blocks: the id of the step they belong to, and the associations.
 */
step?: string, associations?: Array<Association>, 
/**
 * Steps: CODESYS's step actions as written (`ENTRY_ACTION := Init_entry`,
 * `STEP_ACTION := Motor.ACT_Run`, `EXIT_ACTION := …`), in order.
 */
stepActions?: Array<string>, 
/**
 * Steps and transitions: attribute pragmas the editor does not edit (see
 * [`OtherAttribute`]).
 */
attributes?: Array<OtherAttribute>, 
/**
 * Steps and transitions: the comments written before the element in the text (each whole,
 * delimiters included, in order); on other blocks they travel in the layout attribute.
 */
comments?: Array<string>, };

export type Association = { 
/**
 * `N`, `R`, `S`, `L`, `D`, `P`, `P0`, `P1`, `SD`, `DS`, `SL`.
 */
qualifier: string, 
/**
 * A duration literal or a TIME variable, for the timed qualifiers.
 */
duration?: string, 
/**
 * The action name (or a BOOL variable).
 */
action: string, indicator?: string, };

export type Connection = { id: string, source: string, sourcePin: number, target: string, targetPin: number, 
/**
 * The whole orthogonal polyline, both ends included, absolute; empty: the editor routes it.
 */
waypoints?: Array<Point>, color?: string, lineWidth?: number, };

export type Point = { x: number, y: number, };
