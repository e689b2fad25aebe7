//! Wavefront OBJ: `v x y z [w]`, `vt u v [w]`, `vn x y z`, `f a b c …` where each corner is
//! `v`, `v/vt`, `v//vn` or `v/vt/vn`, indices 1-based or negative (relative to the end of the
//! list so far); `#` comments. Other statements (`o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`)
//! are skipped.
//!
//! Speed: the file is cut at line breaks into chunks parsed in parallel (rayon); negative
//! indices are resolved when the chunks are joined, once the vertex counts before each chunk
//! are known. Floats use the standard library's correctly rounded parser, so writing with `{}`
//! (shortest round-trip) and reading back gives the same bits.

use super::text::{parse_f64, parse_i64};
use crate::mesh::{Attributes, Mesh, NONE};
use crate::{Error, Result};
use rayon::prelude::*;
use std::fmt::Write as _;

/// Relative (negative) indices are stored as `REL + local` until the chunk base is known.
const REL: i64 = -(1 << 40);
const ABSENT: i64 = i64::MAX;

#[derive(Default)]
struct Chunk {
    v: Vec<[f64; 3]>,
    vt: Vec<[f64; 3]>,
    vt_dim: usize,
    vn: Vec<[f64; 3]>,
    degrees: Vec<u32>,
    fv: Vec<i64>,
    ft: Vec<i64>,
    fn_: Vec<i64>,
}

fn index(t: &[u8], local: usize, line: usize) -> Result<i64> {
    let i = parse_i64(t, line)?;
    if i > 0 {
        Ok(i - 1)
    } else if i < 0 {
        Ok(REL + local as i64 + i)
    } else {
        Err(Error::format(
            format!("line {line}: index 0"),
            "1-based or negative OBJ indices",
        ))
    }
}

/// A single pass over the chunk: a cursor reads each line's keyword and then its numbers in
/// place (no per-line splitting or token iterators: the parser touches each byte about once).
fn parse_chunk(bytes: &[u8]) -> Result<Chunk> {
    let mut c = Chunk::default();
    let n = bytes.len();
    let mut i = 0;
    let mut line = 0;
    while i < n {
        line += 1;
        let eol = match memchr_nl(&bytes[i..]) {
            Some(k) => i + k,
            None => n,
        };
        let l = &bytes[..eol];
        let mut j = skip_blank(l, i);
        let ke = token_end(l, j);
        let kw = &l[j..ke];
        j = ke;
        match kw {
            b"v" | b"vn" | b"vt" => vertex_line(&mut c, kw, l, j, line)?,
            b"f" => face_line(&mut c, l, j, line)?,
            _ => {}
        }
        i = eol + 1;
    }
    Ok(c)
}

#[inline]
fn skip_blank(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && (b[i] == b' ' || b[i] == b'\t' || b[i] == b'\r') {
        i += 1;
    }
    i
}

#[inline]
fn token_end(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && !b[i].is_ascii_whitespace() && b[i] != b'#' {
        i += 1;
    }
    i
}

/// A `v`, `vn` or `vt` line `l` (up to its end of line) from `j`, after the keyword `kw`.
fn vertex_line(c: &mut Chunk, kw: &[u8], l: &[u8], mut j: usize, line: usize) -> Result<()> {
    let mut p = [0.0; 3];
    let mut k = 0;
    loop {
        j = skip_blank(l, j);
        if j >= l.len() || l[j] == b'#' || k == 3 {
            break;
        }
        let e = token_end(l, j);
        p[k] = parse_f64(&l[j..e], line)?;
        k += 1;
        j = e;
    }
    match kw {
        b"vt" => {
            if k == 0 {
                return Err(Error::format(
                    format!("line {line}: empty vt"),
                    "vt u [v [w]]",
                ));
            }
            c.vt_dim = c.vt_dim.max(k.max(2));
            c.vt.push(p);
        }
        _ => {
            if k < 3 {
                return Err(Error::format(
                    format!("line {line}: fewer than 3 coordinates"),
                    "x y z",
                ));
            }
            if !p.iter().all(|x| x.is_finite()) {
                return Err(Error::format(
                    format!("line {line}: coordinates {p:?}"),
                    "finite numbers",
                ));
            }
            if kw == b"v" {
                c.v.push(p)
            } else {
                c.vn.push(p)
            }
        }
    }
    Ok(())
}

