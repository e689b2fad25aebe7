//! Edge collapse and quadric-error simplification (§6.6.3; Garland and Heckbert 1997).
//!
//! ```text
//!   plane of a face:  p = (n, −n·x₀),   quadric K_p = p pᵀ (4 × 4)
//!   vertex quadric:   Q_v = Σ_{faces ∋ v} K_p   (+ weighted planes ⟂ each boundary edge)
//!   collapse a, b → x:  cost = x̄ᵀ (Q_a + Q_b) x̄,  x̄ = (x, 1),  x = argmin (3 × 3 solve),
//!                      or the best of a, b, (a + b)/2 when the system is singular
//! ```
//!
//! Edges are collapsed cheapest first (a logarithmically binned queue, see `BinQueue`; stale
//! entries are skipped by per-vertex stamps). A collapse is allowed only when it keeps the mesh a 2-manifold: the *link
//! condition* Lk(a) ∩ Lk(b) = Lk(ab) (common neighbours are exactly the vertices opposite ab,
//! and those are not joined to both through a face), an interior edge may not join two boundary
//! vertices, and no remaining face may flip its normal.
//!
//! Storage is flat: faces as triples, and for each vertex a singly linked list of its corners
//! (`head[v]`, `next_corner[c]`), spliced in O(length) on a collapse.

use super::edges::Edges;
use super::{vec3, Attributes, Mesh, NONE};
use crate::{Error, Result};

/// Symmetric 4 × 4 matrix stored as its upper triangle.
#[derive(Clone, Copy, Default, Debug)]
struct Quadric([f64; 10]);

impl Quadric {
    fn plane(n: [f64; 3], d: f64, w: f64) -> Quadric {
        let (a, b, c) = (n[0], n[1], n[2]);
        Quadric([
            w * a * a,
            w * a * b,
            w * a * c,
            w * a * d,
            w * b * b,
            w * b * c,
            w * b * d,
            w * c * c,
            w * c * d,
            w * d * d,
        ])
    }
    fn add(&mut self, o: &Quadric) {
        for i in 0..10 {
            self.0[i] += o.0[i];
        }
    }
    fn sum(a: &Quadric, b: &Quadric) -> Quadric {
        let mut q = *a;
        q.add(b);
        q
    }
    fn eval(&self, p: [f64; 3]) -> f64 {
        let q = &self.0;
        let (x, y, z) = (p[0], p[1], p[2]);
        q[0] * x * x
            + 2.0 * q[1] * x * y
            + 2.0 * q[2] * x * z
            + 2.0 * q[3] * x
            + q[4] * y * y
            + 2.0 * q[5] * y * z
            + 2.0 * q[6] * y
            + q[7] * z * z
            + 2.0 * q[8] * z
            + q[9]
    }
    /// argmin of the quadric, if the 3 × 3 system is well conditioned.
    fn minimiser(&self, scale: f64) -> Option<[f64; 3]> {
        let q = &self.0;
        let m = [[q[0], q[1], q[2]], [q[1], q[4], q[5]], [q[2], q[5], q[7]]];
        let b = [-q[3], -q[6], -q[8]];
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        let norm = m.iter().flatten().fold(0.0f64, |a, &x| a.max(x.abs()));
        if det.abs() <= 1e-10 * norm * norm * norm || norm == 0.0 {
            return None;
        }
        let solve = |k: usize| {
            let mut mm = m;
            for r in 0..3 {
                mm[r][k] = b[r];
            }
            (mm[0][0] * (mm[1][1] * mm[2][2] - mm[1][2] * mm[2][1])
                - mm[0][1] * (mm[1][0] * mm[2][2] - mm[1][2] * mm[2][0])
                + mm[0][2] * (mm[1][0] * mm[2][1] - mm[1][1] * mm[2][0]))
                / det
        };
        let x = [solve(0), solve(1), solve(2)];
        x.iter()
            .all(|v| v.is_finite() && v.abs() < 1e3 * scale.max(1.0))
            .then_some(x)
    }
}

/// A collapse candidate: 16 bytes. `stamp` is the sum of both vertices' stamps when queued;
/// a changed sum marks the entry stale (a collision only means a needless re-check).
#[derive(Clone, Copy)]
struct Candidate {
    a: u32,
    b: u32,
    stamp: u32,
}

