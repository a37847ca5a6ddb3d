// IEC 61131-3 duration literals (`T#5s`, `TIME#1h2m3.5s`), checked the way sfc-syntax decodes
// them (crates/sfc-syntax/src/literal.rs) so the Properties panel rejects what `sfc check` would.

/** Units, largest first, with their length in microseconds (`ns` must make whole µs). */
const UNITS: [string, number][] = [
  ['D', 86_400_000_000],
  ['H', 3_600_000_000],
  ['M', 60_000_000],
  ['S', 1_000_000],
  ['MS', 1_000],
  ['US', 1],
  ['NS', 0],
];

export type DurationCheck =
  | { ok: true; micros: number }
  /** `error` is an i18n key under `duration.`; `detail` the offending part. */
  | { ok: false; error: string; detail?: string };

/** Checks a duration literal and returns its length in microseconds. */
export function parseDuration(literal: string): DurationCheck {
  const text = literal.trim();
  const m = /^(T|TIME)#(.*)$/i.exec(text);
  if (!m) return { ok: false, error: 'duration.prefix' };
  let body = m[2];
  let negative = false;
  if (body.startsWith('-') || body.startsWith('+')) {
    negative = body.startsWith('-');
    body = body.slice(1);
  }
  if (body === '') return { ok: false, error: 'duration.empty' };
  const upper = body.toUpperCase();
  let i = 0;
  let total = 0;
  let lastRank = -1;
  let hadFraction = false;
  while (i < upper.length) {
    if (upper[i] === '_') {
      i++;
      continue;
    }
    const numStart = i;
    while (i < upper.length && /[0-9._]/.test(upper[i])) i++;
    const num = upper.slice(numStart, i);
    if (num === '') return { ok: false, error: 'duration.number', detail: body.slice(numStart) };
    const unitStart = i;
    while (i < upper.length && /[A-Z]/.test(upper[i])) i++;
    const unit = upper.slice(unitStart, i);
    const rank = UNITS.findIndex(([u]) => u === unit);
    if (rank < 0) return { ok: false, error: 'duration.unit', detail: body.slice(unitStart, i) || body.slice(unitStart) };
    if (hadFraction) return { ok: false, error: 'duration.fraction' };
    if (rank <= lastRank) return { ok: false, error: 'duration.order' };
    lastRank = rank;
    const [intPart, fracPart = ''] = num.split('.', 2);
    if (intPart === '' || intPart.includes('__') || (num.includes('.') && fracPart === '') || num.split('.').length > 2) {
      return { ok: false, error: 'duration.number', detail: num };
    }
    const intValue = Number(intPart.replace(/_/g, ''));
    const scale = UNITS[rank][1];
    if (unit === 'NS') {
      const digits = fracPart.replace(/_/g, '');
      if (intValue % 1000 !== 0 || /[1-9]/.test(digits)) return { ok: false, error: 'duration.resolution' };
      total += intValue / 1000;
    } else {
      total += intValue * scale;
      if (fracPart !== '') {
        hadFraction = true;
        const digits = fracPart.replace(/_/g, '');
        const scaled = (Number(digits) * scale) / 10 ** digits.length;
        if (digits.length > 18 || Math.abs(scaled - Math.round(scaled)) > 1e-6) {
          return { ok: false, error: 'duration.resolution' };
        }
        total += Math.round(scaled);
      }
    }
    if (!Number.isSafeInteger(total)) return { ok: false, error: 'duration.range' };
  }
  return { ok: true, micros: negative ? -total : total };
}

/** Seconds as the shortest decimal, the way the ATMT timeout vector writes them (`8.1`, `0.5`). */
export function formatSeconds(micros: number): string {
  return String(Number((micros / 1e6).toFixed(6)));
}

/** A duration literal for a number of seconds (`2.5` → `T#2.5s`), for the seed's real-number timeouts. */
export function secondsToLiteral(seconds: number): string {
  return `T#${formatSeconds(Math.round(seconds * 1e6))}s`;
}
