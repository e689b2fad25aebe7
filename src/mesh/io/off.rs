//! Object File Format: a first line `OFF` (optionally followed by the counts), then
//! `V F E`, V lines `x y z` and F lines `n i_0 … i_{n-1}` (anything after the indices, such as
//! a colour, is ignored). `#` starts a comment.

use super::text::{parse_f64, parse_i64, tokens};
use crate::mesh::{Attributes, Mesh};
use crate::{Error, Result};
use std::fmt::Write as _;

/// Parse an OFF file.
pub fn parse(bytes: &[u8]) -> Result<Mesh> {
    // numbered, comment-free, non-empty lines
    let mut lines = bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.split(|&b| b == b'#').next().unwrap_or(b"")))
        .filter(|(_, l)| tokens(l).next().is_some());
    let (ln, first) = lines
        .next()
        .ok_or_else(|| Error::format("empty file", "an OFF header"))?;
    let mut head = tokens(first);
    let magic = head.next().unwrap_or(b"");
    if magic != b"OFF" {
        return Err(Error::format(
            format!("line {ln}: header {:?}", String::from_utf8_lossy(magic)),
            "OFF",
        ));
    }
    let mut counts: Vec<i64> = head.map(|t| parse_i64(t, ln)).collect::<Result<_>>()?;
    if counts.is_empty() {
        let (ln, l) = lines
            .next()
            .ok_or_else(|| Error::format("no counts line", "V F E"))?;
        counts = tokens(l).map(|t| parse_i64(t, ln)).collect::<Result<_>>()?;
    }
    if counts.len() < 2 || counts[0] < 1 || counts[1] < 0 {
        return Err(Error::format(
            format!("counts {counts:?}"),
            "V F E with V ≥ 1, F ≥ 0",
        ));
    }
    let (nv, nf) = (counts[0] as usize, counts[1] as usize);
    if nv.saturating_add(nf) > bytes.len() {
        return Err(Error::LimitsExceeded {
            what: "OFF element count (bounded by the file's size in bytes)",
            requested: (nv as u64).saturating_add(nf as u64),
            limit: bytes.len() as u64,
        });
    }
    let mut positions = Vec::with_capacity(nv);
    for _ in 0..nv {
        let (ln, l) = lines.next().ok_or_else(|| {
            Error::format(
                format!("file ends after {} of {nv} vertices", positions.len()),
                "V vertex lines",
            )
        })?;
        let mut t = tokens(l);
        let mut p = [0.0; 3];
        for x in p.iter_mut() {
            *x = parse_f64(t.next().unwrap_or(b""), ln)?;
        }
        positions.push(p);
    }
    let mut offsets = Vec::with_capacity(nf + 1);
    offsets.push(0u32);
    let mut indices = Vec::with_capacity(3 * nf);
    for f in 0..nf {
        let (ln, l) = lines.next().ok_or_else(|| {
            Error::format(format!("file ends after {f} of {nf} faces"), "F face lines")
        })?;
        let mut t = tokens(l);
        let n = parse_i64(t.next().unwrap_or(b""), ln)?;
        if !(3..=1_000_000).contains(&n) {
            return Err(Error::format(
                format!("line {ln}: face with {n} vertices"),
                "at least 3 vertices per face",
            ));
        }
        for _ in 0..n {
            let i = parse_i64(t.next().unwrap_or(b""), ln)?;
            if i < 0 || i as usize >= nv {
                return Err(Error::format(
                    format!("line {ln}: face {f} refers to vertex {i} but there are {nv} vertices"),
                    "vertex indices in range",
                ));
            }
            indices.push(i as u32);
        }
        offsets.push(indices.len() as u32);
    }
    Mesh::checked(positions, offsets, indices, Attributes::default())
}

/// Serialise as OFF (numbers in shortest round-trip form).
pub fn to_bytes(mesh: &Mesh) -> Result<Vec<u8>> {
    let mut s = String::with_capacity(mesh.vertex_count() * 40 + mesh.indices.len() * 8);
    let _ = writeln!(s, "OFF\n{} {} 0", mesh.vertex_count(), mesh.face_count());
    for p in &mesh.positions {
        let _ = writeln!(s, "{} {} {}", p[0], p[1], p[2]);
    }
    for f in mesh.faces() {
        let _ = write!(s, "{}", f.len());
        for i in f {
            let _ = write!(s, " {i}");
        }
        s.push('\n');
    }
    Ok(s.into_bytes())
}
