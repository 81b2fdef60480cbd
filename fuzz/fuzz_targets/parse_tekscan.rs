#![no_main]
//! TekScan ASCII reader, strict and lenient, on arbitrary bytes decoded as the CLI decodes files.
use libfuzzer_sys::fuzz_target;
use presrs_io::ReadOptions;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = presrs_io::parse_tekscan(&text, "fuzz.asf", &ReadOptions::default());
    let _ = presrs_io::parse_tekscan(&text, "fuzz.asf", &ReadOptions::lenient());
});
