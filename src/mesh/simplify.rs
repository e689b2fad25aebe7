//! Edge collapse and quadric-error simplification (§6.6.3; Garland and Heckbert 1997).
//!
//! ```text
//!   plane of a face:  p = (n, −n·x₀),   quadric K_p = p pᵀ (4 × 4)
//!   vertex quadric:   Q_v = Σ_{faces ∋ v} K_p   (+ weighted planes ⟂ each boundary edge)
//!   collapse a, b → x:  cost = x̄ᵀ (Q_a + Q_b) x̄,  x̄ = (x, 1),  x = argmin (3 × 3 solve),
//!                      or the best of a, b, (a + b)/2 when the system is singular
//! ```
//!
//! Edges are collapsed cheapest first (a binned queue, 16 bins per octave of cost, see
//! `BinQueue`; stale entries are skipped by per-vertex stamps). A collapse is allowed only when
//! it keeps the mesh a 2-manifold: the *link
//! condition* Lk(a) ∩ Lk(b) = Lk(ab) (common neighbours are exactly the vertices opposite ab,
//! and those are not joined to both through a face), an interior edge may not join two boundary
//! vertices, and no remaining face may flip its normal.
//!
//! Storage is flat and laid out for the collapse loop, which visits the mesh in cost order
//! (jumping around, so cache misses count): per vertex one 128-byte record (quadric, position,
//! mark, flags: two cache lines), faces as triples, the stamps and the face-list places apart
//! in small arrays, and the face lists of all vertices in one array `refs` (one contiguous run
//! per vertex; a collapse appends the merged vertex's new run, compaction when full). While a
//! collapse is processed, the data of the next live queue entry is prefetched. Setup
//! (quadrics, boundary detection, edge costs) runs per vertex over these lists, in parallel;
//! the collapse loop is sequential and deterministic.

use super::{vec3, Attributes, Mesh, NONE};
use crate::{Error, Result};
use rayon::prelude::*;

/// Symmetric 4 × 4 matrix stored as its upper triangle.
#[derive(Clone, Copy, Default, Debug)]
struct Quadric([f64; 10]);

impl Quadric {
    fn plane(n: [f64; 3], d: f64, w: f64) -> Quadric {
        let (a, b, c) = (n[0], n[1], n[2]);
        Quadric([
            w * a * a,
            w * a * b,
            w * a * c,
            w * a * d,
            w * b * b,
            w * b * c,
            w * b * d,
            w * c * c,
            w * c * d,
            w * d * d,
        ])
    }
    fn add(&mut self, o: &Quadric) {
        for i in 0..10 {
            self.0[i] += o.0[i];
        }
    }
    fn sum(a: &Quadric, b: &Quadric) -> Quadric {
        let mut q = *a;
        q.add(b);
        q
    }
    fn eval(&self, p: [f64; 3]) -> f64 {
        eval_lanes(&self.0.map(|v| [v]), &[p])[0]
    }

    /// argmin x of the quadric and its value there, if the 3 × 3 system is well conditioned
    /// and x lies within `lim` of the origin (see [`minimum_lanes`]).
    fn minimum(&self, lim: f64) -> Option<([f64; 3], f64)> {
        let (x, cost, ok) = minimum_lanes(&self.0.map(|v| [v]), lim);
        ok[0].then_some((x[0], cost[0]))
    }
}

/// The quadratic form x̄ᵀ Q x̄, x̄ = (p, 1), of `L` quadrics at once (lane `l`: coefficients
/// `q[k][l]`, point `p[l]`); the lanes are independent, so they vectorise.
#[inline(always)]
fn eval_lanes<const L: usize>(q: &[[f64; L]; 10], p: &[[f64; 3]; L]) -> [f64; L] {
    let mut e = [0.0; L];
    for l in 0..L {
        let [x, y, z] = p[l];
        e[l] = q[0][l] * x * x
            + 2.0 * q[1][l] * x * y
            + 2.0 * q[2][l] * x * z
            + 2.0 * q[3][l] * x
            + q[4][l] * y * y
            + 2.0 * q[5][l] * y * z
            + 2.0 * q[6][l] * y
            + q[7][l] * z * z
            + 2.0 * q[8][l] * z
            + q[9][l];
    }
    e
}

