#!/usr/bin/env bash
# The VS Code extension (editors/vscode), part of the README's test command (test-web.sh calls
# it): installs its npm packages from package-lock.json when they do not match, compiles it,
# runs its unit tests (node --test), the TextMate grammar's tests (vscode-tmgrammar-test) and
# packages it with @vscode/vsce into target/vscode/sfc-<version>.vsix, the file the README says
# to install, checking that the package holds the compiled extension, the grammar and the
# language client it loads at run time. Each part ends with a `test result:` line in cargo's
# format, so .ci/run counts them.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root/editors/vscode"
if ! command -v npm >/dev/null 2>&1; then
    echo "test-vscode: npm is missing; install Node.js 20 and npm (Debian: apt-get install nodejs npm)" >&2
    exit 1
fi
if [ ! -f node_modules/.package-lock.json ] || ! cmp -s package-lock.json node_modules/.package-lock.json.src 2>/dev/null; then
    npm ci --no-audit --no-fund --loglevel=error
    cp package-lock.json node_modules/.package-lock.json.src
fi
status=0
rm -rf out
npx tsc -p .
# Unit tests: node's runner prints TAP-like totals; turn them into a cargo-style line.
log=$(mktemp)
trap 'rm -f "$log"' EXIT
node --test out/test/ >"$log" 2>&1 || status=1
pass=$(sed -n 's/^# pass //p' "$log")
fail=$(sed -n 's/^# fail //p' "$log")
if [ "${fail:-1}" != 0 ]; then cat "$log"; status=1; fi
echo "test result: $([ "${fail:-1}" = 0 ] && echo ok || echo FAILED). ${pass:-0} passed; ${fail:-1} failed; 0 ignored; 0 measured; 0 filtered out (vscode extension)"
# TextMate grammar: every file under test/grammar is a syntax test (scopes asserted in comments).
files=(test/grammar/*.st)
if npx vscode-tmgrammar-test -g syntaxes/sfc.tmLanguage.json "${files[@]}" >"$log" 2>&1; then
    echo "test result: ok. ${#files[@]} passed; 0 failed; 0 ignored; 0 measured; 0 filtered out (TextMate grammar)"
else
    cat "$log"
    bad=$(grep -c '^✖\|failed' "$log" || true)
    echo "test result: FAILED. $(( ${#files[@]} - ${bad:-0} )) passed; ${bad:-1} failed; 0 ignored; 0 measured; 0 filtered out (TextMate grammar)"
    status=1
fi
# The .vsix: packaged with the production dependencies (vscode-languageclient and what it needs).
version=$(node -p 'require("./package.json").version')
vsix="$root/target/vscode/sfc-$version.vsix"
mkdir -p "$root/target/vscode"
rm -f "$vsix"
missing=()
if npx vsce package --allow-missing-repository -o "$vsix" >"$log" 2>&1; then
    listing=$(unzip -Z1 "$vsix")
    for f in extension/package.json extension/out/src/extension.js extension/out/src/junit.js \
        extension/syntaxes/sfc.tmLanguage.json extension/language-configuration.json \
        extension/node_modules/vscode-languageclient/node.js extension/node_modules/vscode-jsonrpc/package.json; do
        grep -qxF "$f" <<<"$listing" || missing+=("$f")
    done
    if [ ${#missing[@]} -gt 0 ]; then echo "test-vscode: $vsix lacks ${missing[*]}" >&2; fi
    if grep -q '^extension/src/\|^extension/test/' <<<"$listing"; then
        echo "test-vscode: $vsix holds sources or tests" >&2
        missing+=(sources)
    fi
else
    cat "$log"
    missing+=(package)
fi
if [ ${#missing[@]} -eq 0 ]; then
    echo "test-vscode: packaged $vsix ($(wc -c <"$vsix") bytes)"
    echo "test result: ok. 1 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out (vsce package)"
else
    echo "test result: FAILED. 0 passed; 1 failed; 0 ignored; 0 measured; 0 filtered out (vsce package)"
    status=1
fi
exit $status
