#!/usr/bin/env bash
# Installs the programs the test suite calls besides cargo and npm, when they are missing:
#   xmllint (Debian libxml2-utils) validates every PLCopen export against the TC6 v2.01 schema
#   and `sfc test --junit` output against the JUnit schema;
#   chromium (Debian) runs the editor's browser tests (Playwright drives it; browsers cannot be
#   downloaded here, so Debian's build is used);
#   python3-jsonschema validates `sfc check --format sarif` against the SARIF 2.1.0 JSON
#   schema, which the npm package @microsoft/jest-sarif ships (fetched with `npm pack` into
#   target/test-tools/, only the schema is kept).
#   unzip lists the VS Code extension's .vsix (scripts/test-vscode.sh checks what it holds).
#   python3 counts the steps, transitions and actions of the PLCopen corpus independently of the
#   importer (tests/corpus/real/count.py, standard library only).
#   MatIEC's iec2c and STruC++ (../shared/tools: source snapshots and their build scripts, which
#   install what they need) compile the ST of `sfc build --target st` in
#   crates/sfc-cli/tests/st_compilers.rs; built once into target/tools/ (a few minutes the
#   first time; the test builds them the same way when they are missing).
# Part of the README's test command, so a fresh machine needs no manual step.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
need=()
command -v xmllint >/dev/null 2>&1 || need+=(libxml2-utils)
command -v python3 >/dev/null 2>&1 || need+=(python3)
command -v unzip >/dev/null 2>&1 || need+=(unzip)
[ -x /usr/bin/chromium ] || need+=(chromium)
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then need+=(nodejs npm); fi
python3 -c 'import jsonschema' >/dev/null 2>&1 || need+=(python3-jsonschema)
if [ ${#need[@]} -gt 0 ]; then
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
fi
tools="$root/target/test-tools"
schema="$tools/sarif-schema-2.1.0.json"
if [ ! -s "$schema" ]; then
    mkdir -p "$tools"
    tmp="$(mktemp -d)"
    trap 'rm -rf "$tmp"' EXIT
    echo "test-deps: fetching the SARIF 2.1.0 schema (npm package @microsoft/jest-sarif)" >&2
    (cd "$tmp" && npm pack --silent @microsoft/jest-sarif@1.0.0-beta.0 >/dev/null &&
        tar -xzf microsoft-jest-sarif-1.0.0-beta.0.tgz package/lib/schemas/sarif-2.1.0-rtm.5.json)
    cp "$tmp/package/lib/schemas/sarif-2.1.0-rtm.5.json" "$schema"
fi
# asyncua (PyPI): the independent OPC UA client of crates/sfc-cli/tests/opcua.rs.
bash "$root/scripts/asyncua-deps.sh" || echo "test-deps: asyncua could not be installed: the OPC UA end-to-end test will skip" >&2
# pymodbus and o6 (PyPI): a Modbus client, and the OPC UA client on open62541 (the second stack).
bash "$root/scripts/pymodbus-deps.sh" || echo "test-deps: pymodbus could not be installed: the Modbus client tests will skip" >&2
bash "$root/scripts/o6-deps.sh" || echo "test-deps: o6 could not be installed: the open62541 OPC UA tests will skip" >&2
# The compilers of crates/sfc-cli/tests/st_compilers.rs: MatIEC (needs autoconf, bison, flex,
# g++: its script installs them) and STruC++ (npm packages from the registry).
shared="$root/../shared/tools"
[ -d "$shared" ] || { echo "test-deps: $shared is missing: the ST compiler test needs MatIEC and STruC++ from it" >&2; exit 1; }
bash "$shared/build-matiec.sh" "$root/target/tools/matiec" >/dev/null ||
    { echo "test-deps: MatIEC could not be built (see above)" >&2; exit 1; }
bash "$shared/build-strucpp.sh" "$root/target/tools/strucpp" >/dev/null ||
    { echo "test-deps: STruC++ could not be built (see above)" >&2; exit 1; }
