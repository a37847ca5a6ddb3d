#!/usr/bin/env bash
# The editor's tests, part of the README's test command (after `cargo test`, whose build of the
# `sfc` binary the browser tests use):
#   1. type check and vitest unit tests of web/ (the canvas rules, model sync, the app's logic,
#      the translation catalogues);
#   2. the web app built into web/dist (what release binaries embed) and its test build, with the
#      browser tests' hook `window.__sfc`, into web/dist-test (the debug binary serves it there);
#   3. end-to-end tests in headless Debian Chromium driven by playwright-core (web/e2e);
#   4. the VS Code extension (scripts/test-vscode.sh): its unit and TextMate grammar tests and
#      its .vsix, packaged with @vscode/vsce into target/vscode/.
# Each part ends with a `test result:` line in cargo's format, so .ci/run counts them.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root/web"
scripts_dir="$root/scripts"
"$scripts_dir/build-web.sh" >/dev/null
npm run --silent build:test >/dev/null
npx tsc --noEmit -p .
report=$(mktemp)
trap 'rm -f "$report"' EXIT
status=0
npx vitest run --reporter=default --reporter=json --outputFile="$report" || status=1
node -e '
const r = JSON.parse(require("fs").readFileSync(process.argv[1], "utf8"));
const ok = r.numFailedTests === 0 && r.numFailedTestSuites === 0;
console.log(`test result: ${ok ? "ok" : "FAILED"}. ${r.numPassedTests} passed; ${r.numFailedTests + r.numFailedTestSuites} failed; 0 ignored; 0 measured; 0 filtered out (vitest)`);
' "$report"
cargo build -p sfc-cli --bin sfc --quiet
SFC_BIN="$root/target/debug/sfc" node e2e/run.mjs || status=1
"$scripts_dir/test-vscode.sh" || status=1
exit $status
