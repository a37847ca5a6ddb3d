// What the editor offers a chart for: the POU's `sfc.target` (Blank, ATMT, EATMT) and, for
// "IEC 61131-3" charts, a Blank chart that carries the build output it is meant for in the
// POU-level editor attribute `sfc.build` (st, stl, plcopen, svg, text).
import type { BuildTarget } from '../api';
import type { ChartTarget, EditorDoc, OtherAttribute } from '../doc';

/** The four choices of the New dialog and the chart's Properties. */
export type ChartKind = ChartTarget | 'iec';

export const CHART_KINDS: ChartKind[] = ['blank', 'atmt', 'eatmt', 'iec'];

/** The attribute that makes a Blank chart an IEC one and names its build output. */
export const BUILD_ATTRIBUTE = 'sfc.build';

/** The outputs `sfc.build` may name; the first is a new IEC chart's. */
export const IEC_BUILDS: BuildTarget[] = ['st', 'stl', 'plcopen', 'text', 'svg'];

const isBuildAttribute = (a: OtherAttribute) => a.name.trim().toLowerCase() === BUILD_ATTRIBUTE;

/** The chart's kind: IEC for a Blank chart with `sfc.build`, else its `sfc.target`. */
export function chartKind(doc: Pick<EditorDoc, 'target' | 'attributes'>): ChartKind {
  return doc.target === 'blank' && (doc.attributes ?? []).some(isBuildAttribute) ? 'iec' : doc.target;
}

/** The build output an IEC chart names (the last `sfc.build`, as the checker reads it); a value
 *  it does not know (the checker reports it) falls back to the default. */
export function chartBuild(doc: Pick<EditorDoc, 'attributes'>): BuildTarget {
  const a = [...(doc.attributes ?? [])].reverse().find(isBuildAttribute);
  const v = (a?.value ?? '').trim().toLowerCase();
  return IEC_BUILDS.find((b) => b === v) ?? IEC_BUILDS[0];
}

/** The POU attributes with `sfc.build` set to `build` (null: removed); others keep their order. */
export function withBuild(attributes: OtherAttribute[] | undefined, build: BuildTarget | null): OtherAttribute[] {
  const list = attributes ?? [];
  const at = list.findIndex(isBuildAttribute);
  const others = list.filter((a) => !isBuildAttribute(a));
  if (build === null) return others;
  const entry = { name: BUILD_ATTRIBUTE, value: build };
  return at < 0 ? [...others, entry] : [...others.slice(0, at), entry, ...others.slice(at)];
}

/** The document fields that make a chart of `kind` (one `updateDoc`): IEC keeps the build output
 *  it names, or gets the default; the other kinds lose `sfc.build`. */
export function kindFields(doc: Pick<EditorDoc, 'target' | 'attributes'>, kind: ChartKind): Pick<EditorDoc, 'target' | 'attributes'> {
  if (kind === 'iec') return { target: 'blank', attributes: withBuild(doc.attributes, chartKind(doc) === 'iec' ? chartBuild(doc) : IEC_BUILDS[0]) };
  const had = (doc.attributes ?? []).some(isBuildAttribute);
  return had ? { target: kind, attributes: withBuild(doc.attributes, null) } : { target: kind };
}
