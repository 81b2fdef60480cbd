#![no_main]
//! Dataset manifest (CSV) reader.
use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = presrs_io::manifest::parse_manifest(data, Path::new("fuzz.csv"), Path::new("/nonexistent"));
});
