//! The Exp-Golomb tail both coefficient codings share: `v ≥ 1` with `v ∈ [2^e, 2^(e+1))`
//! as `e` ones and a zero read with the adaptive models `prefix[min(i, len − 1)]`, then
//! the top mantissa bit with `top[e]`, then the other `e − 1` bits raw, high first.

use super::range::{Decoder, Encoder, Model};
use crate::{Error, Result};

/// Code `v ≥ 1`.
#[inline(always)]
pub fn encode<M: Model>(e: &mut Encoder, prefix: &mut [M], top: &mut [M], v: u64) {
    let last = prefix.len() - 1;
    let nb = 63 - v.leading_zeros() as usize; // v in [2^nb, 2^(nb+1))
    for k in 0..nb {
        e.bit(&mut prefix[k.min(last)], true);
    }
    e.bit(&mut prefix[nb.min(last)], false);
    if nb > 0 {
        e.bit(&mut top[nb], (v >> (nb - 1)) & 1 == 1);
        for j in (0..nb - 1).rev() {
            e.raw((v >> j) & 1 == 1);
        }
    }
}

/// Decode what [`encode`] wrote; fails on an exponent over 62.
#[inline(always)]
pub fn decode<M: Model>(d: &mut Decoder, prefix: &mut [M], top: &mut [M]) -> Result<u64> {
    let last = prefix.len() - 1;
    let mut nb = 0usize;
    while d.bit(&mut prefix[nb.min(last)]) {
        nb += 1;
        if nb > 62 {
            return Err(Error::format(
                "coefficient exponent over 62",
                "a valid band",
            ));
        }
    }
    let mut v: u64 = 1;
    if nb > 0 {
        v = (v << 1) | d.bit(&mut top[nb]) as u64;
        for _ in 0..nb - 1 {
            v = (v << 1) | d.raw() as u64;
        }
    }
    Ok(v)
}

/// The index of magnitude `a` and sign `neg`: `−a` (wrapping, so `a = 2^63` gives
/// `i64::MIN`) or `a`.
#[inline(always)]
pub fn signed(a: u64, neg: bool) -> i64 {
    if neg {
        0u64.wrapping_sub(a) as i64
    } else {
        a as i64
    }
}
