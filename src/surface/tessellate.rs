//! Tessellation (§5.1, Algorithm 5.1): sample `Q(u, v)` on a regular grid, join neighbours into
//! quads (or two triangles each) of a [`crate::mesh::Mesh`], and store at every vertex the unit
//! normal `∂Q/∂u × ∂Q/∂v` (§5.1.1) in the mesh's per-vertex normal attribute, so the mesh
//! writers put it out as OBJ `vn` / PLY `nx ny nz`. Where that cross product vanishes (the poles
//! of a sphere, the apex of a cone) the vertex takes the area-weighted average of the normals of
//! the grid faces around it instead ([`crate::mesh::normals::vertex_normals`], §6.6.1).

use super::{cross, normalize, Surface};
use crate::mesh::normals::{vertex_normals, Weighting};
use crate::mesh::Mesh;
use crate::{Error, Result};

/// Triangles or quads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaceKind {
    Triangles,
    Quads,
}

/// Largest accepted grid (vertices).
pub const MAX_VERTICES: usize = 16 << 20;

/// Sample `s` on `res_u × res_v` vertices (`≥ 2` each) over its parameter ranges. Vertex
/// `(i, j)` has index `i · res_v + j`; the unit normals are in `attributes.vertex_normals`.
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
    let mut indices = Vec::with_capacity((res_u - 1) * (res_v - 1) * 6);
    for i in 0..res_u - 1 {
        for j in 0..res_v - 1 {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            match kind {
                FaceKind::Quads => indices.extend_from_slice(&[a, b, c, d]),
                FaceKind::Triangles => indices.extend_from_slice(&[a, b, c, a, c, d]),
            }
        }
    }
    let degree = match kind {
        FaceKind::Quads => 4,
        FaceKind::Triangles => 3,
    };
    let mut mesh = Mesh::from_faces(positions, crate::mesh::Faces::Uniform { indices, degree })?;
    // fallback normals from the faces around degenerate vertices
    if normals.contains(&[0.0; 3]) {
        let around = vertex_normals(&mesh, Weighting::Area);
        for (n, a) in normals.iter_mut().zip(around) {
            if *n == [0.0; 3] {
                *n = a;
            }
        }
    }
    for n in normals.iter_mut() {
        *n = normalize(*n).unwrap_or([0.0, 0.0, 1.0]);
    }
    mesh.attributes.vertex_normals = Some(normals);
    Ok(mesh)
}
