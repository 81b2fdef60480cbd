//! The discriminant space against Mahalanobis distances computed by definition, and the novelty verdict on
//! Gaussian classes with one left out of training.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::classifier::gaussian::ledoit_wolf;
use crate::projection::Pca;

/// `per_class` vectors of each of `n_classes` Gaussian classes in `dims` dimensions: class `k`'s mean
/// `spacing * k` along axis `k % dims`, unit noise with a correlated pair of axes; groups `g0..g4` in turn.
fn gaussian_classes(
    n_classes: usize,
    per_class: usize,
    dims: usize,
    spacing: f64,
    seed: u64,
) -> (Vec<f64>, Vec<usize>, Vec<String>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut vectors, mut classes, mut groups) = (Vec::new(), Vec::new(), Vec::new());
    for class in 0..n_classes {
        for i in 0..per_class {
            let mut row: Vec<f64> = (0..dims).map(|_| rng.random::<f64>() * 2.0 - 1.0).collect();
            row[1] += 0.8 * row[0];
            row[class % dims] += spacing * (1 + class / dims) as f64;
            vectors.extend(row);
            classes.push(class);
            groups.push(format!("g{}", i % 5));
        }
    }
    (vectors, classes, groups)
}

/// Solves `a x = b` (`a` symmetric positive definite) by Gaussian elimination.
fn solve(mut a: Vec<f64>, mut b: Vec<f64>, d: usize) -> Vec<f64> {
    for k in 0..d {
        for i in k + 1..d {
            let factor = a[i * d + k] / a[k * d + k];
            for j in k..d {
                a[i * d + j] -= factor * a[k * d + j];
            }
            b[i] -= factor * b[k];
        }
    }
    let mut x = vec![0.0; d];
    for i in (0..d).rev() {
        let sum: f64 = (i + 1..d).map(|j| a[i * d + j] * x[j]).sum();
        x[i] = (b[i] - sum) / a[i * d + i];
    }
    x
}

#[test]
fn class_means_are_apart_by_their_mahalanobis_distance() {
    let (dims, n_classes) = (6, 4);
    let (vectors, classes, _) = gaussian_classes(n_classes, 30, dims, 3.0, 1);
    let space = Discriminant::fit(&vectors, &classes, n_classes, dims).unwrap();
    assert_eq!(space.n_axes(), n_classes - 1);
    // The oracle: the shrunk pooled within-class covariance by definition, and (μa - μb)ᵀ Σ⁻¹ (μa - μb).
    let mean = |k: usize| -> Vec<f64> {
        let rows: Vec<&[f64]> = vectors
            .chunks_exact(dims)
            .zip(&classes)
            .filter(|(_, c)| **c == k)
            .map(|(r, _)| r)
            .collect();
        (0..dims)
            .map(|j| rows.iter().map(|r| r[j]).sum::<f64>() / rows.len() as f64)
            .collect()
    };
    let means: Vec<Vec<f64>> = (0..n_classes).map(mean).collect();
    let residuals: Vec<f64> = vectors
        .chunks_exact(dims)
        .zip(&classes)
        .flat_map(|(r, &c)| {
            r.iter()
                .zip(&means[c])
                .map(|(x, m)| x - m)
                .collect::<Vec<_>>()
        })
        .collect();
    let (weight, emp) = ledoit_wolf(&residuals, dims).unwrap();
    let mu = (0..dims).map(|i| emp[i * dims + i]).sum::<f64>() / dims as f64;
    let cov: Vec<f64> = (0..dims * dims)
        .map(|ij| {
            (1.0 - weight) * emp[ij]
                + if ij / dims == ij % dims {
                    weight * mu
                } else {
                    0.0
                }
        })
        .collect();
    let mut projected = vec![0.0; space.n_axes()];
    let mut distances = vec![0.0; n_classes];
    for a in 0..n_classes {
        space
            .distances_into(&means[a], &mut projected, &mut distances)
            .unwrap();
        for b in 0..n_classes {
            let diff: Vec<f64> = means[a].iter().zip(&means[b]).map(|(x, y)| x - y).collect();
            let solved = solve(cov.clone(), diff.clone(), dims);
            let oracle = diff
                .iter()
                .zip(&solved)
                .map(|(x, y)| x * y)
                .sum::<f64>()
                .sqrt();
            assert!(
                (distances[b] - oracle).abs() <= 1e-9 * (1.0 + oracle),
                "classes {a} and {b}: {} against {oracle}",
                distances[b]
            );
        }
    }
}

