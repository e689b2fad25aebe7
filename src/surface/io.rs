//! A minimal mesh writer (OBJ, ASCII PLY) and OBJ reader for tessellated surfaces. Kept small on
//! purpose: `src/mesh/` holds the project's full mesh I/O, which can replace it.

use super::mesh::Mesh;
use super::{add, cross, normalize, sub};
use crate::{Error, Result};
use std::fmt::Write;

/// Wavefront OBJ: `v`, `vn`, and faces `f a//a b//b …` (1-based).
pub fn write_obj(m: &Mesh) -> String {
    let mut s = String::with_capacity(m.positions.len() * 64 + m.faces.len() * 32);
    let _ = writeln!(
        s,
        "# mra surface: {} vertices, {} faces",
        m.positions.len(),
        m.faces.len()
    );
    for p in &m.positions {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    for n in &m.normals {
        let _ = writeln!(s, "vn {} {} {}", n[0], n[1], n[2]);
    }
    for f in &m.faces {
        s.push('f');
        for &i in f {
            let _ = write!(s, " {0}//{0}", i + 1);
        }
        s.push('\n');
    }
    s
}

/// ASCII PLY with per-vertex normals.
pub fn write_ply(m: &Mesh) -> String {
    let mut s = String::with_capacity(m.positions.len() * 80 + m.faces.len() * 24);
    let _ = write!(
        s,
        "ply\nformat ascii 1.0\ncomment mra surface\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         property double nx\nproperty double ny\nproperty double nz\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        m.positions.len(),
        m.faces.len()
    );
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let _ = writeln!(s, "{} {} {} {} {} {}", p[0], p[1], p[2], n[0], n[1], n[2]);
    }
    for f in &m.faces {
        let _ = write!(s, "{}", f.len());
        for i in f {
            let _ = write!(s, " {i}");
        }
        s.push('\n');
    }
    s
}

/// Read the positions and faces of an OBJ file (`v` and `f` lines; `f` entries may be `a`,
/// `a/b`, `a//c`, `a/b/c`, negative indices count from the end). Normals are recomputed as
/// area-weighted averages of the face normals.
pub fn read_obj(text: &str) -> Result<Mesh> {
    let mut m = Mesh::default();
    for (ln, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it
                    .take(3)
                    .map(|t| t.parse::<f64>())
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| {
                        Error::format(format!("line {}: bad vertex {:?}", ln + 1, line), "v x y z")
                    })?;
                if c.len() != 3 || c.iter().any(|x| !x.is_finite()) {
                    return Err(Error::format(
                        format!("line {}: bad vertex {:?}", ln + 1, line),
                        "v x y z",
                    ));
                }
                m.positions.push([c[0], c[1], c[2]]);
            }
            Some("f") => {
                let mut f = Vec::new();
                for t in it {
                    let first = t.split('/').next().unwrap_or("");
                    let i: i64 = first.parse().map_err(|_| {
                        Error::format(
                            format!("line {}: bad face index {:?}", ln + 1, t),
                            "f i j k …",
                        )
                    })?;
                    let n = m.positions.len() as i64;
                    let idx = if i < 0 { n + i } else { i - 1 };
                    if idx < 0 || idx >= n {
                        return Err(Error::format(
                            format!("line {}: face index {} with {} vertices", ln + 1, i, n),
                            "indices of vertices defined above",
                        ));
                    }
                    f.push(idx as u32);
                }
                if f.len() >= 3 {
                    m.faces.push(f);
                }
            }
            _ => {}
        }
    }
    if m.faces.is_empty() {
        return Err(Error::format("no faces", "an OBJ mesh with f lines"));
    }
    m.normals = vertex_normals(&m.positions, &m.faces);
    Ok(m)
}

/// Area-weighted vertex normals (fan-triangulated faces).
pub fn vertex_normals(pos: &[[f64; 3]], faces: &[Vec<u32>]) -> Vec<[f64; 3]> {
    let mut acc = vec![[0.0; 3]; pos.len()];
    for f in faces {
        for t in 1..f.len() - 1 {
            let (a, b, c) = (
                pos[f[0] as usize],
                pos[f[t] as usize],
                pos[f[t + 1] as usize],
            );
            let n = cross(sub(b, a), sub(c, a));
            for &v in &[f[0], f[t], f[t + 1]] {
                acc[v as usize] = add(acc[v as usize], n);
            }
        }
    }
    acc.into_iter()
        .map(|n| normalize(n).unwrap_or([0.0, 0.0, 1.0]))
        .collect()
}
