//! The undirected edge table of a face-vertex list, built in O(n) by bucketing the corners by
//! their smaller vertex (see [`Edges::build`]); `PairMap` (a hash map keyed by the vertex
//! pair) serves lookups elsewhere. Corner `c` of face `f` (vertex `v_i`)
//! owns the edge `v_i → v_{i+1}`. An edge is used by one corner (boundary), two (interior) or
//! more (non-manifold). This table works for any input, including non-orientable and
//! non-manifold meshes, so topology queries run on it; the half-edge structure
//! ([`super::HalfEdgeMesh`]) is built on top of it for oriented manifolds.

use super::{Mesh, NONE};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A multiplicative hasher for `u64` keys (the vertex pair packed as `min << 32 | max`).
/// The std SipHash is ~3× slower here and the keys are not attacker-chosen in a way that
/// matters: worst case is a slow build, never a wrong one.
#[derive(Default, Clone, Copy)]
pub struct PairHasher(u64);

impl Hasher for PairHasher {
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x100000001b3);
        }
    }
    #[inline]
    fn write_u64(&mut self, k: u64) {
        // splitmix64 finaliser
        let mut z = k.wrapping_add(0x9e3779b97f4a7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        self.0 = z ^ (z >> 31);
    }
}

pub type PairMap<V> = HashMap<u64, V, BuildHasherDefault<PairHasher>>;

/// Pack an unordered vertex pair into a hash key.
#[inline]
pub fn pair_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    ((lo as u64) << 32) | hi as u64
}

/// Edge table: `verts[e]` as first met (direction of its first corner), the corner of each
/// face-side (up to two; `NONE` when absent), the number of corners using the edge, and for
/// each corner its edge.
#[derive(Clone, Debug)]
pub struct Edges {
    pub verts: Vec<[u32; 2]>,
    /// The first two corners using the edge; `corners[e][1] == NONE` on a boundary edge.
    pub corners: Vec<[u32; 2]>,
    /// How many corners use the edge (1 boundary, 2 interior, more: non-manifold).
    pub uses: Vec<u32>,
    /// For each corner (half-edge `v_i → v_{i+1}` of its face), its edge.
    pub corner_edge: Vec<u32>,
    /// For each corner, its face.
    pub corner_face: Vec<u32>,
}

/// Vertices per parallel block of the bucket passes of [`Edges::build`].
const BUCKET_CHUNK: usize = 2048;

/// Cut two arrays into matching pieces, one per block of `block` items out of `n`: items
/// `f..g` own `len.0(f, g)` entries of the first array and `len.1(f, g)` of the second.
/// Returns `(f, piece of the first, piece of the second)` per block, for parallel work.
#[allow(clippy::type_complexity)]
fn split_blocks<'a>(
    n: usize,
    block: usize,
    (mut rest_a, mut rest_b): (&'a mut [u32], &'a mut [u32]),
    len: (
        impl Fn(usize, usize) -> usize,
        impl Fn(usize, usize) -> usize,
    ),
) -> Vec<(usize, &'a mut [u32], &'a mut [u32])> {
    let mut out = Vec::new();
    let mut f = 0;
    while f < n {
        let g = (f + block).min(n);
        let (a, b) = std::mem::take(&mut rest_a).split_at_mut(len.0(f, g));
        let (c, d) = std::mem::take(&mut rest_b).split_at_mut(len.1(f, g));
        out.push((f, a, c));
        rest_a = b;
        rest_b = d;
        f = g;
    }
    out
}

/// The corners bucketed by their smaller vertex: vertex `v`'s corners are
/// `bucket[start[v]..start[v + 1]]`, each bucket sorted by (larger vertex, corner);
/// `first_edge[v]` is the id of the first edge at `v`.
#[derive(Clone, Copy)]
struct Buckets<'a> {
    start: &'a [u32],
    bucket: &'a [u32],
    first_edge: &'a [u32],
}

