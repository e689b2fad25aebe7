//! GeoTIFF georeferencing read as GDAL reads it: the GeoKey directory (tag 34735, with its
//! double and ASCII parameters in 34736 / 34737) gives the model and the units, the
//! pixel scale (33550) with a tiepoint (33922), or the model transformation (34264), the
//! world position of the first sample and the step along each raster axis.
//!
//! Units of the horizontal axes: for a geographic model (`GTModelTypeGeoKey` 1024 = 2)
//! `GeogAngularUnitsGeoKey` (2054), degree when absent (every EPSG geographic system
//! GeoTIFFs use is in degrees); for a projected model (1024 = 1) `ProjLinearUnitsGeoKey`
//! (3076), else the unit of a well-known metric `ProjectedCSTypeGeoKey` (3072: UTM zones
//! of WGS 84, NAD83, NAD27 and ETRS89, Web Mercator, …), else unknown. Height unit:
//! `VerticalUnitsGeoKey` (4099). Unit codes are EPSG's (9001 metre, 9002 foot, 9003 US
//! survey foot, 9036 kilometre; 9101 radian, 9102 / 9122 degree, 9103 arc-minute, 9104
//! arc-second, 9105 grad).
//!
//! Position: raster coordinate `(i, j)` maps to world `x = X + (i − I)·Sx`,
//! `y = Y − (j − J)·Sy` for pixel scale `(Sx, Sy)` and tiepoint `(I, J, X, Y)`, or to
//! `(M₀ i + M₁ j + M₃, M₄ i + M₅ j + M₇)` for a transformation `M`. The first sample's
//! centre is raster `(½, ½)` for PixelIsArea (`GTRasterTypeGeoKey` 1025 = 1, the
//! default) and `(0, 0)` for PixelIsPoint (1025 = 2), GDAL's convention.

use super::{GeoTag, GeoValue};

/// The keys of a GeoKey directory that mra interprets.
const MODEL_TYPE: u16 = 1024;
const RASTER_TYPE: u16 = 1025;
const GEOG_ANGULAR_UNITS: u16 = 2054;
const PROJECTED_CS_TYPE: u16 = 3072;
const PROJ_LINEAR_UNITS: u16 = 3076;
const VERTICAL_UNITS: u16 = 4099;

/// What the GeoTIFF tags say about where the samples are.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Georeference {
    /// Unit of the horizontal axes ("degree", "m", …), when known.
    pub units: Option<String>,
    /// Unit of the heights, when `VerticalUnitsGeoKey` says.
    pub height_units: Option<String>,
    /// World (x, y) of the first sample's centre.
    pub origin: Option<[f64; 2]>,
    /// World step of one sample along the raster's x and y axes (x fastest).
    pub directions: Option<[[f64; 2]; 2]>,
}

/// One GeoKey's value: a short stored in the directory, doubles or text.
#[derive(Clone, Debug, PartialEq)]
enum KeyValue {
    Short(u16),
    Doubles(Vec<f64>),
    Ascii(String),
}

fn tag(tags: &[GeoTag], id: u16) -> Option<&GeoValue> {
    tags.iter().find(|t| t.tag == id).map(|t| &t.value)
}

fn doubles(tags: &[GeoTag], id: u16) -> Option<&[f64]> {
    match tag(tags, id)? {
        GeoValue::Doubles(d) => Some(d),
        _ => None,
    }
}

/// The keys of the directory (34735): `(id, value)` for each entry whose value can be
/// found; entries pointing past their parameter tag are skipped.
fn keys(tags: &[GeoTag]) -> Vec<(u16, KeyValue)> {
    let Some(GeoValue::Shorts(dir)) = tag(tags, 34735) else {
        return Vec::new();
    };
    let n = dir.get(3).copied().unwrap_or(0) as usize;
    let params_d = doubles(tags, 34736).unwrap_or(&[]);
    let params_a = match tag(tags, 34737) {
        Some(GeoValue::Ascii(s)) => s.as_str(),
        _ => "",
    };
    let mut out = Vec::new();
    for e in dir.get(4..).unwrap_or(&[]).chunks_exact(4).take(n) {
        let (id, loc, count, off) = (e[0], e[1], e[2] as usize, e[3] as usize);
        let v = match loc {
            0 => Some(KeyValue::Short(off as u16)),
            34735 => dir.get(off).map(|&s| KeyValue::Short(s)),
            34736 => params_d
                .get(off..off + count)
                .map(|d| KeyValue::Doubles(d.to_vec())),
            34737 => params_a
                .get(off..off + count)
                .map(|s| KeyValue::Ascii(s.trim_end_matches('|').to_string())),
            _ => None,
        };
        if let Some(v) = v {
            out.push((id, v));
        }
    }
    out
}

fn short(keys: &[(u16, KeyValue)], id: u16) -> Option<u16> {
    keys.iter().find_map(|(k, v)| match v {
        KeyValue::Short(s) if *k == id => Some(*s),
        _ => None,
    })
}

