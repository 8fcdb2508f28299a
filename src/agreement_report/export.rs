//! The report bundle files.
