//! What the track runner and the gait table share: seeding their random streams and the fall test.

use crate::slip::Hopper;

/// SplitMix64 step.
pub(super) fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// FNV-1a hash of a name.
pub(super) fn name_hash(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Whether the hop just done left the hopper in a state it cannot go on from: moving backwards at the
/// apex (it bounced back off its foot).
pub(super) fn went_backwards(hopper: &Hopper) -> bool {
    hopper.state[2] <= 0.0
}
