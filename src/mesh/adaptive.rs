//! Adaptive Loop and Catmull-Clark subdivision with the incremental algorithm of Pakdel and
//! Samavati (§8.5.2, §8.5.3): only selected faces are refined, and at every level the
//! selection is grown by one ring of faces so that the selected region is exactly uniform
//! subdivision's, with no cracks and a depth difference of at most one between neighbours.
//!
//! The algorithm keeps one *patch* per level: patch 0 is the input; patch k+1 is the uniform
//! refinement of a region R_k of patch k, with positions computed from patch k. A point of
//! level k+1 is exact (equal to uniform subdivision's) when the stencil it reads lies inside
//! patch k, so R_k is restricted to faces whose vertices are *complete* in patch k (every face
//! around them is in the patch; true mesh boundaries count as complete):
//!
//! ```text
//!   S_0 = selection,  R_k = { faces of patch k sharing a vertex with S_k, all vertices complete }
//!   patch k+1 = children(R_k),  S_{k+1} = children(S_k ∩ R_k)
//! ```
//!
//! Because R_k never touches the border of patch k, children of R_k never meet faces two
//! levels coarser. The output is assembled from the finest level down: faces of patch k not in
//! R_k are kept, each vertex takes the position of its finest incarnation, and faces with
//! T-vertices (edge points of a refined neighbour) are split (§8.5.2–8.5.3):
//!
//! ```text
//!   triangle, T on 1 edge: 2 triangles   2 edges: 3 triangles   3 edges: 4 triangles
//!   quad, T on 2 opposite edges: 2 quads   2 adjacent edges: 3 quads around a new face vertex
//!   quad, T on 1 edge: a quad and a triangle   otherwise: a fan around a new centroid vertex
//! ```

use super::edges::{pair_key, Edges, PairMap};
use super::features::Features;
use super::subdivide::Scheme;
use super::{Attributes, Mesh, NONE};
use crate::{Error, Result};

/// Faces with at least one vertex inside the box `[lo, hi]`.
pub fn faces_in_box(mesh: &Mesh, lo: [f64; 3], hi: [f64; 3]) -> Vec<u32> {
    let inside = |p: &[f64; 3]| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
    (0..mesh.face_count() as u32)
        .filter(|&f| {
            mesh.face(f as usize)
                .iter()
                .any(|&v| inside(&mesh.positions[v as usize]))
        })
        .collect()
}

/// Faces whose area exceeds `threshold` (a simple refinement criterion).
pub fn faces_larger_than(mesh: &Mesh, threshold: f64) -> Vec<u32> {
    (0..mesh.face_count())
        .filter(|&f| super::vec3::norm(super::normals::face_area_vector(mesh, f)) > threshold)
        .map(|f| f as u32)
        .collect()
}

/// One level of the hierarchy.
struct Patch {
    mesh: Mesh,
    /// Sharp edges and true mesh-boundary edges, as vertex pairs of this patch.
    sharp: PairMap<()>,
    boundary: PairMap<()>,
    corner: Vec<bool>,
    /// Faces descending from the selection.
    selected: Vec<bool>,
}

/// What refining patch k produced: the region, and where its vertices and edges went.
struct Step {
    region: Vec<bool>,
    /// Patch-k vertex → its vertex point in patch k+1 (`NONE` outside the region).
    vertex_point: Vec<u32>,
    /// Edge of the region (pair key) → its edge point in patch k+1.
    edge_point: PairMap<u32>,
}

#[inline]
fn is_loop(s: Scheme) -> bool {
    matches!(s, Scheme::Loop(_))
}

