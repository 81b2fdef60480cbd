//! What the command line prints: tables, documents and log lines made from the library's values.

pub mod stream_log;
