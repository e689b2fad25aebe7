//! The file a pyramid is stored in: the coefficients as float32 in the Mallat layout
//! (same shape as the input), a TIFF for 2-D data (all channels) or a NRRD for 3-D, with
//! what is needed to invert it in the file's key/value metadata (TIFF ImageDescription
//! lines `mra.extra.KEY=VALUE`, NRRD `KEY:=VALUE`):
//!
//! ```text
//! mra.pyramid=1                 marker
//! mra.scheme=cubic              haar | chaikin | cubic
//! mra.boundary=symmetric        interpolating | periodic | symmetric
//! mra.levels=4                  requested levels
//! mra.order=non-standard        standard | non-standard
//! mra.axes=0,1                  transformed axes of the [dims…, channels] array
//! mra.source.dtype=u16          sample type to restore (integers rounded and clamped)
//! mra.source.kind=image         image | volume | heightmap | sequence
//! mra.source.description=…      the input's own description, if any
//! mra.source.affine=…           the input's NIfTI affine (12 numbers), if any
//! ```
//!
//! Spacing, origin, units, nodata, GeoTIFF tags (TIFF) and NRRD space / directions travel
//! in the container's own fields; other keys of the input's metadata are kept as they are.

use std::path::Path;

use super::{DataKind, Raster, SampleType, Samples};
use crate::{Error, Result};

/// What a pyramid file records besides the coefficients (engine names as text).
#[derive(Clone, Debug, PartialEq)]
pub struct PyramidInfo {
    pub scheme: String,
    pub boundary: String,
    pub levels: usize,
    pub order: String,
    pub axes: Vec<usize>,
    pub source_type: SampleType,
    pub source_kind: DataKind,
}

fn kind_name(k: DataKind) -> &'static str {
    match k {
        DataKind::Image => "image",
        DataKind::Volume => "volume",
        DataKind::Heightmap => "heightmap",
        DataKind::Sequence => "sequence",
    }
}

fn parse_kind(s: &str) -> Result<DataKind> {
    Ok(match s {
        "image" => DataKind::Image,
        "volume" => DataKind::Volume,
        "heightmap" => DataKind::Heightmap,
        "sequence" => DataKind::Sequence,
        _ => {
            return Err(Error::format(
                format!("mra.source.kind={s}"),
                "image, volume, heightmap or sequence",
            ))
        }
    })
}

/// The container for `coefficients` (f32, shape `source.dims` × `source.channels`) of
/// the raster `source`: source metadata kept, pyramid keys added.
pub fn container(source: &Raster, coefficients: Vec<f32>, info: &PyramidInfo) -> Result<Raster> {
    let mut r = Raster::new(
        source.dims.clone(),
        source.channels,
        Samples::F32(coefficients),
        source.kind,
    )?;
    r.meta = source.meta.clone();
    let ex = &mut r.meta.extra;
    ex.insert("mra.pyramid".into(), "1".into());
    ex.insert("mra.scheme".into(), info.scheme.clone());
    ex.insert("mra.boundary".into(), info.boundary.clone());
    ex.insert("mra.levels".into(), info.levels.to_string());
    ex.insert("mra.order".into(), info.order.clone());
    ex.insert(
        "mra.axes".into(),
        info.axes
            .iter()
            .map(|a| a.to_string())
            .collect::<Vec<_>>()
            .join(","),
    );
    ex.insert("mra.source.dtype".into(), info.source_type.name().into());
    ex.insert("mra.source.kind".into(), kind_name(info.source_kind).into());
    if let Some(d) = r.meta.description.take() {
        ex.insert("mra.source.description".into(), d.replace('\n', "\\n"));
    }
    if let Some(a) = r.meta.affine.take() {
        let v: Vec<String> = a.iter().flatten().map(|x| x.to_string()).collect();
        ex.insert("mra.source.affine".into(), v.join(","));
    }
    Ok(r)
}