/// The minimisers of `L` quadrics at once (lanes as in [`eval_lanes`]): with A the upper-left
/// 3 × 3 block and b the last column, x = −adj(A) b / det A; the cost Q(x) is evaluated as a
/// whole (the shortcut Q(x) = bᵀx + c loses small costs to cancellation) and clamped at 0.
/// The flag of a lane is false when A is near singular (|det| ≤ 10⁻¹⁰ ‖A‖³) or x is not
/// within `lim` of the origin.
#[inline(always)]
fn minimum_lanes<const L: usize>(
    q: &[[f64; L]; 10],
    lim: f64,
) -> ([[f64; 3]; L], [f64; L], [bool; L]) {
    let mut x = [[0.0; 3]; L];
    let mut ok = [false; L];
    for l in 0..L {
        let (a00, a01, a02, a11, a12, a22) = (q[0][l], q[1][l], q[2][l], q[4][l], q[5][l], q[7][l]);
        let b = [q[3][l], q[6][l], q[8][l]];
        // cofactors of the symmetric matrix (adj(A) is symmetric too)
        let c00 = a11 * a22 - a12 * a12;
        let c01 = a02 * a12 - a01 * a22;
        let c02 = a01 * a12 - a02 * a11;
        let c11 = a00 * a22 - a02 * a02;
        let c12 = a01 * a02 - a00 * a12;
        let c22 = a00 * a11 - a01 * a01;
        let det = a00 * c00 + a01 * c01 + a02 * c02;
        let norm = a00
            .abs()
            .max(a01.abs())
            .max(a02.abs())
            .max(a11.abs())
            .max(a12.abs())
            .max(a22.abs());
        let r = -1.0 / det;
        x[l] = [
            r * (c00 * b[0] + c01 * b[1] + c02 * b[2]),
            r * (c01 * b[0] + c11 * b[1] + c12 * b[2]),
            r * (c02 * b[0] + c12 * b[1] + c22 * b[2]),
        ];
        ok[l] = det.abs() > 1e-10 * norm * norm * norm
            && x[l][0].abs() < lim
            && x[l][1].abs() < lim
            && x[l][2].abs() < lim;
    }
    let mut cost = eval_lanes(q, &x);
    for c in cost.iter_mut() {
        *c = c.max(0.0);
    }
    (x, cost, ok)
}

/// A collapse candidate: 12 bytes. `stamp` is the sum of both vertices' stamps when queued;
/// a changed sum marks the entry stale (a collision only means a needless re-check).
#[derive(Clone, Copy)]
struct Candidate {
    a: u32,
    b: u32,
    stamp: u16,
}

/// An approximate min-priority queue: costs are binned by their f64 exponent and top four
/// mantissa bits, 16 bins per factor of two (costs within 3–6 % of each other share a bin and
/// leave in any order: last in first out, which keeps successive collapses close together).
/// Push and pop are O(1); a binary heap spent most of the run time in `pop` (cache misses
/// over millions of entries).
struct BinQueue {
    bins: Vec<Vec<Candidate>>,
    lowest: usize,
    /// buffers of emptied bins, reused by bins that get their first entry (most entries are
    /// popped soon after being pushed: recycling keeps the memory touched small)
    spare: Vec<Vec<Candidate>>,
}

impl BinQueue {
    const BINS: usize = 16 * 240 + 2;

    fn new() -> Self {
        BinQueue {
            bins: (0..Self::BINS).map(|_| Vec::new()).collect(),
            lowest: 0,
            spare: Vec::new(),
        }
    }

    /// Fill the queue with `(bin, candidate)` pairs, each bin allocated once at its size.
    fn fill(&mut self, items: &[Vec<(u32, Candidate)>]) {
        let mut count = vec![0usize; Self::BINS];
        for &(b, _) in items.iter().flatten() {
            count[b as usize] += 1;
        }
        for (bin, &n) in self.bins.iter_mut().zip(&count) {
            bin.reserve_exact(n);
        }
        for &(b, c) in items.iter().flatten() {
            self.bins[b as usize].push(c);
            self.lowest = self.lowest.min(b as usize);
        }
    }

    /// Bin of a cost: the exponent and the top 4 mantissa bits of the f64 (16 bins per
    /// octave, linear within the octave; monotone in the cost), octaves 2⁻²⁰⁰ … 2⁴⁰.
    #[inline]
    fn bin(cost: f64) -> usize {
        if cost.is_nan() || cost <= 0.0 {
            return 0;
        }
        const LOW: i64 = (1023 - 200) << 4;
        let key = (cost.to_bits() >> 48) as i64 - LOW;
        (key.max(0) as usize + 1).min(Self::BINS - 1)
    }

    #[inline]
    fn push(&mut self, cost: f64, c: Candidate) {
        let b = Self::bin(cost);
        let bin = &mut self.bins[b];
        if bin.capacity() == 0 {
            if let Some(buf) = self.spare.pop() {
                *bin = buf;
            }
        }
        bin.push(c);
        self.lowest = self.lowest.min(b);
    }

    /// The next entries `pop` would return from the current bin (at most `k`).
    #[inline]
    fn peek(&self, k: usize) -> impl Iterator<Item = &Candidate> {
        let bin = self.bins.get(self.lowest).map_or(&[][..], |b| &b[..]);
        bin.iter().rev().take(k)
    }

    #[inline]
    fn pop(&mut self) -> Option<Candidate> {
        while self.lowest < Self::BINS {
            let bin = &mut self.bins[self.lowest];
            if let Some(c) = bin.pop() {
                return Some(c);
            }
            if bin.capacity() > 0 {
                self.spare.push(std::mem::take(bin));
            }
            self.lowest += 1;
        }
        None
    }
}

