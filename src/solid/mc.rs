//! Marching cubes (§10.6's polygonisation) on a sampled grid, with shared vertices and
//! manifold, consistently oriented output.
//!
//! A sample is *inside* when `value > level`. Each grid edge whose end points differ gets one
//! vertex at the linear zero `t = (level − v₀)/(v₁ − v₀)`; vertices are numbered per plane
//! (grid edge → index), so neighbouring cells share them. Instead of a 256-case table, each
//! cell links its crossings face by face: on every cube face, walked counter-clockwise seen from
//! outside the cell, a segment runs from each *entering* crossing (outside → inside) to a
//! *leaving* one. On an ambiguous face (diagonal corners alike) the asymptotic decider picks the
//! pairing: the inside corners are joined iff `v_a v_c > v_b v_d` (inside pair product above
//! the outside pair product, values minus level), which is the sign of the bilinear saddle.
//! The decision depends only on the face's four samples, so both cells sharing a face draw the
//! same segments; every crossing is the start of one segment and the end of another inside a
//! cell, so the segments close into loops, which are triangulated as fans. The result has every
//! interior edge in exactly two triangles, traversed in opposite directions, with normals
//! pointing from inside (high values) to outside.
//!
//! Four passes, each parallel over z-planes or slabs with rayon, in the spirit of Flying Edges
//! (Schroeder et al. 2015): (1) one bit per sample, "inside", packed in 64-bit words per row;
//! (2) crossing words per row and axis by XOR of neighbouring rows / shifted words, with
//! popcounts giving each row's vertex count; (3) after a prefix sum, vertex positions (and
//! normals) for exactly the crossing edges, numbered row by row, and per-word first indices so
//! any edge's vertex index is a rank query (first index + popcount below the bit); (4) per slab,
//! only the cells whose eight corner bits are not all equal (word-parallel test) are visited;
//! cases without an ambiguous face take their triangles from a table built once by the same
//! linking, the others are linked from their values. No hash maps, no per-cell allocation.

// Index loops over corners, axes and cases follow the formulas (several arrays indexed together).
#![allow(clippy::needless_range_loop)]

use crate::mesh::Mesh;
use crate::tensor::zeroed_vec;
use crate::{Error, Result};
use rayon::prelude::*;

mod case;
use case::{case_table, for_each_loop, link, safe_fan, EDGES};

/// A scalar grid, `x` fastest: `values[(k·ny + j)·nx + i]` sits at
/// `origin + (i·sx, j·sy, k·sz)`.
#[derive(Clone, Copy, Debug)]
pub struct Grid<'a> {
    pub values: &'a [f32],
    pub dims: [usize; 3],
    pub spacing: [f64; 3],
    pub origin: [f64; 3],
}

/// Output of [`polygonize`]: a triangle mesh and optional vertex normals.
#[derive(Clone, Debug)]
pub struct Isosurface {
    pub mesh: Mesh,
    /// Unit outward normals from the grid gradient (central differences), when asked.
    pub normals: Option<Vec<[f64; 3]>>,
}

impl Grid<'_> {
    fn check(&self) -> Result<()> {
        let n: usize = self.dims.iter().product();
        if self.values.len() != n {
            return Err(Error::parameter(
                "grid",
                format!("{} values for dims {:?}", self.values.len(), self.dims),
                "nx·ny·nz values",
            ));
        }
        if self.dims.iter().any(|&d| d < 2) {
            return Err(Error::parameter(
                "grid dims",
                format!("{:?}", self.dims),
                "at least 2 samples per axis",
            ));
        }
        if n > u32::MAX as usize / 8 {
            return Err(Error::LimitsExceeded {
                what: "grid samples",
                requested: n as u64,
                limit: u32::MAX as u64 / 8,
            });
        }
        if self.spacing.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(Error::parameter(
                "spacing",
                format!("{:?}", self.spacing),
                "positive finite spacing",
            ));
        }
        Ok(())
    }
}

/// The largest `f32` `t` with `t ≤ level`: for every `f32` sample `v`,
/// `v > t ⇔ (v as f64) > level`, so the inside test runs on `f32` lanes.
fn f32_threshold(level: f64) -> f32 {
    let t = level as f32;
    if (t as f64) > level {
        next_below(t)
    } else {
        t
    }
}

/// The next `f32` below `t` (`t` neither NaN nor −∞); `f32::next_down` needs Rust 1.86.
fn next_below(t: f32) -> f32 {
    if t == 0.0 {
        return -f32::from_bits(1);
    }
    let b = t.to_bits();
    f32::from_bits(if t > 0.0 { b - 1 } else { b + 1 })
}

