//! The stratified subsample an automatic choice scores its candidates on when the training data are
//! large: the candidates' ranking needs a few thousand samples, not all of them, and the winner is then
//! trained on everything.

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

use crate::pipeline::extract::LabeledImage;

/// The most samples the automatic choice scores its candidates on by default: more are subsampled,
/// stratified by label, group and condition. 4,000 samples leave a held-out fold of 1,000 or more,
/// whose accuracy has a standard error under 1.6 points; the winner is trained on every sample.
pub const SCORING_SAMPLES: usize = 4000;

/// A stratum: label, group and condition.
type Stratum<'a> = (&'a str, Option<&'a str>, Option<&'a str>);

/// `at_most` of `images` (indices, increasing), drawn per stratum, a stratum being the images of one
/// label, group and condition (so that every class keeps its share in every fold the choice makes),
/// each stratum's share in proportion to its size (largest remainders get the rest; ties to the
/// earlier stratum), its members shuffled with `seed`. `None` when there are no more than `at_most`.
/// Deterministic in `seed`.
pub(crate) fn stratified_subsample(
    images: &[LabeledImage<'_>],
    at_most: usize,
    seed: u64,
) -> Option<Vec<usize>> {
    if images.len() <= at_most {
        return None;
    }
    let mut strata: BTreeMap<Stratum<'_>, Vec<usize>> = BTreeMap::new();
    for (i, image) in images.iter().enumerate() {
        strata
            .entry((image.label, image.group, image.condition))
            .or_default()
            .push(i);
    }
    let total = images.len();
    let mut shares: Vec<(usize, usize)> = strata
        .values()
        .map(|members| {
            let exact = members.len() * at_most;
            (exact / total, exact % total)
        })
        .collect();
    let mut left = at_most - shares.iter().map(|(share, _)| share).sum::<usize>();
    let mut by_remainder: Vec<usize> = (0..shares.len()).collect();
    // (a stable sort: ties keep the strata's order)
    by_remainder.sort_by(|&a, &b| shares[b].1.cmp(&shares[a].1));
    for s in by_remainder {
        if left == 0 {
            break;
        }
        shares[s].0 += 1;
        left -= 1;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut chosen = Vec::with_capacity(at_most);
    for (mut members, (share, _)) in strata.into_values().zip(shares) {
        members.shuffle(&mut rng);
        chosen.extend_from_slice(&members[..share.min(members.len())]);
    }
    chosen.sort_unstable();
    Some(chosen)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Frame, Grid};

    fn images<'a>(frame: &'a Frame, labels: &'a [(&'a str, &'a str)]) -> Vec<LabeledImage<'a>> {
        labels
            .iter()
            .map(|&(label, group)| LabeledImage {
                group: Some(group),
                ..LabeledImage::new(frame.view(), label)
            })
            .collect()
    }

    #[test]
    fn the_subsample_keeps_each_class_and_group_share_and_follows_its_seed() {
        let frame = Frame::new(Grid::new(1, 1), vec![0.0]).unwrap();
        // 600 of a, 300 of b, 100 of c; a in two groups of 300
        let mut labels = Vec::new();
        labels.extend(std::iter::repeat_n(("a", "g1"), 300));
        labels.extend(std::iter::repeat_n(("a", "g2"), 300));
        labels.extend(std::iter::repeat_n(("b", "g1"), 300));
        labels.extend(std::iter::repeat_n(("c", "g2"), 100));
        let set = images(&frame, &labels);
        let picked = stratified_subsample(&set, 100, 7).unwrap();
        assert_eq!(picked.len(), 100);
        assert!(picked.windows(2).all(|w| w[0] < w[1]));
        let count = |label: &str, group: &str| {
            picked
                .iter()
                .filter(|&&i| set[i].label == label && set[i].group == Some(group))
                .count()
        };
        assert_eq!(
            [
                count("a", "g1"),
                count("a", "g2"),
                count("b", "g1"),
                count("c", "g2")
            ],
            [30, 30, 30, 10]
        );
        assert_eq!(stratified_subsample(&set, 100, 7).unwrap(), picked);
        assert_ne!(stratified_subsample(&set, 100, 8).unwrap(), picked);
        assert!(stratified_subsample(&set, 1000, 7).is_none());
    }

    #[test]
    fn uneven_shares_are_rounded_to_the_size_asked_for() {
        let frame = Frame::new(Grid::new(1, 1), vec![0.0]).unwrap();
        let labels: Vec<(&str, &str)> = (0..101).map(|i| (["a", "b", "c"][i % 3], "g")).collect();
        let set = images(&frame, &labels);
        for at_most in [1, 2, 10, 50, 100] {
            let picked = stratified_subsample(&set, at_most, 1).unwrap();
            assert_eq!(picked.len(), at_most);
        }
    }
}
