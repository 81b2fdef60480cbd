//! PCA: exactness properties and a slow oracle (power iteration on the covariance matrix).

#![allow(clippy::unwrap_used)] // helpers of integration tests are test code too

use presrs_core::projection::pca::Pca;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `n x d` data with very different variances along random directions, plus an offset (so centring matters).
fn anisotropic_data(n: usize, d: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let offset: Vec<f64> = (0..d).map(|_| rng.random_range(-50.0..50.0)).collect();
    let directions: Vec<Vec<f64>> = (0..d)
        .map(|_| (0..d).map(|_| rng.random_range(-1.0..1.0)).collect())
        .collect();
    let mut data = Vec::with_capacity(n * d);
    for _ in 0..n {
        let mut row = offset.clone();
        for (k, direction) in directions.iter().enumerate() {
            let weight = rng.random_range(-1.0..1.0) * 10.0 / (1.0 + k as f64).powi(2);
            for (value, dir) in row.iter_mut().zip(direction) {
                *value += weight * dir;
            }
        }
        data.extend(row);
    }
    data
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[test]
fn keeps_min_of_dims_and_n_minus_one_components() {
    let data = anisotropic_data(52, 60, 1);
    assert_eq!(Pca::fit(&data, 60, 51).unwrap().n_components(), 51);
    assert_eq!(Pca::fit(&data, 60, 100).unwrap().n_components(), 51);
    assert_eq!(Pca::fit(&data, 60, 10).unwrap().n_components(), 10);
    // more samples than features: capped by the feature count
    let tall = anisotropic_data(30, 5, 2);
    assert_eq!(Pca::fit(&tall, 5, 100).unwrap().n_components(), 5);
}

#[test]
fn paper_shape_52_by_1025_gives_51_orthonormal_components() {
    let data = anisotropic_data(52, 1025, 3);
    let pca = Pca::fit(&data, 1025, 51).unwrap();
    assert_eq!(pca.n_components(), 51);
    assert_eq!(pca.basis().len(), 51 * 1025);
    for i in 0..51 {
        for j in 0..51 {
            let expected = if i == j { 1.0 } else { 0.0 };
            let got = dot(pca.component(i), pca.component(j));
            assert!((got - expected).abs() < 1e-12, "<u{i}, u{j}> = {got}");
        }
    }
}

#[test]
fn all_components_reconstruct_the_training_data() {
    let (n, d) = (12, 30);
    let data = anisotropic_data(n, d, 4);
    let pca = Pca::fit(&data, d, usize::MAX).unwrap();
    assert_eq!(pca.n_components(), n - 1);
    let largest = data.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let mut back = vec![0.0; d];
    for row in data.chunks(d) {
        let z = pca.project(row).unwrap();
        pca.reconstruct_into(&z, &mut back).unwrap();
        for (b, x) in back.iter().zip(row) {
            // the n - 1 components span the centred training data exactly, up to rounding
            assert!((b - x).abs() < 1e-10 * largest, "{b} vs {x}");
        }
    }
}

#[test]
fn variances_descend_and_match_the_projections() {
    let (n, d) = (40, 8);
    let data = anisotropic_data(n, d, 5);
    let pca = Pca::fit(&data, d, d).unwrap();
    let variances = pca.explained_variance();
    assert!(variances.windows(2).all(|w| w[0] >= w[1]), "{variances:?}");
    let projections: Vec<Vec<f64>> = data
        .chunks(d)
        .map(|row| pca.project(row).unwrap())
        .collect();
    for k in 0..pca.n_components() {
        let mean: f64 = projections.iter().map(|p| p[k]).sum::<f64>() / n as f64;
        assert!(mean.abs() < 1e-9, "projections are centred");
        let var: f64 = projections.iter().map(|p| p[k] * p[k]).sum::<f64>() / (n - 1) as f64;
        assert!((var - variances[k]).abs() < 1e-9 * variances[0]);
        for other in 0..k {
            let cov: f64 =
                projections.iter().map(|p| p[k] * p[other]).sum::<f64>() / (n - 1) as f64;
            assert!(
                cov.abs() < 1e-9 * variances[0],
                "components {k} and {other} correlate: {cov}"
            );
        }
    }
    let ratio: f64 = pca.explained_variance_ratio().iter().sum();
    assert!(
        (ratio - 1.0).abs() < 1e-12,
        "all d components explain everything: {ratio}"
    );
}

/// Slow oracle: eigenvectors of the sample covariance by power iteration with deflation.
fn covariance_eigen_by_power_iteration(
    data: &[f64],
    d: usize,
    count: usize,
) -> Vec<(f64, Vec<f64>)> {
    let n = data.len() / d;
    let mut mean = vec![0.0; d];
    for row in data.chunks(d) {
        for (m, x) in mean.iter_mut().zip(row) {
            *m += x / n as f64;
        }
    }
    let mut cov = vec![0.0; d * d];
    for row in data.chunks(d) {
        for i in 0..d {
            for j in 0..d {
                cov[i * d + j] += (row[i] - mean[i]) * (row[j] - mean[j]) / (n - 1) as f64;
            }
        }
    }
    let mut pairs = Vec::new();
    for _ in 0..count {
        let mut v: Vec<f64> = (0..d).map(|i| 1.0 + i as f64 * 0.1).collect();
        let mut lambda = 0.0;
        for _ in 0..20_000 {
            let w: Vec<f64> = (0..d).map(|i| dot(&cov[i * d..(i + 1) * d], &v)).collect();
            let norm = dot(&w, &w).sqrt();
            v = w.iter().map(|x| x / norm).collect();
            lambda = norm;
        }
        for i in 0..d {
            for j in 0..d {
                cov[i * d + j] -= lambda * v[i] * v[j];
            }
        }
        pairs.push((lambda, v));
    }
    pairs
}

#[test]
fn matches_power_iteration_oracle_on_a_small_case() {
    let (n, d) = (25, 6);
    let data = anisotropic_data(n, d, 6);
    let pca = Pca::fit(&data, d, 3).unwrap();
    let oracle = covariance_eigen_by_power_iteration(&data, d, 3);
    for (k, (lambda, vector)) in oracle.iter().enumerate() {
        let variance = pca.explained_variance()[k];
        assert!(
            (variance - lambda).abs() < 1e-8 * lambda,
            "variance {k}: {variance} vs {lambda}"
        );
        let cosine = dot(pca.component(k), vector).abs();
        assert!((cosine - 1.0).abs() < 1e-8, "axis {k}: |cos| = {cosine}");
    }
}

#[test]
fn signs_are_fixed_and_fitting_is_deterministic() {
    let data = anisotropic_data(20, 15, 7);
    let first = Pca::fit(&data, 15, 10).unwrap();
    let second = Pca::fit(&data, 15, 10).unwrap();
    assert_eq!(first, second, "same data, same bits");
    for k in 0..first.n_components() {
        let axis = first.component(k);
        let pivot = axis.iter().copied().fold(
            0.0f64,
            |best, a| if a.abs() > best.abs() { a } else { best },
        );
        assert!(pivot > 0.0, "largest loading of axis {k} is positive");
    }
    // flipping the data through the mean flips no axis sign: signs come from the loadings, not the data
    let negated: Vec<f64> = data.iter().map(|v| -v).collect();
    let flipped = Pca::fit(&negated, 15, 10).unwrap();
    for k in 0..first.n_components() {
        let cosine = dot(first.component(k), flipped.component(k));
        assert!((cosine - 1.0).abs() < 1e-9, "axis {k}: cos {cosine}");
    }
}

#[test]
fn serde_round_trip_and_checked_loading() {
    let data = anisotropic_data(10, 4, 8);
    let pca = Pca::fit(&data, 4, 3).unwrap();
    let json = serde_json::to_string(&pca).unwrap();
    let back: Pca = serde_json::from_str(&json).unwrap();
    assert_eq!(back, pca);
    let x = [1.0, 2.0, 3.0, 4.0];
    assert_eq!(back.project(&x).unwrap(), pca.project(&x).unwrap());

    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    value["mean"] = serde_json::json!([0.0, 0.0]);
    assert!(
        serde_json::from_value::<Pca>(value).is_err(),
        "mean of the wrong length"
    );
}

#[test]
fn projection_checks_lengths() {
    let data = anisotropic_data(10, 4, 9);
    let pca = Pca::fit(&data, 4, 3).unwrap();
    let mut out = vec![0.0; 3];
    assert!(pca.project_into(&[0.0; 5], &mut out).is_err());
    assert!(pca.project_into(&[0.0; 4], &mut out[..2]).is_err());
    assert!(pca.project_into(&[0.0; 4], &mut out).is_ok());
}

/// The f32 classification path against the exact f64 projection, on paper-sized data with a large offset
/// (as |FFT| features have: the DC term is the total load): within `1e-5` of `Σ |basis (x - mean)|` per
/// component, and the same nearest training vector for every test vector.
#[test]
fn fast_projection_matches_the_exact_one_within_single_precision() {
    let (n_train, d) = (80, 1025);
    let data = anisotropic_data(n_train + 40, d, 21);
    let (train, test) = data.split_at(n_train * d);
    let mut lifted: Vec<f64> = train.to_vec();
    let mut test_lifted: Vec<f64> = test.to_vec();
    // A shared offset of 1e5 on the first feature, like the DC bin of a loaded image.
    for row in lifted
        .chunks_exact_mut(d)
        .chain(test_lifted.chunks_exact_mut(d))
    {
        row[0] += 1e5;
    }
    let pca = Pca::fit(&lifted, d, 51).unwrap();
    let mut scratch = pca.scratch();
    let (mut exact, mut fast) = (vec![0.0; 51], vec![0.0; 51]);
    let project_fast = |x: &[f64], scratch: &mut _, out: &mut [f64]| {
        pca.project_fast_into(x, scratch, out).unwrap()
    };
    let train_fast: Vec<Vec<f64>> = lifted
        .chunks_exact(d)
        .map(|x| {
            let mut out = vec![0.0; 51];
            project_fast(x, &mut scratch, &mut out);
            out
        })
        .collect();
    let train_exact: Vec<Vec<f64>> = lifted
        .chunks_exact(d)
        .map(|x| pca.project(x).unwrap())
        .collect();
    let nearest = |set: &[Vec<f64>], z: &[f64]| {
        let distance = |v: &Vec<f64>| v.iter().zip(z).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        (0..set.len())
            .min_by(|&a, &b| distance(&set[a]).total_cmp(&distance(&set[b])))
            .unwrap()
    };
    for x in test_lifted.chunks_exact(d) {
        pca.project_into(x, &mut exact).unwrap();
        project_fast(x, &mut scratch, &mut fast);
        for k in 0..51 {
            let magnitude: f64 = pca
                .component(k)
                .iter()
                .zip(x)
                .zip(pca.mean())
                .map(|((b, v), m)| (b * (v - m)).abs())
                .sum();
            assert!(
                (fast[k] - exact[k]).abs() <= 1e-5 * magnitude,
                "component {k}: {} vs {} (sum of |terms| {magnitude})",
                fast[k],
                exact[k]
            );
        }
        assert_eq!(nearest(&train_fast, &fast), nearest(&train_exact, &exact));
    }
    // Lengths are checked as in the exact path.
    assert!(
        pca.project_fast_into(&[0.0; 3], &mut scratch, &mut fast)
            .is_err()
    );
    assert!(
        pca.project_fast_into(&lifted[..d], &mut scratch, &mut fast[..2])
            .is_err()
    );
}

/// Features given in f32 (the fast 1-D |FFT|'s output) project bit for bit as the same values widened to
/// f64, one at a time and in a batch, and the f32 path stays within the stated accuracy of the exact
/// projection (the means' rounding to f32 is added back: a large common offset costs nothing).
#[test]
fn single_precision_inputs_project_like_their_widened_values() {
    let (n_train, d) = (60, 1025);
    let mut data = anisotropic_data(n_train + 8, d, 33);
    // A large offset on every feature, the DC bin's much larger: the means are far from zero.
    for row in data.chunks_exact_mut(d) {
        row[0] += 1e5;
        for value in &mut row[1..] {
            *value += 3e3;
        }
    }
    let pca = Pca::fit(&data[..n_train * d], d, 51).unwrap();
    let dims = pca.n_components();
    let single: Vec<f32> = data[n_train * d..].iter().map(|&v| v as f32).collect();
    let widened: Vec<f64> = single.iter().map(|&v| f64::from(v)).collect();
    let mut scratch = pca.scratch();
    let (mut from_single, mut from_double) = (vec![0.0; dims], vec![0.0; dims]);
    let mut exact = vec![0.0; dims];
    for (x32, x64) in single.chunks_exact(d).zip(widened.chunks_exact(d)) {
        pca.project_fast_into(x32, &mut scratch, &mut from_single)
            .unwrap();
        pca.project_fast_into(x64, &mut scratch, &mut from_double)
            .unwrap();
        assert_eq!(from_single, from_double);
        pca.project_into(x64, &mut exact).unwrap();
        for k in 0..dims {
            let magnitude: f64 = pca
                .component(k)
                .iter()
                .zip(x64)
                .zip(pca.mean())
                .map(|((b, v), m)| (b * (v - m)).abs())
                .sum();
            assert!(
                (from_single[k] - exact[k]).abs() <= 1e-5 * magnitude,
                "component {k}: {} vs {} (sum of |terms| {magnitude})",
                from_single[k],
                exact[k]
            );
        }
    }
    let mut many_single = vec![0.0; 8 * dims];
    let mut many_double = vec![0.0; 8 * dims];
    pca.project_fast_many(&single, &mut scratch, &mut many_single)
        .unwrap();
    pca.project_fast_many(&widened, &mut scratch, &mut many_double)
        .unwrap();
    assert_eq!(many_single, many_double);
    for (x32, batched) in single.chunks_exact(d).zip(many_single.chunks_exact(dims)) {
        pca.project_fast_into(x32, &mut scratch, &mut from_single)
            .unwrap();
        assert_eq!(from_single, batched);
    }
    // Lengths are checked as in the f64 path.
    assert!(
        pca.project_fast_into(&single[..d - 1], &mut scratch, &mut from_single)
            .is_err()
    );
    assert!(
        pca.project_fast_many(&single[..d + 1], &mut scratch, &mut many_single)
            .is_err()
    );
}
