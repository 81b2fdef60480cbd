//! Support vector machines: C-SVC with linear or RBF kernels, one-vs-one with voting (as libsvm and
//! scikit-learn's `SVC`).
//!
//! Each pair of classes `(i, j)`, `i < j`, is a binary problem with `y = +1` for class `i`, solved exactly
//! (to the KKT tolerance `tol`) by an SMO solver with libsvm's second-order working-set selection; the bias
//! is libsvm's `rho`. The solver stops at the tolerance or after [`SMO_ITERATIONS_PER_VECTOR`] iterations
//! per vector of the pair (at least [`SMO_MIN_ITERATIONS`]), whichever comes first: a large C on classes
//! that overlap can otherwise take millions of iterations for no gain in accuracy, and the capped
//! solution is still feasible (its bias is computed the same way). The decision `f(x) = Σ α_t y_t K(x_t, x) - rho > 0` votes for `i`, otherwise for
//! `j`; the most votes win, ties to the lower class index (libsvm's rule).
//!
//! Hyper-parameters: every kernel of [`SvmConfig::kernels`], every `C` of `c_grid` and (RBF) every
//! `gamma = factor · gamma_scale` with `gamma_scale = 1 / (d · var(X))` (scikit-learn's `gamma="scale"`)
//! is fitted on the training vectors and scored on the validation vectors; the best accuracy wins (ties to
//! the earlier candidate: linear before RBF, smaller C, gamma factors in grid order), and the final model is
//! fitted on training + validation. Posteriors: softmax of `Σ_{j≠c} ln σ(f_cj)` (the pairwise decisions
//! read as log-odds) at a temperature fitted on the five-fold cross-validated scores of the chosen kernel and
//! C over training + validation (`calibration::cross_validated_scores`); the voted class always holds the top posterior
//! (in the rare near-ties where the two disagree, their posteriors are swapped).

use serde::{Deserialize, Serialize};

use super::calibration::{cross_validated_scores, fit_temperature};
use super::common::LabeledVectors;
use super::common::{check_vectors, merged, require_per_class, validation_accuracy};
use crate::error::{CoreError, Result, check_len};

/// A kernel family (what is searched).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KernelKind {
    Linear,
    Rbf,
}

/// A kernel with its parameter.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Kernel {
    /// `K(a, b) = a·b`.
    Linear,
    /// `K(a, b) = exp(-gamma |a - b|²)`.
    Rbf { gamma: f64 },
}

impl Kernel {
    fn eval(&self, a: &[f64], b: &[f64]) -> f64 {
        match *self {
            Self::Linear => a.iter().zip(b).map(|(x, y)| x * y).sum(),
            Self::Rbf { gamma } => {
                let d2: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
                (-gamma * d2).exp()
            }
        }
    }
}

/// Parameters of the SVM and its hyper-parameter search.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SvmConfig {
    #[serde(default = "default_kernels")]
    pub kernels: Vec<KernelKind>,
    #[serde(default = "default_c_grid")]
    pub c_grid: Vec<f64>,
    /// RBF gamma as multiples of `1 / (d · var(X))`.
    #[serde(default = "default_gamma_factors")]
    pub gamma_factors: Vec<f64>,
    /// KKT tolerance of the solver (libsvm's `eps`).
    #[serde(default = "default_tol")]
    pub tol: f64,
}

fn default_kernels() -> Vec<KernelKind> {
    vec![KernelKind::Linear, KernelKind::Rbf]
}
fn default_c_grid() -> Vec<f64> {
    vec![0.1, 1.0, 10.0, 100.0, 1000.0]
}
fn default_gamma_factors() -> Vec<f64> {
    vec![0.1, 0.3, 1.0, 3.0, 10.0]
}
fn default_tol() -> f64 {
    1e-3
}

impl Default for SvmConfig {
    fn default() -> Self {
        Self {
            kernels: default_kernels(),
            c_grid: default_c_grid(),
            gamma_factors: default_gamma_factors(),
            tol: default_tol(),
        }
    }
}

