//! One level along the leading axes `0..k` of an array region at once, out of place.
//!
//! The two-scale operators of different axes commute (tensor product), so a level along
//! axes `0, 1, …, k−1` can be computed slab by slab: output slab `r` along axis 0 is
//! `Σ_c W_rc · (input slab c)` — whole slabs combined with the weights of row `r` of
//! axis 0's operator (the notes' `E1 = 0·D1`: the elements of a lane are whole rows) —
//! and that slab, still in cache, goes through the same level along the remaining axes,
//! ending in one contiguous lane per row ([`Polyphase::apply_lane`]). Every input sample
//! is read from memory once per level and every output sample written once, which is
//! what a level costs at best; analysis `[A; B]` and synthesis `[P | Q]` run the same code.
//!
//! The axes after `k−1` must be whole (not part of this level's region): together they
//! form the elements (`e` samples, e.g. the channels of an image).

use super::aligned::Aligned;
use super::boxes::{strided, strided_mut, Strided, StridedMut};
use super::par::{for_each_part, SharedMut};
use crate::kernel::polyphase::{Polyphase, PAIR_MOST};
use crate::kernel::{
    self, combine_pair_taps, combine_taps, stream_copy, stream_copy_unfenced, stream_fence,
    transpose, GridUnit, Kernels, LaneTaps, PairGrid, PairMemo, PairOut, PairOutput,
};
use crate::scheme::sparse::Csr;
use crate::scheme::Sample;

/// One axis' operator for this level.
pub struct AxisOp<'a> {
    pub op: &'a Csr,
    pub plan: &'a Polyphase,
    /// Rows in the order to compute them (by first column, so analysis visits the coarse
    /// and detail rows of one neighbourhood together and reads its input once).
    pub order: &'a [usize],
    /// `order` cut into the parts one task takes ([`pair_parts`]).
    pub parts: &'a [std::ops::Range<usize>],
}

/// Levels whose region is at least this large write their output past the caches (with
/// [`Writes::StreamLarge`]).
pub(super) const STREAM_BYTES: usize = 16 << 20;

/// Rows of [`AxisOp::order`] handed to one task.
pub(super) const ROWS_PER_TASK: usize = 16;

/// How a level writes its output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Writes {
    /// Past the caches (non-temporal stores) when the level's region is at least
    /// [`STREAM_BYTES`], through them otherwise: analysis, whose output the next level
    /// reads only in part.
    StreamLarge,
    /// Through the caches whatever the size: synthesis. Plain stores straight from the
    /// lanes cost the synthesis less than streaming each finished plane or row out in a
    /// pass of its own (`examples/pyramid_timing`), and leave no write-back to whatever
    /// runs next; the analysis is slower that way, so it streams.
    Cached,
}

/// Apply one level along axes `0..ops.len()` to the box `[0, region[d])` of `src`,
/// writing the same box of `dst`. Both buffers have the array's `strides` (the first
/// `ops.len()` strides; the last of them must equal `e`, the element width).
pub fn fused_level<T: Sample>(
    src: &[T],
    dst: &mut [T],
    strides: &[usize],
    region: &[usize],
    e: usize,
    ops: &[AxisOp],
    writes: Writes,
) {
    let (src, dst) = (strided(src, strides), strided_mut(dst, strides));
    fused_level_strided(src, dst, region, e, ops, writes)
}

