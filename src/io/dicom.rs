//! DICOM through `dicom-object`: one file as a 2-D slice, or a folder holding one series
//! as a volume. Only uncompressed pixel data (implicit / explicit VR little endian) is
//! read; compressed transfer syntaxes are reported as unsupported.
//!
//! Slices are ordered by their position along the slice normal
//! `n = row cosines × column cosines` (`ImagePositionPatient · n`). Their positions must
//! be evenly spaced (every step within 1 % of the median step) and distinct: a missing
//! or duplicated slice is an error naming the folder and the positions, unless
//! [`ReadOptions::uneven_slices`](super::ReadOptions) accepts it (the step is then the mean,
//! `(last − first)/(slices − 1)`, and the positions are kept in
//! `meta.extra["dicom.slice_positions"]`). Stored values are masked to
//! `BitsStored` (sign-extended when `PixelRepresentation` = 1), then rescaled
//! `v = stored × RescaleSlope + RescaleIntercept`: the result is i16 when the slope is 1,
//! the intercept is an integer and every value fits, the stored type when there is no
//! rescale, and f32 otherwise. Spacing `[step, PixelSpacing row, PixelSpacing column]`
//! (mm), origin = `ImagePositionPatient` of the first slice, `space` =
//! left-posterior-superior (DICOM's patient axes) and space directions, fastest axis
//! first: `row cosines × PixelSpacing[1]`, `column cosines × PixelSpacing[0]` and, for a
//! series, `(ImagePositionPatient_last − ImagePositionPatient_first)/(slices − 1)`.
//!
//! Before the file is parsed its element lengths are walked ([`check_lengths`]): an
//! element declaring more bytes than the file holds, or a PixelData whose length is not
//! `Rows × Columns × BitsAllocated / 8`, is rejected before anything is allocated.

use std::path::Path;

use dicom_object::{open_file, DefaultDicomObject, Tag};

use super::{DataKind, Raster, SampleType, Samples};
use crate::{Error, Result};
use byteorder::{ByteOrder, LittleEndian};

const ROWS: Tag = Tag(0x0028, 0x0010);
const COLUMNS: Tag = Tag(0x0028, 0x0011);
const SAMPLES_PER_PIXEL: Tag = Tag(0x0028, 0x0002);
const BITS_ALLOCATED: Tag = Tag(0x0028, 0x0100);
const BITS_STORED: Tag = Tag(0x0028, 0x0101);
const PIXEL_REPRESENTATION: Tag = Tag(0x0028, 0x0103);
const RESCALE_INTERCEPT: Tag = Tag(0x0028, 0x1052);
const RESCALE_SLOPE: Tag = Tag(0x0028, 0x1053);
const PIXEL_SPACING: Tag = Tag(0x0028, 0x0030);
const SLICE_THICKNESS: Tag = Tag(0x0018, 0x0050);
const IMAGE_POSITION: Tag = Tag(0x0020, 0x0032);
const IMAGE_ORIENTATION: Tag = Tag(0x0020, 0x0037);
const SERIES_UID: Tag = Tag(0x0020, 0x000E);
const MODALITY: Tag = Tag(0x0008, 0x0060);
const PIXEL_DATA: Tag = Tag(0x7FE0, 0x0010);

const UNCOMPRESSED: [&str; 3] = [
    "1.2.840.10008.1.2",
    "1.2.840.10008.1.2.1",
    "1.2.840.10008.1.2.1.99",
];

/// One decoded slice with what ordering and rescaling need.
struct Slice {
    rows: usize,
    cols: usize,
    stored: Vec<i64>,
    slope: f64,
    intercept: f64,
    position: Option<[f64; 3]>,
    orientation: Option<[f64; 6]>,
    pixel_spacing: Option<[f64; 2]>,
    thickness: Option<f64>,
    series: String,
    modality: String,
    stored_type: SampleType,
}

/// A malformed file, named by its file name (the caller names the folder or path).
fn bad(path: &Path, what: impl std::fmt::Display) -> Error {
    let name = path.file_name().map_or(path.as_os_str(), |n| n);
    Error::format(
        format!("{}: {what}", Path::new(name).display()),
        "an uncompressed DICOM image",
    )
}

/// What the walk of a file's elements found: the transfer syntax and PixelData length.
struct Walked {
    transfer_syntax: String,
    pixel_data: Option<u64>,
}

/// Value representations with a 4-byte length in explicit VR.
const LONG_VRS: [&[u8; 2]; 13] = [
    b"OB", b"OD", b"OF", b"OL", b"OV", b"OW", b"SQ", b"SV", b"UC", b"UN", b"UR", b"UT", b"UV",
];

