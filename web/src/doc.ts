// The editor's document, mirrored from `crates/sfc-doc/src/lib.rs` (the contract: read its
// module doc for pins and the valid connections). JSON field names are camelCase.

export type PouKind = 'program' | 'functionBlock';
export type ChartTarget = 'blank' | 'atmt' | 'eatmt';
export type Language = 'ST' | 'IL';
export type ElementKind =
  | 'step'
  | 'transition'
  | 'selectionDivergence'
  | 'selectionConvergence'
  | 'simultaneousDivergence'
  | 'simultaneousConvergence'
  | 'jump'
  | 'text'
  | 'actionBlock';

/** An attribute pragma the editor does not edit (`{attribute 'name' := 'value'}`), kept as read
 *  so that saving does not drop it (PLCopen `addData`, other tools' attributes). */
export interface OtherAttribute {
  name: string;
  value?: string;
}

export interface ActionDef {
  name: string;
  language?: Language;
  body: string;
  description?: string;
  attributes?: OtherAttribute[];
  /** The comments written before the action in the text, each whole (`(* … *)`, `// …`). */
  comments?: string[];
}

export interface Association {
  qualifier: string;
  duration?: string;
  action: string;
  indicator?: string;
}

export interface Point {
  x: number;
  y: number;
}

/** One block; fields that do not apply to its kind are absent. */
export interface Element {
  id: string;
  kind: ElementKind;
  x: number;
  y: number;
  w: number;
  h: number;
  name?: string;
  initial?: boolean;
  tag?: number;
  timeout?: string;
  description?: string;
  background?: string;
  foreground?: string;
  lineWidth?: number;
  hideLabel?: boolean;
  /** Steps: `sfc.final`, a step intentionally without a way out. */
  final?: boolean;
  pins?: number;
  target?: string;
  condition?: string;
  conditionLanguage?: Language;
  priority?: number;
  text?: string;
  align?: 'left' | 'center' | 'right';
  font?: string;
  step?: string;
  associations?: Association[];
  /** Steps and transitions: attribute pragmas the editor does not edit. */
  attributes?: OtherAttribute[];
  /** The comments written before the element in the text, each whole (`(* … *)`, `// …`);
   *  they move and are deleted with the block, and a pasted copy has none. */
  comments?: string[];
}

export interface Connection {
  id: string;
  source: string;
  sourcePin: number;
  target: string;
  targetPin: number;
  waypoints?: Point[];
  color?: string;
  lineWidth?: number;
}

export interface EditorDoc {
  pou: string;
  pouKind: PouKind;
  target: ChartTarget;
  description?: string;
  declarations: string;
  actions: ActionDef[];
  elements: Element[];
  connections: Connection[];
  /** Attribute pragmas before the POU that the editor does not edit. */
  attributes?: OtherAttribute[];
  /** The comments after the chart's last element, before `END_PROGRAM`. */
  trailingComments?: string[];
}

/** Number of input and output pins of a block (see the table in sfc-doc). */
export function pinCounts(e: Pick<Element, 'kind' | 'pins'>): { inputs: number; outputs: number } {
  const n = Math.max(2, e.pins ?? 2);
  switch (e.kind) {
    case 'step':
    case 'transition':
      return { inputs: 1, outputs: 1 };
    case 'selectionDivergence':
    case 'simultaneousDivergence':
      return { inputs: 1, outputs: n };
    case 'selectionConvergence':
    case 'simultaneousConvergence':
      return { inputs: n, outputs: 1 };
    case 'jump':
      return { inputs: 1, outputs: 0 };
    default:
      return { inputs: 0, outputs: 0 };
  }
}

/** Which block kinds an output of `source` may feed (the valid pairs of sfc-doc). */
export const VALID_TARGETS: Record<ElementKind, ElementKind[]> = {
  step: ['transition', 'selectionDivergence', 'simultaneousConvergence'],
  // Beyond the plain pairs, IEC draws a selection divergence feeding a simultaneous
  // convergence (one step's branch joins a simultaneous transition) and a simultaneous
  // divergence feeding a selection convergence or a jump (a simultaneous branch re-enters a
  // step that has other predecessors); sfc-doc reads and writes all three.
  selectionDivergence: ['transition', 'simultaneousConvergence'],
  simultaneousConvergence: ['transition'],
  transition: ['step', 'simultaneousDivergence', 'selectionConvergence', 'jump'],
  simultaneousDivergence: ['step', 'selectionConvergence', 'jump'],
  selectionConvergence: ['step'],
  jump: [],
  text: [],
  actionBlock: [],
};
