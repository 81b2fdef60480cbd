//! The 1-D |FFT| features (paper eqs. 3-5) against a naive DFT and against numpy.

#![allow(clippy::unwrap_used)] // helpers of integration tests are test code too

use presrs_core::Grid;
use presrs_core::features::{FeatureConfig, Fft1dConfig, Fft1dExtractor};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `|Σ_l x[l] e^{-2πi k l / n}|` for `k = 0..=n/2`, straight from eq. (4), with `x` zero-padded to `n`.
/// The angle is reduced modulo `n` in integers so that large `k l` keep full precision.
fn naive_dft_magnitudes(x: &[f64], n: usize) -> Vec<f64> {
    (0..=n / 2)
        .map(|k| {
            let (mut re, mut im) = (0.0, 0.0);
            for (l, &value) in x.iter().enumerate() {
                let angle = -2.0 * std::f64::consts::PI * ((k * l) % n) as f64 / n as f64;
                re += value * angle.cos();
                im += value * angle.sin();
            }
            re.hypot(im)
        })
        .collect()
}

fn random_image(grid: Grid, rng: &mut impl Rng) -> Vec<f64> {
    (0..grid.len())
        .map(|_| rng.random_range(0..256) as f64)
        .collect()
}

fn assert_close_to_naive(grid: Grid, fft_len: Option<usize>, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let image = random_image(grid, &mut rng);
    let config = Fft1dConfig { fft_len };
    let mut extractor = Fft1dExtractor::new(grid, &config).unwrap();
    let exact = extractor.extract(&image).unwrap();
    let mut single = vec![f64::NAN; exact.len()];
    extractor.extract_fast_into(&image, &mut single).unwrap();
    let naive = naive_dft_magnitudes(&image, extractor.fft_len());
    assert_eq!(exact.len(), naive.len());
    // Rounding of both sums grows with the sum of |x|; 1e-12 of it is far above f64 noise for n <= 4096
    // and far below any real difference. The single-precision path (f32: 6e-8 per operation, log2 N
    // stages) is held to 1e-6 of it.
    let scale: f64 = image.iter().map(|v| v.abs()).sum::<f64>().max(1.0);
    for (k, ((f, s), n)) in exact.iter().zip(&single).zip(&naive).enumerate() {
        assert!(
            (f - n).abs() <= 1e-12 * scale,
            "grid {grid}, N {}: bin {k}: fft {f} vs naive {n}",
            extractor.fft_len()
        );
        assert!(
            (s - n).abs() <= 1e-6 * scale,
            "grid {grid}, N {}: bin {k}: single-precision fft {s} vs naive {n}",
            extractor.fft_len()
        );
    }
}

#[test]
fn matches_naive_dft_on_the_paper_size() {
    assert_close_to_naive(Grid::new(38, 41), None, 1);
}

#[test]
fn matches_naive_dft_with_non_power_of_two_lengths() {
    assert_close_to_naive(Grid::new(7, 9), Some(63), 2); // odd N, no padding
    assert_close_to_naive(Grid::new(7, 9), Some(100), 3); // even N, not a power of two
    assert_close_to_naive(Grid::new(5, 5), Some(97), 4); // prime N
    assert_close_to_naive(Grid::new(38, 41), Some(1558), 5); // no padding at all
    assert_close_to_naive(Grid::new(1, 1), None, 6); // N = 1: the one value
    assert_close_to_naive(Grid::new(1, 2), None, 7); // N = 2: M = 1, no pair
    assert_close_to_naive(Grid::new(2, 2), None, 8); // N = 4: M = 2, only the middle bin
    assert_close_to_naive(Grid::new(7, 9), Some(70), 9); // N = 2 x odd: M odd, no middle bin
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn matches_naive_dft_on_random_shapes(
        rows in 1usize..12,
        cols in 1usize..12,
        extra in 0usize..40,
        power_of_two in any::<bool>(),
        seed in any::<u64>(),
    ) {
        let grid = Grid::new(rows, cols);
        let fft_len = if power_of_two { None } else { Some(grid.len() + extra) };
        assert_close_to_naive(grid, fft_len, seed);
    }
}

#[test]
fn reusing_an_extractor_gives_the_same_result_as_a_fresh_one() {
    let grid = Grid::new(38, 41);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let first = random_image(grid, &mut rng);
    let second = random_image(grid, &mut rng);
    let mut reused = Fft1dExtractor::new(grid, &Fft1dConfig::PAPER).unwrap();
    let _ = reused.extract(&first).unwrap();
    let again = reused.extract(&second).unwrap();
    let fresh = Fft1dExtractor::new(grid, &Fft1dConfig::PAPER)
        .unwrap()
        .extract(&second)
        .unwrap();
    assert_eq!(again, fresh);
}

#[derive(serde::Deserialize)]
struct NumpyFixture {
    rows: usize,
    cols: usize,
    fft_len: usize,
    image: Vec<f64>,
    magnitudes: Vec<f64>,
}

/// `tests/fixtures/fft1d_38x41.json` is written by `make_fft_fixture.py` with numpy's
/// `abs(np.fft.rfft(x, n=2048))` of a fixed 38 x 41 integer image.
#[test]
fn matches_numpy_rfft_on_a_fixed_38x41_image() {
    let text = include_str!("fixtures/fft1d_38x41.json");
    let fixture: NumpyFixture = serde_json::from_str(text).unwrap();
    let grid = Grid::new(fixture.rows, fixture.cols);
    assert_eq!(grid, Grid::new(38, 41));
    assert_eq!(fixture.fft_len, 2048);
    assert_eq!(fixture.magnitudes.len(), 1025);
    let mut extractor = FeatureConfig::default().extractor(grid).unwrap();
    let ours = extractor.extract(&fixture.image).unwrap();
    assert_eq!(ours.len(), 1025);
    for (k, (ours, numpy)) in ours.iter().zip(&fixture.magnitudes).enumerate() {
        // 1e-9 relative, bin by bin (the smallest bin is about 1e-3 of the largest here)
        let tolerance = 1e-9 * numpy.abs();
        assert!(
            (ours - numpy).abs() <= tolerance,
            "bin {k}: ours {ours} vs numpy {numpy}"
        );
    }
}
