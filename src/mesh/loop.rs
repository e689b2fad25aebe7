//! Loop subdivision (§8.2): every triangle splits into four (face split, §8.2.1) and points are
//! placed by masks (§8.2.2):
//!
//! ```text
//!   vertex point (even), valence n:  (1 − nβ) v + β Σ v_j
//!       Loop:    β = (1/n) (5/8 − (3/8 + ¼ cos 2π/n)²)      (β = 1/16 at n = 6)
//!       Warren:  β = 3/16 at n = 3, 3/(8n) otherwise        (libigl's igl::loop)
//!   edge point (odd):                3/8 (a + b) + 1/8 (c + d),  c, d opposite the edge
//!   boundary / sharp edge point:     ½ (a + b)                          (§8.2.3)
//!   boundary / crease vertex point:  ¾ v + ⅛ (a + b)   (cubic B-spline curve mask)
//!   corner:                          v
//! ```
//!
//! Numbering of the result: old vertices keep their index, the point of edge `e` is `V + e`;
//! triangle `(a, b, c)` with edge points `ab, bc, ca` becomes
//! `(a, ab, ca) (b, bc, ab) (c, ca, bc) (ab, bc, ca)`, so face `f`'s children are `4f .. 4f+4`.

use super::catmull_clark::{child_tags, edge_points, vertex_points};
use super::features::{sharp_edge_point, Features, Tags};
use super::halfedge::HalfEdgeMesh;
use super::Mesh;
use crate::Result;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Vertex weights for Loop subdivision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LoopWeights {
    /// Loop's original β(n) (OpenSubdiv, trimesh).
    #[default]
    Loop,
    /// Warren's simplified β (libigl).
    Warren,
}

/// β(n) for the given weights.
#[inline]
pub fn beta(n: usize, w: LoopWeights) -> f64 {
    let nf = n as f64;
    match w {
        LoopWeights::Loop => {
            let t = 3.0 / 8.0 + 0.25 * (2.0 * PI / nf).cos();
            (5.0 / 8.0 - t * t) / nf
        }
        LoopWeights::Warren => {
            if n == 3 {
                3.0 / 16.0
            } else {
                3.0 / (8.0 * nf)
            }
        }
    }
}

/// Minimum number of elements per rayon task (amortises scheduling).
pub(crate) const GRAIN: usize = 4096;

/// One step of Loop subdivision of a triangle mesh. Returns the refined mesh and the tags of
/// its sharp child edges and corners.
pub fn step(
    mesh: &Mesh,
    he: &HalfEdgeMesh,
    tags: &Tags,
    weights: LoopWeights,
) -> Result<(Mesh, Features)> {
    let (nv, ne) = super::catmull_clark::triangle_counts(
        mesh,
        he,
        "Loop subdivision of faces that are not triangles",
    )?;
    let p = &mesh.positions;
    let beta_table: Vec<f64> = (0..64)
        .map(|n| if n == 0 { 0.0 } else { beta(n, weights) })
        .collect();
    let mut out = vec![[0.0f64; 3]; nv + ne];
    let (vpart, epart) = out.split_at_mut(nv);
    let ring = |h: usize| p[he.from[he.twin[h] as usize] as usize];
    vertex_points(vpart, p, he, tags, ring, |pv, s, n| {
        let b = if n < 64 {
            beta_table[n]
        } else {
            beta(n, weights)
        };
        let w = 1.0 - n as f64 * b;
        std::array::from_fn(|k| w * pv[k] + b * s[k])
    });
    edge_points(epart, p, he, |e, [c0, c1], pa, pb| {
        if tags.sharp[e] {
            sharp_edge_point(pa, pb)
        } else {
            // the vertex opposite corner c's edge is the tail of prev(c)
            let pc = p[he.from[he.prev[c0 as usize] as usize] as usize];
            let pd = p[he.from[he.prev[c1 as usize] as usize] as usize];
            std::array::from_fn(|k| 0.375 * (pa[k] + pb[k]) + 0.125 * (pc[k] + pd[k]))
        }
    });
    quadrisect(mesh, he, tags, out)
}

/// The 1-to-4 split of every triangle shared by Loop and Butterfly: vertex `i` keeps index
/// `i`, the new point of edge `e` is `nv + e`, and each triangle `(a, b, c)` becomes
/// `(a, ab, ca) (b, bc, ab) (c, ca, bc) (ab, bc, ca)`. `out` holds the refined positions;
/// the sharp tags are inherited by the child edges.
pub(crate) fn quadrisect(
    mesh: &Mesh,
    he: &HalfEdgeMesh,
    tags: &Tags,
    out: Vec<[f64; 3]>,
) -> Result<(Mesh, Features)> {
    let nv = mesh.vertex_count();
    let nf = mesh.face_count();
    let mut indices = vec![0u32; 12 * nf];
    let ce = &he.edges.corner_edge;

    indices
        .par_chunks_mut(12)
        .with_min_len(GRAIN)
        .enumerate()
        .for_each(|(f, t)| {
            let c = 3 * f;
            let (a, b, cc) = (mesh.indices[c], mesh.indices[c + 1], mesh.indices[c + 2]);
            let base = nv as u32;
            let (ab, bc, ca) = (base + ce[c], base + ce[c + 1], base + ce[c + 2]);
            t.copy_from_slice(&[a, ab, ca, b, bc, ab, cc, ca, bc, ab, bc, ca]);
        });
    Ok((Mesh::of_degree(out, indices, 3), child_tags(tags, he, nv)))
}
