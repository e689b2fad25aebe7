//! Marching cubes (§10.6's polygonisation) on a sampled grid, with shared vertices and
//! manifold, consistently oriented output.
//!
//! A sample is *inside* when `value > level`. Each grid edge whose end points differ gets one
//! vertex at the linear zero `t = (level − v₀)/(v₁ − v₀)`; vertices are numbered per plane
//! (grid edge → index), so neighbouring cells share them. Instead of a 256-case table, each
//! cell links its crossings face by face: on every cube face, walked counter-clockwise seen from
//! outside the cell, a segment runs from each *entering* crossing (outside → inside) to a
//! *leaving* one. On an ambiguous face (diagonal corners alike) the asymptotic decider picks the
//! pairing: the inside corners are joined iff `v_a v_c > v_b v_d` (inside pair product above
//! the outside pair product, values minus level), which is the sign of the bilinear saddle.
//! The decision depends only on the face's four samples, so both cells sharing a face draw the
//! same segments; every crossing is the start of one segment and the end of another inside a
//! cell, so the segments close into loops, which are triangulated as fans. The result has every
//! interior edge in exactly two triangles, traversed in opposite directions, with normals
//! pointing from inside (high values) to outside.
//!
//! Work runs over z-slabs with rayon: pass 1 counts crossings per plane, pass 2 emits vertices
//! and triangles per chunk of slabs using two rolling per-plane index maps (no per-cell
//! allocation).

use crate::mesh::Mesh;
use crate::{Error, Result};
use rayon::prelude::*;

/// A scalar grid, `x` fastest: `values[(k·ny + j)·nx + i]` sits at
/// `origin + (i·sx, j·sy, k·sz)`.
#[derive(Clone, Copy, Debug)]
pub struct Grid<'a> {
    pub values: &'a [f32],
    pub dims: [usize; 3],
    pub spacing: [f64; 3],
    pub origin: [f64; 3],
}

/// Output of [`polygonize`]: a triangle mesh and optional vertex normals.
#[derive(Clone, Debug)]
pub struct Isosurface {
    pub mesh: Mesh,
    /// Unit outward normals from the grid gradient (central differences), when asked.
    pub normals: Option<Vec<[f64; 3]>>,
}

// corner c has offset (c & 1, c >> 1 & 1, c >> 2 & 1)
/// Edges as (lower corner, axis); the upper corner is lower + axis bit.
const EDGES: [(u8, u8); 12] = [
    (0, 0),
    (2, 0),
    (4, 0),
    (6, 0),
    (0, 1),
    (1, 1),
    (4, 1),
    (5, 1),
    (0, 2),
    (1, 2),
    (2, 2),
    (3, 2),
];

/// Faces as corners in counter-clockwise order seen from outside the cell.
const FACES: [[u8; 4]; 6] = [
    [0, 4, 6, 2],
    [1, 3, 7, 5],
    [0, 1, 5, 4],
    [2, 6, 7, 3],
    [0, 2, 3, 1],
    [4, 5, 7, 6],
];

const fn edge_of(a: u8, b: u8) -> u8 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    let axis = match hi ^ lo {
        1 => 0,
        2 => 1,
        _ => 2,
    };
    let mut e = 0;
    while e < 12 {
        if EDGES[e].0 == lo && EDGES[e].1 == axis {
            return e as u8;
        }
        e += 1;
    }
    255
}

/// For each face, the cell edge between corner i and corner i+1.
const FACE_EDGES: [[u8; 4]; 6] = {
    let mut t = [[0u8; 4]; 6];
    let mut f = 0;
    while f < 6 {
        let mut i = 0;
        while i < 4 {
            t[f][i] = edge_of(FACES[f][i], FACES[f][(i + 1) % 4]);
            i += 1;
        }
        f += 1;
    }
    t
};

