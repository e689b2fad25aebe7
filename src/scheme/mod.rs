//! One-dimensional multiresolution schemes and subdivision.
