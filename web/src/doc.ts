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

export interface ActionDef {
  name: string;
  language?: Language;
  body: string;
  description?: string;
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
  selectionDivergence: ['transition'],
  simultaneousConvergence: ['transition'],
  transition: ['step', 'simultaneousDivergence', 'selectionConvergence', 'jump'],
  simultaneousDivergence: ['step'],
  selectionConvergence: ['step'],
  jump: [],
  text: [],
  actionBlock: [],
};
