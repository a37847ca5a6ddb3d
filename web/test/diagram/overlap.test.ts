import { describe, expect, it } from 'vitest';
import { movesOntoAnother, overlap } from '../../src/diagram/rules/overlap';

const step = (id: string, x: number, y: number) => ({ id, x, y, width: 80, height: 40, kind: 'step' as const });

describe('a move onto another block', () => {
  const all = [step('A', 0, 0), step('B', 200, 0), { id: 'L', x: 100, y: 100, width: 60, height: 20, kind: 'text' as const }];
  it('is refused when the moved block would overlap another', () => {
    expect(movesOntoAnother([all[0]], { x: 170, y: 10 }, all)).toBe(true);
  });
  it('is allowed beside it, edge to edge, and over a text label', () => {
    expect(movesOntoAnother([all[0]], { x: 120, y: 0 }, all)).toBe(false);
    expect(movesOntoAnother([all[0]], { x: 90, y: 90 }, all)).toBe(false);
  });
  it('lets blocks moved together overlap where they were', () => {
    expect(movesOntoAnother([all[0], all[1]], { x: 100, y: 0 }, all)).toBe(false);
  });
  it('moves an action block with its step', () => {
    const ab = { id: 'AB', x: 100, y: 0, width: 60, height: 20, kind: 'actionBlock' as const, step: 'A' };
    expect(movesOntoAnother([all[0]], { x: 20, y: 0 }, [...all, ab])).toBe(false);
    expect(movesOntoAnother([all[0]], { x: 60, y: 0 }, [...all, ab])).toBe(true);
  });
  it('tells overlapping from touching', () => {
    expect(overlap(step('x', 0, 0), step('y', 80, 0))).toBe(false);
    expect(overlap(step('x', 0, 0), step('y', 79, 39))).toBe(true);
  });
});
