//! One pressure image: `rows x cols` sensel values, row-major, with an optional mask of absent sensels.
//!
//! Values are `f64` in the recording's units (raw counts or a pressure unit). A sensel that does not exist
//! (TekScan writes `B` for cells outside an insole's outline) is *absent*, which is different from a zero
//! reading: absent sensels are stored as `0.0` in `values` and flagged `false` in the `present` mask.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};

/// The dimensions of a sensel grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Grid {
    pub rows: usize,
    pub cols: usize,
}

impl Grid {
    pub const fn new(rows: usize, cols: usize) -> Self {
        Self { rows, cols }
    }

    /// Number of sensels, `rows * cols`.
    pub const fn len(&self) -> usize {
        self.rows * self.cols
    }

    pub const fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row-major index of sensel `(row, col)`.
    pub const fn index(&self, row: usize, col: usize) -> usize {
        row * self.cols + col
    }
}

impl std::fmt::Display for Grid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.rows, self.cols)
    }
}

/// An owned pressure image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    grid: Grid,
    values: Vec<f64>,
    /// `None` when every sensel is present.
    present: Option<Vec<bool>>,
}

impl Frame {
    /// A frame with every sensel present.
    pub fn new(grid: Grid, values: Vec<f64>) -> Result<Self> {
        check_len("frame values", grid, values.len())?;
        Ok(Self {
            grid,
            values,
            present: None,
        })
    }

    /// A frame with a mask of present sensels (`true` = a sensor exists there). Absent values are zeroed.
    pub fn with_mask(grid: Grid, mut values: Vec<f64>, present: Option<Vec<bool>>) -> Result<Self> {
        check_len("frame values", grid, values.len())?;
        let present = match present {
            Some(mask) => {
                check_len("frame mask", grid, mask.len())?;
                for (value, &here) in values.iter_mut().zip(&mask) {
                    if !here {
                        *value = 0.0;
                    }
                }
                if mask.iter().all(|&here| here) {
                    None
                } else {
                    Some(mask)
                }
            }
            None => None,
        };
        Ok(Self {
            grid,
            values,
            present,
        })
    }

    pub fn zeros(grid: Grid) -> Self {
        Self {
            grid,
            values: vec![0.0; grid.len()],
            present: None,
        }
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    pub fn values(&self) -> &[f64] {
        &self.values
    }

    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    pub fn present(&self) -> Option<&[bool]> {
        self.present.as_deref()
    }

    pub fn view(&self) -> FrameView<'_> {
        FrameView {
            grid: self.grid,
            values: &self.values,
            present: self.present.as_deref(),
        }
    }

    pub fn into_values(self) -> Vec<f64> {
        self.values
    }
}

/// A borrowed pressure image (a frame of a recording, or an owned [`Frame`]). Unlike a [`Frame`], a view
/// built with [`FrameView::new`] does not zero its absent sensels (it cannot: it borrows); what it holds
/// there is not a reading, and [`total`](Self::total) ignores it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameView<'a> {
    grid: Grid,
    values: &'a [f64],
    present: Option<&'a [bool]>,
}

impl<'a> FrameView<'a> {
    pub fn new(grid: Grid, values: &'a [f64], present: Option<&'a [bool]>) -> Result<Self> {
        check_len("frame values", grid, values.len())?;
        if let Some(mask) = present {
            check_len("frame mask", grid, mask.len())?;
        }
        Ok(Self {
            grid,
            values,
            present,
        })
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    pub fn values(&self) -> &'a [f64] {
        self.values
    }

