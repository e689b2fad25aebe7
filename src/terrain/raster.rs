//! Rasters in and out of the terrain module: heightmaps (and images) as [`Grid`]s with
//! their voids filled, the checks that a base and an example can be combined (same
//! height unit, compatible cell size), and the output's metadata (units kept, cell size
//! scaled by the change of lattice, GeoTIFF pixel scale updated, nodata dropped).

use super::Grid;
use crate::io::nodata::Voids;
use crate::io::{AxisMap, Raster, SampleType, Samples};
use crate::{Error, Result};

/// A 2-D raster as a grid; nodata cells (`meta.nodata`, NaN) are filled first, by the
/// membrane of [`crate::io::nodata`].
/// Returns the grid and the number of filled cells.
pub fn to_grid(r: &Raster) -> Result<(Grid, usize)> {
    if r.dims.len() != 2 {
        return Err(Error::parameter(
            "dimensions",
            format!("{} ({}-D)", r.summary(), r.dims.len()),
            "a 2-D heightmap or image",
        ));
    }
    let mut g = Grid::new(r.dims[0], r.dims[1], r.channels, r.to_f64())?;
    let filled = match Voids::find(g.data(), r.meta.nodata) {
        Some(v) => {
            let (h, w, c) = (g.h(), g.w(), g.c());
            v.fill_membrane(g.data_mut(), h, w, c)?
        }
        None => 0,
    };
    Ok((g, filled))
}

/// The unit of the heights: `meta.extra["elevation_units"]` (SRTM), else none.
fn height_unit(r: &Raster) -> Option<&str> {
    r.meta.extra.get("elevation_units").map(|s| s.as_str())
}

/// Cell size along x in the raster's horizontal unit, if known.
fn cell_x(r: &Raster) -> Option<(f64, &str)> {
    let sp = r.meta.spacing.as_ref()?;
    Some((*sp.last()?, r.meta.units.as_deref().unwrap_or("")))
}

/// Check that the example's heights and cells go with the output's and return the
/// example's cell ÷ the output's cell `base cell × n/M` (1 when either cell is unknown):
/// the same height unit when both say, the same horizontal unit, and a ratio within
/// 1/16 to 16.
pub fn check_compatible(base: &Raster, example: &Raster, out_w: usize) -> Result<f64> {
    if let (Some(a), Some(b)) = (height_unit(base), height_unit(example)) {
        if a != b {
            return Err(Error::parameter(
                "example height unit",
                format!("{b} (base: {a})"),
                "the base's height unit",
            ));
        }
    }
    let mut scale = 1.0;
    if let (Some((cb, ub)), Some((ce, ue))) = (cell_x(base), cell_x(example)) {
        if ub != ue {
            return Err(Error::parameter(
                "example cell unit",
                format!("{ue:?} (base: {ub:?})"),
                "the base's horizontal unit",
            ));
        }
        let n = base.width().max(1) as f64;
        let out = cb * n / out_w.max(1) as f64;
        scale = ce / out;
        if !(1.0 / 16.0..=16.0).contains(&scale) {
            return Err(Error::parameter(
                "example cell size",
                format!("{ce} {ue} (output cell {out:.6} {ub})"),
                "an example cell within a factor 16 of the output cell",
            ));
        }
    }
    Ok(scale)
}

/// The output raster: `g` in `ty`, with `template`'s metadata moved to `g`'s
/// cell-centred lattice ([`AxisMap::centred`]: spacing × n/M, origin moved by half a
/// cell less half an output cell); nodata dropped (the voids were filled).
pub fn from_grid(g: &Grid, template: &Raster, ty: SampleType) -> Result<Raster> {
    let mut r = Raster::new(
        vec![g.h(), g.w()],
        g.c(),
        Samples::from_f64(g.data(), ty),
        template.kind,
    )?;
    // cell-centred lattice: new sample j at old (j + ½)·n/M − ½ on each axis
    let (n_y, n_x) = (template.dims[0], template.dims[1]);
    let maps = [AxisMap::centred(n_y, g.h()), AxisMap::centred(n_x, g.w())];
    let mut meta = template
        .meta
        .resampled(&template.dims, &[g.h(), g.w()], &maps);
    meta.nodata = None;
    meta.extra.remove("asc.nodata_value");
    meta.geotiff.retain(|t| t.tag != 42113);
    r.meta = meta;
    Ok(r)
}

/// Cell size `(dy, dx)` in metres for shading: spacing in metres as stored, degrees
/// converted at the latitude of `asc.yllcorner` (if known) with 111 320 m per degree;
/// 1 when unknown.
pub fn cell_metres(r: &Raster) -> (f64, f64) {
    let Some(sp) = r.meta.spacing.as_ref().filter(|s| s.len() == 2) else {
        return (1.0, 1.0);
    };
    let unit = r.meta.units.as_deref().unwrap_or("");
    if unit.starts_with("deg") {
        let lat = r
            .meta
            .extra
            .get("asc.yllcorner")
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0);
        let m = 111_320.0;
        (sp[0] * m, sp[1] * m * lat.to_radians().cos())
    } else {
        (sp[0], sp[1])
    }
}