/// Row `x` shifted down by one bit (bit `i` ← bit `i + 1`), across word boundaries.
#[inline(always)]
fn shr1(x: &[u64], w: usize) -> u64 {
    (x[w] >> 1) | x.get(w + 1).map_or(0, |n| n << 63)
}

/// Mask of the low `n` bits of word `w` in a row of `n` valid bits.
#[inline(always)]
fn valid(n: usize, w: usize) -> u64 {
    let lo = w * 64;
    if n >= lo + 64 {
        !0
    } else if n <= lo {
        0
    } else {
        (1u64 << (n - lo)) - 1
    }
}

/// Position (and outward unit normal when `with_normal`) of the crossing on the grid edge from
/// point `p` along `axis`.
fn edge_vertex(
    g: &Grid,
    level: f64,
    p: [usize; 3],
    axis: usize,
    with_normal: bool,
) -> ([f64; 3], [f64; 3]) {
    let [nx, ny, _] = g.dims;
    let at = |q: [usize; 3]| g.values[(q[2] * ny + q[1]) * nx + q[0]] as f64;
    let mut p1 = p;
    p1[axis] += 1;
    let (va, vb) = (at(p), at(p1));
    let t = (level - va) / (vb - va);
    let mut idx = [p[0] as f64, p[1] as f64, p[2] as f64];
    idx[axis] += t;
    let pos = [
        g.origin[0] + g.spacing[0] * idx[0],
        g.origin[1] + g.spacing[1] * idx[1],
        g.origin[2] + g.spacing[2] * idx[2],
    ];
    let mut n = [0.0; 3];
    if with_normal {
        let ga = grad_at(g, p);
        let gb = grad_at(g, p1);
        let gr = [
            ga[0] + t * (gb[0] - ga[0]),
            ga[1] + t * (gb[1] - ga[1]),
            ga[2] + t * (gb[2] - ga[2]),
        ];
        let l = (gr[0] * gr[0] + gr[1] * gr[1] + gr[2] * gr[2]).sqrt();
        if l > 0.0 {
            n = [-gr[0] / l, -gr[1] / l, -gr[2] / l];
        }
    }
    (pos, n)
}

/// Gradient of the samples at a grid point (central differences, one-sided at the border).
fn grad_at(g: &Grid, p: [usize; 3]) -> [f64; 3] {
    let [nx, ny, _] = g.dims;
    let at = |q: [usize; 3]| g.values[(q[2] * ny + q[1]) * nx + q[0]] as f64;
    let mut out = [0.0; 3];
    for a in 0..3 {
        let lo = p[a].saturating_sub(1);
        let hi = (p[a] + 1).min(g.dims[a] - 1);
        let mut ql = p;
        let mut qh = p;
        ql[a] = lo;
        qh[a] = hi;
        out[a] = (at(qh) - at(ql)) / ((hi - lo) as f64 * g.spacing[a]);
    }
    out
}

/// The inside bits of the whole grid, `W = ⌈nx/64⌉` words per row (row `r = k·ny + j`, bit
/// `i`), and the index of the first vertex on each row's x, y and z edges.
struct Bits {
    dims: [usize; 3],
    w: usize,
    inside: Vec<u64>,
    /// `first[3r + axis]`: index of the first vertex on the `axis` edges of row `r`.
    first: Vec<u32>,
}

impl Bits {
    /// Crossing word `wi` of the `axis` edges of row `(j, k)`: x edges `(i, j, k)–(i+1, j, k)`,
    /// y edges to row `j + 1`, z edges to plane `k + 1` (XOR of the inside bits).
    #[inline(always)]
    fn cross(&self, axis: usize, j: usize, k: usize, wi: usize) -> u64 {
        let [nx, ny, nz] = self.dims;
        let w = self.w;
        let r = k * ny + j;
        let a = &self.inside[r * w..(r + 1) * w];
        match axis {
            0 => (a[wi] ^ shr1(a, wi)) & valid(nx - 1, wi),
            1 if j + 1 < ny => a[wi] ^ self.inside[(r + 1) * w + wi],
            2 if k + 1 < nz => a[wi] ^ self.inside[(r + ny) * w + wi],
            _ => 0,
        }
    }

    /// The cells `(i, j, k)` whose eight corners are not all alike, with their cases.
    #[inline(always)]
    fn active_cells(&self, k: usize, j: usize) -> ActiveCells<'_> {
        let [nx, ny, _] = self.dims;
        let w = self.w;
        let r00 = k * ny + j;
        ActiveCells {
            rows: [r00, r00 + 1, r00 + ny, r00 + ny + 1].map(|r| &self.inside[r * w..(r + 1) * w]),
            cells: nx - 1,
            wi: 0,
            word: 0,
            lo: [0; 4],
            hi: [0; 4],
            started: false,
        }
    }
}