    pub fn present(&self) -> Option<&'a [bool]> {
        self.present
    }

    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.values[self.grid.index(row, col)]
    }

    /// Appends the values to `out`, absent sensels as 0 (how the pipeline reads them, whatever a
    /// view's values hold there).
    pub fn extend_absent_as_zero(&self, out: &mut Vec<f64>) {
        match self.present {
            None => out.extend_from_slice(self.values),
            Some(mask) => out.extend(
                self.values
                    .iter()
                    .zip(mask)
                    .map(|(&value, &here)| if here { value } else { 0.0 }),
            ),
        }
    }

    /// Whether sensel `(row, col)` exists.
    pub fn is_present(&self, row: usize, col: usize) -> bool {
        self.present
            .is_none_or(|mask| mask[self.grid.index(row, col)])
    }

    /// Sum of the present values (absent sensels count 0, whatever the view holds there): the frame's
    /// total load in value units per sensel.
    pub fn total(&self) -> f64 {
        match self.present {
            // The common case, and the online classifier's per-frame path: a plain sum.
            None => self.values.iter().sum(),
            Some(mask) => self
                .values
                .iter()
                .zip(mask)
                .filter(|&(_, &here)| here)
                .map(|(&value, _)| value)
                .sum(),
        }
    }

    pub fn to_frame(&self) -> Frame {
        Frame {
            grid: self.grid,
            values: self.values.to_vec(),
            present: self.present.map(<[bool]>::to_vec),
        }
    }

    /// The frame with rows and columns swapped (a series whose time runs down the rows, laid as
    /// channels x time), absent sensels kept absent.
    pub fn transposed(&self) -> Frame {
        let Grid { rows, cols } = self.grid;
        let swap = |index: usize| (index % rows) * cols + index / rows;
        Frame {
            grid: Grid::new(cols, rows),
            values: (0..self.values.len())
                .map(|i| self.values[swap(i)])
                .collect(),
            present: self
                .present
                .map(|mask| (0..mask.len()).map(|i| mask[swap(i)]).collect()),
        }
    }
}

fn check_len(what: &'static str, grid: Grid, got: usize) -> Result<()> {
    if grid.len() == got {
        Ok(())
    } else {
        Err(CoreError::Shape {
            what,
            expected: format!("{} values for a {grid} grid", grid.len()),
            got: got.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transposing_swaps_rows_and_columns_with_the_mask() {
        let frame = Frame::with_mask(
            Grid::new(2, 3),
            vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            Some(vec![true, true, false, true, true, true]),
        )
        .unwrap();
        let swapped = frame.view().transposed();
        assert_eq!(swapped.grid(), Grid::new(3, 2));
        // An absent sensel reads 0.
        assert_eq!(swapped.values(), [1.0, 4.0, 2.0, 5.0, 0.0, 6.0]);
        assert_eq!(
            swapped.present().unwrap(),
            [true, true, true, true, false, true]
        );
        assert_eq!(swapped.view().transposed(), frame);
    }

    #[test]
    fn rejects_wrong_length() {
        assert!(Frame::new(Grid::new(2, 3), vec![0.0; 5]).is_err());
        assert!(FrameView::new(Grid::new(2, 3), &[0.0; 6], Some(&[true; 5])).is_err());
    }

    #[test]
    fn total_counts_present_sensels_only() {
        let values = [1.0, 100.0, 3.0, f64::NAN];
        let mask = [true, false, true, false];
        let view = FrameView::new(Grid::new(2, 2), &values, Some(&mask)).unwrap();
        assert_eq!(view.total(), 4.0);
        let all = FrameView::new(Grid::new(1, 3), &values[..3], None).unwrap();
        assert_eq!(all.total(), 104.0);
    }

    #[test]
    fn mask_zeroes_absent_values_and_full_mask_is_dropped() {
        let frame = Frame::with_mask(
            Grid::new(1, 3),
            vec![1.0, 2.0, 3.0],
            Some(vec![true, false, true]),
        )
        .unwrap();
        assert_eq!(frame.values(), &[1.0, 0.0, 3.0]);
        assert!(!frame.view().is_present(0, 1));
        let full =
            Frame::with_mask(Grid::new(1, 2), vec![1.0, 2.0], Some(vec![true, true])).unwrap();
        assert!(full.present().is_none());
    }
}
