// The palette (seed 001 §7.1, panel "Nástroje"): SFC blocks, SFC groups (divergences and
// convergences) and special blocks (text, action block). Drag an entry onto the chart, or
// click it and click where the block goes. ATMT and EATMT charts have no simultaneous
// (AND) branches and no actions: their palette shows those entries greyed, with the reason as
// their tooltip, and the canvas refuses them at the drop, saying why (rules/RefusalTooltip).
import type { Element, ElementKind } from '../../doc';
import type { DocState } from '../core/DocState';
import { actionBlockSize, stepSize } from '../drawing';
import { defaultSize } from '../geometry';
import { freshName, usedNames, type Service } from '../model';
import { kindsRefusedBy, refusalReason } from '../rules/SfcRules';

interface EntrySpec {
  id: string;
  group: 'blocks' | 'groups' | 'special';
  /** Catalogue key of the entry's label (`palette.*`). */
  label: string;
  icon: string;
  make: () => Partial<Element> & { kind: ElementKind };
}

const I = (body: string) =>
  `<svg viewBox="0 0 28 28" width="28" height="28" aria-hidden="true" fill="none" stroke="currentColor" stroke-width="1.6">${body}</svg>`;

const ICONS: Record<string, string> = {
  initialStep: I('<rect x="4" y="7" width="20" height="14"/><rect x="7" y="10" width="14" height="8"/>'),
  step: I('<rect x="4" y="7" width="20" height="14"/>'),
  transition: I('<line x1="14" y1="3" x2="14" y2="25"/><rect x="7" y="12.5" width="14" height="3" fill="currentColor"/>'),
  selectionDivergence: I('<line x1="14" y1="4" x2="14" y2="12"/><line x1="4" y1="12" x2="24" y2="12"/><line x1="6" y1="12" x2="6" y2="24"/><line x1="22" y1="12" x2="22" y2="24"/>'),
  selectionConvergence: I('<line x1="6" y1="4" x2="6" y2="16"/><line x1="22" y1="4" x2="22" y2="16"/><line x1="4" y1="16" x2="24" y2="16"/><line x1="14" y1="16" x2="14" y2="24"/>'),
  simultaneousDivergence: I('<line x1="14" y1="4" x2="14" y2="10"/><line x1="3" y1="10" x2="25" y2="10"/><line x1="3" y1="14" x2="25" y2="14"/><line x1="6" y1="14" x2="6" y2="24"/><line x1="22" y1="14" x2="22" y2="24"/>'),
  simultaneousConvergence: I('<line x1="6" y1="4" x2="6" y2="14"/><line x1="22" y1="4" x2="22" y2="14"/><line x1="3" y1="14" x2="25" y2="14"/><line x1="3" y1="18" x2="25" y2="18"/><line x1="14" y1="18" x2="14" y2="24"/>'),
  jump: I('<line x1="14" y1="3" x2="14" y2="12"/><polygon points="8,12 20,12 14,22" fill="currentColor"/>'),
  text: I('<rect x="3" y="6" width="22" height="16" stroke-dasharray="3 2"/><line x1="7" y1="11" x2="21" y2="11"/><line x1="7" y1="16" x2="17" y2="16"/>'),
  actionBlock: I('<rect x="2" y="8" width="24" height="12"/><line x1="9" y1="8" x2="9" y2="20"/><line x1="20" y1="8" x2="20" y2="20"/>'),
};

/** Catalogue keys of the group titles. */
export const GROUP_TITLES: Record<EntrySpec['group'], string> = {
  blocks: 'palette.blocks',
  groups: 'palette.groups',
  special: 'palette.special',
};

export class SfcPalette {
  static $inject = ['palette', 'create', 'elementFactory', 'elementRegistry', 'config.sfc', 'sfcDocState', 'eventBus'];

  /** Whether the entries shown are those of a table target (ATMT/EATMT). */
  private shownForTable = false;

  constructor(
    palette: Service,
    private create: Service,
    private elementFactory: Service,
    private elementRegistry: Service,
    private config: { t: (key: string, opts?: Record<string, unknown>) => string },
    private state: DocState,
    eventBus: Service,
  ) {
    palette.registerProvider(this);
    // The chart's target comes with a load and changes by an (undoable) edit of the chart.
    eventBus.on(['sfc.loaded', 'commandStack.changed'], () => {
      const forTable = kindsRefusedBy(this.state.fields.target).length > 0;
      if (forTable !== this.shownForTable) palette._update();
    });
  }

