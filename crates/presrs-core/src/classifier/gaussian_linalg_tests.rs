//! The Gaussian classifier's linear algebra (faer's LLᵀ and triangular solve) against the textbook
//! Cholesky and forward substitution it replaced, and the reconstruction `L Lᵀ = A`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

/// The textbook (Cholesky-Banachiewicz) lower factor, row-major; `None` if not positive definite.
fn textbook_cholesky(a: &[f64], d: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0; d * d];
    for j in 0..d {
        let diag = a[j * d + j] - (0..j).map(|k| l[j * d + k] * l[j * d + k]).sum::<f64>();
        if !(diag > 0.0 && diag.is_finite()) {
            return None;
        }
        l[j * d + j] = diag.sqrt();
        for i in j + 1..d {
            let dot: f64 = (0..j).map(|k| l[i * d + k] * l[j * d + k]).sum();
            l[i * d + j] = (a[i * d + j] - dot) / l[j * d + j];
        }
    }
    Some(l)
}

/// `B Bᵀ + d I` for a random `B`: symmetric positive definite, condition number in the hundreds.
fn random_spd(d: usize, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let b: Vec<f64> = (0..d * d).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mut a = vec![0.0; d * d];
    for i in 0..d {
        for j in 0..d {
            a[i * d + j] = (0..d).map(|k| b[i * d + k] * b[j * d + k]).sum::<f64>();
        }
        a[i * d + i] += d as f64;
    }
    a
}

fn max_abs(values: &[f64]) -> f64 {
    values.iter().fold(0.0, |m, v| m.max(v.abs()))
}

#[test]
fn the_factor_reconstructs_the_matrix_and_matches_the_textbook_one() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for d in [1, 2, 3, 7, 16, 33, 64] {
        let a = random_spd(d, &mut rng);
        let l = cholesky_lower(&a, d).unwrap();
        let scale = max_abs(&a);
        for i in 0..d {
            for j in 0..d {
                if j > i {
                    assert_eq!(l[i * d + j], 0.0, "upper entry ({i}, {j}), d = {d}");
                }
                let product: f64 = (0..d).map(|k| l[i * d + k] * l[j * d + k]).sum();
                // L Lᵀ = A to 1e-13 of the largest entry (round-off of d-term sums is ~1e-15 d).
                let error = (product - a[i * d + j]).abs();
                assert!(error <= 1e-13 * scale, "d = {d}, ({i}, {j}): {error:e}");
            }
        }
        // The same factor as the textbook's, to 1e-12 of its largest entry (another summation order).
        let oracle = textbook_cholesky(&a, d).unwrap();
        let tolerance = 1e-12 * max_abs(&oracle);
        for (k, (x, y)) in l.iter().zip(&oracle).enumerate() {
            assert!((x - y).abs() <= tolerance, "d = {d}, entry {k}: {x} vs {y}");
        }
    }
}

#[test]
fn matrices_that_are_not_positive_definite_are_refused() {
    let indefinite = [1.0, 2.0, 2.0, 1.0];
    let singular = [1.0, 1.0, 1.0, 1.0];
    let zero = [0.0; 9];
    let negative = [-1.0];
    let nan = [1.0, f64::NAN, f64::NAN, 1.0];
    let infinite = [f64::INFINITY, 0.0, 0.0, 1.0];
    for (a, d) in [
        (&indefinite[..], 2),
        (&singular[..], 2),
        (&zero[..], 3),
        (&negative[..], 1),
        (&nan[..], 2),
        (&infinite[..], 2),
    ] {
        assert_eq!(cholesky_lower(a, d), None, "{a:?}");
        assert_eq!(textbook_cholesky(a, d), None, "{a:?}");
    }
}

#[test]
fn a_covariance_that_no_ridge_makes_positive_definite_is_the_same_error() {
    let x = [1.0, f64::NAN, -1.0, 2.0];
    let err = shrunk_factor(&x, 2, Shrinkage::Fixed { weight: 0.5 }).unwrap_err();
    assert!(matches!(err, CoreError::NotEnoughData(_)), "{err:?}");
    assert_eq!(
        err.to_string(),
        "not enough data: the class covariance cannot be made positive definite"
    );
}

#[test]
fn a_singular_covariance_gets_a_ridge() {
    // Two identical columns: singular without shrinkage, factored after the ridge.
    let x = [1.0, 1.0, -1.0, -1.0, 2.0, 2.0, -2.0, -2.0];
    let (l, log_det, weight) = shrunk_factor(&x, 2, Shrinkage::Fixed { weight: 0.0 }).unwrap();
    assert_eq!(weight, 0.0);
    assert!(log_det.is_finite() && l[3] > 0.0, "{l:?} {log_det}");
}

#[test]
fn scores_match_textbook_forward_substitution() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (dims, n_classes, per_class) = (12, 3, 20);
    let mut vectors = Vec::new();
    let mut classes = Vec::new();
    for i in 0..n_classes * per_class {
        let class = i % n_classes;
        vectors.extend((0..dims).map(|k| rng.random_range(-1.0..1.0) + (class * k) as f64 * 0.1));
        classes.push(class);
    }
    let data = LabeledVectors {
        vectors: &vectors,
        classes: &classes,
    };
    for shared in [false, true] {
        let model =
            GaussianModel::fit_on(&data, n_classes, dims, shared, Shrinkage::LedoitWolf).unwrap();
        let mut scratch = model.scratch();
        let mut scores = vec![0.0; n_classes];
        for x in vectors.chunks_exact(dims).take(10) {
            model.log_scores_into(x, &mut scratch, &mut scores).unwrap();
            for (class, &score) in scores.iter().enumerate() {
                let group = if shared { 0 } else { class };
                let l = &model.factors[group * dims * dims..][..dims * dims];
                let mean = &model.means[class * dims..][..dims];
                let mut z = vec![0.0; dims];
                for i in 0..dims {
                    let dot: f64 = (0..i).map(|k| l[i * dims + k] * z[k]).sum();
                    z[i] = (x[i] - mean[i] - dot) / l[i * dims + i];
                }
                let quad: f64 = z.iter().map(|v| v * v).sum();
                let oracle = -0.5 * (quad + model.log_dets[group]);
                // 1e-12 relative: the solve's summation order differs from the loop's.
                assert!(
                    (score - oracle).abs() <= 1e-12 * oracle.abs().max(1.0),
                    "shared {shared}, class {class}: {score} vs {oracle}"
                );
            }
        }
    }
}