/// `steps` levels of adaptive subdivision of the faces `selection` (Loop or Catmull-Clark).
pub fn subdivide(
    mesh: &Mesh,
    scheme: Scheme,
    steps: usize,
    selection: &[u32],
    features: &Features,
) -> Result<Mesh> {
    let weights = match scheme {
        Scheme::Loop(w) => Some(w),
        Scheme::CatmullClark => None,
        other => {
            return Err(Error::Unsupported {
                what: "adaptive subdivision with",
                value: format!("{other:?} (use Loop or Catmull-Clark)"),
            })
        }
    };
    if steps > 12 {
        return Err(Error::parameter("steps", steps, "at most 12"));
    }
    if weights.is_some() && !mesh.is_triangle_mesh() {
        return Err(Error::Unsupported {
            what: "Loop subdivision of faces that are not triangles",
            value: format!("{} faces", mesh.face_count()),
        });
    }
    // the input must be a manifold: building the half-edge structure checks it
    let he = super::HalfEdgeMesh::build(mesh)?;
    let tags = features.resolve(&he)?;
    let mut sharp = PairMap::default();
    let mut boundary = PairMap::default();
    for e in 0..he.edge_count() {
        let [a, b] = he.edges.verts[e];
        if tags.sharp[e] {
            sharp.insert(pair_key(a, b), ());
        }
        if he.edges.uses[e] == 1 {
            boundary.insert(pair_key(a, b), ());
        }
    }
    let mut selected = vec![false; mesh.face_count()];
    for &f in selection {
        if f as usize >= mesh.face_count() {
            return Err(Error::parameter(
                "selected face",
                f,
                "a face index of the mesh",
            ));
        }
        selected[f as usize] = true;
    }
    let mut base = mesh.clone();
    base.attributes = Attributes::default();
    let mut patches = vec![Patch {
        mesh: base,
        sharp,
        boundary,
        corner: tags.corner.clone(),
        selected,
    }];
    let mut steps_done: Vec<Step> = Vec::new();
    for _ in 0..steps {
        let (next, step) = refine(patches.last().unwrap(), scheme, weights)?;
        patches.push(next);
        steps_done.push(step);
    }
    Ok(assemble(&patches, &steps_done, is_loop(scheme)))
}

/// Refine the region of one patch; returns the next patch and the bookkeeping.
fn refine(
    p: &Patch,
    scheme: Scheme,
    weights: Option<super::loop_subdivision::LoopWeights>,
) -> Result<(Patch, Step)> {
    let m = &p.mesh;
    let nf = m.face_count();
    let edges = Edges::build(m);
    let region = region_of(p, &edges);
    let (vstart, vedges) = vertex_edges(&edges, m.vertex_count());
    let r = Refining {
        p,
        edges: &edges,
        vstart: &vstart,
        vedges: &vedges,
    };
    // new numbering: vertex points, edge points, face points (CC)
    let mut new_pos: Vec<[f64; 3]> = Vec::new();
    let mut new_corner = Vec::new();
    let vertex_point = r.vertex_points(&region, weights, &mut new_pos, &mut new_corner);
    let edge_point = r.edge_points(&region, scheme, &mut new_pos, &mut new_corner);
    let mut face_first = vec![NONE; nf];
    if !is_loop(scheme) {
        for f in 0..nf {
            if region[f] {
                face_first[f] = new_pos.len() as u32;
                new_pos.push(r.face_point(f));
                new_corner.push(false);
            }
        }
    }
    let points = Points {
        vertex: &vertex_point,
        edge: &edge_point,
        face_first: &face_first,
    };
    let (offsets, indices, selected) = children(p, &region, scheme, &points);
    let (sharp, boundary) = inherited_tags(p, &edges, &points);
    let next = Patch {
        mesh: Mesh {
            positions: new_pos,
            offsets,
            indices,
            attributes: Attributes::default(),
        },
        sharp,
        boundary,
        corner: new_corner,
        selected,
    };
    Ok((
        next,
        Step {
            region,
            vertex_point,
            edge_point,
        },
    ))
}

/// The faces of a patch that a step refines: those sharing a vertex with the selection
/// whose vertices are all complete (every patch-border edge at them a true boundary
/// edge).
fn region_of(p: &Patch, edges: &Edges) -> Vec<bool> {
    let m = &p.mesh;
    let (nv, nf) = (m.vertex_count(), m.face_count());
    // complete vertices: every patch-border edge at them is a true boundary edge
    let mut complete = vec![true; nv];
    for e in 0..edges.len() {
        let [a, b] = edges.verts[e];
        if edges.uses[e] == 1 && !p.boundary.contains_key(&pair_key(a, b)) {
            complete[a as usize] = false;
            complete[b as usize] = false;
        }
    }
    // region: faces sharing a vertex with the selection, all vertices complete
    let mut touches = vec![false; nv];
    for f in 0..nf {
        if p.selected[f] {
            for &v in m.face(f) {
                touches[v as usize] = true;
            }
        }
    }
    (0..nf)
        .map(|f| {
            let face = m.face(f);
            face.iter().any(|&v| touches[v as usize]) && face.iter().all(|&v| complete[v as usize])
        })
        .collect()
}

