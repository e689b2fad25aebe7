//! `--base-scale S` (issue 49): the base trusted down to 1/S of the output, every finer
//! level synthesized from the example. Determinism, fidelity at the trusted scale,
//! landforms from the example below it, and one-line errors for a bad S.

use std::process::Command;

use super::common;

use mra::generate::terrain::diamond_square;
use mra::terrain::synth::block_means;
use mra::terrain::{synthesize, Grid, SynthOptions};

fn grid_of(h: usize, w: usize, seed: u64, rough: f64, scale: f64) -> Grid {
    let f = diamond_square(h, w, seed, rough);
    Grid::new(h, w, 1, f.data().iter().map(|v| v * scale).collect()).unwrap()
}

/// A smooth base: a few broad, gentle hills (a sketch, flatter than the example), `n × n`.
fn sketch(n: usize) -> Grid {
    let mut g = Grid::zeros(n, n, 1);
    let t = std::f64::consts::TAU / n as f64;
    for y in 0..n {
        for x in 0..n {
            let (fy, fx) = (y as f64 * t, x as f64 * t);
            *g.at_mut(y, x, 0) =
                500.0 + 60.0 * (fx.sin() * (0.5 * fy).cos()) + 30.0 * (fy + fx).cos();
        }
    }
    g
}

fn opts(scale: usize) -> SynthOptions {
    SynthOptions {
        levels: 2,
        seed: 3,
        base_scale: scale,
        ..SynthOptions::default()
    }
}

fn psnr(a: &Grid, b: &Grid) -> f64 {
    mra::terrain::grid::psnr(a, b)
}

/// Mean slope magnitude (central differences inside) of `g`'s `s × s` block means.
fn mean_slope_at(g: &Grid, s: usize) -> f64 {
    let b = block_means(g, g.h() / s, g.w() / s, (s, s));
    let (mut t, mut n) = (0.0, 0usize);
    for y in 1..b.h() - 1 {
        for x in 1..b.w() - 1 {
            let gy = (b.at(y + 1, x, 0) - b.at(y - 1, x, 0)) / (2 * s) as f64;
            let gx = (b.at(y, x + 1, 0) - b.at(y, x - 1, 0)) / (2 * s) as f64;
            t += gy.hypot(gx);
            n += 1;
        }
    }
    t / n as f64
}

#[test]
fn base_scale_is_deterministic_and_its_own_scale_is_the_default() {
    let (base, ex) = (sketch(32), grid_of(256, 256, 9, 0.6, 1000.0));
    let (a, rep) = synthesize(&base, &ex, &opts(16)).unwrap();
    let (b, _) = synthesize(&base, &ex, &opts(16)).unwrap();
    assert_eq!(a.data(), b.data());
    assert_eq!((a.h(), a.w()), (128, 128));
    assert_eq!((rep.levels, rep.base_scale), (4, 16));
    assert_eq!(rep.level_gains.len(), 4);
    let (c, _) = synthesize(
        &base,
        &ex,
        &SynthOptions {
            seed: 4,
            ..opts(16)
        },
    )
    .unwrap();
    assert_ne!(a.data(), c.data());
    // S = 2^L is the base's own scale: the same bytes as the default S = 1
    let (d, _) = synthesize(&base, &ex, &opts(1)).unwrap();
    let (e, _) = synthesize(&base, &ex, &opts(4)).unwrap();
    assert_eq!(d.data(), e.data());
}

#[test]
fn base_scale_gives_the_same_bytes_on_one_and_two_threads() {
    // the level gains, their limits and the drainage do not depend on the thread count
    let (base, ex) = (sketch(32), grid_of(256, 256, 9, 0.6, 1000.0));
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| synthesize(&base, &ex, &opts(16)).unwrap())
    };
    let ((one, r1), (two, r2)) = (run(1), run(2));
    assert_eq!(one.data(), two.data());
    assert_eq!((r1.level_gains, r1.drained), (r2.level_gains, r2.drained));
}

#[test]
fn the_trusted_scale_keeps_the_base_and_the_example_supplies_the_landforms_below_it() {
    let (base, ex) = (sketch(32), grid_of(256, 256, 9, 0.6, 1000.0));
    let (g, rep) = synthesize(&base, &ex, &opts(8)).unwrap();
    // the base at 1/8 of the output (its 2x2 block means) against the result's 8x8 ones
    let trusted = block_means(&base, 16, 16, (2, 2));
    let p = psnr(&block_means(&g, 16, 16, (8, 8)), &trusted);
    assert!(p >= 40.0, "16x16 block-mean PSNR {p:.1} dB");
    assert!((rep.fidelity_psnr.unwrap() - p).abs() < 1e-6);
    // at 4 output cells, below the trusted scale, the slopes come from the example: the
    // result is far closer to the example's mean slope than the default synthesis is
    let (def, _) = synthesize(&base, &ex, &opts(1)).unwrap();
    let (want, got, old) = (
        mean_slope_at(&ex, 4),
        mean_slope_at(&g, 4),
        mean_slope_at(&def, 4),
    );
    assert!(
        (got - want).abs() < 0.5 * (old - want).abs(),
        "mean slope at 4 cells: example {want:.3}, base scale 8 {got:.3}, default {old:.3}"
    );
}