#[test]
fn a_class_never_seen_is_unknown_and_known_ones_are_kept() {
    let (dims, n_classes) = (8, 6);
    let (vectors, classes, groups) = gaussian_classes(n_classes, 60, dims, 4.0, 2);
    // Train on classes 0..5 (60 each), hold class 5 out; test on fresh draws of every class.
    let known = classes.iter().position(|&c| c == n_classes - 1).unwrap();
    let groups: Vec<Option<&str>> = groups[..known].iter().map(|g| Some(g.as_str())).collect();
    let model = NoveltyModel::fit(
        LabelledVectors::new(
            &vectors[..known * dims],
            &classes[..known],
            &groups,
            n_classes - 1,
            dims,
        )
        .unwrap(),
        DEFAULT_REJECTION,
    )
    .unwrap();
    assert_eq!(model.folds(), CalibrationFolds::Group);
    let (test, test_classes, _) = gaussian_classes(n_classes, 200, dims, 4.0, 3);
    let mut scratch = model.scratch();
    let (mut known_rejected, mut known_count, mut novel_rejected, mut novel_count) = (0, 0, 0, 0);
    for (row, &class) in test.chunks_exact(dims).zip(&test_classes) {
        let novelty = model.score_into(row, &mut scratch).unwrap();
        assert_eq!(novelty, model.score(row).unwrap());
        if class == n_classes - 1 {
            novel_count += 1;
            novel_rejected += usize::from(novelty.unknown);
        } else {
            known_count += 1;
            known_rejected += usize::from(novelty.unknown);
        }
    }
    let known_rate = known_rejected as f64 / known_count as f64;
    let novel_rate = novel_rejected as f64 / novel_count as f64;
    assert!(known_rate < 0.08, "known rejected {known_rate}");
    assert!(novel_rate > 0.9, "novel rejected {novel_rate}");
}

#[test]
fn with_one_group_the_score_is_refused_saying_why_and_the_threshold_is_the_asked_quantile() {
    let (dims, n_classes) = (5, 3);
    let (vectors, classes, groups) = gaussian_classes(n_classes, 40, dims, 3.0, 4);
    let none = vec![None; classes.len()];
    let err = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &none, n_classes, dims).unwrap(),
        0.1,
    )
    .unwrap_err();
    assert!(
        err.to_string().contains("120 of 120 samples have no group"),
        "{err}"
    );
    let one = vec![Some("a"); classes.len()];
    let err = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &one, n_classes, dims).unwrap(),
        0.1,
    )
    .unwrap_err();
    assert!(err.to_string().contains("come from 1 group(s)"), "{err}");
    // Two groups calibrate, each held out against the other.
    let two: Vec<Option<&str>> = (0..classes.len())
        .map(|i| Some(["a", "b"][i % 2]))
        .collect();
    let paired = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &two, n_classes, dims).unwrap(),
        0.1,
    )
    .unwrap();
    assert_eq!(paired.folds(), CalibrationFolds::Group);
    let groups: Vec<Option<&str>> = groups.iter().map(|g| Some(g.as_str())).collect();
    let model = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &groups, n_classes, dims).unwrap(),
        0.1,
    )
    .unwrap();
    assert_eq!(model.folds(), CalibrationFolds::Group);
    let strict = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &groups, n_classes, dims).unwrap(),
        0.01,
    )
    .unwrap();
    assert!(strict.threshold() > model.threshold());
    // The threshold is the 0.9 quantile of the held-out scores it keeps.
    let calibration = &model.fields.combined;
    let above = calibration
        .iter()
        .filter(|&&d| d > model.threshold())
        .count();
    assert!(above <= calibration.len() / 10 + 1, "{above} above");
    // The training vectors themselves are inside the space they fitted: about 1 - 0.1 of them kept.
    let rejected = vectors
        .chunks_exact(dims)
        .filter(|row| model.score(row).unwrap().unknown)
        .count();
    assert!(rejected <= classes.len() / 10, "{rejected} rejected");
}

#[test]
fn a_class_recorded_in_one_group_does_not_calibrate_and_one_group_per_class_is_refused() {
    let (dims, n_classes) = (5, 3);
    let (vectors, classes, groups) = gaussian_classes(n_classes, 40, dims, 3.0, 7);
    // Class 2 in group "solo" alone: its held-out vectors would measure a class never seen.
    let mixed: Vec<Option<&str>> = classes
        .iter()
        .zip(&groups)
        .map(|(&c, g)| Some(if c == 2 { "solo" } else { g.as_str() }))
        .collect();
    let model = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &mixed, n_classes, dims).unwrap(),
        0.05,
    )
    .unwrap();
    assert_eq!(model.fields.calibration_vectors, 80);
    // Every class in a group of its own: nothing to calibrate on, and the error says so.
    let names = ["c0", "c1", "c2"];
    let own: Vec<Option<&str>> = classes.iter().map(|&c| Some(names[c])).collect();
    let err = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &own, n_classes, dims).unwrap(),
        0.05,
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .contains("no class is recorded in two groups"),
        "{err}"
    );
}

