//! `mra upscale` and `mra downscale` on images, volumes, heightmaps and image sequences
//! (a thin shell over [`crate::upscale`]).

use super::io_cmds::{read_input, write_output_as, RawArgs};
use super::{CliResult, Failure};
use crate::progress::Progress;
use crate::scheme::subdivide::Refinement;
use crate::scheme::{Boundary, Scheme};
use crate::upscale::{self, Clamp, Edge, Method, Mode};
use clap::Args;
use std::path::PathBuf;

/// The raster in and out of `upscale` and `downscale`.
#[derive(Args, Debug, Clone)]
pub struct Files {
    /// Image, volume, heightmap or folder of slices.
    pub input: PathBuf,
    /// Output file (format from its extension; sample type of the input).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub raw: RawArgs,
    /// Format of `-o -` (standard output), as an extension: png, jpg, tif, nrrd, …
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
}

impl Files {
    /// Write `r` to the output (its extension, or `--format` for `-`, picks the format).
    fn write(&self, r: &crate::io::Raster) -> CliResult {
        write_output_as(&self.output, r, false, None, self.format.as_deref())
    }
}

#[derive(Args, Debug, Clone)]
#[command(after_help = "Examples:
  mra generate zone-plate -o zp.png && mra upscale zp.png -o zp4.png --factor 4
  mra upscale zp.png -o zp_smooth.png --factor 2 --scheme cubic --mode control
  mra upscale zp.png -o zp_1000.png --size 1000x700
  mra upscale ../shared/corpus/volumes/ct_pancreas_256.nrrd -o ct_z.nrrd --factor 2 --axes z
  mra upscale ../shared/corpus/terrain/N22W160.hgt -o n22_x2.tif --factor 2
  mra upscale zp.png -o zp_plain.png --factor 2 --clamp off
  mra upscale ct.raw --dims 256x256x64 --dtype u16 -o ct2.nrrd --factor 2 --json
  cat zp.png | mra upscale - -o - --format png --factor 2 > zp2.png
  mra upscale zp.png -o - --format png --factor 2 --json > zp2.png 2> report.json

With -o - the raster alone goes to standard output; --json then prints on standard error.")]
pub struct UpscaleArgs {
    #[command(flatten)]
    pub files: Files,
    /// Integer factor along every chosen axis (2, 4, 8, … or any integer ≥ 2).
    #[arg(long, conflicts_with = "size")]
    pub factor: Option<usize>,
    /// Output size, fastest axis first: WxH for images, WxHxD for volumes.
    #[arg(long)]
    pub size: Option<String>,
    /// box, linear, chaikin (default, best measured), cubic, quartic or four-point.
    #[arg(long, default_value = "chaikin")]
    pub scheme: Refinement,
    /// area (cell means kept; default, best measured), interpolate (through the samples)
    /// or control (plain subdivision, smooth).
    #[arg(long, default_value = "area")]
    pub mode: Mode,
    /// Axes to upscale: letters among x, y, z, t (t = slowest axis as time: frames kept,
    /// new frames in between). Default: every spatial axis.
    #[arg(long)]
    pub axes: Option<String>,
    /// Control points beyond the ends: linear (continue lines) or mirror.
    #[arg(long, default_value = "linear")]
    pub edge: Edge,
    /// Area mode: clamp overshoot to the nearest input cells' range and restore the cell
    /// means; auto (default) blends by a weight learned from the input's coarser level.
    #[arg(long, default_value = "auto")]
    pub clamp: Clamp,
    /// B-spline order overriding the scheme's (1–12; e.g. 6 for quintic).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=12))]
    pub order: Option<u8>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print one JSON object: the compute time (read and write excluded) and the output's
    /// dims (x, y, z); on standard error when `-o -` sends the raster to standard output.
    #[arg(long, alias = "report")]
    pub json: bool,
}

#[derive(Args, Debug, Clone)]
#[command(after_help = "Example:
  mra generate zone-plate -o zp.png && mra downscale zp.png -o zp_quarter.png --levels 2
  mra downscale ct.raw --dims 256x256x64 --dtype u16 -o ct_half.nrrd --json")]