/// [`fused_level`] with the source and the destination laid out differently (their
/// strides both nested, the last equal to `e`).
pub(super) fn fused_level_strided<T: Sample>(
    src: Strided<'_, T>,
    dst: StridedMut<'_, T>,
    region: &[usize],
    e: usize,
    ops: &[AxisOp],
    writes: Writes,
) {
    let (
        Strided {
            data: src,
            strides: src_st,
        },
        StridedMut {
            data: dst,
            strides: dst_st,
        },
    ) = (src, dst);
    let k = ops.len();
    assert!(k >= 1 && region.len() == k && src_st.len() == k && dst_st.len() == k);
    for st in [src_st, dst_st] {
        assert_eq!(st[k - 1], e);
        for d in 1..k {
            assert!(st[d - 1] >= st[d] * region[d]);
        }
    }
    let extent = |st: &[usize]| (0..k).map(|d| (region[d] - 1) * st[d]).sum::<usize>() + e;
    assert!(extent(src_st) <= src.len() && extent(dst_st) <= dst.len());
    let work_bytes = region.iter().product::<usize>() * e * std::mem::size_of::<T>();
    let stream = writes == Writes::StreamLarge && work_bytes >= STREAM_BYTES;
    let ctx = Ctx::new(region, e, ops, stream);
    // a second slab for rows combined in pairs along axis 0 (`Ctx::row_pair`); none
    // where they do not pair (slabs larger than `PAIR_SLAB_MAX`)
    let pairs = ctx.cs()[0] * std::mem::size_of::<T>() <= PAIR_SLAB_MAX;
    let make_scratch = || {
        let slab2 = Aligned::<T>::zeroed(if pairs { ctx.cs()[0] } else { 0 });
        (ctx.scratch::<T>(), slab2)
    };
    let dst_len = dst.len();
    let dptr = SharedMut(dst.as_mut_ptr());
    let order = ops[0].order;
    let work = region.iter().product::<usize>() * e;
    if k == 1 {
        let n = region[0] * e;
        let mut lane_tmp = vec![T::default(); n];
        ops[0]
            .plan
            .apply_lane(ops[0].op, &src[..n], &mut dst[..n], e, &mut lane_tmp);
        return;
    }
    let task = |rows: &[usize], (scratch, slab2): &mut (Vec<Aligned<T>>, Aligned<T>)| {
        let p = dptr;
        let out_row = |r: usize| {
            let at = r * dst_st[0];
            let len = dst_st[0].min(dst_len - at);
            // SAFETY: output row r of axis 0 owns dst[r·s0, r·s0 + s0) (strides are
            // nested, checked above); each row index appears once in `order`, and tasks
            // get disjoint parts of `order`, of which each row is taken once here.
            unsafe { std::slice::from_raw_parts_mut(p.0.add(at), len) }
        };
        let mut i = 0;
        while i < rows.len() {
            if let [r1, r2, ..] = rows[i..] {
                let outs = [out_row(r1), out_row(r2)];
                let from = strided(src, src_st);
                if ctx.row_pair([r1, r2], from, outs, dst_st, scratch, slab2) {
                    i += 2;
                    continue;
                }
            }
            let (from, to) = (strided(src, src_st), strided_mut(out_row(rows[i]), dst_st));
            ctx.row(0, rows[i], from, to, scratch);
            i += 1;
        }
        if ctx.stream {
            // the rows' streamed lanes, copied without a fence each
            stream_fence();
        }
    };
    for_each_part(order, ops[0].parts, work < 1 << 16, make_scratch, task);
}

/// `order` cut into parts of about [`ROWS_PER_TASK`] rows (worked out once per level's
/// operator, [`super::workspace::LevelOps`]), never between two rows that the task
/// loop of [`fused_level_strided`] combines together: it pairs each row with the next
/// when [`kernel::rows_pair`] says so ([`Ctx::row_pair`]), so parts cut at fixed counts
/// would split pairs wherever an unpaired row shifts them by one. The analysis order of
/// the symmetric and periodic cubic operators (`C₀, C₁, D₀, C₂, D₁, …`, one unpaired
/// row near the start) lost two pairs in every part of 16 rows that way: 16 of the 256
/// output planes of a 256³ level made alone.
pub(super) fn pair_parts(order: &[usize], op: &Csr) -> Vec<std::ops::Range<usize>> {
    let per = ROWS_PER_TASK;
    let mut parts = Vec::with_capacity(order.len() / per + 1);
    let (mut start, mut i) = (0, 0);
    while i < order.len() {
        let paired = i + 1 < order.len()
            && kernel::rows_pair(op.row_slices(order[i]).0, op.row_slices(order[i + 1]).0);
        i += if paired { 2 } else { 1 };
        if i - start >= per {
            parts.push(start..i);
            start = i;
        }
    }
    if start < order.len() {
        parts.push(start..order.len());
    }
    parts
}

