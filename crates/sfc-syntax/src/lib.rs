//! The syntax layer of sfc: lexer, parser and canonical printer for IEC 61131-3 source files
//! (POUs with SFC, ST and IL bodies). It depends on no other sfc crate but the diagnostics, and
//! never panics: every function returns a result plus located diagnostics.

pub mod ast;
pub mod attr_value;
pub mod encoding;
pub mod keywords;
pub mod lexer;
pub mod literal;
mod parser;
pub mod print;
pub mod regions;
pub mod visit;

pub use parser::{parse, parse_expression, parse_statements, MAX_DEPTH, MAX_STMT_DEPTH};
