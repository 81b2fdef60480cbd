//! One harness for every backend of every kernel (tests only): each kernel's tests run it on the backends
//! it has, compare each result with a slow, obvious oracle through [`Harness::compare`] (each comparison
//! states its tolerance), and [`Harness::finish`] FAILS when a backend the running CPU supports was not
//! run. A backend the CPU lacks is skipped and listed in the output (`cargo test -- --nocapture`), so a
//! machine without AVX-512 says so instead of passing silently.

use std::collections::BTreeSet;

/// A way a kernel runs: pulp's scalar and portable emulations (every CPU), or an x86 instruction set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Backend {
    /// pulp's scalar backend (one lane) or a kernel's own scalar loop.
    Scalar,
    /// pulp's portable emulations of 128-, 256- and 512-bit registers (every lane count and tail).
    Portable128,
    Portable256,
    Portable512,
    /// pulp's x86-v3: AVX2 + FMA.
    X86V3,
    /// pulp's x86-v4: AVX-512 (F, BW, DQ, VL, CD).
    X86V4,
}

pub(super) use Backend::{Portable128, Portable256, Portable512, Scalar, X86V3, X86V4};

impl Backend {
    /// Whether this CPU can run the backend.
    pub(super) fn supported(self) -> bool {
        match self {
            #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
            X86V3 => pulp::x86::V3::try_new().is_some(),
            #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
            X86V4 => pulp::x86::V4::try_new().is_some(),
            #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
            X86V3 | X86V4 => false,
            Scalar | Portable128 | Portable256 | Portable512 => true,
        }
    }

    /// Runs `op` compiled for this backend (pulp's `vectorize`), or `None` when the CPU lacks it.
    pub(super) fn run<F: pulp::WithSimd>(self, op: F) -> Option<F::Output> {
        use pulp::Simd;
        match self {
            Scalar => Some(pulp::Scalar::new().vectorize(Bound(pulp::Scalar::new(), op))),
            Portable128 => Some(pulp::Scalar128b.vectorize(Bound(pulp::Scalar128b, op))),
            Portable256 => Some(pulp::Scalar256b.vectorize(Bound(pulp::Scalar256b, op))),
            Portable512 => Some(pulp::Scalar512b.vectorize(Bound(pulp::Scalar512b, op))),
            #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
            X86V3 => pulp::x86::V3::try_new().map(|simd| simd.vectorize(Bound(simd, op))),
            #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
            X86V4 => pulp::x86::V4::try_new().map(|simd| simd.vectorize(Bound(simd, op))),
            #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
            X86V3 | X86V4 => None,
        }
    }
}

/// A `WithSimd` operation bound to its instruction set, for `vectorize`.
struct Bound<S, F>(S, F);

impl<S: pulp::Simd, F: pulp::WithSimd> pulp::NullaryFnOnce for Bound<S, F> {
    type Output = F::Output;

    #[inline(always)]
    fn call(self) -> F::Output {
        self.1.with_simd(self.0)
    }
}

/// The record of one kernel's checks: which backends ran.
pub(super) struct Harness {
    kernel: &'static str,
    ran: BTreeSet<Backend>,
}

impl Harness {
    pub(super) fn new(kernel: &'static str) -> Self {
        Self {
            kernel,
            ran: BTreeSet::new(),
        }
    }

    /// THE comparison: `got[i]` against the oracle's `want[i]` within `tolerance(i)` (each caller states
    /// its bound); two NaNs agree. Records that `backend` ran.
    ///
    /// # Panics
    /// On the first value outside its tolerance, naming the kernel, backend, case and index.
    pub(super) fn compare(
        &mut self,
        backend: Backend,
        case: &str,
        got: &[f64],
        want: &[f64],
        tolerance: impl Fn(usize) -> f64,
    ) {
        assert_eq!(
            got.len(),
            want.len(),
            "{} {backend:?} {case}: lengths",
            self.kernel
        );
        for (i, (&got, &want)) in got.iter().zip(want).enumerate() {
            let tolerance = tolerance(i);
            assert!(
                (got - want).abs() <= tolerance || (got.is_nan() && want.is_nan()),
                "{} {backend:?} {case} [{i}]: {got:e} vs the oracle's {want:e} (tolerance {tolerance:e})",
                self.kernel
            );
        }
        self.ran.insert(backend);
    }

    /// Prints which of the kernel's `backends` ran and which this CPU lacks, and FAILS if one the CPU
    /// supports did not run.
    ///
    /// # Panics
    /// If a supported backend of `backends` was never compared.
    pub(super) fn finish(self, backends: &[Backend]) {
        let (supported, skipped): (Vec<Backend>, Vec<Backend>) =
            backends.iter().partition(|backend| backend.supported());
        let missing: Vec<Backend> = supported
            .iter()
            .copied()
            .filter(|backend| !self.ran.contains(backend))
            .collect();
        println!(
            "kernel {}: ran {:?}; skipped (not on this CPU) {:?}",
            self.kernel, self.ran, skipped
        );
        assert!(
            missing.is_empty(),
            "kernel {}: backends this CPU supports were not run: {missing:?}",
            self.kernel
        );
    }
}
