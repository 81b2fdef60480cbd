//! Fitting: the one-vs-one machines for one kernel along a path of `C` (warm-started, see [`Smo`]),
//! and the hyper-parameter search over kernels and `C` scored on validation vectors.

use rayon::prelude::*;

use super::smo::Smo;
use super::{Kernel, KernelKind, PairMachine, SvmCandidate, SvmConfig, SvmModel};
use crate::classifier::calibration::{cross_validated_scores, fit_temperature};
use crate::classifier::common::{LabeledVectors, check_vectors, merged, require_per_class};
use crate::error::Result;

/// The kernel matrix (`n x n`, symmetric) of the row-major vectors (`n x dims`): each row's lower
/// triangle in parallel (every value computed alone, so the matrix does not depend on the thread
/// count), then mirrored.
fn gram_of(vectors: &[f64], dims: usize, kernel: Kernel) -> Vec<f64> {
    let rows: Vec<&[f64]> = vectors.chunks_exact(dims).collect();
    let n = rows.len();
    let mut gram = vec![0.0; n * n];
    gram.par_chunks_mut(n.max(1))
        .enumerate()
        .for_each(|(a, out)| {
            for (b, value) in out.iter_mut().enumerate().take(a + 1) {
                *value = kernel.eval(rows[a], rows[b]);
            }
        });
    for a in 0..n {
        for b in 0..a {
            gram[b * n + a] = gram[a * n + b];
        }
    }
    gram
}

/// The kernel between every query (rows) and every training vector (columns), each value computed as
/// [`SvmModel::classify_into`] computes it (`eval(training vector, query)`), so that decisions read
/// from it are the same, bit for bit.
fn cross_kernel_of(queries: &[f64], train: &[f64], dims: usize, kernel: Kernel) -> Vec<f64> {
    let n_train = train.len() / dims;
    let mut cross = vec![0.0; queries.len() / dims * n_train];
    queries
        .par_chunks_exact(dims)
        .zip(cross.par_chunks_exact_mut(n_train.max(1)))
        .for_each(|(x, row)| {
            for (value, t) in row.iter_mut().zip(train.chunks_exact(dims)) {
                *value = kernel.eval(t, x);
            }
        });
    cross
}

/// A machine fitted on training vectors, with the training index of each stored vector.
struct Fitted {
    model: SvmModel,
    train_index: Vec<usize>,
}

impl Fitted {
    /// The accuracy on `validation` from its kernel against the training vectors (`cross`, rows of
    /// `n_train`): the same decisions as classifying each vector, without recomputing the kernel.
    fn validation_accuracy(
        &self,
        validation: &LabeledVectors<'_>,
        cross: &[f64],
        n_train: usize,
    ) -> f64 {
        let mut scratch = self.model.scratch();
        let mut correct = 0usize;
        for (row, &class) in cross.chunks_exact(n_train).zip(validation.classes) {
            for (value, &t) in scratch.kernel.iter_mut().zip(&self.train_index) {
                *value = row[t];
            }
            if self.model.vote(&mut scratch) == class {
                correct += 1;
            }
        }
        correct as f64 / validation.classes.len().max(1) as f64
    }
}

/// One-vs-one machines with `kernel` on `data` (its kernel matrix `gram`, checked by the caller), one
/// model per `C` of `cs` (in that order). Each pair's problem is solved for the `C` in increasing order,
/// each solve starting from the last solution.
fn fit_path_on_gram(
    data: LabeledVectors<'_>,
    gram: &[f64],
    n_classes: usize,
    dims: usize,
    kernel: Kernel,
    cs: &[f64],
    tol: f64,
) -> Vec<Fitted> {
    let mut increasing: Vec<usize> = (0..cs.len()).collect();
    increasing.sort_by(|&a, &b| cs[a].total_cmp(&cs[b]));
    let class_pairs: Vec<(usize, usize)> = (0..n_classes)
        .flat_map(|ci| (ci + 1..n_classes).map(move |cj| (ci, cj)))
        .collect();
    // The pairs in parallel (each solved alone: the same solutions whatever the thread count); a
    // pair's kernel matrix is dropped once its path is solved.
    let solved: Vec<(PairProblem, PairPath)> = class_pairs
        .par_iter()
        .map(|&(ci, cj)| {
            let pair = PairProblem::of(&data, gram, ci, cj);
            let mut smo = Smo::new(pair.members.len());
            let mut path = vec![(Vec::new(), 0.0); cs.len()];
            for &index in &increasing {
                let (rho, _) = smo.solve(&pair.k, &pair.y, cs[index], tol);
                path[index] = (smo.alpha.clone(), rho);
            }
            (
                PairProblem {
                    k: Vec::new(),
                    ..pair
                },
                path,
            )
        })
        .collect();
    // per C: per pair, (alpha, rho)
    let mut solutions: Vec<Vec<(Vec<f64>, f64)>> = vec![Vec::new(); cs.len()];
    let mut pairs = Vec::with_capacity(solved.len());
    for (pair, path) in solved {
        for (index, solution) in path.into_iter().enumerate() {
            solutions[index].push(solution);
        }
        pairs.push(pair);
    }
    let rows: Vec<&[f64]> = data.vectors.chunks_exact(dims).collect();
    cs.iter()
        .zip(solutions)
        .map(|(&c, per_pair)| {
            let (machines, stored) = machines_of(&pairs, per_pair, data.classes.len());
            let vectors = stored
                .iter()
                .flat_map(|&t| rows[t].iter().copied())
                .collect();
            Fitted {
                model: SvmModel {
                    dims,
                    n_classes,
                    kernel,
                    c,
                    vectors,
                    machines,
                    temperature: 1.0,
                    candidates: Vec::new(),
                },
                train_index: stored,
            }
        })
        .collect()
}

