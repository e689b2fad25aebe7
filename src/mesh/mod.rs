//! Polygon meshes (notes ch. 6) and subdivision surfaces (notes ch. 8).
//!
//! ```text
//! mod.rs            Mesh: the face-vertex list (§6.7.1), flat storage: positions, offsets, indices
//! attributes.rs     per-vertex / per-face properties kept through I/O (normals, colours, PLY extras)
//! edges.rs          undirected edge table built in O(n) (corner → edge, edge → faces)
//! halfedge.rs       half-edge structure with typed handles and boundary half-edges (§6.7.2)
//! io/               obj.rs, ply.rs, off.rs, and `io::read` / `io::write` choosing by extension
//! topology.rs       components, boundary loops, manifoldness, orientability, χ and genus (§6.2–6.5)
//! normals.rs        face and vertex normals (uniform, area, angle weighted) (§6.6.1)
//! laplacian.rs      uniform and cotangent Laplacian, explicit and implicit smoothing (§6.6.2)
//! sparse.rs         CSR matrices and conjugate gradients (for implicit smoothing)
//! simplify.rs       edge collapse with the link condition, quadric error simplification (§6.6.3)
//! subdivide.rs      Scheme and the multi-step driver
//! shapes.rs         generated meshes: cube, tetrahedron, octahedron, torus, quad grid, sphere
//! features.rs       sharp edges and corners: sidecar files, dihedral angle, vertex rules (§8.2.4)
//! loop.rs  catmull_clark.rs  doo_sabin.rs  butterfly.rs   the schemes of ch. 8
//! adaptive.rs       incremental adaptive Loop / Catmull-Clark (Pakdel–Samavati, §8.5)
//! analysis.rs       eigenvalues of local subdivision matrices (§7.5.1)
//! render.rs         a small z-buffer rasteriser writing shaded PNG pictures
//! ```

pub mod adaptive;
pub mod analysis;
pub mod attributes;
pub mod butterfly;
pub mod catmull_clark;
pub mod doo_sabin;
pub mod edges;
pub mod features;
pub mod halfedge;
pub mod io;
pub mod laplacian;
#[path = "loop.rs"]
pub mod loop_subdivision;
pub mod normals;
pub mod render;
pub mod shapes;
pub mod simplify;
pub mod sparse;
pub mod subdivide;
pub mod topology;

pub use attributes::{Attributes, Property};
pub use edges::Edges;
pub use features::Features;
pub use halfedge::{EdgeId, FaceId, HalfEdgeMesh, HalfedgeId, VertexId};

use crate::{Error, Result};

/// Marks an absent index (no face on a boundary half-edge, no second face of an edge, …).
pub const NONE: u32 = u32::MAX;

/// The face-vertex list of §6.7.1: vertex positions and, for each face, its vertex indices in
/// counter-clockwise order. Faces are stored flat: face `f` is
/// `indices[offsets[f] .. offsets[f + 1]]`, so `offsets.len() == face_count() + 1`.
/// The position of face `f`'s `i`-th vertex in `indices` is its *corner* `offsets[f] + i`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<[f64; 3]>,
    pub offsets: Vec<u32>,
    pub indices: Vec<u32>,
    /// Extra data kept through I/O; operations that change connectivity drop it.
    pub attributes: Attributes,
}

/// Faces given to [`Mesh::from_faces`]: a list of index lists, or flat indices with offsets.
pub enum Faces {
    Lists(Vec<Vec<u32>>),
    Flat {
        indices: Vec<u32>,
        offsets: Vec<u32>,
    },
    /// All faces have the same degree (3 for triangles, 4 for quads).
    Uniform {
        indices: Vec<u32>,
        degree: usize,
    },
}

impl From<Vec<Vec<u32>>> for Faces {
    fn from(v: Vec<Vec<u32>>) -> Self {
        Faces::Lists(v)
    }
}

