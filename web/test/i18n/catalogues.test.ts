// The three catalogues have the same keys (up to each language's plural forms), no empty
// values, a title for every diagnostic code of codes.rs, and every key the sources use.
import { describe, expect, it } from 'vitest';
import { detectLanguage, initI18n, keepLanguageWith, nextLanguage, setLanguage, t } from '../../src/i18n';
import cs from '../../src/i18n/cs.json';
import de from '../../src/i18n/de.json';
import en from '../../src/i18n/en.json';
import monitorCs from '../../src/i18n/monitor.cs.json';
import monitorDe from '../../src/i18n/monitor.de.json';
import monitorEn from '../../src/i18n/monitor.en.json';

type Tree = { [k: string]: string | Tree };

function flatten(tree: Tree, prefix = ''): Record<string, string> {
  const out: Record<string, string> = {};
  for (const [k, v] of Object.entries(tree)) {
    if (typeof v === 'string') out[prefix + k] = v;
    else Object.assign(out, flatten(v, `${prefix}${k}.`));
  }
  return out;
}

const PLURAL = /_(zero|one|two|few|many|other)$/;
// The monitor's catalogues (monitor.*.json) are merged in: every check below covers them too.
const catalogues = {
  en: { ...flatten(en), ...flatten(monitorEn) },
  cs: { ...flatten(cs), ...flatten(monitorCs) },
  de: { ...flatten(de), ...flatten(monitorDe) },
};
const base = (keys: string[]) => [...new Set(keys.map((k) => k.replace(PLURAL, '')))].sort();

// codes.rs lies outside the web app (Vite refuses `?raw` there), so it is read with node:fs; the
// module name is a variable so TypeScript does not need @types/node. Tests run from web/.
const nodeFs = 'node:fs';
const fs = (await import(/* @vite-ignore */ nodeFs)) as { readFileSync(path: string, encoding: 'utf8'): string };
const codesRs = fs.readFileSync(
  `${(globalThis as unknown as { process: { cwd(): string } }).process.cwd()}/../crates/sfc-diagnostics/src/codes.rs`,
  'utf8',
);

// Every source file of the app (raw text), read from disk by Vite.
const sources = import.meta.glob('../../src/**/*.{ts,tsx}', { query: '?raw', import: 'default', eager: true }) as Record<string, string>;

describe('catalogues', () => {
  it('have the same keys', () => {
    expect(base(Object.keys(catalogues.cs))).toEqual(base(Object.keys(catalogues.en)));
    expect(base(Object.keys(catalogues.de))).toEqual(base(Object.keys(catalogues.en)));
  });
  it('have the plural forms each language needs', () => {
    for (const [lang, cat] of Object.entries(catalogues)) {
      const forms = new Intl.PluralRules(lang).resolvedOptions().pluralCategories.filter((f) => f !== 'many' || lang !== 'de');
      for (const key of base(Object.keys(cat).filter((k) => PLURAL.test(k)))) {
        for (const f of forms) expect(cat, `${lang} ${key}_${f}`).toHaveProperty([`${key}_${f}`]);
      }
    }
  });
  it('have no empty values', () => {
    for (const [lang, cat] of Object.entries(catalogues)) {
      for (const [k, v] of Object.entries(cat)) expect(v.trim(), `${lang}: ${k}`).not.toBe('');
    }
  });
  it('are real translations: Czech with diacritics, German with umlauts', () => {
    const all = (c: Record<string, string>) => Object.values(c).join(' ');
    expect(all(catalogues.cs)).toMatch(/[ěščřžýáíéůú]/);
    expect(all(catalogues.de)).toMatch(/[äöüß]/);
    expect(catalogues.cs['kind.step']).toBe('Krok');
    expect(catalogues.cs['kind.transition']).toBe('Přechod');
    expect(catalogues.cs['props.initial']).toBe('Počáteční krok');
    expect(catalogues.de['kind.simultaneousDivergence']).toBe('Simultanverzweigung');
    expect(catalogues.de['kind.jump']).toBe('Sprung');
  });
  it('keep the {{placeholders}} of the English text', () => {
    const vars = (s: string) => [...s.matchAll(/\{\{(\w+)\}\}/g)].map((m) => m[1]).sort();
    for (const [k, v] of Object.entries(catalogues.en)) {
      const key = k.replace(PLURAL, '');
      for (const lang of ['cs', 'de'] as const) {
        const other = Object.entries(catalogues[lang]).find(([kk]) => kk.replace(PLURAL, '') === key)?.[1] ?? '';
        expect(vars(other), `${lang}: ${k}`).toEqual(vars(v));
      }
    }
  });
});

