//! Free-form deformation (Sederberg & Parry 1986) by a trivariate B-spline lattice (notes §10.2:
//! "cover the scene by an encompassing cuboid; then any Q(u, v, t) whose domain is the cuboid
//! acts as a deformation of the scene").
//!
//! A point `x` of the box `[min, max]` gets local coordinates `s = (x − min) / (max − min)` in
//! `[0, 1]³` and is mapped to `Q(s)` of a [`HyperPatch`] with clamped knots. The undeformed
//! lattice puts control point `(i, j, k)` at `min + (ξ_i, ξ_j, ξ_k) · (max − min)` with the
//! Greville abscissae `ξ` ([`super::hyperpatch::greville`]); by the linear precision of
//! B-splines `Q(s) = x`, so the lattice starts as the identity map. Moving control points
//! deforms space smoothly (C^{k−2} across knots); points outside the box are left unchanged.
//!
//! Lattice files (JSON, `mra mesh deform --lattice`):
//!
//! ```json
//! { "dims": [4, 4, 4], "degree": 3,
//!   "box": { "min": [-1, -1, -1], "max": [1, 1, 1] },
//!   "moves": [ { "index": [3, 3, 3], "offset": [0.5, 0.5, 0.5] } ] }
//! ```
//!
//! `dims` (control points along x, y, z, 2 to 256 each) is required; `degree` is one number or
//! three (each 1 ≤ degree ≤ dims − 1; default `min(3, dims − 1)`); `box` is optional
//! (default: the mesh's bounding box); either `moves` (offsets added to the identity lattice)
//! or `points` (the full list of `nx·ny·nz` control points, x index fastest), not both.

// Index loops over the three axes follow the formulas (several arrays indexed together).
#![allow(clippy::needless_range_loop)]
use super::hyperpatch::{checked_count, greville, HyperPatch};
use super::scene::finite3;
use crate::curve::KnotVector;
use crate::mesh::vec3::cross;
use crate::mesh::Mesh;
use crate::{Error, Result};
use rayon::prelude::*;
use serde_json::{Map, Value};

/// A lattice over a box: the box and the hyper-patch defined on its local coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Lattice {
    min: [f64; 3],
    size: [f64; 3],
    patch: HyperPatch,
}

/// A box with a zero-width side is widened to one unit (centred) there, so that flat meshes
/// can still be deformed in every direction.
fn widen(min: [f64; 3], max: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let mut lo = min;
    let mut size = [0.0; 3];
    for d in 0..3 {
        size[d] = max[d] - min[d];
        if size[d] <= 0.0 {
            lo[d] = 0.5 * (min[d] + max[d]) - 0.5;
            size[d] = 1.0;
        }
    }
    (lo, size)
}

