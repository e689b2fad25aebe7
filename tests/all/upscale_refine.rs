//! The area mode's overshoot clamping (src/upscale/refine.rs) and nodata handling
//! (src/upscale/voids.rs): invariants on generated data.

use mra::io::{DataKind, Raster, SampleType};
use mra::progress::Progress;
use mra::scheme::subdivide::Refinement;
use mra::upscale::{
    refine, upscale_array, upscale_raster, AxisPlan, Clamp, Edge, Geometry, Method, Mode,
};

use super::common;

fn method(rule: Refinement, clamp: Clamp) -> Method {
    Method {
        rule,
        mode: Mode::Area,
        edge: Edge::Linear,
        order: None,
        clamp,
    }
}

fn plans(shape: &[usize], f: &[usize]) -> Vec<AxisPlan> {
    (0..shape.len())
        .map(|a| AxisPlan {
            axis: a,
            len: shape[a] * f[a],
            geometry: Geometry::Centre,
        })
        .collect()
}

fn grid(h: usize, w: usize, f: impl Fn(f64, f64) -> f64) -> Vec<f32> {
    (0..h * w)
        .map(|i| f((i / w) as f64, (i % w) as f64) as f32)
        .collect()
}

/// Block means of a 2-D array by (fy, fx).
fn block_mean(v: &[f32], h: usize, w: usize, fy: usize, fx: usize) -> Vec<f32> {
    let (ch, cw) = (h / fy, w / fx);
    let mut out = vec![0f32; ch * cw];
    for y in 0..ch * fy {
        for x in 0..cw * fx {
            out[(y / fy) * cw + x / fx] += v[y * w + x] / (fy * fx) as f32;
        }
    }
    out
}

/// A test image with hard edges and texture: a disc, a bar, a ramp and ripples.
fn scene(h: usize, w: usize) -> Vec<f32> {
    grid(h, w, |y, x| {
        let disc = if (y - 20.0).powi(2) + (x - 22.0).powi(2) < 150.0 {
            180.0
        } else {
            40.0
        };
        let bar = if (x - 45.0).abs() < 3.0 { 60.0 } else { 0.0 };
        disc + bar + 0.5 * y + 10.0 * (0.9 * x + 0.4 * y).sin()
    })
}

fn psnr(a: &[f32], b: &[f32]) -> f64 {
    let mse = a
        .iter()
        .zip(b)
        .map(|(a, b)| ((a - b) as f64).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    10.0 * (255.0f64 * 255.0 / mse).log10()
}

#[test]
fn clamping_keeps_constants_exactly() {
    for clamp in [Clamp::On, Clamp::Auto] {
        for rule in [Refinement::Chaikin, Refinement::Cubic] {
            for (shape, f) in [
                (vec![9usize, 13], vec![2usize, 2]),
                (vec![8, 12], vec![4, 4]),
                (vec![6, 5, 7], vec![2, 2, 2]),
                (vec![7, 9], vec![6, 2]),
                (vec![5, 8], vec![1, 8]),
            ] {
                let n: usize = shape.iter().product();
                let (out, s) = upscale_array(
                    vec![-7.25; n],
                    &shape,
                    &method(rule, clamp),
                    &plans(&shape, &f),
                )
                .unwrap();
                assert_eq!(s.iter().product::<usize>(), out.len());
                let worst = out.iter().map(|v| (v + 7.25).abs()).fold(0.0, f32::max);
                assert!(worst < 1e-4, "{clamp:?} {rule:?} {shape:?} ×{f:?}: {worst}");
            }
        }
    }
}

#[test]
fn clamping_keeps_the_block_means() {
    let (h, w) = (24, 32);
    let data = scene(h, w);
    for clamp in [Clamp::On, Clamp::Auto] {
        for f in [[2usize, 2], [4, 4], [8, 8], [6, 4], [2, 1]] {
            let (out, s) = upscale_array(
                data.clone(),
                &[h, w],
                &method(Refinement::Chaikin, clamp),
                &plans(&[h, w], &f),
            )
            .unwrap();
            let back = block_mean(&out, s[0], s[1], f[0], f[1]);
            let worst = back
                .iter()
                .zip(&data)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max);
            assert!(worst < 2e-3, "{clamp:?} ×{f:?}: {worst}");
        }
    }
}