/// Everything the collapse loop reads about a vertex, in two cache lines: the loop visits
/// vertices in cost order (all over the mesh), so one miss per line matters more than layout
/// elegance. Split arrays cost five or six misses per visited vertex.
#[derive(Clone, Copy, Default)]
#[repr(C, align(64))]
struct Vertex {
    quadric: Quadric,
    pos: [f64; 3],
    /// scratch mark for neighbourhood tests (compared with `State::mark_id`)
    mark: u32,
    /// `BOUNDARY`, `NON_MANIFOLD` (only during setup)
    flags: u32,
}

const BOUNDARY: u32 = 1;
const NON_MANIFOLD: u32 = 2;

/// A vertex's face list: `refs[start .. start + count]`.
#[derive(Clone, Copy, Default)]
struct Run {
    start: u32,
    count: u32,
}

/// A triangle; dead faces have `v[0] == NONE`.
#[derive(Clone, Copy)]
struct Face {
    v: [u32; 3],
}

impl Face {
    #[inline]
    fn alive(&self) -> bool {
        self.v[0] != NONE
    }
}

struct State {
    vert: Vec<Vertex>,
    face: Vec<Face>,
    /// the face lists of the vertices, one contiguous run each: a collapse appends the merged
    /// vertex's new list at the end (reading a run lets the face loads overlap, where a linked
    /// list would wait for each miss); compacted when it has grown to `3 ×` its initial size
    refs: Vec<u32>,
    /// per vertex, its run in `refs` (some of the faces there dead): apart from `vert` so
    /// that reaching the faces of a popped edge costs one miss less
    run: Vec<Run>,
    /// per vertex, bumped on every collapse touching it: a queue entry whose stamp sum differs
    /// is stale. Kept apart from `vert` (and 16-bit) so the check, done for every popped entry
    /// (most of them stale), stays in cache.
    stamp: Vec<u16>,
    mark_id: u32,
    /// optimal positions farther than this from the origin are rejected (1000 × the
    /// bounding-box diagonal, at least 1000)
    lim: f64,
}

impl State {
    /// The face list of `v`, dead faces included.
    #[inline]
    fn refs_of(&self, v: u32) -> &[u32] {
        let x = self.run[v as usize];
        &self.refs[x.start as usize..(x.start + x.count) as usize]
    }

    /// Live faces of `v`.
    fn faces_of(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        out.extend(
            self.refs_of(v)
                .iter()
                .copied()
                .filter(|&f| self.face[f as usize].alive()),
        );
    }

    /// Replace `v`'s face list by `list` (appended to `refs`).
    fn set_faces(&mut self, v: u32, list: &[u32]) {
        let x = &mut self.run[v as usize];
        x.start = self.refs.len() as u32;
        x.count = list.len() as u32;
        self.refs.extend_from_slice(list);
    }

    /// Rebuild `refs` with the live faces of each vertex only (same order).
    fn compact_refs(&mut self) {
        let mut refs = Vec::with_capacity(self.refs.capacity());
        for x in self.run.iter_mut() {
            let run = &self.refs[x.start as usize..(x.start + x.count) as usize];
            x.start = refs.len() as u32;
            refs.extend(
                run.iter()
                    .copied()
                    .filter(|&f| self.face[f as usize].v[0] != NONE),
            );
            x.count = refs.len() as u32 - x.start;
        }
        self.refs = refs;
    }

    fn place(&self, a: u32, b: u32) -> ([f64; 3], f64) {
        let (va, vb) = (&self.vert[a as usize], &self.vert[b as usize]);
        let q = Quadric::sum(&va.quadric, &vb.quadric);
        if let Some(m) = q.minimum(self.lim) {
            return m;
        }
        let (pa, pb) = (va.pos, vb.pos);
        let mid = vec3::scale(vec3::add(pa, pb), 0.5);
        [pa, pb, mid]
            .into_iter()
            .map(|x| (x, q.eval(x).max(0.0)))
            .min_by(|u, v| u.1.total_cmp(&v.1))
            .unwrap()
    }

    /// Costs of collapsing `a` with each of `vs` (as `place`), four at a time (the four
    /// solves are independent and share vector instructions).
    fn costs(&self, a: u32, vs: &[u32], out: &mut Vec<f64>) {
        out.clear();
        let qa = &self.vert[a as usize].quadric.0;
        for chunk in vs.chunks(4) {
            let mut q = [[0.0f64; 4]; 10];
            for l in 0..4 {
                let qv = &self.vert[chunk[l.min(chunk.len() - 1)] as usize].quadric.0;
                for k in 0..10 {
                    q[k][l] = qa[k] + qv[k];
                }
            }
            let (_, cost, ok) = minimum_lanes(&q, self.lim);
            for (l, &v) in chunk.iter().enumerate() {
                out.push(if ok[l] { cost[l] } else { self.place(a, v).1 });
            }
        }
    }

    /// A fresh mark id (all marks reset when the counter wraps).
    fn next_mark(&mut self) -> u32 {
        self.mark_id = self.mark_id.wrapping_add(1);
        if self.mark_id == 0 {
            self.vert.iter_mut().for_each(|v| v.mark = 0);
            self.mark_id = 1;
        }
        self.mark_id
    }

