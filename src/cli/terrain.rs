//! `mra terrain synth|render|highpass`: thin shells over [`crate::terrain`]. (`transfer`,
//! `denoise` and `curve style` have their own files.)

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};

use super::io_cmds::{format_name, read_input, report_json, write_result};
use super::stdio;
use super::{CliResult, Failure};
use crate::io::{DataKind, Format, Raster, ReadOptions, SampleType, Samples};
use crate::scheme::Scheme;
use crate::terrain::synth::Details;
use crate::terrain::{self, raster as tr, FinestGain, Grid, Shading, SynthOptions};

#[derive(Subcommand, Debug)]
pub enum TerrainCommand {
    /// Synthesize a detailed terrain from a smooth base and a detailed example (§9.7.4).
    Synth(SynthArgs),
    /// Draw a hillshaded relief of a heightmap as a PNG.
    Render(RenderArgs),
    /// Keep only the finest L levels of a heightmap's MRA: F − P^L A^L F (what synthesis adds).
    Highpass(HighpassArgs),
}

#[derive(Args, Debug)]
#[command(after_help = "Example:
  mra generate terrain --size 256x256 --seed 9 -o t.tif
  mra terrain highpass t.tif --levels 2 -o fine.tif")]
pub struct HighpassArgs {
    /// A heightmap or image.
    pub input: PathBuf,
    /// Output heightmap (the fine details); the extension picks the format (`-`:
    /// standard output, with --format).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output), as an extension: png, tif, exr, nrrd, …
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// Levels removed (the coarse part left out).
    #[arg(long, default_value_t = 2)]
    pub levels: usize,
    /// chaikin or cubic (interpolating boundary, as `synth`).
    #[arg(long, default_value = "chaikin")]
    pub scheme: Scheme,
}

/// Options shared by `terrain synth` and `transfer`.
#[derive(Args, Debug, Clone)]
pub struct MatchArgs {
    /// Levels of refinement L (the output is base × 2^L for `synth`).
    #[arg(long, default_value_t = 2)]
    pub levels: usize,
    /// chaikin (quadratic, the notes' choice) or cubic; boundary is interpolating.
    #[arg(long, default_value = "chaikin")]
    pub scheme: Scheme,
    /// Seed: the same seed gives the same output, byte for byte.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Patch core in coarse cells.
    #[arg(long, default_value_t = 8)]
    pub patch: usize,
    /// Overlap of patches on each side (≤ patch/2).
    #[arg(long, default_value_t = 2)]
    pub overlap: usize,
    /// At most this many example windows are compared per level (a grid offset by the
    /// seed; default 16384 for heightmaps and images, 4096 for volumes).
    #[arg(long)]
    pub candidates: Option<usize>,
    /// Pick each patch at random (seeded) among this many best-matching example windows.
    #[arg(long, default_value_t = 2)]
    pub choices: usize,
    /// matched (the method), copy (same place, no matching) or none (subdivision only).
    #[arg(long, default_value = "matched")]
    pub details: Details,
    /// Cap of the relief gain: each patch's details are scaled by the ratio of its coarse
    /// mean slope to its source window's, at most this (flat ground gets no mountain
    /// detail); 0 turns it off.
    #[arg(long, default_value_t = SynthOptions::default().relief_cap)]
    pub relief_cap: f64,
    /// Print what was done as one JSON object.
    #[arg(long)]
    pub json: bool,
}

impl MatchArgs {
    pub(super) fn options(&self) -> SynthOptions {
        SynthOptions {
            levels: self.levels,
            scheme: self.scheme,
            seed: self.seed,
            patch: self.patch,
            overlap: self.overlap,
            choices: self.choices,
            candidates: self
                .candidates
                .unwrap_or(SynthOptions::default().candidates),
            details: self.details,
            relief_cap: self.relief_cap,
            ..SynthOptions::default()
        }
    }
}