/// Per-vertex incident edges as CSR: vertex `v`'s edges are
/// `vedges[vstart[v]..vstart[v + 1]]`.
fn vertex_edges(edges: &Edges, nv: usize) -> (Vec<u32>, Vec<u32>) {
    let mut vstart = vec![0u32; nv + 1];
    for &[a, b] in &edges.verts {
        vstart[a as usize + 1] += 1;
        vstart[b as usize + 1] += 1;
    }
    for v in 0..nv {
        vstart[v + 1] += vstart[v];
    }
    let mut fill = vstart.clone();
    let mut vedges = vec![0u32; vstart[nv] as usize];
    for (e, &[a, b]) in edges.verts.iter().enumerate() {
        vedges[fill[a as usize] as usize] = e as u32;
        fill[a as usize] += 1;
        vedges[fill[b as usize] as usize] = e as u32;
        fill[b as usize] += 1;
    }
    (vstart, vedges)
}

/// One patch being refined: its edges and each vertex's incident edges.
struct Refining<'a> {
    p: &'a Patch,
    edges: &'a Edges,
    vstart: &'a [u32],
    vedges: &'a [u32],
}

#[allow(clippy::needless_range_loop)] // several arrays indexed by face / vertex
impl Refining<'_> {
    /// A true boundary edge, or one tagged sharp.
    fn is_sharp(&self, e: usize) -> bool {
        let [a, b] = self.edges.verts[e];
        self.edges.uses[e] == 1 || self.p.sharp.contains_key(&pair_key(a, b))
    }

    /// The centroid of face `f`.
    fn face_point(&self, f: usize) -> [f64; 3] {
        let m = &self.p.mesh;
        let face = m.face(f);
        let mut s = [0.0; 3];
        for &v in face {
            for k in 0..3 {
                s[k] += m.positions[v as usize][k];
            }
        }
        s.map(|x| x / face.len() as f64)
    }

    /// The vertex points of the region's vertices, numbered from `new_pos.len()` in
    /// face order (pushed with their corner tags); `NONE` elsewhere.
    fn vertex_points(
        &self,
        region: &[bool],
        weights: Option<super::loop_subdivision::LoopWeights>,
        new_pos: &mut Vec<[f64; 3]>,
        new_corner: &mut Vec<bool>,
    ) -> Vec<u32> {
        let m = &self.p.mesh;
        let mut vertex_point = vec![NONE; m.vertex_count()];
        for f in 0..m.face_count() {
            if !region[f] {
                continue;
            }
            for &v in m.face(f) {
                let v = v as usize;
                if vertex_point[v] != NONE {
                    continue;
                }
                vertex_point[v] = new_pos.len() as u32;
                new_corner.push(self.p.corner[v]);
                new_pos.push(self.vertex_point(v, weights));
            }
        }
        vertex_point
    }

    /// The vertex point of vertex `v`: kept at a corner or where more than two sharp
    /// edges meet, the crease rule `¾v + ⅛(a + b)` on two, else Loop's
    /// `(1 − nβ)v + βΣ` (with `weights`) or Catmull–Clark's `(n−2)/n·v + (Σe + Σf)/n²`.
    fn vertex_point(
        &self,
        v: usize,
        weights: Option<super::loop_subdivision::LoopWeights>,
    ) -> [f64; 3] {
        let (p, edges) = (self.p, self.edges);
        let m = &p.mesh;
        let pos = &m.positions;
        let pv = pos[v];
        let ring = &self.vedges[self.vstart[v] as usize..self.vstart[v + 1] as usize];
        let other = |e: u32| {
            let [a, b] = edges.verts[e as usize];
            if a as usize == v {
                b
            } else {
                a
            }
        };
        let sharp_nb: Vec<u32> = ring
            .iter()
            .filter(|&&e| self.is_sharp(e as usize))
            .map(|&e| other(e))
            .collect();
        if p.corner[v] || sharp_nb.len() > 2 {
            return pv;
        }
        if sharp_nb.len() == 2 {
            let (a, b) = (pos[sharp_nb[0] as usize], pos[sharp_nb[1] as usize]);
            return std::array::from_fn(|k| 0.75 * pv[k] + 0.125 * (a[k] + b[k]));
        }
        let n = ring.len();
        let mut s = [0.0; 3];
        for &e in ring {
            let o = pos[other(e) as usize];
            for k in 0..3 {
                s[k] += o[k];
            }
        }
        match weights {
            Some(w) => {
                let b = super::loop_subdivision::beta(n, w);
                std::array::from_fn(|k| (1.0 - n as f64 * b) * pv[k] + b * s[k])
            }
            None => {
                // Σ face points of the faces at v (all in the patch: v is complete)
                let mut fs = [0.0; 3];
                let nn = n as f64;
                for &e in ring {
                    for &c in &edges.corners[e as usize] {
                        if c != NONE && m.indices[c as usize] as usize == v {
                            let fp = self.face_point(edges.corner_face[c as usize] as usize);
                            for k in 0..3 {
                                fs[k] += fp[k];
                            }
                        }
                    }
                }
                std::array::from_fn(|k| (nn - 2.0) / nn * pv[k] + (s[k] + fs[k]) / (nn * nn))
            }
        }
    }

    /// The edge points of the region's edges, numbered from `new_pos.len()` in corner
    /// order: the midpoint of a sharp edge, Loop's `⅜(a + b) + ⅛(c + d)` or
    /// Catmull–Clark's `¼(a + b + f₀ + f₁)`.
    fn edge_points(
        &self,
        region: &[bool],
        scheme: Scheme,
        new_pos: &mut Vec<[f64; 3]>,
        new_corner: &mut Vec<bool>,
    ) -> PairMap<u32> {
        let (m, edges) = (&self.p.mesh, self.edges);
        let pos = &m.positions;
        let mut edge_point: PairMap<u32> = PairMap::default();
        for f in 0..m.face_count() {
            if !region[f] {
                continue;
            }
            let (s, e) = (m.offsets[f] as usize, m.offsets[f + 1] as usize);
            for c in s..e {
                let ed = edges.corner_edge[c] as usize;
                let [a, b] = edges.verts[ed];
                let key = pair_key(a, b);
                if edge_point.contains_key(&key) {
                    continue;
                }
                edge_point.insert(key, new_pos.len() as u32);
                let (pa, pb) = (pos[a as usize], pos[b as usize]);
                let q = if self.is_sharp(ed) {
                    std::array::from_fn(|k| 0.5 * (pa[k] + pb[k]))
                } else {
                    let [c0, c1] = edges.corners[ed];
                    if is_loop(scheme) {
                        let opp = |c: u32| {
                            let f = edges.corner_face[c as usize] as usize;
                            let (s, e) = (m.offsets[f], m.offsets[f + 1]);
                            let prev = if c == s { e - 1 } else { c - 1 };
                            pos[m.indices[prev as usize] as usize]
                        };
                        let (pc, pd) = (opp(c0), opp(c1));
                        std::array::from_fn(|k| 0.375 * (pa[k] + pb[k]) + 0.125 * (pc[k] + pd[k]))
                    } else {
                        let f0 = self.face_point(edges.corner_face[c0 as usize] as usize);
                        let f1 = self.face_point(edges.corner_face[c1 as usize] as usize);
                        std::array::from_fn(|k| 0.25 * (pa[k] + pb[k] + f0[k] + f1[k]))
                    }
                };
                new_pos.push(q);
                new_corner.push(false);
            }
        }
        edge_point
    }
}