#[test]
fn clamping_leaves_a_ramp_linear() {
    // the ranges beyond the ends follow the edge rule, so lines are not clipped
    let (h, w) = (11, 14);
    let ramp = |y: f64, x: f64| 3.0 + 0.7 * x - 1.3 * y;
    let data = grid(h, w, ramp);
    for f in [2usize, 4] {
        let (out, s) = upscale_array(
            data.clone(),
            &[h, w],
            &method(Refinement::Chaikin, Clamp::On),
            &plans(&[h, w], &[f, f]),
        )
        .unwrap();
        let pos = |j: usize| (j as f64 + 0.5) / f as f64 - 0.5;
        let worst = (0..out.len())
            .map(|i| (out[i] as f64 - ramp(pos(i / s[1]), pos(i % s[1]))).abs())
            .fold(0.0, f64::max);
        assert!(worst < 2e-4, "×{f}: {worst}");
    }
}

#[test]
fn clamping_reduces_overshoot_and_error_on_edges() {
    // degrade a scene with hard edges by exact block means; the clamped result is closer
    let (h, w) = (64, 64);
    let truth = scene(h, w);
    for f in [2usize, 4] {
        let low = block_mean(&truth, h, w, f, f);
        let (lh, lw) = (h / f, w / f);
        let run = |clamp| {
            upscale_array(
                low.clone(),
                &[lh, lw],
                &method(Refinement::Chaikin, clamp),
                &plans(&[lh, lw], &[f, f]),
            )
            .unwrap()
            .0
        };
        let (off, on, auto) = (run(Clamp::Off), run(Clamp::On), run(Clamp::Auto));
        let (lo, hi) = low
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        let over = |u: &[f32]| {
            u.iter()
                .map(|&v| (lo - v).max(v - hi).max(0.0))
                .fold(0.0, f32::max)
        };
        assert!(
            over(&on) < over(&off),
            "×{f}: {} vs {}",
            over(&on),
            over(&off)
        );
        let (p_off, p_on, p_auto) = (psnr(&off, &truth), psnr(&on, &truth), psnr(&auto, &truth));
        assert!(p_on > p_off + 0.1, "×{f}: on {p_on} off {p_off}");
        assert!(p_auto > p_off + 0.1, "×{f}: auto {p_auto} off {p_off}");
    }
}

#[test]
fn learned_weight_prefers_clamping_on_edges_not_on_smooth_data() {
    let m = method(Refinement::Chaikin, Clamp::Auto);
    let f = [(0usize, 4usize), (1, 4)];
    let (h, w) = (64, 64);
    let t_edges = refine::learn_weight(&scene(h, w), &[h, w], &m, &f)
        .unwrap()
        .unwrap();
    let smooth = grid(h, w, |y, x| 100.0 * (x / 9.0).sin() * (y / 11.0).cos());
    let t_smooth = refine::learn_weight(&smooth, &[h, w], &m, &f)
        .unwrap()
        .unwrap();
    assert!((0.0..=1.0).contains(&t_edges) && (0.0..=1.0).contains(&t_smooth));
    assert!(t_edges > 0.5, "edges: {t_edges}");
    assert!(t_smooth < t_edges, "smooth {t_smooth} edges {t_edges}");
    // too small to learn from one level up
    assert!(refine::learn_weight(&[1.0; 12], &[3, 4], &m, &f)
        .unwrap()
        .is_none());
}

fn heightmap(h: usize, w: usize) -> Vec<f32> {
    grid(h, w, |y, x| {
        800.0 + 120.0 * (x / 7.0).sin() + 90.0 * (y / 5.0).cos() + 2.0 * x
    })
}

#[test]
fn srtm_voids_are_filled_for_the_computation_and_kept_in_the_output() {
    let (h, w) = (40, 48);
    let truth = heightmap(h, w);
    let void =
        |y: usize, x: usize| (12..19).contains(&y) && (20..26).contains(&x) || (y, x) == (0, 0);
    let mut data = truth.clone();
    for y in 0..h {
        for x in 0..w {
            if void(y, x) {
                data[y * w + x] = -32768.0;
            }
        }
    }
    for f in [2usize, 4] {
        for clamp in [Clamp::Off, Clamp::Auto] {
            let mut r =
                Raster::from_f32(vec![h, w], 1, &data, SampleType::I16, DataKind::Heightmap)
                    .unwrap();
            r.meta.nodata = Some(-32768.0);
            let m = method(Refinement::Chaikin, clamp);
            let out = upscale_raster(r, &m, &plans(&[h, w], &[f, f]), &Progress::hidden()).unwrap();
            assert_eq!(out.dims, vec![h * f, w * f]);
            assert_eq!(out.meta.nodata, Some(-32768.0));
            let (oh, ow) = (h * f, w * f);
            let mut worst = 0.0f64;
            for y in 0..oh {
                for x in 0..ow {
                    let v = out.samples.get_f64(y * ow + x);
                    // nearest old cell of new sample j is j / f
                    if void(y / f, x / f) {
                        assert_eq!(v, -32768.0, "×{f} ({y}, {x}) should be void");
                    } else {
                        assert!(v > 0.0, "×{f} ({y}, {x}) = {v}: the void leaked");
                        let (yy, xx) = (
                            (y as f64 + 0.5) / f as f64 - 0.5,
                            (x as f64 + 0.5) / f as f64 - 0.5,
                        );
                        let t =
                            800.0 + 120.0 * (xx / 7.0).sin() + 90.0 * (yy / 5.0).cos() + 2.0 * xx;
                        worst = worst.max((v - t).abs());
                    }
                }
            }
            // next to the void the fill is coarse, but nothing like the 33 000 m of a
            // void taken as a height
            assert!(worst < 45.0, "×{f} {clamp:?}: {worst}");
        }
    }
}

