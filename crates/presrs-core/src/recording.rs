//! A recording ("movie"): a sequence of frames on one sensor, with the sensor's metadata.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::{Frame, FrameView, Grid};

/// The unit of the values in a recording.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum PressureUnit {
    /// Raw sensor counts (8-bit TekScan: 0-255).
    #[default]
    Raw,
    KPa,
    MPa,
    Psi,
    /// A unit we do not know how to convert, kept verbatim.
    Other(String),
}

impl PressureUnit {
    /// Parses a TekScan `UNITS` value (case-insensitive: `raw`, `KPa`, `MPa`, `PSI`); anything else is kept.
    pub fn parse(text: &str) -> Self {
        match text.trim().to_ascii_lowercase().as_str() {
            "raw" | "" => Self::Raw,
            "kpa" => Self::KPa,
            "mpa" => Self::MPa,
            "psi" => Self::Psi,
            _ => Self::Other(text.trim().to_owned()),
        }
    }

    /// The spelling TekScan software writes.
    pub fn as_tekscan(&self) -> &str {
        match self {
            Self::Raw => "raw",
            Self::KPa => "KPa",
            Self::MPa => "MPa",
            Self::Psi => "PSI",
            Self::Other(text) => text,
        }
    }

    /// Factor converting a value in this unit to kilopascals, when it is a pressure unit.
    pub fn kpa_per_unit(&self) -> Option<f64> {
        match self {
            Self::KPa => Some(1.0),
            Self::MPa => Some(1000.0),
            Self::Psi => Some(6.894_757_293_168),
            Self::Raw | Self::Other(_) => None,
        }
    }
}

impl std::fmt::Display for PressureUnit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_tekscan())
    }
}

/// What is known about the sensor that made a recording. Every field is optional because real files carry
/// anything from a full header to nothing at all.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
pub struct SensorMeta {
    /// Sensor model (TekScan `SENSOR_TYPE`, e.g. `5051`).
    pub sensor: Option<String>,
    /// Distance between sensel centres along a column (between rows), millimetres.
    pub row_pitch_mm: Option<f64>,
    /// Distance between sensel centres along a row (between columns), millimetres.
    pub col_pitch_mm: Option<f64>,
    /// The unit of the values, when the source states one (TekScan `UNITS`). `None` (a TekScan export
    /// without a `UNITS` line, an image, an array, a text matrix): the values are taken as raw counts,
    /// see [`units_or_raw`](Self::units_or_raw), and tools say that this was assumed.
    pub units: Option<PressureUnit>,
    /// Value that corresponds to the sensor's full scale, in `units` (255 for 8-bit raw counts).
    pub full_scale: Option<f64>,
    /// Readings at or below this value are reported as zero by the acquisition software.
    pub noise_threshold: Option<f64>,
    /// Every other header field, in file order, kept verbatim so that a file can be written back.
    /// Keys are the first token of a header line; a free-text line is stored with an empty value.
    pub extra: Vec<(String, String)>,
}

impl SensorMeta {
    /// The unit of the values: the stated one, or raw counts when the source states none.
    pub fn units_or_raw(&self) -> &PressureUnit {
        self.units.as_ref().unwrap_or(&PressureUnit::Raw)
    }
}

/// Per-frame bookkeeping kept for round-tripping TekScan files.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameInfo {
    /// The frame number as written in the file (`Frame N`); TekScan numbers from `START_FRAME`.
    pub number: i64,
    /// Text after the number on the `Frame` line, verbatim (e.g. `, timestamp 728`), if any.
    pub suffix: Option<String>,
}

/// A sequence of equally sized frames stored contiguously (`frames x rows x cols`, row-major).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Recording {
    grid: Grid,
    /// Seconds between frames, when known.
    frame_period_s: Option<f64>,
    /// Sensels that exist (`None`: all). The same for every frame.
    present: Option<Vec<bool>>,
    data: Vec<f64>,
    info: Vec<FrameInfo>,
    pub meta: SensorMeta,
}

impl Recording {
    /// Builds a recording from contiguous data (`frames * rows * cols` values). Frames are numbered from 1.
    pub fn new(
        grid: Grid,
        frame_period_s: Option<f64>,
        data: Vec<f64>,
        present: Option<Vec<bool>>,
        meta: SensorMeta,
    ) -> Result<Self> {
        let frames = if grid.is_empty() {
            0
        } else {
            data.len() / grid.len()
        };
        let info = (1..=frames as i64)
            .map(|number| FrameInfo {
                number,
                suffix: None,
            })
            .collect();
        Self::with_info(grid, frame_period_s, data, present, info, meta)
    }

    /// Builds a recording with explicit per-frame bookkeeping (one [`FrameInfo`] per frame).
    pub fn with_info(
        grid: Grid,
        frame_period_s: Option<f64>,
        mut data: Vec<f64>,
        present: Option<Vec<bool>>,
        info: Vec<FrameInfo>,
        meta: SensorMeta,
    ) -> Result<Self> {
        if grid.is_empty() {
            return Err(CoreError::Param {
                name: "grid",
                reason: format!("a recording needs at least one sensel, got {grid}"),
            });
        }
        if data.len() != info.len() * grid.len() {
            return Err(CoreError::Shape {
                what: "recording data",
                expected: format!(
                    "{} frames x {grid} = {}",
                    info.len(),
                    info.len() * grid.len()
                ),
                got: data.len().to_string(),
            });
        }
        if let Some(period) = frame_period_s
            && !(period.is_finite() && period > 0.0)
        {
            return Err(CoreError::Param {
                name: "frame_period_s",
                reason: format!("must be a positive number of seconds, got {period}"),
            });
        }
        let present = match present {
            Some(mask) if mask.len() != grid.len() => {
                return Err(CoreError::Shape {
                    what: "recording mask",
                    expected: grid.len().to_string(),
                    got: mask.len().to_string(),
                });
            }
            Some(mask) if mask.iter().all(|&here| here) => None,
            other => other,
        };
        if let Some(mask) = &present {
            for frame in data.chunks_exact_mut(grid.len()) {
                for (value, &here) in frame.iter_mut().zip(mask) {
                    if !here {
                        *value = 0.0;
                    }
                }
            }
        }
        Ok(Self {
            grid,
            frame_period_s,
            present,
            data,
            info,
            meta,
        })
    }