/// The new points of one step: each vertex's vertex point, each edge's edge point (by
/// its end vertices), each face's face point (Catmull–Clark).
struct Points<'a> {
    vertex: &'a [u32],
    edge: &'a PairMap<u32>,
    face_first: &'a [u32],
}

/// The children of the region's faces (offsets, indices) and their selection flags.
#[allow(clippy::needless_range_loop)] // several arrays indexed by face
fn children(
    p: &Patch,
    region: &[bool],
    scheme: Scheme,
    points: &Points,
) -> (Vec<u32>, Vec<u32>, Vec<bool>) {
    let m = &p.mesh;
    let mut offsets = vec![0u32];
    let mut indices = Vec::new();
    let mut selected = Vec::new();
    let ep = |a: u32, b: u32| points.edge[&pair_key(a, b)];
    for f in 0..m.face_count() {
        if !region[f] {
            continue;
        }
        let face = m.face(f);
        let k = face.len();
        let vp = |i: usize| points.vertex[face[i % k] as usize];
        if is_loop(scheme) {
            let (a, b, c) = (vp(0), vp(1), vp(2));
            let (ab, bc, ca) = (
                ep(face[0], face[1]),
                ep(face[1], face[2]),
                ep(face[2], face[0]),
            );
            for t in [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]] {
                indices.extend_from_slice(&t);
                offsets.push(indices.len() as u32);
                selected.push(p.selected[f]);
            }
        } else {
            for i in 0..k {
                let q = [
                    vp(i),
                    ep(face[i], face[(i + 1) % k]),
                    points.face_first[f],
                    ep(face[(i + k - 1) % k], face[i]),
                ];
                indices.extend_from_slice(&q);
                offsets.push(indices.len() as u32);
                selected.push(p.selected[f]);
            }
        }
    }
    (offsets, indices, selected)
}