impl SvmConfig {
    pub fn check(&self) -> Result<()> {
        let bad = |reason: &str| {
            Err(CoreError::Param {
                name: "svm",
                reason: reason.into(),
            })
        };
        let positive = |v: &f64| v.is_finite() && *v > 0.0;
        if self.kernels.is_empty() {
            return bad("at least one kernel");
        }
        if self.c_grid.is_empty() || !self.c_grid.iter().all(positive) {
            return bad("C values must be positive and finite");
        }
        if self.kernels.contains(&KernelKind::Rbf)
            && (self.gamma_factors.is_empty() || !self.gamma_factors.iter().all(positive))
        {
            return bad("gamma factors must be positive and finite");
        }
        if !positive(&self.tol) {
            return bad("the tolerance must be positive");
        }
        Ok(())
    }
}

/// One binary machine of the one-vs-one scheme.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PairMachine {
    /// Indices of the support vectors into the stored vectors.
    support: Vec<usize>,
    /// `α_t y_t` of each support vector.
    coefs: Vec<f64>,
    rho: f64,
}

/// One hyper-parameter candidate and its validation accuracy.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SvmCandidate {
    pub kernel: Kernel,
    pub c: f64,
    pub validation_accuracy: f64,
}

/// A trained one-vs-one SVM. Deserialising checks that the parts fit together: `dims` and `n_classes`
/// at least 1, `vectors` a whole number of finite rows of `dims`, one machine per pair of classes
/// (`n_classes (n_classes - 1) / 2`), each with as many `coefs` as `support` indices, every index below
/// the number of stored vectors, every coefficient and `rho` finite; a finite non-negative RBF `gamma`,
/// and a positive finite `c` and `temperature`. A file that breaks one of these is an error naming the
/// field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SvmFields", into = "SvmFields")]
pub struct SvmModel {
    dims: usize,
    n_classes: usize,
    kernel: Kernel,
    c: f64,
    /// Stored vectors (every training vector that is a support vector of some pair), `n x dims`.
    vectors: Vec<f64>,
    /// Machines for pairs (0,1), (0,2), ..., (1,2), ...
    machines: Vec<PairMachine>,
    temperature: f64,
    /// Every candidate tried, in order (empty when a single one was given).
    candidates: Vec<SvmCandidate>,
}

/// The serialised form of [`SvmModel`], checked on load (see there).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SvmFields {
    dims: usize,
    n_classes: usize,
    kernel: Kernel,
    c: f64,
    vectors: Vec<f64>,
    machines: Vec<PairMachine>,
    temperature: f64,
    candidates: Vec<SvmCandidate>,
}

impl From<SvmModel> for SvmFields {
    fn from(model: SvmModel) -> Self {
        Self {
            dims: model.dims,
            n_classes: model.n_classes,
            kernel: model.kernel,
            c: model.c,
            vectors: model.vectors,
            machines: model.machines,
            temperature: model.temperature,
            candidates: model.candidates,
        }
    }
}

impl TryFrom<SvmFields> for SvmModel {
    type Error = CoreError;

