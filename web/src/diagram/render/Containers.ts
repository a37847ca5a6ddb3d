// diagram-js's GraphicsFactory with the per-element DOM work of opening a chart made cheaper:
// the container of a block or wire (`djs-group` › `djs-element` › `djs-visual`) is cloned from a
// template instead of built node by node with class lists, and a block's position is written as
// the same `matrix(1 0 0 1 x y)` attribute diagram-js's translate leaves, without going through
// an SVGTransform. The nodes, classes and attributes are those diagram-js makes (but for the
// inline `display: block` of a shown element), so everything
// that reads them (selection, move previews, the SVG export) is unchanged. Frames keep
// diagram-js's own path.
import GraphicsFactory from 'diagram-js/lib/core/GraphicsFactory.js';
import type { Service } from '../model';

const NS = 'http://www.w3.org/2000/svg';

type Kind = 'shape' | 'connection';

export class Containers extends (GraphicsFactory as unknown as new (eventBus: Service, elementRegistry: Service) => Service) {
  static $inject = ['eventBus', 'elementRegistry'];

  private templates = new Map<string, SVGGElement>();

  _createContainer(type: string, childrenGfx: SVGElement, parentIndex?: number, isFrame?: boolean): SVGElement {
    if (isFrame || (type !== 'shape' && type !== 'connection')) return super._createContainer(type, childrenGfx, parentIndex, isFrame);
    const outer = this.template(type).cloneNode(true) as SVGGElement;
    if (parentIndex === undefined) {
      childrenGfx.appendChild(outer);
    } else {
      const before = childrenGfx.childNodes[parentIndex] ?? childrenGfx.firstChild;
      if (before !== outer) childrenGfx.insertBefore(outer, before);
    }
    return outer.firstChild as SVGElement;
  }

  update(type: string, element: Service, gfx: SVGElement): void {
    if (!element.parent) return;
    if (type !== 'shape' && type !== 'connection') {
      super.update(type, element, gfx);
      return;
    }
    const visual = this._clear(gfx);
    if (type === 'shape') {
      this.drawShape(visual, element);
      gfx.setAttribute('transform', `matrix(1 0 0 1 ${element.x} ${element.y})`);
    } else {
      this.drawConnection(visual, element);
    }
    // A hidden element gets `display: none`; a shown one no inline style at all (diagram-js
    // writes `display: block`, the default): thousands of inline styles slow the page's style
    // computation.
    const style = (gfx as SVGGElement).style;
    if (element.hidden) style.display = 'none';
    else if (style.length > 0) {
      style.removeProperty('display');
      if (style.length === 0) gfx.removeAttribute('style');
    }
  }

  private template(type: Kind): SVGGElement {
    let t = this.templates.get(type);
    if (!t) {
      t = document.createElementNS(NS, 'g');
      t.setAttribute('class', 'djs-group');
      const gfx = document.createElementNS(NS, 'g');
      gfx.setAttribute('class', `djs-element djs-${type}`);
      const visual = document.createElementNS(NS, 'g');
      visual.setAttribute('class', 'djs-visual');
      gfx.appendChild(visual);
      t.appendChild(gfx);
      this.templates.set(type, t);
    }
    return t;
  }
}
