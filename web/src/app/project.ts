// A file of several POUs as the shell shows it (issue 36): the Error list of each chart's tab
// holds the diagnostics of its own POU (and of its actions' charts, which lie in the POU); those
// of the file outside every chart (a TYPE, a POU in ST, the CONFIGURATION) are listed under the
// file. The project tree lists the file's POUs, their actions and transitions.
import type { Diag, PouEntry } from '../api';
import type { EditorDoc } from '../doc';

const same = (a: string | null | undefined, b: string | null | undefined) => !!a && !!b && a.toLowerCase() === b.toLowerCase();

/** The diagnostics of `diags` (a whole file's, as `open` and `save` answer) that belong to the
 *  chart of POU `pou`. A diagnostic without a POU belongs to the chart only when the file holds
 *  no other (`charts`: the names of the file's charts). */
export function diagnosticsOf(diags: Diag[], pou: string, charts: string[]): Diag[] {
  return diags.filter((d) => (d.pou ? same(d.pou, pou) : charts.length === 1 && same(charts[0], pou)));
}

/** The diagnostics of a file that no chart of it holds (`charts`: the names of its charts). */
export function fileDiagnostics(diags: Diag[], charts: string[]): Diag[] {
  return diags.filter((d) => (d.pou ? !charts.some((c) => same(c, d.pou)) : charts.length !== 1));
}

export type TreeNodeKind = 'file' | 'pou' | 'action' | 'transition';

export interface TreeNode {
  kind: TreeNodeKind;
  /** What the row shows. */
  label: string;
  /** The POU the row belongs to. */
  pou: string;
  /** An action's or transition's name. */
  name?: string;
  /** A transition of an open chart: its block. */
  id?: string;
  /** A POU: `SFC`, `ST`, `IL`; an action: `SFC` when it is a chart, else empty. */
  language?: string;
  /** The row opens a chart (an SFC POU, a POU with SFC actions, an SFC action). */
  openable: boolean;
  depth: number;
}

/**
 * The rows of the project tree of a file: the file, each POU, each POU's actions (an SFC action
 * openable as its chart) and transitions. `live`: the documents of POUs open now (their actions
 * and transitions as edited), by POU name.
 */
export function projectTree(file: string, pous: PouEntry[], live: (pou: string) => EditorDoc | undefined): TreeNode[] {
  const rows: TreeNode[] = [{ kind: 'file', label: file, pou: '', openable: false, depth: 0 }];
  for (const p of pous) {
    const doc = live(p.name);
    rows.push({ kind: 'pou', label: p.name, pou: p.name, language: p.language, openable: p.chart, depth: 1 });
    const actions = doc ? doc.actions.map((a) => ({ name: a.name, sfc: !!a.chart })) : p.actions;
    for (const a of actions) {
      rows.push({ kind: 'action', label: a.name, pou: p.name, name: a.name, language: a.sfc ? 'SFC' : '', openable: a.sfc && p.chart, depth: 2 });
    }
    const transitions: { name: string; id?: string }[] = doc
      ? doc.elements.filter((e) => e.kind === 'transition').map((e, k) => ({ name: e.name || `T${k + 1}`, id: e.id }))
      : p.transitions.map((name) => ({ name }));
    for (const x of transitions) {
      rows.push({ kind: 'transition', label: x.name, pou: p.name, name: x.name, id: x.id, openable: p.chart, depth: 2 });
    }
  }
  return rows;
}

/** Counts of errors and warnings by POU (lower case), for the tree's badges. */
export function problemCounts(diags: Diag[]): Map<string, number> {
  const out = new Map<string, number>();
  for (const d of diags) {
    if (!d.pou || d.severity === 'note') continue;
    const k = d.pou.toLowerCase();
    out.set(k, (out.get(k) ?? 0) + 1);
  }
  return out;
}
