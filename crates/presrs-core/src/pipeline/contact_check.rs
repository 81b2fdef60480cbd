//! The check, inside a frame model's training data, that decides whether its novelty score reads the
//! contact's geometry ([`crate::novelty::NoveltyContact`]): leave the model's classes out in turn and
//! compare the score's AUROC with and without the part (docs/methods.md, "The contact's geometry, where
//! the training data show it helps").

use rayon::prelude::*;

use crate::error::{Result, check_len};
use crate::features::contact::ContactConfig;
use crate::novelty::{ContactCheck, NoveltyContact, NoveltyModel, assign_folds, auroc};

/// The most classes the check leaves out, evenly spaced in the classes' order.
pub(crate) const CHECKED_CLASSES: usize = 6;

/// The most training vectors the check reads, evenly spaced (no random draw): each of its up to
/// `2 x CHECKED_CLASSES x folds` scores fits a space and calibrates it on them.
pub(crate) const CONTACT_CHECK_SAMPLES: usize = 2000;

/// Leaves up to [`CHECKED_CLASSES`] classes out in turn inside the training data (`vectors`, `n x
/// dims`, with their `raw` contact measures of `config`, `classes` and `groups`): for each, and each
/// calibration fold (groups, as the threshold's), a score fitted without the class and the fold (its
/// own calibration included) scores the fold's vectors, and the AUROC of the class's against the
/// others' is read with and without the part. The part is taken when the mean gain exceeds one standard
/// error of the per-class gains (two classes at least). At most [`CONTACT_CHECK_SAMPLES`] vectors are
/// read, evenly spaced. `None` when no class could be checked.
pub(crate) fn check_contact(
    config: &ContactConfig,
    vectors: &[f64],
    raw: &[f64],
    classes: &[usize],
    groups: &[Option<&str>],
    n_classes: usize,
    dims: usize,
) -> Result<Option<ContactCheck>> {
    check_len(
        "novelty classes",
        vectors.len() / dims.max(1),
        classes.len(),
    )?;
    let measures = config.measures();
    let step = classes.len().div_ceil(CONTACT_CHECK_SAMPLES).max(1);
    let at: Vec<usize> = (0..classes.len()).step_by(step).collect();
    let (vectors, raw) = (rows(vectors, dims, &at), rows(raw, measures, &at));
    let classes: Vec<usize> = at.iter().map(|&i| classes[i]).collect();
    let groups: Vec<Option<&str>> = at.iter().map(|&i| groups[i]).collect();
    let folds = assign_folds(&groups)?;
    let n_folds = folds.iter().copied().max().map_or(0, |last| last + 1);
    let present: Vec<usize> = (0..n_classes).filter(|c| classes.contains(c)).collect();
    let picked: Vec<usize> = if present.len() <= CHECKED_CLASSES {
        present.clone()
    } else {
        (0..CHECKED_CLASSES)
            .map(|i| present[i * (present.len() - 1) / (CHECKED_CLASSES - 1)])
            .collect()
    };
    // Each class left out in parallel: its scores depend on nothing but the data.
    let pairs: Vec<Option<(f64, f64)>> = picked
        .par_iter()
        .map(|&left_out| -> Result<Option<(f64, f64)>> {
            let mut scores = [(Vec::new(), Vec::new()), (Vec::new(), Vec::new())];
            for fold in 0..n_folds {
                let fit: Vec<usize> = (0..classes.len())
                    .filter(|&i| classes[i] != left_out && folds[i] != fold)
                    .collect();
                let held: Vec<usize> = (0..classes.len()).filter(|&i| folds[i] == fold).collect();
                let fit_vectors = rows(&vectors, dims, &fit);
                let fit_raw = rows(&raw, measures, &fit);
                let fit_classes: Vec<usize> = fit.iter().map(|&i| classes[i]).collect();
                let fit_groups: Vec<Option<&str>> = fit.iter().map(|&i| groups[i]).collect();
                let held_vectors = rows(&vectors, dims, &held);
                let held_raw = rows(&raw, measures, &held);
                let fitted = |part: bool| -> Result<Vec<f64>> {
                    let (model, held) = if part {
                        let contact = NoveltyContact::fit(config, &fit_raw, &fit_vectors, dims)?;
                        let joined = contact.joined(&fit_vectors, dims, &fit_raw)?;
                        let model = NoveltyModel::fit(
                            &joined,
                            &fit_classes,
                            &fit_groups,
                            n_classes,
                            dims + measures,
                            crate::novelty::DEFAULT_REJECTION,
                        )?;
                        (model, contact.joined(&held_vectors, dims, &held_raw)?)
                    } else {
                        let model = NoveltyModel::fit(
                            &fit_vectors,
                            &fit_classes,
                            &fit_groups,
                            n_classes,
                            dims,
                            crate::novelty::DEFAULT_REJECTION,
                        )?;
                        (model, held_vectors.clone())
                    };
                    let width = if part { dims + measures } else { dims };
                    let mut scratch = model.scratch();
                    held.chunks_exact(width)
                        .map(|x| model.score_into(x, &mut scratch).map(|n| n.score))
                        .collect()
                };
                // A fold whose rest cannot give a score (one group or class left) checks nothing.
                let (Ok(plain), Ok(joined)) = (fitted(false), fitted(true)) else {
                    continue;
                };
                for (k, &i) in held.iter().enumerate() {
                    let novel = classes[i] == left_out;
                    for (side, s) in scores.iter_mut().zip([plain[k], joined[k]]) {
                        if novel { &mut side.0 } else { &mut side.1 }.push(s);
                    }
                }
            }
            Ok(auroc(&scores[0].0, &scores[0].1).zip(auroc(&scores[1].0, &scores[1].1)))
        })
        .collect::<Result<_>>()?;
    let (without, with): (Vec<f64>, Vec<f64>) = pairs.into_iter().flatten().unzip();
    let k = without.len();
    if k == 0 {
        return Ok(None);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let gains: Vec<f64> = with.iter().zip(&without).map(|(w, o)| w - o).collect();
    let gain = mean(&gains);
    let standard_error = if k > 1 {
        let var = gains.iter().map(|g| (g - gain).powi(2)).sum::<f64>() / (k - 1) as f64;
        (var / k as f64).sqrt()
    } else {
        f64::INFINITY
    };
    Ok(Some(ContactCheck {
        without: mean(&without),
        with: mean(&with),
        standard_error,
        classes: k,
        taken: k > 1 && gain > standard_error,
    }))
}

/// The rows `at` of `data` (`width` values each).
fn rows(data: &[f64], width: usize, at: &[usize]) -> Vec<f64> {
    at.iter()
        .flat_map(|&i| data[i * width..(i + 1) * width].iter().copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// Five classes of `per_class` 6-value vectors, apart along their own axes, but class 4 drawn as
    /// class 3 is; 20 raw contact measures of noise, the first five shifted by `contact_shift` times the
    /// class (a contact that grows from class to class). Groups `g0..g4` in turn.
    fn classes_with_contact(
        per_class: usize,
        contact_shift: f64,
        seed: u64,
    ) -> (Vec<f64>, Vec<f64>, Vec<usize>, Vec<String>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let measures = ContactConfig::default().measures();
        let (mut vectors, mut raw, mut classes, mut groups) = (vec![], vec![], vec![], vec![]);
        for class in 0..5 {
            for i in 0..per_class {
                let mut row: Vec<f64> = (0..6).map(|_| rng.random::<f64>() * 2.0 - 1.0).collect();
                row[class.min(3)] += 4.0;
                vectors.extend(row);
                raw.extend((0..measures).map(|m| {
                    let noise = rng.random::<f64>();
                    if m < 5 {
                        noise + contact_shift * class as f64
                    } else {
                        noise
                    }
                }));
                classes.push(class);
                groups.push(format!("g{}", i % 5));
            }
        }
        (vectors, raw, classes, groups)
    }

    fn groups_of(groups: &[String]) -> Vec<Option<&str>> {
        groups.iter().map(|g| Some(g.as_str())).collect()
    }

    /// A class that lands on another in the classifier's space but not in its contact: leaving classes
    /// out inside the training data finds the part helps; contact measures of noise: it does not.
    #[test]
    fn the_check_takes_the_part_only_where_it_separates_classes_left_out() {
        let config = ContactConfig::default();
        let (vectors, raw, classes, groups) = classes_with_contact(30, 3.0, 1);
        let check = check_contact(&config, &vectors, &raw, &classes, &groups_of(&groups), 5, 6)
            .unwrap()
            .unwrap();
        assert_eq!(check.classes, 5);
        assert!(check.taken, "{check:?}");
        assert!(check.with > check.without + 0.05, "{check:?}");

        let (vectors, raw, classes, groups) = classes_with_contact(30, 0.0, 2);
        let check = check_contact(&config, &vectors, &raw, &classes, &groups_of(&groups), 5, 6)
            .unwrap()
            .unwrap();
        assert!(!check.taken, "{check:?}");
    }

    /// A score with the part reads the measures beside the vector (refusing a vector alone), tells the
    /// hidden class apart by them, reads the classifier's length as its own, and survives a round trip.
    #[test]
    fn a_score_with_the_contact_part_reads_both_and_round_trips() {
        let config = ContactConfig::default();
        let (vectors, raw, classes, groups) = classes_with_contact(30, 3.0, 3);
        let measures = config.measures();
        // trained without class 4, which the vectors alone place on class 3
        let keep: Vec<usize> = (0..classes.len()).filter(|&i| classes[i] != 4).collect();
        let rows = |data: &[f64], w: usize| -> Vec<f64> {
            keep.iter()
                .flat_map(|&i| data[i * w..(i + 1) * w].to_vec())
                .collect()
        };
        let kept_groups: Vec<Option<&str>> =
            keep.iter().map(|&i| Some(groups[i].as_str())).collect();
        let kept_classes: Vec<usize> = keep.iter().map(|&i| classes[i]).collect();
        let (fit_vectors, fit_raw) = (rows(&vectors, 6), rows(&raw, measures));
        let with = NoveltyModel::fit_with_contact(
            &config,
            &fit_vectors,
            &fit_raw,
            &kept_classes,
            &kept_groups,
            4,
            6,
            0.05,
        )
        .unwrap();
        let without =
            NoveltyModel::fit(&fit_vectors, &kept_classes, &kept_groups, 4, 6, 0.05).unwrap();
        assert_eq!(with.dims(), 6);
        assert_eq!(with.contact().unwrap().measures(), measures);
        let hidden = classes.iter().position(|&c| c == 4).unwrap();
        let (x, c) = (
            &vectors[hidden * 6..(hidden + 1) * 6],
            &raw[hidden * measures..(hidden + 1) * measures],
        );
        assert!(with.score(x).is_err(), "a vector alone is refused");
        let mut scratch = with.scratch();
        let novel = with.score_parts_into(x, Some(c), &mut scratch).unwrap();
        assert!(novel.unknown, "{novel:?}");
        assert!(
            !without.score(x).unwrap().unknown,
            "the vector alone looks known"
        );
        let text = serde_json::to_string(&with).unwrap();
        let back: NoveltyModel = serde_json::from_str(&text).unwrap();
        assert_eq!(back, with);
        // a part whose spread is not positive is refused on load
        let broken = text.replacen("\"spread\":[", "\"spread\":[-1.0,", 1);
        assert!(serde_json::from_str::<NoveltyModel>(&broken).is_err());
    }
}
