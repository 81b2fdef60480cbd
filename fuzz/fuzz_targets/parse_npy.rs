#![no_main]
//! NumPy reader. The magic bytes are prepended so that the fuzzer explores the header and data.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut bytes = presrs_io::npy::NPY_MAGIC.to_vec();
    bytes.extend_from_slice(data);
    let _ = presrs_io::npy::parse_npy(&bytes, "fuzz.npy");
    let _ = presrs_io::npy::parse_npy(data, "fuzz.npy");
});