/// The file name extension a pyramid of `dims.len()`-D data is written with.
pub fn extension(ndims: usize) -> &'static str {
    if ndims == 2 {
        "tif"
    } else {
        "nrrd"
    }
}

/// Write a container built by [`container`]: `.tif` for 2-D, `.nrrd` otherwise (the
/// extension of `path` must match).
pub fn write(path: &Path, r: &Raster) -> Result<()> {
    let want = extension(r.dims.len());
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let ok = match want {
        "tif" => ext == "tif" || ext == "tiff",
        _ => ext == "nrrd" || ext == "nhdr",
    };
    if !ok {
        return Err(Error::parameter(
            "pyramid output",
            path.display(),
            if want == "tif" {
                "a .tif file for 2-D data"
            } else {
                "a .nrrd file for 3-D data"
            },
        ));
    }
    super::write(path, r)
}

/// Read a pyramid file: the f32 coefficients as a raster and the recorded [`PyramidInfo`].
pub fn read(path: &Path) -> Result<(Raster, PyramidInfo)> {
    let r = super::read(path)?;
    let info = read_info(&r).map_err(|e| match e {
        Error::Format { what, expected } => Error::Format {
            what: format!("{what} in {}", path.display()),
            expected,
        },
        e => e,
    })?;
    Ok((r, info))
}

/// The [`PyramidInfo`] recorded in a container's metadata.
pub fn read_info(r: &Raster) -> Result<PyramidInfo> {
    let ex = &r.meta.extra;
    if ex.get("mra.pyramid").map(String::as_str) != Some("1") {
        return Err(Error::format(
            "no mra pyramid keys",
            "a file written by `mra analyze`",
        ));
    }
    if !matches!(r.samples, Samples::F32(_)) {
        return Err(Error::format(
            format!("{} coefficients", r.sample_type()),
            "float32 coefficients",
        ));
    }
    let get = |k: &str| {
        ex.get(k)
            .cloned()
            .ok_or_else(|| Error::format(format!("no {k} in the pyramid file"), "all mra.* keys"))
    };
    let levels = get("mra.levels")?
        .parse::<usize>()
        .map_err(|_| Error::format("mra.levels is not a count", "a non-negative integer"))?;
    let axes = get("mra.axes")?
        .split(',')
        .filter(|s| !s.is_empty())
        .map(|s| s.trim().parse::<usize>())
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|_| Error::format("mra.axes is not a list of axes", "e.g. 0,1"))?;
    Ok(PyramidInfo {
        scheme: get("mra.scheme")?,
        boundary: get("mra.boundary")?,
        levels,
        order: get("mra.order")?,
        axes,
        source_type: SampleType::parse(&get("mra.source.dtype")?)?,
        source_kind: parse_kind(&get("mra.source.kind")?)?,
    })
}

/// The reconstructed raster: `values` converted to the source type (integers rounded to
/// nearest and clamped), the source metadata restored and the pyramid keys removed.
pub fn restore(container: &Raster, values: &[f32], info: &PyramidInfo) -> Result<Raster> {
    let mut r = Raster::new(
        container.dims.clone(),
        container.channels,
        Samples::from_f32(values, info.source_type),
        info.source_kind,
    )?;
    r.meta = container.meta.clone();
    let ex = &mut r.meta.extra;
    if let Some(d) = ex.remove("mra.source.description") {
        r.meta.description = Some(d.replace("\\n", "\n"));
    }
    if let Some(a) = ex.remove("mra.source.affine") {
        let v: Vec<f64> = a.split(',').filter_map(|s| s.parse().ok()).collect();
        if v.len() == 12 {
            let mut m = [[0.0; 4]; 3];
            for (i, x) in v.into_iter().enumerate() {
                m[i / 4][i % 4] = x;
            }
            r.meta.affine = Some(m);
        }
    }
    ex.retain(|k, _| !k.starts_with("mra."));
    Ok(r)
}
