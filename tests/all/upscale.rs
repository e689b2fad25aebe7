//! Upscaling and downscaling (src/upscale): invariants on generated data, geometry,
//! sample types, errors, and the command line.

use mra::io::{DataKind, Raster, SampleType, Samples};
use mra::progress::Progress;
use mra::scheme::subdivide::Refinement;
use mra::scheme::{Boundary, Scheme};
use mra::upscale::{
    self, downscale_array, plan_raster, upscale_array, upscale_raster, AxisPlan, Clamp, Edge,
    Geometry, Method, Mode,
};
use mra::ErrorKind;

use super::common;

const MODES: [Mode; 3] = [Mode::Area, Mode::Interpolate, Mode::Control];

fn method(rule: Refinement, mode: Mode) -> Method {
    Method {
        rule,
        mode,
        edge: Edge::Linear,
        order: None,
        clamp: Clamp::Off,
    }
}

fn centre_plans(shape: &[usize], f: usize) -> Vec<AxisPlan> {
    (0..shape.len())
        .map(|a| AxisPlan {
            axis: a,
            len: shape[a] * f,
            geometry: Geometry::Centre,
        })
        .collect()
}

fn grid(h: usize, w: usize, f: impl Fn(f64, f64) -> f64) -> Vec<f32> {
    let mut v = Vec::with_capacity(h * w);
    for y in 0..h {
        for x in 0..w {
            v.push(f(y as f64, x as f64) as f32);
        }
    }
    v
}

#[test]
fn constant_stays_constant_every_rule_mode_and_edge() {
    for rule in Refinement::ALL {
        for mode in MODES {
            for edge in [Edge::Linear, Edge::Mirror] {
                let m = Method {
                    edge,
                    ..method(rule, mode)
                };
                for (shape, f) in [
                    (vec![9usize, 13], 2usize),
                    (vec![5, 4, 6], 4),
                    (vec![1, 7], 2),
                ] {
                    let n: usize = shape.iter().product();
                    let (out, s) =
                        upscale_array(vec![42.5; n], &shape, &m, &centre_plans(&shape, f)).unwrap();
                    assert_eq!(s, shape.iter().map(|x| x * f).collect::<Vec<_>>());
                    let worst = out.iter().map(|v| (v - 42.5).abs()).fold(0.0, f32::max);
                    assert!(
                        worst < 1e-4,
                        "{rule:?} {mode:?} {edge:?} {shape:?}: {worst}"
                    );
                }
            }
        }
    }
}

#[test]
fn linear_ramp_stays_linear_to_the_edges() {
    // f(y, x) = 3 + 0.7 x − 1.3 y; new sample j of an ×F axis sits at (j + ½)/F − ½
    let (h, w) = (11, 17);
    let ramp = |y: f64, x: f64| 3.0 + 0.7 * x - 1.3 * y;
    let data = grid(h, w, ramp);
    for rule in Refinement::ALL {
        if rule == Refinement::Box {
            continue; // piecewise constant: reproduces constants only
        }
        for mode in MODES {
            for f in [2usize, 4, 3] {
                let shape = [h, w];
                let (out, s) = upscale_array(
                    data.clone(),
                    &shape,
                    &method(rule, mode),
                    &centre_plans(&shape, f),
                )
                .unwrap();
                let pos = |j: usize| (j as f64 + 0.5) / f as f64 - 0.5;
                let mut worst = 0.0f64;
                for y in 0..s[0] {
                    for x in 0..s[1] {
                        let e = (out[y * s[1] + x] as f64 - ramp(pos(y), pos(x))).abs();
                        worst = worst.max(e);
                    }
                }
                assert!(worst < 2e-4, "{rule:?} {mode:?} ×{f}: {worst}");
            }
        }
    }
}