impl Lattice {
    /// The identity lattice of `dims` control points and `degrees` over `[min, max]`.
    pub fn identity(
        min: [f64; 3],
        max: [f64; 3],
        dims: [usize; 3],
        degrees: [usize; 3],
    ) -> Result<Lattice> {
        for d in 0..3 {
            if !(min[d].is_finite() && max[d].is_finite() && min[d] <= max[d]) {
                return Err(Error::parameter(
                    "lattice box",
                    format!("{min:?} .. {max:?}"),
                    "finite corners with min ≤ max",
                ));
            }
            if degrees[d] == 0 {
                return Err(Error::parameter("lattice degree", 0, "at least 1"));
            }
        }
        let (min, size) = widen(min, max);
        let total = checked_count(dims, "lattice control points")?;
        let xi = (0..3)
            .map(|d| {
                let t = KnotVector::open(dims[d], degrees[d] + 1)?;
                Ok(greville(t.as_slice(), dims[d], degrees[d] + 1))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut points = Vec::with_capacity(total);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    points.push([
                        min[0] + xi[0][i] * size[0],
                        min[1] + xi[1][j] * size[1],
                        min[2] + xi[2][k] * size[2],
                    ]);
                }
            }
        }
        let patch = HyperPatch::clamped(points, dims, degrees)?;
        Ok(Lattice { min, size, patch })
    }

    /// The identity lattice over the bounding box of `mesh`.
    pub fn around(mesh: &Mesh, dims: [usize; 3], degrees: [usize; 3]) -> Result<Lattice> {
        let (lo, hi) = bounds(mesh)?;
        Lattice::identity(lo, hi, dims, degrees)
    }

    /// The hyper-patch (control points in world coordinates).
    pub fn patch(&self) -> &HyperPatch {
        &self.patch
    }

    /// Control point `(i, j, k)`, mutable (world coordinates).
    pub fn point_mut(&mut self, ijk: [usize; 3]) -> Result<&mut [f64; 3]> {
        self.patch.point_mut(ijk)
    }

    /// Replace all control points (`i` fastest).
    pub fn set_points(&mut self, points: Vec<[f64; 3]>) -> Result<()> {
        let degrees = self.patch.orders().map(|k| k - 1);
        self.patch = HyperPatch::clamped(points, self.patch.dims(), degrees)?;
        Ok(())
    }

    /// The box `(min, max)` (after widening zero-width sides).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let max = [0, 1, 2].map(|d| self.min[d] + self.size[d]);
        (self.min, max)
    }

    /// Local coordinates `s = (x − min)/(max − min)`, or `None` outside the box.
    #[inline]
    pub fn local(&self, x: [f64; 3]) -> Option<[f64; 3]> {
        let s = [0, 1, 2].map(|d| (x[d] - self.min[d]) / self.size[d]);
        s.iter().all(|v| (0.0..=1.0).contains(v)).then_some(s)
    }

    /// The deformed position of `x` (unchanged outside the box).
    pub fn apply(&self, x: [f64; 3]) -> [f64; 3] {
        match self.local(x) {
            Some(s) => self.patch.eval_with(s, &mut self.patch.scratch()),
            None => x,
        }
    }

    /// Deform many points (in parallel).
    pub fn apply_all(&self, points: &mut [[f64; 3]]) {
        points.par_chunks_mut(4096).for_each(|chunk| {
            let mut s = self.patch.scratch();
            for p in chunk {
                if let Some(l) = self.local(*p) {
                    *p = self.patch.eval_with(l, &mut s);
                }
            }
        });
    }

    /// The Jacobian `∂Q(s(x))/∂x` of the deformation at `x` (identity outside the box), as rows
    /// `[∂/∂x, ∂/∂y, ∂/∂z]` of the mapped point.
    pub fn jacobian(&self, x: [f64; 3]) -> [[f64; 3]; 3] {
        match self.local(x) {
            Some(s) => match self.patch.eval_jacobian(s) {
                Ok((_, mut j)) => {
                    for d in 0..3 {
                        for c in 0..3 {
                            j[d][c] /= self.size[d];
                        }
                    }
                    j
                }
                Err(_) => IDENTITY,
            },
            None => IDENTITY,
        }
    }

    /// Deform a mesh: positions are mapped, connectivity is kept; per-vertex normals (computed
    /// or PLY `nx ny nz`) are mapped by the cofactor of the Jacobian (`n' ∝ J^{−T} n`) and
    /// renormalised; OBJ corner normals (which are not tied to a vertex) are dropped.
    pub fn deform(&self, mesh: &Mesh) -> Mesh {
        let mut out = mesh.clone();
        let original = &mesh.positions;
        self.apply_all(&mut out.positions);
        if let Some(n) = out.attributes.vertex_normals.as_mut() {
            for (v, nv) in n.iter_mut().enumerate() {
                *nv = self.map_normal(original[v], *nv);
            }
        }
        let props = &mut out.attributes.vertex;
        let find = |name: &str| props.iter().position(|p| p.name == name);
        if let (Some(a), Some(b), Some(c)) = (find("nx"), find("ny"), find("nz")) {
            for v in 0..original.len() {
                let n = [props[a].values[v], props[b].values[v], props[c].values[v]];
                let m = self.map_normal(original[v], n);
                props[a].values[v] = m[0];
                props[b].values[v] = m[1];
                props[c].values[v] = m[2];
            }
        }
        out.attributes.normals.clear();
        out.attributes.corner_normal.clear();
        out
    }

    fn map_normal(&self, x: [f64; 3], n: [f64; 3]) -> [f64; 3] {
        let j = self.jacobian(x);
        // rows of j are the images of the axes; the cofactor matrix maps normals
        let cof = [cross(j[1], j[2]), cross(j[2], j[0]), cross(j[0], j[1])];
        let m = [0, 1, 2].map(|c| cof[0][c] * n[0] + cof[1][c] * n[1] + cof[2][c] * n[2]);
        let len = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
        if len > 0.0 && len.is_finite() {
            m.map(|x| x / len)
        } else {
            n
        }
    }

    /// Parse a lattice file (format above). `mesh_box` is used when the file has no `box`.
    /// Errors name the field: `lattice.moves[2].index: 5 is outside 0..4 (dims[0])`.
    pub fn parse(text: &str, mesh_box: ([f64; 3], [f64; 3])) -> Result<Lattice> {
        let v: Value = serde_json::from_str(text).map_err(|e| {
            Error::format(format!("lattice JSON: {e}"), "a JSON object with \"dims\"")
        })?;
        let o = v
            .as_object()
            .ok_or_else(|| err("lattice", "not a JSON object"))?;
        for key in o.keys() {
            if !matches!(key.as_str(), "dims" | "degree" | "box" | "moves" | "points") {
                return Err(err(
                    &format!("lattice.{key}"),
                    "unknown field (expected dims, degree, box, moves or points)",
                ));
            }
        }
        let (dims, degrees) = dims_and_degrees(o)?;
        let (lo, hi) = match o.get("box") {
            None => mesh_box,
            Some(b) => {
                let bo = b
                    .as_object()
                    .ok_or_else(|| err("lattice.box", "not an object with min and max"))?;
                let lo = vec3(bo, "min", "lattice.box")?;
                let hi = vec3(bo, "max", "lattice.box")?;
                if (0..3).any(|d| lo[d] > hi[d]) {
                    return Err(err("lattice.box", "min exceeds max"));
                }
                (lo, hi)
            }
        };
        let mut lat = Lattice::identity(lo, hi, dims, degrees)?;
        match (o.get("moves"), o.get("points")) {
            (Some(_), Some(_)) => {
                return Err(err("lattice", "both \"moves\" and \"points\" (give one)"))
            }
            (Some(m), None) => apply_moves(&mut lat, m, dims)?,
            (None, Some(p)) => {
                let list = p
                    .as_array()
                    .ok_or_else(|| err("lattice.points", "not an array"))?;
                let total = dims[0] * dims[1] * dims[2];
                if list.len() != total {
                    return Err(err(
                        "lattice.points",
                        format!("{} points (expected {total} = nx·ny·nz)", list.len()),
                    ));
                }
                let pts = list
                    .iter()
                    .enumerate()
                    .map(|(n, v)| to_vec3(v, &format!("lattice.points[{n}]")))
                    .collect::<Result<Vec<_>>>()?;
                lat.set_points(pts)?;
            }
            (None, None) => {}
        }
        Ok(lat)
    }
}

