//! The half-edge data structure of §6.7.2, built from a face-vertex list in O(n).
//!
//! Layout (flat `Vec<u32>`s, no per-element allocation):
//! - half-edges `0 .. C` are the corners of the face-vertex list: half-edge `offsets[f] + i`
//!   runs from face `f`'s vertex `i` to vertex `i + 1`, so `face` and `next` of interior
//!   half-edges follow from the offsets;
//! - half-edges `C .. C + B` are *boundary* half-edges (no face), one per boundary edge, running
//!   opposite to its interior half-edge and linked head to tail around each hole, so every
//!   half-edge has a twin and walking `next(twin(h))` around a vertex never stops early;
//! - twins come from the edge table ([`super::Edges`], built in O(n));
//! - `vert_out[v]` is an outgoing half-edge of `v`, the boundary one when `v` is on a boundary.
//!
//! Building fails with a message naming the edge or vertex when the mesh is not an oriented
//! 2-manifold (with boundary): an edge in three or more faces, an edge traversed in the same
//! direction by both its faces, or a vertex whose faces form more than one fan.

use super::edges::Edges;
use super::{Mesh, NONE};
use crate::{Error, Result};

macro_rules! handle {
    ($(#[$m:meta])* $name:ident) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(pub u32);
        impl $name {
            #[inline]
            pub fn idx(self) -> usize {
                self.0 as usize
            }
        }
    };
}

handle!(
    /// A vertex handle.
    VertexId
);
handle!(
    /// A half-edge handle.
    HalfedgeId
);
handle!(
    /// An undirected edge handle.
    EdgeId
);
handle!(
    /// A face handle.
    FaceId
);

/// Half-edge connectivity of a mesh (positions stay in the [`Mesh`]).
#[derive(Clone, Debug)]
pub struct HalfEdgeMesh {
    /// Origin vertex of each half-edge.
    pub from: Vec<u32>,
    pub next: Vec<u32>,
    pub prev: Vec<u32>,
    pub twin: Vec<u32>,
    /// Face of each half-edge, `NONE` for boundary half-edges.
    pub face: Vec<u32>,
    /// Undirected edge of each half-edge (index into `edges`).
    pub edge: Vec<u32>,
    /// One outgoing half-edge per vertex (the boundary one on a boundary); `NONE` if isolated.
    pub vert_out: Vec<u32>,
    /// Face `f`'s half-edges are `offsets[f] .. offsets[f + 1]`.
    pub offsets: Vec<u32>,
    /// Number of interior half-edges (= corners).
    pub corners: usize,
    pub edges: Edges,
}

impl HalfEdgeMesh {
    /// Build the half-edge structure of `mesh`; see the module doc for the failure cases.
    pub fn build(mesh: &Mesh) -> Result<HalfEdgeMesh> {
        let edges = Edges::build(mesh);
        Self::from_edges(mesh, edges)
    }

    /// Build from an already computed edge table of `mesh`.
    pub fn from_edges(mesh: &Mesh, edges: Edges) -> Result<HalfEdgeMesh> {
        let nc = mesh.indices.len();
        let nv = mesh.positions.len();
        let nb = boundary_edges(mesh, &edges)?;
        let nh = nc + nb;
        let mut from = Vec::with_capacity(nh);
        from.extend_from_slice(&mesh.indices);
        let mut next = vec![0u32; nh];
        let mut prev = vec![0u32; nh];
        let mut face = vec![NONE; nh];
        let mut edge = Vec::with_capacity(nh);
        edge.extend_from_slice(&edges.corner_edge);
        let mut twin = vec![NONE; nh];
        for f in 0..mesh.face_count() {
            let (s, e) = (mesh.offsets[f] as usize, mesh.offsets[f + 1] as usize);
            for c in s..e {
                let n = if c + 1 == e { s } else { c + 1 };
                next[c] = n as u32;
                prev[n] = c as u32;
                face[c] = f as u32;
            }
        }
        // twins, and boundary half-edges appended after the corners
        let mut boundary_out = vec![NONE; nv];
        for e in 0..edges.len() {
            let [c0, c1] = edges.corners[e];
            if c1 != NONE {
                twin[c0 as usize] = c1;
                twin[c1 as usize] = c0;
            } else {
                let h = from.len() as u32;
                let c0 = c0 as usize;
                // boundary half-edge runs from the head of corner c0 to its tail
                let head = mesh.indices[next[c0] as usize];
                from.push(head);
                edge.push(e as u32);
                twin[c0] = h;
                twin[h as usize] = c0 as u32;
                if boundary_out[head as usize] != NONE {
                    return Err(Error::format(
                        format!("non-manifold vertex {head}: it lies on two separate boundary loops or fans"),
                        "a manifold mesh (the faces around each vertex form one fan)",
                    ));
                }
                boundary_out[head as usize] = h;
            }
        }
        for h in nc..nh {
            let to = from[twin[h] as usize] as usize;
            let n = boundary_out[to];
            next[h] = n;
            prev[n as usize] = h as u32;
        }
        let mut vert_out = vec![NONE; nv];
        for c in 0..nc {
            vert_out[from[c] as usize] = c as u32;
        }
        for v in 0..nv {
            if boundary_out[v] != NONE {
                vert_out[v] = boundary_out[v];
            }
        }
        let he = HalfEdgeMesh {
            from,
            next,
            prev,
            twin,
            face,
            edge,
            vert_out,
            offsets: mesh.offsets.clone(),
            corners: nc,
            edges,
        };
        he.check_vertex_fans()?;
        Ok(he)
    }

    #[allow(clippy::needless_range_loop)]
    /// Every outgoing half-edge of a vertex must be reached by rotating around it once.
    fn check_vertex_fans(&self) -> Result<()> {
        let nv = self.vert_out.len();
        let mut out_count = vec![0u32; nv];
        for &v in &self.from {
            out_count[v as usize] += 1;
        }
        use rayon::prelude::*;
        let bad = (0..nv).into_par_iter().with_min_len(4096).find_first(|&v| {
            let start = self.vert_out[v];
            if start == NONE {
                return false;
            }
            let mut h = start;
            let mut k = 0u32;
            loop {
                k += 1;
                h = self.next[self.twin[h as usize] as usize];
                if h == start || k > out_count[v] {
                    break;
                }
            }
            k != out_count[v]
        });
        if let Some(v) = bad {
            return Err(Error::format(
                format!("non-manifold vertex {v}: its faces form more than one fan"),
                "a manifold mesh (the faces around each vertex form one fan)",
            ));
        }
        Ok(())
    }

    pub fn halfedge_count(&self) -> usize {
        self.from.len()
    }

    pub fn vertex_count(&self) -> usize {
        self.vert_out.len()
    }

    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    pub fn face_count(&self) -> usize {
        self.offsets.len() - 1
    }

    #[inline]
    pub fn next(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(self.next[h.idx()])
    }

    #[inline]
    pub fn prev(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(self.prev[h.idx()])
    }

    #[inline]
    pub fn twin(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(self.twin[h.idx()])
    }

    #[inline]
    pub fn from_vertex(&self, h: HalfedgeId) -> VertexId {
        VertexId(self.from[h.idx()])
    }

    #[inline]
    pub fn to_vertex(&self, h: HalfedgeId) -> VertexId {
        VertexId(self.from[self.twin[h.idx()] as usize])
    }

    #[inline]
    pub fn face(&self, h: HalfedgeId) -> Option<FaceId> {
        let f = self.face[h.idx()];
        (f != NONE).then_some(FaceId(f))
    }

    #[inline]
    pub fn edge(&self, h: HalfedgeId) -> EdgeId {
        EdgeId(self.edge[h.idx()])
    }

    #[inline]
    pub fn is_boundary_halfedge(&self, h: HalfedgeId) -> bool {
        h.idx() >= self.corners
    }

    /// True when the vertex lies on a boundary (or is isolated).
    #[inline]
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        let h = self.vert_out[v.idx()];
        h == NONE || h as usize >= self.corners
    }

    #[inline]
    pub fn is_boundary_edge(&self, e: EdgeId) -> bool {
        self.edges.uses[e.idx()] == 1
    }

    /// Outgoing half-edges of `v` in rotation order, starting at the boundary one if any.
    #[inline]
    pub fn outgoing(&self, v: VertexId) -> Outgoing<'_> {
        let start = self.vert_out[v.idx()];
        Outgoing {
            he: self,
            start,
            cur: start,
        }
    }

    /// Number of edges at `v`.
    pub fn valence(&self, v: VertexId) -> usize {
        self.outgoing(v).count()
    }

    /// Half-edges of face `f`.
    pub fn face_halfedges(&self, f: FaceId) -> impl Iterator<Item = HalfedgeId> {
        (self.offsets[f.idx()]..self.offsets[f.idx() + 1]).map(HalfedgeId)
    }

    /// The half-edge from `a` to `b`, if there is one.
    pub fn find_halfedge(&self, a: VertexId, b: VertexId) -> Option<HalfedgeId> {
        self.outgoing(a).find(|&h| self.to_vertex(h) == b)
    }

    /// The boundary loops, each as its list of boundary half-edges in order.
    pub fn boundary_loops(&self) -> Vec<Vec<HalfedgeId>> {
        let nh = self.halfedge_count();
        let mut seen = vec![false; nh - self.corners];
        let mut loops = Vec::new();
        for h0 in self.corners..nh {
            if seen[h0 - self.corners] {
                continue;
            }
            let mut l = Vec::new();
            let mut h = h0;
            while !seen[h - self.corners] {
                seen[h - self.corners] = true;
                l.push(HalfedgeId(h as u32));
                h = self.next[h] as usize;
            }
            loops.push(l);
        }
        loops
    }
}

