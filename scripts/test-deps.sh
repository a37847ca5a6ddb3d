#!/usr/bin/env bash
# Installs the programs the test suite calls besides cargo and npm, when they are missing:
#   xmllint (Debian libxml2-utils) validates every PLCopen export against the TC6 v2.01 schema;
#   chromium (Debian) runs the editor's browser tests (Playwright drives it; browsers cannot be
#   downloaded here, so Debian's build is used);
#   python3 counts the steps, transitions and actions of the PLCopen corpus independently of the
#   importer (tests/corpus/real/count.py, standard library only).
# Part of the README's test command, so a fresh machine needs no manual step.
set -euo pipefail
need=()
command -v xmllint >/dev/null 2>&1 || need+=(libxml2-utils)
command -v python3 >/dev/null 2>&1 || need+=(python3)
[ -x /usr/bin/chromium ] || need+=(chromium)
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then need+=(nodejs npm); fi
if [ ${#need[@]} -eq 0 ]; then
    exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "test-deps: please install ${need[*]} with your package manager" >&2
    exit 1
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "test-deps: installing ${need[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get install -y --no-install-recommends "${need[@]}" >/dev/null 2>&1 ||
    { $sudo apt-get update >/dev/null 2>&1 && $sudo apt-get install -y --no-install-recommends "${need[@]}" >/dev/null; }
