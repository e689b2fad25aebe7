//! `mra analyze` / `mra synthesize` on images, volumes and heightmaps.

use super::analyze::{AnalyzeArgs, SynthesizeArgs};
use super::{CliResult, Failure};

pub fn analyze(a: &AnalyzeArgs) -> CliResult {
    Err(Failure(format!(
        "{}: images, volumes and heightmaps are not readable yet (point lists: .csv)",
        a.input.display()
    )))
}

pub fn synthesize(a: &SynthesizeArgs) -> CliResult {
    Err(Failure(format!(
        "{}: pyramid files are not readable yet (point lists: .csv)",
        a.input.display()
    )))
}