/// Each corner's face and the head vertex of its edge (the next corner's vertex), in
/// parallel over blocks of faces.
#[allow(clippy::type_complexity)]
fn corner_faces_and_heads(mesh: &Mesh) -> (Vec<u32>, Vec<u32>) {
    use rayon::prelude::*;
    let nc = mesh.indices.len();
    let mut corner_face = vec![0u32; nc];
    let mut head_of = vec![0u32; nc];
    let fo = &mesh.offsets;
    let idx = &mesh.indices;
    let nf = mesh.face_count();
    let block = 4096;
    let corners = |f: usize, g: usize| (fo[g] - fo[f]) as usize;
    let cf = split_blocks(
        nf,
        block,
        (&mut corner_face, &mut head_of),
        (corners, corners),
    );
    cf.into_par_iter().for_each(|(f0, cfs, heads)| {
        let base = fo[f0] as usize;
        let mut f = f0;
        let mut c = base;
        while c - base < cfs.len() {
            let (s, e) = (fo[f] as usize, fo[f + 1] as usize);
            for k in s..e {
                cfs[k - base] = f as u32;
                heads[k - base] = idx[if k + 1 == e { s } else { k + 1 }];
            }
            c = e;
            f += 1;
        }
    });
    (corner_face, head_of)
}

