//! A dense row-major N-d array (last axis fastest).

use crate::{Error, Result};

/// An axis index, deliberately not built from a bare `usize` by `From`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Axis(pub usize);

/// Dense row-major array: `shape[0]` is the slowest axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Array<T> {
    shape: Vec<usize>,
    data: Vec<T>,
}

impl<T: Clone + Default> Array<T> {
    /// An array of `shape` filled with zeros, in a fresh buffer on 2 MB pages where the
    /// kernel allows ([`super::zeroed_vec`]).
    pub fn zeros(shape: &[usize]) -> Self {
        let n = shape.iter().product();
        Array {
            shape: shape.to_vec(),
            data: super::pages::zeroed_vec(n),
        }
    }
}

impl<T> Array<T> {
    /// Wrap `data` (row-major) as an array of `shape`.
    pub fn from_shape_vec(shape: &[usize], data: Vec<T>) -> Result<Self> {
        let n = shape
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .ok_or_else(|| {
                Error::parameter(
                    "array shape",
                    format!("{shape:?}"),
                    "a product that fits in memory",
                )
            })?;
        if shape.is_empty() || n != data.len() || n == 0 {
            return Err(Error::parameter(
                "array data length",
                data.len(),
                "the product of the (non-empty, non-zero) shape",
            ));
        }
        Ok(Array {
            shape: shape.to_vec(),
            data,
        })
    }
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }
    pub fn ndim(&self) -> usize {
        self.shape.len()
    }
    pub fn len(&self) -> usize {
        self.data.len()
    }
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    pub fn data(&self) -> &[T] {
        &self.data
    }
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }
    pub fn into_data(self) -> Vec<T> {
        self.data
    }
    /// Exchange the samples with `other` (same length): how an out-of-place level hands
    /// its result over without a copy.
    pub(crate) fn swap_data(&mut self, other: &mut Vec<T>) {
        assert_eq!(other.len(), self.data.len());
        std::mem::swap(&mut self.data, other);
    }
    /// Row-major strides in elements.
    pub fn strides(&self) -> Vec<usize> {
        strides(&self.shape)
    }
}

pub(crate) fn strides(shape: &[usize]) -> Vec<usize> {
    let mut s = vec![1; shape.len()];
    for k in (0..shape.len().saturating_sub(1)).rev() {
        s[k] = s[k + 1] * shape[k + 1];
    }
    s
}
