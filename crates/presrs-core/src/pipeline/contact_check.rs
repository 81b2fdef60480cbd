//! The check, inside a frame model's training data, that decides whether its novelty score reads the
//! contact's geometry ([`crate::novelty::NoveltyContact`]): leave the model's classes out in turn and
//! compare the score's AUROC with and without the part (docs/methods.md, "The contact's geometry, where
//! the training data show it helps").

use rayon::prelude::*;

use crate::error::{Result, check_len};
use crate::features::contact::ContactConfig;
use crate::novelty::{
    ContactCheck, DEFAULT_REJECTION, LabelledVectors, NoveltyModel, assign_folds, auroc,
};

/// The most classes the check leaves out, evenly spaced in the classes' order.
pub(crate) const CHECKED_CLASSES: usize = 6;

/// The most training vectors the check reads, evenly spaced (no random draw): each of its up to
/// `2 x CHECKED_CLASSES x folds` scores fits a space and calibrates it on them.
pub(crate) const CONTACT_CHECK_SAMPLES: usize = 2000;

/// Leaves up to [`CHECKED_CLASSES`] classes out in turn inside the training data (`data`, with their
/// `raw` contact measures of `config`): for each, and each calibration fold (groups, as the
/// threshold's), a score fitted without the class and the fold (its own calibration included) scores
/// the fold's vectors, and the AUROC of the class's against the others' is read with and without the
/// part. The part is taken when the mean gain exceeds one standard error of the per-class gains (two
/// classes at least). At most [`CONTACT_CHECK_SAMPLES`] vectors are read, evenly spaced. `None` when
/// no class could be checked.
pub(crate) fn check_contact(
    config: &ContactConfig,
    data: LabelledVectors<'_>,
    raw: &[f64],
) -> Result<Option<ContactCheck>> {
    let measures = config.measures();
    check_len(
        "contact measures",
        data.classes().len() * measures,
        raw.len(),
    )?;
    let n_classes = data.n_classes();
    let all = Rows {
        vectors: data.vectors(),
        raw,
        classes: data.classes(),
        groups: data.groups(),
        dims: data.dims(),
        measures,
    };
    let classes = data.classes();
    let step = classes.len().div_ceil(CONTACT_CHECK_SAMPLES).max(1);
    let at: Vec<usize> = (0..classes.len()).step_by(step).collect();
    let data = all.select(&at);
    let data = data.rows();
    let folds = assign_folds(data.groups)?;
    let present: Vec<usize> = (0..n_classes)
        .filter(|c| data.classes.contains(c))
        .collect();
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
        .map(|&left_out| class_aurocs(config, &data, &folds, n_classes, left_out))
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

/// The AUROC of `left_out`'s vectors against the others', without and with the part, each fold of
/// `folds` held out in turn from a score fitted without it and without the class; `None` when no fold
/// could be scored or a side is empty.
fn class_aurocs(
    config: &ContactConfig,
    data: &Rows<'_>,
    folds: &[usize],
    n_classes: usize,
    left_out: usize,
) -> Result<Option<(f64, f64)>> {
    let n_folds = folds.iter().copied().max().map_or(0, |last| last + 1);
    // [without, with], each (novel, known)
    let mut scores = [(Vec::new(), Vec::new()), (Vec::new(), Vec::new())];
    for fold in 0..n_folds {
        let fit: Vec<usize> = (0..data.classes.len())
            .filter(|&i| data.classes[i] != left_out && folds[i] != fold)
            .collect();
        let held: Vec<usize> = (0..data.classes.len())
            .filter(|&i| folds[i] == fold)
            .collect();
        let (fit, held_rows) = (data.select(&fit), data.select(&held));
        // A fold whose rest cannot give a score (one group or class left) checks nothing.
        let (Ok(plain), Ok(joined)) = (
            held_out_scores(config, &fit.rows(), &held_rows.rows(), n_classes, false),
            held_out_scores(config, &fit.rows(), &held_rows.rows(), n_classes, true),
        ) else {
            continue;
        };
        for (k, &i) in held.iter().enumerate() {
            let novel = data.classes[i] == left_out;
            for (side, s) in scores.iter_mut().zip([plain[k], joined[k]]) {
                if novel { &mut side.0 } else { &mut side.1 }.push(s);
            }
        }
    }
    Ok(auroc(&scores[0].0, &scores[0].1).zip(auroc(&scores[1].0, &scores[1].1)))
}

/// The scores of `held` under a score fitted (and calibrated) on `fit`, with the contact part or not.
fn held_out_scores(
    config: &ContactConfig,
    fit: &Rows<'_>,
    held: &Rows<'_>,
    n_classes: usize,
    part: bool,
) -> Result<Vec<f64>> {
    let data = LabelledVectors::new(fit.vectors, fit.classes, fit.groups, n_classes, fit.dims)?;
    let model = if part {
        NoveltyModel::fit_with_contact(config, data, fit.raw, DEFAULT_REJECTION)?
    } else {
        NoveltyModel::fit(data, DEFAULT_REJECTION)?
    };
    let mut scratch = model.scratch();
    held.vectors
        .chunks_exact(held.dims)
        .zip(held.raw.chunks_exact(held.measures))
        .map(|(x, raw)| {
            model
                .score_parts_into(x, part.then_some(raw), &mut scratch)
                .map(|n| n.score)
        })
        .collect()
}

/// Training vectors with their raw contact measures, classes and groups, row by row.
struct Rows<'a> {
    vectors: &'a [f64],
    raw: &'a [f64],
    classes: &'a [usize],
    groups: &'a [Option<&'a str>],
    dims: usize,
    measures: usize,
}

