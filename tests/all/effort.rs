//! The effort ladder (`EncodeOptions::effort`, `mra encode --effort`) and the block
//! coders of formats 3.1 and 3.2: every coder round-trips every mode it is given (lossy, lossless, and
//! max-error, which keeps the context coder), 2-D and 3-D, 8 and 16 bits, odd sizes;
//! the bytes do not depend on the thread count; the default effort writes coder 2, and
//! the context coder's file when lossless; a coder byte no reader knows is refused in one line.

use super::common;
use mra::codec::{self, DecodeOptions, EncodeOptions, Ladder, Rate, DEFAULT_EFFORT};
use mra::entropy::codeblocks::Coder;
use mra::io::{Raster, SampleType};
use mra::ErrorKind;

/// A smooth field with texture (xorshift) over `[0, hi]`, `channels` channels of `ty`.
/// The codec tests' wave ([`common::wave_field`]).
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64, hi: f64) -> Raster {
    let wave = common::Wave {
        fx: 0.13,
        fy: 0.07,
        noise: 0.08,
    };
    common::wave_field(dims, channels, ty, seed, hi, wave)
}

fn opts(rate: Rate, effort: u8) -> EncodeOptions {
    EncodeOptions {
        rate,
        levels: 4,
        effort,
        ..Default::default()
    }
}

fn decoded(bytes: &[u8]) -> Raster {
    codec::decode(bytes, &DecodeOptions::default())
        .unwrap()
        .raster
}

/// The HEAD payload's place in a file: (start, end) of the payload (its CRC follows).
fn head(b: &[u8]) -> (usize, usize) {
    let n = u32::from_le_bytes(b[8..12].try_into().unwrap()) as usize;
    assert_eq!(&b[12..16], b"HEAD");
    (16, 16 + n)
}

fn recrc(b: &mut [u8], start: usize, end: usize) {
    let mut c = mra::format::crc::Crc32c::new();
    c.update(&b[start - 4..end]);
    let v = c.finish().to_le_bytes();
    b[end..end + 4].copy_from_slice(&v);
}

fn max_abs(a: &Raster, b: &Raster) -> f64 {
    let (x, y) = (a.samples.to_f64(), b.samples.to_f64());
    x.iter()
        .zip(&y)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max)
}

/// The ladder: efforts 1–3 the HT coder, 4–6 the adaptive coder, 7–9 the context
/// coder; RDO from 4; `--lossless` keeps the context coder at 4–6 (coder 2 meets issue
/// 48's lossy ratio target, not its lossless one on 16-bit data: docs/codec.md); the
/// default is coder 2.
#[test]
fn the_ladder_names_its_coders() {
    for e in 1..=9u8 {
        let l = Ladder::of(e);
        assert_eq!(l.coder == Coder::Ht, e <= 3, "{e}");
        assert_eq!(l.coder == Coder::Adaptive, (4..=6).contains(&e), "{e}");
        assert_eq!(l.rdo, e >= 4, "{e}");
        let lossless = if e <= 3 { Coder::Ht } else { Coder::Context };
        assert_eq!(l.lossless, lossless, "{e}");
    }
    assert_eq!(Ladder::of(DEFAULT_EFFORT).coder, Coder::Adaptive);
    assert_eq!(Ladder::of(DEFAULT_EFFORT).lossless, Coder::Context);
    assert_eq!(EncodeOptions::default().effort, DEFAULT_EFFORT);
    for e in [0u8, 10, 255] {
        let r = field(&[20, 24], 1, SampleType::U8, 1, 255.0);
        let err = codec::encode(&r, &opts(Rate::Quality(50.0), e)).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Parameter, "{e}: {err}");
        assert!(err.to_string().contains("effort"), "{err}");
    }
}