pub struct DownscaleArgs {
    #[command(flatten)]
    pub files: Files,
    /// Levels of REDUCE-RESOLUTION (each about halves every chosen axis).
    #[arg(long, default_value_t = 1)]
    pub levels: usize,
    /// The MRA scheme whose analysis filter A reduces (chaikin-wide, the default, aliases least
    /// and measures best; also haar, chaikin, cubic, linear, cubic-wide, cdf97).
    #[arg(long, default_value = "chaikin-wide")]
    pub scheme: Scheme,
    /// interpolating, periodic or symmetric.
    #[arg(long, default_value = "symmetric")]
    pub boundary: Boundary,
    /// Axes to reduce: letters among x, y, z. Default: every spatial axis.
    #[arg(long)]
    pub axes: Option<String>,
    /// Print one JSON object (output, shape, sample type, spacing, origin, seconds); on
    /// standard error when `-o -` sends the raster to standard output.
    #[arg(long)]
    pub json: bool,
    /// No spinner (it is drawn only on a terminal anyway).
    #[arg(long)]
    pub quiet: bool,
}

fn parse_size(s: &str) -> Result<Vec<usize>, Failure> {
    let v: Option<Vec<usize>> = s
        .split(['x', 'X'])
        .map(|t| t.trim().parse().ok().filter(|&n| n > 0))
        .collect();
    match v {
        Some(mut v) if (2..=3).contains(&v.len()) => {
            v.reverse();
            Ok(v)
        }
        _ => Err(Failure(format!(
            "invalid size: {s} (expected WxH or WxHxD with positive integers)"
        ))),
    }
}

pub fn run_upscale(a: UpscaleArgs) -> CliResult {
    crate::tuning::use_allocator(crate::tuning::Allocator::KeepFreed);
    let r = read_input(&a.files.input, &a.files.raw.options()?)?;
    let nd = r.dims.len();
    let (axes, time) = match &a.axes {
        Some(s) => upscale::parse_axes(s, nd)?,
        None => ((0..nd).collect(), false),
    };
    let size = a.size.as_deref().map(parse_size).transpose()?;
    let plans = upscale::plan_raster(&r.dims, &axes, a.factor, size.as_deref(), time)?;
    let method = Method {
        rule: a.scheme,
        mode: a.mode,
        edge: a.edge,
        order: a.order.map(usize::from),
        clamp: a.clamp,
    };
    // the library checks the memory budget; an output over it is named by its size
    let size: Vec<String> = upscale::output_dims(&r.dims, &plans)
        .iter()
        .rev()
        .map(|d| d.to_string())
        .collect();
    let bar = Progress::new(plans.len() as u64 + 1, "upscale", a.quiet);
    let t = std::time::Instant::now();
    let out = upscale::upscale_raster(r, &method, &plans, &bar).map_err(|e| match e.kind() {
        crate::ErrorKind::LimitsExceeded => Failure(format!(
            "{}: output {}: {e} (MRA_MAX_BYTES raises the budget)",
            a.files.input.display(),
            size.join("x")
        )),
        _ => Failure::context(a.files.input.display(), e),
    })?;
    let seconds = t.elapsed().as_secs_f64();
    bar.finish();
    a.files.write(&out)?;
    if a.json {
        let v = serde_json::json!({
            "compute_seconds": seconds,
            "axis_order": super::io_cmds::AXIS_ORDER,
            "dims": super::io_cmds::xyz(&out.dims),
            "spacing": out.meta.spacing.as_deref().map(super::io_cmds::xyz),
            "origin": out.meta.origin,
        });
        super::io_cmds::report(&a.files.output, &v.to_string())?;
    }
    Ok(())
}

pub fn run_downscale(a: DownscaleArgs) -> CliResult {
    let r = read_input(&a.files.input, &a.files.raw.options()?)?;
    let nd = r.dims.len();
    let axes = match &a.axes {
        Some(s) => upscale::parse_axes(s, nd)?.0,
        None => (0..nd).collect(),
    };
    let t = std::time::Instant::now();
    let out = upscale::downscale_raster(r, a.scheme, a.boundary, a.levels, &axes)
        .map_err(|e| Failure::context(a.files.input.display(), e))?;
    let seconds = t.elapsed().as_secs_f64();
    a.files.write(&out)?;
    if a.json {
        let v = super::io_cmds::raster_report(&a.files.input, &a.files.output, &out, seconds);
        super::io_cmds::report(&a.files.output, &v.to_string())?;
    }
    Ok(())
}