/// The sharp and boundary tags of the split edges' halves.
fn inherited_tags(p: &Patch, edges: &Edges, points: &Points) -> (PairMap<()>, PairMap<()>) {
    let mut sharp = PairMap::default();
    let mut boundary = PairMap::default();
    for e in 0..edges.len() {
        let [a, b] = edges.verts[e];
        let Some(&mid) = points.edge.get(&pair_key(a, b)) else {
            continue;
        };
        let (va, vb) = (points.vertex[a as usize], points.vertex[b as usize]);
        if p.sharp.contains_key(&pair_key(a, b)) {
            sharp.insert(pair_key(va, mid), ());
            sharp.insert(pair_key(mid, vb), ());
        }
        if p.boundary.contains_key(&pair_key(a, b)) {
            boundary.insert(pair_key(va, mid), ());
            boundary.insert(pair_key(mid, vb), ());
        }
    }
    (sharp, boundary)
}

/// Build the conforming output from the patches, finest first.
fn assemble(patches: &[Patch], steps: &[Step], triangles: bool) -> Mesh {
    let levels = patches.len();
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut offsets = vec![0u32];
    let mut indices: Vec<u32> = Vec::new();
    // out id of every vertex of the current (finer) patch
    let finest = &patches[levels - 1].mesh;
    let mut finer_ids: Vec<u32> = (0..finest.vertex_count() as u32).collect();
    positions.extend_from_slice(&finest.positions);
    for f in finest.faces() {
        indices.extend_from_slice(f);
        offsets.push(indices.len() as u32);
    }
    for k in (0..levels - 1).rev() {
        let p = &patches[k];
        let st = &steps[k];
        let m = &p.mesh;
        let ids: Vec<u32> = (0..m.vertex_count())
            .map(|v| {
                if st.vertex_point[v] != NONE {
                    finer_ids[st.vertex_point[v] as usize]
                } else {
                    positions.push(m.positions[v]);
                    (positions.len() - 1) as u32
                }
            })
            .collect();
        let mut poly: Vec<u32> = Vec::new();
        let mut is_t: Vec<bool> = Vec::new();
        for f in 0..m.face_count() {
            if st.region[f] {
                continue;
            }
            let face = m.face(f);
            let k = face.len();
            poly.clear();
            is_t.clear();
            for i in 0..k {
                poly.push(ids[face[i] as usize]);
                is_t.push(false);
                if let Some(&mid) = st.edge_point.get(&pair_key(face[i], face[(i + 1) % k])) {
                    poly.push(finer_ids[mid as usize]);
                    is_t.push(true);
                }
            }
            emit_split(
                &poly,
                &is_t,
                k,
                triangles,
                &mut positions,
                &mut indices,
                &mut offsets,
            );
        }
        finer_ids = ids;
    }
    Mesh {
        positions,
        offsets,
        indices,
        attributes: Attributes::default(),
    }
}

