//! The solver of one binary C-SVC problem: SMO with libsvm's second-order working-set selection,
//! capped, and warm-startable along a path of increasing `C`.

/// The solver's iteration cap per training vector of a binary problem.
pub const SMO_ITERATIONS_PER_VECTOR: usize = 25;
/// The solver's iteration cap for small problems.
pub const SMO_MIN_ITERATIONS: usize = 5_000;

/// The dual variables of one binary problem and their gradient, kept between solves: a solution for
/// one `C` is feasible for any larger `C` (`0 <= α <= C`, `Σ α y = 0` still hold), and its gradient
/// does not depend on `C`, so solving a grid of `C` in increasing order starts each from the last
/// (alpha seeding) and the large, slow `C` start near their solution.
pub(super) struct Smo {
    pub alpha: Vec<f64>,
    grad: Vec<f64>,
    /// The largest `C` solved for so far (a smaller one would make `alpha` infeasible).
    c: f64,
}

impl Smo {
    /// The cold start `α = 0` for a problem of `n` vectors.
    pub fn new(n: usize) -> Self {
        Self {
            alpha: vec![0.0; n],
            grad: vec![-1.0; n],
            c: 0.0,
        }
    }

    /// Solves the C-SVC dual for labels `y` (±1) with the symmetric kernel matrix `k` (`n x n`) from the
    /// current `alpha`, to the KKT tolerance `tol` or the iteration cap; returns (rho, iterations).
    /// `c` must be at least every `C` solved for before.
    pub fn solve(&mut self, k: &[f64], y: &[f64], c: f64, tol: f64) -> (f64, usize) {
        assert!(
            c >= self.c,
            "a warm start needs a C no smaller than the last"
        );
        self.c = c;
        let n = y.len();
        let problem = Problem {
            k,
            y,
            n,
            c,
            // The diagonal read contiguously (K_tt strides by n + 1 in `k`).
            diag: (0..n).map(|t| k[t * n + t]).collect(),
        };
        let Self { alpha, grad, .. } = self;
        let max_iter = (SMO_ITERATIONS_PER_VECTOR * n).max(SMO_MIN_ITERATIONS);
        let mut iterations = 0;
        for _ in 0..max_iter {
            iterations += 1;
            let Some((i, gmax)) = problem.select_i(alpha, grad) else {
                break;
            };
            let Some(j) = problem.select_j(i, gmax, alpha, grad, tol) else {
                break;
            };
            let (old_i, old_j) = (alpha[i], alpha[j]);
            if y[i] != y[j] {
                problem.step_opposite_labels(alpha, grad, i, j);
            } else {
                problem.step_same_labels(alpha, grad, i, j);
            }
            problem.update_gradient(grad, i, j, alpha[i] - old_i, alpha[j] - old_j);
        }
        (problem.rho(alpha, grad), iterations)
    }
}

/// A quadratic below this is taken as this (libsvm's `TAU`): a non-positive-definite pair still moves.
const TAU: f64 = 1e-12;

/// One binary problem as [`Smo::solve`] sees it: the kernel matrix `k` (`n x n`, row-major), the labels
/// `y` (±1), the bound `c`, and the kernel's diagonal.
struct Problem<'a> {
    k: &'a [f64],
    y: &'a [f64],
    n: usize,
    c: f64,
    diag: Vec<f64>,
}

