// `updateDoc`: changes document-level fields as one undoable command.
import type { DocFields, DocState } from '../../core/DocState';
import { clone } from '../../model';

export interface UpdateDocContext {
  props: Partial<DocFields>;
  old?: Partial<DocFields>;
  had?: Record<string, boolean>;
}

export class UpdateDocHandler {
  static $inject = ['sfcDocState'];

  constructor(private state: DocState) {}

  execute(ctx: UpdateDocContext) {
    const f = this.state.fields as unknown as Record<string, unknown>;
    ctx.old = {};
    ctx.had = {};
    for (const [k, v] of Object.entries(ctx.props)) {
      ctx.had[k] = k in f;
      (ctx.old as Record<string, unknown>)[k] = f[k];
      if (v === undefined) delete f[k];
      else f[k] = clone(v);
    }
    return [];
  }

  revert(ctx: UpdateDocContext) {
    const f = this.state.fields as unknown as Record<string, unknown>;
    for (const [k, v] of Object.entries(ctx.old ?? {})) {
      if (ctx.had?.[k]) f[k] = v;
      else delete f[k];
    }
    return [];
  }
}
