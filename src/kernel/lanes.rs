//! The few rows near the ends of many short lanes, several lanes at a time.

use super::*;

/// Most samples of a lane [`combine_lane_taps`] reads in registers (8 windows of 8).
pub(crate) const LANE_TAPS_SLOTS: usize = 64;

/// `y[t·ys + r] = Σ_k w_k · x[t·w + c_k]` for every lane `t < h` of `x` (lane `t` at
/// `x[t·w ..][..w]`) and every row `(r, taps)` of `rows` (`taps` the `(c_k, w_k)`, summed
/// as [`sum_terms`] says: the bits of [`Csr`]'s row kernel). For the few rows near the ends of a volume's lanes, which read a handful
/// of samples at either end of every lane: with AVX2 and 4-byte samples, 8 lanes at a
/// time, the windows of 8 samples the rows read transposed in registers (one load per
/// lane and window instead of one per tap and row), and the sums of 8 rows that follow
/// one another transposed back (one store per lane instead of one per row and lane).
/// [`LaneTaps`] prepares the rows once for many calls ([`combine_lane_taps_with`]).
#[cfg(any(test, feature = "testing"))]
pub fn combine_lane_taps<T: Sample>(
    k: Kernels,
    x: &[T],
    w: usize,
    h: usize,
    rows: &[(usize, Vec<(usize, T)>)],
    y: &mut [T],
    ys: usize,
) {
    let rows = rows
        .iter()
        .map(|(r, t)| (*r, t.iter().map(|&(c, wk)| (c, wk.to_f64())).collect()))
        .collect();
    combine_lane_taps_with(k, &LaneTaps::new(rows, w), x, h, y, ys)
}

/// The rows of [`combine_lane_taps`] (weights as `f64`, each used as `T::from_f64` of
/// it) for lanes of `w` samples, with what the vector build needs worked out once: the
/// windows of 8 samples that cover the taps and the groups of rows stored together.
#[derive(Clone, Debug)]
pub struct LaneTaps {
    pub(crate) w: usize,
    pub(crate) rows: Vec<(usize, Vec<(usize, f64)>)>,
    /// The windows' first samples (a tap at sample `c` of window `i` reads slot
    /// `8·i + c − bases[i]`); empty when they take more than [`LANE_TAPS_SLOTS`] slots or
    /// `w < 8`, and then no vector build runs.
    pub(crate) bases: Vec<usize>,
    /// Every row's terms ([`sum_terms`] of its `f32` weights) as `(slot, slot of the
    /// pair's second tap or usize::MAX, weight)`, row `i`'s at
    /// `slots[ends[i]..ends[i + 1]]`.
    pub(crate) slots: Vec<(usize, usize, f32)>,
    pub(crate) ends: Vec<usize>,
    /// Every row's pairs ([`pair_taps`]) with its weights as `f32`, and as `f64`.
    pub(crate) pairs32: Vec<Vec<usize>>,
    pub(crate) pairs64: Vec<Vec<usize>>,
    /// Rows summed and stored together: `(first row index, count ≤ 8)`, their outputs
    /// `r` following one another. A stretch of 8 or more such rows is covered by groups
    /// of 8 (the last overlapping the one before; its rows written twice, the same
    /// values), shorter ones by one group.
    pub(crate) groups: Vec<(usize, usize)>,
}

