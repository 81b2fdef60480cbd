//! Feature extraction from pressure images (the paper's 1-D |FFT| of eqs. 3-5, and more).
//!
//! Each family implements [`FeatureFamily`] in its own file and is registered once (the built-in list in
//! `registry.rs`, or [`register`] at run time); [`FeatureKind`] names one of its presets as users do. A
//! [`FeatureConfig`] holds a family and its parameters, or several side by side (stored in trained
//! models, tagged by `kind`). [`FeatureConfig::extractor`] builds a reusable [`FeatureExtractor`] for one
//! image grid that owns its plans and buffers, so extracting does not allocate.

pub mod contact;
mod dynamic;
mod erased;
mod family;
pub mod fft1d;
pub mod fft2d;
pub mod glcm;
mod registry;
pub mod rocket;

pub use dynamic::{FeatureConfig, FeatureExtractor, Precision};
pub use family::{FeatureFamily, FitImages, MAX_TRANSFORM_LEN};
pub use registry::{FeatureKind, register};

pub use contact::{ContactConfig, ContactExtractor, ContactFamily, ContactScale};
pub use fft1d::{Fft1dConfig, Fft1dExtractor, Fft1dFamily};
pub use fft2d::{Fft2dConfig, Fft2dExtractor, Fft2dFamily, Fft2dForm};
pub use glcm::{GLCM_ATTRIBUTE_NAMES, GlcmConfig, GlcmExtractor, GlcmFamily};
pub use rocket::family::{FittedRocket, RocketExtractor, RocketFamily, RocketParams};
pub use rocket::multi_family::{
    FittedMultiRocket, MultiRocketExtractor, MultiRocketFamily, MultiRocketParams,
};

/// The MiniRocket draws of `features` ([`RocketParams::draws`]) when they are MiniRocket's, else 1.
pub fn minirocket_draws(features: &FeatureConfig) -> usize {
    features
        .params::<RocketFamily>()
        .map_or(1, |params| params.draws)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Grid;

    #[test]
    fn kind_names_round_trip() {
        for kind in FeatureKind::all() {
            assert_eq!(FeatureKind::parse(kind.as_str()).unwrap(), kind);
            assert_eq!(kind.default_config().kind(), Some(kind));
        }
        assert_eq!(FeatureKind::parse(" FFT1D ").unwrap(), FeatureKind::FFT1D);
        assert!(FeatureKind::parse("wavelet").is_err());
    }

    #[test]
    fn config_serde_is_tagged() {
        let config = FeatureConfig::of::<Fft1dFamily>(Fft1dConfig {
            fft_len: Some(4096),
        });
        let json = serde_json::to_string(&config).unwrap();
        assert_eq!(json, r#"{"kind":"fft1d","fft_len":4096}"#);
        assert_eq!(
            serde_json::from_str::<FeatureConfig>(&json).unwrap(),
            config
        );
        let default: FeatureConfig = serde_json::from_str(r#"{"kind":"fft1d"}"#).unwrap();
        assert_eq!(default, FeatureConfig::default());
    }

    #[test]
    fn every_family_names_each_of_its_features() {
        let grid = Grid::new(38, 41);
        let mut combined = Vec::new();
        for kind in FeatureKind::all() {
            let config = kind.default_config();
            let names = config.feature_names(grid).unwrap();
            assert_eq!(names.len(), config.output_len(grid).unwrap(), "{kind}");
            let unique: std::collections::BTreeSet<&String> = names.iter().collect();
            assert_eq!(unique.len(), names.len(), "{kind}: names repeat");
            assert!(names.iter().all(|n| n.starts_with(kind.as_str())), "{kind}");
            combined.extend(names);
        }
        assert_eq!(
            FeatureConfig::combined(&FeatureKind::all())
                .feature_names(grid)
                .unwrap(),
            combined
        );
        let fft2d = FeatureKind::FFT2D
            .default_config()
            .feature_names(grid)
            .unwrap();
        assert_eq!(&fft2d[..2], ["fft2d_r0_c0", "fft2d_r0_c1"]);
        let polar = FeatureKind::FFT2D_POLAR
            .default_config()
            .feature_names(grid)
            .unwrap();
        assert_eq!(
            (polar[0].as_str(), polar[24].as_str()),
            ("fft2d_polar_ring0", "fft2d_polar_wedge0")
        );
        let glcm = FeatureKind::GLCM
            .default_config()
            .feature_names(grid)
            .unwrap();
        assert_eq!(&glcm[..2], ["glcm_contrast_d1", "glcm_dissimilarity_d1"]);
    }

    #[test]
    fn half_spectrum_names_follow_the_extractors_order() {
        // A single frequency (row bin 2, column bin 3) in a 8 x 8 image: its feature is the largest.
        let grid = Grid::new(8, 8);
        let image: Vec<f64> = (0..64)
            .map(|i| {
                let (r, c) = ((i / 8) as f64, (i % 8) as f64);
                (2.0 * std::f64::consts::PI * (2.0 * r + 3.0 * c) / 8.0).cos()
            })
            .collect();
        let config = FeatureKind::FFT2D.default_config();
        let features = config.extractor(grid).unwrap().extract(&image).unwrap();
        let names = config.feature_names(grid).unwrap();
        let top = (0..features.len())
            .max_by(|&a, &b| features[a].total_cmp(&features[b]))
            .unwrap();
        assert_eq!(names[top], "fft2d_r2_c3");
    }
}
