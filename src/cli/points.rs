//! `mra analyze`, `mra synthesize` and `mra subdivide` on point lists (curves, signals).

use super::{CliResult, Failure};
use crate::points::{self, Tagged};
use crate::scheme::subdivide::{refine_steps, Ends, Refinement};
use crate::scheme::{
    analyze_lane, lane_levels, synthesize_lane, Boundary, LanePyramid, Scheme, TwoScale,
};
use std::io::Read;
use std::path::{Path, PathBuf};

/// Read a file, or standard input for `-`.
pub fn read_text(path: &Path) -> Result<String, Failure> {
    let mut s = String::new();
    if path.as_os_str() == "-" {
        std::io::stdin()
            .read_to_string(&mut s)
            .map_err(|e| Failure::context("<stdin>", e))?;
    } else {
        s = std::fs::read_to_string(path).map_err(|e| Failure::context(path.display(), e))?;
    }
    Ok(s)
}

/// Write to `-o FILE` atomically, or to standard output.
pub fn emit(
    out: Option<&PathBuf>,
    fill: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
) -> CliResult {
    match out {
        Some(p) if p.as_os_str() != "-" => crate::fsutil::write_atomic(p, |w| fill(w))
            .map_err(|e| Failure::context(p.display(), e)),
        _ => {
            let stdout = std::io::stdout();
            let mut lock = stdout.lock();
            fill(&mut lock).map_err(|e| Failure::context("<stdout>", e))
        }
    }
}

/// `mra analyze` on a point list: decompose and print `C` then `D<L>` … `D1` lines.
pub fn analyze(
    input: &Path,
    out: Option<&PathBuf>,
    scheme: Scheme,
    boundary: Boundary,
    levels: Option<usize>,
) -> CliResult {
    let text = read_text(input)?;
    let pts = points::parse(&text).map_err(|e| Failure::context(input.display(), e))?;
    let n = pts.len();
    let max = lane_levels(scheme, boundary, n);
    let levels = levels.unwrap_or(max);
    if levels > max {
        return Err(Failure(format!(
            "{}: {levels} levels asked, but {n} points allow at most {max} with {scheme}/{boundary}",
            input.display()
        )));
    }
    let (packed, plan) = analyze_lane(&pts.data, pts.dim, scheme, boundary, levels)?;
    let d = pts.dim;
    let tagged = Tagged {
        dim: d,
        coarse: packed[..plan.lengths[levels] * d].to_vec(),
        details: (1..=levels)
            .rev()
            .map(|l| {
                let r = plan.detail_range(l);
                packed[r.start * d..r.end * d].to_vec()
            })
            .collect(),
    };
    emit(out, |w| points::write_tagged(&tagged, w))
}

/// `mra synthesize` on a tagged point list.
pub fn synthesize(
    input: &Path,
    out: Option<&PathBuf>,
    scheme: Scheme,
    boundary: Boundary,
) -> CliResult {
    let text = read_text(input)?;
    let t = points::parse_tagged(&text).map_err(|e| Failure::context(input.display(), e))?;
    let d = t.dim;
    // lengths from the coarsest up: m_{l-1} = m_l + |D_l|
    let levels = t.details.len();
    let mut lengths = vec![0usize; levels + 1];
    lengths[levels] = t.coarse.len() / d;
    for (k, band) in t.details.iter().enumerate() {
        let l = levels - k; // band D_l
        lengths[l - 1] = lengths[l] + band.len() / d;
    }
    // the plan must be the one the scheme produces for the fine length
    for l in 0..levels {
        let n = TwoScale::coarse_len(scheme, boundary, lengths[l]);
        if n != lengths[l + 1] {
            return Err(Failure(format!(
                "{}: level {} has {} coarse and {} detail points, but {scheme}/{boundary} reduces {} points to {n} coarse (wrong --scheme or --boundary?)",
                input.display(),
                l + 1,
                lengths[l + 1],
                lengths[l] - lengths[l + 1],
                lengths[l]
            )));
        }
    }
    let plan = LanePyramid {
        scheme,
        boundary,
        lengths,
    };
    let mut packed = t.coarse.clone();
    for band in &t.details {
        packed.extend_from_slice(band);
    }
    let fine = synthesize_lane(&packed, d, &plan)?;
    emit(out, |w| points::write(d, &fine, w))
}

/// `mra subdivide`.
pub fn subdivide(
    input: &Path,
    out: Option<&PathBuf>,
    rule: Refinement,
    closed: bool,
    steps: usize,
) -> CliResult {
    let text = read_text(input)?;
    let pts = points::parse(&text).map_err(|e| Failure::context(input.display(), e))?;
    let ends = if closed { Ends::Closed } else { Ends::Open };
    if pts.len() < rule.min_points(ends) {
        return Err(Failure(format!(
            "{}: {} points, but {rule:?} subdivision with {} ends needs at least {}",
            input.display(),
            pts.len(),
            if closed { "closed" } else { "open" },
            rule.min_points(ends)
        )));
    }
    // the refined length, step by step, against the memory budget before refining
    let budget = crate::limits::Limits::from_env()?;
    let mut n = pts.len();
    for _ in 0..steps {
        n = rule.refined_len(ends, n);
        let bytes = (n as u64).saturating_mul(pts.dim as u64 * 8);
        if bytes > budget.max_bytes {
            return Err(Failure(format!(
                "{}: {steps} steps of {rule:?} subdivision from {} points would need more than {bytes} bytes, over the memory budget of {} bytes (expected fewer steps; MRA_MAX_BYTES raises the budget)",
                input.display(),
                pts.len(),
                budget.max_bytes
            )));
        }
    }
    let fine = refine_steps(&pts.data, pts.dim, rule, ends, steps)
        .map_err(|e| Failure::context(input.display(), e))?;
    emit(out, |w| points::write(pts.dim, &fine, w))
}