    /// Link condition and normal-flip test for collapsing a, b into x.
    fn can_collapse(&mut self, a: u32, b: u32, x: [f64; 3], fa: &[u32], fb: &[u32]) -> bool {
        let tri = |f: u32| self.face[f as usize].v;
        if self.vert[a as usize].flags & self.vert[b as usize].flags & BOUNDARY != 0 {
            // only along a boundary edge: ab must have exactly one face
            let shared = fa.iter().filter(|&&f| tri(f).contains(&b)).count();
            if shared != 1 {
                return false;
            }
        }
        // opposite vertices of the faces on ab
        let mut opposite = [NONE; 2];
        let mut k = 0;
        for &f in fa {
            let t = tri(f);
            if t.contains(&b) {
                if k == 2 {
                    return false;
                }
                opposite[k] = t.into_iter().find(|&v| v != a && v != b).unwrap();
                k += 1;
            }
        }
        if k == 0 {
            return false;
        }
        // vertex link: neighbours of a marked, common neighbours of b must be the opposites
        let id = self.next_mark();
        for &f in fa {
            for v in self.face[f as usize].v {
                self.vert[v as usize].mark = id;
            }
        }
        for &f in fb {
            for v in self.face[f as usize].v {
                if v != a
                    && v != b
                    && self.vert[v as usize].mark == id
                    && !opposite[..k].contains(&v)
                {
                    return false;
                }
            }
        }
        let tri = |f: u32| self.face[f as usize].v;
        // edge link: a face (a, c, d) and a face (b, c, d) with c, d the opposites
        if k == 2 {
            let has = |fs: &[u32], w: u32| {
                fs.iter().any(|&f| {
                    let t = tri(f);
                    t.contains(&w) && t.contains(&opposite[0]) && t.contains(&opposite[1])
                })
            };
            if has(fa, a) && has(fb, b) {
                return false;
            }
        }
        // normal flips
        for (&f, moved) in fa.iter().map(|f| (f, a)).chain(fb.iter().map(|f| (f, b))) {
            let t = tri(f);
            if t.contains(&a) && t.contains(&b) {
                continue;
            }
            let p: [[f64; 3]; 3] = std::array::from_fn(|i| self.vert[t[i] as usize].pos);
            let before = vec3::cross(vec3::sub(p[1], p[0]), vec3::sub(p[2], p[0]));
            let q: [[f64; 3]; 3] = std::array::from_fn(|i| if t[i] == moved { x } else { p[i] });
            let after = vec3::cross(vec3::sub(q[1], q[0]), vec3::sub(q[2], q[0]));
            if vec3::dot(before, after) <= 0.0 {
                return false;
            }
        }
        true
    }
}

/// Hint the cache to load the line at `p` (no effect on results; a no-op off x86-64).
#[inline(always)]
fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: prefetching never faults, whatever the address.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch(p as *const i8, _MM_HINT_T0);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// The distinct neighbours `w` of vertex `v` (with face list `faces`) as
/// `(w, faces on the edge vw, one such face)`, in face-list order.
fn neighbours(face: &[Face], faces: &[u32], v: u32, ring: &mut Vec<(u32, u32, u32)>) {
    ring.clear();
    for &f in faces {
        for w in face[f as usize].v {
            if w == v {
                continue;
            }
            match ring.iter_mut().find(|e| e.0 == w) {
                Some(e) => e.1 += 1,
                None => ring.push((w, 1, f)),
            }
        }
    }
}

/// Simplify a manifold mesh (polygons are triangulated first) to at most `target_faces`
/// triangles, or as few as the link condition allows.
pub fn simplify(mesh: &Mesh, target_faces: usize) -> Result<Mesh> {
    simplify_with_room(mesh, target_faces, 3)
}

