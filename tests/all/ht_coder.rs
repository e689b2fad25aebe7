//! The HT-style code-block coder (`entropy::block::ht`): exact round trips of random
//! bands of every shape (1 to 4 axes, odd extents, 1×1 and odd code-blocks, 3-D blocks,
//! the whole `i32` range, all-zero bands), with the standard codes and with codes
//! trained on the data, in both quad alphabets; damaged streams; and on real bands
//! (kodim01 at 1 bpp, when the corpus is present) the indices back exactly.

use super::block_coder::{band_of, dims, index, kodim01_bands};

use mra::entropy::block::ht::{Counts, Kind, Tables};
use mra::entropy::block::{self, Parent, Shape};
use mra::entropy::BandKind;
use proptest::prelude::*;

/// The codes trained on `q` itself (in `joint` alphabet), as the bench trains them.
fn trained(
    q: &[i32],
    dims: &[usize],
    kind: BandKind,
    par: Option<Parent>,
    shape: Shape,
    k: Kind,
) -> Tables {
    let mut n = Counts::new(k);
    let flat = n.tables();
    block::encode_ht(q, dims, kind, par, shape, &flat, Some(&mut n));
    n.tables()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Every band comes back exactly, in any code-block shape, as a detail band and as
    /// the coarsest band, with the standard codes and with trained ones of either alphabet.
    #[test]
    fn ht_bands_round_trip_exactly(
        (dims, q) in dims().prop_flat_map(band_of),
        z in 1usize..=5, y in 1usize..=9, x in 1usize..=9,
        coarse in any::<bool>(),
        pseed in prop::collection::vec(index(), 0..200),
        levels in 1u8..=4,
        parent in any::<bool>(),
    ) {
        let shape = Shape::new(z, y, x);
        let kind = if coarse { BandKind::Coarse } else { BandKind::Detail };
        let pdims: Vec<usize> = dims.iter().map(|d| d.div_ceil(2)).collect();
        let pn: usize = pdims.iter().product();
        let pq: Vec<i32> = (0..pn).map(|i| pseed.get(i % pseed.len().max(1)).copied().unwrap_or(0)).collect();
        let par = Some(Parent { data: &pq, dims: &pdims });
        // levels 1: the standard codes
        let t = match levels {
            1 => Tables::standard().clone(),
            l => trained(&q, &dims, kind, par, shape, Kind { levels: l, parent }),
        };
        let bytes = block::encode_ht(&q, &dims, kind, par, shape, &t, None);
        let back = block::decode_ht(&bytes, &dims, kind, par, shape, &t).unwrap();
        prop_assert_eq!(back, q);
    }

    /// Damaged or arbitrary bytes decode to something or fail with an error, never a
    /// panic.
    #[test]
    fn ht_arbitrary_bytes_never_panic(
        bytes in prop::collection::vec(any::<u8>(), 0..400),
        dims in dims(),
        coarse in any::<bool>(),
    ) {
        let kind = if coarse { BandKind::Coarse } else { BandKind::Detail };
        let _ = block::decode_ht(&bytes, &dims, kind, None, Shape::new(2, 4, 6), Tables::standard());
    }
}

/// All-zero bands cost little more than a byte or two a block; a band of one huge value
/// among zeros, single positions and 3-D blocks come back; a stream cut short fails
/// cleanly.
#[test]
fn ht_edge_bands() {
    let t = Tables::standard();
    for (dims, shape) in [
        (vec![256usize, 256], Shape::new(1, 64, 64)),
        (vec![1], Shape::new(1, 1, 1)),
        (vec![1, 1], Shape::new(1, 1, 1)),
        (vec![9, 17, 33], Shape::new(4, 8, 16)),
        (vec![3, 5, 7, 11], Shape::new(2, 3, 5)),
    ] {
        let n: usize = dims.iter().product();
        let zero = vec![0i32; n];
        let bytes = block::encode_ht(&zero, &dims, BandKind::Detail, None, shape, t, None);
        if n >= 1 << 16 {
            // the run coder: under a sixteenth of a bit a position
            assert!(bytes.len() * 8 * 16 < n, "{dims:?}: {} bytes", bytes.len());
        }
        assert_eq!(
            block::decode_ht(&bytes, &dims, BandKind::Detail, None, shape, t).unwrap(),
            zero
        );
        for v in [i32::MIN, i32::MAX, -1, 1, 2, 1 << 20] {
            let mut q = zero.clone();
            q[n / 2] = v;
            q[n - 1] = -v.wrapping_add(1);
            for kind in [BandKind::Detail, BandKind::Coarse] {
                let bytes = block::encode_ht(&q, &dims, kind, None, shape, t, None);
                assert_eq!(
                    block::decode_ht(&bytes, &dims, kind, None, shape, t).unwrap(),
                    q,
                    "{dims:?} {v}"
                );
            }
        }
    }
    let dims = [20usize, 30];
    let q: Vec<i32> = (0..600).map(|i: i32| (i * 7919) % 23 - 11).collect();
    let shape = Shape::new(1, 8, 8);
    let bytes = block::encode_ht(&q, &dims, BandKind::Detail, None, shape, t, None);
    for cut in 0..bytes.len() {
        let _ = block::decode_ht(&bytes[..cut], &dims, BandKind::Detail, None, shape, t);
    }
    assert!(block::decode_ht(
        &bytes[..bytes.len() - 1],
        &dims,
        BandKind::Detail,
        None,
        shape,
        t
    )
    .is_err());
}

/// On real bands (kodim01 at 1 bpp) the HT-style coder gives every band's indices back
/// exactly, within a third more bits than today's coder.
#[test]
fn ht_real_bands_round_trip() {
    let Some((bs, _)) = kodim01_bands() else {
        return;
    };
    let shape = Shape::new(1, 256, 256);
    let (mut today, mut ours) = (0, 0);
    for (i, b) in bs.bands.iter().enumerate() {
        let s = block::encode_ht(
            &b.q32,
            &b.dims,
            b.kind,
            bs.parent32(i),
            shape,
            Tables::standard(),
            None,
        );
        let back = block::decode_ht(
            &s,
            &b.dims,
            b.kind,
            bs.parent32(i),
            shape,
            Tables::standard(),
        )
        .unwrap();
        assert_eq!(back, b.q32);
        today += b.stream.len();
        ours += s.len();
    }
    assert!(ours < today * 4 / 3, "{ours} against {today}");
}