/// The rows of [`Rows`] that [`Rows::select`] copies out.
struct OwnedRows<'a> {
    vectors: Vec<f64>,
    raw: Vec<f64>,
    classes: Vec<usize>,
    groups: Vec<Option<&'a str>>,
    dims: usize,
    measures: usize,
}

impl<'a> Rows<'a> {
    /// The rows `at`, in that order.
    fn select(&self, at: &[usize]) -> OwnedRows<'a> {
        let take = |data: &[f64], width: usize| -> Vec<f64> {
            at.iter()
                .flat_map(|&i| data[i * width..(i + 1) * width].iter().copied())
                .collect()
        };
        OwnedRows {
            vectors: take(self.vectors, self.dims),
            raw: take(self.raw, self.measures),
            classes: at.iter().map(|&i| self.classes[i]).collect(),
            groups: at.iter().map(|&i| self.groups[i]).collect(),
            dims: self.dims,
            measures: self.measures,
        }
    }
}

impl<'a> OwnedRows<'a> {
    fn rows(&self) -> Rows<'_> {
        Rows {
            vectors: &self.vectors,
            raw: &self.raw,
            classes: &self.classes,
            groups: &self.groups,
            dims: self.dims,
            measures: self.measures,
        }
    }
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
        let check_of = |separation: f64, seed: u64| {
            let (vectors, raw, classes, groups) = classes_with_contact(30, separation, seed);
            let groups = groups_of(&groups);
            let data = LabelledVectors::new(&vectors, &classes, &groups, 5, 6).unwrap();
            check_contact(&ContactConfig::default(), data, &raw)
                .unwrap()
                .unwrap()
        };
        let check = check_of(3.0, 1);
        assert_eq!(check.classes, 5);
        assert!(check.taken, "{check:?}");
        assert!(check.with > check.without + 0.05, "{check:?}");

        let check = check_of(0.0, 2);
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
            LabelledVectors::new(&fit_vectors, &kept_classes, &kept_groups, 4, 6).unwrap(),
            &fit_raw,
            0.05,
        )
        .unwrap();
        let without = NoveltyModel::fit(
            LabelledVectors::new(&fit_vectors, &kept_classes, &kept_groups, 4, 6).unwrap(),
            0.05,
        )
        .unwrap();
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
