//! 2-D |FFT| against a naive 2-D DFT, and GLCM attributes against scikit-image.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::Grid;
use presrs_core::features::{
    FeatureConfig, FeatureKind, Fft2dConfig, Fft2dExtractor, Fft2dForm, GLCM_ATTRIBUTE_NAMES,
    GlcmConfig, GlcmExtractor,
};

fn test_image(rows: usize, cols: usize) -> Vec<f64> {
    (0..rows * cols)
        .map(|i| {
            let (r, c) = ((i / cols) as f64, (i % cols) as f64);
            (1.3 * r + 0.7 * c).sin() * 10.0 + (r * c * 0.37).cos() * 3.0 + r
        })
        .collect()
}

/// |Y[k][l]| of the zero-padded `R x C` transform, by the definition.
fn naive_magnitude(image: &[f64], grid: Grid, rows: usize, cols: usize) -> Vec<Vec<f64>> {
    let mut out = vec![vec![0.0; cols]; rows];
    for (k, out_row) in out.iter_mut().enumerate() {
        for (l, value) in out_row.iter_mut().enumerate() {
            let (mut re, mut im) = (0.0, 0.0);
            for r in 0..grid.rows {
                for c in 0..grid.cols {
                    let phase = -std::f64::consts::TAU
                        * ((k * r) as f64 / rows as f64 + (l * c) as f64 / cols as f64);
                    let v = image[r * grid.cols + c];
                    re += v * phase.cos();
                    im += v * phase.sin();
                }
            }
            *value = (re * re + im * im).sqrt();
        }
    }
    out
}

#[test]
fn fft2d_half_matches_the_naive_dft() {
    for (grid, pad) in [
        (Grid::new(5, 6), None),
        (Grid::new(5, 6), Some((7, 8))),
        (Grid::new(4, 7), Some((6, 9))),
        (Grid::new(6, 5), None),
    ] {
        let config = Fft2dConfig {
            pad_rows: pad.map(|p| p.0),
            pad_cols: pad.map(|p| p.1),
            ..Fft2dConfig::HALF
        };
        let (rows, cols) = pad.unwrap_or((grid.rows, grid.cols));
        let image = test_image(grid.rows, grid.cols);
        let naive = naive_magnitude(&image, grid, rows, cols);
        let mut extractor = Fft2dExtractor::new(grid, &config).unwrap();
        let mut out = vec![0.0; extractor.output_len()];
        extractor.extract_into(&image, &mut out).unwrap();
        // expected: row-major by k, l = 0..=C/2, skipping k > R/2 on self-mirrored columns
        let mut expected = Vec::new();
        for (k, row) in naive.iter().enumerate() {
            for (l, &value) in row.iter().enumerate().take(cols / 2 + 1) {
                let mirrored = l == 0 || (cols % 2 == 0 && 2 * l == cols);
                if mirrored && k > rows / 2 {
                    continue;
                }
                expected.push(value);
            }
        }
        assert_eq!(out.len(), expected.len(), "{grid} padded {pad:?}");
        assert_eq!(config.output_len(grid).unwrap(), out.len());
        for (i, (a, b)) in out.iter().zip(&expected).enumerate() {
            assert!(
                (a - b).abs() < 1e-9 * (1.0 + b),
                "{grid} {pad:?} [{i}]: {a} vs {b}"
            );
        }
        // the dropped entries really are mirrors: |Y[k][l]| = |Y[-k][-l]|
        for (k, row) in naive.iter().enumerate() {
            for (l, &value) in row.iter().enumerate() {
                let mirror = naive[(rows - k) % rows][(cols - l) % cols];
                assert!((value - mirror).abs() < 1e-9 * (1.0 + value));
            }
        }
    }
}

