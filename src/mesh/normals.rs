//! Face and vertex normals (§6.6.1).
//!
//! ```text
//!   face normal (Newell):  n_f = ½ Σ_i v_i × v_{i+1},  |n_f| = area of f (planar faces)
//!   vertex normal:         n_v = normalise( Σ_{f ∋ v} w_f n̂_f )
//!       uniform:  w_f = 1        area: w_f = area(f)        angle: w_f = interior angle at v
//! ```
//!
//! Uniform, area and angle weighting equal libigl's `per_vertex_normals` UNIFORM, AREA and
//! ANGLE on triangle meshes.

use super::loop_subdivision::GRAIN;
use super::{vec3, Mesh};
use crate::{Error, Result};
use rayon::prelude::*;

/// Weighting of face normals in a vertex normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    Uniform,
    Area,
    Angle,
}

impl Weighting {
    pub fn parse(s: &str) -> Result<Weighting> {
        match s {
            "uniform" => Ok(Weighting::Uniform),
            "area" => Ok(Weighting::Area),
            "angle" => Ok(Weighting::Angle),
            _ => Err(Error::parameter("weighting", s, "uniform, area or angle")),
        }
    }
}

/// Area vector of face `f` (Newell's method): its direction is the normal, its length the area.
#[inline]
pub fn face_area_vector(mesh: &Mesh, f: usize) -> [f64; 3] {
    let face = mesh.face(f);
    let p = &mesh.positions;
    if face.len() == 3 {
        let (a, b, c) = (
            p[face[0] as usize],
            p[face[1] as usize],
            p[face[2] as usize],
        );
        return vec3::scale(vec3::cross(vec3::sub(b, a), vec3::sub(c, a)), 0.5);
    }
    let mut n = [0.0; 3];
    for i in 0..face.len() {
        let a = p[face[i] as usize];
        let b = p[face[(i + 1) % face.len()] as usize];
        n = vec3::add(n, vec3::cross(a, b));
    }
    vec3::scale(n, 0.5)
}

/// Unit face normals (zero for degenerate faces).
pub fn face_normals(mesh: &Mesh) -> Vec<[f64; 3]> {
    (0..mesh.face_count())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|f| vec3::normalized(face_area_vector(mesh, f)))
        .collect()
}

/// Unit vertex normals with the given weighting. Sums run per face (scatter) in parallel over
/// blocks of faces into per-thread buffers, then add up.
pub fn vertex_normals(mesh: &Mesh, weighting: Weighting) -> Vec<[f64; 3]> {
    let nv = mesh.vertex_count();
    let nf = mesh.face_count();
    let p = &mesh.positions;
    let tri = mesh.is_triangle_mesh();
    let accumulate = |acc: &mut Vec<[f64; 3]>, f: usize| {
        if tri {
            // triangles: one cross product gives the normal, the area and, with the three dot
            // products, every corner angle: θ_i = atan2(|e × e'|, e · e') with |e × e'| = 2A
            let t = &mesh.indices[3 * f..3 * f + 3];
            let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
            let (ab, bc, ca) = (vec3::sub(b, a), vec3::sub(c, b), vec3::sub(a, c));
            let cr = vec3::cross(ab, vec3::scale(ca, -1.0));
            let twice_area = vec3::norm(cr);
            if twice_area == 0.0 {
                return;
            }
            let n = vec3::scale(cr, 1.0 / twice_area);
            let w = match weighting {
                Weighting::Uniform => [1.0; 3],
                Weighting::Area => [0.5 * twice_area; 3],
                Weighting::Angle => [
                    twice_area.atan2(-vec3::dot(ca, ab)),
                    twice_area.atan2(-vec3::dot(ab, bc)),
                    twice_area.atan2(-vec3::dot(bc, ca)),
                ],
            };
            for i in 0..3 {
                vec3::axpy(&mut acc[t[i] as usize], w[i], n);
            }
            return;
        }
        let av = face_area_vector(mesh, f);
        let area = vec3::norm(av);
        if area == 0.0 {
            return;
        }
        let n = vec3::scale(av, 1.0 / area);
        let face = mesh.face(f);
        let k = face.len();
        for i in 0..k {
            let v = face[i] as usize;
            let w = match weighting {
                Weighting::Uniform => 1.0,
                Weighting::Area => area,
                Weighting::Angle => {
                    let a = vec3::sub(p[face[(i + 1) % k] as usize], p[v]);
                    let b = vec3::sub(p[face[(i + k - 1) % k] as usize], p[v]);
                    let c = vec3::norm(vec3::cross(a, b));
                    c.atan2(vec3::dot(a, b))
                }
            };
            vec3::axpy(&mut acc[v], w, n);
        }
    };
    let sum = if nf < 8 * GRAIN {
        let mut acc = vec![[0.0; 3]; nv];
        for f in 0..nf {
            accumulate(&mut acc, f);
        }
        acc
    } else {
        let parts = rayon::current_num_threads().max(1);
        let step = nf.div_ceil(parts);
        let partial: Vec<Vec<[f64; 3]>> = (0..parts)
            .into_par_iter()
            .map(|t| {
                let mut acc = vec![[0.0; 3]; nv];
                for f in t * step..((t + 1) * step).min(nf) {
                    accumulate(&mut acc, f);
                }
                acc
            })
            .collect();
        let mut it = partial.into_iter();
        let mut acc = it.next().unwrap_or_else(|| vec![[0.0; 3]; nv]);
        for part in it {
            acc.par_iter_mut()
                .zip(part.par_iter())
                .with_min_len(GRAIN)
                .for_each(|(a, b)| {
                    *a = vec3::add(*a, *b);
                });
        }
        acc
    };
    sum.into_par_iter()
        .with_min_len(GRAIN)
        .map(vec3::normalized)
        .collect()
}
