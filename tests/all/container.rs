//! The container notices what is missing: a file without one of the chunks its header
//! commits to, or with one twice, is an error naming it; with `--allow-truncated` it
//! decodes but never claims to be complete. The guarantees of lossless and
//! `--max-error` are never broken silently.

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::{DataKind, Raster, SampleType, Samples};
use mra::scheme::{Boundary, Scheme};
use mra::ErrorKind;

fn field(dims: &[usize], channels: usize, ty: SampleType) -> Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let w = *dims.last().unwrap();
    let v: Vec<f64> = (0..n)
        .map(|i| {
            let p = i / channels;
            let (x, y) = ((p % w) as f64, (p / w) as f64);
            120.0
                + 80.0 * (x * 0.3 + (i % channels) as f64).sin() * (y * 0.2).cos()
                + ((i * 7919) % 17) as f64
        })
        .collect();
    Raster::new(
        dims.to_vec(),
        channels,
        Samples::from_f64(&v, ty),
        DataKind::Image,
    )
    .unwrap()
}

fn opts(rate: Rate) -> EncodeOptions {
    EncodeOptions {
        scheme: Scheme::Cdf97,
        boundary: Boundary::Symmetric,
        levels: 4,
        rate,
        format: Default::default(),
        effort: mra::codec::DEFAULT_EFFORT,
    }
}

/// The chunks of a file: (type, start, end) with `end` past the CRC.
fn chunks(bytes: &[u8]) -> Vec<([u8; 4], usize, usize)> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 12 <= bytes.len() {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        let kind: [u8; 4] = bytes[at + 4..at + 8].try_into().unwrap();
        out.push((kind, at, at + 12 + len));
        at += 12 + len;
    }
    out
}

fn without(bytes: &[u8], start: usize, end: usize) -> Vec<u8> {
    [&bytes[..start], &bytes[end..]].concat()
}

fn decode(bytes: &[u8], allow_truncated: bool) -> mra::Result<codec::Decoded> {
    codec::decode(
        bytes,
        &DecodeOptions {
            level: 0,
            allow_truncated,
            ..Default::default()
        },
    )
}

