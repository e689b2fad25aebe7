//! Generated meshes for tests, examples and benchmarks: platonic solids, a torus grid and a
//! planar quad grid with boundary. All faces are counter-clockwise seen from outside.

use super::Mesh;
use std::f64::consts::PI;

fn build(positions: Vec<[f64; 3]>, faces: Vec<Vec<u32>>) -> Mesh {
    Mesh::from_faces(positions, faces).expect("generated meshes are valid")
}

/// Unit cube `[0, 1]³` as 6 quads (V 8, E 12, F 6, χ 2).
pub fn cube() -> Mesh {
    let p = (0..8)
        .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
        .collect();
    let f = vec![
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
        vec![0, 1, 5, 4],
        vec![2, 6, 7, 3],
        vec![0, 4, 6, 2],
        vec![1, 3, 7, 5],
    ];
    build(p, f)
}

/// Regular tetrahedron (V 4, E 6, F 4).
pub fn tetrahedron() -> Mesh {
    let p = vec![
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    let f = vec![vec![0, 1, 2], vec![0, 3, 1], vec![0, 2, 3], vec![1, 3, 2]];
    build(p, f)
}

/// Regular octahedron (V 6, E 12, F 8).
pub fn octahedron() -> Mesh {
    let p = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let f = vec![
        vec![0, 2, 4],
        vec![2, 1, 4],
        vec![1, 3, 4],
        vec![3, 0, 4],
        vec![2, 0, 5],
        vec![1, 2, 5],
        vec![3, 1, 5],
        vec![0, 3, 5],
    ];
    build(p, f)
}

/// Torus with `n` segments around the tube axis and `m` around the tube, radii `r_major`,
/// `r_minor`, as an `n × m` closed grid of quads (every vertex of valence 4; genus 1).
/// Vertex `(i, j)` is `i * m + j`.
pub fn torus(n: usize, m: usize, r_major: f64, r_minor: f64) -> Mesh {
    let mut p = Vec::with_capacity(n * m);
    for i in 0..n {
        let u = 2.0 * PI * i as f64 / n as f64;
        for j in 0..m {
            let v = 2.0 * PI * j as f64 / m as f64;
            let r = r_major + r_minor * v.cos();
            p.push([r * u.cos(), r * u.sin(), r_minor * v.sin()]);
        }
    }
    let id = |i: usize, j: usize| ((i % n) * m + (j % m)) as u32;
    let mut f = Vec::with_capacity(n * m);
    for i in 0..n {
        for j in 0..m {
            f.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    build(p, f)
}

/// The torus grid with each quad split into two triangles.
pub fn torus_triangles(n: usize, m: usize, r_major: f64, r_minor: f64) -> Mesh {
    torus(n, m, r_major, r_minor).triangulated()
}

/// A planar `nx × ny` grid of unit quads in z = 0 (an open disk: one boundary loop, χ 1).
/// Vertex `(i, j)` (column i, row j) is `j * (nx + 1) + i`.
pub fn quad_grid(nx: usize, ny: usize) -> Mesh {
    let mut p = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            p.push([i as f64, j as f64, 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut f = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            f.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    build(p, f)
}

/// UV sphere-like closed triangle mesh: an octahedron refined `k` times by midpoint splits and
/// projected to the unit sphere (4^k · 8 triangles).
pub fn sphere(k: usize) -> Mesh {
    let mut m = octahedron();
    for _ in 0..k {
        let he = super::HalfEdgeMesh::build(&m).expect("octahedron is manifold");
        let tags = super::features::Tags::boundary_only(&he);
        // Loop topology with midpoint positions: reuse Butterfly's face split via edge midpoints
        let (mut next, _) = super::loop_subdivision::step(
            &m,
            &he,
            &tags,
            super::loop_subdivision::LoopWeights::Loop,
        )
        .expect("triangle mesh");
        let nv = m.vertex_count();
        for v in 0..nv {
            next.positions[v] = m.positions[v];
        }
        for e in 0..he.edge_count() {
            let [a, b] = he.edges.verts[e];
            let (pa, pb) = (m.positions[a as usize], m.positions[b as usize]);
            next.positions[nv + e] = std::array::from_fn(|k| 0.5 * (pa[k] + pb[k]));
        }
        m = next;
    }
    for p in m.positions.iter_mut() {
        *p = super::vec3::normalized(*p);
    }
    m
}