#[test]
fn interpolating_modes_pass_through_the_samples() {
    // vertex geometry (time axis): old frames land on new frames 0, F, 2F, …
    let shape = [6usize, 5, 4];
    let data: Vec<f32> = (0..120).map(|i| ((i * 37) % 11) as f32).collect();
    for rule in [
        Refinement::Chaikin,
        Refinement::Cubic,
        Refinement::Quartic,
        Refinement::FourPoint,
    ] {
        let m = method(rule, Mode::Interpolate);
        let plans = plan_raster(&shape, &[0], Some(2), None, true).unwrap();
        assert_eq!(plans[0].geometry, Geometry::Vertex);
        let (out, s) = upscale_array(data.clone(), &shape, &m, &plans).unwrap();
        assert_eq!(s, vec![11, 5, 4]);
        for t in 0..6 {
            for k in 0..20 {
                let e = (out[(2 * t) * 20 + k] - data[t * 20 + k]).abs();
                assert!(e < 1e-4, "{rule:?} frame {t}: {e}");
            }
        }
    }
}

#[test]
fn area_mode_averages_back_to_the_input() {
    let (h, w) = (12, 10);
    let data = grid(h, w, |y, x| {
        (x * 1.7 + y * 0.3).sin() * 50.0 + (x * y) % 7.0
    });
    for f in [2usize, 4] {
        let shape = [h, w];
        let (out, s) = upscale_array(
            data.clone(),
            &shape,
            &method(Refinement::Cubic, Mode::Area),
            &centre_plans(&shape, f),
        )
        .unwrap();
        let mut worst = 0.0f32;
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0f32;
                for dy in 0..f {
                    for dx in 0..f {
                        acc += out[(y * f + dy) * s[1] + x * f + dx];
                    }
                }
                worst = worst.max((acc / (f * f) as f32 - data[y * w + x]).abs());
            }
        }
        assert!(worst < 1e-3, "×{f}: {worst}");
    }
}

/// Intensity-weighted centroid (y, x) of a 2-D array.
fn centroid(v: &[f32], h: usize, w: usize) -> (f64, f64) {
    let (mut s, mut sy, mut sx) = (0.0f64, 0.0f64, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let a = v[y * w + x] as f64;
            s += a;
            sy += a * y as f64;
            sx += a * x as f64;
        }
    }
    (sy / s, sx / s)
}

#[test]
fn blob_centroid_is_preserved_to_a_hundredth_of_a_pixel() {
    let (h, w) = (40, 48);
    let (cy, cx) = (17.7, 20.3);
    let blob = grid(h, w, |y, x| {
        200.0 * (-((y - cy).powi(2) + (x - cx).powi(2)) / (2.0 * 3.0f64.powi(2))).exp()
    });
    let (by, bx) = centroid(&blob, h, w);
    for rule in Refinement::ALL {
        for mode in MODES {
            for f in [2usize, 4, 8] {
                let shape = [h, w];
                let (out, s) = upscale_array(
                    blob.clone(),
                    &shape,
                    &method(rule, mode),
                    &centre_plans(&shape, f),
                )
                .unwrap();
                let (ny, nx) = centroid(&out, s[0], s[1]);
                // new pixel j is centred at old coordinate (j + ½)/F − ½
                let back = |c: f64| (c + 0.5) / f as f64 - 0.5;
                let (dy, dx) = ((back(ny) - by).abs(), (back(nx) - bx).abs());
                assert!(dy < 0.01 && dx < 0.01, "{rule:?} {mode:?} ×{f}: {dy} {dx}");
            }
        }
    }
}

#[test]
fn downscale_then_upscale_of_a_smooth_function_is_close() {
    // f = sin(2π x/40) cos(2π y/56), amplitude 1, 256 × 256; one level down, ×2 back.
    let n = 256;
    let f = |y: f64, x: f64| {
        (std::f64::consts::TAU * x / 40.0).sin() * (std::f64::consts::TAU * y / 56.0).cos()
    };
    let data = grid(n, n, f);
    let shape = [n, n];
    // Haar's A is the 2×2 block mean, on the pixel-centre grid of the upscaler
    let (low, ls) = downscale_array(
        data.clone(),
        &shape,
        Scheme::Haar,
        Boundary::Symmetric,
        1,
        &[0, 1],
    )
    .unwrap();
    assert_eq!(ls, vec![128, 128]);
    let (up, us) = upscale_array(low, &ls, &Method::default(), &centre_plans(&ls, 2)).unwrap();
    assert_eq!(us, vec![256, 256]);
    let worst = up
        .iter()
        .zip(&data)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    // stated bound: max error < 1 % of the amplitude (measured 0.0071; area mode undoes
    // the box blur, periods of 40 and 56 samples)
    assert!(worst < 0.01, "max error {worst}");
}

