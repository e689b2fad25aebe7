//! Stanford PLY: `ascii`, `binary_little_endian` and `binary_big_endian`. Element `vertex` must
//! have `x y z`; its other scalar properties are kept (in order, with their types) as
//! [`crate::mesh::Property`]s. Element `face` must have a list property `vertex_indices` (or
//! `vertex_index`); its other scalar properties are kept too. Other elements and other list
//! properties are read past and dropped. Declared counts are checked against the bytes present
//! before anything is allocated.

use crate::mesh::attributes::ScalarType;
use crate::mesh::{Attributes, Mesh, Property};
use crate::{Error, Result};
use std::fmt::Write as _;

/// PLY body encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

#[derive(Debug)]
enum PropKind {
    Scalar(ScalarType),
    List(ScalarType, ScalarType),
}

#[derive(Debug)]
struct PropDecl {
    name: String,
    kind: PropKind,
}

#[derive(Debug)]
struct ElementDecl {
    name: String,
    count: usize,
    props: Vec<PropDecl>,
}

fn bad(what: impl std::fmt::Display) -> Error {
    Error::format(what, "a valid PLY file")
}

fn parse_header(bytes: &[u8]) -> Result<(Encoding, Vec<ElementDecl>, usize)> {
    if !bytes.starts_with(b"ply") {
        return Err(bad("missing 'ply' magic"));
    }
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| bad("no end_header"))?;
    let mut body = end + 10;
    // the header ends with "end_header" then \n (or \r\n)
    if bytes.get(body) == Some(&b'\r') {
        body += 1;
    }
    if bytes.get(body) == Some(&b'\n') {
        body += 1;
    }
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| bad("header is not text"))?;
    let mut encoding = None;
    let mut elements: Vec<ElementDecl> = Vec::new();
    for line in header.lines().skip(1) {
        let t: Vec<&str> = line.split_whitespace().collect();
        match t.first().copied() {
            Some("format") => {
                encoding = Some(match t.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::BinaryLittleEndian,
                    Some("binary_big_endian") => Encoding::BinaryBigEndian,
                    other => {
                        return Err(Error::Unsupported {
                            what: "PLY format",
                            value: format!("{other:?}"),
                        })
                    }
                })
            }
            Some("element") => {
                let name = t
                    .get(1)
                    .ok_or_else(|| bad("element without a name"))?
                    .to_string();
                let count = t
                    .get(2)
                    .and_then(|c| c.parse::<usize>().ok())
                    .ok_or_else(|| bad(format!("element {name} has no valid count")))?;
                elements.push(ElementDecl {
                    name,
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?;
                let ty = |s: Option<&&str>| {
                    s.and_then(|s| ScalarType::from_ply(s))
                        .ok_or_else(|| bad(format!("unknown property type in {line:?}")))
                };
                let (kind, name) = if t.get(1) == Some(&"list") {
                    (PropKind::List(ty(t.get(2))?, ty(t.get(3))?), t.get(4))
                } else {
                    (PropKind::Scalar(ty(t.get(1))?), t.get(2))
                };
                let name = name.ok_or_else(|| bad(format!("property without a name: {line:?}")))?;
                el.props.push(PropDecl {
                    name: name.to_string(),
                    kind,
                });
            }
            Some("comment") | Some("obj_info") | None => {}
            Some(other) => return Err(bad(format!("unknown header keyword {other:?}"))),
        }
    }
    let encoding = encoding.ok_or_else(|| bad("no format line"))?;
    Ok((encoding, elements, body))
}

/// A cursor over the body that yields numbers in either encoding.
struct Body<'a> {
    bytes: &'a [u8],
    pos: usize,
    enc: Encoding,
}

