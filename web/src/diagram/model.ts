// The canvas's view of the document: diagram-js shapes whose businessObject is a copy of a
// doc Element, and connections whose businessObject is the doc Connection.
import type { Connection, Element, Point } from '../doc';

/** A block on the canvas. */
export interface SfcShape {
  id: string;
  x: number;
  y: number;
  width: number;
  height: number;
  businessObject: Element;
  incoming: SfcConnection[];
  outgoing: SfcConnection[];
  parent?: unknown;
  /** Position in the document's element list (kept across delete/undo). */
  sfcOrder: number;
  waypoints?: undefined;
}

/** A wire on the canvas. */
export interface SfcConnection {
  id: string;
  waypoints: Point[];
  source: SfcShape;
  target: SfcShape;
  businessObject: Connection;
  sfcOrder: number;
  parent?: unknown;
}

export type SfcElement = SfcShape | SfcConnection;

/** diagram-js services are used through their JS API; their d.ts types are too generic here. */
// eslint-disable-next-line @typescript-eslint/no-explicit-any
export type Service = any;

export function isConnection(e: unknown): e is SfcConnection {
  return !!e && Array.isArray((e as SfcConnection).waypoints);
}

export function isShape(e: unknown): e is SfcShape {
  return !!e && !isConnection(e) && !!(e as SfcShape).businessObject && !!(e as SfcShape).parent;
}

/** All blocks in the registry, in document order. */
export function shapesOf(elementRegistry: Service): SfcShape[] {
  const out: SfcShape[] = elementRegistry.filter((e: unknown) => isShape(e));
  return out.sort((a, b) => a.sfcOrder - b.sfcOrder);
}

/** All wires in the registry, in document order. */
export function connectionsOf(elementRegistry: Service): SfcConnection[] {
  const out: SfcConnection[] = elementRegistry.filter((e: unknown) => isConnection(e));
  return out.sort((a, b) => a.sfcOrder - b.sfcOrder);
}

/** Document order for new elements: after everything loaded or created so far. */
export class OrderCounter {
  private next = 0;
  take(): number {
    return this.next++;
  }
  reset(n: number) {
    this.next = n;
  }
}

/** An id not used by any element or connection on the canvas (`b1`, `b2`, … / `c1`, …). */
export function freshId(elementRegistry: Service, prefix: string, reserved: Set<string> = new Set()): string {
  for (let i = 1; ; i++) {
    const id = `${prefix}${i}`;
    if (!elementRegistry.get(id) && !reserved.has(id)) return id;
  }
}

/** Step and transition names share one namespace per POU (case-insensitive, semantics.md). */
export function usedNames(elementRegistry: Service): Set<string> {
  const names = new Set<string>();
  for (const s of shapesOf(elementRegistry)) {
    const n = s.businessObject.name;
    if (n) names.add(n.toUpperCase());
  }
  return names;
}

/** The first `PREFIXn` (n = 1, 2, …) not in `used` (upper-case names); adds it to `used`. */
export function freshName(prefix: string, used: Set<string>): string {
  for (let i = 1; ; i++) {
    const n = `${prefix}${i}`;
    if (!used.has(n.toUpperCase())) {
      used.add(n.toUpperCase());
      return n;
    }
  }
}

/** A deep copy of plain JSON data (elements, connections, associations). */
export function clone<T>(v: T): T {
  return v === undefined ? v : (JSON.parse(JSON.stringify(v)) as T);
}