    fn try_from(fields: SvmFields) -> Result<Self> {
        let bad = |reason: String| {
            Err(CoreError::Param {
                name: "svm model",
                reason,
            })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if fields.dims == 0 || fields.n_classes == 0 {
            return bad(format!(
                "`dims` and `n_classes` must be at least 1, got {} and {}",
                fields.dims, fields.n_classes
            ));
        }
        if fields.vectors.len() % fields.dims != 0 {
            return bad(format!(
                "`vectors` holds {} values, not a whole number of rows of {} `dims`",
                fields.vectors.len(),
                fields.dims
            ));
        }
        if fields.vectors.iter().any(|v| !v.is_finite()) {
            return bad("`vectors` holds non-finite values".into());
        }
        let n_support = fields.vectors.len() / fields.dims;
        let pairs = fields
            .n_classes
            .checked_mul(fields.n_classes - 1)
            .map(|n| n / 2);
        if pairs != Some(fields.machines.len()) {
            return bad(format!(
                "`machines` holds {} machines, but {} classes need one per pair ({})",
                fields.machines.len(),
                fields.n_classes,
                pairs.map_or_else(|| "more than fit in memory".into(), |p| p.to_string())
            ));
        }
        for (index, machine) in fields.machines.iter().enumerate() {
            if machine.support.len() != machine.coefs.len() {
                return bad(format!(
                    "`machines[{index}]` has {} `support` indices but {} `coefs`",
                    machine.support.len(),
                    machine.coefs.len()
                ));
            }
            if let Some(&s) = machine.support.iter().find(|&&s| s >= n_support) {
                return bad(format!(
                    "`machines[{index}].support` refers to vector {s}, but `vectors` holds {n_support}"
                ));
            }
            if !machine.rho.is_finite() || machine.coefs.iter().any(|a| !a.is_finite()) {
                return bad(format!(
                    "`machines[{index}]` has non-finite `coefs` or `rho`"
                ));
            }
        }
        if let Kernel::Rbf { gamma } = fields.kernel
            && !(gamma.is_finite() && gamma >= 0.0)
        {
            return bad(format!(
                "the RBF kernel's `gamma` must be finite and non-negative, got {gamma}"
            ));
        }
        if !positive(fields.c) {
            return bad(format!("`c` must be positive and finite, got {}", fields.c));
        }
        if !positive(fields.temperature) {
            return bad(format!(
                "`temperature` must be positive and finite, got {}",
                fields.temperature
            ));
        }
        Ok(Self {
            dims: fields.dims,
            n_classes: fields.n_classes,
            kernel: fields.kernel,
            c: fields.c,
            vectors: fields.vectors,
            machines: fields.machines,
            temperature: fields.temperature,
            candidates: fields.candidates,
        })
    }
}

/// The solver's iteration cap per training vector of a binary problem.
pub const SMO_ITERATIONS_PER_VECTOR: usize = 25;
/// The solver's iteration cap for small problems.
pub const SMO_MIN_ITERATIONS: usize = 5_000;

/// Solves the C-SVC dual for labels `y` (±1) with the symmetric kernel matrix `k` (`n x n`); returns
/// (α, rho, iterations).
fn smo_counted(k: &[f64], y: &[f64], c: f64, tol: f64) -> (Vec<f64>, f64, usize) {
    let n = y.len();
    let q = |i: usize, j: usize| y[i] * y[j] * k[i * n + j];
    let mut alpha = vec![0.0; n];
    let mut grad = vec![-1.0; n];
    let max_iter = (SMO_ITERATIONS_PER_VECTOR * n).max(SMO_MIN_ITERATIONS);
    let tau = 1e-12;
    let mut iterations = 0;
    for _ in 0..max_iter {
        iterations += 1;
        // select i: max over I_up of -y G
        let mut gmax = f64::NEG_INFINITY;
        let mut i_sel = usize::MAX;
        for t in 0..n {
            let up = if y[t] > 0.0 {
                alpha[t] < c
            } else {
                alpha[t] > 0.0
            };
            if up && -y[t] * grad[t] >= gmax {
                gmax = -y[t] * grad[t];
                i_sel = t;
            }
        }
        if i_sel == usize::MAX {
            break;
        }
        let i = i_sel;
        let mut gmax2 = f64::NEG_INFINITY;
        let mut j_sel = usize::MAX;
        let mut obj_min = f64::INFINITY;
        for t in 0..n {
            let low = if y[t] > 0.0 {
                alpha[t] > 0.0
            } else {
                alpha[t] < c
            };
            if !low {
                continue;
            }
            let yg = y[t] * grad[t];
            gmax2 = gmax2.max(yg);
            let b = gmax + yg;
            if b > 0.0 {
                let mut a = k[i * n + i] + k[t * n + t] - 2.0 * y[i] * y[t] * q(i, t);
                if a <= 0.0 {
                    a = tau;
                }
                let obj = -(b * b) / a;
                if obj <= obj_min {
                    obj_min = obj;
                    j_sel = t;
                }
            }
        }
        if gmax + gmax2 < tol || j_sel == usize::MAX {
            break;
        }
        let j = j_sel;
        let (old_i, old_j) = (alpha[i], alpha[j]);
        let qij = q(i, j);
        if y[i] != y[j] {
            let mut quad = q(i, i) + q(j, j) + 2.0 * qij;
            if quad <= 0.0 {
                quad = tau;
            }
            let delta = (-grad[i] - grad[j]) / quad;
            let diff = alpha[i] - alpha[j];
            alpha[i] += delta;
            alpha[j] += delta;
            if diff > 0.0 {
                if alpha[j] < 0.0 {
                    alpha[j] = 0.0;
                    alpha[i] = diff;
                }
            } else if alpha[i] < 0.0 {
                alpha[i] = 0.0;
                alpha[j] = -diff;
            }
            if diff > 0.0 {
                if alpha[i] > c {
                    alpha[i] = c;
                    alpha[j] = c - diff;
                }
            } else if alpha[j] > c {
                alpha[j] = c;
                alpha[i] = c + diff;
            }
        } else {
            let mut quad = q(i, i) + q(j, j) - 2.0 * qij;
            if quad <= 0.0 {
                quad = tau;
            }
            let delta = (grad[i] - grad[j]) / quad;
            let sum = alpha[i] + alpha[j];
            alpha[i] -= delta;
            alpha[j] += delta;
            if sum > c {
                if alpha[i] > c {
                    alpha[i] = c;
                    alpha[j] = sum - c;
                }
            } else if alpha[j] < 0.0 {
                alpha[j] = 0.0;
                alpha[i] = sum;
            }
            if sum > c {
                if alpha[j] > c {
                    alpha[j] = c;
                    alpha[i] = sum - c;
                }
            } else if alpha[i] < 0.0 {
                alpha[i] = 0.0;
                alpha[j] = sum;
            }
        }
        let (di, dj) = (alpha[i] - old_i, alpha[j] - old_j);
        // Q(t, i) read along row i (k is symmetric): contiguous, where column i strides by n.
        let (row_i, row_j) = (&k[i * n..(i + 1) * n], &k[j * n..(j + 1) * n]);
        for t in 0..n {
            grad[t] += y[t] * y[i] * row_i[t] * di + y[t] * y[j] * row_j[t] * dj;
        }
    }
    // rho (libsvm's calculate_rho)
    let (mut ub, mut lb, mut sum_free, mut n_free) =
        (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
    for t in 0..n {
        let yg = y[t] * grad[t];
        if alpha[t] >= c {
            if y[t] < 0.0 {
                ub = ub.min(yg);
            } else {
                lb = lb.max(yg);
            }
        } else if alpha[t] <= 0.0 {
            if y[t] > 0.0 {
                ub = ub.min(yg);
            } else {
                lb = lb.max(yg);
            }
        } else {
            n_free += 1;
            sum_free += yg;
        }
    }
    let rho = if n_free > 0 {
        sum_free / n_free as f64
    } else {
        (ub + lb) / 2.0
    };
    (alpha, rho, iterations)
}

/// The kernel matrix (`n x n`, symmetric) of the row-major vectors (`n x dims`).
fn gram_of(vectors: &[f64], dims: usize, kernel: Kernel) -> Vec<f64> {
    let rows: Vec<&[f64]> = vectors.chunks_exact(dims).collect();
    let n = rows.len();
    let mut gram = vec![0.0; n * n];
    for a in 0..n {
        for b in 0..=a {
            let value = kernel.eval(rows[a], rows[b]);
            gram[a * n + b] = value;
            gram[b * n + a] = value;
        }
    }
    gram
}

impl SvmModel {
    /// Fits one-vs-one machines with a fixed kernel and `C` on `data` (no search, no calibration).
    pub fn fit_fixed(
        data: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        kernel: Kernel,
        c: f64,
        tol: f64,
    ) -> Result<Self> {
        check_vectors(&data, "svm training vectors", dims, n_classes)?;
        require_per_class(&data, n_classes, 1)?;
        let gram = gram_of(data.vectors, dims, kernel);
        Ok(Self::fit_on_gram(
            data,
            &gram,
            n_classes,
            dims,
            (kernel, c),
            tol,
        ))
    }

    /// [`fit_fixed`](Self::fit_fixed) on the kernel matrix `gram` of `data` (checked by the caller).
    fn fit_on_gram(
        data: LabeledVectors<'_>,
        gram: &[f64],
        n_classes: usize,
        dims: usize,
        (kernel, c): (Kernel, f64),
        tol: f64,
    ) -> Self {
        let n = data.classes.len();
        let rows: Vec<&[f64]> = data.vectors.chunks_exact(dims).collect();
        let mut used = vec![usize::MAX; n];
        let mut stored = Vec::new();
        let mut machines = Vec::new();
        for ci in 0..n_classes {
            for cj in ci + 1..n_classes {
                let members: Vec<usize> = (0..n)
                    .filter(|&t| data.classes[t] == ci || data.classes[t] == cj)
                    .collect();
                let m = members.len();
                let y: Vec<f64> = members
                    .iter()
                    .map(|&t| if data.classes[t] == ci { 1.0 } else { -1.0 })
                    .collect();
                let mut k = vec![0.0; m * m];
                for (a, &ta) in members.iter().enumerate() {
                    for (b, &tb) in members.iter().enumerate() {
                        k[a * m + b] = gram[ta * n + tb];
                    }
                }
                let (alpha, rho, _) = smo_counted(&k, &y, c, tol);
                let mut machine = PairMachine {
                    support: Vec::new(),
                    coefs: Vec::new(),
                    rho,
                };
                for (a, &t) in members.iter().enumerate() {
                    if alpha[a] > 0.0 {
                        if used[t] == usize::MAX {
                            used[t] = stored.len();
                            stored.push(t);
                        }
                        machine.support.push(used[t]);
                        machine.coefs.push(alpha[a] * y[a]);
                    }
                }
                machines.push(machine);
            }
        }
        let vectors = stored
            .iter()
            .flat_map(|&t| rows[t].iter().copied())
            .collect();
        Self {
            dims,
            n_classes,
            kernel,
            c,
            vectors,
            machines,
            temperature: 1.0,
            candidates: Vec::new(),
        }
    }

    /// Trains with the hyper-parameter search of the module documentation.
    pub fn fit(
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        config: &SvmConfig,
    ) -> Result<Self> {
        Self::fit_with(train, validation, n_classes, dims, config, true)
    }

    /// [`fit`](Self::fit), with the posterior temperature fitted or left at 1 (`calibrate`): the
    /// classes it decides are the same either way (the voted class holds the top posterior), so an
    /// automatic choice that only counts right answers skips the calibration's cross-validation.
    pub(crate) fn fit_with(
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        config: &SvmConfig,
        calibrate: bool,
    ) -> Result<Self> {
        config.check()?;
        check_vectors(&train, "svm training vectors", dims, n_classes)?;
        check_vectors(&validation, "svm validation vectors", dims, n_classes)?;
        require_per_class(&train, n_classes, 1)?;
        let count = train.vectors.len() as f64;
        let mean = train.vectors.iter().sum::<f64>() / count;
        let variance = train
            .vectors
            .iter()
            .map(|v| (v - mean).powi(2))
            .sum::<f64>()
            / count;
        let gamma_scale = if variance > 0.0 {
            1.0 / (dims as f64 * variance)
        } else {
            1.0
        };
        let mut kernels = Vec::new();
        for kind in &config.kernels {
            match kind {
                KernelKind::Linear => kernels.push(Kernel::Linear),
                KernelKind::Rbf => {
                    kernels.extend(config.gamma_factors.iter().map(|f| Kernel::Rbf {
                        gamma: f * gamma_scale,
                    }))
                }
            }
        }
        let mut candidates = Vec::new();
        let (mut kernel, mut c) = (kernels[0], config.c_grid[0]);
        // The chosen candidate's validation scores: the temperature's fallback (see below).
        let mut validation_scores = None;
        if !validation.classes.is_empty() {
            let mut best_accuracy = f64::NEG_INFINITY;
            // Each kernel's matrix once, for its whole C grid.
            let mut gram = (kernels[0], gram_of(train.vectors, dims, kernels[0]));
            for (candidate_kernel, candidate_c) in kernels
                .iter()
                .flat_map(|&kernel| config.c_grid.iter().map(move |&c| (kernel, c)))
            {
                if gram.0 != candidate_kernel {
                    gram = (
                        candidate_kernel,
                        gram_of(train.vectors, dims, candidate_kernel),
                    );
                }
                let model = Self::fit_on_gram(
                    train,
                    &gram.1,
                    n_classes,
                    dims,
                    (candidate_kernel, candidate_c),
                    config.tol,
                );
                let mut scratch = model.scratch();
                let mut posteriors = vec![0.0; n_classes];
                let accuracy = validation_accuracy(&validation, dims, |x| {
                    model.classify_into(x, &mut scratch, &mut posteriors)
                })?;
                candidates.push(SvmCandidate {
                    kernel: candidate_kernel,
                    c: candidate_c,
                    validation_accuracy: accuracy,
                });
                if accuracy > best_accuracy {
                    best_accuracy = accuracy;
                    // (only the best's scores are kept: the temperature's fallback)
                    validation_scores = calibrate
                        .then(|| model.scores_of(validation.vectors))
                        .transpose()?;
                    (kernel, c) = (candidate_kernel, candidate_c);
                }
            }
        }
        let (vectors, classes) = merged(&train, &validation);
        let all = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let mut temperature = 1.0;
        if let Some(validation_scores) = validation_scores {
            // The chosen kernel and C, cross-validated over every vector (see `cross_validated_scores`);
            // the validation set's scores where a class is too small to fold.
            let cross_validated = cross_validated_scores(
                &all,
                n_classes,
                dims,
                |part| Self::fit_fixed(*part, n_classes, dims, kernel, c, config.tol),
                |model, x, out| {
                    let mut scratch = model.scratch();
                    model.decide(x, &mut scratch)?;
                    out.copy_from_slice(&scratch.scores);
                    Ok(())
                },
            )?;
            temperature = match cross_validated {
                Some(scores) => fit_temperature(&scores, &classes, n_classes)?,
                None => fit_temperature(&validation_scores, validation.classes, n_classes)?,
            };
        }
        let mut model = Self::fit_fixed(all, n_classes, dims, kernel, c, config.tol)?;
        model.temperature = temperature;
        model.candidates = candidates;
        Ok(model)
    }

    fn scores_of(&self, vectors: &[f64]) -> Result<Vec<f64>> {
        let mut scratch = self.scratch();
        let mut out = vec![0.0; vectors.len() / self.dims * self.n_classes];
        for (x, row) in vectors
            .chunks_exact(self.dims)
            .zip(out.chunks_exact_mut(self.n_classes))
        {
            self.decide(x, &mut scratch)?;
            row.copy_from_slice(&scratch.scores);
        }
        Ok(out)
    }

    pub fn dims(&self) -> usize {
        self.dims
    }

    pub fn n_classes(&self) -> usize {
        self.n_classes
    }

    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    pub fn c(&self) -> f64 {
        self.c
    }

    pub fn n_support(&self) -> usize {
        self.vectors.len() / self.dims.max(1)
    }

    pub fn temperature(&self) -> f64 {
        self.temperature
    }

    pub fn candidates(&self) -> &[SvmCandidate] {
        &self.candidates
    }

    pub fn scratch(&self) -> SvmScratch {
        SvmScratch {
            kernel: vec![0.0; self.n_support()],
            decisions: vec![0.0; self.machines.len()],
            votes: vec![0; self.n_classes],
            scores: vec![0.0; self.n_classes],
        }
    }

    /// The pairwise decision values after [`classify_into`](Self::classify_into) or
    /// [`decision_values_into`](Self::decision_values_into), pairs (0,1), (0,2), ..., (1,2), ...
    pub fn decision_values_into<'s>(
        &self,
        x: &[f64],
        scratch: &'s mut SvmScratch,
    ) -> Result<&'s [f64]> {
        self.decide(x, scratch)?;
        Ok(&scratch.decisions)
    }

