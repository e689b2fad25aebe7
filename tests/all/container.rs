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