  private specs(): EntrySpec[] {
    const named = (kind: 'step' | 'transition', prefix: string, extra: Partial<Element> = {}) => () => ({
      kind,
      name: freshName(prefix, usedNames(this.elementRegistry)),
      ...extra,
    });
    return [
      { id: 'initial-step', group: 'blocks', label: 'palette.initialStep', icon: ICONS.initialStep, make: named('step', 'S', { initial: true }) },
      { id: 'step', group: 'blocks', label: 'palette.step', icon: ICONS.step, make: named('step', 'S') },
      { id: 'transition', group: 'blocks', label: 'palette.transition', icon: ICONS.transition, make: named('transition', 'T', { condition: '' }) },
      { id: 'jump', group: 'blocks', label: 'palette.jump', icon: ICONS.jump, make: () => ({ kind: 'jump' }) },
      { id: 'selection-divergence', group: 'groups', label: 'palette.selectionDivergence', icon: ICONS.selectionDivergence, make: () => ({ kind: 'selectionDivergence', pins: 2 }) },
      { id: 'selection-convergence', group: 'groups', label: 'palette.selectionConvergence', icon: ICONS.selectionConvergence, make: () => ({ kind: 'selectionConvergence', pins: 2 }) },
      { id: 'simultaneous-divergence', group: 'groups', label: 'palette.simultaneousDivergence', icon: ICONS.simultaneousDivergence, make: () => ({ kind: 'simultaneousDivergence', pins: 2 }) },
      { id: 'simultaneous-convergence', group: 'groups', label: 'palette.simultaneousConvergence', icon: ICONS.simultaneousConvergence, make: () => ({ kind: 'simultaneousConvergence', pins: 2 }) },
      { id: 'text', group: 'special', label: 'palette.text', icon: ICONS.text, make: () => ({ kind: 'text', text: 'Text', align: 'left' }) },
      { id: 'action-block', group: 'special', label: 'palette.actionBlock', icon: ICONS.actionBlock, make: () => ({ kind: 'actionBlock', associations: [{ qualifier: 'N', action: 'Action' }] }) },
    ];
  }


  /** A new block of the entry's kind with default size, ready for the create tool. */
  newShape(spec: EntrySpec): Service {
    const e = spec.make();
    const size = e.kind === 'step' ? stepSize(e) : e.kind === 'actionBlock' ? actionBlockSize(e.associations ?? []) : defaultSize(e.kind);
    const bo: Element = { id: '', x: 0, y: 0, w: size.w, h: size.h, ...e } as Element;
    return this.elementFactory.createShape({ businessObject: bo, width: size.w, height: size.h });
  }

  getPaletteEntries(): Record<string, Service> {
    const t = this.config.t;
    // diagram-js marks the active tool (lasso) inside a "tools" group; keep an empty one.
    const entries: Record<string, Service> = { 'tools-anchor': { group: 'tools', html: '<div class="sfc-palette-tools"></div>', action: {} } };
    this.shownForTable = kindsRefusedBy(this.state.fields.target).length > 0;
    let group = '';
    const refused = kindsRefusedBy(this.state.fields.target);
    for (const spec of this.specs()) {
      if (spec.group !== group) {
        group = spec.group;
        entries[`title-${group}`] = {
          group,
          html: `<div class="sfc-palette-title">${escapeHtml(t(GROUP_TITLES[spec.group]))}</div>`,
          action: {},
        };
      }
      const label = escapeHtml(t(spec.label));
      const start = (event: Event) => this.create.start(event, this.newShape(spec));
      const why = refused.includes(spec.make().kind) ? refusalReason(spec.make().kind, this.state.fields.target, t) : '';
      const title = why ? `${label} — ${escapeHtml(why)}` : label;
      entries[`create.${spec.id}`] = {
        group,
        title: why ? `${t(spec.label)} — ${why}` : t(spec.label),
        html: `<div class="entry sfc-entry${why ? ' refused' : ''}" draggable="true" title="${title}"${why ? ' aria-disabled="true"' : ''}>${spec.icon}<span>${label}</span></div>`,
        action: { dragstart: start, click: start },
      };
    }
    return entries;
  }
}

function escapeHtml(s: string): string {
  return s.replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]!);
}
