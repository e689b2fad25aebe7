//! The code-block coder prototype (`entropy::block`): exact round trips of random bands
//! of every shape (1 to 4 axes, odd extents, odd code-block shapes, the whole `i32`
//! range, with and without a parent), its range coder and raw bits, damaged streams,
//! and on real bands (the corpus' kodim01 at 1 bpp, when present) the same indices
//! back as today's coder wrote.

use super::common;
#[path = "../../benches/coder/bands.rs"]
pub(super) mod bands;

use mra::entropy::block::rc::{BitReader, BitWriter, Cdf, Decoder, Encoder, SYMBOLS};
use mra::entropy::block::{self, Parent, Shape};
use mra::entropy::BandKind;
use proptest::prelude::*;

/// The bands of kodim01 coded at 1 bpp, one stream per band (`Format::Bands`, as
/// `Bands::of_file` reads them), and the file's length: the real bands the block
/// coders' tests code again; `None` (the test skips) without the corpus.
pub(super) fn kodim01_bands() -> Option<(bands::Bands, usize)> {
    let path = common::corpus("images/kodak/kodim01.png")?;
    let r = mra::io::read(&path).unwrap();
    let bytes = mra::codec::encode(
        &r,
        &mra::codec::EncodeOptions {
            rate: mra::codec::Rate::Bpp(1.0),
            format: mra::codec::Format::Bands,
            ..Default::default()
        },
    )
    .unwrap();
    Some((bands::Bands::of_file(&bytes).unwrap(), bytes.len()))
}

/// Indices: mostly 0 and small, some huge (the extremes of `i32` included).
pub(super) fn index() -> impl Strategy<Value = i32> {
    prop_oneof![
        6 => Just(0),
        4 => -3i32..=3,
        2 => -300i32..=300,
        1 => any::<i32>(),
        1 => prop_oneof![Just(i32::MIN), Just(i32::MAX), Just(i32::MIN + 1)],
    ]
}

/// Extents of 1 to 4 axes, each 1 to 13 (at most a few thousand positions).
pub(super) fn dims() -> impl Strategy<Value = Vec<usize>> {
    prop::collection::vec(1usize..=13, 1..=4)
}

