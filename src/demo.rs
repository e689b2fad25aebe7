//! `mra demo`: the main jobs on generated data, each timed and checked. Later jobs
//! (codec, upscaling, terrain) add rows here.

use crate::scheme::subdivide::{refine_steps, Ends, Refinement};
use crate::scheme::{analyze_lane, synthesize_lane, Boundary, Scheme};
use crate::tensor::{analyze, synthesize, Array, Order, PyramidSpec};
use crate::Result;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One line of the demo's table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemoRow {
    pub job: String,
    pub data: String,
    pub result: String,
    pub seconds: f64,
    pub output: Option<PathBuf>,
}

/// A zig-zag drawn around a circle: a "stroke" with fine detail on a smooth base.
pub fn zigzag_circle(n: usize) -> Vec<f64> {
    (0..n)
        .flat_map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            let r = 10.0 + if i % 2 == 0 { 0.6 } else { -0.6 };
            [r * t.cos(), r * t.sin()]
        })
        .collect()
}

/// The generated zone plate (`mra generate zone-plate`) on the 8-bit scale, as f32.
pub fn zone_plate(h: usize, w: usize) -> Vec<f32> {
    crate::generate::images::zone_plate(h, w)
        .data
        .iter()
        .map(|&v| (v * 255.0) as f32)
        .collect()
}

/// The generated Shepp–Logan-style phantom (`mra generate phantom`) of `n³` voxels,
/// mapped to a CT-like range (−1000 … 1000) as f32.
pub fn blob_volume(n: usize) -> Vec<f32> {
    crate::generate::phantom::shepp_logan(n, n, n)
        .data
        .iter()
        .map(|&v| (v * 2000.0 - 1000.0) as f32)
        .collect()
}

fn max_abs_diff<T: Copy + Into<f64>>(a: &[T], b: &[T]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| (x.into() - y.into()).abs())
        .fold(0.0, f64::max)
}

/// Run every demo job, writing outputs under `out`.
pub fn run(out: &Path) -> Result<Vec<DemoRow>> {
    std::fs::create_dir_all(out)?;
    let mut rows = Vec::new();

    // 1. curve: decompose a stroke, keep the coarse curve, reconstruct
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
    rows.push(DemoRow {
        job: "analyze+synthesize curve".into(),
        data: "zig-zag circle, 256 points 2D, chaikin periodic, 4 levels".into(),
        result: format!(
            "{n} coarse points; max reconstruction error {:.1e}",
            max_abs_diff(&curve, &back)
        ),
        seconds: secs,
        output: Some(coarse_path),
    });

    // 2. subdivision of a square with the interpolating 4-point scheme
    let square = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
    let t = Instant::now();
    let smooth = refine_steps(&square, 2, Refinement::FourPoint, Ends::Closed, 5)?;
    let secs = t.elapsed().as_secs_f64();
    let sub_path = out.join("square_four_point.csv");
    crate::fsutil::write_atomic(&sub_path, |w| crate::points::write(2, &smooth, w))?;
    rows.push(DemoRow {
        job: "subdivide".into(),
        data: "unit square, Dyn-Levin 4-point, closed, 5 steps".into(),
        result: format!(
            "{} points, corners kept: {}",
            smooth.len() / 2,
            smooth[..2] == square[..2]
        ),
        seconds: secs,
        output: Some(sub_path),
    });

    // 3. image pyramid
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

    // 4. volume pyramid
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
    rows.push(DemoRow {
        job: "volume pyramid forward+inverse".into(),
        data: format!("Shepp-Logan phantom {n}^3 f32, cubic interpolating, 3 levels"),
        result: format!(
            "coarse block {coarse}, max error {:.1e}",
            max_abs_diff(&vol, a.data())
        ),
        seconds: secs,
        output: None,
    });
    rows.extend(crate::terrain::demo_rows(out)?);
    rows.extend(crate::upscale::demo_rows(out)?);
    rows.extend(crate::codec::demo::rows(out)?);
    Ok(rows)
}