/// An approximate min-priority queue: costs are binned on a logarithmic scale, 16 bins per
/// factor of two (costs within 4.4 % of each other share a bin and leave in any order).
/// Push and pop are O(1); a binary heap spent most of the run time in `pop` (cache misses
/// over millions of entries).
struct BinQueue {
    bins: Vec<Vec<Candidate>>,
    lowest: usize,
}

impl BinQueue {
    const PER_OCTAVE: f64 = 16.0;
    const BINS: usize = 16 * 240 + 2;

    fn new() -> Self {
        BinQueue {
            bins: (0..Self::BINS).map(|_| Vec::new()).collect(),
            lowest: 0,
        }
    }

    #[inline]
    fn bin(cost: f64) -> usize {
        if cost <= 0.0 || cost.is_nan() {
            return 0;
        }
        // log2 from −200 to +40 maps to bins 1 ..= BINS−1
        let x = (cost.log2() + 200.0) * Self::PER_OCTAVE;
        (x.max(0.0) as usize + 1).min(Self::BINS - 1)
    }

    #[inline]
    fn push(&mut self, cost: f64, c: Candidate) {
        let b = Self::bin(cost);
        self.bins[b].push(c);
        self.lowest = self.lowest.min(b);
    }

    #[inline]
    fn pop(&mut self) -> Option<Candidate> {
        while self.lowest < Self::BINS {
            if let Some(c) = self.bins[self.lowest].pop() {
                return Some(c);
            }
            self.lowest += 1;
        }
        None
    }
}

struct State {
    pos: Vec<[f64; 3]>,
    tri: Vec<[u32; 3]>,
    alive: Vec<bool>,
    head: Vec<u32>,
    next_corner: Vec<u32>,
    quadric: Vec<Quadric>,
    stamp: Vec<u32>,
    boundary: Vec<bool>,
    mark: Vec<u32>,
    mark_id: u32,
    scale: f64,
}

impl State {
    /// Live faces of `v` (by corner lists).
    fn faces_of(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        let mut c = self.head[v as usize];
        while c != NONE {
            let f = c / 3;
            if self.alive[f as usize] {
                out.push(f);
            }
            c = self.next_corner[c as usize];
        }
    }

    fn place(&self, a: u32, b: u32) -> ([f64; 3], f64) {
        let q = Quadric::sum(&self.quadric[a as usize], &self.quadric[b as usize]);
        if let Some(x) = q.minimiser(self.scale) {
            return (x, q.eval(x).max(0.0));
        }
        let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
        let mid = vec3::scale(vec3::add(pa, pb), 0.5);
        [pa, pb, mid]
            .into_iter()
            .map(|x| (x, q.eval(x).max(0.0)))
            .min_by(|u, v| u.1.total_cmp(&v.1))
            .unwrap()
    }

    /// Link condition and normal-flip test for collapsing a, b into x.
    fn can_collapse(&mut self, a: u32, b: u32, x: [f64; 3], fa: &[u32], fb: &[u32]) -> bool {
        if self.boundary[a as usize] && self.boundary[b as usize] {
            // only along a boundary edge: ab must have exactly one face
            let shared = fa
                .iter()
                .filter(|&&f| self.tri[f as usize].contains(&b))
                .count();
            if shared != 1 {
                return false;
            }
        }
        // opposite vertices of the faces on ab
        let mut opposite = [NONE; 2];
        let mut k = 0;
        for &f in fa {
            let t = self.tri[f as usize];
            if t.contains(&b) {
                if k == 2 {
                    return false;
                }
                opposite[k] = t.into_iter().find(|&v| v != a && v != b).unwrap();
                k += 1;
            }
        }
        if k == 0 {
            return false;
        }
        // vertex link: neighbours of a marked, common neighbours of b must be the opposites
        self.mark_id = self.mark_id.wrapping_add(1);
        if self.mark_id == 0 {
            self.mark.iter_mut().for_each(|m| *m = 0);
            self.mark_id = 1;
        }
        let id = self.mark_id;
        for &f in fa {
            for v in self.tri[f as usize] {
                self.mark[v as usize] = id;
            }
        }
        for &f in fb {
            for v in self.tri[f as usize] {
                if v != a && v != b && self.mark[v as usize] == id && !opposite[..k].contains(&v) {
                    return false;
                }
            }
        }
        // edge link: a face (a, c, d) and a face (b, c, d) with c, d the opposites
        if k == 2 {
            let has = |fs: &[u32], w: u32| {
                fs.iter().any(|&f| {
                    let t = self.tri[f as usize];
                    t.contains(&w) && t.contains(&opposite[0]) && t.contains(&opposite[1])
                })
            };
            if has(fa, a) && has(fb, b) {
                return false;
            }
        }
        // normal flips
        for (&f, moved) in fa.iter().map(|f| (f, a)).chain(fb.iter().map(|f| (f, b))) {
            let t = self.tri[f as usize];
            if t.contains(&a) && t.contains(&b) {
                continue;
            }
            let p: [[f64; 3]; 3] = std::array::from_fn(|i| self.pos[t[i] as usize]);
            let before = vec3::cross(vec3::sub(p[1], p[0]), vec3::sub(p[2], p[0]));
            let q: [[f64; 3]; 3] = std::array::from_fn(|i| if t[i] == moved { x } else { p[i] });
            let after = vec3::cross(vec3::sub(q[1], q[0]), vec3::sub(q[2], q[0]));
            if vec3::dot(before, after) <= 0.0 {
                return false;
            }
        }
        true
    }
}

