// Creates canvas elements whose id is the document id: a block keeps its Element id, a new
// block gets a fresh `bN`, a new wire a fresh `cN`; every element gets its document order.
import ElementFactory from 'diagram-js/lib/core/ElementFactory.js';
import { defaultSize } from '../geometry';
import { freshId, OrderCounter, type Service } from '../model';

export class SfcElementFactory extends ElementFactory {
  static $inject = ['elementRegistry', 'sfcOrder'];

  /** Ids handed out but maybe not yet on the canvas (a paste creates several at once). */
  private issued = new Set<string>();

  constructor(
    private elementRegistry: Service,
    private order: OrderCounter,
  ) {
    super();
  }

  create(type: Service, attrs?: Service): Service {
    const a = { ...(attrs ?? {}) };
    if ((type === 'shape' || type === 'connection') && a.businessObject) {
      const bo = a.businessObject;
      const prefix = type === 'shape' ? 'b' : 'c';
      let id: string | undefined = a.id ?? bo.id;
      if (!id || this.elementRegistry.get(id) || this.issued.has(id)) id = freshId(this.elementRegistry, prefix, this.issued);
      this.issued.add(id);
      a.id = id;
      bo.id = id;
      if (typeof a.sfcOrder !== 'number') a.sfcOrder = this.order.take();
      if (type === 'shape') {
        const size = defaultSize(bo.kind);
        if (typeof a.width !== 'number') a.width = bo.w ?? size.w;
        if (typeof a.height !== 'number') a.height = bo.h ?? size.h;
      }
    }
    return super.create(type, a);
  }

  /** Forgets issued ids (after the canvas was cleared). */
  reset() {
    this.issued.clear();
  }
}
