//! Topology of a face-vertex list (§6.2–6.5), computed on the undirected edge table so it works
//! for any input: connected components, boundary loops, manifoldness (edges in at most two
//! faces, the faces around each vertex forming a single fan), orientability with consistent
//! re-orientation, and per component the Euler characteristic χ = V − E + F and the genus from
//! χ = 2 − 2g − b (b = number of boundary loops; orientable components only).

use super::edges::Edges;
use super::{Mesh, NONE};
use crate::{Error, Result};
use serde::Serialize;
use std::collections::BTreeMap;

/// Disjoint sets with path halving and union by size.
pub(crate) struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    pub fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }
    #[inline]
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = p;
            x = p;
        }
        x
    }
    #[inline]
    pub fn union(&mut self, a: u32, b: u32) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a as usize] < self.size[b as usize] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b as usize] = a;
        self.size[a as usize] += self.size[b as usize];
    }
}

/// One connected component (vertices joined by faces).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Component {
    pub vertices: usize,
    pub edges: usize,
    pub faces: usize,
    pub boundary_loops: usize,
    /// χ = V − E + F.
    pub euler: i64,
    pub orientable: bool,
    /// From χ = 2 − 2g − b; `None` for non-orientable components.
    pub genus: Option<i64>,
}

/// Everything `mra mesh info` reports.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub vertices: usize,
    pub edges: usize,
    pub faces: usize,
    /// Face degree → number of faces.
    pub face_degrees: BTreeMap<usize, usize>,
    pub isolated_vertices: usize,
    pub components: Vec<Component>,
    pub boundary_edges: usize,
    pub boundary_loops: usize,
    /// χ of the whole mesh (isolated vertices excluded).
    pub euler: i64,
    /// Sum of the component genera when every component is orientable.
    pub genus: Option<i64>,
    pub manifold: bool,
    /// Edges in three or more faces.
    pub non_manifold_edges: Vec<[u32; 2]>,
    /// Vertices whose faces form more than one fan.
    pub non_manifold_vertices: Vec<u32>,
    pub orientable: bool,
    /// True when the faces are already consistently oriented.
    pub oriented: bool,
    pub closed: bool,
    pub bounding_box: Option<([f64; 3], [f64; 3])>,
}

#[inline]
fn next_corner(mesh: &Mesh, f: u32, c: u32) -> u32 {
    if c + 1 == mesh.offsets[f as usize + 1] {
        mesh.offsets[f as usize]
    } else {
        c + 1
    }
}

/// For every face, +1 or −1 so that flipping the −1 faces orients each component
/// consistently; `Err(edge)` names an edge where orientation fails (non-orientable).
pub fn orientation_signs(mesh: &Mesh, edges: &Edges) -> std::result::Result<Vec<i8>, usize> {
    let mut bad = None;
    let sign = propagate_signs(mesh, edges, |e, _| {
        bad.get_or_insert(e);
    });
    match bad {
        Some(e) => Err(e),
        None => Ok(sign),
    }
}

/// The orientation search: from each face not yet reached, signs spread across the
/// manifold edges (consistent neighbours traverse their shared edge in opposite
/// directions); `conflict(edge, corner)` for every edge whose two faces disagree.
fn propagate_signs(mesh: &Mesh, edges: &Edges, mut conflict: impl FnMut(usize, u32)) -> Vec<i8> {
    let nf = mesh.face_count();
    let mut sign = vec![0i8; nf];
    let mut stack = Vec::new();
    for seed in 0..nf {
        if sign[seed] != 0 {
            continue;
        }
        sign[seed] = 1;
        stack.push(seed as u32);
        while let Some(f) = stack.pop() {
            for c in mesh.offsets[f as usize]..mesh.offsets[f as usize + 1] {
                let e = edges.corner_edge[c as usize] as usize;
                if edges.uses[e] != 2 {
                    continue;
                }
                let o = edges.opposite(e, c);
                let g = edges.corner_face[o as usize] as usize;
                let same_dir = mesh.indices[c as usize] == mesh.indices[o as usize];
                let want = if same_dir {
                    -sign[f as usize]
                } else {
                    sign[f as usize]
                };
                if sign[g] == 0 {
                    sign[g] = want;
                    stack.push(g as u32);
                } else if sign[g] != want {
                    conflict(e, c);
                }
            }
        }
    }
    sign
}