/// Iterator over the cells of one row of cells whose eight corners are not all alike (found
/// word by word: any corner inside and not every corner inside), yielding `(i, case)`; corner
/// `c` of the case is `(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1))`.
struct ActiveCells<'a> {
    /// Inside words of the rows `(j, k)`, `(j+1, k)`, `(j, k+1)`, `(j+1, k+1)`.
    rows: [&'a [u64]; 4],
    cells: usize,
    wi: usize,
    /// Active cells left in word `wi`.
    word: u64,
    /// Word `wi` of each row, and the same shifted by one (bit `i` = sample `i + 1`).
    lo: [u64; 4],
    hi: [u64; 4],
    started: bool,
}

impl Iterator for ActiveCells<'_> {
    type Item = (usize, u8);

    #[inline(always)]
    fn next(&mut self) -> Option<(usize, u8)> {
        while self.word == 0 {
            if self.started {
                self.wi += 1;
            }
            self.started = true;
            if self.wi >= self.rows[0].len() {
                return None;
            }
            let wi = self.wi;
            self.lo = self.rows.map(|r| r[wi]);
            self.hi = self.rows.map(|r| shr1(r, wi));
            let [a, b, c, d] = self.lo;
            let [a1, b1, c1, d1] = self.hi;
            let any = a | b | c | d | a1 | b1 | c1 | d1;
            let all = a & b & c & d & a1 & b1 & c1 & d1;
            self.word = any & !all & valid(self.cells, wi);
        }
        let bit = self.word.trailing_zeros();
        self.word &= self.word - 1;
        let mut case = 0u8;
        for c4 in 0..4 {
            let pair = ((self.lo[c4] >> bit) & 1) | ((self.hi[c4] >> bit) & 1) << 1;
            case |= (pair as u8) << (2 * c4);
        }
        Some((self.wi * 64 + bit as usize, case))
    }
}

/// Which row of [`RowRanks`] (x edges: `dj + 2dk`; y: `4 + dk`; z: `6 + dj`) and which bit
/// offset (`di` for y and z edges) each cell edge reads.
const EDGE_RANK: [(u8, u8); 12] = {
    let mut t = [(0u8, 0u8); 12];
    let mut e = 0;
    while e < 12 {
        let (c, axis) = EDGES[e];
        let (di, dj, dk) = (c & 1, c >> 1 & 1, c >> 2 & 1);
        t[e] = match axis {
            0 => (dj + 2 * dk, 0),
            1 => (4 + dk, di),
            _ => (6 + dj, di),
        };
        e += 1;
    }
    t
};

/// Crossing words and running vertex indices of the eight edge rows a row of cells touches,
/// so the vertex on any cell edge is `first + popcount(crossings below the bit)`.
struct RowRanks {
    w: usize,
    words: Vec<u64>,
    pre: Vec<u32>,
}

impl RowRanks {
    fn new(w: usize) -> Self {
        RowRanks {
            w,
            words: vec![0; 8 * w],
            pre: vec![0; 8 * w],
        }
    }

    /// Load the edge rows of the cells `(·, j, k)`.
    #[inline(always)]
    fn load(&mut self, bits: &Bits, k: usize, j: usize) {
        let ny = bits.dims[1];
        // (axis, dj, dk) of each slot, as EDGE_RANK numbers them
        let rows = [
            (0, 0, 0),
            (0, 1, 0),
            (0, 0, 1),
            (0, 1, 1),
            (1, 0, 0),
            (1, 0, 1),
            (2, 0, 0),
            (2, 1, 0),
        ];
        let w = self.w;
        for (slot, &(axis, dj, dk)) in rows.iter().enumerate() {
            let (jj, kk) = (j + dj, k + dk);
            let mut acc = bits.first[3 * (kk * ny + jj) + axis];
            for wi in 0..w {
                let cw = bits.cross(axis, jj, kk, wi);
                self.words[slot * w + wi] = cw;
                self.pre[slot * w + wi] = acc;
                acc += cw.count_ones();
            }
        }
    }

    /// Vertex index on cell edge `e` of cell `i` of the loaded row.
    #[inline(always)]
    fn id(&self, e: u8, i: usize) -> u32 {
        let (slot, di) = EDGE_RANK[e as usize];
        let bit = i + di as usize;
        let at = slot as usize * self.w + bit / 64;
        self.pre[at] + (self.words[at] & ((1u64 << (bit % 64)) - 1)).count_ones()
    }
}