    /// A one-frame recording. Fails, as [`with_info`](Self::with_info) does, for a frame without any
    /// sensel.
    pub fn from_frame(frame: Frame, meta: SensorMeta) -> Result<Self> {
        let grid = frame.grid();
        let present = frame.present().map(<[bool]>::to_vec);
        let info = vec![FrameInfo {
            number: 1,
            suffix: None,
        }];
        Self::with_info(grid, None, frame.into_values(), present, info, meta)
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    pub fn frame_count(&self) -> usize {
        self.info.len()
    }

    pub fn frame_period_s(&self) -> Option<f64> {
        self.frame_period_s
    }

    /// Gives the recording a frame period when its format states none (`--frame-period`, a manifest's
    /// `frame_period_s`); one the file states is kept. A period that is not a positive number of seconds
    /// is an error.
    pub fn set_frame_period_if_unknown(&mut self, period_s: f64) -> Result<()> {
        if !(period_s.is_finite() && period_s > 0.0) {
            return Err(CoreError::Param {
                name: "frame_period_s",
                reason: format!("must be a positive number of seconds, got {period_s}"),
            });
        }
        self.frame_period_s.get_or_insert(period_s);
        Ok(())
    }

    pub fn present(&self) -> Option<&[bool]> {
        self.present.as_deref()
    }

    pub fn frame_info(&self) -> &[FrameInfo] {
        &self.info
    }

    /// All values, `frames x rows x cols`, row-major.
    pub fn data(&self) -> &[f64] {
        &self.data
    }

    /// Frame `index` (0-based), or `None` past the end.
    pub fn frame(&self, index: usize) -> Option<FrameView<'_>> {
        let len = self.grid.len();
        let start = index.checked_mul(len)?;
        let values = self.data.get(start..start.checked_add(len)?)?;
        FrameView::new(self.grid, values, self.present.as_deref()).ok()
    }

    pub fn frames(&self) -> impl ExactSizeIterator<Item = FrameView<'_>> + '_ {
        let present = self.present.as_deref();
        let grid = self.grid;
        self.data.chunks_exact(grid.len()).map(move |values| {
            FrameView::new(grid, values, present).unwrap_or_else(|_| unreachable!())
        })
    }

    /// Total load per frame (sum of values), the signal stance segmentation works on.
    pub fn total_per_frame(&self) -> Vec<f64> {
        self.data
            .chunks_exact(self.grid.len())
            .map(|frame| frame.iter().sum())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_contiguous_row_major() {
        let grid = Grid::new(2, 2);
        let rec = Recording::new(
            grid,
            Some(0.01),
            vec![1., 2., 3., 4., 5., 6., 7., 8.],
            None,
            SensorMeta::default(),
        )
        .unwrap();
        assert_eq!(rec.frame_count(), 2);
        assert_eq!(rec.frame(1).unwrap().get(1, 0), 7.0);
        assert!(rec.frame(2).is_none());
        assert_eq!(rec.total_per_frame(), vec![10.0, 26.0]);
        assert_eq!(rec.frame_info()[1].number, 2);
    }

    #[test]
    fn rejects_ragged_data_and_bad_period() {
        let grid = Grid::new(2, 2);
        assert!(Recording::new(grid, None, vec![0.0; 7], None, SensorMeta::default()).is_err());
        assert!(
            Recording::new(grid, Some(0.0), vec![0.0; 8], None, SensorMeta::default()).is_err()
        );
    }

    #[test]
    fn a_recording_needs_a_sensel_and_far_indices_are_none() {
        for grid in [Grid::new(0, 3), Grid::new(3, 0)] {
            let err = Recording::from_frame(Frame::zeros(grid), SensorMeta::default()).unwrap_err();
            assert!(err.to_string().contains("at least one sensel"), "{err}");
        }
        let frame = Frame::new(Grid::new(1, 2), vec![4.0, 5.0]).unwrap();
        let rec = Recording::from_frame(frame, SensorMeta::default()).unwrap();
        assert_eq!(rec.frame_count(), 1);
        assert_eq!(rec.total_per_frame(), vec![9.0]);
        assert_eq!(rec.frame(0).unwrap().values(), &[4.0, 5.0]);
        // index * len overflows: past the end, not a panic or a wrapped slice.
        assert!(rec.frame(usize::MAX).is_none());
        assert!(rec.frame(usize::MAX / 2 + 1).is_none());
    }

    #[test]
    fn unit_conversion() {
        assert_eq!(PressureUnit::parse("KPa"), PressureUnit::KPa);
        assert_eq!(PressureUnit::parse(" psi "), PressureUnit::Psi);
        assert_eq!(
            PressureUnit::parse("N/cm2"),
            PressureUnit::Other("N/cm2".into())
        );
        assert_eq!(PressureUnit::MPa.kpa_per_unit(), Some(1000.0));
    }
}