/// Simplify a manifold mesh (polygons are triangulated first) to at most `target_faces`
/// triangles, or as few as the link condition allows.
pub fn simplify(mesh: &Mesh, target_faces: usize) -> Result<Mesh> {
    let m = if mesh.is_triangle_mesh() {
        mesh.clone()
    } else {
        mesh.triangulated()
    };
    let edges = Edges::build(&m);
    if let Some(e) = (0..edges.len()).find(|&e| edges.uses[e] > 2) {
        let [a, b] = edges.verts[e];
        return Err(Error::format(
            format!(
                "non-manifold edge ({a}, {b}): used by {} faces",
                edges.uses[e]
            ),
            "a manifold mesh (each edge in one or two faces)",
        ));
    }
    let nv = m.vertex_count();
    let nf = m.face_count();
    let tri: Vec<[u32; 3]> = m.indices.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    let mut head = vec![NONE; nv];
    let mut next_corner = vec![NONE; 3 * nf];
    for c in (0..3 * nf).rev() {
        let v = m.indices[c] as usize;
        next_corner[c] = head[v];
        head[v] = c as u32;
    }
    let (lo, hi) = m.bounding_box().unwrap_or(([0.0; 3], [1.0; 3]));
    let scale = vec3::norm(vec3::sub(hi, lo)).max(1e-300);
    let mut quadric = vec![Quadric::default(); nv];
    let mut boundary = vec![false; nv];
    for (f, t) in tri.iter().enumerate() {
        let av = super::normals::face_area_vector(&m, f);
        let n = vec3::normalized(av);
        let d = -vec3::dot(n, m.positions[t[0] as usize]);
        let k = Quadric::plane(n, d, 1.0);
        for &v in t {
            quadric[v as usize].add(&k);
        }
    }
    for e in 0..edges.len() {
        if edges.uses[e] != 1 {
            continue;
        }
        let [a, b] = edges.verts[e];
        boundary[a as usize] = true;
        boundary[b as usize] = true;
        let f = edges.corner_face[edges.corners[e][0] as usize] as usize;
        let n = vec3::normalized(super::normals::face_area_vector(&m, f));
        let dir = vec3::sub(m.positions[b as usize], m.positions[a as usize]);
        let p = vec3::normalized(vec3::cross(dir, n));
        let d = -vec3::dot(p, m.positions[a as usize]);
        let k = Quadric::plane(p, d, 100.0);
        quadric[a as usize].add(&k);
        quadric[b as usize].add(&k);
    }
    let mut s = State {
        pos: m.positions.clone(),
        tri,
        alive: vec![true; nf],
        head,
        next_corner,
        quadric,
        stamp: vec![0; nv],
        boundary,
        mark: vec![0; nv],
        mark_id: 0,
        scale,
    };
    let mut heap = BinQueue::new();
    let initial: Vec<f64> = {
        use rayon::prelude::*;
        let st = &s;
        edges
            .verts
            .par_iter()
            .with_min_len(4096)
            .map(|&[a, b]| st.place(a, b).1)
            .collect()
    };
    for (&[a, b], &cost) in edges.verts.iter().zip(&initial) {
        heap.push(cost, Candidate { a, b, stamp: 0 });
    }
    drop(initial);
    let mut faces = nf;
    let (mut fa, mut fb) = (Vec::new(), Vec::new());
    while faces > target_faces {
        let Some(c) = heap.pop() else { break };
        let (a, b) = (c.a, c.b);
        if s.stamp[a as usize].wrapping_add(s.stamp[b as usize]) != c.stamp {
            continue;
        }
        s.faces_of(a, &mut fa);
        s.faces_of(b, &mut fb);
        let (x, _) = s.place(a, b);
        if !s.can_collapse(a, b, x, &fa, &fb) {
            continue;
        }
        // collapse b into a
        for &f in &fa {
            if s.tri[f as usize].contains(&b) {
                s.alive[f as usize] = false;
                faces -= 1;
            }
        }
        // relabel b's corners as a and rebuild a's corner list from the live corners of both
        // (dropping dead corners keeps the lists short: without this, lists grow with the
        // collapse history and the run time becomes quadratic)
        let mut list = NONE;
        fa.clear(); // collects the faces around the merged vertex
        for start in [s.head[b as usize], s.head[a as usize]] {
            let mut c = start;
            while c != NONE {
                let nxt = s.next_corner[c as usize];
                let f = (c / 3) as usize;
                if s.alive[f] {
                    s.tri[f][(c % 3) as usize] = a;
                    s.next_corner[c as usize] = list;
                    list = c;
                    fa.push(f as u32);
                }
                c = nxt;
            }
        }
        s.head[a as usize] = list;
        s.head[b as usize] = NONE;
        s.pos[a as usize] = x;
        let qb = s.quadric[b as usize];
        s.quadric[a as usize].add(&qb);
        s.boundary[a as usize] |= s.boundary[b as usize];
        s.stamp[a as usize] += 1;
        s.stamp[b as usize] += 1;
        // new candidates around a (its live faces were collected above)
        s.mark_id = s.mark_id.wrapping_add(1);
        if s.mark_id == 0 {
            s.mark.iter_mut().for_each(|m| *m = 0);
            s.mark_id = 1;
        }
        let id = s.mark_id;
        for &f in &fa {
            for v in s.tri[f as usize] {
                if v != a && s.mark[v as usize] != id {
                    s.mark[v as usize] = id;
                    let (_, cost) = s.place(a, v);
                    heap.push(
                        cost,
                        Candidate {
                            a,
                            b: v,
                            stamp: s.stamp[a as usize].wrapping_add(s.stamp[v as usize]),
                        },
                    );
                }
            }
        }
    }
    // compact
    let mut remap = vec![NONE; nv];
    let mut positions = Vec::new();
    let mut indices = Vec::with_capacity(3 * faces);
    for (f, t) in s.tri.iter().enumerate() {
        if !s.alive[f] {
            continue;
        }
        for &v in t {
            if remap[v as usize] == NONE {
                remap[v as usize] = positions.len() as u32;
                positions.push(s.pos[v as usize]);
            }
            indices.push(remap[v as usize]);
        }
    }
    let n = indices.len() / 3;
    Ok(Mesh {
        positions,
        offsets: (0..=n as u32).map(|i| 3 * i).collect(),
        indices,
        attributes: Attributes::default(),
    })
}

