//! Where the samples sit after a command changes the grid: one rule for every command
//! that resamples (decode at a coarser level, downscale, upscale) or crops (frames).
//!
//! Along each spatial axis the new grid is an affine map of the old one: new sample `j`
//! sits at the old (continuous) index
//!
//! ```text
//! x_j = offset + j · step          (old sample units, sample centres)
//! ```
//!
//! * crop to samples `a..b`: `offset = a`, `step = 1` ([`AxisMap::crop`]);
//! * resample `n` samples to `m` over the same extent, cells centred
//!   ([`AxisMap::centred`]): `step = n / m`, `offset = (step − 1) / 2`, so new sample `j`
//!   covers old cells `[j·step, (j+1)·step)` (downscale);
//! * one level of a subdivision scheme's reduce (`decode --level`): `step = 2`, the
//!   offset where the scheme's coarse sample sits ([`AxisMap::then`] chains levels);
//! * resample keeping both end samples ([`AxisMap::vertex`]): `step = (n − 1)/(m − 1)`,
//!   `offset = 0`.
//!
//! [`Metadata::resampled`] applies the maps to everything that locates samples:
//! spacing (`× step`), origin (moved to the world position of new sample 0), NRRD
//! space directions and the NIfTI affine (columns `× step`, translation moved), the
//! GeoTIFF ModelPixelScale / ModelTiepoint / ModelTransformation (honouring
//! PixelIsArea / PixelIsPoint), and an ESRI grid's corner and cell size. A free-text
//! description that states the old shape (a tifffile JSON `{"shape": …}` or an ImageJ
//! header) is dropped when the shape changes.

use super::{GeoValue, Metadata};

/// Old index of new sample `j` along one axis: `offset + j · step`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisMap {
    pub offset: f64,
    pub step: f64,
}

impl AxisMap {
    /// The axis is unchanged.
    pub const IDENTITY: AxisMap = AxisMap {
        offset: 0.0,
        step: 1.0,
    };

    /// Keep the samples from `first` on (frames, slices, crops).
    pub fn crop(first: usize) -> AxisMap {
        AxisMap {
            offset: first as f64,
            step: 1.0,
        }
    }

    /// `n` samples resampled to `m` over the same extent, cells centred:
    /// `step = n/m`, `offset = (step − 1)/2`.
    pub fn centred(n: usize, m: usize) -> AxisMap {
        if n == m || m == 0 {
            return AxisMap::IDENTITY;
        }
        let step = n as f64 / m as f64;
        AxisMap {
            offset: (step - 1.0) / 2.0,
            step,
        }
    }

    /// `n` samples resampled to `m` with both end samples kept:
    /// `step = (n − 1)/(m − 1)`, `offset = 0`.
    pub fn vertex(n: usize, m: usize) -> AxisMap {
        if n == m || n < 2 || m < 2 {
            return AxisMap::IDENTITY;
        }
        AxisMap {
            offset: 0.0,
            step: (n - 1) as f64 / (m - 1) as f64,
        }
    }

    /// This map followed by a further one: new sample `j` of `next` sits at
    /// `next.offset + j·next.step` of this map's grid, so at
    /// `offset + step·next.offset + j·step·next.step` of the old one.
    pub fn then(self, next: AxisMap) -> AxisMap {
        AxisMap {
            offset: self.offset + self.step * next.offset,
            step: self.step * next.step,
        }
    }

    fn is_identity(&self) -> bool {
        self.offset == 0.0 && self.step == 1.0
    }
}

/// GeoTIFF `GTRasterTypeGeoKey` (1025): `true` for PixelIsPoint (raster coordinate `c`
/// is the centre of sample `c`), `false` for PixelIsArea (the default: the centre of
/// sample `c` is at `c + ½`).
fn pixel_is_point(m: &Metadata) -> bool {
    m.geotiff.iter().any(|t| {
        t.tag == 34735
            && matches!(&t.value, GeoValue::Shorts(k) if k.len() >= 4
                && k[4..].chunks_exact(4).any(|e| e[0] == 1025 && e[1] == 0 && e[3] == 2))
    })
}

/// Does the description state a shape (tifffile JSON or an ImageJ header)?
fn states_shape(d: &str) -> bool {
    let t = d.trim_start();
    (t.starts_with('{') && t.contains("\"shape\"")) || t.starts_with("ImageJ=")
}