#[test]
fn a_bad_base_scale_is_refused() {
    let (base, ex) = (sketch(32), grid_of(256, 256, 9, 0.6, 1000.0));
    for s in [0, 2, 3, 12, 512] {
        let e = synthesize(&base, &ex, &opts(s)).unwrap_err().to_string();
        assert!(e.contains("base scale") && !e.contains('\n'), "{s}: {e}");
    }
    // the base's sides must be multiples of S / 2^L
    let odd = sketch(33);
    let e = synthesize(&odd, &ex, &opts(8)).unwrap_err().to_string();
    assert!(e.contains("base scale"), "{e}");
    let e = synthesize(
        &base,
        &ex,
        &SynthOptions {
            size: Some((100, 100)),
            ..opts(8)
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("base scale"), "{e}");
}

#[test]
fn cli_base_scale_error_is_one_line_with_no_output() {
    let d = common::scratch_dir("landforms-cli");
    let (base, ex, out) = (d.join("base.tif"), d.join("ex.tif"), d.join("out.tif"));
    for (p, size, seed) in [(&base, "32x32", "3"), (&ex, "256x256", "9")] {
        let o = Command::new(env!("CARGO_BIN_EXE_mra"))
            .args([
                "generate", "terrain", "--size", size, "--seed", seed, "--dtype", "f32", "-o",
            ])
            .arg(p)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let run = |s: &str| {
        Command::new(env!("CARGO_BIN_EXE_mra"))
            .args(["terrain", "synth", "--base"])
            .arg(&base)
            .arg("--example")
            .arg(&ex)
            .arg("-o")
            .arg(&out)
            .args(["--levels", "2", "--base-scale", s])
            .output()
            .unwrap()
    };
    let o = run("3");
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("base scale"), "{e}");
    assert!(!out.exists());
    let o = run("8");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.exists());
}

/// The depth of every pit of `g` (a cell below all its 8 neighbours, off the border)
/// below the level at which it would spill (a priority-flood fill from the border).
fn pit_depths(g: &Grid) -> Vec<f64> {
    use std::cmp::Reverse;
    let (h, w) = (g.h(), g.w());
    let z = g.data();
    let mut level = z.to_vec();
    let mut done = vec![false; h * w];
    let mut heap = std::collections::BinaryHeap::new();
    let key = |v: f64, i: usize| Reverse(((v * 1e6) as i64, i));
    for i in 0..h * w {
        if i / w == 0 || i % w == 0 || i / w + 1 == h || i % w + 1 == w {
            done[i] = true;
            heap.push(key(z[i], i));
        }
    }
    let n8 = |i: usize| {
        let (y, x) = ((i / w) as i64, (i % w) as i64);
        (-1i64..=1)
            .flat_map(move |dy| (-1i64..=1).map(move |dx| (y + dy, x + dx)))
            .filter(move |&(yy, xx)| {
                (yy, xx) != (y, x) && yy >= 0 && xx >= 0 && yy < h as i64 && xx < w as i64
            })
            .map(move |(yy, xx)| yy as usize * w + xx as usize)
    };
    while let Some(Reverse((_, i))) = heap.pop() {
        for j in n8(i) {
            if !done[j] {
                done[j] = true;
                level[j] = level[j].max(level[i]);
                heap.push(key(level[j], j));
            }
        }
    }
    (0..h * w)
        .filter(|&i| {
            let b = i / w == 0 || i % w == 0 || i / w + 1 == h || i % w + 1 == w;
            !b && n8(i).all(|j| z[j] > z[i])
        })
        .map(|i| level[i] - z[i])
        .collect()
}