/// Every coder × mode × shape × depth round-trips: lossless exactly (the context coder
/// at efforts 4–6), max-error within its bound (the context coder, whatever the
/// effort), lossy at the step the rate mode
/// sets; a file of the HT coder is 3.1, of the adaptive coder 3.2, and says so, the
/// others 3.0.
#[test]
fn every_coder_round_trips_every_mode() {
    let shapes: [(&[usize], usize); 4] = [
        (&[67, 45], 3),
        (&[33, 70], 1),
        (&[19, 23, 29], 1),
        (&[9, 130], 2),
    ];
    for (dims, ch) in shapes {
        for (ty, hi) in [
            (SampleType::U8, 255.0),
            (SampleType::U16, 60000.0),
            (SampleType::I16, 3000.0),
        ] {
            let r = field(dims, ch, ty, dims.len() as u64 * 7 + ch as u64, hi);
            for effort in [1u8, 5, 7, 9] {
                let narrow = match effort {
                    ..=3 => "ht",
                    4..=6 => "adaptive",
                    _ => "context",
                };
                for rate in [
                    Rate::Lossless,
                    Rate::MaxError(hi / 100.0),
                    Rate::Quality(60.0),
                ] {
                    let what = format!("{dims:?}×{ch} {ty:?} effort {effort} {rate:?}");
                    let bytes = codec::encode(&r, &opts(rate, effort)).unwrap();
                    let info = codec::info(&bytes).unwrap();
                    // lossless at 4–6 is the context coder's (`Ladder::lossless`);
                    // coder 2's lossless decode is the vector blocks32a_gray16_lossless'
                    let want = match rate {
                        Rate::MaxError(_) => "context",
                        Rate::Lossless if (4..=6).contains(&effort) => "context",
                        _ => narrow,
                    };
                    assert_eq!(info.coder.as_deref(), Some(want), "{what}");
                    assert_eq!(info.version, "3.2", "{what}");
                    let d = decoded(&bytes);
                    assert_eq!(
                        (d.dims.clone(), d.channels),
                        (r.dims.clone(), r.channels),
                        "{what}"
                    );
                    match rate {
                        Rate::Lossless => assert!(d.samples == r.samples, "{what}"),
                        Rate::MaxError(e) => assert!(max_abs(&d, &r) <= e, "{what}"),
                        _ => assert!(max_abs(&d, &r) < hi / 8.0, "{what}: {}", max_abs(&d, &r)),
                    }
                }
            }
        }
    }
}

/// Efforts 4–6 choose their indices by coder 2's own costs, not the context coder's
/// (effort 7): the samples decoded differ, and at the same `--bpp` (a file within the
/// budget) the PSNR is within 0.5 dB of effort 7's.
#[test]
fn the_adaptive_coder_chooses_its_own_indices_near_the_context_coders_quality() {
    let r = field(&[150, 203], 3, SampleType::U8, 5, 255.0);
    let v = field(&[21, 40, 37], 1, SampleType::U16, 6, 30000.0);
    for (r, hi) in [(&r, 255.0), (&v, 30000.0)] {
        let fast = codec::encode(r, &opts(Rate::Bpp(1.0), 5)).unwrap();
        let slow = codec::encode(r, &opts(Rate::Bpp(1.0), 7)).unwrap();
        let (df, ds) = (decoded(&fast), decoded(&slow));
        assert!(df.samples != ds.samples, "{}", r.summary());
        let psnr = |d: &Raster| {
            let (x, y) = (d.samples.to_f64(), r.samples.to_f64());
            let mse = x.iter().zip(&y).map(|(p, q)| (p - q).powi(2)).sum::<f64>() / x.len() as f64;
            10.0 * (hi * hi / mse).log10()
        };
        let (pf, ps) = (psnr(&df), psnr(&ds));
        assert!(pf > ps - 0.5, "{}: {pf} dB against {ps}", r.summary());
        let bits = |b: &[u8]| b.len() as f64 * 8.0 / (r.dims.iter().product::<usize>() as f64);
        assert!(bits(&fast) <= 1.0, "{}", bits(&fast));
    }
}

/// The bytes of each coder's file are the same on one thread and on two.
#[test]
fn each_coder_writes_the_same_bytes_on_any_thread_count() {
    let r = field(&[300, 270], 3, SampleType::U8, 11, 255.0);
    let v = field(&[40, 70, 66], 1, SampleType::U16, 12, 4000.0);
    for effort in [1u8, 4, 7] {
        for (r, rate) in [
            (&r, Rate::Bpp(1.0)),
            (&r, Rate::Lossless),
            (&v, Rate::Quality(50.0)),
            (&v, Rate::Lossless),
        ] {
            let on = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| codec::encode(r, &opts(rate, effort)).unwrap())
            };
            let one = on(1);
            assert!(one == on(2), "{} {rate:?} effort {effort}", r.summary());
            assert!(decoded(&one).dims == r.dims);
        }
    }
}