/// One pair's solutions `(alpha, rho)`, one per `C` of a path (in the order of the `C` given).
type PairPath = Vec<(Vec<f64>, f64)>;

/// The binary problem of classes `ci` (+1) and `cj` (-1): their vectors' indices in `data`, labels and
/// kernel matrix (from `gram`, the kernel matrix of all of `data`).
struct PairProblem {
    members: Vec<usize>,
    y: Vec<f64>,
    k: Vec<f64>,
}

impl PairProblem {
    fn of(data: &LabeledVectors<'_>, gram: &[f64], ci: usize, cj: usize) -> Self {
        let n = data.classes.len();
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
        Self { members, y, k }
    }
}

/// The machines of the `pairs` with their solutions `(alpha, rho)` for one `C`, and the training
/// vectors they keep (indices into the `n` training vectors, in order of first use): each machine's
/// support vectors index into those.
fn machines_of(
    pairs: &[PairProblem],
    solutions: Vec<(Vec<f64>, f64)>,
    n: usize,
) -> (Vec<PairMachine>, Vec<usize>) {
    let mut used = vec![usize::MAX; n];
    let mut stored = Vec::new();
    let mut machines = Vec::new();
    for (pair, (alpha, rho)) in pairs.iter().zip(solutions) {
        let mut machine = PairMachine {
            support: Vec::new(),
            coefs: Vec::new(),
            rho,
        };
        for (a, &t) in pair.members.iter().enumerate() {
            if alpha[a] > 0.0 {
                if used[t] == usize::MAX {
                    used[t] = stored.len();
                    stored.push(t);
                }
                machine.support.push(used[t]);
                machine.coefs.push(alpha[a] * pair.y[a]);
            }
        }
        machines.push(machine);
    }
    (machines, stored)
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
        let mut fitted = fit_path_on_gram(data, &gram, n_classes, dims, kernel, &[c], tol);
        Ok(fitted.remove(0).model)
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
        if let Some(temperature) = config.temperature {
            return Self::fit_pinned(train, validation, n_classes, dims, config, temperature);
        }
        let grid = search_grid(config, gamma_scale(train.vectors, dims));
        let choice = Choice::search(
            &train,
            &validation,
            &grid,
            n_classes,
            dims,
            config,
            calibrate,
        )?;
        let (vectors, classes) = merged(&train, &validation);
        let all = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let (kernel, c) = (choice.kernel, choice.c);
        let mut temperature = 1.0;
        if let Some(validation_scores) = choice.validation_scores {
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
        model.candidates = choice.candidates;
        Ok(model)
    }
}

impl SvmModel {
    /// The one kernel and `C` of `config` (checked: one of each, and a fixed `temperature`) fitted on
    /// training + validation vectors, their scale read from the training vectors (as the search reads
    /// it): no search, no calibration.
    fn fit_pinned(
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        config: &SvmConfig,
        temperature: f64,
    ) -> Result<Self> {
        let (vectors, classes) = merged(&train, &validation);
        let all = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        // (the scale of the training vectors, as the search reads it)
        let grid = search_grid(config, gamma_scale(train.vectors, dims));
        let (kernel, c) = (grid[0].0, grid[0].1[0]);
        let mut model = Self::fit_fixed(all, n_classes, dims, kernel, c, config.tol)?;
        model.temperature = temperature;
        Ok(model)
    }