const UNDEFINED: u32 = 0xFFFF_FFFF;

/// Walk the elements of `b[pos..end]` (items and sequences of undefined length
/// included), checking that every declared length fits in what remains. Returns the
/// position after the walked elements (after a delimiter that ends them).
fn walk(
    path: &Path,
    b: &[u8],
    mut pos: usize,
    end: usize,
    explicit: bool,
    depth: usize,
    found: &mut Walked,
) -> Result<usize> {
    if depth > 32 {
        return Err(bad(path, "sequences nested more than 32 deep"));
    }
    let short = |at: usize| bad(path, format!("element header at byte {at} ends early"));
    while pos < end {
        if end - pos < 8 {
            return Err(short(pos));
        }
        let group = LittleEndian::read_u16(&b[pos..]);
        let elem = LittleEndian::read_u16(&b[pos + 2..]);
        if group == 0xFFFE {
            let len = LittleEndian::read_u32(&b[pos + 4..]);
            pos += 8;
            match elem {
                0xE00D | 0xE0DD => return Ok(pos),
                _ if len == UNDEFINED => pos = walk(path, b, pos, end, explicit, depth + 1, found)?,
                _ => {
                    if len as usize > end - pos {
                        return Err(too_long(path, group, elem, len, end - pos));
                    }
                    pos += len as usize;
                }
            }
            continue;
        }
        let (len, hdr) = if explicit || group == 0x0002 {
            let vr = [b[pos + 4], b[pos + 5]];
            if LONG_VRS.contains(&&vr) {
                if end - pos < 12 {
                    return Err(short(pos));
                }
                (LittleEndian::read_u32(&b[pos + 8..]), 12)
            } else {
                (LittleEndian::read_u16(&b[pos + 6..]) as u32, 8)
            }
        } else {
            (LittleEndian::read_u32(&b[pos + 4..]), 8)
        };
        pos += hdr;
        if len == UNDEFINED {
            pos = walk(path, b, pos, end, explicit, depth + 1, found)?;
            continue;
        }
        if len as usize > end - pos {
            return Err(too_long(path, group, elem, len, end - pos));
        }
        if (group, elem) == (0x0002, 0x0010) {
            found.transfer_syntax = String::from_utf8_lossy(&b[pos..pos + len as usize])
                .trim_end_matches(['\0', ' '])
                .to_string();
        }
        if (group, elem) == (0x7FE0, 0x0010) && depth == 0 {
            found.pixel_data = Some(len as u64);
        }
        pos += len as usize;
    }
    Ok(pos)
}

fn too_long(path: &Path, group: u16, elem: u16, len: u32, left: usize) -> Error {
    bad(
        path,
        format!("element ({group:04X},{elem:04X}) declares {len} bytes but {left} remain"),
    )
}

/// Check every element length of a DICOM file against the file before it is parsed
/// (the parser allocates what a length declares).
fn check_lengths(path: &Path) -> Result<Walked> {
    let b = super::bytes::read_all(path)?;
    if b.len() < 132 || &b[128..132] != b"DICM" {
        return Err(bad(path, "no DICM preamble"));
    }
    let mut found = Walked {
        transfer_syntax: String::new(),
        pixel_data: None,
    };
    // the file meta group (0002) is explicit VR little endian, no sequences
    let mut pos = 132;
    while pos + 8 <= b.len() && LittleEndian::read_u16(&b[pos..]) == 0x0002 {
        let elem = LittleEndian::read_u16(&b[pos + 2..]);
        let vr = [b[pos + 4], b[pos + 5]];
        let (len, hdr) = if LONG_VRS.contains(&&vr) && pos + 12 <= b.len() {
            (LittleEndian::read_u32(&b[pos + 8..]), 12)
        } else {
            (LittleEndian::read_u16(&b[pos + 6..]) as u32, 8)
        };
        let left = b.len() - pos - hdr;
        if len as usize > left {
            return Err(too_long(path, 0x0002, elem, len, left));
        }
        let stop = pos + hdr + len as usize;
        walk(path, &b, pos, stop, true, 0, &mut found)?;
        pos = stop;
    }
    let ts = found.transfer_syntax.clone();
    if !UNCOMPRESSED.contains(&ts.as_str()) {
        let shown: String = ts
            .chars()
            .take(64)
            .map(|c| if c.is_ascii_graphic() { c } else { '?' })
            .collect();
        return Err(Error::Unsupported {
            what: "DICOM transfer syntax",
            value: format!(
                "{shown:?} in {} (expected uncompressed little endian: {})",
                path.display(),
                UNCOMPRESSED.join(", ")
            ),
        });
    }
    let explicit = ts != "1.2.840.10008.1.2";
    walk(path, &b, pos, b.len(), explicit, 0, &mut found)?;
    Ok(found)
}

