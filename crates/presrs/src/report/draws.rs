//! How many images per class the report's evaluations draw, when a class is short.

use std::collections::BTreeMap;

use presrs_core::pipeline::LabeledImage;
use presrs_core::split::ValidationSize;

/// The draw per class when the smallest class has `smallest` images and `per_class` (with `validation`
/// of them) were asked for: as asked when every class has enough; else `smallest` per class, with a
/// count for validation turned into the same fraction of `per_class` (7 of 20 -> 0.35 of what is
/// drawn), so that the draw shrinks as a whole. A fraction stays. (`per_class: usize::MAX` is "every
/// image": a count then stays a count.)
pub fn shrink_draw(
    smallest: usize,
    per_class: usize,
    validation: ValidationSize,
) -> (usize, ValidationSize) {
    if smallest >= per_class {
        return (per_class, validation);
    }
    let validation = match validation {
        ValidationSize::Count(count)
            if count > 0 && count < per_class && per_class != usize::MAX =>
        {
            ValidationSize::Fraction(count as f64 / per_class as f64)
        }
        other => other,
    };
    (smallest, validation)
}

/// How many images per class the report's evaluations draw for training + validation: `per_class`, or
/// [`shrink_draw`]'s fewer when a class has fewer; and when `condition` covers every sample (`None`, or
/// the only condition) and the smallest class would be drawn whole, two thirds of it, so that every class
/// keeps images to test on (true in the third place then).
pub(super) fn evaluation_draw(
    samples: &[LabeledImage<'_>],
    condition: Option<&str>,
    per_class: usize,
    validation: ValidationSize,
) -> (usize, ValidationSize, bool) {
    let smallest = smallest_class(samples, condition);
    let covers_every_sample = condition.is_none_or(|c| {
        samples
            .iter()
            .all(|s| s.condition.is_none_or(|own| own == c))
    });
    if covers_every_sample && smallest <= per_class {
        let draw = smallest - smallest.div_ceil(3);
        let (draw, validation) = shrink_draw(draw, per_class, validation);
        (draw, validation, true)
    } else {
        let (draw, validation) = shrink_draw(smallest, per_class, validation);
        (draw, validation, false)
    }
}

/// The number of images of the smallest class among `samples` of `condition` (all when `None`).
pub(super) fn smallest_class(samples: &[LabeledImage<'_>], condition: Option<&str>) -> usize {
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for s in samples
        .iter()
        .filter(|s| condition.is_none_or(|c| s.condition == Some(c)))
    {
        *counts.entry(s.label).or_default() += 1;
    }
    counts.values().copied().min().unwrap_or(0)
}
