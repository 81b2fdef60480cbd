//! Principal component analysis fitted on training features.
