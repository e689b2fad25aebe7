//! What the filters compute with: `f32` or `f64` samples. An *element* of a lane is a
//! run of `width` samples — a scalar (width 1), a 2D/3D point (width 2/3) or a whole
//! row of an image (width = row length) — so one kernel serves every dimension.

use std::ops::{Add, AddAssign, Mul, Sub};

/// A floating-point sample type the kernels run on.
pub trait Sample:
    Copy
    + Send
    + Sync
    + Default
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + AddAssign
    + std::fmt::Debug
    + 'static
{
    fn from_f64(v: f64) -> Self;
    fn to_f64(self) -> f64;
    /// `self · a + b` rounded once (IEEE 754 fusedMultiplyAdd: the FMA instruction
    /// where the build has it, a correctly rounded software routine otherwise).
    fn fused_mul_add(self, a: Self, b: Self) -> Self;
}

impl Sample for f32 {
    #[inline(always)]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn fused_mul_add(self, a: Self, b: Self) -> Self {
        self.mul_add(a, b)
    }
}

impl Sample for f64 {
    #[inline(always)]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn fused_mul_add(self, a: Self, b: Self) -> Self {
        self.mul_add(a, b)
    }
}
