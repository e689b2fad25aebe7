//! `mra demo`.

use super::{CliResult, Failure};
use crate::demo::{blob_volume, max_abs_diff, zigzag_circle, zone_plate, DemoRow};
use crate::scheme::subdivide::{refine_steps, Ends, Refinement};
use crate::scheme::{analyze_lane, synthesize_lane, Boundary, Scheme};
use crate::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
use crate::Result;
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args, Debug)]
#[command(after_help = "Example:\n  mra demo --out /tmp/mra-demo")]
pub struct DemoArgs {
    /// Folder for the demo's output files.
    #[arg(long, default_value = "mra-demo")]
    pub out: PathBuf,
    /// Print the table as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: DemoArgs) -> CliResult {
    let rows = rows(&a.out).map_err(|e| Failure::context(a.out.display(), e))?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&rows).map_err(|e| Failure(e.to_string()))?
        );
        return Ok(());
    }
    let jw = rows.iter().map(|r| r.job.len()).max().unwrap_or(3).max(3);
    let dw = rows.iter().map(|r| r.data.len()).max().unwrap_or(4).max(4);
    println!("{:<jw$}  {:<dw$}  {:>8}  result", "job", "data", "time");
    for r in &rows {
        println!(
            "{:<jw$}  {:<dw$}  {:>7.3}s  {}",
            r.job, r.data, r.seconds, r.result
        );
    }
    println!("\noutputs in {}:", a.out.display());
    for r in rows.iter().filter_map(|r| r.output.as_ref()) {
        println!("  {}", r.display());
    }
    Ok(())
}

/// Run every demo job, writing outputs under `out`.
pub fn rows(out: &Path) -> Result<Vec<DemoRow>> {
    std::fs::create_dir_all(out)?;
    let mut rows = vec![curve_row(out)?, subdivide_row(out)?];
    rows.extend(image_rows()?);
    rows.push(volume_row()?);
    rows.extend(crate::terrain::demo_rows(out)?);
    rows.extend(crate::upscale::demo_rows(out)?);
    rows.extend(crate::codec::demo::rows(out)?);
    Ok(rows)
}

/// Decompose a stroke, keep the coarse curve, reconstruct.
fn curve_row(out: &Path) -> Result<DemoRow> {
    let curve = zigzag_circle(256);
    let t = Instant::now();
    let (packed, plan) = analyze_lane(&curve, 2, Scheme::Chaikin, Boundary::Periodic, 4)?;
    let back = synthesize_lane(&packed, 2, &plan)?;
    let secs = t.elapsed().as_secs_f64();
    let coarse_path = out.join("curve_coarse.csv");
    let n = plan.lengths[4];
    crate::fsutil::write_atomic(&coarse_path, |w| {
        crate::points::write(2, &packed[..2 * n], w)
    })?;
    Ok(DemoRow {
        job: "analyze+synthesize curve".into(),
        data: "zig-zag circle, 256 points 2D, chaikin periodic, 4 levels".into(),
        result: format!(
            "{n} coarse points; max reconstruction error {:.1e}",
            max_abs_diff(&curve, &back)
        ),
        seconds: secs,
        output: Some(coarse_path),
    })
}

/// Subdivision of a square with the interpolating 4-point scheme.
fn subdivide_row(out: &Path) -> Result<DemoRow> {
    let square = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
    let t = Instant::now();
    let smooth = refine_steps(&square, 2, Refinement::FourPoint, Ends::Closed, 5)?;
    let secs = t.elapsed().as_secs_f64();
    let sub_path = out.join("square_four_point.csv");
    crate::fsutil::write_atomic(&sub_path, |w| crate::points::write(2, &smooth, w))?;
    Ok(DemoRow {
        job: "subdivide".into(),
        data: "unit square, Dyn-Levin 4-point, closed, 5 steps".into(),
        result: format!(
            "{} points, corners kept: {}",
            smooth.len() / 2,
            smooth[..2] == square[..2]
        ),
        seconds: secs,
        output: Some(sub_path),
    })
}

/// Image pyramid forward and inverse, every scheme.
fn image_rows() -> Result<Vec<DemoRow>> {
    let mut rows = Vec::new();
    let (h, w) = (1024, 1024);
    let img = zone_plate(h, w);
    for scheme in Scheme::ALL {
        let spec = PyramidSpec {
            scheme,
            boundary: Boundary::Symmetric,
            levels: 5,
            order: Order::NonStandard,
            axes: vec![0, 1],
        };
        // best of 5 round trips from the same image (the first also pays for the
        // scratch array's fresh pages and the thread pool's start)
        let mut secs = f64::INFINITY;
        let mut err = 0.0;
        for _ in 0..5 {
            let mut a = Array::from_shape_vec(&[h, w], img.clone())?;
            let t = Instant::now();
            let pyr = analyze(&mut a, &spec)?;
            synthesize(&mut a, &pyr)?;
            secs = secs.min(t.elapsed().as_secs_f64());
            err = max_abs_diff(&img, a.data());
        }
        rows.push(DemoRow {
            job: "image pyramid forward+inverse".into(),
            data: format!("zone plate {h}x{w} f32, {scheme} symmetric, 5 levels"),
            result: format!(
                "max error {err:.1e}, {:.0} MB/s (best of 5)",
                (h * w * 4) as f64 / secs / 1e6
            ),
            seconds: secs,
            output: None,
        });
    }
    Ok(rows)
}

/// Volume pyramid forward and inverse.
fn volume_row() -> Result<DemoRow> {
    let n = 128;
    let vol = blob_volume(n);
    let mut a = Array::from_shape_vec(&[n, n, n], vol.clone())?;
    let spec = PyramidSpec {
        scheme: Scheme::Cubic,
        boundary: Boundary::Interpolating,
        levels: 3,
        order: Order::NonStandard,
        axes: vec![0, 1, 2],
    };
    let t = Instant::now();
    let pyr = analyze(&mut a, &spec)?;
    let coarse = pyr.subbands()[0]
        .ranges
        .iter()
        .map(|r| r.len().to_string())
        .collect::<Vec<_>>()
        .join("x");
    synthesize(&mut a, &pyr)?;
    let secs = t.elapsed().as_secs_f64();
    Ok(DemoRow {
        job: "volume pyramid forward+inverse".into(),
        data: format!("Shepp-Logan phantom {n}^3 f32, cubic interpolating, 3 levels"),
        result: format!(
            "coarse block {coarse}, max error {:.1e}",
            max_abs_diff(&vol, a.data())
        ),
        seconds: secs,
        output: None,
    })
}