/// One-sided Hausdorff distance from the vertices of `a` to the surface of `b` (brute force
/// over a uniform grid of `b`'s triangles): max over a's vertices of the distance to b.
pub fn vertex_to_surface_distance(a: &Mesh, b: &Mesh) -> f64 {
    let bt = b.triangulated();
    let Some((lo, hi)) = b.bounding_box() else {
        return f64::INFINITY;
    };
    let n = ((bt.face_count() as f64).cbrt().ceil() as usize).clamp(1, 128);
    let size: [f64; 3] = std::array::from_fn(|k| ((hi[k] - lo[k]) / n as f64).max(1e-12));
    let cell = |p: [f64; 3]| -> [usize; 3] {
        std::array::from_fn(|k| (((p[k] - lo[k]) / size[k]).floor().max(0.0) as usize).min(n - 1))
    };
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); n * n * n];
    for (f, t) in bt.faces().enumerate() {
        let ps: Vec<[f64; 3]> = t.iter().map(|&v| bt.positions[v as usize]).collect();
        let (c0, c1) = (
            cell(std::array::from_fn(|k| {
                ps.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min)
            })),
            cell(std::array::from_fn(|k| {
                ps.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max)
            })),
        );
        for i in c0[0]..=c1[0] {
            for j in c0[1]..=c1[1] {
                for k in c0[2]..=c1[2] {
                    grid[(i * n + j) * n + k].push(f as u32);
                }
            }
        }
    }
    use rayon::prelude::*;
    a.positions
        .par_iter()
        .map(|&p| {
            let c = cell(p);
            let mut best = f64::INFINITY;
            for r in 0..n {
                // search shells of growing radius until the shell is farther than the best hit
                let shell_dist =
                    (r as f64 - 1.0).max(0.0) * size.iter().cloned().fold(f64::INFINITY, f64::min);
                if shell_dist > best {
                    break;
                }
                let lo_i: [usize; 3] = std::array::from_fn(|k| c[k].saturating_sub(r));
                let hi_i: [usize; 3] = std::array::from_fn(|k| (c[k] + r).min(n - 1));
                for i in lo_i[0]..=hi_i[0] {
                    for j in lo_i[1]..=hi_i[1] {
                        for k in lo_i[2]..=hi_i[2] {
                            let on_shell = [i, j, k]
                                .iter()
                                .zip(c.iter())
                                .any(|(&x, &y)| x.abs_diff(y) == r);
                            if !on_shell {
                                continue;
                            }
                            for &f in &grid[(i * n + j) * n + k] {
                                let t = bt.face(f as usize);
                                let d = point_triangle_distance(
                                    p,
                                    bt.positions[t[0] as usize],
                                    bt.positions[t[1] as usize],
                                    bt.positions[t[2] as usize],
                                );
                                best = best.min(d);
                            }
                        }
                    }
                }
            }
            best
        })
        .reduce(|| 0.0, f64::max)
}

