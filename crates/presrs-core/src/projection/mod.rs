//! Projection to the principal axes: the PCA fit and its exact f64 projection (`pca`), and the basis in
//! fixed point with the fast projection the classification path uses (`fixed_basis`, on the kernels of
//! `crate::kernels`).

mod fixed_basis;
pub mod gram_svd;
pub mod pca;

pub use fixed_basis::FastInput;
pub use pca::{Pca, ProjectionScratch};