#[test]
fn a_model_round_trips_and_a_broken_one_is_refused() {
    let (vectors, classes, groups) = gaussian_classes(3, 20, 4, 3.0, 5);
    let groups: Vec<Option<&str>> = groups.iter().map(|g| Some(g.as_str())).collect();
    let model = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &groups, 3, 4).unwrap(),
        0.05,
    )
    .unwrap();
    let json = serde_json::to_value(&model).unwrap();
    let back: NoveltyModel = serde_json::from_value(json.clone()).unwrap();
    assert_eq!(back, model);
    let mut broken = json.clone();
    broken["neighbours"] = serde_json::json!([1.0, 2.0, 3.0]);
    let err = serde_json::from_value::<NoveltyModel>(broken).unwrap_err();
    assert!(err.to_string().contains("neighbour values"), "{err}");
    let mut negative = json;
    negative["threshold"] = serde_json::json!(-1.0);
    assert!(serde_json::from_value::<NoveltyModel>(negative).is_err());
    assert!(model.score(&[0.0; 3]).is_err());
}

#[test]
fn the_credibility_is_the_share_of_held_out_scores_at_least_as_high_and_caps_the_confidence() {
    let (dims, n_classes) = (6, 4);
    let (vectors, classes, groups) = gaussian_classes(n_classes, 50, dims, 4.0, 6);
    let groups: Vec<Option<&str>> = groups.iter().map(|g| Some(g.as_str())).collect();
    let model = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &groups, n_classes, dims).unwrap(),
        0.05,
    )
    .unwrap();
    let calibration = &model.fields.combined;
    let n = calibration.len() as f64;
    assert_eq!(calibration.len(), model.fields.calibration_vectors);
    // Nearer than every held-out distance: (n + 1) / (n + 1); beyond them all: 1 / (n + 1).
    assert_eq!(model.credibility(0.0), Some(1.0));
    assert_eq!(model.credibility(f64::INFINITY), Some(1.0 / (n + 1.0)));
    let median = calibration[calibration.len() / 2];
    let at_least = calibration.iter().filter(|&&d| d >= median).count() as f64;
    assert_eq!(
        model.credibility(median),
        Some((at_least + 1.0) / (n + 1.0))
    );
    // At the threshold, about the rejected share of held-out distances lies beyond.
    let at_threshold = model.credibility(model.threshold()).unwrap();
    assert!((0.03..=0.08).contains(&at_threshold), "{at_threshold}");
    // The verdict carries it and caps a posterior by it, never raising one.
    let far = model.verdict(1.0);
    let credibility = far.credibility.unwrap();
    assert!(far.unknown && credibility < 0.05);
    assert_eq!(far.capped(0.99), credibility);
    assert_eq!(model.verdict(0.0).capped(0.7), 0.7);
    assert_eq!(Novelty::of(1.0, 2.0).capped(0.99), 0.99);
    // A file written before the held-out distances were kept loads, without a credibility.
    let mut older = serde_json::to_value(&model).unwrap();
    older.as_object_mut().unwrap().remove("calibration");
    older.as_object_mut().unwrap().remove("combined");
    let older: NoveltyModel = serde_json::from_value(older).unwrap();
    assert_eq!(older.verdict(1.0).credibility, None);
    for (field, values) in [
        ("calibration", serde_json::json!([2.0, 1.0])),
        ("combined", serde_json::json!([0.2, 0.1])),
        ("combined", serde_json::json!([0.1, 1.5])),
    ] {
        let mut broken = serde_json::to_value(&model).unwrap();
        broken[field] = values;
        assert!(serde_json::from_value::<NoveltyModel>(broken).is_err());
    }
    // Held-out scores without the distances they were read against are refused.
    let mut orphan = serde_json::to_value(&model).unwrap();
    orphan.as_object_mut().unwrap().remove("calibration");
    let err = serde_json::from_value::<NoveltyModel>(orphan).unwrap_err();
    assert!(err.to_string().contains("held-out distances"), "{err}");
}

/// `(k + 1) / (n + 1)` by counting, `k` of `values` at least `x`.
fn p_value_by_counting(values: &[f64], x: f64) -> f64 {
    let at_least = values.iter().filter(|&&v| v >= x).count();
    (at_least + 1) as f64 / (values.len() + 1) as f64
}