/// [`simplify`] with room for `room ×` the initial face lists in `refs` before a compaction:
/// face lists, vertex quadrics, the manifold check, every edge queued by its cost, then
/// collapses from the cheapest until `target_faces` remain, and the live faces compacted.
fn simplify_with_room(mesh: &Mesh, target_faces: usize, room: usize) -> Result<Mesh> {
    let m = if mesh.is_triangle_mesh() {
        std::borrow::Cow::Borrowed(mesh)
    } else {
        std::borrow::Cow::Owned(mesh.triangulated())
    };
    let nv = m.vertex_count();
    let nf = m.face_count();
    let face: Vec<Face> = m
        .indices
        .par_chunks(3)
        .with_min_len(4096)
        .map(|c| Face {
            v: [c[0], c[1], c[2]],
        })
        .collect();
    let (start, refs, refs_limit) = face_lists(&m.indices, nv, room);
    let vert = vertex_quadrics(&m.positions, &face, &refs, &start);
    let run: Vec<Run> = start
        .windows(2)
        .map(|w| Run {
            start: w[0],
            count: w[1] - w[0],
        })
        .collect();
    drop(start);
    check_manifold(&vert, &face, &refs, &run)?;
    let (lo, hi) = m.bounding_box().unwrap_or(([0.0; 3], [1.0; 3]));
    let scale = vec3::norm(vec3::sub(hi, lo)).max(1e-300);
    let mut s = State {
        vert,
        face,
        refs,
        run,
        stamp: vec![0; nv],
        mark_id: 0,
        lim: 1e3 * scale.max(1.0),
    };
    let mut heap = BinQueue::new();
    heap.fill(&s.initial_candidates());
    let mut faces = nf;
    let (mut fa, mut fb) = (Vec::new(), Vec::new());
    let (mut ring, mut ring_cost) = (Vec::new(), Vec::new());
    while faces > target_faces {
        let Some(c) = heap.pop() else { break };
        let (a, b) = (c.a, c.b);
        if !s.is_live(&c) {
            continue;
        }
        // start loading the next live candidate's data while this one is processed
        if let Some(n) = heap.peek(8).find(|n| s.is_live(n)) {
            s.prefetch_edge(n);
        }
        s.faces_of(a, &mut fa);
        s.faces_of(b, &mut fb);
        let (x, _) = s.place(a, b);
        if !s.can_collapse(a, b, x, &fa, &fb) {
            continue;
        }
        faces -= s.collapse(a, b, x, &mut fa, &fb, refs_limit);
        // new candidates around a (its live faces were collected above)
        s.ring_of(a, &fa, &mut ring);
        s.costs(a, &ring, &mut ring_cost);
        let sa = s.stamp[a as usize];
        for (&v, &cost) in ring.iter().zip(&ring_cost) {
            heap.push(
                cost,
                Candidate {
                    a,
                    b: v,
                    stamp: sa.wrapping_add(s.stamp[v as usize]),
                },
            );
        }
    }
    Ok(s.into_mesh(nv, faces))
}

