//! What the commands print, one file per table, document or log: each takes the libraries' results and
//! returns text or a document to serialise, or writes its table to the command's output. Nothing here
//! decides anything: the workflows are `presrs`'s.

pub mod classify_document;
pub mod early_table;
pub mod eval_tables;
pub mod feature_csv;
pub mod inspect_table;
pub mod novelty_table;
pub mod profile_summary;
pub mod progress_lines;
pub mod reproduce_tables;
pub mod selection_table;
pub mod stream_log;
