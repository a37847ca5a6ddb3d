#!/usr/bin/env bash
# asyncua (PyPI): the independent OPC UA client of crates/sfc-cli/tests/opcua.rs.
# scripts/test-deps.sh calls it; the tests call it too and skip, loudly, only when it fails.
exec bash "$(dirname "$0")/pip-deps.sh" asyncua 2.1.0
