#!/usr/bin/env bash
# o6 (PyPI): an OPC UA client for Python built on open62541, the second independent OPC UA
# stack of crates/sfc-cli/tests/opcua.rs besides asyncua. Its free "script mode" ends a process
# after 10 minutes: the soak test restarts its o6 sessions before that. scripts/test-deps.sh
# calls it; the tests call it too and skip, loudly, only when it fails.
exec bash "$(dirname "$0")/pip-deps.sh" o6 2.2.0