#[test]
fn fft2d_polar_sums_the_whole_spectrum_and_ignores_shifts() {
    let grid = Grid::new(6, 7);
    let config = Fft2dConfig {
        // odd sizes: no Nyquist row or column, whose mirror is itself and whose orientation is ambiguous
        pad_rows: Some(9),
        pad_cols: Some(11),
        form: Fft2dForm::Polar,
        radial_bins: 5,
        angular_bins: 4,
    };
    let image = test_image(grid.rows, grid.cols);
    let naive = naive_magnitude(&image, grid, 9, 11);
    let mut extractor = Fft2dExtractor::new(grid, &config).unwrap();
    let out = {
        let mut out = vec![0.0; 9];
        extractor.extract_into(&image, &mut out).unwrap();
        out
    };
    // rings and wedges of the full plane, by the definition
    let mut rings = [0.0; 5];
    let mut wedges = [0.0; 4];
    let signed = |k: usize, n: usize| {
        if 2 * k > n {
            (k as f64 - n as f64) / n as f64
        } else {
            k as f64 / n as f64
        }
    };
    for (k, row) in naive.iter().enumerate() {
        for (l, &value) in row.iter().enumerate() {
            let (fk, fl) = (signed(k, 9), signed(l, 11));
            let radius = (fk * fk + fl * fl).sqrt();
            rings[((radius / 0.5f64.sqrt() * 5.0) as usize).min(4)] += value;
            if k != 0 || l != 0 {
                let angle = fk.atan2(fl).rem_euclid(std::f64::consts::PI);
                wedges[((angle / std::f64::consts::PI * 4.0) as usize).min(3)] += value;
            }
        }
    }
    let total: f64 = naive.iter().flatten().sum();
    for (a, b) in out.iter().zip(rings.iter().chain(&wedges)) {
        assert!(
            (a - b).abs() < 1e-9 * total,
            "{out:?} vs {rings:?} {wedges:?}"
        );
    }
    // a circular shift inside the padded grid leaves the magnitudes unchanged: shift a small blob
    let small = Grid::new(8, 10);
    let blob = |dr: usize, dc: usize| {
        let mut img = vec![0.0; 80];
        for r in 0..4 {
            for c in 0..5 {
                img[(r + dr) * 10 + c + dc] = test_image(4, 5)[r * 5 + c];
            }
        }
        img
    };
    let mut extractor = Fft2dExtractor::new(small, &Fft2dConfig::POLAR).unwrap();
    let a = extractor.extract(&blob(0, 0));
    let b = extractor.extract(&blob(3, 4));
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-9 * (1.0 + x.abs()));
    }
}

trait ExtractExt {
    fn extract(&mut self, image: &[f64]) -> Vec<f64>;
}

impl ExtractExt for Fft2dExtractor {
    fn extract(&mut self, image: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.output_len()];
        self.extract_into(image, &mut out).unwrap();
        out
    }
}

#[derive(serde::Deserialize)]
struct GlcmFixture {
    rows: usize,
    cols: usize,
    levels: usize,
    max_value: f64,
    image: Vec<f64>,
    quantised: Vec<u16>,
    distances: Vec<usize>,
    angles_deg: Vec<f64>,
    props: std::collections::BTreeMap<String, Vec<Vec<f64>>>,
}

#[test]
fn glcm_attributes_match_scikit_image() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/glcm_skimage.json"
    ))
    .unwrap();
    let fixture: GlcmFixture = serde_json::from_str(&text).unwrap();
    let grid = Grid::new(fixture.rows, fixture.cols);
    let config = GlcmConfig {
        levels: fixture.levels,
        distances: fixture.distances.clone(),
        angles_deg: fixture.angles_deg.clone(),
        average_angles: false,
        max_value: Some(fixture.max_value),
    };
    let mut extractor = GlcmExtractor::new(grid, &config).unwrap();
    let mut out = vec![0.0; extractor.output_len()];
    extractor.extract_into(&fixture.image, &mut out).unwrap();
    assert_eq!(extractor.quantised(), fixture.quantised.as_slice());
    let n_angles = fixture.angles_deg.len();
    let mut worst = 0.0f64;
    for d in 0..fixture.distances.len() {
        for a in 0..n_angles {
            for (p, name) in GLCM_ATTRIBUTE_NAMES.iter().enumerate() {
                let expected = fixture.props[*name][d][a];
                let got = out[(d * n_angles + a) * GLCM_ATTRIBUTE_NAMES.len() + p];
                worst = worst.max((got - expected).abs() / (1.0 + expected.abs()));
                assert!(
                    (got - expected).abs() < 1e-12 * (1.0 + expected.abs()),
                    "{name} d={} a={}: {got} vs scikit-image {expected}",
                    fixture.distances[d],
                    fixture.angles_deg[a]
                );
            }
        }
    }
    println!("worst relative difference to scikit-image: {worst:e}");
    // the angle-averaged variant is the mean of the per-angle attributes
    let averaged = GlcmConfig {
        average_angles: true,
        ..config
    };
    let mut extractor = GlcmExtractor::new(grid, &averaged).unwrap();
    let mut mean = vec![0.0; extractor.output_len()];
    extractor.extract_into(&fixture.image, &mut mean).unwrap();
    for d in 0..fixture.distances.len() {
        for p in 0..7 {
            let expected: f64 = (0..n_angles)
                .map(|a| out[(d * n_angles + a) * 7 + p])
                .sum::<f64>()
                / n_angles as f64;
            assert!((mean[d * 7 + p] - expected).abs() < 1e-12);
        }
    }
}

