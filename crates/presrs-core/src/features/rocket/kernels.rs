//! MiniRocket's 84 kernels: length 9, weight -1 at every tap but +2 at three, one kernel for each choice
//! of the three taps (9 choose 3 = 84), in lexicographic order. The weights sum to zero, so a kernel's
//! output does not move with the series' offset.

/// Taps per kernel.
pub const KERNEL_LENGTH: usize = 9;

/// The kernels.
pub const KERNEL_COUNT: usize = 84;

/// The weight of most taps.
pub const ALPHA: f64 = -1.0;

/// The weight of the three chosen taps.
pub const BETA: f64 = 2.0;

/// The three `+2` taps of each kernel, `a < b < c`, in lexicographic order (`[0, 1, 2]`, `[0, 1, 3]`,
/// ..., `[6, 7, 8]`).
pub const KERNEL_TAPS: [[usize; 3]; KERNEL_COUNT] = kernel_taps();

const fn kernel_taps() -> [[usize; 3]; KERNEL_COUNT] {
    let mut taps = [[0; 3]; KERNEL_COUNT];
    let mut next = 0;
    let mut a = 0;
    while a < KERNEL_LENGTH {
        let mut b = a + 1;
        while b < KERNEL_LENGTH {
            let mut c = b + 1;
            while c < KERNEL_LENGTH {
                taps[next] = [a, b, c];
                next += 1;
                c += 1;
            }
            b += 1;
        }
        a += 1;
    }
    taps
}

/// The nine weights of kernel `kernel` (< [`KERNEL_COUNT`]).
pub fn kernel_weights(kernel: usize) -> [f64; KERNEL_LENGTH] {
    let mut weights = [ALPHA; KERNEL_LENGTH];
    for &tap in &KERNEL_TAPS[kernel % KERNEL_COUNT] {
        weights[tap] = BETA;
    }
    weights
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_84_kernels_are_every_choice_of_three_taps_once() {
        let mut seen = std::collections::BTreeSet::new();
        for taps in KERNEL_TAPS {
            assert!(taps[0] < taps[1] && taps[1] < taps[2] && taps[2] < KERNEL_LENGTH);
            assert!(seen.insert(taps));
        }
        assert_eq!(seen.len(), 84);
        assert_eq!(KERNEL_TAPS[0], [0, 1, 2]);
        assert_eq!(KERNEL_TAPS[83], [6, 7, 8]);
        for kernel in 0..KERNEL_COUNT {
            let weights = kernel_weights(kernel);
            assert_eq!(weights.iter().sum::<f64>(), 0.0);
            assert_eq!(weights.iter().filter(|&&w| w == BETA).count(), 3);
        }
    }
}
