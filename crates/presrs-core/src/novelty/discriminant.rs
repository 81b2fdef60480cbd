//! The discriminant space of a set of labelled vectors: Fisher's directions (those that separate the
//! class means most against the pooled within-class spread), scaled so that the within-class covariance
//! is the identity there, as scikit-learn's `LinearDiscriminantAnalysis.transform` gives it. Distances
//! to the class means in this space are what the novelty score measures.

use faer::Mat;
use serde::{Deserialize, Serialize};

use crate::classifier::gaussian::{Shrinkage, shrunk_factor};
use crate::error::{CoreError, Result, check_len};

/// Fisher's discriminant directions of `dims`-long vectors and the class means along them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Discriminant {
    /// Length of the vectors projected.
    pub(crate) dims: usize,
    /// The directions, `axes.len() / dims` rows of `dims` (row-major).
    pub(crate) axes: Vec<f64>,
    /// The projection of the overall mean, subtracted from every projection.
    pub(crate) offset: Vec<f64>,
    /// Each class's mean in the discriminant space, `n_classes x axes` (row-major); NaN for a class
    /// with no vector (its distance is then infinite).
    pub(crate) class_means: Vec<f64>,
}

impl Discriminant {
    /// Fits on `vectors` (`n x dims`, row-major) of `classes` (each below `n_classes`). The pooled
    /// within-class covariance is shrunk by the Ledoit-Wolf weight (what the LDA classifier does), so that
    /// a few vectors in many dimensions still give a well-posed space.
    pub fn fit(vectors: &[f64], classes: &[usize], n_classes: usize, dims: usize) -> Result<Self> {
        check_len("discriminant vectors", classes.len() * dims, vectors.len())?;
        let (means, counts) = class_means(vectors, classes, n_classes, dims)?;
        let present = counts.iter().filter(|&&count| count > 0).count();
        if present < 2 || classes.len() <= present {
            return Err(CoreError::NotEnoughData(format!(
                "the novelty score's discriminant needs two classes and more vectors than classes, got \
                 {present} classes and {} vectors",
                classes.len()
            )));
        }
        let mut residuals = vectors.to_vec();
        for (row, &class) in residuals.chunks_exact_mut(dims).zip(classes) {
            for (value, mean) in row.iter_mut().zip(&means[class * dims..]) {
                *value -= mean;
            }
        }
        let (factor, _, _) = shrunk_factor(&residuals, dims, Shrinkage::LedoitWolf)?;
        let inverse = lower_inverse(&factor, dims);
        let n = classes.len() as f64;
        let mut overall = vec![0.0; dims];
        for (class, &count) in counts.iter().enumerate() {
            for (acc, mean) in overall
                .iter_mut()
                .zip(&means[class * dims..(class + 1) * dims])
            {
                *acc += mean * count as f64 / n;
            }
        }
        // Whitened class means ν_k = L⁻¹(μ_k - μ) and the between-class scatter Σ n_k ν_k ν_kᵀ / n.
        let whitened: Vec<Vec<f64>> = (0..n_classes)
            .map(|class| {
                let centred: Vec<f64> = (0..dims)
                    .map(|j| means[class * dims + j] - overall[j])
                    .collect();
                times(&inverse, dims, &centred)
            })
            .collect();
        let between = Mat::from_fn(dims, dims, |i, j| {
            (0..n_classes)
                .filter(|&class| counts[class] > 0)
                .map(|class| counts[class] as f64 * whitened[class][i] * whitened[class][j])
                .sum::<f64>()
                / n
        });
        let directions = leading_eigenvectors(&between, present - 1)?;
        // axes = Vᵀ L⁻¹: one row per direction.
        let inverse = &inverse;
        let axes: Vec<f64> = directions
            .iter()
            .flat_map(|v| {
                (0..dims).map(move |j| (j..dims).map(|i| v[i] * inverse[i * dims + j]).sum::<f64>())
            })
            .collect();
        let mut model = Self {
            dims,
            offset: vec![0.0; directions.len()],
            axes,
            class_means: Vec::new(),
        };
        model.offset = model.project_raw(&overall);
        model.class_means = (0..n_classes)
            .flat_map(|class| {
                if counts[class] == 0 {
                    vec![f64::NAN; directions.len()]
                } else {
                    model
                        .project_raw(&means[class * dims..(class + 1) * dims])
                        .iter()
                        .zip(&model.offset)
                        .map(|(value, offset)| value - offset)
                        .collect()
                }
            })
            .collect();
        Ok(model)
    }

    /// Number of discriminant directions.
    pub fn n_axes(&self) -> usize {
        self.offset.len()
    }

    /// Number of classes.
    pub fn n_classes(&self) -> usize {
        self.class_means
            .len()
            .checked_div(self.n_axes())
            .unwrap_or(0)
    }

    /// Length of the vectors projected.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// The coordinates of every row of `vectors` (`n x dims`, row-major) in the space, `n x axes`.
    pub fn project_rows(&self, vectors: &[f64]) -> Result<Vec<f64>> {
        check_len("novelty vectors", 0, vectors.len() % self.dims.max(1))?;
        let mut out = vec![0.0; vectors.len() / self.dims.max(1) * self.n_axes()];
        let mut distances = vec![0.0; self.n_classes()];
        for (row, projected) in vectors
            .chunks_exact(self.dims.max(1))
            .zip(out.chunks_exact_mut(self.n_axes().max(1)))
        {
            self.distances_into(row, projected, &mut distances)?;
        }
        Ok(out)
    }

