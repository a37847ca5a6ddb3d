#!/usr/bin/env python3
"""Counts the steps, transitions and actions of every SFC POU of PLCopen XML files, and the
actions of every other POU, straight from the XML and independently of sfc's importer (the
corpus test compares the two).

    python3 count.py FILE...   ->  one JSON object per file: {"POU": [steps, transitions, actions]}

Rules (PLCopen TC6, any version, any producing tool):
- a POU is any `pou` element, wherever the file keeps it (`types/pous`, or a CODESYS resource's
  `addData`), whose `body` holds an `SFC`, or which has `actions` (CODESYS's actions of a
  function block whose body is ST, IL, FBD or LD: 0 steps, 0 transitions);
- steps are its `step` elements, transitions its `transition` elements;
- actions are the POU's `actions/action` elements, plus one per inline action of an action
  block, plus one when a function block instance is wired into a condition (its calls go to an
  action, as Beremiz compiles such charts).
"""
import json
import sys
import xml.etree.ElementTree as ET


def local(tag):
    return tag.rsplit('}', 1)[-1]


def kids(node, name):
    return [c for c in node if local(c.tag) == name]


def count(path):
    out = {}
    root = ET.parse(path).getroot()
    for pou in root.iter():
        if local(pou.tag) != 'pou':
            continue
        sfc = [s for b in kids(pou, 'body') for s in kids(b, 'SFC')]
        if not sfc:
            actions = sum(len(kids(a, 'action')) for a in kids(pou, 'actions'))
            if actions:
                out[pou.get('name').strip().upper()] = [0, 0, actions]
            continue
        body = sfc[0]
        steps = len(kids(body, 'step'))
        transitions = len(kids(body, 'transition'))
        actions = sum(len(kids(a, 'action')) for a in kids(pou, 'actions'))
        actions += sum(1 for ab in kids(body, 'actionBlock') for a in kids(ab, 'action') if kids(a, 'inline'))
        if any(local(e.tag) == 'block' and (e.get('instanceName') or '').strip() for e in body):
            actions += 1
        out[pou.get('name').strip().upper()] = [steps, transitions, actions]
    return out


if __name__ == '__main__':
    for p in sys.argv[1:]:
        print(json.dumps(count(p)))
