//! Butterfly subdivision (§8.4), with the modified rules of Zorin, Schröder and Sweldens
//! (SIGGRAPH '96). Interpolating: old vertices keep their positions; each edge gets a new point;
//! triangles split into four as in Loop (same numbering: edge `e` ↦ vertex `V + e`).
//!
//! ```text
//!   both ends of valence 6 (8-point butterfly, w = 0):
//!       ½ (a + b) + ⅛ (c + d) − 1/16 (e₁ + e₂ + e₃ + e₄)     c, d opposite; e_i the wings
//!   one end v of valence K ≠ 6 (the other regular):  ¾ v + Σ_j s_j v_j,  v_0 = other end,
//!       K ≥ 5: s_j = (¼ + cos(2πj/K) + ½ cos(4πj/K)) / K
//!       K = 4: s = (3/8, 0, −1/8, 0)       K = 3: s = (5/12, −1/12, −1/12)
//!   both ends irregular: the average of the two stencils
//!   boundary / sharp edge: 4-point curve rule  −1/16 a' + 9/16 a + 9/16 b − 1/16 b'
//!       (a', b' the next points along the boundary or crease; ½ (a + b) at a corner end)
//!   interior edge with one boundary end: the stencil of the interior end (any valence)
//!   interior edge with both ends on a boundary: 3/8 (a + b) + 1/8 (c + d)
//! ```
//!
//! The valence-6 test and the stencils match VTK's `vtkButterflySubdivisionFilter` on closed
//! meshes (where valence = number of faces at the vertex).

use super::catmull_clark::edge_points;
use super::features::{Features, Tags, VertexRule};
use super::halfedge::{HalfEdgeMesh, VertexId};
use super::loop_subdivision::{quadrisect, GRAIN};
use super::Mesh;
use crate::Result;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Accumulate ¾ v + Σ s_j v_j around `v`, starting from the neighbour at the head of `h0`.
fn stencil(mesh: &Mesh, he: &HalfEdgeMesh, h0: u32, k: usize, acc: &mut [f64; 3], scale: f64) {
    let p = &mesh.positions;
    let v = p[he.from[h0 as usize] as usize];
    for d in 0..3 {
        acc[d] += scale * 0.75 * v[d];
    }
    let mut h = h0;
    for j in 0..k {
        let s = match k {
            3 => {
                if j == 0 {
                    5.0 / 12.0
                } else {
                    -1.0 / 12.0
                }
            }
            4 => [3.0 / 8.0, 0.0, -1.0 / 8.0, 0.0][j],
            _ => {
                let t = 2.0 * PI * j as f64 / k as f64;
                (0.25 + t.cos() + 0.5 * (2.0 * t).cos()) / k as f64
            }
        };
        let q = p[he.from[he.twin[h as usize] as usize] as usize];
        for d in 0..3 {
            acc[d] += scale * s * q[d];
        }
        h = he.next[he.twin[h as usize] as usize];
    }
}

/// The vertex across the edge of interior half-edge `h`'s twin face: tail of prev(twin(h)).
#[inline]
fn wing(he: &HalfEdgeMesh, h: u32) -> Option<u32> {
    let t = he.twin[h as usize] as usize;
    if t >= he.corners {
        None
    } else {
        Some(he.from[he.prev[t] as usize])
    }
}

/// One step of modified Butterfly subdivision of a triangle mesh.
pub fn step(mesh: &Mesh, he: &HalfEdgeMesh, tags: &Tags) -> Result<(Mesh, Features)> {
    let (nv, ne) = super::catmull_clark::triangle_counts(
        mesh,
        he,
        "Butterfly subdivision of faces that are not triangles",
    )?;
    let p = &mesh.positions;
    let valence: Vec<u32> = (0..nv as u32)
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|v| he.outgoing(VertexId(v)).count() as u32)
        .collect();
    let boundary: Vec<bool> = (0..nv as u32)
        .map(|v| he.is_boundary_vertex(VertexId(v)))
        .collect();
    let mut out = vec![[0.0f64; 3]; nv + ne];
    out[..nv].copy_from_slice(p);
    edge_points(&mut out[nv..], p, he, |e, [c0, c1], pa, pb| {
        let [a, b] = he.edges.verts[e];
        let mut acc = [0.0; 3];
        if tags.sharp[e] {
            // 4-point rule along the boundary / crease
            let far = |v: u32, other: u32| match tags.rule(he, v) {
                VertexRule::Crease(x, y) => Some(if x == other { y } else { x }),
                _ => None,
            };
            match (far(a, b), far(b, a)) {
                (Some(a2), Some(b2)) => {
                    let (qa, qb) = (p[a2 as usize], p[b2 as usize]);
                    for d in 0..3 {
                        acc[d] = 9.0 / 16.0 * (pa[d] + pb[d]) - 1.0 / 16.0 * (qa[d] + qb[d]);
                    }
                }
                _ => acc = std::array::from_fn(|d| 0.5 * (pa[d] + pb[d])),
            }
        } else {
            let (ba, bb) = (boundary[a as usize], boundary[b as usize]);
            let (ka, kb) = (valence[a as usize] as usize, valence[b as usize] as usize);
            // half-edges a→b and b→a
            let (hab, hba) = if he.from[c0 as usize] == a {
                (c0, c1)
            } else {
                (c1, c0)
            };
            let pc = p[he.from[he.prev[hab as usize] as usize] as usize];
            let pd = p[he.from[he.prev[hba as usize] as usize] as usize];
            if ba && bb {
                for d in 0..3 {
                    acc[d] = 0.375 * (pa[d] + pb[d]) + 0.125 * (pc[d] + pd[d]);
                }
            } else if ba {
                stencil(mesh, he, hba, kb, &mut acc, 1.0);
            } else if bb {
                stencil(mesh, he, hab, ka, &mut acc, 1.0);
            } else if ka == 6 && kb == 6 {
                // wings: across (b,c), (c,a) in a→b's face and (a,d), (d,b) in b→a's face
                let n_ab = he.next[hab as usize];
                let p_ab = he.prev[hab as usize];
                let n_ba = he.next[hba as usize];
                let p_ba = he.prev[hba as usize];
                let ws = [
                    wing(he, n_ab),
                    wing(he, p_ab),
                    wing(he, n_ba),
                    wing(he, p_ba),
                ];
                for d in 0..3 {
                    acc[d] = 0.5 * (pa[d] + pb[d]) + 0.125 * (pc[d] + pd[d]);
                }
                for w in ws.into_iter().flatten() {
                    let q = p[w as usize];
                    for d in 0..3 {
                        acc[d] -= q[d] / 16.0;
                    }
                }
            } else if ka == 6 {
                stencil(mesh, he, hba, kb, &mut acc, 1.0);
            } else if kb == 6 {
                stencil(mesh, he, hab, ka, &mut acc, 1.0);
            } else {
                stencil(mesh, he, hab, ka, &mut acc, 0.5);
                stencil(mesh, he, hba, kb, &mut acc, 0.5);
            }
        }
        acc
    });
    quadrisect(mesh, he, tags, out)
}
