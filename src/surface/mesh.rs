//! Tessellation (§5.1, Algorithm 5.1): sample `Q(u, v)` on a regular grid, join neighbours into
//! quads (or two triangles each), and give every vertex the normal `∂Q/∂u × ∂Q/∂v` (§5.1.1).
//! Where that cross product vanishes (the poles of a sphere, the apex of a cone) the vertex takes
//! the average of the normals of the grid faces around it instead.

use super::{add, cross, normalize, sub, Surface};
use crate::{Error, Result};

/// Triangles or quads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaceKind {
    Triangles,
    Quads,
}

/// A polygon mesh with one normal per vertex (face-vertex list, §6.7.1).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<[f64; 3]>,
    pub normals: Vec<[f64; 3]>,
    /// Vertex indices of each face, counter-clockwise seen from the normal side.
    pub faces: Vec<Vec<u32>>,
}

/// Largest accepted grid (vertices).
pub const MAX_VERTICES: usize = 16 << 20;

/// Sample `s` on `res_u × res_v` vertices (`≥ 2` each) over its parameter ranges.
pub fn tessellate(s: &dyn Surface, res_u: usize, res_v: usize, kind: FaceKind) -> Result<Mesh> {
    if res_u < 2 || res_v < 2 {
        return Err(Error::parameter(
            "resolution",
            format!("{res_u},{res_v}"),
            "at least 2,2",
        ));
    }
    let total = res_u
        .checked_mul(res_v)
        .filter(|&t| t <= MAX_VERTICES)
        .ok_or(Error::LimitsExceeded {
            what: "tessellation vertices",
            requested: (res_u as u64).saturating_mul(res_v as u64),
            limit: MAX_VERTICES as u64,
        })?;
    let ((u0, u1), (v0, v1)) = s.ranges();
    let at = |a: f64, b: f64, i: usize, n: usize| {
        if i + 1 == n {
            b
        } else {
            a + (b - a) * i as f64 / (n - 1) as f64
        }
    };
    let mut positions = Vec::with_capacity(total);
    let mut normals = Vec::with_capacity(total);
    for i in 0..res_u {
        let u = at(u0, u1, i, res_u);
        for j in 0..res_v {
            let v = at(v0, v1, j, res_v);
            let [q, qu, qv] = s.partials(u, v)?;
            positions.push(q);
            let n = cross(qu, qv);
            // a normal is trusted when the cross product is not tiny against the tangents
            let scale = super::norm(qu) * super::norm(qv);
            normals.push(if super::norm(n) > 1e-10 * scale && scale > 0.0 {
                n
            } else {
                [0.0; 3]
            });
        }
    }
    let idx = |i: usize, j: usize| (i * res_v + j) as u32;
    let mut faces = Vec::with_capacity((res_u - 1) * (res_v - 1) * 2);
    for i in 0..res_u - 1 {
        for j in 0..res_v - 1 {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            match kind {
                FaceKind::Quads => faces.push(vec![a, b, c, d]),
                FaceKind::Triangles => {
                    faces.push(vec![a, b, c]);
                    faces.push(vec![a, c, d]);
                }
            }
        }
    }
    // fallback normals from the faces around degenerate vertices
    let missing: Vec<usize> = (0..total).filter(|&k| normals[k] == [0.0; 3]).collect();
    if !missing.is_empty() {
        let mut acc = vec![[0.0; 3]; total];
        for f in &faces {
            for t in 1..f.len() - 1 {
                let (p0, p1, p2) = (
                    positions[f[0] as usize],
                    positions[f[t] as usize],
                    positions[f[t + 1] as usize],
                );
                let n = cross(sub(p1, p0), sub(p2, p0));
                for &v in [f[0], f[t], f[t + 1]].iter() {
                    acc[v as usize] = add(acc[v as usize], n);
                }
            }
        }
        for k in missing {
            normals[k] = acc[k];
        }
    }
    for n in normals.iter_mut() {
        *n = normalize(*n).unwrap_or([0.0, 0.0, 1.0]);
    }
    Ok(Mesh {
        positions,
        normals,
        faces,
    })
}
