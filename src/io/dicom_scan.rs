//! Finding DICOM files (with or without the `dicom` feature): the preamble test and a
//! folder's DICOM files.

use crate::Result;
use std::path::{Path, PathBuf};

/// Does the file start with the DICOM preamble + `DICM`?
pub fn is_dicom(path: &Path) -> bool {
    let mut head = [0u8; 132];
    matches!(super::bytes::read_head(path, &mut head), Ok(132)) && &head[128..132] == b"DICM"
}

/// The DICOM files of a folder, by name.
pub fn dicom_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && is_dicom(p))
        .collect();
    files.sort();
    Ok(files)
}