impl Metadata {
    /// The metadata of a grid of `new_dims` whose samples sit on the old grid of
    /// `old_dims` as `maps` says (one [`AxisMap`] per spatial axis, slowest first;
    /// missing entries are the identity). See the module doc for what is moved.
    pub fn resampled(&self, old_dims: &[usize], new_dims: &[usize], maps: &[AxisMap]) -> Metadata {
        let nd = old_dims.len();
        let map = |a: usize| maps.get(a).copied().unwrap_or(AxisMap::IDENTITY);
        let mut m = self.clone();
        if (0..nd).all(|a| map(a).is_identity()) && old_dims == new_dims {
            return m;
        }
        // world step of each dims axis (before scaling): directions, affine columns, or
        // the spacing along the world axis of the same rank (x fastest)
        let world_step = |a: usize| -> Option<Vec<f64>> {
            let f = nd - 1 - a;
            if let Some(d) = self.directions.as_ref().filter(|d| d.len() == nd) {
                return Some(d[f].clone());
            }
            if let Some(aff) = self.affine.as_ref().filter(|_| nd <= 3) {
                return Some(aff.iter().map(|row| row[f]).collect());
            }
            let sp = self.spacing.as_ref().filter(|s| s.len() == nd)?;
            let o = self.origin.as_ref()?;
            let mut v = vec![0.0; o.len()];
            *v.get_mut(f)? = sp[a];
            Some(v)
        };
        if let Some(o) = m.origin.as_mut() {
            let mut known = true;
            for a in 0..nd {
                let off = map(a).offset;
                if off == 0.0 {
                    continue;
                }
                match world_step(a) {
                    Some(d) if d.len() == o.len() => {
                        for (oi, di) in o.iter_mut().zip(&d) {
                            *oi += off * di;
                        }
                    }
                    _ => known = false,
                }
            }
            if !known {
                m.origin = None;
            }
        }
        if let Some(sp) = m.spacing.as_mut().filter(|s| s.len() == nd) {
            for (a, v) in sp.iter_mut().enumerate() {
                *v *= map(a).step;
            }
        }
        if let Some(dirs) = m.directions.as_mut().filter(|d| d.len() == nd) {
            for (f, d) in dirs.iter_mut().enumerate() {
                let s = map(nd - 1 - f).step;
                d.iter_mut().for_each(|v| *v *= s);
            }
        }
        if let Some(aff) = m.affine.as_mut().filter(|_| nd <= 3) {
            for row in aff.iter_mut() {
                for f in 0..nd {
                    let am = map(nd - 1 - f);
                    row[3] += am.offset * row[f];
                    row[f] *= am.step;
                }
            }
        }
        if nd >= 2 {
            let (mx, my) = (map(nd - 1), map(nd - 2));
            resample_geotiff(&mut m, mx, my);
            resample_asc(&mut m, mx, my, old_dims[nd - 2], new_dims[nd - 2]);
        }
        if old_dims != new_dims && m.description.as_deref().is_some_and(states_shape) {
            m.description = None;
        }
        m
    }

    /// [`Metadata::resampled`] with [`AxisMap::centred`] on every axis.
    pub fn rescaled(&self, old_dims: &[usize], new_dims: &[usize]) -> Metadata {
        let maps: Vec<AxisMap> = old_dims
            .iter()
            .zip(new_dims)
            .map(|(&n, &m)| AxisMap::centred(n, m))
            .collect();
        self.resampled(old_dims, new_dims, &maps)
    }
}

/// ModelPixelScale × step; ModelTiepoint re-anchored at new raster (0, 0) when a pixel
/// scale is present (else each tie's raster point mapped back); ModelTransformation
/// composed with the raster map.
fn resample_geotiff(m: &mut Metadata, mx: AxisMap, my: AxisMap) {
    if m.geotiff.is_empty() {
        return;
    }
    let point = pixel_is_point(m);
    // old raster coordinate u_old = p + q · u_new
    let raster = |am: AxisMap| -> (f64, f64) {
        if point {
            (am.offset, am.step)
        } else {
            (am.offset + 0.5 - 0.5 * am.step, am.step)
        }
    };
    let ((px, qx), (py, qy)) = (raster(mx), raster(my));
    let scale = m.geotiff.iter().find_map(|t| match (&t.tag, &t.value) {
        (33550, GeoValue::Doubles(d)) if d.len() >= 2 => Some((d[0], d[1])),
        _ => None,
    });
    for t in m.geotiff.iter_mut() {
        let GeoValue::Doubles(d) = &mut t.value else {
            continue;
        };
        match t.tag {
            33550 if d.len() >= 2 => {
                d[0] *= mx.step;
                d[1] *= my.step;
            }
            33922 => {
                for tie in d.chunks_exact_mut(6) {
                    match scale {
                        Some((sx, sy)) => {
                            tie[3] += (px - tie[0]) * sx;
                            tie[4] -= (py - tie[1]) * sy;
                            tie[0] = 0.0;
                            tie[1] = 0.0;
                        }
                        None => {
                            tie[0] = (tie[0] - px) / qx;
                            tie[1] = (tie[1] - py) / qy;
                        }
                    }
                }
            }
            34264 if d.len() == 16 => {
                for r in 0..4 {
                    d[4 * r + 3] += d[4 * r] * px + d[4 * r + 1] * py;
                    d[4 * r] *= qx;
                    d[4 * r + 1] *= qy;
                }
            }
            _ => {}
        }
    }
}