    /// `config` (the one this model was fitted with) narrowed to the kernel, `C` and gamma factor
    /// the model's search chose, with its temperature: fitting that on other data of the same kind
    /// (more of it) searches nothing and keeps this model's calibration. The linear kernel's `C` and
    /// the RBF's gamma stay relative to the data's scale (see the module documentation).
    pub(crate) fn pinned(&self, config: &SvmConfig) -> SvmConfig {
        // The candidates are in the order of the grid, each kernel's C in `c_grid` order; without
        // candidates (no validation vectors) the first of the grid was taken.
        let entries = grid_entries(config);
        let chosen = self
            .candidates
            .iter()
            .position(|candidate| candidate.kernel == self.kernel && candidate.c == self.c)
            .unwrap_or(0);
        let (kind, factor, c) = entries.get(chosen).copied().unwrap_or(entries[0]);
        SvmConfig {
            kernels: vec![kind],
            c_grid: vec![c],
            gamma_factors: factor.map_or_else(|| config.gamma_factors.clone(), |f| vec![f]),
            tol: config.tol,
            temperature: Some(self.temperature),
        }
    }
}

/// The candidates of `config`'s search in the order it tries them: kernel, RBF gamma factor, `C`.
fn grid_entries(config: &SvmConfig) -> Vec<(KernelKind, Option<f64>, f64)> {
    let mut entries = Vec::new();
    for kind in &config.kernels {
        match kind {
            KernelKind::Linear => {
                entries.extend(config.c_grid.iter().map(|&c| (KernelKind::Linear, None, c)))
            }
            KernelKind::Rbf => {
                for &factor in &config.gamma_factors {
                    entries.extend(
                        config
                            .c_grid
                            .iter()
                            .map(|&c| (KernelKind::Rbf, Some(factor), c)),
                    );
                }
            }
        }
    }
    entries
}

/// The kernels searched, each with its path of `C`, in the order of `config`: the linear kernel's
/// `C` and the RBF's gamma relative to the data's `gamma_scale`.
fn search_grid(config: &SvmConfig, gamma_scale: f64) -> Vec<(Kernel, Vec<f64>)> {
    let mut grid: Vec<(Kernel, Vec<f64>)> = Vec::new();
    for kind in &config.kernels {
        match kind {
            // C relative to the data's scale: the linear kernel of vectors scaled to unit
            // gamma_scale · a·b with C is the raw kernel with C · gamma_scale.
            KernelKind::Linear => grid.push((
                Kernel::Linear,
                config.c_grid.iter().map(|c| c * gamma_scale).collect(),
            )),
            KernelKind::Rbf => grid.extend(config.gamma_factors.iter().map(|f| {
                (
                    Kernel::Rbf {
                        gamma: f * gamma_scale,
                    },
                    config.c_grid.clone(),
                )
            })),
        }
    }
    grid
}

/// The outcome of the search over kernels and `C`: the chosen pair (the first of the grid without
/// validation vectors), every candidate with its validation accuracy, and the chosen model's
/// validation scores when calibrating (the temperature's fallback).
struct Choice {
    kernel: Kernel,
    c: f64,
    candidates: Vec<SvmCandidate>,
    validation_scores: Option<Vec<f64>>,
}

impl Choice {
    /// Fits every kernel's `C` path of `grid` on `train` and keeps the first most accurate on
    /// `validation`.
    fn search(
        train: &LabeledVectors<'_>,
        validation: &LabeledVectors<'_>,
        grid: &[(Kernel, Vec<f64>)],
        n_classes: usize,
        dims: usize,
        config: &SvmConfig,
        calibrate: bool,
    ) -> Result<Self> {
        let mut choice = Self {
            kernel: grid[0].0,
            c: grid[0].1[0],
            candidates: Vec::new(),
            validation_scores: None,
        };
        if validation.classes.is_empty() {
            return Ok(choice);
        }
        let mut best_accuracy = f64::NEG_INFINITY;
        let n_train = train.classes.len();
        for (candidate_kernel, cs) in grid {
            // Each kernel's matrices once, for its whole C path.
            let gram = gram_of(train.vectors, dims, *candidate_kernel);
            let cross = cross_kernel_of(validation.vectors, train.vectors, dims, *candidate_kernel);
            let path = fit_path_on_gram(
                *train,
                &gram,
                n_classes,
                dims,
                *candidate_kernel,
                cs,
                config.tol,
            );
            for fitted in path {
                let accuracy = fitted.validation_accuracy(validation, &cross, n_train);
                choice.candidates.push(SvmCandidate {
                    kernel: *candidate_kernel,
                    c: fitted.model.c,
                    validation_accuracy: accuracy,
                });
                if accuracy > best_accuracy {
                    best_accuracy = accuracy;
                    // (only the best's scores are kept: the temperature's fallback)
                    choice.validation_scores = calibrate
                        .then(|| fitted.model.scores_of(validation.vectors))
                        .transpose()?;
                    (choice.kernel, choice.c) = (*candidate_kernel, fitted.model.c);
                }
            }
        }
        Ok(choice)
    }
}