impl Body<'_> {
    #[inline]
    fn binary(&mut self, ty: ScalarType) -> Result<f64> {
        let n = ty.size();
        let b = self.bytes.get(self.pos..self.pos + n).ok_or_else(|| {
            bad(format!(
                "file ends at byte {} inside the body",
                self.bytes.len()
            ))
        })?;
        self.pos += n;
        let le = self.enc == Encoding::BinaryLittleEndian;
        macro_rules! rd {
            ($t:ty) => {{
                let a = b.try_into().unwrap();
                (if le {
                    <$t>::from_le_bytes(a)
                } else {
                    <$t>::from_be_bytes(a)
                }) as f64
            }};
        }
        Ok(match ty {
            ScalarType::I8 => b[0] as i8 as f64,
            ScalarType::U8 => b[0] as f64,
            ScalarType::I16 => rd!(i16),
            ScalarType::U16 => rd!(u16),
            ScalarType::I32 => rd!(i32),
            ScalarType::U32 => rd!(u32),
            ScalarType::F32 => rd!(f32),
            ScalarType::F64 => rd!(f64),
        })
    }

    #[inline]
    fn ascii(&mut self) -> Result<f64> {
        let b = self.bytes;
        let mut i = self.pos;
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        let s = i;
        while i < b.len() && !b[i].is_ascii_whitespace() {
            i += 1;
        }
        self.pos = i;
        if s == i {
            return Err(bad("the body ends before all elements were read"));
        }
        std::str::from_utf8(&b[s..i])
            .ok()
            .and_then(|t| t.parse::<f64>().ok())
            .ok_or_else(|| {
                bad(format!(
                    "{:?} is not a number",
                    String::from_utf8_lossy(&b[s..i])
                ))
            })
    }

    #[inline]
    fn value(&mut self, ty: ScalarType) -> Result<f64> {
        if self.enc == Encoding::Ascii {
            self.ascii()
        } else {
            self.binary(ty)
        }
    }
}

/// Parse a PLY file.
pub fn parse(bytes: &[u8]) -> Result<Mesh> {
    let (enc, elements, body) = parse_header(bytes)?;
    let remaining = bytes.len() - body;
    // every element takes at least one byte (binary) or two (ascii: a digit and a separator)
    let total: usize = elements
        .iter()
        .map(|e| e.count)
        .fold(0usize, |a, c| a.saturating_add(c));
    if total > remaining {
        return Err(Error::LimitsExceeded {
            what: "PLY element count (bounded by the bytes after the header)",
            requested: total as u64,
            limit: remaining as u64,
        });
    }
    let mut b = Body {
        bytes,
        pos: body,
        enc,
    };
    let mut positions = Vec::new();
    let mut offsets = vec![0u32];
    let mut indices = Vec::new();
    let mut attributes = Attributes::default();
    let mut seen_vertex = false;
    let mut seen_face = false;
    for el in &elements {
        match el.name.as_str() {
            "vertex" => {
                seen_vertex = true;
                read_vertices(el, &mut b, &mut attributes, &mut positions)?;
            }
            "face" => {
                seen_face = true;
                let faces = Faces {
                    offsets: &mut offsets,
                    indices: &mut indices,
                    attributes: &mut attributes,
                };
                read_faces(el, &mut b, faces, remaining)?;
            }
            _ => skip_element(el, &mut b)?,
        }
    }
    if !seen_vertex {
        return Err(bad("no vertex element"));
    }
    if positions.is_empty() {
        return Err(bad("no vertices (element vertex 0)"));
    }
    if !seen_face {
        attributes.face_list_types = None;
    }
    Mesh::checked(positions, offsets, indices, attributes)
}

