// The SVG geometry API diagram-js needs and jsdom lacks: matrices, points, transform lists,
// getCTM/getBBox. Import this first in every canvas test.

class Matrix {
  constructor(
    public a = 1,
    public b = 0,
    public c = 0,
    public d = 1,
    public e = 0,
    public f = 0,
  ) {}
  multiply(m: Matrix): Matrix {
    return new Matrix(
      this.a * m.a + this.c * m.b,
      this.b * m.a + this.d * m.b,
      this.a * m.c + this.c * m.d,
      this.b * m.c + this.d * m.d,
      this.a * m.e + this.c * m.f + this.e,
      this.b * m.e + this.d * m.f + this.f,
    );
  }
  inverse(): Matrix {
    const det = this.a * this.d - this.b * this.c;
    return new Matrix(
      this.d / det,
      -this.b / det,
      -this.c / det,
      this.a / det,
      (this.c * this.f - this.d * this.e) / det,
      (this.b * this.e - this.a * this.f) / det,
    );
  }
  translate(x: number, y: number): Matrix {
    return this.multiply(new Matrix(1, 0, 0, 1, x, y));
  }
  scale(s: number): Matrix {
    return this.multiply(new Matrix(s, 0, 0, s, 0, 0));
  }
  scaleNonUniform(sx: number, sy: number): Matrix {
    return this.multiply(new Matrix(sx, 0, 0, sy, 0, 0));
  }
  rotate(deg: number): Matrix {
    const r = (deg * Math.PI) / 180;
    return this.multiply(new Matrix(Math.cos(r), Math.sin(r), -Math.sin(r), Math.cos(r), 0, 0));
  }
}

class Point {
  x = 0;
  y = 0;
  matrixTransform(m: Matrix): Point {
    const p = new Point();
    p.x = m.a * this.x + m.c * this.y + m.e;
    p.y = m.b * this.x + m.d * this.y + m.f;
    return p;
  }
}

class Transform {
  type = 1;
  angle = 0;
  matrix = new Matrix();
  setMatrix(m: Matrix) {
    this.matrix = new Matrix(m.a, m.b, m.c, m.d, m.e, m.f);
  }
  setTranslate(x: number, y: number) {
    this.matrix = new Matrix(1, 0, 0, 1, x, y);
  }
  setScale(sx: number, sy: number) {
    this.matrix = new Matrix(sx, 0, 0, sy, 0, 0);
  }
  setRotate(angle: number, cx: number, cy: number) {
    this.angle = angle;
    this.matrix = new Matrix().translate(cx, cy).rotate(angle).translate(-cx, -cy);
  }
}

class TransformList {
  items: Transform[] = [];
  constructor(private owner: Element) {}
  get numberOfItems() {
    return this.items.length;
  }
  clear() {
    this.items = [];
    this.sync();
  }
  appendItem(t: Transform) {
    this.items.push(t);
    this.sync();
    return t;
  }
  initialize(t: Transform) {
    this.items = [t];
    this.sync();
    return t;
  }
  getItem(i: number) {
    return this.items[i];
  }
  createSVGTransformFromMatrix(m: Matrix) {
    const t = new Transform();
    t.setMatrix(m);
    return t;
  }
  /** Read back from the attribute: diagram-js also writes the viewport's matrix directly. */
  consolidate(): Transform | null {
    if (!this.owner.getAttribute('transform')) return null;
    const t = new Transform();
    t.setMatrix(attributeMatrix(this.owner));
    return t;
  }
  /** Mirrors the list into the attribute, as a browser does. */
  private sync() {
    const m = this.items.reduce((acc, x) => acc.multiply(x.matrix), new Matrix());
    if (this.items.length === 0) this.owner.removeAttribute('transform');
    else this.owner.setAttribute('transform', `matrix(${m.a},${m.b},${m.c},${m.d},${m.e},${m.f})`);
  }
}

const g = globalThis as unknown as Record<string, unknown>;
g.SVGMatrix = Matrix;
g.SVGPoint = Point;
g.SVGTransform = Transform;

/** The element's own transform (diagram-js writes the viewport's as a `matrix(…)` attribute). */
function attributeMatrix(e: Element): Matrix {
  const m = /matrix\(([^)]*)\)/.exec(e.getAttribute('transform') ?? '');
  if (!m) return new Matrix();
  const [a, b, c, d, ee, f] = m[1].split(/[ ,]+/).map(Number);
  return new Matrix(a, b, c, d, ee, f);
}

const lists = new WeakMap<Element, TransformList>();
const proto = (g.SVGElement as { prototype: object }).prototype;
Object.defineProperty(proto, 'transform', {
  configurable: true,
  get(this: Element) {
    let l = lists.get(this);
    if (!l) lists.set(this, (l = new TransformList(this)));
    return { baseVal: l };
  },
});
Object.assign(proto, {
  getBBox() {
    return { x: 0, y: 0, width: 0, height: 0 };
  },
  getCTM(this: Element) {
    return attributeMatrix(this);
  },
  getScreenCTM(this: Element) {
    return attributeMatrix(this);
  },
  getTotalLength() {
    return 0;
  },
});
const svgProto = (g.SVGSVGElement as { prototype: object }).prototype;
Object.assign(svgProto, {
  createSVGMatrix: () => new Matrix(),
  createSVGPoint: () => new Point(),
  createSVGTransform: () => new Transform(),
  createSVGTransformFromMatrix: (m: Matrix) => {
    const t = new Transform();
    t.setMatrix(m);
    return t;
  },
});

if (!(g.CSS as { escape?: unknown } | undefined)?.escape) {
  g.CSS = { escape: (s: string) => String(s).replace(/[^a-zA-Z0-9_-]/g, (c) => `\\${c}`) };
}

// jsdom does no layout: nothing is ever under the pointer.
const docProto = (g.Document as { prototype: Record<string, unknown> }).prototype;
if (!docProto.elementFromPoint) docProto.elementFromPoint = () => null;
