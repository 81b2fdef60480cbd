#![no_main]
//! MCAP files (ROS 2 bags): the reader of `presrs` commands and `stream --format mcap`, and the CDR
//! decoding of each message type on raw bytes. The first byte picks a topic to ask for.
use libfuzzer_sys::fuzz_target;
use presrs_io::mcap::{FrameType, MCAP_MAGIC, decode_frame, list_topics, parse_mcap};

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let topic = [None, Some("/foot"), Some("/left")][usize::from(pick) % 3];
    let _ = parse_mcap(rest, "f.mcap", topic);
    let _ = list_topics(rest, "f.mcap");
    // The magic prepended: past the first check.
    let with_magic = [MCAP_MAGIC, rest].concat();
    let _ = parse_mcap(with_magic.as_slice(), "f.mcap", topic);
    let mut values = Vec::new();
    for kind in [
        FrameType::Image,
        FrameType::Float32MultiArray,
        FrameType::UInt16MultiArray,
    ] {
        let _ = decode_frame(kind, rest, &mut values);
    }
});