/// The vertices of element `el`: positions (x, y, z) and the other scalar properties as
/// vertex attributes (lists skipped).
fn read_vertices(
    el: &ElementDecl,
    b: &mut Body,
    attributes: &mut Attributes,
    positions: &mut Vec<[f64; 3]>,
) -> Result<()> {
    let mut xyz = [usize::MAX; 3];
    for (i, p) in el.props.iter().enumerate() {
        let k = match p.name.as_str() {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => {
                if let PropKind::Scalar(ty) = p.kind {
                    attributes.vertex.push(Property {
                        name: p.name.clone(),
                        ty,
                        values: Vec::with_capacity(el.count),
                    });
                }
                continue;
            }
        };
        match p.kind {
            PropKind::Scalar(ty) => {
                xyz[k] = i;
                attributes.position_type = Some(ty);
            }
            PropKind::List(..) => return Err(bad("vertex coordinate declared as a list")),
        }
    }
    if xyz.contains(&usize::MAX) {
        return Err(bad("vertex element without x, y and z"));
    }
    positions.reserve(el.count);
    // fast path: binary with only x y z of one type
    for _ in 0..el.count {
        let mut p = [0.0; 3];
        let mut extra = 0;
        for (i, pd) in el.props.iter().enumerate() {
            match pd.kind {
                PropKind::Scalar(ty) => {
                    let x = b.value(ty)?;
                    if let Some(k) = xyz.iter().position(|&j| j == i) {
                        p[k] = x;
                    } else {
                        attributes.vertex[extra].values.push(x);
                        extra += 1;
                    }
                }
                PropKind::List(ct, it) => {
                    let n = b.value(ct)? as usize;
                    for _ in 0..n {
                        b.value(it)?;
                    }
                }
            }
        }
        positions.push(p);
    }
    Ok(())
}

/// Where the faces go: the polygons (offsets, indices) and the face attributes.
struct Faces<'a> {
    offsets: &'a mut Vec<u32>,
    indices: &'a mut Vec<u32>,
    attributes: &'a mut Attributes,
}

/// The faces of element `el` (`remaining`: the bytes after the header, which bound the
/// indices reserved).
fn read_faces(el: &ElementDecl, b: &mut Body, faces: Faces, remaining: usize) -> Result<()> {
    let Faces {
        offsets,
        indices,
        attributes,
    } = faces;
    let list = el
        .props
        .iter()
        .position(|p| {
            matches!(p.kind, PropKind::List(..))
                && (p.name == "vertex_indices" || p.name == "vertex_index")
        })
        .ok_or_else(|| bad("face element without a vertex_indices list"))?;
    if let PropKind::List(ct, it) = el.props[list].kind {
        attributes.face_list_types = Some((ct, it));
    }
    attributes.face_list_name = Some(el.props[list].name.clone());
    for (i, p) in el.props.iter().enumerate() {
        if let (PropKind::Scalar(ty), true) = (&p.kind, i != list) {
            attributes.face.push(Property {
                name: p.name.clone(),
                ty: *ty,
                values: Vec::with_capacity(el.count),
            });
        }
    }
    offsets.reserve(el.count);
    indices.reserve(el.count.saturating_mul(3).min(remaining));
    for f in 0..el.count {
        let mut extra = 0;
        for (i, pd) in el.props.iter().enumerate() {
            match pd.kind {
                PropKind::Scalar(ty) => {
                    let x = b.value(ty)?;
                    attributes.face[extra].values.push(x);
                    extra += 1;
                }
                PropKind::List(ct, it) => {
                    let n = b.value(ct)?;
                    if !(0.0..=1e6).contains(&n) || n.fract() != 0.0 {
                        return Err(bad(format!("face {f} has a list length of {n}")));
                    }
                    for _ in 0..n as usize {
                        let x = b.value(it)?;
                        if i == list {
                            if !(0.0..4294967295.0).contains(&x) || x.fract() != 0.0 {
                                return Err(Error::format(
                                    format!("face {f} refers to vertex {x}"),
                                    "vertex indices in range",
                                ));
                            }
                            indices.push(x as u32);
                        }
                    }
                    if i == list {
                        offsets.push(indices.len() as u32);
                    }
                }
            }
        }
    }
    Ok(())
}

/// Element `el` read past (neither vertices nor faces).
fn skip_element(el: &ElementDecl, b: &mut Body) -> Result<()> {
    for _ in 0..el.count {
        for pd in &el.props {
            match pd.kind {
                PropKind::Scalar(ty) => {
                    b.value(ty)?;
                }
                PropKind::List(ct, it) => {
                    let n = b.value(ct)?;
                    if !(0.0..=1e6).contains(&n) {
                        return Err(bad(format!("list length {n} in element {}", el.name)));
                    }
                    for _ in 0..n as usize {
                        b.value(it)?;
                    }
                }
            }
        }
    }
    Ok(())
}