#[test]
fn the_score_is_one_minus_the_posterior_times_the_distance_credibility_by_definition() {
    let (dims, n_classes) = (6, 4);
    let (vectors, classes, groups) = gaussian_classes(n_classes, 40, dims, 3.0, 8);
    let groups: Vec<Option<&str>> = groups.iter().map(|g| Some(g.as_str())).collect();
    let model = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &groups, n_classes, dims).unwrap(),
        0.05,
    )
    .unwrap();
    let fields = &model.fields;
    assert_eq!(fields.combined.len(), fields.calibration.len());
    let space = &fields.space;
    let axes = space.n_axes();
    let (test, _, _) = gaussian_classes(n_classes + 1, 10, dims, 3.0, 9);
    for row in test.chunks_exact(dims) {
        // The oracle: project, the nearest neighbour by brute force, the posterior as a softmax of
        // -d^2 / 2 over the class means written out.
        let z: Vec<f64> = space
            .axes
            .chunks_exact(dims)
            .zip(&space.offset)
            .map(|(axis, offset)| axis.iter().zip(row).map(|(a, x)| a * x).sum::<f64>() - offset)
            .collect();
        let squared =
            |point: &[f64]| -> f64 { point.iter().zip(&z).map(|(p, v)| (p - v) * (p - v)).sum() };
        let distance = fields
            .neighbours
            .chunks_exact(axes)
            .map(|p| squared(p).sqrt())
            .fold(f64::INFINITY, f64::min);
        let weights: Vec<f64> = space
            .class_means
            .chunks_exact(axes)
            .map(|mean| (-squared(mean) / 2.0).exp())
            .collect();
        let posterior = weights.iter().copied().fold(0.0, f64::max) / weights.iter().sum::<f64>();
        let credibility = p_value_by_counting(&fields.calibration, distance);
        let expected = 1.0 - posterior * credibility;
        let novelty = model.score(row).unwrap();
        assert!(
            (novelty.score - expected).abs() < 1e-9,
            "{} against {expected}",
            novelty.score
        );
        assert_eq!(novelty.unknown, novelty.score > model.threshold());
        let p = p_value_by_counting(&fields.combined, novelty.score);
        assert!((novelty.credibility.unwrap() - p).abs() < 1e-12);
    }
}

#[test]
fn a_file_without_the_held_out_scores_scores_by_the_distance_alone() {
    let (dims, n_classes) = (5, 3);
    let (vectors, classes, groups) = gaussian_classes(n_classes, 30, dims, 3.0, 10);
    let groups: Vec<Option<&str>> = groups.iter().map(|g| Some(g.as_str())).collect();
    let model = NoveltyModel::fit(
        LabelledVectors::new(&vectors, &classes, &groups, n_classes, dims).unwrap(),
        0.05,
    )
    .unwrap();
    let mut json = serde_json::to_value(&model).unwrap();
    json.as_object_mut().unwrap().remove("combined");
    json["threshold"] = serde_json::json!(2.5);
    let older: NoveltyModel = serde_json::from_value(json).unwrap();
    let mut scratch = older.scratch();
    for row in vectors.chunks_exact(dims).take(20) {
        let mut projected = vec![0.0; older.fields.space.n_axes()];
        let mut to_means = vec![0.0; n_classes];
        older
            .fields
            .space
            .distances_into(row, &mut projected, &mut to_means)
            .unwrap();
        let distance = nearest(&older.fields.neighbours, &projected);
        let novelty = older.score_into(row, &mut scratch).unwrap();
        assert_eq!(novelty.score, distance);
        assert_eq!(novelty.unknown, distance > 2.5);
        assert_eq!(
            novelty.credibility,
            Some(p_value_by_counting(&older.fields.calibration, distance))
        );
    }
    assert!(older.describe().starts_with("distance to the nearest"));
    assert!(
        model
            .describe()
            .starts_with("1 - the nearest class's posterior")
    );
}

#[test]
fn the_held_out_scores_read_each_distance_against_all_held_out_ones() {
    let held_out = calibration::HeldOut {
        folds: CalibrationFolds::Group,
        distances: vec![3.0, 1.0, 2.0, 2.0],
        posteriors: vec![0.5, 1.0, 0.8, 0.9],
    };
    let sorted = [1.0, 2.0, 2.0, 3.0];
    // 3.0: 1 of 4 at least as far; 1.0: 4 of 4; 2.0: 3 of 4.
    let expected = [1.0 - 0.5 * 0.25, 0.0, 1.0 - 0.8 * 0.75, 1.0 - 0.9 * 0.75];
    let scores = calibration::held_out_scores(&held_out, &sorted);
    for (score, want) in scores.iter().zip(expected) {
        assert!((score - want).abs() < 1e-12, "{score} against {want}");
    }
}