/// Pass 1: inside bits of plane `k` into `out` (`ny` rows of `w` words).
fn inside_plane(g: &Grid, t: f32, k: usize, w: usize, out: &mut [u64]) {
    let [nx, ny, _] = g.dims;
    for j in 0..ny {
        let row = &g.values[(k * ny + j) * nx..(k * ny + j + 1) * nx];
        for (wi, chunk) in row.chunks(64).enumerate() {
            let mut word = 0u64;
            if let Ok(full) = <&[f32; 64]>::try_from(chunk) {
                word = inside_word(full, t);
            } else {
                for (b, &v) in chunk.iter().enumerate() {
                    word |= ((v > t) as u64) << b;
                }
            }
            out[j * w + wi] = word;
        }
    }
}

/// Bit `b` set where `chunk[b] > t` (NaN is outside): four lanes per SSE compare and
/// `movemask` (SSE is part of the x86-64 baseline).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn inside_word(chunk: &[f32; 64], t: f32) -> u64 {
    use std::arch::x86_64::{_mm_cmpgt_ps, _mm_loadu_ps, _mm_movemask_ps, _mm_set1_ps};
    // SAFETY: SSE is part of every x86-64 target (the intrinsics' feature is always enabled);
    // lanes 4q .. 4q + 4 lie inside the 64-lane array and loadu needs no alignment.
    unsafe {
        let tv = _mm_set1_ps(t);
        let mut word = 0u64;
        for q in 0..16 {
            let v = _mm_loadu_ps(chunk.as_ptr().add(4 * q));
            word |= (_mm_movemask_ps(_mm_cmpgt_ps(v, tv)) as u32 as u64) << (4 * q);
        }
        word
    }
}

/// Bit `b` set where `chunk[b] > t` (portable version).
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn inside_word(chunk: &[f32; 64], t: f32) -> u64 {
    let mut word = 0u64;
    for (b, &v) in chunk.iter().enumerate() {
        word |= ((v > t) as u64) << b;
    }
    word
}

/// The corner values minus `level` of cell `(i, j, k)`.
fn cell_values(g: &Grid, level: f64, [i, j, k]: [usize; 3]) -> [f64; 8] {
    let [nx, ny, _] = g.dims;
    let b = (k * ny + j) * nx + i;
    let plane = nx * ny;
    [
        b,
        b + 1,
        b + nx,
        b + nx + 1,
        b + plane,
        b + plane + 1,
        b + plane + nx,
        b + plane + nx + 1,
    ]
    .map(|c| g.values[c] as f64 - level)
}

/// The loops of a cell linked from its values, each with its safe fan start (or `None`:
/// triangulate around a centre vertex).
fn general_loops(
    g: &Grid,
    level: f64,
    ijk: [usize; 3],
    case: u8,
    mut f: impl FnMut(&[u8], Option<usize>),
) {
    let val = cell_values(g, level, ijk);
    let (next, _) = link(case, Some(&val));
    for_each_loop(&next, |lp| {
        f(lp, safe_fan(lp));
        true
    });
}

/// What every plane of passes 2 and 3 reads: the grid, the level and the inside bits.
#[derive(Clone, Copy)]
struct Pass<'a> {
    g: &'a Grid<'a>,
    level: f64,
    bits: &'a Bits,
}

/// Pass 2 for plane `k`: crossings per row and axis into `counts`; triangles and centre
/// vertices of slab `k` (0 for the last plane).
#[inline(always)]
fn count_plane(pass: &Pass, k: usize, counts: &mut [[u32; 3]]) -> (usize, usize) {
    let Pass { g, level, bits } = *pass;
    let [_, ny, nz] = g.dims;
    for (j, c) in counts.iter_mut().enumerate() {
        for axis in 0..3 {
            let mut n = 0;
            for wi in 0..bits.w {
                n += bits.cross(axis, j, k, wi).count_ones();
            }
            c[axis] = n;
        }
    }
    let (mut tris, mut extra) = (0, 0);
    if k + 1 < nz {
        let table = case_table();
        for j in 0..ny - 1 {
            for (i, case) in bits.active_cells(k, j) {
                let e = &table[case as usize];
                if !e.general {
                    tris += e.count as usize;
                } else {
                    general_loops(g, level, [i, j, k], case, |lp, fan| match fan {
                        Some(_) => tris += lp.len() - 2,
                        None => {
                            tris += lp.len();
                            extra += 1;
                        }
                    });
                }
            }
        }
    }
    (tris, extra)
}

/// Output slices of one plane / slab.
struct Out<'a> {
    /// Vertices of plane `k`, then the centre vertices of slab `k`, with normals if asked.
    pos: &'a mut [[f64; 3]],
    nrm: Option<&'a mut [[f64; 3]]>,
    extra_pos: &'a mut [[f64; 3]],
    extra_nrm: Option<&'a mut [[f64; 3]]>,
    /// Index of the first centre vertex of slab `k`.
    extra_first: u32,
    /// Triangle corners of slab `k`.
    tris: &'a mut [u32],
}

