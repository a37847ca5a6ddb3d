// Inline SVG icons of the menus and toolbar (16 × 16, stroked with the text colour).
import type { JSX } from 'preact';

const PATHS: Record<string, JSX.Element> = {
  new: (
    <>
      <path d="M4 1.5h5l3 3v10H4z" />
      <path d="M9 1.5v3h3M8 7.5v5M5.5 10h5" />
    </>
  ),
  open: <path d="M1.5 4.5v9h11l2-6h-11l-2 6M1.5 4.5v-2h4l1 1.5h6v3.5" />,
  save: (
    <>
      <path d="M2 2h10l2 2v10H2z" />
      <path d="M5 2v4h6V2M4.5 14V9.5h7V14" />
    </>
  ),
  print: (
    <>
      <path d="M4 6V1.5h8V6M4 12H1.5V6h13v6H12" />
      <path d="M4 9.5h8v5H4z" />
    </>
  ),
  svg: (
    <>
      <path d="M2 2h12v12H2z" />
      <path d="M4 11l3-4 2 2.5L11 7l1.5 4z" />
    </>
  ),
  undo: <path d="M5.5 3.5L2.5 6.5l3 3M2.5 6.5h7a4 4 0 010 8h-3" />,
  redo: <path d="M10.5 3.5l3 3-3 3M13.5 6.5h-7a4 4 0 000 8h3" />,
  cut: (
    <>
      <circle cx="4.5" cy="12" r="2" />
      <circle cx="11.5" cy="12" r="2" />
      <path d="M5.8 10.5L12 2M10.2 10.5L4 2" />
    </>
  ),
  copy: (
    <>
      <path d="M5.5 5.5h8v9h-8z" />
      <path d="M10.5 5.5v-4h-8v9h3" />
    </>
  ),
  paste: (
    <>
      <path d="M5 2.5H2.5v12h11v-12H11" />
      <path d="M5.5 1.5h5v2.5h-5zM5 8h6M5 11h4" />
    </>
  ),
  delete: <path d="M2.5 4h11M6 4V2h4v2M4 4l.8 10.5h6.4L12 4M6.5 6.5v5.5M9.5 6.5v5.5" />,
  layout: (
    <>
      <path d="M6 1.5h4v3H6zM2 11.5h4v3H2zM10 11.5h4v3h-4z" />
      <path d="M8 4.5V8M4 11.5V8h8v3.5" />
    </>
  ),
  validate: <path d="M2.5 8.5l3.5 3.5 7.5-8" />,
  build: <path d="M4 2.5l9 5.5-9 5.5z" />,
  zoomIn: (
    <>
      <circle cx="7" cy="7" r="4.5" />
      <path d="M10.3 10.3l4 4M5 7h4M7 5v4" />
    </>
  ),
  zoomOut: (
    <>
      <circle cx="7" cy="7" r="4.5" />
      <path d="M10.3 10.3l4 4M5 7h4" />
    </>
  ),
  fit: <path d="M1.5 5.5v-4h4M10.5 1.5h4v4M14.5 10.5v4h-4M5.5 14.5h-4v-4M5 5h6v6H5z" />,
  close: <path d="M4 4l8 8M12 4l-8 8" />,
  error: (
    <>
      <circle cx="8" cy="8" r="6.5" fill="#d13438" stroke="#d13438" />
      <path d="M5.5 5.5l5 5M10.5 5.5l-5 5" stroke="#fff" />
    </>
  ),
  warning: (
    <>
      <path d="M8 1.5l7 12.5H1z" fill="#e8a317" stroke="#e8a317" />
      <path d="M8 6v4M8 11.5v1" stroke="#fff" />
    </>
  ),
  note: (
    <>
      <circle cx="8" cy="8" r="6.5" fill="#2b79d0" stroke="#2b79d0" />
      <path d="M8 7v4.5M8 4.5v1" stroke="#fff" />
    </>
  ),
  highlight: (
    <>
      <path d="M2 2h12v12H2z" stroke-dasharray="2 1.5" />
      <path d="M5 5h6v6H5z" />
    </>
  ),
  up: <path d="M4 10l4-4 4 4" />,
  down: <path d="M4 6l4 4 4-4" />,
  plus: <path d="M8 3v10M3 8h10" />,
  prev: <path d="M10 3L5 8l5 5" />,
  next: <path d="M6 3l5 5-5 5" />,
  download: <path d="M8 2v8.5M4.5 7L8 10.5 11.5 7M2.5 13.5h11" />,
  witness: <path d="M1.5 8h3l2-4 3 8 2-4h3" />,
};

export type IconName = keyof typeof PATHS;

export function Icon({ name, title }: { name: IconName; title?: string }) {
  return (
    <svg
      class="icon"
      width="16"
      height="16"
      viewBox="0 0 16 16"
      fill="none"
      stroke="currentColor"
      stroke-width="1.3"
      stroke-linecap="round"
      stroke-linejoin="round"
      aria-hidden={title ? undefined : 'true'}
    >
      {title && <title>{title}</title>}
      {PATHS[name]}
    </svg>
  );
}
