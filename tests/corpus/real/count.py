#!/usr/bin/env python3
"""Counts the steps, transitions and actions of every SFC POU of PLCopen XML files, and the
actions of every other POU, straight from the XML and independently of sfc's importer (the
corpus test compares the two).

    python3 count.py FILE...   ->  one JSON object per file:
                                   {"POU": [steps, transitions, actions, step actions]}

Rules (PLCopen TC6, any version, any producing tool):
- a POU is any `pou` element, wherever the file keeps it (`types/pous`, or a CODESYS resource's
  `addData`), whose `body` holds an `SFC`, or which has `actions` (CODESYS's actions of a
  function block whose body is ST, IL, FBD or LD: 0 steps, 0 transitions);
- steps are its `step` elements, transitions its `transition` elements;
- actions are the POU's `actions/action` elements, plus one per inline action of an action
  block, plus one when a function block instance is wired into a condition (its calls go to an
  action, as Beremiz compiles such charts);
- an action whose `body` holds an `SFC` (CODESYS's SFC action) is a chart of its own, counted
  under `POU.ACTION`: its steps and transitions (its associations name the POU's actions, so
  it has none of its own);
- step actions are CODESYS's entry, main and exit actions of the chart's steps: the properties
  with their GUIDs (and a value) in a step's `addData` `sfc/element` data.
"""
import json
import sys
import xml.etree.ElementTree as ET


def local(tag):
    return tag.rsplit('}', 1)[-1]


def kids(node, name):
    return [c for c in node if local(c.tag) == name]


STEP_ACTION_GUIDS = {
    'a6b08bd8-b696-47e3-9cbf-7408b61c9ff8',  # entry
    '700a583f-b4d4-43e4-8c14-629c7cd3bec8',  # main
    'a2621e18-7de3-4ea6-ae6d-89e9e0b7befd',  # exit
}


def step_actions(body):
    n = 0
    for step in kids(body, 'step'):
        for add in kids(step, 'addData'):
            for data in kids(add, 'data'):
                if not (data.get('name') or '').endswith('/sfc/element'):
                    continue
                for a in data.iter():
                    if local(a.tag) == 'attribute' and (a.get('guid') or '').lower() in STEP_ACTION_GUIDS \
                            and (a.text or '').strip():
                        n += 1
    return n


def count(path):
    out = {}
    root = ET.parse(path).getroot()
    for pou in root.iter():
        if local(pou.tag) != 'pou':
            continue
        for a in [a for acts in kids(pou, 'actions') for a in kids(acts, 'action')]:
            charts = [s for b in kids(a, 'body') for s in kids(b, 'SFC')]
            if charts:
                key = pou.get('name').strip().upper() + '.' + a.get('name').strip().upper()
                out[key] = [len(kids(charts[0], 'step')), len(kids(charts[0], 'transition')), 0,
                            step_actions(charts[0])]
        sfc = [s for b in kids(pou, 'body') for s in kids(b, 'SFC')]
        if not sfc:
            actions = sum(len(kids(a, 'action')) for a in kids(pou, 'actions'))
            if actions:
                out[pou.get('name').strip().upper()] = [0, 0, actions, 0]
            continue
        body = sfc[0]
        steps = len(kids(body, 'step'))
        transitions = len(kids(body, 'transition'))
        actions = sum(len(kids(a, 'action')) for a in kids(pou, 'actions'))
        actions += sum(1 for ab in kids(body, 'actionBlock') for a in kids(ab, 'action') if kids(a, 'inline'))
        if any(local(e.tag) == 'block' and (e.get('instanceName') or '').strip() for e in body):
            actions += 1
        out[pou.get('name').strip().upper()] = [steps, transitions, actions, step_actions(body)]
    return out


if __name__ == '__main__':
    for p in sys.argv[1:]:
        print(json.dumps(count(p)))