#[derive(Args, Debug)]
#[command(after_help = "Example:
  mra generate terrain --size 64x64 --seed 3 -o base.png
  mra generate terrain --size 256x256 --seed 9 -o example.png
  mra terrain synth --base base.png --example example.png --levels 2 --seed 7 -o out.tif --preview out.png
  mra terrain synth --base n22.hgt --example helens_30m.asc --example-cell 0.00027 -o out.tif   # base in degrees, example in metres")]
pub struct SynthArgs {
    /// The smooth or low-resolution heightmap (any format `mra` reads; voids are filled).
    #[arg(long)]
    pub base: PathBuf,
    /// The detailed example heightmap (same height unit).
    #[arg(long)]
    pub example: PathBuf,
    /// Output heightmap; the extension picks the format (`-`: standard output, with
    /// --format).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output), as an extension: png, tif, exr, nrrd, …
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// Output size WxH (default: base × 2^L).
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    /// Also write base, example and result side by side, hillshaded, as a PNG (`-`:
    /// standard output, when -o is a file).
    #[arg(long)]
    pub preview: Option<PathBuf>,
    /// The example's cell size in the base's horizontal unit (e.g. 0.000278 for a 30 m
    /// example under a base in degrees; in base cells when the base has no spacing):
    /// overrides the example's own spacing and unit, which are otherwise checked against
    /// the base's. The example is resampled to the output's cell before matching.
    #[arg(long, value_name = "CELL")]
    pub example_cell: Option<f64>,
    /// Skip the height-unit and cell checks of base against example (the example's
    /// heights and cells are taken as the base's).
    #[arg(long)]
    pub any_units: bool,
    /// Gain of the finest details: `fit` (the result's spectral slope over its finest
    /// octave is made the example's; 0.5 to 2) or a fixed gain (1: the example's band RMS).
    #[arg(long, default_value = "fit", value_name = "fit|G")]
    pub finest_gain: FinestGain,
    /// Trust the base only down to 1/S of the output's resolution and synthesize every
    /// finer level from the example (S: 1, or a power of two from 2^levels to 256).
    #[arg(long, default_value_t = 1, value_name = "S")]
    pub base_scale: usize,
    #[command(flatten)]
    pub m: MatchArgs,
}

#[derive(Args, Debug)]
#[command(after_help = "Example:
  mra terrain render ../shared/corpus/terrain/mt_st_helens_30m_f32.tif -o helens.png --colour")]
pub struct RenderArgs {
    /// A heightmap.
    pub input: PathBuf,
    /// Output PNG (`-`: standard output).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output), as an extension (default png).
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// Sun azimuth in degrees clockwise from north.
    #[arg(long, default_value_t = 315.0)]
    pub azimuth: f64,
    /// Sun altitude in degrees.
    #[arg(long, default_value_t = 45.0)]
    pub altitude: f64,
    /// Vertical exaggeration.
    #[arg(long, default_value_t = 1.0)]
    pub z_factor: f64,
    /// Cell size in height units (default: from the file, else relief = ¼ of the width).
    #[arg(long)]
    pub cell: Option<f64>,
    /// Hypsometric colour ramp by elevation.
    #[arg(long, alias = "color")]
    pub colour: bool,
}

fn parse_size(s: &str) -> Result<(usize, usize), Failure> {
    let v: Vec<usize> = s
        .split(['x', 'X'])
        .map(|t| t.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| Failure(format!("invalid --size: {s} (expected WxH, e.g. 512x512)")))?;
    match v[..] {
        [w, h] if w > 0 && h > 0 => Ok((h, w)),
        _ => Err(Failure(format!(
            "invalid --size: {s} (expected WxH, e.g. 512x512)"
        ))),
    }
}

/// Sample type of a result written to `path`: formats without float samples keep an
/// integer type (PNG/PNM u16 unless the template is u8; .hgt i16), the rest f32.
fn output_type(path: &Path, template: SampleType) -> SampleType {
    match Format::from_extension(path) {
        Some(Format::Png) | Some(Format::Pnm) => {
            if template == SampleType::U8 {
                SampleType::U8
            } else {
                SampleType::U16
            }
        }
        Some(Format::Hgt) => SampleType::I16,
        Some(Format::R16) => SampleType::U16,
        _ => SampleType::F32,
    }
}

