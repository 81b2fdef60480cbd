//! The parameters of a MiniRocket model, checked once.

use serde::{Deserialize, Serialize};

use super::kernels::{KERNEL_COUNT, KERNEL_LENGTH};
use crate::error::{CoreError, Result};

/// The most features a model may ask for (about 100 times the paper's 10,000; a model file asking for
/// more is more likely crafted than meant).
pub const MAX_FEATURES: usize = 1_000_000;

/// Parameters of the MiniRocket features.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RocketConfig {
    /// Features wanted: rounded down to a multiple of the 84 kernels (9,996 for 10,000); 1 to 83 give
    /// 84, one per kernel. Zero is an error.
    pub num_features: usize,
    /// The most dilations per kernel (the paper's 32); fewer when there are fewer features per kernel.
    pub max_dilations_per_kernel: usize,
    /// The seed of every random choice (channel combinations, the examples the biases come from).
    pub seed: u64,
}

impl Default for RocketConfig {
    /// The paper's setting: 10,000 features, at most 32 dilations per kernel, seed 0.
    fn default() -> Self {
        Self {
            num_features: 10_000,
            max_dilations_per_kernel: 32,
            seed: 0,
        }
    }
}

impl RocketConfig {
    /// `Ok` when the parameters can make a model; else an error naming the field and what to try.
    pub fn check(&self) -> Result<()> {
        if self.num_features == 0 {
            return Err(CoreError::Param {
                name: "num_features",
                reason: format!(
                    "0 features; ask for at least {KERNEL_COUNT} (one per kernel), 10000 is the paper's"
                ),
            });
        }
        if self.num_features > MAX_FEATURES {
            return Err(CoreError::Param {
                name: "num_features",
                reason: format!(
                    "{} features is more than the {MAX_FEATURES} allowed; the paper uses 10000",
                    self.num_features
                ),
            });
        }
        if self.max_dilations_per_kernel == 0 {
            return Err(CoreError::Param {
                name: "max_dilations_per_kernel",
                reason: "0 dilations per kernel; allow at least 1 (the paper's 32)".to_string(),
            });
        }
        Ok(())
    }

    /// Biases per kernel: `num_features / 84`, at least 1.
    pub fn features_per_kernel(&self) -> usize {
        (self.num_features / KERNEL_COUNT).max(1)
    }

    /// The number of features a model of this configuration gives: `84 * features_per_kernel`.
    pub fn output_len(&self) -> usize {
        KERNEL_COUNT * self.features_per_kernel()
    }
}

/// `Ok` when series of `channels x length` values can be fitted or transformed: at least one channel
/// and at least as many values as a kernel has taps (9); `what` names the data in the error.
pub fn check_shape(what: &'static str, channels: usize, length: usize) -> Result<()> {
    if channels == 0 {
        return Err(CoreError::Shape {
            what,
            expected: "at least 1 channel".to_string(),
            got: "0 channels".to_string(),
        });
    }
    if length < KERNEL_LENGTH {
        return Err(CoreError::Shape {
            what,
            expected: format!(
                "series of at least {KERNEL_LENGTH} values (the kernels' taps); pad shorter ones with zeros"
            ),
            got: format!("{length} values"),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_parameters_are_named() {
        let zero = RocketConfig {
            num_features: 0,
            ..RocketConfig::default()
        };
        assert!(
            zero.check()
                .is_err_and(|e| e.to_string().contains("num_features"))
        );
        let no_dilations = RocketConfig {
            max_dilations_per_kernel: 0,
            ..RocketConfig::default()
        };
        assert!(
            no_dilations
                .check()
                .is_err_and(|e| e.to_string().contains("max_dilations_per_kernel"))
        );
        assert!(RocketConfig::default().check().is_ok());
        assert_eq!(RocketConfig::default().output_len(), 9996);
        let few = RocketConfig {
            num_features: 5,
            ..RocketConfig::default()
        };
        assert_eq!(few.output_len(), 84);
        assert!(check_shape("s", 1, 9).is_ok());
        assert!(check_shape("s", 1, 8).is_err_and(|e| e.to_string().contains("at least 9")));
        assert!(check_shape("s", 0, 100).is_err());
    }

    #[test]
    fn config_reads_with_defaults_and_refuses_unknown_fields() -> serde_json::Result<()> {
        let config: RocketConfig = serde_json::from_str(r#"{"seed": 7}"#)?;
        assert_eq!(config.seed, 7);
        assert_eq!(config.num_features, 10_000);
        assert!(serde_json::from_str::<RocketConfig>(r#"{"kernels": 3}"#).is_err());
        Ok(())
    }
}
