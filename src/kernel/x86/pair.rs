//! AVX2 and AVX-512 builds of the pair kernels, one per pattern of `patterns.rs`.

use crate::kernel::*;
use crate::scheme::Build;

/// Dispatch of [`combine_pair`] to [`pair_avx2_f32`] / [`pair_avx2_f64`] (or their
/// AVX-512 builds at [`CpuLevel::Avx512`]): the kernel of table entry `entry`
/// ([`pair_entry`] of `rows`), over the steps `at` ([`PairSteps`]). `false` (nothing
/// written) when the type has no build, or the entry is not one of the inputs' count and
/// masks.
///
/// # Safety
/// AVX2 present, AVX-512F too at [`CpuLevel::Avx512`] (then the steps of at least one
/// 512-bit vector use it); every access inside its allocation, outputs distinct from
/// each other and from the inputs; the masks as [`combine_pair`] checks them.
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn pair_avx2_at<T: Sample>(
    entry: u8,
    rows: &PairRows<'_, T>,
    at: &PairSteps<'_, T>,
    level: CpuLevel,
) -> bool {
    let PairRows { w1, m1, w2, m2, .. } = *rows;
    let PairSteps {
        o,
        len,
        src,
        count,
        in_step,
        out_step,
        output,
    } = *at;
    let (merge, split) = (output == PairOutput::Merged, output == PairOutput::Split);
    let wide = level == CpuLevel::Avx512;
    let u = src.len();
    if u > PAIR_KERNEL_MOST || w1.len() != u || w2.len() != u {
        return false;
    }
    debug_assert_eq!(pair_entry(w1, m1, w2, m2), Some(entry));
    macro_rules! go {
        ($t:ty, $as:ident, $f:ident, $g:ident, $U:literal, $M1:literal, $M2:literal, $P1:literal, $N1:literal, $P2:literal, $N2:literal, $R1:expr, $R2:expr) => {{
            let wide = wide && len >= 64 / std::mem::size_of::<$t>();
            // (plain loops: the closures of `array::from_fn` were not inlined here)
            let (mut a, mut b) = ([0.0 as $t; $U], [0.0 as $t; $U]);
            for k in 0..$U {
                (a[k], b[k]) = (w1[k].to_f64() as $t, w2[k].to_f64() as $t);
            }
            // the pointers as $t's (`Some` for that type only: `Sample::f32_ptr`, `f64_ptr`)
            let (Some(o0), Some(o1)) = (T::$as(o[0]), T::$as(o[1])) else {
                return false;
            };
            let mut base = [std::ptr::null::<$t>(); $U];
            for k in 0..$U {
                base[k] = T::$as(src[k].cast_mut()).map_or(base[k], |q| q.cast_const());
            }
            for t in 0..count {
                // SAFETY: the caller's bounds.
                unsafe {
                    let mut p = [std::ptr::null::<$t>(); $U];
                    for k in 0..$U {
                        p[k] = base[k].add(t * in_step);
                    }
                    let q1 = o0.add(t * out_step[0]);
                    let q2 = o1.add(t * out_step[1]);
                    match (wide, merge, split) {
                        (true, true, _) => {
                            $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, { $R1 }, { $R2 }, true, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (true, false, true) => {
                            $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, { $R1 }, { $R2 }, false, true>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (true, false, false) => {
                            $g::<$U, $M1, $M2, $P1, $N1, $P2, $N2, { $R1 }, { $R2 }, false, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (false, true, _) => {
                            $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, { $R1 }, { $R2 }, true, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (false, false, true) => {
                            $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, { $R1 }, { $R2 }, false, true>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                        (false, false, false) => {
                            $f::<$U, $M1, $M2, $P1, $N1, $P2, $N2, { $R1 }, { $R2 }, false, false>(
                                q1, q2, len, &p, &a, &b,
                            )
                        }
                    }
                }
            }
            return true;
        }};
    }
    // the entry's kernel (its inputs' count and masks checked: they decide what it reads)
    macro_rules! table {
        ($(($U:literal, $M1:literal, $M2:literal, $P1:literal, $N1:literal, $P2:literal, $N2:literal, $R1:expr, $R2:expr)),*) => {
            let mut idx = 0u8;
            $(
                if entry == idx && (u, m1, m2) == ($U, $M1, $M2) {
                    match T::BUILD {
                        Build::F32 => go!(f32, f32_ptr, pair_avx2_f32, pair_avx512_f32, $U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2),
                        Build::F64 => go!(f64, f64_ptr, pair_avx2_f64, pair_avx512_f64, $U, $M1, $M2, $P1, $N1, $P2, $N2, $R1, $R2),
                        Build::Plain => {}
                    }
                }
                idx += 1;
            )*
            let _ = idx;
        };
    }
    pair_patterns!(table);
    false
}

/// `$body` for `$k` = 0, 1, … 23 ([`PAIR_KERNEL_MOST`]), each copy with its `$k` a
/// constant (the pair kernels' tap loops, which the compiler must see whole to fold their
/// masks).
macro_rules! unroll24 {
    ($k:ident, $body:block) => {
        unroll24!(@ $k, $body, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23)
    };
    (@ $k:ident, $body:block, $($n:literal),*) => {
        $( { let $k: usize = $n; $body } )*
    };
}

/// The body of [`combine_pair`] for one pattern: a vector of each output per step, every
/// input loaded once; then scalars.
macro_rules! pair_avx2_body {
    ($name:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $zero:ident, $mul:ident, $add:ident, $sub:ident, $fma:ident, $load:ident, $store:ident, $merge:ident, $split:ident) => {
        /// See [`pair_avx2_body`].
        ///
        /// # Safety
        /// The target feature present; `o1`, `o2` and every `p[k]` valid for `len` samples; `M1`, `M2`
        /// non-empty within `U` bits.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feat)]
        pub(crate) unsafe fn $name<
            const U: usize,
            const M1: u32,
            const M2: u32,
            const P1: u32,
            const N1: u32,
            const P2: u32,
            const N2: u32,
            const R1: u128,
            const R2: u128,
            const MERGE: bool,
            const SPLIT: bool,
        >(
            o1: *mut $t,
            o2: *mut $t,
            len: usize,
            p: &[*const $t; U],
            w1: &[$t; U],
            w2: &[$t; U],
        ) {
            use std::arch::x86_64::*;
            const L: usize = $lanes;
            let (f1, f2) = (M1.trailing_zeros() as usize, M2.trailing_zeros() as usize);
            let mut v1 = [$zero(); U];
            let mut v2 = [$zero(); U];
            for k in 0..U {
                v1[k] = $set1(w1[k]);
                v2[k] = $set1(w2[k]);
            }
            let (s1, s2) = (Seconds::<R1>::MASK, Seconds::<R2>::MASK);
            let minus = $set1(-1.0);
            // one vector of each output at `i`: the terms of `pair_taps` in order, a tap of
            // weight ±1 added or subtracted (`w·x` is `±x` exactly: the same bits)
            macro_rules! calc {
                ($i:expr) => {{
                    let i = $i;
                    let x: [_; U] = std::array::from_fn(|k| {
                        if (M1 | M2) >> k & 1 == 1 {
                            $load(p[k].add(i))
                        } else {
                            $zero()
                        }
                    });
                    macro_rules! out {
                        ($v:ident, $m:ident, $f:ident, $p:ident, $n:ident, $r:ident, $s:ident) => {{
                            let mut acc = $zero();
                            unroll24!(k, {
                                if k < U && $m >> k & 1 == 1 && $s >> k & 1 == 0 {
                                    let j = ($r >> (PAIR_FIELD * k) & 31) as usize;
                                    let v = if j > 0 { $add(x[k], x[j - 1]) } else { x[k] };
                                    acc = if k == $f {
                                        if $p >> k & 1 == 1 {
                                            v
                                        } else if $n >> k & 1 == 1 {
                                            $mul(minus, v)
                                        } else {
                                            $mul($v[k], v)
                                        }
                                    } else if $p >> k & 1 == 1 {
                                        $add(acc, v)
                                    } else if $n >> k & 1 == 1 {
                                        $sub(acc, v)
                                    } else if j > 0 {
                                        $fma(v, $v[k], acc)
                                    } else {
                                        $add(acc, $mul($v[k], v))
                                    };
                                }
                            });
                            acc
                        }};
                    }
                    (
                        out!(v1, M1, f1, P1, N1, R1, s1),
                        out!(v2, M2, f2, P2, N2, R2, s2),
                    )
                }};
            }
            // scalars at `i`
            macro_rules! calc1 {
                ($i:expr) => {{
                    let i = $i;
                    let x: [$t; U] = std::array::from_fn(|k| {
                        if (M1 | M2) >> k & 1 == 1 {
                            *p[k].add(i)
                        } else {
                            0.0
                        }
                    });
                    macro_rules! out {
                        ($w:ident, $m:ident, $f:ident, $p:ident, $n:ident, $r:ident, $s:ident) => {{
                            let mut acc: $t = 0.0;
                            unroll24!(k, {
                                if k < U && $m >> k & 1 == 1 && $s >> k & 1 == 0 {
                                    let j = ($r >> (PAIR_FIELD * k) & 31) as usize;
                                    let v = if j > 0 { x[k] + x[j - 1] } else { x[k] };
                                    acc = if k == $f {
                                        if $p >> k & 1 == 1 {
                                            v
                                        } else if $n >> k & 1 == 1 {
                                            -v
                                        } else {
                                            $w[k] * v
                                        }
                                    } else if $p >> k & 1 == 1 {
                                        acc + v
                                    } else if $n >> k & 1 == 1 {
                                        acc - v
                                    } else if j > 0 {
                                        v.mul_add($w[k], acc)
                                    } else {
                                        acc + $w[k] * v
                                    };
                                }
                            });
                            acc
                        }};
                    }
                    (
                        out!(w1, M1, f1, P1, N1, R1, s1),
                        out!(w2, M2, f2, P2, N2, R2, s2),
                    )
                }};
            }
            if SPLIT {
                // each output split into its even samples, then its odd ones (as
                // `deinterleave` does), two vectors at a time
                let ne = len.div_ceil(2);
                let mut i = 0;
                // SAFETY: i + 2L <= len; the even outputs i/2.. < ne, the odd ones
                // ne + i/2 + L <= ne + len/2 <= len.
                unsafe {
                    while i + 2 * L <= len {
                        let (a1, a2) = calc!(i);
                        let (b1, b2) = calc!(i + L);
                        let (e1, d1) = $split!(a1, b1);
                        let (e2, d2) = $split!(a2, b2);
                        $store(o1.add(i / 2), e1);
                        $store(o1.add(ne + i / 2), d1);
                        $store(o2.add(i / 2), e2);
                        $store(o2.add(ne + i / 2), d2);
                        i += 2 * L;
                    }
                    while i < len {
                        let (a1, a2) = calc1!(i);
                        let at = if i % 2 == 0 { i / 2 } else { ne + i / 2 };
                        *o1.add(at) = a1;
                        *o2.add(at) = a2;
                        i += 1;
                    }
                }
                return;
            }
            macro_rules! step {
                ($i:expr) => {{
                    let i = $i;
                    let (a1, a2) = calc!(i);
                    if MERGE {
                        // o1[2i] = a1[i], o1[2i + 1] = a2[i]
                        let (lo, hi) = $merge!(a1, a2);
                        $store(o1.add(2 * i), lo);
                        $store(o1.add(2 * i + L), hi);
                    } else {
                        $store(o1.add(i), a1);
                        $store(o2.add(i), a2);
                    }
                }};
            }
            let mut i = 0;
            // SAFETY (all blocks): i + width <= len, so every access is inside the runs.
            unsafe {
                while i + L <= len {
                    step!(i);
                    i += L;
                }
                if i < len && len >= L {
                    // the last vector again, ending at `len` (its first samples
                    // recomputed: the same sums, the same bits, no aliasing as the
                    // outputs and inputs are apart) instead of scalars; outside the
                    // loop, whose control it would otherwise lengthen by a third
                    step!(len - L);
                    i = len;
                }
                while i < len {
                    let (a1, a2) = calc1!(i);
                    if MERGE {
                        *o1.add(2 * i) = a1;
                        *o1.add(2 * i + 1) = a2;
                    } else {
                        *o1.add(i) = a1;
                        *o2.add(i) = a2;
                    }
                    i += 1;
                }
            }
        }
    };
}

/// The two vectors `a`, `b` interleaved, `(a0 b0 a1 b1 …)`, as two vectors (macros, so
/// that they inline into the kernels).
macro_rules! merge_ps256 {
    ($a:expr, $b:expr) => {{
        let (lo, hi) = (_mm256_unpacklo_ps($a, $b), _mm256_unpackhi_ps($a, $b));
        (
            _mm256_permute2f128_ps::<0x20>(lo, hi),
            _mm256_permute2f128_ps::<0x31>(lo, hi),
        )
    }};
}
macro_rules! merge_pd256 {
    ($a:expr, $b:expr) => {{
        let (lo, hi) = (_mm256_unpacklo_pd($a, $b), _mm256_unpackhi_pd($a, $b));
        (
            _mm256_permute2f128_pd::<0x20>(lo, hi),
            _mm256_permute2f128_pd::<0x31>(lo, hi),
        )
    }};
}
macro_rules! merge_ps512 {
    ($a:expr, $b:expr) => {{
        let lo = _mm512_setr_epi32(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
        let hi = _mm512_setr_epi32(8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31);
        (
            _mm512_permutex2var_ps($a, lo, $b),
            _mm512_permutex2var_ps($a, hi, $b),
        )
    }};
}
macro_rules! merge_pd512 {
    ($a:expr, $b:expr) => {{
        let lo = _mm512_setr_epi64(0, 8, 1, 9, 2, 10, 3, 11);
        let hi = _mm512_setr_epi64(4, 12, 5, 13, 6, 14, 7, 15);
        (
            _mm512_permutex2var_pd($a, lo, $b),
            _mm512_permutex2var_pd($a, hi, $b),
        )
    }};
}
/// Two vectors `a`, `b` of consecutive samples `(x0 x1 … )` split into their even samples
/// `(x0 x2 …)` and their odd ones `(x1 x3 …)` (the inverse of the `merge_*` macros).
macro_rules! split_ps256 {
    ($a:expr, $b:expr) => {{
        let ev = _mm256_shuffle_ps::<0x88>($a, $b); // x0 x2 x8 x10 | x4 x6 x12 x14
        let od = _mm256_shuffle_ps::<0xDD>($a, $b); // x1 x3 x9 x11 | x5 x7 x13 x15
        (
            _mm256_castpd_ps(_mm256_permute4x64_pd::<0xD8>(_mm256_castps_pd(ev))),
            _mm256_castpd_ps(_mm256_permute4x64_pd::<0xD8>(_mm256_castps_pd(od))),
        )
    }};
}
macro_rules! split_pd256 {
    ($a:expr, $b:expr) => {{
        let (ev, od) = (_mm256_unpacklo_pd($a, $b), _mm256_unpackhi_pd($a, $b));
        (
            _mm256_permute4x64_pd::<0xD8>(ev),
            _mm256_permute4x64_pd::<0xD8>(od),
        )
    }};
}
macro_rules! split_ps512 {
    ($a:expr, $b:expr) => {{
        let ev = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
        let od = _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
        (
            _mm512_permutex2var_ps($a, ev, $b),
            _mm512_permutex2var_ps($a, od, $b),
        )
    }};
}
macro_rules! split_pd512 {
    ($a:expr, $b:expr) => {{
        let ev = _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14);
        let od = _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15);
        (
            _mm512_permutex2var_pd($a, ev, $b),
            _mm512_permutex2var_pd($a, od, $b),
        )
    }};
}
/// The four builds of the tap loops ([`taps_avx2_body`]) and of the pair loops
/// ([`pair_avx2_body`]): one line each, its names, target feature, type, lanes and
/// intrinsics.
macro_rules! builds {
    ($($taps:ident, $pair:ident, $feat:literal, $t:ty, $lanes:expr, $set1:ident, $zero:ident, $mul:ident, $add:ident, $sub:ident, $fma:ident, $load:ident, $store:ident, $merge:ident, $split:ident;)*) => {
        $(
            taps_avx2_body!($taps, $feat, $t, $lanes, $set1, $zero, $mul, $add, $load, $store);
            pair_avx2_body!($pair, $feat, $t, $lanes, $set1, $zero, $mul, $add, $sub, $fma, $load, $store, $merge, $split);
        )*
    };
}

builds! {
    taps_avx2_f32, pair_avx2_f32, "avx2,fma", f32, 8, _mm256_set1_ps, _mm256_setzero_ps, _mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps, _mm256_fmadd_ps, _mm256_loadu_ps, _mm256_storeu_ps, merge_ps256, split_ps256;
    taps_avx2_f64, pair_avx2_f64, "avx2,fma", f64, 4, _mm256_set1_pd, _mm256_setzero_pd, _mm256_mul_pd, _mm256_add_pd, _mm256_sub_pd, _mm256_fmadd_pd, _mm256_loadu_pd, _mm256_storeu_pd, merge_pd256, split_pd256;
    taps_avx512_f32, pair_avx512_f32, "avx512f,fma", f32, 16, _mm512_set1_ps, _mm512_setzero_ps, _mm512_mul_ps, _mm512_add_ps, _mm512_sub_ps, _mm512_fmadd_ps, _mm512_loadu_ps, _mm512_storeu_ps, merge_ps512, split_ps512;
    taps_avx512_f64, pair_avx512_f64, "avx512f,fma", f64, 8, _mm512_set1_pd, _mm512_setzero_pd, _mm512_mul_pd, _mm512_add_pd, _mm512_sub_pd, _mm512_fmadd_pd, _mm512_loadu_pd, _mm512_storeu_pd, merge_pd512, split_pd512;
}
