// The document-level fields (POU name, kind, target, declarations, actions, description): not
// drawn, but kept with the canvas so `getDoc()` returns a whole document and `updateDoc` is
// undoable like every other change.
import type { EditorDoc } from '../../doc';

export type DocFields = Omit<EditorDoc, 'elements' | 'connections'>;

export class DocState {
  fields: DocFields = { pou: '', pouKind: 'program', target: 'blank', declarations: '', actions: [] };
}
