//! `mra info-file`, `mra convert`, `mra compare`, `mra generate`: data in and out.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};

use super::{CliResult, Failure};
use crate::io::{self, RawSpec, ReadOptions, SampleType};
use crate::metrics::{self, CompareOptions, Convention};
use crate::progress::Progress;

/// Layout of headerless input (`.raw`, and non-square `.r16` / `.r32`).
#[derive(Args, Debug, Clone, Default)]
pub struct RawArgs {
    /// Dimensions of headerless input, fastest first: WxH or WxHxD.
    #[arg(long, value_name = "WxH[xD]")]
    pub dims: Option<String>,
    /// Sample type of headerless input: u8, i8, u16, i16, u32, i32, f16, f32, f64.
    #[arg(long, value_name = "TYPE")]
    pub dtype: Option<String>,
    /// Byte order of headerless input.
    #[arg(long, value_enum, default_value_t = Endian::Little)]
    pub endian: Endian,
    /// Accept a DICOM series with missing or repeated slice positions (step = mean).
    #[arg(long)]
    pub allow_uneven_slices: bool,
}

#[derive(ValueEnum, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Endian {
    #[default]
    Little,
    Big,
}

impl RawArgs {
    /// The read options these flags describe.
    pub fn options(&self) -> Result<ReadOptions, Failure> {
        let Some(dims) = &self.dims else {
            if self.dtype.is_some() {
                return Err(Failure("--dtype needs --dims WxH[xD]".into()));
            }
            return Ok(ReadOptions {
                uneven_slices: self.allow_uneven_slices,
                ..Default::default()
            });
        };
        let mut d: Vec<usize> = dims
            .split(['x', 'X'])
            .map(|t| t.trim().parse::<usize>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                Failure(format!(
                    "invalid --dims: {dims} (expected WxH or WxHxD, e.g. 256x256x64)"
                ))
            })?;
        if d.is_empty() || d.contains(&0) {
            return Err(Failure(format!(
                "invalid --dims: {dims} (expected positive sizes)"
            )));
        }
        d.reverse();
        let ty = match &self.dtype {
            Some(t) => SampleType::parse(t)?,
            None => SampleType::U8,
        };
        Ok(ReadOptions {
            raw: Some(RawSpec {
                dims: d,
                sample_type: ty,
                big_endian: self.endian == Endian::Big,
            }),
            uneven_slices: self.allow_uneven_slices,
        })
    }
}

/// Print `text` on standard output; a closed pipe (`mra info-file x | head -1`) is not
/// an error.
pub fn emit(text: &str) -> CliResult {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|_| stdout.flush())
    {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Failure(format!("standard output: {e}")))
        }
        _ => Ok(()),
    }
}

/// Read a file, naming it in any error.
pub fn read_input(path: &Path, opts: &ReadOptions) -> Result<io::Raster, Failure> {
    io::read_with(path, opts).map_err(|e| Failure::context(path.display(), e))
}

/// Write a file atomically, naming it in any error.
pub fn write_output(path: &Path, r: &io::Raster, compress: bool) -> Result<(), Failure> {
    io::write_with(path, r, &io::WriteOptions { compress })
        .map_err(|e| Failure::context(path.display(), e))
}