#[test]
fn nan_voids_stay_nan_and_do_not_spread() {
    let (h, w) = (16, 16);
    let mut data = heightmap(h, w);
    data[5 * w + 7] = f32::NAN;
    let r = Raster::from_f32(vec![h, w], 1, &data, SampleType::F32, DataKind::Heightmap).unwrap();
    let m = Method::default();
    let out = upscale_raster(r, &m, &plans(&[h, w], &[2, 2]), &Progress::hidden()).unwrap();
    let nan: Vec<usize> = (0..out.samples.len())
        .filter(|&i| out.samples.get_f64(i).is_nan())
        .collect();
    let want: Vec<usize> = [10usize, 11]
        .iter()
        .flat_map(|&y| [14usize, 15].map(|x| y * 32 + x))
        .collect();
    assert_eq!(nan, want);
}

#[test]
fn corpus_srtm_tile_keeps_its_voids() {
    let Some(path) = common::corpus("terrain/N22W160.hgt") else {
        return;
    };
    let r = mra::io::read(&path).unwrap();
    let nd = r.meta.nodata.expect("SRTM nodata");
    let n = r.dims.clone();
    let voids: Vec<bool> = (0..r.samples.len())
        .map(|i| r.samples.get_f64(i) == nd)
        .collect();
    let count = voids.iter().filter(|&&v| v).count();
    assert!(count > 0, "the tile has voids");
    let valid_min = (0..r.samples.len())
        .filter(|&i| !voids[i])
        .map(|i| r.samples.get_f64(i))
        .fold(f64::MAX, f64::min);
    let out = upscale_raster(
        r,
        &Method::default(),
        &plans(&n, &[2, 2]),
        &Progress::hidden(),
    )
    .unwrap();
    let w2 = n[1] * 2;
    let mut out_min = f64::MAX;
    for i in 0..out.samples.len() {
        let v = out.samples.get_f64(i);
        let (y, x) = (i / w2, i % w2);
        assert_eq!(v == nd, voids[(y / 2) * n[1] + x / 2], "({y}, {x}) = {v}");
        if v != nd {
            out_min = out_min.min(v);
        }
    }
    // a void read as −32768 m would drag its neighbours down by hundreds of metres
    assert!(out_min > valid_min - 100.0, "{out_min} vs {valid_min}");
}

#[test]
fn cli_clamp_choices_and_a_bad_one() {
    let dir = std::env::temp_dir().join(format!("mra_upscale_clamp_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = dir.join("in.tif");
    let (h, w) = (24, 32);
    let data = scene(h, w);
    let r = Raster::from_f32(vec![h, w], 1, &data, SampleType::F32, DataKind::Image).unwrap();
    mra::io::write(&src, &r).unwrap();
    let run = |clamp: &str, out: &std::path::Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_mra"))
            .args([
                "upscale",
                src.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ])
            .args(["--factor", "2", "--clamp", clamp])
            .output()
            .unwrap()
    };
    let mut outs = Vec::new();
    for c in ["off", "on", "auto"] {
        let p = dir.join(format!("up_{c}.tif"));
        assert!(run(c, &p).status.success(), "--clamp {c}");
        let o = mra::io::read(&p).unwrap();
        assert_eq!(o.dims, vec![2 * h, 2 * w]);
        outs.push(o.to_f32());
    }
    // the library's result, and clamping changes it
    let lib = upscale_array(
        data.clone(),
        &[h, w],
        &method(Refinement::Chaikin, Clamp::On),
        &plans(&[h, w], &[2, 2]),
    )
    .unwrap()
    .0;
    assert_eq!(outs[1], lib);
    assert_ne!(outs[0], outs[1]);
    let bad = run("sometimes", &dir.join("bad.tif"));
    assert_eq!(bad.status.code(), Some(2));
    assert!(!dir.join("bad.tif").exists());
    std::fs::remove_dir_all(&dir).ok();
}
