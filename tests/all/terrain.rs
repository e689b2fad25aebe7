//! Terrain synthesis, detail transfer, hillshading and denoising: determinism, fidelity
//! to the base, no seams, realism against a subdivision-only result, and one-line
//! errors with exit code 2 on bad input.

use std::path::PathBuf;
use std::process::Command;

use super::common;

use mra::denoise::{denoise, DenoiseOptions};
use mra::generate::terrain::diamond_square;
use mra::scheme::Scheme;
use mra::tensor::Array;
use mra::terrain::synth::Details;
use mra::terrain::volume::coarse_points;
use mra::terrain::{
    highpass, reduce, synthesize, transfer, transfer_volume, Grid, SynthOptions, Volume,
};

fn grid_of(h: usize, w: usize, seed: u64, rough: f64, scale: f64) -> Grid {
    let f = diamond_square(h, w, seed, rough);
    Grid::new(h, w, 1, f.data().iter().map(|v| v * scale).collect()).unwrap()
}

/// A smooth base: a generated terrain box-filtered down by 4.
fn smooth_base(n: usize, seed: u64) -> Grid {
    let f = grid_of(4 * n, 4 * n, seed, 0.55, 1000.0);
    let mut g = Grid::zeros(n, n, 1);
    for y in 0..n {
        for x in 0..n {
            let mut s = 0.0;
            for dy in 0..4 {
                for dx in 0..4 {
                    s += f.at(4 * y + dy, 4 * x + dx, 0);
                }
            }
            *g.at_mut(y, x, 0) = s / 16.0;
        }
    }
    g
}

fn psnr(a: &Grid, b: &Grid) -> f64 {
    let (lo, hi) = b.range();
    let mse = a
        .data()
        .iter()
        .zip(b.data())
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        / a.data().len() as f64;
    10.0 * ((hi - lo).powi(2) / mse).log10()
}

