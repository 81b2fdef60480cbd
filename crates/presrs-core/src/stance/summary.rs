//! A whole stance as a few channels over time: the sample of `--sample stance`.
//!
//! The paper judges a stance by one frame. How the foot loads and unloads over the stance (how fast the
//! load rises, how the centre of pressure rolls, how long contact lasts) carries the ground's compliance
//! and the gait, so a stance's movie is summarised frame by frame into channels:
//!
//! - `load`: the total load of the frame (the recording's units);
//! - `area`: the number of sensels above a contact level (a fraction of the stance's highest sensel, so
//!   that it does not depend on the sensor's units);
//! - `cop_row`, `cop_col`: the centre of pressure, as a fraction of the grid's height and width (0 when
//!   the frame carries no load);
//! - `region_r{i}_c{j}`: the load in each block of a `region_rows x region_cols` grid laid over the frame
//!   (the default 4 x 2: heel, midfoot, forefoot and toes along a foot, each split medial and lateral,
//!   whatever way the foot lies on the array, so that the roll of the load shows).
//!
//! The result is a `channels x frames` matrix in physical time: one column per recorded frame, not
//! resampled, so a stance's duration is kept. [`pad_to`] lays stances of different lengths into the
//! fixed length a model takes: shorter ones padded with zeros after lift-off (no load), longer ones cut
//! to their first frames, which the caller reports.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::{Frame, FrameView, Grid};

/// How a stance is summarised.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SummaryConfig {
    /// Blocks along the rows of the frame.
    pub region_rows: usize,
    /// Blocks along the columns.
    pub region_cols: usize,
    /// A sensel is in contact above this fraction of the stance's highest sensel.
    pub contact_fraction: f64,
}

impl Default for SummaryConfig {
    fn default() -> Self {
        Self {
            region_rows: 4,
            region_cols: 2,
            contact_fraction: 0.05,
        }
    }
}

/// Channels before the regions: load, area, cop_row, cop_col.
const FIXED_CHANNELS: usize = 4;

impl SummaryConfig {
    /// Checks the settings against the frames' grid.
    pub fn check(&self, grid: Grid) -> Result<()> {
        let bad = |reason: String| {
            Err(CoreError::Param {
                name: "stance summary",
                reason,
            })
        };
        if self.region_rows == 0 || self.region_cols == 0 {
            return bad("the grid of regions needs at least one row and one column".into());
        }
        if self.region_rows > grid.rows || self.region_cols > grid.cols {
            return bad(format!(
                "a {} x {} grid of regions does not fit {grid} frames",
                self.region_rows, self.region_cols
            ));
        }
        if !(self.contact_fraction.is_finite() && (0.0..1.0).contains(&self.contact_fraction)) {
            return bad(format!(
                "the contact fraction must be in [0, 1), got {}",
                self.contact_fraction
            ));
        }
        Ok(())
    }

    /// Number of channels.
    pub fn channels(&self) -> usize {
        FIXED_CHANNELS + self.region_rows * self.region_cols
    }

    /// The name of each channel, in order.
    pub fn channel_names(&self) -> Vec<String> {
        let mut names: Vec<String> = ["load", "area", "cop_row", "cop_col"]
            .map(String::from)
            .to_vec();
        for i in 0..self.region_rows {
            names.extend((0..self.region_cols).map(|j| format!("region_r{i}_c{j}")));
        }
        names
    }
}

/// The block of `index` along a side of `len` cut into `blocks` (the first blocks one longer when it
/// does not divide).
fn block_of(index: usize, len: usize, blocks: usize) -> usize {
    (index * blocks / len).min(blocks - 1)
}

