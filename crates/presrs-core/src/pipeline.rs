//! The trained pipeline: crop -> features -> PCA -> classifier, with training and a reusable classification session.