/// Standard deviation of the 5-point Laplacian (roughness).
fn roughness(g: &Grid) -> f64 {
    let mut v = Vec::new();
    for y in 1..g.h() - 1 {
        for x in 1..g.w() - 1 {
            v.push(
                g.at(y - 1, x, 0) + g.at(y + 1, x, 0) + g.at(y, x - 1, 0) + g.at(y, x + 1, 0)
                    - 4.0 * g.at(y, x, 0),
            );
        }
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
}

fn opts(seed: u64) -> SynthOptions {
    SynthOptions {
        levels: 2,
        seed,
        ..SynthOptions::default()
    }
}

#[test]
fn same_seed_gives_identical_output_and_another_seed_differs() {
    let base = smooth_base(40, 3);
    let ex = grid_of(160, 160, 9, 0.6, 1000.0);
    let (a, _) = synthesize(&base, &ex, &opts(7)).unwrap();
    let (b, _) = synthesize(&base, &ex, &opts(7)).unwrap();
    let (c, _) = synthesize(&base, &ex, &opts(8)).unwrap();
    assert_eq!(a.data(), b.data());
    assert_ne!(a.data(), c.data());
    assert_eq!((a.h(), a.w()), (160, 160));
}

#[test]
fn result_reduced_to_the_base_resolution_keeps_the_base() {
    let base = smooth_base(48, 5);
    let ex = grid_of(192, 192, 11, 0.6, 1000.0);
    for scheme in [Scheme::Chaikin, Scheme::Cubic] {
        let o = SynthOptions { scheme, ..opts(1) };
        let (out, report) = synthesize(&base, &ex, &o).unwrap();
        let back = mra::terrain::synth::block_means(&out, base.h(), base.w(), (4, 4));
        let p = psnr(&back, &base);
        assert!(p >= 40.0, "{scheme}: PSNR {p:.1} dB");
        // the details are really there: rougher than the base refined alone
        let plain = synthesize(
            &base,
            &ex,
            &SynthOptions {
                details: Details::None,
                ..o.clone()
            },
        )
        .unwrap()
        .0;
        assert!(roughness(&out) > 2.0 * roughness(&plain));
        // no seams: patch borders no rougher than elsewhere (within 15 %)
        assert!(report.seam_ratio < 1.15, "seam ratio {}", report.seam_ratio);
    }
}

/// The realism figures of benches/terrain_quality.py on the finest levels (F − P^L A^L F):
/// subdivision alone adds nothing there, and the matched details have the example's
/// roughness (per-level band RMS), closer than copying without matching.
#[test]
fn finest_levels_of_matched_details_have_the_examples_roughness() {
    let base = smooth_base(48, 5);
    let ex = grid_of(192, 192, 11, 0.6, 1000.0);
    let ehp = highpass(&ex, Scheme::Chaikin, 2).unwrap();
    // a size that is not a multiple of the base's: no back-projection, so the finest
    // levels are the details alone; the finest gain at 1, so each band keeps the
    // example's RMS (the fitted gain trades it for the example's spectral slope: 1.44×
    // the example's roughness on this generated terrain)
    let run = |d: Details| {
        let o = SynthOptions {
            details: d,
            size: Some((190, 190)),
            finest_gain: mra::terrain::FinestGain::Fixed(1.0),
            ..opts(3)
        };
        let (g, rep) = synthesize(&base, &ex, &o).unwrap();
        assert!(rep.fidelity_psnr.unwrap() > 40.0, "{d:?}: {rep:?}");
        highpass(&g, Scheme::Chaikin, 2).unwrap()
    };
    let none = run(Details::None);
    let (lo, hi) = ex.range();
    let biggest = none.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(
        biggest < 1e-9 * (hi - lo),
        "subdivision alone has finest levels {biggest}"
    );
    let r_matched = roughness(&run(Details::Matched)) / roughness(&ehp);
    let r_copy = roughness(&run(Details::Copy)) / roughness(&ehp);
    assert!(
        (r_matched - 1.0).abs() < 0.1,
        "matched roughness ratio {r_matched}"
    );
    // copying without matching is no longer inflated (one source shift per patch counts
    // once in the blend), so it is only required to be rough too
    assert!(r_copy > 0.5, "copy roughness ratio {r_copy}");
}

#[test]
fn output_size_can_be_chosen_and_transfer_keeps_the_size() {
    let base = smooth_base(32, 2);
    let ex = grid_of(128, 128, 4, 0.6, 1000.0);
    let o = SynthOptions {
        size: Some((100, 140)),
        ..opts(1)
    };
    let (out, _) = synthesize(&base, &ex, &o).unwrap();
    assert_eq!((out.h(), out.w()), (100, 140));
    let blurred = reduce(&ex, 128, 128, Scheme::Chaikin, 0).unwrap();
    let (t, _) = transfer(&blurred, &ex, &opts(1)).unwrap();
    assert_eq!((t.h(), t.w()), (128, 128));
}

#[test]
fn example_smaller_than_the_filter_support_is_an_error() {
    let base = smooth_base(32, 2);
    let small = grid_of(20, 20, 4, 0.6, 1000.0);
    let e = synthesize(&base, &small, &opts(1)).unwrap_err();
    assert_eq!(e.kind(), mra::ErrorKind::Parameter);
    assert!(e.to_string().contains("expected"), "{e}");
}

#[test]
fn denoising_a_noisy_circle_brings_it_back_to_the_circle() {
    let n = 512;
    let mut rng = mra::generate::rng::SplitMix64::new(5);
    let mut pts = Vec::new();
    for i in 0..n {
        let t = i as f64 / n as f64 * std::f64::consts::TAU;
        pts.push(10.0 * t.cos() + 0.3 * rng.symmetric());
        pts.push(10.0 * t.sin() + 0.3 * rng.symmetric());
    }
    let err = |p: &[f64]| {
        p.chunks(2)
            .map(|q| ((q[0] * q[0] + q[1] * q[1]).sqrt() - 10.0).powi(2))
            .sum::<f64>()
            / n as f64
    };
    let before = err(&pts);
    let mut a = Array::from_shape_vec(&[n, 2], pts).unwrap();
    let o = DenoiseOptions {
        scheme: Scheme::Chaikin,
        boundary: mra::scheme::Boundary::Periodic,
        levels: 2,
        ..DenoiseOptions::default()
    };
    denoise(&mut a, &[0], &o).unwrap();
    let after = err(a.data());
    assert!(after < 0.6 * before, "{after} vs {before}");
}

// --- the binary ---

fn mra(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .output()
        .unwrap()
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mra-terrain-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

fn one_line_error(o: &std::process::Output) -> String {
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    e
}

#[test]
fn cli_synth_is_byte_identical_for_a_seed_and_renders() {
    let d = tmpdir("cli");
    let (base, ex) = (d.join("base.png"), d.join("ex.png"));
    let gen = |p: &std::path::Path, size: &str, seed: &str| {
        let o = mra(&[
            "generate",
            "terrain",
            "--size",
            size,
            "--seed",
            seed,
            "-o",
            s(p),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    gen(&base, "48x48", "3");
    gen(&ex, "192x192", "9");
    let run = |out: &std::path::Path, seed: &str| {
        let o = mra(&[
            "terrain",
            "synth",
            "--base",
            s(&base),
            "--example",
            s(&ex),
            "--seed",
            seed,
            "-o",
            s(out),
            "--preview",
            s(&d.join("prev.png")),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(out).unwrap()
    };
    let a = run(&d.join("a.tif"), "5");
    let b = run(&d.join("b.tif"), "5");
    let c = run(&d.join("c.tif"), "6");
    assert_eq!(a, b);
    assert_ne!(a, c);
    let o = mra(&[
        "terrain",
        "render",
        s(&d.join("a.tif")),
        "-o",
        s(&d.join("r.png")),
        "--colour",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pic = mra::io::read(&d.join("r.png")).unwrap();
    assert_eq!((pic.dims.clone(), pic.channels), (vec![192, 192], 3));
    assert!(d.join("prev.png").exists());
}

#[test]
fn cli_bad_inputs_fail_with_one_line_and_no_output() {
    let d = tmpdir("bad");
    let (base, small) = (d.join("base.png"), d.join("small.png"));
    for (p, size) in [(&base, "48x48"), (&small, "16x16")] {
        assert!(mra(&["generate", "terrain", "--size", size, "-o", s(p)])
            .status
            .success());
    }
    let out = d.join("out.tif");
    let e = one_line_error(&mra(&[
        "terrain",
        "synth",
        "--base",
        s(&base),
        "--example",
        s(&small),
        "-o",
        s(&out),
    ]));
    assert!(e.contains("example"), "{e}");
    assert!(!out.exists());
    // mismatched cell sizes (ASCII grids in the same unit, cells 10 m and 1000 m)
    let grid = |p: &std::path::Path, cell: f64, n: usize| {
        let mut t = format!("ncols {n}\nnrows {n}\nxllcorner 0\nyllcorner 0\ncellsize {cell}\n");
        for y in 0..n {
            let row: Vec<String> = (0..n).map(|x| ((x * y) % 17).to_string()).collect();
            t += &(row.join(" ") + "\n");
        }
        std::fs::write(p, t).unwrap();
    };
    grid(&d.join("b.asc"), 1000.0, 40);
    grid(&d.join("e.asc"), 10.0, 200);
    let e = one_line_error(&mra(&[
        "terrain",
        "synth",
        "--base",
        s(&d.join("b.asc")),
        "--example",
        s(&d.join("e.asc")),
        "-o",
        s(&out),
    ]));
    assert!(e.contains("cell"), "{e}");
    assert!(!out.exists());
    // mismatched channels
    let rgb = d.join("rgb.png");
    assert!(mra(&[
        "generate",
        "gradient",
        "--size",
        "200",
        "--channels",
        "3",
        "-o",
        s(&rgb)
    ])
    .status
    .success());
    one_line_error(&mra(&[
        "transfer",
        "--from",
        s(&rgb),
        "--to",
        s(&base),
        "-o",
        s(&out),
    ]));
    assert!(!out.exists());
}

#[test]
fn cli_denoise_images_and_point_lists() {
    let d = tmpdir("denoise");
    // an image: a smooth field plus deterministic noise of σ ≈ 8, as f32
    let (h, w) = (96, 128);
    let mut rng = mra::generate::rng::SplitMix64::new(36);
    let clean: Vec<f64> = (0..h * w)
        .map(|i| {
            let (y, x) = ((i / w) as f64, (i % w) as f64);
            100.0 + 60.0 * (x * 0.09).sin() * (y * 0.07).cos()
        })
        .collect();
    // a sum of 4 uniforms on (−1, 1) has σ = √(4/3); scaled to σ = 8
    let noisy: Vec<f64> = clean
        .iter()
        .map(|&c| {
            c + 8.0 / (4.0f64 / 3.0).sqrt()
                * (0..4).map(|_| 2.0 * rng.next_f64() - 1.0).sum::<f64>()
        })
        .collect();
    let raster = |v: &[f64]| {
        mra::io::Raster::new(
            vec![h, w],
            1,
            mra::io::Samples::from_f64(v, mra::io::SampleType::F32),
            mra::io::DataKind::Image,
        )
        .unwrap()
    };
    mra::io::write(&d.join("noisy.tif"), &raster(&noisy)).unwrap();
    let o = mra(&[
        "denoise",
        s(&d.join("noisy.tif")),
        "-o",
        s(&d.join("z.tif")),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = mra::io::read(&d.join("z.tif")).unwrap();
    assert_eq!(r.dims, vec![h, w]);
    assert_eq!(r.sample_type(), mra::io::SampleType::F32);
    let rms = |a: &[f64], b: &[f64]| {
        (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
    };
    let (before, after) = (rms(&noisy, &clean), rms(&r.to_f64(), &clean));
    // measured: 7.9 → 2.4
    assert!(
        after < 0.5 * before,
        "rms error from the clean image {before} → {after}"
    );
    // a point list: a circle of radius 1 with radial noise
    let n = 64;
    let mut t = String::new();
    let mut noise_rms = 0.0;
    for i in 0..n {
        let a = i as f64 / n as f64 * std::f64::consts::TAU;
        let e = 0.03 * (2.0 * rng.next_f64() - 1.0);
        noise_rms += e * e;
        t += &format!("{},{}\n", (1.0 + e) * a.cos(), (1.0 + e) * a.sin());
    }
    std::fs::write(d.join("c.csv"), t).unwrap();
    let o = mra(&[
        "denoise",
        s(&d.join("c.csv")),
        "--scheme",
        "chaikin",
        "-o",
        s(&d.join("o.csv")),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let back = mra::points::parse(&std::fs::read_to_string(d.join("o.csv")).unwrap()).unwrap();
    assert_eq!((back.len(), back.dim), (n, 2));
    let dev = (back
        .data
        .chunks(2)
        .map(|p| (p[0].hypot(p[1]) - 1.0).powi(2))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    // measured: 0.0147 → 0.0110
    let noise = (noise_rms / n as f64).sqrt();
    assert!(
        dev < 0.85 * noise,
        "rms distance from the circle {noise} → {dev}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn zigzag_style_on_a_circle_keeps_the_circle_coarse_and_the_zigzag_fine() {
    use mra::scheme::{analyze_lane, Boundary};
    // style: a zig-zag of amplitude 0.5 along a straight stroke
    let m = 258;
    let amp = 0.5;
    let style: Vec<f64> = (0..m)
        .flat_map(|i| [i as f64 * 0.2, if i % 2 == 0 { amp } else { -amp }])
        .collect();
    // base: a circle of radius 10 (open: first point repeated at the end)
    let base: Vec<f64> = (0..=64)
        .flat_map(|i| {
            let t = i as f64 / 64.0 * std::f64::consts::TAU;
            [10.0 * t.cos(), 10.0 * t.sin()]
        })
        .collect();
    let levels = 3;
    let out = mra::style::transfer_style(&style, &base, Scheme::Chaikin, levels, false).unwrap();
    assert_eq!(out.len(), style.len());
    // coarse levels: the circle (the result's coarse curve lies on radius 10)
    let (packed, plan) =
        analyze_lane(&out, 2, Scheme::Chaikin, Boundary::Interpolating, levels).unwrap();
    let n = plan.lengths[levels];
    for q in packed[..2 * n].chunks(2).skip(1).take(n - 2) {
        let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
        assert!((r - 10.0).abs() < 0.6, "coarse radius {r}");
    }
    // fine levels: the style's amplitude (finest details as large as the style's)
    let rms = |p: &[f64], r: std::ops::Range<usize>| {
        (p[2 * r.start..2 * r.end].iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt()
    };
    let (sp, splan) =
        analyze_lane(&style, 2, Scheme::Chaikin, Boundary::Interpolating, levels).unwrap();
    let (a, b) = (
        rms(&packed, plan.detail_range(1)),
        rms(&sp, splan.detail_range(1)),
    );
    assert!((a / b - 1.0).abs() < 0.05, "{a} vs {b}");
    // and the zig-zag is visible on the result: radial deviations of the style's size
    let dev = (out
        .chunks(2)
        .map(|q| ((q[0] * q[0] + q[1] * q[1]).sqrt() - 10.0).powi(2))
        .sum::<f64>()
        / m as f64)
        .sqrt();
    assert!(dev > 0.4 * amp && dev < 2.0 * amp, "radial deviation {dev}");
}

#[test]
fn srtm_voids_are_filled_within_the_range_of_their_rims() {
    let Some(p) = common::corpus("terrain/N22W160.hgt") else {
        return;
    };
    let r = mra::io::read(&p).unwrap();
    let voids = mra::io::hgt::void_count(&r);
    assert!(voids > 0);
    let (g, filled) = mra::terrain::raster::to_grid(&r).unwrap();
    assert_eq!(filled, voids);
    let (lo, hi) = g.range();
    assert!(lo >= -34.0 && hi <= 1579.0, "{lo} … {hi}");
}

/// A generated volume: a smooth field plus `rough` × (a sum of short-wavelength waves
/// and deterministic white noise).
fn volume_of(n: usize, seed: u64, rough: f64) -> Volume {
    let mut rng = mra::generate::rng::SplitMix64::new(seed);
    let waves: Vec<[f64; 4]> = (0..12)
        .map(|_| {
            [
                0.3 + 1.2 * rng.next_f64(),
                rng.next_f64(),
                rng.next_f64(),
                6.3 * rng.next_f64(),
            ]
        })
        .collect();
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (zf, yf, xf) = (z as f64, y as f64, x as f64);
                let smooth = 100.0 * (xf / 9.0).sin() * (yf / 11.0).cos() + 60.0 * (zf / 8.0).sin();
                let fine: f64 = waves
                    .iter()
                    .map(|w| (w[0] * (xf + w[1] * yf + w[2] * zf) + w[3]).sin())
                    .sum::<f64>()
                    + 3.0 * (rng.next_f64() - 0.5);
                data.push(smooth + rough * fine);
            }
        }
    }
    Volume::new([n, n, n], 1, data).unwrap()
}

/// Standard deviation of the 7-point Laplacian of a volume (interior).
fn roughness3(v: &Volume) -> f64 {
    let [d, h, w] = v.dims();
    let at = |z: usize, y: usize, x: usize| v.data()[(z * h + y) * w + x];
    let mut s = Vec::new();
    for z in 1..d - 1 {
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                s.push(
                    at(z - 1, y, x)
                        + at(z + 1, y, x)
                        + at(z, y - 1, x)
                        + at(z, y + 1, x)
                        + at(z, y, x - 1)
                        + at(z, y, x + 1)
                        - 6.0 * at(z, y, x),
                );
            }
        }
    }
    let m = s.iter().sum::<f64>() / s.len() as f64;
    (s.iter().map(|x| (x - m).powi(2)).sum::<f64>() / s.len() as f64).sqrt()
}

fn minus(a: &Volume, b: &Volume) -> Volume {
    let d = a.data().iter().zip(b.data()).map(|(x, y)| x - y).collect();
    Volume::new(a.dims(), a.c(), d).unwrap()
}

#[test]
fn volume_transfer_keeps_the_base_coarse_and_takes_the_examples_fine_texture() {
    let base = volume_of(40, 1, 0.0);
    let ex = volume_of(48, 2, 4.0);
    let o = |details: Details, seed: u64| SynthOptions {
        levels: 2,
        patch: 6,
        seed,
        details,
        ..SynthOptions::default()
    };
    let (v, rep) = transfer_volume(&base, &ex, &o(Details::Matched, 5)).unwrap();
    assert_eq!(v.dims(), [40, 40, 40]);
    assert_eq!(rep.patches.len(), 2);
    // A Q = 0: the base's coarse points come back exactly
    let (cb, cv) = (
        coarse_points(&base, Scheme::Chaikin, 2).unwrap(),
        coarse_points(&v, Scheme::Chaikin, 2).unwrap(),
    );
    let err = cb
        .data()
        .iter()
        .zip(cv.data())
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(err < 1e-9, "coarse points moved by {err}");
    // fine texture: the finest levels (result minus subdivision alone) are as rough as
    // the example's finest levels; the base had none
    let (none, _) = transfer_volume(&base, &ex, &o(Details::None, 5)).unwrap();
    let (ex_low, _) = transfer_volume(&ex, &ex, &o(Details::None, 5)).unwrap();
    let ratio = roughness3(&minus(&v, &none)) / roughness3(&minus(&ex, &ex_low));
    assert!(
        (ratio - 1.0).abs() < 0.15,
        "finest-level roughness ratio {ratio}"
    );
    assert!(roughness3(&v) > 5.0 * roughness3(&base));
    assert!(
        (0.8..1.25).contains(&rep.seam_ratio),
        "seam ratio {}",
        rep.seam_ratio
    );
    // determinism
    let (again, _) = transfer_volume(&base, &ex, &o(Details::Matched, 5)).unwrap();
    let (other, _) = transfer_volume(&base, &ex, &o(Details::Matched, 6)).unwrap();
    assert!(again.data() == v.data());
    assert!(other.data() != v.data());
    // an example too small for the patch window at the coarsest level
    let small = volume_of(16, 3, 4.0);
    let e = transfer_volume(&base, &small, &o(Details::Matched, 5)).unwrap_err();
    assert!(e.to_string().contains("example"), "{e}");
}

#[test]
fn cli_transfer_on_nrrd_volumes() {
    let d = tmpdir("vol");
    let write = |v: &Volume, p: &std::path::Path| {
        let samples = mra::io::Samples::F32(v.data().iter().map(|&x| x as f32).collect());
        let r =
            mra::io::Raster::new(v.dims().to_vec(), 1, samples, mra::io::DataKind::Volume).unwrap();
        mra::io::write(p, &r).unwrap();
    };
    let (b, e, out) = (d.join("base.nrrd"), d.join("ex.nrrd"), d.join("out.nrrd"));
    write(&volume_of(36, 1, 0.0), &b);
    write(&volume_of(48, 2, 4.0), &e);
    let o = mra(&[
        "transfer",
        "--from",
        s(&e),
        "--to",
        s(&b),
        "-o",
        s(&out),
        "--patch",
        "6",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rep: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(rep["dims"], serde_json::json!([36, 36, 36]));
    let r = mra::io::read(&out).unwrap();
    assert_eq!(r.dims, vec![36, 36, 36]);
    // a 2-D example for a volume base: one line, exit 2, no output
    let img = d.join("img.png");
    assert!(
        mra(&["generate", "zone-plate", "--size", "64", "-o", s(&img)])
            .status
            .success()
    );
    let bad = d.join("bad.nrrd");
    let o = mra(&["transfer", "--from", s(&img), "--to", s(&b), "-o", s(&bad)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&o.stderr).trim().lines().count(), 1);
    assert!(!bad.exists());
}

/// The output's 4×4 block means lie on the base (back-projection), and the result is the
/// same bytes on one thread as on two.
#[test]
fn block_means_of_the_result_keep_the_base_and_threads_do_not_change_the_bytes() {
    let base = smooth_base(48, 5);
    let ex = grid_of(192, 192, 11, 0.6, 1000.0);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| synthesize(&base, &ex, &opts(4)).unwrap())
    };
    let (one, rep) = run(1);
    let (two, _) = run(2);
    assert_eq!(one.data(), two.data());
    let means = mra::terrain::synth::block_means(&one, 48, 48, (4, 4));
    let p = psnr(&means, &base);
    assert!(p >= 40.0, "block-mean PSNR {p:.1} dB");
    assert!((rep.fidelity_psnr.unwrap() - p).abs() < 1e-6);
}

/// An example with cells 3 times the output's is resampled to the output's cell first:
/// the result has the roughness of the example at that cell, not of the example as stored.
#[test]
fn example_cell_is_matched_to_the_output_cell() {
    let base = smooth_base(48, 5);
    let fine = grid_of(192, 192, 11, 0.6, 1000.0);
    let coarse_cells = mra::terrain::synth::example_at_scale(&fine, 1.0 / 3.0).unwrap();
    assert_eq!((coarse_cells.h(), coarse_cells.w()), (64, 64));
    // the same terrain stored at a third of the resolution, declared as such
    let big = mra::terrain::synth::example_at_scale(&coarse_cells, 3.0).unwrap();
    assert_eq!((big.h(), big.w()), (192, 192));
    let o = SynthOptions {
        example_scale: 1.0 / 3.0,
        ..opts(2)
    };
    let (a, _) = synthesize(&base, &big, &o).unwrap();
    let (b, _) = synthesize(&base, &big, &opts(2)).unwrap();
    let ehp = roughness(&highpass(&example_at(&big, 1.0 / 3.0), Scheme::Chaikin, 2).unwrap());
    let ra = roughness(&highpass(&a, Scheme::Chaikin, 2).unwrap()) / ehp;
    let rb = roughness(&highpass(&b, Scheme::Chaikin, 2).unwrap()) / ehp;
    assert!(
        (ra - 1.0).abs() < 0.25,
        "scaled example: roughness ratio {ra}"
    );
    assert!(
        (rb - 1.0).abs() > (ra - 1.0).abs(),
        "unscaled {rb} vs scaled {ra}"
    );
}

fn example_at(g: &Grid, s: f64) -> Grid {
    mra::terrain::synth::example_at_scale(g, s).unwrap()
}

/// `terrain synth` writes the output on the base's cells split in 2^L (cell-centred):
/// spacing × n/M, the ASCII grid's lower-left corner kept, heights in the base's unit.
#[test]
fn cli_synth_output_keeps_the_extent_and_splits_the_cells() {
    let d = tmpdir("synth-meta");
    let grid = |p: &std::path::Path, cell: f64, n: usize, seed: u64| {
        let g = grid_of(n, n, seed, 0.6, 300.0);
        let mut t =
            format!("ncols {n}\nnrows {n}\nxllcorner 500\nyllcorner 1000\ncellsize {cell}\n");
        for y in 0..n {
            let row: Vec<String> = (0..n).map(|x| format!("{:.2}", g.at(y, x, 0))).collect();
            t += &(row.join(" ") + "\n");
        }
        std::fs::write(p, t).unwrap();
    };
    let (b, e, out) = (d.join("b.asc"), d.join("e.asc"), d.join("out.asc"));
    grid(&b, 40.0, 48, 3);
    grid(&e, 10.0, 160, 9);
    let o = mra(&[
        "terrain",
        "synth",
        "--base",
        s(&b),
        "--example",
        s(&e),
        "-o",
        s(&out),
        "--levels",
        "2",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (rb, ro) = (mra::io::read(&b).unwrap(), mra::io::read(&out).unwrap());
    assert_eq!(ro.dims, vec![192, 192]);
    let (sb, so) = (rb.meta.spacing.unwrap(), ro.meta.spacing.unwrap());
    assert!((so[1] - sb[1] / 4.0).abs() < 1e-9, "{so:?} vs {sb:?}");
    for k in ["asc.xllcorner", "asc.yllcorner"] {
        let (x, y) = (&rb.meta.extra[k], &ro.meta.extra[k]);
        let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
        assert!((x - y).abs() < 1e-6, "{k}: {x} vs {y}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// The JSON report of `terrain synth` gives its extents fastest axis first (x, y), as
/// every other command does: a 48 wide, 32 high base makes a report `dims` of
/// `[width, height]` matching the output file's.
#[test]
fn synth_json_reports_extents_fastest_axis_first() {
    let d = tmpdir("json_axes");
    let (base, ex, out) = (d.join("base.png"), d.join("ex.png"), d.join("out.tif"));
    for (p, size) in [(&base, "48x32"), (&ex, "192x192")] {
        let o = mra(&["generate", "terrain", "--size", size, "-o", s(p)]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let b = mra::io::read(&base).unwrap();
    assert_eq!(b.dims, vec![32, 48], "a 48 wide, 32 high base");
    let o = mra(&[
        "terrain",
        "synth",
        "--base",
        s(&base),
        "--example",
        s(&ex),
        "-o",
        s(&out),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rep: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let r = mra::io::read(&out).unwrap();
    let (h, w) = (r.dims[0] as u64, r.dims[1] as u64);
    assert!(w > h, "{:?}", r.dims);
    assert_eq!(rep["dims"], serde_json::json!([w, h]));
    assert_eq!(rep["axis_order"], "x, y, z (fastest first)");
    let c = rep["coarse"].as_array().unwrap();
    assert!(c[0].as_u64().unwrap() > c[1].as_u64().unwrap(), "{rep}");
}

/// RMS of `a − b` over columns `[x0, x1)` (all rows).
fn rms_diff_cols(a: &Grid, b: &Grid, x0: usize, x1: usize) -> f64 {
    let mut s = 0.0;
    for y in 0..a.h() {
        for x in x0..x1 {
            s += (a.at(y, x, 0) - b.at(y, x, 0)).powi(2);
        }
    }
    (s / (a.h() * (x1 - x0)) as f64).sqrt()
}

/// A base whose left third is a flat sea: with the relief gain the sea gets next to no
/// detail while the hills keep theirs; without it (cap 0) the sea gets the example's.
#[test]
fn flat_ground_gets_no_mountain_detail_with_the_relief_gain() {
    let mut base = smooth_base(48, 5);
    for y in 0..48 {
        for x in 0..16 {
            *base.at_mut(y, x, 0) = 0.0;
        }
    }
    let ex = grid_of(192, 192, 9, 0.6, 1000.0);
    let detail = |cap: f64| {
        let o = SynthOptions {
            relief_cap: cap,
            ..opts(3)
        };
        let (g, _) = synthesize(&base, &ex, &o).unwrap();
        let none = SynthOptions {
            details: Details::None,
            ..o
        };
        let (g0, _) = synthesize(&base, &ex, &none).unwrap();
        // the sea away from its coast (output columns 0..24; the coast is at 64) and the
        // hills (96..192)
        (
            rms_diff_cols(&g, &g0, 0, 24),
            rms_diff_cols(&g, &g0, 96, 192),
        )
    };
    let (sea_on, land_on) = detail(1.0);
    let (sea_off, land_off) = detail(0.0);
    assert!(land_on > 0.0 && land_off > 0.0);
    assert!(
        sea_on < 0.15 * land_on,
        "with the gain: sea {sea_on:.3} against hills {land_on:.3}"
    );
    assert!(
        sea_off > 0.3 * land_off,
        "without the gain: sea {sea_off:.3} against hills {land_off:.3}"
    );
    // a bad cap is an error, not a panic
    let bad = SynthOptions {
        relief_cap: f64::NAN,
        ..opts(3)
    };
    assert!(synthesize(&base, &ex, &bad).is_err());
}

/// The finest details' gain is fitted so that the result's spectral slope over its finest
/// octave is the example's; a fixed gain away from it misses (no back-projection here:
/// the output size is not a multiple of the base's).
#[test]
fn fitted_finest_gain_gives_the_result_the_examples_spectral_slope() {
    use mra::terrain::spectrum::spectral_slope;
    use mra::terrain::FinestGain;
    let base = smooth_base(40, 3);
    let ex = grid_of(200, 200, 9, 0.6, 1000.0);
    let want = spectral_slope(ex.data(), ex.h(), ex.w());
    let o = SynthOptions {
        size: Some((158, 158)),
        ..opts(2)
    };
    let (fit, report) = synthesize(&base, &ex, &o).unwrap();
    assert_eq!(report.example_spectral_slope, Some(want));
    assert!((0.5..=2.0).contains(&report.finest_gain));
    let got = spectral_slope(fit.data(), fit.h(), fit.w());
    assert!(
        (got - want).abs() < 0.03,
        "slope {got:.3}, example {want:.3}"
    );
    for g in [0.5, 2.0] {
        let fixed = SynthOptions {
            finest_gain: FinestGain::Fixed(g),
            ..o.clone()
        };
        let (r, rep) = synthesize(&base, &ex, &fixed).unwrap();
        assert_eq!(rep.finest_gain, g);
        let off = spectral_slope(r.data(), r.h(), r.w());
        assert!(
            (off - want).abs() > 5.0 * (got - want).abs().max(0.01),
            "gain {g}: slope {off:.3}, example {want:.3}"
        );
    }
    // the same bytes for a seed
    assert_eq!(synthesize(&base, &ex, &o).unwrap().0.data(), fit.data());
}
