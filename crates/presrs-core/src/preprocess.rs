//! Image preprocessing applied after the crop, before the features (training and classification alike):
//!
//! - **fill absent sensels** ([`fill_from_neighbours`]): masked sensels (and, optionally, sensels flagged
//!   dead) take the mean of their 4-neighbours, relaxed until the filled values settle (Gauss-Seidel on
//!   the discrete Laplace equation), so clusters are filled from their rim and any harmonic field — a
//!   plane in particular — is reproduced exactly around interior holes;
//! - **normalise the load** ([`normalise_load`]): divide the image by its total, so that an image scaled
//!   by the robot's load gives the same features without knowing the load (the paper scales by the known
//!   load instead).
//!
//! - **an intensity transform** ([`Intensity`]): none, square root or log1p of each value (sign kept),
//!   applied after the fill and before the load normalisation; it compresses the range of real pressure
//!   images, where a few sensels under a hard edge can dominate the features.
//!
//! - **fill dead sensels** ([`fill_dead_sensels`]): the same filling for sensels found dead
//!   ([`crate::dead_sensels`]), leaving absent sensels alone; applied when recordings are read from
//!   files, before any frame is taken from them.
//!
//! All run in caller-owned buffers ([`FillScratch`]): no allocation per image.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::Grid;

/// Which preprocessing steps the pipeline applies after the crop. `Default` (both off) is the paper's
/// method; model files written before these options existed load with the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Preprocess {
    /// Divide each cropped image by its total load (sum of its values).
    pub normalise_load: bool,
    /// Fill absent (masked) sensels from their neighbours instead of reading them as 0.
    pub fill_absent: bool,
    /// Transform each value before the features (not written when none, so model files without it, and
    /// files written without it, read alike).
    #[serde(skip_serializing_if = "Intensity::is_none")]
    pub intensity: Intensity,
}

/// A transform of every value of the image, applied before the features. The sign is kept, so that
/// negative values (after a baseline subtraction) stay ordered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Intensity {
    /// The values as they are (the paper's method).
    #[default]
    None,
    /// `sign(v) * sqrt(|v|)`.
    Sqrt,
    /// `sign(v) * ln(1 + |v|)`.
    Log1p,
}

impl Intensity {
    /// Every transform, the identity first.
    pub const ALL: [Self; 3] = [Self::None, Self::Sqrt, Self::Log1p];

    pub fn is_none(&self) -> bool {
        *self == Self::None
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Sqrt => "sqrt",
            Self::Log1p => "log1p",
        }
    }

    /// Transforms `values` in place.
    pub fn apply(self, values: &mut [f64]) {
        match self {
            Self::None => {}
            Self::Sqrt => values
                .iter_mut()
                .for_each(|v| *v = v.abs().sqrt().copysign(*v)),
            Self::Log1p => values
                .iter_mut()
                .for_each(|v| *v = v.abs().ln_1p().copysign(*v)),
        }
    }
}

impl std::fmt::Display for Intensity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Intensity {
    type Err = CoreError;

    fn from_str(text: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|i| i.as_str().eq_ignore_ascii_case(text.trim()))
            .ok_or_else(|| CoreError::Param {
                name: "intensity",
                reason: format!("{text:?} is not one of none, sqrt, log1p"),
            })
    }
}

impl Preprocess {
    /// The paper's method: absent sensels read as 0, no normalisation.
    pub const NONE: Self = Self {
        normalise_load: false,
        fill_absent: false,
        intensity: Intensity::None,
    };

    /// Whether every step is off.
    pub fn is_none(&self) -> bool {
        *self == Self::NONE
    }

    /// Short description, the steps in the order they run (`none`, `normalise-load`, `fill-absent`,
    /// `fill-absent+normalise-load`, `sqrt`, `fill-absent+log1p+normalise-load`, ...).
    pub fn name(&self) -> String {
        let mut steps = Vec::new();
        if self.fill_absent {
            steps.push("fill-absent");
        }
        if !self.intensity.is_none() {
            steps.push(self.intensity.as_str());
        }
        if self.normalise_load {
            steps.push("normalise-load");
        }
        if steps.is_empty() {
            "none".to_owned()
        } else {
            steps.join("+")
        }
    }
}