/// The default effort writes coder 2 (format 3.2, its coder byte 2) when lossy, the
/// bytes of an explicit `effort: DEFAULT_EFFORT`; its `--lossless` file is effort 7's
/// byte for byte (the context coder: a 3.2 HEAD whose coder byte is 0), so the default's
/// lossless bits are those of before the default moved.
#[test]
fn the_default_effort_writes_coder_2_lossy_and_the_context_coder_lossless() {
    let r = field(&[64, 80], 3, SampleType::U8, 3, 255.0);
    for rate in [Rate::Bpp(1.0), Rate::Lossless, Rate::Quality(70.0)] {
        let d = codec::encode(
            &r,
            &EncodeOptions {
                rate,
                levels: 4,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(d, codec::encode(&r, &opts(rate, DEFAULT_EFFORT)).unwrap());
        let h = codec::header_of(&d).unwrap();
        let coder = if rate == Rate::Lossless {
            assert_eq!(d, codec::encode(&r, &opts(rate, 7)).unwrap());
            Coder::Context
        } else {
            Coder::Adaptive
        };
        assert_eq!(
            (h.version.to_string(), h.coder),
            ("3.2".to_string(), coder.id())
        );
        let (s, e) = head(&d);
        // 3.2's HEAD: 52 + 8N bytes, the flags byte, N exponents and the coder byte
        assert_eq!(e - s, 52 + 8 * 2 + 1 + 2 + 1);
        assert!(decoded(&d).dims == r.dims);
    }
}

/// A 3.1 file whose coder byte names no coder, or coder 2 (which 3.1 lacks), is
/// refused with one line naming it, by the library (a format error) and by `mra
/// decode` (exit 2, no output); so is a 3.2 file of an unknown coder.
#[test]
fn a_coder_byte_no_reader_knows_is_refused() {
    let r = field(&[40, 52], 1, SampleType::U8, 9, 255.0);
    // the writer's 3.2 file of coder 1 made a 3.1 one: the same bytes but the minor (a
    // 40×52 image has one block per band at every level in both)
    let mut good = codec::encode(&r, &opts(Rate::Quality(50.0), 1)).unwrap();
    let (s, e) = head(&good);
    assert_eq!((good[s + 1], good[e - 1]), (2, Coder::Ht.id()));
    good[s + 1] = 1;
    recrc(&mut good, s, e);
    assert_eq!(decoded(&good).dims, r.dims);
    let dir = common::scratch_dir("effort_coder_byte");
    for id in [2u8, 7, 255] {
        let mut b = good.clone();
        b[e - 1] = id;
        recrc(&mut b, s, e);
        let err = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Format, "{id}: {err}");
        assert!(
            err.to_string().contains(&format!("block coder {id}")),
            "{err}"
        );
        let f = dir.join(format!("coder{id}.mra"));
        std::fs::write(&f, &b).unwrap();
        let out = dir.join(format!("coder{id}.png"));
        let o = common::mra_with_stdin(
            None,
            &["decode", f.to_str().unwrap(), "-o", out.to_str().unwrap()],
            b"",
        );
        let msg = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{msg}");
        assert_eq!(msg.trim().lines().count(), 1, "{msg}");
        assert!(msg.contains("block coder"), "{msg}");
        assert!(!out.exists());
    }
    // a 3.2 file (coder 2) whose coder byte names no coder
    let good = codec::encode(&r, &opts(Rate::Quality(50.0), 5)).unwrap();
    let (s, e) = head(&good);
    assert_eq!((good[s + 1], good[e - 1]), (2, Coder::Adaptive.id()));
    assert!(decoded(&good).dims == r.dims);
    for id in [3u8, 200] {
        let mut b = good.clone();
        b[e - 1] = id;
        recrc(&mut b, s, e);
        let err = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Format, "{id}: {err}");
        assert!(
            err.to_string().contains(&format!("block coder {id}")),
            "{err}"
        );
    }
    // a 3.0 HEAD (a 3.2 one without its coder byte) relabelled 3.1 lacks its coder byte
    let b = codec::encode(&r, &opts(Rate::Quality(50.0), 9)).unwrap();
    let (s, _) = head(&b);
    assert_eq!(b[s..s + 2], [3, 2]);
    let mut rd = mra::format::ChunkReader::new(&b[..], b.len() as u64).unwrap();
    let mut out = mra::format::SIGNATURE.to_vec();
    while let Ok(ch) = rd.next_chunk().unwrap() {
        let mut p = ch.payload.clone();
        if &ch.kind == b"HEAD" {
            p.pop();
            p[1] = 1;
        }
        mra::format::put_chunk(&mut out, &ch.kind, &p);
    }
    let err = codec::decode(&out, &DecodeOptions::default()).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::Format, "{err}");
}

