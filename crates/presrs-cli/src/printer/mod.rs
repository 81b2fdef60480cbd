//! What the commands print, one file per table, document or log: each takes the libraries' results and
//! returns text (or a document to serialise); the commands write it.

pub mod classify_document;
pub mod eval_tables;
pub mod feature_csv;
pub mod profile_summary;
pub mod progress_lines;
pub mod selection_table;
pub mod stream_log;