#[test]
fn one_class_cannot_fit_a_space() {
    let vectors = vec![0.0, 1.0, 2.0, 3.0];
    assert!(Discriminant::fit(&vectors, &[0, 0], 1, 2).is_err());
}

#[test]
fn auroc_is_the_share_of_pairs_ordered_right() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    // Rounded scores, so that ties happen.
    let mut draw = |shift: f64, n: usize| -> Vec<f64> {
        (0..n)
            .map(|_| ((rng.random::<f64>() + shift) * 10.0).round() / 10.0)
            .collect()
    };
    let (positives, negatives) = (draw(0.3, 37), draw(0.0, 51));
    let mut pairs = 0.0;
    for p in &positives {
        for n in &negatives {
            pairs += if p > n {
                1.0
            } else if p == n {
                0.5
            } else {
                0.0
            };
        }
    }
    let oracle = pairs / (positives.len() * negatives.len()) as f64;
    let fast = auroc(&positives, &negatives).unwrap();
    assert!((fast - oracle).abs() < 1e-12, "{fast} against {oracle}");
    assert_eq!(auroc(&[1.0], &[0.0]), Some(1.0));
    assert_eq!(auroc(&[], &[0.0]), None);
    assert_eq!(auroc(&[f64::NAN], &[0.0]), None);
}

#[test]
fn a_reduction_scores_the_projection_and_must_fit_the_space() {
    let (dims, n_classes) = (6, 4);
    let (vectors, classes, groups) = gaussian_classes(n_classes, 40, dims, 3.0, 11);
    let groups: Vec<Option<&str>> = groups.iter().map(|g| Some(g.as_str())).collect();
    let pca = Pca::fit(&vectors, dims, 4).unwrap();
    let projected: Vec<f64> = vectors
        .chunks_exact(dims)
        .flat_map(|row| pca.project(row).unwrap())
        .collect();
    let plain = NoveltyModel::fit(
        LabelledVectors::new(&projected, &classes, &groups, n_classes, 4).unwrap(),
        0.05,
    )
    .unwrap();
    let reduced = plain.clone().with_reduction(pca.clone()).unwrap();
    assert_eq!((plain.dims(), reduced.dims()), (4, dims));
    let mut scratch = reduced.scratch();
    for row in vectors.chunks_exact(dims).take(15) {
        assert_eq!(
            reduced.score_into(row, &mut scratch).unwrap(),
            plain.score(&pca.project(row).unwrap()).unwrap()
        );
    }
    assert!(reduced.score(&[0.0; 4]).is_err());
    let json = serde_json::to_value(&reduced).unwrap();
    assert_eq!(
        serde_json::from_value::<NoveltyModel>(json).unwrap(),
        reduced
    );
    let err = plain
        .with_reduction(Pca::fit(&vectors, dims, 3).unwrap())
        .unwrap_err();
    assert!(
        err.to_string().contains("reduction to 3 components"),
        "{err}"
    );
}

/// The labelled vectors are checked once: a row count that does not match the classes, a group per
/// vector missing, a class past the classes' count or vectors of no values are refused by name.
#[test]
fn labelled_vectors_refuse_what_does_not_fit_together() {
    let vectors = [0.0; 6];
    let classes = [0, 1, 1];
    let groups = [Some("a"), Some("b"), None];
    let data = LabelledVectors::new(&vectors, &classes, &groups, 2, 2).unwrap();
    assert_eq!(
        (data.dims(), data.n_classes(), data.classes().len()),
        (2, 2, 3)
    );
    let err = |result: Result<LabelledVectors<'_>>| result.unwrap_err().to_string();
    assert!(
        err(LabelledVectors::new(&vectors, &classes, &groups, 2, 3)).contains("novelty vectors")
    );
    assert!(
        err(LabelledVectors::new(&vectors, &classes, &groups[..2], 2, 2))
            .contains("novelty groups")
    );
    assert!(err(LabelledVectors::new(&vectors, &classes, &groups, 1, 2)).contains("class 1 of 1"));
    assert!(err(LabelledVectors::new(&[], &[], &[], 2, 0)).contains("novelty dims"));
    let wider = [0.0; 9];
    assert_eq!(data.with_vectors(&wider, 3).unwrap().dims(), 3);
    assert!(data.with_vectors(&wider, 2).is_err());
}