/// `dims` (2..=256 control points per axis) and `degree` (one number or three; default
/// `min(dims − 1, 3)`, each in `1..=dims − 1`) of a lattice object.
fn dims_and_degrees(o: &Map<String, Value>) -> Result<([usize; 3], [usize; 3])> {
    let dims_v = o
        .get("dims")
        .ok_or_else(|| err("lattice", "no \"dims\" field"))?;
    let dims = uints3(dims_v, "lattice.dims")?;
    for (d, &n) in dims.iter().enumerate() {
        if !(2..=256).contains(&n) {
            return Err(err(
                &format!("lattice.dims[{d}]"),
                format!("{n} control points is outside 2..=256"),
            ));
        }
    }
    let degrees = match o.get("degree") {
        None => dims.map(|n| (n - 1).min(3)),
        Some(Value::Array(_)) => uints3(&o["degree"], "lattice.degree")?,
        Some(x) => {
            let d = uint(x, "lattice.degree")?;
            [d; 3]
        }
    };
    for d in 0..3 {
        if degrees[d] == 0 || degrees[d] >= dims[d] {
            return Err(err(
                "lattice.degree",
                format!(
                    "{} along axis {d} is outside 1..={} (dims[{d}] − 1)",
                    degrees[d],
                    dims[d] - 1
                ),
            ));
        }
    }
    Ok((dims, degrees))
}