fn load_grid(path: &Path) -> Result<(Raster, Grid), Failure> {
    let r = read_input(path, &ReadOptions::default())?;
    let (g, _) = tr::to_grid(&r).map_err(|e| Failure::context(path.display(), e))?;
    Ok((r, g))
}

/// Cell size for shading: from the file, else such that the relief spans ¼ of the width.
fn shading_cell(r: &Raster, g: &Grid, cell: Option<f64>) -> (f64, f64) {
    if let Some(c) = cell {
        return (c, c);
    }
    if r.meta.spacing.is_some() {
        return tr::cell_metres(r);
    }
    let (lo, hi) = g.range();
    let c = ((hi - lo) / (0.25 * g.w().max(g.h()) as f64)).max(f64::MIN_POSITIVE);
    (c, c)
}

fn shade_raster(g: &Grid, s: &Shading) -> Result<Raster, Failure> {
    let ch = if s.colour { 3 } else { 1 };
    let px = terrain::hillshade(g, s);
    Ok(Raster::new(
        vec![g.h(), g.w()],
        ch,
        Samples::U8(px),
        DataKind::Image,
    )?)
}

/// Nearest-neighbour scaling of an 8-bit picture to `h` rows.
fn scale_to(px: &Raster, h: usize) -> (usize, Vec<u8>) {
    let Samples::U8(v) = &px.samples else {
        return (0, Vec::new());
    };
    let (ph, pw, c) = (px.dims[0], px.dims[1], px.channels);
    let w = (pw * h).div_ceil(ph).max(1);
    let mut out = Vec::with_capacity(h * w * c);
    for y in 0..h {
        let sy = (y * ph / h).min(ph - 1);
        for x in 0..w {
            let sx = (x * pw / w).min(pw - 1);
            out.extend_from_slice(&v[(sy * pw + sx) * c..(sy * pw + sx + 1) * c]);
        }
    }
    (w, out)
}

/// Base, example and result hillshaded, side by side at the result's height, all lit
/// with the result's cell size (the base's scaled by the change of lattice), so that
/// the three share one vertical scale; each panel labelled above it.
fn preview(base: &Grid, example: &Grid, out_r: &Raster, out: &Grid) -> Result<Raster, Failure> {
    let h = out.h().max(example.h());
    let gap = 8;
    let (cy, cx) = shading_cell(out_r, out, None);
    let fy = (out.h().max(2) - 1) as f64 / (base.h().max(2) - 1) as f64;
    let fx = (out.w().max(2) - 1) as f64 / (base.w().max(2) - 1) as f64;
    let parts = [
        (base, (cy * fy, cx * fx)),
        (example, (cy, cx)),
        (out, (cy, cx)),
    ];
    let pics: Vec<(usize, Vec<u8>)> = parts
        .iter()
        .map(|(g, cell)| {
            let s = Shading {
                cell: *cell,
                ..Shading::default()
            };
            shade_raster(g, &s).map(|p| scale_to(&p, h))
        })
        .collect::<Result<_, _>>()?;
    let w: usize = pics.iter().map(|p| p.0).sum::<usize>() + gap * (pics.len() - 1);
    // a white strip above the panels for their labels
    let scale = if h >= 256 { 2 } else { 1 };
    let top = super::label::height(scale) + 2 * scale + 2;
    let mut img = vec![255u8; (top + h) * w];
    let mut x0 = 0;
    for ((pw, px), name) in pics.iter().zip(["BASE", "EXAMPLE", "RESULT"]) {
        super::label::draw(&mut img, w, x0 + 2, scale + 1, name, scale);
        for y in 0..h {
            let row = (top + y) * w + x0;
            img[row..row + pw].copy_from_slice(&px[y * pw..(y + 1) * pw]);
        }
        x0 += pw + gap;
    }
    Ok(Raster::new(
        vec![top + h, w],
        1,
        Samples::U8(img),
        DataKind::Image,
    )?)
}

