//! `mra subdivide`.

use super::CliResult;
use crate::scheme::subdivide::Refinement;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mra subdivide --scheme cubic --steps 3 corpus/curves/zigzag.csv
  mra subdivide --scheme four-point --closed --steps 4 square.csv -o smooth.csv")]
pub struct SubdivideArgs {
    /// A point list (CSV, one point per line; `-` for standard input).
    pub input: PathBuf,
    /// Where to write (standard output when absent).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// box, linear, chaikin, cubic, quartic or four-point.
    #[arg(long, default_value = "cubic")]
    pub scheme: Refinement,
    /// Closed curve (periodic rules); open curves interpolate their end points.
    #[arg(long)]
    pub closed: bool,
    /// Refinement steps.
    #[arg(long, default_value_t = 1)]
    pub steps: usize,
}

pub fn run(a: SubdivideArgs) -> CliResult {
    super::points::subdivide(&a.input, a.output.as_ref(), a.scheme, a.closed, a.steps)
}