/// Add each of `moves`' offsets to its control point.
fn apply_moves(lat: &mut Lattice, moves: &Value, dims: [usize; 3]) -> Result<()> {
    let list = moves
        .as_array()
        .ok_or_else(|| err("lattice.moves", "not an array"))?;
    for (n, mv) in list.iter().enumerate() {
        let place = format!("lattice.moves[{n}]");
        let mo = mv
            .as_object()
            .ok_or_else(|| err(&place, "not an object with index and offset"))?;
        let idx_v = mo.get("index").ok_or_else(|| err(&place, "no \"index\""))?;
        let idx = uints3(idx_v, &format!("{place}.index"))?;
        for d in 0..3 {
            if idx[d] >= dims[d] {
                return Err(err(
                    &format!("{place}.index"),
                    format!("{} is outside 0..{} (dims[{d}])", idx[d], dims[d]),
                ));
            }
        }
        let off = vec3(mo, "offset", &place)?;
        let p = lat.point_mut(idx)?;
        for d in 0..3 {
            p[d] += off[d];
        }
    }
    Ok(())
}

const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Axis-aligned bounding box of a mesh's vertices.
pub fn bounds(mesh: &Mesh) -> Result<([f64; 3], [f64; 3])> {
    if mesh.positions.is_empty() {
        return Err(Error::parameter("mesh", "no vertices", "a non-empty mesh"));
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &mesh.positions {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    Ok((lo, hi))
}

fn err(place: &str, msg: impl std::fmt::Display) -> Error {
    Error::format(
        format!("{place}: {msg}"),
        "a valid lattice (see docs/solid.md)",
    )
}

fn uint(v: &Value, place: &str) -> Result<usize> {
    v.as_u64()
        .map(|x| x as usize)
        .ok_or_else(|| err(place, format!("{v} is not a non-negative integer")))
}

fn uints3(v: &Value, place: &str) -> Result<[usize; 3]> {
    let a = v
        .as_array()
        .filter(|a| a.len() == 3)
        .ok_or_else(|| err(place, "not an array of three integers"))?;
    Ok([
        uint(&a[0], &format!("{place}[0]"))?,
        uint(&a[1], &format!("{place}[1]"))?,
        uint(&a[2], &format!("{place}[2]"))?,
    ])
}

fn to_vec3(v: &Value, place: &str) -> Result<[f64; 3]> {
    finite3(v).map_err(|e| match e {
        None => err(place, "not an array of three numbers"),
        Some(d) => err(
            &format!("{place}[{d}]"),
            format!("{} is not a number", v[d]),
        ),
    })
}

fn vec3(o: &Map<String, Value>, key: &str, place: &str) -> Result<[f64; 3]> {
    let v = o
        .get(key)
        .ok_or_else(|| err(place, format!("no \"{key}\"")))?;
    to_vec3(v, &format!("{place}.{key}"))
}
