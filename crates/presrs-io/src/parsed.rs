//! What a reader is told ([`ReadOptions`]) and what it gives back ([`Parsed`]): a leaf module, so that
//! the readers and the crate root that dispatches to them do not import each other.

use presrs_core::Recording;

use crate::message::Warnings;

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// Accept a TekScan file whose last frame is truncated (or that ends before `END_FRAME`): the
    /// incomplete frame is dropped and reported in [`Parsed::warnings`] instead of being an error. Also
    /// accept `Frame` numbers that repeat or go back (reported in the warnings, the frames kept).
    pub lenient: bool,
    /// What the axes of a 3-D array (`.npy`) are, in the file's order. `None`: frames x rows x cols,
    /// with a warning when the shape looks like rows x cols x frames (see [`crate::npy`]).
    pub axes: Option<ArrayAxes>,
    /// The topic of an MCAP file to read (`None`: the only topic holding frames).
    pub topic: Option<String>,
}

impl ReadOptions {
    /// Options for lenient reading (see [`ReadOptions::lenient`]).
    pub fn lenient() -> Self {
        Self {
            lenient: true,
            ..Self::default()
        }
    }
}

/// One axis of a 3-D array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    Frames,
    Rows,
    Cols,
}

impl Axis {
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Frames => "frames",
            Self::Rows => "rows",
            Self::Cols => "cols",
        }
    }
}

/// What each axis of a 3-D array is, in the file's order: `frames,rows,cols` (the default) or
/// `rows,cols,frames` (the time axis last, as some exporters write), or any other order of the three.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArrayAxes(pub [Axis; 3]);

impl Default for ArrayAxes {
    fn default() -> Self {
        Self([Axis::Frames, Axis::Rows, Axis::Cols])
    }
}

impl ArrayAxes {
    /// The position in the file's order of the axis that is `axis`.
    pub fn position(self, axis: Axis) -> usize {
        self.0.iter().position(|&a| a == axis).unwrap_or(0)
    }
}

impl std::fmt::Display for ArrayAxes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [a, b, c] = self.0.map(Axis::as_str);
        write!(f, "{a},{b},{c}")
    }
}

impl std::str::FromStr for ArrayAxes {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let expected = || {
            format!(
                "expected the three axes in the file's order, each once, e.g. frames,rows,cols or \
                 rows,cols,frames; got {text:?}"
            )
        };
        let axes: Vec<Axis> = text
            .split(',')
            .map(|word| match word.trim().to_ascii_lowercase().as_str() {
                "frames" | "frame" | "time" => Ok(Axis::Frames),
                "rows" | "row" => Ok(Axis::Rows),
                "cols" | "col" | "columns" => Ok(Axis::Cols),
                _ => Err(expected()),
            })
            .collect::<Result<_, _>>()?;
        let order: [Axis; 3] = axes.try_into().map_err(|_| expected())?;
        let each_once = [Axis::Frames, Axis::Rows, Axis::Cols]
            .iter()
            .all(|axis| order.contains(axis));
        if !each_once {
            return Err(expected());
        }
        Ok(Self(order))
    }
}

/// A recording read from a file, with what the reader had to say about it.
#[derive(Clone, Debug, PartialEq)]
pub struct Parsed {
    pub recording: Recording,
    /// Problems that did not stop reading, each naming the file and line (a dropped truncated frame, a
    /// header value that was not understood and was kept verbatim, a frame count that disagrees with
    /// `START_FRAME`/`END_FRAME`, a jump in the frame numbers, ...). Empty for a clean file.
    pub warnings: Warnings,
}
