//! Stance segmentation: finding the stance phases of a recording from its total load per frame.
