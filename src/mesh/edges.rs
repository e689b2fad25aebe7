//! The undirected edge table of a face-vertex list, built in O(n): one pass over the corners
//! with a hash map keyed by the vertex pair (min, max). Corner `c` of face `f` (vertex `v_i`)
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

impl Edges {
    /// Build the table of `mesh` in one pass.
    pub fn build(mesh: &Mesh) -> Edges {
        let nc = mesh.indices.len();
        let mut map: PairMap<u32> =
            PairMap::with_capacity_and_hasher(nc / 2 + 16, Default::default());
        let mut verts = Vec::with_capacity(nc / 2 + 16);
        let mut corners = Vec::with_capacity(nc / 2 + 16);
        let mut uses = Vec::with_capacity(nc / 2 + 16);
        let mut corner_edge = vec![0u32; nc];
        let mut corner_face = vec![0u32; nc];
        for f in 0..mesh.face_count() {
            let (s, e) = (mesh.offsets[f] as usize, mesh.offsets[f + 1] as usize);
            for c in s..e {
                let a = mesh.indices[c];
                let b = mesh.indices[if c + 1 == e { s } else { c + 1 }];
                corner_face[c] = f as u32;
                let next = verts.len() as u32;
                let id = *map.entry(pair_key(a, b)).or_insert(next);
                if id == next {
                    verts.push([a, b]);
                    corners.push([c as u32, NONE]);
                    uses.push(1);
                } else {
                    let u = &mut uses[id as usize];
                    if *u == 1 {
                        corners[id as usize][1] = c as u32;
                    }
                    *u += 1;
                }
                corner_edge[c] = id;
            }
        }
        Edges {
            verts,
            corners,
            uses,
            corner_edge,
            corner_face,
        }
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
