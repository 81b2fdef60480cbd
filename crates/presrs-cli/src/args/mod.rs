//! Option parsing shared by the commands: option values checked from their text (clap's value parsers,
//! whose errors clap reports with exit code 2).

pub mod values;
