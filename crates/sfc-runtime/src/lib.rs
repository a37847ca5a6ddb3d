//! The soft-PLC of `sfc run`: the chart scanned on the wall clock with the `iec` semantics,
//! Modbus TCP I/O, and the monitor protocol (`docs/monitor.md`).