fn put(out: &mut Vec<u8>, enc: Encoding, ty: ScalarType, x: f64) {
    match enc {
        Encoding::Ascii => {
            let mut s = String::new();
            let _ = write!(s, "{x}");
            out.extend_from_slice(s.as_bytes());
        }
        _ => {
            let mut b = [0u8; 8];
            let n = put_bin(&mut b, enc == Encoding::BinaryLittleEndian, ty, x);
            out.extend_from_slice(&b[..n]);
        }
    }
}

/// Serialise as PLY with the given encoding. Positions keep the type they were read with
/// (default `double`), face lists `uchar`/`int` (or as read), extra properties as read.
pub fn to_bytes(mesh: &Mesh, enc: Encoding) -> Result<Vec<u8>> {
    let a = &mesh.attributes;
    let pty = a.position_type.unwrap_or(ScalarType::F64);
    let (ct, it) = a
        .face_list_types
        .unwrap_or((ScalarType::U8, ScalarType::I32));
    let max_deg = (0..mesh.face_count())
        .map(|f| mesh.face_degree(f))
        .max()
        .unwrap_or(0);
    let ct = if max_deg > 255 && ct.size() == 1 {
        ScalarType::I32
    } else {
        ct
    };
    let mut vprops: Vec<(&str, ScalarType, &[f64])> = a
        .vertex
        .iter()
        .map(|p| (p.name.as_str(), p.ty, &p.values[..]))
        .collect();
    let normals_flat: Vec<Vec<f64>>;
    if let Some(n) = &a.vertex_normals {
        if !a.vertex.iter().any(|p| p.name == "nx") {
            normals_flat = (0..3).map(|k| n.iter().map(|v| v[k]).collect()).collect();
            for (k, name) in ["nx", "ny", "nz"].into_iter().enumerate() {
                vprops.push((name, ScalarType::F32.max_for(pty), &normals_flat[k]));
            }
        }
    }
    for (name, _, vals) in &vprops {
        if vals.len() != mesh.vertex_count() {
            return Err(Error::parameter(
                "vertex property length",
                name,
                "one value per vertex",
            ));
        }
    }
    for p in &a.face {
        if p.values.len() != mesh.face_count() {
            return Err(Error::parameter(
                "face property length",
                &p.name,
                "one value per face",
            ));
        }
    }
    let mut out = Vec::with_capacity(mesh.vertex_count() * 24 + mesh.indices.len() * 4 + 256);
    out.extend_from_slice(header(mesh, enc, pty, (ct, it), &vprops).as_bytes());
    if enc != Encoding::Ascii {
        binary_body(mesh, enc, pty, (ct, it), &vprops, &mut out);
        return Ok(out);
    }
    ascii_body(mesh, pty, (ct, it), &vprops, &mut out);
    Ok(out)
}

/// The PLY header: format, the vertex element (x, y, z as `pty`, then `vprops`), the face
/// element (count and index list types, then the face properties).
fn header(
    mesh: &Mesh,
    enc: Encoding,
    pty: ScalarType,
    (ct, it): (ScalarType, ScalarType),
    vprops: &[(&str, ScalarType, &[f64])],
) -> String {
    let a = &mesh.attributes;
    let mut h = String::new();
    let fmt = match enc {
        Encoding::Ascii => "ascii",
        Encoding::BinaryLittleEndian => "binary_little_endian",
        Encoding::BinaryBigEndian => "binary_big_endian",
    };
    let _ = writeln!(h, "ply\nformat {fmt} 1.0\ncomment written by mra");
    let _ = writeln!(h, "element vertex {}", mesh.vertex_count());
    for c in ["x", "y", "z"] {
        let _ = writeln!(h, "property {} {c}", pty.ply_name());
    }
    for (name, ty, _) in vprops {
        let _ = writeln!(h, "property {} {name}", ty.ply_name());
    }
    let _ = writeln!(h, "element face {}", mesh.face_count());
    let list_name = a.face_list_name.as_deref().unwrap_or("vertex_indices");
    let _ = writeln!(
        h,
        "property list {} {} {list_name}",
        ct.ply_name(),
        it.ply_name()
    );
    for p in &a.face {
        let _ = writeln!(h, "property {} {}", p.ty.ply_name(), p.name);
    }
    h.push_str("end_header\n");
    h
}