pub(super) fn band_of(dims: Vec<usize>) -> impl Strategy<Value = (Vec<usize>, Vec<i32>)> {
    let n = dims.iter().product::<usize>();
    (Just(dims), prop::collection::vec(index(), n))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Every band comes back exactly, in any code-block shape, as a detail band with or
    /// without its parent and as the coarsest band (median residuals).
    #[test]
    fn bands_round_trip_exactly(
        (dims, q) in dims().prop_flat_map(band_of),
        pseed in prop::collection::vec(index(), 0..200),
        z in 1usize..=5, y in 1usize..=9, x in 1usize..=9, limit in 1u8..=8, trained in any::<bool>(),
        with_parent in any::<bool>(),
        coarse in any::<bool>(),
        signs in any::<bool>(),
    ) {
        let shape = Shape { z, y, x, limit, trained, signs };
        let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
        let pn: usize = pdims.iter().product();
        let pq: Vec<i32> = (0..pn).map(|i| pseed.get(i % pseed.len().max(1)).copied().unwrap_or(0)).collect();
        let parent = with_parent.then_some(Parent { data: &pq, dims: &pdims });
        let kind = if coarse { BandKind::Coarse } else { BandKind::Detail };
        let bytes = block::encode(&q, &dims, kind, parent, shape);
        let back = block::decode(&bytes, &dims, kind, parent, shape).unwrap();
        prop_assert_eq!(back, q);
    }

    /// Coder 2's rate–distortion choice (`block::encode_rdo`) on any detail band, with
    /// or without its parent: the stream decodes to the indices it returns; each index
    /// is `round(|x|)`, one less, or 0, with the sign of `x`; at λ = 0 they are the
    /// rounded values and the stream is `block::encode`'s of them, byte for byte.
    #[test]
    fn coder2_rdo_streams_decode_to_the_indices_chosen(
        dims in dims(),
        seed in any::<u64>(),
        scale in prop_oneof![Just(0.7f32), Just(3.0), Just(40.0), Just(5000.0)],
        lambda in prop_oneof![Just(0.0f32), Just(0.1), Just(0.4), Just(3.0)],
        with_parent in any::<bool>(),
    ) {
        let n: usize = dims.iter().product();
        let x = values(n, seed, scale);
        let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
        let pq: Vec<i32> = values(pdims.iter().product(), seed ^ 7, scale)
            .iter()
            .map(|v| v.round() as i32)
            .collect();
        let parent = with_parent.then_some(Parent { data: &pq, dims: &pdims });
        let shape = Shape::coder2();
        let (bytes, q) = block::encode_rdo(&x, &dims, parent, shape, lambda);
        let back = block::decode(&bytes, &dims, BandKind::Detail, parent, shape).unwrap();
        prop_assert_eq!(&back, &q);
        for (&v, &i) in x.iter().zip(&q) {
            let a0 = (v.abs() + 0.5) as i32;
            let a = i.abs();
            prop_assert!(a == a0 || a == 0 || (a0 >= 2 && a == a0 - 1), "{} -> {}", v, i);
            prop_assert!(i == 0 || (i < 0) == (v < 0.0), "{} -> {}", v, i);
        }
        if lambda == 0.0 {
            // round half away from zero, in f32 as the encoder does
            let rounded: Vec<i32> = x
                .iter()
                .map(|&v| ((v.abs() + 0.5) as i32) * if v < 0.0 { -1 } else { 1 })
                .collect();
            prop_assert_eq!(&q, &rounded);
            prop_assert_eq!(bytes, block::encode(&rounded, &dims, BandKind::Detail, parent, shape));
        }
    }

    /// Damaged or arbitrary bytes decode to something or fail with an error, never a
    /// panic.
    #[test]
    fn arbitrary_bytes_never_panic(
        bytes in prop::collection::vec(any::<u8>(), 0..400),
        dims in dims(),
        coarse in any::<bool>(),
        coder2 in any::<bool>(),
    ) {
        let kind = if coarse { BandKind::Coarse } else { BandKind::Detail };
        let shape = if coder2 { Shape::coder2() } else { Shape::new(2, 4, 6) };
        let _ = block::decode(&bytes, &dims, kind, None, shape);
    }
}

/// Laplacian-like coefficients (in units of the step) of scale `scale`, from `seed`:
/// mostly small, a few large, both signs.
fn values(n: usize, seed: u64, scale: f32) -> Vec<f32> {
    let mut s = seed | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let u = ((s >> 11) as f64 / (1u64 << 53) as f64).max(1e-12);
            let m = (-u.ln() * 0.5) as f32 * scale;
            if s & 1 == 1 {
                -m
            } else {
                m
            }
        })
        .collect()
}

/// On a band of Laplacian coefficients, coder 2's own rate–distortion choice costs
/// less `D + λ·R` than rounding (`D` the squared error in steps², `R` the stream's
/// bits), and fewer bits; a larger λ spends fewer bits still.
#[test]
fn coder2_rdo_lowers_the_rate_distortion_cost() {
    let dims = [96usize, 128];
    let x = values(96 * 128, 99, 1.5);
    let shape = Shape::coder2();
    let cost = |lambda: f32| {
        let (bytes, q) = block::encode_rdo(&x, &dims, None, shape, lambda);
        let d: f64 = x
            .iter()
            .zip(&q)
            .map(|(&v, &i)| ((v - i as f32) as f64).powi(2))
            .sum();
        (d, bytes.len() as f64 * 8.0)
    };
    let (d0, r0) = cost(0.0);
    let (d1, r1) = cost(0.2);
    let (_, r2) = cost(1.0);
    assert!(
        d1 + 0.2 * r1 < d0 + 0.2 * r0,
        "{d1} + 0.2·{r1} against {d0} + 0.2·{r0}"
    );
    assert!(r1 < r0 && r2 < r1, "{r0} {r1} {r2}");
}

