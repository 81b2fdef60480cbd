//! Regions of interest: which part of the sensor array is the foot.
//!
//! The paper keeps the 38 x 41 sensels under the hopper foot by dropping the bottom 6 rows and the first 3
//! columns of the 44 x 44 TekScan #5051 array ([`Crop::PAPER`]). A crop is stored in a trained model so
//! that the same region is used when classifying.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::{Frame, FrameView, Grid};

/// A rectangular region of a sensel grid, given as margins dropped from each side, or as a fixed window.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Crop {
    /// Drop this many rows/columns from each side (works on any grid large enough).
    Margins {
        top: usize,
        bottom: usize,
        left: usize,
        right: usize,
    },
    /// Keep exactly `rows x cols` sensels starting at `(row0, col0)`.
    Window {
        row0: usize,
        col0: usize,
        rows: usize,
        cols: usize,
    },
}

impl Default for Crop {
    fn default() -> Self {
        Self::NONE
    }
}

impl Crop {
    /// Keep the whole grid.
    pub const NONE: Self = Self::Margins {
        top: 0,
        bottom: 0,
        left: 0,
        right: 0,
    };

    /// The paper's foot region on the 44 x 44 array: drop the bottom 6 rows and the first 3 columns (38 x 41).
    pub const PAPER: Self = Self::Margins {
        top: 0,
        bottom: 6,
        left: 3,
        right: 0,
    };

    /// Parses `none`, `paper`, margins `top,bottom,left,right`, or a window `row0:col0:rows:cols`.
    pub fn parse(text: &str) -> Result<Self> {
        let text = text.trim();
        let bad = |reason: &str| CoreError::Param {
            name: "crop",
            reason: format!(
                "{reason} in {text:?}; expected none, paper, top,bottom,left,right or row0:col0:rows:cols"
            ),
        };
        let numbers = |sep: char| -> Result<Vec<usize>> {
            text.split(sep)
                .map(|part| {
                    part.trim()
                        .parse::<usize>()
                        .map_err(|_| bad("not a whole number"))
                })
                .collect()
        };
        match text.to_ascii_lowercase().as_str() {
            "none" | "" => return Ok(Self::NONE),
            "paper" => return Ok(Self::PAPER),
            _ => {}
        }
        if text.contains(':') {
            match numbers(':')?.as_slice() {
                &[row0, col0, rows, cols] => Ok(Self::Window {
                    row0,
                    col0,
                    rows,
                    cols,
                }),
                _ => Err(bad("a window needs four numbers")),
            }
        } else {
            match numbers(',')?.as_slice() {
                &[top, bottom, left, right] => Ok(Self::Margins {
                    top,
                    bottom,
                    left,
                    right,
                }),
                _ => Err(bad("margins need four numbers")),
            }
        }
    }

    /// The window `(row0, col0, rows, cols)` this crop selects on `grid`, or an error if it does not fit.
    pub fn window(&self, grid: Grid) -> Result<(usize, usize, Grid)> {
        let does_not_fit = || CoreError::Shape {
            what: "crop",
            expected: format!("a crop that fits inside the {grid} grid"),
            got: self.to_string(),
        };
        // Every sum is checked: the numbers come from the command line or a model file, and a wrapped sum
        // would pass the fit test and send a later slice out of bounds.
        let (row0, col0, rows, cols) = match *self {
            Self::Margins {
                top,
                bottom,
                left,
                right,
            } => {
                let vertical = top.checked_add(bottom).ok_or_else(does_not_fit)?;
                let horizontal = left.checked_add(right).ok_or_else(does_not_fit)?;
                (
                    top,
                    left,
                    grid.rows.saturating_sub(vertical),
                    grid.cols.saturating_sub(horizontal),
                )
            }
            Self::Window {
                row0,
                col0,
                rows,
                cols,
            } => (row0, col0, rows, cols),
        };
        let row_end = row0.checked_add(rows).ok_or_else(does_not_fit)?;
        let col_end = col0.checked_add(cols).ok_or_else(does_not_fit)?;
        if rows == 0 || cols == 0 || row_end > grid.rows || col_end > grid.cols {
            return Err(does_not_fit());
        }
        Ok((row0, col0, Grid::new(rows, cols)))
    }

    /// The grid a frame of `grid` has after cropping.
    pub fn output_grid(&self, grid: Grid) -> Result<Grid> {
        self.window(grid).map(|(_, _, out)| out)
    }

