//! Sharp features for subdivision (§8.2.4, §8.3.3): edges tagged sharp and vertices tagged as
//! corners. Boundary edges are always sharp, so the boundary follows the cubic B-spline curve
//! rules (§8.2.3, §8.3.2). A vertex's rule follows from its number of sharp edges:
//!
//! ```text
//!   sharp edges   rule      position of the vertex point
//!   0 or 1        smooth    the scheme's interior mask (a single sharp edge is a "dart")
//!   2             crease    cubic B-spline curve mask  ¾ v + ⅛ (a + b), a, b its sharp neighbours
//!   3 or more     corner    fixed: v
//! ```
//!
//! Vertices tagged as corners are fixed whatever their edges. Sharp edges split into two sharp
//! child edges; the schemes return the child tags with the refined mesh.
//!
//! Sidecar file format (`--creases FILE`): one item per line, `#` comments; `a b` tags the edge
//! between vertices `a` and `b` (0-based) sharp; `corner v` tags vertex `v` as a corner.

use super::halfedge::{HalfEdgeMesh, VertexId};
use super::{vec3, Mesh, NONE};
use crate::{Error, Result};

/// Sharp edges (as vertex pairs) and corner vertices of a mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Features {
    pub sharp_edges: Vec<[u32; 2]>,
    pub corners: Vec<u32>,
}

/// The rule applied at a vertex (see the module table).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VertexRule {
    Smooth,
    /// Two sharp edges, to these neighbours.
    Crease(u32, u32),
    Corner,
}

impl VertexRule {
    /// The new position of vertex `v` (positions `p`) under a corner or crease rule,
    /// shared by Catmull–Clark and Loop: a corner stays, a crease vertex between
    /// neighbours `a`, `b` moves to `¾ v + ⅛ (a + b)` (the cubic B-spline curve's vertex
    /// mask, §8.3.2–8.3.3); `None` for a smooth vertex (the scheme's own mask).
    #[inline]
    pub fn sharp_point(self, p: &[[f64; 3]], v: usize) -> Option<[f64; 3]> {
        let pv = p[v];
        match self {
            VertexRule::Corner => Some(pv),
            VertexRule::Crease(a, b) => {
                let (a, b) = (p[a as usize], p[b as usize]);
                Some(std::array::from_fn(|k| {
                    0.75 * pv[k] + 0.125 * (a[k] + b[k])
                }))
            }
            VertexRule::Smooth => None,
        }
    }
}

/// The new point of a sharp (crease or boundary) edge `(a, b)`: its midpoint `½ (a + b)`
/// (the cubic B-spline curve's edge mask), shared by Catmull–Clark and Loop.
#[inline]
pub fn sharp_edge_point(pa: [f64; 3], pb: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| 0.5 * (pa[k] + pb[k]))
}

/// Features resolved against a half-edge structure: per edge and per vertex flags.
#[derive(Clone, Debug)]
pub struct Tags {
    /// Per edge: sharp (boundary edges included).
    pub sharp: Vec<bool>,
    /// Per vertex: tagged corner.
    pub corner: Vec<bool>,
    /// True when some interior edge is sharp (so child tags must be produced).
    pub any_interior_sharp: bool,
}

impl Features {
    pub fn is_empty(&self) -> bool {
        self.sharp_edges.is_empty() && self.corners.is_empty()
    }

    /// Parse the sidecar format described in the module doc.
    pub fn parse(text: &str) -> Result<Features> {
        let mut f = Features::default();
        for (i, line) in text.lines().enumerate() {
            let l = line.split('#').next().unwrap_or("").trim();
            if l.is_empty() {
                continue;
            }
            let t: Vec<&str> = l.split_whitespace().collect();
            let num = |s: &str| {
                s.parse::<u32>().map_err(|_| {
                    Error::format(
                        format!("line {}: {s:?} is not a vertex index", i + 1),
                        "a vertex index",
                    )
                })
            };
            match t.as_slice() {
                ["corner", v] => f.corners.push(num(v)?),
                [a, b] => f.sharp_edges.push([num(a)?, num(b)?]),
                _ => {
                    return Err(Error::format(
                        format!("line {}: {l:?}", i + 1),
                        "`a b` (sharp edge) or `corner v`",
                    ))
                }
            }
        }
        Ok(f)
    }

