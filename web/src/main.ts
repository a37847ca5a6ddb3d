// Entry point of the SFC Editor: the kept settings (read before the first render, so the page
// comes up in the kept language), localisation, the API client (authenticated by the cookie the
// server set for the printed URL) and the shell.
import { h, render } from 'preact';
import { App } from './app/App';
import { createApi, type StartRequests } from './app/api';
import './app/app.css';
import { settings } from './app/settings';
import { createCanvas } from './diagram';
import { detectLanguage, initI18n, keepLanguageWith } from './i18n';

// The server redirects the printed URL to one without the token; should an address with one
// still be shown, it leaves the address bar and the history.
if (new URLSearchParams(location.search).has('token')) history.replaceState(null, '', location.pathname);
const api = createApi({ start: (window as unknown as { __sfcStart?: StartRequests }).__sfcStart });

async function start(): Promise<void> {
  // At most 3 s: a server that does not answer leaves the settings to localStorage.
  const server = { read: api.settings, write: api.saveSettings };
  await Promise.race([settings.load(server), new Promise((r) => setTimeout(r, 3000))]);
  initI18n(detectLanguage(settings.language() ?? null, globalThis.navigator?.language));
  keepLanguageWith((language) => void settings.update({ language }));
  render(h(App, { api, createCanvas }), document.getElementById('app')!);
}

void start();