/// `mra encode --effort` writes the coder `mra info --json` reports; `--effort 0` and
/// `10` are refused by clap with exit 2.
#[test]
fn cli_effort_picks_the_coder_info_reports() {
    let dir = common::scratch_dir("effort_cli");
    let png = dir.join("z.png");
    let o = common::mra_with_stdin(
        None,
        &[
            "generate",
            "zone-plate",
            "-o",
            png.to_str().unwrap(),
            "--size",
            "96",
        ],
        b"",
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (effort, coder) in [("1", "ht"), ("5", "adaptive"), ("9", "context")] {
        let f = dir.join(format!("z{effort}.mra"));
        let o = common::mra_with_stdin(
            None,
            &[
                "encode",
                png.to_str().unwrap(),
                "-o",
                f.to_str().unwrap(),
                "--bpp",
                "1",
                "--effort",
                effort,
            ],
            b"",
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let o = common::mra_with_stdin(None, &["info", f.to_str().unwrap(), "--json"], b"");
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(j["coder"], coder, "{effort}");
    }
    for bad in ["0", "10"] {
        let f = dir.join("bad.mra");
        let o = common::mra_with_stdin(
            None,
            &[
                "encode",
                png.to_str().unwrap(),
                "-o",
                f.to_str().unwrap(),
                "--effort",
                bad,
            ],
            b"",
        );
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(!f.exists());
    }
}

/// `Σ (x − x̂)²` of two rasters of the same shape.
fn squared_error(a: &Raster, b: &Raster) -> f64 {
    let (x, y) = (a.samples.to_f64(), b.samples.to_f64());
    x.iter().zip(&y).map(|(p, q)| (p - q).powi(2)).sum()
}

/// Effort 9's `--bpp` chooses the number of levels per file: of the files at
/// `--levels` and each count below it (all tried here: 3, 2, 1), within the budget, it
/// keeps the one with the least squared error, which is never more than effort 7's
/// (the same coder and indices at `--levels`); the other efforts keep `--levels`.
#[test]
fn effort_9_bpp_keeps_the_level_count_of_least_error() {
    assert!(Ladder::of(9).bpp_levels);
    assert!((1..=8).all(|e| !Ladder::of(e).bpp_levels));
    let r = field(&[64, 96], 1, SampleType::U16, 3, 4000.0);
    let budget = (64 * 96) as f64;
    let at = |levels: usize, effort: u8| {
        let o = EncodeOptions {
            levels,
            ..opts(Rate::Bpp(1.0), effort)
        };
        codec::encode(&r, &o).unwrap()
    };
    let chosen = at(3, 9);
    assert!(
        chosen.len() as f64 * 8.0 <= budget,
        "{} bytes",
        chosen.len()
    );
    let err = squared_error(&r, &decoded(&chosen));
    let each: Vec<(usize, f64)> = (1..=3)
        .map(|l| (l, squared_error(&r, &decoded(&at(l, 7)))))
        .collect();
    let least = each.iter().map(|e| e.1).fold(f64::INFINITY, f64::min);
    assert_eq!(err, least, "{each:?}");
    let levels = codec::decode(&chosen[..], &DecodeOptions::default())
        .unwrap()
        .header
        .levels;
    assert_eq!(each.iter().find(|e| e.1 == least).unwrap().0, levels);
    assert!(err <= each[2].1, "{err} vs effort 7's {}", each[2].1);
    // effort 7 keeps the levels asked
    let seven = codec::decode(&at(3, 7)[..], &DecodeOptions::default()).unwrap();
    assert_eq!(seven.header.levels, 3);
}
