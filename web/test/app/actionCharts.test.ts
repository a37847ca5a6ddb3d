import { describe, expect, it } from 'vitest';
import { actionChart, assemble, blocksNamed, isStepActionName, sfcActions, stepActionsOf, viewKey, withStepAction } from '../../src/app/actionCharts';
import type { EditorDoc } from '../../src/doc';

const chart = (pou: string, step: string): EditorDoc => ({
  pou,
  pouKind: 'functionBlock',
  target: 'blank',
  declarations: '',
  actions: [],
  elements: [{ id: `step:${step}`, kind: 'step', name: step, initial: true, x: 40, y: 40, w: 80, h: 40 }],
  connections: [],
});

const press: EditorDoc = {
  pou: 'Press',
  pouKind: 'functionBlock',
  target: 'blank',
  declarations: 'VAR\nEND_VAR',
  body: 'Cycle();',
  actions: [
    { name: 'Lower_entry', body: 'Down := TRUE;' },
    { name: 'Cycle', body: 'INITIAL_STEP Ready: END_STEP', chart: chart('Press', 'Ready') },
  ],
  elements: [],
  connections: [],
};

describe('actions written in SFC', () => {
  it('are the actions with a chart', () => {
    expect(sfcActions(press).map((a) => a.name)).toEqual(['Cycle']);
    expect(actionChart(press, 'cycle')?.elements[0].name).toBe('Ready');
    expect(actionChart(press, 'Lower_entry')).toBeUndefined();
  });
  it('have a canvas key of their own in the tab', () => {
    expect(viewKey('tab1', null)).toBe('tab1');
    expect(viewKey('tab1', 'Cycle')).toBe('tab1::Cycle');
  });
  it('are sent as their canvases hold them, the other actions untouched', () => {
    const edited = chart('Press', 'Waiting');
    const doc = assemble({ ...press, pou: 'Press2' }, new Map([['CYCLE', edited]]));
    expect(doc.actions[0]).toBe(press.actions[0]);
    expect(doc.actions[1].chart?.elements[0].name).toBe('Waiting');
    expect(doc.actions[1].chart?.pou).toBe('Press2');
    expect(doc.actions[1].body).toBe(press.actions[1].body);
    // A chart for an action not written in SFC is not attached to it.
    expect(assemble(press, new Map([['Lower_entry', edited]])).actions[0].chart).toBeUndefined();
    expect(assemble(press, new Map())).toBe(press);
  });
  it('locate diagnostics on their blocks by name', () => {
    const c = chart('Press', 'Ready');
    expect(blocksNamed(c, 'READY')).toEqual(['step:Ready']);
    expect(blocksNamed(c, 'Lower')).toEqual([]);
    expect(blocksNamed(c, null)).toEqual([]);
  });
});

describe('step actions', () => {
  it('are read by kind', () => {
    expect(stepActionsOf({ stepActions: ['ENTRY_ACTION := Init_entry', 'exit_action := Motor.ACT_Stop;'] })).toEqual({ entry: 'Init_entry', exit: 'Motor.ACT_Stop' });
    expect(stepActionsOf({})).toEqual({});
  });
  it('are set, replaced and removed in the order entry, step, exit', () => {
    const step = { stepActions: ['EXIT_ACTION := Done'] };
    const set = withStepAction(step, 'entry', ' Start ');
    expect(set).toEqual(['ENTRY_ACTION := Start', 'EXIT_ACTION := Done']);
    expect(withStepAction({ stepActions: set }, 'main', 'Motor.Run')).toEqual(['ENTRY_ACTION := Start', 'STEP_ACTION := Motor.Run', 'EXIT_ACTION := Done']);
    expect(withStepAction({ stepActions: set }, 'entry', 'Again')).toEqual(['ENTRY_ACTION := Again', 'EXIT_ACTION := Done']);
    expect(withStepAction({ stepActions: set }, 'exit', '')).toEqual(['ENTRY_ACTION := Start']);
  });
  it('name an action or an action of an instance', () => {
    for (const ok of ['', 'Init_entry', 'Motor.ACT_Run', 'Move__Pos3']) expect(isStepActionName(ok)).toBe(true);
    for (const bad of ['1x', 'a b', 'a.b.c', 'x := 1', 'A()']) expect(isStepActionName(bad)).toBe(false);
  });
});
