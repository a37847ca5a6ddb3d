//! Code generation from the chart model: REX ATMT/EATMT transition tables (`atmt`), IEC
//! Structured Text (`st`) and Siemens S7-200 statement list (`stl`).

pub mod atmt;
pub mod st;
pub mod stl;
