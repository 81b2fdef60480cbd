#![no_main]
//! PNG reader. The signature is prepended so that the fuzzer explores the chunks.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut bytes = presrs_io::png::PNG_MAGIC.to_vec();
    bytes.extend_from_slice(data);
    let _ = presrs_io::png::parse_png(&bytes, "fuzz.png");
});