/// The summary of one stance's frames (touchdown to lift-off), `channels x frames.len()` as a frame
/// whose rows are the channels. Absent sensels count as no load. Errors on no frames, frames of
/// different grids, or a value that is not finite (naming the frame).
pub fn summarise(frames: &[FrameView<'_>], config: &SummaryConfig) -> Result<Frame> {
    let first = frames.first().ok_or_else(|| CoreError::Param {
        name: "stance",
        reason: "a stance needs at least one frame".into(),
    })?;
    let grid = first.grid();
    config.check(grid)?;
    let size = grid.len();
    let mut loads = vec![0.0; size * frames.len()];
    let mut peak = 0.0_f64;
    for (index, (frame, frame_loads_out)) in
        frames.iter().zip(loads.chunks_exact_mut(size)).enumerate()
    {
        if frame.grid() != grid {
            return Err(CoreError::Shape {
                what: "stance frame",
                expected: grid.to_string(),
                got: format!("{} (frame {index} of the stance)", frame.grid()),
            });
        }
        if let Some(bad) = frame.values().iter().find(|v| !v.is_finite()) {
            return Err(CoreError::Param {
                name: "stance",
                reason: format!("frame {index} of the stance holds {bad}; values must be finite"),
            });
        }
        peak = peak.max(frame_loads(frame, frame_loads_out));
    }
    let contact_level = config.contact_fraction * peak;
    let length = frames.len();
    let channels = config.channels();
    let mut out = vec![0.0; channels * length];
    let mut column = vec![0.0; channels];
    let mut regions = vec![0.0; config.region_rows * config.region_cols];
    for (t, frame_loads) in loads.chunks_exact(size).enumerate() {
        loads_channels(frame_loads, grid, config, &mut regions, &mut column);
        column[AREA_CHANNEL] = contact_area(frame_loads, contact_level);
        for (channel, value) in column.iter().enumerate() {
            out[channel * length + t] = *value;
        }
    }
    Frame::new(Grid::new(config.channels(), length), out)
}

/// The index of the `area` channel: the one channel that depends on the whole stance (its contact
/// level is a fraction of the stance's highest sensel), so it is counted last ([`contact_area`]).
pub const AREA_CHANNEL: usize = 1;

/// Writes the load each sensel of `frame` counts with into `loads` (row-major, the frame's size): its
/// value, at least 0; 0 where absent. Returns the frame's highest value (absent sensels included, as
/// read), at least 0: a stance's contact level is `contact_fraction` times the highest of its frames'.
pub fn frame_loads(frame: &FrameView<'_>, loads: &mut [f64]) -> f64 {
    let mut peak = 0.0_f64;
    match frame.present() {
        None => {
            for (load, &value) in loads.iter_mut().zip(frame.values()) {
                peak = peak.max(value);
                *load = value.max(0.0);
            }
        }
        Some(present) => {
            for ((load, &value), &here) in loads.iter_mut().zip(frame.values()).zip(present) {
                peak = peak.max(value);
                *load = if here { value.max(0.0) } else { 0.0 };
            }
        }
    }
    peak
}

/// The sensels of `loads` (a frame's [`frame_loads`]) in contact: above `contact_level` and above 0.
pub fn contact_area(loads: &[f64], contact_level: f64) -> f64 {
    loads
        .iter()
        .filter(|&&value| value > contact_level && value > 0.0)
        .count() as f64
}

/// One frame's column of the summary from its [`frame_loads`] on `grid`: every channel but
/// [`AREA_CHANNEL`] (left 0), which depend on the frame alone, so an online summary computes them as
/// frames arrive. `regions` (one per region) and `column` ([`SummaryConfig::channels`] long) are the
/// caller's buffers; `grid` must have passed [`SummaryConfig::check`].
pub fn loads_channels(
    loads: &[f64],
    grid: Grid,
    config: &SummaryConfig,
    regions: &mut [f64],
    column: &mut [f64],
) {
    regions.fill(0.0);
    let (mut load, mut row_moment, mut col_moment) = (0.0, 0.0, 0.0);
    for (r, row) in loads.chunks_exact(grid.cols).take(grid.rows).enumerate() {
        let block_row = block_of(r, grid.rows, config.region_rows);
        let row_centre = r as f64 + 0.5;
        let mut c = 0;
        // Column block j spans the columns whose `block_of` is j, up to `ceil((j + 1) cols / blocks)`.
        for j in 0..config.region_cols {
            let end = ((j + 1) * grid.cols)
                .div_ceil(config.region_cols)
                .min(grid.cols);
            // The region's sum goes on in a register: the same additions in the same order.
            let region = &mut regions[block_row * config.region_cols + j];
            let mut sum = *region;
            for &value in &row[c..end] {
                load += value;
                row_moment += value * row_centre;
                col_moment += value * (c as f64 + 0.5);
                sum += value;
                c += 1;
            }
            *region = sum;
        }
    }
    let (cop_row, cop_col) = if load > 0.0 {
        (
            row_moment / load / grid.rows as f64,
            col_moment / load / grid.cols as f64,
        )
    } else {
        (0.0, 0.0)
    };
    let fixed = [load, 0.0, cop_row, cop_col];
    for (slot, value) in column
        .iter_mut()
        .zip(fixed.into_iter().chain(regions.iter().copied()))
    {
        *slot = value;
    }
}

/// `summary` (`channels x frames`) laid into `length` frames: zeros after the stance when it is
/// shorter, its first `length` frames when it is longer. Returns the frame and whether it was cut.
pub fn pad_to(summary: &FrameView<'_>, length: usize) -> Result<(Frame, bool)> {
    if length == 0 {
        return Err(CoreError::Param {
            name: "stance length",
            reason: "a stance sample needs at least one frame".into(),
        });
    }
    let Grid {
        rows: channels,
        cols: frames,
    } = summary.grid();
    let kept = frames.min(length);
    let mut out = vec![0.0; channels * length];
    for (dst, src) in out
        .chunks_exact_mut(length)
        .zip(summary.values().chunks_exact(frames.max(1)))
    {
        dst[..kept].copy_from_slice(&src[..kept]);
    }
    Ok((
        Frame::new(Grid::new(channels, length), out)?,
        frames > length,
    ))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// A frame of `grid` loaded `value` at (row, col) and nowhere else.
    fn point(grid: Grid, row: usize, col: usize, value: f64) -> Frame {
        let mut frame = Frame::zeros(grid);
        frame.values_mut()[row * grid.cols + col] = value;
        frame
    }

    /// The summary by its definition, sensel by sensel (the first implementation): the oracle of the
    /// split into per-frame loads, channels and area that the online path shares.
    fn summarise_by_definition(frames: &[FrameView<'_>], config: &SummaryConfig) -> Vec<f64> {
        let grid = frames[0].grid();
        let peak = frames
            .iter()
            .flat_map(|f| f.values().iter().copied())
            .fold(0.0_f64, f64::max);
        let contact_level = config.contact_fraction * peak;
        let length = frames.len();
        let mut out = vec![0.0; config.channels() * length];
        for (t, frame) in frames.iter().enumerate() {
            let mut regions = vec![0.0; config.region_rows * config.region_cols];
            let (mut load, mut area, mut row_moment, mut col_moment) = (0.0, 0.0, 0.0, 0.0);
            for r in 0..grid.rows {
                for c in 0..grid.cols {
                    let value = if frame.is_present(r, c) {
                        frame.get(r, c).max(0.0)
                    } else {
                        0.0
                    };
                    load += value;
                    area += f64::from(u8::from(value > contact_level && value > 0.0));
                    row_moment += value * (r as f64 + 0.5);
                    col_moment += value * (c as f64 + 0.5);
                    regions[block_of(r, grid.rows, config.region_rows) * config.region_cols
                        + block_of(c, grid.cols, config.region_cols)] += value;
                }
            }
            let (cop_row, cop_col) = if load > 0.0 {
                (
                    row_moment / load / grid.rows as f64,
                    col_moment / load / grid.cols as f64,
                )
            } else {
                (0.0, 0.0)
            };
            let column = [load, area, cop_row, cop_col].into_iter().chain(regions);
            for (channel, value) in column.enumerate() {
                out[channel * length + t] = value;
            }
        }
        out
    }

    /// Bit for bit the definition's, on grids that the regions do and do not divide, with absent
    /// sensels (holding values, as a view may) and negative readings.
    #[test]
    fn the_summary_is_its_definition_to_the_bit() {
        for (rows, cols, region_rows, region_cols) in [(8, 4, 4, 2), (9, 7, 4, 3), (13, 5, 2, 5)] {
            let grid = Grid::new(rows, cols);
            let config = SummaryConfig {
                region_rows,
                region_cols,
                contact_fraction: 0.05,
            };
            let values: Vec<Vec<f64>> = (0..6)
                .map(|t| {
                    (0..grid.len())
                        .map(|i| ((i * 37 + t * 11) % 23) as f64 * 1.37 - 4.0 + (i as f64).sin())
                        .collect()
                })
                .collect();
            let masks: Vec<Vec<bool>> = (0..6)
                .map(|t| (0..grid.len()).map(|i| (i + t) % 5 != 0).collect())
                .collect();
            let views: Vec<_> = values
                .iter()
                .zip(&masks)
                .enumerate()
                .map(|(t, (v, m))| {
                    FrameView::new(grid, v, (t % 2 == 0).then_some(m.as_slice())).unwrap()
                })
                .collect();
            let summary = summarise(&views, &config).unwrap();
            assert_eq!(
                summary.values(),
                summarise_by_definition(&views, &config),
                "{grid}"
            );
        }
    }

    #[test]
    fn channels_follow_their_definitions() {
        let grid = Grid::new(8, 4);
        let config = SummaryConfig::default();
        let mut frames = [
            point(grid, 1, 0, 10.0),
            point(grid, 6, 3, 30.0),
            Frame::zeros(grid),
        ];
        frames[1].values_mut()[0] = 1.0; // below 5 % of the peak 30: not in contact
        let views: Vec<_> = frames.iter().map(Frame::view).collect();
        let summary = summarise(&views, &config).unwrap();
        assert_eq!(summary.grid(), Grid::new(4 + 8, 3));
        let at = |channel: usize, t: usize| summary.values()[channel * 3 + t];
        assert_eq!((at(0, 0), at(0, 1), at(0, 2)), (10.0, 31.0, 0.0), "load");
        assert_eq!((at(1, 0), at(1, 1), at(1, 2)), (1.0, 1.0, 0.0), "area");
        assert!((at(2, 0) - 1.5 / 8.0).abs() < 1e-12, "cop row");
        assert!((at(3, 0) - 0.5 / 4.0).abs() < 1e-12, "cop col");
        assert!((at(2, 1) - (30.0 * 6.5 + 0.5) / 31.0 / 8.0).abs() < 1e-12);
        assert_eq!((at(2, 2), at(3, 2)), (0.0, 0.0), "no load, no centre");
        let names = config.channel_names();
        // Row 1 is in the first of four row blocks, column 0 in the first of two; (6, 3) in r3_c1.
        let region = |name: &str| names.iter().position(|n| n == name).unwrap();
        assert_eq!(at(region("region_r0_c0"), 0), 10.0);
        assert_eq!(at(region("region_r3_c1"), 1), 30.0);
        assert_eq!(at(region("region_r0_c0"), 1), 1.0);
        let regions_sum: f64 = (4..12).map(|c| at(c, 1)).sum();
        assert_eq!(regions_sum, at(0, 1), "the regions share the load");
    }

    #[test]
    fn padding_keeps_the_stance_and_cuts_long_ones() {
        let summary = Frame::new(Grid::new(2, 3), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).unwrap();
        let (padded, cut) = pad_to(&summary.view(), 5).unwrap();
        assert!(!cut);
        assert_eq!(
            padded.values(),
            [1.0, 2.0, 3.0, 0.0, 0.0, 4.0, 5.0, 6.0, 0.0, 0.0]
        );
        let (short, cut) = pad_to(&summary.view(), 2).unwrap();
        assert!(cut);
        assert_eq!(short.values(), [1.0, 2.0, 4.0, 5.0]);
        assert!(pad_to(&summary.view(), 0).is_err());
    }

    #[test]
    fn bad_stances_are_refused_with_the_reason() {
        let grid = Grid::new(8, 4);
        let config = SummaryConfig::default();
        assert!(summarise(&[], &config).is_err());
        let mut nan = Frame::zeros(grid);
        nan.values_mut()[3] = f64::NAN;
        let frames = [Frame::zeros(grid), nan];
        let views: Vec<_> = frames.iter().map(Frame::view).collect();
        let err = summarise(&views, &config).unwrap_err().to_string();
        assert!(err.contains("frame 1"), "{err}");
        let tiny = [Frame::zeros(Grid::new(2, 1))];
        let views: Vec<_> = tiny.iter().map(Frame::view).collect();
        assert!(
            summarise(&views, &config).is_err(),
            "4 x 2 regions on 2 x 1"
        );
        let mixed = [Frame::zeros(grid), Frame::zeros(Grid::new(4, 8))];
        let views: Vec<_> = mixed.iter().map(Frame::view).collect();
        assert!(summarise(&views, &config).is_err());
    }
}
