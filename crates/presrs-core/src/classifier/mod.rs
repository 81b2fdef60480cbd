//! Classifiers on reduced feature vectors (the paper's Parzen-window estimator, and more).
