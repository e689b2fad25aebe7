//! `mra transfer`: the fine details of an example given to an image, heightmap or volume
//! (a thin shell over [`crate::terrain::transfer`] and [`crate::terrain::transfer_volume`]).

use std::path::{Path, PathBuf};

use clap::Args;

use super::io_cmds::{read_input, report_json, write_result};
use super::terrain::MatchArgs;
use super::{CliResult, Failure};
use crate::io::{self, Raster, ReadOptions, Samples};
use crate::terrain::{self, raster as tr, SynthOptions};

#[derive(Args, Debug)]
#[command(after_help = "Example:
  mra generate terrain --size 257 --seed 3 -o smooth.png
  mra generate terrain --size 257 --seed 9 -o rough.png
  mra transfer --from rough.png --to smooth.png --levels 2 -o out.png
  mra transfer --from ../shared/corpus/volumes/ct_pancreas_256.nrrd --to blurred.nrrd -o ct.nrrd")]
pub struct TransferArgs {
    /// The example whose fine details are transferred.
    #[arg(long)]
    pub from: PathBuf,
    /// The image, heightmap or volume that receives them (its own details are replaced).
    #[arg(long)]
    pub to: PathBuf,
    /// Output file; the extension picks the format (`-`: standard output, with --format).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output), as an extension: png, tif, exr, nrrd, …
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    #[command(flatten)]
    pub m: MatchArgs,
}

/// A volume transfer: both inputs 3-D (NRRD, NIfTI, raw, slice folders…), output with
/// the base's size, metadata and sample type.
fn transfer_volume(a: &TransferArgs, br: Raster, er: Raster) -> CliResult {
    if er.dims.len() != 3 {
        return Err(Failure(format!(
            "{}: {}-D data (expected a volume, like --to)",
            a.from.display(),
            er.dims.len()
        )));
    }
    // voids are filled (pull-push) before synthesis, as the 2-D path fills them
    let vol = |r: &Raster, p: &Path| {
        let mut data = r.to_f64();
        let mut shape = r.dims.clone();
        shape.push(r.channels);
        if let Some(v) = io::nodata::Voids::find(&data, r.meta.nodata) {
            v.fill(&mut data, &shape, 3)
                .map_err(|e| Failure::context(p.display(), e))?;
        }
        terrain::Volume::new([r.dims[0], r.dims[1], r.dims[2]], r.channels, data)
            .map_err(|e| Failure::context(p.display(), e))
    };
    let (base, example) = (vol(&br, &a.to)?, vol(&er, &a.from)?);
    let o = SynthOptions {
        candidates: a.m.candidates.unwrap_or(4096),
        ..a.m.options()
    };
    let (v, report) = terrain::transfer_volume(&base, &example, &o)?;
    let ty = br.sample_type();
    let mut out = Raster {
        samples: Samples::from_f64(v.data(), ty),
        ..br
    };
    out.meta.nodata = None;
    write_result(&a.output, &out, a.format.as_deref())?;
    if a.m.json {
        report_json(&a.output, &report);
    }
    Ok(())
}

pub fn transfer(a: TransferArgs) -> CliResult {
    // each input read once (either may be standard input)
    let br = read_input(&a.to, &ReadOptions::default())?;
    let er = read_input(&a.from, &ReadOptions::default())?;
    if br.dims.len() == 3 {
        return transfer_volume(&a, br, er);
    }
    let (base, _) = tr::to_grid(&br).map_err(|e| Failure::context(a.to.display(), e))?;
    let (example, _) = tr::to_grid(&er).map_err(|e| Failure::context(a.from.display(), e))?;
    let scale = tr::check_compatible(&br, &er, base.w())
        .map_err(|e| Failure::context(a.from.display(), e))?;
    let o = SynthOptions {
        example_scale: scale,
        ..a.m.options()
    };
    let (g, report) = terrain::transfer(&base, &example, &o)?;
    let out = tr::from_grid(&g, &br, br.sample_type())?;
    write_result(&a.output, &out, a.format.as_deref())?;
    if a.m.json {
        report_json(&a.output, &report);
    }
    Ok(())
}
