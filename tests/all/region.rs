//! A file parsed once serves many regions ([`codec::Opened`]): every region and level
//! decodes to what a fresh [`codec::decode`] of the same region gives, for one-piece
//! 3.0 files (lossy and lossless, 2-D and 3-D) and for the files read again on each call
//! (format 2, tiled, `--max-error`); one value serves two threads at once; a damaged
//! file fails at open with a one-line error.

use super::common;
use mra::codec::{self, DecodeOptions, EncodeOptions, Opened, Rate};
use mra::io::{Raster, SampleType, Samples};
use std::ops::Range;

/// A smooth field with texture (xorshift), `channels` channels of type `ty`.
/// The codec tests' wave ([`common::wave_field`]).
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let wave = common::Wave {
        fx: 0.11,
        fy: 0.05,
        noise: 0.08,
    };
    common::wave_field(dims, channels, ty, seed, hi, wave)
}

fn fresh(bytes: &[u8], level: usize, region: Option<Vec<Range<usize>>>) -> Raster {
    let o = DecodeOptions {
        level,
        region,
        ..Default::default()
    };
    codec::decode(bytes, &o).unwrap().raster
}

/// Windows inside, at a corner, at the far corner and one sample wide.
fn windows(dims: &[usize]) -> Vec<Vec<Range<usize>>> {
    vec![
        dims.iter().map(|&d| d / 3..d / 3 + d / 4 + 1).collect(),
        dims.iter().map(|&d| 0..d / 5 + 1).collect(),
        dims.iter().map(|&d| d - d / 6 - 1..d).collect(),
        dims.iter().map(|&d| d / 2..d / 2 + 1).collect(),
    ]
}

fn assert_send_sync<T: Send + Sync>() {}

/// Every region and level of one opened file decodes as a fresh decode of it does,
/// whatever the file's layout.
#[test]
fn opened_regions_are_fresh_decodes() {
    assert_send_sync::<Opened>();
    let blocks = EncodeOptions::default();
    let bands = EncodeOptions {
        format: codec::Format::Bands,
        ..Default::default()
    };
    let cases: Vec<(Raster, EncodeOptions, usize, Option<Vec<usize>>)> = vec![
        (
            field(&[301, 419], 3, SampleType::U8, 3, 255.0),
            EncodeOptions {
                rate: Rate::Bpp(1.0),
                levels: 4,
                ..blocks.clone()
            },
            4,
            None,
        ),
        (
            field(&[150, 97], 1, SampleType::U16, 5, 60000.0),
            EncodeOptions {
                rate: Rate::Lossless,
                levels: 3,
                ..blocks.clone()
            },
            3,
            None,
        ),
        (
            field(&[37, 81, 75], 1, SampleType::I16, 7, 3000.0),
            EncodeOptions {
                rate: Rate::Quality(60.0),
                levels: 3,
                ..blocks.clone()
            },
            3,
            None,
        ),
        (
            field(&[61, 90], 1, SampleType::U8, 9, 255.0),
            EncodeOptions {
                rate: Rate::MaxError(2.0),
                levels: 2,
                ..blocks.clone()
            },
            2,
            None,
        ),
        (
            field(&[120, 130], 1, SampleType::U8, 11, 255.0),
            EncodeOptions {
                rate: Rate::Bpp(1.0),
                levels: 3,
                ..bands.clone()
            },
            3,
            None,
        ),
        (
            field(&[120, 130], 1, SampleType::U8, 13, 255.0),
            EncodeOptions {
                rate: Rate::Bpp(1.0),
                levels: 3,
                ..bands.clone()
            },
            3,
            Some(vec![64, 64]),
        ),
    ];
    for (r, o, levels, tile) in cases {
        let bytes = match &tile {
            Some(t) => codec::encode_tiled(&r, &o, t).unwrap(),
            None => codec::encode_tiled(&r, &o, &r.dims).unwrap(),
        };
        let opened = Opened::from_bytes(bytes.clone()).unwrap();
        assert_eq!(opened.header().dims, r.dims);
        for level in 0..=levels.min(2) {
            let whole = opened.region(level, None).unwrap().raster;
            assert_eq!(whole.samples, fresh(&bytes, level, None).samples);
            for win in windows(&r.dims) {
                let a = opened.region(level, Some(&win)).unwrap().raster;
                let b = fresh(&bytes, level, Some(win.clone()));
                assert_eq!(a.dims, b.dims, "{:?} {win:?} level {level}", r.dims);
                assert!(
                    a.samples == b.samples,
                    "{:?} {:?} {win:?} level {level}",
                    r.dims,
                    o.rate
                );
                assert_eq!(a.meta, b.meta);
            }
        }
        assert!(opened.region(levels + 1, None).is_err());
        let bad: Vec<Range<usize>> = r.dims.iter().map(|&d| d..d + 1).collect();
        assert!(opened.region(0, Some(&bad)).is_err());
    }
}