/// The corners bucketed by their smaller vertex (a counting sort): `(start, bucket)`.
#[allow(clippy::needless_range_loop)]
fn buckets(mesh: &Mesh, head_of: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let nc = mesh.indices.len();
    let nv = mesh.positions.len();
    let mut start = vec![0u32; nv + 1];
    for c in 0..nc {
        let lo = mesh.indices[c].min(head_of[c]);
        start[lo as usize + 1] += 1;
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut bucket = vec![0u32; nc];
    for c in 0..nc {
        let lo = mesh.indices[c].min(head_of[c]) as usize;
        bucket[fill[lo] as usize] = c as u32;
        fill[lo] += 1;
    }
    (start, bucket)
}

/// Each bucket sorted by (larger vertex `hi_of(c)`, corner), and the count of its
/// distinct pairs (the edges at its vertex), per block of vertices in parallel.
#[allow(clippy::needless_range_loop, clippy::type_complexity)]
fn sort_buckets(start: &[u32], bucket: &mut [u32], hi_of: impl Fn(u32) -> u32 + Sync) -> Vec<u32> {
    use rayon::prelude::*;
    let nv = start.len() - 1;
    let chunk = BUCKET_CHUNK;
    let mut counts = vec![0u32; nv];
    // split `bucket` at vertex boundaries into blocks of `chunk` vertices
    let in_bucket = |v: usize, w: usize| (start[w] - start[v]) as usize;
    let parts = split_blocks(nv, chunk, (bucket, &mut counts), (in_bucket, |v, w| w - v));
    parts.into_par_iter().for_each(|(v0, b, cnt)| {
        let base = start[v0] as usize;
        for (i, n) in cnt.iter_mut().enumerate() {
            let v = v0 + i;
            let s = &mut b[start[v] as usize - base..start[v + 1] as usize - base];
            s.sort_unstable_by_key(|&c| ((hi_of(c) as u64) << 32) | c as u64);
            let mut k = 0;
            for j in 0..s.len() {
                if j == 0 || hi_of(s[j]) != hi_of(s[j - 1]) {
                    k += 1;
                }
            }
            *n = k;
        }
    });
    counts
}

impl Edges {
    /// Build the table of `mesh` in O(n) (O(n log n) if one vertex has a huge valence):
    /// corners are bucketed by their smaller vertex
    /// (counting sort), then each bucket, a handful of corners, is sorted by the larger vertex
    /// so equal pairs become neighbours. Buckets are independent and run in parallel. (A hash
    /// map keyed by the pair does the same job but its random accesses into a table of
    /// millions of entries made it ~5× slower on 10⁶-face meshes.) Edge ids are ordered by
    /// (smaller vertex, larger vertex).
    pub fn build(mesh: &Mesh) -> Edges {
        let nc = mesh.indices.len();
        let nv = mesh.positions.len();
        let (corner_face, head_of) = corner_faces_and_heads(mesh);
        let (start, mut bucket) = buckets(mesh, &head_of);
        let hi_of = |c: u32| mesh.indices[c as usize].max(head_of[c as usize]);
        let counts = sort_buckets(&start, &mut bucket, hi_of);
        let mut first_edge = vec![0u32; nv + 1];
        for v in 0..nv {
            first_edge[v + 1] = first_edge[v] + counts[v];
        }
        drop(counts);
        let ne = first_edge[nv] as usize;
        let mut edges = Edges {
            verts: vec![[0u32; 2]; ne],
            corners: vec![[NONE; 2]; ne],
            uses: vec![0u32; ne],
            corner_edge: vec![0u32; nc],
            corner_face,
        };
        let table = Buckets {
            start: &start,
            bucket: &bucket,
            first_edge: &first_edge,
        };
        edges.fill(mesh, &head_of, &table);
        edges
    }

    /// The edges, their corners and uses, and each corner's edge from the sorted
    /// buckets, per block of [`BUCKET_CHUNK`] vertices in parallel.
    #[allow(clippy::needless_range_loop, clippy::type_complexity)]
    fn fill(&mut self, mesh: &Mesh, head_of: &[u32], table: &Buckets) {
        use rayon::prelude::*;
        let Buckets {
            start,
            bucket,
            first_edge,
        } = *table;
        let chunk = BUCKET_CHUNK;
        let nv = start.len() - 1;
        let hi_of = |c: u32| mesh.indices[c as usize].max(head_of[c as usize]);
        // fill edges per block of vertices; corner_edge is written through the shared
        // pointer of `tensor::par` since each corner belongs to exactly one bucket
        // (disjoint writes)
        let ce = crate::tensor::par::SharedMut(self.corner_edge.as_mut_ptr());
        let ce = &ce;
        let mut parts: Vec<(usize, &mut [[u32; 2]], &mut [[u32; 2]], &mut [u32])> = Vec::new();
        let (mut rv, mut rc, mut ru): (&mut [[u32; 2]], &mut [[u32; 2]], &mut [u32]) =
            (&mut self.verts, &mut self.corners, &mut self.uses);
        let mut v = 0;
        while v < nv {
            let w = (v + chunk).min(nv);
            let len = (first_edge[w] - first_edge[v]) as usize;
            let (a, b) = std::mem::take(&mut rv).split_at_mut(len);
            let (c, d) = std::mem::take(&mut rc).split_at_mut(len);
            let (e, g) = std::mem::take(&mut ru).split_at_mut(len);
            parts.push((v, a, c, e));
            rv = b;
            rc = d;
            ru = g;
            v = w;
        }
        parts.into_par_iter().for_each(|(v0, pv, pc, pu)| {
            let ebase = first_edge[v0] as usize;
            let w = (v0 + chunk).min(nv);
            let mut e = ebase;
            for v in v0..w {
                let s = &bucket[start[v] as usize..start[v + 1] as usize];
                for j in 0..s.len() {
                    let c = s[j];
                    if j > 0 && hi_of(c) == hi_of(s[j - 1]) {
                        let k = e - 1 - ebase;
                        if pu[k] == 1 {
                            pc[k][1] = c;
                        }
                        pu[k] += 1;
                    } else {
                        let k = e - ebase;
                        pv[k] = [mesh.indices[c as usize], head_of[c as usize]];
                        pc[k] = [c, NONE];
                        pu[k] = 1;
                        e += 1;
                    }
                    // SAFETY: every corner appears in exactly one bucket, so each index
                    // of corner_edge is written by exactly one task.
                    unsafe { ce.write(c as usize, (e - 1) as u32) };
                }
            }
        });
    }

    pub fn len(&self) -> usize {
        self.verts.len()
    }

    pub fn is_empty(&self) -> bool {
        self.verts.is_empty()
    }

    /// True when the edge has exactly one face.
    #[inline]
    pub fn is_boundary(&self, e: usize) -> bool {
        self.uses[e] == 1
    }

    /// The other corner on edge `e` seen from corner `c` (`NONE` on a boundary).
    #[inline]
    pub fn opposite(&self, e: usize, c: u32) -> u32 {
        let [a, b] = self.corners[e];
        if a == c {
            b
        } else {
            a
        }
    }
}
