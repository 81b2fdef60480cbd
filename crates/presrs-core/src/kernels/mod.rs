//! The performance kernels, behind one boundary: the rest of the crate calls them only through what
//! this module re-exports. Each is chosen at run time by the CPU (pulp: scalar, AVX2 + FMA, AVX-512)
//! and checked against a slow, obvious oracle on every backend the CPU has (`harness`).
//!
//! - `simd`: f64 matrix-vector products (the exact PCA projection, the Parzen distance expansion) and
//!   the vectorised `exp(-z)` and `ln` of the Parzen window;
//! - `fixed_dot`: the 16-bit fixed-point matrix and its quantized vectors (the fast PCA projection);
//! - `rocket`: the MiniRocket transform's sums of shifted rows and its threshold counts;
//! - `radix4`: the AVX-512 radix-4 FFT of the 1-D |FFT|;
//! - `split`, `split_avx512`: the real FFT's split step, as compiled loops and in AVX-512 registers;
//! - `aligned`: buffers on 64-byte boundaries for the kernels' loads.

mod aligned;
mod fixed_dot;
#[cfg(test)]
mod harness;
mod radix4;
mod rocket;
mod simd;
mod split;
#[cfg(target_arch = "x86_64")]
mod split_avx512;

pub(crate) use aligned::Aligned;
pub(crate) use fixed_dot::{FixedMatrix, FixedVector};
pub(crate) use radix4::Radix4Fft;
pub(crate) use rocket::{count_greater, sum_at_offsets};
pub(crate) use simd::{columns_times_vector, exp_neg_in_place, ln_in_place, matrix_vector};
pub(crate) use split::SplitSpectrum;
#[cfg(target_arch = "x86_64")]
pub(crate) use split_avx512::Split as SplitAvx512;