/// One level of a region, ready to apply row by row along axis 0 (shared by
/// [`fused_level`] and the cascade of [`super::cascade`]).
pub(super) struct Ctx<'a> {
    /// Write lanes with non-temporal stores (output larger than the caches).
    pub stream: bool,
    /// The kernel table of the level's operator plans ([`Polyphase::kernels`]).
    pub k: Kernels,
    region: &'a [usize],
    e: usize,
    ops: &'a [AxisOp<'a>],
    /// Compact strides of a slab of the region (`cs[0]` = samples of one row along axis 0).
    cs: Vec<usize>,
    /// The rows of the last axis' operator outside its pair, for [`lanes`] (planes
    /// whose last axis runs by lanes; worked out once per level, not per plane).
    lane_taps: Option<LaneTaps>,
}

impl<'a> Ctx<'a> {
    /// The level `ops` (axes `0..k`) over the box `region` of elements of `e` samples.
    pub fn new(region: &'a [usize], e: usize, ops: &'a [AxisOp<'a>], stream: bool) -> Self {
        let k = ops.len();
        assert!(k >= 1 && region.len() == k);
        for d in 0..k {
            assert_eq!(ops[d].op.rows(), region[d]);
            assert_eq!(ops[d].plan.rows, region[d]);
            assert_eq!(ops[d].plan.kernels, ops[0].plan.kernels);
        }
        let mut cs = vec![e; k];
        for d in (0..k - 1).rev() {
            cs[d] = cs[d + 1] * region[d + 1];
        }
        let mut ctx = Ctx {
            stream,
            k: ops[0].plan.kernels,
            region,
            e,
            ops,
            cs,
            lane_taps: None,
        };
        if plane_path(k, region, e) && ctx.by_lanes(k - 2) {
            let a = &ops[k - 1];
            ctx.lane_taps = Some(lane_taps(a, a.plan.col_step == 2, region[k - 1]));
        }
        ctx
    }

    /// Compact strides of the region (a row along axis 0 is `cs()[0]` samples).
    pub fn cs(&self) -> &[usize] {
        &self.cs
    }

    /// The scratch one worker needs: a slab per axis but the last, the lane output and
    /// scratch, and two planes for [`Ctx::plane`].
    pub fn scratch<T: Sample>(&self) -> Vec<Aligned<T>> {
        let (k, region, e) = (self.ops.len(), self.region, self.e);
        let mut v: Vec<Aligned<T>> = (0..k - 1).map(|d| Aligned::heap(self.cs[d])).collect();
        v.push(Aligned::heap(region[k - 1] * e)); // lane output when streaming
        v.push(Aligned::heap(region[k - 1] * e)); // lane scratch
        let planes = if plane_path(k, region, e) {
            region[k - 2] * region[k - 1]
        } else {
            0
        };
        // the planes on page boundaries (see `aligned`): a slab combined along axis
        // k − 2, its lanes split into even and odd samples or their output
        v.push(Aligned::zeroed(planes));
        v.push(Aligned::zeroed(planes));
        v
    }

    /// The rest of the level for one row along axis 0 already combined along axis 0
    /// (`slab`, compact): axes `1..k` into `out` (strides `dst_st`, of which `dst_st[0]`
    /// is unused). `scratch` is [`Ctx::scratch`] without its first buffer.
    pub fn finish_row<T: Sample>(
        &self,
        slab: &[T],
        out: &mut [T],
        dst_st: &[usize],
        scratch: &mut [Aligned<T>],
    ) {
        self.slab(1, slab, out, dst_st, scratch);
    }

    /// Whether rows may reach [`Ctx::finish_split_row`] already split into their even and
    /// odd samples: images of single samples whose lanes (axis 1) run analysis with
    /// [`Polyphase::split_reach`] known, on a machine whose pair kernels write split rows
    /// (elsewhere the split would be a pass of its own, with a buffer per row).
    pub fn takes_split_rows(&self) -> bool {
        let lane = &self.ops[self.ops.len() - 1].plan;
        self.k.avx2()
            && self.ops.len() == 2
            && self.e == 1
            && lane.split_reach.is_some()
            && lane.rows == self.region[1]
    }

    /// [`Ctx::finish_row`] for a row combined along axis 0 into its even samples, then
    /// its odd ones (`halves`; see [`Ctx::takes_split_rows`]): the lane without its split.
    pub fn finish_split_row<T: Sample>(
        &self,
        halves: &[T],
        out: &mut [T],
        scratch: &mut [Aligned<T>],
    ) {
        debug_assert!(self.takes_split_rows());
        let a = &self.ops[1];
        let n = self.region[1];
        let [.., lane_out, lane_tmp, _, _] = scratch else {
            unreachable!("two lane buffers")
        };
        if self.stream {
            a.plan
                .apply_lane_split(a.op, &halves[..n], &mut lane_out[..n], lane_tmp);
            // (fenced by the caller once its rows are done)
            stream_copy_unfenced(self.k, &lane_out[..n], &mut out[..n]);
        } else {
            a.plan
                .apply_lane_split(a.op, &halves[..n], &mut out[..n], lane_tmp);
        }
    }

    /// Output row `r` along axis `d`: `out` starts at that row's slab in the destination,
    /// `src` at the input's origin for axes `d..`.
    fn row<T: Sample>(
        &self,
        d: usize,
        r: usize,
        src: Strided<'_, T>,
        out: StridedMut<'_, T>,
        scratch: &mut [Aligned<T>],
    ) {
        let (
            Strided {
                data: src,
                strides: src_st,
            },
            StridedMut {
                data: out,
                strides: dst_st,
            },
        ) = (src, out);
        let k = self.ops.len();
        let e = self.e;
        if d == k - 1 {
            unreachable!("the last axis is applied lane by lane in `slab`");
        }
        // combine the input slabs of row r into scratch[0] (compact, strides cs[d+1..])
        let (slab, rest) = scratch.split_first_mut().expect("scratch per axis");
        // lines that follow one another in the source as in the slab (the region spans
        // the array there) are one run
        let whole = (d + 1..k - 1).all(|j| src_st[j] == self.cs[j]);
        let (run, lines) = if whole {
            (self.cs[d], 1)
        } else {
            (
                self.region[k - 1] * e,
                self.region[d + 1..k - 1].iter().product(),
            )
        };
        let (cols, ws) = self.ops[d].op.row_slices(r);
        for line in 0..lines {
            let (so, co) = self.line_at(d, line, src_st);
            let at = |c: u32| c as usize * src_st[d] + so;
            combine_taps(self.k, &mut slab[co..co + run], cols, ws, |c| {
                &src[at(c)..at(c) + run]
            });
        }
        self.slab(d + 1, slab, out, dst_st, rest);
    }

    /// Offsets of line `line` of a slab along axis `d` in the source (strides `src_st`)
    /// and in the compact slab.
    fn line_at(&self, d: usize, line: usize, src_st: &[usize]) -> (usize, usize) {
        let k = self.ops.len();
        let (mut so, mut co, mut rem) = (0usize, 0usize, line);
        for j in (d + 1..k - 1).rev() {
            let i = rem % self.region[j];
            rem /= self.region[j];
            so += i * src_st[j];
            co += i * self.cs[j];
        }
        (so, co)
    }

    /// Output rows `r[0]` and `r[1]` along axis 0, as [`Ctx::row`] makes each, with their
    /// slabs combined together ([`combine_pair_taps`]: the input slabs the two rows share
    /// are read once; the second slab goes to `slab2`). `false` (nothing written) when
    /// the two rows do not pair.
    pub(super) fn row_pair<T: Sample>(
        &self,
        r: [usize; 2],
        src: Strided<'_, T>,
        outs: [&mut [T]; 2],
        dst_st: &[usize],
        scratch: &mut [Aligned<T>],
        slab2: &mut [T],
    ) -> bool {
        let Strided {
            data: src,
            strides: src_st,
        } = src;
        let k = self.ops.len();
        if k < 2 {
            return false;
        }
        let (slab, rest) = scratch.split_first_mut().expect("scratch per axis");
        let whole = (1..k - 1).all(|j| src_st[j] == self.cs[j]);
        let (run, lines) = if whole {
            (self.cs[0], 1)
        } else {
            (
                self.region[k - 1] * self.e,
                self.region[1..k - 1].iter().product(),
            )
        };
        if self.cs[0] * std::mem::size_of::<T>() > PAIR_SLAB_MAX || slab2.len() < self.cs[0] {
            return false;
        }
        let op = self.ops[0].op;
        let rows = [op.row_slices(r[0]), op.row_slices(r[1])];
        let mut memo = PairMemo::default();
        for line in 0..lines {
            let (so, co) = self.line_at(0, line, src_st);
            let at = |c: u32| c as usize * src_st[0] + so;
            let (a, b) = (&mut slab[co..co + run], &mut slab2[co..co + run]);
            let tap = |c| &src[at(c)..at(c) + run];
            if !combine_pair_taps(self.k, &mut memo, rows, PairOut::Apart(a, b), tap) {
                debug_assert_eq!(line, 0, "the same rows pair on every line");
                return false;
            }
        }
        let [o1, o2] = outs;
        // the planes of a volume: each slab, once combined along axis 1, is the free
        // plane of its last axis (a worker's planes in use are then the two slabs and
        // one buffer; about 2–3% faster on a 256³ forward + inverse, Chaikin and cubic)
        if k == 3 && plane_path(k, self.region, self.e) {
            self.plane_spent(1, slab, o1, dst_st[1], rest);
            self.plane_spent(1, slab2, o2, dst_st[1], rest);
            return true;
        }
        self.slab(1, slab, o1, dst_st, rest);
        self.slab(1, &slab2[..], o2, dst_st, rest);
        true
    }

    /// The level along axes `d..` of a compact slab, into `out` (strides `dst_st`).
    fn slab<T: Sample>(
        &self,
        d: usize,
        slab: &[T],
        out: &mut [T],
        dst_st: &[usize],
        scratch: &mut [Aligned<T>],
    ) {
        let k = self.ops.len();
        let e = self.e;
        if d + 2 == k && plane_path(k, self.region, e) {
            return self.plane(d, slab, out, dst_st[d], scratch);
        }
        if d == k - 1 {
            let a = &self.ops[d];
            let n = self.region[d] * e;
            let [.., lane_out, lane_tmp, _, _] = scratch else {
                unreachable!("two lane buffers")
            };
            if self.stream {
                a.plan
                    .apply_lane(a.op, &slab[..n], &mut lane_out[..n], e, lane_tmp);
                // (fenced once the task's rows are done, in `fused_level_strided`)
                stream_copy_unfenced(self.k, &lane_out[..n], &mut out[..n]);
            } else {
                a.plan
                    .apply_lane(a.op, &slab[..n], &mut out[..n], e, lane_tmp);
            }
            return;
        }
        for &r in self.ops[d].order {
            let at = r * dst_st[d];
            let o = &mut out[at..];
            self.row(
                d,
                r,
                strided(slab, &self.cs),
                strided_mut(o, dst_st),
                scratch,
            );
        }
    }

    /// The last two axes of a compact slab `[h, w]` (single samples) at once, for short
    /// lanes: axis `d` combines whole rows (`Σ_c W_rc · row_c`), then the last axis runs
    /// on every lane of the plane at once ([`lanes`]: the regular rows of its operator
    /// in one dispatch for all lanes, the weights in registers; analysis first splits
    /// each lane into its even and odd samples). Every output sums the same taps in the
    /// same order as the lane-by-lane path (the same bits).
    fn plane<T: Sample>(
        &self,
        d: usize,
        slab: &[T],
        out: &mut [T],
        out_stride: usize,
        scratch: &mut [Aligned<T>],
    ) {
        let split = self.lanes_split(d);
        let (row, pa, pb) = self.plane_buffers_row(d, scratch);
        combine_rows(
            &self.ops[d],
            &slab[..pa.len()],
            self.region[d + 1],
            pa,
            split.then_some(row),
        );
        self.plane_lanes(d, pa, pb, out, out_stride, split)
    }

    /// [`Ctx::plane`] on a slab this call may overwrite: it serves as the second plane
    /// buffer, so that a worker's planes in use are the slab and one buffer.
    fn plane_spent<T: Sample>(
        &self,
        d: usize,
        slab: &mut [T],
        out: &mut [T],
        out_stride: usize,
        scratch: &mut [Aligned<T>],
    ) {
        let split = self.lanes_split(d);
        let (row, pa, _) = self.plane_buffers_row(d, scratch);
        let n = pa.len();
        combine_rows(
            &self.ops[d],
            &slab[..n],
            self.region[d + 1],
            pa,
            split.then_some(row),
        );
        self.plane_lanes(d, pa, &mut slab[..n], out, out_stride, split)
    }

    /// The lane scratch and the two plane buffers of [`Ctx::scratch`] (a lane of the
    /// last axis; a plane of axes `d, d + 1` each).
    fn plane_buffers_row<'s, T: Sample>(
        &self,
        d: usize,
        scratch: &'s mut [Aligned<T>],
    ) -> (&'s mut [T], &'s mut [T], &'s mut [T]) {
        let n = self.region[d] * self.region[d + 1];
        let [.., row, pa, pb] = scratch else {
            unreachable!("two plane buffers")
        };
        (&mut row[..], &mut pa[..n], &mut pb[..n])
    }

