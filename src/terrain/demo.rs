//! `mra demo` rows for this module: a terrain synthesized from a smooth generated base
//! and a rough generated example, checked for fidelity (the result reduced to the
//! base's resolution against the base) and seams, and its hillshade written.

use std::path::Path;
use std::time::Instant;

use super::{hillshade, reduce, synthesize, Grid, Shading, SynthOptions};
use crate::demo::DemoRow;
use crate::generate::terrain::diamond_square;
use crate::io::{DataKind, Raster, Samples};
use crate::Result;

/// The terrain rows of the demo, outputs under `out`.
pub fn demo_rows(out: &Path) -> Result<Vec<DemoRow>> {
    let (n, l) = (64, 2);
    let fine = diamond_square(4 * n, 4 * n, 3, 0.55);
    // base: the generated terrain box-filtered by 4 (smooth, coarse), in metres
    let mut base = Grid::zeros(n, n, 1);
    for y in 0..n {
        for x in 0..n {
            let mut s = 0.0;
            for k in 0..16 {
                s += fine.data()[(4 * y + k / 4) * 4 * n + 4 * x + k % 4];
            }
            *base.at_mut(y, x, 0) = 1000.0 * s / 16.0;
        }
    }
    let ex = diamond_square(256, 256, 9, 0.65);
    let example = Grid::new(256, 256, 1, ex.data().iter().map(|v| v * 1000.0).collect())?;
    let o = SynthOptions {
        levels: l,
        seed: 7,
        ..SynthOptions::default()
    };
    let t = Instant::now();
    let (g, report) = synthesize(&base, &example, &o)?;
    let secs = t.elapsed().as_secs_f64();
    let back = reduce(&g, n, n, o.scheme, l)?;
    let psnr = super::grid::psnr(&back, &base);
    let (lo, hi) = base.range();
    let c = (hi - lo) / (0.25 * g.w() as f64);
    let px = hillshade(
        &g,
        &Shading {
            cell: (c, c),
            colour: true,
            ..Shading::default()
        },
    );
    let path = out.join("terrain_synth.png");
    let pic = Raster::new(vec![g.h(), g.w()], 3, Samples::U8(px), DataKind::Image)?;
    crate::io::write(&path, &pic)?;
    Ok(vec![DemoRow {
        job: "terrain synth by example".into(),
        data: format!("generated base {n}x{n} (smooth), example 256x256, chaikin, {l} levels"),
        result: format!(
            "{}x{}; reduced back: PSNR {psnr:.1} dB vs base; seam ratio {:.3}",
            g.w(),
            g.h(),
            report.seam_ratio
        ),
        seconds: secs,
        output: Some(path),
    }])
}