#[test]
fn the_result_keeps_only_basins_deeper_than_the_breaching_depth() {
    let (base, ex) = (sketch(32), grid_of(256, 256, 9, 0.6, 1000.0));
    let (g, rep) = synthesize(&base, &ex, &opts(16)).unwrap();
    // the breaching depth: BREACH_STEPS times the example's RMS central difference
    let (mut s, mut n) = (0.0, 0usize);
    for y in 1..ex.h() - 1 {
        for x in 1..ex.w() - 1 {
            let dy = 0.5 * (ex.at(y + 1, x, 0) - ex.at(y - 1, x, 0));
            let dx = 0.5 * (ex.at(y, x + 1, 0) - ex.at(y, x - 1, 0));
            s += dy * dy + dx * dx;
            n += 2;
        }
    }
    let depth = 3.0 * (s / n as f64).sqrt();
    // the default synthesis leaves shallow hollows; breaching removes most of them
    // (a channel or its widening may lower the rim of a kept basin), and the block
    // means stay within 40 dB of the base
    let (def, _) = synthesize(&base, &ex, &opts(1)).unwrap();
    let shallow = |d: &[f64]| d.iter().filter(|&&v| v <= 0.99 * depth).count();
    let (before, after) = (shallow(&pit_depths(&def)), shallow(&pit_depths(&g)));
    assert!(rep.drained > 0 && before > 0);
    assert!(
        4 * after <= before,
        "shallow pits: {after} against {before} by default"
    );
    assert!(rep.fidelity_psnr.unwrap() >= 40.0);
}

#[test]
fn psnr_is_the_references_range_over_the_rms_error_in_decibels() {
    let b = sketch(16);
    let (lo, hi) = b.range();
    let off = Grid::new(
        16,
        16,
        1,
        b.data().iter().map(|v| v + 0.01 * (hi - lo)).collect(),
    )
    .unwrap();
    assert!((psnr(&off, &b) - 40.0).abs() < 1e-9, "{}", psnr(&off, &b));
}

#[test]
fn level_gains_stay_within_their_range_on_a_smooth_sketch() {
    // a smooth base leaves the coarsest level's slope to its details alone: each level's
    // gain is solved for the example's slope, limited by the next level's, and clamped
    let (base, ex) = (sketch(32), grid_of(256, 256, 9, 0.6, 1000.0));
    let (_, rep) = synthesize(&base, &ex, &opts(16)).unwrap();
    // the floor and ceiling of src/terrain/level_gain.rs (GAIN_FLOOR, GAIN_CEIL)
    let (lo, hi) = (0.5, 4.0);
    assert_eq!(rep.level_gains.len(), 4);
    assert!(
        rep.level_gains.iter().all(|g| (lo..=hi).contains(g)),
        "{:?}",
        rep.level_gains
    );
}