/// The faces around each vertex by a counting sort of `indices` (triangles): vertex `v`'s
/// faces are `refs[start[v]..start[v + 1]]`, in face order. `refs` has room for `room ×`
/// these lists (the limit returned third): collapses append lists, compacted when full.
fn face_lists(indices: &[u32], nv: usize, room: usize) -> (Vec<u32>, Vec<u32>, usize) {
    let mut start = vec![0u32; nv + 1];
    for &v in indices {
        start[v as usize + 1] += 1;
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let total = start[nv] as usize;
    let refs_limit = (room * total + 64).min(u32::MAX as usize);
    let mut refs = Vec::with_capacity(refs_limit);
    refs.resize(total, 0u32);
    let mut fill = start.clone();
    for (c, &v) in indices.iter().enumerate() {
        refs[fill[v as usize] as usize] = (c / 3) as u32;
        fill[v as usize] += 1;
    }
    (start, refs, refs_limit)
}

/// Per vertex, in parallel: the quadric of its faces' planes and its edges' face counts
/// (boundary edges add a plane ⟂ the face through the edge, weight 100; edges in three or
/// more faces are flagged).
fn vertex_quadrics(
    positions: &[[f64; 3]],
    face: &[Face],
    refs: &[u32],
    start: &[u32],
) -> Vec<Vertex> {
    let plane_of = |t: [u32; 3]| {
        let p = t.map(|v| positions[v as usize]);
        let n = vec3::normalized(vec3::cross(vec3::sub(p[1], p[0]), vec3::sub(p[2], p[0])));
        (n, -vec3::dot(n, p[0]))
    };
    (0..start.len() - 1)
        .into_par_iter()
        .with_min_len(1024)
        .map_init(Vec::new, |ring, v| {
            let (s0, s1) = (start[v], start[v + 1]);
            let run = &refs[s0 as usize..s1 as usize];
            neighbours(face, run, v as u32, ring);
            let pos = positions[v];
            let mut q = Quadric::default();
            for &f in run {
                let (n, d) = plane_of(face[f as usize].v);
                q.add(&Quadric::plane(n, d, 1.0));
            }
            let mut flags = 0;
            for &(w, uses, f) in ring.iter() {
                if uses == 1 {
                    flags |= BOUNDARY;
                    let (n, _) = plane_of(face[f as usize].v);
                    let pw = positions[w as usize];
                    let p = vec3::normalized(vec3::cross(vec3::sub(pw, pos), n));
                    q.add(&Quadric::plane(p, -vec3::dot(p, pos), 100.0));
                } else if uses > 2 {
                    flags |= NON_MANIFOLD;
                }
            }
            Vertex {
                quadric: q,
                pos,
                mark: 0,
                flags,
            }
        })
        .collect()
}

/// An error naming the first non-manifold edge (from its smaller vertex), if any.
fn check_manifold(vert: &[Vertex], face: &[Face], refs: &[u32], run: &[Run]) -> Result<()> {
    let Some(v) = vert.iter().position(|x| x.flags & NON_MANIFOLD != 0) else {
        return Ok(());
    };
    let mut ring = Vec::new();
    let r = run[v];
    neighbours(
        face,
        &refs[r.start as usize..][..r.count as usize],
        v as u32,
        &mut ring,
    );
    let &(w, uses, _) = ring.iter().filter(|e| e.1 > 2).min().unwrap();
    let (a, b) = (v.min(w as usize), v.max(w as usize));
    Err(Error::format(
        format!("non-manifold edge ({a}, {b}): used by {uses} faces"),
        "a manifold mesh (each edge in one or two faces)",
    ))
}

impl State {
    /// Every edge once (from its smaller vertex) with its cost's bin, in vertex order.
    fn initial_candidates(&self) -> Vec<Vec<(u32, Candidate)>> {
        let nv = self.vert.len() as u32;
        (0..nv)
            .into_par_iter()
            .chunks(16384)
            .map_init(
                || (Vec::new(), Vec::new(), Vec::new()),
                |(ring, ws, cost), vs| {
                    let mut out = Vec::with_capacity(3 * vs.len());
                    for v in vs {
                        neighbours(&self.face, self.refs_of(v), v, ring);
                        ws.clear();
                        ws.extend(ring.iter().map(|e| e.0).filter(|&w| w > v));
                        self.costs(v, ws, cost);
                        for (&w, &c) in ws.iter().zip(cost.iter()) {
                            let b = BinQueue::bin(c) as u32;
                            out.push((
                                b,
                                Candidate {
                                    a: v,
                                    b: w,
                                    stamp: 0,
                                },
                            ));
                        }
                    }
                    out
                },
            )
            .collect()
    }

    /// Whether a queued candidate is current (no collapse touched its ends since).
    #[inline]
    fn is_live(&self, c: &Candidate) -> bool {
        self.stamp[c.a as usize].wrapping_add(self.stamp[c.b as usize]) == c.stamp
    }

    /// Start loading the face lists and vertex data of candidate `n`'s ends.
    fn prefetch_edge(&self, n: &Candidate) {
        for v in [n.a, n.b] {
            let r = self.run[v as usize];
            prefetch(self.refs.as_ptr().wrapping_add(r.start as usize));
            let p = &self.vert[v as usize] as *const Vertex as *const u8;
            prefetch(p);
            prefetch(p.wrapping_add(64));
        }
    }

    /// Collapse `b` into `a` at `x`: its faces on `ab` die, the others move to `a`; `fa`
    /// becomes `a`'s new face list (`a`'s live faces, then `b`'s). Returns the faces removed.
    fn collapse(
        &mut self,
        a: u32,
        b: u32,
        x: [f64; 3],
        fa: &mut Vec<u32>,
        fb: &[u32],
        refs_limit: usize,
    ) -> usize {
        let mut removed = 0;
        for &f in fa.iter() {
            let t = &mut self.face[f as usize];
            if t.v.contains(&b) {
                t.v = [NONE; 3];
                removed += 1;
            }
        }
        fa.retain(|&f| self.face[f as usize].alive());
        for &f in fb {
            let t = &mut self.face[f as usize];
            if t.alive() {
                for w in t.v.iter_mut() {
                    if *w == b {
                        *w = a;
                    }
                }
                fa.push(f);
            }
        }
        if self.refs.len() + fa.len() > refs_limit {
            self.compact_refs();
        }
        self.set_faces(a, fa);
        let vb = self.vert[b as usize];
        let va = &mut self.vert[a as usize];
        va.pos = x;
        va.quadric.add(&vb.quadric);
        va.flags |= vb.flags;
        self.run[b as usize].count = 0;
        self.stamp[a as usize] = self.stamp[a as usize].wrapping_add(1);
        self.stamp[b as usize] = self.stamp[b as usize].wrapping_add(1);
        removed
    }

    /// The distinct vertices other than `a` of faces `fa`, in face order.
    fn ring_of(&mut self, a: u32, fa: &[u32], ring: &mut Vec<u32>) {
        let id = self.next_mark();
        ring.clear();
        for &f in fa {
            for v in self.face[f as usize].v {
                if v != a && self.vert[v as usize].mark != id {
                    self.vert[v as usize].mark = id;
                    ring.push(v);
                }
            }
        }
    }

    /// The live faces as a mesh (`faces` of them) over the vertices they use, in first-use
    /// order; `nv` vertices before simplification.
    fn into_mesh(self, nv: usize, faces: usize) -> Mesh {
        let mut remap = vec![NONE; nv];
        let mut positions = Vec::new();
        let mut indices = Vec::with_capacity(3 * faces);
        for t in &self.face {
            if !t.alive() {
                continue;
            }
            for &v in &t.v {
                if remap[v as usize] == NONE {
                    remap[v as usize] = positions.len() as u32;
                    positions.push(self.vert[v as usize].pos);
                }
                indices.push(remap[v as usize]);
            }
        }
        let n = indices.len() / 3;
        Mesh {
            positions,
            offsets: (0..=n as u32).map(|i| 3 * i).collect(),
            indices,
            attributes: Attributes::default(),
        }
    }
}

/// One-sided Hausdorff distance from the vertices of `a` to the surface of `b` (brute force
/// over a uniform grid of `b`'s triangles): max over a's vertices of the distance to b.
pub fn vertex_to_surface_distance(a: &Mesh, b: &Mesh) -> f64 {
    let bt = b.triangulated();
    let Some((lo, hi)) = b.bounding_box() else {
        return f64::INFINITY;
    };
    let n = ((bt.face_count() as f64).cbrt().ceil() as usize).clamp(1, 128);
    let size: [f64; 3] = std::array::from_fn(|k| ((hi[k] - lo[k]) / n as f64).max(1e-12));
    let cell = |p: [f64; 3]| -> [usize; 3] {
        std::array::from_fn(|k| (((p[k] - lo[k]) / size[k]).floor().max(0.0) as usize).min(n - 1))
    };
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); n * n * n];
    for (f, t) in bt.faces().enumerate() {
        let ps: Vec<[f64; 3]> = t.iter().map(|&v| bt.positions[v as usize]).collect();
        let (c0, c1) = (
            cell(std::array::from_fn(|k| {
                ps.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min)
            })),
            cell(std::array::from_fn(|k| {
                ps.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max)
            })),
        );
        for i in c0[0]..=c1[0] {
            for j in c0[1]..=c1[1] {
                for k in c0[2]..=c1[2] {
                    grid[(i * n + j) * n + k].push(f as u32);
                }
            }
        }
    }
    use rayon::prelude::*;
    a.positions
        .par_iter()
        .map(|&p| {
            let c = cell(p);
            let mut best = f64::INFINITY;
            for r in 0..n {
                // search shells of growing radius until the shell is farther than the best hit
                let shell_dist =
                    (r as f64 - 1.0).max(0.0) * size.iter().cloned().fold(f64::INFINITY, f64::min);
                if shell_dist > best {
                    break;
                }
                let lo_i: [usize; 3] = std::array::from_fn(|k| c[k].saturating_sub(r));
                let hi_i: [usize; 3] = std::array::from_fn(|k| (c[k] + r).min(n - 1));
                for i in lo_i[0]..=hi_i[0] {
                    for j in lo_i[1]..=hi_i[1] {
                        for k in lo_i[2]..=hi_i[2] {
                            let on_shell = [i, j, k]
                                .iter()
                                .zip(c.iter())
                                .any(|(&x, &y)| x.abs_diff(y) == r);
                            if !on_shell {
                                continue;
                            }
                            for &f in &grid[(i * n + j) * n + k] {
                                let t = bt.face(f as usize);
                                let d = point_triangle_distance(
                                    p,
                                    bt.positions[t[0] as usize],
                                    bt.positions[t[1] as usize],
                                    bt.positions[t[2] as usize],
                                );
                                best = best.min(d);
                            }
                        }
                    }
                }
            }
            best
        })
        .reduce(|| 0.0, f64::max)
}

