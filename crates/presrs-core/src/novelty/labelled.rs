//! The labelled vectors a novelty score is fitted on, checked once: the fits, the calibration and the
//! contact part's check read them together.

use crate::error::{CoreError, Result, check_len};

/// Vectors (`n x dims`, row-major: the classifier's training and validation vectors), each with its
/// class (below `n_classes`) and group (the recording it came from, `None` when unknown).
#[derive(Clone, Copy, Debug)]
pub struct LabelledVectors<'a> {
    vectors: &'a [f64],
    classes: &'a [usize],
    groups: &'a [Option<&'a str>],
    n_classes: usize,
    dims: usize,
}

impl<'a> LabelledVectors<'a> {
    /// An error unless there are `dims > 0` values per class, one group per class and every class is
    /// below `n_classes`.
    pub fn new(
        vectors: &'a [f64],
        classes: &'a [usize],
        groups: &'a [Option<&'a str>],
        n_classes: usize,
        dims: usize,
    ) -> Result<Self> {
        if dims == 0 {
            return Err(CoreError::Param {
                name: "novelty dims",
                reason: "the vectors need at least one value".into(),
            });
        }
        check_len("novelty vectors", classes.len() * dims, vectors.len())?;
        check_len("novelty groups", classes.len(), groups.len())?;
        if let Some(&class) = classes.iter().find(|&&class| class >= n_classes) {
            return Err(CoreError::Param {
                name: "novelty classes",
                reason: format!("class {class} of {n_classes}"),
            });
        }
        Ok(Self {
            vectors,
            classes,
            groups,
            n_classes,
            dims,
        })
    }

    pub fn vectors(&self) -> &'a [f64] {
        self.vectors
    }

    pub fn classes(&self) -> &'a [usize] {
        self.classes
    }

    pub fn groups(&self) -> &'a [Option<&'a str>] {
        self.groups
    }

    pub fn n_classes(&self) -> usize {
        self.n_classes
    }

    pub fn dims(&self) -> usize {
        self.dims
    }

    /// The same rows read as `other` vectors of `dims` values each (`n x dims`).
    pub fn with_vectors(self, vectors: &'a [f64], dims: usize) -> Result<Self> {
        Self::new(vectors, self.classes, self.groups, self.n_classes, dims)
    }
}
