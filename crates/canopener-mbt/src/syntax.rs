//! The model language as written: tokens, the syntax tree and the parser.

pub mod ast;
pub(crate) mod lexer;
pub mod parser;