/// Split a face whose boundary `poly` contains T-vertices (flags `is_t`); `k` original corners.
fn emit_split(
    poly: &[u32],
    is_t: &[bool],
    k: usize,
    triangles: bool,
    positions: &mut Vec<[f64; 3]>,
    indices: &mut Vec<u32>,
    offsets: &mut Vec<u32>,
) {
    let mut push = |f: &[u32], indices: &mut Vec<u32>| {
        indices.extend_from_slice(f);
        offsets.push(indices.len() as u32);
    };
    let nt = poly.len() - k;
    if nt == 0 {
        push(poly, indices);
        return;
    }
    let n = poly.len();
    // rotate so that poly starts at an original corner followed by a T-vertex when possible
    let candidates = || (0..n).filter(|&i| !is_t[i] && is_t[(i + 1) % n]);
    let start = candidates()
        .find(|&i| is_t[(i + 3) % n])
        .or_else(|| candidates().next())
        .unwrap_or(0);
    let r: Vec<u32> = (0..n).map(|i| poly[(start + i) % n]).collect();
    let rt: Vec<bool> = (0..n).map(|i| is_t[(start + i) % n]).collect();
    if triangles && k == 3 {
        match nt {
            // a, m, b, c
            1 => {
                push(&[r[0], r[1], r[3]], indices);
                push(&[r[1], r[2], r[3]], indices);
            }
            2 => {
                // a, m1, b, m2, c  (or a, m1, b, c, m2)
                if rt[3] {
                    push(&[r[1], r[2], r[3]], indices);
                    push(&[r[0], r[1], r[3]], indices);
                    push(&[r[0], r[3], r[4]], indices);
                } else {
                    // a m1 b c m2: T on ab and ca
                    push(&[r[0], r[1], r[4]], indices);
                    push(&[r[1], r[2], r[3]], indices);
                    push(&[r[1], r[3], r[4]], indices);
                }
            }
            _ => {
                // a m1 b m2 c m3
                push(&[r[0], r[1], r[5]], indices);
                push(&[r[1], r[2], r[3]], indices);
                push(&[r[5], r[3], r[4]], indices);
                push(&[r[1], r[3], r[5]], indices);
            }
        }
        return;
    }
    if k == 4 && nt == 1 {
        // a m b c d: quad (m b c d) and triangle (a m d)
        push(&[r[1], r[2], r[3], r[4]], indices);
        push(&[r[0], r[1], r[4]], indices);
        return;
    }
    if k == 4 && nt == 2 && n == 6 {
        if rt[4] {
            // a m1 b c m2 d: opposite edges → two quads
            push(&[r[0], r[1], r[4], r[5]], indices);
            push(&[r[1], r[2], r[3], r[4]], indices);
            return;
        }
        if rt[3] {
            // a m1 b m2 c d: adjacent → face vertex f joined to m1, m2 and d (three quads)
            let f = new_centroid(&[r[0], r[2], r[4], r[5]], positions);
            push(&[r[0], r[1], f, r[5]], indices);
            push(&[r[1], r[2], r[3], f], indices);
            push(&[f, r[3], r[4], r[5]], indices);
            return;
        }
    }
    if k == 4 && nt == 4 {
        // a m1 b m2 c m3 d m4: the Catmull-Clark split around a centroid
        let f = new_centroid(&[r[0], r[2], r[4], r[6]], positions);
        for i in 0..4 {
            push(&[r[2 * i], r[2 * i + 1], f, r[(2 * i + 7) % 8]], indices);
        }
        return;
    }
    // fan of triangles around a new centroid vertex
    let corners: Vec<u32> = (0..n).filter(|&i| !rt[i]).map(|i| r[i]).collect();
    let f = new_centroid(&corners, positions);
    for i in 0..n {
        push(&[f, r[i], r[(i + 1) % n]], indices);
    }
}

fn new_centroid(vs: &[u32], positions: &mut Vec<[f64; 3]>) -> u32 {
    let mut c = [0.0; 3];
    for &v in vs {
        for k in 0..3 {
            c[k] += positions[v as usize][k] / vs.len() as f64;
        }
    }
    positions.push(c);
    (positions.len() - 1) as u32
}
