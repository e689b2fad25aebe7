//! The x86-64 builds: AVX2 with FMA, and AVX-512F where the CPU has it. Each function
//! requires its target features (its `# Safety`); the dispatch in the modules above
//! calls it only at a [`super::CpuLevel`] that has them.

#[macro_use]
pub(crate) mod avx2;
pub(crate) mod pair;
