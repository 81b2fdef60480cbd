//! Buffers whose data starts on a 64-byte boundary (a cache line; one AVX-512 register).
//!
//! The allocator aligns a `Vec<f32>` or `Vec<Complex<f32>>` only as its element needs (glibc: 16 bytes),
//! so where a buffer starts decides whether a kernel's 512-bit loads and stores each touch one cache line
//! or most of them two. The hot kernels (the FFT, its split step) measured that difference after unrelated
//! changes moved their allocations; these buffers make it a property of the code, not of the allocator.

use core::ops::{Deref, DerefMut};

/// The alignment, in bytes.
const ALIGN: usize = 64;

/// `len` values in a `Vec` with room to start at the first 64-byte boundary inside it. Derefs to the
/// aligned slice; a clone is aligned again (its allocation is its own).
#[derive(Debug)]
pub(crate) struct Aligned<T> {
    storage: Vec<T>,
    offset: usize,
    len: usize,
}

impl<T: Copy + Default> Aligned<T> {
    /// `len` default values.
    pub(crate) fn new(len: usize) -> Self {
        Self::from_slice_with(len, |_| T::default())
    }

    /// A copy of `values`.
    pub(crate) fn from_slice(values: &[T]) -> Self {
        Self::from_slice_with(values.len(), |i| values[i])
    }

    fn from_slice_with(len: usize, value: impl Fn(usize) -> T) -> Self {
        let size = size_of::<T>().max(1);
        let spare = ALIGN / size;
        let storage = vec![T::default(); len + spare];
        let misalign = storage.as_ptr().addr() % ALIGN;
        let gap = (ALIGN - misalign) % ALIGN;
        // An element size that does not divide the gap cannot be aligned: keep the start (correct, slower).
        let offset = if gap % size == 0 { gap / size } else { 0 };
        let mut aligned = Self {
            storage,
            offset,
            len,
        };
        for (i, slot) in aligned.iter_mut().enumerate() {
            *slot = value(i);
        }
        aligned
    }
}

impl<T: Copy + Default> Clone for Aligned<T> {
    fn clone(&self) -> Self {
        Self::from_slice(self)
    }
}

impl<T: PartialEq> PartialEq for Aligned<T> {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl<T> Deref for Aligned<T> {
    type Target = [T];

    #[inline(always)]
    fn deref(&self) -> &[T] {
        &self.storage[self.offset..self.offset + self.len]
    }
}

impl<T> DerefMut for Aligned<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [T] {
        &mut self.storage[self.offset..self.offset + self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_on_a_cache_line_and_holds_its_values() {
        for len in [0, 1, 7, 64, 1000] {
            let values: Vec<f32> = (0..len).map(|i| i as f32).collect();
            let a = Aligned::from_slice(&values);
            assert_eq!(&*a, values.as_slice());
            assert_eq!(a.as_ptr().addr() % ALIGN, 0);
            let b = a.clone();
            assert_eq!(&*b, values.as_slice());
            assert_eq!(b.as_ptr().addr() % ALIGN, 0);
            let zeros = Aligned::<realfft::num_complex::Complex<f32>>::new(len);
            assert_eq!(zeros.len(), len);
            assert_eq!(zeros.as_ptr().addr() % ALIGN, 0);
        }
    }
}
