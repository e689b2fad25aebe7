//! `mra analyze` and `mra synthesize`: point lists go to [`super::points`], images,
//! volumes and heightmaps to [`super::array`].

use super::array::{analyze_path, synthesize_path, AnalyzeOptions, DEFAULT_LEVELS};
use super::{CliResult, Failure};
use crate::io::ReadOptions;
use crate::scheme::{Boundary, Scheme};
use crate::tensor::{Order, PyramidSpec};
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args, Debug, Clone)]
#[command(after_help = "Examples:
  mra analyze --scheme chaikin --boundary interpolating --levels 3 corpus/curves/zigzag.csv > pyr.txt
  mra synthesize --scheme chaikin --boundary interpolating pyr.txt
  printf '5\\n7\\n10\\n14\\n13\\n13\\n8\\n6\\n' | mra analyze --scheme haar --levels 2 -")]
pub struct AnalyzeArgs {
    /// A point list (CSV, one point per line; `-` for standard input), or an image, volume or heightmap.
    pub input: PathBuf,
    /// Where to write (standard output for point lists when absent; `-`: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Format of `-o -` for an array's pyramid: tif (2-D), nrrd (3-D); png with --visual.
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// haar, chaikin or cubic.
    #[arg(long, default_value = "chaikin")]
    pub scheme: Scheme,
    /// interpolating, periodic or symmetric.
    #[arg(long, default_value = "interpolating")]
    pub boundary: Boundary,
    /// Levels (default: as many as the length allows for point lists, 3 for arrays).
    #[arg(long)]
    pub levels: Option<usize>,
    /// standard or non-standard (Mallat) order, for arrays.
    #[arg(long, default_value = "non-standard")]
    pub order: Order,
    /// Write an 8-bit PNG picture of the pyramid instead of the coefficients (arrays).
    #[arg(long)]
    pub visual: bool,
    /// The slice to picture for volumes (`--visual`).
    #[arg(long)]
    pub slice: Option<usize>,
}

#[derive(Args, Debug, Clone)]
#[command(after_help = "Examples:
  mra synthesize --scheme chaikin --boundary interpolating pyr.txt -o curve.csv
  mra synthesize pyramid.tiff -o restored.png")]
pub struct SynthesizeArgs {
    /// A tagged point list written by `mra analyze`, or a pyramid file written by it.
    pub input: PathBuf,
    /// Where to write (standard output for point lists when absent; `-`: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Format of `-o -` for an array: png, tif, exr, nrrd, … (as an extension).
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// The scheme used by `analyze` (point lists; arrays record it in the file).
    #[arg(long, default_value = "chaikin")]
    pub scheme: Scheme,
    /// The boundary used by `analyze` (point lists).
    #[arg(long, default_value = "interpolating")]
    pub boundary: Boundary,
}

/// Point lists are text: `-`, or `.csv` / `.txt` / `.pts` / `.xy` / `.xyz`.
pub fn is_point_list(p: &Path) -> bool {
    if p.as_os_str() == "-" {
        return true;
    }
    matches!(
        p.extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref(),
        Some("csv" | "txt" | "pts" | "xy" | "xyz")
    )
}

pub fn run_analyze(a: AnalyzeArgs) -> CliResult {
    if is_point_list(&a.input) {
        super::points::analyze(&a.input, a.output.as_ref(), a.scheme, a.boundary, a.levels)
    } else {
        analyze_array(&a)
    }
}

pub fn run_synthesize(a: SynthesizeArgs) -> CliResult {
    if is_point_list(&a.input) {
        super::points::synthesize(&a.input, a.output.as_ref(), a.scheme, a.boundary)
    } else {
        synthesize_array(&a)
    }
}

fn required_output(o: &Option<PathBuf>, input: &Path) -> Result<PathBuf, Failure> {
    o.clone().ok_or_else(|| {
        Failure(format!(
            "{}: images, volumes and heightmaps need an output file (-o OUT)",
            input.display()
        ))
    })
}

/// `mra analyze IN -o OUT` (the arguments as options).
fn analyze_array(a: &AnalyzeArgs) -> CliResult {
    let output = required_output(&a.output, &a.input)?;
    let o = AnalyzeOptions {
        spec: PyramidSpec {
            scheme: a.scheme,
            boundary: a.boundary,
            levels: a.levels.unwrap_or(DEFAULT_LEVELS),
            order: a.order,
            axes: vec![],
        },
        visual: a.visual,
        slice: a.slice,
        read: ReadOptions::default(),
        quiet: false,
    };
    super::stdio::output(
        &output,
        a.format.as_deref(),
        a.visual.then_some("png"),
        "tif for an image, nrrd for a volume",
        |p| analyze_path(&a.input, p, &o),
    )
}

/// `mra synthesize PYRAMID -o OUT` (the arguments as options).
fn synthesize_array(a: &SynthesizeArgs) -> CliResult {
    let output = required_output(&a.output, &a.input)?;
    super::stdio::output(
        &output,
        a.format.as_deref(),
        None,
        "png, tif, exr, nrrd, nii, …",
        |p| synthesize_path(&a.input, p, false),
    )
}