/// For each cell edge, the bit set of cell edges lying on a common cube face with it.
const SHARE: [u16; 12] = {
    let mut t = [0u16; 12];
    let mut f = 0;
    while f < 6 {
        let mut a = 0;
        while a < 4 {
            let mut b = 0;
            while b < 4 {
                t[FACE_EDGES[f][a] as usize] |= 1 << FACE_EDGES[f][b];
                b += 1;
            }
            a += 1;
        }
        f += 1;
    }
    t
};

/// Index flag of a loop-centre vertex (local to a chunk until the merge).
const EXTRA: u32 = 1 << 31;

impl Grid<'_> {
    fn check(&self) -> Result<()> {
        let n: usize = self.dims.iter().product();
        if self.values.len() != n {
            return Err(Error::parameter(
                "grid",
                format!("{} values for dims {:?}", self.values.len(), self.dims),
                "nx·ny·nz values",
            ));
        }
        if self.dims.iter().any(|&d| d < 2) {
            return Err(Error::parameter(
                "grid dims",
                format!("{:?}", self.dims),
                "at least 2 samples per axis",
            ));
        }
        if n > u32::MAX as usize / 8 {
            return Err(Error::LimitsExceeded {
                what: "grid samples",
                requested: n as u64,
                limit: u32::MAX as u64 / 8,
            });
        }
        if self.spacing.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(Error::parameter(
                "spacing",
                format!("{:?}", self.spacing),
                "positive finite spacing",
            ));
        }
        Ok(())
    }
}

const NONE: u32 = u32::MAX;

/// Where [`map_plane`] appends vertex positions and (optionally) normals.
type VertexSink<'a> = Option<(&'a mut Vec<[f64; 3]>, Option<&'a mut Vec<[f64; 3]>>)>;

/// Crossings owned by plane `k`: x and y edges in the plane, z edges to plane `k+1`.
fn count_plane(g: &Grid, level: f64, k: usize) -> usize {
    let [nx, ny, nz] = g.dims;
    let v = g.values;
    let base = k * nx * ny;
    let mut n = 0;
    for j in 0..ny {
        let row = base + j * nx;
        for i in 0..nx {
            let a = v[row + i] as f64 > level;
            if i + 1 < nx && a != (v[row + i + 1] as f64 > level) {
                n += 1;
            }
            if j + 1 < ny && a != (v[row + i + nx] as f64 > level) {
                n += 1;
            }
            if k + 1 < nz && a != (v[row + i + nx * ny] as f64 > level) {
                n += 1;
            }
        }
    }
    n
}

/// Fill `map` (3 entries per grid point of plane `k`) with vertex indices from `first`;
/// append positions (and normals) when `out` is given.
fn map_plane(g: &Grid, level: f64, k: usize, first: u32, map: &mut [u32], mut out: VertexSink<'_>) {
    let [nx, ny, nz] = g.dims;
    let v = g.values;
    let base = k * nx * ny;
    let mut id = first;
    let strides = [1usize, nx, nx * ny];
    for j in 0..ny {
        let row = base + j * nx;
        for i in 0..nx {
            let va = v[row + i] as f64;
            let a = va > level;
            let ok = [i + 1 < nx, j + 1 < ny, k + 1 < nz];
            for axis in 0..3 {
                let m = &mut map[(j * nx + i) * 3 + axis];
                *m = NONE;
                if !ok[axis] {
                    continue;
                }
                let vb = v[row + i + strides[axis]] as f64;
                if a == (vb > level) {
                    continue;
                }
                *m = id;
                id += 1;
                if let Some((pos, nrm)) = out.as_mut() {
                    let (p, n) = edge_vertex(g, level, [i, j, k], axis, nrm.is_some());
                    pos.push(p);
                    if let Some(nrm) = nrm.as_mut() {
                        nrm.push(n);
                    }
                }
            }
        }
    }
}