/// The centre vertices of one slab, with normals if asked, numbered from `first`.
struct Centres<'a> {
    pos: &'a mut [[f64; 3]],
    nrm: Option<&'a mut [[f64; 3]]>,
    first: u32,
}

/// Pass 3 for plane `k`: its vertices (x, y, z crossings of each row, in index order), then the
/// triangles of slab `k`. Only cells with a sign change are visited; their case selects
/// precomputed triangles, or the general linking with the asymptotic decider.
#[inline(always)]
fn emit_plane(pass: &Pass, k: usize, out: Out<'_>) {
    let Pass { g, level, bits } = *pass;
    let Out {
        pos,
        nrm,
        extra_pos,
        extra_nrm,
        extra_first,
        tris,
    } = out;
    emit_vertices(g, level, bits, k, pos, nrm);
    if k + 1 < g.dims[2] {
        let centres = Centres {
            pos: extra_pos,
            nrm: extra_nrm,
            first: extra_first,
        };
        emit_triangles(g, level, bits, k, centres, tris);
    }
}

/// The vertices of plane `k`: per row, the crossings along x, then y, then z, in index
/// order (with normals when `nrm` is given).
#[inline(always)]
fn emit_vertices(
    g: &Grid,
    level: f64,
    bits: &Bits,
    k: usize,
    pos: &mut [[f64; 3]],
    mut nrm: Option<&mut [[f64; 3]]>,
) {
    let [nx, ny, _] = g.dims;
    let w = bits.w;
    let mut at = 0;
    let strides = [1, nx, nx * ny];
    for j in 0..ny {
        let r = k * ny + j;
        let row = &g.values[r * nx..];
        for axis in 0..3 {
            let stride = strides[axis];
            for wi in 0..w {
                let mut word = bits.cross(axis, j, k, wi);
                while word != 0 {
                    let i = wi * 64 + word.trailing_zeros() as usize;
                    word &= word - 1;
                    if let Some(nrm) = nrm.as_mut() {
                        let (p, n) = edge_vertex(g, level, [i, j, k], axis, true);
                        pos[at] = p;
                        nrm[at] = n;
                    } else {
                        // edge_vertex without normals, with the row's offsets hoisted
                        let (va, vb) = (row[i] as f64, row[i + stride] as f64);
                        let t = (level - va) / (vb - va);
                        let mut idx = [i as f64, j as f64, k as f64];
                        idx[axis] += t;
                        pos[at] = [0, 1, 2].map(|a| g.origin[a] + g.spacing[a] * idx[a]);
                    }
                    at += 1;
                }
            }
        }
    }
}

/// The triangles of slab `k` (between planes `k` and `k + 1`), cell by cell in index order:
/// a case's precomputed triangles, or the general loops fanned from a vertex or from a
/// centre vertex of their own (`extra_pos`, numbered from `extra_first`).
#[inline(always)]
fn emit_triangles(
    g: &Grid,
    level: f64,
    bits: &Bits,
    k: usize,
    centres: Centres<'_>,
    tris: &mut [u32],
) {
    let Centres {
        pos: extra_pos,
        nrm: mut extra_nrm,
        first: extra_first,
    } = centres;
    let ny = g.dims[1];
    let table = case_table();
    let mut ranks = RowRanks::new(bits.w);
    let mut t = 0;
    let mut nx_extra = 0;
    for j in 0..ny - 1 {
        let mut loaded = false;
        for (i, case) in bits.active_cells(k, j) {
            if !loaded {
                ranks.load(bits, k, j);
                loaded = true;
            }
            let entry = &table[case as usize];
            if !entry.general {
                for tri in &entry.tris[..entry.count as usize] {
                    tris[t] = ranks.id(tri[0], i);
                    tris[t + 1] = ranks.id(tri[1], i);
                    tris[t + 2] = ranks.id(tri[2], i);
                    t += 3;
                }
                continue;
            }
            general_loops(g, level, [i, j, k], case, |lp, fan| {
                let n = lp.len();
                match fan {
                    Some(s) => {
                        let v0 = ranks.id(lp[s], i);
                        for o in 1..n - 1 {
                            tris[t] = v0;
                            tris[t + 1] = ranks.id(lp[(s + o) % n], i);
                            tris[t + 2] = ranks.id(lp[(s + o + 1) % n], i);
                            t += 3;
                        }
                    }
                    None => {
                        // centre vertex: every new edge is private to this cell
                        let (c, cn) = centre_vertex(g, level, [i, j, k], lp, extra_nrm.is_some());
                        extra_pos[nx_extra] = c;
                        if let Some(en) = extra_nrm.as_mut() {
                            en[nx_extra] = cn;
                        }
                        let vc = extra_first + nx_extra as u32;
                        nx_extra += 1;
                        for o in 0..n {
                            tris[t] = vc;
                            tris[t + 1] = ranks.id(lp[o], i);
                            tris[t + 2] = ranks.id(lp[(o + 1) % n], i);
                            t += 3;
                        }
                    }
                }
            });
        }
    }
    debug_assert_eq!(t, tris.len());
    debug_assert_eq!(nx_extra, extra_pos.len());
}