#[test]
fn downscale_keeps_constants_and_halves_lengths() {
    for scheme in Scheme::ALL {
        let shape = [64usize, 48];
        let (out, s) = downscale_array(
            vec![7.0; 64 * 48],
            &shape,
            scheme,
            Boundary::Symmetric,
            2,
            &[0, 1],
        )
        .unwrap();
        assert!(s[0] < 20 && s[1] < 16, "{scheme:?} {s:?}");
        assert!(out.iter().all(|v| (v - 7.0).abs() < 1e-4), "{scheme:?}");
    }
}

fn raster(dims: Vec<usize>, channels: usize, data: &[f32], ty: SampleType) -> Raster {
    Raster::from_f32(dims, channels, data, ty, DataKind::Image).unwrap()
}

#[test]
fn sample_types_are_kept_rounded_and_clamped() {
    // a hard 0 → max edge overshoots in interpolate mode: integer outputs clamp, floats do not
    let (h, w) = (6, 10);
    let edge = grid(h, w, |_, x| if x < 5.0 { 0.0 } else { 1.0 });
    let m = method(Refinement::Cubic, Mode::Interpolate);
    let plans = centre_plans(&[h, w], 2);
    let (f32out, _) = upscale_array(edge.clone(), &[h, w], &m, &plans).unwrap();
    assert!(f32out.iter().any(|&v| v < 0.0) && f32out.iter().any(|&v| v > 1.0));
    for (ty, top) in [
        (SampleType::U8, 255.0f32),
        (SampleType::U16, 65535.0),
        (SampleType::I16, 32767.0),
        (SampleType::F16, 1000.0),
        (SampleType::F64, 1000.0),
    ] {
        let scaled: Vec<f32> = edge.iter().map(|v| v * top).collect();
        let r = raster(vec![h, w], 1, &scaled, ty);
        let out = upscale_raster(r, &m, &plans, &Progress::hidden()).unwrap();
        assert_eq!(out.sample_type(), ty);
        assert_eq!(out.dims, vec![12, 20]);
        for (i, &e) in f32out.iter().enumerate() {
            let want = match ty {
                SampleType::U8 | SampleType::U16 => (e * top).round().clamp(0.0, top) as f64,
                SampleType::I16 => (e * top).round().clamp(-32768.0, top) as f64,
                _ => (e * top) as f64,
            };
            let got = out.samples.get_f64(i);
            assert!(
                (got - want).abs() <= 0.51 + want.abs() * 1e-3,
                "{ty:?} {i}: {got} {want}"
            );
        }
    }
}

#[test]
fn rgb_channels_are_not_mixed_and_sizes_are_arbitrary() {
    let (h, w) = (7, 9);
    let mut d = Vec::new();
    for i in 0..h * w {
        d.extend_from_slice(&[10.0, 100.0 + (i % 3) as f32, 200.0]);
    }
    let r = raster(vec![h, w], 3, &d, SampleType::U8);
    let plans = plan_raster(&[h, w], &[0, 1], None, Some(&[11, 20]), false).unwrap();
    let out = upscale_raster(r, &Method::default(), &plans, &Progress::hidden()).unwrap();
    assert_eq!((out.dims.clone(), out.channels), (vec![11, 20], 3));
    if let Samples::U8(v) = &out.samples {
        for px in v.chunks(3) {
            assert_eq!(px[0], 10);
            assert_eq!(px[2], 200);
            assert!((99..=103).contains(&px[1]));
        }
    } else {
        panic!("u8 expected");
    }
}