/// The ASCII body: one line per vertex, then one per face.
fn ascii_body(
    mesh: &Mesh,
    pty: ScalarType,
    (ct, it): (ScalarType, ScalarType),
    vprops: &[(&str, ScalarType, &[f64])],
    out: &mut Vec<u8>,
) {
    let a = &mesh.attributes;
    for (v, p) in mesh.positions.iter().enumerate() {
        for (k, &x) in p.iter().enumerate() {
            if k > 0 {
                out.push(b' ');
            }
            put(out, Encoding::Ascii, pty, x);
        }
        for (_, ty, vals) in vprops {
            out.push(b' ');
            put(out, Encoding::Ascii, *ty, vals[v]);
        }
        out.push(b'\n');
    }
    for f in 0..mesh.face_count() {
        let face = mesh.face(f);
        put(out, Encoding::Ascii, ct, face.len() as f64);
        for &i in face {
            out.push(b' ');
            put(out, Encoding::Ascii, it, i as f64);
        }
        for p in &a.face {
            out.push(b' ');
            put(out, Encoding::Ascii, p.ty, p.values[f]);
        }
        out.push(b'\n');
    }
}

/// `x` as `ty` into the front of `dst` (binary encodings); returns the bytes written.
#[inline]
fn put_bin(dst: &mut [u8], le: bool, ty: ScalarType, x: f64) -> usize {
    macro_rules! wr {
        ($t:ty) => {{
            let v = x as $t;
            let b = if le { v.to_le_bytes() } else { v.to_be_bytes() };
            dst[..b.len()].copy_from_slice(&b);
            b.len()
        }};
    }
    match ty {
        ScalarType::I8 => wr!(i8),
        ScalarType::U8 => wr!(u8),
        ScalarType::I16 => wr!(i16),
        ScalarType::U16 => wr!(u16),
        ScalarType::I32 => wr!(i32),
        ScalarType::U32 => wr!(u32),
        ScalarType::F32 => wr!(f32),
        ScalarType::F64 => wr!(f64),
    }
}

/// Vertices (or faces) per parallel chunk of the binary body.
const BODY_CHUNK: usize = 1 << 14;

/// The binary body, the same bytes as the value-by-value writer: every vertex record
/// has a fixed size and face `f` starts at `f · (count + face properties) + offsets[f] ·
/// index` bytes into the face block, so chunks of vertices and of faces are serialised
/// in parallel straight into their place in one buffer.
fn binary_body(
    mesh: &Mesh,
    enc: Encoding,
    pty: ScalarType,
    (ct, it): (ScalarType, ScalarType),
    vprops: &[(&str, ScalarType, &[f64])],
    out: &mut Vec<u8>,
) {
    use rayon::prelude::*;
    let le = enc == Encoding::BinaryLittleEndian;
    let a = &mesh.attributes;
    let vrec = 3 * pty.size() + vprops.iter().map(|p| p.1.size()).sum::<usize>();
    let ffix = ct.size() + a.face.iter().map(|p| p.ty.size()).sum::<usize>();
    let (nv, nf) = (mesh.vertex_count(), mesh.face_count());
    let face_at = |f: usize| f * ffix + mesh.offsets[f] as usize * it.size();
    let vbytes = nv * vrec;
    let fbytes = face_at(nf);
    let start = out.len();
    // one fresh buffer (on huge pages where the kernel allows: tens of MB for a large
    // surface) holding the header already written and the body
    let mut buf: Vec<u8> = crate::tensor::zeroed_vec(start + vbytes + fbytes);
    buf[..start].copy_from_slice(out);
    *out = buf;
    let (vb, fb) = out[start..].split_at_mut(vbytes);
    vb.par_chunks_mut(BODY_CHUNK * vrec.max(1))
        .enumerate()
        .for_each(|(c, dst)| {
            let first = c * BODY_CHUNK;
            for (k, rec) in dst.chunks_exact_mut(vrec).enumerate() {
                let v = first + k;
                let mut at = 0;
                for &x in &mesh.positions[v] {
                    at += put_bin(&mut rec[at..], le, pty, x);
                }
                for (_, ty, vals) in vprops {
                    at += put_bin(&mut rec[at..], le, *ty, vals[v]);
                }
            }
        });
    // split the face block at chunk boundaries
    let mut parts = Vec::with_capacity(nf.div_ceil(BODY_CHUNK));
    let mut rest = fb;
    let mut f0 = 0;
    while f0 < nf {
        let f1 = (f0 + BODY_CHUNK).min(nf);
        let (head, tail) = rest.split_at_mut(face_at(f1) - face_at(f0));
        parts.push((f0, f1, head));
        rest = tail;
        f0 = f1;
    }
    parts.into_par_iter().for_each(|(f0, f1, dst)| {
        let mut at = 0;
        for f in f0..f1 {
            let face = mesh.face(f);
            at += put_bin(&mut dst[at..], le, ct, face.len() as f64);
            for &i in face {
                at += put_bin(&mut dst[at..], le, it, i as f64);
            }
            for p in &a.face {
                at += put_bin(&mut dst[at..], le, p.ty, p.values[f]);
            }
        }
    });
}

