//! NIfTI-1 single-file images (`.nii`, `.nii.gz`): a 348-byte header, then voxels from
//! `vox_offset`, x fastest. Either byte order (told by `sizeof_hdr` = 348).
//!
//! Header fields used (byte offsets): `dim` i16×8 @40, `datatype` i16 @70, `bitpix` @72,
//! `pixdim` f32×8 @76, `vox_offset` f32 @108, `scl_slope`/`scl_inter` f32 @112/116,
//! `xyzt_units` u8 @123, `qform_code`/`sform_code` i16 @252/254, quaternion b c d and
//! offsets f32 @256–276, `srow_x/y/z` f32×4 @280/296/312, magic @344.
//!
//! Voxel values are kept as stored; `scl_slope`/`scl_inter` go into
//! `meta.extra["nifti.scl_slope"/"nifti.scl_inter"]` when the slope is set. The affine is
//! the sform when `sform_code > 0`, else the qform (NIfTI-1 "method 2"), else the pixdim
//! diagonal. RGB24 (datatype 128) reads as 3 channels of u8.

use std::io::{Read, Write};
use std::path::Path;

use byteorder::{BigEndian, ByteOrder, LittleEndian};
use flate2::read::MultiGzDecoder;

use super::bytes::{self, checked_bytes};
use super::{DataKind, Raster, SampleType};
use crate::{Error, Result};

const HDR: usize = 348;

fn bad(what: impl std::fmt::Display) -> Error {
    Error::format(what, "a valid NIfTI-1 file")
}

fn datatype(code: i16) -> Result<(SampleType, usize)> {
    Ok(match code {
        2 => (SampleType::U8, 1),
        4 => (SampleType::I16, 1),
        8 => (SampleType::I32, 1),
        16 => (SampleType::F32, 1),
        64 => (SampleType::F64, 1),
        128 => (SampleType::U8, 3),
        256 => (SampleType::I8, 1),
        512 => (SampleType::U16, 1),
        768 => (SampleType::U32, 1),
        2304 => (SampleType::U8, 4),
        other => {
            return Err(Error::Unsupported {
                what: "NIfTI datatype",
                value: other.to_string(),
            })
        }
    })
}

fn datatype_code(t: SampleType, channels: usize) -> Result<i16> {
    Ok(match (t, channels) {
        (SampleType::U8, 1) => 2,
        (SampleType::I16, 1) => 4,
        (SampleType::I32, 1) => 8,
        (SampleType::F32, 1) => 16,
        (SampleType::F64, 1) => 64,
        (SampleType::U8, 3) => 128,
        (SampleType::I8, 1) => 256,
        (SampleType::U16, 1) => 512,
        (SampleType::U32, 1) => 768,
        (SampleType::U8, 4) => 2304,
        (t, c) => {
            return Err(Error::Unsupported {
                what: "NIfTI output",
                value: format!("{c} channels of {t}"),
            })
        }
    })
}

/// The file as a stream (inflated for `.nii.gz`), with the most bytes it can yield:
/// its length when plain, deflate's largest expansion (1032:1) of it when gzip.
fn open(path: &Path) -> Result<(Box<dyn Read>, u64)> {
    let mut head = [0u8; 2];
    let n = bytes::read_head(path, &mut head)?;
    let file = std::fs::File::open(path)?;
    let len = file.metadata()?.len();
    let file = std::io::BufReader::new(file);
    Ok(if n == 2 && head == [0x1f, 0x8b] {
        (
            Box::new(MultiGzDecoder::new(file)),
            len.saturating_mul(1032),
        )
    } else {
        (Box::new(file), len)
    })
}

/// Read at most `n` more bytes of `src` onto `out` (gzip errors reported as format errors).
fn read_up_to(src: &mut dyn Read, n: u64, out: &mut Vec<u8>) -> Result<()> {
    src.take(n)
        .read_to_end(out)
        .map_err(|e| bad(format!("gzip stream: {e}")))?;
    Ok(())
}