/// Position (and outward unit normal when `with_normal`) of the crossing on the grid edge from
/// point `p` along `axis`.
fn edge_vertex(
    g: &Grid,
    level: f64,
    p: [usize; 3],
    axis: usize,
    with_normal: bool,
) -> ([f64; 3], [f64; 3]) {
    let [nx, ny, _] = g.dims;
    let at = |q: [usize; 3]| g.values[(q[2] * ny + q[1]) * nx + q[0]] as f64;
    let mut p1 = p;
    p1[axis] += 1;
    let (va, vb) = (at(p), at(p1));
    let t = (level - va) / (vb - va);
    let mut idx = [p[0] as f64, p[1] as f64, p[2] as f64];
    idx[axis] += t;
    let pos = [
        g.origin[0] + g.spacing[0] * idx[0],
        g.origin[1] + g.spacing[1] * idx[1],
        g.origin[2] + g.spacing[2] * idx[2],
    ];
    let mut n = [0.0; 3];
    if with_normal {
        let ga = grad_at(g, p);
        let gb = grad_at(g, p1);
        let gr = [
            ga[0] + t * (gb[0] - ga[0]),
            ga[1] + t * (gb[1] - ga[1]),
            ga[2] + t * (gb[2] - ga[2]),
        ];
        let l = (gr[0] * gr[0] + gr[1] * gr[1] + gr[2] * gr[2]).sqrt();
        if l > 0.0 {
            n = [-gr[0] / l, -gr[1] / l, -gr[2] / l];
        }
    }
    (pos, n)
}

/// Gradient of the samples at a grid point (central differences, one-sided at the border).
fn grad_at(g: &Grid, p: [usize; 3]) -> [f64; 3] {
    let [nx, ny, _] = g.dims;
    let at = |q: [usize; 3]| g.values[(q[2] * ny + q[1]) * nx + q[0]] as f64;
    let mut out = [0.0; 3];
    for a in 0..3 {
        let lo = p[a].saturating_sub(1);
        let hi = (p[a] + 1).min(g.dims[a] - 1);
        let mut ql = p;
        let mut qh = p;
        ql[a] = lo;
        qh[a] = hi;
        out[a] = (at(qh) - at(ql)) / ((hi - lo) as f64 * g.spacing[a]);
    }
    out
}