trait MaxFor {
    fn max_for(self, other: ScalarType) -> ScalarType;
}

impl MaxFor for ScalarType {
    /// `double` if either is `double`, else `self`.
    fn max_for(self, other: ScalarType) -> ScalarType {
        if other == ScalarType::F64 {
            ScalarType::F64
        } else {
            self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mesh of triangles and quads over several body chunks, with vertex and face
    /// properties of mixed types.
    fn mesh() -> Mesh {
        let nf = 2 * BODY_CHUNK + 77;
        let nv = nf + 3;
        let positions: Vec<[f64; 3]> = (0..nv)
            .map(|i| {
                let x = i as f64;
                [x * 0.25, (x * 0.37).sin() * 100.0, -x / 3.0]
            })
            .collect();
        let mut offsets = vec![0u32];
        let mut indices = Vec::new();
        for f in 0..nf {
            let deg = if f % 5 == 0 { 4 } else { 3 };
            for k in 0..deg {
                indices.push(((f + k) % nv) as u32);
            }
            offsets.push(indices.len() as u32);
        }
        let mut attributes = Attributes {
            position_type: Some(ScalarType::F32),
            ..Attributes::default()
        };
        attributes.vertex.push(Property {
            name: "quality".into(),
            ty: ScalarType::U16,
            values: (0..nv).map(|i| (i % 60000) as f64).collect(),
        });
        attributes.face.push(Property {
            name: "label".into(),
            ty: ScalarType::I8,
            values: (0..nf).map(|f| (f % 200) as f64 - 100.0).collect(),
        });
        Mesh {
            positions,
            offsets,
            indices,
            attributes,
        }
    }

    #[test]
    fn binary_body_written_in_parallel_reads_back_value_for_value() {
        let m = mesh();
        for enc in [Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian] {
            let bytes = to_bytes(&m, enc).unwrap();
            // header + 3 f32 + u16 per vertex; count + indices + i8 per face
            let (_, _, body) = parse_header(&bytes).unwrap();
            let want = m.vertex_count() * 14 + m.face_count() * 2 + m.indices.len() * 4;
            assert_eq!(bytes.len() - body, want, "{enc:?}");
            let back = parse(&bytes).unwrap();
            assert_eq!(back.offsets, m.offsets);
            assert_eq!(back.indices, m.indices);
            for (a, b) in back.positions.iter().zip(&m.positions) {
                for k in 0..3 {
                    assert_eq!(a[k], b[k] as f32 as f64);
                }
            }
            assert_eq!(back.attributes.vertex, m.attributes.vertex);
            assert_eq!(back.attributes.face, m.attributes.face);
        }
    }
}