/// The 348 bytes of a NIfTI-1 header, `big`-endian or not.
struct Hdr<'a> {
    b: &'a [u8],
    big: bool,
}

impl Hdr<'_> {
    fn i16_at(&self, o: usize) -> i16 {
        if self.big {
            BigEndian::read_i16(&self.b[o..])
        } else {
            LittleEndian::read_i16(&self.b[o..])
        }
    }

    fn f32_at(&self, o: usize) -> f32 {
        if self.big {
            BigEndian::read_f32(&self.b[o..])
        } else {
            LittleEndian::read_f32(&self.b[o..])
        }
    }

    /// The axis sizes, fastest first (`dim[1..=dim[0]]`), trailing unit axes folded away;
    /// at most 3.
    fn sizes(&self) -> Result<Vec<usize>> {
        let ndim = self.i16_at(40);
        if !(1..=7).contains(&ndim) {
            return Err(bad(format!("dim[0] = {ndim} (expected 1..7)")));
        }
        let mut sizes = Vec::new();
        for i in 1..=ndim as usize {
            let d = self.i16_at(40 + 2 * i);
            if d < 1 {
                return Err(bad(format!("dim[{i}] = {d} (expected ≥ 1)")));
            }
            sizes.push(d as usize);
        }
        // fold trailing unit dims (t = 1) away, keep at least x
        while sizes.len() > 1 && *sizes.last().unwrap() == 1 {
            sizes.pop();
        }
        if sizes.len() > 3 {
            return Err(Error::Unsupported {
                what: "NIfTI dimensions",
                value: format!("{} (expected at most 3 spatial axes)", sizes.len()),
            });
        }
        Ok(sizes)
    }

    /// The voxel-to-world affine: the sform where its code is set, else the qform
    /// (quaternion, offsets, `pixdim` scales with `qfac`), else the `pixdim` diagonal.
    #[allow(clippy::needless_range_loop)]
    fn affine(&self, pixdim: &[f64]) -> [[f64; 4]; 3] {
        let (qform, sform) = (self.i16_at(252), self.i16_at(254));
        let f32_at = |o: usize| self.f32_at(o);
        if sform > 0 {
            let mut a = [[0.0; 4]; 3];
            for (r, row) in a.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    *v = f32_at(280 + 16 * r + 4 * c) as f64;
                }
            }
            a
        } else if qform > 0 {
            let (qb, qc, qd) = (f32_at(256) as f64, f32_at(260) as f64, f32_at(264) as f64);
            let qa = (1.0 - (qb * qb + qc * qc + qd * qd)).max(0.0).sqrt();
            let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
            let r = [
                [
                    qa * qa + qb * qb - qc * qc - qd * qd,
                    2.0 * (qb * qc - qa * qd),
                    2.0 * (qb * qd + qa * qc),
                ],
                [
                    2.0 * (qb * qc + qa * qd),
                    qa * qa + qc * qc - qb * qb - qd * qd,
                    2.0 * (qc * qd - qa * qb),
                ],
                [
                    2.0 * (qb * qd - qa * qc),
                    2.0 * (qc * qd + qa * qb),
                    qa * qa + qd * qd - qc * qc - qb * qb,
                ],
            ];
            let s = [pixdim[1], pixdim[2], qfac * pixdim[3]];
            let o = [f32_at(268) as f64, f32_at(272) as f64, f32_at(276) as f64];
            let mut a = [[0.0; 4]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    a[i][j] = r[i][j] * s[j];
                }
                a[i][3] = o[i];
            }
            a
        } else {
            [
                [pixdim[1], 0.0, 0.0, 0.0],
                [0.0, pixdim[2], 0.0, 0.0],
                [0.0, 0.0, pixdim[3], 0.0],
            ]
        }
    }
}

