// The canvas's router, on the same cases as sfc-doc's route.rs unit tests: straight when
// aligned and free, round a block in the way without running back up, a Z between offset pins.
import { describe, expect, it } from 'vitest';
import { hits, route } from '../../src/diagram/layout/router';

const p = (x: number, y: number) => ({ x, y });

describe('router', () => {
  it('is straight when the pins are aligned and nothing is in the way', () => {
    expect(route(p(100, 50), p(100, 200), [])).toEqual([p(100, 50), p(100, 200)]);
  });
  it('goes round a block in the way, never back up', () => {
    const block = { x: 60, y: 100, width: 80, height: 40 };
    const r = route(p(100, 50), p(100, 200), [block]);
    expect(hits(r, [block])).toBe(0);
    for (let i = 1; i < r.length; i++) expect(r[i].y).toBeGreaterThanOrEqual(r[i - 1].y);
  });
  it('draws a Z between offset pins', () => {
    expect(route(p(100, 50), p(200, 150), [])).toEqual([p(100, 50), p(100, 100), p(200, 100), p(200, 150)]);
  });
  it('follows a dragged lane when it is free', () => {
    const r = route(p(100, 50), p(100, 200), [{ x: 60, y: 100, width: 80, height: 40 }], 300);
    expect(r.some((q) => q.x === 300)).toBe(true);
  });
});
