//! `mra info-file`, `mra convert`, `mra compare`, `mra generate`: data in and out.

use std::fmt::Write as _;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};

use super::{stdio, CliResult, Failure};
use crate::fsutil::Watch;
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

use super::stdio::StdTemp;
pub use super::stdio::{is_std, stdin_bytes, write_stdout};

/// The raster in `bytes` read from standard input: its format recognised by its
/// signature, or raw with `--dims`.
pub fn read_std_bytes(bytes: Vec<u8>, opts: &ReadOptions) -> Result<io::Raster, Failure> {
    let t = StdTemp::new()?;
    let f = t.join(if opts.raw.is_some() {
        "stdin.raw"
    } else {
        "stdin"
    });
    std::fs::write(&f, &bytes).map_err(|e| Failure::context(f.display(), e))?;
    drop(bytes);
    io::read_with(&f, opts).map_err(|e| Failure::context("standard input", e))
}

/// Read a file (`-`: standard input, its format recognised by its signature, or raw
/// with `--dims`), naming it in any error.
pub fn read_input(path: &Path, opts: &ReadOptions) -> Result<io::Raster, Failure> {
    if is_std(path) {
        return read_std_bytes(stdin_bytes()?, opts);
    }
    io::read_with(path, opts).map_err(|e| Failure::context(path.display(), e))
}

/// Print a command's `--json` report: on standard output, or on standard error when the
/// command's output `-o -` already sends data to standard output (the two never mix).
pub fn report(output: &Path, line: &str) -> CliResult {
    if is_std(output) {
        eprintln!("{line}");
        return Ok(());
    }
    emit(&format!("{line}\n"))
}

/// The `--json` report of a command that writes one raster (`convert`, `downscale`):
/// input, output, shape (x, y, z order), sample type, spacing, origin and the seconds
/// of the command's work.
pub fn raster_report(
    input: &Path,
    output: &Path,
    r: &io::Raster,
    seconds: f64,
) -> serde_json::Value {
    serde_json::json!({
        "input": input.display().to_string(),
        "output": output.display().to_string(),
        "axis_order": AXIS_ORDER,
        "dims": xyz(&r.dims),
        "channels": r.channels,
        "dtype": r.sample_type().name(),
        "spacing": r.meta.spacing.as_deref().map(xyz),
        "origin": r.meta.origin,
        "seconds": seconds,
    })
}

/// [`write_output_q`], `-` writing to standard output in `format` (an extension: png,
/// jpg, tif, pgm, ppm, exr, nrrd, nii, hgt, asc, r16, r32, raw).
pub fn write_output_as(
    path: &Path,
    r: &io::Raster,
    compress: bool,
    quality: Option<u8>,
    format: Option<&str>,
) -> Result<(), Failure> {
    if !is_std(path) {
        return write_output_q(path, r, compress, quality);
    }
    let Some(ext) = format else {
        return Err(Failure(
            "standard output: -o - needs --format (png, jpg, tif, pgm, exr, nrrd, nii, asc, …)"
                .into(),
        ));
    };
    let t = StdTemp::new()?;
    let f = t.join(&format!("stdout.{}", ext.trim_start_matches('.')));
    if io::Format::from_extension(&f).is_none() {
        return Err(Failure(format!(
            "invalid --format: {ext} (expected png, jpg, tif, pgm, ppm, pam, exr, nrrd, nii, hgt, asc, r16, r32 or raw)"
        )));
    }
    write_output_q(&f, r, compress, quality)
        .map_err(|e| Failure(e.0.replace(&f.display().to_string(), "standard output")))?;
    let bytes = std::fs::read(&f).map_err(|e| Failure::context(f.display(), e))?;
    write_stdout(&bytes)
}

/// The name whose extension says what `path` is written as: `path`, or for `-` (standard
/// output) `stdout.FORMAT`.
pub fn format_name(path: &Path, format: Option<&str>) -> PathBuf {
    match format {
        Some(f) if stdio::is_std(path) => {
            PathBuf::from(format!("stdout.{}", f.trim_start_matches('.')))
        }
        _ => path.to_path_buf(),
    }
}