/// Triangles of the cells in slab `k` (between planes `k` and `k+1`).
#[allow(clippy::too_many_arguments)]
fn slab(
    g: &Grid,
    level: f64,
    k: usize,
    m0: &[u32],
    m1: &[u32],
    tris: &mut Vec<u32>,
    extra: &mut (Vec<[f64; 3]>, Option<Vec<[f64; 3]>>),
) {
    let [nx, ny, _] = g.dims;
    let v = g.values;
    let plane = nx * ny;
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let b = (k * ny + j) * nx + i;
            let corner = [
                b,
                b + 1,
                b + nx,
                b + nx + 1,
                b + plane,
                b + plane + 1,
                b + plane + nx,
                b + plane + nx + 1,
            ];
            let mut val = [0f64; 8];
            let mut case = 0u8;
            for c in 0..8 {
                val[c] = v[corner[c]] as f64 - level;
                if val[c] > 0.0 {
                    case |= 1 << c;
                }
            }
            if case == 0 || case == 255 {
                continue;
            }
            let inside = |c: u8| case >> c & 1 == 1;
            // next[e] = the crossing that follows crossing e in its loop
            let mut next = [255u8; 12];
            for f in 0..6 {
                let q = FACES[f];
                let ins = [inside(q[0]), inside(q[1]), inside(q[2]), inside(q[3])];
                let fe = FACE_EDGES[f];
                let mut enter = [0usize; 2];
                let mut leave = [0usize; 2];
                let (mut ne, mut nl) = (0, 0);
                for i in 0..4 {
                    let (a, bb) = (ins[i], ins[(i + 1) % 4]);
                    if !a && bb {
                        enter[ne] = i;
                        ne += 1;
                    } else if a && !bb {
                        leave[nl] = i;
                        nl += 1;
                    }
                }
                if ne == 1 {
                    next[fe[enter[0]] as usize] = fe[leave[0]];
                } else if ne == 2 {
                    // ambiguous face: asymptotic decider
                    let (p_in, p_out) = if ins[0] {
                        (
                            val[q[0] as usize] * val[q[2] as usize],
                            val[q[1] as usize] * val[q[3] as usize],
                        )
                    } else {
                        (
                            val[q[1] as usize] * val[q[3] as usize],
                            val[q[0] as usize] * val[q[2] as usize],
                        )
                    };
                    let joined = p_in > p_out;
                    for &e in &enter {
                        // separated: pair with the next edge (around one inside corner);
                        // joined: with the previous edge (around one outside corner)
                        let partner = if joined { (e + 3) % 4 } else { (e + 1) % 4 };
                        next[fe[e] as usize] = fe[partner];
                    }
                }
            }
            let id = |e: u8| -> u32 {
                let (c, axis) = EDGES[e as usize];
                let (di, dj, dk) = (
                    (c & 1) as usize,
                    (c >> 1 & 1) as usize,
                    (c >> 2 & 1) as usize,
                );
                let m = if dk == 0 { m0 } else { m1 };
                m[((j + dj) * nx + i + di) * 3 + axis as usize]
            };
            let mut seen = 0u16;
            for start in 0..12u8 {
                if next[start as usize] == 255 || seen >> start & 1 == 1 {
                    continue;
                }
                let mut lp = [0u8; 12];
                let mut n = 0;
                let mut cur = start;
                loop {
                    seen |= 1 << cur;
                    lp[n] = cur;
                    n += 1;
                    cur = next[cur as usize];
                    if cur == start || n == 12 {
                        break;
                    }
                }
                // a fan from lp[s] is safe when none of its diagonals joins two vertices of one
                // cube face (a neighbour could draw the same diagonal: non-manifold edge)
                let safe = (0..n).find(|&s| {
                    (2..n - 1).all(|o| SHARE[lp[s] as usize] >> lp[(s + o) % n] & 1 == 0)
                });
                match safe {
                    Some(s) => {
                        let v0 = id(lp[s]);
                        for o in 1..n - 1 {
                            tris.extend_from_slice(&[
                                v0,
                                id(lp[(s + o) % n]),
                                id(lp[(s + o + 1) % n]),
                            ]);
                        }
                    }
                    None => {
                        // centre vertex: every new edge is private to this cell
                        let mut c = [0.0; 3];
                        let mut cn = [0.0; 3];
                        for &e in &lp[..n] {
                            let (cc, axis) = EDGES[e as usize];
                            let p = [
                                i + (cc & 1) as usize,
                                j + (cc >> 1 & 1) as usize,
                                k + (cc >> 2 & 1) as usize,
                            ];
                            let (q, nn) =
                                edge_vertex(g, level, p, axis as usize, extra.1.is_some());
                            for a in 0..3 {
                                c[a] += q[a] / n as f64;
                                cn[a] += nn[a];
                            }
                        }
                        let vc = EXTRA | extra.0.len() as u32;
                        extra.0.push(c);
                        if let Some(en) = extra.1.as_mut() {
                            let l = (cn[0] * cn[0] + cn[1] * cn[1] + cn[2] * cn[2]).sqrt();
                            en.push(if l > 0.0 {
                                [cn[0] / l, cn[1] / l, cn[2] / l]
                            } else {
                                cn
                            });
                        }
                        for o in 0..n {
                            tris.extend_from_slice(&[vc, id(lp[o]), id(lp[(o + 1) % n])]);
                        }
                    }
                }
            }
        }
    }
}

