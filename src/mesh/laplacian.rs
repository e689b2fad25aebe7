//! Discrete Laplacians and Laplacian smoothing (§6.6.2).
//!
//! ```text
//!   uniform (umbrella):  (L u)_i = Σ_{j ∈ N(i)} (u_j − u_i)          (graph Laplacian A − D)
//!   cotangent:           L_ij = ½ (cot α_ij + cot β_ij),  L_ii = −Σ_j L_ij
//!                        (α, β the angles opposite edge ij; equals libigl's cotmatrix)
//!   explicit smoothing:  u ← u + λ D⁻¹ L u        (D = diag of −L, i.e. the mean of the neighbours)
//!   implicit smoothing:  (M − λ L) u' = M u       (M = I for uniform, lumped areas for cotangent)
//! ```
//!
//! Implicit cotangent smoothing keeps the Laplacian `L` of the input mesh and updates only
//! the mass matrix `M` each iteration (the "conformalized" flow of Kazhdan, Solomon and
//! Ben-Chen, SGP 2012): recomputing `L` on the smoothed mesh degenerates it, thin parts
//! collapse into needle triangles whose cotangents blow up, and the system stops being
//! solvable (the Stanford bunny after 9 iterations at λ = 1).
//!
//! Boundary vertices are kept fixed by `smooth` when `fix_boundary` is set.

use super::edges::Edges;
use super::sparse::{conjugate_gradient, Csr};
use super::{vec3, Mesh};
use crate::{Error, Result};

/// Which Laplacian.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Uniform,
    Cotangent,
}

impl Kind {
    pub fn parse(s: &str) -> Result<Kind> {
        match s {
            "uniform" => Ok(Kind::Uniform),
            "cotangent" | "cot" => Ok(Kind::Cotangent),
            _ => Err(Error::parameter("laplacian", s, "uniform or cotangent")),
        }
    }
}

/// The uniform graph Laplacian A − D (one entry per undirected edge).
pub fn uniform(mesh: &Mesh) -> Csr {
    let edges = Edges::build(mesh);
    let mut t = Vec::with_capacity(4 * edges.len());
    for &[a, b] in &edges.verts {
        t.push((a, b, 1.0));
        t.push((b, a, 1.0));
        t.push((a, a, -1.0));
        t.push((b, b, -1.0));
    }
    Csr::from_triplets(mesh.vertex_count(), t)
}

/// The cotangent Laplacian of a triangle mesh.
pub fn cotangent(mesh: &Mesh) -> Result<Csr> {
    if !mesh.is_triangle_mesh() {
        return Err(Error::Unsupported {
            what: "cotangent Laplacian of faces that are not triangles",
            value: format!("{} faces", mesh.face_count()),
        });
    }
    let p = &mesh.positions;
    let mut t = Vec::with_capacity(12 * mesh.face_count());
    for f in mesh.faces() {
        for i in 0..3 {
            // angle at corner i is opposite edge (i+1, i+2)
            let (a, b, c) = (f[i], f[(i + 1) % 3], f[(i + 2) % 3]);
            let u = vec3::sub(p[b as usize], p[a as usize]);
            let v = vec3::sub(p[c as usize], p[a as usize]);
            let cot = vec3::dot(u, v) / vec3::norm(vec3::cross(u, v));
            let w = 0.5 * cot;
            t.push((b, c, w));
            t.push((c, b, w));
            t.push((b, b, -w));
            t.push((c, c, -w));
        }
    }
    Ok(Csr::from_triplets(mesh.vertex_count(), t))
}

/// Lumped (barycentric) vertex areas: a third of the area of each incident triangle.
pub fn barycentric_areas(mesh: &Mesh) -> Vec<f64> {
    let mut m = vec![0.0; mesh.vertex_count()];
    for f in 0..mesh.face_count() {
        let a = vec3::norm(super::normals::face_area_vector(mesh, f));
        let d = mesh.face_degree(f) as f64;
        for &v in mesh.face(f) {
            m[v as usize] += a / d;
        }
    }
    m
}

/// Smoothing method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    Explicit,
    Implicit,
}