/// The number of boundary edges; an error on an edge in more than two faces or traversed in
/// the same direction by both of its faces.
fn boundary_edges(mesh: &Mesh, edges: &Edges) -> Result<usize> {
    let mut nb = 0usize;
    for e in 0..edges.len() {
        let [a, b] = edges.verts[e];
        match edges.uses[e] {
            1 => nb += 1,
            2 => {
                let [c0, c1] = edges.corners[e];
                if mesh.indices[c0 as usize] == mesh.indices[c1 as usize] {
                    return Err(Error::format(
                        format!(
                            "edge ({a}, {b}) is traversed in the same direction by faces {} and {}",
                            edges.corner_face[c0 as usize], edges.corner_face[c1 as usize]
                        ),
                        "consistently oriented faces (try `mra mesh orient`)",
                    ));
                }
            }
            n => {
                return Err(Error::format(
                    format!("non-manifold edge ({a}, {b}): used by {n} faces"),
                    "a manifold mesh (each edge in one or two faces)",
                ))
            }
        }
    }
    Ok(nb)
}

/// Iterator over the outgoing half-edges of a vertex.
pub struct Outgoing<'a> {
    he: &'a HalfEdgeMesh,
    start: u32,
    cur: u32,
}

impl Iterator for Outgoing<'_> {
    type Item = HalfedgeId;
    #[inline]
    fn next(&mut self) -> Option<HalfedgeId> {
        if self.cur == NONE {
            return None;
        }
        let h = self.cur;
        let n = self.he.next[self.he.twin[h as usize] as usize];
        self.cur = if n == self.start { NONE } else { n };
        Some(HalfedgeId(h))
    }
}
