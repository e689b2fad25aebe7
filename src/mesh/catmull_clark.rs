//! Catmull-Clark subdivision (§8.3) on any polygon mesh; after one step every face is a quad.
//!
//! ```text
//!   face point:    f = (1/m) Σ v_k                         (centroid of an m-gon)
//!   edge point:    e = ¼ (a + b + f_0 + f_1)               (boundary / sharp: ½ (a + b))
//!   vertex point:  v' = (n−2)/n v + 1/n² Σ v_j + 1/n² Σ f_j   (valence n, §8.3.1)
//!   boundary / crease vertex:  ¾ v + ⅛ (a + b)   (cubic B-spline curve mask, §8.3.2–8.3.3)
//!   corner:        v
//! ```
//!
//! Numbering of the result: old vertices keep their index, the point of edge `e` is `V + e`, the
//! point of face `f` is `V + E + f`. Corner `c` (vertex `v_i` of face `f`) becomes the quad
//! `(v_i, e(v_i v_{i+1}), f, e(v_{i−1} v_i))`, so the children of face `f` are its corners'
//! indices `offsets[f] .. offsets[f+1]`.

use super::features::{sharp_edge_point, Features, Tags};
use super::halfedge::{HalfEdgeMesh, VertexId};
use super::loop_subdivision::GRAIN;
use super::Mesh;
use crate::{Error, Result};
use rayon::prelude::*;

/// `(vertices, edges)` of a triangle mesh about to take a step that splits every
/// triangle in four; an error unless every face is a triangle (`what`: the step that needs
/// them) and the refined mesh fits 32-bit indices ([`check_size`]).
pub(crate) fn triangle_counts(
    mesh: &Mesh,
    he: &HalfEdgeMesh,
    what: &'static str,
) -> Result<(usize, usize)> {
    if !mesh.is_triangle_mesh() {
        return Err(Error::Unsupported {
            what,
            value: format!(
                "{} faces, {} corners",
                mesh.face_count(),
                mesh.corner_count()
            ),
        });
    }
    let (nv, ne, nf) = (mesh.vertex_count(), he.edge_count(), mesh.face_count());
    check_size(nv + ne, 12 * nf)?;
    Ok((nv, ne))
}

/// Fail early when the refined mesh would not fit 32-bit indices.
pub(crate) fn check_size(vertices: usize, indices: usize) -> Result<()> {
    let n = vertices.max(indices);
    if n >= u32::MAX as usize {
        return Err(Error::LimitsExceeded {
            what: "refined mesh size",
            requested: n as u64,
            limit: u32::MAX as u64 - 1,
        });
    }
    Ok(())
}

/// The new point of every edge `e`, in parallel: `out[e] = rule(e, [c0, c1], a, b)` with
/// `c0, c1` the edge's two corners (half-edges) and `a, b` the positions of its end points.
pub(crate) fn edge_points(
    out: &mut [[f64; 3]],
    p: &[[f64; 3]],
    he: &HalfEdgeMesh,
    rule: impl Fn(usize, [u32; 2], [f64; 3], [f64; 3]) -> [f64; 3] + Sync,
) {
    out.par_iter_mut()
        .with_min_len(GRAIN)
        .enumerate()
        .for_each(|(e, o)| {
            let [a, b] = he.edges.verts[e];
            *o = rule(e, he.edges.corners[e], p[a as usize], p[b as usize]);
        });
}

/// The new point of every old vertex `v`, in parallel: the tagged rule's point on a crease,
/// boundary or corner; else `smooth(v, s, n)` with `s = Σ ring(h)` over the `n` outgoing
/// half-edges `h` of `v`; an isolated vertex stays.
pub(crate) fn vertex_points(
    out: &mut [[f64; 3]],
    p: &[[f64; 3]],
    he: &HalfEdgeMesh,
    tags: &Tags,
    ring: impl Fn(usize) -> [f64; 3] + Sync,
    smooth: impl Fn([f64; 3], [f64; 3], usize) -> [f64; 3] + Sync,
) {
    out.par_iter_mut()
        .with_min_len(GRAIN)
        .enumerate()
        .for_each(|(v, o)| {
            *o = match tags.rule(he, v as u32).sharp_point(p, v) {
                Some(q) => q,
                None => {
                    let mut s = [0.0; 3];
                    let mut n = 0usize;
                    for h in he.outgoing(VertexId(v as u32)) {
                        let q = ring(h.idx());
                        for k in 0..3 {
                            s[k] += q[k];
                        }
                        n += 1;
                    }
                    if n == 0 {
                        p[v]
                    } else {
                        smooth(p[v], s, n)
                    }
                }
            };
        });
}

