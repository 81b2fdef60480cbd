//! Messages taken off the wire as they came: their CDR bytes, so that the frames are decoded by the
//! same code as a bag's (`presrs_io::mcap::decode_frame`), not by a second decoder.

use std::convert::Infallible;

use ros2_client::dds::rustdds::RepresentationIdentifier;
use ros2_client::dds::rustdds::no_key::{Decode, DefaultDecoder, DeserializerAdapter};

/// One message's CDR bytes, its 4-byte encapsulation header first (as a bag stores them).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawCdr(pub Vec<u8>);

/// The RustDDS adapter that keeps a message's bytes instead of deserializing them.
#[derive(Clone, Copy, Debug)]
pub struct RawAdapter;

/// The decoder of [`RawAdapter`]: puts the encapsulation header back in front of the payload.
#[derive(Clone, Copy, Debug)]
pub struct RawDecoder;

/// Plain CDR and XCDR2 in either byte order: `presrs_io::mcap` reads them all (they agree for the
/// messages it reads, which have no 8-byte fields).
const ENCODINGS: [RepresentationIdentifier; 6] = [
    RepresentationIdentifier::CDR_LE,
    RepresentationIdentifier::CDR_BE,
    RepresentationIdentifier::XCDR2_LE,
    RepresentationIdentifier::XCDR2_BE,
    RepresentationIdentifier::CDR2_LE,
    RepresentationIdentifier::CDR2_BE,
];

impl DeserializerAdapter<RawCdr> for RawAdapter {
    type Error = Infallible;
    type Decoded = RawCdr;

    fn supported_encodings() -> &'static [RepresentationIdentifier] {
        &ENCODINGS
    }

    fn transform_decoded(decoded: RawCdr) -> RawCdr {
        decoded
    }
}

impl DefaultDecoder<RawCdr> for RawAdapter {
    type Decoder = RawDecoder;
    const DECODER: RawDecoder = RawDecoder;
}

impl Decode<'_, RawCdr> for RawDecoder {
    type Error = Infallible;

    fn decode_bytes(
        self,
        input_bytes: &[u8],
        encoding: RepresentationIdentifier,
    ) -> Result<RawCdr, Infallible> {
        let mut bytes = Vec::with_capacity(input_bytes.len() + 4);
        bytes.extend_from_slice(&encoding.to_bytes());
        bytes.extend_from_slice(&[0, 0]);
        bytes.extend_from_slice(input_bytes);
        Ok(RawCdr(bytes))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use presrs_io::mcap::{FrameType, Image, Stamp, decode_frame, encode_image};

    #[test]
    fn a_payload_with_its_header_put_back_decodes_as_a_bag_message() {
        let data = [1u8, 0, 2, 0, 3, 0, 4, 0];
        let image = Image {
            stamp: Stamp { sec: 3, nanosec: 7 },
            frame_id: "foot".to_owned(),
            height: 2,
            width: 2,
            encoding: "mono16".to_owned(),
            is_bigendian: false,
            step: 4,
            data: &data,
        };
        let wire = encode_image(&image);
        let raw = RawDecoder
            .decode_bytes(&wire[4..], RepresentationIdentifier::CDR_LE)
            .unwrap();
        assert_eq!(raw.0, wire);
        let mut values = Vec::new();
        let (grid, stamp) = decode_frame(FrameType::Image, &raw.0, &mut values).unwrap();
        assert_eq!((grid.rows, grid.cols), (2, 2));
        assert_eq!(values, [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(stamp, Some(image.stamp));
    }
}