    /// Whether [`Ctx::plane_lanes`] runs the last axis (after axis `d`) on lanes split
    /// into their even and odd samples: then axis `d` writes its rows split
    /// ([`kernel::combine_pair_grid`]), which saves the split's pass over the plane.
    fn lanes_split(&self, d: usize) -> bool {
        self.ops[d + 1].plan.col_step == 2 && self.by_lanes(d)
    }

    /// Whether [`Ctx::plane_lanes`] runs the last axis (after axis `d`) lane by lane
    /// ([`lanes`]) rather than on the transposed plane: at most
    /// [`LANES_MOST_UNPAIRED`] rows of its operator outside the pair.
    fn by_lanes(&self, d: usize) -> bool {
        let unpaired: usize = self.ops[d + 1].plan.unpaired.iter().map(|r| r.len()).sum();
        unpaired <= LANES_MOST_UNPAIRED
    }

    /// The last axis of [`Ctx::plane`]: `pa` holds the plane combined along axis `d`
    /// (its rows already split into even and odd samples when `presplit`, see
    /// [`Ctx::lanes_split`]), `pb` is free.
    fn plane_lanes<T: Sample>(
        &self,
        d: usize,
        pa: &mut [T],
        pb: &mut [T],
        out: &mut [T],
        out_stride: usize,
        presplit: bool,
    ) {
        let (h, w) = (self.region[d], self.region[d + 1]);
        let a = &self.ops[d + 1];
        if !self.by_lanes(d) {
            // many rows outside the pair (interpolating ends; the interpolating Chaikin
            // analysis has no pair, its detail rows read other places than its coarse
            // rows): the plane transposed so that the lanes become rows, combined as
            // rows, and transposed back
            let k = self.k;
            transpose(k, pa, h, w, pb, h);
            combine_rows(a, pb, h, pa, None);
            if !self.stream {
                return transpose(k, pa, w, h, out, out_stride);
            }
            transpose(k, pa, w, h, pb, w);
            return stream_rows(k, pb, w, h, out, out_stride);
        }
        let split = a.plan.col_step == 2;
        let taps = self.lane_taps.as_ref().expect("made for planes by lanes");
        let lanes = |x: &[T], y: &mut [T], ys: usize| {
            let x = Lanes { x, h, w, split };
            lanes(a, taps, x, y, ys)
        };
        if split && !presplit {
            for (x, y) in pa.chunks_exact(w).zip(pb.chunks_exact_mut(w)) {
                kernel::deinterleave(self.k, x, 1, y);
            }
        }
        // the lanes' input, and the plane free for their output
        let (x, free) = if split && !presplit {
            (pb, pa)
        } else {
            (pa, pb)
        };
        if !self.stream && out_stride == w {
            return lanes(x, out, out_stride);
        }
        if !self.stream {
            // the plane's rows apart in the output (a level inside a larger array): the
            // lanes into the free plane, then copied, rather than stored there one lane
            // at a time (15–20% faster on level 1 of a 256³ cubic; a whole array, whose
            // rows follow one another, is stored directly: copying is slower there)
            lanes(x, free, w);
            for (o, f) in out.chunks_mut(out_stride).zip(free.chunks_exact(w)).take(h) {
                o[..w].copy_from_slice(f);
            }
            return;
        }
        lanes(x, free, w);
        stream_rows(self.k, free, w, h, out, out_stride);
    }
}

