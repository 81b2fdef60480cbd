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
//! fitted on training + validation. The linear kernel's `C` is relative to the same scale: it is
//! fitted with `C · gamma_scale` (the raw kernel with that C is the kernel of vectors scaled to unit
//! `d · var(X)` with C), so that the grid means the same on features of any magnitude (the stored `c`
//! is the one fitted). Each kernel's matrix, and its values against the validation vectors, are
//! computed once for its whole `C` grid, which is solved in increasing order, each `C` warm-started
//! from the last (`fit`).
//!
//! Posteriors: softmax of `Σ_{j≠c} ln σ(f_cj)` (the pairwise decisions
//! read as log-odds) at a temperature fitted on the five-fold cross-validated scores of the chosen kernel and
//! C over training + validation (`calibration::cross_validated_scores`); the voted class always holds the top posterior
//! (in the rare near-ties where the two disagree, their posteriors are swapped).

use serde::{Deserialize, Serialize};

use crate::classifier::family::{ClassifierFamily, FitData};
use crate::error::{CoreError, Result, check_len};

mod fit;
mod smo;

pub use smo::{SMO_ITERATIONS_PER_VECTOR, SMO_MIN_ITERATIONS};

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
    /// The `C` searched (for the linear kernel, in units of `gamma_scale`: see the module docs).
    #[serde(default = "default_c_grid")]
    pub c_grid: Vec<f64>,
    /// RBF gamma as multiples of `1 / (d · var(X))`.
    #[serde(default = "default_gamma_factors")]
    pub gamma_factors: Vec<f64>,
    /// KKT tolerance of the solver (libsvm's `eps`).
    #[serde(default = "default_tol")]
    pub tol: f64,
    /// A posterior temperature fixed beforehand: with one kernel and one `C` (and gamma), nothing is
    /// searched and nothing calibrated, and the machines are fitted on every vector. What
    /// [`ClassifierFamily::pinned`] gives, to train a choice made on a subsample on all the data;
    /// `None` (the default): the search and the calibration of the module documentation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature: Option<f64>,
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
            temperature: None,
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
        if let Some(temperature) = self.temperature {
            if !positive(&temperature) {
                return bad("a fixed temperature must be positive and finite");
            }
            let gammas = if self.kernels == [KernelKind::Rbf] {
                self.gamma_factors.len()
            } else {
                1
            };
            if self.kernels.len() != 1 || self.c_grid.len() != 1 || gammas != 1 {
                return bad("a fixed temperature needs one kernel, one C and one gamma factor");
            }
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

/// What is wrong with `machines[index]` of a model of `n_support` vectors, or `None`.
fn machine_problem(index: usize, machine: &PairMachine, n_support: usize) -> Option<String> {
    if machine.support.len() != machine.coefs.len() {
        return Some(format!(
            "`machines[{index}]` has {} `support` indices but {} `coefs`",
            machine.support.len(),
            machine.coefs.len()
        ));
    }
    if let Some(&s) = machine.support.iter().find(|&&s| s >= n_support) {
        return Some(format!(
            "`machines[{index}].support` refers to vector {s}, but `vectors` holds {n_support}"
        ));
    }
    if !machine.rho.is_finite() || machine.coefs.iter().any(|a| !a.is_finite()) {
        return Some(format!(
            "`machines[{index}]` has non-finite `coefs` or `rho`"
        ));
    }
    None
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
        if let Some(reason) = fields
            .machines
            .iter()
            .enumerate()
            .find_map(|(index, machine)| machine_problem(index, machine, n_support))
        {
            return bad(reason);
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

impl SvmModel {
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
        for (value, sv) in scratch
            .kernel
            .iter_mut()
            .zip(self.vectors.chunks_exact(self.dims))
        {
            *value = self.kernel.eval(sv, x);
        }
        Ok(self.vote(scratch))
    }

    /// [`decide`](Self::decide) from the kernel values in `scratch.kernel` (one per stored vector).
    fn vote(&self, scratch: &mut SvmScratch) -> usize {
        scratch.decisions.resize(self.machines.len(), 0.0);
        scratch.votes.resize(self.n_classes, 0);
        scratch.scores.resize(self.n_classes, 0.0);
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
        best
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

/// The one-vs-one C-SVC as a registered family (`svm`).
#[derive(Debug)]
pub struct SvmFamily;

impl ClassifierFamily for SvmFamily {
    const NAME: &'static str = "svm";
    type Config = SvmConfig;
    type Model = SvmModel;
    type Scratch = SvmScratch;

    fn check(config: &SvmConfig) -> Result<()> {
        config.check()
    }

    fn fit(config: &SvmConfig, data: FitData<'_>) -> Result<SvmModel> {
        SvmModel::fit_with(
            data.train,
            data.validation,
            data.n_classes,
            data.dims,
            config,
            data.calibrate,
        )
    }

    const PINS: bool = true;

    fn pinned(config: &SvmConfig, model: &SvmModel) -> Option<SvmConfig> {
        Some(model.pinned(config))
    }

    fn dims(model: &SvmModel) -> usize {
        model.dims()
    }

    fn n_classes(model: &SvmModel) -> usize {
        model.n_classes()
    }

    fn describe(model: &SvmModel) -> String {
        match model.kernel() {
            Kernel::Linear => format!("linear, C {}, {} SVs", model.c(), model.n_support()),
            Kernel::Rbf { gamma } => {
                format!(
                    "rbf gamma {gamma:.3e}, C {}, {} SVs",
                    model.c(),
                    model.n_support()
                )
            }
        }
    }

    fn scratch(model: &SvmModel) -> SvmScratch {
        model.scratch()
    }

    fn classify_into(
        model: &SvmModel,
        x: &[f64],
        scratch: &mut SvmScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        model.classify_into(x, scratch, posteriors)
    }
}