/// An `f` line `l` (up to its end of line) from `j`: `v[/vt[/vn]]` per corner, at least 3.
fn face_line(c: &mut Chunk, l: &[u8], mut j: usize, line: usize) -> Result<()> {
    let mut deg = 0u32;
    loop {
        j = skip_blank(l, j);
        if j >= l.len() || l[j] == b'#' {
            break;
        }
        let e = token_end(l, j);
        let t = &l[j..e];
        j = e;
        let mut parts = t.split(|&b| b == b'/');
        let v = parts.next().unwrap_or(b"");
        c.fv.push(index(v, c.v.len(), line)?);
        let vt = parts.next().unwrap_or(b"");
        c.ft.push(if vt.is_empty() {
            ABSENT
        } else {
            index(vt, c.vt.len(), line)?
        });
        let vn = parts.next().unwrap_or(b"");
        c.fn_.push(if vn.is_empty() {
            ABSENT
        } else {
            index(vn, c.vn.len(), line)?
        });
        deg += 1;
    }
    if deg < 3 {
        return Err(Error::format(
            format!("line {line}: face with {deg} vertices"),
            "at least 3 vertices per face",
        ));
    }
    c.degrees.push(deg);
    Ok(())
}

/// Position of the next line break (word-at-a-time scan).
#[inline]
fn memchr_nl(b: &[u8]) -> Option<usize> {
    const LO: u64 = 0x0101_0101_0101_0101;
    const HI: u64 = 0x8080_8080_8080_8080;
    const NL: u64 = LO * b'\n' as u64;
    let mut i = 0;
    while i + 8 <= b.len() {
        let w = u64::from_le_bytes(b[i..i + 8].try_into().unwrap()) ^ NL;
        let z = w.wrapping_sub(LO) & !w & HI;
        if z != 0 {
            return Some(i + (z.trailing_zeros() / 8) as usize);
        }
        i += 8;
    }
    b[i..].iter().position(|&c| c == b'\n').map(|k| i + k)
}

/// Cut `bytes` into about `n` pieces at line breaks.
fn split_lines(bytes: &[u8], n: usize) -> Vec<&[u8]> {
    let mut out = Vec::with_capacity(n);
    let step = bytes.len() / n + 1;
    let mut start = 0;
    while start < bytes.len() {
        let mut end = (start + step).min(bytes.len());
        while end < bytes.len() && bytes[end - 1] != b'\n' {
            end += 1;
        }
        out.push(&bytes[start..end]);
        start = end;
    }
    out
}

fn resolve(x: i64, base: usize, total: usize, what: &str) -> Result<u32> {
    let i = if x >= 0 { x } else { x - REL + base as i64 };
    if i < 0 || i as usize >= total {
        let shown = if x >= 0 { x + 1 } else { x - REL - base as i64 };
        return Err(Error::format(
            format!("{what} index {shown} out of range ({total} defined)"),
            "indices of defined elements",
        ));
    }
    Ok(i as u32)
}

/// A chunk's corner indices made global: vertices, texture coordinates, normals.
type Resolved = (Vec<u32>, Vec<u32>, Vec<u32>);

/// Resolve chunk `c`'s corner indices against the counts before it (`bases`) and in all
/// (`totals`), each as (vertex, texture, normal); absent corners become `NONE`, and a kind
/// no face uses (`has_t`, `has_n` false) stays empty.
fn resolve_chunk(
    c: &Chunk,
    (bv, bt, bn): (usize, usize, usize),
    [nv, nt, nn]: [usize; 3],
    has_t: bool,
    has_n: bool,
) -> Result<Resolved> {
    let v =
        c.fv.iter()
            .map(|&x| resolve(x, bv, nv, "vertex"))
            .collect::<Result<Vec<_>>>()?;
    let optional = |list: &[i64], has: bool, base: usize, total: usize, what: &str| {
        if !has {
            return Ok(Vec::new());
        }
        list.iter()
            .map(|&x| {
                if x == ABSENT {
                    Ok(NONE)
                } else {
                    resolve(x, base, total, what)
                }
            })
            .collect::<Result<Vec<_>>>()
    };
    let t = optional(&c.ft, has_t, bt, nt, "texture")?;
    let n = optional(&c.fn_, has_n, bn, nn, "normal")?;
    Ok((v, t, n))
}

