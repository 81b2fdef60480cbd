//! Several independent MiniRocket draws side by side: the `draws` setting of the rocket family.
//!
//! One MiniRocket model is one random draw (which channels each kernel and dilation sums, which
//! training example gives its biases), and on many-channel series the draw alone moves the accuracy by
//! a few tenths of a point (on `icub20`'s 60 taxels, four draws 97.8 to 98.2 %; aeon's draws spread the
//! same). The features of `draws` models fitted with the seeds `seed, seed + 1, ...` are concatenated,
//! so that one classifier reads them all, the way averaging several draws removes the draw's luck
//! (bench/real/RESULTS.md, "MiniRocket's draws"). Each draw costs one more transform and as many
//! features again.

use crate::error::{CoreError, Result};
use crate::features::rocket::config::RocketConfig;
use crate::features::rocket::model::RocketModel;

/// The most draws a model may have (a model file asking for more is more likely crafted than meant).
pub const MAX_DRAWS: usize = 64;

/// The configuration of draw `index` (0 is `config` itself): the same settings, the seed `index`
/// further on.
pub fn draw_config(config: &RocketConfig, index: usize) -> RocketConfig {
    RocketConfig {
        seed: config.seed.wrapping_add(index as u64),
        ..*config
    }
}

/// `Ok` when `draws` is 1 to [`MAX_DRAWS`].
pub fn check_count(draws: usize) -> Result<()> {
    if (1..=MAX_DRAWS).contains(&draws) {
        Ok(())
    } else {
        Err(CoreError::Param {
            name: "draws",
            reason: format!(
                "{draws} MiniRocket draws; ask for 1 (one model, the paper's) to {MAX_DRAWS}"
            ),
        })
    }
}

/// The draws after the first, each fitted like it on the same (scaled, padded) training series.
pub fn fit_more(
    config: &RocketConfig,
    draws: usize,
    samples: &[f64],
    channels: usize,
    length: usize,
) -> Result<Vec<RocketModel>> {
    check_count(draws)?;
    (1..draws)
        .map(|index| RocketModel::fit(&draw_config(config, index), samples, channels, length))
        .collect()
}

/// `Ok` when `more` are the draws after `first` of a model with `draws` draws of `config`: as many,
/// each of its seed and of the first's shape.
pub fn check_more(
    config: &RocketConfig,
    draws: usize,
    first: &RocketModel,
    more: &[RocketModel],
) -> Result<()> {
    check_count(draws)?;
    if more.len() + 1 != draws {
        return Err(CoreError::Param {
            name: "draws",
            reason: format!(
                "a rocket model of {draws} draws holds {} fitted draws",
                more.len() + 1
            ),
        });
    }
    for (index, model) in more.iter().enumerate() {
        model.check()?;
        let shape = (model.channels(), model.length());
        if model.config() != &draw_config(config, index + 1)
            || shape != (first.channels(), first.length())
        {
            return Err(CoreError::Param {
                name: "draws",
                reason: format!(
                    "fitted draw {} differs from the family's settings or from the first draw's shape",
                    index + 1
                ),
            });
        }
    }
    Ok(())
}

/// Feature names of draw `index`: the first draw's as they are (`rocket_d1_k0_q0`), the others with
/// the draw after the family's name (`rocket_r1_d1_k0_q0`).
pub fn names_of_draw(model: &RocketModel, family: &str, index: usize) -> Vec<String> {
    let names = model.feature_names();
    if index == 0 {
        return names;
    }
    names
        .into_iter()
        .map(|name| match name.strip_prefix(family) {
            Some(rest) => format!("{family}_r{index}{rest}"),
            None => format!("r{index}_{name}"),
        })
        .collect()
}
