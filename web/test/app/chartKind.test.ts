// The IEC 61131-3 chart kind: a Blank chart with `sfc.build`, and how switching kinds edits it.
import { describe, expect, it } from 'vitest';
import { chartBuild, chartKind, kindFields, withBuild } from '../../src/app/chartKind';

describe('chart kinds', () => {
  it('reads IEC from a Blank chart with sfc.build, in any case, the last one winning', () => {
    expect(chartKind({ target: 'blank' })).toBe('blank');
    expect(chartKind({ target: 'blank', attributes: [{ name: 'SFC.Build', value: 'stl' }] })).toBe('iec');
    expect(chartKind({ target: 'atmt', attributes: [{ name: 'sfc.build', value: 'st' }] })).toBe('atmt');
    const attributes = [
      { name: 'sfc.build', value: 'svg' },
      { name: 'sfc.build', value: ' PLCopen ' },
    ];
    expect(chartBuild({ attributes })).toBe('plcopen');
    expect(chartBuild({ attributes: [{ name: 'sfc.build', value: 'exe' }] })).toBe('st');
  });
  it('sets sfc.build in place and keeps the other attributes', () => {
    const other = { name: 'vendor.x', value: '1' };
    expect(withBuild(undefined, 'st')).toEqual([{ name: 'sfc.build', value: 'st' }]);
    expect(withBuild([{ name: 'sfc.build', value: 'st' }, other], 'svg')).toEqual([{ name: 'sfc.build', value: 'svg' }, other]);
    expect(withBuild([other, { name: 'sfc.build', value: 'st' }], null)).toEqual([other]);
  });
  it('switches IEC and Blank by adding and removing sfc.build, keeping a chosen output', () => {
    expect(kindFields({ target: 'blank' }, 'iec')).toEqual({ target: 'blank', attributes: [{ name: 'sfc.build', value: 'st' }] });
    const iec = { target: 'blank' as const, attributes: [{ name: 'sfc.build', value: 'text' }] };
    expect(kindFields(iec, 'iec')).toEqual(iec);
    expect(kindFields(iec, 'blank')).toEqual({ target: 'blank', attributes: [] });
    expect(kindFields(iec, 'eatmt')).toEqual({ target: 'eatmt', attributes: [] });
    expect(kindFields({ target: 'blank' }, 'atmt')).toEqual({ target: 'atmt' });
  });
});
