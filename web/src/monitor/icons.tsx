// Icons of the monitor toolbar (16×16, stroked like the shell's; the breakpoint dots filled).
const PATHS = {
  run: <path d="M4.5 2.5l9 5.5-9 5.5z" fill="currentColor" />,
  halt: (
    <>
      <rect x="3.5" y="3" width="3" height="10" rx="0.5" fill="currentColor" />
      <rect x="9.5" y="3" width="3" height="10" rx="0.5" fill="currentColor" />
    </>
  ),
  scan: (
    <>
      <path d="M2.5 3v10" />
      <path d="M5.5 3l7 5-7 5z" fill="currentColor" />
    </>
  ),
  eye: (
    <>
      <path d="M1 8s2.6-4.5 7-4.5S15 8 15 8s-2.6 4.5-7 4.5S1 8 1 8z" />
      <circle cx="8" cy="8" r="2" />
    </>
  ),
  eyeOff: (
    <>
      <path d="M1 8s2.6-4.5 7-4.5S15 8 15 8s-2.6 4.5-7 4.5S1 8 1 8z" />
      <path d="M2.5 13.5l11-11" />
    </>
  ),
  bpSet: <circle cx="8" cy="8" r="4.5" fill="#dc2626" stroke="#dc2626" />,
  bpDisable: <circle cx="8" cy="8" r="4.5" stroke="#dc2626" stroke-width="1.6" />,
  bpDelete: (
    <>
      <circle cx="8" cy="8" r="4.5" fill="#fca5a5" stroke="#fca5a5" />
      <path d="M5 5l6 6M11 5l-6 6" stroke="#991b1b" stroke-width="1.6" />
    </>
  ),
  bpDisableAll: (
    <>
      <circle cx="6" cy="9.5" r="3.5" stroke="#dc2626" stroke-width="1.4" />
      <circle cx="10.5" cy="5.5" r="3.5" stroke="#dc2626" stroke-width="1.4" />
    </>
  ),
  bpDeleteAll: (
    <>
      <circle cx="6" cy="9.5" r="3.5" fill="#fca5a5" stroke="#fca5a5" />
      <circle cx="10.5" cy="5.5" r="3.5" fill="#fca5a5" stroke="#fca5a5" />
      <path d="M3 3l10 10" stroke="#991b1b" stroke-width="1.6" />
    </>
  ),
  first: <path d="M3.5 3v10M12.5 3l-6 5 6 5z" />,
  back: <path d="M11 3l-6 5 6 5z" />,
  forward: <path d="M5 3l6 5-6 5z" />,
  last: <path d="M12.5 3v10M3.5 3l6 5-6 5z" />,
  live: (
    <>
      <circle cx="8" cy="8" r="2.5" fill="currentColor" />
      <path d="M3.8 3.8a6 6 0 000 8.4M12.2 3.8a6 6 0 010 8.4" />
    </>
  ),
  why: (
    <>
      <circle cx="8" cy="8" r="6.5" />
      <path d="M6 6.2a2 2 0 113 1.7c-.7.4-1 .8-1 1.6M8 11.5v.3" />
    </>
  ),
  stop: <rect x="3.5" y="3.5" width="9" height="9" rx="1" fill="currentColor" />,
  monitor: (
    <>
      <rect x="1.5" y="2.5" width="13" height="9" rx="1" />
      <path d="M3.5 9l2.5-3 2 2 2.5-3.5 2 2.5M5.5 14h5" />
    </>
  ),
  plug: <path d="M6 1.5v3M10 1.5v3M4.5 4.5h7v3a3.5 3.5 0 01-7 0zM8 11v3.5" />,
};

export type MonitorIconName = keyof typeof PATHS;

export function MonitorIcon({ name }: { name: MonitorIconName }) {
  return (
    <svg class="icon" width="16" height="16" viewBox="0 0 16 16" fill="none" stroke="currentColor" stroke-width="1.3" stroke-linecap="round" stroke-linejoin="round" aria-hidden="true">
      {PATHS[name]}
    </svg>
  );
}