describe('diagnostic titles', () => {
  const codes = [...codesRs.matchAll(/^\s*"(SFC\d{4})"\s+(Error|Warning|Note)\s+"((?:[^"\\]|\\.)*)"/gm)].map((m) => ({ code: m[1], title: m[3] }));
  it('reads codes.rs', () => expect(codes.length).toBeGreaterThanOrEqual(100));
  it('every code has a title in every language, the English one as in codes.rs', () => {
    for (const { code, title } of codes) {
      expect(catalogues.en[`diag.${code}`], code).toBe(title);
      expect(catalogues.cs[`diag.${code}`], code).toBeTruthy();
      expect(catalogues.de[`diag.${code}`], code).toBeTruthy();
    }
  });
  it('no title for a code that does not exist', () => {
    const known = new Set(codes.map((c) => `diag.${c.code}`));
    for (const k of Object.keys(catalogues.en).filter((k) => k.startsWith('diag.'))) expect(known.has(k), k).toBe(true);
  });
});

describe('keys used in the sources', () => {
  it('scans the sources', () => expect(Object.keys(sources).length).toBeGreaterThan(10));
  it("every t('…') key exists in the English catalogue", () => {
    const missing: string[] = [];
    for (const [file, text] of Object.entries(sources)) {
      for (const m of text.matchAll(/\bt\(\s*'([^'$`{}]+)'/g)) {
        const key = m[1];
        const exists = key in catalogues.en || Object.keys(catalogues.en).some((k) => k.replace(PLURAL, '') === key);
        if (!exists) missing.push(`${file}: ${key}`);
      }
    }
    expect(missing).toEqual([]);
  });
});

describe('language switch', () => {
  it('detects the language from storage, then the browser', () => {
    expect(detectLanguage('de', 'cs-CZ')).toBe('de');
    expect(detectLanguage(null, 'cs-CZ')).toBe('cs');
    expect(detectLanguage('xx', 'de-AT')).toBe('de');
    expect(detectLanguage(null, 'fr-FR')).toBe('en');
    expect(detectLanguage(null, undefined)).toBe('en');
  });
  it('cycles cs → en → de → cs', () => {
    expect(nextLanguage('cs')).toBe('en');
    expect(nextLanguage('en')).toBe('de');
    expect(nextLanguage('de')).toBe('cs');
  });
  it('translates at once, with Czech plurals, and keeps the choice where it is told (the settings)', () => {
    const kept: string[] = [];
    keepLanguageWith((l) => kept.push(l));
    initI18n('en');
    expect(t('errors.count.error', { count: 2 })).toBe('2 errors');
    setLanguage('cs');
    expect(t('menu.file')).toBe('Soubor');
    expect(t('errors.count.error', { count: 1 })).toBe('1 chyba');
    expect(t('errors.count.error', { count: 3 })).toBe('3 chyby');
    expect(t('errors.count.error', { count: 5 })).toBe('5 chyb');
    expect(kept).toEqual(['cs']);
    setLanguage('de');
    expect(t('menu.file')).toBe('Datei');
    expect(kept).toEqual(['cs', 'de']);
    expect(localStorage.getItem('sfc.language')).toBeNull();
    keepLanguageWith(() => {});
  });
});
