// The editor's document: its types are generated from crates/sfc-doc/src/lib.rs by ts-rs
// (./contracts/doc.ts, kept current by sfc-doc's `contracts_are_current` test; read the Rust
// module doc for pins and the valid connections). JSON field names are camelCase. This file
// adds what the canvas needs on top: pin counts and the valid connection pairs.
export type {
  ActionDef,
  Association,
  ChartTarget,
  Connection,
  EditorDoc,
  Element,
  ElementKind,
  Language,
  OtherAttribute,
  Point,
  PouKind,
} from './contracts/doc';
import type { Element, ElementKind } from './contracts/doc';

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