/// The `h` rows of `w` samples of `src` (compact) into `dst`, rows `stride` apart, with
/// non-temporal stores.
fn stream_rows<T: Sample>(k: Kernels, src: &[T], w: usize, h: usize, dst: &mut [T], stride: usize) {
    if stride == w {
        return stream_copy(k, &src[..h * w], &mut dst[..h * w]);
    }
    for r in 0..h {
        stream_copy_unfenced(
            k,
            &src[r * w..r * w + w],
            &mut dst[r * stride..r * stride + w],
        );
    }
    stream_fence();
}

/// Most rows of a lane's operator outside its pair for [`lanes`] (computed 8 lanes at a
/// time there, [`kernel::combine_lane_taps`]); with more, [`Ctx::plane`] transposes the
/// plane. 20 takes the interpolating cubic operators (12 such rows in analysis, 18 in
/// synthesis) through the lanes, which is faster than transposing them twice per plane
/// (`examples/pyramid_timing`).
const LANES_MOST_UNPAIRED: usize = 20;

/// `h` lanes of `w` samples, lane `t` at `x[t·w..]`; `split`: each lane holds its even
/// samples, then its odd ones ([`kernel::deinterleave`]).
#[derive(Clone, Copy)]
struct Lanes<'a, T> {
    x: &'a [T],
    h: usize,
    w: usize,
    split: bool,
}