pub fn run(c: TerrainCommand) -> CliResult {
    match c {
        TerrainCommand::Synth(a) => synth(a),
        TerrainCommand::Render(a) => render(a),
        TerrainCommand::Highpass(a) => highpass(a),
    }
}

fn highpass(a: HighpassArgs) -> CliResult {
    let (r, g) = load_grid(&a.input)?;
    let h = terrain::highpass(&g, a.scheme, a.levels)
        .map_err(|e| Failure::context(a.input.display(), e))?;
    let out = tr::from_grid(&h, &r, SampleType::F32)?;
    write_result(&a.output, &out, a.format.as_deref())
}

fn synth(a: SynthArgs) -> CliResult {
    if stdio::is_std(&a.output) && a.preview.as_deref().is_some_and(stdio::is_std) {
        return Err(Failure(
            "standard output: both -o and --preview are - (expected a file for one of them)".into(),
        ));
    }
    let (br, base) = load_grid(&a.base)?;
    let (mut er, example) = load_grid(&a.example)?;
    if let Some(c) = a.example_cell {
        if !(c.is_finite() && c > 0.0) {
            return Err(Failure(format!(
                "invalid --example-cell: {c} (expected a positive cell size)"
            )));
        }
        er.meta.spacing = Some(vec![c; er.dims.len()]);
        er.meta.units = br.meta.units.clone();
    }
    let mut o = a.m.options();
    o.finest_gain = a.finest_gain;
    o.base_scale = a.base_scale;
    if let Some(s) = &a.size {
        o.size = Some(parse_size(s)?);
    }
    let out_w = o
        .size
        .map(|s| s.1)
        .unwrap_or(base.w().saturating_mul(1 << o.levels.min(16)));
    // the example's cell ÷ the output's: from --example-cell (in the base's unit, or in
    // base cells when the base has no spacing), else from both files' spacing
    let base_cell = br
        .meta
        .spacing
        .as_ref()
        .and_then(|s| s.last().copied())
        .unwrap_or(1.0);
    let out_cell = base_cell * base.w() as f64 / out_w.max(1) as f64;
    o.example_scale = if a.any_units || br.meta.spacing.is_none() {
        a.example_cell.map_or(1.0, |c| c / out_cell)
    } else {
        tr::check_compatible(&br, &er, out_w).map_err(|e| {
            Failure(format!(
                "{}: {e}; give --example-cell (the example's cell in the base's unit) \
                 or --any-units to skip the check",
                a.example.display()
            ))
        })?
    };
    drop(er);
    let (g, report) = terrain::synthesize(&base, &example, &o)?;
    let fmt = a.format.as_deref();
    let out = tr::from_grid(
        &g,
        &br,
        output_type(&format_name(&a.output, fmt), br.sample_type()),
    )?;
    write_result(&a.output, &out, fmt)?;
    if let Some(p) = &a.preview {
        let pic = preview(&base, &example, &out, &g)?;
        write_result(p, &pic, Some("png"))?;
    }
    if a.m.json {
        report_json(&a.output, &report);
    } else {
        eprintln!(
            "{}: {}x{} from base {}x{} (coarse lattice {}x{}), {} levels, seam ratio {:.3}",
            a.output.display(),
            g.w(),
            g.h(),
            base.w(),
            base.h(),
            report.coarse[1],
            report.coarse[0],
            report.levels,
            report.seam_ratio
        );
    }
    Ok(())
}

fn render(a: RenderArgs) -> CliResult {
    let (r, g) = load_grid(&a.input)?;
    let s = Shading {
        azimuth: a.azimuth,
        altitude: a.altitude,
        z_factor: a.z_factor,
        cell: shading_cell(&r, &g, a.cell),
        colour: a.colour,
    };
    s.validate()?;
    write_result(
        &a.output,
        &shade_raster(&g, &s)?,
        Some(a.format.as_deref().unwrap_or("png")),
    )
}