    /// Decision values, votes and log-odds scores into `scratch`; returns the voted class.
    fn decide(&self, x: &[f64], scratch: &mut SvmScratch) -> Result<usize> {
        check_len("svm input", self.dims, x.len())?;
        scratch.kernel.resize(self.n_support(), 0.0);
        scratch.decisions.resize(self.machines.len(), 0.0);
        scratch.votes.resize(self.n_classes, 0);
        scratch.scores.resize(self.n_classes, 0.0);
        for (value, sv) in scratch
            .kernel
            .iter_mut()
            .zip(self.vectors.chunks_exact(self.dims))
        {
            *value = self.kernel.eval(sv, x);
        }
        scratch.votes.fill(0);
        scratch.scores.fill(0.0);
        let mut pair = 0;
        for ci in 0..self.n_classes {
            for cj in ci + 1..self.n_classes {
                let machine = &self.machines[pair];
                let f: f64 = machine
                    .support
                    .iter()
                    .zip(&machine.coefs)
                    .map(|(&s, &a)| a * scratch.kernel[s])
                    .sum::<f64>()
                    - machine.rho;
                scratch.decisions[pair] = f;
                if f > 0.0 {
                    scratch.votes[ci] += 1;
                } else {
                    scratch.votes[cj] += 1;
                }
                // ln σ(f) for class i, ln σ(-f) for class j; ln σ(z) = -ln(1 + e^{-z}), stably
                let log_sigmoid = |z: f64| -> f64 {
                    if z >= 0.0 {
                        -(-z).exp().ln_1p()
                    } else {
                        z - z.exp().ln_1p()
                    }
                };
                scratch.scores[ci] += log_sigmoid(f);
                scratch.scores[cj] += log_sigmoid(-f);
                pair += 1;
            }
        }
        let mut best = 0;
        for class in 1..self.n_classes {
            if scratch.votes[class] > scratch.votes[best] {
                best = class;
            }
        }
        Ok(best)
    }