#[test]
fn volume_axes_and_metadata() {
    let shape = [4usize, 6, 5];
    let data: Vec<f32> = (0..120).map(|i| i as f32).collect();
    let mut r =
        Raster::from_f32(shape.to_vec(), 1, &data, SampleType::I16, DataKind::Volume).unwrap();
    r.meta.spacing = Some(vec![3.0, 1.0, 1.0]);
    let (axes, time) = upscale::parse_axes("z", 3).unwrap();
    assert_eq!((axes.clone(), time), (vec![0], false));
    let plans = plan_raster(&shape, &axes, Some(4), None, false).unwrap();
    let out = upscale_raster(r, &Method::default(), &plans, &Progress::hidden()).unwrap();
    assert_eq!(out.dims, vec![16, 6, 5]);
    assert_eq!(out.meta.spacing, Some(vec![0.75, 1.0, 1.0]));
}

#[test]
fn bad_parameters_are_errors_not_panics() {
    let shape = [8usize, 8];
    let m = Method::default();
    let e = plan_raster(&shape, &[0, 1], Some(1), None, false).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Parameter);
    let e = plan_raster(&shape, &[0, 1], None, Some(&[3]), false).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Parameter);
    let e = plan_raster(&shape, &[0, 1], None, None, false).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Parameter);
    assert!(upscale::parse_axes("q", 2).is_err());
    assert!(upscale::parse_axes("z", 2).is_err());
    assert!(upscale::parse_axes("xx", 2).is_err());
    let kind = |r: mra::Result<(Vec<f32>, Vec<usize>)>| r.err().map(|e| e.kind());
    let e = upscale_array(vec![0.0; 10], &shape, &m, &centre_plans(&shape, 2));
    assert_eq!(kind(e), Some(ErrorKind::Parameter));
    let e = upscale_array(vec![0.0; 64], &shape, &m, &[]);
    assert_eq!(kind(e), Some(ErrorKind::Parameter));
    // area mode on a time axis is meaningless
    let plans = plan_raster(&[4, 8, 8], &[0], Some(2), None, true).unwrap();
    let e = upscale_array(vec![0.0; 256], &[4, 8, 8], &m, &plans);
    assert_eq!(kind(e), Some(ErrorKind::Parameter));
    // an absurd output size is refused before allocating
    let huge = [AxisPlan {
        axis: 0,
        len: 8 * 1024 + 1,
        geometry: Geometry::Centre,
    }];
    let e = upscale_array(vec![0.0; 64], &shape, &m, &huge);
    assert_eq!(kind(e), Some(ErrorKind::Parameter));
    let e = downscale_array(
        vec![0.0; 64],
        &shape,
        Scheme::Cubic,
        Boundary::Symmetric,
        0,
        &[0],
    );
    assert!(e.is_err());
    let e = downscale_array(
        vec![0.0; 64],
        &shape,
        Scheme::Cubic,
        Boundary::Symmetric,
        9,
        &[0],
    );
    assert!(e.is_err());
}

fn mra_bin() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_mra"))
}