/// Print what a file holds: format, shape, sample type, range, metadata.
///
/// Example: `mra info-file ../shared/corpus/terrain/N44W072.hgt --json`
#[derive(Args, Debug)]
#[command(after_help = "Example:\n  mra info-file ../shared/corpus/terrain/N44W072.hgt --json")]
pub struct InfoFileArgs {
    /// Input file or folder (DICOM series, folder of slices).
    pub input: PathBuf,
    #[command(flatten)]
    pub raw: RawArgs,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

pub fn info_file(a: InfoFileArgs) -> CliResult {
    let opts = a.raw.options()?;
    let format =
        io::Format::detect(&a.input).map_err(|e| Failure::context(a.input.display(), e))?;
    let r = read_input(&a.input, &opts)?;
    let (lo, hi) = r.samples.min_max().unwrap_or((f64::NAN, f64::NAN));
    let nodata_count = r.meta.nodata.map(|nd| {
        (0..r.samples.len())
            .filter(|&i| r.samples.get_f64(i) == nd)
            .count()
    });
    let mut out = String::new();
    if a.json {
        let v = serde_json::json!({
            "file": a.input.display().to_string(),
            "format": format.name(),
            "dims": r.dims,
            "channels": r.channels,
            "dtype": r.sample_type().name(),
            "kind": format!("{:?}", r.kind).to_lowercase(),
            "min": lo,
            "max": hi,
            "spacing": r.meta.spacing,
            "origin": r.meta.origin,
            "units": r.meta.units,
            "nodata": r.meta.nodata,
            "nodata_count": nodata_count,
            "geotiff_tags": r.meta.geotiff.iter().map(|g| g.tag).collect::<Vec<_>>(),
            "extra": r.meta.extra,
        });
        let _ = writeln!(out, "{v}");
    } else {
        let _ = writeln!(
            out,
            "{}: {} {}",
            a.input.display(),
            format.name(),
            r.summary()
        );
        let _ = writeln!(
            out,
            "  dims (slowest first) {:?}, range {lo} … {hi}",
            r.dims
        );
        if let Some(s) = &r.meta.spacing {
            let _ = writeln!(
                out,
                "  spacing {:?} {}",
                s,
                r.meta.units.clone().unwrap_or_default()
            );
        }
        if let Some(o) = &r.meta.origin {
            let _ = writeln!(out, "  origin {o:?}");
        }
        if let (Some(nd), Some(c)) = (r.meta.nodata, nodata_count) {
            let _ = writeln!(out, "  nodata {nd}: {c} samples");
        }
        if !r.meta.geotiff.is_empty() {
            let tags: Vec<String> = r.meta.geotiff.iter().map(|g| g.tag.to_string()).collect();
            let _ = writeln!(out, "  GeoTIFF tags {}", tags.join(" "));
        }
        for (k, v) in &r.meta.extra {
            let _ = writeln!(out, "  {k} = {v}");
        }
    }
    emit(&out)
}

/// Convert between formats, keeping samples exact (or converting with --dtype-out).
#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  mra convert ../shared/corpus/terrain/N44W072.hgt -o n44.tif\n  mra convert ct.raw --dims 256x256x64 --dtype u16 -o ct.nrrd --compress"
)]
pub struct ConvertArgs {
    /// Input file or folder.
    pub input: PathBuf,
    /// Output file; the extension picks the format.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub raw: RawArgs,
    /// Convert samples to this type (rounded and clamped for integer types).
    #[arg(long, value_name = "TYPE")]
    pub dtype_out: Option<String>,
    /// Compress where the format offers a choice (NRRD gzip, TIFF Deflate).
    #[arg(long)]
    pub compress: bool,
    /// No progress bar (it is drawn only on a terminal anyway).
    #[arg(long)]
    pub quiet: bool,
}

pub fn convert(a: ConvertArgs) -> CliResult {
    let opts = a.raw.options()?;
    let bar = Progress::new(2, "convert", a.quiet);
    let mut r = read_input(&a.input, &opts)?;
    bar.inc(1);
    if let Some(t) = &a.dtype_out {
        let ty = SampleType::parse(t)?;
        r.samples = io::Samples::from_f64(&r.to_f64(), ty);
    }
    write_output(&a.output, &r, a.compress)?;
    bar.finish();
    Ok(())
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConventionArg {
    Skimage,
    Oiio,
}

/// Compare two images, volumes or heightmaps of the same shape: MSE, PSNR, max abs
/// error, SSIM.
#[derive(Args, Debug)]
#[command(
    after_help = "Conventions:\n  skimage  PSNR = 10 log10(R² / MSE), R = --data-range or scikit-image's default by dtype\n  oiio     PSNR = 20 log10(1 / RMS) on values normalised like OpenImageIO (u8 /255, u16 /65535, floats as is)\n\nExample:\n  mra generate zone-plate -o a.png --size 256 && mra generate noise -o n.png --size 256\n  mra compare a.png n.png --json"
)]
pub struct CompareArgs {
    /// Reference (its sample type sets the default data range).
    pub a: PathBuf,
    /// Test data.
    pub b: PathBuf,
    #[command(flatten)]
    pub raw: RawArgs,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Peak-to-peak data range R for PSNR and SSIM (skimage convention).
    #[arg(long)]
    pub data_range: Option<f64>,
    /// Which library's PSNR definition to follow.
    #[arg(long, value_enum, default_value_t = ConventionArg::Skimage)]
    pub convention: ConventionArg,
    /// No progress bar (it is drawn only on a terminal anyway).
    #[arg(long)]
    pub quiet: bool,
}

