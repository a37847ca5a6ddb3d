// Entry point of the SFC Editor: localisation, the API client (authenticated by the cookie the
// server set for the printed URL) and the shell.
import { h, render } from 'preact';
import { App } from './app/App';
import { createApi, type StartRequests } from './app/api';
import './app/app.css';
import { createCanvas } from './diagram';
import { initI18n } from './i18n';

initI18n();
// The server answers the printed URL with a redirect that drops the token; should an address
// with one still be shown, it leaves the address bar and the history.
if (new URLSearchParams(location.search).has('token')) history.replaceState(null, '', location.pathname);
const api = createApi({ start: (window as unknown as { __sfcStart?: StartRequests }).__sfcStart });
render(h(App, { api, createCanvas }), document.getElementById('app')!);