/// An ESRI ASCII grid's `xllcorner` / `yllcorner` (or `…center`) and cell size kept in
/// `meta.extra` (`asc.*`): row 0 is the northern row, so the lower-left corner moves
/// with the last new row.
fn resample_asc(m: &mut Metadata, mx: AxisMap, my: AxisMap, old_h: usize, new_h: usize) {
    let get = |m: &Metadata, k: &str| {
        m.extra
            .get(&format!("asc.{k}"))
            .and_then(|v| v.trim().parse::<f64>().ok())
    };
    let (dx, dy) = match (get(m, "cellsize"), get(m, "dx"), get(m, "dy")) {
        (Some(c), _, _) => (c, c),
        (None, Some(dx), Some(dy)) => (dx, dy),
        _ => return,
    };
    let (h, h2) = (old_h as f64, new_h as f64);
    // old row (from the top) of the new last row's centre
    let last = my.offset + my.step * (h2 - 1.0);
    let set = |m: &mut Metadata, k: &str, v: f64| {
        if get(m, k).is_some() {
            m.extra.insert(format!("asc.{k}"), v.to_string());
        }
    };
    if let Some(x) = get(m, "xllcorner") {
        set(m, "xllcorner", x + (mx.offset + 0.5 - 0.5 * mx.step) * dx);
    }
    if let Some(x) = get(m, "xllcenter") {
        set(m, "xllcenter", x + mx.offset * dx);
    }
    if let Some(y) = get(m, "yllcorner") {
        set(m, "yllcorner", y + (h - last - 0.5 - 0.5 * my.step) * dy);
    }
    if let Some(y) = get(m, "yllcenter") {
        set(m, "yllcenter", y + (h - 1.0 - last) * dy);
    }
    if (dx * mx.step - dy * my.step).abs() <= 1e-12 * dx.abs().max(dy.abs()) {
        m.extra.remove("asc.dx");
        m.extra.remove("asc.dy");
        m.extra
            .insert("asc.cellsize".into(), (dx * mx.step).to_string());
    } else {
        m.extra.remove("asc.cellsize");
        m.extra.insert("asc.dx".into(), (dx * mx.step).to_string());
        m.extra.insert("asc.dy".into(), (dy * my.step).to_string());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::GeoTag;

    #[test]
    fn a_centred_halving_keeps_the_extent_and_moves_the_origin_half_a_cell() {
        let m = Metadata {
            spacing: Some(vec![1.5, 3.2, 3.2]),
            origin: Some(vec![10.0, 20.0, 30.0]),
            ..Default::default()
        };
        let r = m.rescaled(&[94, 64, 64], &[47, 32, 32]);
        assert_eq!(r.spacing, Some(vec![3.0, 6.4, 6.4]));
        // origin (x, y, z): x along the fastest axis
        let o = r.origin.unwrap();
        for (a, b) in o.iter().zip([11.6, 21.6, 30.75]) {
            assert!((a - b).abs() < 1e-12, "{o:?}");
        }
    }

    #[test]
    fn geotiff_area_scale_doubles_and_corner_stays() {
        let m = Metadata {
            spacing: Some(vec![30.0, 30.0]),
            geotiff: vec![
                GeoTag {
                    tag: 33550,
                    value: GeoValue::Doubles(vec![30.0, 30.0, 0.0]),
                },
                GeoTag {
                    tag: 33922,
                    value: GeoValue::Doubles(vec![0.0, 0.0, 0.0, 500.0, 900.0, 0.0]),
                },
            ],
            ..Default::default()
        };
        let r = m.rescaled(&[460, 318], &[230, 159]);
        assert_eq!(r.geotiff[0].value, GeoValue::Doubles(vec![60.0, 60.0, 0.0]));
        assert_eq!(
            r.geotiff[1].value,
            GeoValue::Doubles(vec![0.0, 0.0, 0.0, 500.0, 900.0, 0.0])
        );
        // a crop of rows 10.. moves the tie 10 rows south
        let c = m.resampled(&[460, 318], &[450, 318], &[AxisMap::crop(10)]);
        assert_eq!(
            c.geotiff[1].value,
            GeoValue::Doubles(vec![0.0, 0.0, 0.0, 500.0, 600.0, 0.0])
        );
    }
}