/// Distance from `p` to triangle `abc` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn point_triangle_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    use vec3::{dot, norm, sub};
    let ab = sub(b, a);
    let ac = sub(c, a);
    // (ab · (p − q), ac · (p − q)) for q = a, b, c
    let [(d1, d2), (d3, d4), (d5, d6)] = [a, b, c].map(|q| {
        let qp = sub(p, q);
        (dot(ab, qp), dot(ac, qp))
    });
    // distance to the point `q + t·e` of an edge
    let to_edge = |q: [f64; 3], e: [f64; 3], t: f64| norm(sub(p, vec3::add(q, vec3::scale(e, t))));
    if d1 <= 0.0 && d2 <= 0.0 {
        return norm(sub(p, a));
    }
    if d3 >= 0.0 && d4 <= d3 {
        return norm(sub(p, b));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return to_edge(a, ab, d1 / (d1 - d3));
    }
    if d6 >= 0.0 && d5 <= d6 {
        return norm(sub(p, c));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return to_edge(a, ac, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return to_edge(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    norm(sub(
        p,
        vec3::add(a, vec3::add(vec3::scale(ab, v), vec3::scale(ac, w))),
    ))
}

/// Collapse the edge `a`–`b` of a triangle mesh into one vertex at `position` (§6.6.3). Fails
/// when there is no such edge or when the collapse would break the 2-manifold: the link
/// condition Lk(a) ∩ Lk(b) = Lk(ab), and no interior edge joining two boundary vertices.
/// Vertex `b` is removed (later vertices shift down by one).
pub fn collapse_edge(mesh: &Mesh, a: u32, b: u32, position: [f64; 3]) -> Result<Mesh> {
    if !mesh.is_triangle_mesh() {
        return Err(Error::Unsupported {
            what: "edge collapse on faces that are not triangles",
            value: format!("{} faces", mesh.face_count()),
        });
    }
    let nv = mesh.vertex_count() as u32;
    if a >= nv || b >= nv || a == b {
        return Err(Error::parameter(
            "edge",
            format!("({a}, {b})"),
            "two distinct vertex indices",
        ));
    }
    let he = super::HalfEdgeMesh::build(mesh)?;
    let (va, vb) = (super::VertexId(a), super::VertexId(b));
    let h = he.find_halfedge(va, vb).ok_or_else(|| {
        Error::parameter(
            "edge",
            format!("({a}, {b})"),
            "two vertices joined by an edge",
        )
    })?;
    let ring =
        |v: super::VertexId| -> Vec<u32> { he.outgoing(v).map(|h| he.to_vertex(h).0).collect() };
    let (ra, rb) = (ring(va), ring(vb));
    let opposite: Vec<u32> = [h, he.twin(h)]
        .iter()
        .filter(|&&x| !he.is_boundary_halfedge(x))
        .map(|&x| he.from_vertex(he.prev(x)).0)
        .collect();
    let common: Vec<u32> = ra.iter().copied().filter(|v| rb.contains(v)).collect();
    let fail = |why: &str| {
        Error::format(
            format!("collapsing edge ({a}, {b}) {why}"),
            "an edge whose collapse keeps the mesh a manifold (link condition)",
        )
    };
    if common.len() != opposite.len() || !common.iter().all(|v| opposite.contains(v)) {
        return Err(fail(
            "would pinch the surface: a and b share a neighbour off their faces",
        ));
    }
    if he.is_boundary_vertex(va) && he.is_boundary_vertex(vb) && !he.is_boundary_edge(he.edge(h)) {
        return Err(fail("would join two boundary arcs through the interior"));
    }
    if opposite.len() == 2 {
        let (c, d) = (super::VertexId(opposite[0]), super::VertexId(opposite[1]));
        if let Some(hcd) = he.find_halfedge(c, d) {
            // faces (a, c, d) and (b, c, d) both present: the edge cd is in both links
            let faces_with = |w: u32| {
                [hcd, he.twin(hcd)]
                    .iter()
                    .any(|&x| !he.is_boundary_halfedge(x) && he.from_vertex(he.prev(x)).0 == w)
            };
            if faces_with(a) && faces_with(b) {
                return Err(fail("would create a doubled face"));
            }
        }
    }
    let mut positions = mesh.positions.clone();
    positions[a as usize] = position;
    positions.remove(b as usize);
    let map = |v: u32| {
        let v = if v == b { a } else { v };
        if v > b {
            v - 1
        } else {
            v
        }
    };
    let mut indices = Vec::with_capacity(mesh.indices.len());
    for f in mesh.faces() {
        if f.contains(&a) && f.contains(&b) {
            continue;
        }
        indices.extend(f.iter().map(|&v| map(v)));
    }
    Ok(Mesh::of_degree(positions, indices, 3))
}

/// Remove an interior vertex of a triangle mesh and fill its hole with a fan of triangles from
/// one of its neighbours (§6.6.3), chosen so that no fan edge already exists. Later vertices
/// shift down by one.
pub fn remove_vertex(mesh: &Mesh, v: u32) -> Result<Mesh> {
    if !mesh.is_triangle_mesh() {
        return Err(Error::Unsupported {
            what: "vertex removal on faces that are not triangles",
            value: format!("{} faces", mesh.face_count()),
        });
    }
    if v as usize >= mesh.vertex_count() {
        return Err(Error::parameter("vertex", v, "a vertex index of the mesh"));
    }
    let he = super::HalfEdgeMesh::build(mesh)?;
    let vid = super::VertexId(v);
    if he.is_boundary_vertex(vid) {
        return Err(Error::Unsupported {
            what: "removal of a boundary vertex",
            value: v.to_string(),
        });
    }
    // ring in counter-clockwise order: in face (v, x, y) the link edge runs x → y
    let mut next_of = std::collections::HashMap::new();
    for h in he.outgoing(vid) {
        let x = he.to_vertex(h).0;
        let y = he.to_vertex(he.next(h)).0;
        next_of.insert(x, y);
    }
    let start = *next_of.keys().min().unwrap();
    let mut ring = vec![start];
    while ring.len() < next_of.len() {
        let n = next_of[ring.last().unwrap()];
        if n == start {
            break;
        }
        ring.push(n);
    }
    let k = ring.len();
    let pick = (0..k).find(|&s| {
        (2..k - 1).all(|i| {
            he.find_halfedge(super::VertexId(ring[s]), super::VertexId(ring[(s + i) % k]))
                .is_none()
        })
    });
    let s = pick.ok_or_else(|| {
        Error::format(
            format!(
                "vertex {v}: every fan over its {k} neighbours would duplicate an existing edge"
            ),
            "a vertex whose hole can be filled without creating a non-manifold edge",
        )
    })?;
    let map = |w: u32| if w > v { w - 1 } else { w };
    let mut indices = Vec::with_capacity(mesh.indices.len());
    for f in mesh.faces() {
        if !f.contains(&v) {
            indices.extend(f.iter().map(|&w| map(w)));
        }
    }
    for i in 1..k - 1 {
        indices.extend([ring[s], ring[(s + i) % k], ring[(s + i + 1) % k]].map(map));
    }
    let mut positions = mesh.positions.clone();
    positions.remove(v as usize);
    Ok(Mesh::of_degree(positions, indices, 3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compacting_the_face_lists_often_changes_nothing() {
        let torus = super::super::shapes::torus_triangles(30, 20, 3.0, 1.0);
        let roomy = simplify_with_room(&torus, 300, 3).unwrap();
        let tight = simplify_with_room(&torus, 300, 1).unwrap();
        assert_eq!(roomy.face_count(), 300);
        assert_eq!(roomy, tight);
    }
}