impl From<Vec<[u32; 3]>> for Faces {
    fn from(v: Vec<[u32; 3]>) -> Self {
        Faces::Uniform {
            indices: v.into_iter().flatten().collect(),
            degree: 3,
        }
    }
}

impl From<Vec<[u32; 4]>> for Faces {
    fn from(v: Vec<[u32; 4]>) -> Self {
        Faces::Uniform {
            indices: v.into_iter().flatten().collect(),
            degree: 4,
        }
    }
}

impl Mesh {
    /// Build a mesh from positions and faces, checking that every index is in range, every face
    /// has at least three distinct-in-sequence vertices, and every coordinate is finite.
    ///
    /// ```
    /// use mra::mesh::Mesh;
    /// let m = Mesh::from_faces(
    ///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
    ///     vec![[0u32, 1, 2]],
    /// ).unwrap();
    /// assert_eq!(m.face_count(), 1);
    /// ```
    pub fn from_faces(positions: Vec<[f64; 3]>, faces: impl Into<Faces>) -> Result<Mesh> {
        let (indices, offsets) = match faces.into() {
            Faces::Lists(lists) => {
                let mut offsets = Vec::with_capacity(lists.len() + 1);
                let mut indices = Vec::with_capacity(lists.iter().map(|f| f.len()).sum());
                offsets.push(0u32);
                for f in &lists {
                    indices.extend_from_slice(f);
                    offsets.push(indices.len() as u32);
                }
                (indices, offsets)
            }
            Faces::Flat { indices, offsets } => (indices, offsets),
            Faces::Uniform { indices, degree } => {
                if degree < 3 || indices.len() % degree != 0 {
                    return Err(Error::parameter(
                        "face degree",
                        degree,
                        "≥ 3 and dividing the index count",
                    ));
                }
                let offsets = (0..=indices.len() / degree)
                    .map(|i| (i * degree) as u32)
                    .collect();
                (indices, offsets)
            }
        };
        Mesh::checked(positions, offsets, indices, Attributes::default())
    }

    /// A mesh whose faces all have `degree` corners: face `f` is
    /// `indices[degree·f .. degree·(f+1)]`.
    pub fn of_degree(positions: Vec<[f64; 3]>, indices: Vec<u32>, degree: u32) -> Mesh {
        let faces = indices.len() as u32 / degree;
        Mesh {
            positions,
            offsets: (0..=faces).map(|f| degree * f).collect(),
            indices,
            attributes: Attributes::default(),
        }
    }