/// Orient every component consistently (flipping faces against each component's first face).
pub fn orient(mesh: &Mesh) -> Result<Mesh> {
    let edges = Edges::build(mesh);
    let signs = orientation_signs(mesh, &edges).map_err(|e| {
        let [a, b] = edges.verts[e];
        Error::format(
            format!("the mesh is not orientable (orientation fails at edge ({a}, {b}))"),
            "an orientable mesh",
        )
    })?;
    let mut out = mesh.clone();
    for (f, &s) in signs.iter().enumerate() {
        if s < 0 {
            out.flip_face(f);
        }
    }
    out.attributes.corner_normal.clear();
    out.attributes.corner_texcoord.clear();
    Ok(out)
}

/// Vertices whose faces form more than one fan (corners joined across manifold edges).
pub fn non_manifold_vertices(mesh: &Mesh, edges: &Edges) -> Vec<u32> {
    let nc = mesh.indices.len();
    let mut uf = UnionFind::new(nc);
    for e in 0..edges.len() {
        if edges.uses[e] != 2 {
            continue;
        }
        let [c0, c1] = edges.corners[e];
        let n0 = next_corner(mesh, edges.corner_face[c0 as usize], c0);
        let n1 = next_corner(mesh, edges.corner_face[c1 as usize], c1);
        if mesh.indices[c0 as usize] == mesh.indices[c1 as usize] {
            uf.union(c0, c1);
            uf.union(n0, n1);
        } else {
            uf.union(c0, n1);
            uf.union(n0, c1);
        }
    }
    let nv = mesh.positions.len();
    let mut root = vec![NONE; nv];
    let mut bad = vec![false; nv];
    for c in 0..nc as u32 {
        let v = mesh.indices[c as usize] as usize;
        let r = uf.find(c);
        if root[v] == NONE {
            root[v] = r;
        } else if root[v] != r {
            bad[v] = true;
        }
    }
    for e in 0..edges.len() {
        if edges.uses[e] > 2 {
            bad[edges.verts[e][0] as usize] = true;
            bad[edges.verts[e][1] as usize] = true;
        }
    }
    (0..nv as u32).filter(|&v| bad[v as usize]).collect()
}

/// Analyse the topology of `mesh`.
pub fn analyze(mesh: &Mesh) -> Report {
    let edges = Edges::build(mesh);
    analyze_with(mesh, &edges)
}