/// Write a raster result to `path`, or to standard output for `-` in `format`.
pub fn write_result(path: &Path, r: &io::Raster, format: Option<&str>) -> CliResult {
    write_output_as(path, r, false, None, format)
}

/// A report as one JSON line ([`json_line`]), on standard error when the data goes to standard output (`-o -`).
pub fn report_json(output: &Path, v: &impl serde::Serialize) {
    if stdio::is_std(output) {
        eprintln!("{}", json_line(v));
    } else {
        println!("{}", json_line(v));
    }
}

/// A report as one JSON object in the axis order of every other command: `dims`
/// and `coarse` fastest axis first (x, y, z; the reports hold them slowest first), and
/// `axis_order` saying so.
pub fn json_line(v: &impl serde::Serialize) -> String {
    let mut j = serde_json::to_value(v).unwrap_or_default();
    if let Some(o) = j.as_object_mut() {
        for key in ["dims", "coarse"] {
            if let Some(serde_json::Value::Array(a)) = o.get_mut(key) {
                a.reverse();
            }
        }
        if o.contains_key("dims") {
            o.insert(
                "axis_order".into(),
                serde_json::Value::from("x, y, z (fastest first)"),
            );
        }
    }
    j.to_string()
}

/// Write a file atomically, naming it in any error.
pub fn write_output(path: &Path, r: &io::Raster, compress: bool) -> Result<(), Failure> {
    io::write_with(path, r, &io::WriteOptions { compress })
        .map_err(|e| Failure::context(path.display(), e))
}

/// `fill` written to `output` through [`crate::fsutil::write_atomic`] (a command that
/// reads its input while it writes); a failure names `output` when writing it failed (a
/// full disk, a file-size limit, an output that cannot be created), else `input`.
pub fn write_streamed<F>(output: &Path, input: &str, fill: F) -> CliResult
where
    F: FnOnce(&mut Watch<&mut BufWriter<File>>) -> crate::Result<()>,
{
    // true unless `fill` fails with its writes intact (the input's fault)
    let mut output_failed = true;
    crate::fsutil::write_atomic(output, |w| {
        let mut w = Watch::new(w);
        let r = fill(&mut w);
        output_failed = r.is_ok() || w.failed();
        r
    })
    .map_err(|e: crate::Error| {
        if output_failed {
            Failure::context(output.display(), e)
        } else {
            Failure::context(input, e)
        }
    })
}

/// [`write_output`], a `.jpg` / `.jpeg` at JPEG `quality` (1–100) when given.
pub fn write_output_q(
    path: &Path,
    r: &io::Raster,
    compress: bool,
    quality: Option<u8>,
) -> Result<(), Failure> {
    match (quality, io::Format::from_extension(path)) {
        (Some(q), Some(io::Format::Jpeg)) => {
            crate::fsutil::write_atomic(path, |w| io::jpeg::write(w, r, q))
                .map_err(|e| Failure::context(path.display(), e))
        }
        _ => write_output(path, r, compress),
    }
}

/// Every vector `mra` prints (dims, spacing, origin, directions, sizes) lists the axes
/// fastest first: x, y, z (then t), as NRRD and NIfTI headers do.
pub const AXIS_ORDER: &str = "x, y, z (fastest first)";

/// A per-axis vector of the array order (slowest first) in the printed order (x, y, z).
pub fn xyz<T: Clone>(v: &[T]) -> Vec<T> {
    v.iter().rev().cloned().collect()
}

/// Print what a file holds: for an `.mra` file its header and bytes per level, for any
/// other file mra reads its format, shape, sample type, range and metadata.
#[derive(Args, Debug)]
#[command(
    after_help = "Vectors (dims, spacing, origin, directions) are printed x, y, z: fastest axis first.