#[test]
fn kinds_parse_and_combine() {
    assert_eq!(
        FeatureKind::parse_list("fft1d+glcm").unwrap(),
        [FeatureKind::FFT1D, FeatureKind::GLCM]
    );
    let grid = Grid::new(38, 41);
    let combined = FeatureConfig::combined(&[FeatureKind::FFT2D_POLAR, FeatureKind::GLCM]);
    assert_eq!(combined.name(), "fft2d_polar+glcm");
    assert_eq!(combined.output_len(grid).unwrap(), 36 + 28);
    let json = serde_json::to_string(&combined).unwrap();
    assert_eq!(
        serde_json::from_str::<FeatureConfig>(&json).unwrap(),
        combined
    );
    let mut extractor = combined.extractor(grid).unwrap();
    let features = extractor.extract(&test_image(38, 41)).unwrap();
    // each part has unit norm
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((norm(&features[..36]) - 1.0).abs() < 1e-12);
    assert!((norm(&features[36..]) - 1.0).abs() < 1e-12);
    for kind in FeatureKind::all() {
        let config = kind.default_config();
        assert_eq!(config.kind(), Some(kind));
        if config.learns() {
            // Learned from training images: no extractor before a fit.
            assert!(config.extractor(grid).is_err(), "{kind}");
            continue;
        }
        let mut extractor = config.extractor(grid).unwrap();
        let features = extractor.extract(&test_image(38, 41)).unwrap();
        assert!(features.iter().all(|v| v.is_finite()));
    }
}

/// A configured padding shorter than the image grows to the next power of two at least each side (the
/// polar form's 64 x 64 on a 60 x 75 image: 64 x 128), and the grown transform is still the DFT; a
/// padding that fits (64 x 64 on the simulator's 44 x 44) is kept as configured.
#[test]
fn fft2d_padding_grows_to_fit_larger_images() {
    assert_eq!(
        Fft2dConfig::POLAR.resolved(Grid::new(44, 44)).unwrap(),
        (64, 64)
    );
    assert_eq!(
        Fft2dConfig::POLAR.resolved(Grid::new(60, 75)).unwrap(),
        (64, 128)
    );
    assert_eq!(
        Fft2dConfig::POLAR.resolved(Grid::new(130, 20)).unwrap(),
        (256, 64)
    );
    let extractor = Fft2dExtractor::new(Grid::new(60, 75), &Fft2dConfig::POLAR).unwrap();
    assert_eq!(extractor.transform_size(), (64, 128));
    // The half form with a too-small padding: the grown transform against the naive DFT.
    let grid = Grid::new(5, 6);
    let config = Fft2dConfig {
        pad_rows: Some(3),
        pad_cols: Some(4),
        ..Fft2dConfig::HALF
    };
    let image = test_image(grid.rows, grid.cols);
    let mut extractor = Fft2dExtractor::new(grid, &config).unwrap();
    assert_eq!(extractor.transform_size(), (8, 8));
    let mut out = vec![0.0; extractor.output_len()];
    extractor.extract_into(&image, &mut out).unwrap();
    let naive = naive_magnitude(&image, grid, 8, 8);
    // The first kept entries are row k = 0, columns l = 0 ..= 4.
    for (l, value) in out.iter().take(5).enumerate() {
        assert!(
            (value - naive[0][l]).abs() < 1e-9 * (1.0 + naive[0][l]),
            "l = {l}"
        );
    }
}
