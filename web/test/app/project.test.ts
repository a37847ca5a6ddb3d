import { describe, expect, it } from 'vitest';
import type { Diag, PouEntry } from '../../src/api';
import type { EditorDoc } from '../../src/doc';
import { diagnosticsOf, fileDiagnostics, problemCounts, projectTree } from '../../src/app/project';

const diag = (pou: string | undefined, code = 'SFC0301', severity: Diag['severity'] = 'error'): Diag => ({
  code,
  severity,
  message: '',
  title: '',
  file: 'p.xml',
  line: 1,
  column: 1,
  endLine: 1,
  endColumn: 1,
  element: null,
  elementIds: [],
  notes: [],
  witness: null,
  ...(pou ? { pou } : {}),
});

describe('diagnostics scoped to their chart', () => {
  const all = [diag('Intake'), diag('mixer'), diag('Scale'), diag(undefined, 'SFC0104', 'note')];
  it('gives each chart its own POU’s, case-insensitively', () => {
    expect(diagnosticsOf(all, 'Intake', ['Intake', 'Mixer'])).toEqual([all[0]]);
    expect(diagnosticsOf(all, 'Mixer', ['Intake', 'Mixer'])).toEqual([all[1]]);
  });
  it('lists those of no chart under the file', () => {
    expect(fileDiagnostics(all, ['Intake', 'Mixer'])).toEqual([all[2], all[3]]);
  });
  it('gives the only chart of a file what lies in no POU', () => {
    expect(diagnosticsOf(all, 'Intake', ['Intake'])).toEqual([all[0], all[3]]);
    expect(fileDiagnostics(all, ['Intake'])).toEqual([all[1], all[2]]);
  });
  it('counts errors and warnings per POU', () => {
    expect([...problemCounts(all)]).toEqual([
      ['intake', 1],
      ['mixer', 1],
      ['scale', 1],
    ]);
  });
});

describe('the project tree', () => {
  const pous: PouEntry[] = [
    { name: 'Line', kind: 'program', language: 'SFC', chart: true, actions: [{ name: 'Fill', sfc: true }, { name: 'Reset', sfc: false }], transitions: ['T1', 'Go'] },
    { name: 'Scale', kind: 'function', language: 'ST', chart: false, actions: [], transitions: [] },
  ];
  it('lists the file, its POUs, their actions and transitions', () => {
    const rows = projectTree('p.xml', pous, () => undefined);
    expect(rows.map((r) => [r.kind, r.label, r.openable, r.depth])).toEqual([
      ['file', 'p.xml', false, 0],
      ['pou', 'Line', true, 1],
      ['action', 'Fill', true, 2],
      ['action', 'Reset', false, 2],
      ['transition', 'T1', true, 2],
      ['transition', 'Go', true, 2],
      ['pou', 'Scale', false, 1],
    ]);
  });
  it('takes an open chart’s actions and transitions as edited', () => {
    const live = {
      pou: 'Line',
      actions: [{ name: 'Drain', chart: { pou: 'Line' } }],
      elements: [
        { id: 't1', kind: 'transition', name: '' },
        { id: 's1', kind: 'step', name: 'S' },
        { id: 't2', kind: 'transition', name: 'Stop' },
      ],
    } as unknown as EditorDoc;
    const rows = projectTree('p.xml', pous, (p) => (p === 'Line' ? live : undefined)).filter((r) => r.pou === 'Line' && r.kind !== 'pou');
    expect(rows.map((r) => [r.kind, r.label, r.id ?? null])).toEqual([
      ['action', 'Drain', null],
      ['transition', 'T1', 't1'],
      ['transition', 'Stop', 't2'],
    ]);
  });
});