Examples:
  mra info ../shared/corpus/terrain/N44W072.hgt --json
  mra info ../shared/corpus/volumes/ct_pancreas_256.nrrd
  mra info ct.raw --dims 256x256x64 --dtype u16
  mra generate zone-plate -o z.png && mra encode z.png -o z.mra && mra info z.mra --json"
)]
pub struct InfoFileArgs {
    /// Input file or folder (any format mra reads, an `.mra` file, a DICOM series, a folder
    /// of slices).
    pub input: PathBuf,
    #[command(flatten)]
    pub raw: RawArgs,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Whether `path` starts with the `.mra` signature.
pub fn is_mra(path: &Path) -> bool {
    use std::io::Read as _;
    let mut head = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && head == crate::format::SIGNATURE
}

/// `mra info` of any file mra reads but `.mra` files; `stdin`: the bytes of standard
/// input when the caller has read them already (to tell an `.mra` stream apart).
pub fn info_file(a: InfoFileArgs, stdin: Option<Vec<u8>>) -> CliResult {
    let opts = a.raw.options()?;
    if !is_std(&a.input) && opts.raw.is_none() {
        let format =
            io::Format::detect(&a.input).map_err(|e| Failure::context(a.input.display(), e))?;
        if format == io::Format::Jpeg {
            return info_jpeg(&a);
        }
    }
    let r = if is_std(&a.input) {
        let bytes = match stdin {
            Some(b) => b,
            None => stdin_bytes()?,
        };
        read_std_bytes(bytes, &opts)?
    } else {
        read_input(&a.input, &opts)?
    };
    let format = if is_std(&a.input) {
        "standard input"
    } else {
        io::Format::detect(&a.input)
            .map_err(|e| Failure::context(a.input.display(), e))?
            .name()
    };
    let (lo, hi) = data_range(&r);
    let nodata_count = r.meta.nodata.map(|nd| {
        (0..r.samples.len())
            .filter(|&i| r.samples.get_f64(i) == nd)
            .count()
    });
    let mut out = String::new();
    if a.json {
        let v = serde_json::json!({
            "file": a.input.display().to_string(),
            "format": format,
            "axis_order": AXIS_ORDER,
            "dims": xyz(&r.dims),
            "channels": r.channels,
            "dtype": r.sample_type().name(),
            "kind": format!("{:?}", r.kind).to_lowercase(),
            "min": lo,
            "max": hi,
            "spacing": r.meta.spacing.as_deref().map(xyz),
            "origin": r.meta.origin,
            "directions": r.meta.directions,
            "units": r.meta.units,
            "nodata": r.meta.nodata,
            "nodata_count": nodata_count,
            "geotiff_tags": r.meta.geotiff.iter().map(|g| g.tag).collect::<Vec<_>>(),
            "extra": r.meta.extra,
        });
        let _ = writeln!(out, "{v}");
    } else {
        let _ = writeln!(out, "{}: {} {}", a.input.display(), format, r.summary());
        let _ = writeln!(
            out,
            "  dims (x, y, z) {:?}, range {lo} … {hi}{}",
            xyz(&r.dims),
            if r.meta.nodata.is_some() {
                " (nodata excluded)"
            } else {
                ""
            }
        );
        if let Some(s) = &r.meta.spacing {
            let _ = writeln!(
                out,
                "  spacing (x, y, z) {:?} {}",
                xyz(s),
                r.meta.units.clone().unwrap_or_default()
            );
        }
        if let Some(o) = &r.meta.origin {
            let _ = writeln!(out, "  origin (x, y, z) {o:?}");
        }
        if let Some(d) = &r.meta.directions {
            let _ = writeln!(out, "  directions (of x, y, z) {d:?}");
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

/// The smallest and largest sample of `r` that is data: the nodata value (−32768 of an
/// SRTM void, −9999 of an ESRI grid) is not a height; NaN when no sample is data.
fn data_range(r: &io::Raster) -> (f64, f64) {
    let Some(nd) = r.meta.nodata else {
        return r.samples.min_max().unwrap_or((f64::NAN, f64::NAN));
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..r.samples.len() {
        let v = r.samples.get_f64(i);
        if v != nd && !v.is_nan() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if lo > hi {
        (f64::NAN, f64::NAN)
    } else {
        (lo, hi)
    }
}

/// `mra info` of a JPEG: its frame header only (size, channels; 8-bit samples), checked
/// against the file's length and the memory budget; the pixels are not decoded, so the
/// range is not shown.
fn info_jpeg(a: &InfoFileArgs) -> CliResult {
    let h = io::jpeg::read_header(&a.input).map_err(|e| Failure::context(a.input.display(), e))?;
    let dims = [h.width as usize, h.height as usize];
    let out = if a.json {
        let v = serde_json::json!({
            "file": a.input.display().to_string(),
            "format": io::Format::Jpeg.name(),
            "axis_order": AXIS_ORDER,
            "dims": dims,
            "channels": h.channels,
            "dtype": SampleType::U8.name(),
            "kind": "image",
            "header_only": true,
            "min": null,
            "max": null,
        });
        format!("{v}\n")
    } else {
        format!(
            "{}: {} {}x{} {} u8 image\n  dims (x, y, z) {dims:?}, range not read (header only)\n",
            a.input.display(),
            io::Format::Jpeg.name(),
            h.width,
            h.height,
            match h.channels {
                1 => "gray".to_string(),
                3 => "RGB".to_string(),
                c => format!("{c}-channel"),
            },
        )
    };
    emit(&out)
}

/// Convert between formats, keeping samples exact (or converting with --dtype-out).
#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  mra convert ../shared/corpus/terrain/N44W072.hgt -o n44.tif\n  mra convert ct.raw --dims 256x256x64 --dtype u16 -o ct.nrrd --compress\n  mra convert photo.png -o photo.jpg --quality 85\n  cat scan.png | mra convert - -o - --format tif > scan.tif
  mra convert scan.png -o scan.tif --json"
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
    /// Format of `-o -` (standard output), as an extension: png, jpg, tif, pgm, nrrd, …
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// JPEG quality of a `.jpg` output, 1–100.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=100), default_value_t = io::jpeg::DEFAULT_QUALITY)]
    pub quality: u8,
    /// No progress bar (it is drawn only on a terminal anyway).
    #[arg(long)]
    pub quiet: bool,
    /// Print one JSON object (output, shape, sample type, spacing, origin, seconds); on
    /// standard error when `-o -` sends the raster to standard output.
    #[arg(long)]
    pub json: bool,
}

pub fn convert(a: ConvertArgs) -> CliResult {
    let opts = a.raw.options()?;
    let t = std::time::Instant::now();
    let bar = Progress::new(2, "convert", a.quiet);
    let mut r = read_input(&a.input, &opts)?;
    bar.inc(1);
    if let Some(t) = &a.dtype_out {
        let ty = SampleType::parse(t)?;
        r.samples = io::Samples::from_f64(&r.to_f64(), ty);
    }
    write_output_as(
        &a.output,
        &r,
        a.compress,
        Some(a.quality),
        a.format.as_deref(),
    )?;
    bar.finish();
    if a.json {
        let v = raster_report(&a.input, &a.output, &r, t.elapsed().as_secs_f64());
        report(&a.output, &v.to_string())?;
    }
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
        let mut v = serde_json::to_value(&m).map_err(|e| Failure(e.to_string()))?;
        if let Some(d) = v.get_mut("dims").and_then(|d| d.as_array_mut()) {
            d.reverse();
        }
        v["axis_order"] = AXIS_ORDER.into();
        let _ = writeln!(out, "{v}");
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

/// `mra generate`'s kinds are the library's, by their names.
impl ValueEnum for crate::generate::Kind {
    fn value_variants<'a>() -> &'a [Self] {
        &crate::generate::Kind::ALL
    }
    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

#[derive(Args, Debug)]
#[command(
    after_help = "Defaults: images 256x256 u8, phantom 64x64x64 u16, terrain 257x257 u16.\n\nExample:\n  mra generate zone-plate -o zone.png --size 256\n  mra generate phantom -o phantom.nrrd --size 64 --compress\n  mra generate terrain -o terrain.tif --size 257 --seed 7 --dtype f32"
)]
pub struct GenerateArgs {
    /// What to generate.
    #[arg(value_enum)]
    pub kind: crate::generate::Kind,
    /// Output file; the extension picks the format (`-`: standard output, with --format).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output), as an extension: png, tif, nrrd, …
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
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
    let kind = a.kind;
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
    write_output_as(&a.output, &r, a.compress, None, a.format.as_deref())
}
