//! Doo-Sabin subdivision (§8.1): every face contracts towards its centroid and the holes are
//! filled. One new vertex per corner: for face `f` of degree `n` and its corner `i`,
//!
//! ```text
//!   v'_i = Σ_j α_{|i−j|} v_j,   α_0 = ¼ + 5/(4n),   α_k = (3 + 2 cos(2πk/n)) / (4n)
//! ```
//!
//! (at n = 4: 9/16, 3/16, 1/16, 3/16 — Chaikin in both directions, §8.1.2). New faces (§8.1.3):
//! FF, one per face (its contracted corners); FE, one quad per edge; FV, one per vertex (its
//! corners around it). The result has F + E + V faces.
//!
//! Boundaries (the curve scheme of §8.2.3 for Doo-Sabin is Chaikin's): each boundary edge
//! `u → w` gets the two Chaikin points ¾u + ¼w and ¼u + ¾w; its FE face joins the face's two
//! contracted corners to them, and a boundary vertex's FV face runs through its corners and the
//! two Chaikin points next to it. The boundary then converges to the quadratic B-spline of the
//! boundary polygon, every edge and vertex still gets its face (F + E + V faces), and the
//! topology (χ, boundary loops) is kept. Sharp tags are not supported.

use super::halfedge::{HalfEdgeMesh, VertexId};
use super::loop_subdivision::GRAIN;
use super::{Attributes, Mesh};
use crate::Result;
use rayon::prelude::*;
use std::f64::consts::PI;

/// One step of Doo-Sabin subdivision. New vertex `c` is the contracted corner `c`.
pub fn step(mesh: &Mesh, he: &HalfEdgeMesh) -> Result<Mesh> {
    let nc = mesh.corner_count();
    let nf = mesh.face_count();
    let p = &mesh.positions;
    super::catmull_clark::check_size(nc + 2 * he.halfedge_count(), 4 * nc + 4 * he.edge_count())?;
    let mut out = vec![[0.0f64; 3]; nc];
    let fo = &mesh.offsets;
    out.par_iter_mut()
        .with_min_len(GRAIN)
        .enumerate()
        .for_each(|(c, o)| {
            let f = he.face[c] as usize;
            let (s, e) = (fo[f] as usize, fo[f + 1] as usize);
            let n = e - s;
            let i = c - s;
            let nf64 = n as f64;
            let mut acc = [0.0; 3];
            for j in 0..n {
                let k = (i + n - j) % n;
                let w = if k == 0 {
                    0.25 + 5.0 / (4.0 * nf64)
                } else {
                    (3.0 + 2.0 * (2.0 * PI * k as f64 / nf64).cos()) / (4.0 * nf64)
                };
                let q = p[mesh.indices[s + j] as usize];
                for d in 0..3 {
                    acc[d] += w * q[d];
                }
            }
            *o = acc;
        });
    // Chaikin points of boundary half-edge h (from x to y): 2(h − C) near x, 2(h − C) + 1 near y
    let hc = he.corners;
    for h in hc..he.halfedge_count() {
        let x = p[he.from[h] as usize];
        let y = p[he.from[he.twin[h] as usize] as usize];
        out.push(std::array::from_fn(|k| 0.75 * x[k] + 0.25 * y[k]));
        out.push(std::array::from_fn(|k| 0.25 * x[k] + 0.75 * y[k]));
    }
    let near_from = |h: u32| (nc + 2 * (h as usize - hc)) as u32;
    let mut offsets = Vec::with_capacity(nf + he.edge_count() + mesh.vertex_count() + 1);
    offsets.extend_from_slice(&mesh.offsets);
    let mut indices: Vec<u32> = (0..nc as u32).collect();
    // FE faces: edge with corners c0 (a→b) and c1 (b→a): quad next(c0) → c0 → next(c1) → c1;
    // on a boundary the other side is the Chaikin pair: next(c0) → c0 → q_a → q_b
    for e in 0..he.edge_count() {
        let [c0, c1] = he.edges.corners[e];
        let n0 = he.next[c0 as usize];
        if he.edges.uses[e] == 2 {
            let n1 = he.next[c1 as usize];
            indices.extend_from_slice(&[n0, c0, n1, c1]);
        } else {
            let h = he.twin[c0 as usize]; // boundary half-edge b → a
            indices.extend_from_slice(&[n0, c0, near_from(h) + 1, near_from(h)]);
        }
        offsets.push(indices.len() as u32);
    }
    // FV faces: the corners at a vertex against the rotation order next(twin(h)); at a boundary
    // vertex the two Chaikin points next to it close the polygon
    let mut ring = Vec::new();
    for v in 0..mesh.vertex_count() as u32 {
        ring.clear();
        ring.extend(he.outgoing(VertexId(v)).map(|h| h.0));
        if ring.is_empty() {
            continue;
        }
        if he.is_boundary_vertex(VertexId(v)) {
            let hb = ring[0]; // boundary half-edge v → w
            let hin = he.prev[hb as usize]; // boundary half-edge u → v
            indices.extend(ring[1..].iter().rev());
            indices.push(near_from(hb));
            indices.push(near_from(hin) + 1);
        } else {
            indices.extend(ring.iter().rev());
        }
        offsets.push(indices.len() as u32);
    }
    Ok(Mesh {
        positions: out,
        offsets,
        indices,
        attributes: Attributes::default(),
    })
}