/// Laplacian smoothing: `iterations` steps of size `lambda`.
pub fn smooth(
    mesh: &Mesh,
    kind: Kind,
    method: Method,
    lambda: f64,
    iterations: usize,
    fix_boundary: bool,
) -> Result<Mesh> {
    if !(lambda.is_finite() && lambda > 0.0) {
        return Err(Error::parameter("lambda", lambda, "a positive number"));
    }
    if method == Method::Explicit && lambda > 1.0 {
        return Err(Error::parameter(
            "lambda",
            lambda,
            "at most 1 for explicit smoothing",
        ));
    }
    let nv = mesh.vertex_count();
    let edges = Edges::build(mesh);
    let mut fixed = vec![false; nv];
    if fix_boundary {
        for e in 0..edges.len() {
            if edges.uses[e] == 1 {
                fixed[edges.verts[e][0] as usize] = true;
                fixed[edges.verts[e][1] as usize] = true;
            }
        }
    }
    let mut out = mesh.clone();
    out.attributes.vertex_normals = None;
    // the input's Laplacian, kept by implicit smoothing (see the module doc)
    let kept = match (method, kind) {
        (Method::Implicit, Kind::Cotangent) => Some(cotangent(mesh)?),
        _ => None,
    };
    for _ in 0..iterations {
        let l = match (&kept, kind) {
            (Some(l), _) => l.clone(),
            (None, Kind::Uniform) => uniform(&out),
            (None, Kind::Cotangent) => cotangent(&out)?,
        };
        let x = out.positions.clone();
        let new = match method {
            Method::Explicit => explicit_step(&l, &x, lambda),
            Method::Implicit => implicit_step(&l, &x, &out, kind, lambda, &fixed)?,
        };
        for i in 0..nv {
            if !fixed[i] {
                out.positions[i] = new[i];
            }
        }
    }
    Ok(out)
}

/// One explicit step: `x_i + λ (L x)_i / (−L_ii)` (rows without a diagonal stay).
fn explicit_step(l: &Csr, x: &[[f64; 3]], lambda: f64) -> Vec<[f64; 3]> {
    let nv = x.len();
    let mut lx = vec![[0.0; 3]; nv];
    l.mul3(x, &mut lx);
    let d = l.diagonal();
    (0..nv)
        .map(|i| {
            if d[i] == 0.0 {
                x[i]
            } else {
                std::array::from_fn(|k| x[i][k] + lambda * lx[i][k] / -d[i])
            }
        })
        .collect::<Vec<_>>()
}

/// One implicit step: solve `(M − λ' L) x' = M x` by conjugate gradients, with `M` the mass
/// (1, or the barycentric areas for the cotangent Laplacian), `λ' = λ·mean(M)` for the
/// cotangent kind (λ otherwise), and fixed vertices kept (their columns moved to the
/// right-hand side).
fn implicit_step(
    l: &Csr,
    x: &[[f64; 3]],
    mesh: &Mesh,
    kind: Kind,
    lambda: f64,
    fixed: &[bool],
) -> Result<Vec<[f64; 3]>> {
    let nv = x.len();
    let mass = match kind {
        Kind::Uniform => vec![1.0; nv],
        Kind::Cotangent => barycentric_areas(mesh),
    };
    // scale λ by the mean mass so the step size does not depend on the mesh's units
    let mean = mass.iter().sum::<f64>() / nv.max(1) as f64;
    let lam = lambda * if kind == Kind::Cotangent { mean } else { 1.0 };
    let mut t = Vec::with_capacity(l.val.len() + nv);
    for i in 0..nv {
        if fixed[i] {
            t.push((i as u32, i as u32, 1.0));
            continue;
        }
        t.push((i as u32, i as u32, mass[i]));
        for k in l.row_start[i]..l.row_start[i + 1] {
            let j = l.col[k] as usize;
            if fixed[j] && j != i {
                continue; // moved to the right-hand side below
            }
            t.push((i as u32, j as u32, -lam * l.val[k]));
        }
    }
    let a = Csr::from_triplets(nv, t);
    let b: Vec<[f64; 3]> = (0..nv)
        .map(|i| {
            if fixed[i] {
                return x[i];
            }
            let mut r = vec3::scale(x[i], mass[i]);
            for k in l.row_start[i]..l.row_start[i + 1] {
                let j = l.col[k] as usize;
                if fixed[j] && j != i {
                    vec3::axpy(&mut r, lam * l.val[k], x[j]);
                }
            }
            r
        })
        .collect();
    conjugate_gradient(&a, &b, x, 1e-10, 10 * nv + 100)
}