fn int(obj: &DefaultDicomObject, tag: Tag) -> Option<i64> {
    obj.element_opt(tag).ok().flatten()?.to_int::<i64>().ok()
}

fn float(obj: &DefaultDicomObject, tag: Tag) -> Option<f64> {
    obj.element_opt(tag).ok().flatten()?.to_float64().ok()
}

fn floats(obj: &DefaultDicomObject, tag: Tag) -> Option<Vec<f64>> {
    obj.element_opt(tag).ok().flatten()?.to_multi_float64().ok()
}

fn text(obj: &DefaultDicomObject, tag: Tag) -> String {
    obj.element_opt(tag)
        .ok()
        .flatten()
        .and_then(|e| {
            e.to_str()
                .ok()
                .map(|s| s.trim().trim_end_matches('\0').to_string())
        })
        .unwrap_or_default()
}

fn load_slice(path: &Path) -> Result<Slice> {
    let walked = check_lengths(path)?;
    let obj = open_file(path).map_err(|e| {
        let e = e.to_string();
        let e: String = e.lines().next().unwrap_or("").chars().take(200).collect();
        bad(path, format!("cannot parse: {e}"))
    })?;
    let rows = int(&obj, ROWS).ok_or_else(|| bad(path, "no Rows"))? as usize;
    let cols = int(&obj, COLUMNS).ok_or_else(|| bad(path, "no Columns"))? as usize;
    let spp = int(&obj, SAMPLES_PER_PIXEL).unwrap_or(1);
    if spp != 1 {
        return Err(Error::Unsupported {
            what: "DICOM samples per pixel",
            value: format!("{spp} (expected 1)"),
        });
    }
    let alloc = int(&obj, BITS_ALLOCATED).unwrap_or(16);
    let bits_stored = int(&obj, BITS_STORED)
        .unwrap_or(alloc)
        .clamp(1, alloc.max(1));
    let signed = int(&obj, PIXEL_REPRESENTATION).unwrap_or(0) == 1;
    let n = rows
        .checked_mul(cols)
        .ok_or_else(|| bad(path, "Rows × Columns overflows"))?;
    let want = (n as u64)
        .checked_mul(alloc.max(0) as u64)
        .map(|b| b.div_ceil(8))
        .ok_or_else(|| bad(path, "Rows × Columns × BitsAllocated overflows"))?;
    match walked.pixel_data {
        Some(len) if len != want && len != want + (want & 1) => {
            return Err(bad(
                path,
                format!(
                "PixelData of {len} bytes for {rows}x{cols} samples of {alloc} bits ({want} bytes)"
            ),
            ))
        }
        _ => {}
    }
    let raw = pixel_values(&obj, alloc, path)?;
    if raw.len() < n {
        return Err(bad(
            path,
            format!("PixelData holds {} samples for {rows}x{cols}", raw.len()),
        ));
    }
    let mask = (1i64 << bits_stored) - 1;
    let stored: Vec<i64> = raw[..n]
        .iter()
        .map(|&x| {
            let v = x & mask;
            if signed && v >> (bits_stored - 1) & 1 == 1 {
                v - (1i64 << bits_stored)
            } else {
                v
            }
        })
        .collect();
    let stored_type = match (alloc, signed) {
        (8, false) => SampleType::U8,
        (8, true) => SampleType::I8,
        (_, false) => SampleType::U16,
        (_, true) => SampleType::I16,
    };
    let arr3 = |v: Option<Vec<f64>>| v.filter(|v| v.len() == 3).map(|v| [v[0], v[1], v[2]]);
    Ok(Slice {
        rows,
        cols,
        stored,
        slope: float(&obj, RESCALE_SLOPE).unwrap_or(1.0),
        intercept: float(&obj, RESCALE_INTERCEPT).unwrap_or(0.0),
        position: arr3(floats(&obj, IMAGE_POSITION)),
        orientation: floats(&obj, IMAGE_ORIENTATION)
            .filter(|v| v.len() == 6)
            .map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]]),
        pixel_spacing: floats(&obj, PIXEL_SPACING)
            .filter(|v| v.len() == 2)
            .map(|v| [v[0], v[1]]),
        thickness: float(&obj, SLICE_THICKNESS),
        series: text(&obj, SERIES_UID),
        modality: text(&obj, MODALITY),
        stored_type,
    })
}