/// Face centroids, in parallel.
pub fn face_points(mesh: &Mesh) -> Vec<[f64; 3]> {
    let p = &mesh.positions;
    (0..mesh.face_count())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|f| {
            let face = mesh.face(f);
            let mut s = [0.0; 3];
            for &v in face {
                let q = p[v as usize];
                s[0] += q[0];
                s[1] += q[1];
                s[2] += q[2];
            }
            let w = 1.0 / face.len() as f64;
            [s[0] * w, s[1] * w, s[2] * w]
        })
        .collect()
}

/// One step of Catmull-Clark subdivision. Returns the refined quad mesh and its child tags.
pub fn step(mesh: &Mesh, he: &HalfEdgeMesh, tags: &Tags) -> Result<(Mesh, Features)> {
    let nv = mesh.vertex_count();
    let ne = he.edge_count();
    let nf = mesh.face_count();
    let nc = mesh.corner_count();
    check_size(nv + ne + nf, 4 * nc)?;
    let p = &mesh.positions;
    let mut out = vec![[0.0f64; 3]; nv + ne + nf];
    let (vpart, rest) = out.split_at_mut(nv);
    let (epart, fpart) = rest.split_at_mut(ne);
    fpart.copy_from_slice(&face_points(mesh));
    let fp: &[[f64; 3]] = fpart;
    edge_points(epart, p, he, |e, [c0, c1], pa, pb| {
        if tags.sharp[e] {
            sharp_edge_point(pa, pb)
        } else {
            let f0 = fp[he.face[c0 as usize] as usize];
            let f1 = fp[he.face[c1 as usize] as usize];
            std::array::from_fn(|k| 0.25 * (pa[k] + pb[k] + f0[k] + f1[k]))
        }
    });
    // each ring step adds the far end of the edge and the point of the face on its left
    let ring = |h: usize| {
        let q = p[he.from[he.twin[h] as usize] as usize];
        let f = fp[he.face[h] as usize];
        std::array::from_fn(|k| q[k] + f[k])
    };
    vertex_points(vpart, p, he, tags, ring, |pv, s, n| {
        let nn = n as f64;
        let w = (nn - 2.0) / nn;
        let u = 1.0 / (nn * nn);
        std::array::from_fn(|k| w * pv[k] + u * s[k])
    });
    let mut indices = vec![0u32; 4 * nc];
    let ce = &he.edges.corner_edge;
    let (vb, fb) = (nv as u32, (nv + ne) as u32);
    // corners are processed face by face so each task writes its faces' quads
    let fo = &mesh.offsets;
    let chunks: Vec<(usize, &mut [u32])> = {
        let mut v = Vec::new();
        let mut rest: &mut [u32] = &mut indices;
        let step = GRAIN;
        let mut f = 0;
        while f < nf {
            let g = (f + step).min(nf);
            let len = 4 * (fo[g] - fo[f]) as usize;
            let (a, b) = rest.split_at_mut(len);
            v.push((f, a));
            rest = b;
            f = g;
        }
        v
    };
    chunks.into_par_iter().for_each(|(f0, q)| {
        let mut w = 0;
        let mut f = f0;
        while w < q.len() {
            let (s, e) = (fo[f] as usize, fo[f + 1] as usize);
            for c in s..e {
                let pc = if c == s { e - 1 } else { c - 1 };
                q[w] = mesh.indices[c];
                q[w + 1] = vb + ce[c];
                q[w + 2] = fb + f as u32;
                q[w + 3] = vb + ce[pc];
                w += 4;
            }
            f += 1;
        }
    });
    Ok((Mesh::of_degree(out, indices, 4), child_tags(tags, he, nv)))
}

/// The tags of a refined mesh's old vertices and edge halves: none unless some interior
/// edge is sharp or some vertex a corner.
pub(crate) fn child_tags(tags: &Tags, he: &HalfEdgeMesh, nv: usize) -> Features {
    if tags.any_interior_sharp || tags.corner.iter().any(|&c| c) {
        tags.children(he, nv as u32)
    } else {
        Features::default()
    }
}