/// The name of an EPSG linear unit.
fn linear_unit(code: u16) -> Option<&'static str> {
    Some(match code {
        9001 => "m",
        9002 => "ft",
        9003 => "US survey ft",
        9036 => "km",
        _ => return None,
    })
}

/// The name of an EPSG angular unit.
fn angular_unit(code: u16) -> Option<&'static str> {
    Some(match code {
        9101 => "radian",
        9102 | 9122 => "degree",
        9103 => "arc-minute",
        9104 => "arc-second",
        9105 | 9106 => "grad",
        _ => return None,
    })
}

/// Projected systems in metres that files carry without a `ProjLinearUnitsGeoKey`:
/// UTM zones (WGS 84 north and south, NAD83, NAD27, ETRS89, GDA94 MGA), Web Mercator,
/// World Mercator, Lambert-93, British National Grid, ETRS89-LAEA, Conus Albers, NZTM,
/// the polar stereographics, Australian Albers.
fn metric_projection(code: u16) -> bool {
    matches!(code,
        32601..=32660 | 32701..=32760 | 26901..=26923 | 26701..=26722 | 25828..=25838
        | 28348..=28358 | 3857 | 3395 | 2154 | 27700 | 3035 | 5070 | 2193 | 3413 | 3031
        | 3577)
}

/// The georeference of a raster with these GeoTIFF tags (`None` without a GeoKey
/// directory, pixel scale or transformation).
pub fn georeference(tags: &[GeoTag]) -> Option<Georeference> {
    let keys = keys(tags);
    let scale = doubles(tags, 33550).filter(|d| d.len() >= 2);
    let tie = doubles(tags, 33922).filter(|d| d.len() >= 6);
    let matrix = doubles(tags, 34264).filter(|d| d.len() == 16);
    if keys.is_empty() && scale.is_none() && matrix.is_none() {
        return None;
    }
    let units = match short(&keys, MODEL_TYPE) {
        Some(2) => match short(&keys, GEOG_ANGULAR_UNITS) {
            Some(c) => angular_unit(c),
            None => Some("degree"),
        },
        Some(1) => match short(&keys, PROJ_LINEAR_UNITS) {
            Some(c) => linear_unit(c),
            None => short(&keys, PROJECTED_CS_TYPE)
                .filter(|&c| metric_projection(c))
                .map(|_| "m"),
        },
        _ => None,
    };
    let height_units = short(&keys, VERTICAL_UNITS).and_then(linear_unit);
    // raster coordinate of the first sample's centre
    let c = if short(&keys, RASTER_TYPE) == Some(2) {
        0.0
    } else {
        0.5
    };
    let (origin, directions) = match (matrix, scale, tie) {
        (Some(m), _, _) => (
            Some([m[0] * c + m[1] * c + m[3], m[4] * c + m[5] * c + m[7]]),
            Some([[m[0], m[4]], [m[1], m[5]]]),
        ),
        (None, Some(s), Some(t)) => (
            Some([t[3] + (c - t[0]) * s[0], t[4] - (c - t[1]) * s[1]]),
            Some([[s[0], 0.0], [0.0, -s[1]]]),
        ),
        _ => (None, None),
    };
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    Some(Georeference {
        units: units.map(str::to_string),
        height_units: height_units.map(str::to_string),
        origin: origin.filter(|o| finite(o)),
        directions: directions.filter(|d| finite(&d[0]) && finite(&d[1])),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shorts(v: &[u16]) -> GeoTag {
        GeoTag {
            tag: 34735,
            value: GeoValue::Shorts(v.to_vec()),
        }
    }

    fn dbl(tag: u16, v: &[f64]) -> GeoTag {
        GeoTag {
            tag,
            value: GeoValue::Doubles(v.to_vec()),
        }
    }

    #[test]
    fn geographic_wgs84_is_in_degrees_with_the_corner_moved_half_a_cell() {
        let s = 0.000833;
        let tags = [
            dbl(33550, &[s, s, 0.0]),
            dbl(33922, &[0.0, 0.0, 0.0, -122.5, 46.5, 0.0]),
            shorts(&[1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326]),
        ];
        let g = georeference(&tags).unwrap();
        assert_eq!(g.units.as_deref(), Some("degree"));
        assert_eq!(g.origin, Some([-122.5 + s / 2.0, 46.5 - s / 2.0]));
        assert_eq!(g.directions, Some([[s, 0.0], [0.0, -s]]));
    }

    #[test]
    fn projected_units_from_the_key_or_the_epsg_code() {
        let key = |pcs: u16, lin: Option<u16>| {
            let mut d = vec![1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, pcs];
            if let Some(l) = lin {
                d[3] = 3;
                d.extend([3076, 0, 1, l]);
            }
            georeference(&[shorts(&d)]).unwrap().units
        };
        assert_eq!(key(32610, None).as_deref(), Some("m"));
        assert_eq!(key(2227, Some(9003)).as_deref(), Some("US survey ft"));
        assert_eq!(key(2227, None), None);
        // a projected model with neither a unit key nor a known system: unknown
        let d = [1, 1, 0, 1, 1024, 0, 1, 1];
        assert_eq!(georeference(&[shorts(&d)]).unwrap().units, None);
    }
}