impl LaneTaps {
    /// `rows` as [`combine_lane_taps`] takes them, for lanes of `w` samples.
    pub fn new(rows: Vec<(usize, Vec<(usize, f64)>)>, w: usize) -> Self {
        for (_, taps) in &rows {
            assert!(taps.iter().all(|&(c, _)| c < w));
        }
        let mut cols: Vec<usize> = rows
            .iter()
            .flat_map(|(_, t)| t.iter().map(|p| p.0))
            .collect();
        cols.sort_unstable();
        cols.dedup();
        let mut bases: Vec<usize> = Vec::new();
        if w >= 8 {
            for &c in &cols {
                if bases.last().is_none_or(|&b| c >= b + 8) {
                    bases.push(c.min(w - 8));
                }
            }
        }
        if bases.len() * 8 > LANE_TAPS_SLOTS {
            bases.clear();
        }
        let slot = |c: usize| {
            let i = bases
                .iter()
                .position(|&b| b <= c && c < b + 8)
                .expect("covered");
            i * 8 + c - bases[i]
        };
        let (mut slots, mut ends) = (Vec::new(), vec![0]);
        if !bases.is_empty() {
            for (_, t) in &rows {
                let wf: Vec<f32> = t.iter().map(|&(_, wk)| wk as f32).collect();
                let mut partner = vec![0; t.len()];
                pair_taps(&wf, &mut partner);
                for (k, &(c, _)) in t.iter().enumerate() {
                    match partner[k] {
                        SECOND => {}
                        q if q == k => slots.push((slot(c), usize::MAX, wf[k])),
                        q => slots.push((slot(c), slot(t[q].0), wf[k])),
                    }
                }
                ends.push(slots.len());
            }
        }
        // stretches of rows whose outputs follow one another
        let mut groups = Vec::new();
        let mut i = 0;
        while i < rows.len() {
            let mut n = 1;
            while i + n < rows.len() && rows[i + n].0 == rows[i].0 + n {
                n += 1;
            }
            if n < 8 {
                groups.push((i, n));
            } else {
                groups.extend((0..n / 8).map(|g| (i + 8 * g, 8)));
                if n % 8 != 0 {
                    groups.push((i + n - 8, 8));
                }
            }
            i += n;
        }
        let pairs = |to: &dyn Fn(f64) -> f64| -> Vec<Vec<usize>> {
            rows.iter()
                .map(|(_, t)| {
                    let ws: Vec<f64> = t.iter().map(|&(_, wk)| to(wk)).collect();
                    let mut partner = vec![0; ws.len()];
                    pair_taps(&ws, &mut partner);
                    partner
                })
                .collect()
        };
        // (an f32 weight widened to f64 compares as the f32 did)
        let (pairs32, pairs64) = (pairs(&|v| v as f32 as f64), pairs(&|v| v));
        LaneTaps {
            w,
            rows,
            bases,
            slots,
            ends,
            pairs32,
            pairs64,
            groups,
        }
    }
}

/// [`combine_lane_taps`] with its rows prepared (`taps`, for lanes of `taps.w` samples).
pub fn combine_lane_taps_with<T: Sample>(
    k: Kernels,
    taps: &LaneTaps,
    x: &[T],
    h: usize,
    y: &mut [T],
    ys: usize,
) {
    let (w, rows) = (taps.w, &taps.rows);
    if h == 0 || rows.is_empty() {
        return;
    }
    assert!(x.len() >= h * w);
    for (r, _) in rows {
        assert!((h - 1) * ys + r < y.len());
    }
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if std::mem::size_of::<T>() == 4 && !taps.bases.is_empty() && k.avx2() {
        // SAFETY: AVX2 is present (a table holds no build the CPU lacks); T is a 4-byte float (f32), bounds checked above and
        // in `LaneTaps::new`.
        done = unsafe { lane_taps_avx2_f32(taps, x, h, y, ys) };
    }
    if done == h {
        return;
    }
    // the rows' pairs as `T` compares their weights (worked out once, in `LaneTaps::new`)
    let pairs = if std::mem::size_of::<T>() == 4 {
        &taps.pairs32
    } else {
        &taps.pairs64
    };
    for ((r, row), partner) in rows.iter().zip(pairs) {
        let mut ws = [T::default(); 32];
        let heap: Vec<T>;
        let ws: &[T] = if row.len() <= 32 {
            for (w, &(_, v)) in ws.iter_mut().zip(row) {
                *w = T::from_f64(v);
            }
            &ws[..row.len()]
        } else {
            heap = row.iter().map(|&(_, v)| T::from_f64(v)).collect();
            &heap
        };
        for t in done..h {
            let lane = &x[t * w..t * w + w];
            y[t * ys + r] = sum_terms(ws, partner, |k| lane[row[k].0]);
        }
    }
}
