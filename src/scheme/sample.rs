//! What the filters compute with: `f32` or `f64` samples. An *element* of a lane is a
//! run of `width` samples — a scalar (width 1), a 2D/3D point (width 2/3) or a whole
//! row of an image (width = row length) — so one kernel serves every dimension.

use std::ops::{Add, AddAssign, Mul, Sub};

/// Which vector build of the kernels serves a sample type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Build {
    F32,
    F64,
    /// The plain loops only.
    Plain,
}

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

    /// Which vector build of the kernels serves the type (chosen at compile time: each
    /// kernel entry matches on it instead of comparing type ids).
    const BUILD: Build = Build::Plain;

    /// `p` as a pointer to `f32`: `Some` only for `f32` itself, so that the vector
    /// builds view samples as their own type without a cast taken on trust.
    #[inline(always)]
    fn f32_ptr(p: *mut Self) -> Option<*mut f32> {
        let _ = p;
        None
    }

    /// `p` as a pointer to `f64`: `Some` only for `f64` itself.
    #[inline(always)]
    fn f64_ptr(p: *mut Self) -> Option<*mut f64> {
        let _ = p;
        None
    }
}

impl Sample for f32 {
    const BUILD: Build = Build::F32;
    #[inline(always)]
    fn f32_ptr(p: *mut Self) -> Option<*mut f32> {
        Some(p)
    }
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
    const BUILD: Build = Build::F64;
    #[inline(always)]
    fn f64_ptr(p: *mut Self) -> Option<*mut f64> {
        Some(p)
    }
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