/// Read a `.nii` / `.nii.gz` file.
pub fn read(path: &Path) -> Result<Raster> {
    // the header first; then only as many bytes as it declares (a stream that inflates
    // to more is not read further)
    let (mut src, most) = open(path)?;
    let mut b = Vec::with_capacity(HDR);
    read_up_to(&mut src, HDR as u64, &mut b)?;
    if b.len() < HDR {
        return Err(bad(format!(
            "{} bytes, shorter than the 348-byte header",
            b.len()
        )));
    }
    let big = if LittleEndian::read_i32(&b[0..4]) == 348 {
        false
    } else if BigEndian::read_i32(&b[0..4]) == 348 {
        true
    } else {
        return Err(bad("sizeof_hdr is not 348"));
    };
    if &b[344..348] != b"n+1\0" {
        return Err(Error::Unsupported {
            what: "NIfTI variant",
            value: "header/image pair (.hdr/.img) or NIfTI-2".into(),
        });
    }
    let h = Hdr { b: &b, big };
    let (i16_at, f32_at) = (|o: usize| h.i16_at(o), |o: usize| h.f32_at(o));
    let sizes = h.sizes()?;
    let (ty, channels) = datatype(i16_at(70))?;
    let vox_offset = f32_at(108);
    if vox_offset.is_nan() || vox_offset < HDR as f32 {
        return Err(bad(format!("vox_offset {vox_offset} (expected ≥ 352)")));
    }
    let off = vox_offset as u64;
    let dims: Vec<usize> = sizes.iter().rev().copied().collect();
    let budget = crate::limits::Limits::from_env()?;
    let declared = (bytes::sample_count(&dims, channels)? as u64).saturating_mul(ty.size() as u64);
    budget.check("NIfTI data bytes (memory budget MRA_MAX_BYTES)", declared)?;
    // what the file can hold at most, checked before reading (exact for a plain file)
    checked_bytes(&dims, channels, ty, most.saturating_sub(off))?;
    let skip = off - HDR as u64;
    let skipped = std::io::copy(&mut (&mut src).take(skip), &mut std::io::sink())
        .map_err(|e| bad(format!("gzip stream: {e}")))?;
    if skipped != skip {
        return Err(bad(format!("vox_offset {off} beyond the end of the data")));
    }
    let mut data = Vec::with_capacity(declared.min(most.saturating_sub(off)).min(1 << 30) as usize);
    read_up_to(&mut src, declared, &mut data)?;
    // one byte more, so that a gzip stream that ends here has its trailer (CRC, length)
    // checked; a stream that goes on is not read further
    if data.len() as u64 == declared {
        src.read(&mut [0u8; 1])
            .map_err(|e| bad(format!("gzip stream: {e}")))?;
    }
    let need = checked_bytes(&dims, channels, ty, data.len() as u64)?;
    let samples = bytes::decode(&data[..need], ty, big);

    let pixdim: Vec<f64> = (0..8).map(|i| f32_at(76 + 4 * i) as f64).collect();
    let mut spacing: Vec<f64> = (1..=sizes.len()).map(|i| pixdim[i].abs()).collect();
    spacing.reverse();
    let qform = i16_at(252);
    let sform = i16_at(254);
    let affine = h.affine(&pixdim);
    let kind = match dims.len() {
        1 => DataKind::Sequence,
        2 => DataKind::Image,
        _ => DataKind::Volume,
    };
    let mut r = Raster::new(dims, channels, samples, kind)?;
    r.meta.spacing = Some(spacing);
    r.meta.affine = Some(affine);
    r.meta.origin = Some(vec![affine[0][3], affine[1][3], affine[2][3]]);
    r.meta.units = match b[123] & 0x07 {
        1 => Some("m".into()),
        2 => Some("mm".into()),
        3 => Some("um".into()),
        _ => None,
    };
    let slope = f32_at(112);
    if slope != 0.0 && slope.is_finite() {
        r.meta
            .extra
            .insert("nifti.scl_slope".into(), slope.to_string());
        r.meta
            .extra
            .insert("nifti.scl_inter".into(), f32_at(116).to_string());
    }
    r.meta
        .extra
        .insert("nifti.qform_code".into(), qform.to_string());
    r.meta
        .extra
        .insert("nifti.sform_code".into(), sform.to_string());
    Ok(r)
}