    fn project_raw(&self, x: &[f64]) -> Vec<f64> {
        self.axes
            .chunks_exact(self.dims)
            .map(|axis| axis.iter().zip(x).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// Writes `x`'s coordinates in the discriminant space into `out` (`n_axes` long) and each class's
    /// distance from them into `distances` (`n_classes` long; infinite for a class without vectors).
    /// Does not allocate.
    pub fn distances_into(&self, x: &[f64], out: &mut [f64], distances: &mut [f64]) -> Result<()> {
        check_len("novelty input", self.dims, x.len())?;
        check_len("novelty projection", self.n_axes(), out.len())?;
        check_len("novelty distances", self.n_classes(), distances.len())?;
        for ((value, axis), offset) in out
            .iter_mut()
            .zip(self.axes.chunks_exact(self.dims))
            .zip(&self.offset)
        {
            *value = axis.iter().zip(x).map(|(a, b)| a * b).sum::<f64>() - offset;
        }
        for (distance, mean) in distances
            .iter_mut()
            .zip(self.class_means.chunks_exact(self.n_axes().max(1)))
        {
            let squared: f64 = out.iter().zip(mean).map(|(z, m)| (z - m) * (z - m)).sum();
            *distance = if squared.is_nan() {
                f64::INFINITY
            } else {
                squared.sqrt()
            };
        }
        Ok(())
    }
}

/// The mean of each class (`n_classes x dims`, zero for an absent class) and its count.
fn class_means(
    vectors: &[f64],
    classes: &[usize],
    n_classes: usize,
    dims: usize,
) -> Result<(Vec<f64>, Vec<usize>)> {
    let mut means = vec![0.0; n_classes * dims];
    let mut counts = vec![0usize; n_classes];
    for (row, &class) in vectors.chunks_exact(dims).zip(classes) {
        if class >= n_classes {
            return Err(CoreError::Param {
                name: "class",
                reason: format!("class index {class} for {n_classes} classes"),
            });
        }
        counts[class] += 1;
        for (acc, value) in means[class * dims..].iter_mut().zip(row) {
            *acc += value;
        }
    }
    for (class, &count) in counts.iter().enumerate() {
        if count > 0 {
            for value in &mut means[class * dims..(class + 1) * dims] {
                *value /= count as f64;
            }
        }
    }
    Ok((means, counts))
}

/// The inverse of the lower-triangular `factor` (`d x d`, row-major, positive diagonal), by forward
/// substitution; lower-triangular itself.
fn lower_inverse(factor: &[f64], d: usize) -> Vec<f64> {
    let mut inverse = vec![0.0; d * d];
    for column in 0..d {
        for i in column..d {
            let identity = if i == column { 1.0 } else { 0.0 };
            let sum: f64 = (column..i)
                .map(|k| factor[i * d + k] * inverse[k * d + column])
                .sum();
            inverse[i * d + column] = (identity - sum) / factor[i * d + i];
        }
    }
    inverse
}

/// `matrix · x` for a square row-major `matrix`.
fn times(matrix: &[f64], d: usize, x: &[f64]) -> Vec<f64> {
    matrix
        .chunks_exact(d)
        .map(|row| row.iter().zip(x).map(|(a, b)| a * b).sum())
        .collect()
}

/// The eigenvectors of the symmetric `matrix` with the `count` largest eigenvalues (those above rounding
/// of the largest), largest first; the eigendecomposition is sequential, so that it does not depend on
/// the thread count.
fn leading_eigenvectors(matrix: &Mat<f64>, count: usize) -> Result<Vec<Vec<f64>>> {
    let d = matrix.nrows();
    let (values, vectors) =
        crate::linalg::symmetric_eigen(matrix.as_ref()).map_err(|err| CoreError::Param {
            name: "novelty",
            reason: format!("the between-class eigendecomposition did not converge ({err:?})"),
        })?;
    let values = values.column_vector();
    let mut order: Vec<usize> = (0..d).collect();
    order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let largest = order.first().map_or(0.0, |&k| values[k]);
    let tolerance = largest.max(0.0) * d as f64 * f64::EPSILON;
    Ok(order
        .into_iter()
        .take(count)
        .filter(|&k| values[k] > tolerance)
        .map(|k| (0..d).map(|i| vectors[(i, k)]).collect())
        .collect())
}

/// The distance from `x` to the nearest of `points` (rows of `x.len()` values); infinite without points.
pub(crate) fn nearest(points: &[f64], x: &[f64]) -> f64 {
    points
        .chunks_exact(x.len().max(1))
        .map(|point| {
            point
                .iter()
                .zip(x)
                .map(|(p, v)| (p - v) * (p - v))
                .sum::<f64>()
        })
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

/// The largest posterior of Gaussian classes centred on the class means with the identity covariance
/// (the discriminant space's pooled one) and equal priors, from the distances to the means: linear
/// discriminant analysis's confidence, read in the novelty score's own space. Classes no vector held
/// (an infinite distance) have none; 0 when no class mean is reachable.
pub(crate) fn nearest_posterior(distances: &[f64]) -> f64 {
    let nearest = distances.iter().copied().fold(f64::INFINITY, f64::min);
    if !nearest.is_finite() {
        return 0.0;
    }
    // Shifted by the nearest squared distance so that the largest term is exp(0) = 1.
    let total: f64 = distances
        .iter()
        .map(|d| (-(d * d - nearest * nearest) / 2.0).exp())
        .sum();
    1.0 / total
}
