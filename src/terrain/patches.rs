//! The patches of one synthesized level (notes §9.7.4): which example window each patch
//! of the output's coarse grid takes its details from, and how the patches' details are
//! blended into the level's detail bands.
//!
//! **Candidates.** At the coarsest level (no parent) a grid of at most `candidates`
//! example windows offset by the seed, a pick among the `choices` best; below it the
//! parent patch's source and those of its 8 neighbours, each doubled to this level and
//! moved by up to one cell (so ridges and valleys continue from level to level and from
//! patch to patch), plus a sparse grid of `candidates/16` windows, the best one kept.
//! With a base scale above the base's own (`--base-scale`), the finer levels search
//! nothing: each patch takes its parent's source doubled, so every coarsest patch is one
//! piece of the example transplanted with all its levels in register ([`inherits`]).
//!
//! **Blending.** Each detail sample gathers the (up to four) patches whose windows cover
//! it, with separable ramps `w` rising over `2o` cells across each border; patches taking
//! the same source shift count once with their weights summed, and the distinct ones are
//! blended as `Σ Wᵢ Dᵢ / √(Σ Wᵢ²)`. Each band is then scaled to the RMS of the example's
//! band at the same level.

use rayon::prelude::*;

use super::matching::{distance, Tables, LEN};
use super::options::{Details, SynthOptions};
use super::Grid;
use crate::generate::rng::SplitMix64;
use crate::{Error, Result};

/// The matching distance `Σ (z_t − z_e)²/q² + λ ((g_t − g_e)/(g_t + g_e + ε))²`, or
/// any value ≥ `bound` as soon as the partial sum of the height term reaches `bound`
/// (the sum only grows, and rounding is monotone, so a candidate rejected early would
/// have been rejected anyway: the choice is unchanged).
pub(super) fn distance_below(t: &[f32], e: &[f32], lambda: f64, bound: f64) -> f64 {
    let q2 = t.len() - 1;
    let limit = bound * q2 as f64;
    let mut s = 0.0f32;
    for (tc, ec) in t[..q2].chunks(16).zip(e[..q2].chunks(16)) {
        for (a, b) in tc.iter().zip(ec) {
            let d = a - b;
            s += d * d;
        }
        if s as f64 >= limit {
            return bound;
        }
    }
    let (gt, ge) = (t[q2] as f64, e[q2] as f64);
    let r = (gt - ge) / (gt + ge + 1e-9);
    s as f64 / q2 as f64 + lambda * r * r
}

/// Ramp weight of band-local index `i` for a core `[t, t + p)` with overlap `o`
/// (`first`/`last`: no ramp on that side).
pub(super) fn ramp(i: usize, t: usize, p: usize, o: usize, first: bool, last: bool) -> f64 {
    let i = i as f64 + 0.5;
    let (t, p, o) = (t as f64, p as f64, o as f64);
    let mut w: f64 = 1.0;
    if !first && o > 0.0 {
        w = w.min((i - (t - o)) / (2.0 * o));
    }
    if !last && o > 0.0 {
        w = w.min(((t + p + o) - i) / (2.0 * o));
    }
    w.clamp(0.0, 1.0)
}

/// Patch origins along an axis of `n` coarse cells.
pub(super) fn origins(n: usize, p: usize) -> Vec<usize> {
    (0..n).step_by(p).collect()
}

/// The candidate for a target feature `f`: one of the `o.choices` nearest example features
/// (distance of [`distance_below`], comparisons cut off past the current k-th best),
/// picked by the patch's own seeded generator. Returns (candidate index, distance).
pub(super) fn pick_match(
    f: &[f32],
    feats: &[Vec<f32>],
    o: &SynthOptions,
    level: usize,
    idx: usize,
) -> (usize, f64) {
    let k = o.choices.max(1);
    let mut best: Vec<(f64, usize)> = Vec::with_capacity(k + 1);
    for (ci, ef) in feats.iter().enumerate() {
        let bound = if best.len() < k {
            f64::INFINITY
        } else {
            best[k - 1].0
        };
        let d = distance_below(f, ef, o.slope_weight, bound);
        if best.len() < k || d < best[best.len() - 1].0 {
            let pos = best.partition_point(|b| b.0 <= d);
            best.insert(pos, (d, ci));
            best.truncate(k);
        }
    }
    let mut r = mix(o.seed, level, idx);
    let pick = best[(r.next_u64() % best.len() as u64) as usize];
    (pick.1, pick.0)
}