/// The centre vertex of a loop `lp` of cell `[i, j, k]`'s edges: the mean of its edge
/// vertices, and (when `normals`) the normalized sum of their normals.
#[inline(always)]
fn centre_vertex(
    g: &Grid,
    level: f64,
    [i, j, k]: [usize; 3],
    lp: &[u8],
    normals: bool,
) -> ([f64; 3], [f64; 3]) {
    let n = lp.len();
    let mut c = [0.0; 3];
    let mut cn = [0.0; 3];
    for &e in lp {
        let (cc, axis) = EDGES[e as usize];
        let p = [
            i + (cc & 1) as usize,
            j + (cc >> 1 & 1) as usize,
            k + (cc >> 2 & 1) as usize,
        ];
        let (q, nn) = edge_vertex(g, level, p, axis as usize, normals);
        for a in 0..3 {
            c[a] += q[a] / n as f64;
            cn[a] += nn[a];
        }
    }
    let l = (cn[0] * cn[0] + cn[1] * cn[1] + cn[2] * cn[2]).sqrt();
    let cn = if l > 0.0 {
        [cn[0] / l, cn[1] / l, cn[2] / l]
    } else {
        cn
    };
    (c, cn)
}

/// [`count_plane`] and [`emit_plane`] compiled for the CPU's `popcnt` instruction when it has
/// one: rank queries and crossing counts are popcounts, which the x86-64 baseline computes with
/// a dozen shifts and masks. Both bodies (and the helpers of their hot loops) are
/// `#[inline(always)]`, so they are compiled inside the feature-enabled function.
#[cfg(target_arch = "x86_64")]
mod popcnt {
    use super::*;

    /// # Safety
    /// The CPU must support popcnt.
    #[target_feature(enable = "popcnt")]
    unsafe fn count(pass: &Pass, k: usize, c: &mut [[u32; 3]]) -> (usize, usize) {
        count_plane(pass, k, c)
    }

    /// # Safety
    /// The CPU must support popcnt.
    #[target_feature(enable = "popcnt")]
    unsafe fn emit(pass: &Pass, k: usize, out: Out<'_>) {
        emit_plane(pass, k, out)
    }

    pub(super) fn count_fast(pass: &Pass, k: usize, c: &mut [[u32; 3]]) -> (usize, usize) {
        if std::is_x86_feature_detected!("popcnt") {
            // SAFETY: the CPU supports popcnt (checked just above).
            return unsafe { count(pass, k, c) };
        }
        count_plane(pass, k, c)
    }

    pub(super) fn emit_fast(pass: &Pass, k: usize, out: Out<'_>) {
        if std::is_x86_feature_detected!("popcnt") {
            // SAFETY: the CPU supports popcnt (checked just above).
            return unsafe { emit(pass, k, out) };
        }
        emit_plane(pass, k, out)
    }
}
#[cfg(target_arch = "x86_64")]
use popcnt::{count_fast, emit_fast};
#[cfg(not(target_arch = "x86_64"))]
use {count_plane as count_fast, emit_plane as emit_fast};

/// Split `v` into consecutive mutable pieces of the given lengths.
fn split_lengths<T>(mut v: &mut [T], lens: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut out = Vec::new();
    for n in lens {
        let (head, tail) = std::mem::take(&mut v).split_at_mut(n);
        out.push(head);
        v = tail;
    }
    out
}

