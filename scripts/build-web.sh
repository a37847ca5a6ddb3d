#!/usr/bin/env bash
# Builds the SFC Editor's web app into web/dist, which `cargo build --release` embeds in the `sfc`
# binary. Installs the npm packages of web/package-lock.json first (Node 20 and npm are needed).
set -euo pipefail
cd "$(dirname "$0")/../web"
if ! command -v npm >/dev/null 2>&1; then
    echo "build-web: npm is missing; install Node.js 20 and npm (Debian: apt-get install nodejs npm)" >&2
    exit 1
fi
# npm ci only when the installed packages do not match the lock file.
if [ ! -f node_modules/.package-lock.json ] || ! cmp -s package-lock.json node_modules/.package-lock.json.src 2>/dev/null; then
    npm ci --no-audit --no-fund --loglevel=error
    cp package-lock.json node_modules/.package-lock.json.src
fi
npm run --silent build