/// The operator of `a` on the lanes `x` into `y` (lane `t` at `y[t·ys..]`): the rows of
/// its pair with [`kernel::combine_pair_grid`], the others sample by sample.
fn lanes<T: Sample>(a: &AxisOp, taps: &LaneTaps, x: Lanes<'_, T>, y: &mut [T], ys: usize) {
    let Lanes { x, h, w, split } = x;
    let plan = a.plan;
    let at = |c: usize| lane_at(split, w, c);
    if let Some(pair) = &plan.pair {
        let (r0, r1) = (&plan.runs[pair.runs[0]], &plan.runs[pair.runs[1]]);
        let (f, n) = (pair.first, pair.count);
        let u = pair.cols.len();
        let mut off = [0usize; PAIR_MOST];
        for (o, &c) in off.iter_mut().zip(&pair.cols) {
            *o = at(c);
        }
        let [w0, w1] = pair.sample_weights::<T>();
        // analysis: the coarse and the detail rows; synthesis: the even and the odd fine
        // samples, interleaved (as `Polyphase::apply_lane` places them)
        let (out, output) = if split {
            ([r0.row0 + f[0], r1.row0 + f[1]], PairOutput::Apart)
        } else {
            let p0 = r0.row0 / 2 + f[0];
            ([2 * p0, 2 * p0], PairOutput::Merged)
        };
        let grid = PairGrid {
            off: &off[..u],
            in_step: w,
            out,
            out_step: [ys, ys],
            len: n,
            count: h,
            unit: GridUnit::Samples,
            output,
        };
        let rows = pair.rows(plan.kernels, &w0[..u], &w1[..u]);
        kernel::combine_pair_grid(plan.kernels, &rows, x, y, &grid);
    }
    // the other rows (near the ends of the lanes)
    kernel::combine_lane_taps_with(plan.kernels, taps, x, h, y, ys);
}

