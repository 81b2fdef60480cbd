#![no_main]
//! Plain text matrix reader.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = presrs_io::text::parse_text_matrix(&text, "fuzz.txt");
});