/// A stream cut short fails or decodes without a panic, and a band of one block whose
/// lengths point past the data is an error.
#[test]
fn truncated_bands_fail_cleanly() {
    let dims = [20usize, 30];
    let q: Vec<i32> = (0..600).map(|i: i32| (i * 7919) % 23 - 11).collect();
    let shape = Shape::new(1, 8, 8);
    let bytes = block::encode(&q, &dims, BandKind::Detail, None, shape);
    assert_eq!(
        block::decode(&bytes, &dims, BandKind::Detail, None, shape).unwrap(),
        q
    );
    for cut in 0..bytes.len() {
        let _ = block::decode(&bytes[..cut], &dims, BandKind::Detail, None, shape);
    }
    assert!(block::decode(
        &bytes[..bytes.len() - 1],
        &dims,
        BandKind::Detail,
        None,
        shape
    )
    .is_err());
}

/// Skewed symbols in several adaptive contexts and raw fields of 0 to 32 bits, coded
/// side by side, come back in order.
#[test]
fn symbols_and_raw_bits_round_trip() {
    let mut x = 12345u64;
    let mut rnd = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let seq: Vec<(usize, usize, u64, u32)> = (0..20000)
        .map(|i| {
            let r = rnd();
            let s = if i % 3 == 0 {
                (r % 16) as usize
            } else {
                (r % 3 == 0) as usize
            };
            let n = (r >> 20) as u32 % 33;
            (s, i % 5, rnd(), n)
        })
        .collect();
    let mut e = Encoder::new();
    let mut w = BitWriter::default();
    let mut cdfs = [Cdf::default(); 5];
    for &(s, c, v, n) in &seq {
        e.symbol(&mut cdfs[c], s);
        w.put(v, n);
    }
    let (bytes, raw) = (e.finish(), w.finish());
    // skewed contexts cost well under 4 bits a symbol
    assert!(bytes.len() * 8 < seq.len() * 3, "{} bytes", bytes.len());
    let mut d = Decoder::new(&bytes);
    let mut r = BitReader::new(&raw);
    let mut cdfs = [Cdf::default(); 5];
    for &(s, c, v, n) in &seq {
        assert_eq!(d.symbol(&mut cdfs[c]), s);
        assert_eq!(r.get(n), v & ((1u64 << n) - 1));
    }
}

/// A CDF adapted to one symbol gives it almost all the mass and keeps every other
/// symbol codable.
#[test]
fn every_symbol_keeps_a_frequency() {
    let mut c = Cdf::default();
    let mut e = Encoder::new();
    for _ in 0..10000 {
        e.symbol(&mut c, 7);
    }
    for s in 0..SYMBOLS {
        assert!(c.cost(s).is_finite(), "{s}");
    }
    assert!(c.cost(7) < 0.01, "{}", c.cost(7));
}

/// On real bands (kodim01 at 1 bpp): today's coder re-encodes the file's streams
/// byte for byte (the bands are read right), and the block coder gives every band's
/// indices back exactly in a few percent of today's bits.
#[test]
fn real_bands_round_trip_in_both_coders() {
    let Some((bs, file_len)) = kodim01_bands() else {
        return;
    };
    assert!(bs.bands.len() > 10);
    let shape = Shape::new(1, 64, 64);
    let (mut today, mut ours) = (0, 0);
    for (i, b) in bs.bands.iter().enumerate() {
        assert_eq!(bs.encode_today(i), b.stream, "band {i}");
        let s = block::encode(&b.q32, &b.dims, b.kind, bs.parent32(i), shape);
        let back = block::decode(&s, &b.dims, b.kind, bs.parent32(i), shape).unwrap();
        assert_eq!(back, b.q32, "band {i}");
        today += b.stream.len();
        ours += s.len();
    }
    // the streams are most of the file
    assert!(today * 10 > file_len * 9, "{today} of {file_len}");
    assert!(ours < today * 13 / 10, "{ours} against {today}");
}
