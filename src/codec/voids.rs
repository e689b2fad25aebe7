//! Void samples (NaN, `meta.nodata`) through the codec: filled by pull-push before the
//! transform, listed in the metadata, and marked again after decoding.

use crate::io::{Raster, Samples};
use crate::Result;

/// The `meta.extra` key listing the void samples of an encoded raster as runs
/// `start:length` (sample indices, channels interleaved).
const VOID_RUNS: &str = "nodata.voids";

/// `r` with its void samples ([`crate::io::nodata`]) filled by pull-push and their runs
/// kept in [`VOID_RUNS`]; `None` when no sample (or every sample) is void.
pub(super) fn with_voids_filled(r: &Raster) -> Result<Option<Raster>> {
    let mut v = r.to_f64();
    let Some(voids) = crate::io::nodata::Voids::find(&v, r.meta.nodata) else {
        return Ok(None);
    };
    if voids.count() == v.len() {
        return Ok(None);
    }
    let mut shape = r.dims.clone();
    shape.push(r.channels);
    voids.fill(&mut v, &shape, r.dims.len())?;
    let mut runs = Vec::new();
    let mut i = 0;
    while i < voids.mask.len() {
        if voids.mask[i] {
            let start = i;
            while i < voids.mask.len() && voids.mask[i] {
                i += 1;
            }
            runs.push(format!("{start}:{}", i - start));
        } else {
            i += 1;
        }
    }
    let mut out = Raster::new(
        r.dims.clone(),
        r.channels,
        Samples::from_f64(&v, r.sample_type()),
        r.kind,
    )?;
    out.meta = r.meta.clone();
    out.meta.extra.insert(VOID_RUNS.into(), runs.join(" "));
    Ok(Some(out))
}

/// Mark the voids listed in `meta.extra[VOID_RUNS]` on a raster decoded at level `k`
/// (an output sample is void when its whole footprint on the full grid is) and drop
/// the key. Malformed runs are ignored.
pub(super) fn mark_voids(r: &mut Raster, full: &[usize], maps: &[crate::io::AxisMap]) {
    let Some(runs) = r.meta.extra.remove(VOID_RUNS) else {
        return;
    };
    let Ok(n) = crate::io::bytes::sample_count(full, r.channels) else {
        return;
    };
    let mut mask = vec![false; n];
    for run in runs.split_whitespace() {
        let Some((a, l)) = run.split_once(':') else {
            return;
        };
        let (Ok(a), Ok(l)) = (a.parse::<usize>(), l.parse::<usize>()) else {
            return;
        };
        match a.checked_add(l).filter(|&e| e <= n) {
            Some(e) => mask[a..e].iter_mut().for_each(|m| *m = true),
            None => return,
        }
    }
    let voids = crate::io::nodata::Voids {
        mask,
        marker: r.meta.nodata.unwrap_or(f64::NAN),
        range: (f64::NEG_INFINITY, f64::INFINITY),
    };
    let mut shape = full.to_vec();
    shape.push(r.channels);
    let m = voids.footprint(&shape, &r.dims, maps);
    crate::io::with_samples!(&mut r.samples, v => voids.restore(v, &m, false));
}