/// Encode `r` as a little-endian NIfTI-1 single file (header + 4 pad bytes + voxels),
/// with the affine as sform (code from `nifti.sform_code`, default 2 "aligned").
pub fn encode(r: &Raster) -> Result<Vec<u8>> {
    if r.dims.is_empty() || r.dims.len() > 3 {
        return Err(Error::Unsupported {
            what: "NIfTI output",
            value: format!("{}-D data", r.dims.len()),
        });
    }
    let code = datatype_code(r.sample_type(), r.channels)?;
    let mut h = vec![0u8; HDR + 4];
    LittleEndian::write_i32(&mut h[0..], 348);
    h[38] = b'r'; // regular
    let sizes: Vec<usize> = r.dims.iter().rev().copied().collect();
    LittleEndian::write_i16(&mut h[40..], sizes.len() as i16);
    for (i, &s) in sizes.iter().enumerate() {
        let s = i16::try_from(s).map_err(|_| Error::Unsupported {
            what: "NIfTI-1 axis length",
            value: format!("{s} (at most 32767)"),
        })?;
        LittleEndian::write_i16(&mut h[42 + 2 * i..], s);
    }
    for i in sizes.len()..7 {
        LittleEndian::write_i16(&mut h[42 + 2 * i..], 1);
    }
    LittleEndian::write_i16(&mut h[70..], code);
    LittleEndian::write_i16(
        &mut h[72..],
        (r.sample_type().size() * r.channels * 8) as i16,
    );
    let spacing: Vec<f64> = match &r.meta.spacing {
        Some(s) if s.len() == sizes.len() => s.iter().rev().copied().collect(),
        _ => vec![1.0; sizes.len()],
    };
    LittleEndian::write_f32(&mut h[76..], 1.0);
    for (i, &s) in spacing.iter().enumerate() {
        LittleEndian::write_f32(&mut h[80 + 4 * i..], s as f32);
    }
    LittleEndian::write_f32(&mut h[108..], 352.0);
    let slope: f32 = r
        .meta
        .extra
        .get("nifti.scl_slope")
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.0);
    let inter: f32 = r
        .meta
        .extra
        .get("nifti.scl_inter")
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.0);
    LittleEndian::write_f32(&mut h[112..], slope);
    LittleEndian::write_f32(&mut h[116..], inter);
    h[123] = match r.meta.units.as_deref() {
        Some("m") => 1,
        Some("um") => 3,
        _ => 2,
    };
    let affine = r.meta.affine.unwrap_or_else(|| {
        let o = r.meta.origin.clone().unwrap_or_default();
        let mut a = [[0.0; 4]; 3];
        for (i, row) in a.iter_mut().enumerate() {
            row[i] = *spacing.get(i).unwrap_or(&1.0);
            row[3] = *o.get(i).unwrap_or(&0.0);
        }
        a
    });
    let sform: i16 = r
        .meta
        .extra
        .get("nifti.sform_code")
        .and_then(|s| s.parse().ok())
        .filter(|&c: &i16| c > 0)
        .unwrap_or(2);
    LittleEndian::write_i16(&mut h[254..], sform);
    for (ri, row) in affine.iter().enumerate() {
        for (c, &v) in row.iter().enumerate() {
            LittleEndian::write_f32(&mut h[280 + 16 * ri + 4 * c..], v as f32);
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend_from_slice(&bytes::encode(&r.samples, false));
    Ok(h)
}

/// Write `.nii` or (by name) gzip-compressed `.nii.gz`.
pub fn write_path(path: &Path, r: &Raster) -> Result<()> {
    let data = encode(r)?;
    let gz = path.to_string_lossy().to_ascii_lowercase().ends_with(".gz");
    bytes::atomic_write(path, |w| {
        if gz {
            let mut enc = flate2::write::GzEncoder::new(w, flate2::Compression::fast());
            enc.write_all(&data)?;
            enc.finish()?;
        } else {
            w.write_all(&data)?;
        }
        Ok(())
    })
}
