// Languages switched from the status bar without a reload, English → Czech → German: the menus,
// the palette, the Properties panel and the error list follow at once, and a diagnostic's title
// shows in Czech (its English message as the tooltip).
import fs from 'node:fs';
import path from 'node:path';
import { assert, openEditor, select, shotPath, waitChart } from '../helpers.mjs';

const here = path.dirname(new URL(import.meta.url).pathname);
const catalogue = (lang) => JSON.parse(fs.readFileSync(path.join(here, '..', '..', 'src', 'i18n', `${lang}.json`), 'utf8'));

/** The texts the test reads, in the language `lang`. */
async function texts(page) {
  return page.evaluate(() => ({
    lang: document.documentElement.lang,
    menus: [...document.querySelectorAll('.menubar .menu-title')].map((e) => e.textContent.trim()),
    palette: [...document.querySelectorAll('.canvas-pane.active .sfc-entry span')].map((e) => e.textContent.trim()),
    groups: [...document.querySelectorAll('.canvas-pane.active .sfc-palette-title')].map((e) => e.textContent.trim()),
    properties: document.querySelector('.side-panel .panel-header span')?.textContent.trim(),
    sections: [...document.querySelectorAll('.side-panel .prop-section h3')].map((e) => e.textContent.trim()),
    errorsTab: document.querySelector('.bottom-panel .panel-tab')?.childNodes[0]?.textContent.trim(),
    headers: [...document.querySelectorAll('.bottom-panel thead th')].map((e) => e.textContent.trim()).filter(Boolean),
    message: document.querySelector('.bottom-panel tbody tr .col-message')?.textContent.trim(),
    tooltip: document.querySelector('.bottom-panel tbody tr .col-message')?.getAttribute('title'),
    // The selected block's own diagnostics, at the top of its properties.
    inline: document.querySelector('.side-panel .prop-heading + .inline-diagnostics li span:last-child')?.textContent.trim(),
  }));
}

function expectLanguage(seen, lang) {
  const c = catalogue(lang);
  const check = (what, actual, expected) => assert(JSON.stringify(actual) === JSON.stringify(expected), `${lang} ${what}: ${JSON.stringify(actual)} ≠ ${JSON.stringify(expected)}`);
  check('lang attribute', seen.lang, lang);
  check('menus', seen.menus.slice(0, 3), [c.menu.file, c.menu.edit, c.menu.view]);
  check('palette groups', seen.groups, [c.palette.blocks, c.palette.groups, c.palette.special]);
  for (const key of ['initialStep', 'step', 'transition', 'jump', 'selectionDivergence', 'actionBlock']) {
    assert(seen.palette.includes(c.palette[key]), `${lang} palette lacks ${c.palette[key]}: ${seen.palette}`);
  }
  check('properties title', seen.properties, c.panel.properties);
  assert(seen.sections.includes(c.props.general), `${lang} properties sections: ${seen.sections}`);
  check('error list tab', seen.errorsTab, c.panel.errors);
  check('error list headers', seen.headers, [c.errors.code, c.errors.element, c.errors.message, c.errors.line]);
}

export const tests = [
  {
    name: 'switch en → cs → de from the status bar: menus, palette, properties and error list follow',
    run: async (t) => {
      const { page } = t;
      fs.copyFileSync(path.join(here, '..', 'fixtures', 'lamp_typo.st'), path.join(t.scratch, 'lamp_typo.st'));
      await openEditor(t, ['lamp_typo.st']);
      await waitChart(page);
      // Opening checks the file: SFC0301 (undeclared variable) on transition SwitchOff.
      await page.waitForSelector('.bottom-panel tbody tr');
      await select(page, 'transition:SwitchOff');
      const english = await texts(page);
      expectLanguage(english, 'en');
      assert(english.message === 'undeclared variable `Buton`', `English message: ${english.message}`);
      assert(english.inline === english.message, `English diagnostic in the properties: ${english.inline}`);
      const loads = [];
      page.on('load', () => loads.push(page.url()));

      // Czech from the list beside the language name.
      await page.locator('.statusbar .status-lang select').selectOption('cs');
      await page.waitForFunction(() => document.documentElement.lang === 'cs');
      const czech = await texts(page);
      expectLanguage(czech, 'cs');
      const cs = catalogue('cs');
      assert(czech.message === `${cs.diag.SFC0301}: Buton`, `Czech diagnostic: ${czech.message} (expected ${cs.diag.SFC0301}: Buton)`);
      assert(czech.tooltip === 'undeclared variable `Buton`', `the English message as tooltip: ${czech.tooltip}`);
      assert(czech.inline === `${cs.diag.SFC0301}: Buton`, `Czech diagnostic in the properties: ${czech.inline}`);
      assert((await page.locator('.statusbar .lang-cycle').textContent()).trim() === cs.lang.cs, 'the status bar names Czech');
      await page.screenshot({ path: shotPath(t, 'czech-ui.png') });

      // German by clicking the language name (Czech → English → German).
      await page.locator('.statusbar .lang-cycle').click();
      await page.waitForFunction(() => document.documentElement.lang === 'en');
      await page.locator('.statusbar .lang-cycle').click();
      await page.waitForFunction(() => document.documentElement.lang === 'de');
      const german = await texts(page);
      expectLanguage(german, 'de');
      assert(german.message === `${catalogue('de').diag.SFC0301}: Buton`, `German diagnostic: ${german.message}`);
      assert(loads.length === 0, `the page was reloaded: ${loads}`);
      // The choice is remembered for the next start: the server keeps it (tests/settings.mjs).
      const kept = () => page.evaluate(async () => (await (await fetch('/api/settings', { headers: { 'X-Sfc-Page': '1' } })).json()).language);
      for (let k = 0; k < 50 && (await kept()) !== 'de'; k++) await page.waitForTimeout(100);
      assert((await kept()) === 'de', 'language not remembered');
    },
  },
];