pub(super) fn mix(seed: u64, level: usize, patch: usize) -> SplitMix64 {
    let mut r = SplitMix64::new(
        seed ^ (level as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (patch as u64).wrapping_mul(0xD1B5_4A32_D192_ED03),
    );
    r.next_u64();
    r
}

/// The source chosen for every patch of a level: window-origin shifts `(s_y, s_x)`
/// (example index = output index + shift, in coarse cells), patches row-major.
pub(super) struct Shifts {
    pub(super) rows: usize,
    pub(super) cols: usize,
    shift: Vec<(i64, i64)>,
    /// Relief gain of each patch (see [`SynthOptions::relief_cap`]).
    gain: Vec<f64>,
}

impl Shifts {
    fn at(&self, a: usize, b: usize) -> (i64, i64) {
        self.shift[a.min(self.rows - 1) * self.cols + b.min(self.cols - 1)]
    }

    fn gain_at(&self, a: usize, b: usize) -> f64 {
        self.gain[a.min(self.rows - 1) * self.cols + b.min(self.cols - 1)]
    }
}

/// Top-left of the `q`-window around the core at `t` (overlap `o`), kept inside `[0, n − q]`.
fn window_origin(t: usize, o: usize, q: usize, n: usize) -> usize {
    t.saturating_sub(o).min(n - q)
}
/// Details for one level: the Mallat block of `m_y × m_x` whose coarse part is `t`, the
/// source of every patch and the mean matching distance (candidates as in the module's
/// notes).
pub(super) fn level_details(
    t: &Grid,
    (e, ne_y, ne_x): &(Grid, usize, usize),
    (m_y, m_x): (usize, usize),
    o: &SynthOptions,
    level: usize,
    parent: Option<&Shifts>,
) -> Result<(Grid, Shifts, f64)> {
    let (n_y, n_x) = (t.h(), t.w());
    let p = o.patch;
    let q = (p + 2 * o.overlap).min(n_y).min(n_x);
    let cnt = window_count(e, (*ne_y, *ne_x), q, level)?;
    let (npy, npx) = (n_y.div_ceil(p), n_x.div_ceil(p));
    let mut shifts = Shifts {
        rows: npy,
        cols: npx,
        shift: vec![(0, 0); npy * npx],
        gain: vec![1.0; npy * npx],
    };
    let mut mean_d = 0.0;
    let inherit = parent.filter(|_| o.details == Details::Matched && inherits(o, level));
    match o.details {
        Details::Matched if inherit.is_some() => {
            let par = inherit.unwrap_or_else(|| unreachable!());
            let tables = Tables::new(&e.crop(*ne_y, *ne_x));
            let chosen: Vec<((i64, i64), f64)> = (0..npy * npx)
                .into_par_iter()
                .map(|idx| inherited(&tables, t, (idx / npx, idx % npx), cnt, q, o, par))
                .collect();
            mean_d = chosen.iter().map(|c| c.1).sum::<f64>() / chosen.len().max(1) as f64;
            shifts.shift = chosen.into_iter().map(|c| c.0).collect();
            // the relief gain of the piece, too
            shifts.gain = (0..npy * npx)
                .map(|idx| par.gain_at((idx / npx) * p / 2 / p, (idx % npx) * p / 2 / p))
                .collect();
        }
        Details::Matched => {
            let cands = Candidates::new(&e.crop(*ne_y, *ne_x), cnt, q, o, level, parent.is_some());
            let chosen: Vec<((i64, i64), f64, f64)> = (0..npy * npx)
                .into_par_iter()
                .map(|idx| cands.choose(t, (idx / npx, idx % npx), o, level, idx, parent))
                .collect();
            mean_d = chosen.iter().map(|c| c.1).sum::<f64>() / chosen.len().max(1) as f64;
            shifts.gain = chosen.iter().map(|c| c.2).collect();
            shifts.shift = chosen.into_iter().map(|c| c.0).collect();
        }
        Details::Copy => copy_shifts(&mut shifts, (n_y, n_x), cnt, p, o.overlap),
        Details::None => {}
    }
    let mut acc = Grid::zeros(m_y, m_x, t.c());
    if o.details != Details::None {
        blend(
            &mut acc,
            (n_y, n_x),
            e,
            (*ne_y, *ne_x),
            &shifts,
            p,
            o.overlap,
        );
        if o.details == Details::Matched {
            match_band_rms(&mut acc, (n_y, n_x), e, (*ne_y, *ne_x));
            if o.relief_cap > 0.0 {
                relief_gain(&mut acc, (n_y, n_x), &shifts, p, o.overlap);
            }
        }
    }
    acc.paste(t);
    Ok((acc, shifts, mean_d))
}

/// Whether the patches of `level` (which has a parent level) take their parents' sources
/// as they are (doubled, not searched again): with a base scale above the base's own, at
/// every level finer than the coarsest, so that each coarsest patch of the result holds
/// the details of one piece of the example at every level, in register (a ridge is the
/// sum of its levels' details; a source moved by one cell at one level breaks it into
/// bumps). Patches are then joined level by level over their overlaps: wide ramps at the
/// coarse levels, narrow ones at the fine (a multiresolution blend).
fn inherits(o: &SynthOptions, _level: usize) -> bool {
    o.base_scale > 1
}

/// The source of patch `(a, b)` of `t` taken from its parent: the parent's shift doubled
/// (example index = output index + shift at each level), the window kept inside the
/// `cnt` origins; with the matching distance of that window.
fn inherited(
    tables: &Tables,
    t: &Grid,
    (a, b): (usize, usize),
    cnt: (usize, usize),
    q: usize,
    o: &SynthOptions,
    par: &Shifts,
) -> ((i64, i64), f64) {
    let p = o.patch;
    let wy = window_origin(a * p, o.overlap, q, t.h());
    let wx = window_origin(b * p, o.overlap, q, t.w());
    let sh = par.at((a * p / 2) / p, (b * p / 2) / p);
    let y = (wy as i64 + 2 * sh.0).clamp(0, cnt.0 as i64 - 1);
    let x = (wx as i64 + 2 * sh.1).clamp(0, cnt.1 as i64 - 1);
    let (mut f, mut v) = ([0.0f32; LEN], [0.0f32; LEN]);
    Tables::window_descriptor(t, wy, wx, q, &mut f);
    tables.descriptor(y as usize, x as usize, q, &mut v);
    (
        (y - wy as i64, x - wx as i64),
        distance(&f, &v, o.slope_weight),
    )
}

/// The number of example window origins `(rows, columns)` for windows of `q`: they must
/// lie inside the example's coarse grid and its detail bands; an error when not one fits.
fn window_count(
    e: &Grid,
    (ne_y, ne_x): (usize, usize),
    q: usize,
    level: usize,
) -> Result<(usize, usize)> {
    let (lim_y, lim_x) = (ne_y.min(e.h() - ne_y), ne_x.min(e.w() - ne_x));
    if lim_y < q + 1 || lim_x < q + 1 {
        return Err(Error::parameter(
            "example",
            format!("{}x{} coefficients at level {level}", e.w(), e.h()),
            "an example whose coarse grid holds at least one patch window at every level",
        ));
    }
    Ok((lim_y - q + 1, lim_x - q + 1))
}

/// The example's windows of one level: its summed-area tables, the global candidate grid
/// and the grid's descriptors.
struct Candidates {
    tables: Tables,
    /// Window origins `(y, x)` of the global grid.
    global: Vec<(usize, usize)>,
    /// Their descriptors, [`LEN`] each.
    feats: Vec<f32>,
    /// Window origins per axis.
    cnt: (usize, usize),
    q: usize,
    /// The relief gain's ε: 5 % of the mean coarse slope of the grid's windows.
    eps: f64,
    /// How many best candidates a patch picks among.
    keep: usize,
}

impl Candidates {
    /// The global grid: at most `candidates` windows (`candidates/16` below the coarsest
    /// level, `finer`), on a stride offset by the seed.
    fn new(
        ce: &Grid,
        cnt: (usize, usize),
        q: usize,
        o: &SynthOptions,
        level: usize,
        finer: bool,
    ) -> Self {
        let tables = Tables::new(ce);
        let budget = if finer {
            (o.candidates / 16).max(1)
        } else {
            o.candidates.max(1)
        };
        let (cnt_y, cnt_x) = cnt;
        let stride = (((cnt_y * cnt_x) as f64 / budget as f64).sqrt().ceil() as usize).max(1);
        let mut rng = mix(o.seed, level, usize::MAX);
        let (off_y, off_x) = (
            (rng.next_u64() % stride as u64) as usize % cnt_y,
            (rng.next_u64() % stride as u64) as usize % cnt_x,
        );
        let global: Vec<(usize, usize)> = (off_y..cnt_y)
            .step_by(stride)
            .flat_map(|y| (off_x..cnt_x).step_by(stride).map(move |x| (y, x)))
            .collect();
        let feats: Vec<f32> = global
            .par_iter()
            .flat_map_iter(|&(y, x)| {
                let mut v = [0.0f32; LEN];
                tables.descriptor(y, x, q, &mut v);
                v
            })
            .collect();
        let slope_sum = feats
            .chunks_exact(LEN)
            .map(|v| v[LEN - 1] as f64)
            .sum::<f64>();
        Candidates {
            eps: 0.05 * slope_sum / global.len().max(1) as f64,
            keep: if finer { 1 } else { o.choices.max(1) },
            tables,
            global,
            feats,
            cnt,
            q,
        }
    }

    /// The source of patch `(a, b)` of `t`: the shift to its chosen window, the matching
    /// distance and the relief gain.
    fn choose(
        &self,
        t: &Grid,
        (a, b): (usize, usize),
        o: &SynthOptions,
        level: usize,
        idx: usize,
        parent: Option<&Shifts>,
    ) -> ((i64, i64), f64, f64) {
        let (best, (wy, wx), f) = self.rank(t, (a, b), o, parent);
        let mut r = mix(o.seed, level, idx);
        let (d, y, x) = best.0[(r.next_u64() % best.0.len() as u64) as usize];
        (
            (y as i64 - wy as i64, x as i64 - wx as i64),
            d,
            self.relief(&f, (y, x), o),
        )
    }

    /// The relief gain of a patch with descriptor `f` taking the window at `(y, x)`.
    fn relief(&self, f: &[f32], (y, x): (usize, usize), o: &SynthOptions) -> f64 {
        if o.relief_cap > 0.0 {
            let mut v = [0.0f32; LEN];
            self.tables.descriptor(y, x, self.q, &mut v);
            let (gt, ge) = (f[LEN - 1] as f64, v[LEN - 1] as f64);
            ((gt + self.eps) / (ge + self.eps)).min(o.relief_cap)
        } else {
            1.0
        }
    }

    /// The best candidates of patch `(a, b)` of `t`, its window origin and descriptor.
    fn rank(
        &self,
        t: &Grid,
        (a, b): (usize, usize),
        o: &SynthOptions,
        parent: Option<&Shifts>,
    ) -> (Best, (usize, usize), [f32; LEN]) {
        let (p, q) = (o.patch, self.q);
        let wy = window_origin(a * p, o.overlap, q, t.h());
        let wx = window_origin(b * p, o.overlap, q, t.w());
        let mut f = [0.0f32; LEN];
        Tables::window_descriptor(t, wy, wx, q, &mut f);
        let mut best = Best::new(self.keep);
        for (gi, &(y, x)) in self.global.iter().enumerate() {
            let d = distance(&f, &self.feats[gi * LEN..(gi + 1) * LEN], o.slope_weight);
            best.offer(d, y, x);
        }
        if let Some(par) = parent {
            self.offer_parents(&f, par, (a, b), (wy, wx), o, &mut best);
        }
        (best, (wy, wx), f)
    }

    /// Offer the sources of the parent of patch `(a, b)` and of the parent's 8
    /// neighbours (each distinct shift once), doubled to this level and moved by up to
    /// one cell, for the patch's window at `(wy, wx)` with descriptor `f`.
    fn offer_parents(
        &self,
        f: &[f32],
        par: &Shifts,
        (a, b): (usize, usize),
        (wy, wx): (usize, usize),
        o: &SynthOptions,
        best: &mut Best,
    ) {
        let p = o.patch;
        let (pa, pb) = ((a * p / 2) / p, (b * p / 2) / p);
        let (cnt_y, cnt_x) = (self.cnt.0 as i64, self.cnt.1 as i64);
        let mut v = [0.0f32; LEN];
        let mut seen: [(i64, i64); 9] = [(i64::MIN, 0); 9];
        for da in -1i64..=1 {
            for db in -1i64..=1 {
                let (qa, qb) = (pa as i64 + da, pb as i64 + db);
                if qa < 0 || qb < 0 {
                    continue;
                }
                let sh = par.at(qa as usize, qb as usize);
                let slot = ((da + 1) * 3 + db + 1) as usize;
                if seen[..slot].contains(&sh) {
                    continue;
                }
                seen[slot] = sh;
                for ry in -1i64..=1 {
                    for rx in -1i64..=1 {
                        let y = (wy as i64 + 2 * sh.0 + ry).clamp(0, cnt_y - 1) as usize;
                        let x = (wx as i64 + 2 * sh.1 + rx).clamp(0, cnt_x - 1) as usize;
                        self.tables.descriptor(y, x, self.q, &mut v);
                        best.offer(distance(f, &v, o.slope_weight), y, x);
                    }
                }
            }
        }
    }
}

/// The `k` lowest `(distance, y, x)` offered so far, lowest first (ties: first offered).
struct Best(Vec<(f64, usize, usize)>, usize);

impl Best {
    fn new(k: usize) -> Self {
        Best(Vec::with_capacity(k + 1), k)
    }

    fn offer(&mut self, d: f64, y: usize, x: usize) {
        let (v, k) = (&mut self.0, self.1);
        if v.len() < k || d < v[v.len() - 1].0 {
            let pos = v.partition_point(|b| b.0 <= d);
            v.insert(pos, (d, y, x));
            v.truncate(k);
        }
    }
}

/// `--details copy`: every patch takes the example's window at its own place (wrapped into
/// the `cnt` window origins).
fn copy_shifts(
    s: &mut Shifts,
    (n_y, n_x): (usize, usize),
    (cnt_y, cnt_x): (usize, usize),
    p: usize,
    ov: usize,
) {
    let q = (p + 2 * ov).min(n_y).min(n_x);
    for a in 0..s.rows {
        for b in 0..s.cols {
            let (wy, wx) = (
                window_origin(a * p, ov, q, n_y),
                window_origin(b * p, ov, q, n_x),
            );
            s.shift[a * s.cols + b] = (
                (wy % cnt_y) as i64 - wy as i64,
                (wx % cnt_x) as i64 - wx as i64,
            );
        }
    }
}

/// The patches covering band-local index `i` along an axis of `np` patches: up to two
/// `(patch, ramp weight)`.
fn cover(i: usize, np: usize, p: usize, ov: usize) -> [(usize, f64); 2] {
    let a = (i / p).min(np - 1);
    let w = |j: usize| ramp(i, j * p, p, ov, j == 0, j + 1 == np);
    let other = if a > 0 && i < a * p + ov {
        a - 1
    } else if a + 1 < np && i + ov >= (a + 1) * p {
        a + 1
    } else {
        a
    };
    if other == a {
        [(a, 1.0), (a, 0.0)]
    } else {
        [(a, w(a)), (other, w(other))]
    }
}

/// Call `f((hy, iy), (hx, ix), sample)` for every sample of the three detail bands of the
/// Mallat block `acc` (coarse part `n_y × n_x`): `hy`/`hx` whether the row/column lies in
/// the high band, `iy`/`ix` the band-local index; rows in parallel.
fn for_each_detail<F>(acc: &mut Grid, (n_y, n_x): (usize, usize), f: F)
where
    F: Fn((bool, usize), (bool, usize), &mut [f64]) + Sync,
{
    let (m_x, c) = (acc.w(), acc.c());
    let local = |i: usize, n: usize| if i >= n { (true, i - n) } else { (false, i) };
    acc.data_mut()
        .par_chunks_mut(m_x * c)
        .enumerate()
        .for_each(|(py, row)| {
            let y = local(py, n_y);
            for (px, v) in row.chunks_exact_mut(c).enumerate() {
                let x = local(px, n_x);
                if y.0 || x.0 {
                    f(y, x, v);
                }
            }
        });
}

/// Fill the three detail bands of the Mallat block `acc` (coarse part `n_y × n_x`) from
/// the example block `e` (coarse part `ne_y × ne_x`), each sample gathered from the (up
/// to four) patches whose windows cover it with their ramp weights `w`. Patches with the
/// same source shift carry the same value and are one term with their weights summed; the
/// distinct terms are blended as `Σ W D / √(Σ W²)` (the variance of uncorrelated details
/// is kept, and coherent neighbours are not inflated).
fn blend(
    acc: &mut Grid,
    n: (usize, usize),
    e: &Grid,
    (ne_y, ne_x): (usize, usize),
    s: &Shifts,
    p: usize,
    ov: usize,
) {
    let c = acc.c();
    let (de_y, de_x) = (e.h() - ne_y, e.w() - ne_x);
    for_each_detail(acc, n, |(hy, iy), (hx, ix), out| {
        let (ebase_y, elen_y) = if hy { (ne_y, de_y) } else { (0, ne_y) };
        let (ebase_x, elen_x) = if hx { (ne_x, de_x) } else { (0, ne_x) };
        let mut terms: [((i64, i64), f64, usize); 4] = [((0, 0), 0.0, 0); 4];
        let mut nt = 0;
        for &(a, wy) in &cover(iy, s.rows, p, ov) {
            for &(b, wx) in &cover(ix, s.cols, p, ov) {
                let wgt = wy * wx;
                if wgt <= 0.0 {
                    continue;
                }
                let sh = s.at(a, b);
                if let Some(t) = terms[..nt].iter_mut().find(|t| t.0 == sh) {
                    t.1 += wgt;
                } else {
                    let jy = (iy as i64 + sh.0).clamp(0, elen_y as i64 - 1) as usize;
                    let jx = (ix as i64 + sh.1).clamp(0, elen_x as i64 - 1) as usize;
                    terms[nt] = (sh, wgt, (ebase_y + jy) * e.w() + ebase_x + jx);
                    nt += 1;
                }
            }
        }
        let w2: f64 = terms[..nt].iter().map(|t| t.1 * t.1).sum();
        if w2 <= 0.0 {
            return;
        }
        let inv = 1.0 / w2.sqrt();
        for (k, v) in out.iter_mut().enumerate() {
            *v = terms[..nt]
                .iter()
                .map(|t| t.1 * e.data()[t.2 * c + k])
                .sum::<f64>()
                * inv;
        }
    });
}

/// Scale the detail bands of the Mallat block `acc` (coarse part `n_y × n_x`) by the
/// patches' relief gains `gᵢ`, blended with the ramps `w` of [`blend`]: each detail
/// sample is multiplied by `Σ wᵢ gᵢ / Σ wᵢ` over the patches whose windows cover it (a
/// gain field as smooth as the blend, so no seam is made).
fn relief_gain(acc: &mut Grid, n: (usize, usize), s: &Shifts, p: usize, ov: usize) {
    for_each_detail(acc, n, |(_, iy), (_, ix), out| {
        let (mut sw, mut sg) = (0.0, 0.0);
        for &(a, wy) in &cover(iy, s.rows, p, ov) {
            for &(b, wx) in &cover(ix, s.cols, p, ov) {
                let w = wy * wx;
                sw += w;
                sg += w * s.gain[a.min(s.rows - 1) * s.cols + b.min(s.cols - 1)];
            }
        }
        if sw > 0.0 {
            let g = sg / sw;
            out.iter_mut().for_each(|v| *v *= g);
        }
    });
}

/// Root mean square of the channel values of `g` over rows `ry` × columns `rx`.
fn rms(g: &Grid, ry: std::ops::Range<usize>, rx: std::ops::Range<usize>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for y in ry {
        for x in rx.clone() {
            for k in 0..g.c() {
                s += g.at(y, x, k).powi(2);
                n += 1;
            }
        }
    }
    (s / n.max(1) as f64).sqrt()
}

/// Scale each of the three detail bands of the Mallat block `acc` (coarse part
/// `n_y × n_x`) so that its RMS equals the same band's RMS in the example's block
/// (coarse part `ne_y × ne_x`): `D_b ← D_b · rms(E_b)/rms(D_b)`. Matching picks *which*
/// details go where; this keeps each level's amplitude that of the example, so the
/// blend and the choice of quieter windows do not change the spectrum's slope.
fn match_band_rms(
    acc: &mut Grid,
    (n_y, n_x): (usize, usize),
    e: &Grid,
    (ne_y, ne_x): (usize, usize),
) {
    for (hy, hx) in [(true, false), (false, true), (true, true)] {
        let (ry, rx) = (
            if hy { n_y..acc.h() } else { 0..n_y },
            if hx { n_x..acc.w() } else { 0..n_x },
        );
        let (ey, ex) = (
            if hy { ne_y..e.h() } else { 0..ne_y },
            if hx { ne_x..e.w() } else { 0..ne_x },
        );
        let (have, want) = (rms(acc, ry.clone(), rx.clone()), rms(e, ey, ex));
        if have > 0.0 {
            let f = want / have;
            for y in ry {
                for x in rx.clone() {
                    for k in 0..acc.c() {
                        *acc.at_mut(y, x, k) *= f;
                    }
                }
            }
        }
    }
}