    /// Tag as sharp every interior edge whose dihedral angle (between the two face normals)
    /// exceeds `degrees`.
    pub fn from_crease_angle(mesh: &Mesh, he: &HalfEdgeMesh, degrees: f64) -> Result<Features> {
        if !(0.0..=180.0).contains(&degrees) {
            return Err(Error::parameter(
                "crease angle",
                degrees,
                "degrees in [0, 180]",
            ));
        }
        let normals = super::normals::face_normals(mesh);
        let cos_limit = degrees.to_radians().cos();
        let mut f = Features::default();
        for e in 0..he.edge_count() {
            let [c0, c1] = he.edges.corners[e];
            if c1 == NONE {
                continue;
            }
            let n0 = normals[he.face[c0 as usize] as usize];
            let n1 = normals[he.face[c1 as usize] as usize];
            if vec3::dot(n0, n1) < cos_limit {
                f.sharp_edges.push(he.edges.verts[e]);
            }
        }
        Ok(f)
    }

    /// Resolve the vertex pairs to edges of `he`.
    pub fn resolve(&self, he: &HalfEdgeMesh) -> Result<Tags> {
        let mut sharp: Vec<bool> = he.edges.uses.iter().map(|&u| u == 1).collect();
        let mut corner = vec![false; he.vertex_count()];
        let nv = he.vertex_count() as u32;
        let mut any_interior_sharp = false;
        for &[a, b] in &self.sharp_edges {
            if a >= nv || b >= nv {
                return Err(Error::parameter(
                    "sharp edge",
                    format!("({a}, {b})"),
                    "vertex indices of the mesh",
                ));
            }
            let h = he.find_halfedge(VertexId(a), VertexId(b)).ok_or_else(|| {
                Error::parameter(
                    "sharp edge",
                    format!("({a}, {b})"),
                    "a pair of vertices joined by an edge",
                )
            })?;
            let e = he.edge[h.idx()] as usize;
            if he.edges.uses[e] == 2 {
                any_interior_sharp = true;
            }
            sharp[e] = true;
        }
        for &v in &self.corners {
            if v >= nv {
                return Err(Error::parameter(
                    "corner vertex",
                    v,
                    "a vertex index of the mesh",
                ));
            }
            corner[v as usize] = true;
        }
        Ok(Tags {
            sharp,
            corner,
            any_interior_sharp,
        })
    }
}

impl Tags {
    /// Only the boundary edges sharp.
    pub fn boundary_only(he: &HalfEdgeMesh) -> Tags {
        Tags {
            sharp: he.edges.uses.iter().map(|&u| u == 1).collect(),
            corner: vec![false; he.vertex_count()],
            any_interior_sharp: false,
        }
    }

    /// The rule at vertex `v` (see the module table).
    #[inline]
    pub fn rule(&self, he: &HalfEdgeMesh, v: u32) -> VertexRule {
        if self.corner[v as usize] {
            return VertexRule::Corner;
        }
        let mut k = 0;
        let mut nb = [0u32; 2];
        for h in he.outgoing(VertexId(v)) {
            if self.sharp[he.edge[h.idx()] as usize] {
                if k < 2 {
                    nb[k] = he.from[he.twin[h.idx()] as usize];
                }
                k += 1;
            }
        }
        match k {
            0 | 1 => VertexRule::Smooth,
            2 => VertexRule::Crease(nb[0], nb[1]),
            _ => VertexRule::Corner,
        }
    }

    /// Child tags after a step that numbers the point of edge `e` as `edge_base + e` and keeps
    /// the old vertex numbers (Loop, Catmull-Clark, Butterfly).
    pub fn children(&self, he: &HalfEdgeMesh, edge_base: u32) -> Features {
        let mut f = Features::default();
        for (e, &s) in self.sharp.iter().enumerate() {
            if s && he.edges.uses[e] == 2 {
                let [a, b] = he.edges.verts[e];
                let m = edge_base + e as u32;
                f.sharp_edges.push([a, m]);
                f.sharp_edges.push([m, b]);
            }
        }
        f.corners = (0..self.corner.len() as u32)
            .filter(|&v| self.corner[v as usize])
            .collect();
        f
    }
}