/// An opened file on disk serves regions from two threads at once, each what a fresh
/// decode of the file gives; a truncated file fails at open.
#[test]
fn an_opened_file_serves_two_threads() {
    let r = field(&[700, 650], 1, SampleType::U8, 17, 255.0);
    let o = EncodeOptions {
        rate: Rate::Bpp(1.5),
        levels: 5,
        ..Default::default()
    };
    let bytes = codec::encode_tiled(&r, &o, &r.dims).unwrap();
    let dir = std::env::temp_dir().join(format!("mra-region-opened-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.mra");
    std::fs::write(&path, &bytes).unwrap();
    let opened = Opened::open(&path).unwrap();
    let wins: Vec<Vec<Range<usize>>> = (0..8)
        .map(|i| vec![i * 80..i * 80 + 64, 600 - i * 70..650 - i * 70])
        .collect();
    std::thread::scope(|s| {
        for half in wins.chunks(4) {
            let (opened, bytes) = (&opened, &bytes);
            s.spawn(move || {
                for w in half {
                    for level in 0..2 {
                        let a = opened.region(level, Some(w)).unwrap().raster;
                        let b = fresh(bytes, level, Some(w.clone()));
                        assert!(a.samples == b.samples, "{w:?} level {level}");
                    }
                }
            });
        }
    });
    let cut = dir.join("cut.mra");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let e = Opened::open(&cut)
        .err()
        .expect("a truncated file fails at open");
    assert!(!e.to_string().contains('\n'), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The boxes a window's synthesis reads in each band ([`mra::tensor::WindowPlan::reads`],
/// the coarse block's [`mra::tensor::WindowPlan::coarse_box`]) are its exact support:
/// every coefficient outside them zeroed, the whole synthesis gives the same window
/// (within rounding); and the coefficient at each end of each box, perturbed, changes
/// the window. Every scheme and boundary, 1-D to 3-D, odd extents, levels 1 to 3,
/// windows inside, at the corners and one sample wide.
#[test]
fn window_reads_are_the_exact_support() {
    use mra::scheme::{Boundary, Scheme};
    use mra::tensor::{analyze, synthesize, Array, Order, PyramidSpec, WindowPlan};
    let mut seed = 11u64;
    let mut rnd = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 33) % 1000) as f64 / 7.0 - 60.0
    };
    for shape in [vec![53usize], vec![29, 23], vec![13, 15, 11]] {
        let n: usize = shape.iter().product();
        let st: Vec<usize> = (0..shape.len())
            .map(|a| shape[a + 1..].iter().product())
            .collect();
        let positions: Vec<Vec<usize>> = (0..n)
            .map(|i| st.iter().zip(&shape).map(|(s, e)| i / s % e).collect())
            .collect();
        for scheme in Scheme::ALL {
            for boundary in Boundary::ALL {
                for levels in 1..=3 {
                    let spec = PyramidSpec {
                        scheme,
                        boundary,
                        levels,
                        order: Order::NonStandard,
                        axes: (0..shape.len()).collect(),
                    };
                    let data: Vec<f64> = (0..n).map(|_| rnd()).collect();
                    let mut a = Array::from_shape_vec(&shape, data).unwrap();
                    let Ok(pyr) = analyze(&mut a, &spec) else {
                        continue;
                    };
                    let coeffs = a.data().to_vec();
                    let whole = |c: &[f64]| {
                        let mut s = Array::from_shape_vec(&shape, c.to_vec()).unwrap();
                        synthesize(&mut s, &pyr).unwrap();
                        s.data().to_vec()
                    };
                    let base = whole(&coeffs);
                    let windows: Vec<Vec<Range<usize>>> = vec![
                        shape.iter().map(|&e| e / 3..e / 2 + 1).collect(),
                        shape.iter().map(|_| 0..1).collect(),
                        shape.iter().map(|&e| e - 2..e).collect(),
                        shape.iter().map(|&e| e / 2..e / 2 + 1).collect(),
                    ];
                    for w in windows {
                        let plan = WindowPlan::new(&pyr, &w).unwrap();
                        // the support, as plane boxes
                        let boxes: Vec<Vec<Range<usize>>> = pyr
                            .subbands()
                            .iter()
                            .map(|b| {
                                let r = if b.level == 0 {
                                    plan.coarse_box.clone()
                                } else {
                                    plan.reads(b.level - 1, &b.ranges)
                                };
                                r.iter()
                                    .zip(&b.ranges)
                                    .map(|(x, br)| x.start + br.start..x.end + br.start)
                                    .collect()
                            })
                            .collect();
                        let inside = |p: &[usize]| {
                            boxes
                                .iter()
                                .any(|bx| bx.iter().zip(p).all(|(r, x)| r.contains(x)))
                        };
                        let pos = |i: usize| -> &[usize] { &positions[i] };
                        let in_window: Vec<bool> = (0..n)
                            .map(|i| pos(i).iter().zip(&w).all(|(x, r)| r.contains(x)))
                            .collect();
                        let differs = |c: &[f64], tol: f64| {
                            let got = whole(c);
                            (0..n).any(|i| in_window[i] && (got[i] - base[i]).abs() > tol)
                        };
                        let zeroed: Vec<f64> = (0..n)
                            .map(|i| if inside(pos(i)) { coeffs[i] } else { 0.0 })
                            .collect();
                        let what = format!("{shape:?} {scheme:?} {boundary:?} {levels} {w:?}");
                        assert!(!differs(&zeroed, 1e-6), "not sufficient: {what}");
                        for bx in boxes.iter().filter(|b| b.iter().all(|r| !r.is_empty())) {
                            for ax in 0..shape.len() {
                                for end in [bx[ax].start, bx[ax].end - 1] {
                                    let mut p: Vec<usize> = bx.iter().map(|r| r.start).collect();
                                    p[ax] = end;
                                    let i: usize = p.iter().zip(&st).map(|(x, s)| x * s).sum();
                                    let mut c = coeffs.clone();
                                    c[i] += 1000.0;
                                    // some point of the box's face changes the window
                                    let face_matters = differs(&c, 1e-6) || {
                                        let mut c = coeffs.clone();
                                        let mut any = false;
                                        for (j, cj) in c.iter_mut().enumerate().take(n) {
                                            let q = pos(j);
                                            if q[ax] == end
                                                && bx.iter().zip(q).all(|(r, x)| r.contains(x))
                                            {
                                                *cj += 1000.0 * (1.0 + j as f64 * 0.37);
                                                any = true;
                                            }
                                        }
                                        any && differs(&c, 1e-6)
                                    };
                                    assert!(
                                        face_matters,
                                        "not tight on axis {ax} at {end}: {what} {bx:?}"
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}

/// A region of a lossless 3.0 file is computed from the window's support alone (the
/// integer lifting of the window), and of a `--max-error` file from the window's
/// lossy synthesis with the residual layer added over it: the samples of the same box
/// of the whole decode, for both lossless schemes, RGB (YCoCg-R) and gray, 8 and 16
/// bits and floats, 2-D and 3-D, odd sizes over several blocks, levels 0 to 3, windows
/// inside, at the corners, at the far edges and one sample wide.
#[test]
fn lossless_and_max_error_regions_are_windows_of_the_whole_decode() {
    use mra::scheme::Scheme;
    let cases: Vec<(Raster, usize, Rate)> = vec![
        (
            field(&[301, 277], 3, SampleType::U8, 31, 255.0),
            4,
            Rate::Lossless,
        ),
        (
            field(&[263, 300], 1, SampleType::U16, 33, 60000.0),
            5,
            Rate::Lossless,
        ),
        (
            field(&[97, 89], 1, SampleType::F32, 35, 7.0),
            3,
            Rate::Lossless,
        ),
        (
            field(&[41, 70, 67], 1, SampleType::I16, 37, 3000.0),
            3,
            Rate::Lossless,
        ),
        (
            field(&[203, 177], 3, SampleType::U8, 39, 255.0),
            4,
            Rate::MaxError(3.0),
        ),
        (
            field(&[37, 50, 61], 1, SampleType::U16, 41, 4000.0),
            3,
            Rate::MaxError(20.0),
        ),
    ];
    for (r, levels, rate) in cases {
        let schemes = if rate == Rate::Lossless {
            vec![Scheme::Linear, Scheme::Haar]
        } else {
            vec![Scheme::Cdf97]
        };
        for scheme in schemes {
            let o = EncodeOptions {
                rate,
                levels,
                scheme,
                ..Default::default()
            };
            let bytes = codec::encode_tiled(&r, &o, &r.dims).unwrap();
            assert!(mra::codec::header_of(&bytes).unwrap().version.has_blocks());
            for level in 0..=levels.min(3) {
                let whole = fresh(&bytes, level, None);
                if level == 0 && rate == Rate::Lossless {
                    assert_eq!(whole.samples, r.samples, "{:?} {scheme:?}", r.dims);
                }
                let mut wins = windows(&r.dims);
                wins.push(r.dims.iter().map(|&d| d - 1..d).collect());
                wins.push(r.dims.iter().map(|&d| 0..d).collect());
                for win in wins {
                    let part = fresh(&bytes, level, Some(win.clone()));
                    let cut = crop(&whole, &bytes, level, &win);
                    assert!(
                        part.samples == cut,
                        "{:?} {rate:?} {scheme:?} {win:?} level {level}",
                        r.dims
                    );
                }
            }
        }
    }
}

/// The samples of `whole` (a decode at `level`) over the level's box that the
/// full-resolution `win` maps to (as `DecodeOptions::region` maps it).
fn crop(whole: &Raster, bytes: &[u8], level: usize, win: &[Range<usize>]) -> Samples {
    let h = mra::codec::header_of(bytes).unwrap();
    let ext = codec::level_extents(&h, level).unwrap();
    let bx: Vec<Range<usize>> = win
        .iter()
        .zip(&h.dims)
        .zip(&ext)
        .map(|((r, &d), &e)| r.start * e / d..(r.end * e).div_ceil(d))
        .collect();
    let c = whole.channels;
    let st: Vec<usize> = (0..ext.len())
        .map(|a| ext[a + 1..].iter().product())
        .collect();
    let mut idx = Vec::new();
    let total: usize = bx.iter().map(|r| r.len()).product();
    for t in 0..total {
        let mut rem = t;
        let mut at = 0;
        for a in (0..bx.len()).rev() {
            let len = bx[a].len();
            at += (bx[a].start + rem % len) * st[a];
            rem /= len;
        }
        for ch in 0..c {
            idx.push(at * c + ch);
        }
    }
    let v: Vec<f64> = idx.iter().map(|&i| whole.samples.get_f64(i)).collect();
    Samples::from_f64(&v, whole.samples.sample_type())
}
