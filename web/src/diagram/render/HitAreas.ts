// The invisible hit areas diagram-js puts on every block and wire (what the mouse grabs), made
// by cloning one made by diagram-js itself: the same node and attributes, without diagram-js
// building and applying the style object per element (a sixth of opening a 500-step chart), and
// with its inline style moved to the stylesheet (diagram.css, `.djs-hit.sfc-hit`): thousands of
// inline styles slow the page's style computation. Frames, which have other hit areas, are left
// to diagram-js.
import { updateLine } from 'diagram-js/lib/util/RenderUtil.js';
import type { Service } from '../model';

export class HitAreas {
  static $inject = ['eventBus', 'interactionEvents'];

  private box?: SVGElement;
  private line?: SVGElement;

  constructor(
    eventBus: Service,
    private interactionEvents: Service,
  ) {
    // Before diagram-js's own (low priority) listener, which is skipped once this one answers.
    eventBus.on('interactionEvents.createHit', (e: Service) => this.create(e.element, e.gfx));
  }

  private create(element: Service, gfx: SVGElement): SVGElement | undefined {
    if (element.waypoints) {
      const hit = this.template('line').cloneNode(false) as SVGElement;
      updateLine(hit, element.waypoints);
      gfx.appendChild(hit);
      return hit;
    }
    if (element.isFrame) return undefined;
    const hit = this.template('box').cloneNode(false) as SVGElement;
    hit.setAttribute('width', String(element.width));
    hit.setAttribute('height', String(element.height));
    gfx.appendChild(hit);
    return hit;
  }

  /** diagram-js's own hit area of a block or wire, made once in a detached group. */
  private template(kind: 'box' | 'line'): SVGElement {
    if (kind === 'box') {
      this.box ??= styled(this.interactionEvents.createBoxHit(scratch(), 'all', { width: 0, height: 0 }) as SVGElement);
      return this.box;
    }
    this.line ??= styled(
      this.interactionEvents.createWaypointsHit(scratch(), [
        { x: 0, y: 0 },
        { x: 0, y: 0 },
      ]) as SVGElement,
    );
    return this.line;
  }
}

function scratch(): SVGGElement {
  return document.createElementNS('http://www.w3.org/2000/svg', 'g');
}

/** The hit area styled by the stylesheet's `.djs-hit.sfc-hit` instead of its inline style. */
function styled(hit: SVGElement): SVGElement {
  hit.removeAttribute('style');
  hit.classList.add('sfc-hit');
  return hit;
}