/// A separable Gaussian blur of `σ` cells (radius 4σ, ends repeated) followed by the
/// 5-point Laplacian (ends repeated): the curvature of the relief at the scale `σ`.
fn gaussian_laplace(g: &Grid, sigma: f64) -> Vec<f64> {
    let (h, w) = (g.h(), g.w());
    let r = (4.0 * sigma).ceil() as i64;
    let k: Vec<f64> = (-r..=r)
        .map(|d| (-((d * d) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    let ks: f64 = k.iter().sum();
    let pass = |src: &[f64], along_x: bool| -> Vec<f64> {
        let mut out = vec![0.0; h * w];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for (j, kv) in k.iter().enumerate() {
                    let d = j as i64 - r;
                    let (yy, xx) = if along_x {
                        (y, (x as i64 + d).clamp(0, w as i64 - 1) as usize)
                    } else {
                        ((y as i64 + d).clamp(0, h as i64 - 1) as usize, x)
                    };
                    s += kv * src[yy * w + xx];
                }
                out[y * w + x] = s / ks;
            }
        }
        out
    };
    let b = pass(&pass(g.data(), true), false);
    let at = |y: i64, x: i64| {
        b[y.clamp(0, h as i64 - 1) as usize * w + x.clamp(0, w as i64 - 1) as usize]
    };
    (0..h * w)
        .map(|i| {
            let (y, x) = ((i / w) as i64, (i % w) as i64);
            at(y - 1, x) + at(y + 1, x) + at(y, x - 1) + at(y, x + 1) - 4.0 * at(y, x)
        })
        .collect()
}

/// The cell-weighted mean size `Σ s² / Σ s` of the 8-connected runs of `mask` (`h × w`).
fn run_size(mask: &[bool], h: usize, w: usize) -> f64 {
    let mut seen = vec![false; h * w];
    let (mut s2, mut s1) = (0.0, 0.0);
    for start in 0..h * w {
        if !mask[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        let (mut stack, mut n) = (vec![start], 0usize);
        while let Some(i) = stack.pop() {
            n += 1;
            let (y, x) = ((i / w) as i64, (i % w) as i64);
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let (yy, xx) = (y + dy, x + dx);
                    if yy < 0 || xx < 0 || yy >= h as i64 || xx >= w as i64 {
                        continue;
                    }
                    let j = yy as usize * w + xx as usize;
                    if mask[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        s2 += (n * n) as f64;
        s1 += n as f64;
    }
    s2 / s1.max(1.0)
}

/// The 10th and 90th percentiles of the curvature of [`gaussian_laplace`] at σ = 2:
/// the example's most convex (crest) and most concave (valley floor) cells.
fn crest_thresholds(example: &Grid) -> (f64, f64) {
    let mut l = gaussian_laplace(example, 2.0);
    l.sort_by(f64::total_cmp);
    let n = l.len() - 1;
    (l[n / 10], l[9 * n / 10])
}

/// The crest length of `benches/terrain_quality.py`: the mean of the cell-weighted mean
/// run sizes of the crest cells (curvature below `lo`) and of the valley-floor cells
/// (above `hi`), on the top-left `th × tw` tile of `g` (the example's shape).
fn crest_length(g: &Grid, (th, tw): (usize, usize), (lo, hi): (f64, f64)) -> f64 {
    let tile = Grid::new(
        th,
        tw,
        1,
        (0..th * tw).map(|i| g.at(i / tw, i % tw, 0)).collect(),
    )
    .unwrap();
    let l = gaussian_laplace(&tile, 2.0);
    let crest: Vec<bool> = l.iter().map(|v| *v < lo).collect();
    let floor: Vec<bool> = l.iter().map(|v| *v > hi).collect();
    0.5 * (run_size(&crest, th, tw) + run_size(&floor, th, tw))
}

/// A noise texture with the example's own relief: the smooth base's upscale plus the
/// example's detail (the example minus its 9×9 box mean) cut into 16×16 tiles laid in a
/// shuffled order: the example's slopes and curvatures, its landforms cut short.
fn tile_texture(up: &Grid, example: &Grid, seed: u64) -> Grid {
    let (eh, ew) = (example.h(), example.w());
    let mean = |y: usize, x: usize| {
        let (mut s, mut n) = (0.0, 0.0);
        for yy in y.saturating_sub(4)..(y + 5).min(eh) {
            for xx in x.saturating_sub(4)..(x + 5).min(ew) {
                s += example.at(yy, xx, 0);
                n += 1.0;
            }
        }
        s / n
    };
    let mut out = up.clone();
    let mut r = mra::generate::rng::SplitMix64::new(seed);
    let t = 16;
    for ty in (0..up.h()).step_by(t) {
        for tx in (0..up.w()).step_by(t) {
            let sy = (r.next_u64() % (eh - t) as u64) as usize;
            let sx = (r.next_u64() % (ew - t) as u64) as usize;
            for y in 0..t.min(up.h() - ty) {
                for x in 0..t.min(up.w() - tx) {
                    *out.at_mut(ty + y, tx + x, 0) +=
                        example.at(sy + y, sx + x, 0) - mean(sy + y, sx + x);
                }
            }
        }
    }
    out
}

/// Issue 49's look on the bench's example (N44W072 rows 801–1201, cols 857–1201): from a
/// smooth 128² sketch with `--base-scale 16`, the result has crest and valley-floor lines
/// of at least half the example's length, the plain upscale has no cell as curved, and a
/// texture of the example's own 16-cell tiles has short runs (corpus; skipped without it).
#[test]
fn base_scale_results_have_the_examples_long_crests_and_a_texture_does_not() {
    let Some(path) = common::corpus("terrain/N44W072.hgt") else {
        return;
    };
    let r = mra::io::read(&path).unwrap();
    let (tile, _) = mra::terrain::raster::to_grid(&r).unwrap();
    let (eh, ew) = (400, 344);
    let ex = Grid::new(
        eh,
        ew,
        1,
        (0..eh * ew)
            .map(|i| tile.at(801 + i / ew, 857 + i % ew, 0))
            .collect(),
    )
    .unwrap();
    let base = Grid::new(
        128,
        128,
        1,
        sketch(128).data().iter().map(|v| 4.0 * v).collect(),
    )
    .unwrap();
    let o = SynthOptions {
        levels: 2,
        seed: 1,
        base_scale: 16,
        ..SynthOptions::default()
    };
    let (g, _) = synthesize(&base, &ex, &o).unwrap();
    let (up, _) = synthesize(
        &base,
        &ex,
        &SynthOptions {
            details: mra::terrain::synth::Details::None,
            base_scale: 1,
            ..o.clone()
        },
    )
    .unwrap();
    let thr = crest_thresholds(&ex);
    let want = crest_length(&ex, (eh, ew), thr);
    let [got, smooth, texture] =
        [&g, &up, &tile_texture(&up, &ex, 7)].map(|h| crest_length(h, (eh, ew), thr) / want);
    // the bench's target is 0.8 (not yet met there: 0.74 and 0.69); here the measure must
    // part the three: no curved cells, short runs, long runs
    assert!(
        got >= 0.5 && got >= 1.5 * texture && smooth < 0.25,
        "crest length ÷ example's: result {got:.2}, upscale {smooth:.2}, tile texture {texture:.2}"
    );
}