/// Polygonise the isosurface `value = level` of `grid` (inside where `value > level`).
pub fn polygonize(grid: &Grid, level: f64, normals: bool) -> Result<Isosurface> {
    grid.check()?;
    if !level.is_finite() {
        return Err(Error::parameter("level", level, "a finite number"));
    }
    let [nx, ny, nz] = grid.dims;
    let counts: Vec<usize> = (0..nz)
        .into_par_iter()
        .map(|k| count_plane(grid, level, k))
        .collect();
    let mut base = vec![0u32; nz + 1];
    for k in 0..nz {
        base[k + 1] = base[k] + counts[k] as u32;
    }
    let threads = rayon::current_num_threads().max(1);
    let chunk = nz.div_ceil(threads * 4).max(1);
    let chunks: Vec<(usize, usize)> = (0..nz)
        .step_by(chunk)
        .map(|s| (s, (s + chunk).min(nz)))
        .collect();
    type Part = (
        Vec<[f64; 3]>,
        Vec<[f64; 3]>,
        Vec<u32>,
        (Vec<[f64; 3]>, Option<Vec<[f64; 3]>>),
    );
    let parts: Vec<Part> = chunks
        .par_iter()
        .map(|&(p0, p1)| {
            let mut pos = Vec::with_capacity((base[p1] - base[p0]) as usize);
            let mut nrm = Vec::new();
            let mut tris = Vec::new();
            let mut extra = (Vec::new(), normals.then(Vec::new));
            let mut m0 = vec![NONE; nx * ny * 3];
            let mut m1 = vec![NONE; nx * ny * 3];
            map_plane(
                grid,
                level,
                p0,
                base[p0],
                &mut m0,
                Some((&mut pos, normals.then_some(&mut nrm))),
            );
            for k in p0..p1.min(nz - 1) {
                let owned = k + 1 < p1;
                map_plane(
                    grid,
                    level,
                    k + 1,
                    base[k + 1],
                    &mut m1,
                    owned.then_some((&mut pos, normals.then_some(&mut nrm))),
                );
                slab(grid, level, k, &m0, &m1, &mut tris, &mut extra);
                std::mem::swap(&mut m0, &mut m1);
            }
            (pos, nrm, tris, extra)
        })
        .collect();
    let nv = base[nz] as usize;
    let n_extra: usize = parts.iter().map(|p| p.3 .0.len()).sum();
    let mut positions = Vec::with_capacity(nv + n_extra);
    let mut nrm_all = Vec::with_capacity(if normals { nv + n_extra } else { 0 });
    for p in &parts {
        positions.extend_from_slice(&p.0);
        nrm_all.extend_from_slice(&p.1);
    }
    let mut indices = Vec::with_capacity(parts.iter().map(|p| p.2.len()).sum());
    for (_, _, t, (ex, exn)) in parts {
        let off = positions.len() as u32;
        indices.extend(t.iter().map(|&v| {
            if v & EXTRA != 0 {
                off + (v & !EXTRA)
            } else {
                v
            }
        }));
        positions.extend_from_slice(&ex);
        if let Some(exn) = exn {
            nrm_all.extend_from_slice(&exn);
        }
    }
    let nf = indices.len() / 3;
    let mesh = Mesh {
        positions,
        offsets: (0..=nf as u32).map(|f| 3 * f).collect(),
        indices,
        attributes: Default::default(),
    };
    Ok(Isosurface {
        mesh,
        normals: normals.then_some(nrm_all),
    })
}

/// Area and enclosed (signed) volume of a triangle mesh (divergence theorem; positive when
/// the triangles face outwards).
pub fn area_volume(mesh: &Mesh) -> (f64, f64) {
    let mut area = 0.0;
    let mut vol = 0.0;
    for f in mesh.faces() {
        let p0 = mesh.positions[f[0] as usize];
        for w in 1..f.len() - 1 {
            let p1 = mesh.positions[f[w] as usize];
            let p2 = mesh.positions[f[w + 1] as usize];
            let u = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
            let v = [p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]];
            let c = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            area += 0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            vol += (p0[0] * (p1[1] * p2[2] - p1[2] * p2[1])
                + p0[1] * (p1[2] * p2[0] - p1[0] * p2[2])
                + p0[2] * (p1[0] * p2[1] - p1[1] * p2[0]))
                / 6.0;
        }
    }
    (area, vol)
}
