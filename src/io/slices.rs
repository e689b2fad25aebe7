//! A folder as a volume: either one DICOM series ([`super::dicom::read_series`]) or a
//! set of equal 2-D slices (TIFF, PNG, PGM), stacked in file-name order, first file = z 0.

use std::path::{Path, PathBuf};

use super::{DataKind, Format, Raster, Samples};
use crate::{Error, Result};

fn is_slice_file(p: &Path) -> bool {
    p.is_file()
        && matches!(
            Format::from_extension(p),
            Some(Format::Tiff | Format::Png | Format::Pnm)
        )
        && !p
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'))
}

/// The slice files of a folder, by name.
pub fn slice_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| is_slice_file(p))
        .collect();
    files.sort();
    Ok(files)
}

/// Decide what a folder holds: a DICOM series, image slices, or nothing readable.
pub fn classify_folder(dir: &Path) -> Result<Format> {
    if !super::dicom::dicom_files(dir)?.is_empty() {
        return Ok(Format::DicomSeries);
    }
    if !slice_files(dir)?.is_empty() {
        return Ok(Format::SliceFolder);
    }
    Err(Error::format(
        "folder holds no DICOM files and no image slices",
        "a folder with one DICOM series or .tif/.png slices",
    ))
}

/// Stack the 2-D slices of a folder into a volume `[files, H, W]`.
pub fn read(dir: &Path) -> Result<Raster> {
    let files = slice_files(dir)?;
    let Some(first) = files.first() else {
        return Err(Error::format(
            "folder holds no image slices",
            "a folder with .tif/.png slices",
        ));
    };
    let r0 = super::read(first)?;
    if r0.dims.len() != 2 {
        return Err(Error::format(
            format!("slice {} is not 2-D", first.display()),
            "2-D slices",
        ));
    }
    let mut samples = r0.samples.clone();
    for f in &files[1..] {
        let r = super::read(f)?;
        if r.dims != r0.dims || r.channels != r0.channels || r.sample_type() != r0.sample_type() {
            return Err(Error::format(
                format!(
                    "slice {} is {} but the first is {}",
                    f.display(),
                    r.summary(),
                    r0.summary()
                ),
                "slices of equal size and type",
            ));
        }
        match (&mut samples, r.samples) {
            (Samples::U8(a), Samples::U8(b)) => a.extend(b),
            (Samples::I8(a), Samples::I8(b)) => a.extend(b),
            (Samples::U16(a), Samples::U16(b)) => a.extend(b),
            (Samples::I16(a), Samples::I16(b)) => a.extend(b),
            (Samples::U32(a), Samples::U32(b)) => a.extend(b),
            (Samples::I32(a), Samples::I32(b)) => a.extend(b),
            (Samples::F16(a), Samples::F16(b)) => a.extend(b),
            (Samples::F32(a), Samples::F32(b)) => a.extend(b),
            (Samples::F64(a), Samples::F64(b)) => a.extend(b),
            _ => unreachable!("types checked above"),
        }
    }
    let dims = vec![files.len(), r0.dims[0], r0.dims[1]];
    let mut r = Raster::new(dims, r0.channels, samples, DataKind::Volume)?;
    r.meta = r0.meta;
    if let Some(sp) = r.meta.spacing.take() {
        if sp.len() == 2 {
            r.meta.spacing = Some(vec![1.0, sp[0], sp[1]]);
        }
    }
    Ok(r)
}
