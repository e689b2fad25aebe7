//! `mra curve style`: curve style transfer (§9.7.1), a stroke's details added to a new
//! base curve (a thin shell over [`crate::style`]).

use std::path::{Path, PathBuf};

use clap::Args;

use super::{stdio, CliResult, Failure};
use crate::scheme::Scheme;

#[derive(Args, Debug)]
#[command(after_help = "Example:
  mra curve style --style corpus/curves/zigzag.csv --base corpus/curves/arc.csv --levels 3 -o styled.csv")]
pub struct StyleArgs {
    /// The style stroke: a 2-D point list whose fine details are the style.
    #[arg(long)]
    pub style: PathBuf,
    /// The new base curve: a 2-D point list (resampled by arc length).
    #[arg(long)]
    pub base: PathBuf,
    /// Output point list (CSV; `-`: standard output).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Levels of detail carried over from the style curve.
    #[arg(long, default_value_t = 3)]
    pub levels: usize,
    /// chaikin (the notes' Figure 9.18) or cubic.
    #[arg(long, default_value = "chaikin")]
    pub scheme: Scheme,
    /// Treat both curves as closed (periodic boundary).
    #[arg(long)]
    pub closed: bool,
}

fn read_points(p: &Path) -> Result<crate::points::Points, Failure> {
    let text = stdio::read_text(p)?;
    let pts = crate::points::parse(&text).map_err(|e| Failure::context(p.display(), e))?;
    if pts.dim != 2 {
        return Err(Failure(format!(
            "{}: points of dimension {} (expected 2-D points)",
            p.display(),
            pts.dim
        )));
    }
    Ok(pts)
}

pub fn style(a: StyleArgs) -> CliResult {
    let s = read_points(&a.style)?;
    let b = read_points(&a.base)?;
    let out = crate::style::transfer_style(&s.data, &b.data, a.scheme, a.levels, a.closed)?;
    let mut text = Vec::new();
    crate::points::write(2, &out, &mut text)
        .map_err(|e| Failure::context(a.output.display(), e))?;
    stdio::write_bytes(&a.output, &text)
}
