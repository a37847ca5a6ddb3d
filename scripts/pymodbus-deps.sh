#!/usr/bin/env bash
# Makes sure `python3 -c "import pymodbus"` works: installs pymodbus from PyPI with pip when it
# is missing. The Modbus end-to-end test of `sfc run` (crates/sfc-runtime/tests/modbus.rs) calls
# it and skips, loudly, only when this script fails.
set -euo pipefail
# Pinned: the version the tests were written against (pymodbus renames arguments between releases).
version=3.16.1
command -v python3 >/dev/null 2>&1 || { echo "pymodbus-deps: python3 is not installed" >&2; exit 1; }
if python3 -c "import pymodbus" >/dev/null 2>&1; then
    exit 0
fi
echo "pymodbus-deps: installing pymodbus $version with pip" >&2
python3 -m pip install --quiet "pymodbus==$version" >&2 ||
    python3 -m pip install --quiet --user "pymodbus==$version" >&2 ||
    python3 -m pip install --quiet --break-system-packages "pymodbus==$version" >&2
python3 -c "import pymodbus" >/dev/null 2>&1