#[test]
fn cli_upscale_downscale_and_one_line_errors() {
    let dir = std::env::temp_dir().join(format!("mra_upscale_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = dir.join("in.png");
    let data = grid(24, 32, |y, x| (x * 5.0 + y * 3.0) % 256.0);
    mra::io::write(&src, &raster(vec![24, 32], 1, &data, SampleType::U8)).unwrap();
    let up = dir.join("up.png");
    let st = mra_bin()
        .args([
            "upscale",
            src.to_str().unwrap(),
            "-o",
            up.to_str().unwrap(),
            "--factor",
            "4",
        ])
        .status()
        .unwrap();
    assert!(st.success());
    let r = mra::io::read(&up).unwrap();
    assert_eq!(
        (r.dims.clone(), r.sample_type()),
        (vec![96, 128], SampleType::U8)
    );
    let down = dir.join("down.png");
    let st = mra_bin()
        .args([
            "downscale",
            up.to_str().unwrap(),
            "-o",
            down.to_str().unwrap(),
            "--levels",
            "2",
            "--scheme",
            "haar",
        ])
        .status()
        .unwrap();
    assert!(st.success());
    assert_eq!(mra::io::read(&down).unwrap().dims, vec![24, 32]);
    for bad in [
        vec![
            "upscale",
            src.to_str().unwrap(),
            "-o",
            "x.png",
            "--factor",
            "1",
        ],
        vec![
            "upscale",
            src.to_str().unwrap(),
            "-o",
            "x.png",
            "--size",
            "10",
        ],
        vec![
            "upscale",
            src.to_str().unwrap(),
            "-o",
            "x.png",
            "--factor",
            "2",
            "--axes",
            "z",
        ],
        vec![
            "upscale",
            "/nonexistent.png",
            "-o",
            "x.png",
            "--factor",
            "2",
        ],
        vec![
            "downscale",
            src.to_str().unwrap(),
            "-o",
            "x.png",
            "--levels",
            "0",
        ],
    ] {
        let o = mra_bin().args(&bad).current_dir(&dir).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{bad:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{bad:?}: {err}");
        assert!(!dir.join("x.png").exists());
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn corpus_ct_volume_upscales_along_z() {
    let Some(path) = common::corpus("volumes/ct_pancreas_crop_256x256x64_u16le.raw") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let v: Vec<f32> = bytes
        .chunks(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]) as f32)
        .collect();
    // keep every 2nd slice, upscale z ×2 (vertex geometry: kept slices stay), compare
    let thin: Vec<f32> = (0..32)
        .flat_map(|z| v[2 * z * 65536..(2 * z + 1) * 65536].to_vec())
        .collect();
    let m = method(Refinement::Cubic, Mode::Interpolate);
    let plans = plan_raster(&[32, 256, 256], &[0], Some(2), None, true).unwrap();
    let (up, s) = upscale_array(thin, &[32, 256, 256], &m, &plans).unwrap();
    assert_eq!(s, vec![63, 256, 256]);
    let (mut se_spline, mut se_linear) = (0.0f64, 0.0f64);
    for z in 0..31 {
        for i in 0..65536 {
            let truth = v[(2 * z + 1) * 65536 + i] as f64;
            let lin = 0.5 * (v[2 * z * 65536 + i] + v[(2 * z + 2) * 65536 + i]) as f64;
            se_spline += (up[(2 * z + 1) * 65536 + i] as f64 - truth).powi(2);
            se_linear += (lin - truth).powi(2);
        }
    }
    assert!(
        se_spline < se_linear,
        "spline {se_spline} vs linear {se_linear}"
    );
}

#[test]
fn wide_and_narrow_lanes_give_the_same_result() {
    // [40, 300]: axis 0 runs in strip mode (rows ≥ 32 wide), the transposed array
    // [300, 40] along axis 1 in gather mode; the two results must be transposes.
    let (h, w) = (40usize, 300usize);
    let a = grid(h, w, |y, x| ((x * 0.37).sin() + (y * 0.21).cos()) * 100.0);
    let mut t = vec![0f32; h * w];
    for y in 0..h {
        for x in 0..w {
            t[x * h + y] = a[y * w + x];
        }
    }
    for mode in MODES {
        let m = method(Refinement::Cubic, mode);
        let p0 = [AxisPlan {
            axis: 0,
            len: 3 * h,
            geometry: Geometry::Centre,
        }];
        let p1 = [AxisPlan {
            axis: 1,
            len: 3 * h,
            geometry: Geometry::Centre,
        }];
        let (ua, sa) = upscale_array(a.clone(), &[h, w], &m, &p0).unwrap();
        let (ut, st) = upscale_array(t.clone(), &[w, h], &m, &p1).unwrap();
        assert_eq!((sa.clone(), st), (vec![3 * h, w], vec![w, 3 * h]));
        let mut worst = 0.0f32;
        for y in 0..3 * h {
            for x in 0..w {
                worst = worst.max((ua[y * w + x] - ut[x * 3 * h + y]).abs());
            }
        }
        assert!(worst < 1e-3, "{mode:?}: {worst}");
    }
}