impl std::fmt::Display for Preprocess {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

/// Buffers of [`fill_from_neighbours`] for one grid size.
#[derive(Clone, Debug, Default)]
pub struct FillScratch {
    /// Whether each sensel has a value (given or already seeded).
    known: Vec<bool>,
    /// Indices of the sensels to fill.
    holes: Vec<usize>,
    /// Holes seeded in the current onion-peeling pass.
    seeded: Vec<usize>,
}

impl FillScratch {
    /// Buffers for images of `len` sensels (so that filling them does not allocate).
    pub fn new(len: usize) -> Self {
        Self {
            known: Vec::with_capacity(len),
            holes: Vec::with_capacity(len),
            seeded: Vec::with_capacity(len),
        }
    }
}

/// Relaxation stops when no filled value moves by more than this fraction of the image's largest
/// magnitude, or after [`MAX_SWEEPS`] sweeps.
const TOLERANCE: f64 = 1e-13;
const MAX_SWEEPS: usize = 20_000;

/// Fills the sensels of `values` (a row-major `grid` image) that are absent — `present[i] == false` — or
/// flagged `dead[i] == true`, from their present 4-neighbours. First every hole that touches a known
/// sensel takes the mean of its known neighbours, layer by layer from the rim of each cluster inwards;
/// then every filled value is relaxed to the mean of all its neighbours until it settles. A hole with no
/// known sensel anywhere in the image (all absent) becomes 0. Does not allocate once `scratch` has
/// grown to the grid's size ([`FillScratch::new`]).
pub fn fill_from_neighbours(
    values: &mut [f64],
    grid: Grid,
    present: Option<&[bool]>,
    dead: Option<&[bool]>,
    scratch: &mut FillScratch,
) -> Result<()> {
    check_mask_lengths(
        grid,
        values.len(),
        present.map(<[bool]>::len),
        dead.map(<[bool]>::len),
    )?;
    let all = |_: usize| true;
    let hole = |i: usize| !present.is_none_or(|p| p[i]) || dead.is_some_and(|d| d[i]);
    fill_holes(values, grid, &all, &hole, Unreachable::Zero, scratch);
    Ok(())
}

/// The image and its masks (when given) must all hold one value per sensel of `grid`.
fn check_mask_lengths(
    grid: Grid,
    image: usize,
    present: Option<usize>,
    dead: Option<usize>,
) -> Result<()> {
    let len = grid.len();
    for (what, got) in [
        ("image", Some(image)),
        ("present mask", present),
        ("dead mask", dead),
    ] {
        if let Some(got) = got
            && got != len
        {
            return Err(CoreError::Shape {
                what,
                expected: format!("{len} values ({grid})"),
                got: got.to_string(),
            });
        }
    }
    Ok(())
}

/// Fills the present sensels of `values` flagged `dead[i] == true` from their present, live
/// neighbours (like [`fill_from_neighbours`]), leaving every other sensel — absent ones included —
/// as it is. Absent sensels are neither filled nor used: a dead sensel next to the sensor's outline
/// takes the mean of its neighbours inside. A dead sensel without any live sensel reachable through
/// present sensels keeps its value. Does not allocate once `scratch` has grown to the grid's size.
pub fn fill_dead_sensels(
    values: &mut [f64],
    grid: Grid,
    present: Option<&[bool]>,
    dead: &[bool],
    scratch: &mut FillScratch,
) -> Result<()> {
    check_mask_lengths(
        grid,
        values.len(),
        present.map(<[bool]>::len),
        Some(dead.len()),
    )?;
    let exists = |i: usize| present.is_none_or(|p| p[i]);
    let hole = |i: usize| exists(i) && dead[i];
    fill_holes(values, grid, &exists, &hole, Unreachable::Keep, scratch);
    Ok(())
}

/// What becomes of holes that no known sensel can be reached from.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Unreachable {
    /// They read 0 (an image with nothing known: [`fill_from_neighbours`]).
    Zero,
    /// They keep their values ([`fill_dead_sensels`]).
    Keep,
}