    /// A mesh from its parts, after [`Mesh::validate`].
    pub fn checked(
        positions: Vec<[f64; 3]>,
        offsets: Vec<u32>,
        indices: Vec<u32>,
        attributes: Attributes,
    ) -> Result<Mesh> {
        let mesh = Mesh {
            positions,
            offsets,
            indices,
            attributes,
        };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Check the invariants of the face-vertex list (see [`Mesh::from_faces`]).
    pub fn validate(&self) -> Result<()> {
        if self.indices.len() > u32::MAX as usize - 1
            || self.positions.len() > u32::MAX as usize - 1
        {
            return Err(Error::LimitsExceeded {
                what: "mesh size",
                requested: self.indices.len().max(self.positions.len()) as u64,
                limit: u32::MAX as u64 - 1,
            });
        }
        if self.offsets.first() != Some(&0)
            || *self.offsets.last().unwrap() as usize != self.indices.len()
        {
            return Err(Error::format(
                format!(
                    "face offsets start at {:?} and end at {:?} for {} indices",
                    self.offsets.first(),
                    self.offsets.last(),
                    self.indices.len()
                ),
                "offsets from 0 to the index count",
            ));
        }
        for (i, p) in self.positions.iter().enumerate() {
            if !p.iter().all(|x| x.is_finite()) {
                return Err(Error::format(
                    format!("vertex {i} has coordinates {p:?}"),
                    "finite coordinates",
                ));
            }
        }
        let nv = self.positions.len() as u32;
        for f in 0..self.face_count() {
            let face = self.face(f);
            if face.len() < 3 {
                return Err(Error::format(
                    format!("face {f} has {} vertices", face.len()),
                    "at least 3 vertices per face",
                ));
            }
            for (i, &v) in face.iter().enumerate() {
                if v >= nv {
                    return Err(Error::format(
                        format!("face {f} refers to vertex {v} but there are {nv} vertices"),
                        "vertex indices in range",
                    ));
                }
                if face[(i + 1) % face.len()] == v {
                    return Err(Error::format(
                        format!("face {f} repeats vertex {v} on consecutive corners"),
                        "faces without zero-length edges",
                    ));
                }
            }
        }
        Ok(())
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn face_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Number of corners (Σ deg f), which is also the number of interior half-edges.
    pub fn corner_count(&self) -> usize {
        self.indices.len()
    }

    /// Vertex indices of face `f`.
    #[inline]
    pub fn face(&self, f: usize) -> &[u32] {
        &self.indices[self.offsets[f] as usize..self.offsets[f + 1] as usize]
    }

    #[inline]
    pub fn face_degree(&self, f: usize) -> usize {
        (self.offsets[f + 1] - self.offsets[f]) as usize
    }

    /// Iterator over the faces as index slices.
    pub fn faces(&self) -> impl Iterator<Item = &[u32]> + '_ {
        self.offsets
            .windows(2)
            .map(move |w| &self.indices[w[0] as usize..w[1] as usize])
    }

    /// True when every face is a triangle.
    pub fn is_triangle_mesh(&self) -> bool {
        self.indices.len() == 3 * self.face_count()
    }

    /// True when every face is a quadrilateral.
    pub fn is_quad_mesh(&self) -> bool {
        self.indices.len() == 4 * self.face_count()
    }

    /// Axis-aligned bounding box (min, max); `None` for an empty mesh.
    pub fn bounding_box(&self) -> Option<([f64; 3], [f64; 3])> {
        let first = *self.positions.first()?;
        let mut lo = first;
        let mut hi = first;
        for p in &self.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Some((lo, hi))
    }

    /// Reverse the orientation of face `f` (keeps its first vertex).
    pub fn flip_face(&mut self, f: usize) {
        let (a, b) = (self.offsets[f] as usize, self.offsets[f + 1] as usize);
        self.indices[a + 1..b].reverse();
    }

    /// Split every polygon into a fan of triangles from its first vertex.
    pub fn triangulated(&self) -> Mesh {
        let mut idx = Vec::with_capacity(3 * (self.indices.len() - 2 * self.face_count()));
        for f in self.faces() {
            for i in 1..f.len() - 1 {
                idx.extend_from_slice(&[f[0], f[i], f[i + 1]]);
            }
        }
        let n = idx.len() / 3;
        Mesh {
            positions: self.positions.clone(),
            offsets: (0..=n as u32).map(|i| 3 * i).collect(),
            indices: idx,
            attributes: Attributes::default(),
        }
    }
}

/// Small vector helpers of the geometry modules (meshes, surfaces, solids): the one copy.
pub mod vec3 {
    #[inline]
    pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }
    #[inline]
    pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
    #[inline]
    pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
        [a[0] * s, a[1] * s, a[2] * s]
    }
    #[inline]
    pub fn axpy(acc: &mut [f64; 3], s: f64, a: [f64; 3]) {
        acc[0] += s * a[0];
        acc[1] += s * a[1];
        acc[2] += s * a[2];
    }
    #[inline]
    pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    #[inline]
    pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    #[inline]
    pub fn norm(a: [f64; 3]) -> f64 {
        dot(a, a).sqrt()
    }
    #[inline]
    pub fn normalized(a: [f64; 3]) -> [f64; 3] {
        let n = norm(a);
        if n > 0.0 {
            scale(a, 1.0 / n)
        } else {
            [0.0; 3]
        }
    }
}