impl Problem<'_> {
    /// `Q_ij = y_i y_j K_ij`.
    fn q(&self, i: usize, j: usize) -> f64 {
        self.y[i] * self.y[j] * self.k[i * self.n + j]
    }

    /// Row `i` of the kernel matrix.
    fn row(&self, i: usize) -> &[f64] {
        &self.k[i * self.n..(i + 1) * self.n]
    }

    /// The first of the working set: the largest `-y G` over the vectors that can move up (the last of
    /// equals), and that value; `None` if none can.
    fn select_i(&self, alpha: &[f64], grad: &[f64]) -> Option<(usize, f64)> {
        let (y, c) = (self.y, self.c);
        let mut gmax = f64::NEG_INFINITY;
        let mut i_sel = usize::MAX;
        for t in 0..self.n {
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
        (i_sel != usize::MAX).then_some((i_sel, gmax))
    }

    /// The second of the working set, by libsvm's second-order rule (the largest decrease of the
    /// objective with `i`); `None` once the KKT gap is below `tol` or no vector can move down.
    fn select_j(
        &self,
        i: usize,
        gmax: f64,
        alpha: &[f64],
        grad: &[f64],
        tol: f64,
    ) -> Option<usize> {
        let (y, c) = (self.y, self.c);
        let row_i = self.row(i);
        let mut gmax2 = f64::NEG_INFINITY;
        let mut j_sel = usize::MAX;
        let mut obj_min = f64::INFINITY;
        for t in 0..self.n {
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
                // (= K_ii + K_tt - 2 y_i y_t Q_it exactly: y is ±1)
                let mut a = self.diag[i] + self.diag[t] - 2.0 * row_i[t];
                if a <= 0.0 {
                    a = TAU;
                }
                let obj = -(b * b) / a;
                if obj <= obj_min {
                    obj_min = obj;
                    j_sel = t;
                }
            }
        }
        if gmax + gmax2 < tol || j_sel == usize::MAX {
            None
        } else {
            Some(j_sel)
        }
    }

    /// The analytic step of the pair `i`, `j` with `y_i != y_j` (their difference is kept), clipped to
    /// the box `[0, c]`.
    fn step_opposite_labels(&self, alpha: &mut [f64], grad: &[f64], i: usize, j: usize) {
        let c = self.c;
        let mut quad = self.q(i, i) + self.q(j, j) + 2.0 * self.q(i, j);
        if quad <= 0.0 {
            quad = TAU;
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
    }

    /// The analytic step of the pair `i`, `j` with `y_i == y_j` (their sum is kept), clipped to the box
    /// `[0, c]`.
    fn step_same_labels(&self, alpha: &mut [f64], grad: &[f64], i: usize, j: usize) {
        let c = self.c;
        let mut quad = self.q(i, i) + self.q(j, j) - 2.0 * self.q(i, j);
        if quad <= 0.0 {
            quad = TAU;
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

    /// The gradient after `alpha_i` and `alpha_j` moved by `di` and `dj`.
    fn update_gradient(&self, grad: &mut [f64], i: usize, j: usize, di: f64, dj: f64) {
        let y = self.y;
        // Q(t, i) read along row i (k is symmetric): contiguous, where column i strides by n.
        let (row_i, row_j) = (self.row(i), self.row(j));
        for t in 0..self.n {
            grad[t] += y[t] * y[i] * row_i[t] * di + y[t] * y[j] * row_j[t] * dj;
        }
    }

    /// The offset `rho` (libsvm's `calculate_rho`): the mean `y G` of the free vectors, or the middle of
    /// the bounds the others set when none is free.
    fn rho(&self, alpha: &[f64], grad: &[f64]) -> f64 {
        let (y, c) = (self.y, self.c);
        let (mut ub, mut lb, mut sum_free, mut n_free) =
            (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
        for t in 0..self.n {
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
        if n_free > 0 {
            sum_free / n_free as f64
        } else {
            (ub + lb) / 2.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Kernel;
    use super::*;
    use rand::{Rng, SeedableRng};

    fn gram(kernel: Kernel, x: &[[f64; 2]]) -> Vec<f64> {
        x.iter()
            .flat_map(|a| x.iter().map(move |b| kernel.eval(a, b)))
            .collect()
    }

    fn points(n: usize, seed: u64) -> Vec<[f64; 2]> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)])
            .collect()
    }

    /// The dual objective `½ αᵀQα - Σα` (lower is better).
    fn objective(k: &[f64], y: &[f64], alpha: &[f64]) -> f64 {
        let n = y.len();
        let mut quad = 0.0;
        for i in 0..n {
            for j in 0..n {
                quad += alpha[i] * alpha[j] * y[i] * y[j] * k[i * n + j];
            }
        }
        0.5 * quad - alpha.iter().sum::<f64>()
    }

    fn assert_feasible(alpha: &[f64], y: &[f64], c: f64) {
        assert!(alpha.iter().all(|&a| (0.0..=c).contains(&a)));
        let balance: f64 = alpha.iter().zip(y).map(|(a, y)| a * y).sum();
        assert!(balance.abs() < 1e-9 * c.max(1.0), "{balance}");
    }

    /// Classes that overlap completely with a huge C: the solver stops at its cap, with a feasible
    /// solution (0 <= alpha <= C, sum of alpha y = 0); a separable problem converges well before it.
    #[test]
    fn the_solver_is_capped_and_stays_feasible() {
        let n = 300;
        let x = points(n, 4);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let k = gram(Kernel::Rbf { gamma: 50.0 }, &x);
        let noise: Vec<f64> = (0..n)
            .map(|_| if rng.random_bool(0.5) { 1.0 } else { -1.0 })
            .collect();
        let c = 1e6;
        let mut smo = Smo::new(n);
        let (rho, iterations) = smo.solve(&k, &noise, c, 1e-3);
        assert!(iterations <= SMO_MIN_ITERATIONS.max(SMO_ITERATIONS_PER_VECTOR * n));
        assert!(rho.is_finite());
        assert!(smo.alpha.iter().all(|&a| (0.0..=c).contains(&a)));
        let balance: f64 = smo.alpha.iter().zip(&noise).map(|(a, y)| a * y).sum();
        assert!(balance.abs() < 1e-6 * c, "{balance}");
        let separable: Vec<f64> = x
            .iter()
            .map(|p| if p[0] > 0.0 { 1.0 } else { -1.0 })
            .collect();
        let (_, iterations) = Smo::new(n).solve(&gram(Kernel::Linear, &x), &separable, 10.0, 1e-3);
        assert!(iterations < SMO_MIN_ITERATIONS, "{iterations}");
    }

    /// Along a grid of increasing C, each solve warm-started from the last reaches the cold start's
    /// optimum (the dual objective within the tolerance's reach, the bias close) with a feasible
    /// solution. (Whether it takes fewer iterations depends on the problem: on the real sets it saves
    /// about a tenth of the large C's; `bench/auto-cost.sh` measures it.)
    #[test]
    fn warm_starts_along_c_reach_the_cold_optimum() {
        let n = 200;
        let x = points(n, 7);
        // two overlapping classes split by a curve, so that every C leaves some margin errors
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let y: Vec<f64> = x
            .iter()
            .map(|p| {
                let side = p[1] > p[0] * p[0] - 0.3;
                if side ^ rng.random_bool(0.1) {
                    1.0
                } else {
                    -1.0
                }
            })
            .collect();
        let k = gram(Kernel::Rbf { gamma: 2.0 }, &x);
        let mut warm = Smo::new(n);
        for c in [0.1, 1.0, 10.0, 100.0] {
            let mut cold = Smo::new(n);
            let (cold_rho, cold_iterations) = cold.solve(&k, &y, c, 1e-3);
            let (warm_rho, warm_iterations) = warm.solve(&k, &y, c, 1e-3);
            let cap = SMO_MIN_ITERATIONS.max(SMO_ITERATIONS_PER_VECTOR * n);
            assert!(
                cold_iterations < cap && warm_iterations < cap,
                "C = {c}: capped"
            );
            assert_feasible(&warm.alpha, &y, c);
            let (cold_objective, warm_objective) = (
                objective(&k, &y, &cold.alpha),
                objective(&k, &y, &warm.alpha),
            );
            // (both stop at the tolerance 1e-3 on the gradient: the objectives agree to about tol · Σα)
            let slack = 1e-3 * cold.alpha.iter().sum::<f64>().max(1.0);
            assert!(
                (cold_objective - warm_objective).abs() <= slack,
                "C = {c}: cold {cold_objective}, warm {warm_objective}"
            );
            assert!(
                (cold_rho - warm_rho).abs() < 0.05 * cold_rho.abs().max(1.0),
                "C = {c}: {cold_rho} vs {warm_rho}"
            );
        }
    }

    #[test]
    #[should_panic(expected = "no smaller")]
    fn a_warm_start_refuses_a_smaller_c() {
        let x = points(10, 1);
        let y: Vec<f64> = x
            .iter()
            .map(|p| if p[0] > 0.0 { 1.0 } else { -1.0 })
            .collect();
        let k = gram(Kernel::Linear, &x);
        let mut smo = Smo::new(10);
        smo.solve(&k, &y, 10.0, 1e-3);
        smo.solve(&k, &y, 1.0, 1e-3);
    }
}
