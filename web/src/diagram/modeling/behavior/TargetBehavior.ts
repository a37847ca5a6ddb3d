// The ATMT/EATMT target rules while drawing (seed 001 chapter 3 and 7.2.1): a transition's Tag
// is the number of the automaton input its condition reads, so the condition follows the Tag
// (`C<n>` for ATMT, `c<n>` for EATMT, whose inputs may be negated: `!c<n>`), and a condition
// typed as such an input sets the Tag. A new transition takes the lowest input no other
// transition reads. All within the same undoable command.
import CommandInterceptor from 'diagram-js/lib/command/CommandInterceptor.js';
import type { ChartTarget, Element } from '../../../doc';
import type { DocState } from '../../core/DocState';
import { isConnection, type Service, type SfcShape } from '../../model';

export class TargetBehavior extends CommandInterceptor {
  static $inject = ['eventBus', 'elementRegistry', 'sfcDocState'];

  constructor(eventBus: Service, elementRegistry: Service, state: DocState) {
    super(eventBus);

    this.preExecute('sfc.element.update', (event: Service) => {
      const ctx = event.context;
      const e = ctx.element;
      const target = state.fields.target;
      if (isConnection(e) || e.businessObject?.kind !== 'transition' || !isTable(target)) return;
      const p = ctx.props as Partial<Element>;
      if ('tag' in p && typeof p.tag === 'number' && !('condition' in p)) {
        p.condition = conditionFor(target, p.tag, isNegated(e.businessObject.condition));
        p.conditionLanguage = 'ST';
      } else if ('condition' in p && !('tag' in p) && typeof p.condition === 'string') {
        const n = inputOf(target, p.condition);
        if (n !== undefined && n !== e.businessObject.tag) p.tag = n;
      }
    });

    this.preExecute('shape.create', (event: Service) => {
      const shape = event.context.shape as SfcShape;
      const bo = shape.businessObject;
      const target = state.fields.target;
      if (!bo || bo.kind !== 'transition' || !isTable(target) || (shape as Service).sfcCopiedFrom) return;
      const used = new Set<number>();
      for (const s of elementRegistry.filter((x: Service) => x.businessObject?.kind === 'transition')) {
        const tag = s.businessObject.tag ?? inputOf(target, s.businessObject.condition ?? '');
        if (tag !== undefined) used.add(tag);
      }
      let n = 0;
      while (used.has(n)) n++;
      bo.tag = n;
      bo.condition = conditionFor(target, n, false);
      bo.conditionLanguage = 'ST';
    });
  }
}

function isTable(t: ChartTarget | undefined): t is 'atmt' | 'eatmt' {
  return t === 'atmt' || t === 'eatmt';
}

function isNegated(condition: string | undefined): boolean {
  return /^\s*(!|NOT\s)/i.test(condition ?? '');
}

/** The condition of a transition reading input `n`: `C<n>` (ATMT), `c<n>` or `!c<n>` (EATMT). */
export function conditionFor(target: 'atmt' | 'eatmt', n: number, negated: boolean): string {
  return target === 'atmt' ? `C${n}` : `${negated ? '!' : ''}c${n}`;
}

/** The input number a condition reads (`C5`, `c5`, `!c5`, `NOT c5`, `c0.5` = 5, `c1.2` = 18), if it is one. */
export function inputOf(target: 'atmt' | 'eatmt', condition: string): number | undefined {
  const m = /^\s*(?:!|NOT\s+)?\s*[cC](\d+)(?:\.(\d+))?\s*$/i.exec(condition);
  if (!m) return undefined;
  if (m[2] !== undefined) return target === 'eatmt' ? 16 * Number(m[1]) + Number(m[2]) : undefined;
  return Number(m[1]);
}