/// Where sample `c` of a lane of `w` samples is in its row (`split`: the even samples,
/// then the odd ones).
fn lane_at(split: bool, w: usize, c: usize) -> usize {
    if split {
        (c % 2) * w.div_ceil(2) + c / 2
    } else {
        c
    }
}

/// The rows of `a`'s operator outside its pair, each with its taps' places in a lane of
/// `w` samples (split or not) and weights, for [`kernel::combine_lane_taps_with`].
fn lane_taps(a: &AxisOp, split: bool, w: usize) -> LaneTaps {
    let rows = a
        .plan
        .unpaired
        .iter()
        .flat_map(|r| r.clone())
        .map(|r| {
            let (cols, ws) = a.op.row_slices(r);
            let taps = cols
                .iter()
                .zip(ws)
                .map(|(&c, &wk)| (lane_at(split, w, c as usize), wk))
                .collect();
            (r, taps)
        })
        .collect();
    LaneTaps::new(rows, w)
}

/// Largest slab (bytes) combined in pairs ([`Ctx::row_pair`]): rows of images and the
/// planes of volumes up to 256² (256 KB), whose coarse and detail planes along axis 0
/// then read their input planes from L3 once instead of twice. Whether a second plane
/// per worker pays depends on the L2: where the plane path's three planes overflow it
/// anyway (512 KB per core), pairing is faster; with 1 MB of L2 it is slower for larger
/// planes, hence the cap (`examples/pyramid_timing`, docs/engine-performance.md).
const PAIR_SLAB_MAX: usize = 256 << 10;