/// The filling shared by [`fill_from_neighbours`] and [`fill_dead_sensels`]: sensels for which
/// `hole` holds are filled from the neighbours for which `exists` holds (holes are a subset of those),
/// starting from the known ones (existing, not holes). Only holes reachable from a known sensel through
/// existing sensels are filled, and only from known or already filled neighbours; the others are left
/// to `unreachable`.
fn fill_holes(
    values: &mut [f64],
    grid: Grid,
    exists: &dyn Fn(usize) -> bool,
    hole: &dyn Fn(usize) -> bool,
    unreachable: Unreachable,
    scratch: &mut FillScratch,
) {
    let FillScratch {
        known,
        holes,
        seeded,
    } = scratch;
    let any_known = find_holes(grid, exists, hole, known, holes);
    if holes.is_empty() {
        return;
    }
    if !any_known {
        if unreachable == Unreachable::Zero {
            for &i in holes.iter() {
                values[i] = 0.0;
            }
        }
        return;
    }
    let remaining = seed_holes(values, grid, holes, known, seeded);
    // Holes left unseeded are cut off: none of them touches a known or seeded sensel, so relaxing the
    // seeded ones never reads them, and they keep their values.
    if remaining > 0 {
        if unreachable == Unreachable::Zero {
            for &i in holes.iter().filter(|&&i| !known[i]) {
                values[i] = 0.0;
            }
        }
        holes.retain(|&i| known[i]);
    }
    relax_holes(values, grid, holes, exists);
}

/// Fills `known` (per sensel: existing and not a hole) and `holes` (the holes' indices, in order);
/// whether any sensel is known.
fn find_holes(
    grid: Grid,
    exists: &dyn Fn(usize) -> bool,
    hole: &dyn Fn(usize) -> bool,
    known: &mut Vec<bool>,
    holes: &mut Vec<usize>,
) -> bool {
    known.clear();
    holes.clear();
    let mut any_known = false;
    for i in 0..grid.len() {
        let is_hole = hole(i);
        let here = !is_hole && exists(i);
        any_known |= here;
        known.push(here);
        if is_hole {
            holes.push(i);
        }
    }
    any_known
}

/// Sum and count of the neighbours of sensel `i` (up, down, left, right) for which `use_it` holds.
fn neighbour_sum(
    values: &[f64],
    grid: Grid,
    i: usize,
    use_it: &dyn Fn(usize) -> bool,
) -> (f64, usize) {
    let (rows, cols) = (grid.rows, grid.cols);
    let (r, c) = (i / cols, i % cols);
    let (mut sum, mut count) = (0.0, 0usize);
    let mut add = |j: usize| {
        if use_it(j) {
            sum += values[j];
            count += 1;
        }
    };
    if r > 0 {
        add(i - cols);
    }
    if r + 1 < rows {
        add(i + cols);
    }
    if c > 0 {
        add(i - 1);
    }
    if c + 1 < cols {
        add(i + 1);
    }
    (sum, count)
}

/// Seeds the holes by onion peeling from the known sensels: each round, every hole with a known
/// neighbour becomes the mean of its known neighbours and is known from then on. Returns how many holes
/// were left unseeded (cut off from every known sensel).
fn seed_holes(
    values: &mut [f64],
    grid: Grid,
    holes: &[usize],
    known: &mut [bool],
    seeded: &mut Vec<usize>,
) -> usize {
    let mut remaining = holes.len();
    while remaining > 0 {
        seeded.clear();
        for &i in holes {
            if known[i] {
                continue;
            }
            let (sum, count) = neighbour_sum(values, grid, i, &|j| known[j]);
            if count > 0 {
                values[i] = sum / count as f64;
                seeded.push(i);
            }
        }
        if seeded.is_empty() {
            // holes cut off from every known sensel (only possible when absent sensels isolate them)
            break;
        }
        for &i in seeded.iter() {
            known[i] = true;
        }
        remaining -= seeded.len();
    }
    remaining
}