fn max_abs_error(a: &Raster, b: &Raster) -> f64 {
    (0..a.samples.len())
        .map(|i| (a.samples.get_f64(i) - b.samples.get_f64(i)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn every_band_chunk_removed_is_named_and_never_complete() {
    let r = field(&[23, 31], 3, SampleType::U8);
    for rate in [Rate::Lossless, Rate::Quality(50.0), Rate::MaxError(2.0)] {
        let bytes = codec::encode(&r, &opts(rate)).unwrap();
        let cs = chunks(&bytes);
        let bands: Vec<_> = cs.iter().filter(|c| &c.0 == b"LEVL").collect();
        assert!(bands.len() >= 4, "{rate:?}: {} level chunks", bands.len());
        for &&(_, s, e) in &bands {
            let cut = without(&bytes, s, e);
            let err = decode(&cut, false).unwrap_err();
            assert!(matches!(err.kind(), ErrorKind::Format), "{rate:?}: {err}");
            assert!(
                err.to_string().contains("LEVL") || err.to_string().contains("level"),
                "{rate:?}: {err}"
            );
            if let Ok(d) = decode(&cut, true) {
                assert!(
                    !d.complete,
                    "{rate:?}: a file without a level claims complete"
                );
            }
        }
    }
}

#[test]
fn a_max_error_file_without_its_residuals_is_an_error() {
    let r = field(&[19, 26], 1, SampleType::U16);
    let bytes = codec::encode(&r, &opts(Rate::MaxError(2.0))).unwrap();
    let d = decode(&bytes, false).unwrap();
    assert!(d.complete && max_abs_error(&r, &d.raster) <= 2.0);
    let cs = chunks(&bytes);
    let &(_, s, e) = cs.iter().find(|c| &c.0 == b"RESI").unwrap();
    let cut = without(&bytes, s, e);
    let err = decode(&cut, false).unwrap_err();
    assert!(err.to_string().contains("RESI"), "{err}");
    let d = decode(&cut, true).unwrap();
    assert!(!d.complete);
}

#[test]
fn a_chunk_twice_is_an_error() {
    let r = field(&[17, 20], 3, SampleType::U8);
    for rate in [Rate::Lossless, Rate::MaxError(1.5)] {
        let bytes = codec::encode(&r, &opts(rate)).unwrap();
        let cs = chunks(&bytes);
        for kind in [b"LEVL", b"RESI"] {
            let Some(&(_, s, e)) = cs.iter().rev().find(|c| &c.0 == kind) else {
                continue;
            };
            let twice = [&bytes[..e], &bytes[s..e], &bytes[e..]].concat();
            let err = decode(&twice, false).unwrap_err();
            assert!(err.to_string().contains("second"), "{rate:?}: {err}");
            assert!(decode(&twice, true).is_err());
        }
    }
}

#[test]
fn an_exception_index_past_the_raster_is_an_error() {
    // a --max-error file whose residual layer lists exceptions: point the first at
    // sample 2^64 − 1 (and fix the CRC)
    let r = {
        let mut r = field(&[16, 16], 1, SampleType::F32);
        if let Samples::F32(v) = &mut r.samples {
            v[37] = 1.0e30; // far outside: the residual layer cannot reach it
        }
        r
    };
    let bytes = codec::encode(&r, &opts(Rate::MaxError(0.5))).unwrap();
    let cs = chunks(&bytes);
    let &(_, s, e) = cs.iter().find(|c| &c.0 == b"RESI").unwrap();
    let payload = &bytes[s + 8..e - 4];
    let n = u32::from_le_bytes(payload[10..14].try_into().unwrap());
    assert!(n >= 1, "no exception listed");
    let mut p = payload.to_vec();
    p[14..22].copy_from_slice(&u64::MAX.to_le_bytes());
    let mut chunk = Vec::new();
    mra::format::put_chunk(&mut chunk, b"RESI", &p);
    let bad = [&bytes[..s], &chunk[..], &bytes[e..]].concat();
    let err = decode(&bad, false).unwrap_err();
    assert!(err.to_string().contains("exception"), "{err}");
}

#[test]
fn complete_files_say_so() {
    let r = field(&[12, 9], 3, SampleType::U8);
    for rate in [Rate::Lossless, Rate::Bpp(2.0), Rate::MaxError(3.0)] {
        let bytes = codec::encode(&r, &opts(rate)).unwrap();
        let d = decode(&bytes, false).unwrap();
        assert!(d.complete, "{rate:?}");
        if rate == Rate::Lossless {
            assert!(d.raster.samples == r.samples);
        }
    }
}

fn decode_at(bytes: &[u8], level: usize, allow_truncated: bool) -> mra::Result<codec::Decoded> {
    codec::decode(
        bytes,
        &DecodeOptions {
            level,
            allow_truncated,
            ..Default::default()
        },
    )
}

/// The file with the chunk at `start..end` replaced by a chunk of `kind` and `payload`
/// (its length and CRC-32C recomputed, as a consistent forgery would be).
fn rechunk(bytes: &[u8], start: usize, end: usize, kind: &[u8; 4], payload: &[u8]) -> Vec<u8> {
    let mut out = bytes[..start].to_vec();
    mra::format::put_chunk(&mut out, kind, payload);
    out.extend_from_slice(&bytes[end..]);
    out
}

#[test]
fn a_reduced_level_decode_refuses_a_coarser_level_missing_or_out_of_order() {
    let r = field(&[32, 40], 1, SampleType::U8);
    for rate in [Rate::Lossless, Rate::Quality(50.0)] {
        let bytes = codec::encode(&r, &opts(rate)).unwrap();
        let good = decode_at(&bytes, 1, false).unwrap();
        assert!(good.complete, "{rate:?}");
        let levels: Vec<_> = chunks(&bytes)
            .into_iter()
            .filter(|c| &c.0 == b"LEVL")
            .collect();
        // coarse to fine: the last chunk is level 1, the one before it level 2
        let (_, s2, e2) = levels[levels.len() - 2];
        let (_, s1, e1) = levels[levels.len() - 1];
        assert_eq!(e2, s1);
        let missing = without(&bytes, s2, e2);
        let swapped = [&bytes[..s2], &bytes[s1..e1], &bytes[s2..e2], &bytes[e1..]].concat();
        for (what, file) in [("missing", &missing), ("swapped", &swapped)] {
            let err = decode_at(file, 1, false).unwrap_err();
            assert_eq!(err.kind(), ErrorKind::Format, "{rate:?} {what}: {err}");
            assert!(
                err.to_string().contains("LEVL chunk of level 2"),
                "{rate:?} {what}: {err}"
            );
            let d = decode_at(file, 1, true).unwrap();
            assert!(!d.complete, "{rate:?} {what}: claims complete");
            assert!(decode_at(file, 0, false).is_err(), "{rate:?} {what}");
        }
        // level 2 needs neither level 1 nor 2: the missing level 2 is still refused at
        // level 1, and level 3 decodes as from the intact file
        let d = decode_at(&missing, 3, false).unwrap();
        let want = decode_at(&bytes, 3, false).unwrap();
        assert!(
            d.complete && d.raster.samples == want.raster.samples,
            "{rate:?}"
        );
    }
}

#[test]
fn a_head_step_that_is_not_positive_and_finite_is_an_error() {
    let r = field(&[16, 16], 1, SampleType::U8);
    let bytes = codec::encode(&r, &opts(Rate::Quality(50.0))).unwrap();
    let (_, s, e) = chunks(&bytes)[0];
    let head = &bytes[s + 8..e - 4];
    // Δ at 12 + 4N of the HEAD payload (N = 2 axes)
    for step in [f64::NAN, f64::INFINITY, 0.0, -1.0] {
        let mut h = head.to_vec();
        h[20..28].copy_from_slice(&step.to_le_bytes());
        let forged = rechunk(&bytes, s, e, b"HEAD", &h);
        let err = decode(&forged, true).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Format, "step {step}: {err}");
        assert!(err.to_string().contains("step"), "step {step}: {err}");
        assert!(codec::info(&forged).is_err(), "step {step}");
    }
}

#[test]
fn a_second_meta_or_one_after_the_bands_is_an_error() {
    let mut r = field(&[16, 16], 1, SampleType::U8);
    r.meta.spacing = Some(vec![2.0, 3.0]);
    for tile in [None, Some(vec![8, 8])] {
        let bytes = match &tile {
            None => codec::encode(&r, &opts(Rate::Quality(50.0))).unwrap(),
            Some(t) => codec::encode_tiled(&r, &opts(Rate::Quality(50.0)), t).unwrap(),
        };
        assert!(decode(&bytes, false).is_ok());
        let cs = chunks(&bytes);
        let &(_, ms, me) = cs.iter().find(|c| &c.0 == b"mETA").expect("mETA");
        let meta = &bytes[ms..me];
        // twice, right after the first
        let twice = [&bytes[..me], meta, &bytes[me..]].concat();
        // moved to just before MEND, after every band or tile
        let &(_, end, _) = cs.iter().find(|c| &c.0 == b"MEND").unwrap();
        let late = [&bytes[..ms], &bytes[me..end], meta, &bytes[end..]].concat();
        for (what, file) in [("second", &twice), ("after", &late)] {
            // read in order: a seeking reader of a tiled file stops at its index
            let opts = DecodeOptions {
                allow_truncated: true,
                ..Default::default()
            };
            let err = codec::decode_stream(&file[..], file.len() as u64, &opts).unwrap_err();
            assert!(
                err.to_string().contains("mETA") && err.to_string().contains(what),
                "{tile:?} {what}: {err}"
            );
        }
    }
}

#[test]
fn a_file_whose_header_says_it_has_voids_is_refused_without_its_meta() {
    let mut r = field(&[20, 24], 1, SampleType::F32);
    r.kind = DataKind::Heightmap;
    let mut v = r.samples.to_f64();
    for i in (30..60).chain([200, 201, 333]) {
        v[i] = f64::NAN;
    }
    r.samples = Samples::from_f64(&v, SampleType::F32);
    for rate in [Rate::Lossless, Rate::Quality(50.0), Rate::MaxError(0.5)] {
        let bytes = codec::encode(&r, &opts(rate)).unwrap();
        let h = codec::header_of(&bytes).unwrap();
        assert!(h.voids && h.version.has_head_flags(), "{rate:?}");
        let d = decode(&bytes, false).unwrap();
        let voids = |x: &Raster| {
            (0..x.samples.len())
                .filter(|&i| x.samples.get_f64(i).is_nan())
                .count()
        };
        assert_eq!(voids(&d.raster), 33, "{rate:?}");
        let &(_, s, e) = chunks(&bytes).iter().find(|c| &c.0 == b"mETA").unwrap();
        let cut = without(&bytes, s, e);
        for allow in [false, true] {
            let err = decode(&cut, allow).unwrap_err();
            assert!(err.to_string().contains("void"), "{rate:?}: {err}");
        }
    }
    // a raster without voids keeps the version it had: 3.2, or 2.0 in format 2
    let plain = field(&[20, 24], 1, SampleType::F32);
    let h = codec::header_of(&codec::encode(&plain, &opts(Rate::Quality(50.0))).unwrap()).unwrap();
    assert!(!h.voids && h.version == mra::format::Version::LEVEL_BLOCKS);
    let two = EncodeOptions {
        format: codec::Format::Bands,
        ..opts(Rate::Quality(50.0))
    };
    let h = codec::header_of(&codec::encode(&plain, &two).unwrap()).unwrap();
    assert!(!h.voids && !h.version.has_head_flags());
}