/// The pixel data as raw stored words (before masking to BitsAllocated), for 8 or 16 bits
/// allocated; encapsulated (compressed) data is refused.
fn pixel_values(obj: &DefaultDicomObject, alloc: i64, path: &Path) -> Result<Vec<i64>> {
    let elem = obj
        .element(PIXEL_DATA)
        .map_err(|_| bad(path, "no PixelData"))?;
    let prim = elem.value().primitive().ok_or_else(|| Error::Unsupported {
        what: "DICOM pixel data",
        value: "encapsulated (compressed) fragments".into(),
    })?;
    use dicom_core::value::PrimitiveValue as P;
    Ok(match (alloc, prim) {
        (16, P::U16(v)) => v.iter().map(|&x| x as i64).collect(),
        (16, P::I16(v)) => v.iter().map(|&x| x as u16 as i64).collect(),
        (16, P::U8(b)) => b
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]) as i64)
            .collect(),
        (8, P::U8(b)) => b.iter().map(|&x| x as i64).collect(),
        (8, P::U16(v)) => v
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .map(|x| x as i64)
            .collect(),
        (a, _) => {
            return Err(Error::Unsupported {
                what: "DICOM BitsAllocated",
                value: format!("{a} (expected 8 or 16)"),
            })
        }
    })
}

/// Rescale stored values and pick the output type (see the module doc).
fn rescale(values: Vec<i64>, slope: f64, intercept: f64, stored: SampleType) -> Samples {
    if slope == 1.0 && intercept == 0.0 {
        let v: Vec<f64> = values.iter().map(|&x| x as f64).collect();
        return Samples::from_f64(&v, stored);
    }
    if slope == 1.0 && intercept.fract() == 0.0 {
        let out: Vec<i64> = values.iter().map(|&x| x + intercept as i64).collect();
        if out
            .iter()
            .all(|&x| x >= i16::MIN as i64 && x <= i16::MAX as i64)
        {
            return Samples::I16(out.into_iter().map(|x| x as i16).collect());
        }
    }
    Samples::F32(
        values
            .iter()
            .map(|&x| (x as f64 * slope + intercept) as f32)
            .collect(),
    )
}