/// Polygonise the isosurface `value = level` of `grid` (inside where `value > level`).
pub fn polygonize(grid: &Grid, level: f64, normals: bool) -> Result<Isosurface> {
    grid.check()?;
    if !level.is_finite() {
        return Err(Error::parameter("level", level, "a finite number"));
    }
    let [_, ny, nz] = grid.dims;

    // pass 1: inside bits
    let mut bits = inside_bits(grid, f32_threshold(level));

    // pass 2: vertices per row and axis, triangles and centre vertices per slab
    let mut counts = vec![[0u32; 3]; nz * ny];
    let per_slab: Vec<(usize, usize)> = {
        let pass = Pass {
            g: grid,
            level,
            bits: &bits,
        };
        counts
            .par_chunks_mut(ny)
            .enumerate()
            .map(|(k, c)| count_fast(&pass, k, c))
            .collect()
    };
    let (first, plane_len, nv) = number_rows(&counts, ny, nz);
    bits.first = first;
    let n_extra: usize = per_slab.iter().map(|p| p.1).sum();
    let n_tris: usize = per_slab.iter().map(|p| p.0).sum();
    if nv + n_extra > u32::MAX as usize || 3 * n_tris > u32::MAX as usize {
        return Err(Error::LimitsExceeded {
            what: "isosurface vertices or triangle corners",
            requested: (nv + n_extra).max(3 * n_tris) as u64,
            limit: u32::MAX as u64,
        });
    }

    // pass 3: vertices and triangles, written in place
    // the output arrays on huge pages where the kernel allows (tensor::pages): a large
    // surface's arrays are tens of MB, a page fault per 4 KB otherwise
    let mut positions: Vec<[f64; 3]> = zeroed_vec(nv + n_extra);
    let mut nrm_all: Vec<[f64; 3]> = if normals {
        zeroed_vec(nv + n_extra)
    } else {
        Vec::new()
    };
    let mut indices: Vec<u32> = zeroed_vec(3 * n_tris);
    let sizes = SlabSizes {
        nv,
        plane_len: &plane_len,
        per_slab: &per_slab,
    };
    let nrm = normals.then_some(&mut nrm_all[..]);
    let pass = Pass {
        g: grid,
        level,
        bits: &bits,
    };
    slab_outputs(&sizes, &mut positions, nrm, &mut indices)
        .into_par_iter()
        .enumerate()
        .for_each(|(k, out)| emit_fast(&pass, k, out));
    let mesh = Mesh {
        positions,
        offsets: triangle_offsets(n_tris),
        indices,
        attributes: Default::default(),
    };
    Ok(Isosurface {
        mesh,
        normals: normals.then_some(nrm_all),
    })
}

/// Pass 1: one bit per sample, `value > t`, packed in 64-bit words per row.
fn inside_bits(grid: &Grid, t: f32) -> Bits {
    let [nx, ny, nz] = grid.dims;
    let w = nx.div_ceil(64);
    let mut inside = vec![0u64; nz * ny * w];
    inside
        .par_chunks_mut(ny * w)
        .enumerate()
        .for_each(|(k, out)| inside_plane(grid, t, k, w, out));
    Bits {
        dims: grid.dims,
        w,
        inside,
        first: Vec::new(),
    }
}

/// Vertex numbering: rows in order, x then y then z crossings, increasing i (centre vertices
/// follow slab by slab). Returns the first index per row and axis, the vertex count per plane
/// and the number of grid-edge vertices.
fn number_rows(counts: &[[u32; 3]], ny: usize, nz: usize) -> (Vec<u32>, Vec<usize>, usize) {
    let mut first = vec![0u32; 3 * nz * ny];
    let mut plane_len = vec![0usize; nz];
    let mut next = 0u32;
    for (r, c) in counts.iter().enumerate() {
        for axis in 0..3 {
            first[3 * r + axis] = next;
            next += c[axis];
        }
        plane_len[r / ny] += (c[0] + c[1] + c[2]) as usize;
    }
    (first, plane_len, next as usize)
}

/// How the output arrays divide between planes and slabs.
struct SlabSizes<'a> {
    /// Grid-edge vertices (centre vertices follow them).
    nv: usize,
    /// Grid-edge vertices per plane.
    plane_len: &'a [usize],
    /// (triangles, centre vertices) per slab.
    per_slab: &'a [(usize, usize)],
}

/// Split the output arrays into one disjoint [`Out`] per slab.
fn slab_outputs<'a>(
    sizes: &SlabSizes,
    positions: &'a mut [[f64; 3]],
    normals: Option<&'a mut [[f64; 3]]>,
    indices: &'a mut [u32],
) -> Vec<Out<'a>> {
    let nz = sizes.plane_len.len();
    let per_slab = sizes.per_slab;
    let split = |v: &'a mut [[f64; 3]]| {
        let (a, b) = v.split_at_mut(sizes.nv);
        (
            split_lengths(a, sizes.plane_len.iter().copied()),
            split_lengths(b, per_slab.iter().map(|p| p.1)),
        )
    };
    let (pos_parts, extra_parts) = split(positions);
    let (mut nrm_parts, mut extra_nrm_parts): (Vec<_>, Vec<_>) = match normals {
        Some(n) => {
            let (a, b) = split(n);
            (
                a.into_iter().map(Some).collect(),
                b.into_iter().map(Some).collect(),
            )
        }
        None => (
            (0..nz).map(|_| None).collect(),
            (0..nz).map(|_| None).collect(),
        ),
    };
    let tri_parts = split_lengths(indices, per_slab.iter().map(|p| 3 * p.0));
    let mut extra_first = sizes.nv as u32;
    let mut outs = Vec::with_capacity(nz);
    for (k, ((pos, extra_pos), tris)) in pos_parts
        .into_iter()
        .zip(extra_parts)
        .zip(tri_parts)
        .enumerate()
    {
        outs.push(Out {
            pos,
            nrm: nrm_parts[k].take(),
            extra_pos,
            extra_nrm: extra_nrm_parts[k].take(),
            extra_first,
            tris,
        });
        extra_first += per_slab[k].1 as u32;
    }
    outs
}

