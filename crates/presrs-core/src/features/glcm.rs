//! Grey-level co-occurrence matrix (GLCM) texture attributes (Haralick et al.).
//!
//! The image is quantised to `levels` grey levels: `q = floor(levels · v / v_max)`, clamped to
//! `0 ..= levels - 1`, where `v_max` is the image's own maximum (so the quantisation does not depend on the
//! load) or a fixed value; values `<= 0` are level 0. For every distance `d` and angle `θ` the offset is
//! `(Δrow, Δcol) = (round(d sin θ), round(d cos θ))` (scikit-image's `graycomatrix` convention), pairs
//! `(q[r][c], q[r + Δrow][c + Δcol])` inside the image are counted, the matrix is made symmetric
//! (`P + Pᵀ`) and normalised to sum 1. The attributes are scikit-image's `graycoprops`:
//! contrast `Σ P (i-j)²`, dissimilarity `Σ P |i-j|`, homogeneity `Σ P / (1 + (i-j)²)`, ASM `Σ P²`,
//! energy `sqrt(ASM)`, correlation `Σ P (i-μi)(j-μj) / (σi σj)` (1 when a σ is below 1e-15) and entropy
//! `-Σ P ln P`.
//!
//! Features: for each distance (outer) and each angle (inner), the seven attributes in that order; with
//! `average_angles` the attributes are averaged over the angles (a rotation-robust variant), giving seven
//! per distance.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_len};
use crate::features::family::FeatureFamily;
use crate::frame::Grid;

/// Number of attributes per co-occurrence matrix.
pub const GLCM_ATTRIBUTES: usize = 7;

/// Names of the attributes, in feature order.
pub const GLCM_ATTRIBUTE_NAMES: [&str; GLCM_ATTRIBUTES] = [
    "contrast",
    "dissimilarity",
    "homogeneity",
    "ASM",
    "energy",
    "correlation",
    "entropy",
];

/// Parameters of the GLCM features.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlcmConfig {
    /// Number of grey levels (2 ..= 256).
    #[serde(default = "default_levels")]
    pub levels: usize,
    /// Pixel-pair distances (each >= 1).
    #[serde(default = "default_distances")]
    pub distances: Vec<usize>,
    /// Angles in degrees.
    #[serde(default = "default_angles")]
    pub angles_deg: Vec<f64>,
    /// Average the attributes over the angles.
    #[serde(default = "default_true")]
    pub average_angles: bool,
    /// The value mapped to the top grey level; `None`: each image's own maximum.
    #[serde(default)]
    pub max_value: Option<f64>,
}

fn default_levels() -> usize {
    16
}
fn default_distances() -> Vec<usize> {
    vec![1, 2, 3, 5]
}
fn default_angles() -> Vec<f64> {
    vec![0.0, 45.0, 90.0, 135.0]
}
fn default_true() -> bool {
    true
}

impl Default for GlcmConfig {
    /// 16 levels, distances 1, 2, 3, 5, angles 0/45/90/135 averaged, per-image maximum: 28 features.
    fn default() -> Self {
        Self {
            levels: default_levels(),
            distances: default_distances(),
            angles_deg: default_angles(),
            average_angles: true,
            max_value: None,
        }
    }
}

impl Eq for GlcmConfig {}

impl GlcmConfig {
    pub fn check(&self) -> Result<()> {
        let bad = |reason: String| {
            Err(CoreError::Param {
                name: "glcm",
                reason,
            })
        };
        if !(2..=256).contains(&self.levels) {
            return bad(format!("levels must be 2 ..= 256, got {}", self.levels));
        }
        if self.distances.is_empty() || self.distances.contains(&0) {
            return bad("at least one distance, each at least 1".into());
        }
        if self.angles_deg.is_empty() || self.angles_deg.iter().any(|a| !a.is_finite()) {
            return bad("at least one finite angle".into());
        }
        if let Some(max) = self.max_value
            && !(max.is_finite() && max > 0.0)
        {
            return bad(format!("max_value must be positive, got {max}"));
        }
        Ok(())
    }

    pub fn output_len(&self, grid: Grid) -> Result<usize> {
        self.check()?;
        if grid.is_empty() {
            return Err(CoreError::Param {
                name: "glcm image",
                reason: format!("the image grid {grid} has no sensels"),
            });
        }
        let per_distance = if self.average_angles {
            1
        } else {
            self.angles_deg.len()
        };
        Ok(self.distances.len() * per_distance * GLCM_ATTRIBUTES)
    }