/// Spacing, origin, space and directions of a slice (`step`: the slice vector of a
/// series, from the first slice to the next).
fn set_meta(r: &mut Raster, s: &Slice, step: Option<[f64; 3]>) {
    let ps = s.pixel_spacing.unwrap_or([1.0, 1.0]);
    let norm = |v: &[f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    r.meta.spacing = Some(match &step {
        Some(dz) => vec![norm(dz), ps[0], ps[1]],
        None => vec![ps[0], ps[1]],
    });
    r.meta.origin = s.position.map(|p| p.to_vec());
    r.meta.units = Some("mm".into());
    if let (Some(o), Some(_)) = (s.orientation, s.position) {
        r.meta.space = Some("left-posterior-superior".into());
        let mut dirs = vec![
            vec![o[0] * ps[1], o[1] * ps[1], o[2] * ps[1]],
            vec![o[3] * ps[0], o[4] * ps[0], o[5] * ps[0]],
        ];
        if let Some(dz) = step {
            dirs.push(dz.to_vec());
        }
        r.meta.directions = Some(dirs);
    }
    let ex = &mut r.meta.extra;
    ex.insert("dicom.modality".into(), s.modality.clone());
    ex.insert("dicom.series_uid".into(), s.series.clone());
    ex.insert("dicom.rescale_slope".into(), s.slope.to_string());
    ex.insert("dicom.rescale_intercept".into(), s.intercept.to_string());
    ex.insert("dicom.stored_type".into(), s.stored_type.name().into());
    if let Some(o) = s.orientation {
        ex.insert(
            "dicom.orientation".into(),
            o.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(","),
        );
    }
}

/// Read one DICOM file as a 2-D slice.
pub fn read_file(path: &Path) -> Result<Raster> {
    let s = load_slice(path)?;
    let (rows, cols) = (s.rows, s.cols);
    let samples = rescale(s.stored.clone(), s.slope, s.intercept, s.stored_type);
    let mut r = Raster::new(vec![rows, cols], 1, samples, DataKind::Image)?;
    set_meta(&mut r, &s, None);
    Ok(r)
}

pub use super::dicom_scan::{dicom_files, is_dicom};

/// Whether the sorted slice `positions` are evenly spaced: every step positive and within
/// 1 % of the median step. Uneven (or repeated) positions are an error unless `uneven_ok`.
fn even_steps(positions: &[f64], uneven_ok: bool) -> Result<bool> {
    let depth = positions.len();
    let mut steps: Vec<f64> = positions.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let median = steps.get(steps.len() / 2).copied().unwrap_or(0.0);
    let even = steps
        .iter()
        .all(|&d| d > 0.0 && (d - median).abs() <= 0.01 * median);
    if depth > 1 && !even && !uneven_ok {
        let shown: Vec<String> = positions.iter().map(|p| format!("{p}")).collect();
        let what = if steps
            .iter()
            .any(|&d| d.abs() <= 0.01 * median.abs().max(1e-6))
        {
            "repeated"
        } else {
            "unevenly spaced"
        };
        return Err(Error::format(
            format!(
                "{what} slice positions {} mm along the slice normal of the series",
                shown.join(" / ")
            ),
            "distinct, evenly spaced slices (or --allow-uneven-slices)",
        ));
    }
    Ok(even)
}

/// The slices' samples in order, rescaled together when they share slope and intercept,
/// else each by its own into `f32`.
fn stack_samples(slices: &[Slice]) -> Samples {
    let depth = slices.len();
    let (rows, cols) = (slices[0].rows, slices[0].cols);
    let (slope, intercept) = (slices[0].slope, slices[0].intercept);
    let same_rescale = slices
        .iter()
        .all(|s| s.slope == slope && s.intercept == intercept);
    let stored_type = slices[0].stored_type;
    if same_rescale {
        let mut all = Vec::with_capacity(depth * rows * cols);
        for s in slices {
            all.extend_from_slice(&s.stored);
        }
        rescale(all, slope, intercept, stored_type)
    } else {
        let mut all = Vec::with_capacity(depth * rows * cols);
        for s in slices {
            all.extend(
                s.stored
                    .iter()
                    .map(|&x| (x as f64 * s.slope + s.intercept) as f32),
            );
        }
        Samples::F32(all)
    }
}

/// Read a folder holding one DICOM series as a volume `[slices, rows, columns]`;
/// `uneven_ok` accepts missing or repeated slice positions (see the module doc).
pub fn read_series(dir: &Path, uneven_ok: bool) -> Result<Raster> {
    let files = dicom_files(dir)?;
    if files.is_empty() {
        return Err(Error::format(
            format!("no DICOM files in folder {}", dir.display()),
            "a folder holding one DICOM series",
        ));
    }
    let mut slices = files
        .iter()
        .map(|p| load_slice(p))
        .collect::<Result<Vec<_>>>()?;
    let series = slices[0].series.clone();
    if let Some(other) = slices.iter().find(|s| s.series != series) {
        return Err(Error::Unsupported {
            what: "DICOM folder",
            value: format!("more than one series ({series} and {})", other.series),
        });
    }
    let (rows, cols) = (slices[0].rows, slices[0].cols);
    if slices.iter().any(|s| s.rows != rows || s.cols != cols) {
        return Err(Error::format(
            "slices of different sizes in one series",
            "equal Rows and Columns in every slice",
        ));
    }
    // order along the slice normal
    let o = slices[0]
        .orientation
        .unwrap_or([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let normal = [
        o[1] * o[5] - o[2] * o[4],
        o[2] * o[3] - o[0] * o[5],
        o[0] * o[4] - o[1] * o[3],
    ];
    let key = |s: &Slice| {
        s.position
            .map(|p| p[0] * normal[0] + p[1] * normal[1] + p[2] * normal[2])
            .unwrap_or(0.0)
    };
    slices.sort_by(|a, b| key(a).total_cmp(&key(b)));
    let positions: Vec<f64> = slices.iter().map(key).collect();
    let depth = slices.len();
    let even = even_steps(&positions, uneven_ok)?;
    // the slice vector: first to last over the steps between them (mean step)
    let step = if depth > 1 {
        match (slices[0].position, slices[depth - 1].position) {
            (Some(a), Some(b)) if positions[depth - 1] > positions[0] => {
                let k = (depth - 1) as f64;
                [(b[0] - a[0]) / k, (b[1] - a[1]) / k, (b[2] - a[2]) / k]
            }
            _ => {
                let t = slices[0].thickness.unwrap_or(1.0);
                [normal[0] * t, normal[1] * t, normal[2] * t]
            }
        }
    } else {
        let t = slices[0].thickness.unwrap_or(1.0);
        [normal[0] * t, normal[1] * t, normal[2] * t]
    };
    let samples = stack_samples(&slices);
    let mut r = Raster::new(vec![depth, rows, cols], 1, samples, DataKind::Volume)?;
    set_meta(&mut r, &slices[0], Some(step));
    if !even {
        let shown: Vec<String> = positions.iter().map(|p| format!("{p}")).collect();
        r.meta
            .extra
            .insert("dicom.slice_positions".into(), shown.join(" "));
    }
    Ok(r)
}