    /// Posteriors into `posteriors`; returns the voted class. Does not allocate once `scratch` is sized.
    pub fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut SvmScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        check_len("svm posteriors", self.n_classes, posteriors.len())?;
        let class = self.decide(x, scratch)?;
        posteriors.copy_from_slice(&scratch.scores);
        let top = super::common::softmax_in_place(posteriors, self.temperature);
        // The vote decides (libsvm's rule); in the near-ties where the smooth score disagrees, the voted
        // class takes the top posterior.
        posteriors.swap(top, class);
        Ok(class)
    }
}

/// Reusable buffers of [`SvmModel::classify_into`].
#[derive(Clone, Debug, Default)]
pub struct SvmScratch {
    kernel: Vec<f64>,
    decisions: Vec<f64>,
    votes: Vec<usize>,
    scores: Vec<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Classes that overlap completely with a huge C: the solver stops at its cap, with a feasible
    /// solution (0 <= alpha <= C, sum of alpha y = 0); a separable problem converges well before it.
    #[test]
    fn the_solver_is_capped_and_stays_feasible() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let n = 300;
        let x: Vec<[f64; 2]> = (0..n)
            .map(|_| [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)])
            .collect();
        let gram = |kernel: Kernel, x: &[[f64; 2]]| -> Vec<f64> {
            x.iter()
                .flat_map(|a| x.iter().map(move |b| kernel.eval(a, b)))
                .collect()
        };
        let rbf = Kernel::Rbf { gamma: 50.0 };
        let k = gram(rbf, &x);
        let noise: Vec<f64> = (0..n)
            .map(|_| if rng.random_bool(0.5) { 1.0 } else { -1.0 })
            .collect();
        let c = 1e6;
        let (alpha, rho, iterations) = smo_counted(&k, &noise, c, 1e-3);
        assert!(iterations <= SMO_MIN_ITERATIONS.max(SMO_ITERATIONS_PER_VECTOR * n));
        assert!(rho.is_finite());
        assert!(alpha.iter().all(|&a| (0.0..=c).contains(&a)));
        let balance: f64 = alpha.iter().zip(&noise).map(|(a, y)| a * y).sum();
        assert!(balance.abs() < 1e-6 * c, "{balance}");
        let separable: Vec<f64> = x
            .iter()
            .map(|p| if p[0] > 0.0 { 1.0 } else { -1.0 })
            .collect();
        let (_, _, iterations) = smo_counted(&gram(Kernel::Linear, &x), &separable, 10.0, 1e-3);
        assert!(iterations < SMO_MIN_ITERATIONS, "{iterations}");
    }
}
