#!/usr/bin/env bash
# Makes sure `python3 -c "import asyncua"` works: installs asyncua (the independent OPC UA
# client of the end-to-end test crates/sfc-cli/tests/opcua.rs) from PyPI with pip when it is
# missing. scripts/test-deps.sh calls it; the test calls it too and skips, loudly, only when
# this script fails. The version is pinned (the one the tests were written against), so a new
# release of the client cannot turn CI red on its own.
set -euo pipefail
version=2.1.0
command -v python3 >/dev/null 2>&1 || { echo "asyncua-deps: python3 is not installed" >&2; exit 1; }
if python3 -c "import asyncua" >/dev/null 2>&1; then
    exit 0
fi
echo "asyncua-deps: installing asyncua $version with pip" >&2
python3 -m pip install --quiet "asyncua==$version" >&2 ||
    python3 -m pip install --quiet --user "asyncua==$version" >&2 ||
    python3 -m pip install --quiet --break-system-packages "asyncua==$version" >&2
python3 -c "import asyncua" >/dev/null 2>&1
