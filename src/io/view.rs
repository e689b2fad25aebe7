//! Borrowed rasters: samples the caller owns (a [`Raster`]'s, or memory such as a NumPy
//! array's) seen without a copy, so that coding reads them where they are.

use super::{bytes, DataKind, Metadata, Raster, SampleType, Samples};
use crate::{Error, Result};

/// Borrowed samples, one variant per stored type (the borrowed form of [`Samples`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SamplesRef<'a> {
    U8(&'a [u8]),
    I8(&'a [i8]),
    U16(&'a [u16]),
    I16(&'a [i16]),
    U32(&'a [u32]),
    I32(&'a [i32]),
    F16(&'a [half::f16]),
    F32(&'a [f32]),
    F64(&'a [f64]),
}

impl Samples {
    /// The samples, borrowed.
    #[inline]
    pub fn view(&self) -> SamplesRef<'_> {
        match self {
            Samples::U8(v) => SamplesRef::U8(v),
            Samples::I8(v) => SamplesRef::I8(v),
            Samples::U16(v) => SamplesRef::U16(v),
            Samples::I16(v) => SamplesRef::I16(v),
            Samples::U32(v) => SamplesRef::U32(v),
            Samples::I32(v) => SamplesRef::I32(v),
            Samples::F16(v) => SamplesRef::F16(v),
            Samples::F32(v) => SamplesRef::F32(v),
            Samples::F64(v) => SamplesRef::F64(v),
        }
    }
}

impl SamplesRef<'_> {
    #[inline]
    pub fn len(&self) -> usize {
        match self {
            SamplesRef::U8(v) => v.len(),
            SamplesRef::I8(v) => v.len(),
            SamplesRef::U16(v) => v.len(),
            SamplesRef::I16(v) => v.len(),
            SamplesRef::U32(v) => v.len(),
            SamplesRef::I32(v) => v.len(),
            SamplesRef::F16(v) => v.len(),
            SamplesRef::F32(v) => v.len(),
            SamplesRef::F64(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    #[inline]
    pub fn sample_type(&self) -> SampleType {
        match self {
            SamplesRef::U8(_) => SampleType::U8,
            SamplesRef::I8(_) => SampleType::I8,
            SamplesRef::U16(_) => SampleType::U16,
            SamplesRef::I16(_) => SampleType::I16,
            SamplesRef::U32(_) => SampleType::U32,
            SamplesRef::I32(_) => SampleType::I32,
            SamplesRef::F16(_) => SampleType::F16,
            SamplesRef::F32(_) => SampleType::F32,
            SamplesRef::F64(_) => SampleType::F64,
        }
    }

    /// Sample `i` as f64 (exact for every stored type).
    #[inline]
    pub fn get_f64(&self, i: usize) -> f64 {
        match self {
            SamplesRef::U8(v) => v[i] as f64,
            SamplesRef::I8(v) => v[i] as f64,
            SamplesRef::U16(v) => v[i] as f64,
            SamplesRef::I16(v) => v[i] as f64,
            SamplesRef::U32(v) => v[i] as f64,
            SamplesRef::I32(v) => v[i] as f64,
            SamplesRef::F16(v) => v[i].to_f64(),
            SamplesRef::F32(v) => v[i] as f64,
            SamplesRef::F64(v) => v[i],
        }
    }

    /// All samples as f32 (exact for u8, i8, u16, i16, f16, f32; rounded for the rest).
    pub fn to_f32(&self) -> Vec<f32> {
        match self {
            SamplesRef::F32(v) => v.to_vec(),
            SamplesRef::F16(v) => v.iter().map(|x| x.to_f32()).collect(),
            SamplesRef::F64(v) => v.iter().map(|&x| x as f32).collect(),
            SamplesRef::U8(v) => v.iter().map(|&x| x as f32).collect(),
            SamplesRef::I8(v) => v.iter().map(|&x| x as f32).collect(),
            SamplesRef::U16(v) => v.iter().map(|&x| x as f32).collect(),
            SamplesRef::I16(v) => v.iter().map(|&x| x as f32).collect(),
            SamplesRef::U32(v) => v.iter().map(|&x| x as f32).collect(),
            SamplesRef::I32(v) => v.iter().map(|&x| x as f32).collect(),
        }
    }

    /// All samples as f64 (exact).
    pub fn to_f64(&self) -> Vec<f64> {
        (0..self.len()).map(|i| self.get_f64(i)).collect()
    }

    /// The samples `r` (a copy).
    pub fn range(&self, r: std::ops::Range<usize>) -> Samples {
        match self {
            SamplesRef::U8(v) => Samples::U8(v[r].to_vec()),
            SamplesRef::I8(v) => Samples::I8(v[r].to_vec()),
            SamplesRef::U16(v) => Samples::U16(v[r].to_vec()),
            SamplesRef::I16(v) => Samples::I16(v[r].to_vec()),
            SamplesRef::U32(v) => Samples::U32(v[r].to_vec()),
            SamplesRef::I32(v) => Samples::I32(v[r].to_vec()),
            SamplesRef::F16(v) => Samples::F16(v[r].to_vec()),
            SamplesRef::F32(v) => Samples::F32(v[r].to_vec()),
            SamplesRef::F64(v) => Samples::F64(v[r].to_vec()),
        }
    }

    /// An owned copy.
    pub fn to_owned(&self) -> Samples {
        self.range(0..self.len())
    }

    /// `(min, max)` over all samples, ignoring NaN; `None` when empty or all NaN.
    pub fn min_max(&self) -> Option<(f64, f64)> {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for i in 0..self.len() {
            let x = self.get_f64(i);
            if x < lo {
                lo = x;
            }
            if x > hi {
                hi = x;
            }
        }
        (lo <= hi).then_some((lo, hi))
    }
}

/// A raster whose samples are borrowed: the fields of [`Raster`], with the samples and
/// the metadata seen in place.
#[derive(Clone, Copy, Debug)]
pub struct RasterView<'a> {
    /// Spatial extent, slowest axis first: `[H, W]` or `[D, H, W]`.
    pub dims: &'a [usize],
    /// Samples per position.
    pub channels: usize,
    pub samples: SamplesRef<'a>,
    pub kind: DataKind,
    pub meta: &'a Metadata,
}

impl Raster {
    /// The raster, borrowed.
    pub fn view(&self) -> RasterView<'_> {
        RasterView {
            dims: &self.dims,
            channels: self.channels,
            samples: self.samples.view(),
            kind: self.kind,
            meta: &self.meta,
        }
    }
}

impl<'a> RasterView<'a> {
    /// A view of `samples` as a raster of `dims` × `channels`; errors as [`Raster::new`]
    /// when a size is 0 or the sample count does not match.
    pub fn new(
        dims: &'a [usize],
        channels: usize,
        samples: SamplesRef<'a>,
        kind: DataKind,
        meta: &'a Metadata,
    ) -> Result<Self> {
        if dims.is_empty() || dims.contains(&0) || channels == 0 {
            return Err(Error::format(
                format!("empty raster: dims {dims:?}, {channels} channels"),
                "every size and the channel count ≥ 1",
            ));
        }
        let n = bytes::sample_count(dims, channels)?;
        if n != samples.len() {
            return Err(Error::format(
                format!(
                    "{} samples for dims {:?} × {} channels",
                    samples.len(),
                    dims,
                    channels
                ),
                "dims × channels samples",
            ));
        }
        Ok(RasterView {
            dims,
            channels,
            samples,
            kind,
            meta,
        })
    }

    pub fn sample_type(&self) -> SampleType {
        self.samples.sample_type()
    }

    /// Number of spatial positions (product of `dims`).
    pub fn positions(&self) -> usize {
        self.dims.iter().product()
    }

    /// An owned copy.
    pub fn to_owned(&self) -> Raster {
        Raster {
            dims: self.dims.to_vec(),
            channels: self.channels,
            samples: self.samples.to_owned(),
            kind: self.kind,
            meta: self.meta.clone(),
        }
    }
}