pub fn compare(a: CompareArgs) -> CliResult {
    let opts = a.raw.options()?;
    let bar = Progress::new(3, "compare", a.quiet);
    let ra = read_input(&a.a, &opts)?;
    bar.inc(1);
    let rb = read_input(&a.b, &opts)?;
    bar.inc(1);
    let options = CompareOptions {
        data_range: a.data_range,
        convention: match a.convention {
            ConventionArg::Skimage => Convention::Skimage,
            ConventionArg::Oiio => Convention::Oiio,
        },
    };
    let m = metrics::compare(&ra, &rb, &options)?;
    bar.finish();
    let mut out = String::new();
    if a.json {
        let _ = writeln!(
            out,
            "{}",
            serde_json::to_string(&m).map_err(|e| Failure(e.to_string()))?
        );
    } else {
        let psnr = m
            .psnr
            .map(|p| format!("{p:.4} dB"))
            .unwrap_or_else(|| "inf (identical)".into());
        let _ = writeln!(out, "convention  {}", m.convention);
        let _ = writeln!(out, "data range  {}", m.data_range);
        let _ = writeln!(out, "MSE         {}", m.mse);
        let _ = writeln!(out, "PSNR        {psnr}");
        let _ = writeln!(out, "max |a-b|   {}", m.max_abs_error);
        match m.ssim {
            Some(s) => out += &format!("SSIM        {s:.6}\n"),
            None => out += "SSIM        n/a (a side shorter than 7)\n",
        }
    }
    emit(&out)
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum KindArg {
    ZonePlate,
    Gradient,
    Edges,
    Strokes,
    Noise,
    Phantom,
    Terrain,
}

impl KindArg {
    fn kind(self) -> crate::generate::Kind {
        use crate::generate::Kind;
        match self {
            KindArg::ZonePlate => Kind::ZonePlate,
            KindArg::Gradient => Kind::Gradient,
            KindArg::Edges => Kind::Edges,
            KindArg::Strokes => Kind::Strokes,
            KindArg::Noise => Kind::Noise,
            KindArg::Phantom => Kind::Phantom,
            KindArg::Terrain => Kind::Terrain,
        }
    }
}

/// Generate deterministic test data: images, a CT phantom, fractal terrain.
#[derive(Args, Debug)]
#[command(
    after_help = "Defaults: images 256x256 u8, phantom 64x64x64 u16, terrain 257x257 u16.\n\nExample:\n  mra generate zone-plate -o zone.png --size 256\n  mra generate phantom -o phantom.nrrd --size 64 --compress\n  mra generate terrain -o terrain.tif --size 257 --seed 7 --dtype f32"
)]
pub struct GenerateArgs {
    /// What to generate.
    #[arg(value_enum)]
    pub kind: KindArg,
    /// Output file; the extension picks the format.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Size: N (square / cube) or WxH / WxHxD.
    #[arg(long)]
    pub size: Option<String>,
    /// Random seed (strokes, noise, terrain).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stored sample type (u8, u16, i16, f32, …).
    #[arg(long, value_name = "TYPE")]
    pub dtype: Option<String>,
    /// Channels (gradient and noise; others are gray).
    #[arg(long)]
    pub channels: Option<usize>,
    /// Compress where the format offers a choice (NRRD gzip, TIFF Deflate).
    #[arg(long)]
    pub compress: bool,
}

pub fn generate(a: GenerateArgs) -> CliResult {
    let kind = a.kind.kind();
    let ndims = kind.default_dims().len();
    let dims = match &a.size {
        None => kind.default_dims(),
        Some(s) => {
            let mut d: Vec<usize> = s
                .split(['x', 'X'])
                .map(|t| t.trim().parse::<usize>())
                .collect::<Result<_, _>>()
                .map_err(|_| Failure(format!("invalid --size: {s} (expected N or WxH[xD])")))?;
            if d.len() == 1 {
                d = vec![d[0]; ndims];
            }
            d.reverse();
            d
        }
    };
    let channels = a.channels.unwrap_or(match kind {
        crate::generate::Kind::Gradient => 3,
        _ => 1,
    });
    let ty = match &a.dtype {
        Some(t) => SampleType::parse(t)?,
        None => kind.default_type(),
    };
    let field = crate::generate::generate(kind, &dims, channels, a.seed)?;
    let r = field.to_raster(ty)?;
    write_output(&a.output, &r, a.compress)
}