/// Distance from `p` to triangle `abc` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn point_triangle_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    use vec3::{dot, norm, sub};
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return norm(ap);
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return norm(bp);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return norm(sub(p, vec3::add(a, vec3::scale(ab, v))));
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return norm(cp);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return norm(sub(p, vec3::add(a, vec3::scale(ac, w))));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return norm(sub(p, vec3::add(b, vec3::scale(sub(c, b), w))));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    norm(sub(
        p,
        vec3::add(a, vec3::add(vec3::scale(ab, v), vec3::scale(ac, w))),
    ))
}

/// Collapse the edge `a`–`b` of a triangle mesh into one vertex at `position` (§6.6.3). Fails
/// when there is no such edge or when the collapse would break the 2-manifold: the link
/// condition Lk(a) ∩ Lk(b) = Lk(ab), and no interior edge joining two boundary vertices.
/// Vertex `b` is removed (later vertices shift down by one).
pub fn collapse_edge(mesh: &Mesh, a: u32, b: u32, position: [f64; 3]) -> Result<Mesh> {
    if !mesh.is_triangle_mesh() {
        return Err(Error::Unsupported {
            what: "edge collapse on faces that are not triangles",
            value: format!("{} faces", mesh.face_count()),
        });
    }
    let nv = mesh.vertex_count() as u32;
    if a >= nv || b >= nv || a == b {
        return Err(Error::parameter(
            "edge",
            format!("({a}, {b})"),
            "two distinct vertex indices",
        ));
    }
    let he = super::HalfEdgeMesh::build(mesh)?;
    let (va, vb) = (super::VertexId(a), super::VertexId(b));
    let h = he.find_halfedge(va, vb).ok_or_else(|| {
        Error::parameter(
            "edge",
            format!("({a}, {b})"),
            "two vertices joined by an edge",
        )
    })?;
    let ring =
        |v: super::VertexId| -> Vec<u32> { he.outgoing(v).map(|h| he.to_vertex(h).0).collect() };
    let (ra, rb) = (ring(va), ring(vb));
    let opposite: Vec<u32> = [h, he.twin(h)]
        .iter()
        .filter(|&&x| !he.is_boundary_halfedge(x))
        .map(|&x| he.from_vertex(he.prev(x)).0)
        .collect();
    let common: Vec<u32> = ra.iter().copied().filter(|v| rb.contains(v)).collect();
    let fail = |why: &str| {
        Error::format(
            format!("collapsing edge ({a}, {b}) {why}"),
            "an edge whose collapse keeps the mesh a manifold (link condition)",
        )
    };
    if common.len() != opposite.len() || !common.iter().all(|v| opposite.contains(v)) {
        return Err(fail(
            "would pinch the surface: a and b share a neighbour off their faces",
        ));
    }
    if he.is_boundary_vertex(va) && he.is_boundary_vertex(vb) && !he.is_boundary_edge(he.edge(h)) {
        return Err(fail("would join two boundary arcs through the interior"));
    }
    if opposite.len() == 2 {
        let (c, d) = (super::VertexId(opposite[0]), super::VertexId(opposite[1]));
        if let Some(hcd) = he.find_halfedge(c, d) {
            // faces (a, c, d) and (b, c, d) both present: the edge cd is in both links
            let faces_with = |w: u32| {
                [hcd, he.twin(hcd)]
                    .iter()
                    .any(|&x| !he.is_boundary_halfedge(x) && he.from_vertex(he.prev(x)).0 == w)
            };
            if faces_with(a) && faces_with(b) {
                return Err(fail("would create a doubled face"));
            }
        }
    }
    let mut positions = mesh.positions.clone();
    positions[a as usize] = position;
    positions.remove(b as usize);
    let map = |v: u32| {
        let v = if v == b { a } else { v };
        if v > b {
            v - 1
        } else {
            v
        }
    };
    let mut indices = Vec::with_capacity(mesh.indices.len());
    for f in mesh.faces() {
        if f.contains(&a) && f.contains(&b) {
            continue;
        }
        indices.extend(f.iter().map(|&v| map(v)));
    }
    let n = indices.len() / 3;
    Ok(Mesh {
        positions,
        offsets: (0..=n as u32).map(|i| 3 * i).collect(),
        indices,
        attributes: Attributes::default(),
    })
}

