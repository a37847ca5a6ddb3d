// A code editor: a textarea over a highlighted <pre> (same font and metrics, the textarea's
// text transparent), with squiggles where diagnostics fall and the diagnostics listed below.
import { useEffect, useRef, useState } from 'preact/hooks';
import type { Diag } from '../api';
import { t, diagMessage } from '../i18n';
import { locateInText, segments } from './highlight';
import { Icon } from './icons';

export function CodeEditor(props: {
  value: string;
  language: 'ST' | 'IL';
  /** Called with the text when the user stops typing (debounced), to check it. */
  onDraft?: (text: string) => void;
  /** Called when the edit is finished (blur, Ctrl+Enter): the change goes to the canvas. */
  onCommit: (text: string) => void;
  diagnostics: Diag[];
  rows?: number;
  label: string;
  readOnly?: boolean;
}) {
  const [text, setText] = useState(props.value);
  const editing = useRef(false);
  const pre = useRef<HTMLPreElement>(null);
  const timer = useRef<ReturnType<typeof setTimeout> | null>(null);
  const latest = useRef({ text, props });
  latest.current = { text, props };

  // A new value from outside (undo, another selection) replaces the text unless the user is typing.
  useEffect(() => {
    if (!editing.current) setText(props.value);
  }, [props.value]);

  // An unfinished edit is not lost when the editor goes away (selection changes, panel closes).
  useEffect(
    () => () => {
      if (timer.current) clearTimeout(timer.current);
      const { text: last, props: p } = latest.current;
      if (editing.current && last !== p.value) p.onCommit(last);
    },
    [],
  );

  const commit = () => {
    editing.current = false;
    if (text !== props.value) props.onCommit(text);
  };

  const marks = props.diagnostics
    .map((d) => locateInText(text, d))
    .filter((m): m is { start: number; end: number } => m !== null);
  const rows = Math.max(props.rows ?? 3, Math.min(16, text.split('\n').length + 1));
  return (
    <div class="code-editor-wrap">
      <div class={`code-editor ${props.diagnostics.some((d) => d.severity === 'error') ? 'has-error' : ''}`}>
        <pre ref={pre} class="code-highlight" aria-hidden="true">
          {segments(text, props.language, marks).map((s, k) => (
            <span key={k} class={`tok-${s.kind}${s.marked ? ' squiggle' : ''}`}>
              {s.text}
            </span>
          ))}
          {'\n'}
        </pre>
        <textarea
          aria-label={props.label}
          spellcheck={false}
          readOnly={props.readOnly}
          rows={rows}
          value={text}
          onInput={(e) => {
            const v = e.currentTarget.value;
            editing.current = true;
            setText(v);
            if (timer.current) clearTimeout(timer.current);
            timer.current = setTimeout(() => latest.current.props.onDraft?.(v), 400);
          }}
          onScroll={(e) => {
            if (pre.current) {
              pre.current.scrollTop = e.currentTarget.scrollTop;
              pre.current.scrollLeft = e.currentTarget.scrollLeft;
            }
          }}
          onKeyDown={(e) => {
            if (e.key === 'Enter' && (e.ctrlKey || e.metaKey)) {
              e.preventDefault();
              commit();
            } else if (e.key === 'Tab' && !e.shiftKey) {
              // Tab indents instead of leaving the editor.
              e.preventDefault();
              const ta = e.currentTarget;
              const s = ta.selectionStart;
              const v = text.slice(0, s) + '    ' + text.slice(ta.selectionEnd);
              editing.current = true;
              setText(v);
              requestAnimationFrame(() => ta.setSelectionRange(s + 4, s + 4));
            }
          }}
          onBlur={commit}
        />
      </div>
      {props.diagnostics.length > 0 && (
        <ul class="inline-diagnostics">
          {props.diagnostics.map((d, k) => (
            <li key={k} class={`sev-${d.severity}`} title={d.message}>
              <Icon name={d.severity} />
              <span class="diag-code">{d.code}</span>
              <span>{diagMessage(d)}</span>
            </li>
          ))}
        </ul>
      )}
      {props.diagnostics.length === 0 && text !== props.value && <div class="editor-hint">{t('props.commitHint')}</div>}
    </div>
  );
}
