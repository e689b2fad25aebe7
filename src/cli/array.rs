//! `mra analyze` / `mra synthesize` on images, volumes and heightmaps (any input
//! [`crate::io`] reads). `src/cli/analyze.rs` parses the arguments and calls
//! [`analyze_path`] / [`synthesize_path`] for every input that is not a point list
//! (tests and other commands call them too).
//!
//! `analyze IN -o OUT` writes the pyramid in the Mallat layout as float32 TIFF (2-D,
//! all channels) or float32 NRRD (3-D) with scheme, boundary, levels, order and the
//! source type in its metadata; with `--visual` it writes an 8-bit PNG picture instead
//! (`--slice z` picks the slice of a volume). `synthesize PYRAMID -o OUT` reconstructs
//! the input in its own sample type, in the format OUT's extension names.

use std::path::Path;

use super::io_cmds::{read_input, write_output};
use super::{CliResult, Failure};
use crate::io::{self, pyramid_file, ReadOptions};
use crate::progress::Progress;
use crate::tensor::PyramidSpec;

/// Levels for arrays when `--levels` is not given.
pub const DEFAULT_LEVELS: usize = 3;

/// What `mra analyze` needs besides the paths.
#[derive(Clone, Debug)]
pub struct AnalyzeOptions {
    /// Scheme, boundary, levels, order (`axes` is set to all spatial axes).
    pub spec: PyramidSpec,
    /// Write an 8-bit PNG picture of the pyramid instead of the coefficients.
    pub visual: bool,
    /// Slice of a volume to picture (default 0, through the coarse block).
    pub slice: Option<usize>,
    /// Layout of headerless input (`--dims/--dtype/--endian`).
    pub read: ReadOptions,
    /// No progress bar.
    pub quiet: bool,
}

/// Analyze the array file `input` into the pyramid file (or picture) `output`.
pub fn analyze_path(input: &Path, output: &Path, o: &AnalyzeOptions) -> CliResult {
    let bar = Progress::new(3, "analyze", o.quiet);
    let r = read_input(input, &o.read)?;
    bar.inc(1);
    let ndims = r.dims.len();
    if !o.visual && !(2..=3).contains(&ndims) {
        return Err(Failure::context(
            input.display(),
            format!("{}-D data (expected an image, heightmap or volume)", ndims),
        ));
    }
    if !o.visual {
        let want = pyramid_file::extension(ndims);
        let ext = output
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let ok = if want == "tif" {
            ext == "tif" || ext == "tiff"
        } else {
            ext == "nrrd" || ext == "nhdr"
        };
        if !ok {
            return Err(Failure(format!(
                "{}: a {}-D pyramid is written as .{want} (or use --visual for a .png picture)",
                output.display(),
                ndims
            )));
        }
    }
    let (container, pyr) =
        io::array::analyze_raster(r, &o.spec).map_err(|e| Failure::context(input.display(), e))?;
    bar.inc(1);
    if o.visual {
        let pic = io::array::picture(&container, &pyr, o.slice)
            .map_err(|e| Failure::context(input.display(), e))?;
        drop(container);
        write_output(output, &pic, false)?;
    } else {
        pyramid_file::write(output, &container)
            .map_err(|e| Failure::context(output.display(), e))?;
    }
    bar.inc(1);
    bar.finish();
    Ok(())
}

/// Reconstruct the array file `output` from the pyramid file `input` (written by
/// [`analyze_path`]).
pub fn synthesize_path(input: &Path, output: &Path, quiet: bool) -> CliResult {
    let bar = Progress::new(3, "synthesize", quiet);
    let (container, info) =
        pyramid_file::read(input).map_err(|e| Failure::context(input.display(), e))?;
    bar.inc(1);
    let r = io::array::synthesize_raster(container, &info)
        .map_err(|e| Failure::context(input.display(), e))?;
    bar.inc(1);
    write_output(output, &r, false)?;
    bar.inc(1);
    bar.finish();
    Ok(())
}