    /// The name of each feature, in order: `glcm_{attribute}_d{distance}` (averaged over the angles) or
    /// `glcm_{attribute}_d{distance}_a{angle}` (angle in degrees), distance-major.
    pub fn feature_names(&self, grid: Grid) -> Result<Vec<String>> {
        self.output_len(grid)?;
        let mut names = Vec::new();
        for &d in &self.distances {
            let angles: Vec<Option<f64>> = if self.average_angles {
                vec![None]
            } else {
                self.angles_deg.iter().copied().map(Some).collect()
            };
            for angle in angles {
                for attribute in GLCM_ATTRIBUTE_NAMES {
                    let attribute = attribute.to_ascii_lowercase();
                    names.push(match angle {
                        None => format!("glcm_{attribute}_d{d}"),
                        Some(a) => format!("glcm_{attribute}_d{d}_a{a}"),
                    });
                }
            }
        }
        Ok(names)
    }

    /// The `(Δrow, Δcol)` offset of each (distance, angle), distance-major.
    pub fn offsets(&self) -> Vec<(isize, isize)> {
        let mut out = Vec::new();
        for &d in &self.distances {
            for &angle in &self.angles_deg {
                let theta = angle.to_radians();
                out.push((
                    (theta.sin() * d as f64).round() as isize,
                    (theta.cos() * d as f64).round() as isize,
                ));
            }
        }
        out
    }
}

/// Quantises `image` into `out` as [`GlcmConfig`] describes.
pub fn quantise_into(image: &[f64], levels: usize, max_value: Option<f64>, out: &mut [u16]) {
    let max = max_value.unwrap_or_else(|| image.iter().copied().fold(0.0, f64::max));
    for (q, &v) in out.iter_mut().zip(image) {
        *q = if max > 0.0 && v > 0.0 {
            ((levels as f64 * v / max) as usize).min(levels - 1) as u16
        } else {
            0
        };
    }
}

/// The symmetric, normalised co-occurrence matrix (`levels x levels`, row-major) of a quantised image.
pub fn glcm_into(
    quantised: &[u16],
    grid: Grid,
    offset: (isize, isize),
    levels: usize,
    p: &mut [f64],
) {
    p.fill(0.0);
    let (dr, dc) = offset;
    let (rows, cols) = (grid.rows as isize, grid.cols as isize);
    let mut total = 0.0;
    for r in 0.max(-dr)..rows.min(rows - dr) {
        for c in 0.max(-dc)..cols.min(cols - dc) {
            let i = quantised[(r * cols + c) as usize] as usize;
            let j = quantised[((r + dr) * cols + c + dc) as usize] as usize;
            p[i * levels + j] += 1.0;
            p[j * levels + i] += 1.0;
            total += 2.0;
        }
    }
    if total > 0.0 {
        for value in p.iter_mut() {
            *value /= total;
        }
    }
}

/// The seven attributes of a normalised co-occurrence matrix, in [`GLCM_ATTRIBUTE_NAMES`] order.
pub fn attributes(p: &[f64], levels: usize) -> [f64; GLCM_ATTRIBUTES] {
    let (mut contrast, mut dissimilarity, mut homogeneity, mut asm, mut entropy) =
        (0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut mean_i, mut mean_j) = (0.0, 0.0);
    for i in 0..levels {
        for j in 0..levels {
            let value = p[i * levels + j];
            let diff = i as f64 - j as f64;
            contrast += value * diff * diff;
            dissimilarity += value * diff.abs();
            homogeneity += value / (1.0 + diff * diff);
            asm += value * value;
            if value > 0.0 {
                entropy -= value * value.ln();
            }
            mean_i += value * i as f64;
            mean_j += value * j as f64;
        }
    }
    let (mut var_i, mut var_j, mut cov) = (0.0, 0.0, 0.0);
    for i in 0..levels {
        for j in 0..levels {
            let value = p[i * levels + j];
            let (di, dj) = (i as f64 - mean_i, j as f64 - mean_j);
            var_i += value * di * di;
            var_j += value * dj * dj;
            cov += value * di * dj;
        }
    }
    let (std_i, std_j) = (var_i.sqrt(), var_j.sqrt());
    let correlation = if std_i < 1e-15 || std_j < 1e-15 {
        1.0
    } else {
        cov / (std_i * std_j)
    };
    [
        contrast,
        dissimilarity,
        homogeneity,
        asm,
        asm.sqrt(),
        correlation,
        entropy,
    ]
}

/// Computes GLCM features; holds its buffers (no allocation per image).
#[derive(Clone, Debug)]
pub struct GlcmExtractor {
    grid: Grid,
    config: GlcmConfig,
    offsets: Vec<(isize, isize)>,
    quantised: Vec<u16>,
    matrix: Vec<f64>,
    output_len: usize,
}

