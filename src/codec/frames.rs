//! A range of frames of a raster's slowest axis, with its metadata.

use crate::io::{Raster, Samples};
use crate::{Error, Result};

/// Keep frames `a..b` of the slowest axis (time of an (x, y, t) sequence, slices of
/// a volume); the origin moves to frame `a` ([`crate::io::AxisMap::crop`]).
pub fn frames(r: Raster, a: usize, b: usize) -> Result<Raster> {
    let t = if r.dims.len() >= 2 { r.dims[0] } else { 0 };
    if a >= b || b > t {
        return Err(Error::parameter(
            "frames",
            format!("{a}..{b} of {t}"),
            "a non-empty range within the slowest axis of a 2-D or 3-D raster",
        ));
    }
    let per = r.samples.len() / t;
    let v = r.samples.to_f64();
    let mut dims = r.dims.clone();
    dims[0] = b - a;
    let samples = match &r.samples {
        Samples::F16(x) => Samples::F16(x[a * per..b * per].to_vec()),
        Samples::F32(x) => Samples::F32(x[a * per..b * per].to_vec()),
        _ => Samples::from_f64(&v[a * per..b * per], r.sample_type()),
    };
    let mut maps = vec![crate::io::AxisMap::IDENTITY; r.dims.len()];
    maps[0] = crate::io::AxisMap::crop(a);
    let meta = r.meta.resampled(&r.dims, &dims, &maps);
    let mut out = Raster::new(dims, r.channels, samples, r.kind)?;
    out.meta = meta;
    Ok(out)
}
