#!/usr/bin/env bash
# Makes sure `python3 -c "import o6"` works: installs o6 (an OPC UA client for Python built on
# open62541, the second independent OPC UA stack of crates/sfc-cli/tests/opcua.rs besides
# asyncua) from PyPI with pip when it is missing. scripts/test-deps.sh calls it; the tests call
# it too and skip, loudly, only when this script fails. Pinned to the version the tests were
# written against. o6's free "script mode" ends a process after 10 minutes: the soak test
# restarts its o6 sessions before that.
set -euo pipefail
version=2.2.0
command -v python3 >/dev/null 2>&1 || { echo "o6-deps: python3 is not installed" >&2; exit 1; }
if python3 -c "import o6" >/dev/null 2>&1; then
    exit 0
fi
echo "o6-deps: installing o6 $version with pip" >&2
python3 -m pip install --quiet "o6==$version" >&2 ||
    python3 -m pip install --quiet --user "o6==$version" >&2 ||
    python3 -m pip install --quiet --break-system-packages "o6==$version" >&2
python3 -c "import o6" >/dev/null 2>&1