/// Lanes at most this long go through [`Ctx::plane`] (volumes of a few hundred samples a
/// side), longer ones lane by lane.
const PLANE_MAX_LANE: usize = 1024;

/// Whether the last two axes of a level run as planes ([`Ctx::plane`]).
fn plane_path(k: usize, region: &[usize], e: usize) -> bool {
    k >= 3 && e == 1 && region[k - 1] <= PLANE_MAX_LANE
}

/// `dst[r] = Σ_c W_rc · src[c]` for every row `r` of `a.op`, rows of `len` samples: the
/// rows of the operator's pair ([`crate::kernel::polyphase::Pair`]) two at a time ([`kernel::combine_pair_grid`]: the input
/// rows they share read once), the others one by one ([`kernel::combine_rows`]).
///
/// With `split` (a lane's room), every output row is written split into its even
/// samples, then its odd ones ([`kernel::deinterleave`]).
fn combine_rows<T: Sample>(
    a: &AxisOp,
    src: &[T],
    len: usize,
    dst: &mut [T],
    split: Option<&mut [T]>,
) {
    let (op, plan) = (a.op, a.plan);
    let k = plan.kernels;
    let rows_split = |rows: std::ops::Range<usize>, dst: &mut [T], row: &mut [T]| {
        for r in rows {
            kernel::combine_rows(k, op, src, len, r..r + 1, &mut row[..len]);
            kernel::deinterleave(k, &row[..len], 1, &mut dst[r * len..r * len + len]);
        }
    };
    let Some(pair) = &plan.pair else {
        return match split {
            Some(row) => rows_split(0..op.rows(), dst, row),
            None => kernel::combine_rows(k, op, src, len, 0..op.rows(), dst),
        };
    };
    let runs = [&plan.runs[pair.runs[0]], &plan.runs[pair.runs[1]]];
    let first = [0, 1].map(|j| runs[j].row0 + runs[j].row_step * pair.first[j]);
    let steps = [runs[0].row_step, runs[1].row_step];
    let u = pair.cols.len();
    let w = pair.sample_weights::<T>();
    // (the pair's entry of the pair kernels, looked up when the plan was made)
    let rows = pair.rows(k, &w[0][..u], &w[1][..u]);
    let grid = PairGrid {
        off: &pair.cols,
        in_step: runs[0].col_step,
        out: first,
        out_step: steps,
        len,
        count: pair.count,
        unit: GridUnit::Rows,
        output: if split.is_some() {
            PairOutput::Split
        } else {
            PairOutput::Apart
        },
    };
    kernel::combine_pair_grid(k, &rows, src, dst, &grid);
    match split {
        Some(row) => {
            for r in &plan.unpaired {
                rows_split(r.clone(), dst, row);
            }
        }
        None => {
            for r in &plan.unpaired {
                kernel::combine_rows(k, op, src, len, r.clone(), &mut dst[r.start * len..]);
            }
        }
    }
}
