// Entry point of the SFC Editor: localisation, the API client (token from the URL) and the shell.
import { h, render } from 'preact';
import { App } from './app/App';
import { createApi, tokenFromSearch } from './app/api';
import './app/app.css';
import { createCanvas } from './diagram';
import { initI18n } from './i18n';

initI18n();
const api = createApi({ token: tokenFromSearch(location.search) });
render(h(App, { api, createCanvas }), document.getElementById('app')!);
