#![no_main]
//! Binary stream protocol decoder (`presrs stream --listen`): reads messages until the end or a fatal
//! error, continuing after skipped ones, as the server does.
use libfuzzer_sys::fuzz_target;
use presrs_io::frame_protocol::FrameReader;

fuzz_target!(|data: &[u8]| {
    let mut reader = FrameReader::new("fuzz", 1 << 16);
    let mut cursor = std::io::Cursor::new(data);
    let mut values = Vec::new();
    loop {
        match reader.read_frame(&mut cursor, &mut values) {
            Ok(Some(header)) => assert_eq!(values.len(), header.rows * header.cols),
            Ok(None) => break,
            Err(err) if err.is_fatal() => break,
            Err(_) => {}
        }
    }
});