/// Parse an OBJ file.
pub fn parse(bytes: &[u8]) -> Result<Mesh> {
    let pieces = if bytes.len() < 1 << 20 {
        vec![bytes]
    } else {
        split_lines(bytes, 4 * rayon::current_num_threads())
    };
    let chunks: Vec<Chunk> = match pieces
        .par_iter()
        .map(|p| parse_chunk(p))
        .collect::<Result<Vec<_>>>()
    {
        Ok(c) => c,
        // re-parse sequentially so the error names the global line number
        Err(e) => return Err(parse_chunk(bytes).err().unwrap_or(e)),
    };
    let nv: usize = chunks.iter().map(|c| c.v.len()).sum();
    if nv == 0 {
        // empty, or text with no OBJ statement in it: not a mesh
        return Err(Error::format(
            "no vertex ('v' line)",
            "an OBJ file with at least one vertex",
        ));
    }
    let nt: usize = chunks.iter().map(|c| c.vt.len()).sum();
    let nn: usize = chunks.iter().map(|c| c.vn.len()).sum();
    let nf: usize = chunks.iter().map(|c| c.degrees.len()).sum();
    let ni: usize = chunks.iter().map(|c| c.fv.len()).sum();
    if ni >= u32::MAX as usize || nv >= u32::MAX as usize {
        return Err(Error::LimitsExceeded {
            what: "OBJ element count",
            requested: ni.max(nv) as u64,
            limit: u32::MAX as u64 - 1,
        });
    }
    let has_t = chunks.iter().any(|c| c.ft.iter().any(|&x| x != ABSENT));
    let has_n = chunks.iter().any(|c| c.fn_.iter().any(|&x| x != ABSENT));
    // bases of each chunk, then each chunk's indices resolved in parallel
    let mut bases = Vec::with_capacity(chunks.len());
    let (mut bv, mut bt, mut bn) = (0, 0, 0);
    for c in &chunks {
        bases.push((bv, bt, bn));
        bv += c.v.len();
        bt += c.vt.len();
        bn += c.vn.len();
    }
    let totals = [nv, nt, nn];
    let resolved: Vec<Resolved> = chunks
        .par_iter()
        .zip(bases.par_iter())
        .map(|(c, &bases)| resolve_chunk(c, bases, totals, has_t, has_n))
        .collect::<Result<Vec<_>>>()?;
    let mut positions = Vec::with_capacity(nv);
    let mut attributes = Attributes::default();
    let mut offsets = Vec::with_capacity(nf + 1);
    let mut indices = Vec::with_capacity(ni);
    offsets.push(0u32);
    let mut acc = 0u32;
    for (c, (v, t, n)) in chunks.iter().zip(resolved) {
        positions.extend_from_slice(&c.v);
        attributes.texcoords.extend_from_slice(&c.vt);
        attributes.texcoord_dim = attributes.texcoord_dim.max(c.vt_dim);
        attributes.normals.extend_from_slice(&c.vn);
        for &d in &c.degrees {
            acc += d;
            offsets.push(acc);
        }
        indices.extend_from_slice(&v);
        attributes.corner_texcoord.extend_from_slice(&t);
        attributes.corner_normal.extend_from_slice(&n);
    }
    Mesh::checked(positions, offsets, indices, attributes)
}

/// Serialise as OBJ. Numbers are written in shortest round-trip form.
pub fn to_bytes(mesh: &Mesh) -> Result<Vec<u8>> {
    let a = &mesh.attributes;
    let normals: &[[f64; 3]] = match &a.vertex_normals {
        Some(n) if a.normals.is_empty() => n,
        _ => &a.normals,
    };
    let per_vertex_normals = a.vertex_normals.is_some() && a.normals.is_empty();
    // positions and faces are formatted in parallel pieces, then joined
    let vlines: Vec<String> = mesh
        .positions
        .par_chunks(4096)
        .map(|ps| {
            let mut s = String::with_capacity(ps.len() * 40);
            for p in ps {
                let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
            }
            s
        })
        .collect();
    let mut out = String::new();
    out.push_str("# written by mra\n");
    for l in &vlines {
        out.push_str(l);
    }
    for t in &a.texcoords {
        match a.texcoord_dim {
            3 => writeln!(out, "vt {} {} {}", t[0], t[1], t[2]),
            _ => writeln!(out, "vt {} {}", t[0], t[1]),
        }
        .ok();
    }
    for n in normals {
        let _ = writeln!(out, "vn {} {} {}", n[0], n[1], n[2]);
    }
    let has_t = !a.corner_texcoord.is_empty();
    let has_n = !a.corner_normal.is_empty() || per_vertex_normals;
    let nf = mesh.face_count();
    let flines: Vec<String> = (0..nf)
        .into_par_iter()
        .chunks(4096)
        .map(|fs| {
            let mut s = String::with_capacity(fs.len() * 32);
            for f in fs {
                s.push('f');
                for c in mesh.offsets[f] as usize..mesh.offsets[f + 1] as usize {
                    let v = mesh.indices[c] + 1;
                    let t = if has_t { a.corner_texcoord[c] } else { NONE };
                    let n = if per_vertex_normals {
                        mesh.indices[c]
                    } else if has_n {
                        a.corner_normal[c]
                    } else {
                        NONE
                    };
                    let _ = match (t != NONE, n != NONE) {
                        (false, false) => write!(s, " {v}"),
                        (true, false) => write!(s, " {v}/{}", t + 1),
                        (false, true) => write!(s, " {v}//{}", n + 1),
                        (true, true) => write!(s, " {v}/{}/{}", t + 1, n + 1),
                    };
                }
                s.push('\n');
            }
            s
        })
        .collect();
    for l in &flines {
        out.push_str(l);
    }
    Ok(out.into_bytes())
}