/// [`analyze`] with a precomputed edge table.
pub fn analyze_with(mesh: &Mesh, edges: &Edges) -> Report {
    let nv = mesh.vertex_count();
    let nf = mesh.face_count();
    let mut face_degrees = BTreeMap::new();
    for f in 0..nf {
        *face_degrees.entry(mesh.face_degree(f)).or_insert(0) += 1;
    }
    let (mut comps, vcomp, used) = components(mesh);
    let mut boundary_edges = 0;
    let mut non_manifold_edges = Vec::new();
    // boundary loops: components of the graph of boundary edges
    let mut buf = UnionFind::new(nv);
    let mut on_boundary = vec![false; nv];
    for e in 0..edges.len() {
        let [a, b] = edges.verts[e];
        comps[vcomp[a as usize] as usize].edges += 1;
        match edges.uses[e] {
            1 => {
                boundary_edges += 1;
                buf.union(a, b);
                on_boundary[a as usize] = true;
                on_boundary[b as usize] = true;
            }
            2 => {}
            _ => non_manifold_edges.push([a, b]),
        }
    }
    let mut loop_seen = vec![false; nv];
    let mut boundary_loops = 0;
    for v in 0..nv {
        if on_boundary[v] {
            let r = buf.find(v as u32) as usize;
            if !loop_seen[r] {
                loop_seen[r] = true;
                boundary_loops += 1;
                comps[vcomp[v] as usize].boundary_loops += 1;
            }
        }
    }
    let (orientable, oriented) = match orientation_signs(mesh, edges) {
        Ok(s) => (true, s.iter().all(|&x| x > 0)),
        Err(_) => {
            // find which components fail: the search again, marking the conflicts
            propagate_signs(mesh, edges, |_, c| {
                comps[vcomp[mesh.indices[c as usize] as usize] as usize].orientable = false;
            });
            (false, false)
        }
    };
    let non_manifold_vertices = non_manifold_vertices(mesh, edges);
    let genus_sum = euler_and_genus(&mut comps);
    let manifold = non_manifold_edges.is_empty() && non_manifold_vertices.is_empty();
    Report {
        vertices: nv,
        edges: edges.len(),
        faces: nf,
        face_degrees,
        isolated_vertices: used.iter().filter(|&&u| !u).count(),
        euler: comps.iter().map(|c| c.euler).sum(),
        genus: if manifold { genus_sum } else { None },
        components: comps,
        boundary_edges,
        boundary_loops,
        manifold,
        non_manifold_edges,
        non_manifold_vertices,
        orientable,
        oriented,
        closed: boundary_edges == 0,
        bounding_box: mesh.bounding_box(),
    }
}

/// Components of `mesh` (vertices joined by faces; unused vertices in none), with their vertex
/// and face counts; the component of each vertex (`NONE` when unused) and which vertices are used.
fn components(mesh: &Mesh) -> (Vec<Component>, Vec<u32>, Vec<bool>) {
    let nv = mesh.vertex_count();
    let mut uf = UnionFind::new(nv);
    for f in mesh.faces() {
        for w in 1..f.len() {
            uf.union(f[0], f[w]);
        }
    }
    let mut used = vec![false; nv];
    for &v in &mesh.indices {
        used[v as usize] = true;
    }
    let mut comp_of_root = vec![NONE; nv];
    let mut comps: Vec<Component> = Vec::new();
    let mut vcomp = vec![NONE; nv];
    for v in 0..nv {
        if !used[v] {
            continue;
        }
        let r = uf.find(v as u32) as usize;
        if comp_of_root[r] == NONE {
            comp_of_root[r] = comps.len() as u32;
            comps.push(Component {
                vertices: 0,
                edges: 0,
                faces: 0,
                boundary_loops: 0,
                euler: 0,
                orientable: true,
                genus: None,
            });
        }
        vcomp[v] = comp_of_root[r];
        comps[vcomp[v] as usize].vertices += 1;
    }
    for f in mesh.faces() {
        comps[vcomp[f[0] as usize] as usize].faces += 1;
    }
    (comps, vcomp, used)
}

/// Fill each component's Euler characteristic `χ = V − E + F` and, when orientable, its genus
/// `g = (2 − χ − b)/2` (b boundary loops); the sum of the genera when every one is known.
fn euler_and_genus(comps: &mut [Component]) -> Option<i64> {
    let mut genus_sum = Some(0i64);
    for c in comps.iter_mut() {
        c.euler = c.vertices as i64 - c.edges as i64 + c.faces as i64;
        c.genus = if c.orientable {
            let twice = 2 - c.euler - c.boundary_loops as i64;
            (twice >= 0 && twice % 2 == 0).then_some(twice / 2)
        } else {
            None
        };
        genus_sum = match (genus_sum, c.genus) {
            (Some(a), Some(b)) => Some(a + b),
            _ => None,
        };
    }
    genus_sum
}
