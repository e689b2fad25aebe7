//! Tensor-product engine: N-d arrays, transforms along any axis, pyramids.
