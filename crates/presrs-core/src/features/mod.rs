//! Feature extraction from pressure images (the paper's 1-D |FFT| of eqs. 3-5, and more).