    /// Copies the cropped values of `frame` into `out` (row-major, `output_grid` sized). No allocation.
    pub fn apply_into(&self, frame: &FrameView<'_>, out: &mut [f64]) -> Result<Grid> {
        let (row0, col0, out_grid) = self.window(frame.grid())?;
        if out.len() != out_grid.len() {
            return Err(CoreError::Shape {
                what: "crop output buffer",
                expected: out_grid.len().to_string(),
                got: out.len().to_string(),
            });
        }
        let src = frame.values();
        let in_cols = frame.grid().cols;
        for (r, dst_row) in out.chunks_exact_mut(out_grid.cols).enumerate() {
            let start = (row0 + r) * in_cols + col0;
            dst_row.copy_from_slice(&src[start..start + out_grid.cols]);
        }
        Ok(out_grid)
    }

    /// The cropped frame, mask included.
    pub fn apply(&self, frame: &FrameView<'_>) -> Result<Frame> {
        let out_grid = self.output_grid(frame.grid())?;
        let mut values = vec![0.0; out_grid.len()];
        self.apply_into(frame, &mut values)?;
        let present = match frame.present() {
            Some(mask) => {
                let (row0, col0, _) = self.window(frame.grid())?;
                let mut out = Vec::with_capacity(out_grid.len());
                for r in 0..out_grid.rows {
                    let start = (row0 + r) * frame.grid().cols + col0;
                    out.extend_from_slice(&mask[start..start + out_grid.cols]);
                }
                Some(out)
            }
            None => None,
        };
        Frame::with_mask(out_grid, values, present)
    }
}

impl std::fmt::Display for Crop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::NONE => f.write_str("none"),
            Self::PAPER => f.write_str("paper"),
            Self::Margins {
                top,
                bottom,
                left,
                right,
            } => write!(f, "{top},{bottom},{left},{right}"),
            Self::Window {
                row0,
                col0,
                rows,
                cols,
            } => write!(f, "{row0}:{col0}:{rows}:{cols}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_crop_gives_38_by_41_from_the_right_corner() {
        let grid = Grid::new(44, 44);
        let values: Vec<f64> = (0..grid.len()).map(|i| i as f64).collect();
        let frame = FrameView::new(grid, &values, None).unwrap();
        let cropped = Crop::PAPER.apply(&frame).unwrap();
        assert_eq!(cropped.grid(), Grid::new(38, 41));
        // first kept sensel is row 0, col 3; last kept is row 37, col 43
        assert_eq!(cropped.values()[0], 3.0);
        assert_eq!(*cropped.values().last().unwrap(), (37 * 44 + 43) as f64);
    }

    #[test]
    fn parse_and_display_round_trip() {
        for text in ["none", "paper", "1,2,3,4", "0:3:38:41"] {
            let crop = Crop::parse(text).unwrap();
            assert_eq!(Crop::parse(&crop.to_string()).unwrap(), crop);
        }
        assert!(Crop::parse("1,2,3").is_err());
        assert!(Crop::parse("a:b:c:d").is_err());
    }

    #[test]
    fn crop_that_does_not_fit_is_an_error() {
        assert!(Crop::PAPER.output_grid(Grid::new(16, 16)).is_ok());
        assert!(Crop::PAPER.output_grid(Grid::new(6, 3)).is_err());
        assert!(
            Crop::parse("0:0:17:1")
                .unwrap()
                .output_grid(Grid::new(16, 16))
                .is_err()
        );
    }

    #[test]
    fn crop_numbers_near_usize_max_are_an_error_not_a_wrap() {
        let grid = Grid::new(44, 44);
        let values = vec![1.0; grid.len()];
        let frame = FrameView::new(grid, &values, None).unwrap();
        let max = usize::MAX;
        for text in [
            format!("{max}:0:2:2"),
            format!("0:{max}:2:2"),
            format!("1:0:{max}:2"),
            format!("0:1:2:{max}"),
            format!("{max},1,0,0"),
            format!("0,0,1,{max}"),
        ] {
            let crop = Crop::parse(&text).unwrap();
            let err = crop.apply(&frame).unwrap_err();
            assert!(
                matches!(err, CoreError::Shape { what: "crop", ref got, .. } if *got == crop.to_string()),
                "{text}: {err}"
            );
            assert!(err.to_string().contains(&text), "{err}");
        }
    }
}
