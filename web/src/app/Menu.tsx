// The menu bar: File, Edit, View, Help, each a drop-down with shortcuts shown beside the items.
import { useEffect, useRef, useState } from 'preact/hooks';
import { Icon, type IconName } from './icons';

export interface MenuItem {
  label: string;
  action?: () => void;
  shortcut?: string;
  icon?: IconName;
  disabled?: boolean;
  /** A check mark (panel toggles, the current language). */
  checked?: boolean;
  separator?: boolean;
}

export interface MenuDef {
  id: string;
  label: string;
  items: MenuItem[];
}

export function MenuBar(props: { menus: MenuDef[] }) {
  const [open, setOpen] = useState<string | null>(null);
  const bar = useRef<HTMLDivElement>(null);
  useEffect(() => {
    if (open === null) return;
    const onDown = (e: MouseEvent) => {
      if (!bar.current?.contains(e.target as Node)) setOpen(null);
    };
    const onKey = (e: KeyboardEvent) => {
      if (e.key === 'Escape') setOpen(null);
    };
    document.addEventListener('mousedown', onDown);
    document.addEventListener('keydown', onKey);
    return () => {
      document.removeEventListener('mousedown', onDown);
      document.removeEventListener('keydown', onKey);
    };
  }, [open]);
  return (
    <div class="menubar no-print" role="menubar" ref={bar}>
      {props.menus.map((m) => (
        <div class="menu" key={m.id}>
          <button
            class={`menu-title ${open === m.id ? 'open' : ''}`}
            role="menuitem"
            aria-haspopup="true"
            aria-expanded={open === m.id}
            onClick={() => setOpen(open === m.id ? null : m.id)}
            onMouseEnter={() => open !== null && setOpen(m.id)}
          >
            {m.label}
          </button>
          {open === m.id && (
            <div class="menu-dropdown" role="menu">
              {m.items.map((it, k) =>
                it.separator ? (
                  <div class="menu-separator" key={k} />
                ) : (
                  <button
                    key={k}
                    role="menuitem"
                    class="menu-item"
                    disabled={it.disabled}
                    onClick={() => {
                      setOpen(null);
                      it.action?.();
                    }}
                  >
                    <span class="menu-check">{it.checked ? '✓' : it.icon ? <Icon name={it.icon} /> : ''}</span>
                    <span class="menu-label">{it.label}</span>
                    <span class="menu-shortcut">{it.shortcut ?? ''}</span>
                  </button>
                ),
              )}
            </div>
          )}
        </div>
      ))}
    </div>
  );
}
