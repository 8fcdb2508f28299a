//! The use cases: one function each, called alike by the web handlers and the command line.
//! They own the transactions and the decisions; the store only maps rows.

pub mod import;
