//! `mra denoise`: thresholded details (§9.7.2) of curves, images, volumes and heightmaps
//! (a thin shell over [`crate::denoise`]).

use std::path::PathBuf;

use clap::Args;

use super::io_cmds::{read_input, report_json, write_result};
use super::{stdio, CliResult, Failure};
use crate::denoise::{self, DenoiseOptions, Mode, Rule};
use crate::io::{self, Raster, ReadOptions, Samples};
use crate::scheme::{Boundary, Scheme};
use crate::tensor::Array;

#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mra denoise noisy.png -o clean.png
  mra denoise ../shared/corpus/volumes/ct_pancreas_256.nrrd --mode hard --levels 3 -o ct.nrrd
  mra denoise stroke.csv --scheme chaikin -o smooth.csv")]
pub struct DenoiseArgs {
    /// An image, volume or heightmap, or a point list (.csv / .txt); `-`: standard input
    /// (a raster told by its signature, else a point list).
    pub input: PathBuf,
    /// Output file; the extension picks the format (a point list for point-list input;
    /// `-`: standard output, with --format for a raster).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output), as an extension: png, tif, exr, nrrd, …
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// Levels (default: 4 for haar; for chaikin/cubic chosen among 1–4 by the smallest
    /// SURE risk; 0 = that choice for any scheme).
    #[arg(long)]
    pub levels: Option<usize>,
    /// Cycle spinning: average over shifts 0..N along every axis (N^d transforms;
    /// default 2; 1 = one decimated transform).
    #[arg(long, default_value_t = 2)]
    pub shifts: usize,
    /// haar (best measured), chaikin or cubic.
    #[arg(long, default_value = "haar")]
    pub scheme: Scheme,
    /// Boundary (default: symmetric for arrays, interpolating for point lists).
    #[arg(long)]
    pub boundary: Option<Boundary>,
    /// A fixed threshold in sample units (default: BayesShrink per band).
    #[arg(long)]
    pub threshold: Option<f64>,
    /// Use the universal threshold σ√(2 ln N) instead of BayesShrink.
    #[arg(long, conflicts_with = "threshold")]
    pub universal: bool,
    /// The noise σ in sample units (default: estimated from the finest band's MAD).
    #[arg(long)]
    pub sigma: Option<f64>,
    /// Thresholding: soft (shrink toward zero) or hard (keep or zero).
    #[arg(long, default_value = "soft")]
    pub mode: Mode,
    /// Print what was done as one JSON object.
    #[arg(long)]
    pub json: bool,
}

pub fn denoise(a: DenoiseArgs) -> CliResult {
    let rule = match (a.threshold, a.universal) {
        (Some(t), _) => Rule::Fixed(t),
        (None, true) => Rule::Universal,
        _ => Rule::Bayes,
    };
    // standard input is read once, then told apart: a raster by its signature, else a
    // point list
    let stdin = if stdio::is_std(&a.input) {
        Some(stdio::stdin_bytes()?)
    } else {
        None
    };
    let is_points = match &stdin {
        Some(b) => io::Format::sniff(b).is_none(),
        None => super::analyze::is_point_list(&a.input),
    };
    let o = DenoiseOptions {
        scheme: a.scheme,
        boundary: a.boundary.unwrap_or(if is_points {
            Boundary::Interpolating
        } else {
            Boundary::Symmetric
        }),
        levels: a
            .levels
            .unwrap_or(if a.scheme == Scheme::Haar { 4 } else { 0 }),
        mode: a.mode,
        rule,
        sigma: a.sigma,
        shifts: a.shifts,
    };
    let report = if is_points {
        let text = match stdin {
            Some(b) => String::from_utf8(b).map_err(|_| {
                Failure("standard input: not a raster mra reads nor a point list".into())
            })?,
            None => std::fs::read_to_string(&a.input)
                .map_err(|e| Failure::context(a.input.display(), e))?,
        };
        let pts =
            crate::points::parse(&text).map_err(|e| Failure::context(a.input.display(), e))?;
        let (n, d) = (pts.len(), pts.dim);
        let mut arr = Array::from_shape_vec(&[n, d], pts.data)?;
        let r = denoise::denoise(&mut arr, &[0], &o)
            .map_err(|e| Failure::context(a.input.display(), e))?;
        let mut text = Vec::new();
        crate::points::write(d, arr.data(), &mut text)
            .map_err(|e| Failure::context(a.output.display(), e))?;
        stdio::write_bytes(&a.output, &text)?;
        r
    } else {
        let r = match stdin {
            Some(b) => super::io_cmds::read_std_bytes(b, &ReadOptions::default())?,
            None => read_input(&a.input, &ReadOptions::default())?,
        };
        let (shape, axes) = io::array::array_shape(&r.dims, r.channels);
        // voids never enter the filter: filled for it, marked again after
        let mut data = r.to_f64();
        let voids = io::nodata::Voids::find(&data, r.meta.nodata);
        if let Some(v) = &voids {
            let mut grid = r.dims.clone();
            grid.push(r.channels);
            v.fill(&mut data, &grid, r.dims.len())
                .map_err(|e| Failure::context(a.input.display(), e))?;
        }
        let mut arr = Array::from_shape_vec(&shape, data)?;
        let rep = denoise::denoise(&mut arr, &axes, &o)
            .map_err(|e| Failure::context(a.input.display(), e))?;
        let mut out_data = arr.into_data();
        if let Some(v) = &voids {
            v.restore(&mut out_data, &v.mask, false);
        }
        let samples = Samples::from_f64(&out_data, r.sample_type());
        if samples == r.samples {
            // a clean input: said, not written silently as if something was removed
            eprintln!(
                "mra: {}: noise σ ≈ {:.3} (a clean input): no sample changed (--sigma sets the noise level)",
                a.input.display(),
                rep.sigma
            );
        }
        let out = Raster { samples, ..r };
        write_result(&a.output, &out, a.format.as_deref())?;
        rep
    };
    if a.json {
        report_json(&a.output, &report);
    }
    Ok(())
}