impl GlcmExtractor {
    pub fn new(grid: Grid, config: &GlcmConfig) -> Result<Self> {
        let output_len = config.output_len(grid)?;
        Ok(Self {
            grid,
            offsets: config.offsets(),
            quantised: vec![0; grid.len()],
            matrix: vec![0.0; config.levels * config.levels],
            config: config.clone(),
            output_len,
        })
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    pub fn output_len(&self) -> usize {
        self.output_len
    }

    /// The quantised image of the last extraction.
    pub fn quantised(&self) -> &[u16] {
        &self.quantised
    }

    pub fn extract_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("glcm image", self.grid.len(), image.len())?;
        check_len("glcm feature buffer", self.output_len, out.len())?;
        let levels = self.config.levels;
        quantise_into(image, levels, self.config.max_value, &mut self.quantised);
        out.fill(0.0);
        let n_angles = self.config.angles_deg.len();
        for (index, &offset) in self.offsets.iter().enumerate() {
            glcm_into(&self.quantised, self.grid, offset, levels, &mut self.matrix);
            let values = attributes(&self.matrix, levels);
            let (distance, angle) = (index / n_angles, index % n_angles);
            if self.config.average_angles {
                let dst = &mut out[distance * GLCM_ATTRIBUTES..(distance + 1) * GLCM_ATTRIBUTES];
                for (d, v) in dst.iter_mut().zip(values) {
                    *d += v / n_angles as f64;
                }
            } else {
                let start = (distance * n_angles + angle) * GLCM_ATTRIBUTES;
                out[start..start + GLCM_ATTRIBUTES].copy_from_slice(&values);
            }
        }
        Ok(())
    }
}

/// Grey-level co-occurrence attributes as a [`FeatureFamily`]: a texture family, costly, so the
/// automatic choice scores it last.
#[derive(Debug)]
pub struct GlcmFamily;

impl FeatureFamily for GlcmFamily {
    const NAME: &'static str = "glcm";
    const PRESETS: &'static [&'static str] = &["glcm"];
    const COSTLY: bool = true;
    type Config = GlcmConfig;
    type Extractor = GlcmExtractor;

    fn preset(_index: usize) -> GlcmConfig {
        GlcmConfig::default()
    }

    fn check(config: &GlcmConfig) -> Result<()> {
        config.check()
    }

    fn output_len(config: &GlcmConfig, grid: Grid) -> Result<usize> {
        config.output_len(grid)
    }

    fn feature_names(config: &GlcmConfig, grid: Grid) -> Result<Vec<String>> {
        config.feature_names(grid)
    }

    fn extractor(config: &GlcmConfig, grid: Grid) -> Result<GlcmExtractor> {
        GlcmExtractor::new(grid, config)
    }

    fn grid(extractor: &GlcmExtractor) -> Grid {
        extractor.grid()
    }

    fn len(extractor: &GlcmExtractor) -> usize {
        extractor.output_len()
    }

    fn extract_into(extractor: &mut GlcmExtractor, image: &[f64], out: &mut [f64]) -> Result<()> {
        extractor.extract_into(image, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form_on_a_tiny_image() {
        // 0 1 / 2 3 with 4 levels, offset (0, 1): pairs (0,1), (2,3) -> symmetric counts 4, P = 1/4 each
        let quantised = [0u16, 1, 2, 3];
        let mut p = vec![0.0; 16];
        glcm_into(&quantised, Grid::new(2, 2), (0, 1), 4, &mut p);
        for (i, j) in [(0, 1), (1, 0), (2, 3), (3, 2)] {
            assert!((p[i * 4 + j] - 0.25).abs() < 1e-15);
        }
        let a = attributes(&p, 4);
        assert!((a[0] - 1.0).abs() < 1e-15); // contrast
        assert!((a[1] - 1.0).abs() < 1e-15); // dissimilarity
        assert!((a[2] - 0.5).abs() < 1e-15); // homogeneity
        assert!((a[3] - 0.25).abs() < 1e-15); // ASM
        assert!((a[6] - 4.0f64.ln()).abs() < 1e-12); // entropy
    }

    #[test]
    fn offsets_follow_scikit_image() {
        let config = GlcmConfig {
            distances: vec![1, 2],
            angles_deg: vec![0.0, 45.0, 90.0, 135.0],
            ..GlcmConfig::default()
        };
        assert_eq!(
            config.offsets(),
            [
                (0, 1),
                (1, 1),
                (1, 0),
                (1, -1),
                (0, 2),
                (1, 1),
                (2, 0),
                (1, -1)
            ]
        );
    }
}
