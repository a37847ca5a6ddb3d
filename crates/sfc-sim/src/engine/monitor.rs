//! What a runtime and its monitor need from a simulation beyond the scan itself (used by
//! `sfc-runtime`): forced variables, guard values, elapsed step times and located variables.