/// scikit-learn's `gamma = "scale"`: `1 / (d · var(X))` over every value of the vectors (1 when they
/// do not vary).
fn gamma_scale(vectors: &[f64], dims: usize) -> f64 {
    let count = vectors.len() as f64;
    let mean = vectors.iter().sum::<f64>() / count;
    let variance = vectors.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / count;
    if variance > 0.0 {
        1.0 / (dims as f64 * variance)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classifier::common::validation_accuracy;
    use rand::{Rng, SeedableRng};

    /// Validation accuracies read from the cross kernel are those of classifying each vector.
    #[test]
    fn validation_from_the_cross_kernel_equals_classifying() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let dims = 4;
        let n = 90;
        let vectors: Vec<f64> = (0..n * dims).map(|_| rng.random_range(-1.0..1.0)).collect();
        let classes: Vec<usize> = (0..n).map(|i| i % 3).collect();
        let (train, validation) = (
            LabeledVectors {
                vectors: &vectors[..60 * dims],
                classes: &classes[..60],
            },
            LabeledVectors {
                vectors: &vectors[60 * dims..],
                classes: &classes[60..],
            },
        );
        for kernel in [Kernel::Linear, Kernel::Rbf { gamma: 0.7 }] {
            let gram = gram_of(train.vectors, dims, kernel);
            let cross = cross_kernel_of(validation.vectors, train.vectors, dims, kernel);
            for fitted in fit_path_on_gram(train, &gram, 3, dims, kernel, &[10.0, 0.1, 1.0], 1e-3) {
                let mut scratch = fitted.model.scratch();
                let mut posteriors = [0.0; 3];
                let classified = validation_accuracy(&validation, dims, |x| {
                    fitted.model.classify_into(x, &mut scratch, &mut posteriors)
                })
                .unwrap();
                assert_eq!(
                    fitted.validation_accuracy(&validation, &cross, 60),
                    classified
                );
            }
        }
    }

    /// The oracle of pinning: the configuration a searched model pins, fitted on the same vectors,
    /// gives that model (its kernel, C, machines and temperature) without searching, for either
    /// kernel the search may choose.
    #[test]
    fn a_pinned_fit_on_the_same_data_is_the_searched_model() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let dims = 3;
        let n = 120;
        let classes: Vec<usize> = (0..n).map(|i| i % 3).collect();
        let vectors: Vec<f64> = (0..n * dims)
            .map(|k| rng.random_range(-1.0..1.0) + classes[k / dims] as f64 * 0.8)
            .collect();
        let (train, validation) = (
            LabeledVectors {
                vectors: &vectors[..80 * dims],
                classes: &classes[..80],
            },
            LabeledVectors {
                vectors: &vectors[80 * dims..],
                classes: &classes[80..],
            },
        );
        for kernels in [
            vec![KernelKind::Linear],
            vec![KernelKind::Rbf],
            SvmConfig::default().kernels,
        ] {
            let config = SvmConfig {
                kernels,
                ..SvmConfig::default()
            };
            let searched = SvmModel::fit(train, validation, 3, dims, &config).unwrap();
            let pinned = searched.pinned(&config);
            pinned.check().unwrap();
            assert_eq!(pinned.temperature, Some(searched.temperature()));
            let refit = SvmModel::fit(train, validation, 3, dims, &pinned).unwrap();
            assert!(refit.candidates().is_empty());
            assert_eq!(
                SvmModel {
                    candidates: Vec::new(),
                    ..searched
                },
                refit
            );
        }
    }

    /// The first C of a path is solved from a cold start: the model is the one `fit_fixed` gives.
    #[test]
    fn a_path_starts_cold() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let dims = 3;
        let vectors: Vec<f64> = (0..50 * dims)
            .map(|_| rng.random_range(-1.0..1.0))
            .collect();
        let classes: Vec<usize> = (0..50).map(|i| i % 2).collect();
        let data = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let kernel = Kernel::Rbf { gamma: 1.0 };
        let gram = gram_of(&vectors, dims, kernel);
        let path = fit_path_on_gram(data, &gram, 2, dims, kernel, &[5.0, 0.5], 1e-3);
        let fixed = SvmModel::fit_fixed(data, 2, dims, kernel, 0.5, 1e-3).unwrap();
        assert_eq!(path[1].model, fixed);
        assert_eq!(path[0].model.c, 5.0);
    }
}
