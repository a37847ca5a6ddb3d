// Localisation: i18next with the Czech, English and German catalogues of this directory. The
// language is switched at run time (status bar); components re-render on `languageChanged`.
import i18next from 'i18next';
import cs from './cs.json';
import de from './de.json';
import en from './en.json';
import monitorCs from './monitor.cs.json';
import monitorDe from './monitor.de.json';
import monitorEn from './monitor.en.json';

export const LANGUAGES = ['cs', 'en', 'de'] as const;
export type Lang = (typeof LANGUAGES)[number];

export const i18n = i18next.createInstance();

/** The stored choice, else the browser's language (cs, de, anything else English). */
export function detectLanguage(stored: string | null, browser: string | undefined): Lang {
  if (stored && (LANGUAGES as readonly string[]).includes(stored)) return stored as Lang;
  const primary = (browser ?? '').toLowerCase().split('-')[0];
  return primary === 'cs' || primary === 'de' ? primary : 'en';
}

/** Language after `lang` when the status bar label is clicked: cs → en → de → cs. */
export function nextLanguage(lang: Lang): Lang {
  return LANGUAGES[(LANGUAGES.indexOf(lang) + 1) % LANGUAGES.length];
}

/** Keeps the language the user chose: main.ts hands it to the settings the server keeps
 *  (src/app/settings.ts); until then (and in unit tests) it lasts for the page. */
let keep: (lang: Lang) => void = () => {};

/** Where `setLanguage` keeps the choice from now on. */
export function keepLanguageWith(fn: (lang: Lang) => void): void {
  keep = fn;
}

/** Initialises i18next synchronously with `lang`, else the browser's language (main.ts passes
 *  the kept choice, read before the first render). */
export function initI18n(lang?: Lang): Lang {
  const chosen = lang ?? detectLanguage(null, globalThis.navigator?.language);
  if (!i18n.isInitialized) {
    void i18n.init({
      lng: chosen,
      fallbackLng: 'en',
      initAsync: false,
      // The monitor's strings live in their own catalogues (monitor.*.json), under `monitor.`.
      resources: {
        en: { translation: { ...en, ...monitorEn } },
        cs: { translation: { ...cs, ...monitorCs } },
        de: { translation: { ...de, ...monitorDe } },
      },
      interpolation: { escapeValue: false },
      returnNull: false,
    });
  } else {
    void i18n.changeLanguage(chosen);
  }
  return chosen;
}

/** Switches the language (takes effect at once) and remembers it. */
export function setLanguage(lang: Lang): void {
  void i18n.changeLanguage(lang);
  keep(lang);
}

export function currentLanguage(): Lang {
  const l = i18n.language as Lang;
  return (LANGUAGES as readonly string[]).includes(l) ? l : 'en';
}

/** Translates a UI key. */
export function t(key: string, options?: Record<string, unknown>): string {
  return i18n.t(key, options ?? {}) as string;
}

/** The translated title of a diagnostic code, else the server's English title. */
export function diagTitle(code: string, english: string): string {
  const key = `diag.${code}`;
  return i18n.exists(key) ? t(key) : english;
}

/**
 * A diagnostic in the current language. English shows the server's message as `sfc check`
 * prints it; the other languages show the code's translated title followed by the names the
 * message quotes (`nedeklarovaná proměnná: Buton`), so the specifics are not lost.
 */
export function diagMessage(d: { code: string; title: string; message: string }): string {
  if (currentLanguage() === 'en') return d.message;
  const names = [...new Set([...d.message.matchAll(/`([^`]+)`/g)].map((m) => m[1].trim()).filter((q) => q !== ''))];
  const title = diagTitle(d.code, d.title);
  return names.length ? `${title}: ${names.join(', ')}` : title;
}