/// Face offsets of an all-triangle mesh: `offsets[f] = 3·f`.
fn triangle_offsets(n_tris: usize) -> Vec<u32> {
    let mut offsets: Vec<u32> = zeroed_vec(n_tris + 1);
    offsets
        .par_chunks_mut(1 << 16)
        .enumerate()
        .for_each(|(c, o)| {
            for (n, x) in o.iter_mut().enumerate() {
                *x = 3 * ((c << 16) + n) as u32;
            }
        });
    offsets
}

/// Area and enclosed (signed) volume of a triangle mesh (divergence theorem; positive when
/// the triangles face outwards).
pub fn area_volume(mesh: &Mesh) -> (f64, f64) {
    // fixed chunks summed in order: the same result on any number of threads
    const CHUNK: usize = 1 << 15;
    let nf = mesh.face_count();
    let parts: Vec<(f64, f64)> = (0..nf.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut area = 0.0;
            let mut vol = 0.0;
            for fi in c * CHUNK..(c * CHUNK + CHUNK).min(nf) {
                let f = mesh.face(fi);
                let p0 = mesh.positions[f[0] as usize];
                for w in 1..f.len() - 1 {
                    let p1 = mesh.positions[f[w] as usize];
                    let p2 = mesh.positions[f[w + 1] as usize];
                    let u = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
                    let v = [p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]];
                    let c = [
                        u[1] * v[2] - u[2] * v[1],
                        u[2] * v[0] - u[0] * v[2],
                        u[0] * v[1] - u[1] * v[0],
                    ];
                    area += 0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                    vol += (p0[0] * (p1[1] * p2[2] - p1[2] * p2[1])
                        + p0[1] * (p1[2] * p2[0] - p1[0] * p2[2])
                        + p0[2] * (p1[0] * p2[1] - p1[1] * p2[0]))
                        / 6.0;
                }
            }
            (area, vol)
        })
        .collect();
    parts
        .iter()
        .fold((0.0, 0.0), |(a, v), &(pa, pv)| (a + pa, v + pv))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table holds exactly what the general linking draws for every case without an
    /// ambiguous face, whatever the magnitudes of the corner values.
    #[test]
    fn case_table_matches_the_general_linking() {
        let mut seed = 0x2545f4914f6cdd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut tabled = 0;
        for case in 1..255u8 {
            let entry = &case_table()[case as usize];
            for _ in 0..20 {
                let val: [f64; 8] = std::array::from_fn(|c| {
                    let m = 0.01 + rnd();
                    if case >> c & 1 == 1 {
                        m
                    } else {
                        -m
                    }
                });
                let (next, ambiguous) = link(case, Some(&val));
                assert_eq!(ambiguous, entry.general && link(case, None).1);
                if entry.general {
                    continue;
                }
                let mut tris = Vec::new();
                for_each_loop(&next, |lp| {
                    let s = safe_fan(lp).expect("tabled cases have safe fans");
                    let n = lp.len();
                    for o in 1..n - 1 {
                        tris.push([lp[s], lp[(s + o) % n], lp[(s + o + 1) % n]]);
                    }
                    true
                });
                assert_eq!(
                    tris,
                    entry.tris[..entry.count as usize].to_vec(),
                    "case {case}"
                );
            }
            tabled += !entry.general as usize;
        }
        // every case without an ambiguous face is tabled unless it needs a centre vertex
        assert!(tabled > 100, "{tabled}");
    }

    #[test]
    fn f32_threshold_agrees_with_the_f64_test() {
        for level in [
            0.0,
            0.1,
            -0.1,
            1e-30,
            300.0,
            1.0 / 3.0,
            -7.123456789,
            1e39,
            -1e39,
        ] {
            let t = f32_threshold(level);
            for v in [
                t,
                -next_below(-t),
                if t == f32::NEG_INFINITY {
                    t
                } else {
                    next_below(t)
                },
                level as f32,
                0.0,
                f32::MAX,
                f32::MIN,
            ] {
                assert_eq!(v > t, (v as f64) > level, "level {level} v {v}");
            }
        }
    }
}