/// Remove an interior vertex of a triangle mesh and fill its hole with a fan of triangles from
/// one of its neighbours (§6.6.3), chosen so that no fan edge already exists. Later vertices
/// shift down by one.
pub fn remove_vertex(mesh: &Mesh, v: u32) -> Result<Mesh> {
    if !mesh.is_triangle_mesh() {
        return Err(Error::Unsupported {
            what: "vertex removal on faces that are not triangles",
            value: format!("{} faces", mesh.face_count()),
        });
    }
    if v as usize >= mesh.vertex_count() {
        return Err(Error::parameter("vertex", v, "a vertex index of the mesh"));
    }
    let he = super::HalfEdgeMesh::build(mesh)?;
    let vid = super::VertexId(v);
    if he.is_boundary_vertex(vid) {
        return Err(Error::Unsupported {
            what: "removal of a boundary vertex",
            value: v.to_string(),
        });
    }
    // ring in counter-clockwise order: in face (v, x, y) the link edge runs x → y
    let mut next_of = std::collections::HashMap::new();
    for h in he.outgoing(vid) {
        let x = he.to_vertex(h).0;
        let y = he.to_vertex(he.next(h)).0;
        next_of.insert(x, y);
    }
    let start = *next_of.keys().min().unwrap();
    let mut ring = vec![start];
    while ring.len() < next_of.len() {
        let n = next_of[ring.last().unwrap()];
        if n == start {
            break;
        }
        ring.push(n);
    }
    let k = ring.len();
    let pick = (0..k).find(|&s| {
        (2..k - 1).all(|i| {
            he.find_halfedge(super::VertexId(ring[s]), super::VertexId(ring[(s + i) % k]))
                .is_none()
        })
    });
    let s = pick.ok_or_else(|| {
        Error::format(
            format!(
                "vertex {v}: every fan over its {k} neighbours would duplicate an existing edge"
            ),
            "a vertex whose hole can be filled without creating a non-manifold edge",
        )
    })?;
    let map = |w: u32| if w > v { w - 1 } else { w };
    let mut indices = Vec::with_capacity(mesh.indices.len());
    for f in mesh.faces() {
        if !f.contains(&v) {
            indices.extend(f.iter().map(|&w| map(w)));
        }
    }
    for i in 1..k - 1 {
        indices.extend([ring[s], ring[(s + i) % k], ring[(s + i + 1) % k]].map(map));
    }
    let mut positions = mesh.positions.clone();
    positions.remove(v as usize);
    let n = indices.len() / 3;
    Ok(Mesh {
        positions,
        offsets: (0..=n as u32).map(|i| 3 * i).collect(),
        indices,
        attributes: Attributes::default(),
    })
}
