//! What a reader is told ([`ReadOptions`]) and what it gives back ([`Parsed`]): a leaf module, so that
//! the readers and the crate root that dispatches to them do not import each other.

use presrs_core::Recording;

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// Accept a TekScan file whose last frame is truncated (or that ends before `END_FRAME`): the
    /// incomplete frame is dropped and reported in [`Parsed::warnings`] instead of being an error. Also
    /// accept `Frame` numbers that repeat or go back (reported in the warnings, the frames kept).
    pub lenient: bool,
}

impl ReadOptions {
    /// Options for lenient reading (see [`ReadOptions::lenient`]).
    pub fn lenient() -> Self {
        Self { lenient: true }
    }
}

/// A recording read from a file, with what the reader had to say about it.
#[derive(Clone, Debug, PartialEq)]
pub struct Parsed {
    pub recording: Recording,
    /// Problems that did not stop reading, each naming the file and line (a dropped truncated frame, a
    /// header value that was not understood and was kept verbatim, a frame count that disagrees with
    /// `START_FRAME`/`END_FRAME`, a jump in the frame numbers, ...). Empty for a clean file.
    pub warnings: Vec<String>,
}
