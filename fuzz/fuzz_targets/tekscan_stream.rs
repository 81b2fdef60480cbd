#![no_main]
//! Frame-by-frame TekScan reader (`presrs stream` on a file or stdin): keeps reading after errors
//! (it resynchronises on the next `Frame` line) as the CLI does, with a bound on the number of calls.
use libfuzzer_sys::fuzz_target;
use presrs_io::tekscan::TekscanStream;

fuzz_target!(|data: &[u8]| {
    let mut stream = TekscanStream::new(std::io::Cursor::new(data), "fuzz.asf");
    let (mut values, mut present) = (Vec::new(), Vec::new());
    for _ in 0..10_000 {
        match stream.next_frame(&mut values, &mut present) {
            Ok(Some(_)) => {}
            Ok(None) => break,
            Err(_) => {
                if stream.header().is_none() {
                    break;
                }
            }
        }
    }
});