/// Relaxes the `holes`: each becomes the mean of all its existing neighbours (Gauss-Seidel), until they
/// settle (at most [`MAX_SWEEPS`] sweeps).
fn relax_holes(values: &mut [f64], grid: Grid, holes: &[usize], exists: &dyn Fn(usize) -> bool) {
    let scale = values
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    for _ in 0..MAX_SWEEPS {
        let mut largest_change = 0.0f64;
        for &i in holes {
            let (sum, count) = neighbour_sum(values, grid, i, exists);
            if count == 0 {
                continue;
            }
            let new = sum / count as f64;
            largest_change = largest_change.max((new - values[i]).abs());
            values[i] = new;
        }
        // settled (or non-finite values, which later stages reject)
        if largest_change <= TOLERANCE * scale || largest_change.is_nan() {
            break;
        }
    }
}

/// Divides `values` by their sum (the image's total load) and returns that total. An image whose total
/// is not positive and finite (empty contact, or bad values that later stages reject) is left unchanged.
pub fn normalise_load(values: &mut [f64]) -> f64 {
    let total: f64 = values.iter().sum();
    if total > 0.0 && total.is_finite() {
        let inverse = 1.0 / total;
        values.iter_mut().for_each(|v| *v *= inverse);
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbour_sum_adds_the_four_neighbours_inside_the_grid() {
        let grid = Grid::new(3, 3);
        let values: Vec<f64> = (0..9).map(|i| i as f64).collect();
        assert_eq!(neighbour_sum(&values, grid, 4, &|_| true), (16.0, 4));
        assert_eq!(neighbour_sum(&values, grid, 0, &|_| true), (4.0, 2));
        assert_eq!(neighbour_sum(&values, grid, 8, &|j| j != 7), (5.0, 1));
    }

    #[test]
    fn names() {
        assert_eq!(Preprocess::default().name(), "none");
        assert!(Preprocess::default().is_none());
        let both = Preprocess {
            normalise_load: true,
            fill_absent: true,
            ..Preprocess::NONE
        };
        assert_eq!(both.to_string(), "fill-absent+normalise-load");
        let all = Preprocess {
            intensity: Intensity::Log1p,
            ..both
        };
        assert_eq!(all.to_string(), "fill-absent+log1p+normalise-load");
        let sqrt = Preprocess {
            intensity: Intensity::Sqrt,
            ..Preprocess::NONE
        };
        assert_eq!(sqrt.to_string(), "sqrt");
        assert!(!sqrt.is_none());
    }

    /// Against the obvious formulas, value by value, signs included.
    #[test]
    fn intensity_transforms_match_their_formulas() {
        let values = [0.0, 1.0, 4.0, 2.5, 1e6, -9.0, -0.25];
        for intensity in Intensity::ALL {
            let mut out = values;
            intensity.apply(&mut out);
            for (&v, &got) in values.iter().zip(&out) {
                let want = match intensity {
                    Intensity::None => v,
                    Intensity::Sqrt if v < 0.0 => -((-v).sqrt()),
                    Intensity::Sqrt => v.sqrt(),
                    Intensity::Log1p if v < 0.0 => -((1.0 - v).ln()),
                    Intensity::Log1p => (1.0 + v).ln(),
                };
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                    "{intensity} {v}: {got} vs {want}"
                );
            }
            assert_eq!(intensity.as_str().parse::<Intensity>().unwrap(), intensity);
        }
        assert_eq!("SQRT".parse::<Intensity>().unwrap(), Intensity::Sqrt);
        assert!("cube".parse::<Intensity>().is_err());
    }

    /// Model files written before the transform existed (no `intensity`) read as none, and a file
    /// written without one has no `intensity` key; one with a transform round-trips.
    #[test]
    fn intensity_in_stored_preprocessing() {
        let old: Preprocess =
            serde_json::from_str(r#"{"normalise_load":true,"fill_absent":false}"#).unwrap();
        assert_eq!(old.intensity, Intensity::None);
        assert!(old.normalise_load);
        assert!(
            !serde_json::to_string(&Preprocess::NONE)
                .unwrap()
                .contains("intensity")
        );
        let log = Preprocess {
            intensity: Intensity::Log1p,
            ..Preprocess::NONE
        };
        let text = serde_json::to_string(&log).unwrap();
        assert!(text.contains(r#""intensity":"log1p""#), "{text}");
        assert_eq!(serde_json::from_str::<Preprocess>(&text).unwrap(), log);
    }

    #[test]
    fn zero_total_is_left_alone() {
        let mut v = [0.0; 4];
        assert_eq!(normalise_load(&mut v), 0.0);
        assert_eq!(v, [0.0; 4]);
    }

    #[test]
    fn dead_sensels_without_a_live_sensel_keep_their_values() {
        // Every present sensel is dead (the absent one holds 0): nothing to fill from.
        let grid = Grid::new(1, 3);
        let mut v = [5.0, 7.0, 0.0];
        let mut scratch = FillScratch::new(3);
        let present = [true, true, false];
        let dead = [true, true, false];
        fill_dead_sensels(&mut v, grid, Some(&present), &dead, &mut scratch).unwrap();
        assert_eq!(v, [5.0, 7.0, 0.0]);
        // No mask and every sensel dead.
        let mut v = [5.0, 7.0, 9.0];
        fill_dead_sensels(&mut v, grid, None, &[true; 3], &mut scratch).unwrap();
        assert_eq!(v, [5.0, 7.0, 9.0]);
    }

    #[test]
    fn a_dead_cluster_cut_off_by_absent_sensels_keeps_its_values() {
        // Row: live 1, absent, dead 4, dead 8, absent, dead 20 next to live 10 and 30.
        let grid = Grid::new(1, 8);
        let present = [true, false, true, true, false, true, true, true];
        let dead = [false, false, true, true, false, false, true, false];
        let mut v = [1.0, 0.0, 4.0, 8.0, 0.0, 10.0, 20.0, 30.0];
        let mut scratch = FillScratch::new(8);
        fill_dead_sensels(&mut v, grid, Some(&present), &dead, &mut scratch).unwrap();
        assert_eq!(
            v[..6],
            [1.0, 0.0, 4.0, 8.0, 0.0, 10.0],
            "the cut-off pair is untouched"
        );
        assert!((v[6] - 20.0).abs() < 1e-9, "{v:?}");
        assert_eq!(v[7], 30.0);
        // The same cut-off pair beside a reachable dead pair: only the reachable one is filled.
        let grid = Grid::new(2, 4);
        let present = [true, false, true, true, true, true, false, false];
        let dead = [false, false, true, true, true, true, false, false];
        let mut v = [2.0, 0.0, 4.0, 8.0, 3.0, 5.0, 0.0, 0.0];
        fill_dead_sensels(&mut v, grid, Some(&present), &dead, &mut scratch).unwrap();
        // The dead (0,2), (0,3) touch only each other and absent sensels: cut off. The dead (1,0), (1,1)
        // are reachable from the live (0,0) = 2 and take its value.
        assert_eq!(v[2..4], [4.0, 8.0]);
        assert!(
            (v[4] - 2.0).abs() < 1e-9 && (v[5] - 2.0).abs() < 1e-9,
            "{v:?}"
        );
    }

    #[test]
    fn all_absent_becomes_zero() {
        let grid = Grid::new(2, 3);
        let mut v = [1.0; 6];
        let mut scratch = FillScratch::new(6);
        fill_from_neighbours(&mut v, grid, Some(&[false; 6]), None, &mut scratch).unwrap();
        assert_eq!(v, [0.0; 6]);
    }
}
