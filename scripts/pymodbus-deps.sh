#!/usr/bin/env bash
# pymodbus (PyPI): the Modbus client of the `sfc run` tests (crates/sfc-runtime/tests/modbus.rs,
# crates/sfc-cli/tests/run_plant.rs, opcua.rs). Pinned: pymodbus renames arguments between
# releases. scripts/test-deps.sh calls it; the tests call it too and skip, loudly, only when it
# fails.
exec bash "$(dirname "$0")/pip-deps.sh" pymodbus 3.16.1
